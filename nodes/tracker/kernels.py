"""Compiled kernel of the tracker's likelihood: the image costs of N poses in one pass per pose.

``cone_image_costs`` fuses what ``likelihood.ConeLikelihood.image_costs`` and
``likelihood.evaluate_joint`` did as a dozen numpy calls over (N, S, K) and (N, S, M) arrays
(projection of the anchors, the cones' sample points, the gather from the cost maps, the coverage
test): at the few hundred particles of a real-time frame the cost of those calls and of their
temporaries, not the arithmetic, dominated.

The kernel repeats the numpy formulation operation by operation in float32, so that its costs are
those of the numpy code to the last bit: numba compiles without fast-math (no multiply and add is
fused behind our back); the small matrix products of the numpy code (``pts @ R.T``, the sample
points' ``F @ G``, the coverage test's ``F @ G``), which OpenBLAS's float32 kernels accumulate as
a chain of fused multiply-adds in the order of the inner index, are written as that chain
(``_fma``); the means are summed in numpy's pairwise order (``_pairwise_sum``). It matters: a
sample point's pixel is its rounded position, so a rounding apart would move a point by a pixel
now and then, and the particle filter would go its own way from there. (With a BLAS that sums
those products otherwise the numpy code itself would give such differences.)
"""

from __future__ import annotations

from typing import Any

import numba
import numpy as np
from llvmlite import ir
from numba.core import types
from numba.extending import intrinsic

_F32_0 = np.float32(0.0)
_F32_1 = np.float32(1.0)
#: the nearest depth in front of the camera (metres) and the shortest cone axis (pixels)
_NEAR = np.float32(0.05)
_MIN_AXIS = np.float32(1e-6)
_MIN_AA = np.float32(1e-6)
_HALF = np.float32(0.5)
_TWO = np.float32(2.0)


@intrinsic
def _fma(typingctx: Any, a: Any, b: Any, c: Any) -> tuple[Any, Any]:
    """``a * b + c`` of float32s rounded once (LLVM's ``llvm.fma.f32``: one instruction where the
    CPU has FMA, as OpenBLAS's float32 kernels use it; an exact library call where it has not).
    """
    sig = types.float32(types.float32, types.float32, types.float32)

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        f = ir.FloatType()
        return builder.call(builder.module.declare_intrinsic("llvm.fma", [f], ir.FunctionType(f, [f, f, f])), args)

    return sig, codegen


@intrinsic
def _rint(typingctx: Any, a: Any) -> tuple[Any, Any]:
    """float32 ``np.rint`` (to the nearest integer, ties to even), kept in float32 (numba's own
    ``np.rint`` goes through float64).
    """
    sig = types.float32(types.float32)

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        f = ir.FloatType()
        return builder.call(builder.module.declare_intrinsic("llvm.rint", [f], ir.FunctionType(f, [f])), args)

    return sig, codegen


@numba.njit(cache=True, nogil=True)
def _pairwise_block(x: np.ndarray, lo: int, n: int) -> np.float32:
    """``_pairwise_sum`` of at most 128 terms."""
    if n < 8:
        res = _F32_0
        for i in range(lo, lo + n):
            res += x[i]
        return res
    r0, r1, r2, r3 = x[lo], x[lo + 1], x[lo + 2], x[lo + 3]
    r4, r5, r6, r7 = x[lo + 4], x[lo + 5], x[lo + 6], x[lo + 7]
    i = 8
    while i + 8 <= n:
        j = lo + i
        r0, r1, r2, r3 = r0 + x[j], r1 + x[j + 1], r2 + x[j + 2], r3 + x[j + 3]
        r4, r5, r6, r7 = r4 + x[j + 4], r5 + x[j + 5], r6 + x[j + 6], r7 + x[j + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += x[lo + i]
        i += 1
    return res


@numba.njit(cache=True, nogil=True)
def _pairwise_sum(x: np.ndarray, lo: int, n: int) -> np.float32:
    """Sum of ``x[lo:lo + n]`` (float32) in numpy's order (its ``pairwise_sum`` of a contiguous
    float32 reduction): under 8 terms one by one; up to 128 in 8 interleaved partial sums combined
    as ((0+1)+(2+3))+((4+5)+(6+7)), then the rest one by one; above, the two halves (the first a
    multiple of 8 long) summed apart and added. The halving runs on an explicit stack (a
    self-recursive function does not load from numba's cache).
    """
    if n <= 128:
        return _pairwise_block(x, lo, n)
    task = np.empty((64, 3), np.int64)  # (start, length, halves summed) still to do
    val = np.empty(64, np.float32)
    nt, nv = 1, 0
    task[0, 0], task[0, 1], task[0, 2] = lo, n, 0
    while nt:
        nt -= 1
        a, m, done = task[nt, 0], task[nt, 1], task[nt, 2]
        if m <= 128:
            val[nv] = _pairwise_block(x, a, m)
            nv += 1
        elif done:
            nv -= 1
            val[nv - 1] = val[nv - 1] + val[nv]
        else:
            m2 = m // 2
            m2 -= m2 % 8
            task[nt, 0], task[nt, 1], task[nt, 2] = a, m, 1
            task[nt + 1, 0], task[nt + 1, 1], task[nt + 1, 2] = a + m2, m - m2, 0
            task[nt + 2, 0], task[nt + 2, 1], task[nt + 2, 2] = a, m2, 0
            nt += 3
    return val[0]


@numba.njit(cache=True, nogil=True)
def cone_image_costs(
    pts: np.ndarray,
    R: np.ndarray,
    tc: np.ndarray,
    intr: np.ndarray,
    fr: np.ndarray,
    seg: np.ndarray,
    G: np.ndarray,
    n_in: int,
    win: np.ndarray,
    base: np.ndarray,
    maps: np.ndarray,
    person: np.ndarray,
    cover_o: np.ndarray,
    cover_G: np.ndarray,
    cover_qq: np.ndarray,
    cover_start: np.ndarray,
    cover_len: np.ndarray,
    with_cover: bool,
    out: np.ndarray,
) -> None:
    """S_r, S_e, S_c of N poses from their anchor points (see ``likelihood`` for the costs).

    Per pose n, anchor a (camera frame ``X = R p + t``, pixels ``u = fx X_x / z + cx``,
    ``v = fy X_y / z + cy``, ``z = max(X_z, 0.05)``), cone s between anchors (a0, a1) with end
    centres c0, c1, half-widths ``rho_i = f r_i / z_i``, axis ``a = c1 - c0``, unit normal n:

    - sample k at (s_k, t_k): ``c0 + s_k a + (rho0 + s_k (rho1 - rho0)) t_k n``, rounded to a pixel
      of the pose's window; ``S_r`` is the mean of the cost map at the ``n_in`` interior samples,
      ``S_e`` at the outline ones (a point outside the window reads the window's last entry);
    - ``S_c = 1 - |{q_m : exists s, |q_m - (c0 + s' a)|^2 <= (rho0 + s' (rho1 - rho0) + 1)^2}| / M``,
      ``s' = clip((q_m - c0).a / |a|^2, 0, 1)``, over the M coverage samples q_m of the pose's person;
    - all three are 1 for a pose with an anchor less than 0.05 m in front of the camera.

    Parameters
    ----------
    pts : ndarray of shape (N, A, 3), dtype float32
        Anchor points, metres, world frame.
    R : ndarray of shape (3, 3), dtype float32
        World-to-camera rotation.
    tc : ndarray of shape (3,), dtype float32
        World-to-camera translation, metres.
    intr : ndarray of shape (4,), dtype float32
        fx, fy, cx, cy, pixels.
    fr : ndarray of shape (P, S, 2), dtype float32
        Focal length times the cones' end radii of each of P people (pixel metres).
    seg : ndarray of shape (S, 2), dtype int64
        The anchors at the two ends of each cone.
    G : ndarray of shape (4, K), dtype float32
        (1, s_k, t_k, s_k t_k) of the samples, the first ``n_in`` interior, the rest outline.
    n_in : int
        Interior samples per cone.
    win : ndarray of shape (P, 4), dtype float32
        Each person's window: x0, y0 (its top-left pixel in the image), width W, height H.
    base : ndarray of shape (P, 2), dtype int64
        Where the person's interior and outline costs start in ``maps`` (each W H + 1 long).
    maps : ndarray of shape (L,), dtype float32
        The cost maps laid end to end.
    person : ndarray of shape (N,), dtype int64
        Each pose's person: its row of the per-person tables (``fr``, ``win``, ``base``, ``cover_*``).
    cover_o : ndarray of shape (P, 2), dtype float32
        Centre of each person's coverage samples, pixels.
    cover_G : ndarray of shape (3, sum M), dtype float32
        The samples relative to their centre, and a row of ones (``ConeLikelihood.cover_terms``),
        people laid end to end.
    cover_qq : ndarray of shape (sum M,), dtype float32
        Their squared distances to the centre.
    cover_start, cover_len : ndarray of shape (P,), dtype int64
        Each person's first sample and number M of samples (0: S_c is 0).
    with_cover : bool
        Compute S_c (else 0).
    out : ndarray of shape (N, 3), dtype float32
        Filled with S_r, S_e, S_c.
    """
    N, A = pts.shape[0], pts.shape[1]
    S, K = seg.shape[0], G.shape[1]
    fx, fy, cx, cy = intr[0], intr[1], intr[2], intr[3]
    n_out = K - n_in
    u = np.empty(A, np.float32)
    v = np.empty(A, np.float32)
    zi = np.empty(A, np.float32)
    # per cone of the pose: c0 (x, y), axis (x, y), rho0, rho1
    cone = np.empty((S, 6), np.float32)
    # per cone of the pose, the coverage test's terms
    cov = np.empty((S, 10), np.float32)
    # the pose's interior and outline costs, cone by cone
    c_in = np.empty(S * n_in, np.float32)
    c_out = np.empty(S * (K - n_in), np.float32)
    for n in range(N):
        p = person[n]
        ok = True
        for a in range(A):
            p0, p1, p2 = pts[n, a, 0], pts[n, a, 1], pts[n, a, 2]
            X0 = _fma(p2, R[0, 2], _fma(p1, R[0, 1], _fma(p0, R[0, 0], _F32_0))) + tc[0]
            X1 = _fma(p2, R[1, 2], _fma(p1, R[1, 1], _fma(p0, R[1, 0], _F32_0))) + tc[1]
            z = _fma(p2, R[2, 2], _fma(p1, R[2, 1], _fma(p0, R[2, 0], _F32_0))) + tc[2]
            if not z > _NEAR:
                ok = False
            zz = _F32_1 / (z if z > _NEAR else _NEAR)
            zi[a] = zz
            u[a] = fx * X0 * zz + cx
            v[a] = fy * X1 * zz + cy
        if not ok:
            out[n, 0] = _F32_1
            out[n, 1] = _F32_1
            out[n, 2] = _F32_1
            continue
        x0w, y0w, W, H = win[p, 0], win[p, 1], win[p, 2], win[p, 3]
        WH = W * H
        b_in, b_out = base[p, 0], base[p, 1]
        for s in range(S):
            a0, a1 = seg[s, 0], seg[s, 1]
            x0, y0 = u[a0], v[a0]
            ax, ay = u[a1] - x0, v[a1] - y0
            rho0 = fr[p, s, 0] * zi[a0]
            rho1 = fr[p, s, 1] * zi[a1]
            cone[s, 0], cone[s, 1], cone[s, 2], cone[s, 3], cone[s, 4], cone[s, 5] = x0, y0, ax, ay, rho0, rho1
            L = np.float32(np.sqrt(ax * ax + ay * ay))
            if L > _MIN_AXIS:
                inv = _F32_1 / L
                nx = -ay * inv
            else:
                inv = _F32_0
                nx = _F32_1
            ny = ax * inv
            dr = rho1 - rho0
            fu0, fu1, fu2, fu3 = x0, ax, rho0 * nx, dr * nx
            fv0, fv1, fv2, fv3 = y0, ay, rho0 * ny, dr * ny
            for k in range(K):
                pu = _fma(fu3, G[3, k], _fma(fu2, G[2, k], _fma(fu1, G[1, k], _fma(fu0, G[0, k], _F32_0))))
                pv = _fma(fv3, G[3, k], _fma(fv2, G[2, k], _fma(fv1, G[1, k], _fma(fv0, G[0, k], _F32_0))))
                ui = _rint(pu) - x0w
                vi = _rint(pv) - y0w
                if ui >= _F32_0 and ui < W and vi >= _F32_0 and vi < H:
                    i = np.int64(vi * W + ui)
                else:
                    i = np.int64(WH)
                if k < n_in:
                    c_in[s * n_in + k] = maps[b_in + i]
                else:
                    c_out[s * n_out + k - n_in] = maps[b_out + i]
        # the means as numpy takes them: the pairwise sum, divided in float64
        out[n, 0] = np.float32(np.float64(_pairwise_sum(c_in, 0, S * n_in)) / (S * n_in))
        out[n, 1] = np.float32(np.float64(_pairwise_sum(c_out, 0, S * n_out)) / (S * n_out))
        M = cover_len[p]
        if not with_cover or M == 0:
            out[n, 2] = _F32_0
            continue
        m0 = cover_start[p]
        ox, oy = cover_o[p, 0], cover_o[p, 1]
        for s in range(S):
            c0x, c0y = cone[s, 0] - ox, cone[s, 1] - oy
            ax, ay = cone[s, 2], cone[s, 3]
            aa = ax * ax + ay * ay
            if aa < _MIN_AA:
                aa = _MIN_AA
            # 2 d.a and |d|^2 - |q|^2 (d = q - c0) are linear in (qx, qy, 1): these rows, as the
            # numpy code's matrix product
            cov[s, 0], cov[s, 1] = _TWO * ax, _TWO * ay
            cov[s, 2] = -_TWO * (c0x * ax + c0y * ay)
            cov[s, 3], cov[s, 4] = -_TWO * c0x, -_TWO * c0y
            cov[s, 5] = c0x * c0x + c0y * c0y
            cov[s, 6], cov[s, 7] = aa, _HALF / aa
            cov[s, 8], cov[s, 9] = cone[s, 5] - cone[s, 4], cone[s, 4] + _F32_1
        hit = 0
        for m in range(m0, m0 + M):
            qx, qy, qq = cover_G[0, m], cover_G[1, m], cover_qq[m]
            for s in range(S):
                pd2 = _fma(cov[s, 2], _F32_1, _fma(cov[s, 1], qy, _fma(cov[s, 0], qx, _F32_0)))
                d2 = _fma(cov[s, 5], _F32_1, _fma(cov[s, 4], qy, _fma(cov[s, 3], qx, _F32_0))) + qq
                # t: the nearest axis point; |d - t a|^2 = |d|^2 - t (2 d.a - t |a|^2)
                t = pd2 * cov[s, 7]
                t = min(max(t, _F32_0), _F32_1)
                d2 = d2 - (pd2 - t * cov[s, 6]) * t
                # + 1 px: a rasterised mask holds every pixel the body touches
                r = t * cov[s, 8] + cov[s, 9]
                if d2 <= r * r:
                    hit += 1
                    break
        out[n, 2] = _F32_1 - np.float32(np.float64(np.float32(hit)) / M)


__all__ = ["cone_image_costs"]
