"""Observation model of the tracker: silhouette, edge and coverage terms over projected cones.

Follows Deutscher, Blake & Reid 2000 (sect. 3, eqs. 4-6). For a pose X with model sample points
projected into the image, the two "model -> image" costs are

    S_r(X) = 1/K_r * sum_k (1 - p_r(x_k))^2     K_r points inside the cones (body.raster
                                                  cone_interior_points), p_r the foreground mask
    S_e(X) = 1/K_e * sum_k (1 - p_e(x_k))^2     K_e points on the cone outlines, p_e a smoothed
                                                  edge map in [0, 1]

and the weighting function is ``w(Z, X) = exp(-(S_r + S_e))``. A third, "image -> model" cost is
added because the two terms above are satisfied by a body whose limbs hide inside the torso:
``S_c(X)`` is the fraction of M foreground pixels (sampled once per frame) that no projected cone
covers. A fourth, ``S_g``, asks a foot to touch the ground plane (``ConeLikelihood``), which with
the calibrated camera ties the depth to the image row of the feet. The log-likelihood returned is
``-(w_sil S_r + w_edge S_e + w_cover S_c + w_ground S_g) * gain``.

Several calibrated cameras (Deutscher et al. use three) combine in ``MultiViewLikelihood``: the
image costs of every view are summed over one forward kinematics.

One forward kinematics call for N particles (``counterpart.body.kinematics.anchor_points``), then
the image costs in one compiled pass per particle (``kernels.cone_image_costs``): the projection of
the 23 anchor points, the sample points of each cone, their lookups in the frame's per-pixel cost
map (``Observation.cost``) and the coverage test. The kernel repeats, in float32 and operation by
operation, the numpy formulation kept in ``ConeLikelihood.project`` / ``sample_points`` /
``coverage_cost`` (the sample points as one small matmul, the coverage test as a matmul plus
array arithmetic), and gives its costs to the last bit. Pixel units throughout; points outside
a person's window read 0 (no foreground, no edge); the window goes on past the frame's borders
where the person is cut off by them (``make_observation``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np

from counterpart.body.camera import Camera, default_camera
from counterpart.body.kinematics import anchor_points, row_dims
from counterpart.body.pose import neutral_pose
from counterpart.body.skeleton import ANCHOR_INDEX, DEFAULT_DIMS, N_SEGMENTS, SEGMENT_ANCHORS, BodyDims

#: anchors whose lowest point is the sole: the two ankles (``ankle_height`` above it), the two toes
#: (``r_toe`` above it)
_FOOT_ANCHORS = np.array([ANCHOR_INDEX[n] for n in ("l_ankle", "r_ankle", "l_toe", "r_toe")])


#: the coverage tables of no sample
_NO_G = np.zeros((3, 0), np.float32)
_NO_QQ = np.zeros(0, np.float32)


def _cost_map(fg: np.ndarray, edge: np.ndarray) -> np.ndarray:
    """Flattened fg and edge maps (H*W + 1,) -> (2 (H*W + 1),) float32 ``(1 - fg)^2`` then
    ``(1 - edge)^2``: the per-sample costs of S_r and S_e.
    """
    return np.concatenate([(1.0 - fg) ** 2, (1.0 - edge) ** 2]).astype(np.float32, copy=False)


@dataclass(frozen=True)
class Observation:
    """One person in one frame, ready for the likelihood.

    The maps cover a window of the image around the person (``make_observation``: the mask's
    bounding box with a margin that holds every pixel of the smoothed edge map), so that they cost
    a person's area rather than the frame's; outside the window a point reads no foreground and
    no edge.

    Parameters
    ----------
    fg : ndarray of shape (height*width + 1,), dtype float32
        Flattened foreground mask of the window (1 person, 0 background), with a trailing 0 that
        points outside the window read.
    edge : ndarray of shape (height*width + 1,), dtype float32
        Flattened smoothed edge map of the window in [0, 1], same layout.
    cover_uv : ndarray of shape (M, 2), dtype float32
        Pixel positions (image coordinates) of foreground samples for the coverage term.
    width, height : int
        Size of the window, pixels.
    cost : ndarray of shape (2 (height*width + 1),), dtype float32, or None
        Per-pixel costs ``(1 - fg)^2`` then ``(1 - edge)^2`` (outside the window: 1), so that S_r
        and S_e are one gather; None: derived from fg and edge.
    x0, y0 : int
        Image position of the window's top-left pixel (0, 0: the window is the image; negative
        where it goes on past the frame's top or left border, ``make_observation``).
    """

    fg: np.ndarray
    edge: np.ndarray
    cover_uv: np.ndarray
    width: int
    height: int
    cost: np.ndarray | None = None
    x0: int = 0
    y0: int = 0

    def cost_map(self) -> np.ndarray:
        """The ``cost`` array (computed from fg and edge when it was not given).

        Returns
        -------
        ndarray of shape (2 (height*width + 1),), dtype float32
            ``(1 - fg)^2`` then ``(1 - edge)^2``.
        """
        if self.cost is not None:
            return self.cost
        return _cost_map(self.fg, self.edge)

    @property
    def empty(self) -> bool:
        """True when the mask holds no foreground pixel (nothing to track)."""
        return self.cover_uv.shape[0] == 0


def frame_edges(image: np.ndarray, canny: tuple[int, int] = (40, 120)) -> np.ndarray:
    """The Canny edges of a whole frame, which every person's :func:`edge_map` of that frame reads
    (computed once per frame when several people are tracked on it).

    Parameters
    ----------
    image : ndarray of shape (H, W, 3) or (H, W), dtype uint8
        BGR or gray frame.
    canny : tuple of (int, int)
        Canny hysteresis thresholds (grey levels).

    Returns
    -------
    ndarray of shape (H, W), dtype bool
        The edge pixels.
    """
    gray = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    return cv2.Canny(gray, canny[0], canny[1]) > 0


@lru_cache(maxsize=8)
def _blur_peak(ksize: int, sigma: float) -> float:
    """The blurred value of a lone edge pixel: the edge map's scale, so that an edge reads 1."""
    return float(cv2.GaussianBlur(np.pad(np.ones((1, 1), np.float32), ksize), (ksize, ksize), sigma).max())


def edge_map(
    image: np.ndarray | None,
    mask: np.ndarray,
    canny: tuple[int, int] = (40, 120),
    dilate_px: int = 5,
    blur_sigma: float = 1.5,
    edges: np.ndarray | None = None,
) -> np.ndarray:
    """Deutscher's smoothed edge map: Canny edges within the dilated foreground, Gaussian blurred
    and scaled so that an edge pixel reads 1.

    Parameters
    ----------
    image : ndarray of shape (H, W, 3) or (H, W), dtype uint8, or None
        BGR or gray frame, or None to use the mask's own boundary.
    mask : ndarray of shape (H, W), dtype bool
        Foreground of the tracked person.
    canny : tuple of (int, int)
        Canny hysteresis thresholds (grey levels).
    dilate_px : int
        How far outside the mask image edges still count (pixels).
    blur_sigma : float
        Gaussian sigma (pixels) of the smoothing that gives the cost a basin.
    edges : ndarray of shape (H, W), dtype bool, or None
        The frame's Canny edges (:func:`frame_edges`) when already computed; then ``image`` and
        ``canny`` are not read.

    Returns
    -------
    ndarray of shape (H, W), dtype float32
        The edge map, in [0, 1].
    """
    m = mask.astype(np.uint8)
    k = np.ones((2 * dilate_px + 1, 2 * dilate_px + 1), np.uint8)
    region = cv2.dilate(m, k)
    # The mask boundary is always an edge of the person, even where the image contrast is low.
    boundary = m - cv2.erode(m, np.ones((3, 3), np.uint8), borderType=cv2.BORDER_CONSTANT, borderValue=0)
    out = boundary.astype(np.float32)
    if edges is None and image is not None:
        edges = frame_edges(image, canny)
    if edges is not None:
        out = np.maximum(out, (edges & (region > 0)).astype(np.float32))
    ksize = int(2 * round(3 * blur_sigma) + 1)
    sm = cv2.GaussianBlur(out, (ksize, ksize), blur_sigma)
    return np.clip(sm / np.float32(_blur_peak(ksize, blur_sigma)), 0.0, 1.0)


def _extent(mask: np.ndarray) -> tuple[int, int, int, int] | None:
    """(first row, last row, first column, last column) of the mask's pixels; None when empty."""
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if not len(rows):
        return None
    return int(rows[0]), int(rows[-1]), int(cols[0]), int(cols[-1])


def _window(extent: tuple[int, int, int, int] | None, shape: tuple[int, int], margin: int) -> tuple[int, int, int, int]:
    """(x0, y0, x1, y1): the bounding box of a mask's pixels (``_extent``) grown by ``margin`` and
    clipped to the image of ``shape`` (H, W); (0, 0, 0, 0) for an empty mask.
    """
    if extent is None:
        return 0, 0, 0, 0
    r0, r1, c0, c1 = extent
    H, W = shape
    return max(c0 - margin, 0), max(r0 - margin, 0), min(c1 + margin + 1, W), min(r1 + margin + 1, H)


def _past_border(
    extent: tuple[int, int, int, int] | None, shape: tuple[int, int], margin: int, past_border: float
) -> tuple[int, int, int, int]:
    """Rows above and below, columns left and right, that the window of a mask (``_extent``, in an
    image of ``shape``) goes on past the frame's borders (``make_observation``): 0 where the mask
    keeps clear of a border, else ``past_border`` times the mask's extent across it (at least the
    window's ``margin``).
    """
    if extent is None or past_border <= 0:
        return 0, 0, 0, 0
    r0, r1, c0, c1 = extent
    H, W = shape
    down = max(int(round(past_border * (r1 - r0 + 1))), margin)
    across = max(int(round(past_border * (c1 - c0 + 1))), margin)
    return (
        down if r0 == 0 else 0,
        down if r1 == H - 1 else 0,
        across if c0 == 0 else 0,
        across if c1 == W - 1 else 0,
    )


def _continue(a: np.ndarray, top: int, bottom: int, left: int, right: int) -> np.ndarray:
    """A bool window continued past the frame's borders by repeating its border rows and columns."""
    return cv2.copyMakeBorder(a.view(np.uint8), top, bottom, left, right, cv2.BORDER_REPLICATE).view(bool)


def make_observation(
    image: np.ndarray | None,
    mask: np.ndarray,
    n_cover: int = 32,
    rng: np.random.Generator | None = None,
    edges: np.ndarray | None = None,
    past_border: float = 1.0,
    **edge_kw,
) -> Observation:
    """Build the per-frame maps once (Deutscher: computed once per frame, read by every particle).

    The maps cover the mask's bounding box grown by a margin (``dilate_px`` + twice the blur's
    radius + 1) beyond which the edge map and its smoothing read nothing but zeros, so the window's
    maps hold the same values as maps of the whole frame would.

    A person cut off by the frame (legs below its bottom edge: someone near the camera, a webcam
    on a desk) would make every body part beyond the edge read "no foreground, no edge", and the
    fit would squeeze the whole body into the part in view. Where the mask touches a border, the
    window therefore goes on past it, by ``past_border`` times the mask's extent across that
    border, with the mask and the frame's edges continued as they meet the border (its last row
    or column repeated): a limb that leaves the picture is taken to go on as it left. The coverage
    samples stay in the picture.

    Parameters
    ----------
    image : ndarray of shape (H, W) or (H, W, 3), dtype uint8, or None
        The frame, or None (edges from the mask boundary only).
    mask : ndarray of shape (H, W), dtype bool or uint8
        Foreground of this person.
    n_cover : int
        Foreground pixels sampled for the coverage term (0 disables it).
    rng : numpy.random.Generator or None
        Generator for the coverage sample (default: seeded 0, so a frame maps the same way).
    edges : ndarray of shape (H, W), dtype bool, or None
        The frame's Canny edges (:func:`frame_edges`), when several people of one frame share them;
        None: computed from ``image``.
    past_border : float, default=1.0
        How far the window goes on past a frame border the mask touches, in multiples of the
        mask's extent across it (0: not at all).
    **edge_kw
        Keyword parameters of :func:`edge_map` (``canny``, ``dilate_px``, ``blur_sigma``).

    Returns
    -------
    Observation
        The frame's maps.

    Raises
    ------
    ValueError
        If the mask is not 2-D, or the image or the edges and the mask differ in size.
    """
    mask = np.asarray(mask, dtype=bool)  # no copy of a bool mask
    if mask.ndim != 2:
        raise ValueError(f"mask has shape {mask.shape}; expected (H, W) foreground of one person")
    if image is not None and image.shape[:2] != mask.shape:
        raise ValueError(f"image {image.shape[:2]} and mask {mask.shape} differ in size")
    if edges is not None and edges.shape != mask.shape:
        raise ValueError(f"edges {edges.shape} and mask {mask.shape} differ in size")
    if edges is None and image is not None:
        edges = frame_edges(image, edge_kw.get("canny", (40, 120)))
    dilate_px = int(edge_kw.get("dilate_px", 5))
    radius = int(round(3 * edge_kw.get("blur_sigma", 1.5)))
    margin = dilate_px + 2 * radius + 1
    extent = _extent(mask)
    x0, y0, x1, y1 = _window(extent, mask.shape, margin)
    win = mask[y0:y1, x0:x1]
    crop = None if edges is None else edges[y0:y1, x0:x1]
    top, bottom, left, right = _past_border(extent, mask.shape, margin, past_border)
    maps_win, maps_crop = win, crop
    if top or bottom or left or right:
        maps_win = _continue(win, top, bottom, left, right)
        maps_crop = None if crop is None else _continue(crop, top, bottom, left, right)
    fg = np.append(maps_win.ravel().astype(np.float32), np.float32(0))
    edge = np.zeros(1, np.float32)  # an empty mask: no window, every point reads nothing
    if win.size:
        edge = np.append(edge_map(None, maps_win, edges=maps_crop, **edge_kw).ravel(), np.float32(0))
    # the mask's pixels in the same (row-major) order as over the whole mask, as flat indices of the
    # window: only the picked ones are turned into rows and columns
    at = np.flatnonzero(win)
    rng = np.random.default_rng(0) if rng is None else rng
    if len(at) and n_cover:
        ys, xs = np.divmod(at[rng.choice(len(at), size=min(n_cover, len(at)), replace=False)], win.shape[1])
        cover = np.stack([xs + x0, ys + y0], axis=1).astype(np.float32)
    else:
        cover = np.zeros((0, 2), np.float32)
    h, w = maps_win.shape
    return Observation(fg, edge, cover, w, h, _cost_map(fg, edge), x0 - left, y0 - top)


def pose_anchor_points(P: np.ndarray, dims: BodyDims) -> np.ndarray:
    """Anchor points of poses (one forward kinematics, shared by every camera's view).

    Parameters
    ----------
    P : ndarray of shape (N, 28)
        Poses (metres and radians, ``counterpart.body.pose``).
    dims : BodyDims
        Body dimensions, metres.

    Returns
    -------
    ndarray of shape (N, A, 3), dtype float32
        Anchor points, metres, world frame.

    Raises
    ------
    ValueError
        For poses of a wrong shape.
    """
    P = np.asarray(P, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] != 28:
        raise ValueError(f"poses have shape {P.shape}; expected (N, 28)")
    return anchor_points(P, dims).astype(np.float32)


@dataclass(frozen=True)
class LikelihoodConfig:
    """The sample points and weights of the observation model (Deutscher et al. 2000, eqs. 4-6).

    Parameters
    ----------
    n_along, n_across : int
        Interior grid of sample points per cone, along and across its axis (as
        ``counterpart.body.raster.cone_interior_points``); default 4 x 3.
    per_side : int
        Outline sample points per long side of each cone (``cone_outline_points``); default 4.
    w_sil, w_edge, w_cover : float
        Weights of the silhouette cost S_r, the edge cost S_e and the coverage cost S_c (default 1).
    gain : float
        Overall scale of the cost: its sharpness before annealing (the APF's beta rescales it).
    w_ground : float
        Weight of the ground-contact cost ``S_g = min(1, (h / ground_sigma)^2)``, h the height
        (metres) of the lowest sole above y = 0. One camera cannot see depth; a foot on the ground
        plane fixes it (the image row of the foot and the calibrated camera give the distance).
    ground_sigma : float
        Width of the ground-contact cost, metres (default 0.05).
    past_border : float
        How far a person's observation window goes on past a frame border their mask touches,
        in multiples of the mask's extent across it (``make_observation``; 0: a body part beyond
        the border reads no foreground and no edge, as before).
    """

    n_along: int = 4
    n_across: int = 3
    per_side: int = 4
    w_sil: float = 1.0
    w_edge: float = 1.0
    w_cover: float = 1.0
    gain: float = 1.0
    w_ground: float = 1.0
    ground_sigma: float = 0.05
    past_border: float = 1.0


class ConeLikelihood:
    """Log-likelihood of N poses against one Observation (see the module docstring).

    Parameters
    ----------
    camera : Camera
        The calibrated camera.
    dims : BodyDims
        Body dimensions of the tracked person.
    config : LikelihoodConfig
        Sample points per cone and the weights of the costs.
    """

    def __init__(
        self, camera: Camera, dims: BodyDims = DEFAULT_DIMS, config: LikelihoodConfig = LikelihoodConfig()
    ) -> None:
        self.camera = camera
        self.dims = dims
        self.config = config
        self.radii = dims.segment_radii().astype(np.float32)  # (S, 2)
        self.w = (float(config.w_sil), float(config.w_edge), float(config.w_cover))
        self.gain = float(config.gain)
        self.w_ground = float(config.w_ground)
        self.ground_sigma = float(config.ground_sigma)
        self.sole_offset = np.array([dims.ankle_height] * 2 + [dims.r_toe] * 2, np.float32)
        # (s, t) of each sample: s along the axis, t across in units of the half-width.
        n_along, n_across, per_side = config.n_along, config.n_across, config.per_side
        s_in = np.repeat((np.arange(n_along) + 0.5) / n_along, n_across)
        t_in = np.tile((2 * np.arange(n_across) + 1) / n_across - 1.0, n_along)
        s_out = np.tile((np.arange(per_side) + 0.5) / per_side, 2)
        t_out = np.repeat([1.0, -1.0], per_side)
        self.n_in = len(s_in)
        self.s = np.concatenate([s_in, s_out]).astype(np.float32)  # (K,)
        self.t = np.concatenate([t_in, t_out]).astype(np.float32)
        # a sample is sum_j F_j G_j with F = (x0, ax, rho0 n, drho n) per cone: one matmul
        self._G = np.stack([np.ones_like(self.s), self.s, self.t, self.s * self.t])  # (4, K)
        self.f = np.float32(0.5 * (camera.fx + camera.fy))
        self.R = camera.R.astype(np.float32)
        self.tc = camera.t.astype(np.float32)
        # the compiled kernel's view of the same: fx, fy, cx, cy as the float32 the numpy code rounds
        # them to, and each cone's two anchors
        self._intr = np.array([camera.fx, camera.fy, camera.cx, camera.cy], np.float32)
        self._seg = np.ascontiguousarray(SEGMENT_ANCHORS, dtype=np.int64)
        self.n_evals = 0
        #: (cover_uv, its centre, its (3, M) matmul operand, its squared norms) of the last frame
        self._cover: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None

    # ---------------------------------------------------------------------------------------
    def project(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Project the cones of poses into the image.

        Parameters
        ----------
        P : ndarray of shape (N, 28)
            Poses (metres and radians, ``counterpart.body.pose``).

        Returns
        -------
        ends : ndarray of shape (N, S, 2, 2), dtype float32
            Cone end centres, pixels.
        half_widths : ndarray of shape (N, S, 2), dtype float32
            Half-widths at the ends, pixels.
        ok : ndarray of shape (N,), dtype bool
            Every anchor in front of the camera.
        """
        return self._project(anchor_points(P, self.dims).astype(np.float32))

    def ground_cost(self, pts: np.ndarray) -> np.ndarray:
        """The ground-contact cost S_g (see :class:`LikelihoodConfig`).

        Parameters
        ----------
        pts : ndarray of shape (N, A, 3)
            Anchor points, metres.

        Returns
        -------
        ndarray of shape (N,)
            S_g, in [0, 1].
        """
        h = self.sole_height(pts)
        return np.minimum((h / np.float32(self.ground_sigma)) ** 2, np.float32(1.0))

    def _project(self, pts: np.ndarray, fr: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cone ends (N, S, 2, 2) px, half-widths (N, S, 2) px and the in-front test (N,) of anchor
        points (N, A, 3); ``fr``: the focal length times the radii, (S, 2) or per pose (N, S, 2)
        (None: this likelihood's body).
        """
        fr = self.f * self.radii if fr is None else fr
        Xc = pts @ self.R.T + self.tc
        z = Xc[..., 2]
        ok = (z > 0.05).all(axis=1)
        zi = 1.0 / np.maximum(z, np.float32(0.05))
        uv = np.stack(
            [self.camera.fx * Xc[..., 0] * zi + self.camera.cx, self.camera.fy * Xc[..., 1] * zi + self.camera.cy],
            axis=-1,
        ).astype(np.float32, copy=False)
        c = uv[:, SEGMENT_ANCHORS]  # (N, S, 2, 2)
        rho = fr * zi[:, SEGMENT_ANCHORS]  # (N, S, 2)
        return c, rho, ok

    def sample_points(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The sample points of poses' projected cones.

        Same points as ``counterpart.body.raster.cone_interior_points`` / ``cone_outline_points`` (trapezoid
        approximation of each projected cone), computed in one broadcast.

        Parameters
        ----------
        P : ndarray of shape (N, 28)
            Poses (metres and radians, ``counterpart.body.pose``).

        Returns
        -------
        interior : ndarray of shape (N, S*K_in, 2), dtype float32
            Interior points, pixels.
        outline : ndarray of shape (N, S*K_out, 2), dtype float32
            Outline points, pixels.
        ok : ndarray of shape (N,), dtype bool
            Every anchor in front of the camera.
        """
        c, rho, ok = self.project(P)
        u, v = self._points_uv(c, rho)
        pts = np.stack([u, v], axis=-1)  # (N, S, K, 2)
        N = pts.shape[0]
        return pts[:, :, : self.n_in].reshape(N, -1, 2), pts[:, :, self.n_in :].reshape(N, -1, 2), ok

    def _points_uv(self, c: np.ndarray, rho: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Cone ends (N, S, 2, 2) px, half-widths (N, S, 2) px -> u, v (N, S, K) of all samples.

        Each sample is c0 + s a + (r0 + s dr) t n (axis a, unit normal n, sample (s, t)): linear
        in (1, s, t, s t), so all of them are one (N S 2, 4) x (4, K) matmul.
        """
        x0, y0 = c[:, :, 0, 0], c[:, :, 0, 1]  # (N, S)
        ax, ay = c[:, :, 1, 0] - x0, c[:, :, 1, 1] - y0
        L = np.sqrt(ax * ax + ay * ay)
        ok = L > 1e-6
        inv = np.where(ok, 1.0 / np.where(ok, L, 1.0), 0).astype(np.float32, copy=False)
        nx = np.where(ok, -ay * inv, np.float32(1.0))
        ny = ax * inv
        r0, dr = rho[..., 0], rho[..., 1] - rho[..., 0]
        # point = c0 + s a + (r0 + s dr) t n, per axis sum_j F_j G_j over (1, s, t, s t)
        F = np.stack([x0, ax, r0 * nx, dr * nx, y0, ay, r0 * ny, dr * ny], axis=-1).astype(np.float32, copy=False)
        uv = (F.reshape(-1, 4) @ self._G).reshape(*x0.shape, 2, -1)  # (N, S, 2, K)
        return uv[:, :, 0], uv[:, :, 1]

    def coverage_cost(self, c: np.ndarray, rho: np.ndarray, cover_uv: np.ndarray) -> np.ndarray:
        """The fraction of the M foreground samples outside every projected cone, S_c (capsule test:
        distance to the cone's image axis below the interpolated half-width + 1 px).

        The projection of a sample q onto the axis and its squared distance come from 2 d.a and
        |d|^2 (d = q - c0), both linear in (q_x, q_y, 1): one matmul over cones x samples, then
        in-place arithmetic on the (N, S, M) arrays.

        Parameters
        ----------
        c : ndarray of shape (N, S, 2, 2), dtype float32
            Cone end centres, pixels.
        rho : ndarray of shape (N, S, 2), dtype float32
            Half-widths at the ends, pixels.
        cover_uv : ndarray of shape (M, 2), dtype float32
            Foreground samples, pixels.

        Returns
        -------
        ndarray of shape (N,), dtype float32
            S_c, in [0, 1] (0 without samples).
        """
        if cover_uv.shape[0] == 0:
            return np.zeros(c.shape[0], np.float32)
        o, G, qq = self.cover_terms(cover_uv)
        return _coverage(c, rho, o[0], o[1], G, qq)

    def cover_terms(self, cover_uv: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The coverage samples' own terms (computed once a frame).

        Parameters
        ----------
        cover_uv : ndarray of shape (M, 2), dtype float32
            Foreground samples, pixels (M >= 1).

        Returns
        -------
        o : ndarray of shape (2,)
            Their centre.
        G : ndarray of shape (3, M), dtype float32
            (x - o_x, y - o_y, 1) of each.
        qq : ndarray of shape (M,)
            Their squared distances to the centre.
        """
        if self._cover is None or self._cover[0] is not cover_uv:  # once a frame
            # coordinates relative to the samples' centre keep the float32 squares accurate
            o = cover_uv.mean(axis=0)
            q = cover_uv - o  # (M, 2)
            G = np.concatenate([q.T, np.ones((1, len(q)), np.float32)]).astype(np.float32)  # (3, M)
            self._cover = (cover_uv, o, G, (q * q).sum(axis=1))
        return self._cover[1:]

    def terms(self, P: np.ndarray, obs: Observation) -> np.ndarray:
        """The image costs of poses.

        Parameters
        ----------
        P : ndarray of shape (N, 28)
            Poses (metres and radians, ``counterpart.body.pose``).
        obs : Observation
            The frame's maps.

        Returns
        -------
        ndarray of shape (N, 3)
            S_r, S_e, S_c, each in [0, 1]; poses behind the camera get 1.
        """
        return self.evaluate(P, obs)[0]

    def sole_height(self, pts: np.ndarray) -> np.ndarray:
        """Height of the lowest sole above the ground.

        Parameters
        ----------
        pts : ndarray of shape (N, A, 3)
            Anchor points, metres.

        Returns
        -------
        ndarray of shape (N,)
            The height, metres.
        """
        return (pts[:, _FOOT_ANCHORS, 1] - self.sole_offset).min(axis=1)

    def evaluate(self, P: np.ndarray, obs: Observation) -> tuple[np.ndarray, np.ndarray]:
        """Image and ground costs from one forward kinematics (``combine`` turns them into
        log-likelihoods).

        Parameters
        ----------
        P : ndarray of shape (N, 28)
            Poses (metres and radians, ``counterpart.body.pose``).
        obs : Observation
            The frame's maps.

        Returns
        -------
        terms : ndarray of shape (N, 3), dtype float32
            S_r, S_e, S_c.
        ground : ndarray of shape (N,), dtype float32
            S_g (0 when ``w_ground`` is 0).

        Raises
        ------
        ValueError
            For poses of a wrong shape.
        """
        pts = pose_anchor_points(P, self.dims)
        g = self.ground_cost(pts) if self.w_ground else np.zeros(len(pts), np.float32)
        return self.image_costs(pts, obs), g

    def image_costs(self, pts: np.ndarray, obs: Observation) -> np.ndarray:
        """The image costs of this camera's view.

        Parameters
        ----------
        pts : ndarray of shape (N, A, 3), dtype float32
            Anchor points, metres (``pose_anchor_points``).
        obs : Observation
            The frame's maps of this view.

        Returns
        -------
        ndarray of shape (N, 3)
            S_r, S_e, S_c; poses with an anchor behind the camera get 1.
        """
        from .kernels import cone_image_costs  # numba's import: in the processes that weigh poses

        N = pts.shape[0]
        M = obs.cover_uv.shape[0] if self.w[2] else 0
        o, G, qq = self.cover_terms(obs.cover_uv) if M else (np.zeros(2, np.float32), _NO_G, _NO_QQ)
        out = np.empty((N, 3), np.float32)
        cone_image_costs(
            np.ascontiguousarray(pts, dtype=np.float32),
            self.R,
            self.tc,
            self._intr,
            (self.f * self.radii)[None],
            self._seg,
            self._G,
            self.n_in,
            np.array([[obs.x0, obs.y0, obs.width, obs.height]], np.float32),
            np.array([[0, obs.width * obs.height + 1]], np.int64),
            obs.cost_map(),
            np.zeros(N, np.int64),
            np.asarray(o, np.float32)[None],
            np.ascontiguousarray(G),
            qq,
            np.zeros(1, np.int64),
            np.array([M], np.int64),
            M > 0,
            out,
        )
        self.n_evals += pts.shape[0]
        return out

    def __call__(self, P: np.ndarray, obs: Observation) -> np.ndarray:
        """(N, 28) poses -> (N,) float64 log-likelihoods ``-gain * (w . [S_r, S_e, S_c] + w_ground S_g)``."""
        return self.combine(*self.evaluate(P, obs))

    def combine(self, terms: np.ndarray, ground: np.ndarray) -> np.ndarray:
        """Log-likelihoods from the costs of ``evaluate``.

        Parameters
        ----------
        terms : ndarray of shape (N, 3)
            Image costs S_r, S_e, S_c.
        ground : ndarray of shape (N,)
            Ground costs S_g.

        Returns
        -------
        ndarray of shape (N,), dtype float64
            ``-gain * (w . [S_r, S_e, S_c] + w_ground S_g)``.
        """
        return -self.gain * (terms @ np.asarray(self.w, np.float32) + self.w_ground * ground).astype(np.float64)


def _coverage(
    c: np.ndarray, rho: np.ndarray, ox: np.ndarray, oy: np.ndarray, G: np.ndarray, qq: np.ndarray
) -> np.ndarray:
    """``ConeLikelihood.coverage_cost`` from the samples' terms (``cover_terms``): of one person
    (``ox``, ``oy`` scalars, ``G`` (3, M), ``qq`` (M,)) or per pose of several people's (``ox``,
    ``oy`` (N, 1), ``G`` (N, 3, M), ``qq`` (N, 1, M), the same M for all): (N,) S_c.
    """
    x0, y0 = c[:, :, 0, 0] - ox, c[:, :, 0, 1] - oy  # (N, S)
    ax, ay = c[:, :, 1, 0] - c[:, :, 0, 0], c[:, :, 1, 1] - c[:, :, 0, 1]
    aa = np.maximum(ax * ax + ay * ay, np.float32(1e-6))
    # with d = q - c0: 2 d.a and |d|^2 - |q|^2 are linear in (qx, qy, 1): one matmul
    F = np.stack(
        [
            np.stack([2 * ax, 2 * ay, -2 * (x0 * ax + y0 * ay)], axis=-1),
            np.stack([-2 * x0, -2 * y0, x0 * x0 + y0 * y0], axis=-1),
        ]
    ).astype(np.float32)
    pd2, d2 = F @ G  # 2 x (N, S, M)
    d2 += qq  # |d|^2
    # s = clip(d.a / |a|^2, 0, 1), the nearest axis point; |d - s a|^2 = |d|^2 - s (2 d.a - s |a|^2)
    s = np.multiply(pd2, (0.5 / aa)[..., None])
    np.clip(s, 0.0, 1.0, out=s)
    tmp = np.multiply(s, aa[..., None])
    np.subtract(pd2, tmp, out=tmp)
    tmp *= s
    d2 -= tmp  # squared distance to the axis
    # + 1 px: a rasterised mask holds every pixel the body touches, the capsule test their centres
    r = np.multiply(s, (rho[..., 1] - rho[..., 0])[..., None], out=tmp)
    r += (rho[..., 0] + np.float32(1.0))[..., None]
    r *= r
    covered = (d2 <= r).any(axis=1)  # (N, M)
    return 1.0 - covered.mean(axis=1, dtype=np.float32)


class MultiViewLikelihood:
    """The weighting function over several calibrated cameras (Deutscher et al. use three): the
    image costs of every view in which the person is seen are summed, the ground term counts once.

    With one camera it is ``ConeLikelihood`` itself. A second view sees the depth and the heading
    that one silhouette leaves open (a limb towards the camera, a person turned towards or away).

    Parameters
    ----------
    cameras : sequence of Camera
        The calibrated cameras, the first one the reference view (initialisation, 2D).
    dims : BodyDims
        Body dimensions of the tracked person.
    config : LikelihoodConfig
        Every view's sample points and weights (:class:`ConeLikelihood`).

    Raises
    ------
    ValueError
        Without a camera.
    """

    def __init__(
        self, cameras: Sequence[Camera], dims: BodyDims = DEFAULT_DIMS, config: LikelihoodConfig = LikelihoodConfig()
    ) -> None:
        if not cameras:
            raise ValueError("MultiViewLikelihood needs at least one camera")
        self.views = [ConeLikelihood(cam, dims, config) for cam in cameras]
        self.dims = dims

    def evaluate(self, P: np.ndarray, obs: Sequence[Observation]) -> tuple[np.ndarray, np.ndarray]:
        """Image costs summed over the views, and ground costs.

        Parameters
        ----------
        P : ndarray of shape (N, 28)
            Poses (metres and radians, ``counterpart.body.pose``).
        obs : sequence of Observation
            One per camera.

        Returns
        -------
        terms : ndarray of shape (N, 3), dtype float32
            S_r, S_e, S_c summed over the views whose observation is not empty (0 <= each <= views seen).
        ground : ndarray of shape (N,), dtype float32
            S_g (once, from the reference view).

        Raises
        ------
        ValueError
            When the number of observations is not the number of cameras, or for poses of a wrong shape.
        """
        if len(obs) != len(self.views):
            raise ValueError(f"{len(obs)} observations for {len(self.views)} cameras; give one per camera")
        pts = pose_anchor_points(P, self.dims)
        terms = np.zeros((len(pts), 3), np.float32)
        for view, o in zip(self.views, obs):
            if not o.empty:
                terms += view.image_costs(pts, o)
        head = self.views[0]
        g = head.ground_cost(pts) if head.w_ground else np.zeros(len(pts), np.float32)
        return terms, g

    def __call__(self, P: np.ndarray, obs: Sequence[Observation]) -> np.ndarray:
        """(N, 28) poses -> (N,) float64 log-likelihoods (``ConeLikelihood.combine`` of the sums)."""
        return self.combine(*self.evaluate(P, obs))

    def combine(self, terms: np.ndarray, ground: np.ndarray) -> np.ndarray:
        """Log-likelihoods from the summed costs of ``evaluate``.

        Parameters
        ----------
        terms : ndarray of shape (N, 3)
            Summed image costs.
        ground : ndarray of shape (N,)
            Ground costs.

        Returns
        -------
        ndarray of shape (N,), dtype float64
            The log-likelihoods (``ConeLikelihood.combine``).
        """
        return self.views[0].combine(terms, ground)


def _same_view(a: ConeLikelihood, b: ConeLikelihood) -> bool:
    """Both project through the same camera with the same sample points and weights."""
    ca, cb = a.camera, b.camera
    return (
        a.config == b.config
        and (ca.width, ca.height, ca.fx, ca.fy, ca.cx, ca.cy) == (cb.width, cb.height, cb.fx, cb.fy, cb.cx, cb.cy)
        and np.array_equal(a.R, b.R)
        and np.array_equal(a.tc, b.tc)
    )


class _Batch:
    """The per-frame constants of :func:`evaluate_joint` for one set of people of one frame, as the
    compiled kernel's per-person tables: each person's body (kinematics, radii, soles), window, the
    place of its cost map in the maps laid end to end and its coverage samples, and each pose's
    person.
    """

    def __init__(self, likelihoods: Sequence[MultiViewLikelihood], counts: list[int], o0: list[Observation]) -> None:
        views = [lk.views[0] for lk in likelihoods]
        # held, so that they are compared by identity (``serves``)
        self.likelihoods, self.counts, self.obs = list(likelihoods), list(counts), list(o0)
        self.dims = row_dims(tuple(lk.dims for lk in likelihoods), tuple(counts))
        self.sole_offset = np.repeat(np.stack([v.sole_offset for v in views]), counts, axis=0)
        self.person = np.repeat(np.arange(len(views), dtype=np.int64), counts)
        self.fr = np.stack([v.f * v.radii for v in views])  # (P, S, 2)
        maps = [o.cost_map() for o in o0]
        self.maps = np.concatenate(maps)
        self.win = np.array([(o.x0, o.y0, o.width, o.height) for o in o0], np.float32)
        start = np.cumsum([0] + [len(m) for m in maps[:-1]]).astype(np.int64)
        # the edge costs follow the fg costs in each map
        self.base = np.stack([start, start + [o.width * o.height + 1 for o in o0]], axis=1)
        with_cover = views[0].w[2] != 0
        sizes = [len(o.cover_uv) if with_cover else 0 for o in o0]
        terms = [v.cover_terms(o.cover_uv) if m else None for v, o, m in zip(views, o0, sizes)]
        self.cover_o = np.array([t[0] if t else (0.0, 0.0) for t in terms], np.float32).reshape(-1, 2)
        self.cover_G = np.ascontiguousarray(np.concatenate([_NO_G] + [t[1] for t in terms if t], axis=1))
        self.cover_qq = np.concatenate([_NO_QQ] + [t[2] for t in terms if t]).astype(np.float32)
        self.cover_len = np.array(sizes, np.int64)
        self.cover_start = (np.cumsum(self.cover_len) - self.cover_len).astype(np.int64)

    def serves(self, likelihoods: Sequence[MultiViewLikelihood], counts: list[int], o0: list[Observation]) -> bool:
        """The same people (the same objects), particle counts and observations."""
        return (
            counts == self.counts
            and len(likelihoods) == len(self.likelihoods)
            and all(a is b for a, b in zip(likelihoods, self.likelihoods))
            and all(a is b for a, b in zip(o0, self.obs))
        )


#: the newest _Batch (the layers of one frame reuse it)
_BATCH: list[_Batch | None] = [None]


def evaluate_joint(
    likelihoods: Sequence[MultiViewLikelihood], poses: Sequence[np.ndarray], obs: Sequence[Sequence[Observation]]
) -> list[tuple[np.ndarray, np.ndarray]]:
    """``MultiViewLikelihood.evaluate`` of several people of one frame at once.

    The particles of all of them go through one forward kinematics (each with its own body, as
    :class:`counterpart.body.kinematics.RowDims`) and one call of the image-cost kernel over their
    cost maps laid end to end (each pose against its person's body, window and foreground
    samples). At the few dozen particles per person of a real-time frame the cost of the calls,
    not of the particles, dominated, so two people cost little more than one. The kernel weighs
    each pose alone: the numbers are those of each person's own ``evaluate``, up to the rounding of
    the forward kinematics of a batch of several bodies. People of several views, or of other cameras or settings, are
    evaluated one by one.

    Parameters
    ----------
    likelihoods : sequence of MultiViewLikelihood
        Each person's observation model.
    poses : sequence of ndarray of shape (N_i, 28)
        Each person's particles.
    obs : sequence of sequence of Observation
        Each person's observations (one per camera).

    Returns
    -------
    list of (terms, ground)
        Each person's ``evaluate``: terms (N_i, 3) float32, ground (N_i,) float32.
    """
    views = [lk.views[0] for lk in likelihoods]
    counts = [len(P) for P in poses]
    o0 = [o[0] for o in obs]
    # the per-pose constants, the same for every layer of the frame (made by its first layer, once
    # the people are found to share a view)
    b = _BATCH[0]
    if b is None or not b.serves(likelihoods, counts, o0):
        if (
            len(likelihoods) < 2
            or any(len(lk.views) != 1 for lk in likelihoods)
            or any(o.empty for o in o0)
            or not all(_same_view(views[0], v) for v in views[1:])
        ):
            return [lk.evaluate(P, o) for lk, P, o in zip(likelihoods, poses, obs)]
        b = _BATCH[0] = _Batch(likelihoods, counts, o0)
    v0 = views[0]
    P = np.concatenate([np.asarray(p, dtype=np.float64) for p in poses])
    if P.ndim != 2 or P.shape[1] != 28:
        raise ValueError(f"poses have shape {P.shape}; expected (N, 28)")
    pts = anchor_points(P, b.dims).astype(np.float32)
    if v0.w_ground:
        h = (pts[:, _FOOT_ANCHORS, 1] - b.sole_offset).min(axis=1)
        ground = np.minimum((h / np.float32(v0.ground_sigma)) ** 2, np.float32(1.0))
    else:
        ground = np.zeros(len(pts), np.float32)
    from .kernels import cone_image_costs  # numba's import: in the processes that weigh poses

    terms = np.empty((len(pts), 3), np.float32)
    cone_image_costs(
        pts,
        v0.R,
        v0.tc,
        v0._intr,
        b.fr,
        v0._seg,
        v0._G,
        v0.n_in,
        b.win,
        b.base,
        b.maps,
        b.person,
        b.cover_o,
        b.cover_G,
        b.cover_qq,
        b.cover_start,
        b.cover_len,
        bool(v0.w[2]),
        terms,
    )
    out, start = [], 0
    for view, n in zip(views, counts):  # every person's terms handed out as views of one array
        sl = slice(start, start + n)
        start += n
        view.n_evals += n
        out.append((terms[sl], ground[sl]))
    return out


def warm_kernels() -> None:
    """Load the compiled kernels the likelihood runs (the forward kinematics of the anchor points
    and the image costs), compiling them on an install's first run, on one pose against a tiny
    mask: called when a tracker node starts, so that its first frame does not wait for them.
    """
    mask = np.zeros((24, 32), bool)
    mask[4:20, 12:20] = True
    ConeLikelihood(default_camera(32, 24)).evaluate(neutral_pose()[None], make_observation(None, mask, n_cover=4))


__all__ = [
    "evaluate_joint",
    "warm_kernels",
    "Observation",
    "edge_map",
    "frame_edges",
    "make_observation",
    "ConeLikelihood",
    "LikelihoodConfig",
    "MultiViewLikelihood",
    "pose_anchor_points",
    "N_SEGMENTS",
]
