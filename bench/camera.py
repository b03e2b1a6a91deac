"""Camera node throughput: file replay through the bus vs a raw ``cv2.VideoCapture`` read loop.

Usage: python bench/camera.py [--video FILE] [--frames N] [--runs R] [--out FILE]

For each of R rounds (interleaved, so both see the same machine load):
  * raw: ``cv2.VideoCapture(file).read()`` of the first N frames in a loop (decode only);
  * camera, pacing lockstep and fast (and lockstep with ``prefetch: 0``, decoding inline):
    ``counterpart launch`` of camera -> counting sink (reliable policy), throughput from the sink's
    receive times of the first and last frame (process start-up excluded, as the raw loop excludes
    opening the file).
Figures are medians over the rounds; ``throughput_ratio`` is the median of the per-round
ratios. On a small shared machine the two-process pipeline suffers more from other load than the
one-thread raw loop: compare runs at similar ``load_avg_1min``. The video is ../shared/data/video/vtest.avi (768x576 MP43)
when present, else a generated 640x480 MJPG clip. Last stdout line: one JSON object with
``camera_fps`` (lockstep), ``fast_fps``, ``no_prefetch_fps``, ``raw_fps``, ``throughput_ratio`` (camera / raw; target
>= 0.8), ``sim_fps`` (null until the simulator exists).
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

import cv2
import numpy as np
import yaml

from counterpart.bus import Input, Node, Param
from counterpart.messages import Frame

REPO = Path(__file__).resolve().parents[1]
VTEST = REPO.parent / "shared" / "data" / "video" / "vtest.avi"


class CountSink(Node):
    """Counts frames; at end of stream writes {"count", "first_ns", "last_ns", "drops", "bytes"} to ``path``."""

    inputs = {"frame": Input(Frame)}
    params = {"path": Param(str, "", "output JSON file", check=lambda v: None if v else "must name a file")}

    def setup(self) -> None:
        self.count = 0
        self.bytes = 0
        self.first_ns = self.last_ns = 0

    def on_frame(self, msg: Frame) -> None:
        now = time.monotonic_ns()
        if not self.count:
            self.first_ns = now
        self.last_ns = now
        self.count += 1
        self.bytes += msg.image.nbytes

    def on_end(self) -> None:
        Path(self.p["path"]).write_text(
            json.dumps(
                {
                    "count": self.count,
                    "first_ns": self.first_ns,
                    "last_ns": self.last_ns,
                    "drops": self._in["frame"].drops,
                    "bytes": self.bytes,
                }
            )
        )


def generated_video(folder: Path, n: int = 400, size: tuple[int, int] = (640, 480), fps: float = 25.0) -> Path:
    """A moving-texture MJPG clip: decodes at a realistic cost, unlike a flat image."""
    path = folder / "bench.avi"
    w, h = size
    wr = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), fps, (w, h))
    rng = np.random.default_rng(0)
    base = cv2.GaussianBlur(rng.integers(0, 256, (h * 2, w * 2, 3), dtype=np.uint8), (0, 0), 3)
    for i in range(n):
        wr.write(np.ascontiguousarray(base[i % h : i % h + h, (2 * i) % w : (2 * i) % w + w]))
    wr.release()
    return path


def raw_fps(video: Path, frames: int) -> tuple[float, int]:
    cap = cv2.VideoCapture(str(video))
    ok, _ = cap.read()
    n = 1 if ok else 0
    t0 = time.perf_counter()
    while n < frames:
        ok, _ = cap.read()
        if not ok:
            break
        n += 1
    dt = time.perf_counter() - t0
    cap.release()
    return (n - 1) / dt, n


def camera_fps(video: Path, frames: int, pacing: str, work: Path, prefetch: int = 4) -> tuple[float, dict]:
    out = work / f"count-{pacing}.json"
    out.unlink(missing_ok=True)
    doc = {
        "nodes": {
            "camera": {
                "run": "counterpart.nodes.camera",
                "params": {"source": f"file:{video}", "pacing": pacing, "max_frames": frames, "prefetch": prefetch},
            },
            "sink": {"run": "bench.camera:CountSink", "params": {"path": str(out)}, "policy": "reliable"},
        }
    }
    file = work / "graph.yaml"
    file.write_text(yaml.safe_dump(doc))
    r = subprocess.run(
        [sys.executable, "-m", "counterpart.bus.cli", "launch", str(file)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=300,
    )
    if r.returncode != 0 or not out.exists():
        raise RuntimeError(f"camera graph failed ({r.returncode}):\n{r.stdout}{r.stderr}")
    res = json.loads(out.read_text())
    fps = (res["count"] - 1) / ((res["last_ns"] - res["first_ns"]) / 1e9)
    return fps, res


def sim_fps(frames: int) -> float | None:
    """Rendering fps of the built-in simulator's default scenario, or None while ``sim`` has no
    ``open_stream`` (TODO(sim): this figure appears by itself once the simulator lands).
    """
    from counterpart.nodes.camera.sources import SourceError, make_source

    try:
        src = make_source("sim:handshake")
        src.open()
    except SourceError as exc:
        print(f"sim_fps: {exc}", file=sys.stderr)
        return None
    n = min(frames, src.frame_count or frames)
    t0 = time.perf_counter()
    for _ in range(n):
        if not src.read()[0]:
            break
    fps = n / (time.perf_counter() - t0)
    src.close()
    return round(fps, 1)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--video", type=Path, default=None, help="video file (default: vtest.avi or a generated clip)")
    ap.add_argument("--frames", type=int, default=795, help="frames per run (capped by the file)")
    ap.add_argument("--runs", type=int, default=5, help="rounds; figures are medians")
    ap.add_argument("--out", type=Path, default=None, help="also write the JSON here")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-camera-") as tmp:
        work = Path(tmp)
        video = args.video or (VTEST if VTEST.exists() else generated_video(work))
        cap = cv2.VideoCapture(str(video))
        total = int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) or args.frames
        size = (int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)), int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT)))
        cap.release()
        frames = min(args.frames, total)
        raw, lock, fast, inline = [], [], [], []
        for i in range(args.runs):
            r, n = raw_fps(video, frames)
            c, res_l = camera_fps(video, frames, "lockstep", work)
            f, res_f = camera_fps(video, frames, "fast", work)
            c0, res_0 = camera_fps(video, frames, "lockstep", work, prefetch=0)
            for res in (res_l, res_f, res_0):
                if res["count"] != n or res["drops"]:
                    raise RuntimeError(f"sink got {res['count']} frames ({res['drops']} drops), raw read {n}")
            raw.append(r), lock.append(c), fast.append(f), inline.append(c0)
            print(
                f"round {i + 1}/{args.runs}: raw {r:.0f} fps, camera lockstep {c:.0f} fps, fast {f:.0f} fps, "
                f"lockstep without prefetch {c0:.0f} fps",
                file=sys.stderr,
            )
    result = {
        "video": str(video) if video == VTEST or args.video else "generated MJPG",
        "size": list(size),
        "frames": frames,
        "runs": args.runs,
        "cpus": os.cpu_count(),
        "raw_fps": round(float(np.median(raw)), 1),
        "camera_fps": round(float(np.median(lock)), 1),
        "fast_fps": round(float(np.median(fast)), 1),
        "no_prefetch_fps": round(float(np.median(inline)), 1),
        # per round (same load for both), then the median over rounds
        "throughput_ratio": round(float(np.median(np.divide(lock, raw))), 3),
        "load_avg_1min": round(os.getloadavg()[0], 2),
        "mbytes_per_s": round(float(np.median(lock)) * size[0] * size[1] * 3 / 1e6, 1),
        "sim_fps": sim_fps(frames),
    }
    line = json.dumps(result)
    if args.out:
        args.out.write_text(line + "\n")
    print(line)


if __name__ == "__main__":
    main()
