"""Small nodes for the runtime's multi-process tests: a counter source, relays and a recording sink."""

from __future__ import annotations

import json
import os
import time
from collections import deque
from dataclasses import replace

import cv2
import numpy as np

from counterpart.bus import Input, Node, Output, Param
from counterpart.messages import CameraInfo, Pose3D, message


@message("test.Number", 1)
class Number:
    value: float = 0.0
    payload: np.ndarray = np.zeros(0, np.uint8)


class Counter(Node):
    """Publishes ``count`` numbers 0, 1, 2, ... at ``rate`` Hz (0: as fast as possible)."""

    outputs = {"out": Output(Number)}
    params = {
        "count": Param(int, 100, "how many numbers", min=0),
        "rate": Param(float, 0.0, "messages per second, 0 for as fast as possible", min=0),
        "payload_bytes": Param(int, 0, "bytes of array payload per message", min=0),
        "hold_s": Param(float, 0.0, "seconds to wait after the last number before the end of stream", min=0),
    }

    def generate(self) -> None:
        period = 1.0 / self.p["rate"] if self.p["rate"] else 0.0
        payload = np.arange(self.p["payload_bytes"], dtype=np.uint64).astype(np.uint8)
        t_next = time.monotonic()
        for i in range(self.p["count"]):
            if self.stopping:
                return
            self.publish("out", Number(stamp=time.monotonic_ns(), seq=i, value=float(i), payload=payload))
            if period:
                t_next += period
                time.sleep(max(0.0, t_next - time.monotonic()))
        end = time.monotonic() + self.p["hold_s"]
        while not self.stopping and time.monotonic() < end:
            time.sleep(0.05)


class Relay(Node):
    """Forwards numbers multiplied by ``gain``, optionally sleeping ``delay_ms`` per message."""

    inputs = {"in": Input(Number)}
    outputs = {"out": Output(Number)}
    params = {
        "gain": Param(float, 1.0, "factor"),
        "delay_ms": Param(float, 0.0, "processing time to simulate", min=0),
    }

    def on_in(self, msg: Number) -> None:
        if self.p["delay_ms"]:
            time.sleep(self.p["delay_ms"] / 1000)
        self.publish("out", replace(msg, value=msg.value * self.p["gain"]))


class LateCamera(Node):
    """Forwards the graph's first camera at once and each later one only once the poses of ``pose``
    are ``frames`` past the frame it holds from: to the nodes subscribed here, the camera of a
    calibration node that runs that far behind the tracker, whatever the machine's speed.
    """

    inputs = {"camera_info": Input(CameraInfo), "pose": Input(Pose3D)}
    outputs = {"late_camera_info": Output(CameraInfo, "the same cameras, late", latched=True)}
    params = {"frames": Param(int, 5, "how far past a camera's frame the poses are when it is forwarded", min=0)}

    def setup(self) -> None:
        self.held: deque[CameraInfo] = deque()
        self.pose_seq = -1
        self.first = True

    def on_camera_info(self, msg: CameraInfo) -> None:
        self.held.append(msg)
        self._forward()

    def on_pose(self, msg: Pose3D) -> None:
        self.pose_seq = max(self.pose_seq, msg.seq)
        self._forward()

    def on_end(self) -> None:
        self._forward(end=True)

    def _forward(self, end: bool = False) -> None:
        while self.held and (end or self.first or self.pose_seq >= self.held[0].seq + self.p["frames"]):
            self.publish("late_camera_info", self.held.popleft())
            self.first = False


class Sink(Node):
    """Appends every received number (and its payload checksum) to ``path`` as JSON lines."""

    inputs = {"in": Input(Number)}
    params = {
        "path": Param(str, "", "output file (JSON lines)", check=lambda v: None if v else "must name a file"),
        "delay_ms": Param(float, 0.0, "processing time to simulate", min=0),
        "exit_after": Param(int, 0, "exit with exit_code after this many messages (0: never)", min=0),
        "exit_code": Param(int, 3, "the code for exit_after"),
    }

    def setup(self) -> None:
        self.f = open(self.p["path"], "a", buffering=1)
        self.f.write(
            json.dumps(
                {
                    "event": "start",
                    "pid": os.getpid(),
                    "nice": os.nice(0),
                    "omp": os.environ.get("OMP_NUM_THREADS"),
                    "opencv": cv2.getNumThreads(),
                }
            )
            + "\n"
        )

    def on_in(self, msg: Number) -> None:
        if self.p["delay_ms"]:
            time.sleep(self.p["delay_ms"] / 1000)
        self.f.write(json.dumps({"seq": msg.seq, "value": msg.value, "sum": int(msg.payload.sum())}) + "\n")
        self.n = getattr(self, "n", 0) + 1
        if self.n == self.p["exit_after"]:
            self.f.close()
            os._exit(self.p["exit_code"])

    def on_end(self) -> None:
        self.f.write(json.dumps({"event": "end", "drops": self._in["in"].drops}) + "\n")

    def teardown(self) -> None:
        self.f.close()


class FrameSink(Node):
    """Takes camera frames (used to provoke a type mismatch in launch checks)."""

    from counterpart.messages import Frame as _Frame

    inputs = {"in": Input(_Frame)}

    def on_in(self, msg) -> None:
        pass
