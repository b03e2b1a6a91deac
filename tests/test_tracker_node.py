"""The tracker node in launched graphs: simulator frames + silhouettes -> one Pose3D per frame."""

from __future__ import annotations

import json
import re
import time
from pathlib import Path

import numpy as np
import pytest

from counterpart.bus import Node, Output, Param
from counterpart.messages import Frame, PersonShape, Silhouettes
from tests.launching import read_jsonl, run_launch, write_launch


class SimPeople(Node):
    """Test source: simulator frames with their ground-truth masks as Silhouettes (labels A=1, B=2).

    ``hide_from``: from this frame on, the silhouettes hold nobody (a person-less view);
    ``merged``: every person is flagged as merged with the other.
    """

    outputs = {"frame": Output(Frame), "silhouettes": Output(Silhouettes)}
    params = {
        "frames": Param(int, 6, "frames to publish", min=1),
        "hide_from": Param(int, -1, "publish no people from this frame on (-1: never)"),
        "merged": Param(bool, False, "flag the people as merged"),
        "fps": Param(float, 0.0, "the frames' rate, Hz (0: unknown)", min=0.0),
        "drop_frames": Param(list, [], "seqs whose frame is not published (their silhouettes are)"),
        "skip": Param(list, [], "seqs of which nothing is published (dropped before the tracker)"),
    }

    def generate(self) -> None:
        from counterpart.sim.stream import open_stream

        stream = open_stream("handshake", seed=2, frames=self.p["frames"])
        for i in range(stream.n_frames):
            if i in self.p["skip"]:
                continue
            image, truth = stream.render_with_truth(i)
            stamp = time.monotonic_ns()
            labels = np.zeros(image.shape[:2], np.uint8)
            people = []
            if self.p["hide_from"] < 0 or i < self.p["hide_from"]:
                for pid, side in ((0, "left"), (1, "right")):
                    m = truth.masks[pid]
                    labels[m] = pid + 1
                    ys, xs = np.nonzero(m)
                    bbox = (int(xs.min()), int(ys.min()), int(np.ptp(xs) + 1), int(np.ptp(ys) + 1))
                    people.append(
                        PersonShape(
                            id=pid,
                            side=side,
                            bbox=bbox,
                            height=float(bbox[3]),
                            area=int(m.sum()),
                            merged=self.p["merged"],
                        )
                    )
            if i not in self.p["drop_frames"]:
                self.publish("frame", Frame(stamp=stamp, seq=i, image=image, fps=self.p["fps"]))
            self.publish(
                "silhouettes",
                Silhouettes(
                    stamp=stamp, seq=i, people=people, labels=labels, width=image.shape[1], height=image.shape[0]
                ),
            )


def _graph(tmp_path: Path, source: dict, tracker: dict) -> tuple[Path, Path]:
    out = tmp_path / "pose.jsonl"
    doc = {
        "nodes": {
            "source": {"run": "tests.test_tracker_node:SimPeople", "params": source},
            "calibration": {"run": "counterpart.nodes.calibration", "policy": "reliable"},
            "tracker": {
                "run": "counterpart.nodes.tracker",
                "policy": "reliable",
                "params": {"layers": 3, "particles": 48, "prior": "none", **tracker},
            },
            "sink": {"run": "tests.topic_sink", "policy": "reliable", "params": {"topic": "pose", "path": str(out)}},
        }
    }
    return write_launch(tmp_path / "graph.yaml", doc), out


def _poses(out: Path) -> list[dict]:
    return [r for r in read_jsonl(out) if r.get("type") == "tracker.Pose3D/1"]


def test_one_pose_per_frame_for_two_people(tmp_path: Path) -> None:
    f, out = _graph(tmp_path, {"frames": 6}, {"people": ["left", "right"]})
    rc, log = run_launch(f, timeout=90)
    assert rc == 0, log
    poses = _poses(out)
    assert [p["seq"] for p in poses] == list(range(6))
    for p in poses:
        assert [b["side"] for b in p["people"]] == ["left", "right"]
        joints = np.array(p["people"][0]["joints"], float)
        assert joints.shape == (14, 3) and np.isfinite(joints).all()
        # the left person stands left of the right one, feet near the floor, head above 1.3 m
        left, right = (np.array(b["joints"], float) for b in p["people"])
        assert left[:, 0].mean() < right[:, 0].mean()
        assert left[0, 1] > 1.3 and left[[10, 13], 1].min() < 0.3


def test_frames_dropped_before_the_tracker_are_stepped_over(tmp_path: Path) -> None:
    """A live graph drops frames its slowest node cannot take: the tracker gets seqs 0, 1, 4, 5, 6,
    7, counts the two it never saw, and its tracks go on through the longer step.
    """
    f, out = _graph(tmp_path, {"frames": 8, "skip": [2, 3], "fps": 25.0}, {"people": ["left", "right"]})
    rc, log = run_launch(f, timeout=90)
    assert rc == 0, log
    poses = _poses(out)
    assert [p["seq"] for p in poses] == [0, 1, 4, 5, 6, 7]
    assert all(len(p["people"]) == 2 and not any(b["lost"] for b in p["people"]) for p in poses)
    run_dir = Path(re.search(r"run directory (\S+)", log).group(1))
    figures = json.loads((run_dir / "stats" / "tracker.json").read_text())["figures"]
    assert figures["frames_stepped_over"] == 2


def test_nobody_in_view_and_merged_people(tmp_path: Path) -> None:
    f, out = _graph(tmp_path, {"frames": 5, "hide_from": 2, "merged": True}, {"people": ["left"]})
    rc, log = run_launch(f, timeout=90)
    assert rc == 0, log
    poses = _poses(out)
    assert [p["seq"] for p in poses] == list(range(5))
    assert [len(p["people"]) for p in poses] == [1, 1, 0, 0, 0]
    assert "merged" in log


@pytest.mark.parametrize(
    "camera, needle",
    [
        (
            {"eye": [0, 1.6, 4], "target": [0, 0.9, 0], "fov_deg": 55, "width": 320, "height": 240, "zoom": 2},
            "unknown key(s) ['zoom']",
        ),
        ({"fx": 300}, "missing key(s)"),
    ],
)
def test_bad_calibration_is_refused_by_name(tmp_path: Path, camera: dict, needle: str) -> None:
    f, out = _graph(tmp_path, {"frames": 2}, {"camera": camera})
    rc, log = run_launch(f, timeout=60)
    assert rc != 0
    assert "camera" in log and needle in log, log
    assert not _poses(out)


def test_bad_people_and_prior_are_refused(tmp_path: Path) -> None:
    f, _ = _graph(tmp_path, {"frames": 2}, {"people": ["left", "middle"]})
    rc, log = run_launch(f, timeout=60)
    assert rc != 0 and "people" in log and "middle" in log, log
    f, _ = _graph(tmp_path, {"frames": 2}, {"prior": str(tmp_path / "nope.npz")})
    rc, log = run_launch(f, timeout=60)
    assert rc != 0 and "prior" in log and "does not exist" in log, log
