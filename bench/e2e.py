"""End-to-end benchmark: the whole demo graph at 320x240 with the tracker at 10 x 256.

1. Real time: the camera replays the simulator's handshake at 25 fps (``pacing: realtime``) through
   all six nodes; a recorder takes the renderer's ``rendered`` topic. ``fps_sustained`` is rendered
   frames per second of the run, ``drop_frac`` the fraction of camera frames never rendered,
   ``latency_p50_ms``/``latency_p95_ms`` from the capture stamp to the recorder receiving the
   rendered frame (CLOCK_MONOTONIC, one host), ``rss_mb_total`` the peak summed RSS of the nodes.
   Run once with the demo's queues (reliable) and once with ``policy: latest`` everywhere (live).
2. Lockstep, twice with the same seeds: ``lockstep_identical`` when the partner messages of both
   runs carry the same arrays and fields (stamps aside).

Usage: python bench/e2e.py [--frames N]. Last stdout line: one JSON object.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import psutil
import yaml

from bus.bag import BagReader

REPO = Path(__file__).resolve().parents[1]


def run_graph(workdir: Path, name: str, frames: int, pacing: str, policy: str | None,
              topics: list[str]) -> tuple[Path, float, float]:
    """Launch demo.yaml plus a recorder; returns (bag, wall seconds, peak RSS MB of the nodes)."""
    bag = workdir / f"{name}.mcap"
    doc = {
        "include": [{"file": str(REPO / "launch" / "demo.yaml"), "set": {
            "camera.pacing": pacing, "camera.max_frames": frames, "renderer.video": str(workdir / f"{name}.avi")}}],
        "nodes": {"recorder": {"run": "bus.bag_nodes:Recorder", "policy": "reliable",
                               "params": {"path": str(bag), "topics": topics, "overwrite": True}}},
    }
    if policy:
        doc["policy"] = policy
    launch = workdir / f"{name}.yaml"
    launch.write_text(yaml.safe_dump(doc))
    env = {**os.environ, "COUNTERPART_HOME": tempfile.mkdtemp(prefix="cpe-", dir="/tmp"), "OMP_NUM_THREADS": "1"}
    t0 = time.monotonic()
    proc = subprocess.Popen([sys.executable, "-m", "bus.cli", "launch", str(launch)], cwd=REPO, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    peak = 0.0
    me = psutil.Process(proc.pid)
    while proc.poll() is None:
        try:
            rss = sum(c.memory_info().rss for c in me.children(recursive=True))
            peak = max(peak, rss / 2**20)
        except psutil.Error:
            pass
        time.sleep(0.2)
    if proc.returncode != 0:
        raise RuntimeError(f"{name}: the graph exited with {proc.returncode}")
    return bag, time.monotonic() - t0, peak


def realtime_figures(bag: Path, frames: int) -> dict[str, float]:
    rows = [(r.log_time, r.publish_time, r.sequence) for r in BagReader(bag).records(["rendered"])]
    log = np.array([r[0] for r in rows], dtype=np.int64)
    lat = (log - np.array([r[1] for r in rows], dtype=np.int64)) / 1e6
    span = (log[-1] - log[0]) / 1e9 if len(log) > 1 else float("nan")
    return {
        "rendered": len(rows),
        "fps_sustained": round((len(rows) - 1) / span, 2),
        "drop_frac": round(1 - len(rows) / frames, 4),
        "latency_p50_ms": round(float(np.percentile(lat, 50)), 1),
        "latency_p95_ms": round(float(np.percentile(lat, 95)), 1),
    }


def partner_outputs(bag: Path) -> list[tuple]:
    out = []
    for _, _, msg in BagReader(bag).messages(["partner"], decode_messages=True):
        out.append((msg.seq, msg.model, msg.behaviour, msg.joints.tobytes(), msg.ctrl.tobytes(), round(msg.strength, 9)))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=200, help="frames of the scene to play (25 fps)")
    args = ap.parse_args()
    import nodes.responder.node  # noqa: F401 (imported for its message types, to decode partners)
    from bus.cli_demo import ensure_models

    ensure_models()
    work = Path(tempfile.mkdtemp(prefix="e2e-"))
    out: dict[str, float | bool | int] = {"frames": args.frames, "load_avg_1min": round(os.getloadavg()[0], 2)}
    for name, policy in (("reliable", None), ("latest", "latest")):
        bag, wall, rss = run_graph(work, f"rt-{name}", args.frames, "realtime", policy, ["rendered"])
        figs = realtime_figures(bag, args.frames)
        print(f"{name:8s} realtime: {figs}  rss {rss:.0f} MB  wall {wall:.1f} s", file=sys.stderr)
        suffix = "" if name == "reliable" else "_latest"
        out.update({f"{k}{suffix}": v for k, v in figs.items()})
        out[f"rss_mb_total{suffix}"] = round(rss, 1)
    runs = []
    for i in range(2):
        bag, wall, _ = run_graph(work, f"lockstep-{i}", args.frames, "lockstep", None, ["partner"])
        runs.append(partner_outputs(bag))
        print(f"lockstep run {i}: {len(runs[-1])} partner messages in {wall:.1f} s", file=sys.stderr)
    out["lockstep_partner_messages"] = len(runs[0])
    out["lockstep_identical"] = bool(runs[0]) and runs[0] == runs[1]
    print(json.dumps(out))


if __name__ == "__main__":
    main()
