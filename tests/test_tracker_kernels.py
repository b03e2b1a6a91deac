"""The tracker's compiled likelihood kernel against the numpy formulation it replaced."""

from __future__ import annotations

import numpy as np
import pytest

from counterpart.body.camera import Camera
from counterpart.body.pose import DOF, neutral_pose
from counterpart.body.raster import rasterise_silhouettes, render_edge_maps
from counterpart.body.skeleton import DEFAULT_DIMS
from counterpart.nodes.tracker.kernels import _pairwise_sum
from counterpart.nodes.tracker.likelihood import (
    ConeLikelihood,
    LikelihoodConfig,
    MultiViewLikelihood,
    Observation,
    _coverage,
    evaluate_joint,
    make_observation,
    pose_anchor_points,
    warm_kernels,
)


def _numpy_image_costs(L: ConeLikelihood, pts: np.ndarray, obs: Observation) -> np.ndarray:
    """``ConeLikelihood.image_costs`` as numpy arrays over (N, S, K) and (N, S, M), as it was before
    the kernel: projection, the samples' matmul, one gather, the coverage matmul.
    """
    c, rho, ok = L._project(pts)
    u, v = L._points_uv(c, rho)
    W, H = obs.width, obs.height
    k = L.n_in
    ui, vi = np.rint(u), np.rint(v)
    ui -= np.float32(obs.x0)
    vi -= np.float32(obs.y0)
    inside = (ui >= 0) & (ui < W) & (vi >= 0) & (vi < H)
    vi *= W
    vi += ui
    idx = np.where(inside, vi, np.float32(W * H)).astype(np.intp)
    idx[:, :, k:] += W * H + 1
    cost = obs.cost_map()[idx]
    S_r = cost[:, :, :k].mean(axis=(1, 2))
    S_e = cost[:, :, k:].mean(axis=(1, 2))
    if L.w[2] and len(obs.cover_uv):
        o, G, qq = L.cover_terms(obs.cover_uv)
        S_c = _coverage(c, rho, o[0], o[1], G, qq)
    else:
        S_c = np.zeros_like(S_r)
    out = np.stack([S_r, S_e, S_c], axis=1)
    out[~ok] = 1.0
    return out


def _assert_same_costs(got: np.ndarray, want: np.ndarray) -> None:
    """The same costs: to the last bit for (nearly) every pose; where a BLAS sums the numpy code's
    small matrix products in another order than the kernel, a sample's pixel may round the other way.
    """
    assert got.dtype == want.dtype == np.float32 and got.shape == want.shape
    diff = np.abs(got.astype(np.float64) - want)
    assert (diff.max(axis=1) == 0).mean() >= 0.99
    assert diff.max() <= 0.02


def _scene(rng: np.random.Generator, n: int) -> tuple[Camera, np.ndarray, np.ndarray, np.ndarray]:
    """A random camera, a person's rendered frame and mask, and n poses about it: perturbed, some
    far off the window and some behind the camera.
    """
    eye = (rng.uniform(-1, 1), rng.uniform(1.0, 2.5), rng.uniform(3.0, 5.0))
    cam = Camera.look_at(eye, (rng.uniform(-0.3, 0.3), 0.9, 0.0), rng.uniform(40, 75), 320, 240)
    P0 = neutral_pose(DEFAULT_DIMS, x=rng.uniform(-0.5, 0.5), yaw=rng.uniform(-np.pi, np.pi))
    P0[12], P0[15] = rng.uniform(0, 1.5), rng.uniform(0, 1.5)
    mask = rasterise_silhouettes(P0[None], DEFAULT_DIMS, cam)[0]
    image = np.where(mask, 90, 200).astype(np.uint8)
    image[render_edge_maps(P0[None], DEFAULT_DIMS, cam, mode="cones")[0]] = 20
    image = np.clip(image + rng.normal(0, 25, image.shape), 0, 255).astype(np.uint8)  # edges off the body too
    P = P0[None] + rng.normal(size=(n, DOF)) * 0.15
    P[: n // 8, 0] += rng.normal(size=n // 8) * 2.0  # out of the window, out of the image
    P[n // 8 : n // 6, 2] += 6.0  # behind the camera
    return cam, image, mask, P


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_kernel_costs_equal_the_numpy_formulation(seed: int) -> None:
    rng = np.random.default_rng(seed)
    cam, image, mask, P = _scene(rng, 400)
    obs = make_observation(image, mask, n_cover=int(rng.integers(1, 80)), rng=rng)
    for config in (LikelihoodConfig(), LikelihoodConfig(n_along=3, n_across=2, per_side=5, w_cover=0.0)):
        L = ConeLikelihood(cam, DEFAULT_DIMS, config)
        pts = pose_anchor_points(P, L.dims)
        got, want = L.image_costs(pts, obs), _numpy_image_costs(L, pts, obs)
        _assert_same_costs(got, want)
        assert (got[:, 0] > 0).any() and (got[:, 0] < 1).any() and (got[:, 1] < 1).any()  # poses on the person
        if config.w_cover:
            assert ((got[:, 2] > 0) & (got[:, 2] < 1)).any()
        behind = (cam.depth(pts.astype(np.float64)) < 0.05).any(axis=1)
        assert behind.any()
        np.testing.assert_array_equal(got[behind], 1.0)


def test_joint_kernel_equals_each_persons_numpy_costs() -> None:
    """Two people of one frame with their own bodies, windows and numbers of coverage samples."""
    rng = np.random.default_rng(7)
    cam, image, mask, P = _scene(rng, 90)
    other = np.zeros_like(mask)
    other[60:200, 230:290] = True  # a second person's region
    obs = [make_observation(image, mask, n_cover=32), make_observation(image, other, n_cover=20)]
    dims = [DEFAULT_DIMS, DEFAULT_DIMS.scaled(1.1)]
    lks = [MultiViewLikelihood([cam], d) for d in dims]
    poses = [P[:50], P[50:] + np.array([1.6] + [0.0] * (DOF - 1))]
    for (terms, ground), lk, X, o in zip(evaluate_joint(lks, poses, [[o] for o in obs]), lks, poses, obs):
        L = lk.views[0]
        pts = pose_anchor_points(X, L.dims)
        _assert_same_costs(terms, _numpy_image_costs(L, pts, o))
        np.testing.assert_array_equal(ground, L.ground_cost(pts))


def test_pairwise_sum_is_numpys_float32_sum() -> None:
    rng = np.random.default_rng(0)
    x = (rng.random(600) ** 2).astype(np.float32) * 3
    for n in list(range(0, 140)) + [191, 192, 256, 257, 300, 600]:
        assert _pairwise_sum(x, 0, n) == np.add.reduce(x[:n]), n
        assert _pairwise_sum(x, 5, n - 5 if n > 5 else 0) == np.add.reduce(x[5:n]), n


def test_warm_loads_the_one_signature_every_call_path_uses() -> None:
    """``warm_kernels`` (the tracker node's start) compiles or loads what a tracker's frames then
    run: the one person's path, the joint path and the estimates' kinematics add no other types.
    """
    from counterpart.body.kinematics_kernel import anchor_kernel
    from counterpart.nodes.tracker.kernels import cone_image_costs

    warm_kernels()
    test_joint_kernel_equals_each_persons_numpy_costs()
    test_kernel_costs_equal_the_numpy_formulation(0)
    assert len(cone_image_costs.signatures) == 1
    assert len(anchor_kernel.signatures) == 1
