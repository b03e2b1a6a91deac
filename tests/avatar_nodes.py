"""A node for the avatar's launch test: a speaker who nods at set frames (Pose3D + SocialSignals)."""

from __future__ import annotations

import time

import numpy as np

from counterpart.body.kinematics import forward_kinematics
from counterpart.body.pose import neutral_pose
from counterpart.bus import Node, Output, Param
from counterpart.messages import Pose3D, SocialSignals
from counterpart.messages.labeller import PersonSignals
from counterpart.messages.tracker import TrackedBody


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
            self.publish(
                "signals",
                SocialSignals(
                    stamp=stamp,
                    seq=t,
                    people=[
                        PersonSignals(
                            id=1,
                            names=names,
                            scores=np.zeros(6, np.float32),
                            labels=np.array([nod, 0, 1, 0, 1, 0], np.int8),
                        )
                    ],
                ),
            )
            self.publish("pose", Pose3D(stamp=stamp, seq=t, people=[TrackedBody(id=1, side="left", joints=joints)]))
            time.sleep(0.005)
