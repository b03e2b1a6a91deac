"""Simulator rendering speed at 320x240 on one core (noise, shadows, ground truth included).

Usage: python bench/simulator.py (from the repository root, with the project installed). Prints one line per scenario and, last, one JSON object:
{"fps_median": ..., "fps": {scenario: ...}, "ms_per_frame_median": ..., "size": [320, 240], ...}
"""

from __future__ import annotations

import json
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from counterpart.sim.scenarios import SCENARIOS  # noqa: E402
from counterpart.sim.stream import open_stream  # noqa: E402


def main() -> None:
    cv2.setNumThreads(1)
    fps = {}
    for name in SCENARIOS:
        kw = {"duration": 8.0} if name == "conversation" else {}
        s = open_stream(name, seed=0, width=320, height=240, **kw)
        s.render(0)  # warm-up: first chunk of geometry, imports
        t0 = time.perf_counter()
        for i in range(s.n_frames):
            s.render(i)
        dt = time.perf_counter() - t0
        fps[name] = s.n_frames / dt
        print(f"{name:13s} {s.n_frames:4d} frames  {fps[name]:7.1f} frames/s")
    med = float(np.median(list(fps.values())))
    print(
        json.dumps(
            {
                "fps_median": round(med, 1),
                "fps": {k: round(v, 1) for k, v in fps.items()},
                "ms_per_frame_median": round(1000 / med, 2),
                "size": [320, 240],
                "threads": 1,
                "load_avg_1min": os.getloadavg()[0],
            }
        )
    )


if __name__ == "__main__":
    main()
