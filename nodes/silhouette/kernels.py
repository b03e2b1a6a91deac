"""Compiled per-pixel kernels of the background models (numba).

The models' per-frame steps were chains of numpy and OpenCV calls, each a pass over the frame or
over a few thousand gathered pixels: about a thousand calls a frame, each short, and the two
threads of the extractor (the caller and the models' worker) took turns on the GIL between them.
Here a step is one compiled loop that visits each pixel once and holds no GIL (``nogil=True``),
so the worker's learning runs truly beside the caller. ``cache=True``: the compile happens once
per install, a process only loads it.

Every kernel does the same integer and float32 operations, in the same order, as the numpy
formulation it replaces (numba without fastmath follows IEEE), so the outputs are bit-identical;
the tests check each against that formulation on random inputs. The one exception is
``texture_ncc``: numpy summed its windows in float32 in its own (SIMD) order, which a loop cannot
reproduce, so it sums in float64 and agrees to float32 rounding; ``leg_ncc`` likewise (OpenCV's
float32 box filters before).
"""

from __future__ import annotations

from collections.abc import Callable

import numba
import numpy as np

#: 8-neighbourhood offsets (dy, dx) of ViBe's spatial diffusion, in the order of the draws
NEIGHBOUR_DY = np.array([-1, -1, -1, 0, 0, 1, 1, 1], np.int64)
NEIGHBOUR_DX = np.array([-1, 0, 1, -1, 1, -1, 0, 1], np.int64)

# error_model "numpy": a division by zero gives inf or nan as in the numpy formulations, not an exception
_JIT = {"cache": True, "nogil": True, "error_model": "numpy"}
# helpers called per pixel: inlined into the kernels (a call per pixel cost more than its work)
_INLINE = {**_JIT, "inline": "always"}


@numba.njit(**_JIT)
def learnable(cand: np.ndarray, flat_labels: np.ndarray, blink: np.ndarray, level: np.float32) -> np.ndarray:
    """The pixels of ``cand`` the samples may learn, in order: ``cand[(labels[cand] == 0) | (blink[cand] >= level)]``.

    Parameters
    ----------
    cand : ndarray of shape (M,), dtype int64
        Flat pixel indices.
    flat_labels : ndarray of shape (H * W,), dtype uint8
        Horprasert classes (BACKGROUND is 0).
    blink : ndarray of shape (H * W,), dtype float32
        Blink levels v(x).
    level : float32
        ``learn_blink``.

    Returns
    -------
    ndarray of shape (M',), dtype int64
        The learnable ones of ``cand``.
    """
    out = np.empty(cand.size, np.int64)
    n = 0
    for i in range(cand.size):
        p = cand[i]
        if flat_labels[p] == 0 or blink[p] >= level:
            out[n] = p
            n += 1
    return out[:n]


@numba.njit(**_INLINE)
def _touch(samples: np.ndarray, box: np.ndarray, pixels: np.ndarray, m: int) -> int:
    """Read the first and last byte of the sample row and the box of the first m ``pixels``, and
    return their sum, never -1 (callers test for it, so that the compiler keeps the reads). Why:
    the pixels are random, and their rows mostly miss the caches; these loads are independent of
    each other, so the processor overlaps their misses, where the long loop body of the update
    that follows would take them one by one.
    """
    t = 0
    last = samples.shape[1] - 1
    for i in range(m):
        p = pixels[i]
        t += samples[p, 0] + samples[p, last]
        if box.size:
            t += box[p, 0]
    return t


@numba.njit(**_INLINE)
def _put(samples: np.ndarray, box: np.ndarray, p: int, slot: int, colour: np.ndarray, n: int) -> None:
    """Write ``colour`` (3,) uint8 over sample ``slot`` of pixel p and keep its box (min B, G, R,
    0, max B, G, R, 0 over the N samples) exact: a new value beyond an end moves that end, and
    only where the value replaced was an end itself is that channel's end searched again (the
    same integer min / max as a search over all N).
    """
    for c in range(3):
        at = c * n + slot
        old = samples[p, at]
        v = colour[c]
        samples[p, at] = v
        lo, hi = box[p, c], box[p, 4 + c]
        if v <= lo:
            box[p, c] = v
        elif old == lo:
            lo = samples[p, c * n]
            for s in range(1, n):
                lo = min(lo, samples[p, c * n + s])
            box[p, c] = lo
        if v >= hi:
            box[p, 4 + c] = v
        elif old == hi:
            hi = samples[p, c * n]
            for s in range(1, n):
                hi = max(hi, samples[p, c * n + s])
            box[p, 4 + c] = hi


@numba.njit(**_JIT)
def learn_own(
    samples: np.ndarray,
    box: np.ndarray,
    spread: np.ndarray,
    px: np.ndarray,
    cand: np.ndarray,
    k: np.ndarray,
    rate: np.float32,
    follow: bool,
) -> None:
    """ViBe's own-pixel update with SuBSENSE's spread: each drawn pixel p = cand[i] follows
    d(p) += rate (sum_{c,s} |S_s,c(p) - I_c(p)| / N - d(p)) (from the samples before this call's
    writes, and from d before them: a pixel drawn twice takes its last result), then writes
    its colour over sample k[i], keeping the box (min, max per channel) of the pixel exact.

    Parameters
    ----------
    samples : ndarray of shape (H * W, 3 N), dtype uint8
        Per pixel its B, G, R rows of N samples side by side (written in place).
    box : ndarray of shape (H * W, 8), dtype uint8
        Per pixel min B, G, R, 0, max B, G, R, 0 of its samples (written in place).
    spread : ndarray of shape (H * W,), dtype float32
        d(x) (written in place when ``follow``).
    px : ndarray of shape (H * W, 3), dtype uint8
        The frame's BGR pixels.
    cand, k : ndarray of shape (M,), dtype int64
        Drawn flat pixels and the sample each replaces, in [0, N).
    rate : float32
        ``spread_rate``.
    follow : bool
        Whether d(x) is followed (``spread_k`` > 0).
    """
    n = samples.shape[1] // 3
    m = cand.size
    nf = np.float32(n)
    if _touch(samples, box, cand, m) == -1:
        return
    if follow:
        d_new = np.empty(m, np.float32)
        for i in range(m):
            p = cand[i]
            row = samples[p]
            g = 0
            for c in range(3):
                col = np.int32(px[p, c])
                for s in range(n):
                    g += abs(np.int32(row[c * n + s]) - col)
            d = spread[p]
            d_new[i] = d + rate * (np.float32(g) / nf - d)
        for i in range(m):
            spread[cand[i]] = d_new[i]
    for i in range(m):
        p = cand[i]
        _put(samples, box, p, k[i], px[p], n)


@numba.njit(**_JIT)
def learn_neighbours(
    samples: np.ndarray,
    box: np.ndarray,
    px: np.ndarray,
    cand: np.ndarray,
    k: np.ndarray,
    j: np.ndarray,
    h: int,
    w: int,
    flat_labels: np.ndarray,
    blink: np.ndarray,
    level: np.float32,
) -> None:
    """ViBe's diffusion: the colour of each drawn pixel cand[i] goes into sample k[i] of its
    8-neighbour j[i] (NEIGHBOUR_DY, NEIGHBOUR_DX; clipped to the frame) when that neighbour is
    learnable (``learnable``'s test), in order (a pixel written twice keeps the last), keeping
    the box of each written pixel exact.

    Parameters
    ----------
    samples, box, px :
        As ``learn_own``'s.
    cand, k, j : ndarray of shape (M,), dtype int64
        Drawn flat pixels, sample slots in [0, N) and neighbour numbers in [0, 8).
    h, w : int
        Frame size.
    flat_labels, blink, level :
        As ``learnable``'s.
    """
    n = samples.shape[1] // 3
    nb = np.empty(cand.size, np.int64)
    at = np.empty(cand.size, np.int64)
    m = 0
    for i in range(cand.size):
        p = cand[i]
        y = p // w + NEIGHBOUR_DY[j[i]]
        x = p % w + NEIGHBOUR_DX[j[i]]
        y = min(max(y, 0), h - 1)
        x = min(max(x, 0), w - 1)
        q = y * w + x
        if flat_labels[q] == 0 or blink[q] >= level:
            nb[m] = q
            at[m] = i
            m += 1
    if _touch(samples, box, nb, m) == -1:
        return
    for t in range(m):
        i = at[t]
        _put(samples, box, nb[t], k[i], px[cand[i]], n)


@numba.njit(**_JIT)
def classify(
    b0: np.ndarray,
    b1: np.ndarray,
    b2: np.ndarray,
    w0: np.ndarray,
    w1: np.ndarray,
    w2: np.ndarray,
    v0: np.ndarray,
    v1: np.ndarray,
    v2: np.ndarray,
    inv_den: np.ndarray,
    alpha_hi: np.ndarray,
    alpha_lo: np.ndarray,
    alpha_min: np.ndarray,
    alpha_max: np.ndarray,
    cd2_max: np.ndarray,
    labels: np.ndarray,
    alpha: np.ndarray,
) -> None:
    """Horprasert's classes (eq. 9) from the raw distortions (eqs. 5-6), one pass over the frame.

    S = (I_0 w_0 + I_1 w_1) + I_2 w_2 with w_c = E_c / s_c^2; alpha = S / sum_c (E_c / s_c)^2;
    CD^2 = max(((I_0^2 v_0 + I_1^2 v_1) + I_2^2 v_2) - S alpha, 0) with v_c = 1 / s_c^2, float32
    in that order. Class: FOREGROUND 3 where CD^2 > cd2_max, alpha < alpha_min or alpha >
    alpha_max; else BACKGROUND 0 where alpha_lo < alpha < alpha_hi; else HIGHLIGHT 2 where
    alpha >= 1 and SHADOW 1 where not. Flat arrays and no branches: the compiler runs it on SIMD
    lanes.

    Parameters
    ----------
    b0, b1, b2 : ndarray of shape (H * W,), dtype uint8
        The frame's B, G, R planes, flat.
    w0, w1, w2, v0, v1, v2 : ndarray of shape (H * W,), dtype float32
        E_c / s_c^2 and 1 / s_c^2.
    inv_den : ndarray of shape (H * W,), dtype float32
        1 / sum_c (E_c / s_c)^2.
    alpha_hi, alpha_lo, alpha_min, alpha_max, cd2_max : ndarray of shape (H * W,), dtype float32
        Per-pixel thresholds in raw alpha and CD^2 units.
    labels : ndarray of shape (H * W,), dtype uint8
        Out: the classes.
    alpha : ndarray of shape (H * W,), dtype float32
        Out: the raw brightness distortion.
    """
    zero = np.float32(0.0)
    one = np.float32(1.0)
    for p in range(inv_den.size):
        i0 = np.float32(b0[p])
        i1 = np.float32(b1[p])
        i2 = np.float32(b2[p])
        s = i0 * w0[p] + i1 * w1[p]
        s = s + i2 * w2[p]
        a = s * inv_den[p]
        cd2 = (i0 * i0) * v0[p] + (i1 * i1) * v1[p]
        cd2 = cd2 + (i2 * i2) * v2[p]
        cd2 = max(cd2 - s * a, zero)
        alpha[p] = a
        fg = (cd2 > cd2_max[p]) | (a < alpha_min[p]) | (a > alpha_max[p])
        band = (a < alpha_hi[p]) & (a > alpha_lo[p])
        lab = (np.uint8(1) + np.uint8(a >= one)) * np.uint8(not band)
        labels[p] = lab | (np.uint8(3) * np.uint8(fg))


@numba.njit(**_INLINE)
def _matches(p: int, px: np.ndarray, samples: np.ndarray, gain: np.float32, base: np.float32, rel: np.float32) -> int:
    """The number of samples S_k of pixel p with |I - S_k|_1 gain - rel |S_k|_1 < base."""
    n = samples.shape[1] // 3
    hits = 0
    c0 = np.int32(px[p, 0])
    c1 = np.int32(px[p, 1])
    c2 = np.int32(px[p, 2])
    for s in range(n):
        s0 = np.int32(samples[p, s])
        s1 = np.int32(samples[p, n + s])
        s2 = np.int32(samples[p, 2 * n + s])
        dist = abs(s0 - c0) + abs(s1 - c1) + abs(s2 - c2)
        lhs = np.float32(dist) * gain
        lhs = lhs - rel * np.float32(s0 + s1 + s2)
        hits += np.int32(lhs < base)
    return hits


@numba.njit(**_JIT)
def explained(
    idx: np.ndarray,
    px: np.ndarray,
    samples: np.ndarray,
    box: np.ndarray,
    blink: np.ndarray,
    spread: np.ndarray,
    radius: np.float32,
    spread_k: np.float32,
    rel: np.float32,
    min_matches: int,
) -> np.ndarray:
    """ViBe's consensus with SuBSENSE's radius at the flat pixels ``idx``: at least
    ``min_matches`` samples S_k with |I - S_k|_1 / (1 + v) - rel |S_k|_1 < max(radius,
    spread_k d), float32 in that order.

    Parameters
    ----------
    idx : ndarray of shape (K,), dtype int64
        Flat pixel indices.
    px : ndarray of shape (H * W, 3), dtype uint8
        The frame's BGR pixels.
    samples, box : ndarray
        (H * W, 3 N) and (H * W, 8) uint8, as ``learn_own``'s.
    blink, spread : ndarray of shape (H * W,), dtype float32
        Blink levels v(x) and spreads d(x).
    radius, spread_k, rel : float32
        The model's ``radius``, ``spread_k`` and ``relative_radius``.
    min_matches : int
        #min.

    Returns
    -------
    ndarray of shape (K,), dtype bool
        True where the colour matches the pixel's samples.
    """
    # two passes: the box prefilter over all (the boxes are small and read in order), then the
    # samples of the few near their box (about a tenth), their rows touched first (rows that miss
    # the caches: independent loads overlap)
    out = np.zeros(idx.size, np.bool_)
    at = np.empty(idx.size, np.int64)
    gains = np.empty(idx.size, np.float32)
    bases = np.empty(idx.size, np.float32)
    m = 0
    for i in range(idx.size):
        # The box prefilter: the L1 distance from the colour to the box of the pixel's samples
        # is at most the distance to any sample, and the box's top corner's norm at least any
        # sample's, so where that distance reaches the widest radius no sample matches; the
        # margin covers float32 rounding (written out here: as a helper it ran 2x slower)
        p = idx[i]
        gain = np.float32(1.0) / (np.float32(1.0) + blink[p])
        base = radius
        if spread_k > np.float32(0.0):
            b = spread_k * spread[p]
            if b > base:
                base = b
        near = 0
        top = 0
        for c in range(3):
            v = np.int32(px[p, c])
            lo = np.int32(box[p, c])
            hi = np.int32(box[p, 4 + c])
            if lo > v:
                near += lo - v
            if v > hi:
                near += v - hi
            top += hi
        f = np.float32(near) * gain
        f = f - rel * np.float32(top)
        f = f * np.float32(1.0 - 1e-4)
        if f < base + np.float32(1e-3):
            at[m] = i
            gains[m] = gain
            bases[m] = base
            m += 1
    if _touch(samples, box[:0], idx[at[:m]], m) == -1:
        return out
    for j in range(m):
        i = at[j]
        out[i] = _matches(idx[i], px, samples, gains[j], bases[j], rel) >= min_matches
    return out


@numba.njit(**_JIT)
def veto(
    labels: np.ndarray,
    px: np.ndarray,
    samples: np.ndarray,
    box: np.ndarray,
    blink: np.ndarray,
    spread: np.ndarray,
    radius: np.float32,
    spread_k: np.float32,
    rel: np.float32,
    min_matches: int,
) -> tuple[np.ndarray, np.ndarray]:
    """The labels with each FOREGROUND (3) pixel that ``explained`` matches turned BACKGROUND (0).

    Parameters
    ----------
    labels : ndarray of shape (H * W,), dtype uint8
        Horprasert classes (not changed).
    px, samples, box, blink, spread, radius, spread_k, rel, min_matches :
        As ``explained``'s.

    Returns
    -------
    out : ndarray of shape (H * W,), dtype uint8
        The vetoed labels (a new array).
    fg_idx : ndarray of shape (K,), dtype int64
        Ascending flat indices of its FOREGROUND pixels.
    """
    idx = np.empty(labels.size, np.int64)
    k = 0
    for p in range(labels.size):
        if labels[p] == 3:
            idx[k] = p
            k += 1
    idx = idx[:k]
    ok = explained(idx, px, samples, box, blink, spread, radius, spread_k, rel, min_matches)
    out = labels.copy()
    fg = np.empty(k, np.int64)
    m = 0
    for i in range(k):
        if ok[i]:
            out[idx[i]] = 0
        else:
            fg[m] = idx[i]
            m += 1
    return out, fg[:m].copy()


@numba.njit(**_JIT)
def region_rows(comp: np.ndarray, idx: np.ndarray, w: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Each region's first and last row among the pixels ``idx``: top[r] = min, bottom[r] = max of
    idx // w over the pixels of region r = comp[idx] (``np.minimum.at`` / ``np.maximum.at``).

    Parameters
    ----------
    comp : ndarray of shape (H * W,), dtype int32
        Region labels in [0, n).
    idx : ndarray of shape (K,), dtype int64
        Flat pixel indices.
    w : int
        Frame width.
    n : int
        Number of regions.

    Returns
    -------
    top, bottom : ndarray of shape (n,), dtype int64
        The rows; the frame height H (top) and -1 (bottom) where a region has none of the pixels.
    """
    top = np.full(n, comp.size // w, np.int64)
    bottom = np.full(n, -1, np.int64)
    for i in range(idx.size):
        p = idx[i]
        r = comp[p]
        y = p // w
        if y < top[r]:
            top[r] = y
        if y > bottom[r]:
            bottom[r] = y
    return top, bottom


@numba.njit(**_JIT)
def shadow_masks(
    labels: np.ndarray, fg_code: np.uint8, sh_code: np.uint8
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The body-shadow step's masks in one pass: ``cv2.compare`` of the labels with the foreground
    and shadow codes, their ``cv2.bitwise_or``, and the leg step's starts, the shadow pixels
    straight below foreground, sh[y, x] & fg[y - 1, x] (``cv2.findNonZero`` of that, raster order).

    Parameters
    ----------
    labels : ndarray of shape (H, W), dtype uint8
        Class labels.
    fg_code, sh_code : uint8
        The foreground and shadow codes.

    Returns
    -------
    fg, sh, either : ndarray of shape (H, W), dtype uint8
        255 where the label is foreground, shadow, either; 0 elsewhere.
    starts : ndarray of shape (K, 1, 2), dtype int32
        The starts' x, y, as ``cv2.findNonZero`` gives them.
    """
    h, w = labels.shape
    fg = np.empty((h, w), np.uint8)
    sh = np.empty((h, w), np.uint8)
    either = np.empty((h, w), np.uint8)
    full = np.uint8(255)
    zero = np.uint8(0)
    for y in range(h):
        for x in range(w):
            v = labels[y, x]
            f = full if v == fg_code else zero
            s = full if v == sh_code else zero
            fg[y, x] = f
            sh[y, x] = s
            either[y, x] = f | s
    # the starts: a second pass over the rows below the first (a branch in the loop above would
    # keep it from being vectorised)
    k = 0
    for y in range(1, h):
        for x in range(w):
            if sh[y, x] & fg[y - 1, x]:
                k += 1
    starts = np.empty((k, 1, 2), np.int32)
    k = 0
    for y in range(1, h):
        for x in range(w):
            if sh[y, x] & fg[y - 1, x]:
                starts[k, 0, 0] = x
                starts[k, 0, 1] = y
                k += 1
    return fg, sh, either, starts


@numba.njit(**_JIT)
def leg_pixels(
    pts: np.ndarray,
    sh: np.ndarray,
    comp: np.ndarray,
    top: np.ndarray,
    bottom: np.ndarray,
    unseen: np.ndarray,
    has_unseen: bool,
    depth: float,
    foot: float,
    width: float,
) -> tuple[np.ndarray, np.ndarray]:
    """The body-shadow leg step's hanging shadow pixels that lie in a narrow run along their row
    (``body_shadow._legs`` before its correlation; the numpy formulation is in the tests).

    From each start (x, y) of region c = comp[y, x], with height h_c = bottom[c] - top[c] + 1 and
    only where depth h_c >= 1 and bottom[c] - y > foot h_c, the pixels (x, y + d), d = 0, 1, ...,
    while they are shadow inside the frame and d + 1 <= depth h_c, that lie above the feet band,
    bottom[c] - (y + d) > foot h_c, and are not unseen; of those, the ones whose run of shadow
    along their row is at most width h_c' long (c' their own region). Float64 products as in numpy.

    Parameters
    ----------
    pts : ndarray of shape (K, 1, 2), dtype int32
        The starts, ``cv2.findNonZero``'s x, y.
    sh : ndarray of shape (H, W), dtype uint8
        Shadow mask (non-zero: shadow).
    comp : ndarray of shape (H, W), dtype int32
        Region labels of foreground | shadow.
    top, bottom : ndarray of shape (n,), dtype int64
        Each region's first and last foreground row.
    unseen : ndarray of shape (H, W) (or any, when ``has_unseen`` is False), dtype bool
        Pixels whose background was never seen: never legs.
    has_unseen : bool
        Whether ``unseen`` is given.
    depth, foot, width : float
        ``leg_depth``, ``leg_foot``, ``leg_width`` of the config (fractions of h_c).

    Returns
    -------
    flat : ndarray of shape (M,), dtype int64
        The pixels' flat indices, ascending.
    c : ndarray of shape (M,), dtype int32
        Their regions.
    """
    h, w = sh.shape
    # at most min(depth h_c, rows left) pixels below a start
    size = 0
    for k in range(pts.shape[0]):
        r = comp[pts[k, 0, 1], pts[k, 0, 0]]
        size += min(int(depth * (bottom[r] - top[r] + 1)), h - pts[k, 0, 1])
    hang = np.empty(max(size, 0), np.int64)
    m = 0
    for k in range(pts.shape[0]):
        x = np.int64(pts[k, 0, 0])
        y = np.int64(pts[k, 0, 1])
        r = comp[y, x]
        hs = bottom[r] - top[r] + 1
        reach = depth * hs
        limit = foot * hs
        if not (reach >= 1 and bottom[r] - y > limit):
            continue
        d = 0
        # the run down the column ends at the first pixel that is not shadow (or the frame's end);
        # the depth, the feet band and unseen pixels only leave pixels out of it
        while y + d < h and sh[y + d, x] != 0 and d + 1 <= reach:
            yy = y + d
            if bottom[r] - yy > limit and not (has_unseen and unseen[yy, x]):
                hang[m] = yy * w + x
                m += 1
            d += 1
    hang = np.sort(hang[:m])
    flat = np.empty(m, np.int64)
    c = np.empty(m, np.int32)
    n = 0
    for i in range(m):
        p = hang[i]
        y = p // w
        x = p - y * w
        r = comp[y, x]
        x0 = x
        while x0 > 0 and sh[y, x0 - 1] != 0:
            x0 -= 1
        x1 = x
        while x1 < w - 1 and sh[y, x1 + 1] != 0:
            x1 += 1
        if x1 - x0 + 1 <= width * (bottom[r] - top[r] + 1):
            flat[n] = p
            c[n] = r
            n += 1
    return flat[:n], c[:n]


@numba.njit(**_INLINE)
def _reflect_index(i: int, n: int) -> int:
    """Index ``i`` into an axis of length ``n``, out-of-range ones mirrored as ``cv2.BORDER_REFLECT``
    pads (-1 -> 0, n -> n - 1; OpenCV's ``borderInterpolate`` loop).
    """
    if n == 1:
        return 0
    while i < 0 or i >= n:
        i = -i - 1 if i < 0 else 2 * n - 1 - i
    return i


@numba.njit(**_INLINE)
def _window_ncc(inv_n: float, me: float, ve: float, si: float, sii: float, sie: float) -> float:
    """NCC of a window from its sums over n pixels (``inv_n`` = 1 / max(n, 1)): the background's
    mean and variance ``me``, ``ve``, and the frame's sum, sum of squares and cross sum with the
    background ``si``, ``sii``, ``sie`` (the formula in :func:`texture_ncc`).
    """
    mi = si * inv_n
    vi = sii * inv_n - mi * mi
    cov = sie * inv_n - mi * me
    return cov / np.sqrt(max(vi, 0.0) * max(ve, 0.0) + 1e-6)


@numba.njit(**_JIT)
def texture_ncc(
    idx: np.ndarray,
    labels: np.ndarray,
    sh_code: np.uint8,
    e_pad: np.ndarray,
    var: np.ndarray,
    floor_k2: np.float32,
    frame: np.ndarray,
    r: int,
) -> np.ndarray:
    """The shadow texture test's correlation at the shadow pixels ``idx``.

    Each over its (2r+1) x (2r+1) window's shadow pixels (the window read across the frame's
    edges as ``cv2.BORDER_REFLECT`` pads): with m the window's shadow indicator, n = sum m, E
    the background's grey sum (b + g + r of the mean) and I the frame's:

        m(E) = sum m E / n,  var(E) = sum m E^2 / n - m(E)^2   (the same for I),
        cov = sum m I E / n - m(I) m(E),
        NCC = cov / sqrt(max(var(I), 0) max(var(E), 0) + 1e-6),

    computed only where the background is textured there, var(E) > (s_b^2 + s_g^2 + s_r^2) k^2
    (the noise of the grey sum; float32 as the numpy formulation); +inf elsewhere.

    The window sums and moments are float64 (one pass per window): the numpy formulation they
    replace summed in float32 in numpy's (SIMD-dependent) order, so the two agree to float32
    rounding, not bit for bit.

    Parameters
    ----------
    idx : ndarray of shape (K,), dtype int64
        Flat indices of shadow pixels, ascending.
    labels : ndarray of shape (H, W), dtype uint8
        The frame's classes; ``sh_code`` marks the shadow.
    sh_code : uint8
        The shadow code.
    e_pad : ndarray of shape (H + 2r, W + 2r), dtype float32
        E's grey sum, padded by r on each side with ``cv2.BORDER_REFLECT``.
    var : ndarray of shape (3, H, W), dtype float32
        The background's per-channel variance s^2.
    floor_k2 : float32
        k^2, the texture floor's factor on the summed variance.
    frame : ndarray of shape (H, W, 3), dtype uint8
        The frame.
    r : int
        Half the window side.

    Returns
    -------
    ndarray of shape (K,), dtype float64
        NCC at each pixel of ``idx``; +inf where the background is not textured.
    """
    h, w = labels.shape
    out = np.empty(idx.size, np.float64)
    for i in range(idx.size):
        p = idx[i]
        y = p // w
        x = p - y * w
        n = 0
        se = 0.0
        see = 0.0
        for dy in range(-r, r + 1):
            yy = _reflect_index(y + dy, h)
            for dx in range(-r, r + 1):
                xx = _reflect_index(x + dx, w)
                if labels[yy, xx] == sh_code:
                    ev = np.float64(e_pad[y + dy + r, x + dx + r])
                    n += 1
                    se += ev
                    see += ev * ev
        inv_n = 1.0 / max(n, 1)
        me = se * inv_n
        ve = see * inv_n - me * me
        floor = (var[0, y, x] + var[1, y, x] + var[2, y, x]) * floor_k2
        if not ve > floor:
            out[i] = np.inf
            continue
        si = 0.0
        sii = 0.0
        sie = 0.0
        for dy in range(-r, r + 1):
            yy = _reflect_index(y + dy, h)
            for dx in range(-r, r + 1):
                xx = _reflect_index(x + dx, w)
                if labels[yy, xx] == sh_code:
                    g = np.float64(np.int64(frame[yy, xx, 0]) + np.int64(frame[yy, xx, 1]) + np.int64(frame[yy, xx, 2]))
                    si += g
                    sii += g * g
                    sie += g * e_pad[y + dy + r, x + dx + r]
        out[i] = _window_ncc(inv_n, me, ve, si, sii, sie)
    return out


@numba.njit(**_JIT)
def advance_still(
    still: np.ndarray, still_ref: np.ndarray, px: np.ndarray, inv_s: np.ndarray, idx: np.ndarray, k: np.float32
) -> tuple[np.ndarray, np.ndarray]:
    """The ghost step's still runs: at each foreground pixel p = idx[i] (ascending, unique) the run
    goes on (n = still[p] + 1, uint16) where it had begun and every channel is within k spreads
    of the run's mean, max_c |I_c - ref_c| / s_c <= k, and restarts (n = 1) where not; the mean
    follows, ref += (I - ref) / n, float32 in that order. Runs off ``idx`` end (0).

    Parameters
    ----------
    still : ndarray of shape (H * W,), dtype uint16
        Run lengths (written in place).
    still_ref : ndarray of shape (3, H * W), dtype float32
        Runs' mean colours (written in place at ``idx``).
    px : ndarray of shape (H * W, 3), dtype uint8
        The frame's BGR pixels.
    inv_s : ndarray of shape (3, H * W), dtype float32
        1 / s_c.
    idx : ndarray of shape (K,), dtype int64
        The foreground's flat indices.
    k : float32
        ``absorb_k``.

    Returns
    -------
    n : ndarray of shape (K,), dtype uint16
        The runs' lengths.
    refs : ndarray of shape (3, K), dtype float32
        Their mean colours.
    """
    m = idx.size
    prev = np.empty(m, np.uint16)
    for i in range(m):
        prev[i] = still[idx[i]]
    still[:] = 0
    n = np.empty(m, np.uint16)
    refs = np.empty((3, m), np.float32)
    for i in range(m):
        p = idx[i]
        dev = np.float32(0.0)
        for c in range(3):
            d = abs(np.float32(px[p, c]) - still_ref[c, p]) * inv_s[c, p]
            dev = max(dev, d)
        run = np.uint16(prev[i] + np.uint16(1)) if prev[i] > 0 and dev <= k else np.uint16(1)
        n[i] = run
        still[p] = run
        inv_n = np.float32(1.0) / np.float32(run)
        for c in range(3):
            r = still_ref[c, p]
            r = r + (np.float32(px[p, c]) - r) * inv_n
            refs[c, i] = r
            still_ref[c, p] = r
    return n, refs


@numba.njit(**_JIT)
def feedback(
    v: np.ndarray,
    prev_fg: np.ndarray,
    prev_idx: np.ndarray,
    fg_idx: np.ndarray,
    h: int,
    w: int,
    open_dy: np.ndarray,
    open_dx: np.ndarray,
    near_dy: np.ndarray,
    near_dx: np.ndarray,
    decay: np.float32,
    rise: np.float32,
    top: np.float32,
) -> np.ndarray:
    """SuBSENSE's blink levels: v <- v - decay everywhere; at the pixels whose foreground label
    switched (fg != prev) outside the solid foreground of the last frame, v <- v + rise; then,
    on the box of both frames' foreground with a margin of 4, v <- min(v, top); last
    v <- max(v, 0); float32 in that order. The solid foreground is the last frame's mask opened
    by the ``open`` element and dilated by the ``near`` element (offsets from its anchor, which
    both elements hold; pixels outside the frame ignored, as OpenCV's default borders do),
    worked out only where it is read: at the switched pixels.

    Parameters
    ----------
    v : ndarray of shape (H * W,), dtype float32
        Blink levels (written in place).
    prev_fg : ndarray of shape (H * W,), dtype uint8
        The last frame's foreground, 0 / 1.
    prev_idx, fg_idx : ndarray of shape (K,), dtype int64
        Ascending flat indices of the last and this frame's foreground.
    h, w : int
        Frame size.
    open_dy, open_dx, near_dy, near_dx : ndarray of shape (E,), dtype int64
        Offsets of the opening's and the dilation's structuring elements.
    decay, rise, top : float32
        ``blink_decay``, ``blink_gain + blink_decay`` and ``max_radius_gain - 1``.

    Returns
    -------
    ndarray of shape (H * W,), dtype uint8
        This frame's foreground, 0 / 1 (the next call's ``prev_fg``).
    """
    npx = h * w
    fg = np.zeros(npx, np.uint8)
    for i in range(fg_idx.size):
        fg[fg_idx[i]] = 1
    raised = np.zeros(npx, np.uint8)
    y0, y1, x0, x1 = h, -1, w, -1
    if fg_idx.size + prev_idx.size > 0:
        for lst in (fg_idx, prev_idx):
            for i in range(lst.size):
                y, x = lst[i] // w, lst[i] % w
                y0, y1, x0, x1 = min(y0, y), max(y1, y), min(x0, x), max(x1, x)
        y0, y1 = max(0, y0 - 4), min(h, y1 + 5)
        x0, x1 = max(0, x0 - 4), min(w, x1 + 5)
        # erosion, then dilation, of the last foreground: both nonzero only at or beside it
        er = np.zeros(npx, np.uint8)
        for i in range(prev_idx.size):
            y, x = prev_idx[i] // w, prev_idx[i] % w
            keep = 1
            for e in range(open_dy.size):
                yy, xx = y + open_dy[e], x + open_dx[e]
                if 0 <= yy < h and 0 <= xx < w and prev_fg[yy * w + xx] == 0:
                    keep = 0
            er[prev_idx[i]] = keep
        opened = np.zeros(npx, np.uint8)
        for i in range(prev_idx.size):
            if er[prev_idx[i]]:
                y, x = prev_idx[i] // w, prev_idx[i] % w
                for e in range(open_dy.size):
                    yy, xx = y - open_dy[e], x - open_dx[e]
                    if 0 <= yy < h and 0 <= xx < w:
                        opened[yy * w + xx] = 1
        # the switched pixels (in one list and not the other) outside the dilated opening
        for lst, other in ((fg_idx, prev_fg), (prev_idx, fg)):
            for i in range(lst.size):
                p = lst[i]
                if other[p] != 0:
                    continue
                y, x = p // w, p % w
                solid = False
                for e in range(near_dy.size):
                    yy, xx = y + near_dy[e], x + near_dx[e]
                    if 0 <= yy < h and 0 <= xx < w and opened[yy * w + xx] != 0:
                        solid = True
                        break
                if not solid:
                    raised[p] = 1
    if y1 < 0:
        y0, y1, x0, x1 = h, h, 0, 0  # no foreground in either frame: no box in either frame: no box
    zero = np.float32(0.0)
    # outside the box only the decay: plain loops, which the compiler runs on SIMD lanes
    for p in range(y0 * w):
        v[p] = max(v[p] - decay, zero)
    for y in range(y0, y1):
        for p in range(y * w, y * w + x0):
            v[p] = max(v[p] - decay, zero)
        for p in range(y * w + x0, y * w + x1):
            a = v[p] - decay
            if raised[p]:
                a = a + rise
            v[p] = max(min(a, top), zero)
        for p in range(y * w + x1, y * w + w):
            v[p] = max(v[p] - decay, zero)
    for p in range(y1 * w, npx):
        v[p] = max(v[p] - decay, zero)
    return fg


@numba.njit(**_JIT)
def head_first_samples(
    p: np.ndarray, c: np.ndarray, up: np.ndarray, along: np.ndarray, w: int, m: int
) -> tuple[int, float, np.ndarray]:
    """The second half of ``body.spline.oriented_boundary`` and the arc-length resampling of
    ``body.spline.resample_closed`` in one pass over the boundary, with the same float64 steps.

    The reference crossing i0: of the points within one pixel of the upward axis,
    perp = |(p - c)_x up_y - (p - c)_y up_x| <= 1 with along > 0, the one with the largest
    along rounded to 6 decimals (rint(along 1e6) / 1e6, as ``np.round``), then the least perp,
    then the lowest index; without any, the least perp among along > 0 (index 0 when none).
    The start: the highest point (least y) within ``w`` points of i0, the nearest to it (the
    earlier on ties). The boundary from the start, closed, is resampled at s_j = j (L / m),
    L its length, by ``np.interp`` 's linear steps along the cumulative chord lengths
    (points that repeat their predecessor dropped).

    Parameters
    ----------
    p : ndarray of shape (K, 2), dtype float64
        The boundary, counter-clockwise on screen, pixels (``body.spline.boundary_and_axis``).
    c : ndarray of shape (2,), dtype float64
        The region's centroid, pixels.
    up : ndarray of shape (2,), dtype float64
        Unit upward axis.
    along : ndarray of shape (K,), dtype float64
        (p - c) @ up (numpy's product, passed in: its sum may be fused).
    w : int
        Half-width of the search for the highest point, points.
    m : int
        Samples to return.

    Returns
    -------
    start : int
        Index into ``p`` of the reference point (the samples' first).
    length : float
        L, pixels; the samples are meaningless when it is not > 0.
    samples : ndarray of shape (m, 2), dtype float64
        The resampled boundary, pixels.
    """
    k = p.shape[0]
    i0 = -1
    best_r = 0.0
    best_perp = 0.0
    far = 0
    far_perp = np.inf
    for i in range(k):
        perp = abs((p[i, 0] - c[0]) * up[1] - (p[i, 1] - c[1]) * up[0])
        if along[i] > 0:
            if perp < far_perp:
                far_perp = perp
                far = i
            if perp <= 1.0:
                r = np.rint(along[i] * 1e6) / 1e6
                if i0 < 0 or r > best_r or (r == best_r and perp < best_perp):
                    i0, best_r, best_perp = i, r, perp
    if i0 < 0:
        i0 = far
    ymin = np.inf
    for o in range(-w, w + 1):
        ymin = min(ymin, p[(i0 + o) % k, 1])
    best_off = 0
    best_abs = w + 1
    for o in range(-w, w + 1):
        if p[(i0 + o) % k, 1] == ymin and abs(o) < best_abs:
            best_abs = abs(o)
            best_off = o
    start = (i0 + best_off) % k
    # the closed boundary from the start, its cumulative chord lengths, repeated points dropped
    xs = np.empty(k + 1)
    ys = np.empty(k + 1)
    cum = np.empty(k + 1)
    xs[0] = p[start, 0]
    ys[0] = p[start, 1]
    cum[0] = 0.0
    n = 1
    run = 0.0
    for i in range(1, k + 1):
        q = (start + i) % k
        seg = np.hypot(p[q, 0] - p[(start + i - 1) % k, 0], p[q, 1] - p[(start + i - 1) % k, 1])
        run = seg if i == 1 else run + seg
        if seg > 1e-12:
            xs[n] = p[q, 0]
            ys[n] = p[q, 1]
            cum[n] = run
            n += 1
    total = cum[n - 1]
    out = np.zeros((m, 2))
    if not total > 0.0:
        return start, total, out
    step = total / m
    j = 0
    for i in range(m):
        s = np.float64(i) * step
        while j + 1 < n and cum[j + 1] <= s:
            j += 1
        if j == n - 1 or cum[j] == s:
            out[i, 0] = xs[j]
            out[i, 1] = ys[j]
        else:
            d = s - cum[j]
            out[i, 0] = (xs[j + 1] - xs[j]) / (cum[j + 1] - cum[j]) * d + xs[j]
            out[i, 1] = (ys[j + 1] - ys[j]) / (cum[j + 1] - cum[j]) * d + ys[j]
    return start, total, out


@numba.njit(**_JIT)
def overlap_counts(comp: np.ndarray, crop: np.ndarray, x0: int, y0: int, n: int) -> np.ndarray:
    """Pixels of each region under a mask placed in the frame: counts[r] = #{p : crop[p] and
    comp[p + (y0, x0)] = r} over the part of the crop inside the frame
    (``np.bincount(comp[window][crop_window], minlength=n)``).

    Parameters
    ----------
    comp : ndarray of shape (H, W), dtype uint16 or int32
        Region labels in [0, n).
    crop : ndarray of shape (h, w), dtype bool
        The mask, its top-left pixel at (x0, y0) of the frame (either may be off the frame).
    x0, y0 : int
        The crop's position, pixels.
    n : int
        Number of regions.

    Returns
    -------
    ndarray of shape (n,), dtype int64
        The counts.
    """
    h_img, w_img = comp.shape
    ch, cw = crop.shape
    out = np.zeros(n, np.int64)
    for yy in range(max(y0, 0), min(y0 + ch, h_img)):
        for xx in range(max(x0, 0), min(x0 + cw, w_img)):
            if crop[yy - y0, xx - x0]:
                out[comp[yy, xx]] += 1
    return out


@numba.njit(**_JIT)
def mask_moments(crop: np.ndarray) -> tuple[float, float, float]:
    """A mask's raw moments m00, m10, m01 (pixel count and sums of x and of y, whole numbers):
    the same values as ``cv2.moments(crop, binaryImage=True)``'s, exact in float64.

    Parameters
    ----------
    crop : ndarray of shape (h, w), dtype bool
        The mask.

    Returns
    -------
    m00, m10, m01 : float
        Count, sum of x, sum of y over the set pixels.
    """
    h, w = crop.shape
    n = 0
    sx = 0
    sy = 0
    for y in range(h):
        for x in range(w):
            if crop[y, x]:
                n += 1
                sx += x
                sy += y
    return float(n), float(sx), float(sy)


@numba.njit(**_JIT)
def leg_ncc(flat: np.ndarray, sh: np.ndarray, frame: np.ndarray, background: np.ndarray, r: int) -> np.ndarray:
    """The body-shadow leg step's correlation at the pixels ``flat``.

    Each over its (2r+1) x (2r+1) window's shadow pixels (read across the frame's edges as
    ``cv2.BORDER_REFLECT`` pads): with m the window's shadow indicator, n = sum m, E the
    background's grey level and I the frame's (b + g + r):

        m(E) = sum m E / n,  var(E) = sum m E^2 / n - m(E)^2   (the same for I),
        cov = sum m I E / n - m(I) m(E),
        NCC = cov / sqrt(max(var(I), 0) max(var(E), 0) + 1e-6).

    Float64 window sums, one pass per pixel: the numpy formulation it replaces took float32 box
    filters of the region's box, centred on its means, so the two agree to float32 rounding.

    Parameters
    ----------
    flat : ndarray of shape (K,), dtype int64
        Flat pixel indices.
    sh : ndarray of shape (H, W), dtype uint8
        Non-zero on the shadow pixels.
    frame : ndarray of shape (H, W, 3), dtype uint8
        The frame.
    background : ndarray of shape (H, W), dtype float32
        The background's grey levels E.
    r : int
        Half the window side.

    Returns
    -------
    ndarray of shape (K,), dtype float64
        NCC at each pixel.
    """
    h, w = sh.shape
    out = np.empty(flat.size, np.float64)
    for i in range(flat.size):
        p = flat[i]
        y = p // w
        x = p - y * w
        n = 0
        se = 0.0
        see = 0.0
        si = 0.0
        sii = 0.0
        sie = 0.0
        for dy in range(-r, r + 1):
            yy = _reflect_index(y + dy, h)
            for dx in range(-r, r + 1):
                xx = _reflect_index(x + dx, w)
                if sh[yy, xx] != 0:
                    ev = np.float64(background[yy, xx])
                    g = np.float64(np.int64(frame[yy, xx, 0]) + np.int64(frame[yy, xx, 1]) + np.int64(frame[yy, xx, 2]))
                    n += 1
                    se += ev
                    see += ev * ev
                    si += g
                    sii += g * g
                    sie += g * ev
        inv_n = 1.0 / max(n, 1)
        me = se * inv_n
        ve = see * inv_n - me * me
        out[i] = _window_ncc(inv_n, me, ve, si, sii, sie)
    return out


def _warm_calls() -> list[Callable[[], object]]:
    """One call a kernel (the three that learn the samples together: they share ``learnable``'s
    output), on tiny inputs of the argument types the models pass; the costliest to compile first,
    so that every ``parts``-th of them from any start (:func:`warm`) takes about as long.
    """
    h, w, n = 2, 4, 3
    npx = h * w
    samples = np.zeros((npx, 3 * n), np.uint8)
    box = np.zeros((npx, 8), np.uint8)
    px = np.zeros((npx, 3), np.uint8)
    labels = np.zeros(npx, np.uint8)
    f32 = np.zeros(npx, np.float32)
    idx = np.arange(2, dtype=np.int64)
    one, zero = np.float32(1.0), np.float32(0.0)
    terms = (samples, box, f32, f32, one, one, one, 2)
    offsets = np.zeros(1, np.int64)
    pts = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    # the tracker's masks: whole arrays (compares) and crops of them (views)
    crop = np.ones((h, 2 * w), bool)
    crops = (crop, crop[:, ::2])

    def learning() -> None:
        cand = learnable(idx, labels, f32.copy(), one)
        learn_own(samples, box, f32.copy(), px, cand, idx, one, True)
        learn_neighbours(samples, box, px, cand, idx, idx, h, w, labels, f32.copy(), one)

    def overlaps() -> None:
        for c in crops:
            for comp in (np.zeros((h, w), np.uint16), np.zeros((h, w), np.int32)):
                overlap_counts(comp, c, -1, 0, 1)

    planes = [np.zeros(npx, np.uint8) for _ in range(3)] + [np.zeros(npx, np.float32) for _ in range(12)]
    return [
        learning,
        lambda: leg_pixels(
            np.zeros((1, 1, 2), np.int32),
            labels.reshape(h, w),
            np.zeros((h, w), np.int32),
            idx,
            idx,
            np.zeros((h, w), bool),
            True,
            0.1,
            0.05,
            0.15,
        ),
        lambda: feedback(f32.copy(), labels.copy(), idx, idx, h, w, offsets, offsets, offsets, offsets, zero, one, one),
        overlaps,
        lambda: head_first_samples(pts, pts[0], pts[1], pts[:, 0].copy(), 2, 4),
        lambda: texture_ncc(
            idx,
            labels.reshape(h, w),
            np.uint8(1),
            np.zeros((h + 2, w + 2), np.float32),
            np.zeros((3, h, w), np.float32),
            one,
            np.zeros((h, w, 3), np.uint8),
            1,
        ),
        lambda: explained(idx, px, *terms),
        # the background's grey levels: a view into the padded array (``HorprasertBackground.grey_``)
        lambda: leg_ncc(
            idx,
            labels.reshape(h, w),
            np.zeros((h, w, 3), np.uint8),
            np.zeros((h + 2, w + 2), np.float32)[1:-1, 1:-1],
            1,
        ),
        lambda: advance_still(
            np.zeros(npx, np.uint16), np.zeros((3, npx), np.float32), px, np.ones((3, npx), np.float32), idx, one
        ),
        lambda: veto(labels, px, *terms),
        lambda: shadow_masks(labels.reshape(h, w), np.uint8(1), np.uint8(2)),
        lambda: classify(*planes, labels.copy(), f32.copy()),
        lambda: region_rows(np.zeros(npx, np.int32), idx, w, 1),
        lambda: [mask_moments(c) for c in crops],
    ]


def warm(part: int = 0, parts: int = 1) -> None:
    """Load (or, on the first run of an install, compile) every kernel for the argument types the
    models pass, on tiny inputs: called when a model is fitted, so that the first frames after
    the training do not wait for it (tens of ms from the cache, seconds to compile).

    Parameters
    ----------
    part, parts : int, default=0, 1
        Only every ``parts``-th kernel from the ``part``-th: an install's first compile shared
        between ``parts`` processes, each caching what it compiles.

    Raises
    ------
    ValueError
        If ``part`` is not one of ``range(parts)``.
    """
    if not 0 <= part < parts:
        raise ValueError(f"part {part} of {parts}: must be one of 0..{parts - 1}")
    for call in _warm_calls()[part::parts]:
        call()
