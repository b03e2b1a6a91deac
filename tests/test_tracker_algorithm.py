"""Tracker algorithms on silhouettes rendered from known poses (body.raster)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from counterpart.body.camera import Camera, default_camera
from counterpart.body.kinematics import forward_kinematics
from counterpart.body.pose import DOF, LOWER, UPPER, YAW, neutral_pose
from counterpart.body.raster import cone_interior_points, cone_outline_points, rasterise_silhouettes, render_edge_maps
from counterpart.body.skeleton import DEFAULT_DIMS
from counterpart.nodes.tracker.apf import AnnealedParticleFilter, choose_beta, survival_rate
from counterpart.nodes.tracker.init import bbox_from_mask, facing_yaw, place_from_bbox
from counterpart.nodes.tracker.likelihood import (
    ConeLikelihood,
    LikelihoodConfig,
    MultiViewLikelihood,
    Observation,
    edge_map,
    frame_edges,
    make_observation,
)
from counterpart.nodes.tracker.tracker import APFConfig, InitConfig, Tracker, TrackerConfig, track_sequence
from counterpart.sim.scenarios import make_scenario

CAM = default_camera()
#: small filters that keep the tests fast: 5 layers x 128 particles, and 2 x 16 where only the
#: interface is checked
SMALL = TrackerConfig(apf=APFConfig(n_layers=5, n_particles=128))
TINY = TrackerConfig(apf=APFConfig(n_layers=2, n_particles=16))


def _pose() -> np.ndarray:
    P = neutral_pose(DEFAULT_DIMS, x=-0.5, yaw=0.4)
    P[12], P[15], P[20], P[23] = 1.2, 0.8, 0.4, 0.6  # arm forward, elbow bent, hip and knee flexed
    return P


def _render(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    mask = rasterise_silhouettes(P[None], DEFAULT_DIMS, CAM)[0]
    edges = render_edge_maps(P[None], DEFAULT_DIMS, CAM, mode="cones")[0]
    image = np.where(mask, 90, 200).astype(np.uint8)
    image[edges] = 20  # shading seams where cones overlap
    return image, mask


def test_coverage_cost_matches_direct_capsule_test() -> None:
    rng = np.random.default_rng(4)
    P = _pose()[None] + rng.normal(size=(16, DOF)) * 0.2
    image, mask = _render(_pose())
    obs = make_observation(image, mask)
    L = ConeLikelihood(CAM)
    c, rho, _ = L.project(P)
    q = obs.cover_uv.astype(np.float64)
    c0, a = c[:, :, 0, None].astype(np.float64), (c[:, :, 1] - c[:, :, 0])[:, :, None].astype(np.float64)
    d = q[None, None] - c0  # (N, S, M, 2)
    s = np.clip((d * a).sum(-1) / np.maximum((a * a).sum(-1), 1e-6), 0, 1)
    dist = np.linalg.norm(d - s[..., None] * a, axis=-1)
    r = rho[..., :1] + s * (rho[..., 1:] - rho[..., :1]) + 1.0
    expect = 1.0 - (dist <= r).any(axis=1).mean(axis=1)
    np.testing.assert_allclose(L.coverage_cost(c, rho, obs.cover_uv), expect, atol=1.5 / len(q))


def test_sample_points_match_body_raster() -> None:
    P = np.stack([_pose(), neutral_pose()])
    inner, outline, ok = ConeLikelihood(CAM).sample_points(P)
    assert ok.all()
    np.testing.assert_allclose(inner, cone_interior_points(P, DEFAULT_DIMS, CAM), atol=1e-3)
    np.testing.assert_allclose(outline, cone_outline_points(P, DEFAULT_DIMS, CAM), atol=1e-3)


def test_true_pose_scores_higher_than_perturbed_poses() -> None:
    P = _pose()
    image, mask = _render(P)
    obs = make_observation(image, mask)
    L = ConeLikelihood(CAM)
    rng = np.random.default_rng(3)
    for scale in (0.05, 0.15, 0.4):
        noise = rng.normal(size=(64, DOF)) * scale
        noise[:, :3] *= 0.3  # metres
        perturbed = np.clip(P + noise, LOWER, UPPER)
        ll = L(np.vstack([P[None], perturbed]), obs)
        assert ll[0] > ll[1:].max(), f"scale {scale}: true {ll[0]:.3f} vs best perturbed {ll[1:].max():.3f}"
    # each single joint moved 0.3 rad costs likelihood
    for dof in (12, 15, 20, 23):
        Q = P.copy()
        Q[dof] += 0.3
        assert L(Q[None], obs)[0] < L(P[None], obs)[0], f"DOF {dof}"
    # an empty mask is an empty observation, not an error
    assert make_observation(image, np.zeros_like(mask)).empty


def test_observation_window_holds_the_whole_frames_maps() -> None:
    P = _pose()
    image, mask = _render(P)
    # a second person's region and textured background: edges the window must leave out
    image[:, : image.shape[1] // 4] = np.random.default_rng(2).integers(0, 255, (image.shape[0], image.shape[1] // 4))
    obs = make_observation(image, mask)
    H, W = mask.shape
    assert 0 < obs.width * obs.height < W * H / 2  # the person's window, not the frame
    full_edge = edge_map(image, mask)
    win = np.zeros((H, W), bool)
    win[obs.y0 : obs.y0 + obs.height, obs.x0 : obs.x0 + obs.width] = True
    assert not full_edge[~win].any() and not mask[~win].any()
    np.testing.assert_array_equal(obs.edge[:-1].reshape(obs.height, obs.width), full_edge[win].reshape(obs.height, -1))
    np.testing.assert_array_equal(obs.fg[:-1].reshape(obs.height, obs.width), mask[win].reshape(obs.height, -1))
    # the costs of poses read the same as from maps of the whole frame
    whole = Observation(
        np.append(mask.ravel(), False).astype(np.float32),
        np.append(full_edge.ravel(), np.float32(0)),
        obs.cover_uv,
        W,
        H,
    )
    rng = np.random.default_rng(5)
    X = P[None] + rng.normal(size=(64, DOF)) * 0.2
    X[:, 0] += rng.normal(size=64) * 0.5  # some poses reach out of the window
    L = ConeLikelihood(CAM)
    np.testing.assert_array_equal(L.terms(X, obs), L.terms(X, whole))
    # the frame's edges computed once for several people give the same maps
    shared = make_observation(image, mask, edges=frame_edges(image))
    np.testing.assert_array_equal(shared.cost_map(), obs.cost_map())
    np.testing.assert_array_equal(shared.cover_uv, obs.cover_uv)


def test_beta_hits_survival_rate() -> None:
    rng = np.random.default_rng(0)
    ll = -rng.gamma(2.0, 0.2, size=256)
    for alpha in (0.2, 0.5, 0.8):
        beta = choose_beta(ll, alpha)
        assert abs(survival_rate(ll, beta) - alpha) < 1e-3
    assert choose_beta(np.zeros(10), 0.5) > 0  # flat likelihood: any beta, no crash
    with pytest.raises(ValueError, match="survival"):
        choose_beta(ll, 1.5)


def _beta_by_bisection(ll: np.ndarray, alpha: float, lo: float = 1e-3, hi: float = 1e6) -> float:
    """The reference: 200 halvings of the log-beta bracket on ``survival_rate`` itself."""
    a, b = np.log(lo), np.log(hi)
    for _ in range(200):
        m = 0.5 * (a + b)
        a, b = (m, b) if survival_rate(ll, np.exp(m)) > alpha else (a, m)
    return float(np.exp(0.5 * (a + b)))


def test_beta_matches_a_bisection_over_particle_counts_and_spreads() -> None:
    # the real-time frame's few dozen particles to the offline 256; log-likelihood spreads from
    # nearly flat to a collapse, and skewed shapes (a few good particles among many bad)
    rng = np.random.default_rng(3)
    worst = 0.0
    for n in (8, 33, 64, 256):
        for spread in (0.5, 5.0, 50.0, 500.0):
            for shape in (0.3, 1.0, 3.0):
                ll = -spread * rng.random(n) ** shape
                for alpha in (0.2, 0.5, 0.8):
                    ref = _beta_by_bisection(ll, alpha)
                    if not 1.01e-3 < ref < 0.99e6:  # the bracket's ends: returned as they are
                        continue
                    worst = max(worst, abs(np.log(choose_beta(ll, alpha) / ref)))
    assert worst < 2e-4
    # beyond the bracket its ends come back
    ll = -rng.random(64)
    assert choose_beta(ll * 1e-9, 0.5) == 1e6  # nearly flat: even the largest beta survives too many
    assert choose_beta(ll * 1e9, 0.5) == 1e-3  # a collapse: even the smallest survives too few
    with pytest.raises(ValueError, match="grid point"):
        choose_beta(ll, 0.5, refine=(1,))


def test_annealing_schedule_and_limits() -> None:
    P = _pose()
    image, mask = _render(P)
    obs = make_observation(image, mask)
    L = ConeLikelihood(CAM)
    apf = AnnealedParticleFilter(n_layers=6, n_particles=128, survival=0.5, seed=1)
    rng = np.random.default_rng(1)
    start = P + rng.normal(size=(128, DOF)) * 0.1
    apf.initialise(start)
    est = apf.step(lambda X: L(X, obs))
    np.testing.assert_allclose(est.survival, 0.5, atol=0.02)
    assert est.betas[-1] > est.betas[0]  # the density sharpens over the layers
    assert est.n_evals == 6 * 128
    inside = (apf.particles >= LOWER) & (apf.particles <= UPPER)
    inside[:, YAW] = True
    assert inside.all()
    truth = forward_kinematics(P)
    err = np.linalg.norm(forward_kinematics(est.mean)[0] - truth[0], axis=-1).mean()
    err0 = np.linalg.norm(forward_kinematics(start) - truth, axis=-1).mean()
    assert err < 0.5 * err0, f"estimate {err:.3f} m vs initial particles {err0:.3f} m"


def test_placement_from_bbox() -> None:
    P = neutral_pose(DEFAULT_DIMS.scaled(1.8), x=0.6, z=-0.3)
    mask = rasterise_silhouettes(P[None], DEFAULT_DIMS.scaled(1.8), CAM)[0]
    g, height = place_from_bbox(bbox_from_mask(mask), CAM)
    assert abs(height - 1.8) < 0.05
    assert abs(g[0] - 0.6) < 0.05 and abs(g[2] + 0.3) < 0.15


#: (scenario, its seed, first frame): a stretch of each where person A walks, so that a tracker that
#: does not follow falls behind (the pelvis moves 0.23-0.57 m over the 10 frames tracked)
WALKS = (("handshake", 4, 20), ("handshake", 5, 20), ("push", 1, 10), ("push", 3, 50))


def test_tracker_follows_rendered_sequence() -> None:
    # the filter is chaotic: one seed's error is luck (over 40 seeds of one scene it spreads
    # 0.10-0.30 m), so the figure is the mean of four scenes, each with its own filter seed
    err, behind, pelvis = [], [], []
    for seed, (name, scenario_seed, start) in enumerate(WALKS):
        sc = make_scenario(name, seed=scenario_seed)
        P = sc.poses_a[start::2][:10]
        masks = rasterise_silhouettes(P, sc.dims_a, CAM)
        out = track_sequence([None] * len(P), masks, CAM, side="left", config=SMALL, seed=seed)
        assert out["joints"].shape == (10, 14, 3)
        truth = forward_kinematics(P, sc.dims_a)
        err.append(np.linalg.norm(out["joints"] - truth, axis=-1).mean())
        off = np.abs(out["poses"][:, [0, 2]] - P[:, [0, 2]]).max(axis=1)  # pelvis off the truth, m
        pelvis.append(off.max())
        # how far behind the walk the last frame is, as a share of the way walked (1: stood still)
        behind.append(off[-1] / np.abs(P[-1, [0, 2]] - P[0, [0, 2]]).max())
    assert np.mean(err) < 0.19, f"mean joint error {np.mean(err):.3f} m (per scene {np.round(err, 3)})"
    assert np.mean(behind) < 0.75, f"the pelvis {np.round(behind, 2)} of the way walked behind"
    # stays with the person: the pelvis within 0.35 m of the truth on every frame
    assert max(pelvis) < 0.35, f"pelvis off by up to {np.round(pelvis, 3)} m"


@pytest.mark.parametrize("with_prior", [False, True])
def test_a_gap_of_dropped_frames_widens_the_prediction_and_the_search_bounds(with_prior: bool) -> None:
    from counterpart.nodes.tracker.prior import train_prior

    prior = train_prior(["sim:wave?seed=7"], n_states=3) if with_prior else None
    tr = Tracker(CAM, "left", SMALL, prior=prior, fps=25.0)
    std, lo, hi = tr.predictor.std.copy(), tr.filter.min_std.copy(), tr.filter.max_std.copy()
    tr.set_gap(2)
    np.testing.assert_allclose(tr.predictor.std, 2 * std)
    np.testing.assert_allclose(tr.filter.min_std, 2 * lo)
    np.testing.assert_allclose(tr.filter.max_std, 2 * hi)
    tr.set_gap(1)
    np.testing.assert_allclose(tr.predictor.std, std)
    np.testing.assert_allclose(tr.filter.max_std, hi)
    # a 10 fps video's tracker starts out 2.5 times as wide as the 25 fps one
    slow = Tracker(CAM, "left", SMALL, prior=prior, fps=10.0)
    np.testing.assert_allclose(slow.predictor.std, 2.5 * std)
    np.testing.assert_allclose(slow.filter.max_std, 2.5 * hi)


#: a second camera left of the scene, aimed at person A (as bench/tracker.py's ``--views 2``)
SIDE_CAM = Camera.look_at((-3.8, 2.0, 1.2), (-0.5, 0.9, 0.0), 55.0, 320, 240)


def test_a_second_view_sees_the_depth_one_camera_barely_does() -> None:
    P = _pose()
    obs = [make_observation(None, rasterise_silhouettes(P[None], DEFAULT_DIMS, cam)[0]) for cam in (CAM, SIDE_CAM)]
    ray = P[:3] - CAM.centre
    ray[1] = 0.0
    ray /= np.linalg.norm(ray)
    X = np.vstack([P] + [np.r_[P[:3] + d * ray, P[3:]] for d in (-0.3, -0.2, 0.2, 0.3)])  # along the view
    mono = MultiViewLikelihood([CAM])(X, obs[:1])
    np.testing.assert_array_equal(mono, ConeLikelihood(CAM)(X, obs[0]))  # one view: the plain likelihood
    both = MultiViewLikelihood([CAM, SIDE_CAM])(X, obs)
    margin_mono, margin_both = mono[0] - mono[1:], both[0] - both[1:]
    assert (margin_mono > 0).all()
    assert (margin_both > 3 * margin_mono).all(), f"two views {margin_both}, one view {margin_mono}"
    # a view where the person is out of sight (empty mask) is left out, not counted as a miss
    empty = make_observation(None, np.zeros((240, 320), bool))
    np.testing.assert_allclose(MultiViewLikelihood([CAM, SIDE_CAM])(X, [obs[0], empty]), mono)


def test_two_cameras_track_the_body_closer_than_one() -> None:
    err = {1: [], 2: []}
    for seed in (5, 6):
        sc = make_scenario("handshake", seed=seed)
        P = sc.poses_a[::2][:20]
        front = rasterise_silhouettes(P, sc.dims_a, CAM)
        side = rasterise_silhouettes(P, sc.dims_a, SIDE_CAM)
        truth = forward_kinematics(P, sc.dims_a)
        one = track_sequence([None] * len(P), front, CAM, config=SMALL, seed=0)
        two = track_sequence(
            [None] * len(P), [[a, b] for a, b in zip(front, side)], [CAM, SIDE_CAM], config=SMALL, seed=0
        )
        err[1].append(np.linalg.norm(one["joints"] - truth, axis=-1).mean())
        err[2].append(np.linalg.norm(two["joints"] - truth, axis=-1).mean())
    one, two = np.mean(err[1]), np.mean(err[2])
    assert two < 0.12 and two < 0.8 * one, f"two cameras {two:.3f} m, one camera {one:.3f} m"


def test_several_cameras_need_one_mask_per_camera() -> None:
    mask = rasterise_silhouettes(_pose()[None], DEFAULT_DIMS, CAM)[0]
    trk = Tracker([CAM, SIDE_CAM], config=TINY)
    with pytest.raises(ValueError, match="2 cameras: give a list of 2 masks"):
        trk.update(None, mask)
    with pytest.raises(ValueError, match="2 cameras: give a list of 2 frames"):
        trk.update([None], [mask, mask])
    with pytest.raises(ValueError, match="3 observations for 2 cameras"):
        MultiViewLikelihood([CAM, SIDE_CAM])(_pose()[None], [make_observation(None, mask)] * 3)
    with pytest.raises(ValueError, match="non-empty sequence of Cameras"):
        Tracker([])
    with pytest.raises(TypeError, match="expected a TrackerConfig"):
        Tracker(CAM, "left", 10)  # type: ignore[arg-type]  # the flat parameters are grouped now
    # the person out of the reference view: no estimate, no error
    assert trk.update(None, [np.zeros_like(mask), mask]) is None
    assert trk.update(None, [mask, mask]) is not None
    # one camera takes a mask, or a list of one
    assert Tracker([CAM], config=TINY).update(None, [mask]) is not None


def test_ess_is_that_of_the_final_weighted_set_not_fixed_by_the_annealing() -> None:
    """The annealed weights have ESS = survival x N by construction; the published ESS weighs the
    final set by the un-annealed density: N for a flat one, about 1 for one peaked on a particle.
    """
    rng = np.random.default_rng(0)
    start = neutral_pose()[None] + rng.normal(scale=0.05, size=(64, DOF))
    flat = AnnealedParticleFilter(n_layers=2, n_particles=64, seed=0)
    flat.initialise(start)
    assert flat.step(lambda X: np.zeros(len(X))).ess == pytest.approx(64.0)
    peaked = AnnealedParticleFilter(n_layers=2, n_particles=64, seed=0)
    peaked.initialise(start)
    target = neutral_pose()
    est = peaked.step(lambda X: -1e4 * np.sum((X - target) ** 2, axis=1))
    assert 1.0 <= est.ess < 3.0  # one particle holds nearly all the mass
    assert est.survival[-1] * 64 == pytest.approx(32.0, rel=0.05)  # while annealing kept half alive


def _loose_clothing(masks: np.ndarray, seed: int = 0) -> np.ndarray:
    """Masks as real footage gives them: the person's outline 10 px wider all round than the body
    model's (loose clothing, a coat) with blotches of clothing the colour of the background
    (8 x 8 px holes over a quarter of the frame).
    """
    rng = np.random.default_rng(seed)
    out = []
    for m in masks:
        holes = rng.random((m.shape[0] // 8 + 1, m.shape[1] // 8 + 1)) < 0.25
        holes = np.kron(holes, np.ones((8, 8), bool))[: m.shape[0], : m.shape[1]]
        out.append(cv2.dilate(m.astype(np.uint8), np.ones((21, 21), np.uint8)).astype(bool) & ~holes)
    return np.array(out)


def test_loose_clothing_does_not_lose_a_track_that_fits() -> None:
    # the outline the model draws misses the wider one of the mask (edge cost high, as on the real
    # clips) while the body stays on the person: the track must go on
    sc = make_scenario("handshake", seed=4)
    P = sc.poses_a[::2][:12]
    masks = _loose_clothing(rasterise_silhouettes(P, sc.dims_a, CAM))
    image = np.full(masks.shape[1:] + (3,), 128, np.uint8)  # no contrast: the mask's outline is the only edge
    tr = Tracker(CAM, "left", SMALL, seed=0)
    results = [tr.update(image, m) for m in masks]
    truth = forward_kinematics(P, sc.dims_a)
    err = np.array([np.linalg.norm(r.joints - t, axis=-1).mean() for r, t in zip(results, truth)])
    costs = np.array([r.cost for r in results])
    # three frames in a row above 0.9 in the full cost S_r + S_e + S_c: what dropped such tracks
    run = np.convolve(costs > 0.9, np.ones(3), "valid").max()
    assert run == 3, f"full costs {costs.round(2)}: the case must hold the full cost above 0.9"
    assert not any(r.lost for r in results), f"lost with costs {costs.round(2)}"
    assert err.max() < 0.35, f"joint errors {err.round(3)} m"


def test_a_track_off_its_mask_is_lost_within_patience() -> None:
    # the mask jumps to the mirror place across the frame (about 1 m away): the body lies off it
    sc = make_scenario("handshake", seed=4)
    P = sc.poses_a[::2][:8]
    masks = rasterise_silhouettes(P, sc.dims_a, CAM)
    masks[4:] = masks[4:, :, ::-1]
    tr = Tracker(CAM, "left", SMALL, seed=0)
    lost = [tr.update(None, m).lost for m in masks]
    assert lost[:4] == [False] * 4 and any(lost[4:7]), lost


def test_a_track_starts_facing_the_other_person() -> None:
    # two people at different depths: the nearer (left) one faces the farther one, half away
    # from the camera; the other's box gives that heading, which the silhouette alone leaves
    # open between it and its mirror image (half towards the camera)
    a = neutral_pose(DEFAULT_DIMS, x=-0.5, z=0.4)
    b = neutral_pose(DEFAULT_DIMS, x=0.5, z=-0.4)
    box_a, box_b = (bbox_from_mask(rasterise_silhouettes(p[None], DEFAULT_DIMS, CAM)[0]) for p in (a, b))
    g_a, _ = place_from_bbox(box_a, CAM)
    assert abs(facing_yaw(g_a, box_b, CAM, np.pi / 2) - np.arctan2(1.0, -0.8)) < 0.1
    # and a track started with that box searches around it
    tr = Tracker(CAM, "left", TINY, seed=0)
    r = tr.update(None, rasterise_silhouettes(a[None], DEFAULT_DIMS, CAM)[0], towards=box_b)
    assert abs(r.pose[YAW] - np.arctan2(1.0, -0.8)) < 0.35


def _two_people(n: int) -> tuple[Camera, list[np.ndarray], list[np.ndarray], list[np.ndarray]]:
    """The camera, frames and both people's masks of the simulator's handshake (seed 3), every
    other frame.
    """
    from counterpart.sim.stream import open_stream

    stream = open_stream("handshake", seed=3, frames=2 * n)
    frames, a, b = [], [], []
    for i in range(0, 2 * n, 2):
        image, truth = stream.render_with_truth(i)
        frames.append(image)
        a.append(truth.masks[0])
        b.append(truth.masks[1])
    return stream.camera, frames, a, b


# with a motion prior both people share, at a real-time frame's odd particle count
@pytest.mark.parametrize(("with_prior", "particles"), [(False, 24), (True, 33)], ids=["random-walk", "motion-prior"])
def test_two_people_searched_side_by_side_get_what_each_search_alone_gets(with_prior: bool, particles: int) -> None:
    from counterpart.nodes.tracker.likelihood import evaluate_joint
    from counterpart.nodes.tracker.prior import train_prior
    from counterpart.nodes.tracker.tracker import joints_jointly, search_jointly

    cam, frames, a, b = _two_people(6)
    prior = train_prior(["sim:handshake?seed=7"], n_states=3) if with_prior else None

    def pair() -> list[Tracker]:
        # a first search of 6 layers beside running ones of 3: the two schedules differ on the start
        cfg = TrackerConfig(apf=APFConfig(n_layers=3, n_particles=particles), init=InitConfig(layers=6))
        return [Tracker(cam, side, cfg, prior=prior, seed=s) for s, side in enumerate(("left", "right"))]

    alone, joint = pair(), pair()
    b[0] = np.zeros_like(b[0])  # the right person comes in a frame later: its start beside a running track
    for i, image in enumerate(frames):
        edges = frame_edges(image)
        ra = [tr.update(image, m, None, edges) for tr, m in zip(alone, (a[i], b[i]))]
        begun = [(tr, tr.begin(image, m, None, edges)) for tr, m in zip(joint, (a[i], b[i]))]
        begun = [(tr, s) for tr, s in begun if s is not None]
        ests = search_jointly([tr for tr, _ in begun], [s for _, s in begun])
        joints = joints_jointly([tr for tr, _ in begun], ests)
        rj = [tr.end(s, e, j) for (tr, s), e, j in zip(begun, ests, joints)]
        assert len(rj) == (1 if i == 0 else 2) and [r.initialised for r in rj] == [i == 0, i == 1][: len(rj)]
        for x, y in zip([r for r in ra if r is not None], rj):
            assert np.array_equal(x.joints, y.joints) and x.lost == y.lost and x.initialised == y.initialised
        assert alone[0].dims != alone[1].dims  # each person's own body, scaled to its silhouette
    # the joint image costs are each person's own, with its own body and maps
    P = [np.repeat(tr.prev[None], 5, axis=0) + np.random.default_rng(0).normal(0, 0.05, (5, DOF)) for tr in joint]
    obs = [[make_observation(frames[-1], m)] for m in (a[-1], b[-1])]
    for (tj, gj), tr, p, o in zip(evaluate_joint([t.likelihood for t in joint], P, obs), joint, P, obs):
        ts, gs = tr.likelihood.evaluate(p, o)
        np.testing.assert_allclose(tj, ts, atol=1e-6)
        np.testing.assert_allclose(gj, gs, atol=1e-6)


def _cut_off(P: np.ndarray, rows: int) -> tuple[np.ndarray, np.ndarray]:
    """A frame and mask of pose P with the frame ending at ``rows`` (the person's legs below it)."""
    mask = rasterise_silhouettes(P[None], DEFAULT_DIMS, CAM)[0][:rows]
    return np.where(mask, 90, 200).astype(np.uint8), mask


def _projected_height(joints: np.ndarray) -> float:
    """Pixels from the head to the mid-ankle of (14, 3) joints seen by CAM."""
    p = CAM.project(joints.astype(np.float64))
    return float(np.linalg.norm(p[0] - p[[10, 13]].mean(axis=0)))


#: a person near the camera (3 m away: 181 pixels tall in a 240-row frame) cut off mid-thigh
NEAR_ROWS = 160


def _near(x: float, yaw: float) -> np.ndarray:
    P = neutral_pose(DEFAULT_DIMS, x=x, z=1.0, yaw=yaw)
    P[12], P[15] = 0.6, 0.5  # an arm forward: the box is wider than the body
    return P


def test_observation_goes_on_past_the_border_a_person_is_cut_off_by() -> None:
    P = _near(-0.3, 0.4)
    image, mask = _cut_off(P, NEAR_ROWS)
    obs = make_observation(image, mask)
    x, y, w, h = bbox_from_mask(mask)
    # the window reaches below the frame by the part in view's height, the mask's last row repeated
    assert obs.y0 + obs.height >= NEAR_ROWS + h
    fg = obs.fg[:-1].reshape(obs.height, obs.width)
    last = NEAR_ROWS - 1 - obs.y0
    assert fg[last].any()
    np.testing.assert_array_equal(fg[last + 1 :], np.repeat(fg[last : last + 1], obs.height - last - 1, axis=0))
    assert (obs.cover_uv[:, 1] < NEAR_ROWS).all()  # the coverage samples stay in the picture
    # the true body costs little; with the window ending at the frame its legs read "no person"
    L = ConeLikelihood(CAM)
    ours = float(L.terms(P[None], obs).sum())
    ended = float(L.terms(P[None], make_observation(image, mask, past_border=0.0)).sum())
    assert ours < 0.2 and ended > 0.5, (ours, ended)
    # a person clear of the borders keeps the window it had
    whole = rasterise_silhouettes(P[None], DEFAULT_DIMS, default_camera())[0]
    image_w = np.where(whole, 90, 200).astype(np.uint8)
    a, b = make_observation(image_w, whole), make_observation(image_w, whole, past_border=0.0)
    assert (a.x0, a.y0, a.width, a.height) == (b.x0, b.y0, b.width, b.height)


def test_track_of_a_person_cut_off_by_the_frame_keeps_their_size() -> None:
    before = TrackerConfig(apf=SMALL.apf, init=InitConfig(cut_off=False), likelihood=LikelihoodConfig(past_border=0.0))
    ratio: dict[str, list[float]] = {"ours": [], "before": []}
    for seed, (x, yaw) in enumerate(((-0.3, 0.4), (0.4, -1.2), (0.0, 1.5), (-0.5, -0.3))):
        P = _near(x, yaw)
        image, mask = _cut_off(P, NEAR_ROWS)
        truth = _projected_height(forward_kinematics(P)[0])
        for name, config in (("ours", SMALL), ("before", before)):
            tracker = Tracker(CAM, "left", config, seed=seed)
            for _ in range(3):
                result = tracker.update(image, mask)
            ratio[name].append(_projected_height(result.joints) / truth)
    ours, old = np.array(ratio["ours"]), np.array(ratio["before"])
    # the body stands on below the frame at the person's size; before, it was squeezed into the part in view
    assert abs(np.median(ours) - 1) < 0.15 and (abs(ours - 1) < 0.3).all(), ours
    assert (old < 0.75).all(), old
