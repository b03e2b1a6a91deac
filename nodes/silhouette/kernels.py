"""Compiled per-pixel kernels of the background models (numba).

The models' per-frame steps were chains of numpy and OpenCV calls, each a pass over the frame or
over a few thousand gathered pixels: about a thousand calls a frame, each short, and the two
threads of the extractor (the caller and the models' worker) took turns on the GIL between them.
Here a step is one compiled loop that visits each pixel once and holds no GIL (``nogil=True``),
so the worker's learning runs truly beside the caller. ``cache=True``: the compile happens once
per install, a process only loads it.

Every kernel does the same integer and float32 operations, in the same order, as the numpy
formulation it replaces (numba without fastmath follows IEEE), so the outputs are bit-identical;
the tests check each against that formulation on random inputs.
"""

from __future__ import annotations

import numba
import numpy as np

#: 8-neighbourhood offsets (dy, dx) of ViBe's spatial diffusion, in the order of the draws
NEIGHBOUR_DY = np.array([-1, -1, -1, 0, 0, 1, 1, 1], np.int64)
NEIGHBOUR_DX = np.array([-1, 0, 1, -1, 1, -1, 0, 1], np.int64)

_JIT = {"cache": True, "nogil": True}


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


@numba.njit(**_JIT)
def _touch(samples: np.ndarray, box: np.ndarray, pixels: np.ndarray, m: int) -> int:
    """Read the first and last byte of the sample row and the box of the first m ``pixels``, and
    return a sum that keeps the reads. Why: the pixels are random, and their rows mostly miss
    the caches; these loads are independent of each other, so the processor overlaps their
    misses, where the long loop body of the update that follows would take them one by one.
    """
    t = 0
    last = samples.shape[1] - 1
    for i in range(m):
        p = pixels[i]
        t += samples[p, 0] + samples[p, last] + box[p, 0]
    return t


@numba.njit(**_JIT)
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
    _touch(samples, box, cand, m)
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
    _touch(samples, box, nb, m)
    for t in range(m):
        i = at[t]
        _put(samples, box, nb[t], k[i], px[cand[i]], n)
