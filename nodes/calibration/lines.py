"""Straight lines of the scene for the camera estimate: families of parallel scene lines and their
vanishing points (the ground's horizon, the vertical).

Line segments of a frame (OpenCV's LSD, von Gioi et al. 2010), without those on the people, each
refitted along its whole edge (:func:`refine_segments`: LSD's pieces of a long edge of a small,
aliased frame read a degree or two off its direction), are grouped by the vanishing point they
converge to (a segment agrees with a vanishing point when the
line from its midpoint to that point is within ``angle_deg`` of its own direction).
:func:`scene_lines` groups them by the three vanishing points of one square frame of the room (two
ground directions at right angles and the vertical, searched jointly with the camera's focal length
and tilt: :func:`find_manhattan_families`); one vanishing point at a time (:func:`find_families`,
sequential RANSAC over pairs of segments) the floor's boards, the wall's lines and the texture's
chance alignments made families several degrees off any direction of the room. The free grouping is
kept for a scene that is not laid out square (the square frame groups much less of it). A family whose segments are mostly steep (within
``vertical_deg`` of the image vertical) is taken as the world's vertical; the others as horizontal
directions, whose vanishing points lie on the horizon (the vanishing line of the ground plane).
``counterpart.nodes.calibration.estimate`` fits the camera to them together with the people: each horizontal
family adds only its unknown direction on the ground, so it says where the horizon is (tilt and
roll) without any assumption about the angles between the families.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np

#: shortest segment :func:`scene_lines` keeps, pixels (short pieces of the floor's boards far away
#: still agree with a vanishing point once the frame of three of them is searched jointly)
MIN_LENGTH = 10.0
#: the least share of the segment length grouped freely that the square frame must group
MANHATTAN_SHARE = 0.8
#: LSD's resampling scales whose segments :func:`scene_lines` pools (:func:`detect_segments`): the
#: previous single 0.6, and one each side of it (0.8 is OpenCV's default)
LSD_SCALES = (0.45, 0.6, 0.8)


@dataclass(frozen=True)
class LineFamilies:
    """Scene line segments grouped by vanishing point.

    Parameters
    ----------
    segments : ndarray of shape (N, 4), dtype float64
        Pixels, x1, y1, x2, y2.
    family : ndarray of shape (N,), dtype int
        The family of each segment (index into ``vertical`` and ``vp``).
    vertical : ndarray of shape (F,), dtype bool
        Whether each family is the world's vertical.
    vp : ndarray of shape (F, 3)
        Homogeneous vanishing points found (pixels; last coordinate 0 at infinity).
    square : bool, default=False
        The families are the directions of one square frame, found jointly
        (:func:`find_manhattan_families`): none of them is a chance meeting of segments.
    """

    segments: np.ndarray
    family: np.ndarray
    vertical: np.ndarray
    vp: np.ndarray
    square: bool = False

    @property
    def n_horizontal(self) -> int:
        return int((~self.vertical).sum())


def detect_segments(
    image: np.ndarray,
    boxes: Iterable[Any] = (),
    min_length: float = 20.0,
    scale: float | tuple[float, ...] = 0.6,
) -> np.ndarray:
    """LSD segments of an image, without those on the people.

    Parameters
    ----------
    image : ndarray of shape (H, W, 3) or (H, W), dtype uint8
        BGR or grey image.
    boxes : iterable of (x, y, w, h), default=()
        Boxes in pixels (the people); a segment with both ends in one box is dropped (it lies on the
        person). Segments that reach out of the box are kept: the floor's and the wall's lines
        passing behind a person are the horizon's best evidence, and a box grown around the people
        or a midpoint test cut most of them in the simulator's rooms.
    min_length : float, default=20.0
        Shortest segment kept, pixels.
    scale : float or tuple of float, default=0.6
        LSD's own resampling of the image before it looks for lines (its Gaussian sub-sampling, von
        Gioi et al. 2010, section 4; OpenCV's default 0.8). Smaller scales smooth more: the faint,
        aliased edges of a floor's boards receding from a low-resolution camera (320x240) come out
        as long segments instead of broken pieces, and these give the ground's second vanishing
        point (the horizon's position, and the focal length through the right-angle prior).
        Several scales: the union of the segments found at each (a faint edge broken up by the
        floor's grain at one scale comes out whole at another; an edge found at several scales is
        counted at each, so it weighs more than one that only one scale sees).

    Returns
    -------
    ndarray of shape (N, 4), dtype float64
        Segments x1, y1, x2, y2, pixels.
    """
    grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image
    scales = (scale,) if np.isscalar(scale) else tuple(scale)
    if not scales or not all(0.0 < v <= 1.0 for v in scales):
        raise ValueError(f"scale must be in (0, 1], got {scale}")
    found = [cv2.createLineSegmentDetector(cv2.LSD_REFINE_STD, float(v)).detect(grey)[0] for v in scales]
    found = [f.reshape(-1, 4) for f in found if f is not None]
    if not found:
        return np.zeros((0, 4))
    s = np.concatenate(found).astype(np.float64)
    s = s[np.hypot(s[:, 2] - s[:, 0], s[:, 3] - s[:, 1]) >= min_length]
    keep = np.ones(len(s), bool)
    for x, y, w, h in boxes:
        inside = (s[:, [0, 2]] >= x) & (s[:, [0, 2]] <= x + w) & (s[:, [1, 3]] >= y) & (s[:, [1, 3]] <= y + h)
        keep &= ~inside.all(axis=1)
    return s[keep]


@dataclass(frozen=True)
class RefineConfig:
    """How :func:`refine_segments` follows an edge.

    Parameters
    ----------
    reach_px : float, default=2.0
        Half-width of the band searched across each line for its edge, pixels.
    max_gap_px : int, default=4
        Longest gap bridged along an edge, pixels.
    min_strength : float, default=0.5
        Least gradient across the line of an edge sample, as a share of its median on the segment.
    """

    reach_px: float = 2.0
    max_gap_px: int = 4
    min_strength: float = 0.5


def refine_segments(image: np.ndarray, segments: np.ndarray, config: RefineConfig = RefineConfig()) -> np.ndarray:
    """Each segment refitted to its whole edge: followed along its line both ways while the edge goes
    on, and its line fitted by least squares to the edge's subpixel positions there.

    LSD cuts a long straight edge of a small frame into pieces, and each piece's direction is only as
    good as its few pixels: a nearly horizontal edge of an aliased or compressed frame runs in steps,
    and a piece 40 pixels long lying along one step reads one or two degrees off (the wall's lines
    far from a camera that faces it, whose vanishing point is far to one side and fixes the focal
    length only through such small angles). Along the whole edge the steps average out.

    For each segment, the gradient across its line (the image lightly smoothed, Sobel) is sampled
    every pixel along the line's whole length in the frame, at offsets within ``reach_px`` across it.
    A sample belongs to the edge where its strongest gradient of the segment's polarity is at least
    ``min_strength`` of the segment's median and lies inside the band; the edge is the run of such
    samples, with gaps of at most ``max_gap_px``, that holds the segment's middle. The edge position
    at each sample is the parabola peak of the gradient across the line (subpixel); a straight line
    is fitted to them, weighted by the gradient, samples more than a pixel off left out (three
    rounds). A segment whose edge has fewer than five samples is returned as it was.

    Parameters
    ----------
    image : ndarray of shape (H, W, 3) or (H, W), dtype uint8
        BGR or grey image the segments were found in.
    segments : ndarray of shape (N, 4)
        Segments x1, y1, x2, y2, pixels.
    config : RefineConfig, default=RefineConfig()
        The band, the gaps bridged and the edge's least strength.

    Returns
    -------
    ndarray of shape (N, 4), dtype float64
        The refitted segments, in the order given: the fitted line between the ends of its edge.
    """
    s = np.asarray(segments, np.float64).reshape(-1, 4)
    if not len(s):
        return s.copy()
    grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image
    H, W = grey.shape
    g = cv2.GaussianBlur(grey.astype(np.float32), (0, 0), 0.7)
    gx = cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3) / 8.0
    gy = cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3) / 8.0
    u, n, mid, length = _segment_frames(s)
    offs = np.arange(-config.reach_px, config.reach_px + 1e-9, 0.5)
    t_lo, t_hi = _span_in_frame(mid, u, W, H)
    out = s.copy()
    for i in np.flatnonzero((length >= 1.0) & (t_hi >= t_lo)):
        # the segment's whole line in the frame, every pixel along it from its middle
        t = np.arange(np.ceil(t_lo[i]), np.floor(t_hi[i]) + 1.0)
        pts = mid[i] + t[:, None, None] * u[i] + offs[None, :, None] * n[i]
        xs, ys = pts[..., 0].astype(np.float32), pts[..., 1].astype(np.float32)
        inside = ((xs >= 1) & (xs <= W - 2) & (ys >= 1) & (ys <= H - 2)).all(axis=-1)
        across = _bilinear(gx, xs, ys) * n[i, 0] + _bilinear(gy, xs, ys) * n[i, 1]
        out[i] = _refit_edge(s[i], across, t, inside, offs, config)
    return out


def _span_in_frame(mid: np.ndarray, u: np.ndarray, W: int, H: int) -> tuple[np.ndarray, np.ndarray]:
    """(N,) least and greatest t at which the lines ``mid + t u`` (N, 2) lie within the frame's
    pixels 1 to W - 2 and 1 to H - 2 (a line that misses it: the least above the greatest).
    """
    lo, hi = np.full(len(mid), -np.inf), np.full(len(mid), np.inf)
    for axis, size in ((0, W), (1, H)):
        d, c = u[:, axis], mid[:, axis]
        with np.errstate(divide="ignore", invalid="ignore"):
            a, b = (1.0 - c) / d, (size - 2.0 - c) / d
        moving = np.abs(d) > 1e-12
        lo = np.where(moving, np.maximum(lo, np.minimum(a, b)), np.where((c >= 1) & (c <= size - 2), lo, np.inf))
        hi = np.where(moving, np.minimum(hi, np.maximum(a, b)), hi)
    return lo, hi


def _segment_frames(segments: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Unit directions (N, 2), unit normals (N, 2), middles (N, 2) and lengths (N,) of segments (N, 4)."""
    d = segments[:, 2:] - segments[:, :2]
    length = np.linalg.norm(d, axis=1)
    u = d / np.maximum(length, 1e-12)[:, None]
    return u, np.column_stack([-u[:, 1], u[:, 0]]), 0.5 * (segments[:, :2] + segments[:, 2:]), length


def _bilinear(image: np.ndarray, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """``image`` (float32) at the points (``xs``, ``ys``) of any shape, bilinear.

    ``cv2.remap``'s maps must be under 32767 rows and columns: the points go in rows of 4096.
    """
    m = xs.size
    rows = -(-m // 4096)
    mx, my = np.zeros((2, rows * 4096), np.float32)
    mx[:m], my[:m] = xs.ravel(), ys.ravel()
    out = cv2.remap(image, mx.reshape(rows, 4096), my.reshape(rows, 4096), cv2.INTER_LINEAR)
    return out.ravel()[:m].reshape(xs.shape)


def _refit_edge(
    segment: np.ndarray, across: np.ndarray, t: np.ndarray, inside: np.ndarray, offs: np.ndarray, config: RefineConfig
) -> np.ndarray:
    """:func:`refine_segments` of one segment (4,) from the gradient across its line, ``across`` (T, O),
    sampled at ``t`` (T,) pixels along it from its middle (``inside``: within the frame) and ``offs``
    (O,) pixels across.
    """
    u, n, mid, length = (v[0] for v in _segment_frames(segment[None]))
    on = inside & (np.abs(t) <= 0.5 * length)
    if not on.any():
        return segment
    g = across if np.median(across[on, len(offs) // 2]) >= 0 else -across
    k = np.argmax(g, axis=1)
    peak = g[np.arange(len(t)), k]
    strength = float(np.median(peak[on]))
    if not strength > 0:
        return segment
    idx = np.flatnonzero(inside & (peak >= config.min_strength * strength) & (k > 0) & (k < len(offs) - 1))
    if len(idx) < 5:
        return segment
    run = np.concatenate([[0], np.cumsum(np.diff(t[idx]) > config.max_gap_px + 1)])
    idx = idx[run == run[np.argmin(np.abs(t[idx]))]]
    if len(idx) < 5:
        return segment
    a, b, e = g[idx, k[idx] - 1], peak[idx], g[idx, k[idx] + 1]
    den = a - 2.0 * b + e
    sub = np.divide(0.5 * (a - e), den, out=np.zeros_like(den), where=np.abs(den) > 1e-9)
    pos = offs[k[idx]] + 0.5 * np.clip(sub, -1.0, 1.0)
    tt = t[idx]
    keep = np.ones(len(tt), bool)
    for _ in range(3):
        A = np.column_stack([tt[keep], np.ones(int(keep.sum()))]) * b[keep, None]
        slope, offset = np.linalg.lstsq(A, pos[keep] * b[keep], rcond=None)[0]
        new = np.abs(pos - (slope * tt + offset)) < 1.0
        if new.sum() < 5 or (new == keep).all():
            break
        keep = new
    t1, t2 = tt[keep].min(), tt[keep].max()
    return np.concatenate([mid + t1 * u + (slope * t1 + offset) * n, mid + t2 * u + (slope * t2 + offset) * n])


def duplicate_groups(
    segments: np.ndarray, angle_deg: float = 2.0, distance_px: float = 2.0, min_overlap: float = 0.5
) -> np.ndarray:
    """Groups of near-duplicate segments: the same edge found more than once (at several of LSD's
    scales, or as both sides of a thin line), which are one observation of the scene, not several.

    Two segments are near-duplicates when their directions are within ``angle_deg``, each one's
    midpoint is within ``distance_px`` of the other's line, and they overlap along their direction
    by at least ``min_overlap`` of the shorter; a group is a connected set of such pairs (an edge
    broken up at one scale and whole at another is one group).

    Parameters
    ----------
    segments : ndarray of shape (N, 4)
        Segments x1, y1, x2, y2, pixels.
    angle_deg : float, default=2.0
        Largest angle between near-duplicates, degrees.
    distance_px : float, default=2.0
        Largest distance of a midpoint from the other segment's line, pixels.
    min_overlap : float, default=0.5
        Least overlap along the direction, as a share of the shorter segment.

    Returns
    -------
    ndarray of shape (N,), dtype int
        The group of each segment, 0 to G - 1.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    s = np.asarray(segments, np.float64).reshape(-1, 4)
    n = len(s)
    if n == 0:
        return np.zeros(0, int)
    d = s[:, 2:] - s[:, :2]
    length = np.maximum(np.linalg.norm(d, axis=1), 1e-12)
    u = d / length[:, None]
    mid = 0.5 * (s[:, :2] + s[:, 2:])
    i, j = np.triu_indices(n, 1)
    parallel = np.abs(u[i, 0] * u[j, 1] - u[i, 1] * u[j, 0]) < np.sin(np.radians(angle_deg))
    i, j = i[parallel], j[parallel]
    dm = mid[j] - mid[i]
    near = np.maximum(np.abs(u[i, 0] * dm[:, 1] - u[i, 1] * dm[:, 0]), np.abs(u[j, 0] * dm[:, 1] - u[j, 1] * dm[:, 0]))
    i, j, dm = i[near < distance_px], j[near < distance_px], dm[near < distance_px]
    # the other segment's extent along this one's direction, about this one's midpoint
    along = (u[i] * dm).sum(axis=1)
    half = 0.5 * length[j] * np.abs((u[i] * u[j]).sum(axis=1))
    overlap = np.minimum(0.5 * length[i], along + half) - np.maximum(-0.5 * length[i], along - half)
    dup = overlap >= min_overlap * np.minimum(length[i], length[j])
    graph = coo_matrix((np.ones(int(dup.sum())), (i[dup], j[dup])), shape=(n, n))
    return connected_components(graph, directed=False)[1]


def duplicate_weights(segments: np.ndarray) -> np.ndarray:
    """Each segment's share of its group of near-duplicates (:func:`duplicate_groups`): one over the
    group's size, so that a group counts once in an uncertainty however often its edge was found.

    Parameters
    ----------
    segments : ndarray of shape (N, 4)
        Segments x1, y1, x2, y2, pixels.

    Returns
    -------
    ndarray of shape (N,), dtype float64
        Weights in (0, 1]; they sum to the number of groups.
    """
    g = duplicate_groups(segments)
    return 1.0 / np.bincount(g)[g] if len(g) else np.zeros(0)


def segment_angles(segments: np.ndarray, vp: np.ndarray) -> np.ndarray:
    """Sine of the angle between each segment and the line from its midpoint to its vanishing point.

    Parameters
    ----------
    segments : ndarray of shape (N, 4)
        Segments x1, y1, x2, y2, pixels.
    vp : ndarray of shape (3,), (N, 3) or (B, N, 3)
        Homogeneous vanishing point for all segments, or one per segment (at infinity a direction);
        or B such sets of one per segment.

    Returns
    -------
    ndarray of shape (N,) or (B, N)
        Signed sine of the angle.
    """
    d = segments[:, 2:] - segments[:, :2]
    mid = 0.5 * (segments[:, :2] + segments[:, 2:])
    vp = np.asarray(vp)
    vp = np.broadcast_to(vp, (*vp.shape[:-2], len(segments), 3))
    to = vp[..., :2] - vp[..., 2:3] * mid
    cross = d[:, 0] * to[..., 1] - d[:, 1] * to[..., 0]
    return cross / np.maximum(np.linalg.norm(d, axis=1) * np.linalg.norm(to, axis=-1), 1e-12)


def find_families(
    segments: np.ndarray,
    centre_row: float,
    max_families: int = 3,
    angle_deg: float = 1.5,
    min_segments: int = 5,
    vertical_deg: float = 25.0,
    iters: int = 400,
    seed: int = 0,
) -> LineFamilies:
    """Group segments by vanishing point (sequential RANSAC; see the module docstring).

    Parameters
    ----------
    segments : ndarray of shape (N, 4)
        Segments x1, y1, x2, y2, pixels.
    centre_row : float
        The principal point's row, pixels (the image's middle row).
    max_families : int, default=3
        Vanishing points sought at most.
    angle_deg : float, default=1.5
        Agreement of a segment with a vanishing point, degrees.
    min_segments : int, default=5
        Segments each family needs.
    vertical_deg : float, default=25.0
        A family whose length-weighted segments are within this of the image vertical (degrees) and
        whose vanishing point is below ``centre_row`` (or at infinity) is the world's vertical (at
        most one: the steepest).
    iters : int, default=400
        Pairs tried per vanishing point.
    seed : int, default=0
        Seed of their draw.

    Returns
    -------
    LineFamilies
        The segments that joined a family, their families and vanishing points.
    """
    rng = np.random.default_rng(seed)
    s = np.asarray(segments, np.float64).reshape(-1, 4)
    length = np.hypot(s[:, 2] - s[:, 0], s[:, 3] - s[:, 1])
    lines = np.cross(np.column_stack([s[:, :2], np.ones(len(s))]), np.column_stack([s[:, 2:], np.ones(len(s))]))
    family = np.full(len(s), -1)
    vps: list[np.ndarray] = []
    tol = np.sin(np.radians(angle_deg))
    for f in range(max_families):
        free = np.flatnonzero(family < 0)
        if len(free) < min_segments:
            break
        i, j = rng.choice(free, (2, iters)) if len(free) > 1 else (free, free)
        cand = np.cross(lines[i], lines[j])
        cand = cand[np.linalg.norm(cand, axis=1) > 1e-12]
        cand /= np.linalg.norm(cand, axis=1, keepdims=True)
        if not len(cand):
            break
        d = s[free, 2:] - s[free, :2]
        mid = 0.5 * (s[free, :2] + s[free, 2:])
        to = cand[:, None, :2] - cand[:, None, 2:3] * mid[None]  # (C, n, 2)
        sin = (d[None, :, 0] * to[..., 1] - d[None, :, 1] * to[..., 0]) / np.maximum(
            np.linalg.norm(d, axis=1)[None] * np.linalg.norm(to, axis=2), 1e-12
        )
        score = ((np.abs(sin) < tol) * length[free][None]).sum(axis=1)
        best = cand[int(np.argmax(score))]
        members = free[np.abs(segment_angles(s[free], best)) < tol]
        if len(members) < min_segments:
            break
        family[members] = f
        vps.append(best)
    keep = family >= 0
    n = len(vps)
    steep = np.zeros(n)
    for f in range(n):
        m = family == f
        d = s[m, 2:] - s[m, :2]
        steep[f] = np.average(np.abs(d[:, 0]) / np.maximum(np.linalg.norm(d, axis=1), 1e-12), weights=length[m])
    # the vertical: steep segments whose vanishing point is below the image centre (a camera level or
    # looking down) or at infinity; steep families converging upwards are ground lines running away
    # from the camera, whose vanishing point is on the horizon above
    vertical = np.zeros(n, bool)
    vp = np.array(vps).reshape(-1, 3)
    below = (np.abs(vp[:, 2]) < 1e-9 * np.linalg.norm(vp[:, :2], axis=1)) | (
        vp[:, 1] * np.sign(vp[:, 2]) > centre_row * np.abs(vp[:, 2])
    )
    ok = (steep < np.sin(np.radians(vertical_deg))) & below
    if ok.any():
        vertical[int(np.argmin(np.where(ok, steep, np.inf)))] = True
    return LineFamilies(s[keep], family[keep], vertical, vp)


def _frame_vps(f: np.ndarray, tilt: np.ndarray, yaw: np.ndarray, centre: tuple[float, float]) -> np.ndarray:
    """(H, 3, 3) homogeneous vanishing points of the world's X, Z and vertical directions, rotated
    by ``yaw`` about the vertical, for cameras of focal ``f`` (pixels) pitched down by ``tilt``
    (radians), no roll; one row per hypothesis.
    """
    cx, cy = centre
    st, ct = np.sin(tilt), np.cos(tilt)
    sy, cyw = np.sin(yaw), np.cos(yaw)
    # world-to-camera rotation of a camera looking along -Z, pitched down (as the estimate's)
    # applied to X = (cos yaw, 0, sin yaw), Z = (-sin yaw, 0, cos yaw), Y = (0, 1, 0)
    dirs = np.stack(
        [
            np.stack([cyw, st * sy, -ct * sy], -1),
            np.stack([-sy, st * cyw, -ct * cyw], -1),
            np.stack([np.zeros_like(tilt), -ct * np.ones_like(yaw), -st * np.ones_like(yaw)], -1),
        ],
        -2,
    )  # (H, 3, 3) camera-frame directions
    x, y, z = dirs[..., 0], dirs[..., 1], dirs[..., 2]
    f = f[..., None]
    return np.stack([f * x + cx * z, f * y + cy * z, z], -1)


def _frame_sin2(segments: np.ndarray, vps: np.ndarray) -> np.ndarray:
    """Squared sine of the angle between each segment and the direction from its midpoint to each
    vanishing point.

    The cross product and the squared distance of a segment's midpoint to a (homogeneous) point are
    both linear in a few products of the point's coordinates, so all hypotheses are two matrix
    products instead of a (H, 3, N, 2) array of directions.

    Parameters
    ----------
    segments : ndarray of shape (N, 4)
        Segments x1, y1, x2, y2, pixels.
    vps : ndarray of shape (H, 3, 3)
        Homogeneous vanishing points, three per hypothesis.

    Returns
    -------
    ndarray of shape (H, 3, N)
        sin^2 of each angle.
    """
    d = segments[:, 2:] - segments[:, :2]
    u = d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-12)  # (N, 2) unit directions
    m = 0.5 * (segments[:, :2] + segments[:, 2:])
    px, py, w = vps[..., 0], vps[..., 1], vps[..., 2]
    # u x (p - w m) = p_y u_x - p_x u_y - w (u_x m_y - u_y m_x)
    cross = np.stack([px, py, w], -1) @ np.stack([-u[:, 1], u[:, 0], -(u[:, 0] * m[:, 1] - u[:, 1] * m[:, 0])])
    # |p - w m|^2 = |p|^2 - 2 w p.m + w^2 |m|^2
    dist2 = np.stack([px * px + py * py, -2 * w * px, -2 * w * py, w * w], -1) @ np.stack(
        [np.ones(len(m)), m[:, 0], m[:, 1], (m * m).sum(axis=1)]
    )
    return cross * cross / np.maximum(dist2, 1e-24)


def _frame_score(segments: np.ndarray, vps: np.ndarray, tol: float) -> np.ndarray:
    """Score of each hypothesis: the length-weighted share of segments within ``tol`` (a sine) of one
    of its three vanishing points, with a quadratic falloff.

    Parameters
    ----------
    segments : ndarray of shape (N, 4)
        Segments x1, y1, x2, y2, pixels.
    vps : ndarray of shape (H, 3, 3)
        Homogeneous vanishing points, three per hypothesis.
    tol : float
        Sine of the largest angle that counts.

    Returns
    -------
    ndarray of shape (H,)
        The scores (pixels of segment length).
    """
    length = np.hypot(segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1])
    best2 = _frame_sin2(segments, vps).min(axis=1)  # (H, N)
    return np.clip(1.0 - best2 / (tol * tol), 0.0, None) @ length


def find_manhattan_families(
    segments: np.ndarray,
    size: tuple[int, int],
    angle_deg: float = 1.5,
    min_segments: int = 5,
    tilt_deg: tuple[float, float] = (-5.0, 50.0),
    fov_deg: tuple[float, float] = (30.0, 100.0),
) -> LineFamilies:
    """Group segments by the three vanishing points of one square frame of the scene (two
    horizontal directions at right angles and the vertical; a "Manhattan world", Coughlan & Yuille
    2003): the camera's focal length, tilt and the frame's yaw that explain the most segment
    length, searched on a coarse grid and refined on a fine one, with no roll.

    Parameters
    ----------
    segments : ndarray of shape (N, 4)
        Segments x1, y1, x2, y2, pixels.
    size : tuple of (int, int)
        (width, height) of the image, pixels (the principal point at its centre).
    angle_deg : float, default=1.5
        Agreement of a segment with a vanishing point, degrees.
    min_segments : int, default=5
        Segments each family needs.
    tilt_deg, fov_deg : tuple of (float, float)
        Ranges searched: the camera's downward pitch and horizontal field of view, degrees.

    Returns
    -------
    LineFamilies
        The families found (the vertical last), their segments and vanishing points.
    """
    s = np.asarray(segments, np.float64).reshape(-1, 4)
    W, H = int(size[0]), int(size[1])
    centre = ((W - 1) / 2.0, (H - 1) / 2.0)
    if len(s) < min_segments:
        return LineFamilies(np.zeros((0, 4)), np.zeros(0, int), np.zeros(0, bool), np.zeros((0, 3)))

    def grid(t: np.ndarray, v: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, ...]:
        T, V, Y = (a.ravel() for a in np.meshgrid(t, v, y, indexing="ij"))
        return T, (W / 2.0) / np.tan(V / 2), Y

    def best_of(T: np.ndarray, F: np.ndarray, Y: np.ndarray, tol: float) -> tuple[float, float, float]:
        scores = np.concatenate(
            [
                _frame_score(s, _frame_vps(F[i : i + 512], T[i : i + 512], Y[i : i + 512], centre), tol)
                for i in range(0, len(T), 512)
            ]
        )
        i = int(np.argmax(scores))
        return T[i], np.degrees(2 * np.arctan(W / 2.0 / F[i])), Y[i]

    r = np.radians
    t, v, y = best_of(
        *grid(
            r(np.arange(tilt_deg[0], tilt_deg[1] + 1e-9, 2.5)),
            r(np.arange(fov_deg[0], fov_deg[1] + 1e-9, 5.0)),
            r(np.arange(0.0, 90.0, 3.0)),
        ),
        np.sin(r(3 * angle_deg)),
    )
    t, v, y = best_of(
        *grid(
            np.arange(t - r(2.5), t + r(2.51), r(0.5)),
            r(np.arange(max(fov_deg[0], v - 5.0), min(fov_deg[1], v + 5.0) + 1e-9, 1.0)),
            np.arange(y - r(3.0), y + r(3.01), r(0.5)),
        ),
        np.sin(r(angle_deg)),
    )
    f = (W / 2.0) / np.tan(r(v) / 2)
    vp = _frame_vps(np.array([f]), np.array([t]), np.array([y]), centre)[0]
    sin = np.sqrt(_frame_sin2(s, vp[None])[0])  # (3, N)
    fam = np.argmin(sin, axis=0)
    ok = sin[fam, np.arange(len(s))] < np.sin(r(angle_deg))
    counts = np.bincount(fam[ok], minlength=3)
    present = np.flatnonzero(counts >= min_segments)
    ok &= np.isin(fam, present)
    remap = np.full(3, -1)
    remap[present] = np.arange(len(present))
    vp = vp[present]
    return LineFamilies(
        s[ok], remap[fam[ok]], present == 2, vp / np.linalg.norm(vp, axis=1, keepdims=True), square=True
    )


def scene_lines(image: np.ndarray, boxes: Iterable[Any] = ()) -> LineFamilies:
    """The line families of a view of the scene: its segments (:func:`detect_segments`, the
    people's boxes out, down to ``MIN_LENGTH`` pixels, pooled over ``LSD_SCALES``, each refitted
    along its whole edge by :func:`refine_segments`) grouped by the
    three vanishing points of one square frame (:func:`find_manhattan_families`); by
    :func:`find_families` instead when that frame explains under ``MANHATTAN_SHARE`` of the segment
    length the latter groups (a scene that is not laid out square).

    Parameters
    ----------
    image : ndarray of shape (H, W, 3) or (H, W), dtype uint8
        BGR or grey image (the median of a few frames: people who move are gone from it).
    boxes : iterable of (x, y, w, h), default=()
        The people's boxes, pixels.

    Returns
    -------
    LineFamilies
        The families.
    """
    H, W = image.shape[:2]
    segments = refine_segments(image, detect_segments(image, boxes, min_length=MIN_LENGTH, scale=LSD_SCALES))
    segments = segments[np.hypot(*(segments[:, 2:] - segments[:, :2]).T) >= MIN_LENGTH]
    square = find_manhattan_families(segments, (W, H))
    free = find_families(segments, (H - 1) / 2.0)
    return square if _grouped_length(square) >= MANHATTAN_SHARE * _grouped_length(free) else free


def _grouped_length(lines: LineFamilies) -> float:
    return float(np.hypot(*(lines.segments[:, 2:] - lines.segments[:, :2]).T).sum()) if len(lines.segments) else 0.0


__all__ = [
    "LineFamilies",
    "RefineConfig",
    "detect_segments",
    "duplicate_groups",
    "duplicate_weights",
    "find_families",
    "find_manhattan_families",
    "refine_segments",
    "scene_lines",
    "segment_angles",
]
