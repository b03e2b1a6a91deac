"""Where the generated partner stands: the stage's limits, and the dual HMM's pose on a person unlike
any of training."""
from __future__ import annotations

import numpy as np
import pytest

from nodes.responder.dual_hmm import DualHMM
from nodes.responder.frames import actor_frame
from nodes.responder.staging import Stage, StageConfig
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
    out = Stage()(obs, obs.copy(), 0.04)
    d = ground(out) - ground(obs)
    assert d[0] == pytest.approx(0.5, abs=1e-6) and abs(d[1]) < 1e-6


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
    hmm = DualHMM(n_states=8, n_iter=10, both_roles=False).fit([planted_pair(s) for s in range(6)])
    odd = planted_pair(9).a[0].copy()
    odd[:, 1] *= 3.0        # a 5 m tall, stretched estimate (a tracker's bad frame)
    odd[4] += [2.0, -1.0, 3.0]
    hmm.reset()
    out = hmm.step(odd)
    height = out[:, 1].max() - out[:, 1].min()
    span = np.ptp(out[:, [0, 2]], axis=0).max()
    assert 1.0 < height < 2.2 and span < 1.5
