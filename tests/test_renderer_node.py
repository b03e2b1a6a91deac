"""The renderer node in launched graphs: a scene source -> renderer -> video file and `rendered` topic."""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

import cv2
import numpy as np
import pytest

from counterpart.body.camera import default_camera
from counterpart.bus.launchfile import LaunchError, check, load
from counterpart.messages import Frame, Partner
from counterpart.nodes.renderer import draw
from counterpart.nodes.renderer.compositor import Compositor
from counterpart.nodes.renderer.video import count_frames
from tests.camera_sink import cv2_frames
from tests.launching import read_jsonl, run_launch, start_launch, stop_launch, wait_for, write_launch
from tests.renderer_nodes import partner_joints, scene_frame

W, H = 160, 120


def graph(tmp_path: Path, source: dict, renderer: dict) -> Path:
    return write_launch(
        tmp_path / "graph.yaml",
        {
            "nodes": {
                "source": {"run": "tests.renderer_nodes:SceneSource", "params": source},
                "calibration": {"run": "counterpart.nodes.calibration", "policy": "reliable"},
                "renderer": {"run": "counterpart.nodes.renderer", "params": renderer, "policy": "reliable"},
                "sink": {
                    "run": "tests.camera_sink",
                    "params": {"path": str(tmp_path / "rendered.jsonl")},
                    "remap": {"frame": "rendered"},
                    "policy": "reliable",
                },
            }
        },
    )


def test_graph_writes_a_video_with_every_frame_and_the_partner_visible(tmp_path: Path) -> None:
    n = 24
    # a replay: every frame waits for its own partner however busy the machine is (the default
    # 0.1 s is for live use, where a late partner must not hold the video up)
    code, text = run_launch(
        graph(
            tmp_path,
            {"count": n, "width": W, "height": H, "emotion": "angry", "strength": 1.0},
            {"video": str(tmp_path / "out.mp4"), "pair_timeout": 10.0, "adaptive_wait": False},
        ),
        timeout=60,
    )
    assert code == 0, text
    written = [p for p in (tmp_path / "out.mp4", tmp_path / "out.avi") if p.exists()]
    assert len(written) == 1, text
    assert f"wrote {n} frames to {written[0]}" in text
    assert "partner exact 24, held 0, missing 0" in text
    frames = cv2_frames(written[0])
    assert len(frames) == n == count_frames(written[0])
    cam = default_camera(W, H)  # the renderer's camera by default: the tracker's at the frame size
    for seq in (0, n - 1):
        mask = (draw.draw_partner_3d(np.zeros((H, W, 3), np.uint8), partner_joints(seq), cam) > 0).any(-1)
        core = cv2.erode(mask.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
        far = ~cv2.dilate(mask.astype(np.uint8), np.ones((9, 9), np.uint8)).astype(bool)
        far[-30:] = False  # the darkened control strip along the bottom
        far[:10] = False  # the moving bar of the scene
        img = frames[seq].astype(int)
        # the angry partner is red where its cones project; the background elsewhere stays as it was
        assert core.sum() > 150
        assert (img[core][:, 2] - img[core][:, 0]).mean() > 60
        assert np.abs(img[far] - scene_frame(seq, W, H)[far]).mean() < 3
    # the `rendered` topic carries exactly what the compositor makes of each frame and its partner
    records = read_jsonl(tmp_path / "rendered.jsonl")
    assert records[-1] == {"event": "end", "drops": 0}
    assert [r["seq"] for r in records[:-1]] == list(range(n))
    comp = Compositor(default_camera())
    for seq in (0, 7):
        comp.add_frame(Frame(seq=seq, image=scene_frame(seq, W, H)))
        comp.add_partner(Partner(seq=seq, model="test", joints=partner_joints(seq), emotion="angry", strength=1.0))
        img = comp.render(comp.ready(flush=True)[0])
        assert records[seq]["sha1"] == hashlib.sha1(img.tobytes()).hexdigest()


def test_a_frame_whose_partner_never_comes_is_rendered_when_its_wait_is_over(tmp_path: Path) -> None:
    """The node's timer wakes for the first waiting frame's deadline (not on a fixed tick): every
    frame comes out pair_timeout after it was captured, give or take the machine's delays.
    """
    timeout = 0.25
    code, text = run_launch(
        graph(
            tmp_path,
            {"count": 12, "rate": 10.0, "width": W, "height": H, "partner_every": 0},
            {"pair_timeout": timeout, "adaptive_wait": False},
        ),
        timeout=60,
    )
    assert code == 0, text
    assert "partner exact 0, held 0, missing 12" in text
    records = read_jsonl(tmp_path / "rendered.jsonl")[:-1]
    assert [r["seq"] for r in records] == list(range(12))
    # the first frame also waits for the graph's camera; the last ones go out at end of stream
    waited = np.array([(r["received"] - r["stamp"]) / 1e9 for r in records[1:-2]])
    assert (waited >= timeout).all(), waited
    assert np.median(waited) < timeout + 0.03, waited


def test_ctrl_c_leaves_a_playable_video_with_every_rendered_frame(tmp_path: Path) -> None:
    snaps = tmp_path / "snaps"
    file = graph(
        tmp_path,
        {"count": 100000, "rate": 30.0, "width": W, "height": H},
        {"video": str(tmp_path / "live.avi"), "snapshot_every": 5, "snapshot_dir": str(snaps)},
    )
    proc = start_launch(file)
    try:
        assert wait_for(lambda: len(read_jsonl(tmp_path / "rendered.jsonl")) >= 12, timeout=30), "no frames rendered"
    finally:
        stop_launch(proc)
    text = proc.stdout.read()
    m = re.search(r"wrote (\d+) frames to (\S+)", text)
    assert m, text
    written = int(m.group(1))
    assert Path(m.group(2)) == tmp_path / "live.avi"
    assert written >= 12
    assert count_frames(tmp_path / "live.avi") == written
    pngs = sorted(snaps.glob("frame*.png"))
    assert len(pngs) == written // 5
    assert cv2.imread(str(pngs[0])).shape == (H, W, 3)


def test_bad_parameters_are_refused_before_start(tmp_path: Path) -> None:
    for params, msg in [
        ({"video": "x.mkv"}, "video"),
        ({"style": "wire"}, "style"),
        ({"snapshot_every": 3}, "snapshot_dir"),
        ({"camera": {"fx": 1}}, "camera"),
        ({"stats_topics": ["a/stats", "a/stats"]}, "listed twice"),
    ]:
        file = graph(tmp_path, {"count": 1}, params)
        with pytest.raises(LaunchError, match=msg):
            check(load(file))
