"""Camera shake: the shift of a frame against the background model, so that a camera on a pole in
the wind, a tripod on a wooden floor or a hand-held phone can still be compared pixel by pixel with
the room it has learnt.

A background model compares each pixel with the same pixel of the room; a shift of one or two
pixels turns every edge of the room into foreground. Here the frame's shift against the model's
mean image is estimated as a translation (the dominant part of shake over a frame interval;
Zitova & Flusser 2003, "Image registration methods: a survey", for the two steps used), on a few
thousand points of the room (:class:`_Reference`: in each cell of a grid, the pixels of the
strongest horizontal and vertical gradients), the pixels where people were on the last frame
left out (they do not move with the room, and on a plain floor they hold most of the texture):

1. starts: the last frame's shift, and the peak of the phase correlation (Kuglin & Hines 1975;
   ``cv2.phaseCorrelate``, Hann-windowed, at a quarter of the resolution) for a jolt;
2. from each, Gauss-Newton refinement of the translation t minimising
   ``sum_x w(r_x) r_x^2 + |t|^2 / s_t^2, r_x = F(x + t) - R(x) - o`` (Lucas & Kanade 1981, their
   translation case, with the reference's gradient: Baker & Matthews 2004's inverse compositional
   form), on the images blurred by 3 then 1 pixels, with Tukey's biweight w of the residual
   scaled by its median absolute deviation (iteratively reweighted least squares), an offset o
   for a change of exposure, and a Gaussian prior of std s_t on the shift (a shaken camera stays
   about one place);
3. the shift stands only where it fits the room's points clearly better than no shift
   (``ShakeConfig.support``): a still camera's frames are never moved, whatever the people do.

The frame is then resampled onto the model's pixels (:func:`align`), classified there, and the
labels moved back onto the frame's pixels (:func:`unalign_labels`), so that every consumer of the
silhouettes keeps the frame's own coordinates.

Images are float32 grey (H, W), pixels (x = column, y = row). A shift t = (tx, ty) says that the
room point at model pixel x is at frame pixel x + t.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

__all__ = ["ShakeConfig", "ShakeEstimator", "estimate_shift", "align", "align_stack", "unalign_labels", "grey"]


@dataclass(frozen=True)
class ShakeConfig:
    """How the shift is estimated.

    Parameters
    ----------
    max_shift : float, default=0.06
        Largest shift followed, as a share of the frame's width (19 pixels at 320 wide): a larger
        one is a camera that was moved, not shaken, and the frame is left as it is.
    min_shift_px : float, default=0.5
        Shifts shorter than this (pixels) are taken as none: the frame is classified as it is
        (resampling blurs a frame a little, which costs more than so small a shift).
    iterations : int, default=6
        Gauss-Newton steps of the refinement at each blur.
    tolerance_px : float, default=0.02
        The refinement stops once a step is shorter than this, pixels.
    sigmas : tuple of float, default=(3.0, 1.0)
        Gaussian blurs (pixels) the refinement runs at in turn: the wide one converges from
        several pixels off, the last one is the finest.
    points : int, default=3000
        Pixels of the room the refinement compares (those of the strongest gradients).
    refresh : int, default=100
        Frames between two readings of the reference (the model's mean changes slowly).
    grow_px : int, default=8
        The pixels left out of a shift (``ignore``) are grown by this many pixels first: how far
        a person moves between two frames.
    prior : float, default=0.015
        Std of a zero-mean Gaussian prior on the shift, as a share of the frame's width (5 pixels
        at 320 wide): a shaken camera stays about one place, and along a direction in which the
        room shows no texture (a plain floor with one line across it) the shift stays near it
        instead of drifting with the people.
    tukey_c : float, default=4.685
        Tukey's biweight constant, in robust standard deviations (1.4826 MAD) of the residuals:
        95% efficiency under Gaussian noise.
    min_inliers : float, default=0.3
        Share of the pixels that must keep a weight for the estimate to stand: below it the
        room is mostly hidden or has changed, and the frame is left as it is.
    support : float, default=0.5
        A shift stands only where it leaves the room's points at most this share of their median
        absolute residual without a shift; otherwise the frame is taken as not shifted.
    """

    max_shift: float = 0.06
    min_shift_px: float = 0.5
    iterations: int = 6
    tolerance_px: float = 0.02
    sigmas: tuple[float, ...] = (3.0, 1.0)
    points: int = 3000
    refresh: int = 100
    grow_px: int = 8
    prior: float = 0.015
    tukey_c: float = 4.685
    min_inliers: float = 0.3
    support: float = 0.5

    def __post_init__(self) -> None:
        if not 0.0 < self.max_shift < 0.5:
            raise ValueError(f"max_shift must be a share of the width in (0, 0.5), got {self.max_shift}")
        if self.min_shift_px < 0.0:
            raise ValueError(f"min_shift_px must be >= 0 pixels, got {self.min_shift_px}")
        if not self.sigmas or min(self.sigmas) <= 0.0:
            raise ValueError(f"sigmas must be blurs > 0 pixels, got {self.sigmas}")
        if self.points < 20:
            raise ValueError(f"points must be >= 20, got {self.points}")
        if self.refresh < 1:
            raise ValueError(f"refresh must be >= 1 frame, got {self.refresh}")
        if self.grow_px < 0:
            raise ValueError(f"grow_px must be >= 0 pixels, got {self.grow_px}")
        if self.tolerance_px <= 0.0:
            raise ValueError(f"tolerance_px must be > 0 pixels, got {self.tolerance_px}")
        if self.iterations < 0:
            raise ValueError(f"iterations must be >= 0, got {self.iterations}")
        if self.prior <= 0.0:
            raise ValueError(f"prior must be a share of the width > 0, got {self.prior}")
        if self.tukey_c <= 0.0:
            raise ValueError(f"tukey_c must be > 0, got {self.tukey_c}")
        if not 0.0 < self.support <= 1.0:
            raise ValueError(f"support must be a share in (0, 1], got {self.support}")
        if not 0.0 <= self.min_inliers < 1.0:
            raise ValueError(f"min_inliers must be a share in [0, 1), got {self.min_inliers}")


def grey(frame: np.ndarray) -> np.ndarray:
    """(H, W) float32 grey levels of a uint8 BGR frame (H, W, 3) or of a float (H, W, 3) mean image."""
    if frame.dtype == np.uint8:
        return cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY).astype(np.float32)
    return cv2.cvtColor(np.ascontiguousarray(frame, np.float32), cv2.COLOR_BGR2GRAY)


def _translate(image: np.ndarray, t: np.ndarray, interpolation: int, border: int, value: float = 0.0) -> np.ndarray:
    """``out(x) = image(x + t)``, the same shape."""
    m = np.float32([[1.0, 0.0, t[0]], [0.0, 1.0, t[1]]])
    h, w = image.shape[:2]
    flags = interpolation | cv2.WARP_INVERSE_MAP
    return cv2.warpAffine(image, m, (w, h), flags=flags, borderMode=border, borderValue=value)


#: cells of the grid the points are spread over (across, down)
_GRID = (8, 6)
#: the fewest points a shift is told from
_MIN_POINTS = 100
#: frames with a shorter side have too few pixels for a shift to be told (and for the reference's grid)
_MIN_SIDE = 32
#: a frame whose room fits the last shift with a residual at most this many times the usual one
#: keeps that shift without a search (:class:`ShakeEstimator`), and the usual residual's rate
_QUIET = 1.3
_USUAL_RATE = 0.05
#: the phase correlation's start (a jolt) replaces the last frame's only when it leaves the room's
#: points this much closer to the reference (median absolute residual): people who are not left
#: out make a peak of their own
_JOLT_MARGIN = 0.8
#: a training frame's pixel this far from the frames' median (grey levels) moved: left out of its
#: shift (:func:`align_stack`)
_MOVED_GREY = 25.0


def _sample(image: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """(N,) bilinear values of ``image`` at the N points ``xy`` (N, 2) float32 (edges repeated)."""
    out = cv2.remap(image, xy[None, :, 0], xy[None, :, 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return out.reshape(-1)


@dataclass(frozen=True)
class _Level:
    """The reference as one stage of the refinement sees it: blurred by ``sigma``, its grey values
    and gradients at the candidate points.
    """

    sigma: float
    values: np.ndarray  # (M,) float32
    grad: np.ndarray  # (M, 2) float32


class _Reference:
    """What the refinement needs of one reference image, computed once for many frames.

    The candidate points are, in each cell of a grid, the pixels of the strongest horizontal and of
    the strongest vertical gradient (half each), so that one long edge does not leave the shift
    along it unknown and one object does not decide it.
    """

    def __init__(self, reference: np.ndarray, cfg: ShakeConfig) -> None:
        h, w = reference.shape
        self.shape = (h, w)
        base = cv2.GaussianBlur(reference, (0, 0), cfg.sigmas[-1])
        gx = cv2.Sobel(base, cv2.CV_32F, 1, 0, ksize=3, scale=0.125)
        gy = cv2.Sobel(base, cv2.CV_32F, 0, 1, ksize=3, scale=0.125)
        # a grid of cells, each giving its share of the points: one textured object (a striped
        # shirt in the model) must not hold them all
        cells_x, cells_y = _GRID
        per = max(1, cfg.points // (cells_x * cells_y * 2))
        picks = []
        xs = np.linspace(2, w - 2, cells_x + 1).astype(int)
        ys = np.linspace(2, h - 2, cells_y + 1).astype(int)
        for g in (np.abs(gx), np.abs(gy)):
            for y0, y1 in zip(ys[:-1], ys[1:]):
                for x0, x1 in zip(xs[:-1], xs[1:]):
                    cell = g[y0:y1, x0:x1].reshape(-1)
                    k = min(per, cell.size - 1)
                    if k < 1:
                        continue
                    best = np.argpartition(-cell, k)[:k]
                    cw = x1 - x0
                    picks.append(np.stack([best % cw + x0, best // cw + y0, cell[best]], 1))
        cand = np.concatenate(picks)
        cand = cand[np.argsort(-cand[:, 2], kind="stable")]  # strongest first: ``points`` may cut the list
        idx = cand[:, 1].astype(np.int64) * w + cand[:, 0].astype(np.int64)
        _, first = np.unique(idx, return_index=True)
        idx = idx[np.sort(first)]
        self.points = np.stack([idx % w, idx // w], 1).astype(np.float32)
        self.levels = []
        for sigma in cfg.sigmas:
            img = cv2.GaussianBlur(reference, (0, 0), sigma)
            gx = cv2.Sobel(img, cv2.CV_32F, 1, 0, ksize=3, scale=0.125)
            gy = cv2.Sobel(img, cv2.CV_32F, 0, 1, ksize=3, scale=0.125)
            yy, xx = idx // w, idx % w
            self.levels.append(_Level(sigma, img[yy, xx], np.stack([gx[yy, xx], gy[yy, xx]], 1)))
        self.small = cv2.pyrDown(cv2.pyrDown(reference))
        self.window = cv2.createHanningWindow((self.small.shape[1], self.small.shape[0]), cv2.CV_32F)
        self._corners: dict[int, np.ndarray] = {}

    def box_corners(self, grow: int) -> np.ndarray:
        """(4, M) flat indices, in an (H + 1, W + 1) integral image, of the corners (y0 x0, y0 x1,
        y1 x0, y1 x1) of the square of half-side ``grow`` pixels about each candidate point.
        """
        if grow not in self._corners:
            h, w = self.shape
            px = self.points.astype(np.intp)
            x0, x1 = np.clip(px[:, 0] - grow, 0, w), np.clip(px[:, 0] + grow + 1, 0, w)
            y0, y1 = np.clip(px[:, 1] - grow, 0, h), np.clip(px[:, 1] + grow + 1, 0, h)
            self._corners[grow] = np.stack([y0 * (w + 1) + x0, y0 * (w + 1) + x1, y1 * (w + 1) + x0, y1 * (w + 1) + x1])
        return self._corners[grow]


def _gauss_newton(
    frame: np.ndarray,
    points: np.ndarray,
    values: np.ndarray,
    grad: np.ndarray,
    t: np.ndarray,
    prior_px: float,
    cfg: ShakeConfig,
) -> tuple[np.ndarray, float, float]:
    """Robust Gauss-Newton steps (module docstring, step 2) on the points, the reference's gradient
    standing in for the frame's (inverse compositional: for a translation they agree at the
    solution), with a zero-mean Gaussian prior of std ``prior_px`` on the shift.

    Returns the shift, the share of the points that keep a weight and the median absolute
    residual (grey levels) at the last step.
    """
    gx, gy = grad[:, 0], grad[:, 1]
    prior = 1.0 / prior_px**2
    r = _sample(frame, points + t.astype(np.float32)) - values
    # a change of exposure moves every grey level alike: an offset, robust at the first step and
    # the weighted mean after; the residuals' scale is fixed at the first step (IRLS)
    offset = float(np.median(r))
    mad = float(np.median(np.abs(r - offset)))
    cut = cfg.tukey_c * (1.4826 * mad + 1e-3)
    inliers = 0.0
    for _ in range(cfg.iterations):
        r -= offset
        u = r / cut
        wgt = np.clip(1.0 - u * u, 0.0, None) ** 2
        inliers = float(np.count_nonzero(wgt)) / max(len(wgt), 1)
        wgt *= 1.0 / (cut * cut)
        wx, wy = wgt * gx, wgt * gy
        a = np.array([[wx @ gx + prior, wx @ gy], [wx @ gy, wy @ gy + prior]], np.float64)
        b = -np.array([wx @ r, wy @ r], np.float64) - prior * t
        step = np.linalg.solve(a, b)
        t = t + step
        r = _sample(frame, points + t.astype(np.float32)) - values
        total = float(wgt.sum())
        offset = float(wgt @ r) / total if total > 0 else offset
        if np.abs(step).max() < cfg.tolerance_px:
            break
    return t, inliers, float(np.median(np.abs(r - offset)))


def estimate_shift(
    reference: np.ndarray | _Reference,
    frame: np.ndarray,
    start: np.ndarray | None = None,
    ignore: np.ndarray | None = None,
    config: ShakeConfig | None = None,
) -> np.ndarray | None:
    """The frame's shift against the reference (module docstring: phase correlation, then robust
    Gauss-Newton refinement, on blurred images first).

    Two starts are refined, the last frame's shift (shake is slow against the frame rate) and the
    phase correlation's peak (a jolt); the jolt is kept where it leaves the room's pixels clearly
    closer to the reference.

    Parameters
    ----------
    reference : ndarray of shape (H, W), dtype float32
        The background's grey image (:func:`grey` of the model's mean).
    frame : ndarray of shape (H, W), dtype float32
        The frame's grey image.
    start : ndarray of shape (2,) or None, default=None
        The last frame's shift, pixels; None: no shift.
    ignore : ndarray of shape (H, W), dtype bool, or None, default=None
        Reference pixels left out, with those within ``grow_px`` of them (where people were on
        the last frame: they do not move with the room, and on a plain floor they would hold
        most of the texture).
    config : ShakeConfig or None, default=None
        Estimation settings; None: ``ShakeConfig()``.

    Returns
    -------
    ndarray of shape (2,) or None
        float64 (tx, ty), pixels: the room point at reference pixel x is at frame pixel x + t;
        zero where no shift fits the room clearly better than none (``support``); None when no
        shift can be told (one beyond ``max_shift``, too little of the room in view or agreeing).

    Raises
    ------
    ValueError
        If the images (and ``ignore``) differ in shape.
    """
    cfg = config or ShakeConfig()
    ref = reference if isinstance(reference, _Reference) else _Reference(reference, cfg)
    if ref.shape != frame.shape or (ignore is not None and ignore.shape != frame.shape):
        raise ValueError(f"reference {ref.shape}, frame {frame.shape} and ignore must have one shape")
    found = _estimate(ref, frame, start, ignore, cfg, None)
    return None if found is None else found[0]


def _clear_of(mask: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """(N,) bool: the points with no pixel of ``mask`` (H, W) in their box, from its integral image
    (the points alone are looked at, not a grown mask); ``corners`` (4, N) are the flat indices of
    each box's corners in that image (:meth:`_Reference.box_corners`).
    """
    ii = cv2.integral(mask.view(np.uint8)).reshape(-1)
    return (ii[corners[3]] - ii[corners[2]] - ii[corners[1]] + ii[corners[0]]) == 0


def _mad(r: np.ndarray) -> float:
    """Median absolute deviation of residuals from their median."""
    return float(np.median(np.abs(r - np.median(r))))


def _estimate(
    ref: _Reference,
    frame: np.ndarray,
    start: np.ndarray | None,
    ignore: np.ndarray | None,
    cfg: ShakeConfig,
    quiet: float | None,
) -> tuple[np.ndarray, float] | None:
    """:func:`estimate_shift`, with the median absolute residual of the room's points at the shift;
    where that residual at ``start`` is at most ``quiet`` (grey levels), ``start`` at once (the
    camera has not moved since: the common case, with no search).
    """
    h, w = frame.shape
    if min(h, w) < _MIN_SIDE:
        return None
    t0 = np.zeros(2) if start is None else np.asarray(start, np.float64)
    points = ref.points
    keep: np.ndarray | slice = slice(None)
    people = ignore is not None and ignore.any()
    if people:
        keep = _clear_of(ignore, ref.box_corners(cfg.grow_px))
        points = points[keep]
    points = points[: cfg.points]
    n = len(points)
    if n < _MIN_POINTS:  # people close to the camera hide the room: no shift to tell
        return None
    finest = cv2.GaussianBlur(frame, (0, 0), ref.levels[-1].sigma)
    finest_values = ref.levels[-1].values[keep][:n]
    if quiet is not None:
        mad = _mad(_sample(finest, points + t0.astype(np.float32)) - finest_values)
        if mad <= quiet:
            return t0, mad
    # the search's own inputs, only where there is a search (most frames take the quiet path)
    values = [lv.values[keep][:n] for lv in ref.levels[:-1]] + [finest_values]
    grads = [lv.grad[keep][:n] for lv in ref.levels]
    small = cv2.pyrDown(cv2.pyrDown(frame))
    if people:
        # the people replaced by the room as the last shift puts it: their motion makes no peak
        grow = 2 * (cfg.grow_px // 4) + 1
        small_ignore = cv2.dilate(
            cv2.resize(ignore.view(np.uint8), small.shape[::-1], interpolation=cv2.INTER_AREA),
            np.ones((grow, grow), np.uint8),
        )
        moved = _translate(ref.small, -t0 / 4.0, cv2.INTER_LINEAR, cv2.BORDER_REPLICATE)
        small = np.where(small_ignore > 0, moved, small)
    (sx, sy), _ = cv2.phaseCorrelate(ref.small, small.astype(np.float32), ref.window)
    blurred = [cv2.GaussianBlur(frame, (0, 0), lv.sigma) for lv in ref.levels[:-1]] + [finest]
    limit = cfg.max_shift * w
    best = None
    for s, margin in ((t0, 1.0), (4.0 * np.array([sx, sy]), _JOLT_MARGIN)):
        if np.abs(s).max() > limit or (best is not None and np.abs(s - t0).max() < 1.0):
            continue
        t, inliers, mad = s, 0.0, np.inf
        for img, v, g in zip(blurred, values, grads):
            t, inliers, mad = _gauss_newton(img, points, v, g, t, cfg.prior * w, cfg)
        if np.all(np.isfinite(t)) and np.abs(t).max() <= limit and inliers >= cfg.min_inliers:
            if best is None or mad < margin * best[1]:
                best = (t, mad)
    if best is None:
        return None
    # a shift must explain the room clearly better than none: people who are not left out pull a
    # still camera's estimate by a pixel or more, and fit the room no better for it
    mad0 = _mad(_sample(finest, points) - values[-1])
    if best[1] > cfg.support * mad0:
        return np.zeros(2), mad0
    return best


def align(frame: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The frame resampled onto the reference's pixels: ``out(x) = frame(x + t)`` (bilinear; the
    edge pixels repeated where ``x + t`` leaves the frame).

    Parameters
    ----------
    frame : ndarray of shape (H, W, 3) or (H, W)
        The frame.
    t : ndarray of shape (2,)
        Its shift (:func:`estimate_shift`), pixels.

    Returns
    -------
    ndarray
        The aligned frame, the same shape and dtype.
    """
    return _translate(frame, np.asarray(t, np.float64), cv2.INTER_LINEAR, cv2.BORDER_REPLICATE)


def unalign_labels(labels: np.ndarray, t: np.ndarray, fill: int = 0) -> np.ndarray:
    """Labels found on an aligned frame moved back onto the frame's pixels: ``out(y) = labels(y - t)``
    (nearest pixel; ``fill`` where ``y - t`` leaves the image).

    Parameters
    ----------
    labels : ndarray of shape (H, W), dtype uint8
        Per-pixel labels on the reference's pixels.
    t : ndarray of shape (2,)
        The frame's shift, pixels.
    fill : int, default=0
        The label of the frame's pixels that no reference pixel covers.

    Returns
    -------
    ndarray of shape (H, W), dtype uint8
        The labels on the frame's pixels.
    """
    return _translate(labels, -np.asarray(t, np.float64), cv2.INTER_NEAREST, cv2.BORDER_CONSTANT, float(fill))


def align_stack(frames: np.ndarray, config: ShakeConfig | None = None) -> np.ndarray:
    """Training frames aligned on one another: each frame's shift undone where it is at least
    ``min_shift_px``.

    Two passes: each frame against the first (the last frame's shift as the start), then each
    frame against the per-pixel median of the frames so aligned, with the pixels that differ from
    that median both as they are and as the first pass moved them left out (people who moved
    during training: against the first frame they would pull the shift with them, on a still
    camera too).

    Parameters
    ----------
    frames : ndarray of shape (N, H, W, 3), dtype uint8
        BGR frames.
    config : ShakeConfig or None, default=None
        Estimation settings; None: ``ShakeConfig()``.

    Returns
    -------
    ndarray of shape (N, H, W, 3), dtype uint8
        The frames on the pixels of their median (``frames`` itself when none had to move).
    """
    cfg = config or ShakeConfig()
    if min(frames.shape[1:3]) < _MIN_SIDE:
        return frames
    greys = [grey(f) for f in frames]
    first = _Reference(greys[0], cfg)
    shifts = [np.zeros(2)]
    for g in greys[1:]:
        t = estimate_shift(first, g, shifts[-1], None, cfg)
        shifts.append(shifts[-1] if t is None else t)
    median = np.median(np.stack([align(g, t) for g, t in zip(greys, shifts)]), axis=0).astype(np.float32)
    ref = _Reference(median, cfg)
    out = frames
    for i, (g, t) in enumerate(zip(greys, shifts)):
        # a person differs from the median both where the frame is and where the first pass put
        # it; the room's edges in one of the two only, where that one is off
        differs = (np.abs(g - median) > _MOVED_GREY) & (np.abs(align(g, t) - median) > _MOVED_GREY)
        t2 = estimate_shift(ref, g, t, differs, cfg)
        if t2 is not None and np.hypot(*t2) >= cfg.min_shift_px:
            if out is frames:
                out = frames.copy()
            out[i] = align(frames[i], t2)
    return out


class ShakeEstimator:
    """The shift of each frame of one stream against a background model's mean image.

    Parameters
    ----------
    config : ShakeConfig or None, default=None
        Estimation settings; None: ``ShakeConfig()``.

    Attributes
    ----------
    last : ndarray of shape (2,) or None
        The last frame's shift as estimated, pixels (the next frame's start); None where none
        could be told.
    shaken : int
        Frames so far whose shift was followed.
    """

    def __init__(self, config: ShakeConfig | None = None) -> None:
        self.config = config or ShakeConfig()
        self.last: np.ndarray | None = None
        self.shaken = 0
        self._ref: _Reference | None = None
        self._age = 0
        #: the room's usual median absolute residual at a found shift (grey levels), None until known
        self._usual: float | None = None

    def renew(self) -> None:
        """Read the reference again on the next frame, before ``refresh`` frames have passed: the
        background changed all over (re-exposed to a new light).
        """
        self._ref = None

    def shift(self, reference: np.ndarray, frame: np.ndarray, ignore: np.ndarray | None = None) -> np.ndarray | None:
        """The frame's shift to follow, or None to classify it as it is.

        Parameters
        ----------
        reference : ndarray of shape (H, W, 3) or (H, W), dtype float32
            The background's mean colour (or grey) image; read once every ``refresh`` frames.
        frame : ndarray of shape (H, W, 3), dtype uint8
            BGR frame.
        ignore : ndarray of shape (H, W), dtype bool, or None, default=None
            Reference pixels to leave out (:func:`estimate_shift`).

        Returns
        -------
        ndarray of shape (2,) or None
            (tx, ty) pixels, or None when it is shorter than ``min_shift_px`` or cannot be told.
        """
        if min(frame.shape[:2]) < _MIN_SIDE:
            self.last = None
            return None
        if self._ref is None or self._age >= self.config.refresh or self._ref.shape != frame.shape[:2]:
            ref = grey(reference) if reference.ndim == 3 else reference.astype(np.float32)
            self._ref, self._age = _Reference(ref, self.config), 0
        self._age += 1
        g = grey(frame)
        if ignore is not None and ignore.shape != g.shape:
            raise ValueError(f"ignore {ignore.shape} must have the frame's shape {g.shape}")
        quiet = None if self._usual is None or self.last is None else _QUIET * self._usual
        found = _estimate(self._ref, g, self.last, ignore, self.config, quiet)
        if found is None:
            self.last = None
            return None
        t, mad = found
        # the usual residual follows the room's noise (light, compression) slowly
        self._usual = mad if self._usual is None else self._usual + _USUAL_RATE * (mad - self._usual)
        self.last = t
        if np.hypot(*t) < self.config.min_shift_px:
            return None
        self.shaken += 1
        return t
