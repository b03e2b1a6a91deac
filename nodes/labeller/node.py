"""The labeller node: social signals per person and frame (Okwechime et al.) on topic ``signals``.

Inputs, paired by ``seq`` (the runtime's :class:`~counterpart.bus.pairing.Pairing`; its counters are the
``paired_*`` figures of the node's stats):

* ``silhouettes`` (required): the 2D fallback (head reference point, centroid, height, spline) and
  each person's box for the face search;
* ``pose`` when ``use_tracker`` (default): the tracker's 3D joints, used for a person whenever they
  are present and not lost; a frame whose pose never comes (the pose topic went past it) is
  labelled from its silhouettes;
* ``frame`` when ``use_face`` or ``fps`` is 0 (the default): the camera image, for the face path
  (faces tracked, nods/shakes and talking/laughing from them) and for the stream's frame rate
  (``Frame.fps``), which sets every window in frames unless ``fps`` is given.

Every frame paired gives one SocialSignals with the seq and stamp of its silhouettes, one
PersonSignals per person (``source``: the input nod/shake came from, ``face``, ``3d`` or ``2d``;
a face that belongs to no silhouette is a person of its own, id 1000 + slot); what the input cannot
support is UNKNOWN (-1), never guessed. The node's stats count the sources (``source_face``,
``source_3d``, ``source_2d``), the person-frames labelled from 2D although the tracker is
subscribed (``fallback_3d_to_2d``, logged once with its reason) and the silhouette regions taken
as parts of a face's person (``regions_absorbed``). Run in a graph (``run: counterpart.nodes.labeller``) or
alone::

    python -m counterpart.nodes.labeller --param use_tracker=false
"""

from __future__ import annotations

import math
import re
from dataclasses import replace
from typing import Any

import numpy as np

from counterpart.body.pose import DOF, DOF_INDEX
from counterpart.bus import Input, Node, Output, PairedSet, Pairing, Param, ParamError
from counterpart.messages import Frame, Pose3D, Silhouettes, SocialSignals
from counterpart.messages.labeller import PersonSignals

from .labeller import FACE_ID_BASE, PersonObservation, SocialLabeller
from .signals import SIGNALS

#: the highest frame rate taken from a stream's Frame messages (Hz); above it the message is not believed
MAX_STREAM_FPS = 1000.0
#: the spline size the 2D activity detector reads (upper-body control points of 32)
ACTIVITY_CTRL = 32

_HEAD_TURN, _HEAD_NOD = DOF_INDEX["head_turn"], DOF_INDEX["head_nod"]


def head_angles(pose: np.ndarray) -> tuple[float | None, float | None]:
    """Head yaw and pitch relative to the torso from a tracker's pose vector.

    Parameters
    ----------
    pose : ndarray of shape (DOF,)
        The pose vector (``counterpart.body.pose``: ``head_turn``, ``head_nod``).

    Returns
    -------
    head_yaw, head_pitch : float or None
        Radians; (None, None) when the pose is not a finite (DOF,) vector (a tracker that publishes
        joints only).
    """
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

    Parameters
    ----------
    sil : Silhouettes
        The silhouette node's message of the frame.
    pose : Pose3D or None
        The tracker's message of the same frame, when subscribed.

    Returns
    -------
    obs : dict of int to PersonObservation
        Per person id, what the inputs say about them.
    sides : dict of int to str
        Per person id, their side (``"left"`` / ``"right"``).
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
        obs[b.id] = PersonObservation(
            joints=joints,
            head_yaw=head_yaw,
            head_pitch=head_pitch,
            head_px=base.head_px,
            ref_px=base.ref_px,
            height_px=base.height_px,
            control_points=base.control_points,
            box=base.box,
        )
        sides.setdefault(b.id, b.side)
    return obs, sides


def signals_message(
    seq: int,
    stamp: int,
    labels: dict[Any, dict[str, tuple[float, int]]],
    obs: dict[int, PersonObservation],
    sides: dict[int, str],
    sources: dict[Any, str] | None = None,
) -> SocialSignals:
    """One SocialSignals from ``SocialLabeller.update`` output, people in id order.

    Parameters
    ----------
    seq : int
        Message sequence number.
    stamp : int
        Message time stamp.
    labels : dict
        Per person id, signal name -> (score, label), as ``SocialLabeller.update`` returns it.
    obs : dict of int to PersonObservation
        Per person id, the observations labelled.
    sides : dict of int to str
        Per person id, their side (default ``"left"``).
    sources : dict or None, default=None
        ``SocialLabeller.sources`` (default: ``3d`` where the observation has joints, else ``2d``).

    Returns
    -------
    SocialSignals
        The message.
    """
    people = []
    for pid in sorted(labels):
        res = labels[pid]
        o = obs.get(pid)
        src = (sources or {}).get(pid) or ("3d" if o is not None and o.has_3d() else "2d")
        people.append(
            PersonSignals(
                id=int(pid),
                side=sides.get(pid, "left"),
                names=list(SIGNALS),
                scores=np.array([res[s][0] for s in SIGNALS], np.float32),
                labels=np.array([res[s][1] for s in SIGNALS], np.int8),
                source=src,
            )
        )
    return SocialSignals(stamp=stamp, seq=seq, people=people)


#: node parameter -> (keyword of SocialLabeller's parameter group, field name there)
_GROUPED: dict[str, tuple[str, str]] = {
    "nod_median_s": ("head_params", "nod_median_s"),
    "shake_median_s": ("head_params", "shake_median_s"),
    "shake_swing": ("head_params", "shake_swing"),
    "swing_median_s": ("head_params", "swing_median_s"),
    "head_threshold": ("head_params", "threshold"),
    "nod_floor_m": ("head_params", "nod_floor_m"),
    "shake_floor_m": ("head_params", "shake_floor_m"),
    "face_nod_floor": ("head_params", "face_nod_floor"),
    "face_shake_floor": ("head_params", "face_shake_floor"),
    "event_on": ("head_params", "event_on"),
    "event_off": ("head_params", "event_off"),
    "event_local_s": ("head_params", "local_s"),
    "max_flow_s": ("track_params", "max_flow_s"),
    "profile_faces": ("track_params", "profile_faces"),
    "min_face_px": ("track_params", "min_face_px"),
    "max_miss_s": ("track_params", "max_miss_s"),
    "anchor_s": ("track_params", "anchor_s"),
    "search_every_s": ("track_params", "search_every_s"),
    "full_search_every_s": ("track_params", "full_search_every_s"),
    "max_faces": ("track_params", "max_faces"),
    "talk_window_s": ("face_params", "window_s"),
    "talk_energy": ("face_params", "talk_energy_tracked"),
    "talk_gap_s": ("face_params", "talk_gap_s"),
    "laugh_energy": ("face_params", "laugh_energy_tracked"),
}
#: what the algorithm's messages call a node parameter that has another name in the node
_FIELD_NAMES = {
    "threshold": "head_threshold",
    "band_hz": "band_low_hz/band_high_hz",
    "window_s": "head_window_s",
    "talk_energy_tracked": "talk_energy",
    "laugh_energy_tracked": "laugh_energy",
    "local_s": "event_local_s",
}


def make_labeller(p: dict[str, Any], fps: float) -> SocialLabeller:
    """The SocialLabeller of the node's parameters.

    Parameters
    ----------
    p : dict
        The node's checked parameters.
    fps : float
        Frame rate, Hz.

    Returns
    -------
    SocialLabeller
        The labeller.

    Raises
    ------
    ParamError
        Naming the node parameters (and the frame rate) that do not fit together.
    """
    groups: dict[str, dict[str, Any]] = {
        "head_params": {"band_hz": (p["band_low_hz"], p["band_high_hz"])},
        "track_params": {},
        "face_params": {},
    }
    for name, (group, field) in _GROUPED.items():
        groups[group][field] = p[name]
    groups["face_params"]["min_face_px"] = p["min_face_px"]
    try:
        return SocialLabeller(fps, p["head_window_s"], math.radians(p["gaze_threshold_deg"]), **groups)
    except ValueError as exc:
        text = str(exc)
        for field, name in _FIELD_NAMES.items():
            text = re.sub(rf"(?<![a-z_]){field}(?![a-z_])", name, text)
        named = [n for n in Labeller.params if re.search(rf"(?<![a-z_]){n}(?![a-z_])", text)]
        if "band_low_hz/band_high_hz" in text:
            named += ["band_low_hz", "band_high_hz"]
        named = list(dict.fromkeys(named + ["fps"]))
        src = "the parameter 'fps'" if p["fps"] else "the camera's Frame messages ('fps' 0: from the stream)"
        raise ParamError(
            f"parameters {', '.join(map(repr, named))} do not fit together at {fps:g} fps (from "
            f"{src}), head_window_s={p['head_window_s']}: {text}"
        ) from None


class Labeller(Node):
    """Labels nod, shake, gaze at the other, activity, talking and laughing for every person."""

    inputs = {
        "silhouettes": Input(Silhouettes, doc="people of each frame (2D input, boxes)"),
        "pose": Input(Pose3D, doc="tracked 3D bodies (3D input); only with use_tracker"),
        "frame": Input(Frame, doc="camera image for talking/laughing; only with use_face"),
    }
    outputs = {"signals": Output(SocialSignals, "one per frame with silhouettes; seq and stamp of that frame")}
    # a frame whose pose or camera image never comes is labelled without it
    pairing = Pairing(required=("silhouettes",), optional=("pose", "frame"))
    params = {
        "fps": Param(
            float,
            0.0,
            "frame rate of the stream (Hz): sets every window in frames; 0: from the "
            "camera's Frame messages (subscribes to frame)",
            min=0.0,
            max=1e4,
        ),
        "head_window_s": Param(float, 1.6, "FFT window of nod/shake (s)", min=0.05, max=60.0),
        "nod_median_s": Param(
            float,
            1.0,
            "running median removed from the nod channels before the FFT (s; "
            "0: none): movements that go one way and stay are not nods",
            min=0.0,
            max=60.0,
        ),
        "shake_median_s": Param(float, 0.44, "the same for the shake channels (s)", min=0.0, max=60.0),
        "shake_swing": Param(
            float,
            0.3,
            "least swing back against a window's largest lateral excursion, before and after it "
            "together, a fraction of it (unitless; 0: no test): a shake swings back, a glance "
            "aside and back only by its overshoot",
            min=0.0,
            max=2.0,
        ),
        "swing_median_s": Param(
            float,
            0.8,
            "running median removed from the lateral motion before the shake_swing test (s): at "
            "least twice a quick glance, so that the glance is kept whole",
            min=0.0,
            max=60.0,
        ),
        "band_low_hz": Param(float, 1.0, "lowest frequency of nods and shakes (Hz)", min=0.0),
        "band_high_hz": Param(float, 4.0, "highest frequency of nods and shakes (Hz)", min=0.0),
        "head_threshold": Param(
            float,
            0.5,
            "nod/shake score threshold (fraction of the head's oscillating motion in the band)",
            min=0.0,
            max=1.0,
        ),
        "face_nod_floor": Param(
            float, 0.06, "amplitude floor of a face's nod motion (face widths): smaller motion scores lower", min=0.0
        ),
        "face_shake_floor": Param(float, 0.06, "amplitude floor of a face's shake motion (face widths)", min=0.0),
        "event_on": Param(
            float,
            0.6,
            "a nod/shake is a run of frames whose local motion is at least event_off of its "
            "window's largest and reaches this fraction (0: every frame of a detected window)",
            min=0.0,
            max=1.0,
        ),
        "event_off": Param(
            float, 0.3, "the fraction of the window's largest local motion a nod/shake's frames keep", min=0.0, max=1.0
        ),
        "event_local_s": Param(float, 0.25, "width of the local motion average of event_on/event_off (s)", min=0.01),
        "nod_floor_m": Param(float, 0.01, "amplitude floor of 3D/2D head-point nod motion (m)", min=0.0),
        "shake_floor_m": Param(float, 0.01, "amplitude floor of 3D/2D head-point shake motion (m)", min=0.0),
        "min_face_px": Param(int, 40, "smallest face width used (px); smaller faces are not tracked", min=24, max=4096),
        "max_miss_s": Param(
            float, 0.5, "longest run of missed face detections bridged by optical flow (s)", min=0.0, max=10.0
        ),
        "max_flow_s": Param(
            float,
            2.0,
            "the same while the flow still follows the face's points (a look away) (s)",
            min=0.0,
            max=60.0,
        ),
        "profile_faces": Param(
            bool,
            True,
            "look for faces turned aside with OpenCV's profile cascade where the frontal one finds none",
        ),
        "anchor_s": Param(
            float,
            1.0,
            "time constant of the pull of a face's tracked point towards its "
            "detections (s): longer is stiller, shorter follows the detector",
            min=0.01,
            max=60.0,
        ),
        "search_every_s": Param(
            float,
            0.5,
            "period of the search for new faces (s): in the head regions of the people's silhouettes, "
            "in the whole frame where there are none",
            min=0.01,
            max=60.0,
        ),
        "full_search_every_s": Param(
            float,
            2.0,
            "period of the whole-frame search for new faces while there are silhouettes (s; at least "
            "search_every_s): faces the silhouettes miss",
            min=0.01,
            max=600.0,
        ),
        "max_faces": Param(int, 2, "most faces tracked at once", min=1, max=16),
        "talk_window_s": Param(
            float, 1.0, "averaging window of mouth motion for talking/laughing (s)", min=0.05, max=60.0
        ),
        "talk_energy": Param(
            float,
            0.008,
            "talking threshold of a face's mouth motion above its upper face's "
            "(mean absolute difference of mean-normalised patches per frame)",
            min=0.0,
        ),
        "laugh_energy": Param(float, 0.05, "laughing threshold of the same mouth motion", min=0.0),
        "talk_gap_s": Param(
            float,
            0.45,
            "a face talks only where its mouth moved within this long before and after (s): "
            "shorter pauses are bridged, the label does not spread past the first and last syllable",
            min=0.0,
            max=30.0,
        ),
        "gaze_threshold_deg": Param(
            float,
            30.0,
            "largest angle between gaze and the direction to the other still counted as looking at them (degrees)",
            check=lambda v: None if 0.0 < v < 180.0 else "must be in (0, 180) degrees",
        ),
        "use_tracker": Param(bool, True, "subscribe to pose (Pose3D) and use 3D joints where tracked"),
        "use_face": Param(
            bool,
            True,
            "track faces in the camera frames (subscribes to frame): nods, shakes, "
            "talking and laughing from faces where they are big enough",
        ),
        "max_pending": Param(
            int,
            8,
            "frames with silhouettes held back waiting for a slow pose or frame before going on without it",
            min=1,
            max=1000,
        ),
        "max_ahead": Param(
            int,
            64,
            "frames of pose/camera messages kept while their silhouettes are still "
            "to come (memory: camera frames are large); older ones are discarded",
            min=0,
            max=10_000,
        ),
    }

    @classmethod
    def validate_params(cls, given: dict[str, Any], where: str = "") -> dict[str, Any]:
        """Check the parameters as :class:`Node` does, and that they make a labeller at ``fps`` (or,
        when the rate comes from the stream, at 25 and 29.97 fps).

        Parameters
        ----------
        given : dict
            The parameters given (launch file and overrides).
        where : str, default=""
            Where they come from, prefixed to error messages.

        Returns
        -------
        dict
            Every parameter, defaults filled in.

        Raises
        ------
        ParamError
            Naming the parameters that do not fit together.
        """
        p = super().validate_params(given, where)
        # the windows in frames must be long enough for their detectors, at the given rate or, when
        # it comes from the stream, at the common ones
        for fps in [p["fps"]] if p["fps"] else [25.0, 29.97]:
            try:
                make_labeller(p, fps)
            except ParamError as exc:
                prefix = f"{where}: " if where else ""
                raise ParamError(f"{prefix}{exc}") from None
        return p

    @classmethod
    def ports(cls, params: dict[str, Any]) -> tuple[dict[str, Input], dict[str, Output]]:
        """The inputs these parameters use: ``pose`` with ``use_tracker``, ``frame`` with ``use_face``
        or ``fps`` 0 (the rate from the stream).

        Parameters
        ----------
        params : dict
            The checked parameters.

        Returns
        -------
        inputs : dict of str to Input
            The inputs subscribed.
        outputs : dict of str to Output
            The outputs.
        """
        ins = {"silhouettes": cls.inputs["silhouettes"]}
        if params["use_tracker"]:
            ins["pose"] = cls.inputs["pose"]
        if params["use_face"] or not params["fps"]:
            ins["frame"] = cls.inputs["frame"]
        return ins, dict(cls.outputs)

    @classmethod
    def paired_inputs(cls, params: dict[str, Any]) -> Pairing | None:
        pairing = super().paired_inputs(params)
        return replace(pairing, max_pending=params["max_pending"], max_ahead=params["max_ahead"]) if pairing else None

    def setup(self) -> None:
        p = self.p
        self.labeller: SocialLabeller | None = None
        self.fps = p["fps"] or 25.0  # until the stream says
        self.last_seq = -1
        self.sources = {"face": 0, "3d": 0, "2d": 0}
        self._warned_ctrl = False
        self._warned_rate = False
        self._warned_image = False
        self._refused: set[float] = set()
        self._warned_fallback: set[str] = set()

    def _rate(self, frame: Frame | None) -> SocialLabeller:
        """The labeller at the stream's frame rate (``fps`` 0) or the given one; rebuilt (windows
        restart) when the stream's rate changes.
        """
        p = self.p
        fps = self.fps
        if not p["fps"] and frame is not None:
            rate = frame.fps if isinstance(frame.fps, (int, float)) else 0.0
            if math.isfinite(rate) and 0 < rate <= MAX_STREAM_FPS:
                fps = float(rate)
            elif rate and not self._warned_rate:
                self._warned_rate = True
                self.log.warning(
                    "a frame says the stream runs at %r fps; ignored (labelling at %g fps): set labeller.fps "
                    "to the video's rate",
                    frame.fps,
                    fps,
                )
            elif not self._warned_rate:
                self._warned_rate = True
                self.log.warning(
                    "the camera's frames do not say their frame rate (Frame.fps 0); labelling at "
                    "%g fps: set labeller.fps to the video's rate",
                    fps,
                )
        if self.labeller is None or fps != self.fps:
            try:
                lab = make_labeller(p, fps)
            except ParamError as exc:
                if self.labeller is None:
                    raise
                if fps not in self._refused:
                    self._refused.add(fps)
                    self.log.error(
                        "the stream's frame rate changed to %g fps, which the parameters do not allow; "
                        "labelling at %g fps: %s",
                        fps,
                        self.fps,
                        exc,
                    )
                return self.labeller
            if self.labeller is not None:
                self.log.info("frame rate %g fps from the stream (was %g): the analysis windows restart", fps, self.fps)
            self.labeller = lab
            self.fps = fps
        return self.labeller

    def _image(self, frame: Frame | None) -> np.ndarray | None:
        """The frame's image when faces can be searched in it: uint8, (H, W) or (H, W, 3), at least
        min_face_px a side; otherwise None (counted as ``frames_unusable``, said once).
        """
        if frame is None or not self.p["use_face"]:
            return None
        img = frame.image
        ok = (
            isinstance(img, np.ndarray)
            and img.dtype == np.uint8
            and (img.ndim == 2 or (img.ndim == 3 and img.shape[2] == 3))
            and min(img.shape[:2]) >= self.p["min_face_px"]
        )
        if ok:
            return img
        self.tally("frames_unusable")
        if not self._warned_image:
            self._warned_image = True
            self.log.warning(
                "frame %d: image %s %s cannot hold a face of min_face_px=%d (need uint8 gray or BGR); "
                "such frames are labelled without faces",
                frame.seq,
                getattr(img, "dtype", type(img).__name__),
                getattr(img, "shape", ""),
                self.p["min_face_px"],
            )
        return None

    def on_paired(self, item: PairedSet) -> None:
        frame: Frame | None = item.get("frame")
        lab = self._rate(frame)
        if item.restart:
            self.log.info("seq went back to %d: the stream restarted; forgetting every person", item.seq)
            lab.reset()
        elif self.last_seq >= 0 and item.seq > self.last_seq + 1:
            lab.skip(item.seq - self.last_seq - 1)
        self.last_seq = item.seq
        sil: Silhouettes = item.msgs["silhouettes"]
        obs, sides = observations(sil, item.get("pose"))
        odd = [np.shape(p.ctrl) for p in sil.people if np.size(p.ctrl) and np.shape(p.ctrl) != (ACTIVITY_CTRL, 2)]
        if odd and not self._warned_ctrl:
            self._warned_ctrl = True
            self.log.warning(
                "silhouettes carry splines of shape %s; 2D activity needs (%d, 2) and stays UNKNOWN "
                "(set the silhouette node's n_ctrl to %d)",
                odd[0],
                ACTIVITY_CTRL,
                ACTIVITY_CTRL,
            )
        labels = lab.update(obs, image=self._image(frame))
        if lab.absorbed:
            self.tally("regions_absorbed", len(lab.absorbed))
        width = sil.width or (np.shape(frame.image)[1] if frame is not None and np.ndim(frame.image) >= 2 else 0)
        for pid, face in lab.faces.items():
            if pid >= FACE_ID_BASE:
                sides[pid] = "left" if width and face.center[0] < width / 2 else "right"
        out = signals_message(item.seq, sil.stamp, labels, obs, sides, lab.sources)
        for ps in out.people:
            if ps.source in self.sources:
                self.sources[ps.source] += 1
                self.tally(f"source_{ps.source}")
            if "pose" in self._in and ps.source == "2d":
                self._fallback(item, ps.id)
        self.publish("signals", out)

    def _fallback(self, item: PairedSet, pid: int) -> None:
        """A person labelled from their silhouette although the tracker is subscribed: counted, and
        said once per reason.
        """
        self.tally("fallback_3d_to_2d")
        pose = item.get("pose")
        if pose is None:
            why = (
                "no pose message for this frame (it came late or was dropped; labeller.max_pending sets how "
                "long a frame waits for it)"
            )
        elif not any(b.id == pid for b in pose.people):
            why = "the tracker has no body for this person"
        else:
            why = "the tracker lost this person's body (or its joints were not finite)"
        if why not in self._warned_fallback:
            self._warned_fallback.add(why)
            self.log.warning(
                "person %d labelled from the silhouette (2D) instead of the tracker (3D) from frame %d: "
                "%s; counted in the stats as fallback_3d_to_2d",
                pid,
                item.seq,
                why,
            )

    def on_end(self) -> None:
        st = self.pairing_stats
        missing = ", ".join(f"{n} without {p}" for p, n in st.missing.items() if n)
        self.log.info(
            "labelled %d frames (%s; people: %d from 3D, %d from 2D, %d from faces; %d fell back from 3D "
            "to 2D); %d dropped without silhouettes, %d released early, %d side messages over max_ahead, "
            "%d late messages, %d restarts; frame rate %g fps",
            st.delivered,
            missing or "every input present",
            self.sources["3d"],
            self.sources["2d"],
            self.sources["face"],
            int(self.figures.get("fallback_3d_to_2d", 0)),
            st.dropped,
            st.forced,
            st.overflow,
            st.late,
            st.restarts,
            self.fps,
        )


NODE = Labeller

if __name__ == "__main__":
    Labeller.main()
