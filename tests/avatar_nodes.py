"""Nodes for the avatar's launch test: a speaker who nods at set frames (Pose3D + SocialSignals), and a
sink that writes each Partner's avatar fields."""
from __future__ import annotations

import json
import time

import numpy as np

from body.kinematics import forward_kinematics
from body.pose import neutral_pose
from bus import Input, Node, Output, Param
from messages import Partner, Pose3D, SocialSignals
from messages.labeller import PersonSignals
from messages.tracker import TrackedBody


class NoddingSpeaker(Node):
    """A person standing on the left facing right; from frame ``nod_from`` on they nod (signals)."""

    outputs = {"pose": Output(Pose3D), "signals": Output(SocialSignals)}
    params = {"frames": Param(int, 80, "frames", min=1), "nod_from": Param(int, 30, "first nodding frame", min=0)}

    def generate(self) -> None:
        joints = forward_kinematics(neutral_pose(x=-0.8, z=0.0, yaw=np.pi / 2))[0].astype(np.float32)
        names = ["nod", "shake", "gaze_at_other", "activity", "talking", "laughing"]
        for t in range(self.p["frames"]):
            if self.stopping:
                return
            stamp = time.monotonic_ns()
            nod = int(t >= self.p["nod_from"])
            self.publish("signals", SocialSignals(stamp=stamp, seq=t, people=[PersonSignals(
                id=1, names=names, scores=np.zeros(6, np.float32), labels=np.array([nod, 0, 1, 0, 1, 0], np.int8))]))
            self.publish("pose", Pose3D(stamp=stamp, seq=t, people=[TrackedBody(id=1, side="left", joints=joints)]))
            time.sleep(0.005)


class AvatarSink(Node):
    """Writes one JSON line per Partner with its avatar fields."""

    inputs = {"partner": Input(Partner)}
    params = {"path": Param(str, "", "output JSON lines")}

    def setup(self) -> None:
        self.f = open(self.p["path"], "w", buffering=1)

    def on_partner(self, m: Partner) -> None:
        self.f.write(json.dumps({"seq": m.seq, "model": m.model, "behaviour": m.behaviour, "file": m.avatar_file,
                                 "frames": np.asarray(m.avatar_frames).tolist(),
                                 "weights": np.asarray(m.avatar_weights).tolist(),
                                 "joints": np.asarray(m.joints).tolist()}) + "\n")

    def teardown(self) -> None:
        self.f.close()
