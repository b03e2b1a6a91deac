"""The labeller node: social signals per person and frame (Okwechime et al.) on topic ``signals``.

Inputs, paired by ``seq`` (:class:`~nodes.labeller.pairing.SeqPairer`):

* ``silhouettes`` (required): the 2D fallback (head reference point, centroid, height, spline) and
  each person's box for the face search;
* ``pose`` when ``use_tracker`` (default): the tracker's 3D joints, used for a person whenever they
  are present and not lost; a frame whose pose never comes (the pose topic went past it) is
  labelled from its silhouettes;
* ``frame`` when ``use_face``: the camera image for talking/laughing.

Every released frame gives one SocialSignals with the seq and stamp of its silhouettes, one
PersonSignals per person (``source`` ``3d`` or ``2d``); what the input cannot support is UNKNOWN
(-1), never guessed. Run in a graph (``run: nodes.labeller``) or alone::

    python -m nodes.labeller --param use_tracker=false
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from body.pose import DOF, DOF_INDEX
from bus import Input, Node, Output, Param, ParamError
from messages import Frame, Pose3D, Silhouettes, SocialSignals
from messages.labeller import PersonSignals

from .labeller import PersonObservation, SocialLabeller
from .pairing import Paired, SeqPairer
from .signals import SIGNALS

#: the spline size the 2D activity detector reads (upper-body control points of 32)
ACTIVITY_CTRL = 32

_HEAD_TURN, _HEAD_NOD = DOF_INDEX["head_turn"], DOF_INDEX["head_nod"]


def head_angles(pose: np.ndarray) -> tuple[float | None, float | None]:
    """(head_yaw, head_pitch) relative to the torso (rad) from a tracker's pose vector
    (``body.pose``: ``head_turn``, ``head_nod``); (None, None) when the pose is not a finite
    (DOF,) vector (a tracker that publishes joints only)."""
    p = np.asarray(pose, dtype=np.float64)
    if p.shape != (DOF,) or not np.isfinite(p[[_HEAD_TURN, _HEAD_NOD]]).all():
        return None, None
    return float(p[_HEAD_TURN]), float(p[_HEAD_NOD])


def observations(sil: Silhouettes, pose: Pose3D | None) -> tuple[dict[int, PersonObservation], dict[int, str]]:
    """Per person id: what the silhouettes (and pose, when given) say about them, and their side.

    A tracked body that is lost or has non-finite joints gives no 3D input (the labeller then falls
    back to the person's silhouette). The head yaw and pitch come from the body's ``pose`` vector
    when it has one (:func:`head_angles`): shakes are head rotations that barely move the head
    joint, so they are seen in the yaw, not in the joints. Control points other than (32, 2) are left out (2D activity
    UNKNOWN), as are outlines the silhouette node could not trace.
    """
    obs: dict[int, PersonObservation] = {}
    sides: dict[int, str] = {}
    for p in sil.people:
        ctrl = np.asarray(p.ctrl, dtype=np.float64)
        ref = np.asarray(p.ref_point, dtype=np.float64)
        cen = np.asarray(p.centroid, dtype=np.float64)
        has_head = ref.shape == (2,) and cen.shape == (2,) and bool(np.isfinite(ref).all() and np.isfinite(cen).all())
        obs[p.id] = PersonObservation(
            head_px=ref if has_head else None,
            ref_px=cen if has_head else None,
            height_px=float(p.height) if has_head and p.height > 0 else None,
            control_points=ctrl if ctrl.shape == (ACTIVITY_CTRL, 2) and np.isfinite(ctrl).all() else None,
            box=tuple(int(v) for v in p.bbox) if p.bbox[2] > 0 and p.bbox[3] > 0 else None,
        )
        sides[p.id] = p.side
    for b in pose.people if pose is not None else ():
        joints = np.asarray(b.joints, dtype=np.float64)
        if b.lost or joints.shape != (14, 3) or not np.isfinite(joints).all():
            continue
        base = obs.get(b.id, PersonObservation())
        head_yaw, head_pitch = head_angles(b.pose)
        obs[b.id] = PersonObservation(joints=joints, head_yaw=head_yaw, head_pitch=head_pitch,
                                      head_px=base.head_px,
                                      ref_px=base.ref_px, height_px=base.height_px,
                                      control_points=base.control_points, box=base.box)
        sides.setdefault(b.id, b.side)
    return obs, sides


def signals_message(seq: int, stamp: int, labels: dict[Any, dict[str, tuple[float, int]]],
                    obs: dict[int, PersonObservation], sides: dict[int, str]) -> SocialSignals:
    """One SocialSignals from ``SocialLabeller.update`` output, people in id order."""
    people = []
    for pid in sorted(labels):
        res = labels[pid]
        people.append(PersonSignals(
            id=int(pid), side=sides.get(pid, "left"), names=list(SIGNALS),
            scores=np.array([res[s][0] for s in SIGNALS], np.float32),
            labels=np.array([res[s][1] for s in SIGNALS], np.int8),
            source="3d" if obs[pid].has_3d() else "2d",
        ))
    return SocialSignals(stamp=stamp, seq=seq, people=people)


class Labeller(Node):
    """Labels nod, shake, gaze at the other, activity, talking and laughing for every person."""

    inputs = {
        "silhouettes": Input(Silhouettes, doc="people of each frame (2D input, boxes)"),
        "pose": Input(Pose3D, doc="tracked 3D bodies (3D input); only with use_tracker"),
        "frame": Input(Frame, doc="camera image for talking/laughing; only with use_face"),
    }
    outputs = {"signals": Output(SocialSignals, "one per frame with silhouettes; seq and stamp of that frame")}
    params = {
        "fps": Param(float, 25.0, "frame rate of the stream (Hz): sets every window in frames", min=1e-3, max=1e4),
        "head_window_s": Param(float, 1.6, "FFT window of nod/shake (s)", min=0.05, max=60.0),
        "gaze_threshold_deg": Param(float, 30.0, "largest angle between gaze and the direction to the other "
                                    "still counted as looking at them (degrees)",
                                    check=lambda v: None if 0.0 < v < 180.0 else "must be in (0, 180) degrees"),
        "use_tracker": Param(bool, True, "subscribe to pose (Pose3D) and use 3D joints where tracked"),
        "use_face": Param(bool, False, "subscribe to frame (Frame) for talking/laughing from faces"),
        "max_pending": Param(int, 8, "frames with silhouettes held back waiting for a slow pose or frame "
                             "before going on without it", min=1, max=1000),
        "max_ahead": Param(int, 64, "frames of pose/camera messages kept while their silhouettes are still "
                           "to come (memory: camera frames are large); older ones are discarded", min=0, max=10_000),
    }

    @classmethod
    def validate_params(cls, given: dict[str, Any], where: str = "") -> dict[str, Any]:
        p = super().validate_params(given, where)
        try:  # the windows in frames must be long enough for their detectors
            SocialLabeller(p["fps"], p["head_window_s"], math.radians(p["gaze_threshold_deg"]))
        except ValueError as exc:
            prefix = f"{where}: " if where else ""
            raise ParamError(f"{prefix}parameters 'fps' and 'head_window_s' (fps {p['fps']}, head_window_s "
                             f"{p['head_window_s']}): {exc}") from None
        return p

    @classmethod
    def ports(cls, params: dict[str, Any]) -> tuple[dict[str, Input], dict[str, Output]]:
        ins = {"silhouettes": cls.inputs["silhouettes"]}
        if params["use_tracker"]:
            ins["pose"] = cls.inputs["pose"]
        if params["use_face"]:
            ins["frame"] = cls.inputs["frame"]
        return ins, dict(cls.outputs)

    def setup(self) -> None:
        p = self.p
        self.labeller = SocialLabeller(p["fps"], p["head_window_s"], math.radians(p["gaze_threshold_deg"]))
        self.pairer = SeqPairer(list(self.ports(p)[0]), "silhouettes", p["max_pending"], p["max_ahead"])
        self.last_seq = -1
        self.sources = {"3d": 0, "2d": 0}
        self._warned_ctrl = False

    def on_message(self, port: str, msg: Any) -> None:
        for item in self.pairer.add(port, msg.seq, msg):
            self._label(item)
        # a side input that ended (tracker gone) must not hold frames back
        for other, sub in self._in.items():
            if sub.ended and other != port:
                for item in self.pairer.end(other):
                    self._label(item)

    def _label(self, item: Paired) -> None:
        if item.restart:
            self.log.info("seq went back to %d: the stream restarted; forgetting every person", item.seq)
            self.labeller.reset()
        elif self.last_seq >= 0 and item.seq > self.last_seq + 1:
            self.labeller.skip(item.seq - self.last_seq - 1)
        self.last_seq = item.seq
        sil: Silhouettes = item.msgs["silhouettes"]
        obs, sides = observations(sil, item.msgs.get("pose"))
        odd = [np.shape(p.ctrl) for p in sil.people if np.size(p.ctrl) and np.shape(p.ctrl) != (ACTIVITY_CTRL, 2)]
        if odd and not self._warned_ctrl:
            self._warned_ctrl = True
            self.log.warning("silhouettes carry splines of shape %s; 2D activity needs (%d, 2) and stays UNKNOWN "
                             "(set the silhouette node's n_ctrl to %d)", odd[0], ACTIVITY_CTRL, ACTIVITY_CTRL)
        frame: Frame | None = item.msgs.get("frame")
        labels = self.labeller.update(obs, image=None if frame is None else frame.image)
        out = signals_message(item.seq, sil.stamp, labels, obs, sides)
        for ps in out.people:
            self.sources[ps.source] += 1
        self.publish("signals", out)

    def on_end(self) -> None:
        for item in self.pairer.flush():
            self._label(item)
        st = self.pairer.stats
        missing = ", ".join(f"{n} without {p}" for p, n in st.missing.items() if n)
        self.log.info("labelled %d frames (%s; people: %d from 3D, %d from 2D); %d dropped without silhouettes, "
                      "%d released early, %d side messages over max_ahead, %d late messages, %d restarts",
                      st.released, missing or "every input present", self.sources["3d"], self.sources["2d"],
                      st.unpaired, st.forced, st.overflow, st.late, st.restarts)


NODE = Labeller

if __name__ == "__main__":
    Labeller.main()
