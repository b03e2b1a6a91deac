"""The compiled kernels of the background models equal the numpy formulations they replace.

Each reference below is the numpy code the kernel replaced (the models' methods before the
kernels), run on random inputs; the kernel's outputs must be bit-identical (``texture_ncc``
alone sums in float64: it must agree to float32 rounding, see its test).
"""

from __future__ import annotations

import json
import subprocess
import sys

import cv2
import numpy as np
import pytest

from counterpart.body import spline
from counterpart.nodes.silhouette import kernels, pipeline, regions
from counterpart.nodes.silhouette import samples as samples_mod
from counterpart.nodes.silhouette.background import BACKGROUND, FOREGROUND, HIGHLIGHT, SHADOW, distortions

H, W, N = 24, 32, 20


def _set_box_ref(samples: np.ndarray, box: np.ndarray, pixels: np.ndarray) -> None:
    n = samples.shape[1] // 3
    rows = cv2.transpose(np.take(samples, pixels, axis=0).reshape(-1, n))
    b = np.zeros((pixels.size, 8), np.uint8)
    b[:, :3] = rows.min(axis=0).reshape(-1, 3)
    b[:, 4:7] = rows.max(axis=0).reshape(-1, 3)
    box[pixels] = b


def _write_ref(samples: np.ndarray, box: np.ndarray, pixels: np.ndarray, k: np.ndarray, colours: np.ndarray) -> None:
    n = samples.shape[1] // 3
    flat = samples.reshape(-1)
    at = pixels * (3 * n) + k
    for c in range(3):
        flat[at] = colours[:, c]
        at += n
    _set_box_ref(samples, box, pixels)


def _learnable_ref(cand: np.ndarray, labels: np.ndarray, blink: np.ndarray, level: float) -> np.ndarray:
    return cand[(labels[cand] == BACKGROUND) | (blink[cand] >= level)]


def _state(seed: int) -> tuple[np.ndarray, ...]:
    rng = np.random.default_rng(seed)
    samples = rng.integers(0, 256, (H * W, 3 * N), dtype=np.uint8)
    box = np.zeros((H * W, 8), np.uint8)
    _set_box_ref(samples, box, np.arange(H * W))
    spread = (rng.random(H * W) * 30).astype(np.float32)
    px = rng.integers(0, 256, (H * W, 3), dtype=np.uint8)
    labels = rng.integers(0, 4, H * W).astype(np.uint8)
    blink = (rng.random(H * W) * 1.5).astype(np.float32)
    # many repeats: a pixel drawn twice must keep the last of its writes, as numpy's scatter does
    cand = rng.integers(0, H * W, 3000)
    k = rng.integers(0, N, cand.size)
    j = rng.integers(0, 8, cand.size)
    return samples, box, spread, px, labels, blink, cand, k, j


def test_the_class_codes_are_those_the_kernels_take() -> None:
    assert (BACKGROUND, SHADOW, HIGHLIGHT, FOREGROUND) == (0, 1, 2, 3)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_learnable_equals_the_numpy_selection(seed: int) -> None:
    _, _, _, _, labels, blink, cand, _, _ = _state(seed)
    got = kernels.learnable(cand, labels, blink, np.float32(0.7))
    np.testing.assert_array_equal(got, _learnable_ref(cand, labels, blink, np.float32(0.7)))


@pytest.mark.parametrize("follow", [True, False])
@pytest.mark.parametrize("seed", [0, 1])
def test_learn_own_equals_the_spread_then_write_in_numpy(seed: int, follow: bool) -> None:
    samples, box, spread, px, _, _, cand, k, _ = _state(seed)
    rate = np.float32(0.1)
    ref_s, ref_b, ref_d = samples.copy(), box.copy(), spread.copy()
    colours = np.take(px, cand, axis=0)
    if follow:
        rows = np.take(ref_s, cand, axis=0)
        gap = cv2.reduce(cv2.absdiff(rows, np.repeat(colours, N, axis=1)), 1, cv2.REDUCE_SUM, dtype=cv2.CV_32S)
        d = ref_d[cand]
        d += rate * (gap[:, 0].astype(np.float32) / np.float32(N) - d)
        ref_d[cand] = d
    _write_ref(ref_s, ref_b, cand, k, colours)
    kernels.learn_own(samples, box, spread, px, cand, k, rate, follow)
    np.testing.assert_array_equal(samples, ref_s)
    np.testing.assert_array_equal(box, ref_b)
    np.testing.assert_array_equal(spread, ref_d)


@pytest.mark.parametrize("seed", [0, 1])
def test_learn_neighbours_equals_the_diffusion_in_numpy(seed: int) -> None:
    samples, box, _, px, labels, blink, cand, k, j = _state(seed)
    level = np.float32(0.5)
    ref_s, ref_b = samples.copy(), box.copy()
    colours = np.take(px, cand, axis=0)
    y, x = np.divmod(cand, W)
    y = np.clip(y + kernels.NEIGHBOUR_DY[j], 0, H - 1)
    x = np.clip(x + kernels.NEIGHBOUR_DX[j], 0, W - 1)
    nb = y * W + x
    ok = (labels[nb] == BACKGROUND) | (blink[nb] >= level)
    _write_ref(ref_s, ref_b, nb[ok], k[ok], colours[ok])
    kernels.learn_neighbours(samples, box, px, cand, k, j, H, W, labels, blink, level)
    np.testing.assert_array_equal(samples, ref_s)
    np.testing.assert_array_equal(box, ref_b)


def _classify_ref(frame: np.ndarray, w: np.ndarray, inv_var: np.ndarray, inv_den: np.ndarray, th: dict) -> tuple:
    """``distortions`` and ``classify`` as they were in OpenCV calls."""
    planes = [p.astype(np.float32) for p in cv2.split(frame)]
    alpha, cd2 = distortions(planes, w, inv_var, inv_den)
    labels = cv2.add(cv2.bitwise_and(cv2.compare(alpha, 1.0, cv2.CMP_GE), 1), SHADOW)
    band = cv2.bitwise_and(cv2.compare(alpha, th["hi"], cv2.CMP_LT), cv2.compare(alpha, th["lo"], cv2.CMP_GT))
    cv2.bitwise_and(labels, cv2.bitwise_not(band), dst=labels)
    fg = cv2.bitwise_or(cv2.compare(cd2, th["cd2"], cv2.CMP_GT), cv2.compare(alpha, th["min"], cv2.CMP_LT))
    cv2.bitwise_or(fg, cv2.compare(alpha, th["max"], cv2.CMP_GT), dst=fg)
    cv2.bitwise_or(labels, cv2.bitwise_and(fg, FOREGROUND), dst=labels)
    return labels, alpha


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_classify_equals_the_distortions_and_thresholds_in_opencv(seed: int) -> None:
    rng = np.random.default_rng(seed)
    h, w = 48, 64
    mu = rng.uniform(0, 255, (3, h, w)).astype(np.float32)
    mu[:, 0, :4] = 0.0  # black background pixels: 1 / den is 0 there
    var = rng.uniform(1, 200, (3, h, w)).astype(np.float32)
    inv_var = (np.float32(1.0) / var).astype(np.float32)
    wt = (mu * inv_var).astype(np.float32)
    den = (mu[0] * wt[0] + mu[1] * wt[1] + mu[2] * wt[2]).astype(np.float32)
    inv_den = np.where(den > 1e-6, np.float32(1.0) / np.maximum(den, 1e-6), 0).astype(np.float32)
    # frames near the background (all classes occur) and exactly on it (alpha 1, CD^2 0)
    frame = np.clip(mu.transpose(1, 2, 0) * rng.uniform(0.4, 1.6, (h, w, 1)) + rng.normal(0, 6, (h, w, 3)), 0, 255)
    frame = frame.astype(np.uint8)
    frame[-4:] = np.rint(mu.transpose(1, 2, 0)[-4:]).astype(np.uint8)
    a = rng.uniform(0.02, 0.1, (h, w)).astype(np.float32)
    th = {"hi": (1 + 2 * a).astype(np.float32), "lo": (1 - 2 * a).astype(np.float32)}
    th["min"] = np.minimum(np.float32(0.5), th["lo"]).astype(np.float32)
    th["max"] = np.maximum(np.float32(1.4), th["hi"]).astype(np.float32)
    th["cd2"] = rng.uniform(0.5, 40, (h, w)).astype(np.float32)
    want_labels, want_alpha = _classify_ref(frame, wt, inv_var, inv_den, th)
    labels, alpha = np.empty((h, w), np.uint8), np.empty((h, w), np.float32)
    flat = [a.reshape(-1) for a in (*cv2.split(frame), *wt, *inv_var, inv_den)]
    flat += [th[k].reshape(-1) for k in ("hi", "lo", "min", "max", "cd2")]
    kernels.classify(*flat, labels.reshape(-1), alpha.reshape(-1))
    np.testing.assert_array_equal(alpha, want_alpha)
    np.testing.assert_array_equal(labels, want_labels)
    assert set(np.unique(labels)) == {0, 1, 2, 3}


def _explained_ref(idx, px, samples, box, blink, spread, radius, spread_k, rel, min_matches) -> np.ndarray:
    """``SampleConsensus.explained`` as it was in numpy and OpenCV calls."""
    n = samples.shape[1] // 3
    colours = np.take(px, idx, axis=0)
    gain = 1.0 / (1.0 + np.take(blink, idx))
    base = np.float32(radius)
    if spread_k > 0.0:
        base = np.maximum(base, np.float32(spread_k) * np.take(spread, idx))
    b = np.take(box, idx, axis=0)
    gap = cv2.add(cv2.subtract(b[:, :3], colours), cv2.subtract(colours, b[:, 4:7]))
    near = np.add(gap[:, 0], gap[:, 1], dtype=np.int16)
    near += gap[:, 2]
    top = np.add(b[:, 4], b[:, 5], dtype=np.int16)
    top += b[:, 6]
    near = near * gain
    near -= np.float32(rel) * top
    near *= np.float32(1.0 - 1e-4)
    near = np.flatnonzero(near < base + np.float32(1e-3))
    out = np.zeros(idx.size, bool)
    if near.size == 0:
        return out
    idx, colours, gain = idx[near], colours[near], gain[near]
    if np.ndim(base):
        base = base[near]
    rows = np.take(samples, idx, axis=0)
    diff = cv2.absdiff(rows, np.repeat(colours, n, axis=1))
    dist = np.add(diff[:, :n], diff[:, n : 2 * n], dtype=np.int16)
    dist += diff[:, 2 * n :]
    total = np.add(rows[:, :n], rows[:, n : 2 * n], dtype=np.int16)
    total += rows[:, 2 * n :]
    lhs = dist * gain[:, None]
    lhs -= np.float32(rel) * total
    out[near] = np.einsum("ij->i", (lhs < np.reshape(base, (-1, 1))).view(np.uint8)) >= min_matches
    return out


@pytest.mark.parametrize("spread_k", [0.0, 0.75])
@pytest.mark.parametrize("seed", [0, 1])
def test_explained_and_veto_equal_the_consensus_in_numpy(seed: int, spread_k: float) -> None:
    rng = np.random.default_rng(seed)
    p = H * W
    base = rng.integers(20, 230, (p, 3, 1))
    samples = np.clip(base + rng.integers(-6, 7, (p, 3, N)), 0, 255).astype(np.uint8).reshape(p, 3 * N)
    box = np.zeros((p, 8), np.uint8)
    _set_box_ref(samples, box, np.arange(p))
    # colours near their samples (matches, near misses) and far from them
    px = np.clip(base[:, :, 0] + rng.integers(-12, 13, (p, 3)) * rng.integers(1, 4, (p, 1)), 0, 255).astype(np.uint8)
    blink = (rng.random(p) * 1.5 * (rng.random(p) < 0.5)).astype(np.float32)
    spread = (rng.random(p) * 12).astype(np.float32)
    terms = (samples, box, blink, spread, np.float32(0.5), np.float32(spread_k), np.float32(0.025), 2)
    idx = np.sort(rng.choice(p, p // 2, replace=False))
    want = _explained_ref(idx, px, *terms)
    assert 0 < want.sum() < want.size
    np.testing.assert_array_equal(kernels.explained(idx, px, *terms), want)
    labels = rng.integers(0, 4, p).astype(np.uint8)
    fg = np.flatnonzero(labels == FOREGROUND)
    ok = _explained_ref(fg, px, *terms)
    want_out = labels.copy()
    want_out[fg[ok]] = BACKGROUND
    out, fg_idx = kernels.veto(labels, px, *terms)
    np.testing.assert_array_equal(out, want_out)
    np.testing.assert_array_equal(fg_idx, fg[~ok])


@pytest.mark.parametrize("seed", [0, 1])
def test_region_rows_equals_numpys_unbuffered_min_and_max(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 7
    comp = rng.integers(0, n, H * W).astype(np.int32)
    idx = np.sort(rng.choice(H * W, 200, replace=False))
    top, bottom = np.full(n, H, np.int64), np.full(n, -1, np.int64)
    np.minimum.at(top, comp[idx], idx // W)
    np.maximum.at(bottom, comp[idx], idx // W)
    got_top, got_bottom = kernels.region_rows(comp, idx, W, n)
    np.testing.assert_array_equal(got_top, top)
    np.testing.assert_array_equal(got_bottom, bottom)


@pytest.mark.parametrize("seed", [0, 1])
def test_shadow_masks_equal_opencvs_compares_or_and_the_starts(seed: int) -> None:
    rng = np.random.default_rng(seed)
    labels = rng.choice(np.array([BACKGROUND, SHADOW, HIGHLIGHT, FOREGROUND], np.uint8), (H, W), p=[0.4, 0.3, 0.1, 0.2])
    fg = cv2.compare(labels, FOREGROUND, cv2.CMP_EQ)
    sh = cv2.compare(labels, SHADOW, cv2.CMP_EQ)
    start = np.zeros_like(sh)
    cv2.bitwise_and(sh[1:], fg[:-1], dst=start[1:])
    want = cv2.findNonZero(start)
    got_fg, got_sh, got_either, got_starts = kernels.shadow_masks(labels, np.uint8(FOREGROUND), np.uint8(SHADOW))
    np.testing.assert_array_equal(got_fg, fg)
    np.testing.assert_array_equal(got_sh, sh)
    np.testing.assert_array_equal(got_either, cv2.bitwise_or(fg, sh))
    assert got_starts.dtype == want.dtype and want.shape[0] > 0
    np.testing.assert_array_equal(got_starts, want)
    # no foreground: no starts (findNonZero gives None, the kernel an empty array)
    none = kernels.shadow_masks(np.full((H, W), SHADOW, np.uint8), np.uint8(FOREGROUND), np.uint8(SHADOW))[3]
    assert none.shape == (0, 1, 2)


def _leg_pixels_ref(pts, sh, comp, top, bottom, unseen, depth, foot, width):
    """``body_shadow._legs`` before its correlation, as numpy (the code the kernel replaced)."""
    h, w = sh.shape
    sy = pts[:, 0, 1]
    sc = comp[sy, pts[:, 0, 0]]
    height_s = bottom[sc] - top[sc] + 1
    keep = (depth * height_s >= 1) & (bottom[sc] - sy > foot * height_s)
    sx, sy, sc = pts[keep, 0, 0], sy[keep], sc[keep]
    if sc.size == 0:
        return np.empty(0, np.int64), np.empty(0, np.int32)
    height_s = height_s[keep]
    reach = depth * height_s
    d = np.arange(int(reach.max()))
    ys = sy[:, None] + d
    inside = ys < h
    ys = np.minimum(ys, h - 1)
    hang = sh[ys, sx[:, None]] != 0
    hang &= inside
    np.logical_and.accumulate(hang, axis=1, out=hang)
    hang &= d + 1 <= reach[:, None]
    hang &= bottom[sc][:, None] - ys > foot * height_s[:, None]
    if unseen is not None:
        hang &= ~unseen[ys, sx[:, None]]
    si, di = np.nonzero(hang)
    if si.size == 0:
        return np.empty(0, np.int64), np.empty(0, np.int32)
    flat = np.sort((sy[si] + di) * w + sx[si])
    ys, xs = np.divmod(flat, w)
    c = comp[ys, xs]
    height = bottom[c] - top[c] + 1
    band = np.flatnonzero(np.bincount(ys))
    sr = np.zeros((band.size, w + 2), np.int8)
    sr[:, 1:-1] = sh[band] != 0
    step = np.diff(sr.ravel())
    rise, fall = np.flatnonzero(step == 1), np.flatnonzero(step == -1)
    run = np.searchsorted(rise, np.searchsorted(band, ys) * (w + 2) + xs + 1) - 1
    ok = fall[run] - rise[run] <= width * height
    return flat[ok], c[ok]


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("with_unseen", [False, True])
def test_leg_pixels_equal_the_hang_table_and_row_runs_in_numpy(seed: int, with_unseen: bool) -> None:
    rng = np.random.default_rng(seed)
    h, w = 60, 80
    # blobs of foreground with shadow below and beside them, some reaching the frame's edges
    labels = np.zeros((h, w), np.uint8)
    for _ in range(6):
        y, x = int(rng.integers(0, h - 5)), int(rng.integers(0, w - 3))
        bh, bw = int(rng.integers(5, 30)), int(rng.integers(3, 20))
        labels[y : y + bh, x : x + bw] = FOREGROUND
        sy = y + bh
        labels[
            sy : sy + int(rng.integers(1, 40)), x + int(rng.integers(-2, 3)) : x + bw + int(rng.integers(-2, 20))
        ] = SHADOW
    labels[rng.random((h, w)) < 0.05] = SHADOW  # holes and specks break runs
    fg = cv2.compare(labels, FOREGROUND, cv2.CMP_EQ)
    sh = cv2.compare(labels, SHADOW, cv2.CMP_EQ)
    n, comp = cv2.connectedComponents(cv2.bitwise_or(fg, sh), connectivity=8)
    fg_idx = np.flatnonzero(labels.ravel() == FOREGROUND)
    top, bottom = kernels.region_rows(comp.ravel(), fg_idx, w, n)
    start = np.zeros_like(sh)
    cv2.bitwise_and(sh[1:], fg[:-1], dst=start[1:])
    pts = cv2.findNonZero(start)
    assert pts is not None
    unseen = rng.random((h, w)) < 0.1 if with_unseen else None
    for depth, foot, width in [(0.1, 0.05, 0.15), (1.0, 0.0, 0.5), (0.6, 0.3, 0.05)]:
        want_flat, want_c = _leg_pixels_ref(pts, sh, comp, top, bottom, unseen, depth, foot, width)
        got_flat, got_c = kernels.leg_pixels(
            pts,
            sh,
            comp,
            top,
            bottom,
            np.zeros((1, 1), bool) if unseen is None else unseen,
            unseen is not None,
            depth,
            foot,
            width,
        )
        np.testing.assert_array_equal(got_flat, want_flat)
        np.testing.assert_array_equal(got_c, want_c)
        assert got_flat.dtype == np.int64
    assert want_flat.size > 0


def _texture_ncc_ref(idx, labels, e_pad, var, k2, frame, r):
    """``HorprasertBackground.shadow_texture_mismatch``'s sparse path before the kernel: window
    gathers and float32 einsum sums; returns (textured (K,) bool, ve (K,), floor (K,), ncc (K,)),
    ncc at every pixel (the method took only the textured ones).
    """
    h, w = labels.shape
    sh = (labels == SHADOW).view(np.uint8)
    wp = w + 2 * r
    ys, xs = np.divmod(idx, w)
    off = (np.arange(2 * r + 1)[:, None] * wp + np.arange(2 * r + 1)[None, :]).reshape(-1)
    win = (ys * wp + xs)[:, None] + off[None, :]
    m = np.take(cv2.copyMakeBorder(sh, r, r, r, r, cv2.BORDER_REFLECT).reshape(-1), win).astype(np.float32)
    e = np.take(e_pad, win)
    inv_n = 1.0 / np.maximum(np.einsum("ij->i", m), 1.0)
    em = e * m
    me = np.einsum("ij->i", em) * inv_n
    ve = np.einsum("ij,ij->i", em, e) * inv_n - me * me
    v = var.reshape(3, -1)
    floor = (v[0][idx] + v[1][idx] + v[2][idx]) * np.float32(k2)
    planes = [
        cv2.copyMakeBorder(p.astype(np.float32), r, r, r, r, cv2.BORDER_REFLECT).reshape(-1) for p in cv2.split(frame)
    ]
    grey = np.take(planes[0], win) + np.take(planes[1], win)
    grey += np.take(planes[2], win)
    gm = grey * m
    mi = np.einsum("ij->i", gm) * inv_n
    vi = np.einsum("ij,ij->i", gm, grey) * inv_n - mi * mi
    cov = np.einsum("ij,ij->i", gm, e) * inv_n - mi * me
    ncc = cov / np.sqrt(np.maximum(vi, 0.0) * np.maximum(ve, 0.0) + 1e-6)
    return ve > floor, ve, floor, ncc


@pytest.mark.parametrize("seed", range(4))
def test_texture_ncc_equals_the_window_sums_in_numpy_to_float32_rounding(seed: int) -> None:
    rng = np.random.default_rng(seed)
    h, w, r = 24, 31, 3
    # shadow in blobs and speckle, to the frame's edges (the windows read across them)
    labels = rng.choice(np.array([BACKGROUND, SHADOW, FOREGROUND], np.uint8), (h, w), p=[0.3, 0.5, 0.2])
    labels[rng.random((h, w)) < 0.2] = SHADOW
    e = (rng.random((h, w)) * 600.0).astype(np.float32)
    e[:, : w // 2] = cv2.GaussianBlur(e, (0, 0), 3.0)[:, : w // 2]  # half of it smooth: untextured
    e_pad = cv2.copyMakeBorder(e, r, r, r, r, cv2.BORDER_REFLECT)
    var = (rng.random((3, h, w)) * 60.0 + 1.0).astype(np.float32)
    # the frame: a dimmed copy of E's texture with noise in one half, unrelated in the other
    base = np.clip(e / 3.0 * 0.6 + rng.normal(0.0, 3.0, (h, w)), 0, 255)
    base[h // 2 :] = rng.random((h - h // 2, w)) * 255
    frame = np.repeat(base[:, :, None], 3, axis=2).astype(np.uint8)
    idx = np.flatnonzero(labels == SHADOW)
    k2 = np.float32(8.0**2)
    textured, ve, floor, ncc_ref = _texture_ncc_ref(idx, labels, e_pad, var, k2, frame, r)
    got = kernels.texture_ncc(idx, labels, np.uint8(SHADOW), e_pad, var, k2, frame, r)
    assert got.shape == idx.shape and 0 < textured.sum() < textured.size
    # textured where the numpy test was, but for a variance within float32 rounding of its floor
    near = np.abs(ve - floor) <= 1e-5 * floor
    np.testing.assert_array_equal(np.isfinite(got)[~near], textured[~near])
    # the correlation to float32 rounding of its window sums, over both the related and the
    # unrelated half (so both sides of the 0.4 threshold are met)
    both = np.isfinite(got) & textured
    np.testing.assert_allclose(got[both], ncc_ref[both], rtol=0, atol=2e-5)
    assert (got[both] > 0.9).any() and (got[both] < 0.4).any()


def _blob_masks(seed: int) -> list[np.ndarray]:
    """Random silhouette-like masks: unions of ellipses (upright, lying, round), some touching the
    crop's edges, some in pieces; and thin lines (boundaries that run back over themselves).
    """
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(40):
        h, w = int(rng.integers(8, 120)), int(rng.integers(8, 80))
        m = np.zeros((h, w), np.uint8)
        for _ in range(int(rng.integers(1, 5))):
            centre = (int(rng.integers(0, w)), int(rng.integers(0, h)))
            axes = (int(rng.integers(1, w // 2 + 2)), int(rng.integers(1, h // 2 + 2)))
            cv2.ellipse(m, centre, axes, float(rng.uniform(0, 180)), 0, 360, 1, -1)
        m[rng.random((h, w)) < 0.03] ^= 1
        out.append(m.astype(bool))
    for pts in ([(0, 0), (5, 5)], [(2, 0), (2, 9)], [(0, 3), (9, 3)], [(1, 1), (3, 1)]):
        m = np.zeros((12, 12), np.uint8)
        cv2.line(m, *pts, 1)
        out.append(m.astype(bool))
    return out


@pytest.mark.parametrize("seed", range(3))
def test_compiled_spline_equals_body_splines_numpy_fit(seed: int) -> None:
    # pipeline.silhouette_spline: the boundary ordering and resampling by head_first_samples
    fits = 0
    for mask in _blob_masks(seed):
        try:
            want_ctrl, want_ref = spline.silhouette_spline(mask, 32)
        except ValueError:
            with pytest.raises(ValueError):
                pipeline.silhouette_spline(mask, 32)
            continue
        for n in (32, 8):
            want_ctrl, want_ref = spline.silhouette_spline(mask, n)
            got_ctrl, got_ref = pipeline.silhouette_spline(mask, n)
            np.testing.assert_array_equal(got_ctrl, want_ctrl)
            np.testing.assert_array_equal(got_ref, want_ref)
        fits += 1
    assert fits >= 30
    with pytest.raises(ValueError):
        pipeline.silhouette_spline(np.zeros((10, 10), bool))
    with pytest.raises(ValueError):
        pipeline.silhouette_spline(np.ones((10, 10), bool), 3)


def _region_masks(seed: int, h: int = H, w: int = W) -> list[np.ndarray]:
    """Foreground masks (h, w) bool: a few blobs and speckle in a random part of the frame (at its
    edges too, on odd and even rows and columns), and the empty one.
    """
    rng = np.random.default_rng(seed)
    out = [np.zeros((h, w), bool)]
    for _ in range(12):
        m = np.zeros((h, w), np.uint8)
        x0, y0 = int(rng.integers(0, w - 4)), int(rng.integers(0, h - 4))
        x1, y1 = int(rng.integers(x0 + 4, w + 1)), int(rng.integers(y0 + 4, h + 1))
        part = m[y0:y1, x0:x1]
        for _ in range(int(rng.integers(1, 6))):
            centre = (int(rng.integers(0, x1 - x0)), int(rng.integers(0, y1 - y0)))
            axes = (int(rng.integers(1, max(2, (x1 - x0) // 4))), int(rng.integers(1, max(2, (y1 - y0) // 3))))
            cv2.ellipse(part, centre, axes, float(rng.uniform(0, 180)), 0, 360, 1, -1)
        part[rng.random(part.shape) < 0.01] = 1
        out.append(m.astype(bool))
    return out


@pytest.mark.parametrize("seed", range(3))
def test_overlap_counts_and_mask_moments_equal_bincount_and_opencvs_moments(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for m in _region_masks(seed):
        n, comp, _, _ = regions.components_with_stats(m.view(np.uint8))
        for dtype in (np.uint16, np.int32):
            comp = comp.astype(dtype)
            for _ in range(5):
                # a template anywhere, partly off the frame, contiguous or a view
                big = rng.random((30, 24)) < 0.6
                crop = big[: int(rng.integers(1, 30)), : int(rng.integers(1, 24))]
                x0, y0 = int(rng.integers(-10, W)), int(rng.integers(-10, H))
                ch, cw = crop.shape
                ax0, ay0, ax1, ay1 = max(x0, 0), max(y0, 0), min(x0 + cw, W), min(y0 + ch, H)
                want = np.zeros(n, np.int64)
                if ax1 > ax0 and ay1 > ay0:
                    sub = comp[ay0:ay1, ax0:ax1][crop[ay0 - y0 : ay1 - y0, ax0 - x0 : ax1 - x0]]
                    want = np.bincount(sub, minlength=n)
                np.testing.assert_array_equal(kernels.overlap_counts(comp, crop, x0, y0, n), want)
                mo = cv2.moments(np.ascontiguousarray(crop).view(np.uint8), binaryImage=True)
                assert kernels.mask_moments(crop) == (mo["m00"], mo["m10"], mo["m01"])


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("threads", [1, 2])
def test_components_in_box_equal_those_of_the_whole_frame(seed: int, threads: int) -> None:
    # the labels' order, the stats and the centroids to the bit (row 0, the background, aside)
    before = cv2.getNumThreads()
    cv2.setNumThreads(threads)
    try:
        boxed = 0
        for m in _region_masks(seed, 120, 160):
            m8 = m.view(np.uint8)
            _, _, bw, bh = cv2.boundingRect(m8)
            boxed += 0 < bw * bh < 0.5 * m.size
            n, comp, stats, cents = regions.components_with_stats(m8)
            n2, comp2, stats2, cents2 = regions.components_in_box(m8)
            assert n2 == n and comp2.dtype == comp.dtype
            np.testing.assert_array_equal(comp2, comp)
            np.testing.assert_array_equal(stats2[1:], stats[1:])
            np.testing.assert_array_equal(cents2[1:], cents[1:])
        assert boxed >= 4
    finally:
        cv2.setNumThreads(before)


def _leg_ncc_ref(flat, sh, frame, background, r):
    """The leg step's scale-1 correlation before ``kernels.leg_ncc``: float32 box filters
    (BORDER_REFLECT) over the candidates' box, centred on its means.
    """
    h, w = sh.shape
    gy, gx = np.divmod(flat, w)
    by0, by1 = max(int(gy.min()) - r, 0), min(int(gy.max()) + r + 1, h)
    bx0, bx1 = max(int(gx.min()) - r, 0), min(int(gx.max()) + r + 1, w)
    k = (2 * r + 1, 2 * r + 1)
    at = (gy - by0, gx - bx0)

    def box(a):
        return cv2.boxFilter(a, -1, k, normalize=False, borderType=cv2.BORDER_REFLECT)[at]

    m = (sh[by0:by1, bx0:bx1] != 0).astype(np.float32)
    grey = cv2.transform(frame[by0:by1, bx0:bx1].astype(np.float32), np.ones((1, 3), np.float32))
    e = background[by0:by1, bx0:bx1]
    grey -= np.float32(grey.mean())
    e = e - np.float32(e.mean())
    inv_n = 1.0 / np.maximum(box(m), 1.0)
    em, gm = e * m, grey * m
    me, mi = box(em) * inv_n, box(gm) * inv_n
    ve = box(em * e) * inv_n - me * me
    vi = box(gm * grey) * inv_n - mi * mi
    cov = box(gm * e) * inv_n - mi * me
    return cov / np.sqrt(np.maximum(vi, 0.0) * np.maximum(ve, 0.0) + 1e-6)


@pytest.mark.parametrize("seed", range(4))
def test_leg_ncc_equals_the_box_filters_in_opencv_to_float32_rounding(seed: int) -> None:
    rng = np.random.default_rng(seed)
    h, w, r = 40, 36, 3
    sh = np.where(rng.random((h, w)) < 0.6, 255, 0).astype(np.uint8)
    background = (rng.random((h, w)) * 700.0).astype(np.float32)
    # the frame: a dimmed copy of the background's texture on the left, unrelated on the right
    base = np.clip(background / 3.0 * 0.5 + rng.normal(0.0, 4.0, (h, w)), 0, 255)
    base[:, w // 2 :] = rng.random((h, w - w // 2)) * 255
    frame = np.repeat(base[:, :, None], 3, axis=2).astype(np.uint8)
    # a background view into a padded array, as the model hands it over
    padded = cv2.copyMakeBorder(background, 2, 2, 2, 2, cv2.BORDER_REFLECT)
    view = padded[2:-2, 2:-2]
    # candidates over the whole frame (its edges too) and in a corner box
    for flat in (np.sort(rng.choice(h * w, 60, replace=False)), np.array([0, 1, w, w + 1, 2 * w + 3], np.int64)):
        flat = flat.astype(np.int64)
        want = _leg_ncc_ref(flat, sh, frame, background, r)
        got = kernels.leg_ncc(flat, sh, frame, view, r)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-5)
    assert (got > 0.5).any() or (want > 0.5).any()


@pytest.mark.parametrize("absorb_k", [4.0, 2.3])
def test_advance_still_equals_the_still_runs_in_numpy(absorb_k: float) -> None:
    rng = np.random.default_rng(3)
    p = H * W
    still = rng.integers(0, 5, p).astype(np.uint16)
    still[:3] = 65535  # a run at its longest wraps as numpy's uint16 does
    ref = rng.uniform(0, 255, (3, p)).astype(np.float32)
    px = np.clip(ref.T + rng.normal(0, 12, (p, 3)), 0, 255).astype(np.uint8)
    inv_s = (1.0 / rng.uniform(2, 8, (3, p))).astype(np.float32)
    idx = np.sort(rng.choice(p, p // 3, replace=False))
    idx[:3] = [0, 1, 2]
    idx = np.unique(idx)
    # numpy, as ``HorprasertBackground._advance_still_runs`` was
    w_still, w_ref = still.copy(), ref.copy()
    prev = w_still[idx]
    w_still.fill(0)
    obs = np.take(px, idx, axis=0).T.astype(np.float32)
    refs = np.take(w_ref, idx, axis=1)
    dev = np.abs(obs - refs)
    dev *= np.take(inv_s, idx, axis=1)
    n = np.where((prev > 0) & (dev.max(axis=0) <= absorb_k), prev + 1, 1).astype(np.uint16)
    w_still[idx] = n
    obs -= refs
    with np.errstate(divide="ignore", invalid="ignore"):  # the wrapped run: n = 0
        obs *= 1.0 / n.astype(np.float32)
    refs += obs
    for c in range(3):
        w_ref[c][idx] = refs[c]
    assert 0 < np.count_nonzero(n > 1) < n.size
    got_n, got_refs = kernels.advance_still(still, ref, px, inv_s, idx, np.float32(absorb_k))
    np.testing.assert_array_equal(got_n, n)
    np.testing.assert_array_equal(got_refs, refs)
    np.testing.assert_array_equal(still, w_still)
    np.testing.assert_array_equal(ref, w_ref)


def _feedback_ref(v, prev_fg, prev_idx, fg_idx, h, w, decay, gain, top) -> np.ndarray:
    """``SampleConsensus._feedback`` as it was in numpy and OpenCV calls; returns the new mask."""
    fg = np.zeros((h, w), np.uint8)
    fg.reshape(-1)[fg_idx] = 1
    prev = prev_fg.reshape(h, w)
    vv = v.reshape(h, w)
    np.subtract(vv, np.float32(decay), out=vv)
    both = np.concatenate((fg_idx, prev_idx))
    if both.size:
        ys, xs = np.divmod(both, w)
        y0, y1 = max(0, int(ys.min()) - 4), min(h, int(ys.max()) + 5)
        x0, x1 = max(0, int(xs.min()) - 4), min(w, int(xs.max()) + 5)
        fg_c, prev_c = fg[y0:y1, x0:x1], prev[y0:y1, x0:x1]
        blink = cv2.compare(fg_c, prev_c, cv2.CMP_NE)
        solid = cv2.dilate(cv2.morphologyEx(prev_c, cv2.MORPH_OPEN, samples_mod._OPEN), samples_mod._NEAR)
        cv2.bitwise_and(blink, cv2.compare(solid, 0, cv2.CMP_EQ), dst=blink)
        vc = vv[y0:y1, x0:x1]
        cv2.add(vc, float(np.float32(gain + decay)), dst=vc, mask=blink)
        cv2.min(vc, float(np.float32(top)), dst=vc)
    cv2.max(vv, 0.0, dst=vv)
    return fg.reshape(-1)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_feedback_equals_the_masks_and_morphology_in_opencv(seed: int) -> None:
    rng = np.random.default_rng(seed)
    h, w = 40, 56
    v = (rng.random(h * w) * 1.6).astype(np.float32)
    v[rng.random(h * w) < 0.3] = 0.0
    masks = []
    for _ in range(5):
        # solid blobs that move (some at the frame's edges) and speckle
        m = np.zeros((h, w), np.uint8)
        for _ in range(3):
            y, x = rng.integers(-4, h), rng.integers(-4, w)
            m[max(y, 0) : y + rng.integers(3, 15), max(x, 0) : x + rng.integers(3, 12)] = 1
        m[rng.random((h, w)) < 0.05] = 1
        masks.append(m.reshape(-1))
    masks += [np.zeros(h * w, np.uint8)] * 2  # no foreground, then none in either frame
    prev_ref = np.zeros(h * w, np.uint8)
    prev_idx = np.zeros(0, np.int64)
    v_ref, prev_k = v.copy(), prev_ref.copy()
    args = (*samples_mod._OFFSETS, np.float32(0.005), np.float32(0.105), np.float32(1.5))
    for m in masks:
        fg_idx = np.flatnonzero(m)
        prev_ref = _feedback_ref(v_ref, prev_ref, prev_idx, fg_idx, h, w, 0.005, 0.1, 1.5)
        prev_k = kernels.feedback(v, prev_k, prev_idx, fg_idx, h, w, *args)
        prev_idx = fg_idx
        np.testing.assert_array_equal(prev_k, prev_ref)
        np.testing.assert_array_equal(v, v_ref)
    assert np.count_nonzero(v) > 0


def test_warm_runs_every_kernel_on_the_models_argument_types() -> None:
    kernels.warm()
    for name in ("learnable", "learn_own", "learn_neighbours", "classify", "explained", "veto"):
        assert getattr(kernels, name).signatures, name
    for name in (
        "region_rows",
        "shadow_masks",
        "leg_pixels",
        "advance_still",
        "feedback",
        "texture_ncc",
        "head_first_samples",
    ):
        assert getattr(kernels, name).signatures, name


def test_the_parts_of_warm_share_out_every_kernel_once() -> None:
    # a process of its own: in this one the earlier tests have run the kernels already
    code = """
import json
import numba
from counterpart.nodes.silhouette import kernels as k

jit = {n: f for n, f in vars(k).items() if isinstance(f, numba.core.registry.CPUDispatcher)}
kernels = sorted(n for n, f in jit.items() if f.targetoptions.get("inline") != "always")
ran = lambda: {n for n, f in jit.items() if f.signatures}
k.warm(0, 2)
first = ran()
k.warm(1, 2)
print(json.dumps([kernels, sorted(first), sorted(ran() - first)]))
"""
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr[-2000:]
    every, first, second = json.loads(res.stdout.strip().splitlines()[-1])
    assert first and second and not set(first) & set(second)
    assert sorted(first + second) == every  # each kernel in one part, the helpers inlined into them
    with pytest.raises(ValueError, match="part 2 of 2"):
        kernels.warm(2, 2)
