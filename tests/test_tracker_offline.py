"""``counterpart track``: offline 3D tracking of a real video file, as a real process."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from counterpart.apps.offline import FrameProgress
from counterpart.apps.shared_pass import SharedPass, item_bytes
from counterpart.apps.tracking import track_video
from counterpart.body.camera import Camera
from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor, iter_video
from counterpart.nodes.tracker.prior import MotionPrior, train_prior
from counterpart.sim.cli import open_writer
from counterpart.sim.stream import open_stream

EMPTY = 20  # frames of the empty room the background model is fitted on
SCENE = 40


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, np.ndarray, Path]:
    """A video (the empty room, then a handshake), the people's true joints (SCENE, 2, 14, 3) and a
    small motion prior trained on other handshakes.
    """
    d = tmp_path_factory.mktemp("track")
    st = open_stream("handshake", seed=3, frames=SCENE)
    writer, _ = open_writer(str(d / "video.avi"), st.fps, st.size)
    rng = np.random.default_rng(0)
    for _ in range(EMPTY):  # sensor noise as on the scene's frames, so the model learns a spread
        writer.write(np.clip(st.background(0) + rng.normal(0, 2, (240, 320, 3)), 0, 255).astype(np.uint8))
    truth = []
    for i in range(st.n_frames):
        frame, t = st.render_with_truth(i)
        writer.write(frame)
        truth.append(t.joints3d)
    writer.release()
    prior = train_prior(["sim:handshake?seed=100", "sim:handshake?seed=101"], n_states=10)
    return d / "video.avi", np.array(truth), Path(prior.save(str(d / "prior.npz")))


def _track(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "counterpart.bus.cli", "track", *args], capture_output=True, text=True, timeout=300
    )


def test_track_follows_both_people_of_a_video(recording: tuple[Path, np.ndarray, Path], tmp_path: Path) -> None:
    video, truth, prior = recording
    out = tmp_path / "poses.npz"
    r = _track(
        str(video),
        "--out",
        str(out),
        "--camera",
        "default",  # the simulator's, the truth's: the joints are compared in its world frame
        "--train-frames",
        str(EMPTY),
        "--prior",
        str(prior),
        "--layers",
        "5",
        "--particles",
        "128",
    )
    assert r.returncode == 0, r.stderr
    summary = json.loads(r.stdout.strip().splitlines()[-1])
    assert summary["n_frames"] == EMPTY + SCENE and summary["tracked"] == {"left": SCENE, "right": SCENE}
    assert summary["camera_source"] == "default"
    d = np.load(out)
    assert list(d["sides"]) == ["left", "right"] and bool(d["complete"])
    assert d["joints"].shape == (EMPTY + SCENE, 2, 14, 3) and d["poses"].shape == (EMPTY + SCENE, 2, 28)
    assert np.isnan(d["joints"][:EMPTY]).all()  # the empty room: nobody tracked
    assert (d["ids"][EMPTY:, 0] != d["ids"][EMPTY:, 1]).all()  # two people, never the same region
    err = np.linalg.norm(d["joints"][EMPTY:] - truth, axis=-1).mean(axis=(0, 2))
    assert (err < 0.1).all(), f"mean joint error per person {err} m"
    assert json.loads(str(d["camera"]))["width"] == 320


def test_track_estimates_the_camera_of_a_video_from_its_people(
    recording: tuple[Path, np.ndarray, Path], tmp_path: Path
) -> None:
    """Without a calibration file the camera is estimated from the people, as the graph's
    calibration node does, and tracked with: a camera 2.9 m high looking 22 degrees down, far from
    the default level one at 1.6 m, is found and recorded.
    """
    _, _, prior = recording
    stream = open_stream("push", seed=8, camera="random", frames=75)
    video = tmp_path / "steep.avi"
    writer, _ = open_writer(str(video), stream.fps, stream.size)
    for i in range(stream.n_frames):
        writer.write(stream.render(i)[0])
    writer.release()
    out = tmp_path / "poses.npz"
    r = _track(str(video), "--out", str(out), "--prior", str(prior), "--layers", "3", "--particles", "64",
               "--train-frames", "20")  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert "camera estimated from the people" in r.stderr
    summary = json.loads(r.stdout.strip().splitlines()[-1])
    d = np.load(out)
    assert summary["camera_source"] == json.loads(str(d["params"]))["camera_source"] == "estimated"
    assert summary["tracked"]["left"] > 0 and summary["tracked"]["right"] > 0  # both sides by default
    used, truth = Camera.from_dict(json.loads(str(d["camera"]))), stream.camera
    assert abs(used.centre[1] / truth.centre[1] - 1.0) < 0.10
    tilt = [np.degrees(np.arcsin(-c.R[2, 1])) for c in (used, truth)]
    assert abs(tilt[0] - tilt[1]) < 3.0 and tilt[1] > 20.0


def test_the_camera_and_the_tracking_share_one_pass_of_the_silhouettes(
    recording: tuple[Path, np.ndarray, Path],
) -> None:
    """``counterpart track`` estimates the camera from the first frames and tracks every frame: the
    silhouettes of one pass, the first frames kept for the tracking, give the tracking the same
    frames, labels and people as a pass of its own (and so the same joints: the tracker is seeded).
    """
    video, _, _ = recording
    n = EMPTY + 10
    shared = SharedPass(iter_video(video, SilhouetteExtractor(), None, EMPTY))
    seen = list(shared.first(n))
    assert len(seen) == n and sum(len(r.people) for _, r in seen) > 0
    again = shared.again()
    assert again is not None
    own = iter_video(video, SilhouetteExtractor(), None, EMPTY)
    k = 0
    for (frame, result), (frame_own, result_own) in zip(again, own, strict=True):
        assert np.array_equal(frame, frame_own) and np.array_equal(result.labels, result_own.labels), k
        assert [p.bbox for p in result.people] == [p.bbox for p in result_own.people], k
        k += 1
    assert k == EMPTY + SCENE
    # frames that would not fit the memory it may take are not kept: the video is read again (the
    # same frames and results given again, as a pass would give them)
    over = SharedPass(iter(seen), max_bytes=5 * item_bytes(seen[0]))
    assert len(list(over.first(n))) == n and over.again() is None
    # nor are they where the first reader stopped early
    early = SharedPass(iter(seen))
    next(early.first(n))
    assert early.again() is None


def test_track_refuses_bad_input_with_the_reason(recording: tuple[Path, np.ndarray, Path], tmp_path: Path) -> None:
    video, _, _ = recording
    out = tmp_path / "poses.npz"
    r = _track(str(tmp_path / "missing.avi"), "--out", str(out))
    assert r.returncode == 2 and "video file or image folder not found" in r.stderr
    junk = tmp_path / "junk.avi"
    junk.write_bytes(b"not a video" * 100)
    r = _track(str(junk), "--out", str(out))
    assert r.returncode == 2 and "cannot read video" in r.stderr
    cam = tmp_path / "cam.yaml"
    cam.write_text("eye: [0, 1.6, 4]\ntarget: [0, 0.9, 0]\nfov: 55\nwidth: 320\nheight: 240\n")
    r = _track(str(video), "--out", str(out), "--camera", str(cam), "--prior", "none")
    assert r.returncode == 2 and "fov" in r.stderr and "cam.yaml" in r.stderr
    cam.write_text(
        json.dumps({"eye": [0, 1.6, 4], "target": [0, 0.9, 0], "fov_deg": 55, "width": 640, "height": 360})
    )  # another aspect ratio than the video's 4:3
    r = _track(str(video), "--out", str(out), "--camera", str(cam), "--prior", "none", "--train-frames", "5")
    assert r.returncode == 2 and "calibrated for 640x360" in r.stderr
    r = _track(str(video), "--out", str(out), "--people", "left", "left", "--prior", "none")
    assert r.returncode == 2 and "distinct sides" in r.stderr and "[track]" not in r.stderr, r.stderr  # at once
    r = _track(str(video), "--out", str(out), "--calibration-frames", "0", "--prior", "none")
    assert r.returncode == 2 and "--calibration-frames must be at least 1" in r.stderr
    # a video given as the calibration: said as such, not as a text codec's complaint
    r = _track(str(video), "--out", str(out), "--camera", str(video), "--prior", "none")
    assert r.returncode == 2 and "not a text file" in r.stderr and "codec" not in r.stderr, r.stderr
    # an output that cannot be written: said before the camera is estimated and the people tracked
    for bad, says in ((tmp_path, "is a folder"), (tmp_path / "no" / "poses.npz", "does not exist; make it first")):
        r = _track(str(video), "--out", str(bad), "--prior", "none")
        assert r.returncode == 2 and says in r.stderr and "[track]" not in r.stderr, r.stderr
    assert not out.exists()  # nothing half-written


def test_an_interrupted_run_keeps_the_frames_done(recording: tuple[Path, np.ndarray, Path], tmp_path: Path) -> None:
    video, _, prior = recording
    out = tmp_path / "poses.npz"

    def stop_after_25(done: int, declared: int) -> None:
        assert declared == EMPTY + SCENE
        if done == 25:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        track_video(
            video,
            out,
            prior=MotionPrior.load(str(prior)),
            layers=3,
            particles=64,
            train_frames=EMPTY,
            progress=stop_after_25,
        )
    d = np.load(out)
    assert int(d["n_frames"]) == 25 and not bool(d["complete"]) and d["joints"].shape == (25, 2, 14, 3)
    assert np.isfinite(d["joints"][EMPTY:25]).all()


def test_progress_counts_to_the_frames_the_command_will_take(capsys: pytest.CaptureFixture[str]) -> None:
    # `counterpart track video.avi --max-frames 300` on a file of 795 frames counts to 300
    progress = FrameProgress("track", every=0.0, limit=300)
    for done in (1, 2, 3):
        progress(done, 795)
    lines = capsys.readouterr().err.splitlines()
    assert lines and all(line.startswith("[track] frame ") and "/300," in line for line in lines), lines
    whole = FrameProgress("track", every=0.0)
    whole(1, 795)
    whole(2, 795)
    assert "frame 2/795," in capsys.readouterr().err
    unknown = FrameProgress("track", every=0.0)  # a stream that declares no length, no cap: no total
    unknown(1, 0)
    unknown(2, 0)
    assert "frame 2, " in capsys.readouterr().err
