"""A source for the contract test: frames with one person in them, as the tracker and the
silhouette node would describe that person (Pose3D and Silhouettes of the same seq), looped.
"""

from __future__ import annotations

import time

import numpy as np

from counterpart.body.camera import default_camera
from counterpart.bus import Node, Output, Param
from counterpart.messages import Frame, Pose3D, Silhouettes
from counterpart.messages.silhouette import PersonShape
from counterpart.messages.tracker import TrackedBody
from counterpart.nodes.responder.shapes import silhouette_track
from tests.renderer_nodes import scene_frame
from tests.responder_fixtures import planted_pair

W, H = 160, 120


class PersonSource(Node):
    """``count`` frames at ``rate`` Hz of person A of a planted pair (looped every 120 frames)."""

    outputs = {"frame": Output(Frame), "pose": Output(Pose3D), "silhouettes": Output(Silhouettes)}
    params = {
        "count": Param(int, 100000, "frames", min=1),
        "rate": Param(float, 20.0, "frames per second", min=1.0),
    }

    def generate(self) -> None:
        tr = planted_pair(7, T=120)
        shapes = silhouette_track(tr.a, default_camera(W, H))
        t_next = time.monotonic()
        for seq in range(self.p["count"]):
            if self.stopping:
                return
            t = seq % len(tr.a)
            stamp = time.monotonic_ns()
            self.publish("frame", Frame(stamp=stamp, seq=seq, image=scene_frame(seq, W, H), source="test:person"))
            self.publish(
                "pose",
                Pose3D(stamp=stamp, seq=seq, fps=25.0, people=[TrackedBody(id=1, side="left", joints=tr.a[t])]),
            )
            shape = PersonShape(
                id=1,
                side="left",
                ctrl=shapes.ctrl[t].astype(np.float32),
                centroid=shapes.pos[t].astype(np.float32),
                height=float(shapes.height[t]),
            )
            self.publish("silhouettes", Silhouettes(stamp=stamp, seq=seq, people=[shape], width=W, height=H))
            t_next += 1.0 / self.p["rate"]
            time.sleep(max(0.0, t_next - time.monotonic()))
