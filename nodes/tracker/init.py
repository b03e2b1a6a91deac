"""Initialisation of a track from a silhouette, and lost-track detection.

Placement (pinhole geometry, ``counterpart.body.camera``): the feet stand where the ray through the bottom
centre of the person's bounding box meets the ground (``Camera.ground_point``); the stature is
the height at that place whose top projects onto the bbox's top row; the heading comes from the
side of the frame the person stands on (the simulator's and a face-to-face interaction's layout:
the left person faces +X, the right one -X), spread widely because a silhouette barely shows it.
"""

from __future__ import annotations

import numpy as np

from counterpart.body.camera import Camera
from counterpart.body.pose import DOF, clip_to_limits, neutral_pose
from counterpart.body.skeleton import DEFAULT_DIMS, BodyDims

#: heading (root_yaw, radians) assumed for a person on each side of the frame
SIDE_YAW = {"left": np.pi / 2, "right": -np.pi / 2, "centre": 0.0}
#: the heights a person cut off by the frame's bottom edge is tried at, in multiples of the part in
#: view: 1 (the box ends at the feet) to 4 (the frame cuts the chest)
BELOW_FACTORS = 1.05 ** np.arange(29)
#: the statures (metres) a body placed from a box is given: a box cut short (a fragment, a camera
#: that misreads the scene) measures someone shorter or taller than anyone
STATURE_RANGE = (1.4, 2.1)
#: std of the wider first search: metres for the root, radians for the angles
INIT_STD = np.r_[[0.08, 0.03, 0.15], [0.6, 0.05, 0.05], [0.1] * 6, [0.25] * 16]


class PlacementError(ValueError):
    """A person's region that no ground point of this camera can stand under: one bad region,
    counted and skipped by the tracker node and ``counterpart track``, never the end of a run.
    """


def bbox_from_mask(mask: np.ndarray) -> tuple[int, int, int, int] | None:
    """Bounding box of the foreground of a mask.

    Parameters
    ----------
    mask : ndarray of shape (H, W)
        bool foreground mask.

    Returns
    -------
    tuple of int (x, y, w, h) or None
        Bounding box in pixels, or None when the mask is empty.
    """
    ys, xs = np.nonzero(mask)
    if len(xs) == 0:
        return None
    return int(xs.min()), int(ys.min()), int(xs.max() - xs.min() + 1), int(ys.max() - ys.min() + 1)


def stand_at(u: float, top: float, bottom: float, camera: Camera) -> tuple[np.ndarray, float]:
    """Ground point and stature of someone whose feet are at pixel (u, bottom) and whose top is on
    row ``top``, as ``camera`` reads them: no bounds on the stature.

    The feet stand where the ray through (u, bottom) meets the ground (``Camera.ground_point``); the
    stature is the height of the vertical line through that point at its closest approach to the
    ray through (u, top).

    Parameters
    ----------
    u : float
        Column of the feet and the top, pixels.
    top, bottom : float
        Rows of the top and of the feet, pixels.
    camera : Camera
        The camera.

    Returns
    -------
    ground : ndarray of shape (3,)
        Ground point, metres, world frame.
    height : float
        Stature, metres.

    Raises
    ------
    PlacementError
        When row ``bottom`` at column ``u`` lies at or above the horizon (no ground point).
    """
    g = camera.ground_point(np.float64(u), np.float64(bottom))
    if not np.isfinite(g).all():
        raise PlacementError(f"pixel ({u:.0f}, {bottom:.0f}) is at or above the horizon; cannot place the person")
    d = camera.rays(np.float64(u), np.float64(top))
    c = camera.centre
    horiz = np.array([d[0], 0.0, d[2]])
    s = np.dot(np.array([g[0] - c[0], 0.0, g[2] - c[2]]), horiz) / max(np.dot(horiz, horiz), 1e-12)
    return g, float(c[1] + s * d[1])


def place_from_bbox(
    bbox: tuple[int, int, int, int],
    camera: Camera,
    base: BodyDims = DEFAULT_DIMS,
    bounds: tuple[float, float] | None = STATURE_RANGE,
) -> tuple[np.ndarray, float]:
    """Ground position and stature of a person from its bounding box: :func:`stand_at` of its
    bottom centre and top row.

    Parameters
    ----------
    bbox : tuple of int (x, y, w, h)
        The person's bounding box, pixels.
    camera : Camera
        The camera that saw the person.
    base : BodyDims, default=DEFAULT_DIMS
        Body dimensions (unused by the placement itself).
    bounds : tuple of float or None, default=STATURE_RANGE
        The least and greatest stature given, metres; None: unbounded.

    Returns
    -------
    ground : ndarray of shape (3,)
        Ground point under the bbox's bottom centre, metres, world frame.
    height : float
        Stature, metres, within ``bounds``.

    Raises
    ------
    PlacementError
        When the bbox bottom lies at or above the horizon (no ground point).
    """
    x, y, w, h = bbox
    try:
        g, height = stand_at(x + 0.5 * (w - 1), y, y + h - 1, camera)
    except PlacementError:
        raise PlacementError(
            f"bbox {bbox}: its bottom row is at or above the horizon; cannot place the person"
        ) from None
    return g, float(height if bounds is None else np.clip(height, *bounds))


def guess_pose(
    bbox: tuple[int, int, int, int],
    side: str,
    camera: Camera,
    base: BodyDims = DEFAULT_DIMS,
    towards: tuple[int, int, int, int] | None = None,
    yaw: float | None = None,
) -> tuple[np.ndarray, BodyDims]:
    """The silhouette's guess of a new track: a relaxed standing pose placed from the box, and
    the body scaled to the stature it measures (``place_from_bbox``).

    Parameters
    ----------
    bbox, side, camera, base, towards
        As :func:`initial_particles`.
    yaw : float or None, default=None
        The heading (radians, ``body.pose``: 0 faces +Z); None: from ``side`` and ``towards``.

    Returns
    -------
    pose : ndarray of shape (28,)
        The guess.
    dims : BodyDims
        ``base`` scaled to the measured stature.

    Raises
    ------
    ValueError
        If ``side`` is not a key of ``SIDE_YAW``.
    PlacementError
        When the bbox bottom lies at or above the horizon.
    """
    if side not in SIDE_YAW:
        raise ValueError(f"side={side!r}: expected one of {sorted(SIDE_YAW)}")
    g, height = place_from_bbox(bbox, camera, base)
    dims = base.scaled(height)
    # The bbox's bottom row is the sole of the foot nearest the camera, not the pelvis: the root
    # stands about half a hip width plus an ankle radius further along the line of sight.
    away = np.array([g[0] - camera.centre[0], 0.0, g[2] - camera.centre[2]])
    g = g + away / max(float(np.linalg.norm(away)), 1e-9) * (dims.hip_width / 2 + dims.r_ankle)
    if yaw is None:
        yaw = SIDE_YAW[side] if towards is None else facing_yaw(g, towards, camera, SIDE_YAW[side])
    return neutral_pose(dims, x=float(g[0]), z=float(g[2]), yaw=yaw), dims


def camera_yaw(pose: np.ndarray, camera: Camera) -> float:
    """The heading (radians) that turns a pose's body to face the camera (someone at a webcam)."""
    return float(np.arctan2(camera.centre[0] - pose[0], camera.centre[2] - pose[2]))


def initial_particles(
    bbox: tuple[int, int, int, int],
    side: str,
    camera: Camera,
    n: int,
    rng: np.random.Generator,
    base: BodyDims = DEFAULT_DIMS,
    spread: float = 1.0,
    towards: tuple[int, int, int, int] | None = None,
    yaw: float | None = None,
) -> tuple[np.ndarray, BodyDims]:
    """Particles for a new track and the body dimensions scaled to the measured stature.

    The first particle is the un-jittered guess (:func:`guess_pose`); the rest are spread by
    ``INIT_STD * spread``.

    Parameters
    ----------
    bbox : tuple of int (x, y, w, h)
        The person's bounding box, pixels (for a person cut off by the frame's bottom edge, the
        whole person's: :func:`boxes_below`).
    side : str
        Side of the frame the person stands on, a key of ``SIDE_YAW`` (sets the heading).
    camera : Camera
        The camera that saw the person.
    n : int
        Number of particles.
    rng : numpy.random.Generator
        Source of the jitter.
    base : BodyDims, default=DEFAULT_DIMS
        Body dimensions scaled to the measured stature.
    spread : float, default=1.0
        Multiplier of ``INIT_STD``.
    towards : tuple of int (x, y, w, h) or None
        The bounding box of the person this one interacts with: the heading faces that person's
        ground point (``facing_yaw``) instead of the side's ``SIDE_YAW``.
    yaw : float or None, default=None
        The heading (radians), overriding ``side`` and ``towards``.

    Returns
    -------
    particles : ndarray of shape (n, 28)
        Pose vectors (body.pose), clipped to the joint limits.
    dims : BodyDims
        ``base`` scaled to the measured stature.

    Raises
    ------
    ValueError, PlacementError
        As :func:`guess_pose`.
    """
    P0, dims = guess_pose(bbox, side, camera, base, towards, yaw)
    P = P0 + rng.normal(size=(n, DOF)) * INIT_STD * spread
    P[0] = P0
    return clip_to_limits(P), dims


def cut_off_below(bbox: tuple[int, int, int, int], frame_height: int) -> bool:
    """Whether a person's box reaches the frame's bottom row: their feet are out of the picture."""
    return bbox[1] + bbox[3] >= frame_height


def boxes_below(mask: np.ndarray, factors: np.ndarray = BELOW_FACTORS) -> list[tuple[int, int, int, int]]:
    """The boxes a whole person cut off by the frame's bottom edge may have: the part in view's
    box made ``factors`` times as tall, reaching below the frame (:data:`BELOW_FACTORS`), and
    centred on the mask's median column (an arm held out widens the box to one side).

    Parameters
    ----------
    mask : ndarray of shape (H, W), dtype bool
        The person's pixels (not empty).
    factors : ndarray of shape (K,)
        Heights in multiples of the part in view.

    Returns
    -------
    list of tuple of int (x, y, w, h)
        K boxes, pixels.
    """
    x, y, w, h = bbox_from_mask(mask)
    centre = float(np.median(np.nonzero(mask)[1]))
    x = int(round(centre - 0.5 * (w - 1)))
    return [(x, y, w, int(round(h * m))) for m in factors]


def facing_yaw(ground: np.ndarray, other: tuple[int, int, int, int], camera: Camera, default: float) -> float:
    """The heading that faces another person: people who interact face each other.

    Where the two stand at different depths, a silhouette cannot tell the person turned half
    away from the camera from its mirror image turned half towards it (the same outline);
    which one it is follows from where the other person stands: the nearer of the two faces
    away from the camera, the farther one towards it.

    Parameters
    ----------
    ground : ndarray of shape (3,)
        This person's ground point, metres, world frame.
    other : tuple of int (x, y, w, h)
        The other person's bounding box, pixels.
    camera : Camera
        The camera that saw both.
    default : float
        The heading returned when the other person cannot be placed (radians).

    Returns
    -------
    float
        root_yaw (``body.pose``: 0 faces +Z), radians.
    """
    try:
        g, _ = place_from_bbox(other, camera)
    except PlacementError:
        return default
    d = g - ground
    if np.hypot(d[0], d[2]) < 1e-3:
        return default
    return float(np.arctan2(d[0], d[2]))


class LostDetector:
    """Declares a track lost when its best silhouette cost stays above ``threshold`` (a likelihood
    collapse: the model lies off the person's mask and leaves it uncovered) for ``patience``
    frames in a row.

    The cost it is given is ``S_r + S_c`` (``likelihood``): the silhouette terms alone. The edge
    term S_e is left out because on real footage it stays high on a body that fits (clothing
    texture, a cluttered background: Canny edges that are not the body's outline), and with it a
    track that still fitted was dropped every few frames of a handshake.

    Parameters
    ----------
    threshold : float, default=1.2
        Silhouette cost (0 best, 2 worst) above which a frame counts as bad: 2 is a model wholly
        off its mask; real footage keeps a track that fits below about 0.9.
    patience : int, default=3
        Number of bad frames in a row after which the track is lost.
    """

    def __init__(self, threshold: float = 1.2, patience: int = 3) -> None:
        self.threshold = float(threshold)
        self.patience = int(patience)
        self.bad = 0

    def update(self, cost: float) -> bool:
        """Count one frame and say whether the track is lost.

        Parameters
        ----------
        cost : float
            Silhouette cost of the best particle (S_r + S_c, 0 best, 2 worst); non-finite counts as bad.

        Returns
        -------
        bool
            True when the last ``patience`` frames were all bad.
        """
        self.bad = self.bad + 1 if (not np.isfinite(cost) or cost > self.threshold) else 0
        return self.bad >= self.patience

    def reset(self) -> None:
        self.bad = 0


__all__ = [
    "SIDE_YAW",
    "INIT_STD",
    "bbox_from_mask",
    "place_from_bbox",
    "stand_at",
    "STATURE_RANGE",
    "facing_yaw",
    "initial_particles",
    "LostDetector",
]
