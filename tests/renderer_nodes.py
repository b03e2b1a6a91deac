"""Helpers of the renderer tests: a frame + partner source, a control-following responder, and the
synthetic scene they draw (shared with the tests so that expected pixels can be computed).
"""

from __future__ import annotations

import json
import time
from typing import Any

import numpy as np

from counterpart.body.kinematics import forward_kinematics
from counterpart.body.pose import DOF_INDEX, neutral_pose
from counterpart.bus import LATEST, RELIABLE, Input, Node, Output, Param
from counterpart.messages import Control, Frame, Partner


def scene_frame(seq: int, width: int = 160, height: int = 120) -> np.ndarray:
    """A dark grey frame with a bright bar that moves along the top rows (every frame differs)."""
    img = np.full((height, width, 3), 60, np.uint8)
    x = (seq * 3) % max(width - 8, 1)
    img[2:8, x : x + 8] = 255
    return img


def partner_joints(seq: int = 0) -> np.ndarray:
    """(14, 3) metres: a standing partner right of centre, raising its right arm slowly."""
    P = neutral_pose(x=0.6, yaw=-1.2)
    P[DOF_INDEX["r_shoulder_flex"]] = 0.8 + 0.01 * (seq % 40)
    return forward_kinematics(P)[0].astype(np.float32)


class SceneSource(Node):
    """Publishes ``count`` frames of :func:`scene_frame` at ``rate`` Hz (0: unpaced) and, when
    ``partner`` is true, a Partner of the same seq with :func:`partner_joints` (of every
    ``partner_every``-th frame only).
    """

    params = {
        "count": Param(int, 30, "frames", min=1),
        "rate": Param(float, 0.0, "frames per second, 0: as fast as the consumers take them", min=0.0),
        "width": Param(int, 160, "image width", min=16),
        "height": Param(int, 120, "image height", min=16),
        "partner": Param(bool, True, "also publish the partner"),
        "partner_every": Param(
            int, 1, "publish the partner of every Nth frame only (0: the port, never a partner)", min=0
        ),
        "emotion": Param(str, "neutral", "the partner's emotion"),
        "strength": Param(float, 0.0, "the partner's emotion strength"),
    }

    @classmethod
    def ports(cls, params: dict[str, Any]) -> tuple[dict[str, Input], dict[str, Output]]:
        outs = {"frame": Output(Frame)}
        if params["partner"]:
            outs["partner"] = Output(Partner)
        return {}, outs

    def generate(self) -> None:
        p = self.p
        t_next = time.monotonic()
        for seq in range(p["count"]):
            if self.stopping:
                return
            stamp = time.monotonic_ns()
            self.publish(
                "frame",
                Frame(
                    stamp=stamp,
                    seq=seq,
                    image=scene_frame(seq, p["width"], p["height"]),
                    source="test:scene",
                    source_time=seq / 25.0,
                ),
            )
            if p["partner"] and p["partner_every"] and seq % p["partner_every"] == 0:
                self.publish(
                    "partner",
                    Partner(
                        stamp=stamp,
                        seq=seq,
                        model="test",
                        joints=partner_joints(seq),
                        emotion=p["emotion"],
                        strength=p["strength"],
                    ),
                )
            if p["rate"]:
                # a late frame starts the schedule again rather than bursting to catch up: on a
                # loaded machine the rate drops below ``rate``, never above it
                t_next = max(t_next + 1.0 / p["rate"], time.monotonic())
                time.sleep(max(0.0, t_next - time.monotonic()))


class ControlledResponder(Node):
    """A stand-in responder: a Partner for every frame whose emotion and strength follow the
    Control messages received; each Control is appended to ``path`` as a JSON line.
    """

    inputs = {"frame": Input(Frame, RELIABLE), "control": Input(Control, LATEST, awaits_end=False)}
    outputs = {"partner": Output(Partner)}
    params = {"path": Param(str, "", "JSON lines of received controls", check=lambda v: None if v else "needed")}

    def setup(self) -> None:
        self.f = open(self.p["path"], "a", buffering=1)
        self.emotion, self.strength = "neutral", 0.0

    def on_control(self, msg: Control) -> None:
        self.f.write(
            json.dumps(
                {k: getattr(msg, k) for k in ("model", "speaker", "interest", "emotion", "strength", "overlays")}
            )
            + "\n"
        )
        self.emotion = msg.emotion or self.emotion
        self.strength = msg.strength if msg.strength is not None else self.strength

    def on_frame(self, msg: Frame) -> None:
        self.publish(
            "partner",
            Partner(
                stamp=msg.stamp,
                seq=msg.seq,
                model="test",
                joints=partner_joints(msg.seq),
                emotion=self.emotion,
                strength=self.strength,
            ),
        )

    def teardown(self) -> None:
        if hasattr(self, "f"):
            self.f.close()
