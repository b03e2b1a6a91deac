"""Helpers of the camera tests: a recording sink node (one JSON line per received frame) and test videos."""

from __future__ import annotations

import hashlib
import json
import time
from pathlib import Path

import cv2
import numpy as np

from counterpart.bus import Input, Node, Param
from counterpart.messages import Frame


class FrameSink(Node):
    """Appends ``{"seq", "sha1", "shape", "encoding", "stamp", "source_time", "source"}`` per frame
    to ``path`` (``sha1`` of the image bytes), then ``{"event": "end", "drops"}`` at end of stream.
    """

    inputs = {"frame": Input(Frame)}
    params = {"path": Param(str, "", "output file (JSON lines)", check=lambda v: None if v else "must name a file")}

    def setup(self) -> None:
        self.f = open(self.p["path"], "a", buffering=1)

    def on_frame(self, msg: Frame) -> None:
        self.f.write(
            json.dumps(
                {
                    "seq": msg.seq,
                    "sha1": hashlib.sha1(msg.image.tobytes()).hexdigest(),
                    "shape": list(msg.image.shape),
                    "encoding": msg.encoding,
                    "stamp": msg.stamp,
                    "source_time": msg.source_time,
                    "source": msg.source,
                    "received": time.monotonic_ns(),
                }
            )
            + "\n"
        )

    def on_end(self) -> None:
        self.f.write(json.dumps({"event": "end", "drops": self._in["frame"].drops}) + "\n")

    def teardown(self) -> None:
        self.f.close()


#: the real test video of /work/shared/data (tests skip when it is absent)
from tests.shared_data import VTEST  # noqa: E402,F401 (re-exported for the camera tests)


def write_video(path: Path, n: int = 12, size: tuple[int, int] = (96, 72), fps: float = 25.0) -> Path:
    """An MJPG .avi of moving gradients: every frame differs from the others."""
    w, h = size
    wr = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), fps, (w, h))
    if not wr.isOpened():
        raise RuntimeError(f"cv2.VideoWriter cannot write MJPG to {path}")
    yy, xx = np.mgrid[0:h, 0:w]
    for i in range(n):
        img = np.stack([(xx * 3 + i * 20) % 256, (yy * 3 + i * 7) % 256, np.full_like(xx, (i * 40) % 256)], -1)
        wr.write(img.astype(np.uint8))
    wr.release()
    return path


def cv2_frames(path: Path) -> list[np.ndarray]:
    cap = cv2.VideoCapture(str(path))
    out = []
    while True:
        ok, f = cap.read()
        if not ok:
            return out
        out.append(f)
