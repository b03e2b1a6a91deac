"""The compiled kernels of the background models equal the numpy formulations they replace.

Each reference below is the numpy code the kernel replaced (the models' methods before the
kernels), run on random inputs; the kernel's outputs must be bit-identical.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from counterpart.nodes.silhouette import kernels
from counterpart.nodes.silhouette.background import BACKGROUND

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


def test_background_is_zero_as_the_kernels_take_it() -> None:
    assert BACKGROUND == 0


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
