"""Nodes for the responder's launch test: a Pose3D source that sends a Control half way (and the
graph's camera, as a calibration node does), a sink.
"""

from __future__ import annotations

import json
import time

import numpy as np

from counterpart.body.camera import Camera, camera_to_info
from counterpart.bus import Input, Node, Output, Param
from counterpart.messages import CameraInfo, Control, Partner, Pose3D, SocialSignals
from counterpart.messages.labeller import PersonSignals
from counterpart.messages.tracker import TrackedBody
from tests.responder_fixtures import planted_pair


def bearing_camera(joints: np.ndarray, bearing_deg: float) -> Camera:
    """A 320x240 camera 4 m from the body ``joints`` (14, 3) (their mean), 1.6 m high, at ``bearing_deg``
    round them (0: looking along -Z, no yaw), looking at their mean.
    """
    mid = np.asarray(joints, np.float64).mean(axis=0)
    b = np.deg2rad(bearing_deg)
    return Camera.look_at(mid + [4.0 * np.sin(b), 1.6 - mid[1], 4.0 * np.cos(b)], mid, 55.0, 320, 240)


class PoseSource(Node):
    """Publishes person A of a planted pair as Pose3D, ``frames`` frames at 25 fps (or the same
    seconds at ``fps``), and, from ``nod_s``, A's nod as SocialSignals; before frame
    ``control_at`` it publishes a Control (angry, strength 1, listener model when ``switch``). With
    each pose it publishes a camera 4 m from person A at ``bearing_deg`` round them (0: from +Z),
    for frames from seq 0 (a source's ``generate`` does not serve late subscribers their latched
    message, as a calibration node's loop does: sent on every frame, it reaches them).
    """

    outputs = {
        "pose": Output(Pose3D),
        "control": Output(Control),
        "camera_info": Output(CameraInfo, latched=True),
        "signals": Output(SocialSignals),
    }
    params = {
        "frames": Param(int, 60, "frames", min=1),
        "control_at": Param(int, 30, "frame of the control", min=0),
        "switch": Param(str, "", "model to switch to ('' keeps it)"),
        "gap_at": Param(int, -1, "first frame without the person (-1: none)"),
        "gap": Param(int, 0, "frames without the person from gap_at", min=0),
        "bearing_deg": Param(float, 0.0, "the camera's bearing round person A, degrees"),
        "fps": Param(float, 0.0, "the pair resampled to this rate, said in each pose (0: its own 25, unsaid)", min=0),
        "nod_s": Param(float, -1.0, "A nods for half a second from this second on (signals before each pose)"),
        "signals_after": Param(bool, False, "each frame's signals 20 ms after its pose, as a labeller sends them"),
    }

    def generate(self) -> None:
        tr = planted_pair(7, T=self.p["frames"])
        tr = tr.resample(self.p["fps"]) if self.p["fps"] > 0 else tr
        camera = bearing_camera(tr.a[0], self.p["bearing_deg"])
        for t in range(len(tr.a)):
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
            signals = None
            if self.p["nod_s"] >= 0:
                nod = 0.0 <= t / (self.p["fps"] or tr.fps) - self.p["nod_s"] < 0.5
                people = [PersonSignals(id=1, names=["nod"], scores=np.float32([nod]), labels=np.int8([nod]))]
                signals = SocialSignals(stamp=t, seq=t, people=people)
            if signals is not None and not self.p["signals_after"]:
                self.publish("signals", signals)
            self.publish("camera_info", camera_to_info(camera, time.monotonic_ns()))
            self.publish(
                "pose",
                Pose3D(
                    stamp=time.monotonic_ns(),
                    seq=t,
                    people=[] if gone else [TrackedBody(id=1, side="left", joints=tr.a[t])],
                    fps=self.p["fps"],
                ),
            )
            if signals is not None and self.p["signals_after"]:
                time.sleep(0.02)
                self.publish("signals", signals)
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
