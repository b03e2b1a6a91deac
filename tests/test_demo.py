"""`counterpart demo` end to end on a fresh model cache: trains the defaults, runs all six nodes on
every frame of the built-in scene, writes the video, the contact sheet, the summary and the per-node
statistics.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import cv2
import pytest

from counterpart.bus.launchfile import check, find_launch_file, load
from tests.launching import REPO


@pytest.mark.timeout(600)  # the session's first demo trains every default model first
def test_demo_builds_models_runs_the_graph_and_writes_its_outputs(tmp_path: Path, demo_models: Path) -> None:
    env = {
        **os.environ,
        "COUNTERPART_MODELS": str(demo_models),
        "COUNTERPART_HOME": tempfile.mkdtemp(prefix="cpd-", dir="/tmp"),
    }
    res = subprocess.run(
        [sys.executable, "-m", "counterpart.bus.cli", "demo", "--out", str(tmp_path / "out")],
        cwd=REPO,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert res.returncode == 0, res.stderr[-3000:]
    models = sorted(p.name for p in demo_models.iterdir())
    assert "tracker_prior.npz" in models and "responder-dual-hmm.npz" in models
    videos = [p for p in (tmp_path / "out").glob("demo.*") if p.suffix in (".mp4", ".avi")]
    assert len(videos) == 1
    cap = cv2.VideoCapture(str(videos[0]))
    n = 0
    while cap.read()[0]:
        n += 1
    stats = json.loads((tmp_path / "out" / "demo_stats.json").read_text())
    assert n == stats["frames_in"] == stats["frames_out"] > 200  # the whole scene, every frame (lockstep)
    sheet = cv2.imread(str(tmp_path / "out" / "demo_contact_sheet.png"))
    assert sheet is not None and sheet.shape[0] >= 240 and sheet.shape[1] >= 4 * 320
    assert set(stats["nodes"]) == {
        "camera",
        "calibration",
        "silhouette",
        "tracker",
        "labeller",
        "responder",
        "renderer",
    }
    assert all(sum(t["count"] for t in st["inputs"] + st["outputs"]) > 0 for st in stats["nodes"].values())
    assert stats["fps_in"] == stats["fps_out"] == 25.0
    # the built-in scene's partner is drawn on most frames (0.81; 0.91 after the first second)
    assert stats["partner_present"] > 0.7 and stats["partner_present_after_1s"] > 0.85, stats
    assert str(videos[0]) in res.stdout and "contact sheet" in res.stdout and "partner drawn on" in res.stdout


def _subscriptions(file: str) -> dict[tuple[str, str], str]:
    graph = check(load(find_launch_file(file)))
    return {(node, port): policy for t in graph.topics.values() for node, port, policy in t["subscribers"]}


def test_the_real_time_demo_and_the_lockstep_replay_are_the_same_graph_with_other_queues() -> None:
    demo, replay = load(find_launch_file("demo.yaml")), load(find_launch_file("replay.yaml"))
    assert set(replay.nodes) == set(demo.nodes) | {"recorder"}
    assert set(load(find_launch_file("lockstep.yaml")).nodes) == set(demo.nodes)
    # the lockstep/queue/pairing keys may differ; every other parameter is the same
    own = {
        ("camera", "pacing"),
        ("renderer", "video"),
        ("renderer", "pair_timeout"),
        ("labeller", "max_pending"),
        ("renderer", "adaptive_wait"),
        ("silhouette", "replay_training"),
        ("tracker", "people"),
        ("camera", "width"),  # real time: frames 320 wide, no sample model, a time budget per frame
        ("silhouette", "dynamic"),
        ("silhouette", "fit_in_background"),
        ("silhouette", "body_shadow_leg_scale"),  # real time: the leg check on 2 x 2 blocks
        ("tracker", "frame_budget"),
        ("tracker", "min_layers"),  # real time: at the floors 2 layers of more particles, not 3
        ("tracker", "frame_wall"),  # real time: under load fewer particles rather than dropped frames
        ("calibration", "detect_frames"),
        ("calibration", "every"),
        ("calibration", "cpu_share"),  # real time: the estimates' share of a core (lockstep: deterministic)
        ("calibration", "cpu_burst_s"),
        ("calibration", "refit_growth"),  # real time: until the first credible estimate, by the people observed
        ("calibration", "lockstep"),  # lockstep: every frame waits for its camera to be decided
    }
    for name, decl in demo.nodes.items():
        other = replay.nodes[name]
        assert other.run == decl.run, name
        keys = set(decl.params) | set(other.params)
        assert {k: decl.params.get(k) for k in keys if (name, k) not in own} == {
            k: other.params.get(k) for k in keys if (name, k) not in own
        }, name
    assert (demo.nodes["camera"].params["pacing"], replay.nodes["camera"].params["pacing"]) == ("realtime", "lockstep")
    # real time: every input keeps the newest message except the renderer's frames; lockstep: nothing dropped
    live = _subscriptions("demo.yaml")
    assert live.pop(("renderer", "frame")) == "reliable" and set(live.values()) == {"latest"}
    assert set(_subscriptions("replay.yaml").values()) == {"reliable"}
    assert set(_subscriptions("lockstep.yaml").values()) == {"reliable"}
    assert set(_subscriptions("live.yaml").items()) == set(_subscriptions("demo.yaml").items())
