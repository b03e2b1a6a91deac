"""Camera self-calibration from the people in view: focal length, tilt, roll and height above the
ground from the head and foot image points of upright people, against a prior on human height.

The model (Lv, Zhao & Nevatia 2006; Krahnstoever & Mendonca 2005, "Bayesian autocalibration for
surveillance"): a pinhole camera with square pixels and its principal point at the image centre,
at height ``h_c`` above the ground plane y = 0, pitched down by the tilt theta and rolled by rho
about its optical axis (no yaw: the world is set up around the camera). Person k stands upright
with stature H_k; an observation i of that person is a foot point b_i (the middle of the bottom of
its region, on the ground) and a head point t_i (the top of its region, H_k above the foot). The
foot's viewing ray meets the ground at G_i; the head predicted at G_i + H_k e_y projects to
t_hat_i. Minimised over (log f, theta, rho, log h_c, log H_1..H_K)::

    sum_i rho(|t_hat_i - t_i|^2 / (w_i sigma_i)^2)                              (head reprojection)
    + sum_k rho(((log H_k - log H0) / s_H)^2) + ((log f - log f0) / s_f)^2 + (rho / s_rho)^2   (priors)

rho is a robust loss (soft L1: raised arms, merged or cut regions are outliers, and so is a
"person" whose stature is far from the prior: a fragment or a ghost), sigma_i a share of
the person's pixel height, and w_i = sqrt(c_k) with c_k the observations of person k per
correlation time (consecutive frames of one person are not independent views). The head residual
holds both cues of the literature at once: its direction across the head-foot line is the vertical
vanishing point (tilt, roll and focal together), its length along it the consistency of a person's
height at different depths, which places the horizon (the vanishing line of the ground).

A person seen in several places may lean their own way besides (a posture, a bag, two people
walking side by side taken as one region): their predicted head moves across by l_k times their
pixel height, with the prior sum_k (l_k / s_l)^2; the l_k are linear in the residuals and solved
for in closed form at each camera (``_person_leans``). Along a path the camera's lean of a
head-foot line changes and a person's own does not, so the vertical vanishing point stays fixed by
the people's paths, not by how each of them stands.

At zero tilt the focal length is not observable from heads and feet at all (scaling f and every
depth together gives the same image), so the weak prior on f (the default camera's 55 degrees)
decides it there, and the reported uncertainty of f is wide. The scale of the scene (h_c) comes
only from the human height prior: with K people it is known to about s_H / sqrt(K).

Uncertainty: the covariance of the Gauss-Newton approximation at the solution, ``(J^T J)^-1`` of
the normalised residuals (priors included), times the reduced chi-square when it exceeds 1; a group
of near-duplicate scene segments (one edge found at several scales) counts once in it. Where the
lines fix the rotation and focal length first and the people the scale only, the lines' uncertainty
is carried into the height's (``CalibrationConfig.propagate_lines``).
Starts: a grid over tilt and field of view (vectorised), the best few refined by
``scipy.optimize.least_squares`` (trust region reflective).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace
from functools import cached_property
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

from counterpart.body.camera import Camera

from .lines import LineFamilies, duplicate_weights, segment_angles

#: std of the focal length's prior (log f) for a field of view the user gives
#: (:meth:`CalibrationConfig.with_known_fov`): a spec sheet's figure is for a lens model, a crop or
#: a video mode may narrow it a little
KNOWN_FOV_STD = 0.05


@dataclass(frozen=True)
class CalibrationConfig:
    """Priors and noise model of :func:`estimate_camera`.

    Parameters
    ----------
    person_height, person_height_std : float, default=1.75, 0.09
        Prior on the height of an adult's outline, metres (mean, std): from the top of the hair to
        the sole, which is the stature (adult means 1.63-1.77 m, women and men) plus hair and shoes;
        and the lowest point of the outline is the toe nearest the camera, below the foot's centre.
        In the simulator (statures drawn from 1.55-1.92 m) the outlines read 3% over the stature.
    fov_deg : float, default=55.0
        Centre of the weak prior on the horizontal field of view, degrees (the default camera's).
    focal_log_std : float, default=0.35
        Std of that prior on log f (0.35: 40-75 degrees within about one std).
    roll_std_deg : float, default=3.0
        Std of the prior on roll, degrees (cameras are mounted or held nearly level; with a loose
        prior, a ground line whose vanishing point lies far to one side fixes the horizon only
        through that point, and roll and tilt trade off about it).
    pixel_noise : float, default=0.05
        Std of a head point along the image vertical, as a share of the person's pixel height
        (posture, the outline's top and bottom).
    lateral_noise : float, default=0.10
        Its std across (people lean: walking, reaching to each other), same share.
    max_tilt_deg, min_tilt_deg : float, default=80.0, -5.0
        Bounds of the tilt, degrees (a camera level or looking down; people leaning towards each
        other otherwise read as a camera looking up).
    min_pixel_noise : float, default=1.0
        The least std of a head point, pixels.
    correlation_s : float, default=1.0
        Seconds over which one person's observations are counted as one.
    min_observations : int, default=15
        Fewer usable observations give no estimate (three people, each seen ``min_person_views``
        times: a far view of a few small people gives few whole ones).
    line_noise_px, min_line_noise_deg : float, default=1.5, 0.5
        Std of a scene segment's direction: this many pixels across its length, at least this many
        degrees.
    grid_tilt_deg, grid_fov_deg : tuple of float
        Start values tried, degrees (the best ``n_starts`` are refined); default tilts -5 to 50 in
        steps of 5, fields of view 30 to 95.
    n_starts : int, default=3
        Refined starts (up to twice as many where every fit ends on a bound of the tilt:
        :func:`_refine_best`).
    manhattan_std_deg : float or None, default=3.0
        Std of the prior that two horizontal line families run at right angles on the ground, degrees
        (rooms, streets and buildings are mostly laid out square: Coughlan & Yuille's "Manhattan
        world"); with two such families it fixes the focal length even with the camera level, where
        people alone cannot. The robust loss lets a scene that is not square go. None: no such prior.
    family_outlier_cost : float or None, default=4.0
        A line family is dropped, and the camera fitted again, when leaving it out lowers the fit's
        cost (half its robust chi-square) by more than this: segments that meet at a point that is
        not the image of one horizontal scene direction; one family at a time, the one whose leaving
        out gains most. Left out, the family's segments still count, about a vanishing point of
        their own (:func:`_free_family_cost`): else leaving out a family of many segments lowers
        the cost by their own scatter alone, and on a real view (PETS 2009's) every family went.
        None: keep every family. Not for the families of one square frame (``LineFamilies.square``): found jointly, none is a chance meeting, and with their many
        segments a true family that the people's lean disagrees with gains more than this.
    max_stature_ratio : float or None, default=1.3
        When the fitted statures of the people differ by more than this ratio, only the group of
        people whose statures lie within it of each other and who were seen most (their independent
        views: observations within ``correlation_s`` of each other count as one) is kept, and the
        camera fitted again. Two adults'
        outlines seldom differ by more (1.55 and 1.92 m: 1.24); a body cut at the waist or a
        fragment does, and it pulls the scale of the whole scene towards its own. None: keep
        everyone.
    nested_share : float or None, default=0.25
        A person (track id) who stood in one place and lies within a taller one who did is left
        out (:func:`_nested_tracks`; this share of the taller one's pixel height is the margin): a
        part of that person (the people detector's box on the upper body, a head and raised arm),
        whose lowest point is not on the ground. None: keep every person.
    max_stature_sd : float or None, default=3.0
        A person whose fitted stature is further than this many prior stds from the prior's centre
        is dropped and the camera fitted again (once; kept when the rest are too few): a fragment of
        a person or a ghost, whose lowest point need not be on the ground. None: keep everyone.
    min_person_views : int, default=5
        A person (track id) seen fewer times is left out: more likely a passing false find (a
        fragment of a region, a detector's box on the room) than a person, and its stature prior
        would weigh as much as a real person's in setting the scale.
    lines_first_focal_std, lines_first_tilt_std_deg : float or None, default=1.0, 90.0
        When the lines are the families of one square frame (``LineFamilies.square``) and they
        alone fix the camera's rotation and focal length (a fit of the lines with the priors on
        focal length, roll and the right angle, :func:`fit_lines`) to within this relative std of
        the focal length and this std of the tilt (degrees), the camera is fitted in two stages:
        tilt, roll and focal length from the lines, then the height and the statures from the
        people with those fixed (the people's lean, which pulls a joint fit off the lines, then
        moves the scale only); how far the joint fit lands from it counts, twice over, in the
        ``split_*`` figures. The joint fit otherwise. The defaults take any square frame's fit (on
        the simulator tighter bounds sent well-fixed frames to the joint fit). None: always the
        joint fit.
    propagate_lines : bool, default=True
        In that two-stage fit, carry the lines' uncertainty of (focal length, tilt, roll) into the
        reported uncertainty of the height (and the statures): the height fitted with the rotation
        held fixed is only as sure as that rotation (a horizon a few pixels off moves it by several
        per cent). False: the people's fit's own uncertainty, as if the lines were exact.
    split_halves : bool, default=True
        Fit the camera again on each half of the observations (split at their median time, the
        scene's lines with both) and report how far each lands from the whole
        (``CameraEstimate.split_*``): an estimate that the people's lean or a passing posture
        carries moves between the halves, one that the scene and the people agree on does not.
    lines_focal_log_std : float, default=0.5
        Std of the prior on log f in the lines-only fit (:func:`fit_lines`), wider than
        ``focal_log_std``: where one horizontal family's vanishing point is far off, the lines fix
        the focal length weakly, and a prior as tight as the people's pulled their estimate
        towards the prior's 55 degrees (chosen on the tuning seeds 0-49).
    person_lean_std : float or None, default=0.03
        Std of the prior on each person's own lean, as a share of their height (a posture, a bag,
        two people walking side by side taken as one region: one's head over both's feet), fitted
        with the camera for each person seen in ``lean_min_places`` places or more
        (:func:`_person_leans`). None: every head-foot line leans as the camera makes it lean.
    lean_min_places : int, default=4
        Places (cells a quarter of the person's height across) a person's feet must be seen in for
        their own lean to be fitted: of a person in one place, their lean and the camera's cannot be
        told apart.
    max_track_spread : float or None, default=0.15
        A person (track id) whose log pixel heights scatter about a line in the foot row by more
        than this (median absolute deviation) is left out: not one whole upright body but a
        fragment whose lower edge stays while its top comes and goes (a whole person's scatter
        is the posture's few per cent). None: keep every person.
    """

    person_height: float = 1.75
    person_height_std: float = 0.09
    fov_deg: float = 55.0
    focal_log_std: float = 0.35
    roll_std_deg: float = 3.0
    pixel_noise: float = 0.05
    lateral_noise: float = 0.10
    max_tilt_deg: float = 80.0
    min_tilt_deg: float = -5.0
    min_pixel_noise: float = 1.0
    correlation_s: float = 1.0
    min_observations: int = 15
    line_noise_px: float = 1.5
    min_line_noise_deg: float = 0.5
    grid_tilt_deg: tuple[float, ...] = tuple(np.arange(-5.0, 50.1, 5.0).tolist())
    grid_fov_deg: tuple[float, ...] = (30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 95.0)
    n_starts: int = 3
    manhattan_std_deg: float | None = 3.0
    min_person_views: int = 5
    family_outlier_cost: float | None = 4.0
    max_stature_sd: float | None = 3.0
    lines_first_focal_std: float | None = 1.0
    lines_first_tilt_std_deg: float = 90.0
    split_halves: bool = True
    lines_focal_log_std: float = 0.5
    max_track_spread: float | None = 0.15
    propagate_lines: bool = True
    person_lean_std: float | None = 0.03
    lean_min_places: int = 4
    max_stature_ratio: float | None = 1.3
    nested_share: float | None = 0.25

    def with_known_fov(self, fov_deg: float, rel_std: float = KNOWN_FOV_STD) -> CalibrationConfig:
        """These settings for a camera whose horizontal field of view is known (its spec sheet, a
        lens's focal length over the sensor's width): the prior on the focal length, in the joint fit
        and in the lines' fit alike, centred on it and ``rel_std`` wide. Where neither the people nor
        the scene's lines fix the focal length (a camera nearly level, or facing a wall square, so
        that one horizontal vanishing point lies near infinity), it is then the lens's.

        Parameters
        ----------
        fov_deg : float
            The horizontal field of view, degrees, in (1, 170).
        rel_std : float, default=KNOWN_FOV_STD
            Std of the prior on log f (relative): how sure the figure is.

        Returns
        -------
        CalibrationConfig
            A copy with ``fov_deg``, ``focal_log_std`` and ``lines_focal_log_std`` set.

        Raises
        ------
        ValueError
            A field of view outside (1, 170) degrees, or a ``rel_std`` that is not positive.
        """
        if not 1.0 < fov_deg < 170.0:
            raise ValueError(f"field of view {fov_deg!r} degrees: the camera's horizontal view must be in (1, 170)")
        if not rel_std > 0:
            raise ValueError(f"rel_std {rel_std!r}: must be > 0")
        return replace(self, fov_deg=float(fov_deg), focal_log_std=rel_std, lines_focal_log_std=rel_std)


@dataclass(frozen=True)
class CameraEstimate:
    """A camera estimated from people, with its uncertainty (one standard deviation).

    Attributes
    ----------
    focal : float
        Focal length, pixels (fx = fy), for frames of ``width`` x ``height_px``.
    tilt_deg : float
        Downward pitch of the optical axis, degrees.
    roll_deg : float
        Roll about the optical axis, degrees.
    height : float
        Camera centre above the ground, metres.
    focal_std : float
        Relative std of the focal length.
    tilt_std_deg, roll_std_deg : float
        Std of the tilt and the roll, degrees.
    height_std : float
        Relative std of the height (with the lines' uncertainty of the rotation where they fix it).
    distance : float
        Horizontal distance from the camera to the median foot position, metres (the world origin
        is put there, as in the simulator's scene).
    offset_x : float
        Lateral position of the median foot position, metres (camera frame).
    people_heights : tuple of float
        The K estimated statures of the people, metres.
    n_observations : int
        Head/foot pairs used.
    n_people : int
        People used.
    inliers : float
        Share of the observations within 3 std of the model.
    width, height_px : int
        The frame size it holds for, pixels.
    depth_spread : float, default=0.0
        How far the people moved in depth (:func:`depth_spread`: the spread of a person's foot rows
        over its pixel height; 0 when everyone stays at one depth). People all at one depth show the
        vertical vanishing point only, not the horizon: focal length and tilt are then left to the
        priors and the lean of the people.
    horizon_segments : int, default=0
        Scene segments of horizontal families whose vanishing point is within five image widths of
        the centre (they place the horizon; lines parallel to the image show its direction only).
    split_height, split_tilt_deg, split_focal : float, default=0.0
        The largest difference between this estimate and the estimate from either half of the
        observations in time (``CalibrationConfig.split_halves``): of the log height, of the tilt
        (degrees) and of the log focal length; 0 for a half too short for an estimate of its own.
    """

    focal: float
    tilt_deg: float
    roll_deg: float
    height: float
    focal_std: float
    tilt_std_deg: float
    roll_std_deg: float
    height_std: float
    distance: float
    offset_x: float
    people_heights: tuple[float, ...]
    n_observations: int
    n_people: int
    inliers: float
    width: int
    height_px: int
    depth_spread: float = 0.0
    horizon_segments: int = 0
    split_height: float = 0.0
    split_tilt_deg: float = 0.0
    split_focal: float = 0.0

    @property
    def fov_deg(self) -> float:
        """Horizontal field of view, degrees."""
        return float(np.degrees(2 * np.arctan(self.width / (2 * self.focal))))

    def camera(self) -> Camera:
        """The estimate as a camera: world Y up, the ground y = 0, the camera looking along -Z at the
        people, the world origin under their median position.

        Returns
        -------
        Camera
            The ``counterpart.body.camera.Camera``.
        """
        R = rotation(np.radians(self.tilt_deg), np.radians(self.roll_deg))
        centre = np.array([-self.offset_x, self.height, self.distance])
        return Camera(
            self.focal,
            self.focal,
            (self.width - 1) / 2.0,
            (self.height_px - 1) / 2.0,
            self.width,
            self.height_px,
            R,
            -R @ centre,
        )

    def summary(self) -> dict[str, Any]:
        """Plain figures for printing and JSON (degrees, metres, pixels).

        Returns
        -------
        dict
            Every field (statures rounded to mm) and ``fov_deg``.
        """
        d = asdict(self)
        d["people_heights"] = [round(h, 3) for h in self.people_heights]
        d["fov_deg"] = self.fov_deg
        return d

    def describe(self) -> str:
        """One line: each figure with its one-std uncertainty."""
        return (
            f"focal {self.focal:.0f} px +- {100 * self.focal_std:.0f}% (horizontal view {self.fov_deg:.0f} deg), "
            f"tilt {self.tilt_deg:.1f} +- {self.tilt_std_deg:.1f} deg, roll {self.roll_deg:.1f} +- "
            f"{self.roll_std_deg:.1f} deg, height {self.height:.2f} m +- {100 * self.height_std:.0f}% "
            f"({self.n_observations} observations of {self.n_people} people, "
            f"{100 * self.inliers:.0f}% inliers, depth spread {100 * self.depth_spread:.0f}%)"
        )


def rotation(tilt: float, roll: float) -> np.ndarray:
    """World-to-camera rotation of a camera looking along -Z; as ``Camera.look_at`` for roll 0.

    Parameters
    ----------
    tilt : float
        Downward pitch, radians.
    roll : float
        Roll about the optical axis, radians.

    Returns
    -------
    ndarray of shape (3, 3)
        The rotation.
    """
    s, c = np.sin(tilt), np.cos(tilt)
    R0 = np.array([[1.0, 0.0, 0.0], [0.0, -c, s], [0.0, -s, -c]])
    sr, cr = np.sin(roll), np.cos(roll)
    Rz = np.array([[cr, -sr, 0.0], [sr, cr, 0.0], [0.0, 0.0, 1.0]])
    return Rz @ R0


def head_foot(bbox: Any, ctrl: np.ndarray | None, ref_point: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """A person region's head and foot image points, pixels.

    Head: the reference point at the top of the head (``ref_point``: the outline's highest point
    near its upward axis), at its pixel's upper edge: a hand held up beside the head tops the box,
    not the head. Without it (or NaN), the middle of the box's top. Foot: the region's lower edge,
    at the mean x of the outline's control points in its lowest tenth (between the feet; the bbox
    middle without an outline).

    Parameters
    ----------
    bbox : sequence of 4 numbers
        The region's box (x, y, w, h), pixels.
    ctrl : ndarray of shape (n, 2) or None
        The outline's control points, pixels (used with 3 or more).
    ref_point : ndarray of shape (2,) or None
        The reference point at the top of the head, pixels.

    Returns
    -------
    head : ndarray of shape (2,)
        Head point, pixels.
    foot : ndarray of shape (2,)
        Foot point, pixels.
    """
    x, y, w, h = (float(v) for v in bbox)
    top, bottom = y - 0.5, y + h - 0.5
    hx = x + (w - 1) / 2
    if ref_point is not None and np.size(ref_point) == 2 and np.isfinite(ref_point).all():
        hx, top = float(ref_point[0]), max(top, float(ref_point[1]) - 0.5)
    fx = x + (w - 1) / 2
    if ctrl is not None and np.size(ctrl) >= 6:
        c = np.asarray(ctrl, np.float64).reshape(-1, 2)
        low = c[:, 1] >= c[:, 1].max() - 0.1 * h
        fx = float(np.clip(c[low, 0].mean(), x, x + w - 1))
    return np.array([hx, top]), np.array([fx, bottom])


def usable(
    bbox: Any, width: int, height: int, merged: bool = False, min_height: float = 20.0, min_aspect: float = 1.3
) -> bool:
    """Whether a region can serve as an upright person: whole (off the image borders), not shared
    with another person, tall enough, and taller than ``min_aspect`` times its width.

    Parameters
    ----------
    bbox : sequence of 4 numbers
        The region's box (x, y, w, h), pixels.
    width, height : int
        Frame size, pixels.
    merged : bool, default=False
        The region is shared with another person.
    min_height : float, default=20.0
        Least region height, pixels.
    min_aspect : float, default=1.3
        Least height over width.

    Returns
    -------
    bool
        True when usable.
    """
    x, y, w, h = (int(v) for v in bbox)
    return (
        not merged and h >= min_height and h >= min_aspect * w and x > 0 and y > 0 and x + w < width and y + h < height
    )


def _rotations(tilt: np.ndarray, roll: np.ndarray) -> np.ndarray:
    """(B, 3, 3) :func:`rotation` of each of the B (tilt, roll) pairs, radians."""
    s, c = np.sin(tilt), np.cos(tilt)
    sr, cr = np.sin(roll), np.cos(roll)
    R0, Rz = np.zeros((2, len(s), 3, 3))
    R0[:, 0, 0], R0[:, 1, 1], R0[:, 1, 2], R0[:, 2, 1], R0[:, 2, 2] = 1.0, -c, s, -s, -c
    Rz[:, 0, 0], Rz[:, 0, 1], Rz[:, 1, 0], Rz[:, 1, 1], Rz[:, 2, 2] = cr, -sr, sr, cr, 1.0
    return Rz @ R0


def _project_heads(
    x: np.ndarray, head: np.ndarray, foot: np.ndarray, track: np.ndarray, size: tuple[int, int]
) -> np.ndarray:
    """(N, 2) predicted head pixels for parameters ``x`` = (log f, tilt, roll, log h_c, log H_k...);
    (B, N, 2) for B parameter vectors ``x`` of shape (B, 4 + K) at once (one vectorised call for all
    of a finite-difference Jacobian's columns, :class:`_Batched`).
    """
    X = np.asarray(x, np.float64)
    B = X.reshape(-1, X.shape[-1])
    f, hc, Hk = np.exp(B[:, 0])[:, None, None], np.exp(B[:, 3])[:, None], np.exp(B[:, 4:])
    W, H = size
    c = np.array([(W - 1) / 2.0, (H - 1) / 2.0])
    R = _rotations(B[:, 1], B[:, 2])
    rays = np.concatenate([(foot - c) / f, np.ones((len(B), len(foot), 1))], axis=-1)
    d = rays @ R  # world directions of the foot rays
    down = np.maximum(-d[..., 1], 1e-4)  # at or above the horizon: far away
    s = hc / down
    rel = s[..., None] * d  # G - C
    rel[..., 1] += Hk[:, track]  # head - C
    Xc = rel @ R.transpose(0, 2, 1)
    z = np.maximum(Xc[..., 2], 1e-3)
    return (f * Xc[..., :2] / z[..., None] + c).reshape(*X.shape[:-1], len(foot), 2)


def _vanishing_points(x: np.ndarray, n_people: int, lines: LineFamilies, size: tuple[int, int]) -> np.ndarray:
    """(N, 3) homogeneous vanishing point predicted for each scene segment: the image of the world
    vertical for the vertical family, of the direction (cos phi_j, 0, sin phi_j) for horizontal
    family j (phi_j = x[4 + n_people + j]); (B, N, 3) for B parameter vectors ``x`` (B, P).
    """
    X = np.asarray(x, np.float64)
    B = X.reshape(-1, X.shape[-1])
    KR = _intrinsics(np.exp(B[:, 0]), size) @ _rotations(B[:, 1], B[:, 2])
    phi = B[:, 4 + n_people :]
    dirs = np.zeros((len(B), len(lines.vertical), 3))
    dirs[:, lines.vertical, 1] = 1.0
    dirs[:, ~lines.vertical, 0], dirs[:, ~lines.vertical, 2] = np.cos(phi), np.sin(phi)
    return (dirs @ KR.transpose(0, 2, 1))[:, lines.family].reshape(*X.shape[:-1], len(lines.family), 3)


@dataclass(frozen=True, eq=False)
class _People:
    """What a fit explains of the people in view.

    Attributes
    ----------
    head, foot : ndarray of shape (N, 2)
        Head and foot points of the N observations, pixels.
    track : ndarray of shape (N,), dtype int
        The person (0 .. n_people - 1) of each observation.
    scale : ndarray of shape (N, 2)
        Std of each head point, pixels.
    size : tuple of (int, int)
        Frame (width, height), pixels.
    f0 : float
        The focal length's prior, pixels.
    n_people : int
        Number of people (K).
    pix : ndarray of shape (N,)
        Head-to-foot height of each observation, pixels.
    lean_std : ndarray of shape (K,)
        Std of each person's own lean's prior (:func:`_person_leans`), shares of their height; 0: none.
    """

    head: np.ndarray
    foot: np.ndarray
    track: np.ndarray
    scale: np.ndarray
    size: tuple[int, int]
    f0: float
    n_people: int
    pix: np.ndarray
    lean_std: np.ndarray

    @cached_property
    def by_person(self) -> tuple[np.ndarray, np.ndarray]:
        """The observations' order grouped by person (stable) and where each person starts in it."""
        order = np.argsort(self.track, kind="stable")
        return order, np.searchsorted(self.track[order], np.arange(self.n_people))


def _residuals(
    x: np.ndarray,
    people: _People,
    cfg: CalibrationConfig,
    lines: LineFamilies | None = None,
    line_scale: np.ndarray | None = None,
) -> np.ndarray:
    """Normalised residuals (M,) of the fit at ``x`` (P,): the people's heads (2N), the statures (K),
    the people's leans (K, :func:`_person_leans`), the camera's priors (2), then the segments and the
    right angles; (B, M) for B vectors ``x`` (B, P).
    """
    head, foot, track, scale, size = people.head, people.foot, people.track, people.scale, people.size
    f0, n_people = people.f0, people.n_people
    X = np.asarray(x, np.float64)
    B = X.reshape(-1, X.shape[-1])
    r = ((_project_heads(B[:, : 4 + n_people], head, foot, track, size) - head) / scale).reshape(len(B), -1, 2)
    lean = _person_leans(r[..., 0], people)
    r[..., 0] += lean[:, people.track] * (people.pix / scale[:, 0])
    r = r.reshape(len(B), -1)
    statures = (B[:, 4 : 4 + n_people] - np.log(cfg.person_height)) / (cfg.person_height_std / cfg.person_height)
    # the camera's priors stay Gaussian; a stature's stays robust (a fragment of a person, or a
    # ghost, tracked as a person of its own must not set the scale)
    camera = _gaussian_under_soft_l1(
        np.stack([(B[:, 0] - np.log(f0)) / cfg.focal_log_std, B[:, 2] / np.radians(cfg.roll_std_deg)], -1)
    )
    priors = np.concatenate([statures, lean / np.where(people.lean_std > 0, people.lean_std, 1.0), camera], -1)
    if lines is None or not len(lines.segments):
        out = np.concatenate([r, priors], -1)
    else:
        rl = segment_angles(lines.segments, _vanishing_points(B, n_people, lines, size)) / line_scale
        out = np.concatenate([r, priors, rl, _manhattan(B[:, 4 + n_people :], cfg.manhattan_std_deg)], -1)
    return out.reshape(*X.shape[:-1], -1)


def _person_leans(rx: np.ndarray, people: _People) -> np.ndarray:
    """(B, K) each person's own lean, in shares of their height, that best explains the heads' x
    residuals ``rx`` (B, N) of B cameras under its Gaussian prior (``people.lean_std``; none where
    0): a posture, a bag, two people walking side by side taken as one whose head is one's and whose
    feet are both's (their head-foot line leans by a tenth of their height, whatever the camera).
    Only for people seen in several places: there the camera's lean of their head-foot line changes
    along their path and their own does not; of a person in one place, the two cannot be told
    apart, and their lean stays the camera's.

    The lean is linear in the residuals, so it is solved for in closed form at each camera (variable
    projection) rather than fitted as K more parameters; each residual weighs as its soft-L1 loss
    weighs it at zero lean (an arm held out does not set a lean).
    """
    if not people.lean_std.any():
        return np.zeros((len(rx), people.n_people))
    c = people.pix / people.scale[:, 0]  # a unit lean, in each residual's std
    w = 1.0 / np.sqrt(1.0 + rx * rx)
    # sums per person in one fixed order (a matrix product's would differ in the last bits between
    # a batch of cameras and one, and so would the Jacobian)
    order, starts = people.by_person

    def per(v: np.ndarray) -> np.ndarray:
        return np.add.reduceat(v[..., order], starts, axis=-1)

    with np.errstate(divide="ignore"):
        precision = np.where(people.lean_std > 0, 1.0 / people.lean_std**2, np.inf)
    return -per(w * c * rx) / (per(w * c * c) + precision)


def _gaussian_under_soft_l1(q: np.ndarray) -> np.ndarray:
    """Residuals whose soft-L1 loss is ``q**2``: a Gaussian prior kept Gaussian in a robust fit.

    ``least_squares`` applies its loss to every residual; a prior's would then grow only linearly
    far from its centre, and a fit could leave it by many standard deviations (a focal length 25
    times the prior's) for a small gain on the data. With ``rho(z) = 2 (sqrt(1 + z) - 1)``,
    ``r = q sqrt(1 + q**2 / 4)`` gives ``rho(r**2) = q**2``.

    Parameters
    ----------
    q : ndarray of shape (n,)
        Prior residuals in standard deviations.

    Returns
    -------
    ndarray of shape (n,)
        The residuals to hand to the robust fit.
    """
    return q * np.sqrt(1.0 + 0.25 * q * q)


def _manhattan(phi: np.ndarray, std_deg: float | None) -> np.ndarray:
    """(P,) residuals of the right-angle prior over the P pairs of ground directions ``phi`` (radians):
    sin(2 (phi_i - phi_j)) / (2 sigma), zero for square or parallel pairs, about the angle off square
    over sigma near it; (B, P) for B rows of directions ``phi``.
    """
    phi = np.asarray(phi)
    if std_deg is None or phi.shape[-1] < 2:
        return np.zeros((*phi.shape[:-1], 0))
    i, j = np.triu_indices(phi.shape[-1], 1)
    return np.sin(2 * (phi[..., i] - phi[..., j])) / (2 * np.radians(std_deg))


def _directions(x: np.ndarray, lines: LineFamilies, size: tuple[int, int]) -> np.ndarray:
    """(Fh,) ground directions phi of the horizontal families' detected vanishing points under the
    camera of ``x`` (their start values); (B, Fh) for B vectors ``x`` (B, P).
    """
    X = np.asarray(x, np.float64)
    B = X.reshape(-1, X.shape[-1])
    K = _intrinsics(np.exp(B[:, 0]), size)
    d = np.linalg.solve(K, lines.vp[~lines.vertical].T).transpose(0, 2, 1) @ _rotations(B[:, 1], B[:, 2])
    return np.arctan2(d[..., 2], d[..., 0]).reshape(*X.shape[:-1], -1)


def _intrinsics(f: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """(B, 3, 3) camera matrices of the B focal lengths ``f`` (pixels), the principal point at the
    centre of frames of ``size`` (width, height).
    """
    W, H = size
    K = np.zeros((len(f), 3, 3))
    K[:, 0, 0] = K[:, 1, 1] = f
    K[:, 0, 2], K[:, 1, 2], K[:, 2, 2] = (W - 1) / 2.0, (H - 1) / 2.0, 1.0
    return K


def _relative_heights(
    f: float | np.ndarray,
    tilt: float | np.ndarray,
    roll: float | np.ndarray,
    head: np.ndarray,
    foot: np.ndarray,
    size: tuple[int, int],
) -> np.ndarray:
    """(N,) head heights over a camera of height 1: the point of the foot's vertical line nearest to
    the head, in the algebraic sense ``t x (a + h b) = 0`` (a the foot's image, b the vertical's);
    (B, N) for B cameras (``f``, ``tilt``, ``roll`` of shape (B,)).
    """
    single = np.ndim(f) == 0 and np.ndim(tilt) == 0 and np.ndim(roll) == 0
    f, tilt, roll = np.broadcast_arrays(*(np.atleast_1d(np.asarray(v, np.float64)) for v in (f, tilt, roll)))
    K = _intrinsics(f, size)
    R = _rotations(tilt, roll)
    ones = np.ones((len(f), len(foot), 1))
    d = np.concatenate([(foot - K[0, :2, 2]) / f[:, None, None], ones], -1) @ R
    s = 1.0 / np.maximum(-d[..., 1], 1e-4)
    KR = K @ R
    a = (s[..., None] * d) @ KR.transpose(0, 2, 1)  # foot, homogeneous pixels
    b = np.broadcast_to(KR[:, None, :, 1], a.shape)  # the vertical direction's image
    t = np.column_stack([head, np.ones(len(head))])
    ta, tb = np.cross(t, a), np.cross(t, b)
    h = -(ta * tb).sum(axis=-1) / np.maximum((tb * tb).sum(axis=-1), 1e-12)
    return h[0] if single else h


def _line_scale(lines: LineFamilies, config: CalibrationConfig) -> np.ndarray:
    """(N,) std of each segment's direction residual (sine of an angle)."""
    length = np.hypot(*(lines.segments[:, 2:] - lines.segments[:, :2]).T)
    return np.maximum(config.line_noise_px / length, np.sin(np.radians(config.min_line_noise_deg)))


def _solve(people: _People, config: CalibrationConfig, lines: LineFamilies | None) -> Any:
    """The robust fit from the best ``config.n_starts`` of the start grid: scipy's result with the
    least cost, or None when no start puts every person above the ground.
    """
    if lines is not None and not len(lines.segments):
        lines = None
    line_scale = _line_scale(lines, config) if lines is not None else None
    head, foot, k, size, nk = people.head, people.foot, people.track, people.size, people.n_people
    W, H = size
    args = (people, config, lines, line_scale)
    # every start of the grid at once
    tilt, fov = (v.ravel() for v in np.meshgrid(np.radians(config.grid_tilt_deg), config.grid_fov_deg, indexing="ij"))
    f = (W / 2.0) / np.tan(np.radians(fov) / 2)
    h = _relative_heights(f, tilt, np.zeros_like(tilt), head, foot, size)
    hk = np.stack([np.median(h[:, k == j], axis=1) for j in range(nk)], -1)
    above = (hk > 0.05).all(axis=1)
    if not above.any():
        return None
    f, tilt, hk = f[above], tilt[above], hk[above]
    hc = config.person_height / np.exp(np.mean(np.log(hk), axis=1))
    x0 = np.column_stack([np.log(f), tilt, np.zeros_like(f), np.log(hc), np.log(hk * hc[:, None])])
    if lines is not None:
        x0 = np.concatenate([x0, _directions(x0, lines, size)], -1)
    r = _residuals(x0, *args)
    cost = np.sum(2 * (np.sqrt(1 + r * r) - 1), axis=-1)
    return _refine_best(_residuals, [(float(c), x) for c, x in zip(cost, x0)], args, config)


def _refine_best(fun: Any, starts: list[tuple[float, np.ndarray]], args: tuple, config: CalibrationConfig) -> Any:
    """The best least-squares fit (soft L1) from the ``config.n_starts`` cheapest starts.

    A fit that ends on a bound of the tilt is one the rest of the evidence contradicts, not a better
    one: a fragment of a person (a lower body seen five times) can cost less as a whole person seen
    by a camera at the ground looking up than as what it is under the camera that the lines and the
    other people agree on. Of the refined fits, the cheapest inside the bounds is taken; where every
    one ended on a bound, up to ``config.n_starts`` more starts are refined, and only if all of
    them end there too is the cheapest of all taken.

    Parameters
    ----------
    fun : callable
        Residuals ``fun(x, *args)``; ``x[1]`` is the tilt, radians, bounded to the config's range.
    starts : list of (float, ndarray)
        (cost, x0) of each start on the grid.
    args : tuple
        The residuals' other arguments.
    config : CalibrationConfig
        ``n_starts`` and the tilt's bounds.

    Returns
    -------
    scipy.optimize.OptimizeResult
        The refined fit of lowest cost inside the tilt's bounds, else of lowest cost.
    """
    starts.sort(key=lambda s: s[0])
    fits, inside = [], []
    for i, (_, x0) in enumerate(starts[: 2 * config.n_starts]):
        if i >= config.n_starts and inside:
            break
        lo = np.full(len(x0), -np.inf)
        hi = np.full(len(x0), np.inf)
        lo[1], hi[1] = np.radians(config.min_tilt_deg), np.radians(config.max_tilt_deg)
        x0[1] = np.clip(x0[1], lo[1] + 1e-6, hi[1] - 1e-6)
        res = _robust_fit(fun, x0, args, (lo, hi))
        fits.append(res)
        if not _on_tilt_bound(res.x, config):
            inside.append(res)
    return min(inside or fits, key=lambda r: r.cost)


def _on_tilt_bound(x: np.ndarray, config: CalibrationConfig) -> bool:
    """Whether the tilt ``x[1]`` (radians) lies within 1e-3 of either of ``config``'s bounds."""
    return not np.radians(config.min_tilt_deg) + 1e-3 < x[1] < np.radians(config.max_tilt_deg) - 1e-3


def _robust_fit(fun: Any, x0: np.ndarray, args: tuple = (), bounds: tuple = (-np.inf, np.inf)) -> Any:
    """``scipy.optimize.least_squares`` of ``fun(x, *args)`` from ``x0`` with the soft-L1 loss (trust
    region reflective, at most 200 evaluations, the Jacobian batched by :class:`_Batched`).

    A trial step far off (a loosely held stature, a foot ray grazing the horizon) can give
    residuals whose squares overflow; the fit rejects such a step as it should, so numpy's
    overflow warnings are silenced here rather than printed to a user among the estimate's lines.
    """
    # here, not at the top: a command that only checks its options (``CalibrationConfig``), and a
    # calibration node until its first estimate, do not wait for scipy.optimize's import
    from scipy.optimize import least_squares

    with np.errstate(over="ignore", invalid="ignore"):
        return least_squares(
            fun,
            x0,
            args=args,
            bounds=bounds,
            loss="soft_l1",
            method="trf",
            x_scale="jac",
            max_nfev=200,
            workers=_Batched(fun, args),
        )


class _Batched:
    """``least_squares``' map for its finite differences: the residuals at all of a Jacobian's
    perturbed parameter vectors in one vectorised call of ``fun`` (which takes (B, P) rows), where
    scipy would call it once per parameter. Each row is the same arithmetic as the single call, so
    the Jacobian, and the fit, are the same to the bit; the cost of a fit was mostly these calls'
    overhead (a person's stature, a family's direction: one column each).

    Parameters
    ----------
    fun : callable
        Residuals ``fun(x, *args)``, (B, M) for x of shape (B, P).
    args : tuple
        Its other arguments.
    """

    def __init__(self, fun: Any, args: tuple) -> None:
        self.fun, self.args = fun, args

    def __call__(self, _single: Any, xs: Any) -> list[np.ndarray]:
        X = np.array(list(xs), np.float64)
        return list(self.fun(X, *self.args)) if len(X) else []


@dataclass(frozen=True)
class LinesCamera:
    """The camera's rotation and focal length from the scene's lines alone (:func:`fit_lines`).

    Attributes
    ----------
    x : ndarray of shape (3,)
        (log f, tilt, roll): focal length in pixels, radians.
    sd : ndarray of shape (3,)
        Their stds (Gauss-Newton, times the reduced chi-square of the segments when over 1).
    cov : ndarray of shape (3, 3) or None, default=None
        Their covariance (the same approximation; the stds are the roots of its diagonal).
    """

    x: np.ndarray
    sd: np.ndarray
    cov: np.ndarray | None = None


def _line_residuals(
    y: np.ndarray, lines: LineFamilies, line_scale: np.ndarray, size: tuple[int, int], cfg: CalibrationConfig, f0: float
) -> np.ndarray:
    """Residuals of the lines-only fit over ``y`` = (log f, tilt, roll, phi_1..phi_Fh); (B, M) for B
    rows ``y``.
    """
    Y = np.asarray(y, np.float64)
    B = Y.reshape(-1, Y.shape[-1])
    x = np.concatenate([B[:, :3], np.zeros((len(B), 1)), B[:, 3:]], -1)
    rl = segment_angles(lines.segments, _vanishing_points(x, 0, lines, size)) / line_scale
    camera = _gaussian_under_soft_l1(
        np.stack([(B[:, 0] - np.log(f0)) / cfg.lines_focal_log_std, B[:, 2] / np.radians(cfg.roll_std_deg)], -1)
    )
    return np.concatenate([rl, _manhattan(B[:, 3:], cfg.manhattan_std_deg), camera], -1).reshape(*Y.shape[:-1], -1)


def fit_lines(
    lines: LineFamilies, size: tuple[int, int], config: CalibrationConfig = CalibrationConfig()
) -> LinesCamera | None:
    """The camera's focal length, tilt and roll from the scene's line families alone (their
    vanishing points, the right angle between horizontal families, the priors on focal length and
    roll), with their uncertainty from the segments' own scatter.

    Parameters
    ----------
    lines : LineFamilies
        The scene's families (``counterpart.nodes.calibration.lines``).
    size : tuple of (int, int)
        (width, height) of the frames, pixels.
    config : CalibrationConfig, default=CalibrationConfig()
        Priors and the segments' noise.

    Returns
    -------
    LinesCamera or None
        The fit, or None without segments or without a horizontal family.
    """
    if not len(lines.segments) or lines.n_horizontal == 0:
        return None
    # the same lines are fitted again for every re-estimate while the scene's frames are unchanged,
    # and within one estimate for each half of the window: the fit is their dearest part
    key = (
        tuple((a.dtype.str, a.shape, a.tobytes()) for a in (lines.segments, lines.family, lines.vertical, lines.vp)),
        lines.square,
        int(size[0]),
        int(size[1]),
        config,
    )
    # taken out and put back last: the least recently used fit goes first
    fit = _LINES_FITS.pop(key) if key in _LINES_FITS else _fit_lines(lines, size, config)
    _LINES_FITS[key] = fit
    while len(_LINES_FITS) > _LINES_FITS_KEPT:
        _LINES_FITS.pop(next(iter(_LINES_FITS)))
    return (
        None if fit is None else LinesCamera(fit.x.copy(), fit.sd.copy(), None if fit.cov is None else fit.cov.copy())
    )


#: the last few lines-only fits, by their lines, frame size and config (:func:`fit_lines`)
_LINES_FITS: dict[tuple[Any, ...], LinesCamera | None] = {}
_LINES_FITS_KEPT = 8


def _fit_lines(lines: LineFamilies, size: tuple[int, int], config: CalibrationConfig) -> LinesCamera | None:
    """:func:`fit_lines` without the cache."""
    W, H = int(size[0]), int(size[1])
    f0 = (W / 2.0) / np.tan(np.radians(config.fov_deg) / 2)
    line_scale = _line_scale(lines, config)
    args = (lines, line_scale, (W, H), config, f0)
    tilt, fov = (v.ravel() for v in np.meshgrid(np.radians(config.grid_tilt_deg), config.grid_fov_deg, indexing="ij"))
    x0 = np.column_stack([np.log((W / 2.0) / np.tan(np.radians(fov) / 2)), tilt, np.zeros_like(tilt)])
    y0 = np.concatenate([x0, _directions(np.column_stack([x0, np.zeros_like(tilt)]), lines, (W, H))], -1)
    r = _line_residuals(y0, *args)
    starts = [(float(c), y) for c, y in zip(np.sum(2 * (np.sqrt(1 + r * r) - 1), axis=-1), y0)]
    best = _refine_best(_line_residuals, starts, args, config)
    weights = np.ones(len(best.fun))
    weights[: len(lines.segments)] = duplicate_weights(lines.segments)
    cov = _covariance(best, weights)
    if cov is None:
        return None
    return LinesCamera(best.x[:3].copy(), np.sqrt(np.abs(np.diag(cov)))[:3], cov[:3, :3].copy())


def _consistent_people(log_statures: np.ndarray, views: np.ndarray, ratio: float | None) -> np.ndarray | None:
    """The people whose fitted statures agree: of the groups whose statures lie within ``ratio`` of
    each other, the one seen most.

    Parameters
    ----------
    log_statures : ndarray of shape (K,)
        Fitted log statures of the K people, log metres.
    views : ndarray of shape (K,)
        Independent views of each (observations within the correlation time counted as one).
    ratio : float or None
        Largest ratio of two statures in a group (``CalibrationConfig.max_stature_ratio``).

    Returns
    -------
    ndarray of int or None
        Indices of the group's people, ascending; None with fewer than two people or no ``ratio``.
    """
    if ratio is None or len(log_statures) < 2:
        return None
    low = log_statures[:, None]
    inside = (log_statures[None, :] >= low) & (log_statures[None, :] <= low + np.log(ratio))
    return np.flatnonzero(inside[int(np.argmax(inside @ views))])


def _covariance(res: Any, weights: np.ndarray) -> np.ndarray | None:
    """The Gauss-Newton covariance of a robust fit, each residual counted with its weight.

    A group of near-duplicate segments (one edge found at several of LSD's scales) stays in the fit
    whole, but counts once here (``weights`` 1 / its size, :func:`lines.duplicate_weights`): counted
    several times, it would shrink the reported uncertainty by the square root of its size without
    any more evidence.

    Parameters
    ----------
    res : scipy.optimize.OptimizeResult
        The fit (soft-L1 loss): ``jac`` (M, P), the loss-scaled Jacobian, and ``fun`` (M,), the
        normalised residuals.
    weights : ndarray of shape (M,)
        Weight of each residual in the information and in the reduced chi-square.

    Returns
    -------
    ndarray of shape (P, P) or None
        ``(J^T W J)^-1`` times the weighted reduced chi-square where it exceeds 1; None where
        ``J^T W J`` is singular.
    """
    J = res.jac * np.sqrt(weights)[:, None]
    rho = 2.0 * (np.sqrt(1.0 + res.fun * res.fun) - 1.0)  # the soft-L1 loss of each residual
    chi2 = float(weights @ rho) / max(1.0, float(weights.sum()) - J.shape[1])
    try:
        return np.linalg.inv(J.T @ J) * max(1.0, chi2)
    except np.linalg.LinAlgError:
        return None


def _solve_people(people: _People, config: CalibrationConfig, cam: np.ndarray) -> Any:
    """The robust fit of the height and the statures with (log f, tilt, roll) = ``cam`` fixed: scipy's
    result with ``x`` the whole parameter vector, or None when the people are not above the ground.
    """
    h = _relative_heights(float(np.exp(cam[0])), cam[1], cam[2], people.head, people.foot, people.size)
    hk = np.array([np.median(h[people.track == j]) for j in range(people.n_people)])
    if not (hk > 0.05).all():
        return None
    hc = config.person_height / np.exp(np.mean(np.log(hk)))
    z0 = np.concatenate([[np.log(hc)], np.log(hk * hc)])

    def fun(z: np.ndarray) -> np.ndarray:
        x = np.concatenate([np.broadcast_to(cam, (*np.shape(z)[:-1], len(cam))), z], -1)
        return _residuals(x, people, config)

    res = _robust_fit(fun, z0)
    res.x = np.concatenate([cam, res.x])
    return res


def _propagated(x: np.ndarray, cam_cov: np.ndarray, people: _People, config: CalibrationConfig) -> np.ndarray:
    """(1 + nk, 1 + nk) covariance that the lines' uncertainty of (log f, tilt, roll) adds to the
    people's fit of (log h_c, log H_k) made with them fixed: ``D cam_cov D^T`` with ``D`` the
    solution's derivative by the fixed parameters (implicit function, Gauss-Newton, soft-L1 weights).
    """

    def res(v: np.ndarray) -> np.ndarray:
        return _residuals(v, people, config)

    r0 = res(x)
    w = np.sqrt(1.0 / np.sqrt(1.0 + r0 * r0))  # soft L1: the square root of rho' of each residual
    eps = 1e-6
    J = np.column_stack([(res(x + eps * np.eye(len(x))[i]) - r0) / eps for i in range(len(x))]) * w[:, None]
    Jc, Jz = J[:, :3], J[:, 3:]
    try:
        D = -np.linalg.solve(Jz.T @ Jz, Jz.T @ Jc)
    except np.linalg.LinAlgError:
        return np.zeros((len(x) - 3, len(x) - 3))
    return D @ cam_cov @ D.T


def _without_family(lines: LineFamilies, j: int) -> LineFamilies:
    """``lines`` less family ``j`` (the later families renumbered)."""
    keep = lines.family != j
    family = lines.family[keep]
    return LineFamilies(
        lines.segments[keep],
        family - (family > j),
        np.delete(lines.vertical, j),
        np.delete(lines.vp, j, axis=0),
    )


def _places(foot: np.ndarray, pix: np.ndarray, k: np.ndarray, nk: int) -> np.ndarray:
    """(K,) places each person's feet were seen in: cells a quarter of their median pixel height
    across (``foot`` (N, 2) pixels, ``pix`` (N,) pixel heights, ``k`` (N,) persons 0 .. nk - 1).
    """
    out = np.zeros(nk, int)
    for j in range(nk):
        m = k == j
        out[j] = len(np.unique(np.floor(foot[m] / max(1.0, 0.25 * float(np.median(pix[m])))), axis=0))
    return out


def _free_family_cost(lines: LineFamilies, j: int, scale: np.ndarray) -> float:
    """The robust cost (as ``least_squares`` reports it) of family ``j``'s segments about their own
    best vanishing point, free of any camera: what they cost where the family is left out of the
    camera's fit. ``scale`` (N,): each segment's residual std (:func:`_line_scale`).
    """
    m = lines.family == j
    seg, sc = lines.segments[m], scale[m]
    v = lines.vp[j] / np.linalg.norm(lines.vp[j])

    def vp(a: np.ndarray) -> np.ndarray:
        return np.array([np.sin(a[0]) * np.cos(a[1]), np.sin(a[0]) * np.sin(a[1]), np.cos(a[0])])

    a0 = np.array([np.arccos(np.clip(v[2], -1.0, 1.0)), np.arctan2(v[1], v[0])])
    from scipy.optimize import least_squares  # as in _robust_fit

    with np.errstate(over="ignore", invalid="ignore"):
        res = least_squares(lambda a: segment_angles(seg, vp(a)) / sc, a0, loss="soft_l1", method="trf", max_nfev=50)
    return float(res.cost)


def estimate_camera(*args: Any, **kw: Any) -> CameraEstimate | None:
    """:func:`fit_camera` on one BLAS thread (its matrices are small: more threads only contend).

    Parameters
    ----------
    *args, **kw
        The arguments of :func:`fit_camera`.

    Returns
    -------
    CameraEstimate or None
        As :func:`fit_camera`.
    """
    with threadpool_limits(1):
        return fit_camera(*args, **kw)


def _inconsistent_tracks(
    head: np.ndarray, foot: np.ndarray, track: np.ndarray, ok: np.ndarray, max_spread: float | None
) -> np.ndarray:
    """Ids of the tracks whose pixel heights do not follow their foot rows as one upright body's do.

    On a ground plane a person's pixel height is nearly a linear function of its foot's row (the
    farther, the higher in the image and the smaller), so the log pixel heights of a whole person
    follow a line in the foot row to within the posture's few per cent. A fragment (a torso and an
    arm whose lower edge stays put while the rest comes and goes) or a region that joins and leaves
    other things does not: its heights scatter about that line.

    Parameters
    ----------
    head, foot : ndarray of shape (N, 2)
        Image points, pixels.
    track : ndarray of shape (N,)
        Person ids.
    ok : ndarray of shape (N,), bool
        The observations to look at.
    max_spread : float or None
        Largest median absolute deviation of the log pixel heights from the track's line; None:
        no track is dropped.

    Returns
    -------
    ndarray
        The ids of the tracks to drop.
    """
    if max_spread is None:
        return np.zeros(0, track.dtype)
    bad = []
    for k in np.unique(track[ok]):
        m = ok & (track == k)
        if m.sum() < 3:
            continue
        y = np.log(foot[m, 1] - head[m, 1])
        A = np.column_stack([np.ones(m.sum()), foot[m, 1] - foot[m, 1].mean()])
        r = y - A @ np.linalg.lstsq(A, y, rcond=None)[0]
        if np.median(np.abs(r - np.median(r))) > max_spread:
            bad.append(k)
    return np.array(bad, track.dtype)


def _nested_tracks(
    head: np.ndarray, foot: np.ndarray, track: np.ndarray, ok: np.ndarray, share: float | None
) -> np.ndarray:
    """Ids of the tracks that lie within a taller one in the image: parts of that person.

    Of two tracks that each stood in one place (the median distance of their foot points from
    their median one under ``share`` of their pixel height), track a lies within track b when,
    with their median head and foot points, a is shorter than b and, in shares of b's pixel
    height: a's middle is within ``share`` of b's across, a's top at most ``share`` above b's (a
    raised hand), and a's bottom at least ``share`` above b's. The people detector's box on a
    person's upper body and the silhouettes' head and raised arm of a person standing still are
    such parts; their lowest point is not on the ground. Of people who walk, the median points
    are nowhere they stood.

    Parameters
    ----------
    head, foot : ndarray of shape (N, 2)
        Image points, pixels.
    track : ndarray of shape (N,)
        Person ids.
    ok : ndarray of shape (N,), bool
        The observations to look at.
    share : float or None
        The share of the taller track's pixel height; None: no track is dropped.

    Returns
    -------
    ndarray
        The ids of the tracks to drop.
    """
    ids = np.unique(track[ok])
    if share is None or len(ids) < 2:
        return np.zeros(0, track.dtype)
    points = np.hstack([head, foot])
    each = [ok & (track == k) for k in ids]
    med = np.array([np.median(points[m], axis=0) for m in each])
    x, top, bottom = 0.5 * (med[:, 0] + med[:, 2]), med[:, 1], med[:, 3]
    # where a person walks, their median points are nowhere they stood
    moved = np.array([np.median(np.hypot(*(foot[m] - c[2:]).T)) for m, c in zip(each, med)])
    still = moved < share * (bottom - top)
    reach = share * (bottom - top)[None, :]
    # [a, b]: a within b
    within = (
        (still[:, None] & still[None, :])
        & ((bottom - top)[:, None] < (bottom - top)[None, :])
        & (np.abs(x[:, None] - x[None, :]) < reach)
        & (top[:, None] > top[None, :] - reach)
        & (bottom[:, None] < bottom[None, :] - reach)
    )
    return ids[within.any(axis=1)]


def fit_camera(
    head: np.ndarray,
    foot: np.ndarray,
    track: np.ndarray,
    size: tuple[int, int],
    time_s: np.ndarray | None = None,
    config: CalibrationConfig = CalibrationConfig(),
    lines: LineFamilies | None = None,
) -> CameraEstimate | None:
    """Estimate the camera from head and foot points of upright people.

    Parameters
    ----------
    head, foot : ndarray of shape (N, 2)
        Image points, pixels (top of the head, middle of the feet).
    track : ndarray of shape (N,)
        Person identity of each observation (any integers).
    size : tuple of (int, int)
        (width, height) of the frames, pixels.
    time_s : ndarray of shape (N,) or None, default=None
        Time of each observation, seconds (None: 25 frames per second in order).
    config : CalibrationConfig, default=CalibrationConfig()
        Priors and noise model.
    lines : LineFamilies or None, default=None
        Families of straight scene lines (``counterpart.nodes.calibration.lines``): the vertical
        ones and the horizon of the horizontal ones join the fit (None: the people alone).

    Returns
    -------
    CameraEstimate or None
        The estimate, or None with fewer than ``config.min_observations`` observations.

    Raises
    ------
    ValueError
        If ``head``, ``foot`` and ``track`` differ in length.
    """
    head = np.asarray(head, np.float64).reshape(-1, 2)
    foot = np.asarray(foot, np.float64).reshape(-1, 2)
    track = np.asarray(track).reshape(-1)
    if not len(head) == len(foot) == len(track):
        raise ValueError(f"head, foot and track must have the same length, got {len(head)}, {len(foot)}, {len(track)}")
    ok = np.isfinite(head).all(1) & np.isfinite(foot).all(1) & (foot[:, 1] - head[:, 1] > 2)
    # a person seen a few times only is more likely a passing false find (a fragment, a detector's
    # box on the room) than a person, and its stature prior would weigh as much as a real one's
    ids, count = np.unique(track[ok], return_counts=True)
    ok &= np.isin(track, ids[count >= config.min_person_views])
    ok &= ~np.isin(track, _inconsistent_tracks(head, foot, track, ok, config.max_track_spread))
    ok &= ~np.isin(track, _nested_tracks(head, foot, track, ok, config.nested_share))
    head, foot, track = head[ok], foot[ok], track[ok]
    time_s = (np.arange(len(ok)) / 25.0 if time_s is None else np.asarray(time_s, np.float64).reshape(-1))[ok]
    if len(head) < config.min_observations:
        return None
    ids, k = np.unique(track, return_inverse=True)
    W, H = int(size[0]), int(size[1])
    pix = foot[:, 1] - head[:, 1]
    # observations of one person within the correlation time count as about one
    per = np.ones(len(ids))
    for j in range(len(ids)):
        tk = time_s[k == j]
        per[j] = max(1.0, len(tk) / max(1.0, (tk.max() - tk.min()) / config.correlation_s))
    scale = (
        np.maximum(np.multiply.outer(pix, [config.lateral_noise, config.pixel_noise]), config.min_pixel_noise)
        * np.sqrt(per[k])[:, None]
    )
    f0 = (W / 2.0) / np.tan(np.radians(config.fov_deg) / 2)

    if lines is not None and not len(lines.segments):
        lines = None
    nk = len(ids)
    fixed = None
    if lines is not None and lines.square and config.lines_first_focal_std is not None:
        cam = fit_lines(lines, (W, H), config)
        # the lines alone fix the rotation and the focal length: the people give the scale only
        # (their lean would otherwise pull the rotation off the lines)
        if (
            cam is not None
            and cam.sd[0] <= config.lines_first_focal_std
            and np.degrees(cam.sd[1]) <= config.lines_first_tilt_std_deg
        ):
            fixed = cam
    # next to the lines-first fit, the joint fit is the measure of how far the people pull off the
    # lines (the split below): with the lines' own prior on the focal length, so that it does not
    # count the two priors' difference as the people's
    joint_config = replace(config, focal_log_std=config.lines_focal_log_std) if fixed is not None else config
    lean_std = np.where(_places(foot, pix, k, nk) >= config.lean_min_places, config.person_lean_std or 0.0, 0.0)
    people = _People(head, foot, k, scale, (W, H), f0, nk, pix, lean_std)
    joint = _solve(people, joint_config, lines)
    best = joint
    if fixed is not None:
        best = _solve_people(people, config, fixed.x)
        if best is None:
            fixed, best = None, _solve(people, config, lines)
    if best is None:
        return None
    # a family of segments that is not a set of parallel scene lines (edges of several things that
    # happen to meet, a family off the ground's horizon) drags the horizon to its point, and with two
    # families any two points make a horizon: drop the family whose leaving out lowers the cost
    # most, while that gain is over the bound (a likelihood-ratio test per family), and fit again
    while (
        fixed is None
        and lines is not None
        and not lines.square
        and config.family_outlier_cost is not None
        and len(lines.vp)
    ):
        # left out, a family's segments still lie about a point of their own: the test weighs the
        # fit without the family plus that (their scatter, which no camera removes) against the fit
        # with it
        scale = _line_scale(lines, config)
        fits = []
        for j in range(len(lines.vp)):
            fewer = _without_family(lines, j)
            fit = _solve(people, config, fewer)
            if fit is not None:
                fits.append((fit.cost + _free_family_cost(lines, j, scale), fit, fewer))
        if not fits:
            break
        cost, fit, fewer = min(fits, key=lambda v: v[0])
        # a fit that ends on the tilt's bound is one the rest contradicts (the people's lean taken
        # for a camera looking up), not a better one
        if best.cost - cost <= config.family_outlier_cost or _on_tilt_bound(fit.x, config):
            break
        best, lines = fit, (fewer if len(fewer.segments) else None)
    x = best.x
    off = np.abs(x[4 : 4 + nk] - np.log(config.person_height)) / (config.person_height_std / config.person_height)
    for chosen in (
        # people whose statures no two adults' differences explain: some are not whole people (a
        # torso, whose lowest point is its waist, reads as a giant far off or a dwarf nearby), and
        # the rest of them decide the scale only as a compromise with those
        _consistent_people(x[4 : 4 + nk], np.bincount(k, minlength=nk) / per, config.max_stature_ratio),
        # a "person" of a stature far from any adult's is a fragment of one (a torso, a lower leg)
        # or a ghost, whose lowest point need not be on the ground
        None if config.max_stature_sd is None else np.flatnonzero(off <= config.max_stature_sd),
    ):
        if chosen is not None and 0 < len(chosen) < nk:
            keep = np.isin(k, chosen)
            refit = fit_camera(head[keep], foot[keep], track[keep], size, time_s[keep], config, lines)
            if refit is not None:
                return refit
    n = best.jac.shape[1]
    r = best.fun[: 2 * len(head)].reshape(-1, 2) * np.sqrt(per[k])[:, None]  # per observation, in its own std
    inlier = np.hypot(r[:, 0], r[:, 1]) < 3.0
    weights = np.ones(len(best.fun))
    if fixed is None and lines is not None:
        # the joint fit's residuals: people (2N), statures and leans (2K), camera priors (2), then the
        # segments
        start = 2 * len(head) + 2 * nk + 2
        weights[start : start + len(lines.segments)] = duplicate_weights(lines.segments)
    cov = _covariance(best, weights)
    if cov is None:
        cov = np.full((n, n), np.inf)
    if fixed is not None and config.propagate_lines and fixed.cov is not None:
        cov = cov + _propagated(best.x, fixed.cov, people, config)
    sd = np.sqrt(np.abs(np.diag(cov)))
    if fixed is not None:
        sd = np.concatenate([fixed.sd, sd])
    f, tilt, roll, hc = float(np.exp(x[0])), float(x[1]), float(x[2]), float(np.exp(x[3]))
    # the world origin under the people's median foot position
    d = np.column_stack([(foot - [(W - 1) / 2.0, (H - 1) / 2.0]) / f, np.ones(len(foot))]) @ rotation(tilt, roll)
    g = (hc / np.maximum(-d[:, 1], 1e-4))[:, None] * d
    split = np.zeros(3)
    if fixed is not None and joint is not None:
        # the two cues disagree by as much as the fit with the people lands off the lines alone;
        # that difference is one draw of their disagreement, counted twice over against the
        # halves' bounds
        split = 2.0 * np.abs([joint.x[3] - x[3], np.degrees(joint.x[1] - x[1]), joint.x[0] - x[0]])
    if config.split_halves:
        # the halves in time, each with the scene's lines: where they land off the whole, the people
        # carry the estimate with something that changes over the window (a lean, a posture)
        half = replace(config, split_halves=False)
        for m in (time_s <= np.median(time_s), time_s > np.median(time_s)):
            part = fit_camera(head[m], foot[m], track[m], size, time_s[m], half, lines)
            if part is not None:
                split = np.maximum(
                    split,
                    np.abs([np.log(part.height / hc), part.tilt_deg - np.degrees(tilt), np.log(part.focal / f)]),
                )
    return CameraEstimate(
        focal=f,
        tilt_deg=float(np.degrees(tilt)),
        roll_deg=float(np.degrees(roll)),
        height=hc,
        focal_std=float(sd[0]),
        tilt_std_deg=float(np.degrees(sd[1])),
        roll_std_deg=float(np.degrees(sd[2])),
        height_std=float(sd[3]),
        distance=float(-np.median(g[inlier | ~inlier.any(), 2])),
        offset_x=float(np.median(g[:, 0])),
        people_heights=tuple(float(v) for v in np.exp(x[4 : 4 + nk])),
        n_observations=int(len(head)),
        n_people=int(len(ids)),
        inliers=float(inlier.mean()),
        width=W,
        height_px=H,
        depth_spread=depth_spread(foot[:, 1], pix, k),
        horizon_segments=horizon_segments(lines, (W, H)),
        split_height=float(split[0]),
        split_tilt_deg=float(split[1]),
        split_focal=float(split[2]),
    )


def horizon_segments(lines: LineFamilies | None, size: tuple[int, int]) -> int:
    """Segments of the horizontal families whose vanishing point lies within five image widths of
    the image centre.

    Parameters
    ----------
    lines : LineFamilies or None
        The scene's line families.
    size : tuple of (int, int)
        (width, height) of the frames, pixels.

    Returns
    -------
    int
        Number of segments (0 without lines).
    """
    if lines is None or not len(lines.vp):
        return 0
    W, H = size
    vp = lines.vp
    w = vp[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        d = np.hypot(vp[:, 0] / w - (W - 1) / 2, vp[:, 1] / w - (H - 1) / 2)
    near = np.isfinite(d) & (d < 5 * W) & ~lines.vertical
    return int(np.isin(lines.family, np.flatnonzero(near)).sum())


def depth_spread(foot_row: np.ndarray, pixel_height: np.ndarray, person: np.ndarray, min_views: int = 10) -> float:
    """How far the people moved in depth: for each person seen ``min_views`` times or more, the
    interquartile range of its foot's image row over its median pixel height; the largest of them.

    Parameters
    ----------
    foot_row : ndarray of shape (N,)
        Image row of each observation's foot, pixels.
    pixel_height : ndarray of shape (N,)
        Each observation's pixel height.
    person : ndarray of shape (N,), dtype int
        Person index of each observation, from 0.
    min_views : int, default=10
        Least observations of a person for it to count.

    Returns
    -------
    float
        The largest spread (0 when no person has enough observations).
    """
    out = 0.0
    for j in range(int(person.max()) + 1 if len(person) else 0):
        m = person == j
        if m.sum() >= min_views:
            q25, q75 = np.percentile(foot_row[m], [25, 75])
            out = max(out, float((q75 - q25) / np.median(pixel_height[m])))
    return out


__all__ = [
    "CalibrationConfig",
    "CameraEstimate",
    "depth_spread",
    "estimate_camera",
    "fit_camera",
    "fit_lines",
    "LinesCamera",
    "horizon_segments",
    "head_foot",
    "rotation",
    "usable",
]
