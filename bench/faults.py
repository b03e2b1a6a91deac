"""Fault benchmark: the runtime when things go wrong, measured with real processes and sockets.

1. ``cycles`` kill -9 cycles: a three-node graph is launched, runs, and its launcher is SIGKILLed;
   ``orphans`` counts node processes still alive 5 s later (PR_SET_PDEATHSIG and the nodes' parent
   watch should leave none). ``stale_sockets`` counts the socket files the killed launchers left,
   ``stale_sockets_after_next_launch`` those left once the next launch has cleaned up.
2. Early failures, each through ``counterpart demo`` as a user meets them: a file of random bytes
   (``--input``), a camera that does not exist (``--live --device /dev/video9``), a corrupt model
   file (``--set responder.model_file=``). ``end_after_failure_s`` is the worst time from the
   failing node's error line to the demo's exit (the reference, before this was fixed: never;
   the issue's tester killed it after 240 s); ``early_failures`` has each case's time and exit code.
   ``missing_model_check_s``: a model file that does not exist, refused by ``launch --check``
   (from start to exit: nothing starts).
3. Fuzz: ``--fuzz`` hostile messages (bus.fuzz: random bytes, truncated and nested msgpack, bad
   arrays, oversize, wrong field types, other registered types, forged end of stream and counters,
   odd well-formed messages) to each of the silhouette node and the labeller. ``fuzz_sent``,
   ``fuzz_uncounted`` (sent minus counted by the nodes' stats, as received or bad), ``crashes``
   (nodes that exited non-zero, or a graph that did not end), ``fuzz_rate_hz``.
4. Recorder: ``counterpart bag record`` of a 50 fps camera, stopped with SIGSTOP for 3 s:
   ``recorder_stall_blocks`` (did the camera stall?) and, as the reference, the same with
   ``--lossless`` (``recorder_stall_blocks_lossless``: a reliable recorder does hold it back).

Usage: python bench/faults.py [--cycles N] [--fuzz N] [--quick]. Last stdout line: one JSON object.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import psutil

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.faulting import fuzz_silhouette_and_labeller, recorder_stalls_camera  # noqa: E402
from tests.launching import REPO, descendants, kill_tree, start_launch, wait_for, write_launch  # noqa: E402

N = "tests.graph_nodes:"


def progress(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _cli(*args: str, home: Path, timeout: float) -> tuple[int | None, str, float]:
    """Run ``counterpart ARGS``; (exit code or None on timeout, output, wall-clock end time)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "counterpart.bus.cli", *args],
        cwd=REPO,
        start_new_session=True,
        env={**os.environ, "COUNTERPART_HOME": str(home)},
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        out, _ = proc.communicate(timeout=timeout)
        return proc.returncode, out, time.time()
    except subprocess.TimeoutExpired:
        kill_tree(proc)
        return None, proc.stdout.read() if proc.stdout else "", time.time()


# ------------------------------------------------------------------------------- kill -9 cycles


def kill_cycles(cycles: int, work: Path) -> dict[str, int]:
    home = Path(tempfile.mkdtemp(prefix="cpk", dir="/tmp"))
    sink = work / "sink.jsonl"
    doc = {
        "nodes": {
            "source": {"run": N + "Counter", "params": {"count": 10**9, "rate": 100.0}, "remap": {"out": "numbers"}},
            "relay": {"run": N + "Relay", "remap": {"in": "numbers", "out": "doubled"}},
            "sink": {"run": N + "Sink", "params": {"path": str(sink)}, "remap": {"in": "doubled"}},
        }
    }
    f = write_launch(work / "cycle.yaml", doc)
    orphans = 0
    try:
        for i in range(cycles):
            sink.unlink(missing_ok=True)
            proc = start_launch(f, env={"COUNTERPART_HOME": str(home)})
            ok = wait_for(lambda: sink.exists() and sink.read_text().count("seq") > 5, 30)
            kids = descendants(proc.pid)
            os.kill(proc.pid, signal.SIGKILL)
            proc.wait()
            wait_for(lambda kids=kids: not [k for k in kids if _alive(k)], 5)
            left = [k for k in kids if _alive(k)]
            orphans += len(left)
            for k in left:
                k.kill()
            progress(
                f"  kill -9 cycle {i + 1}/{cycles}: {len(kids)} nodes{'' if ok else ' (no messages)'}, {len(left)} left"
            )
        stale = _sockets(home)
        # the next launch cleans up first (and its own sockets when it ends)
        one = write_launch(work / "one.yaml", {"nodes": {"source": {"run": N + "Counter", "params": {"count": 1}}}})
        _cli("launch", str(one), home=home, timeout=60)
        return {
            "cycles": cycles,
            "orphans": orphans,
            "stale_sockets": stale,
            "stale_sockets_after_next_launch": _sockets(home),
        }
    finally:
        shutil.rmtree(home, ignore_errors=True)


def _alive(p: psutil.Process) -> bool:
    try:
        return p.is_running() and p.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def _sockets(home: Path) -> int:
    return sum(1 for p in home.rglob("*") if p.is_socket())


# ------------------------------------------------------------------------------- early failures

_ERROR = re.compile(r"^\[(\d\d):(\d\d):(\d\d)\.(\d{3}) (\w+)\] ERROR", re.M)


def _first_node_error(out: str) -> float | None:
    """Wall-clock time of the first ERROR line of a node (not of the demo or the launcher)."""
    for m in _ERROR.finditer(out):
        if m.group(5) not in ("demo", "launch"):
            h, mi, s, ms = (int(g) for g in m.groups()[:4])
            today = dt.datetime.now()
            t = today.replace(hour=h, minute=mi, second=s, microsecond=ms * 1000)
            if t > today + dt.timedelta(minutes=1):  # logged before midnight
                t -= dt.timedelta(days=1)
            return t.timestamp()
    return None


def early_failures(work: Path, timeout: float) -> dict[str, object]:
    home = Path(tempfile.mkdtemp(prefix="cpe", dir="/tmp"))
    noise = work / "r.avi"
    noise.write_bytes(np.random.default_rng(0).integers(0, 256, 200_000, dtype=np.uint8).tobytes())
    corrupt = work / "corrupt.npz"
    corrupt.write_bytes(noise.read_bytes()[:5000])
    out_dir = str(work / "out")
    cases = {
        "input_not_a_video": ["demo", "--input", str(noise), "--out", out_dir],
        "no_such_camera": ["demo", "--live", "--device", "/dev/video9", "--out", out_dir],
        "corrupt_model_file": ["demo", "--set", f"responder.model_file={corrupt}", "--out", out_dir],
    }
    results: dict[str, dict[str, object]] = {}
    try:
        for name, args in cases.items():
            code, out, ended = _cli(*args, home=home, timeout=timeout)
            failed_at = _first_node_error(out)
            took = timeout if code is None or failed_at is None else round(ended - failed_at, 2)
            results[name] = {"code": code, "end_after_failure_s": took}
            progress(f"  {name}: exit {code} {took} s after the node's error")
        t0 = time.monotonic()
        code, out, _ = _cli(
            "launch",
            "demo.yaml",
            "--check",
            "--set",
            "responder.model_file=/nonexistent/model.npz",
            home=home,
            timeout=timeout,
        )
        check_s = round(time.monotonic() - t0, 2)
        progress(f"  missing model file: exit {code} after {check_s} s: {out.strip()[-120:]}")
    finally:
        shutil.rmtree(home, ignore_errors=True)
    return {
        "end_after_failure_s": max(r["end_after_failure_s"] for r in results.values()),  # type: ignore[type-var]
        "early_failures": results,
        "missing_model_check_s": check_s,
        "missing_model_check_code": code,
    }


# ------------------------------------------------------------------------------------------ fuzz


def fuzz(n: int, work: Path) -> dict[str, object]:
    targets, code, out, took = fuzz_silhouette_and_labeller(work, n, timeout=60 + n / 50)
    failed = [m for m in re.findall(r"\] \w+ (\w+) exited with (\d+)", out) if m[1] != "0"]
    for t in targets:
        progress(f"  {t.node}: sent {t.sent} ({t.valid} well-formed), received {t.received}, bad {t.bad}")
    return {
        "fuzz_sent": sum(t.sent for t in targets),
        "fuzz_uncounted": sum(t.uncounted for t in targets),
        "crashes": len(failed) + (code is None),
        "fuzz_rate_hz": round(sum(t.sent for t in targets) / took, 1),
        "fuzz_exit_code": code,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cycles", type=int, default=30, help="kill -9 cycles")
    ap.add_argument("--fuzz", type=int, default=10_000, help="hostile messages per fuzzed node")
    ap.add_argument("--timeout", type=float, default=240.0, help="give up on an early-failure case after this")
    ap.add_argument("--quick", action="store_true", help="5 cycles, 2,000 messages per node")
    args = ap.parse_args()
    if args.quick:
        args.cycles, args.fuzz = 5, 2000
    work = Path(tempfile.mkdtemp(prefix="bench-faults-"))
    result: dict[str, object] = {"load_avg_1min": round(os.getloadavg()[0], 2)}
    try:
        from counterpart.apps.demo import ensure_models

        progress("default models (built once, cached)...")
        ensure_models()
        progress(f"kill -9 cycles ({args.cycles})...")
        result.update(kill_cycles(args.cycles, work))
        progress("early failures...")
        result.update(early_failures(work, args.timeout))
        progress(f"fuzz ({args.fuzz} per node)...")
        result.update(fuzz(args.fuzz, work))
        progress("recorder stopped with SIGSTOP...")
        result["recorder_stall_blocks"], _ = recorder_stalls_camera(work, lossless=False)
        result["recorder_stall_blocks_lossless"], _ = recorder_stalls_camera(work, lossless=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(json.dumps(result))


if __name__ == "__main__":
    main()
