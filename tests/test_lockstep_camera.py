"""A lockstep graph whose camera is estimated while it runs is the same in every run: the tracker
and the responder hold each frame until the calibration node has decided its camera, however far
behind them it runs (``CameraInfo.undecided_from``).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.launching import read_jsonl, run_launch, write_launch
from tests.test_calibration_node import ALL_CREDIBLE

FRAMES = 100


def _graph(tmp: Path, lockstep: bool) -> Path:
    """Two trackers and two responders, twins, on one camera, one silhouette node and one
    calibration node that estimates the camera on every frame and publishes it for the very frame
    it was estimated on (``lead`` 0); twin b gets each camera only once twin a's poses are five
    frames past the frame it holds from (``tests.graph_nodes:LateCamera``).
    """
    nodes: dict[str, dict] = {
        "camera": {
            "run": "counterpart.nodes.camera",
            "params": {"source": "sim:high_five?seed=1&camera=random", "pacing": "lockstep", "max_frames": FRAMES},
        },
        "silhouette": {"run": "counterpart.nodes.silhouette", "params": {"train_frames": 20, "replay_training": True}},
        "calibration": {
            "run": "counterpart.nodes.calibration",
            "params": {
                **ALL_CREDIBLE,
                "estimate": True,
                "lockstep": lockstep,
                "lead": 0,
                "every": 5,
                "min_seconds": 0.5,
                "max_step": 0.02,
                "detect_frames": 0,
                "wait_frames": 60,
            },
        },
        "info_sink": {"run": "tests.topic_sink", "params": {"topic": "camera_info", "path": str(tmp / "info.jsonl")}},
        "late": {"run": "tests.graph_nodes:LateCamera", "params": {"frames": 5}, "remap": {"pose": "a/pose"}},
    }
    for twin in ("a", "b"):
        camera = {"camera_info": "late_camera_info"} if twin == "b" else {}
        nodes[f"tracker_{twin}"] = {
            "run": "counterpart.nodes.tracker",
            "params": {"layers": 10, "particles": 128, "prior": "none", "people": ["left", "right"]},
            "remap": {"pose": f"{twin}/pose", **camera},
        }
        nodes[f"responder_{twin}"] = {
            "run": "counterpart.nodes.responder",
            "params": {"model": "dual-hmm", "use_silhouettes": True, "camera_info": True, "use_control": False},
            "remap": {"pose": f"{twin}/pose", "partner": f"{twin}/partner", **camera},
        }
        for topic in ("pose", "partner"):
            nodes[f"{twin}_{topic}_sink"] = {
                "run": "tests.topic_sink",
                "params": {"topic": f"{twin}/{topic}", "path": str(tmp / f"{twin}_{topic}.jsonl")},
            }
    return write_launch(tmp / "graph.yaml", {"policy": "reliable", "nodes": nodes})


def _messages(path: Path) -> list[dict]:
    """The recorded messages without the time each came to the sink."""
    return [{k: v for k, v in r.items() if k != "received"} for r in read_jsonl(path) if "seq" in r]


@pytest.mark.slow
def test_every_frame_gets_the_same_camera_however_late_the_calibration_decides_it(
    tmp_path: Path, models_dir: Path
) -> None:
    rc, log = run_launch(_graph(tmp_path, True), timeout=240, env={"COUNTERPART_MODELS": str(models_dir)})
    assert rc == 0, log
    infos = _messages(tmp_path / "info.jsonl")
    # the camera moved on many frames while the graph ran, and the frames it decides went on with
    # every frame the silhouettes came for, never back, each message deciding its own frame
    estimated = [i for i in infos if i["source"] == "estimated"]
    assert len({(i["fx"], i["t"][1]) for i in estimated}) >= 10, [(i["seq"], i["fx"]) for i in infos]
    undecided = [i["undecided_from"] for i in infos[:-1]]
    assert undecided == sorted(undecided) and len(infos) >= FRAMES - 60, undecided
    assert all(i["seq"] < i["undecided_from"] for i in infos[1:-1]) and infos[-1]["undecided_from"] == -1
    # the first estimate came within the frames waiting for it: it is the first frame's camera
    assert infos[0]["source"] == "default" and estimated[0]["seq"] == infos[0]["seq"] == 0, infos[:3]
    for topic in ("pose", "partner"):
        a, b = _messages(tmp_path / f"a_{topic}.jsonl"), _messages(tmp_path / f"b_{topic}.jsonl")
        assert [m["seq"] for m in a] == list(range(FRAMES)), topic
        # twin b saw every refinement later, yet they tracked and answered alike
        assert a == b, topic
    assert sum(bool(m["people"]) for m in _messages(tmp_path / "a_pose.jsonl")) > FRAMES // 2
