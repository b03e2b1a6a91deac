"""`counterpart demo --input FILE` on recordings: every frame processed, the output at the input's
frame rate, a summary that says what the run gave, and an end after any input however short.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from tests.launching import REPO

FPS = 10.0
N_FRAMES = 30


@pytest.fixture(scope="module")
def env(demo_models: Path) -> dict[str, str]:
    """The session's model cache (the first demo builds the default models into it)."""
    return {
        **os.environ,
        "COUNTERPART_MODELS": str(demo_models),
        "COUNTERPART_HOME": tempfile.mkdtemp(prefix="cpi-", dir="/tmp"),
    }


@pytest.fixture(scope="module")
def clip(tmp_path_factory: pytest.TempPathFactory, env: dict[str, str]) -> Path:
    """A handshake recorded from the simulator at 10 fps (its video file, MJPG)."""
    out = tmp_path_factory.mktemp("clip")
    subprocess.run(
        [
            sys.executable,
            "-m",
            "counterpart.bus.cli",
            "sim",
            "--scenario",
            "handshake",
            "--seed",
            "3",
            "--fps",
            str(FPS),
            "--frames",
            str(N_FRAMES),
            "--out",
            str(out),
        ],
        cwd=REPO,
        env=env,
        check=True,
        capture_output=True,
        timeout=300,
    )
    videos = [p for p in out.iterdir() if p.suffix in (".avi", ".mp4")]
    assert len(videos) == 1, sorted(p.name for p in out.iterdir())
    return videos[0]


def _demo(env: dict[str, str], out: Path, *args: str, timeout: float = 300) -> tuple[subprocess.CompletedProcess, dict]:
    res = subprocess.run(
        [sys.executable, "-m", "counterpart.bus.cli", "demo", "--out", str(out), *args],
        cwd=REPO,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    stats = json.loads((out / "demo_stats.json").read_text()) if (out / "demo_stats.json").exists() else {}
    return res, stats


def _video_frames_and_fps(out: Path) -> tuple[int, float]:
    (video,) = [p for p in out.glob("demo.*") if p.suffix in (".mp4", ".avi")]
    cap = cv2.VideoCapture(str(video))
    fps = cap.get(cv2.CAP_PROP_FPS)
    n = 0
    while cap.read()[0]:
        n += 1
    cap.release()
    return n, fps


@pytest.mark.timeout(600)  # the first demo of the session trains the default models
def test_a_file_is_processed_frame_by_frame_and_written_at_its_own_rate(
    clip: Path, env: dict[str, str], tmp_path: Path
) -> None:
    res, stats = _demo(env, tmp_path, "--input", str(clip), timeout=600)
    assert res.returncode == 0, res.stderr[-3000:]
    assert (stats["frames_in"], stats["frames_out"]) == (N_FRAMES, N_FRAMES)
    assert stats["fps_in"] == stats["fps_out"] == FPS
    assert _video_frames_and_fps(tmp_path) == (N_FRAMES, FPS)
    # lockstep: every node handled every frame offered to it, and none was dropped
    assert all(v["handled"] == v["offered"] == N_FRAMES for v in stats["handled"].values()), stats["handled"]
    # the training frames (20) are held back and their people found once the background is learnt:
    # people in more frames than the 11 after training (the two stand still for the first second,
    # which a background fitted on those frames partly absorbs)
    assert stats["frames_with_people"] >= 20, stats
    assert stats["partner_drawn"] >= 10, stats
    assert f"partner drawn on:   {stats['partner_drawn']}" in res.stdout


@pytest.mark.timeout(300)
@pytest.mark.parametrize("frames", [0, 1, 5])
def test_every_short_input_ends_by_itself_and_says_why_it_drew_no_partner(
    clip: Path, env: dict[str, str], tmp_path: Path, frames: int
) -> None:
    # 0 frames: the replay starts past the end of the file, a source that fails before its first frame
    args = ["--frames", str(frames)] if frames else ["--set", f"camera.start_frame={N_FRAMES + 10}"]
    res, stats = _demo(env, tmp_path, "--input", str(clip), *args, timeout=120)
    assert stats["frames_in"] == stats["frames_out"] == frames, res.stderr[-3000:]
    if frames == 0:  # the camera's error and exit code (3: its source failed) end the demo
        assert res.returncode == 3 and "is past the end of" in res.stderr, res.stderr[-3000:]
        # and the demo's last words say which node failed and why, below the statistics
        last = res.stderr.strip().splitlines()[-2:]
        assert last[0] == "counterpart demo: the graph ended with exit code 3", res.stderr[-3000:]
        assert last[1].startswith("  camera: ") and "is past the end of" in last[1], last
    elif frames == 1:  # nothing to learn a background from: no people, no partner, and the run says so
        assert res.returncode == 1 and stats["partner_present"] == 0.0
        assert "no partner was drawn on any of the 1 frames" in res.stderr, res.stderr[-3000:]
    else:  # the background is learnt from the 5 frames there are (the people stand still in them)
        assert "background learnt from 5 frames" in res.stderr, res.stderr[-3000:]
        assert res.returncode == (0 if stats["partner_drawn"] else 1)


@pytest.mark.timeout(300)
def test_a_folder_of_frames_is_an_input_too(clip: Path, env: dict[str, str], tmp_path: Path) -> None:
    folder = tmp_path / "frames"
    folder.mkdir()
    cap = cv2.VideoCapture(str(clip))
    n = 0
    while n < 12:
        ok, frame = cap.read()
        assert ok
        cv2.imwrite(str(folder / f"{n:04d}.png"), frame)
        n += 1
    cap.release()
    out = tmp_path / "out"
    res, stats = _demo(env, out, "--input", str(folder), timeout=240)
    assert res.returncode in (0, 1) and (stats["frames_in"], stats["frames_out"]) == (12, 12), res.stderr[-3000:]
    assert stats["fps_in"] == stats["fps_out"] == 25.0  # a folder declares no rate: the camera's 25
    assert _video_frames_and_fps(out) == (12, 25.0)
    res, _ = _demo(env, tmp_path / "out2", "--input", str(tmp_path / "missing"), timeout=60)
    assert res.returncode == 2 and "no such file or folder" in res.stderr


def test_an_out_that_is_no_folder_is_refused_before_anything_runs(env: dict[str, str], tmp_path: Path) -> None:
    """``--out`` is the folder the demo writes into: a video's name or an existing file is refused
    with the reason and the way out, before a model is loaded, and nothing is made.
    """
    video_name = tmp_path / "result.mp4"
    a_file = tmp_path / "notes.txt"
    a_file.write_text("kept")
    for out, says in ((video_name, "names a video file"), (a_file, "is a file")):
        res, _ = _demo(env, out, "--frames", "5", timeout=60)
        assert res.returncode == 2, res.stderr[-2000:]
        assert says in res.stderr and "give a folder" in res.stderr and "Traceback" not in res.stderr
        assert "preparing the default models" not in res.stderr
    assert not video_name.exists() and a_file.read_text() == "kept"


@pytest.mark.timeout(300)
def test_a_demo_stopped_by_ctrl_c_says_so_and_keeps_the_frames_done(
    clip: Path, env: dict[str, str], tmp_path: Path
) -> None:
    """A looping replay in real time, interrupted as Ctrl-C does: the demo says it was stopped (not
    that the graph failed), exits 130, and the video holds the frames done.
    """
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [sys.executable, "-m", "counterpart.bus.cli", "demo", "--out", str(out), "--input", str(clip)]
        + ["--realtime", "--set", "camera.loop=true"],
        cwd=REPO,
        env=env,
        stderr=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.monotonic() + 120
        while not (out / "demo_stats.json").exists() and time.monotonic() < deadline:
            # the renderer writes frames once the graph runs; its video grows on disk
            if any(p.stat().st_size > 10_000 for p in out.glob("demo.*") if p.suffix in (".mp4", ".avi")):
                break
            time.sleep(0.5)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, err[-3000:]
    assert "counterpart demo: stopped (Ctrl-C or a stop signal)" in err and "ended with exit code" not in err
    n, _ = _video_frames_and_fps(out)
    assert n > 0


def _session_processes(sid: int) -> list[int]:
    """Pids of the live processes of session ``sid`` (from /proc)."""
    pids = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[3]) == sid and fields[0] != "Z":
            pids.append(int(stat.parent.name))
    return pids


def _builders(pid: int) -> list[int]:
    """Pids of the model builders of the demo ``pid``: its multiprocessing workers."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            ppid = int(stat.read_text().rsplit(")", 1)[1].split()[1])
            cmd = (stat.parent / "cmdline").read_bytes()
        except OSError:
            continue
        if ppid == pid and b"spawn_main" in cmd:
            found.append(int(stat.parent.name))
    return found


@pytest.mark.timeout(120)
@pytest.mark.parametrize(
    "stop, code, says",
    [
        ("terminal", 130, "interrupted while the default models were built"),
        ("demo-alone", 130, "interrupted while the default models were built"),
        ("builder-killed", 1, "a process building the default models died"),
    ],
)
def test_ctrl_c_while_the_models_are_built_says_so_and_keeps_those_finished(
    env: dict[str, str], tmp_path: Path, stop: str, code: int, says: str
) -> None:
    """Ctrl-C during the first run's model building, as a terminal sends it (SIGINT to the whole
    process group) or to the demo's process alone (``kill -INT``), or a builder killed (as by the
    kernel out of memory): the demo says what happened, ends at once with 130 (1 for the killed
    builder), stops its builders and leaves only whole model files.
    """
    models = tmp_path / "models"
    proc = subprocess.Popen(
        [sys.executable, "-m", "counterpart.bus.cli", "demo", "--out", str(tmp_path / "out")],
        cwd=REPO,
        env={**env, "COUNTERPART_MODELS": str(models)},
        stderr=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        start_new_session=True,
        # as from a terminal: a test run started in the background (a CI script's job) ignores
        # SIGINT, and its children would inherit that
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        said = []
        for line in proc.stderr:  # the first model's builder at work: the longest of them
            said.append(line)
            if "simulating training data" in line:
                break
        if stop == "terminal":
            os.killpg(proc.pid, signal.SIGINT)
        elif stop == "demo-alone":
            os.kill(proc.pid, signal.SIGINT)
        else:
            os.kill(_builders(proc.pid)[0], signal.SIGKILL)
        _, rest = proc.communicate(timeout=30)
        err = "".join(said) + rest
        deadline = time.monotonic() + 10
        while _session_processes(proc.pid) and time.monotonic() < deadline:
            time.sleep(0.2)
        left = _session_processes(proc.pid)
    finally:
        for pid in _session_processes(proc.pid):
            os.kill(pid, signal.SIGKILL)
    assert proc.returncode == code, err[-3000:]
    assert not left, f"builders still at work: {left}"
    # the model whose builder was at work was not finished after the signal
    from counterpart.apps.demo import RESPONDER_MODELS

    assert not any(models.glob(f"*{RESPONDER_MODELS[0]}*.npz")), sorted(p.name for p in models.iterdir())
    assert says in err and "Traceback" not in err, err[-3000:]
    for f in models.glob("*"):  # nothing half-written: each file there loads
        assert f.suffix == ".npz" and not f.name.endswith(".tmp.npz"), sorted(p.name for p in models.iterdir())
        with np.load(f) as z:
            assert z.files
