"""Shadow labels inside a body: dark clothes and hair that the shadow test takes for shadows.

Horprasert's shadow class (a pixel darker than its background with the same chromaticity) also
takes in dark trousers, hair and shirts on a grey room. A cast shadow lies on the ground or a wall
BESIDE a person: at or below their feet, or off to one side. Two steps take such labels back as
foreground:

* Enclosed: a shadow-labelled pixel that has foreground both above and below it within
  ``span_px`` rows (Serra's closing by a vertical line), and that lies above the lowest
  ``foot_fraction`` of the foreground's vertical extent in its connected region of foreground and
  shadow, is inside the body. The feet band keeps the floor shadow between and around the feet,
  and the closing keeps shadows beside the body.
* Legs: grey trousers below a foreground torso are shadow from the hips to the shoes, longer than
  any closing that leaves cast shadows alone. A shadow pixel that hangs from foreground (the
  foreground is straight above it in its column, with only shadow between, at most
  ``leg_depth`` of the region's foreground height below it), in a run of shadow along its row
  no wider than ``leg_width`` of that height, above the lowest ``leg_foot`` of the foreground's
  extent, and whose neighbourhood does not keep the background's texture (normalised cross-correlation of
  grey levels over the shadow pixels of a ``leg_window`` square under ``leg_ncc``; Jacques, Jung &
  Musse 2005, eq. 4), is a leg. A cast shadow is the floor, darker: it keeps the floor's pattern
  and correlates with it, trousers do not. Unlike the model's own texture test this one does not
  need a textured floor, because it is asked only where a body is straight above.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from . import kernels
from .background import FOREGROUND, SHADOW


@dataclass(frozen=True)
class BodyShadowConfig:
    """Which shadow labels are taken back as foreground.

    Parameters
    ----------
    span_px : int, default=15
        Length in pixels of the vertical closing: a shadow pixel needs foreground above and below
        it within this many rows (at 320x240; scale with the frame height). 0: off (both steps).
    foot_fraction : float, default=0.2
        The lowest part of a region's foreground extent, as a fraction of its height, where
        enclosed shadows stay shadows (the feet touch their own cast shadow there); in [0, 1).
    edge_px : int, default=0
        Also take back the shadow pixels within this many pixels of foreground (a person's
        blurred, darker rim), above the feet band too; 0: none.
    leg_ncc : float, default=0.5
        A hanging shadow pixel whose neighbourhood correlates less than this with the
        background's grey levels is a leg; in [-1, 1], -1: no leg step.
    leg_depth : float, default=0.1
        How far below the foreground above it a hanging shadow pixel may be, as a fraction of its
        region's foreground height; in (0, 1].
    leg_width : float, default=0.15
        The widest run of shadow along its row that a leg pixel may lie in, as a fraction of its
        region's foreground height (a leg is narrow; a cast shadow on the floor spreads).
    leg_foot : float, default=0.05
        The lowest part of a region's foreground extent, as a fraction of its height, where no
        shadow is a leg (the shoes stand in their cast shadow); in [0, 1).
    leg_window : int, default=7
        Side of the square window of the correlation, pixels (odd, >= 3).
    leg_scale : int, default=1
        The correlation is worked out on blocks of this many pixels a side (each block's mean grey
        level over its shadow pixels, weighted by their number), over a window of about
        ``leg_window`` pixels (an odd number of blocks, at least 3): at 2, a quarter of the
        pixels, for real-time graphs (trousers do not keep the floor's pattern at either scale).
        1: on the pixels.
    """

    span_px: int = 15
    foot_fraction: float = 0.2
    edge_px: int = 0
    leg_ncc: float = 0.5
    leg_depth: float = 0.1
    leg_width: float = 0.15
    leg_foot: float = 0.05
    leg_window: int = 7
    leg_scale: int = 1

    def __post_init__(self) -> None:
        if self.span_px < 0:
            raise ValueError(f"body shadow span_px must be >= 0 (0: off), got {self.span_px}")
        if not 0.0 <= self.foot_fraction < 1.0:
            raise ValueError(f"body shadow foot_fraction must be in [0, 1), got {self.foot_fraction}")
        if self.edge_px < 0:
            raise ValueError(f"body shadow edge_px must be >= 0 (0: none), got {self.edge_px}")
        if not -1.0 <= self.leg_ncc <= 1.0:
            raise ValueError(f"body shadow leg_ncc must be in [-1, 1] (-1: no leg step), got {self.leg_ncc}")
        if not 0.0 < self.leg_depth <= 1.0:
            raise ValueError(f"body shadow leg_depth must be in (0, 1], got {self.leg_depth}")
        if self.leg_width <= 0.0:
            raise ValueError(f"body shadow leg_width must be > 0, got {self.leg_width}")
        if not 0.0 <= self.leg_foot < 1.0:
            raise ValueError(f"body shadow leg_foot must be in [0, 1), got {self.leg_foot}")
        if self.leg_scale < 1:
            raise ValueError(f"body shadow leg_scale must be >= 1 (1: pixels), got {self.leg_scale}")
        if self.leg_window < 3 or self.leg_window % 2 == 0:
            raise ValueError(f"body shadow leg_window must be odd and >= 3, got {self.leg_window}")


def reclaim_body_shadow(
    labels: np.ndarray,
    config: BodyShadowConfig,
    frame: np.ndarray | None = None,
    background: np.ndarray | None = None,
    unseen: np.ndarray | None = None,
    fg_idx: np.ndarray | None = None,
) -> np.ndarray:
    """Relabel the shadow pixels inside a body as foreground.

    Parameters
    ----------
    labels : ndarray of shape (H, W), uint8
        Class labels (``background`` codes). Not modified.
    config : BodyShadowConfig
        The closing length, the feet band and the leg step.
    frame : ndarray of shape (H, W, 3), uint8, optional
        The frame the labels are of; with ``background``, for the leg step (skipped without).
    background : ndarray of shape (H, W), float32, optional
        The background's grey level (sum of the three channels of its expected colour E) that
        ``labels`` were classified against.
    unseen : ndarray of shape (H, W), bool, optional
        Pixels where the background was filled in, never seen (``HorprasertBackground.unseen_``):
        its texture there is a guess, so the leg step leaves them alone.
    fg_idx : ndarray of shape (K,), dtype int, optional
        Ascending flat indices of the FOREGROUND pixels of ``labels``, where the caller has them
        already (None: found here).

    Returns
    -------
    ndarray of shape (H, W), uint8
        ``labels`` itself when nothing changes, else a copy with the reclaimed pixels FOREGROUND.
    """
    if config.span_px == 0:
        return labels
    # the 0 / 255 masks of foreground, shadow and either, and the leg step's starts (shadow
    # pixels straight below foreground), in one compiled pass over the labels
    fg, sh, either, pts = kernels.shadow_masks(labels, _FG_CODE, _SH_CODE)
    closed = cv2.morphologyEx(fg, cv2.MORPH_CLOSE, np.ones((config.span_px, 1), np.uint8))
    if config.edge_px:
        side = 2 * config.edge_px + 1
        cv2.max(closed, cv2.dilate(fg, np.ones((side, side), np.uint8)), dst=closed)
    # nonzero of a bool array: several times faster than of the 0 / 255 bytes
    cand = np.flatnonzero(cv2.bitwise_and(sh, closed).ravel() != 0)
    legs = config.leg_ncc > -1.0 and frame is not None and background is not None
    # the legs' starts: shadow pixels straight below foreground (none: no leg, and the
    # regions need not be labelled for that step)
    starts = pts if legs and pts.shape[0] > 0 else None
    if cand.size == 0 and starts is None:
        return labels
    h, w = labels.shape
    n, comp = cv2.connectedComponents(either, connectivity=8)
    comp_flat = comp.ravel()
    if fg_idx is None:
        fg_idx = np.flatnonzero(labels.ravel() == FOREGROUND)  # on bool: several times faster than on fg's 0 / 255
    # each region's first and last foreground row, in one compiled pass (numpy's ufunc.at was slow)
    top, bottom = kernels.region_rows(comp_flat, fg_idx, w, n)
    c = comp_flat[cand]
    # a candidate touches or is enclosed by foreground, so its region has some: bottom >= top
    take = [cand[(bottom[c] - cand // w) > config.foot_fraction * (bottom[c] - top[c] + 1)]]
    if starts is not None:
        take.append(_legs(starts, fg, sh, comp, top, bottom, frame, background, unseen, config))
    idx = np.concatenate(take)
    if idx.size == 0:
        return labels
    out = labels.copy()
    out.ravel()[idx] = FOREGROUND
    return out


def _legs(
    pts: np.ndarray,
    fg: np.ndarray,
    sh: np.ndarray,
    comp: np.ndarray,
    top: np.ndarray,
    bottom: np.ndarray,
    frame: np.ndarray,
    background: np.ndarray,
    unseen: np.ndarray | None,
    config: BodyShadowConfig,
) -> np.ndarray:
    """Flat indices of the shadow pixels that are legs (see the module docstring).

    ``pts``: the starts, (K, 1, 2) x, y (``kernels.shadow_masks``); ``fg``, ``sh``: (H, W) 0/255 masks; ``comp``: (H, W)
    region labels of fg | sh; ``top``, ``bottom``: (n,) each region's first and last foreground
    row.

    A leg is a run of shadow down a column from the foreground, and a run along a row: pixels
    next to each other along a column or a row are in one region (of 8-connected fg | sh), so
    both runs can be measured on the whole masks, over the rows the starts reach, and only the
    limits are each region's (from its foreground height). The correlation is one compiled pass
    over each candidate's window (``kernels.leg_ncc``), or on blocks (``leg_scale`` > 1) on each
    region's own box (a few per frame).
    """
    h, w = fg.shape
    r = config.leg_window // 2
    scale = config.leg_scale
    block_k = max(3, (config.leg_window // scale) | 1)  # the window in blocks: odd, about as wide

    # The hanging pixels, in one compiled pass over the starts: a leg pixel hangs below a start
    # (shadow straight under foreground) of its region, down the run of shadow from it (fg ends
    # the run, and a pixel below that hangs from the next start), within the region's depth and
    # above its feet band; and lies in a run of shadow along its row no wider than the region's
    # limit (pixels next to each other along a column or a row are in one region of 8-connected
    # fg | sh). Returned in raster order, as the steps below take them.
    no_unseen = unseen is None
    flat, c = kernels.leg_pixels(
        pts,
        sh,
        comp,
        top,
        bottom,
        _NO_UNSEEN if no_unseen else unseen,
        not no_unseen,
        float(config.leg_depth),
        float(config.leg_foot),
        float(config.leg_width),
    )
    if flat.size == 0:
        return np.empty(0, np.intp)
    if scale == 1:
        # normalised cross-correlation over the window's shadow pixels (of any region): one
        # compiled pass over each candidate's window (the region boxes' box filters before)
        ncc = kernels.leg_ncc(flat, sh, np.ascontiguousarray(frame), background, r)
        return flat[ncc < config.leg_ncc]
    out = []
    # region by region, in the order of their labels, each one's pixels in raster order
    order = np.argsort(c, kind="stable")
    ys, xs = np.divmod(flat[order], w)
    c = c[order]
    cut = np.flatnonzero(np.diff(c)) + 1
    for gy, gx in zip(np.split(ys, cut), np.split(xs, cut)):
        # on the candidates' box with a margin of the window's half side
        by0, by1 = max(int(gy.min()) - r, 0), min(int(gy.max()) + r + 1, h)
        bx0, bx1 = max(int(gx.min()) - r, 0), min(int(gx.max()) + r + 1, w)
        # the box on whole blocks: its near corner down to the block grid, a part block at
        # the frame's far edge left out (its candidates read the last whole block)
        by0, bx0 = by0 - by0 % scale, bx0 - bx0 % scale
        by1, bx1 = by0 + max((by1 - by0) // scale, 1) * scale, bx0 + max((bx1 - bx0) // scale, 1) * scale
        box_sl = (slice(by0, by1), slice(bx0, bx1))
        ncc = _block_ncc(sh[box_sl], frame[box_sl], background[box_sl], gy - by0, gx - bx0, scale, block_k)
        out.append((gy * w + gx)[ncc < config.leg_ncc])
    return np.concatenate(out) if out else np.empty(0, np.intp)


#: the label codes as the masks' kernel takes them
_FG_CODE, _SH_CODE = np.uint8(FOREGROUND), np.uint8(SHADOW)

#: ``unseen`` when there is none (the kernel takes an array either way)
_NO_UNSEEN = np.zeros((1, 1), bool)

#: the grey sum of a BGR pixel, as a ``cv2.transform`` matrix
_GREY_SUM = np.ones((1, 3), np.float32)


def _block_ncc(
    m: np.ndarray, frame: np.ndarray, e: np.ndarray, ys: np.ndarray, xs: np.ndarray, scale: int, k: int
) -> np.ndarray:
    """The leg step's correlation on ``scale`` x ``scale`` blocks: of the blocks' mean grey levels
    over their shadow pixels, frame against background, each block weighted by its shadow
    pixels, over a ``k`` x ``k`` window of blocks (``BORDER_REFLECT``) around each candidate's.

    Parameters
    ----------
    m : ndarray of shape (H, W), dtype uint8 or float32
        The same non-zero weight (1, or 255 of a 0 / 255 mask) on the shadow pixels of the box, 0
        elsewhere; H and W multiples of ``scale``.
    frame : ndarray of shape (H, W, 3), dtype uint8
        The frame there (its grey level: the sum of the three channels).
    e : ndarray of shape (H, W), dtype float32
        The background's grey levels there.
    ys, xs : ndarray of shape (K,), dtype int
        The candidates, pixels in the box (those past its last whole block read that block).
    scale, k : int
        Block side, pixels; window side, blocks (odd).

    Returns
    -------
    ndarray of shape (K,), dtype float32
        The correlation at each candidate, in [-1, 1].
    """
    bh, bw = m.shape[0] // scale, m.shape[1] // scale

    def small(a: np.ndarray) -> np.ndarray:  # block means
        return cv2.resize(a, (bw, bh), interpolation=cv2.INTER_AREA)

    at = (np.minimum(ys // scale, bh - 1), np.minimum(xs // scale, bw - 1))

    def box(a: np.ndarray) -> np.ndarray:
        return cv2.boxFilter(a, -1, (k, k), normalize=False, borderType=cv2.BORDER_REFLECT)[at]

    mf = m.astype(np.float32)
    grey = cv2.transform(frame.astype(np.float32), _GREY_SUM)
    # per block: its shadow weight n_b and the sums of the grey levels over its shadow pixels
    # (all in the block's mean: the scale cancels below); a block's mean grey over its shadow
    # is g_b / n_b, and its weighted square n_b (g_b / n_b)^2 = g_b^2 / n_b
    nb = small(mf)
    gb, eb = small(cv2.multiply(grey, mf)), small(cv2.multiply(e, mf))
    # centred on the box's mean over its shadow (g_b - c n_b is the block of (grey - c) m): the
    # moments below are differences of float32 sums, exact enough only near zero
    total = np.float32(nb.sum())
    gb -= nb * (gb.sum() / total)
    eb -= nb * (eb.sum() / total)
    inv_nb = 1.0 / np.maximum(nb, np.float32(1e-6) * total)
    inv_n = 1.0 / np.maximum(box(nb), np.float32(1e-6) * total)
    me, mi = box(eb) * inv_n, box(gb) * inv_n
    ve = box(eb * eb * inv_nb) * inv_n - me * me
    vi = box(gb * gb * inv_nb) * inv_n - mi * mi
    cov = box(gb * eb * inv_nb) * inv_n - mi * me
    return cov / np.sqrt(np.maximum(vi, 0.0) * np.maximum(ve, 0.0) + 1e-6)
