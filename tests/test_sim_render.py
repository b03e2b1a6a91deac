"""counterpart.sim.render / sim.stream / sim.cli: pixels agree with the ground truth, shadows, determinism,
the people are not the cone model, the camera-node URI, the CLI's files, the CMU pair.
"""

from __future__ import annotations

import argparse
import os

import cv2
import numpy as np
import pytest

from counterpart.body.raster import rasterise_silhouettes
from counterpart.body.trajectory import TwoPersonTrajectory
from counterpart.sim import cli
from counterpart.sim.stream import default_sequence, open_stream

CMU = os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data", "cmu")


@pytest.fixture(scope="module")
def hs():
    return open_stream("handshake", seed=0)


def _frames(stream, n: int = 6) -> list[int]:
    ph = stream.scenario.phase
    picks = np.linspace(0, stream.n_frames - 1, n).round().astype(int).tolist()
    return sorted(set(picks + [int(np.flatnonzero(ph == 1)[len(np.flatnonzero(ph == 1)) // 2])]))


def test_masks_agree_with_pixels(hs) -> None:
    for name, s in (("handshake", hs), ("push", open_stream("push", seed=4))):
        for i in _frames(s):
            frame, tr = s.render_with_truth(i, noise=False)
            bg = s.background(i)
            differs = np.any(frame != bg, axis=-1)
            a, b = tr.masks
            assert a.sum() > 200 and b.sum() > 200, f"{name} frame {i}: both people visible"
            assert not np.any(a & b) and not np.any(tr.shadow & (a | b))
            np.testing.assert_array_equal(differs, a | b | tr.shadow, err_msg=f"{name} frame {i}")
            assert tr.shadow.sum() > 50


def test_shadows_darken_the_floor_keeping_chromaticity(hs) -> None:
    i = _frames(hs)[3]
    frame, tr = hs.render_with_truth(i, noise=False)
    bg = hs.background(i).astype(np.float64)[tr.shadow]
    sh = frame.astype(np.float64)[tr.shadow]
    ratio = sh.sum(1) / bg.sum(1)
    f = hs.renderer.lighting.shadow_factor
    assert np.all(ratio < 0.8) and abs(np.median(ratio) - f) < 0.03
    chroma = lambda x: x / x.sum(1, keepdims=True)  # noqa: E731
    assert np.abs(chroma(sh) - chroma(bg)).max() < 0.03


def test_noise_lighting_and_determinism(hs) -> None:
    i = 10
    noisy, _ = hs.render_with_truth(i)
    clean, tr = hs.render_with_truth(i, noise=False)
    d = noisy.astype(np.float64) - clean
    assert 1.5 < d[~(tr.masks.any(0))].std() < 2.5, "sensor noise sigma about 2 grey levels"
    again = open_stream("handshake", seed=0).render(i)[0]
    assert again.tobytes() == noisy.tobytes()
    other = open_stream("handshake", seed=1).render(i)[0]
    assert not np.array_equal(other, noisy)
    g = np.array([hs.renderer.lighting.gain(t) for t in np.linspace(0, 60, 200)])
    assert 0.02 <= (g.max() - g.min()) / 2 <= 0.05, "slow global gain drift of a few percent"
    b0, b1 = hs.background(0).astype(float).mean(), hs.background(hs.n_frames - 1).astype(float).mean()
    r = hs.renderer.lighting.gain(hs.renderer.time(hs.n_frames - 1)) / hs.renderer.lighting.gain(0.0)
    assert abs(b1 / b0 - r) < 0.005


def test_people_are_not_the_cone_model(hs) -> None:
    sc = hs.scenario
    ious = []
    for i in _frames(hs):
        _, tr = hs.render_with_truth(i, noise=False)
        ours = tr.masks.any(0)
        cones = (
            rasterise_silhouettes(sc.poses_a[i : i + 1], sc.dims_a, hs.camera)[0]
            | rasterise_silhouettes(sc.poses_b[i : i + 1], sc.dims_b, hs.camera)[0]
        )
        ious.append((ours & cones).sum() / (ours | cones).sum())
        # yet the same people in the same place: projected joints fall in (or next to) the masks
        uv = np.round(tr.joints2d.reshape(-1, 2)).astype(int)
        grown = cv2.dilate(ours.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)
        assert grown[uv[:, 1], uv[:, 0]].mean() > 0.9
    assert np.mean(ious) < 0.9 and np.mean(ious) > 0.4, f"IoU with the cone model {np.mean(ious):.2f}"


def test_camera_node_opens_the_simulator() -> None:
    from counterpart.nodes.camera.sources import SourceError, make_source

    src = make_source("sim:push?seed=3&emotion=angry&strength=0.7&frames=12", width=160, height=120)
    src.open()
    n = 0
    while True:
        ok, img, t = src.read()
        if not ok:
            break
        assert img.shape == (120, 160, 3) and abs(t - n / 25.0) < 1e-9
        n += 1
    assert n == 12
    with pytest.raises(SourceError, match="unknown simulator option"):
        make_source("sim:push?colour=red")
    with pytest.raises(SourceError, match="unknown scenario"):
        make_source("sim:tango")
    d = default_sequence()
    assert d.scenario.label == "handshake" and d.size == (320, 240) and d.fps == 25.0


def _run_cli(out: str, *extra: str) -> int:
    ap = argparse.ArgumentParser()
    cli.add_arguments(ap)
    return cli.main(ap.parse_args(["--out", out, *extra]))


def test_cli_writes_all_files_deterministically(tmp_path) -> None:
    args = (
        "--scenario",
        "high_five",
        "--seed",
        "2",
        "--frames",
        "20",
        "--width",
        "160",
        "--height",
        "120",
        "--emotion",
        "happy",
        "--strength",
        "0.5",
    )
    assert _run_cli(str(tmp_path / "a"), *args) == 0
    assert _run_cli(str(tmp_path / "b"), *args) == 0
    names = ("video.avi", "truth.npz", "trajectory.npz", "contact_sheet.png")
    for n in names:
        assert (tmp_path / "a" / n).read_bytes() == (tmp_path / "b" / n).read_bytes(), n
    cap = cv2.VideoCapture(str(tmp_path / "a" / "video.avi"))
    frames = []
    while True:
        ok, f = cap.read()
        if not ok:
            break
        frames.append(f)
    cap.release()
    assert len(frames) == 20 and frames[0].shape == (120, 160, 3)
    z = np.load(tmp_path / "a" / "truth.npz")
    assert z["masks"].shape == (20, 2, 120, 160) and z["joints2d"].shape == (20, 2, 14, 2)
    assert z["signals"].shape == (20, 2, 5) and str(z["label"]) == "high_five"
    s = open_stream("high_five", seed=2, width=160, height=120, emotion="happy", strength=0.5)
    if str(z["codec"]) == "FFV1":  # lossless: the video holds exactly the rendered frames
        assert np.array_equal(frames[7], s.render(7)[0])
    tr = TwoPersonTrajectory.load(tmp_path / "a" / "trajectory.npz")
    assert tr.n_frames == 20 and tr.signal_names[0] == "nod"
    sheet = cv2.imread(str(tmp_path / "a" / "contact_sheet.png"))
    assert sheet.shape == (3 * 120, 4 * 160, 3)
    assert _run_cli(str(tmp_path / "c"), "--scenario", "nope") == 2


def test_cmu_pair_renders(tmp_path) -> None:
    if not os.path.exists(os.path.join(CMU, "18_01.bvh")):
        pytest.skip(f"CMU BVH files not found in {CMU} (shared development data)")
    assert _run_cli(str(tmp_path), "--scenario", "cmu", "--frames", "8", "--width", "160", "--height", "120") == 0
    z = np.load(tmp_path / "truth.npz")
    assert z["masks"].shape[0] == 8 and z["masks"][:, 0].any() and z["masks"][:, 1].any()
