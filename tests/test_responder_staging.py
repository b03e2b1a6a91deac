"""Where the generated partner stands (the stage's limits), its hand contact, and the dual HMM's pose
on a person unlike any of training.
"""

from __future__ import annotations

import numpy as np
import pytest

from counterpart.nodes.responder.dual_hmm import DualHMM, DualHMMConfig, FitConfig
from counterpart.nodes.responder.frames import actor_frame
from counterpart.nodes.responder.reach import ReachConfig, reach, two_bone_ik
from counterpart.nodes.responder.staging import Stage, StageConfig
from tests.pose_source import facing
from tests.responder_fixtures import planted_pair


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
    stage(obs, person(0.8, 2.0), 0.04)
    # the model flips the partner to the other side of the person: it moves 0.1 m per 1/25 s
    offsets = [ground(stage(obs, person(-0.8, 2.0), 0.04)) - ground(obs) for _ in range(30)]
    steps = np.linalg.norm(np.diff([[0.8, 0.0], *offsets], axis=0), axis=1)
    assert steps.max() <= 0.1 + 1e-9
    assert all(0.5 - 1e-9 <= np.hypot(*o) <= 1.2 + 1e-9 for o in offsets)
    assert offsets[-1] == pytest.approx([-0.8, 0.0], abs=1e-6)


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


def test_the_partner_steps_back_when_a_hand_pushes_its_chest_and_then_returns() -> None:
    stage = Stage(StageConfig(recoil_m=0.3, recoil_s=0.8))
    obs, par = person(0.0, 2.0), person(0.7, 2.0, -np.pi / 2)

    def gap(X: np.ndarray, P: np.ndarray) -> float:
        return float(np.hypot(*(ground(P) - ground(X))))

    assert gap(obs, stage(obs, par, 0.04)) == pytest.approx(0.7)
    pushing = obs.copy()
    pushing[7] = [0.6, 1.3, 2.0]  # the right wrist on the partner's chest
    gaps = [gap(pushing, stage(pushing, par, 0.04)) for _ in range(10)]
    assert stage.pushes == 1  # one push, however long the hand stays
    assert max(gaps) > 0.9 and np.all(np.diff(gaps[:3]) > 0) and max(np.diff([0.7, *gaps])) <= 0.1 + 1e-9
    later = [gap(obs, stage(obs, par, 0.04)) for _ in range(100)]
    assert later[-1] == pytest.approx(0.7, abs=0.01)  # the push fades: back where the model puts it
