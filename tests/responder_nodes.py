"""Nodes for the responder's launch test: a Pose3D source that sends a Control half way, a sink."""

from __future__ import annotations

import json
import time

from counterpart.bus import Input, Node, Output, Param
from counterpart.messages import Control, Partner, Pose3D
from counterpart.messages.tracker import TrackedBody
from tests.responder_fixtures import planted_pair


class PoseSource(Node):
    """Publishes person A of a planted pair as Pose3D, ``frames`` frames; before frame
    ``control_at`` it publishes a Control (angry, strength 1, listener model when ``switch``).
    """

    outputs = {"pose": Output(Pose3D), "control": Output(Control)}
    params = {
        "frames": Param(int, 60, "frames", min=1),
        "control_at": Param(int, 30, "frame of the control", min=0),
        "switch": Param(str, "", "model to switch to ('' keeps it)"),
        "gap_at": Param(int, -1, "first frame without the person (-1: none)"),
        "gap": Param(int, 0, "frames without the person from gap_at", min=0),
    }

    def generate(self) -> None:
        tr = planted_pair(7, T=self.p["frames"])
        for t in range(self.p["frames"]):
            if self.stopping:
                return
            if t == self.p["control_at"]:
                # the control is a separate topic: give the responder time to take the poses before it
                # (it may still be loading its models), then to take the control before the next pose
                time.sleep(3.0)
                self.publish(
                    "control",
                    Control(
                        stamp=time.monotonic_ns(),
                        seq=t,
                        emotion="angry",
                        strength=1.0,
                        model=self.p["switch"] or None,
                        interest=1,
                    ),
                )
                time.sleep(0.5)
            gone = 0 <= t - self.p["gap_at"] < self.p["gap"]
            self.publish(
                "pose",
                Pose3D(
                    stamp=time.monotonic_ns(),
                    seq=t,
                    people=[] if gone else [TrackedBody(id=1, side="left", joints=tr.a[t])],
                ),
            )
            time.sleep(0.005)


class PartnerSink(Node):
    """Writes one JSON line per Partner."""

    inputs = {"partner": Input(Partner)}
    params = {"path": Param(str, "", "output JSON lines")}

    def setup(self) -> None:
        self.f = open(self.p["path"], "w", buffering=1)

    def on_partner(self, m: Partner) -> None:
        self.f.write(
            json.dumps(
                {
                    "seq": m.seq,
                    "model": m.model,
                    "emotion": m.emotion,
                    "strength": m.strength,
                    "speaker": m.speaker,
                    "interest": m.interest,
                    "shape": list(m.joints.shape),
                    "ctrl_shape": list(m.ctrl.shape),
                    "joints": m.joints.tolist(),
                    "behaviour": m.behaviour,
                    "file": m.avatar_file,
                    "frames": m.avatar_frames.tolist(),
                    "weights": m.avatar_weights.tolist(),
                }
            )
            + "\n"
        )

    def teardown(self) -> None:
        self.f.close()
