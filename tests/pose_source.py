"""A stand-in for the tracker in launch tests of its consumers: Silhouettes in, Pose3D out.

Not a tracker: each silhouette person becomes a standing skeleton (14 joints, metres) at a fixed
depth, placed left to right like the silhouettes and facing the other person (+X for the left one),
so that 3D-only signals (gaze) become known. Only frames with ``seq % every == 0`` get a pose, so a
consumer sees the pose topic skip frames, as a tracker that gives up on a frame does.
"""

from __future__ import annotations

import numpy as np

from counterpart.bus import Input, Node, Output, Param
from counterpart.messages import Pose3D, Silhouettes
from counterpart.messages.tracker import TrackedBody

#: a standing person facing +Z (left shoulder at +X), project joint order, metres, Y up
STANDING = np.array(
    [
        [0.0, 1.70, 0.0],
        [0.0, 1.50, 0.0],
        [0.20, 1.45, 0.0],
        [0.25, 1.20, 0.0],
        [0.25, 0.95, 0.0],
        [-0.20, 1.45, 0.0],
        [-0.25, 1.20, 0.0],
        [-0.25, 0.95, 0.0],
        [0.10, 0.95, 0.0],
        [0.10, 0.50, 0.0],
        [0.10, 0.05, 0.0],
        [-0.10, 0.95, 0.0],
        [-0.10, 0.50, 0.0],
        [-0.10, 0.05, 0.0],
    ]
)


def facing(yaw: float) -> np.ndarray:
    """STANDING turned by ``yaw`` radians about +Y (0 faces +Z, pi/2 faces +X)."""
    c, s = np.cos(yaw), np.sin(yaw)
    rot = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    return STANDING @ rot.T


class PoseSource(Node):
    inputs = {"silhouettes": Input(Silhouettes)}
    outputs = {"pose": Output(Pose3D)}
    params = {
        "every": Param(int, 2, "publish a pose for frames with seq % every == 0", min=1),
        "metres_per_px": Param(float, 0.02, "image x to world x", min=1e-6),
    }

    def on_silhouettes(self, msg: Silhouettes) -> None:
        if msg.seq % self.p["every"]:
            return
        bodies = []
        for p in msg.people:
            x = (float(p.centroid[0]) - msg.width / 2) * self.p["metres_per_px"]
            joints = facing(np.pi / 2 if p.side == "left" else -np.pi / 2) + [x, 0.0, 3.0]
            bodies.append(TrackedBody(id=p.id, side=p.side, joints=joints.astype(np.float32)))
        self.publish("pose", Pose3D(stamp=msg.stamp, seq=msg.seq, people=bodies))


NODE = PoseSource
