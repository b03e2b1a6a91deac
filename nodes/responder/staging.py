"""Where the generated partner stands: beside the observed person, at a partner's distance, never jumping.

An interaction model places the partner relative to the observed person's frame
(:mod:`.frames`); on real tracking that frame is noisy (a person bending over turns their
estimated facing, a tracker's jump moves their origin), and a model's placement that is right
for the training pairs can then put the partner inside the observed person or metres away.
:class:`Stage` corrects the generated pose as a whole, a rigid move on the ground plane, so the
model's posture and gestures are kept. First the pose is put on the observed person's bones, bone by
bone (``bones``): a model's generated joints do not keep one body from frame to frame, and a partner
of the person's build at their depth is drawn at their size in the picture. Then:

1. the partner stands beside the observed person as the camera sees them (``beside``): its ground
   offset from the person, p - o (p, o the mid-hips dropped to the floor,
   :func:`.frames.actor_frame`), is taken across the camera's view, at the person's depth: along
   the ground direction of the camera's x axis (:func:`across_view` of the caller's ``camera``;
   image right is that way), world X when the caller has no camera (a camera looking along -Z with no yaw,
   as the default one, :mod:`counterpart.body.camera`). Its side is where the real second person stands
   when one is tracked (``other``; it changes only when they are more than ``side_margin_m`` on
   the other side), else the side the caller gives (the observed person's side of the picture:
   the partner stands towards the middle), else the model's. Not beside: the model's direction.
   Its length is the model's ground distance clipped to [``min_distance_m``, ``max_distance_m``]
   (along the observed person's facing when p lies on o and nothing gives a side). With the
   camera and the observed person's silhouette box (``box``; a region shared with another person's
   is split, the split box is theirs), it
   then grows, within ``max_distance_m``, as little as makes the partner's projected box overlap
   that box by at most ``clear_iou`` (intersection over union) with at most ``clear_inside`` of
   its own box inside it: the tracked person's place is off by decimetres on real video, their
   silhouette is where the picture shows them;
2. that offset changes by at most ``max_speed_m_s`` times the time between frames, in polar
   coordinates about the person (the partner walks round them, never through them; it never
   jumps), so the distance holds on every frame. The offset is relative to the observed person:
   where the tracker's estimate of the person jumps, the partner stays beside them in the picture
   rather than walking after them;
3. the partner recoils when pushed: when the observed person's tracked wrists or elbows come
   within ``contact_m`` of its torso axis (neck to mid-hip), or, where the caller has the person's
   silhouette (:func:`silhouette_reach`), when it holds a hand out (its leading point ``offer_m``
   from its centre) while its centre advances towards the partner at ``push_speed_m_s`` or more
   (the torso and the arm forward together: tracked arms are the least reliable joints on real
   video, a silhouette's outline is not), with ``push_touch`` the silhouette touches someone
   else's (:attr:`Reach.touching`: a pusher walks in with the arm out well before the hand lands),
   and the hand was last seen held high (``push_height`` of the stature: a push lands on the chest,
   people walking in to shake hands hold the hand lower) or the centre advances at ``push_rush_m_s``
   or more (faster than people come up to shake hands). As a pushed person does on real video,
   it gives way while the push goes on (the pusher's hand held out on someone, their silhouette
   touching another's, or driven on): its distance grows at ``yield_speed_m_s`` up to ``recoil_m``
   from where the push landed; when the push is released it is thrown back, to ``recoil_max_m``
   at ``recoil_speed_m_s``, and once there it returns with time constant ``recoil_s``. All of it
   within ``max_distance_m``: a partner standing further than ``recoil_m`` inside the limit when
   pushed stands where the push lands, with room to recoil.
   A hand held out without a push (the silhouette reaching ``offer_m``, or having done so within
   ``offer_hold_s``; none while a push goes on or the partner recoils from one, nor from someone
   driving or rushing in as a pusher does, not yet touching: a partner reaching for a pushing hand
   stands with its arm inside the pusher) is offered (:attr:`Stage.offered_`): with the camera and the
   person's box where the outline's tip is in the picture (``tip_in_picture``, at the depth of the
   person's hips: the tip is the hand; ``tip_back`` short of it, where clasping wrists are), else at
   the height of the silhouette's tip, ``meet_frac`` of the way to the partner at most; where the
   silhouette touches someone else's
   (its tip is then where the regions were split, not the hand), with the camera, the person's box
   and the other's region, where the picture says (``meet_touch`` of the way between the two
   regions' centroids, ``hand_box_frac`` of the box's height above its bottom, at the person's
   depth: the tracked places of the two are off by decimetres on real video), else at
   ``hand_frac`` of the person's stature, ``meet_touch`` of the way to the one they hold it out to
   (the real second person across the view, else the partner). With ``step_in`` the partner
   stands to take it, its arm's length (``STEP_REACH`` of it) beyond the hand, no nearer than
   ``take_min_m`` (an outline that ends short of the hand, or at the split of a hug, would put it
   inside the arm held out);
4. the lowest ankle is brought into [0, ``max_ankle_m``] above the ground plane y = 0 (a partner
   may hop, never sink into the floor or float);
5. then (:meth:`Stage.finish`) its arms: while a push goes on or it recoils from one it guards, its
   arms drawn in before its chest (:func:`guard_arms`: a partner reaching for the pusher's hand has
   its arm inside the pusher while it is thrown back); else its hand meets the hand offered or the
   one it comes near (:func:`.reach.reach`). Last, as drawn (its arms set), it keeps clear of the
   person's box in the picture (``clear_iou``, ``clear_inside``) whatever the speed limit left, its
   body that is: an arm that took the other's hand is where the two touch. Not while pushed, where
   the push places it (the pusher's arm is on it).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from counterpart.body.camera import Camera
from counterpart.body.skeleton import JOINT_INDEX, bone_lengths, with_bone_lengths

from .frames import actor_frame
from .reach import ARMS, ReachConfig, reach, two_bone_ik

_ANKLES = [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]]
_ARMS = [JOINT_INDEX[j] for j in ("l_elbow", "r_elbow", "l_wrist", "r_wrist")]
_WRISTS = [JOINT_INDEX["l_wrist"], JOINT_INDEX["r_wrist"]]
_NECK, _HIPS = JOINT_INDEX["neck"], [JOINT_INDEX["l_hip"], JOINT_INDEX["r_hip"]]
_SHOULDERS = [JOINT_INDEX["l_shoulder"], JOINT_INDEX["r_shoulder"]]
#: the ground direction (x, z) across the camera's view, image right, without a camera: that of a
#: camera looking along -Z with no yaw (the default camera, calibration.estimate.rotation)
ACROSS = np.array([1.0, 0.0])
#: the heights of the arms (hips to shoulders, a little either way) as fractions of a person's height
ARM_BAND = (0.35, 0.85)
#: a silhouette centre moving faster than this is a region merging or splitting, not a body, m/s
JUMP_M_S = 3.0
#: a partner taking an offered hand stands at most this fraction of its arm's length beyond the hand
#: (its shoulder is to the side and above the hand: the arm's length does not all go across)
STEP_REACH = 0.8
#: the share of the way the smoothed held-out hand's height moves to a new sighting per frame
HEIGHT_RATE = 0.3
#: crown of the head above the head joint (the head centre at eye level), metres, for a stature
HEAD_TOP_M = 0.12
#: a guarding arm's wrist (:func:`guard_arms`): this fraction of the way down the torso from the neck
#: to the mid-hip, this fraction of the way from the body's midline out to its shoulder, and this far
#: in front of the chest (metres)
GUARD_DOWN, GUARD_OUT, GUARD_FRONT_M = 0.35, 0.5, 0.12
#: where the partner's bone lengths come from (:attr:`StageConfig.bones`)
BONES = ("observed", "model")
#: the share of the way the partner's bone lengths move to the observed person's per frame
BONE_RATE = 0.2
#: the hand contact's distances where the caller gives none (:meth:`Stage.finish`)
REACH = ReachConfig()


@dataclass(frozen=True)
class StageConfig:
    """Limits of the partner's placement and its responses (metres, metres per second, seconds).

    Parameters
    ----------
    min_distance_m, max_distance_m : float, default=0.5, 1.2
        The range of the partner's ground distance from the observed person, metres.
    max_speed_m_s : float, default=2.5
        The most the partner's ground offset changes per second, metres per second.
    max_ankle_m : float, default=0.3
        The highest the lowest ankle may be above the ground plane, metres.
    contact_m : float, default=0.2
        A reach of the observed person within this distance of the partner's torso axis is a push, metres.
    recoil_m : float, default=0.3
        The most the partner gives way while pushed, metres, and the room it keeps for its recoil
        within ``max_distance_m`` (0: it does not recoil).
    recoil_max_m : float, default=0.4
        How far the partner is thrown back when the push is released, metres from where the push
        landed, within ``max_distance_m``.
    recoil_s : float, default=0.4
        Time constant of the recoil's fading once the partner has been thrown back, seconds.
    beside : bool, default=True
        Stand beside the observed person across the camera's view, at their depth (False: in the
        model's direction).
    side_margin_m : float, default=0.2
        How far on the other side of the observed person the real second person must be before the
        partner changes side, metres.
    offer_m : float, default=0.45
        A silhouette reaching this far towards the partner from its centre is a hand held out,
        metres (:attr:`Stage.offered_`).
    meet_frac : float, default=0.7
        A hand held out is met at most this fraction of the way to the partner (hands meet between
        the two; a silhouette merged with someone else's reaches further than the hand).

    push_speed_m_s : float, default=0.5
        A silhouette holding a hand out (``offer_m``) whose centre advances towards the partner at
        least this fast is a push (the torso and the arm forward together), metres per second.
    advance_s : float, default=0.15
        Time constant of the smoothing of that advance, seconds (steps faster than
        ``JUMP_M_S``, a region merging or splitting, are left out).
    push_touch : bool, default=True
        A silhouette push needs the silhouette to touch someone else's (:attr:`Reach.touching`):
        a pusher walks in with the arm out well before the hand lands.
    hand_frac : float, default=0.66
        The height of a hand held out while the silhouette touches someone else's, fraction of the
        person's stature above their lowest ankle (where the regions were split, the outline's tip
        says nothing of the hand's height); 0: the outline's tip as elsewhere.
    recoil_speed_m_s : float, default=0.75
        How fast the partner is thrown back when the push is released, metres per second (the
        return is the fading, ``recoil_s``).
    yield_speed_m_s : float, default=0.2
        How fast the partner gives way while the push goes on, metres per second (a pushed person
        is thrown back mostly when the push is released).
    meet_touch : float, default=0.45
        Where the silhouette touches someone else's, the offered hand is met this fraction of the way
        from the observed person to the one they hold it out to (the real second person where one is
        tracked, else the partner): the outline's tip is then where the regions were split, not the hand.
    step_in : bool, default=True
        A partner taking an offered hand stands to take it: ``STEP_REACH`` of its arm's length beyond
        the hand (stepping in from further, out from nearer), no nearer than ``take_min_m``, within the
        distance limits.
    push_height : float, default=0.7
        A silhouette push needs the hand held out to have been seen high, at this fraction of the
        person's stature or above (smoothed, where the silhouette touched no one's: there its
        outline's tip is the hand): a push lands on the chest, a hand to shake is held lower
        (people walking in to shake hands are no push); 0: any height.
    push_rush_m_s : float, default=1.0
        A silhouette holding a hand out whose centre advances towards the partner at least this
        fast is a push whatever the hand's height (``push_height``), metres per second: people come
        up to shake hands more slowly.
    offer_hold_s : float, default=0.3
        A hand held out stays held out this long after the silhouette last reached ``offer_m``,
        seconds (an outline's tip flickers about the limit while the hand stays out).
    hand_box_frac : float, default=0.62
        With a camera, the observed person's box and the other person's region, a hand held out while
        the silhouettes touch lies at this fraction of the box's height above its bottom, ``meet_touch``
        of the way between the two regions' centroids across the picture; 0: placed from the tracked
        bodies (``hand_frac``) as without them.
    tip_in_picture : bool, default=True
        With a camera and the observed person's box, a hand held out while the silhouette touches no
        one else's lies where the outline's tip is in the picture (:func:`silhouette_tip_px`), at the
        depth of the person's hips, up to ``meet_frac`` of ``max_distance_m`` out (the partner stands to
        take it there): the tracked body's place is off by decimetres on real video, and a hand met at
        ``meet_frac`` of the model's distance lies inside the arm held out. False: from the tracked body.
    tip_back : float, default=0.07
        With ``tip_in_picture``, the hand is met this fraction of the person's stature short of the
        outline's tip, towards the person: the tip is the fingertips, a hand's length beyond the wrist,
        and clasping hands' wrists are about half a hand apart.
    take_min_m : float, default=1.0
        With ``step_in``, the nearest the partner stands to take an offered hand, metres (within the
        distance limits): the outline may end short of the hand (a sleeve like the background, an arm
        pointing) or at the split of two regions (arms round the other, a hug), and an arm's length
        beyond that point is inside the arm held out. People shaking hands stand further apart than
        this: there it changes nothing.
    clear_iou : float, default=0.15
        With a camera and the observed person's silhouette box, the most the partner's projected
        box may overlap that box (intersection over union) before it stands further away.
    clear_inside : float, default=0.6
        With a camera and the observed person's silhouette box, the most of the partner's own
        projected box that may lie inside that box (a silhouette with an arm held out, or shared
        with another person's, is so much larger than the partner that the union stays large).
    bones : {"observed", "model"}, default="observed"
        The partner's bone lengths. "observed": the observed person's (smoothed over frames,
        ``BONE_RATE``), the model's pose kept bone by bone (:func:`counterpart.body.skeleton.with_bone_lengths`):
        a model's generated joints do not keep one body (their limbs stretch and shrink from frame
        to frame), and a partner of the observed person's build standing at their depth is drawn at
        their size in the picture whatever the camera's error, as the tracked body was fitted to
        the picture through the same camera. "model": as the model gives them.

    Raises
    ------
    ValueError
        If the limits are inconsistent (min > max, negative values, non-positive speed or time constant).
    """

    min_distance_m: float = 0.5
    max_distance_m: float = 1.2
    max_speed_m_s: float = 2.5
    max_ankle_m: float = 0.3
    contact_m: float = 0.2
    recoil_m: float = 0.3
    recoil_s: float = 0.4
    recoil_max_m: float = 0.4
    beside: bool = True
    side_margin_m: float = 0.2
    offer_m: float = 0.45
    meet_frac: float = 0.7
    push_speed_m_s: float = 0.5
    advance_s: float = 0.15
    clear_iou: float = 0.15
    clear_inside: float = 0.6
    push_touch: bool = True
    hand_frac: float = 0.66
    recoil_speed_m_s: float = 0.75
    meet_touch: float = 0.45
    step_in: bool = True
    push_height: float = 0.7
    yield_speed_m_s: float = 0.2
    push_rush_m_s: float = 1.0
    offer_hold_s: float = 0.3
    hand_box_frac: float = 0.62
    tip_in_picture: bool = True
    tip_back: float = 0.07
    take_min_m: float = 1.0
    bones: str = "observed"

    def __post_init__(self) -> None:
        if not 0.0 <= self.min_distance_m <= self.max_distance_m:
            raise ValueError(
                f"partner distance limits [{self.min_distance_m}, {self.max_distance_m}] m: need 0 <= min <= max"
            )
        if self.max_speed_m_s <= 0 or self.max_ankle_m < 0:
            raise ValueError(f"max_speed_m_s={self.max_speed_m_s} must be > 0 and max_ankle_m={self.max_ankle_m} >= 0")
        if self.contact_m < 0 or self.recoil_m < 0 or self.recoil_s <= 0:
            raise ValueError(
                f"contact_m={self.contact_m}, recoil_m={self.recoil_m} must be >= 0 and recoil_s={self.recoil_s} > 0"
            )
        if self.recoil_speed_m_s <= 0 or self.yield_speed_m_s < 0:
            raise ValueError(
                f"recoil_speed_m_s={self.recoil_speed_m_s} must be > 0 and yield_speed_m_s={self.yield_speed_m_s} >= 0"
            )
        if self.offer_hold_s < 0 or not 0.0 <= self.hand_box_frac <= 1.0:
            raise ValueError(
                f"offer_hold_s={self.offer_hold_s} must be >= 0 and hand_box_frac={self.hand_box_frac} in [0, 1]"
            )
        if self.tip_back < 0 or self.take_min_m < 0:
            raise ValueError(f"tip_back={self.tip_back} and take_min_m={self.take_min_m} must be >= 0")
        if not (0.0 <= self.clear_iou <= 1.0 and 0.0 <= self.clear_inside <= 1.0):
            raise ValueError(f"clear_iou={self.clear_iou} and clear_inside={self.clear_inside} must be in [0, 1]")
        if self.bones not in BONES:
            raise ValueError(f"bones={self.bones!r}: choose one of {BONES}")
        if self.side_margin_m < 0 or self.offer_m < 0:
            raise ValueError(f"side_margin_m={self.side_margin_m} and offer_m={self.offer_m} must be >= 0")


def guard_arms(joints: np.ndarray, toward: np.ndarray) -> np.ndarray:
    """The body with its arms drawn in before its chest, elbows down: how a pushed person holds them.

    Each wrist goes ``GUARD_FRONT_M`` in front of the chest (towards ``toward``), ``GUARD_DOWN`` of the
    way down the torso from the neck and ``GUARD_OUT`` of the way out to its shoulder; the elbow bends
    below the shoulder (:func:`.reach.two_bone_ik`, bone lengths kept). A partner reaching for the one
    who pushes it has its arm inside them while it is thrown back.

    Parameters
    ----------
    joints : ndarray of shape (14, 3)
        World joints, metres, Y up.
    toward : ndarray of shape (2,)
        Ground direction (x, z) the body faces (to the pusher); need not be unit.

    Returns
    -------
    ndarray of shape (14, 3)
        A new array of ``joints``' dtype, world metres; only the elbows and wrists moved.
    """
    X = np.asarray(joints, np.float64).copy()
    n = float(np.hypot(*toward))
    front = np.zeros(3) if n < 1e-9 else np.array([toward[0] / n, 0.0, toward[1] / n])
    neck, hips = X[_NECK], X[_HIPS].mean(axis=0)
    chest = neck + GUARD_DOWN * (hips - neck) + GUARD_FRONT_M * front
    down = np.array([0.0, -1.0, 0.0])
    for s, e, w in ARMS:
        a, b = float(np.linalg.norm(X[e] - X[s])), float(np.linalg.norm(X[w] - X[e]))
        # start from the arm hanging down, so the elbow bends below the shoulder
        elbow, wrist = X[s] + a * down, X[s] + (a + b) * down
        X[e], X[w] = two_bone_ik(X[s], elbow, wrist, chest + GUARD_OUT * (X[s] - neck))
    return X.astype(np.asarray(joints).dtype)


def across_view(R: np.ndarray) -> np.ndarray:
    """The ground direction across a camera's view, towards image right.

    The camera's x axis in world coordinates is the first row of its world-to-camera rotation
    (``X_c = R X_w + t``); dropped onto the ground plane (world Y up) it is the direction along
    which a point moves right in the picture at constant depth, whatever the camera's yaw.

    Parameters
    ----------
    R : ndarray of shape (3, 3)
        World-to-camera rotation.

    Returns
    -------
    ndarray of shape (2,)
        Unit ground vector (x, z); ``ACROSS`` for a camera whose x axis is vertical (rolled 90 degrees).
    """
    x = np.asarray(R, np.float64).reshape(3, 3)[0, [0, 2]]
    n = float(np.hypot(*x))
    return x / n if n > 1e-6 else ACROSS.copy()


def stature(joints: np.ndarray) -> float:
    """A body's height, metres: its head joint above its lowest ankle plus the crown (``HEAD_TOP_M``).

    Parameters
    ----------
    joints : ndarray of shape (14, 3)
        World joints, metres, Y up.

    Returns
    -------
    float
        Metres.
    """
    X = np.asarray(joints, np.float64)
    return float(X[JOINT_INDEX["head"], 1] - X[_ANKLES, 1].min() + HEAD_TOP_M)


class Reach(NamedTuple):
    """What a person's silhouette says of their reach towards the partner (:func:`silhouette_reach`).

    Attributes
    ----------
    extent_m : float
        How far the silhouette's leading point lies from its centre towards the partner, metres.
    height_m : float or None
        That point's height above the ground, metres (None: not known).
    centre_m : float
        The silhouette's centre across the view towards the partner, metres at the person's depth
        from an arbitrary origin: only its changes mean anything (the body advancing).
    touching : bool, default=False
        Whether the silhouette touches someone else's (its region was shared with another person's
        and split, ``silhouette.Person.merged``).
    centre_px : tuple of float or None, default=None
        The region's centroid ``(x, y)``, pixels (None: not known).
    other_px : tuple of float or None, default=None
        The centroid ``(x, y)`` of the other person's region, pixels, where one is seen (None: none):
        a hand held out to them while the regions touch lies between the two.
    """

    extent_m: float
    height_m: float | None
    centre_m: float
    touching: bool = False
    centre_px: tuple[float, float] | None = None
    other_px: tuple[float, float] | None = None


def silhouette_reach(
    bbox: tuple[float, float, float, float],
    centroid: tuple[float, float],
    direction: float,
    stature_m: float,
    ctrl: np.ndarray | None = None,
    band: tuple[float, float] = ARM_BAND,
    touching: bool = False,
    other: tuple[float, float] | None = None,
) -> Reach:
    """How far a person's silhouette extends towards ``direction`` from its centre, how high, and where
    its centre is, metres.

    The silhouette's leading point on that side (of its outline's control points at the heights
    of the arms, ``band``, the one furthest that way: a stride's foot or a turned head is not a
    reach; without an outline, the box's edge), from the region's centroid column, over the box's height,
    times the person's stature: an arm held out or a body leaning in moves it, whatever the
    tracked arm does. Its height is the point's height above the box's bottom (the feet) the
    same way. Pixels across and down scale alike at the person's depth, so no camera is needed.

    Parameters
    ----------
    bbox : tuple of float
        The silhouette's box ``(x, y, w, h)``, pixels.
    centroid : tuple of float
        The region's centroid ``(x, y)``, pixels.
    direction : float
        +1: towards image right (world +X), -1: towards image left.
    stature_m : float
        The person's height, metres (:func:`stature`).
    ctrl : ndarray of shape (n, 2) or None, default=None
        The outline's B-spline control points, pixels (None or empty: the box's edge).
    band : tuple of float, default=ARM_BAND
        The heights a reach is looked for at, fractions of the box's height above its bottom.
    touching : bool, default=False
        Whether the silhouette touches someone else's (``silhouette.Person.merged``).
    other : tuple of float or None, default=None
        The centroid ``(x, y)`` of the other person's region, pixels (None: none seen).

    Returns
    -------
    Reach
        Metres (extent 0 for an empty box; height None without an outline).
    """
    x, y, w, h = (float(v) for v in bbox)
    if h <= 0:
        return Reach(0.0, None, 0.0, touching, None, other)
    pts = None if ctrl is None else np.asarray(ctrl, np.float64).reshape(-1, 2)
    if pts is not None:
        up = (y + h - pts[:, 1]) / h
        pts = pts[(up >= band[0]) & (up <= band[1])]
    if pts is not None and len(pts):
        tip = pts[int(np.argmax(direction * pts[:, 0]))]
        edge, height = float(tip[0]), (y + h - float(tip[1])) / h * stature_m
    else:
        edge, height = (x + w if direction > 0 else x), None
    cx = float(centroid[0])
    extent = max(direction * (edge - cx), 0.0) / h * stature_m
    centre = (cx, float(centroid[1]))
    return Reach(extent, height, direction * cx / h * stature_m, touching, centre, other)


def whole_box(
    box: tuple[float, float, float, float], frame_height: int, joints: np.ndarray, camera: Camera | None
) -> tuple[float, float, float, float]:
    """A person's box, continued below the frame where its bottom edge cuts them off (someone near
    the camera): down to the lowest row the tracked body's ankles stand on, so that the heights
    and reaches measured in fractions of the box (:func:`silhouette_reach`) are fractions of the
    whole person. Unchanged for a box clear of the bottom edge, or without a camera.

    Parameters
    ----------
    box : tuple of float
        The silhouette's box ``(x, y, w, h)``, pixels.
    frame_height : int
        The frame's height, pixels (0: not known).
    joints : ndarray of shape (14, 3)
        The tracked body's world joints, metres, Y up.
    camera : Camera or None
        The camera of the frame.

    Returns
    -------
    tuple of float
        ``(x, y, w, h)``, pixels.
    """
    x, y, w, h = (float(v) for v in box)
    if camera is None or frame_height <= 0 or y + h < frame_height:
        return x, y, w, h
    soles = np.asarray(joints, np.float64)[_ANKLES] * [1.0, 0.0, 1.0]
    feet = float(np.max(camera.project(soles)[:, 1]))
    if not np.isfinite(feet) or feet <= y + h:
        return x, y, w, h
    return x, y, w, feet - y


def observed_silhouette(
    shapes: list,
    person_id: int,
    side: str,
    joints: np.ndarray,
    direction: float,
    camera: Camera | None = None,
    frame_height: int = 0,
) -> tuple[Reach | None, tuple[float, float, float, float] | None]:
    """The observed person's silhouette among a frame's, and what it says of their reach towards
    the partner (:func:`silhouette_reach`), as the responder node finds them.

    Of the silhouettes on their ``side``, the one with the tracked person's id, else the first;
    its box continued below the frame where the frame cuts them off (:func:`whole_box`); the other
    person's region is the one off their side nearest theirs across the picture (a hand held out
    to them lies between the two). A region shared with the other person is split: its box is theirs.

    Parameters
    ----------
    shapes : list of silhouette.PersonShape
        The frame's silhouettes.
    person_id : int
        The tracked person's id.
    side : str
        Their side of the frame.
    joints : ndarray of shape (14, 3)
        Their tracked world joints, metres.
    direction : float
        +1: the partner stands towards image right, -1: left, 0: not known (no reach).
    camera : Camera or None, default=None
        The camera of the frame (:func:`whole_box`).
    frame_height : int, default=0
        The frame's height, pixels (0: not known).

    Returns
    -------
    reach : Reach or None
        None without a silhouette on their side or a direction.
    box : tuple of float or None
        Their box ``(x, y, w, h)``, pixels; None without a silhouette.
    """
    mine = [q for q in shapes if q.side == side]
    shape = next((q for q in mine if q.id == person_id), mine[0] if mine else None)
    if shape is None:
        return None, None
    box = whole_box(tuple(shape.bbox), frame_height, joints, camera)
    if direction == 0.0:
        return None, box
    theirs = [q for q in shapes if q.side != side]
    near = min(theirs, key=lambda q: abs(float(q.centroid[0]) - float(shape.centroid[0])), default=None)
    reach = silhouette_reach(
        box,
        shape.centroid,
        direction,
        stature(joints),
        shape.ctrl,
        touching=bool(getattr(shape, "merged", False)),
        other=None if near is None else (float(near.centroid[0]), float(near.centroid[1])),
    )
    return reach, box


def touching_hand_px(
    silhouette: Reach, box: tuple[float, float, float, float], meet: float, box_frac: float
) -> tuple[float, float] | None:
    """Where, in the picture, a person holds a hand out to the one whose silhouette theirs touches.

    Hands held out to each other meet between the two people: ``meet`` of the way from the person's
    region's centroid to the other's across the picture, at ``box_frac`` of the person's box height
    above its bottom. Pixels need neither a tracked depth nor a body size (the tracked places of two
    people are off by decimetres on real video), and where the regions were split the outline's tip
    is the split, not the hand.

    Parameters
    ----------
    silhouette : Reach
        The person's reach, with ``centre_px`` and ``other_px`` (:func:`silhouette_reach`).
    box : tuple of float
        The person's silhouette box ``(x, y, w, h)``, pixels.
    meet : float
        Fraction of the way from the person's centroid to the other's.
    box_frac : float
        Fraction of the box's height above its bottom.

    Returns
    -------
    tuple of float or None
        ``(u, v)`` pixels; None without both centroids or with an empty box.
    """
    if silhouette.centre_px is None or silhouette.other_px is None or float(box[3]) <= 0:
        return None
    u = float(silhouette.centre_px[0]) + meet * (float(silhouette.other_px[0]) - float(silhouette.centre_px[0]))
    return u, float(box[1]) + float(box[3]) * (1.0 - box_frac)


def silhouette_tip_px(
    silhouette: Reach, box: tuple[float, float, float, float], stature_m: float, direction: float
) -> tuple[float, float] | None:
    """The outline's leading point towards the partner in the picture, as :func:`silhouette_reach` found it.

    Inverts :func:`silhouette_reach`'s scaling: ``extent_m`` and ``height_m`` are pixels over the box's
    height times ``stature_m``, so the point lies ``extent_m / stature_m`` box heights from the region's
    centroid column towards ``direction`` and ``height_m / stature_m`` box heights above the box's bottom.

    Parameters
    ----------
    silhouette : Reach
        The person's reach (:func:`silhouette_reach`), with ``centre_px`` and ``height_m``.
    box : tuple of float
        The person's silhouette box ``(x, y, w, h)``, pixels (the one the reach was found in).
    stature_m : float
        The stature the reach was scaled with, metres.
    direction : float
        The side the reach was found towards: +1 image right, -1 image left.

    Returns
    -------
    tuple of float or None
        ``(u, v)`` pixels; None without the centroid or the height, or with an empty box or stature.
    """
    h = float(box[3])
    if silhouette.centre_px is None or silhouette.height_m is None or h <= 0 or stature_m <= 0:
        return None
    cx = float(silhouette.centre_px[0])
    u = cx + float(np.sign(direction)) * silhouette.extent_m / stature_m * h
    v = float(box[1]) + h - silhouette.height_m / stature_m * h
    return u, v


def _at_depth(camera: Camera, px: tuple[float, float], X: np.ndarray) -> np.ndarray | None:
    """The point of pixel ``px`` ``(u, v)`` at the depth of the hips of the body X (14, 3), world metres
    (3,); None where the ray does not go forward or the hips are behind the camera.
    """
    ray = camera.rays(np.array(px[0]), np.array(px[1]))
    along = float(ray @ camera.R[2])
    depth = float(camera.depth(X[_HIPS].mean(axis=0)))
    if along <= 1e-6 or depth <= 1e-3:
        return None
    return camera.centre + depth / along * ray


def _arm_length(joints: np.ndarray) -> float:
    """The mean length of a body's arms, shoulder to elbow to wrist, metres; joints (14, 3)."""
    X = np.asarray(joints, np.float64)
    s, e, w = (X[[JOINT_INDEX[f"{k}_{j}"] for k in "lr"]] for j in ("shoulder", "elbow", "wrist"))
    return float(np.mean(np.linalg.norm(e - s, axis=1) + np.linalg.norm(w - e, axis=1)))


def _segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distances (N,) of points (N, 3) from the segment a-b (3,) each, metres."""
    ab = b - a
    t = np.clip((points - a) @ ab / max(float(ab @ ab), 1e-12), 0.0, 1.0)
    return np.linalg.norm(points - (a + t[:, None] * ab), axis=1)


def _clip_length(d: np.ndarray, facing: float, lo: float, hi: float) -> np.ndarray:
    """Ground vector d (2,) (x, z) with its length clipped to [lo, hi]; the facing direction
    (heading ``facing``, radians) where d is too short to have one.
    """
    r = float(np.hypot(*d))
    u = d / r if r > 1e-6 else np.array([np.sin(facing), np.cos(facing)])
    return u * min(max(r, lo), hi)


def _box_overlap(boxes: np.ndarray, box: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Intersection over union (K,) of boxes (K, 4) with one box (4,), each (x0, y0, x1, y1), pixels,
    and the share (K,) of each of ``boxes`` that lies in ``box``.
    """
    w = np.clip(np.minimum(boxes[:, 2], box[2]) - np.maximum(boxes[:, 0], box[0]), 0.0, None)
    h = np.clip(np.minimum(boxes[:, 3], box[3]) - np.maximum(boxes[:, 1], box[1]), 0.0, None)
    inter = w * h
    own = (boxes[:, 2] - boxes[:, 0]) * (boxes[:, 3] - boxes[:, 1])
    union = own + (box[2] - box[0]) * (box[3] - box[1]) - inter
    iou = np.where(union > 0, inter / np.maximum(union, 1e-12), 0.0)
    return iou, np.where(own > 0, inter / np.maximum(own, 1e-12), 0.0)


def clear_length(
    partner: np.ndarray,
    shift: np.ndarray,
    u: np.ndarray,
    lengths: np.ndarray,
    camera: Camera,
    box: tuple[float, float, float, float],
    max_iou: float,
    max_inside: float = 1.0,
) -> float:
    """The first of ``lengths`` at which the partner's projected box overlaps ``box`` by at most ``max_iou``
    and has at most ``max_inside`` of itself inside it.

    Parameters
    ----------
    partner : ndarray of shape (n, 3)
        The partner's joints (all 14, or those that must keep clear), world metres.
    shift : ndarray of shape (2,)
        Ground shift (x, z) that puts the partner at the observed person's place, metres.
    u : ndarray of shape (2,)
        Unit ground direction (x, z) from the observed person to the partner.
    lengths : ndarray of shape (K,)
        Candidate distances along ``u``, increasing, metres.
    camera : Camera
        The camera of the picture.
    box : tuple of float
        The observed person's silhouette box ``(x, y, w, h)``, pixels.
    max_iou : float
        Largest overlap allowed (intersection over union).
    max_inside : float, default=1.0
        Largest share of the partner's own box allowed inside ``box`` (a box much larger than the
        partner's, a person with an arm held out, leaves the union large whatever the partner's place).

    Returns
    -------
    float
        That length, metres; the one of least overlap where none is clear enough.
    """
    g = shift[None] + lengths[:, None] * u[None]  # (K, 2)
    X = np.asarray(partner, np.float64)[None] + np.stack([g[:, 0], np.zeros(len(g)), g[:, 1]], axis=1)[:, None]
    uv = camera.project(X)  # (K, 14, 2)
    boxes = np.concatenate([np.nanmin(uv, axis=1), np.nanmax(uv, axis=1)], axis=1)
    x, y, w, h = (float(v) for v in box)
    iou, inside = (np.nan_to_num(v, nan=0.0) for v in _box_overlap(boxes, np.array([x, y, x + w, y + h])))
    # the worse of the two overlaps, as a share of its limit
    score = np.maximum(iou / max(max_iou, 1e-9), inside / max(max_inside, 1e-9))
    ok = np.flatnonzero(score <= 1.0)
    return float(lengths[ok[0]] if len(ok) else lengths[int(np.argmin(score))])


def _walk(start: np.ndarray, goal: np.ndarray, limit: float) -> np.ndarray:
    """Ground offset (2,) from ``start`` towards ``goal`` (both (2,), metres, non-zero), moved at most
    about ``limit`` metres: in polar coordinates about the person, so that a partner going to the
    other side walks round them rather than through them.
    """
    r0, r1 = float(np.hypot(*start)), float(np.hypot(*goal))
    a0, a1 = np.arctan2(start[1], start[0]), np.arctan2(goal[1], goal[0])
    da = (a1 - a0 + np.pi) % (2 * np.pi) - np.pi
    dr = r1 - r0
    length = float(np.hypot(0.5 * (r0 + r1) * da, dr))
    if length <= limit:
        return goal
    f = limit / length
    r, a = r0 + f * dr, a0 + f * da
    return np.array([r * np.cos(a), r * np.sin(a)])


class Stage:
    """Keeps a generated partner where a partner would stand, frame by frame.

    Parameters
    ----------
    config : StageConfig
        the limits.

    Attributes
    ----------
    corrected : int
        Frames on which the model's placement was moved.
    pushes : int
        Pushes the partner recoiled from.
    offered_ : ndarray of shape (3,) or None
        After a call: where the observed person holds out a hand towards the partner (their
        silhouette reaching at least ``offer_m`` towards it, not a push), world metres, at the height
        of the silhouette's leading point (else of their tracked wrist nearest the partner) kept
        between their hips and shoulders; None when
        they hold none out (for :func:`.reach.reach`).
    """

    def __init__(self, config: StageConfig = StageConfig()) -> None:
        self.config = config
        self.corrected = 0  # frames on which the model's placement was moved
        self.reset()

    def reset(self) -> None:
        """Forget the last placement (another person observed, or a new stream)."""
        self._last: np.ndarray | None = None  # the last ground offset from the observed person
        self._side = 0.0  # the side across the view the partner stands on (+1: image right), 0: none yet
        self._recoil = 0.0  # metres added to the partner's distance by a push, fading
        self._recoil_goal = 0.0  # where the recoil is going: recoil_m on a push, fading after
        self._touching = False
        self._pushed = False  # a push goes on (see __call__)
        self._base = 0.0  # the partner's distance where the push landed, metres
        self._height: float | None = None  # the held-out hand's smoothed height, fraction of the stature
        self._centre: float | None = None  # the silhouette's last centre across the view, metres
        self._advance = 0.0  # its smoothed speed towards the partner, metres per second
        self._since_offer = np.inf  # seconds since the silhouette last reached offer_m
        self.pushes = 0  # pushes the partner recoiled from
        self.offered_: np.ndarray | None = None
        self._scene: tuple[Camera | None, tuple[float, float, float, float] | None, np.ndarray] | None = None
        self._bones: np.ndarray | None = None  # the partner's bone lengths (bones="observed"), metres

    def _on_bones(self, observed: np.ndarray, partner: np.ndarray) -> np.ndarray:
        """The partner's pose on its bones (:attr:`StageConfig.bones`)."""
        if self.config.bones == "model":
            return partner
        lengths = bone_lengths(observed)
        if np.isfinite(lengths).all():
            self._bones = lengths if self._bones is None else self._bones + BONE_RATE * (lengths - self._bones)
        return partner if self._bones is None else with_bone_lengths(partner, self._bones)

    @property
    def pushed(self) -> bool:
        """Whether a push goes on (after a call): the partner gives way and takes no hand."""
        return self._pushed

    @property
    def guarding(self) -> bool:
        """Whether the partner guards (after a call): a push goes on or it recoils from one; it takes no
        hand and holds its arms in (:func:`guard_arms`).
        """
        return self._pushed or self._recoil_goal > 0.01

    def finish(
        self, observed: np.ndarray, staged: np.ndarray, reach_config: ReachConfig | None = REACH
    ) -> tuple[np.ndarray, float]:
        """The partner's arms and its final place, after a call (``staged``: what it returned).

        While it guards (:attr:`guarding`) its arms are drawn in (:func:`guard_arms`), facing the
        observed person; else its hand meets the hand offered (:attr:`offered_`) or the one it comes
        near (:func:`.reach.reach`, with ``reach_config``; None: no reach). Last, with the call's
        camera and the observed person's box, the partner as drawn keeps clear of that box
        (``clear_iou``, ``clear_inside``, :func:`clear_length`): where its arms bring it into it, it
        stands further away, within ``max_distance_m`` (its next placement walks on from there).

        Parameters
        ----------
        observed : ndarray of shape (14, 3)
            The observed person's world joints, metres (as given to the call).
        staged : ndarray of shape (14, 3)
            The partner the call returned, world metres.
        reach_config : ReachConfig or None, default=REACH
            The hand contact's distances; None: the model's arms are kept (guarding aside).

        Returns
        -------
        partner : ndarray of shape (14, 3)
            A new array of ``staged``'s dtype, world metres.
        pull : float
            The hand contact's pull in [0, 1] (0 while guarding or without reach).
        """
        P, pull = np.asarray(staged), 0.0
        if self._last is None or self._scene is None:
            return P.copy(), pull
        if self.guarding:
            P = guard_arms(P, -self._last)
        elif reach_config is not None:
            P, pull = reach(observed, P, reach_config, self.offered_)
        # an arm that took the other's hand is where the two touch, not in them
        keep = np.ones(len(P), dtype=bool)
        for _, e, w in ARMS:
            if pull > 0 and np.abs(np.asarray(P[w], np.float64) - np.asarray(staged[w], np.float64)).max() > 1e-9:
                keep[[e, w]] = False
        camera, box, o = self._scene
        r = float(np.hypot(*self._last))
        if camera is None or box is None or r <= 1e-6 or self.guarding:
            return P.copy(), pull
        c = self.config
        u = self._last / r
        p = actor_frame(np.asarray(P, np.float64))[0][[0, 2]]
        lengths = np.linspace(r, max(r, c.max_distance_m), 8)
        length = clear_length(P[keep], o - p, u, lengths, camera, box, c.clear_iou, c.clear_inside)
        if length > r + 1e-9:
            shift = np.zeros(3)
            shift[[0, 2]] = (length - r) * u
            P = (np.asarray(P, np.float64) + shift).astype(np.asarray(staged).dtype)
            self._last = u * length
        return P.copy(), pull

    @property
    def side(self) -> float:
        """The side across the view the partner stands on: +1 image right (world +X), -1 left, 0 not yet placed."""
        return self._side

    def _choose_side(
        self, o: np.ndarray, other: np.ndarray | None, side: float, model: np.ndarray, across: np.ndarray
    ) -> float:
        """The side across the view (+1 / -1) the partner stands on; see the module's step 1."""
        if other is not None and np.isfinite(other).all():
            across = float((actor_frame(np.asarray(other, np.float64))[0][[0, 2]] - o) @ across)
            if self._side == 0.0 or (np.sign(across) != self._side and abs(across) > self.config.side_margin_m):
                self._side = float(np.sign(across)) or self._side
        if self._side == 0.0:
            self._side = float(np.sign(side)) or float(np.sign(model @ across))
        return self._side

    def _gap_to(self, o: np.ndarray, other: np.ndarray | None, offset: np.ndarray, u: np.ndarray) -> float:
        """The distance (metres) from the observed person (``o``, (2,)) to the one they hold a hand out
        to: the real second person where one is tracked (across the view, ``u`` (2,): a tracked depth
        is off by far more than a place in the picture), else the partner (``offset``, (2,)); within
        the partner's distance limits.
        """
        gap = float(np.hypot(*offset))
        if other is not None and np.isfinite(other).all():
            gap = abs(float((actor_frame(np.asarray(other, np.float64))[0][[0, 2]] - o) @ u))
        return float(np.clip(gap, self.config.min_distance_m, self.config.max_distance_m))

    def _held_high(self, silhouette: Reach | None, X: np.ndarray, held_out: bool) -> bool:
        """Whether the hand the observed person holds out, as last seen apart from anyone else's silhouette
        (there the outline's tip is the hand), is held high (``push_height``): a push lands on the
        chest, a hand to shake is held at the waist. True while not yet seen so.
        """
        if held_out and not silhouette.touching and silhouette.height_m is not None:
            frac = silhouette.height_m / max(stature(X), 1e-6)
            self._height = frac if self._height is None else self._height + HEIGHT_RATE * (frac - self._height)
        return self._height is None or self._height >= self.config.push_height

    def _holding_out(self, silhouette: Reach | None, dt: float) -> bool:
        """Whether the observed person holds a hand out towards the partner: their silhouette reaching
        ``offer_m`` or more, or having done so within the last ``offer_hold_s`` (an outline's tip
        flickers about the limit while the hand stays out).
        """
        if silhouette is None:
            self._since_offer = np.inf
            return False
        self._since_offer = 0.0 if silhouette.extent_m >= self.config.offer_m else self._since_offer + dt
        return self._since_offer <= self.config.offer_hold_s

    def _hand_in_picture(
        self, silhouette: Reach, camera: Camera | None, box: tuple[float, float, float, float] | None, X: np.ndarray
    ) -> np.ndarray | None:
        """Where a hand held out to the other person lies while the two silhouettes touch, world metres (3,):
        :func:`touching_hand_px` back-projected to the depth of the observed person's hips; None without
        the camera, the box or the other's region.
        """
        c = self.config
        px = (
            None
            if box is None or c.hand_box_frac <= 0
            else touching_hand_px(silhouette, box, c.meet_touch, c.hand_box_frac)
        )
        return None if camera is None or px is None else _at_depth(camera, px, X)

    def _tip_in_picture(
        self,
        silhouette: Reach,
        camera: Camera | None,
        box: tuple[float, float, float, float] | None,
        X: np.ndarray,
        toward: np.ndarray,
    ) -> np.ndarray | None:
        """Where a hand held out apart from anyone else's silhouette lies, world metres (3,): the outline's
        leading point towards the ground direction ``toward`` (2,) (:func:`silhouette_tip_px`)
        back-projected to the depth of the observed person's hips; None without the camera, the box,
        the outline's height or the region's centroid.
        """
        if camera is None or box is None or not self.config.tip_in_picture:
            return None
        direction = float(np.sign(toward @ across_view(camera.R)))
        px = None if direction == 0.0 else silhouette_tip_px(silhouette, box, stature(X), direction)
        return None if px is None else _at_depth(camera, px, X)

    def _advancing(self, silhouette: Reach | None, dt: float) -> float:
        """The silhouette centre's smoothed speed towards the partner, metres per second."""
        if silhouette is None:
            self._centre = None
            return 0.0
        if self._centre is not None and dt > 0:
            v = (silhouette.centre_m - self._centre) / dt
            if abs(v) <= JUMP_M_S:
                a = 1.0 - float(np.exp(-dt / self.config.advance_s))
                self._advance += a * (v - self._advance)
        self._centre = silhouette.centre_m
        return self._advance

    def _touching_now(self, X: np.ndarray, P: np.ndarray, o: np.ndarray, p: np.ndarray, pushing: bool) -> bool:
        """Whether the observed person's tracked arms are on the partner where it stood (last frame's
        offset), or their silhouette pushes (``pushing``).
        """
        if self._last is None:
            return False
        c = self.config
        at = np.zeros(3)
        at[[0, 2]] = o + self._last - p
        arms = (_segment_distance(X[_ARMS], P[_NECK] + at, P[_HIPS].mean(axis=0) + at) < c.contact_m).any()
        return bool(arms or pushing)

    def __call__(
        self,
        observed: np.ndarray,
        partner: np.ndarray,
        dt: float,
        other: np.ndarray | None = None,
        side: float = 0.0,
        silhouette: Reach | None = None,
        camera: Camera | None = None,
        box: tuple[float, float, float, float] | None = None,
    ) -> np.ndarray:
        """The partner's joints, world metres, moved rigidly to a valid place.

        Parameters
        ----------
        observed, partner : ndarray of shape (14, 3)
            World joints (metres, Y up, ground y = 0) of the observed person and of the model's partner.
        dt : float
            Seconds since the last call (the speed limit is per second).
        other : ndarray of shape (14, 3) or None, default=None
            The real second person's joints where one is tracked (world metres): the partner stands
            on their side of the observed person.
        side : float, default=0.0
            The side to stand on when no second person is tracked: +1 image right (world +X), -1
            left, 0 the model's.
        silhouette : Reach or None, default=None
            What the observed person's silhouette says of their reach towards the partner
            (:func:`silhouette_reach`): a hand held out, and with the body advancing a push; None:
            only their tracked arms are their reach.
        camera : Camera or None, default=None
            The camera of the picture: the partner stands across its view (:func:`across_view`);
            None: across the view of a camera looking along -Z with no yaw (``ACROSS``).
        box : tuple of float or None, default=None
            The observed person's silhouette box ``(x, y, w, h)``, pixels, where it is theirs alone
            (not merged with someone else's): with ``camera``, the partner keeps clear of it
            (``clear_iou``); None: not known.

        Returns
        -------
        ndarray of shape (14, 3)
            A new array of ``partner``'s dtype, world metres.
        """
        c = self.config
        X = np.asarray(observed, np.float64)
        P = self._on_bones(X, np.asarray(partner, np.float64))
        o3, facing = actor_frame(X)
        p3, _ = actor_frame(P)
        o, p = o3[[0, 2]], p3[[0, 2]]
        dt = max(float(dt), 0.0)
        advance = self._advancing(silhouette, dt)
        held_out = self._holding_out(silhouette, dt)
        high = self._held_high(silhouette, X, held_out)
        # a hand held high driven in, or a body rushing in faster than people come up to shake hands
        driven = (advance >= c.push_speed_m_s and high) or advance >= c.push_rush_m_s
        pushing = held_out and driven and (silhouette.touching or not c.push_touch)
        touching = self._touching_now(X, P, o, p, pushing)
        onset = touching and not self._pushed
        self.pushes += onset
        was_pushed = self._pushed
        # the push goes on while the pusher holds the hand out on someone (their silhouette touching
        # another's) or drives it on: a pusher's advance comes in bursts, regions merge and part
        self._pushed = touching or (self._pushed and held_out and (silhouette.touching or advance >= c.push_speed_m_s))
        if self._pushed:  # it gives way while pushed, up to recoil_m
            self._recoil_goal = c.recoil_m
            self._recoil = min(self._recoil + c.yield_speed_m_s * dt, max(c.recoil_m, self._recoil))
        else:
            if was_pushed:  # the push released: thrown back
                self._recoil_goal = c.recoil_max_m if c.recoil_m > 0 else 0.0
            elif self._recoil >= self._recoil_goal - 1e-6:  # landed: the return
                self._recoil_goal *= float(np.exp(-dt / c.recoil_s))
            self._recoil = min(self._recoil_goal, self._recoil + c.recoil_speed_m_s * dt)
        self._touching = touching
        d = p - o
        r = float(np.hypot(*d))
        across = ACROSS if camera is None else across_view(camera.R)
        if c.beside:
            u = across
            s = self._choose_side(o, other, side, d, u)
            # the model's distance across the view; along the person's facing when nothing gives a side
            if s != 0.0:
                d = s * max(r, 1e-3) * u
        offset = _clip_length(d, float(facing), c.min_distance_m, c.max_distance_m)
        out = None  # how far out towards the partner the observed person holds a hand, metres
        hand = None  # where the hand is, world metres, where the picture says
        if held_out and not (self._pushed or driven or self._recoil_goal > 0.01):  # no pushing hand to take
            r = float(np.hypot(*offset))
            out = min(silhouette.extent_m, c.meet_frac * r)  # hands meet between the two
            if not silhouette.touching:  # the outline's tip is the hand: where the picture shows it
                tip = self._tip_in_picture(silhouette, camera, box, X, offset)
                if tip is not None:
                    along = float((tip[[0, 2]] - o) @ offset) / max(r, 1e-9)
                    # the partner stands to take it wherever it is (step_in): not bound to its placement's distance
                    # its wrist half a hand short of the fingertips, as clasping hands' are
                    out = min(max(along - c.tip_back * stature(X), 0.0), c.meet_frac * c.max_distance_m)
                    hand = tip + (out - along) * np.array([offset[0], 0.0, offset[1]]) / max(r, 1e-9)
            else:  # the outline's tip is where the regions were split, not the hand
                hand = self._hand_in_picture(silhouette, camera, box, X)
                out = (
                    c.meet_touch * self._gap_to(o, other, offset, across)
                    if hand is None
                    else max(float((hand[[0, 2]] - o) @ offset) / max(r, 1e-9), 0.0)
                )
            if c.step_in:  # the partner stands to take the hand: within its arm's reach, not on top of it
                stand = out + STEP_REACH * _arm_length(P)
                # never nearer than take_min_m: the outline may end short of the hand (an arm it missed) or at
                # the split of two regions (arms round the other), where its arm's length would put it in the arm
                offset = offset * min(max(stand, c.min_distance_m, c.take_min_m), c.max_distance_m) / max(r, 1e-9)
        r = float(np.hypot(*offset))
        if camera is not None and box is not None and r > 1e-6:  # never inside the person in the picture
            lengths = np.linspace(r, max(r, c.max_distance_m), 8)
            offset = offset / r * clear_length(P, o - p, offset / r, lengths, camera, box, c.clear_iou, c.clear_inside)
        r = float(np.hypot(*offset))
        if onset and r > 1e-6:
            # pushed, it steps back from where it stands, within max_distance_m: a partner near the
            # limit stands where the push lands (the pusher's hand on its chest) with room to recoil
            self._base = min(r, max(c.max_distance_m - c.recoil_m, c.min_distance_m))
        if (self._pushed or self._recoil_goal > 0.01) and r > 1e-6:  # stepping back from where the push landed
            offset = offset / r * min(self._base + self._recoil, c.max_distance_m)
        if self._last is not None:
            offset = _walk(self._last, offset, c.max_speed_m_s * max(float(dt), 0.0))
        self._last = offset
        self._scene = (camera, box, o)  # for finish: the final clearance
        self.offered_ = None
        if hand is not None:
            self.offered_ = hand
        elif out is not None:
            lo, hi = float(X[_HIPS, 1].mean()), float(X[_SHOULDERS, 1].mean())
            u = offset / max(float(np.hypot(*offset)), 1e-9)
            near = X[_WRISTS][int(np.argmax((X[_WRISTS][:, [0, 2]] - o) @ u))]
            y = near[1] if silhouette.height_m is None else silhouette.height_m
            if silhouette.touching and c.hand_frac > 0:
                y = c.hand_frac * stature(X) + float(X[_ANKLES, 1].min())
            y = float(np.clip(y, lo, hi))
            self.offered_ = np.array([o[0] + out * u[0], y, o[1] + out * u[1]])
        shift = np.zeros(3)
        shift[[0, 2]] = o + offset - p
        ankle = float(P[_ANKLES, 1].min())
        shift[1] = min(max(ankle, 0.0), c.max_ankle_m) - ankle
        if np.abs(shift).max() > 1e-3:
            self.corrected += 1
        return (P + shift).astype(np.asarray(partner).dtype)
