"""Silhouette boundaries as closed uniform cubic B-splines (Baumberg & Hogg; Johnson et al. 1998).

Shared by the silhouette node (which fits them), the responder (joint shapes) and the renderer
(which fills them), so it lives with the body model rather than in one node.

Curve convention. With n control points P_0..P_{n-1} (indices mod n) the curve parameter u runs
over [0, n); on span i (u in [i, i+1), t = u - i)

    C(u) = B0(t) P_{i-1} + B1(t) P_i + B2(t) P_{i+1} + B3(t) P_{i+2},
    B0 = (1-t)^3/6, B1 = (3t^3 - 6t^2 + 4)/6, B2 = (-3t^3 + 3t^2 + 3t + 1)/6, B3 = t^3/6,

so C(i) = (P_{i-1} + 4 P_i + P_{i+1}) / 6 lies next to P_i: control point k belongs to the curve
point at u = k. A boundary is fitted by linear least squares to M points resampled at equal arc
length, point j at u_j = j n / M, so the control points are evenly spaced along the outline.

Ordering (Baumberg & Hogg). Point 0 is the reference point at the top of the head: where the
silhouette's principal axis (the vertical axis, when the principal axis is closer to horizontal
or undefined) leaves the boundary at its upper end, then moved to the highest boundary point
within a small arc-length window around it. From there the boundary is traversed
counter-clockwise as seen on screen (image x right, y down): from the top of the head towards
image-left, down that side, along the bottom and up the image-right side. Image coordinates
are pixels, x = column, y = row.
"""

from __future__ import annotations

import math
from functools import lru_cache

import cv2
import numpy as np

# Resampled boundary points per control point for the least-squares fit.
SAMPLES_PER_CTRL = 8


def _basis(t: np.ndarray) -> np.ndarray:
    """Uniform cubic B-spline basis, (len(t), 4) for B0..B3."""
    t2, t3 = t * t, t * t * t
    return np.stack(
        [(1 - t) ** 3 / 6.0, (3 * t3 - 6 * t2 + 4) / 6.0, (-3 * t3 + 3 * t2 + 3 * t + 1) / 6.0, t3 / 6.0],
        axis=1,
    )


@lru_cache(maxsize=64)
def design_matrix(m: int, n: int) -> np.ndarray:
    """The read-only matrix A with C(u_j) = A[j] @ P for u_j = j n / m, j = 0..m-1. Cached.

    Parameters
    ----------
    m : int
        Curve samples (>= 1).
    n : int
        Control points (>= 4).

    Returns
    -------
    ndarray of shape (m, n)
        The design matrix (read-only).

    Raises
    ------
    ValueError
        If n < 4 or m < 1.
    """
    if n < 4:
        raise ValueError(f"a closed cubic B-spline needs n >= 4 control points, got n={n}")
    if m < 1:
        raise ValueError(f"number of curve samples must be >= 1, got {m}")
    u = np.arange(m) * (n / m)
    span = np.floor(u).astype(np.int64)
    basis = _basis(u - span)
    a = np.zeros((m, n))
    rows = np.arange(m)
    for k in range(4):
        a[rows, (span - 1 + k) % n] += basis[:, k]
    a.setflags(write=False)
    return a


@lru_cache(maxsize=64)
def _fit_operator(m: int, n: int) -> np.ndarray:
    """(n, m) least-squares solution operator pinv(A) for design_matrix(m, n). Cached."""
    if m < n:
        raise ValueError(f"need at least n={n} boundary samples to fit n control points, got {m}")
    op = np.linalg.pinv(design_matrix(m, n))
    op.setflags(write=False)
    return op


def resample_closed(points: np.ndarray, m: int) -> np.ndarray:
    """Resample a closed polyline at m points of equal arc length, starting at points[0].

    Parameters
    ----------
    points : ndarray of shape (K, 2)
        The closed polyline, pixels.
    m : int
        Points to return.

    Returns
    -------
    ndarray of shape (m, 2), dtype float64
        The resampled points, pixels.

    Raises
    ------
    ValueError
        If the boundary has zero length (all points coincide).
    """
    p = np.asarray(points, np.float64).reshape(-1, 2)
    # x and y as rows of one (2, K + 1) array, the first point again at the end
    closed = np.empty((2, len(p) + 1))
    closed[:, :-1] = p.T
    closed[:, -1] = p[0]
    step = np.diff(closed, axis=1)
    seg = np.hypot(step[0], step[1])
    cum = np.empty(len(p) + 1)
    cum[0] = 0.0
    np.cumsum(seg, out=cum[1:])
    keep = seg > 1e-12
    if not keep.all():  # drop repeated points: interp needs increasing s
        keep = np.concatenate([[True], keep])
        cum, closed = cum[keep], closed[:, keep]
    total = cum[-1]
    if total <= 0.0:
        raise ValueError("boundary has zero length: all points coincide")
    s = np.arange(m) * (total / m)
    out = np.empty((m, 2))
    out[:, 0] = np.interp(s, cum, closed[0])
    out[:, 1] = np.interp(s, cum, closed[1])
    return out


def fit_closed_bspline(points: np.ndarray, n: int = 32, resample: bool = True) -> np.ndarray:
    """Least-squares closed uniform cubic B-spline through an ordered closed boundary.

    Parameters
    ----------
    points : ndarray of shape (M, 2)
        Boundary, pixels, in traversal order (M >= 3); the curve starts (u = 0) at points[0].
    n : int
        Number of control points (>= 4).
    resample : bool
        Resample the boundary at ``SAMPLES_PER_CTRL * n`` points of equal arc length first (evenly
        spaced control points); False uses the given points as equally spaced samples.

    Returns
    -------
    ndarray of shape (n, 2), dtype float64
        Control points, pixels.

    Raises
    ------
    ValueError
        If ``points`` is not (M, 2) with M >= 3, n < 4, or fewer than n samples are given unresampled.
    """
    p = np.asarray(points, np.float64)
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 3:
        raise ValueError(f"points must be (M, 2) with M >= 3, got shape {p.shape}")
    if n < 4:
        raise ValueError(f"a closed cubic B-spline needs n >= 4 control points, got n={n}")
    if resample:
        p = resample_closed(p, SAMPLES_PER_CTRL * n)
    return _fit_operator(len(p), n) @ p


def evaluate_closed_bspline(ctrl: np.ndarray, samples_per_span: int = 8) -> np.ndarray:
    """Points on the curve at u = j / samples_per_span, j = 0..n*samples_per_span-1.

    Parameters
    ----------
    ctrl : ndarray of shape (n, 2)
        Control points (n >= 4), pixels.
    samples_per_span : int
        Curve points per span (>= 1).

    Returns
    -------
    ndarray of shape (n * samples_per_span, 2), dtype float64
        The curve points, pixels.

    Raises
    ------
    ValueError
        If ``ctrl`` is not (n, 2) with n >= 4 or ``samples_per_span`` < 1.
    """
    c = np.asarray(ctrl, np.float64)
    if c.ndim != 2 or c.shape[1] != 2 or len(c) < 4:
        raise ValueError(f"ctrl must be (n, 2) with n >= 4, got shape {c.shape}")
    if samples_per_span < 1:
        raise ValueError(f"samples_per_span must be >= 1, got {samples_per_span}")
    return design_matrix(len(c) * samples_per_span, len(c)) @ c


def spline_distance(contour: np.ndarray, ctrl: np.ndarray, samples_per_span: int = 16) -> float:
    """Mean distance from each contour point to the closed spline curve.

    The curve is evaluated densely and treated as a closed polyline; distances are exact
    point-to-segment distances.

    Parameters
    ----------
    contour : ndarray of shape (M, 2)
        Contour points, pixels.
    ctrl : ndarray of shape (n, 2)
        Control points, pixels.
    samples_per_span : int
        Curve points per span of the dense evaluation.

    Returns
    -------
    float
        The mean distance, pixels.
    """
    p = np.asarray(contour, np.float64).reshape(-1, 2)
    a = evaluate_closed_bspline(ctrl, samples_per_span)
    ab = np.roll(a, -1, axis=0) - a
    ab2 = np.maximum((ab * ab).sum(axis=1), 1e-12)
    best = np.empty(len(p))
    step = max(1, 2_000_000 // (4 * len(a)))
    for s in range(0, len(p), step):
        ap = p[s : s + step, None, :] - a[None]
        t = np.clip((ap * ab[None]).sum(axis=2) / ab2, 0.0, 1.0)
        d = ap - t[..., None] * ab[None]
        best[s : s + step] = np.sqrt((d * d).sum(axis=2).min(axis=1))
    return float(best.mean())


def _signed_area2(p: np.ndarray) -> float:
    """Twice the shoelace area in image coordinates; negative = counter-clockwise on screen."""
    x, y = p[:, 0], p[:, 1]
    return float(np.dot(x[:-1], y[1:]) + x[-1] * y[0] - np.dot(x[1:], y[:-1]) - x[0] * y[-1])


def _up_axis(mask_u8: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centroid (2,) and unit upward axis (2,) of a binary mask (principal axis or vertical)."""
    mo = cv2.moments(mask_u8, binaryImage=True)
    m00 = mo["m00"]
    c = np.array([mo["m10"] / m00, mo["m01"] / m00])
    # The covariance [[a, b], [b, d]]'s eigenvalues mid -/+ r and the major one's eigenvector in
    # closed form (np.linalg.eigh costs ~25 us a call, a tenth of a spline's fit). Of the two
    # forms of that eigenvector, (r + half, b) and (b, r - half), the one whose first term adds
    # two values of one sign is taken: no cancellation.
    a, b, d = mo["mu20"] / m00, mo["mu11"] / m00, mo["mu02"] / m00
    half = 0.5 * (a - d)
    r = math.hypot(half, b)
    mid = 0.5 * (a + d)
    vx, vy = (r + half, b) if half >= 0.0 else (b, r - half)
    norm = math.hypot(vx, vy)
    # Near-isotropic blobs have no principal axis; near-horizontal ones would put the
    # "top" on a side: both fall back to the vertical axis.
    if mid + r < 1.1 * (mid - r) or norm == 0.0 or abs(vy) < math.sqrt(0.5) * norm:
        return c, np.array([0.0, -1.0])
    vx, vy = vx / norm, vy / norm
    return c, (np.array([vx, vy]) if vy < 0 else np.array([-vx, -vy]))


def boundary_and_axis(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The first half of :func:`oriented_boundary`: the outer boundary of the mask's largest
    region, counter-clockwise on screen but not yet started at the reference point, with the
    region's centroid, its upward axis and each boundary point's distance along that axis.

    Parameters
    ----------
    mask : ndarray of shape (H, W)
        Bool or 0/non-zero.

    Returns
    -------
    contour : ndarray of shape (K, 2), dtype float64
        The boundary, pixels (x, y), K >= 3.
    centroid : ndarray of shape (2,), dtype float64
        The region's centroid, pixels.
    up : ndarray of shape (2,), dtype float64
        Unit upward axis (principal axis or vertical, see :func:`_up_axis`).
    along : ndarray of shape (K,), dtype float64
        (contour - centroid) @ up, pixels.

    Raises
    ------
    ValueError
        As :func:`oriented_boundary`.
    """
    m = np.asarray(mask)
    if m.ndim != 2:
        raise ValueError(f"mask must be 2-D (H, W), got shape {m.shape}")
    # findContours reads any non-zero byte as set (and leaves its input as it is): a bool or
    # uint8 mask goes in as its own bytes, without a pass over it
    if m.dtype == np.uint8 or m.dtype == bool:
        m8 = np.ascontiguousarray(m).view(np.uint8)
    else:
        m8 = (m != 0).astype(np.uint8)
    contours, _ = cv2.findContours(m8, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        raise ValueError("mask is empty: no silhouette to fit")
    best = contours[0] if len(contours) == 1 else max(contours, key=cv2.contourArea)
    p = best.reshape(-1, 2).astype(np.float64)
    if len(p) < 3:
        raise ValueError(f"silhouette too small for a boundary ({len(p)} boundary pixels)")
    if _signed_area2(p) > 0:
        p = p[::-1]
    region = np.zeros_like(m8)
    cv2.drawContours(region, [best], 0, 1, thickness=cv2.FILLED)
    c, up = _up_axis(region)
    along = (p - c) @ up
    return p, c, up, along


def oriented_boundary(mask: np.ndarray, ref_window: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    """Outer boundary of the largest region of a mask, ordered as described in the module doc.

    Parameters
    ----------
    mask : ndarray of shape (H, W)
        Bool or 0/non-zero.
    ref_window : float
        Half-width of the search for the locally highest point, as a fraction of the boundary length.

    Returns
    -------
    contour : ndarray of shape (K, 2), dtype float64
        The boundary, pixels, starting at the reference point.
    ref_point : ndarray of shape (2,), dtype float64
        The reference point at the top of the head, pixels.

    Raises
    ------
    ValueError
        If the mask is not 2-D, is empty, or its region is too small for a boundary.
    """
    p, c, up, along = boundary_and_axis(mask)
    rel = p - c
    perp = np.abs(rel[:, 0] * up[1] - rel[:, 1] * up[0])
    near = (perp <= 1.0) & (along > 0)
    if near.any():
        idx = np.flatnonzero(near)
        # Outermost crossing (top of the head, not a shoulder); ties go to the nearest the axis.
        i0 = int(idx[np.lexsort((perp[idx], -np.round(along[idx], 6)))[0]])
    else:
        i0 = int(np.argmin(np.where(along > 0, perp, np.inf)))
    k = len(p)
    w = max(2, int(round(ref_window * k)))
    offsets = np.arange(-w, w + 1)
    ys = p[(i0 + offsets) % k, 1]
    top = ys == ys.min()
    best_off = offsets[top][np.argmin(np.abs(offsets[top]))]
    start = (i0 + int(best_off)) % k
    p = np.concatenate((p[start:], p[:start]))
    return p, p[0].copy()


def silhouette_spline(mask: np.ndarray, n: int = 32, ref_window: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
    """Closed B-spline of a silhouette's outer boundary.

    ctrl[0] belongs to the reference point at the top of the head; the order is counter-clockwise
    on screen (see module doc).

    Parameters
    ----------
    mask : ndarray of shape (H, W)
        Bool or 0/non-zero.
    n : int
        Number of control points (>= 4).
    ref_window : float
        Half-width of the search for the reference point, as a fraction of the boundary length.

    Returns
    -------
    ctrl : ndarray of shape (n, 2), dtype float64
        Control points, pixels.
    ref_point : ndarray of shape (2,), dtype float64
        The reference point, pixels.

    Raises
    ------
    ValueError
        For an empty mask (see :func:`oriented_boundary`).
    """
    contour, ref = oriented_boundary(mask, ref_window)
    return fit_closed_bspline(contour, n), ref


def shape_vector(ctrl: np.ndarray, height: float, pos: np.ndarray) -> np.ndarray:
    """Actor-centred, height-normalised control points.

    Parameters
    ----------
    ctrl : ndarray of shape (n, 2)
        Control points, pixels.
    height : float
        The person's height, pixels (> 0).
    pos : ndarray of shape (2,)
        The person's image position, pixels.

    Returns
    -------
    ndarray of shape (2n,)
        [x0, y0, x1, y1, ...] of (ctrl - pos) / height.

    Raises
    ------
    ValueError
        If ``ctrl`` is not (n, 2) or ``height`` is not > 0.
    """
    c = np.asarray(ctrl, np.float64)
    if c.ndim != 2 or c.shape[1] != 2:
        raise ValueError(f"ctrl must be (n, 2), got shape {c.shape}")
    if not height > 0:
        raise ValueError(f"height must be > 0 pixels, got {height}")
    return ((c - np.asarray(pos, np.float64).reshape(1, 2)) / height).ravel()


def combined_shape_vector(
    ctrl_a: np.ndarray,
    height_a: float,
    pos_a: np.ndarray,
    ctrl_b: np.ndarray,
    height_b: float,
    pos_b: np.ndarray,
) -> np.ndarray:
    """Joint shape of two interacting people (Johnson, Galata & Hogg 1998), (4n + 3,) float64.

    Layout, with h_m = (height_a + height_b) / 2:
      [0, 2n)       shape_vector(ctrl_a, height_a, pos_a)  (x0, y0, x1, y1, ... of person a)
      [2n, 4n)      shape_vector(ctrl_b, height_b, pos_b)
      [4n, 4n + 2)  (pos_b - pos_a) / h_m                  relative separation
      4n + 2        log(height_b / height_a)               relative scale
    The vector is unchanged by a common image translation and scaling.

    Parameters
    ----------
    ctrl_a, ctrl_b : ndarray of shape (n, 2)
        Control points of person a and b, pixels.
    height_a, height_b : float
        Their heights, pixels.
    pos_a, pos_b : ndarray of shape (2,)
        Their image positions, pixels (the pipeline uses the region centroid).

    Returns
    -------
    ndarray of shape (4n + 3,), dtype float64
        The joint shape vector (layout above).

    Raises
    ------
    ValueError
        If the control points' shapes differ (or see :func:`shape_vector`).
    """
    ca, cb = np.asarray(ctrl_a), np.asarray(ctrl_b)
    if ca.shape != cb.shape:
        raise ValueError(f"ctrl_a and ctrl_b must have the same shape (n, 2), got {ca.shape} and {cb.shape}")
    va = shape_vector(ca, height_a, pos_a)
    vb = shape_vector(cb, height_b, pos_b)
    sep = (np.asarray(pos_b, np.float64) - np.asarray(pos_a, np.float64)).reshape(2) / (0.5 * (height_a + height_b))
    return np.concatenate([va, vb, sep, [np.log(height_b / height_a)]])
