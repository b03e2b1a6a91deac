"""The social-signal labeller: every signal of :data:`SIGNALS` per person and frame.

Inputs are chosen per person and frame, best first, and the choice for nod/shake is recorded
(:attr:`SocialLabeller.sources`: ``face``, ``3d``, ``2d`` or ``""``):

1. **a tracked face** (:mod:`counterpart.nodes.labeller.face_track`, when a camera image is given and a frontal
   face of at least ``min_face_px`` is found): nod/shake from the face's head point in units of
   its own width (:class:`~counterpart.nodes.labeller.head_motion.HeadMotionDetectorFace`), talking/laughing
   from its stabilised mouth patch (:meth:`~counterpart.nodes.labeller.face.FaceSignalDetector.update_track`);
2. the tracker's 3D joints (14,3) -> nod/shake relative to the neck (facing from the shoulders, plus
   the tracker's head angles when given), activity from shoulders and hips, gaze from the shoulder
   normal (+ head yaw) against the direction to the other person;
3. else the silhouette: head reference point relative to the silhouette centroid (2D nod/shake,
   scaled by the height in pixels), activity from the upper-body spline points; gaze UNKNOWN.

Activity and gaze come from 3D, else 2D, whatever the nod/shake source. A face belongs to the
person whose box holds its centre and is at least 1.5 face widths tall (a body below a head); a
person given without a box takes the largest face only when alone. A face that belongs to
nobody (a close-up, where the silhouettes are only fragments of motion) is a person of its own,
id ``FACE_ID_BASE + slot``; the silhouette people that overlap its body region (the face box
widened by one face width to each side and down to the bottom of the frame), and are not
bodies holding another face, are then parts of it and not reported (:attr:`SocialLabeller.absorbed`).
Talking/laughing are UNKNOWN without a face, and UNKNOWN (with one RuntimeWarning) when no Haar
cascade file is installed (see :func:`counterpart.nodes.labeller.face.find_face_cascade`).

A person switching between sources, a face track restarting, or a person missing from a frame,
restarts the windows of the affected detectors (so a window never mixes two sources or spans a
gap): those signals are UNKNOWN until a window has filled again.
"""

from __future__ import annotations

import warnings
from collections.abc import Hashable, Mapping
from dataclasses import dataclass

import cv2
import numpy as np

from counterpart.nodes.labeller.activity import ActivityDetector, activity_3d
from counterpart.nodes.labeller.face import (
    PROFILE_CASCADE_NAME,
    Box,
    FaceSignalDetector,
    find_face_cascade,
    load_face_cascade,
    to_gray,
)
from counterpart.nodes.labeller.face_track import FaceTrack, FaceTracker, FaceTrackParams
from counterpart.nodes.labeller.gaze import facing_yaw_from_shoulders, gaze_at_other
from counterpart.nodes.labeller.head_motion import (
    HeadMotionDetector,
    HeadMotionDetector2D,
    HeadMotionDetectorFace,
    head_motion,
)
from counterpart.nodes.labeller.signals import JOINT_INDEX, SIGNALS, UNKNOWN, UNKNOWN_VALUE

_H, _N = JOINT_INDEX["head"], JOINT_INDEX["neck"]
_LS, _RS = JOINT_INDEX["l_shoulder"], JOINT_INDEX["r_shoulder"]

Labels = dict[str, tuple[float, int]]

#: person id of a face that belongs to no given person: FACE_ID_BASE + its track's slot
FACE_ID_BASE = 1000
#: a person's box holds a face as a body only when at least this many face widths tall
BODY_FACES = 1.5


@dataclass(frozen=True)
class PersonObservation:
    """What is known about one person on one frame; any field may be None.

    Parameters
    ----------
    joints : ndarray of shape (14, 3) or None
        Joints, metres, project joint order, world frame Y up (tracker).
    head_yaw : float or None
        Head yaw relative to the torso, radians, positive to the person's left: the ``head_turn``
        of the tracker's pose vector when it publishes one (see
        :mod:`counterpart.nodes.labeller.head_motion`: it replaces the head point for shakes).
    head_pitch : float or None
        Head pitch relative to the torso, radians, positive chin down: the tracker's ``head_nod``
        (it replaces the head point for nods).
    head_px : ndarray of shape (2,) or None
        Silhouette head reference point, pixels.
    ref_px : ndarray of shape (2,) or None
        Body reference point, pixels, e.g. the silhouette centroid.
    height_px : float or None
        Silhouette height, pixels.
    control_points : ndarray of shape (32, 2) or None
        Silhouette spline from the top of the head, pixels.
    box : tuple of int or None
        (x, y, w, h) region of the person in the image, pixels (face search region).
    """

    joints: np.ndarray | None = None
    head_yaw: float | None = None
    head_pitch: float | None = None
    head_px: np.ndarray | None = None
    ref_px: np.ndarray | None = None
    height_px: float | None = None
    control_points: np.ndarray | None = None
    box: Box | None = None

    def has_3d(self) -> bool:
        """Whether the joints are given and all finite."""
        return self.joints is not None and bool(np.isfinite(self.joints).all())

    def has_2d_head(self) -> bool:
        """Whether the 2D head point, reference point and a positive height are given."""
        return (
            self.head_px is not None and self.ref_px is not None and self.height_px is not None and self.height_px > 0
        )


class _PersonState:
    def __init__(self, lab: SocialLabeller) -> None:
        self.head3 = HeadMotionDetector(lab.fps, lab.head_window_s, **lab.head_params)
        self.head2 = HeadMotionDetector2D(lab.fps, lab.head_window_s, **lab.head_params)
        self.act3 = ActivityDetector(lab.fps, **lab.activity_params)
        self.act2 = ActivityDetector(lab.fps, **lab.activity_params)
        self.headf = HeadMotionDetectorFace(lab.fps, lab.head_window_s, **lab.head_params)
        self.face = FaceSignalDetector(lab.fps, cascade=lab._cascade, **lab.face_params)
        self.mode = ""
        self.act_mode = ""
        self.track_id: int | None = None
        self.last_frame = -2

    def reset(self) -> None:
        for d in (self.head3, self.head2, self.headf, self.act3, self.act2, self.face):
            d.reset()
        self.mode = self.act_mode = ""
        self.track_id = None


class SocialLabeller:
    """Streaming labeller for any number of people.

    ``update(people, image=None, targets=None)`` -> ``{person_id: {signal: (score, label)}}`` with
    every signal of :data:`SIGNALS`.

    Parameters
    ----------
    fps : float
        Frame rate, Hz.
    head_window_s : float, default=1.6
        FFT window of nod/shake, seconds.
    gaze_threshold : float, default=radians(30)
        Largest angle (radians) between gaze and the direction to the other still counted as
        "at the other".
    head_params : mapping of str to object or None, default=None
        Extra keyword parameters of :class:`~counterpart.nodes.labeller.head_motion.HeadMotionParams`.
    activity_params : mapping of str to object or None, default=None
        Extra keyword parameters of :class:`~counterpart.nodes.labeller.activity.ActivityDetector`.
    face_params : mapping of str to object or None, default=None
        Extra keyword parameters of :class:`~counterpart.nodes.labeller.face.FaceParams`.
    track_params : mapping of str to object or None, default=None
        Extra keyword parameters of :class:`~counterpart.nodes.labeller.face_track.FaceTrackParams`.

    Attributes
    ----------
    sources : dict of Hashable to str
        After :meth:`update`, per person which input gave nod/shake (``face``, ``3d``, ``2d``,
        ``""`` for none).
    faces : dict of Hashable to FaceTrack
        The face tracked for each person that has one.
    absorbed : list of Hashable
        The ids of given people that were parts of a face's person.
    """

    def __init__(
        self,
        fps: float,
        head_window_s: float = 1.6,
        gaze_threshold: float = float(np.radians(30.0)),
        head_params: Mapping[str, object] | None = None,
        activity_params: Mapping[str, object] | None = None,
        face_params: Mapping[str, object] | None = None,
        track_params: Mapping[str, object] | None = None,
    ) -> None:
        self.fps = float(fps)
        self.head_window_s = head_window_s
        self.gaze_threshold = gaze_threshold
        self.head_params = dict(head_params or {})
        self.activity_params = dict(activity_params or {})
        self.face_params = dict(face_params or {})
        self.track_params = FaceTrackParams(fps=self.fps, **dict(track_params or {}))  # type: ignore[arg-type]
        self._tracker: FaceTracker | None = None
        self.sources: dict[Hashable, str] = {}
        self.faces: dict[Hashable, FaceTrack] = {}
        self.absorbed: list[Hashable] = []
        self._cascade: cv2.CascadeClassifier | None = None
        self._cascade_missing = False
        self._people: dict[Hashable, _PersonState] = {}
        self._frame = 0
        _PersonState(self)  # validate every parameter now, not on the first person

    def _face_cascade(self) -> cv2.CascadeClassifier | None:
        """The face detector, loaded on first use; None (talking/laughing UNKNOWN, one warning)
        when no cascade file can be found.
        """
        if self._cascade is None and not self._cascade_missing:
            try:
                self._cascade = load_face_cascade()
            except FileNotFoundError as e:
                self._cascade_missing = True
                warnings.warn(f"talking/laughing will be UNKNOWN: {e}", RuntimeWarning, stacklevel=3)
        return self._cascade

    def _profile_cascade(self) -> cv2.CascadeClassifier | None:
        """The profile face detector when ``track_params.profile_faces`` and OpenCV ships it, else
        None (frontal faces only; said once).
        """
        if not self.track_params.profile_faces:
            return None
        path = find_face_cascade(PROFILE_CASCADE_NAME)
        if path is None:
            warnings.warn(
                f"no {PROFILE_CASCADE_NAME} found: faces turned aside are not found (frontal faces only)",
                RuntimeWarning,
                stacklevel=3,
            )
            return None
        return load_face_cascade(path)

    def reset(self) -> None:
        """Forget every person and face."""
        self._people.clear()
        if self._tracker is not None:
            self._tracker.reset()

    def skip(self, n_frames: int = 1) -> None:
        """``n_frames`` frames are missing from the stream (dropped upstream): every person's
        windows restart at the next :meth:`update`, so that no window spans the gap.

        Parameters
        ----------
        n_frames : int, default=1
            Frames missing, >= 0.

        Raises
        ------
        ValueError
            A negative ``n_frames``.
        """
        if n_frames < 0:
            raise ValueError(f"n_frames must be >= 0, got {n_frames}")
        self._frame += int(n_frames)
        if n_frames and self._tracker is not None:
            self._tracker.reset()  # the flow cannot bridge a gap in the stream

    def _state(self, pid: Hashable) -> _PersonState:
        st = self._people.get(pid)
        if st is None:
            st = self._people[pid] = _PersonState(self)
        if st.last_frame != self._frame - 1:
            st.reset()
        st.last_frame = self._frame
        return st

    def update(
        self,
        people: Mapping[Hashable, PersonObservation],
        image: np.ndarray | None = None,
        targets: Mapping[Hashable, np.ndarray] | None = None,
    ) -> dict[Hashable, Labels]:
        """Label one frame.

        Parameters
        ----------
        people : mapping of Hashable to PersonObservation
            Person id -> what is known about the person. Where every person has a ``box``, new
            faces are searched for in their head regions (and in the whole frame only every
            ``track_params.full_search_every_s``; see :mod:`counterpart.nodes.labeller.face_track`).
        image : ndarray of shape (H, W) or (H, W, 3), dtype uint8, or None, default=None
            The camera frame (gray or BGR) for talking/laughing, or None.
        targets : mapping of Hashable to ndarray of shape (3,), or None, default=None
            Person id -> the world point (metres) the person's gaze is judged against (e.g. the
            virtual partner); by default the nearest other person's head.

        Returns
        -------
        dict of Hashable to dict of str to (float, int)
            Person id -> signal -> (score, label) for every signal of :data:`SIGNALS`; the people
            are the given ones less those absorbed, plus faces of their own.
        """
        gray = None
        tracks: list[FaceTrack] = []
        if image is not None and self._face_cascade() is not None:
            gray = to_gray(image)
            if self._tracker is None:
                self._tracker = FaceTracker(self.track_params, self._cascade, self._profile_cascade())  # type: ignore[arg-type]
            # where every person's box is known, new faces are looked for in their head regions
            boxes = [o.box for o in people.values()]
            known = [b for b in boxes if b is not None] if boxes and None not in boxes else None
            tracks = [t for t in self._tracker.update(gray, known) if t.confirmed]
        people, faces = self._attribute(people, tracks)
        self.faces = faces
        heads = {pid: np.asarray(o.joints, dtype=np.float64)[_H] for pid, o in people.items() if o.has_3d()}
        out: dict[Hashable, Labels] = {}
        self.sources = {}
        for pid, obs in people.items():
            st = self._state(pid)
            res: Labels = {s: UNKNOWN_VALUE for s in SIGNALS}
            face = faces.get(pid)
            mode = "face" if face is not None else "3d" if obs.has_3d() else "2d" if obs.has_2d_head() else ""
            if mode != st.mode:
                for d in (st.head3, st.head2, st.headf):
                    d.reset()
                st.mode = mode
            act_mode = "3d" if obs.has_3d() else "2d" if obs.has_2d_head() else ""
            if act_mode != st.act_mode:
                st.act3.reset()
                st.act2.reset()
                st.act_mode = act_mode
            j = np.asarray(obs.joints, dtype=np.float64) if obs.has_3d() else None
            if face is not None:
                if st.track_id != face.track_id:  # another face (or the same one found again)
                    st.headf.reset()
                    st.face.reset()
                    st.track_id = face.track_id
                ns, n, ss, s = st.headf.update(face.center, face.size, face.tilt)
                res["nod"], res["shake"] = (ns, n), (ss, s)
            elif j is not None:
                yaw = float(facing_yaw_from_shoulders(j[_LS], j[_RS]))
                yaw = yaw if yaw == yaw else None
                ns, n, ss, s = st.head3.update(j[_H], j[_N], yaw, obs.head_yaw, obs.head_pitch)
                res["nod"], res["shake"] = (ns, n), (ss, s)
            elif mode == "2d":
                ns, n, ss, s = st.head2.update(np.asarray(obs.head_px), np.asarray(obs.ref_px), float(obs.height_px))  # type: ignore[arg-type]
                res["nod"], res["shake"] = (ns, n), (ss, s)
            if j is not None:
                res["activity"] = st.act3.update_3d(j)
                target = None if targets is None else targets.get(pid)
                if target is None:
                    target = _nearest_other(pid, heads)
                if target is not None:
                    g = gaze_at_other(
                        j[_H], j[_LS], j[_RS], np.asarray(target, dtype=np.float64), obs.head_yaw, self.gaze_threshold
                    )
                    res["gaze_at_other"] = (float(g.score[0]), int(g.label[0]))
            elif act_mode == "2d":
                if obs.control_points is not None:
                    res["activity"] = st.act2.update_2d(obs.control_points, float(obs.height_px))  # type: ignore[arg-type]
                else:
                    st.act2.reset()  # a window must not span the gap
            if face is not None and gray is not None:
                ts, t, ls, lg = st.face.update_track(gray, face.center, face.size)
                res["talking"], res["laughing"] = (ts, t), (ls, lg)
            else:
                st.face.reset()
                st.track_id = None
            out[pid] = res
            self.sources[pid] = mode
        self._frame += 1
        return out

    def _attribute(
        self,
        people: Mapping[Hashable, PersonObservation],
        tracks: list[FaceTrack],
    ) -> tuple[dict[Hashable, PersonObservation], dict[Hashable, FaceTrack]]:
        """Give each tracked face to a person (see the module docstring): returns the people to
        label (the given ones less those absorbed, plus faces of their own) and person id -> face.
        """
        people = dict(people)
        faces: dict[Hashable, FaceTrack] = {}
        self.absorbed = []
        if not tracks:
            return people, faces
        for tr in sorted(tracks, key=lambda t: -t.size):
            cx, cy = tr.center
            best, best_top = None, np.inf
            for pid, o in people.items():
                if pid in faces or o.box is None:
                    continue
                x, y, w, h = o.box
                if x <= cx <= x + w and y <= cy <= y + h and h >= BODY_FACES * tr.size and y < best_top:
                    best, best_top = pid, y
            if best is None and len(people) == 1:
                only = next(iter(people))
                if people[only].box is None and only not in faces:
                    best = only
            if best is not None:
                faces[best] = tr
                continue
            # a face of its own: the silhouette regions over its body are parts of it
            w = tr.size
            x0, x1, y0 = cx - 1.5 * w, cx + 1.5 * w, cy - w
            for pid, o in list(people.items()):
                if pid in faces or o.box is None:
                    continue
                x, y, bw, bh = o.box
                if x < x1 and x + bw > x0 and y + bh > y0:
                    del people[pid]
                    self.absorbed.append(pid)
            pid = FACE_ID_BASE + tr.slot
            people[pid] = PersonObservation()
            faces[pid] = tr
        return people, faces


def _nearest_other(pid: Hashable, heads: Mapping[Hashable, np.ndarray]) -> np.ndarray | None:
    if pid not in heads:
        return None
    me = heads[pid]
    best, best_d = None, np.inf
    for other, h in heads.items():
        if other == pid:
            continue
        d = float(np.hypot(h[0] - me[0], h[2] - me[2]))
        if d < best_d:
            best, best_d = h, d
    return best


def label_pair_3d(
    joints_a: np.ndarray,
    joints_b: np.ndarray,
    fps: float,
    center: bool = True,
    head_window_s: float = 1.6,
    gaze_threshold: float = float(np.radians(30.0)),
    head_yaw_a: np.ndarray | None = None,
    head_yaw_b: np.ndarray | None = None,
    head_pitch_a: np.ndarray | None = None,
    head_pitch_b: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Offline batch labels of two tracked people looking at each other (vectorised over frames).

    Parameters
    ----------
    joints_a, joints_b : ndarray of shape (T, 14, 3)
        The two people's joints, metres, world frame.
    fps : float
        Frame rate, Hz.
    center : bool, default=True
        Centred nod/shake windows (better timing offline; activity windows stay causal).
    head_window_s : float, default=1.6
        FFT window of nod/shake, seconds.
    gaze_threshold : float, default=radians(30)
        Largest angle (radians) between gaze and the direction to the other still counted as
        "at the other".
    head_yaw_a, head_yaw_b, head_pitch_a, head_pitch_b : ndarray of shape (T,) or None, default=None
        Head angles relative to the torso, radians, from the tracker's pose, or None.

    Returns
    -------
    scores_a, labels_a, scores_b, labels_b : ndarray of shape (T, 6)
        Scores (float) and labels (int8) per frame in :data:`SIGNALS` order; talking/laughing are
        UNKNOWN (no images).

    Raises
    ------
    ValueError
        ``joints_a`` is not of shape (T, 14, 3) or ``joints_b`` differs in shape.
    """
    ja = np.asarray(joints_a, dtype=np.float64)
    jb = np.asarray(joints_b, dtype=np.float64)
    if ja.ndim != 3 or ja.shape[1:] != (14, 3) or jb.shape != ja.shape:
        raise ValueError(f"joints_a and joints_b must both be (T,14,3) metres; got {ja.shape}, {jb.shape}")
    outs = []
    for me, other, hy, hp in ((ja, jb, head_yaw_a, head_pitch_a), (jb, ja, head_yaw_b, head_pitch_b)):
        t = me.shape[0]
        sc = np.full((t, len(SIGNALS)), np.nan)
        lb = np.full((t, len(SIGNALS)), UNKNOWN, dtype=np.int8)
        yaw = np.nan_to_num(facing_yaw_from_shoulders(me[:, _LS], me[:, _RS]))
        hm = head_motion(
            me[:, _H], me[:, _N], fps, head_window_s, facing_yaw=yaw, head_yaw=hy, center=center, head_pitch=hp
        )
        sc[:, 0], lb[:, 0], sc[:, 1], lb[:, 1] = hm.nod_score, hm.nod, hm.shake_score, hm.shake
        g = gaze_at_other(me[:, _H], me[:, _LS], me[:, _RS], other[:, _H], hy, gaze_threshold)
        sc[:, 2], lb[:, 2] = g.score, g.label
        sc[:, 3], lb[:, 3] = activity_3d(me, fps)
        outs += [sc, lb]
    return outs[0], outs[1], outs[2], outs[3]
