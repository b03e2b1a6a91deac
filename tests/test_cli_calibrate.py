"""`counterpart calibrate VIDEO --out camera.yaml`: the camera estimated offline from the people in a
video, printed with its uncertainty, written as a calibration file every camera-taking node and
command reads; a video without people is refused with the reason.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from counterpart.body.camera import camera_for_size, load_camera_file
from tests.launching import REPO


def _cli(*args: str, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "counterpart.bus.cli", *args], cwd=REPO, capture_output=True, text=True, timeout=timeout
    )


@pytest.fixture(scope="module")
def clip(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A simulated handshake seen from a random camera (its video file)."""
    out = tmp_path_factory.mktemp("clip")
    res = _cli(
        "sim", "--scenario", "handshake", "--seed", "2", "--camera", "random", "--frames", "60", "--out", str(out)
    )
    assert res.returncode == 0, res.stderr[-2000:]
    return out / "video.avi"


@pytest.fixture(scope="module")
def square_clip(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A simulated handshake seen from the simulator's default camera (its video file): square to the
    room's back wall and tilted 10 degrees, so that neither the wall's lines, whose vanishing point is
    at infinity, nor the people fix the focal length.
    """
    out = tmp_path_factory.mktemp("square")
    res = _cli("sim", "--scenario", "handshake", "--seed", "2", "--frames", "60", "--out", str(out))
    assert res.returncode == 0, res.stderr[-2000:]
    return out / "video.avi"


@pytest.mark.slow
def test_calibrate_writes_a_camera_file_with_the_estimate_and_its_uncertainty(clip: Path, tmp_path: Path) -> None:
    out = tmp_path / "camera.yaml"
    res = _cli("calibrate", str(clip), "--out", str(out))
    assert res.returncode == 0, res.stderr[-2000:]
    summary = json.loads(res.stdout.strip().splitlines()[-1])
    est = summary["estimate"]
    assert summary["n_frames"] == 60 and summary["observations"] >= 20
    for key in ("focal", "tilt_deg", "roll_deg", "height", "focal_std", "tilt_std_deg", "height_std"):
        assert np.isfinite(est[key]), key
    assert "[calibrate] focal" in res.stderr and "+-" in res.stderr  # the estimate, with its uncertainty
    # the camera (1.9 m high, tilted 6 degrees, 55 degrees wide, 15 degrees round from the wall) within
    # the limits of the issue: the graph would use it
    truth = np.load(clip.parent / "truth.npz")
    true = json.loads(str(truth["meta"]))["camera"]
    assert abs(est["height"] / true["height"] - 1) < 0.1 and abs(est["tilt_deg"] - true["tilt_deg"]) < 3.0, est
    assert abs(est["focal"] / truth["camera_K"][0, 0] - 1) < 0.1, est
    assert summary["graph_would_use"] is True and "not sure enough" not in res.stderr
    # the file is a calibration: the same camera read back, for these frames and scaled to others
    cam = load_camera_file(str(out))
    assert (cam.width, cam.height) == (320, 240)
    assert cam.fx == pytest.approx(est["focal"]) and cam.centre[1] == pytest.approx(est["height"])
    assert camera_for_size(cam, 160, 120).fx == pytest.approx(est["focal"] / 2)
    assert out.read_text().startswith("# camera estimated by `counterpart calibrate`")


@pytest.mark.slow
def test_a_known_field_of_view_fixes_the_focal_length_the_people_leave_open(square_clip: Path, tmp_path: Path) -> None:
    # a camera square to the wall leaves the focal length uncertain beyond the calibration node's
    # bound (max_focal_std 0.2): the graph would keep its default camera, and the command says so
    res = _cli("calibrate", str(square_clip), "--out", str(tmp_path / "open.yaml"))
    assert res.returncode == 0, res.stderr[-2000:]
    summary = json.loads(res.stdout.strip().splitlines()[-1])
    assert summary["estimate"]["focal_std"] > 0.2 and summary["graph_would_use"] is False
    assert "not sure enough" in res.stderr
    # with the lens's view as a spec sheet gives it
    clip = square_clip
    fx = float(np.load(clip.parent / "truth.npz")["camera_K"][0, 0])
    fov = round(float(np.degrees(2 * np.arctan(160.0 / fx))))
    res = _cli("calibrate", str(clip), "--out", str(tmp_path / "camera.yaml"), "--fov", str(fov))
    assert res.returncode == 0, res.stderr[-2000:]
    summary = json.loads(res.stdout.strip().splitlines()[-1])
    est = summary["estimate"]
    assert abs(est["focal"] / fx - 1) < 0.05 and est["focal_std"] < 0.06, est
    assert (
        summary["fov_given_deg"] == fov
        and f"field of view given (--fov): {fov} deg" in (tmp_path / "camera.yaml").read_text()
    )
    for bad in ("0.5", "200"):
        res = _cli("calibrate", str(clip), "--out", str(tmp_path / "x.yaml"), "--fov", bad)
        assert res.returncode == 2 and f"--fov: field of view {float(bad)!r} degrees" in res.stderr, res.stderr
    assert not (tmp_path / "x.yaml").exists()


def test_a_video_without_people_is_refused_with_the_reason(tmp_path: Path) -> None:
    video = tmp_path / "empty.avi"
    w = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 10.0, (160, 120))
    rng = np.random.default_rng(0)
    for _ in range(12):
        w.write(np.clip(120 + rng.normal(0, 2, (120, 160, 3)), 0, 255).astype(np.uint8))
    w.release()
    out = tmp_path / "camera.yaml"
    res = _cli("calibrate", str(video), "--out", str(out), "--train-frames", "5")
    assert res.returncode == 2 and "views of whole upright people" in res.stderr, res.stderr[-2000:]
    assert not out.exists()
    res = _cli("calibrate", str(tmp_path / "missing.avi"), "--out", str(out))
    assert res.returncode == 2 and "missing.avi" in res.stderr


def test_people_cut_off_above_their_feet_are_refused_with_the_reason_and_the_way_out(
    clip: Path, tmp_path: Path
) -> None:
    # the simulated people stand from about row 100 down to row 220: the frames cut at row 170
    cut = tmp_path / "cut.avi"
    cap = cv2.VideoCapture(str(clip))
    w = cv2.VideoWriter(str(cut), cv2.VideoWriter_fourcc(*"MJPG"), 25.0, (320, 170))
    ok, frame = cap.read()
    while ok:
        w.write(np.ascontiguousarray(frame[:170]))
        ok, frame = cap.read()
    w.release()
    out = tmp_path / "camera.yaml"
    # 30 frames: the detector runs on every frame without a whole person, and half the clip says as much
    res = _cli("calibrate", str(cut), "--out", str(out), "--max-frames", "30")
    assert res.returncode == 2, res.stderr[-2000:]
    assert re.search(r"feet were out of the picture in (9\d|100)% of their views", res.stderr), res.stderr[-2000:]
    assert "recording of this camera where people stand or walk in full view" in res.stderr
    assert not out.exists()
