"""Where the generated partner stands (the stage's limits), its hand contact, and the dual HMM's pose
on a person unlike any of training.
"""

from __future__ import annotations

import numpy as np
import pytest

from counterpart.body.camera import Camera
from counterpart.body.kinematics import forward_kinematics
from counterpart.body.pose import DOF_INDEX, neutral_pose
from counterpart.body.skeleton import DEFAULT_DIMS, JOINT_INDEX, bone_lengths
from counterpart.messages.silhouette import PersonShape
from counterpart.nodes.responder.dual_hmm import DualHMM, DualHMMConfig, FitConfig
from counterpart.nodes.responder.frames import actor_frame
from counterpart.nodes.responder.reach import ReachConfig, reach, two_bone_ik
from counterpart.nodes.responder.staging import (
    Reach,
    Stage,
    StageConfig,
    observed_silhouette,
    silhouette_reach,
    silhouette_tip_px,
    stature,
    touching_hand_px,
    whole_box,
)
from tests.pose_source import facing
from tests.responder_fixtures import CAM, box_overlap, planted_pair


def person(x: float, z: float, yaw: float = np.pi / 2) -> np.ndarray:
    return facing(yaw) + [x, 0.0, z]


def ground(X: np.ndarray) -> np.ndarray:
    return actor_frame(X)[0][[0, 2]]


@pytest.mark.parametrize("gap,expect", [(0.1, 0.5), (0.8, 0.8), (4.0, 1.2)])
def test_the_partner_stands_between_the_limits_along_the_line_to_the_model_placement(gap: float, expect: float) -> None:
    obs, par = person(0.0, 2.0), person(gap, 2.0, -np.pi / 2)
    out = Stage()(obs, par, 0.04)
    d = ground(out) - ground(obs)
    assert np.hypot(*d) == pytest.approx(expect, abs=1e-6)
    assert d[0] > 0 and abs(d[1]) < 1e-6  # on the side the model chose
    # a rigid move: the partner's posture is kept
    np.testing.assert_allclose(out - out.mean(0), par - par.mean(0), atol=1e-5)


def test_a_partner_on_top_of_the_person_steps_out_along_the_persons_facing() -> None:
    obs = person(1.0, 2.0, yaw=np.pi / 2)  # facing +X
    stage = Stage()
    out = stage(obs, obs.copy(), 0.04)
    d = ground(out) - ground(obs)
    assert d[0] == pytest.approx(0.5, abs=1e-6) and abs(d[1]) < 1e-6
    # the person's own hands are not a push on a partner the model put inside them: it stands apart
    stage(obs, obs.copy(), 0.04)
    assert stage.pushes == 0


def test_the_partner_walks_round_the_person_instead_of_jumping() -> None:
    stage = Stage(StageConfig(max_speed_m_s=2.5))
    obs = person(0.0, 2.0)
    stage(obs, person(0.8, 2.0), 0.04, other=person(1.0, 2.0))
    # the real second person goes round to the other side of the person: it moves 0.1 m per 1/25 s
    offsets = [ground(stage(obs, person(0.8, 2.0), 0.04, other=person(-1.0, 2.0))) - ground(obs) for _ in range(30)]
    steps = np.linalg.norm(np.diff([[0.8, 0.0], *offsets], axis=0), axis=1)
    assert steps.max() <= 0.1 + 1e-9
    assert all(0.5 - 1e-9 <= np.hypot(*o) <= 1.2 + 1e-9 for o in offsets)
    assert offsets[-1] == pytest.approx([-0.8, 0.0], abs=1e-6)


def test_the_partner_keeps_its_side_when_the_model_flips_or_the_other_person_wavers() -> None:
    stage = Stage()
    obs = person(0.0, 2.0)
    stage(obs, person(0.8, 2.0), 0.04, other=person(1.0, 2.0))
    out = [ground(stage(obs, person(-0.8, 2.0), 0.04, other=person(-0.1, 2.0))) - ground(obs) for _ in range(20)]
    assert all(o[0] == pytest.approx(0.8) for o in out)  # 0.1 m across: within side_margin_m, no change


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_the_partner_stands_beside_the_person_across_the_view_not_in_front_or_behind(side: float) -> None:
    # the model puts the partner 0.9 m in front of the person (towards the camera, +Z): in the
    # picture it would cover them; the stage puts it at their depth, on the side given
    obs = person(0.3, 1.0)
    out = Stage()(obs, person(0.3, 1.9, np.pi), 0.04, side=side)
    d = ground(out) - ground(obs)
    assert d == pytest.approx([side * 0.9, 0.0], abs=1e-6)
    # with a second person tracked, their side wins over the one given
    out = Stage()(obs, person(0.3, 1.9, np.pi), 0.04, other=person(0.3 - side, 1.4), side=side)
    assert (ground(out) - ground(obs)) == pytest.approx([-side * 0.9, 0.0], abs=1e-6)


@pytest.mark.parametrize("bearing_deg", [0.0, 40.0, -60.0])
def test_the_partner_stands_beside_the_person_as_a_turned_camera_sees_them(bearing_deg: float) -> None:
    # a camera 4 m away at a bearing round the person (the simulator's random cameras turn up to 60
    # degrees): the partner stands at the person's depth in that camera, to the right in its picture
    obs = person(0.0, 0.0)
    b = np.deg2rad(bearing_deg)
    cam = Camera.look_at([4.0 * np.sin(b), 1.6, 4.0 * np.cos(b)], [0.0, 0.9, 0.0], 55.0, 320, 240)
    out = Stage()(obs, person(0.0, 0.8, np.pi), 0.04, side=1.0, camera=cam)
    hips = [JOINT_INDEX["l_hip"], JOINT_INDEX["r_hip"]]
    depth = cam.depth(np.stack([out[hips].mean(0), obs[hips].mean(0)]))
    assert depth[0] == pytest.approx(depth[1], abs=1e-6)
    assert np.hypot(*(ground(out) - ground(obs))) == pytest.approx(0.8, abs=1e-6)
    u = cam.project(np.stack([out[hips].mean(0), obs[hips].mean(0)]))[:, 0]
    assert u[0] - u[1] > 30.0  # image right, clear of the person
    if bearing_deg:  # world X (a camera without yaw) would put it in front of or behind them in this view
        old = Stage()(obs, person(0.0, 0.8, np.pi), 0.04, side=1.0)
        assert abs(cam.depth(old[hips].mean(0)[None])[0] - depth[1]) > 0.3


def arm_out_box(arm_m: float) -> tuple[float, float, float, float]:
    """The silhouette box ``(x, y, w, h)`` in ``CAM`` of ``person(0, 0, 0)`` (facing the camera, 0.5 m
    wide) with an arm held out ``arm_m`` past their body towards image right, pixels.
    """
    uv = CAM.project(person(0.0, 0.0, 0.0))
    x0, y0, x1, y1 = uv[:, 0].min(), uv[:, 1].min(), uv[:, 0].max(), uv[:, 1].max()
    arm = CAM.project(np.array([[arm_m, 1.3, 0.0]]))[0, 0] - CAM.project(np.array([[0.0, 1.3, 0.0]]))[0, 0]
    return (x0, y0, x1 - x0 + arm, y1 - y0)


def test_the_partner_keeps_clear_of_the_persons_silhouette_in_the_picture() -> None:
    # the model puts the partner 0.5 m beside the person; their silhouette, an arm held out its way,
    # reaches 0.6 m past their body: the partner stands further off, as little as clears it
    obs, par = person(0.0, 0.0, 0.0), person(0.5, 0.0, 0.0)  # both facing the camera: 0.5 m wide
    box = arm_out_box(0.6)
    assert box_overlap(Stage()(obs, par, 0.04, side=1.0, camera=CAM), box)[0] > 0.15  # the model's place covers the arm
    out = Stage()(obs, par, 0.04, side=1.0, camera=CAM, box=box)
    gap = np.hypot(*(ground(out) - ground(obs)))
    assert box_overlap(out, box)[0] <= 0.15 and 0.5 < gap < 1.2
    # a box it cannot clear within max_distance_m (a silhouette 2 m wide): never further than the limit
    wide = arm_out_box(1.56)
    out = Stage()(obs, par, 0.04, side=1.0, camera=CAM, box=wide)
    assert box_overlap(out, wide)[0] > 0.15 and 0.5 - 1e-9 <= np.hypot(*(ground(out) - ground(obs))) <= 1.2 + 1e-9


def test_the_partner_keeps_most_of_itself_out_of_the_persons_silhouette() -> None:
    # a box much larger than the partner's (a silhouette with an arm held out 0.6 m) keeps the union
    # large wherever the partner stands: by intersection over union alone (clear_iou 1: off here) the
    # partner stays inside it; with clear_inside (0.6) at most 0.6 of its own box lies inside
    obs, par = person(0.0, 0.0, 0.0), person(0.5, 0.0, 0.0)
    box = arm_out_box(0.6)
    loose = Stage(StageConfig(clear_iou=1.0, clear_inside=1.0))(obs, par, 0.04, side=1.0, camera=CAM, box=box)
    out = Stage(StageConfig(clear_iou=1.0))(obs, par, 0.04, side=1.0, camera=CAM, box=box)
    gap = float(np.hypot(*(ground(out) - ground(obs))))
    assert box_overlap(loose, box)[1] > 0.6 and box_overlap(out, box)[1] <= 0.6
    assert np.hypot(*(ground(loose) - ground(obs))) < gap <= 1.2
    with pytest.raises(ValueError, match="clear_inside"):
        StageConfig(clear_inside=1.5)


def test_the_partner_stays_beside_a_person_whose_estimate_jumps() -> None:
    stage = Stage()
    stage(person(0.0, 2.0), person(0.8, 2.0), 0.04)
    obs = person(-1.5, -1.0)  # the tracker's estimate of the person jumps 3.4 m in one frame
    out = stage(obs, person(0.8, 2.0), 0.04)
    assert np.hypot(*(ground(out) - ground(obs))) <= 1.2 + 1e-9


@pytest.mark.parametrize("lift", [-0.4, 0.0, 1.5])
def test_the_partner_stands_on_the_ground(lift: float) -> None:
    par = person(0.8, 2.0) + [0.0, lift, 0.0]
    out = Stage()(person(0.0, 2.0), par, 0.04)
    ankle = out[[10, 13], 1].min()
    assert 0.0 <= ankle <= 0.3 + 1e-6
    if lift == 0.0:
        assert ankle == pytest.approx(par[[10, 13], 1].min())


def test_bad_limits_are_refused_naming_them() -> None:
    with pytest.raises(ValueError, match="distance limits"):
        StageConfig(min_distance_m=1.5, max_distance_m=1.0)
    with pytest.raises(ValueError, match="take_min_m"):
        StageConfig(take_min_m=-0.1)
    with pytest.raises(ValueError, match="bones='tall'"):
        StageConfig(bones="tall")


def drawn_height(X: np.ndarray) -> float:
    """Projected height in ``CAM`` of joints X (14, 3), head to mid-ankle, pixels."""
    uv = CAM.project(X)
    return float(np.linalg.norm(uv[JOINT_INDEX["head"]] - uv[[JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]]].mean(0)))


def test_the_partner_keeps_one_body_of_the_observed_persons_build_and_is_drawn_at_their_size() -> None:
    rng = np.random.default_rng(0)
    T = 40
    P = np.tile(neutral_pose(x=0.0, z=0.0, yaw=np.pi / 2), (T, 1))
    P[:, DOF_INDEX["r_shoulder_flex"]] = np.linspace(0.0, 1.5, T)
    observed = forward_kinematics(P, DEFAULT_DIMS.scaled(1.9))
    Q = np.tile(neutral_pose(x=0.8, z=0.0, yaw=-np.pi / 2), (T, 1))
    Q[:, DOF_INDEX["l_shoulder_flex"]] = np.linspace(0.0, 1.5, T)
    # a model's partner: a smaller build whose limbs stretch and shrink from frame to frame
    model = forward_kinematics(Q, DEFAULT_DIMS.scaled(1.5))
    hips = 0.5 * (model[:, [JOINT_INDEX["l_hip"]]] + model[:, [JOINT_INDEX["r_hip"]]])
    model = hips + (model - hips) * rng.uniform(0.9, 1.1, (T, 1, 1))
    ratios = {}
    for bones in ("observed", "model"):
        stage = Stage(StageConfig(bones=bones))
        out = np.array([stage(observed[t], model[t], 0.04, camera=CAM) for t in range(T)])
        ratios[bones] = [drawn_height(out[t]) / drawn_height(observed[t]) for t in range(T)]
        if bones == "observed":  # every frame on the observed person's bones
            np.testing.assert_allclose(bone_lengths(out), bone_lengths(observed), atol=1e-6)
        else:
            np.testing.assert_allclose(bone_lengths(out), bone_lengths(model), atol=1e-6)
    # beside them at their depth, drawn at their size; as the model gave it, a head shorter and changing
    assert np.abs(np.array(ratios["observed"]) - 1.0).max() < 0.03
    assert np.median(ratios["model"]) < 0.85 and np.ptp(ratios["model"]) > 0.1


def test_the_dual_hmm_gives_a_body_for_a_person_unlike_any_of_training() -> None:
    hmm = DualHMM(DualHMMConfig(fit=FitConfig(n_states=8, n_iter=10, both_roles=False))).fit(
        [planted_pair(s) for s in range(6)]
    )
    odd = planted_pair(9).a[0].copy()
    odd[:, 1] *= 3.0  # a 5 m tall, stretched estimate (a tracker's bad frame)
    odd[4] += [2.0, -1.0, 3.0]
    hmm.reset()
    out = hmm.step(odd)
    height = out[:, 1].max() - out[:, 1].min()
    span = np.ptp(out[:, [0, 2]], axis=0).max()
    assert 1.0 < height < 2.2 and span < 1.5


def test_two_bone_ik_puts_the_wrist_on_a_reachable_target_and_keeps_the_bones() -> None:
    s, e, w = np.array([0.0, 1.45, 0.0]), np.array([0.0, 1.2, 0.05]), np.array([0.0, 0.95, 0.1])
    for target in (np.array([0.3, 1.2, 0.2]), np.array([0.0, 1.45, 0.4]), np.array([-0.2, 1.1, 0.25])):
        e2, w2 = two_bone_ik(s, e, w, target)
        np.testing.assert_allclose(w2, target, atol=1e-5)
        assert np.linalg.norm(e2 - s) == pytest.approx(np.linalg.norm(e - s), abs=1e-6)
        assert np.linalg.norm(w2 - e2) == pytest.approx(np.linalg.norm(w - e), abs=1e-6)
    # out of reach: the arm stretches towards it from its shoulder
    e2, w2 = two_bone_ik(s, e, w, np.array([2.0, 1.45, 0.0]))
    assert np.linalg.norm(w2 - s) == pytest.approx(np.linalg.norm(e - s) + np.linalg.norm(w - e), abs=1e-4)
    assert w2[0] > 0.49 and abs(w2[1] - 1.45) < 1e-3


def test_the_partners_hand_meets_the_hand_it_comes_near_and_ignores_a_far_one() -> None:
    obs, par = person(0.0, 2.0), person(0.8, 2.0, -np.pi / 2)
    far, pull = reach(obs, par)
    assert pull == 0.0 and np.array_equal(far, par)
    offered = obs.copy()
    offered[7] = par[4] + [-0.08, 0.05, 0.0]  # the observed right wrist 10 cm from the partner's left
    met, pull = reach(offered, par)
    assert pull == 1.0
    np.testing.assert_allclose(met[4], offered[7], atol=1e-5)
    np.testing.assert_array_equal(np.delete(met, [3, 4], axis=0), np.delete(par, [3, 4], axis=0))
    half, pull = reach(offered, par, ReachConfig(r_engage=0.45, r_contact=0.0))
    assert 0.0 < pull < 1.0 and np.linalg.norm(half[4] - offered[7]) < np.linalg.norm(par[4] - offered[7])


def test_the_partner_gives_way_while_a_hand_pushes_its_chest_is_thrown_back_when_released_and_returns() -> None:
    stage = Stage(StageConfig(recoil_m=0.3, recoil_s=0.8))
    obs, par = person(0.0, 2.0), person(0.7, 2.0, -np.pi / 2)

    def gap(X: np.ndarray, P: np.ndarray) -> float:
        return float(np.hypot(*(ground(P) - ground(X))))

    assert gap(obs, stage(obs, par, 0.04)) == pytest.approx(0.7)
    pushing = obs.copy()
    pushing[7] = [0.6, 1.3, 2.0]  # the right wrist on the partner's chest
    gaps = [gap(pushing, stage(pushing, par, 0.04)) for _ in range(5)]
    assert stage.pushes == 1  # one push, however long the hand stays
    # while pushed it gives way at yield_speed_m_s (0.2 m/s: 8 mm a frame)
    np.testing.assert_allclose(np.diff([0.7, *gaps]), 0.2 * 0.04, atol=1e-6)
    released = [gap(obs, stage(obs, par, 0.04)) for _ in range(20)]
    # released, it is thrown back at recoil_speed_m_s (3 cm a frame) to recoil_max_m (0.4 m) from where
    # the push landed, within max_distance_m
    steps = np.diff([gaps[-1], *released])
    assert max(released) == pytest.approx(0.7 + 0.4) and steps.max() <= 0.03 + 1e-9 and (steps[:5] > 0).all()
    later = [gap(obs, stage(obs, par, 0.04)) for _ in range(100)]
    assert later[-1] == pytest.approx(0.7, abs=0.01)  # then it returns where the model puts it
    assert stage.pushes == 1 and max(gaps + released + later) <= 1.2 + 1e-9


def test_a_pushed_partner_near_the_limit_stands_where_the_push_lands_and_recoils_within_it() -> None:
    # the model puts the partner at 1.2 m (the limit): pushed, it stands in to keep recoil_m (0.3 m) of
    # room, never past max_distance_m, and is thrown back as far as the limit when released
    stage = Stage()
    obs, par = person(0.0, 2.0), person(1.2, 2.0, -np.pi / 2)

    def gap(X: np.ndarray) -> float:
        return float(np.hypot(*(ground(stage(X, par, 0.04)) - ground(X))))

    assert gap(obs) == pytest.approx(1.2)
    pushing = obs.copy()
    pushing[7] = [1.05, 1.3, 2.0]  # the right wrist on the partner's chest
    during = [gap(pushing) for _ in range(3)]
    assert stage.pushes == 1 and during[-1] < 1.0
    after = [gap(obs) for _ in range(30)]
    assert max(during + after) <= 1.2 + 1e-9 and max(after) - during[-1] >= 0.2
    # recoil_m 0: it does not recoil
    still = Stage(StageConfig(recoil_m=0.0))
    gaps = [float(np.hypot(*(ground(still(X, par, 0.04)) - ground(X)))) for X in [obs, pushing, pushing, *[obs] * 20]]
    assert max(gaps) == pytest.approx(1.2) and min(gaps[3:]) >= 0.9 - 1e-9


def outline(x0: float, top: float, height: float, arm_at: float | None, arm_px: float) -> np.ndarray:
    """Control points (n, 2) of a standing person's outline facing image right: a 0.25 h wide body
    from ``x0``, a stride's foot 0.2 h ahead at the floor, and an arm held out ``arm_px`` beyond the
    body at ``arm_at`` of the height above the floor (None: arms down).
    """
    w, floor = 0.25 * height, top + height
    pts = [[x0, top], [x0 + w, top], [x0 + w, top + 0.5 * height], [x0 + w, floor - 0.1 * height]]
    pts += [[x0 + w + 0.2 * height, floor], [x0, floor], [x0, top + 0.5 * height]]
    if arm_at is not None:
        pts.insert(2, [x0 + w + arm_px, floor - arm_at * height])
    return np.array(pts, np.float64)


def test_the_silhouette_says_how_far_and_how_high_a_hand_is_held_out() -> None:
    # a 1.7 m person 200 px tall; centroid at the body's middle; the arm 80 px beyond the body at 0.55 h
    ctrl = outline(100.0, 50.0, 200.0, 0.55, 80.0)
    box = (100, 50, int(ctrl[:, 0].max() - 100), 200)
    got = silhouette_reach(box, (125.0, 150.0), 1.0, 1.7, ctrl)
    assert got.extent_m == pytest.approx((25 + 80) / 200 * 1.7) and got.height_m == pytest.approx(0.55 * 1.7)
    assert got.centre_m == pytest.approx(125 / 200 * 1.7) and not got.touching
    assert got.centre_px == (125.0, 150.0) and got.other_px is None
    assert silhouette_reach(box, (125.0, 150.0), 1.0, 1.7, ctrl, other=(300.0, 140.0)).other_px == (300.0, 140.0)
    assert silhouette_reach(box, (125.0, 150.0), 1.0, 1.7, ctrl, touching=True).touching
    # arms down: the stride's foot reaches further than the body but is no reach; the body's edge is
    down = outline(100.0, 50.0, 200.0, None, 0.0)
    reach_m = silhouette_reach((100, 50, 90, 200), (125.0, 150.0), 1.0, 1.7, down).extent_m
    assert reach_m == pytest.approx(25 / 200 * 1.7)
    # towards image left: the back of the body; without an outline, the box's edge and no height
    assert silhouette_reach(box, (125.0, 150.0), -1.0, 1.7, ctrl).extent_m == pytest.approx(25 / 200 * 1.7)
    assert silhouette_reach((100, 50, 90, 200), (125.0, 150.0), 1.0, 1.7).height_m is None


def test_the_partner_stands_to_take_a_hand_held_out_and_meets_it_where_the_silhouette_says() -> None:
    stage = Stage()
    obs, par = person(0.0, 2.0), person(0.9, 2.0, -np.pi / 2)  # the tracked arms stay down
    stage(obs, par, 0.04, side=1.0, silhouette=Reach(0.2, None, 0.0))
    assert stage.offered_ is None and stage.pushes == 0
    for _ in range(10):  # a hand held out, the body still: offered where the silhouette says
        out = stage(obs, par, 0.04, side=1.0, silhouette=Reach(0.6, 1.0, 0.0))
    assert stage.pushes == 0
    np.testing.assert_allclose(stage.offered_, [0.6, 1.0, 2.0], atol=1e-6)
    # the partner stands to take it: 0.8 of its arm's length (0.505 m) beyond the hand, not where the model put it
    assert np.hypot(*(ground(out) - ground(obs))) == pytest.approx(0.6 + 0.8 * 0.505, abs=1e-3)
    # a model's partner at 0.7 m: the hand met 0.7 of the way to it at most (0.49 m), the partner steps out
    # to an arm's length beyond it (take_min_m 0 here) ...
    near = Stage(StageConfig(take_min_m=0.0))
    for _ in range(10):
        out = near(obs, person(0.7, 2.0, -np.pi / 2), 0.04, side=1.0, silhouette=Reach(0.6, 1.0, 0.0))
    np.testing.assert_allclose(near.offered_, [0.49, 1.0, 2.0], atol=1e-6)
    assert np.hypot(*(ground(out) - ground(obs))) == pytest.approx(0.49 + 0.8 * 0.505, abs=1e-3)
    # ... and by default never nearer than take_min_m (1.0 m)
    floor = Stage()
    for _ in range(10):
        out = floor(obs, person(0.7, 2.0, -np.pi / 2), 0.04, side=1.0, silhouette=Reach(0.6, 1.0, 0.0))
    assert np.hypot(*(ground(out) - ground(obs))) == pytest.approx(1.0, abs=1e-3)
    # a silhouette reaching further: met 0.7 of the way to the model's partner (0.9 m) at most
    stage(obs, par, 0.04, side=1.0, silhouette=Reach(0.85, 1.0, 0.0))
    np.testing.assert_allclose(stage.offered_, [0.63, 1.0, 2.0], atol=1e-6)


def test_a_hand_held_out_while_the_silhouettes_touch_is_met_where_the_picture_shows_it() -> None:
    # the two regions' centroids 200 px apart across the picture, the person's box 180 px tall: the hand
    # meets meet_touch (0.45) of the way across, hand_box_frac (0.62) of the box above its bottom
    obs, par = person(0.0, 0.0, 0.0), person(0.9, 0.0, 0.0)
    box = (100.0, 40.0, 60.0, 180.0)
    shape = Reach(1.1, 0.5, 0.0, True, (130.0, 130.0), (330.0, 128.0))
    assert touching_hand_px(shape, box, 0.45, 0.62) == pytest.approx((130.0 + 0.45 * 200.0, 40.0 + 0.38 * 180.0))
    stage = Stage()
    stage(obs, par, 0.04, side=1.0, other=person(2.5, 0.0, 0.0), silhouette=shape, camera=CAM, box=box)
    assert stage.pushes == 0
    # the offered hand projects onto that pixel, at the depth of the person's hips, whatever the tracked
    # second person's place (2.5 m off here)
    np.testing.assert_allclose(CAM.project(stage.offered_[None])[0], [220.0, 108.4], atol=1e-6)
    hips = obs[[JOINT_INDEX["l_hip"], JOINT_INDEX["r_hip"]]].mean(axis=0)
    assert CAM.depth(stage.offered_) == pytest.approx(float(CAM.depth(hips)))
    # without the other's region: placed from the tracked bodies as before
    alone = Stage()
    alone(obs, par, 0.04, side=1.0, silhouette=shape._replace(other_px=None), camera=CAM, box=box)
    assert alone.offered_[0] == pytest.approx(0.45 * 0.9)


def test_a_hand_held_out_apart_is_met_at_the_outlines_tip_where_the_picture_shows_it() -> None:
    # the observed person as CAM sees them, an arm held out 45 px beyond the body at 0.6 of the height
    obs = person(0.0, 0.0, 0.0)
    uv = CAM.project(obs)
    top, floor = float(uv[:, 1].min()), float(uv[:, 1].max())
    height = floor - top
    x0 = float(uv[:, 0].mean()) - 0.125 * height
    ctrl = outline(x0, top, height, 0.6, 45.0)
    box = (x0, top, float(ctrl[:, 0].max()) - x0, height)
    shape = silhouette_reach(box, (x0 + 0.125 * height, top + 0.5 * height), 1.0, stature(obs), ctrl)
    assert shape.extent_m > StageConfig().offer_m and not shape.touching
    tip = (x0 + 0.25 * height + 45.0, floor - 0.6 * height)
    assert silhouette_tip_px(shape, box, stature(obs), 1.0) == pytest.approx(tip)
    hips = obs[[JOINT_INDEX["l_hip"], JOINT_INDEX["r_hip"]]].mean(axis=0)
    arm = 0.8 * 0.505  # STEP_REACH of the partner's arm's length
    for model_gap in (0.5, 0.9):  # wherever the model put the partner
        stage = Stage(StageConfig(tip_back=0.0))
        for _ in range(5):
            out = stage(obs, person(model_gap, 0.0, 0.0), 0.04, side=1.0, silhouette=shape, camera=CAM, box=box)
        # offered where the picture shows the hand, at the depth of the person's hips ...
        np.testing.assert_allclose(CAM.project(stage.offered_[None])[0], tip, atol=1e-6)
        assert CAM.depth(stage.offered_) == pytest.approx(float(CAM.depth(hips)))
        # ... not drawn in to meet_frac of the model's distance: the partner stands to take it there
        along = stage.offered_[0] - hips[0]
        assert along > StageConfig().meet_frac * 0.5
        assert np.hypot(*(ground(out) - ground(obs))) == pytest.approx(along + arm, abs=0.02)
        drawn, pull = stage.finish(obs, out)
        assert pull == 1.0 and min(np.linalg.norm(drawn[[4, 7]] - stage.offered_, axis=1)) < 1e-5
        # its hand on the tip, its body clear of the person's box
        iou, _ = box_overlap(drawn, box)
        assert iou <= StageConfig().clear_iou
    # by default its wrist is met tip_back (0.07) of the stature short of the fingertips, towards the person
    clasp = Stage()
    clasp(obs, person(0.5, 0.0, 0.0), 0.04, side=1.0, silhouette=shape, camera=CAM, box=box)
    np.testing.assert_allclose(clasp.offered_ - stage.offered_, [-0.07 * stature(obs), 0.0, 0.0], atol=1e-6)
    # without the camera and the box: the tip is not placed in the picture (meet_frac of the model's distance)
    blind = Stage()
    blind(obs, person(0.5, 0.0, 0.0), 0.04, side=1.0, silhouette=shape)
    assert blind.offered_[0] == pytest.approx(min(shape.extent_m, 0.7 * 0.5))


def test_a_partner_taking_a_hand_the_outline_ends_short_of_stays_out_of_the_arm_held_out() -> None:
    # the observed person as CAM sees them; the outline holds only the upper arm (20 px beyond the body at
    # 0.6 of the height, just over offer_m): the forearm and hand, another 0.15 h further, it missed (a
    # sleeve like the background, an arm pointing)
    obs = person(0.0, 0.0, 0.0)
    uv = CAM.project(obs)
    top, floor = float(uv[:, 1].min()), float(uv[:, 1].max())
    height = floor - top
    x0 = float(uv[:, 0].mean()) - 0.125 * height
    ctrl = outline(x0, top, height, 0.6, 20.0)
    box = (x0, top, float(ctrl[:, 0].max()) - x0, height)
    shape = silhouette_reach(box, (x0 + 0.125 * height, top + 0.5 * height), 1.0, stature(obs), ctrl)
    assert StageConfig().offer_m < shape.extent_m < 0.6 and not shape.touching
    arm = (x0, top, box[2] + 0.15 * height, height)  # the person with the whole arm, as the picture shows them
    drawn = {}
    for take_min in (0.0, StageConfig().take_min_m):
        stage = Stage(StageConfig(take_min_m=take_min))
        for _ in range(10):
            out = stage(obs, person(0.5, 0.0, 0.0), 0.04, side=1.0, silhouette=shape, camera=CAM, box=box)
        drawn[take_min], pull = stage.finish(obs, out)
        assert pull == 1.0  # the hand the outline offers is taken either way
    gap = {k: float(np.hypot(*(ground(v) - ground(obs)))) for k, v in drawn.items()}
    # an arm's length beyond the outline's tip: no overlap with the outline's box, but inside the arm held out
    assert gap[0.0] < 0.8 and box_overlap(drawn[0.0], box)[0] < 0.25
    assert box_overlap(drawn[0.0], arm)[0] > 0.3
    # never nearer than take_min_m (1 m): out of it (as real_partner.py counts an overlap, IoU over 0.25)
    assert gap[1.0] == pytest.approx(1.0, abs=1e-3)
    assert box_overlap(drawn[1.0], arm)[0] < 0.25
    # a whole arm in the outline (45 px): an arm's length beyond its tip is further than take_min_m
    whole = outline(x0, top, height, 0.6, 45.0)
    wbox = (x0, top, float(whole[:, 0].max()) - x0, height)
    wshape = silhouette_reach(wbox, (x0 + 0.125 * height, top + 0.5 * height), 1.0, stature(obs), whole)
    far = []
    for take_min in (0.0, 1.0):
        stage = Stage(StageConfig(take_min_m=take_min))
        for _ in range(10):
            out = stage(obs, person(0.5, 0.0, 0.0), 0.04, side=1.0, silhouette=wshape, camera=CAM, box=wbox)
        far.append(stage.finish(obs, out)[0])
    np.testing.assert_allclose(far[0], far[1])
    assert np.hypot(*(ground(far[1]) - ground(obs))) > 1.0


def test_a_hand_held_out_stays_offered_while_the_outline_flickers_about_the_limit() -> None:
    obs, par = person(0.0, 2.0), person(0.9, 2.0, -np.pi / 2)
    stage = Stage()
    offered = []
    for extent in [0.6, 0.42, 0.43, 0.41, 0.6, 0.42]:  # offer_m 0.45; 0.04 s a frame, held 0.3 s
        stage(obs, par, 0.04, side=1.0, silhouette=Reach(extent, 1.0, 0.0))
        offered.append(stage.offered_ is not None)
    assert all(offered)
    for _ in range(8):  # the hand down for longer than offer_hold_s: no longer offered
        stage(obs, par, 0.04, side=1.0, silhouette=Reach(0.2, 1.0, 0.0))
    assert stage.offered_ is None
    held = Stage(StageConfig(offer_hold_s=0.0))
    held(obs, par, 0.04, side=1.0, silhouette=Reach(0.6, 1.0, 0.0))
    held(obs, par, 0.04, side=1.0, silhouette=Reach(0.42, 1.0, 0.0))
    assert held.offered_ is None


def test_a_hand_held_out_while_the_silhouettes_touch_is_met_between_the_two_at_a_handshakes_height() -> None:
    obs, par = person(0.0, 2.0), person(0.9, 2.0, -np.pi / 2)
    ankle = obs[[10, 13], 1].min()
    # the outline's tip is where the regions were split (1.1 m out, 0.5 m high): no hand there. The hand
    # is met meet_touch (0.45) of the way to the real second person (1.1 m across the view) ...
    stage = Stage()
    stage(obs, par, 0.04, side=1.0, other=person(1.1, 2.0, -np.pi / 2), silhouette=Reach(1.1, 0.5, 0.0, True))
    assert stage.pushes == 0
    np.testing.assert_allclose(stage.offered_[[0, 2]], [0.45 * 1.1, 2.0], atol=1e-6)
    # ... at hand_frac (0.66) of the person's stature, whatever the tip's height
    assert stage.offered_[1] == pytest.approx(0.66 * stature(obs) + ankle)
    # ... whose depth the tracker has 1 m off: across the view only
    deep = Stage()
    deep(obs, par, 0.04, side=1.0, other=person(1.1, 3.0, -np.pi / 2), silhouette=Reach(1.1, 0.5, 0.0, True))
    np.testing.assert_allclose(deep.offered_[[0, 2]], [0.45 * 1.1, 2.0], atol=1e-6)
    # without a second person, 0.45 of the way to the partner the model placed (0.9 m)
    alone = Stage()
    alone(obs, par, 0.04, side=1.0, silhouette=Reach(1.1, 0.5, 0.0, True))
    np.testing.assert_allclose(alone.offered_[[0, 2]], [0.45 * 0.9, 2.0], atol=1e-6)


def test_a_pusher_walking_in_with_a_hand_held_high_pushes_when_the_silhouettes_touch() -> None:
    stage = Stage()
    obs, par = person(0.0, 2.0), person(0.9, 2.0, -np.pi / 2)

    def gap(k: int, touching: bool, height: float = 1.4) -> float:
        # the body advancing at 1 m/s (its silhouette's centre 4 cm a frame), a hand held out
        out = stage(obs, par, 0.04, side=1.0, silhouette=Reach(0.6, height, 0.04 * k, touching))
        return float(np.hypot(*(ground(out) - ground(obs))))

    # a hand held out at the chest (1.4 m: 0.79 of the stature) walking in: no push until the hand
    # lands (their silhouette touches someone else's)
    [gap(k, False) for k in range(1, 11)]
    assert stage.pushes == 0
    gaps = [gap(k, True) for k in range(11, 31)]
    assert stage.pushes == 1 and stage.offered_ is None  # no hand to take from someone pushing it
    # pushed on, it gives way at yield_speed_m_s (0.2 m/s: 8 mm a frame) from where the push landed (0.9 m)
    np.testing.assert_allclose(np.diff(gaps), 0.008, atol=1e-6)
    # the pusher's burst of advance over, the hand still on the other person: the push goes on
    held = [gap(31, True) for _ in range(5)]
    assert stage.pushes == 1 and np.all(np.diff([gaps[-1], *held]) > 0)
    # nor while the push goes on without the advance: a pushed partner reaching for the pushing hand
    # would stand with its arm inside the pusher
    assert stage.offered_ is None
    down = Reach(0.2, None, 0.04 * 31)
    later = [
        float(np.hypot(*(ground(stage(obs, par, 0.04, side=1.0, silhouette=down)) - ground(obs)))) for _ in range(60)
    ]
    # the push released (the arm down), it is thrown back as far as max_distance_m (1.2 m), then returns
    assert max(later) == pytest.approx(1.2) and later[-1] == pytest.approx(0.9, abs=0.01)


def test_people_walking_in_to_shake_hands_are_no_push_and_one_rushing_in_is() -> None:
    # walking in at 0.7 m/s (2.8 cm a frame) into a touch with the hand held at the waist (1.0 m: 0.56 of
    # the stature): no push
    obs, par = person(0.0, 2.0), person(0.9, 2.0, -np.pi / 2)

    def pushes(config: StageConfig, speed: float) -> int:
        stage = Stage(config)
        for k in range(1, 31):
            stage(obs, par, 0.04, side=1.0, silhouette=Reach(0.6, 1.0, speed * 0.04 * k, k > 10))
        return stage.pushes

    assert pushes(StageConfig(), 0.7) == 0
    # push_height 0: any hand advancing into a touch is a push
    assert pushes(StageConfig(push_height=0.0), 0.7) == 1
    # rushing in at 1.5 m/s (faster than push_rush_m_s): a push whatever the hand's height
    assert pushes(StageConfig(), 1.5) == 1


def test_no_hand_is_taken_from_someone_rushing_in_or_from_a_pusher_while_thrown_back() -> None:
    obs, par = person(0.0, 2.0), person(0.9, 2.0, -np.pi / 2)

    def offered(stage: Stage, speed: float, k: int, touching: bool, height: float = 1.0) -> bool:
        stage(obs, par, 0.04, side=1.0, silhouette=Reach(0.6, height, speed * 0.04 * k, touching))
        return stage.offered_ is not None

    # a hand held out at the waist walking in at 0.3 m/s: offered; rushing in at 1.5 m/s (push_rush_m_s),
    # or driven in at 0.7 m/s held at the chest (push_speed_m_s, push_height), not yet touching: none
    # once the smoothed advance (advance_s) says so
    walk, rush, drive = Stage(), Stage(), Stage()
    assert all(offered(walk, 0.3, k, False) for k in range(1, 16))
    assert not any([offered(rush, 1.5, k, False) for k in range(1, 16)][6:])
    assert not any([offered(drive, 0.7, k, False, 1.4) for k in range(1, 16)][6:])
    # the push lands and is released, the pusher's hand still out: the partner is thrown back and takes
    # no hand until the recoil has faded
    for k in range(16, 26):
        offered(rush, 1.5, k, True)
    assert rush.pushes == 1
    after = [offered(rush, 0.0, 25, False) for _ in range(60)]
    assert not any(after[:10]) and after[-1]


def test_without_push_touch_the_advance_alone_is_a_push_and_a_region_merging_is_none() -> None:
    obs, par = person(0.0, 2.0), person(0.9, 2.0, -np.pi / 2)
    # without push_touch, the advance alone is a push (a graph whose silhouettes never merge)
    eager = Stage(StageConfig(push_touch=False))
    for k in range(10):
        eager(obs, par, 0.04, side=1.0, silhouette=Reach(0.6, 1.4, 0.04 * k))
    assert eager.pushes == 1
    # a region merging (its centre jumping 0.5 m in a frame) is no advance
    calm = Stage()
    for k in range(10):
        calm(obs, par, 0.04, side=1.0, silhouette=Reach(0.6, 1.4, 0.5 * (k % 2), True))
    assert calm.pushes == 0


def test_the_partner_takes_a_hand_held_out_within_its_reach_and_not_one_out_of_it() -> None:
    obs, par = person(0.0, 2.0), person(0.9, 2.0, -np.pi / 2)
    hand = np.array([0.6, 1.15, 2.0])
    met, pull = reach(obs, par, offered=hand)
    assert pull == 1.0
    assert min(np.linalg.norm(met[[4, 7]] - hand, axis=1)) < 1e-5
    arm = [4, 3] if np.linalg.norm(met[4] - hand) < 1e-5 else [7, 6]  # its bones are kept
    np.testing.assert_allclose(
        np.linalg.norm(met[arm[0]] - met[arm[1]]), np.linalg.norm(par[arm[0]] - par[arm[1]]), atol=1e-6
    )
    far, pull = reach(obs, par, offered=np.array([-1.5, 1.0, 2.0]))  # 2.4 m away: the model's hands as they are
    assert pull == 0.0 and np.array_equal(far, par)


def test_a_box_cut_off_by_the_frame_reaches_down_to_the_tracked_feet() -> None:
    X = person(0.3, 2.0)
    uv = CAM.project(X)
    soles = X[[JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]]] * [1.0, 0.0, 1.0]
    head, feet = float(uv[JOINT_INDEX["head"], 1]), float(CAM.project(soles)[:, 1].max())
    rows = int(round(0.5 * (head + feet)))  # the frame ends halfway down the person
    box = (100.0, head, 50.0, rows - head)
    x, y, w, h = whole_box(box, rows, X, CAM)
    assert (x, y, w) == box[:3] and y + h == pytest.approx(feet, abs=1.0)
    assert whole_box(box, rows + 1, X, CAM) == box  # clear of the bottom edge: as it is
    assert whole_box(box, rows, X, None) == box  # no camera: as it is
    # their reach measured on the box cut off is the reach of the whole person: the arm held out
    # at 0.55 of their height, 0.4 of it beyond the body's edge
    tall = feet - head
    ctrl = outline(100.0, head, tall, 0.55, 0.4 * tall)
    cut = ctrl.copy()
    cut[:, 1] = np.minimum(cut[:, 1], rows - 1)
    centroid = (110.0, head + 0.3 * tall)
    shape = PersonShape(
        id=3, side="left", ctrl=cut, centroid=np.array(centroid), bbox=(100, int(head), 150, rows - int(head))
    )
    whole = silhouette_reach((100, head, 150, tall), centroid, 1.0, stature(X), ctrl)
    got, got_box = observed_silhouette([shape], 3, "left", X, 1.0, CAM, rows)
    assert got_box[3] == pytest.approx(feet - int(head), abs=1.0)
    assert got.extent_m == pytest.approx(whole.extent_m, rel=0.02) and got.height_m == pytest.approx(
        whole.height_m, rel=0.02
    )
    # without the camera, the part in view is taken for the whole person: the reach comes out far too long
    assert observed_silhouette([shape], 3, "left", X, 1.0, None, rows)[0].extent_m > 1.5 * whole.extent_m
