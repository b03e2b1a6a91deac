"""Fault experiments shared by tests/test_faults.py and bench/faults.py: hostile input to the
silhouette node and the labeller, and a camera whose frames a recorder takes, then the recorder
stopped with SIGSTOP (does the camera stall?).
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np
import zmq

from counterpart.bus import registry
from counterpart.bus.bag import BagReader
from counterpart.bus.fuzz import FuzzTarget, run_fuzz
from counterpart.bus.transport import LATEST, Subscriber
from counterpart.messages import NodeStats
from tests.launching import REPO, kill_tree, start_launch, wait_for, write_launch

#: frames per second of the camera under test (a 25 fps clip played twice as fast)
CAMERA_FPS = 50


def fuzz_silhouette_and_labeller(
    workdir: Path, n: int, timeout: float
) -> tuple[list[FuzzTarget], int | None, str, float]:
    """``n`` hostile messages each to the silhouette node's frames and the labeller's silhouettes
    (counterpart.bus.fuzz.run_fuzz). Returns the targets with their counts, the launcher's exit code, its
    output and the seconds it all took.
    """
    targets = [
        # frames of every size down to 0 pixels a side: the silhouette node refuses those below 2x2
        FuzzTarget("silhouette", "frame", "frame", "camera.Frame"),
        FuzzTarget("labeller", "silhouettes", "fuzzed_silhouettes", "silhouette.Silhouettes"),
    ]
    nodes = {
        "silhouette": {"run": "counterpart.nodes.silhouette", "params": {"train_frames": 2}},
        # the labeller takes silhouettes only here (a given rate, no faces): the fuzzed frames are the
        # silhouette node's
        "labeller": {
            "run": "counterpart.nodes.labeller",
            "params": {"use_tracker": False, "use_face": False, "fps": 25.0},
            "remap": {"silhouettes": "fuzzed_silhouettes", "signals": "signals"},
        },
    }
    t0 = time.monotonic()
    code, out = run_fuzz(nodes, targets, n, workdir, timeout=timeout)
    return targets, code, out, time.monotonic() - t0


def video(path: Path, frames: int = 50) -> Path:
    """A small Motion-JPEG clip (160 x 120, 25 fps, grey levels changing per frame) at ``path``."""
    w = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25, (160, 120))
    for i in range(frames):
        w.write(np.full((120, 160, 3), (i * 5) % 255, np.uint8))
    w.release()
    return path


def _require(ok: bool, what: str) -> None:
    if not ok:
        raise RuntimeError(what)


def _last_count(sub: Subscriber, seconds: float) -> int | None:
    """The camera's published frame count in the newest of its stats over ``seconds`` (None when
    none came: a camera blocked in a send publishes no stats either).
    """
    count, deadline = None, time.monotonic() + seconds
    while time.monotonic() < deadline:
        if sub.socket.poll(50):
            msg = sub.receive()
            if isinstance(msg, NodeStats):
                count = msg.outputs[0].count
    return count


def recorder_stalls_camera(workdir: Path, lossless: bool, stopped_s: float = 3.0) -> tuple[bool, str]:
    """Launch a camera looping a clip at :data:`CAMERA_FPS` in a live (``latest``) graph, record
    its frames with ``counterpart bag record`` (``--lossless`` when asked), stop the recorder with
    SIGSTOP for ``stopped_s`` seconds, then let it go on and stop it with Ctrl-C.

    Returns whether the camera stalled while the recorder was stopped (fewer than 10 frames out)
    and the recorder's output.
    """
    workdir.mkdir(parents=True, exist_ok=True)
    home = Path(tempfile.mkdtemp(prefix="cpr", dir="/tmp"))  # short: unix socket paths are limited
    doc = {
        "policy": "latest",
        "nodes": {
            "camera": {
                "run": "counterpart.nodes.camera",
                "params": {
                    "source": str(video(workdir / "v.avi")),
                    "loop": True,
                    "pacing": "rate",
                    "rate": CAMERA_FPS / 25,
                },
            }
        },
    }
    launch = start_launch(write_launch(workdir / "recorded.yaml", doc), env={"COUNTERPART_HOME": str(home)})
    bag = workdir / f"recorded{'_lossless' if lossless else ''}.mcap"
    rec: subprocess.Popen | None = None
    ctx = zmq.Context()
    stats: Subscriber | None = None
    recorded = lambda: sum(1 for _ in BagReader(bag).records()) if bag.exists() else 0  # noqa: E731
    try:
        _require(wait_for(lambda: (home / "latest" / "registry.json").is_file(), 30), "the launch did not start")
        reg = registry.read(str(home / "latest"))
        stats = Subscriber(
            ctx, "camera/stats", registry.topic_endpoints(reg, "camera/stats"), LATEST, msg_type=NodeStats
        )
        _require(wait_for(lambda: (_last_count(stats, 1.2) or 0) > 10, 60), "the camera published nothing")
        rec = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "counterpart.bus.cli",
                "bag",
                "record",
                "-t",
                "frame",
                "-o",
                str(bag),
                *(["--lossless"] if lossless else []),
            ],
            cwd=REPO,
            start_new_session=True,
            env={**os.environ, "COUNTERPART_HOME": str(home)},
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        _require(wait_for(lambda: recorded() > 5, 30), "the recorder wrote nothing")
        os.kill(rec.pid, signal.SIGSTOP)
        _last_count(stats, 1.0)  # what was in flight fills the queues meanwhile
        before = _last_count(stats, 1.5)
        after = _last_count(stats, stopped_s)
        at_stop = recorded()
        os.kill(rec.pid, signal.SIGCONT)
        # recording goes on past what the queues held: only then does the recorder see the gap
        _require(wait_for(lambda: recorded() > at_stop + 2 * CAMERA_FPS, 30), "the recorder did not go on")
        rec.send_signal(signal.SIGINT)
        out, _ = rec.communicate(timeout=30)
        _require(rec.returncode == 0, f"the recorder failed:\n{out}")
        return before is None or after is None or after - before < 10, out
    finally:
        if stats is not None:
            stats.close()
        ctx.term()
        if rec is not None:
            if rec.poll() is None:
                os.kill(rec.pid, signal.SIGCONT)
            kill_tree(rec)
        launch.send_signal(signal.SIGINT)
        try:
            launch.wait(15)
        finally:
            kill_tree(launch)
            shutil.rmtree(home, ignore_errors=True)
