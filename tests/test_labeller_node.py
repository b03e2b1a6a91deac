"""The labeller node: message conversion, and real graphs camera -> silhouette -> [pose stand-in] ->
labeller -> recording sinks (its seq pairing alone: tests/test_bus_pairing.py).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from counterpart.messages import Pose3D, Silhouettes
from counterpart.messages.silhouette import PersonShape
from counterpart.messages.tracker import TrackedBody
from counterpart.nodes.labeller.labeller import SocialLabeller
from counterpart.nodes.labeller.node import observations, signals_message
from counterpart.nodes.labeller.signals import SIGNALS
from counterpart.sim.flat_scenes import two_person_sequence
from tests.launching import REPO, read_jsonl, run_launch, write_launch
from tests.pose_source import facing

GAZE, TALK, LAUGH, ACT, NOD = (SIGNALS.index(s) for s in ("gaze_at_other", "talking", "laughing", "activity", "nod"))


# ------------------------------------------------------------------------------------- conversion
def shape(pid: int, side: str, cx: float, n_ctrl: int = 32) -> PersonShape:
    t = np.linspace(0, 2 * np.pi, n_ctrl, endpoint=False)
    ctrl = np.stack([cx + 10 * np.sin(t), 100 - 50 * np.cos(t)], 1).astype(np.float32)
    return PersonShape(
        id=pid,
        side=side,
        ctrl=ctrl,
        ref_point=ctrl[0],
        centroid=np.array([cx, 100], np.float32),
        bbox=(int(cx - 10), 50, 21, 101),
        height=101.0,
        area=1500,
    )


def test_observations_choose_3d_where_tracked_else_the_silhouette() -> None:
    sil = Silhouettes(
        seq=5,
        stamp=9,
        width=320,
        height=240,
        people=[shape(0, "left", 80.0), shape(1, "right", 240.0), shape(2, "left", 160.0, n_ctrl=16)],
    )
    pose = Pose3D(
        seq=5,
        stamp=9,
        people=[
            TrackedBody(id=0, side="left", joints=(facing(np.pi / 2) + [-0.8, 0, 3]).astype(np.float32)),
            TrackedBody(id=1, side="right", joints=(facing(-np.pi / 2) + [0.8, 0, 3]).astype(np.float32)),
            TrackedBody(id=2, side="left", joints=np.zeros((14, 3), np.float32), lost=True),
        ],
    )
    obs, sides = observations(sil, pose)
    assert [obs[i].has_3d() for i in (0, 1, 2)] == [True, True, False]
    assert obs[2].has_2d_head() and obs[2].control_points is None  # 16 points: no 2D activity
    assert obs[0].box == (70, 50, 21, 101) and sides == {0: "left", 1: "right", 2: "left"}
    lab = SocialLabeller(25.0)
    msg = signals_message(5, 9, lab.update(obs), obs, sides)
    assert (msg.seq, msg.stamp) == (5, 9) and [p.source for p in msg.people] == ["3d", "3d", "2d"]
    a, b, c = msg.people
    assert a.names == list(SIGNALS) and a.scores.dtype == np.float32 and a.labels.dtype == np.int8
    # two tracked people facing each other look at each other; a silhouette cannot tell gaze
    assert (a.labels[GAZE], b.labels[GAZE], c.labels[GAZE]) == (1, 1, -1) and np.isnan(c.scores[GAZE])
    assert all(p.labels[TALK] == -1 and p.labels[LAUGH] == -1 for p in msg.people)  # no image given
    obs2, _ = observations(sil, None)
    assert not any(o.has_3d() for o in obs2.values())


# ----------------------------------------------------------------------------------- real graphs
EMPTY, TRAIN, N = 15, 15, 70


@pytest.fixture(scope="module")
def scene(tmp_path_factory: pytest.TempPathFactory) -> str:
    import cv2

    seq = two_person_sequence(n_frames=N - EMPTY, size=(120, 160), empty_frames=EMPTY)
    folder = tmp_path_factory.mktemp("scene")
    for i, f in enumerate(seq.frames):
        cv2.imwrite(str(folder / f"f{i:03d}.png"), f)
    return f"folder:{folder}"


def sink(topic: str, path: Path) -> dict[str, Any]:
    return {"run": "tests.topic_sink", "params": {"topic": topic, "path": str(path)}, "policy": "reliable"}


def run_graph(tmp_path: Path, source: str, labeller: dict[str, Any], pose_every: int = 0) -> tuple[list, list]:
    nodes: dict[str, Any] = {
        "camera": {"run": "counterpart.nodes.camera", "params": {"source": source, "pacing": "lockstep", "fps": 25.0}},
        "silhouette": {
            "run": "counterpart.nodes.silhouette",
            "params": {"train_frames": TRAIN, "mask_every": 0},
            "policy": "reliable",
        },
        "labeller": {"run": "counterpart.nodes.labeller", "params": labeller, "policy": "reliable"},
        "frames": sink("frame", tmp_path / "frames.jsonl"),
        "signals": sink("signals", tmp_path / "signals.jsonl"),
    }
    if pose_every:
        nodes["tracker"] = {"run": "tests.pose_source", "params": {"every": pose_every}, "policy": "reliable"}
    code, text = run_launch(write_launch(tmp_path / "graph.yaml", {"nodes": nodes}), timeout=60)
    assert code == 0, text
    out = []
    for name in ("frames", "signals"):
        recs = read_jsonl(tmp_path / f"{name}.jsonl")
        assert recs and recs[-1]["event"] == "end" and recs[-1]["drops"] == 0, f"{name}: no clean end\n{text}"
        out.append(recs[:-1])
    return out[0], out[1]


def test_2d_graph_one_signals_per_frame_unknown_where_unsupported(tmp_path: Path, scene: str) -> None:
    frames, sigs = run_graph(tmp_path, scene, {"use_tracker": False})
    assert [(r["seq"], r["stamp"]) for r in sigs] == [(r["seq"], r["stamp"]) for r in frames]
    assert len(sigs) == N and all(r["type"] == "labeller.SocialSignals/1" for r in sigs)
    assert all(r["people"] == [] for r in sigs[:EMPTY])
    for r in sigs[EMPTY:]:
        assert [(p["id"], p["side"], p["source"]) for p in r["people"]] == [(0, "left", "2d"), (1, "right", "2d")]
        for p in r["people"]:
            assert p["names"] == list(SIGNALS) and set(p["labels"]) <= {-1, 0, 1}
            # no 3D body: gaze unknown; no frames subscribed: talking/laughing unknown
            assert [p["labels"][i] for i in (GAZE, TALK, LAUGH)] == [-1, -1, -1]
            assert [p["scores"][i] for i in (GAZE, TALK, LAUGH)] == [None, None, None]
    # what 2D supports becomes known once its window has filled (activity 1 s, nod/shake 1.6 s)
    last = sigs[-1]["people"]
    assert all(p["labels"][ACT] in (0, 1) and p["labels"][NOD] in (0, 1) for p in last), last
    assert all(p["labels"][ACT] == -1 for p in sigs[EMPTY]["people"])


def test_pose_every_other_frame_3d_there_silhouette_fallback_between(tmp_path: Path, scene: str) -> None:
    # max_pending above the frame count: however late the stand-in tracker runs on a loaded machine,
    # the labeller waits for its pose rather than falling back early
    frames, sigs = run_graph(tmp_path, scene, {"use_tracker": True, "max_pending": 1000}, pose_every=2)
    assert [(r["seq"], r["stamp"]) for r in sigs] == [(r["seq"], r["stamp"]) for r in frames]
    for r in sigs[EMPTY:]:
        want = "3d" if r["seq"] % 2 == 0 else "2d"
        assert [p["source"] for p in r["people"]] == [want, want], r["seq"]
        gaze = [p["labels"][GAZE] for p in r["people"]]
        # the stand-in bodies face each other: gaze known (and at the other) only from 3D
        assert gaze == ([1, 1] if want == "3d" else [-1, -1]), r["seq"]


def test_face_input_paired_although_frames_arrive_long_before_silhouettes(tmp_path: Path, scene: str) -> None:
    nodes = {
        "camera": {"run": "counterpart.nodes.camera", "params": {"source": scene, "pacing": "lockstep", "fps": 25.0}},
        "silhouette": {"run": "counterpart.nodes.silhouette", "params": {"train_frames": TRAIN}, "policy": "reliable"},
        "labeller": {
            "run": "counterpart.nodes.labeller",
            "params": {"use_tracker": False, "use_face": True},
            "policy": "reliable",
        },
        "signals": sink("signals", tmp_path / "signals.jsonl"),
    }
    code, text = run_launch(write_launch(tmp_path / "graph.yaml", {"nodes": nodes}), timeout=60)
    assert code == 0, text
    assert f"labelled {N} frames (every input present;" in text and "0 released early" in text, text
    sigs = read_jsonl(tmp_path / "signals.jsonl")[:-1]
    assert [r["seq"] for r in sigs] == list(range(N))
    for r in sigs[EMPTY:]:  # flat-coloured figures have no faces: talking/laughing stay unknown
        assert all(p["labels"][TALK] == -1 and p["labels"][LAUGH] == -1 for p in r["people"])


def test_use_tracker_without_a_tracker_refused_naming_pose(tmp_path: Path) -> None:
    code, text = run_launch(
        REPO / "launch" / "labeller_file.yaml", "--set", "labeller.use_tracker=true", "--check", timeout=30
    )
    assert code == 2 and "node 'labeller': inputs.pose: no node publishes topic 'pose'" in text, text
    code, text = run_launch(
        REPO / "launch" / "labeller_file.yaml", "--set", "labeller.head_window_s=0.1", "--check", timeout=30
    )
    assert code == 2 and "'head_window_s'" in text and "need >= 8" in text, text
    code, text = run_launch(REPO / "launch" / "labeller_file.yaml", "--check", timeout=30)
    assert code == 0, text
