"""counterpart.sim.scenarios: physics, contacts, determinism, emotion, planted listener rules, CMU pairs."""

from __future__ import annotations

import os

import numpy as np
import pytest

from counterpart.body.kinematics import forward_kinematics, lowest_point
from counterpart.body.pose import DOF_INDEX, within_limits
from counterpart.body.skeleton import JOINT_INDEX as J
from counterpart.body.trajectory import TwoPersonTrajectory
from counterpart.sim.dataset import generate_dataset
from counterpart.sim.scenarios import PLANTED_RULES, SCENARIOS, SIGNAL_INDEX, make_scenario

CMU = os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data", "cmu")
TORSO = [J[n] for n in ("head", "neck", "l_shoulder", "r_shoulder", "l_hip", "r_hip")]


def _pelvis(X: np.ndarray) -> np.ndarray:
    return 0.5 * (X[..., J["l_hip"], :] + X[..., J["r_hip"], :])


@pytest.mark.parametrize("name", list(SCENARIOS))
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_scenario_physics(name: str, seed: int) -> None:
    kw = {"duration": 10.0} if name == "conversation" else {}
    sc = make_scenario(name, seed=seed, **kw)
    T = sc.n_frames
    assert sc.poses_a.shape == (T, 28) and sc.signals_a.shape == (T, 5) and sc.phase.shape == (T,)
    assert sc.signals_a.dtype == np.int8 and set(np.unique(sc.phase)) <= {0, 1, 2}
    assert np.all(np.diff(sc.phase) >= 0), "phases run approach -> contact -> retreat"
    X = sc.joints()
    for P, d, k in ((sc.poses_a, sc.dims_a, 0), (sc.poses_b, sc.dims_b, 1)):
        assert within_limits(P).all()
        # feet on the floor: the body's lowest point touches y = 0 in every frame
        assert np.abs(lowest_point(P, d)).max() < 1e-6
        assert X[:, k, [J["l_ankle"], J["r_ankle"]], 1].min(axis=1).max() < 0.2
        np.testing.assert_allclose(X[:, k], forward_kinematics(P, d))
        upper = np.linalg.norm(X[:, k, J["l_elbow"]] - X[:, k, J["l_shoulder"]], axis=1)
        np.testing.assert_allclose(upper, d.upper_arm, atol=1e-9)
    # A stays on the left, B on the right, and their trunks never overlap
    assert np.all(_pelvis(X[:, 0])[:, 0] < _pelvis(X[:, 1])[:, 0])
    gaps = np.linalg.norm(X[:, 0, TORSO][:, :, None] - X[:, 1, TORSO][:, None], axis=-1)
    assert gaps.min() > 0.2, f"{name}: trunks come within {gaps.min():.2f} m"


@pytest.mark.parametrize("name", ["handshake", "high_five", "pull"])
def test_hands_meet_during_contact(name: str) -> None:
    for seed in range(4):
        sc = make_scenario(name, seed=seed)
        X = sc.joints()
        d = np.linalg.norm(X[:, 0, J["r_wrist"]] - X[:, 1, J["r_wrist"]], axis=1)
        contact = sc.phase == 1
        assert contact.sum() >= 3
        assert d[contact].max() < 0.15, f"{name} seed {seed}: wrists {d[contact].max():.3f} m apart"
        assert d[sc.phase == 0][0] > 0.5, "the people start apart"
        if name == "high_five":
            assert X[contact, 0, J["r_wrist"], 1].min() > X[contact, :, J["neck"], 1].min()


def test_push_recoils_the_pushed_person_and_pull_draws_in() -> None:
    for seed in range(4):
        sc = make_scenario("push", seed=seed, emotion="neutral")
        X = sc.joints()
        pushed = 0 if sc.meta["pushed"] == "a" else 1
        away = -1.0 if pushed == 0 else 1.0  # A recoils to -X, B to +X
        c0 = int(np.flatnonzero(sc.phase == 1)[0])
        x = _pelvis(X[:, pushed])[:, 0] * away
        assert x[-1] - x[c0] > 0.25, f"seed {seed}: pushed person moved back {x[-1] - x[c0]:.2f} m"
        lean = sc.poses_a if pushed == 0 else sc.poses_b
        assert lean[sc.phase >= 1, DOF_INDEX["torso_flex"]].min() < -0.15  # leans back
        pusher = 1 - pushed
        chest = 0.5 * (X[:, pushed, J["neck"]] + _pelvis(X[:, pushed]))
        hands = X[:, pusher][:, [J["l_wrist"], J["r_wrist"]]]
        assert np.linalg.norm(hands - chest[:, None], axis=-1)[sc.phase == 1].max() < 0.35
        sc = make_scenario("pull", seed=seed, emotion="neutral")
        X = sc.joints()
        pulled = 1 if sc.meta["initiator"] == "a" else 0
        toward = -1.0 if pulled == 1 else 1.0
        on = np.flatnonzero(sc.phase == 1)
        x = _pelvis(X[:, pulled])[:, 0] * toward
        assert x[on[-1]] - x[on[0]] > 0.2


def test_seeded_determinism() -> None:
    for name in SCENARIOS:
        kw = {"duration": 8.0} if name == "conversation" else {}
        a, b = make_scenario(name, seed=5, **kw), make_scenario(name, seed=5, **kw)
        c = make_scenario(name, seed=6, **kw)
        assert a.poses_a.tobytes() == b.poses_a.tobytes() and a.signals_b.tobytes() == b.signals_b.tobytes()
        assert a.meta == b.meta
        assert a.poses_a.shape != c.poses_a.shape or not np.array_equal(a.poses_a, c.poses_a)


def _wrist_speed(name: str, emotion: str, strength: float, seed: int) -> tuple[float, float]:
    sc = make_scenario(name, seed=seed, emotion=emotion, strength=strength, initiator="a")
    X = sc.joints()
    v = np.linalg.norm(np.diff(X[:, 0, J["r_wrist"]], axis=0), axis=1) * sc.fps
    return float(np.percentile(v, 95)), sc.n_frames / sc.fps


def test_emotion_strength_changes_speed_and_amplitude() -> None:
    for seed in range(3):
        v0, d0 = _wrist_speed("wave", "angry", 0.0, seed)
        v1, d1 = _wrist_speed("wave", "angry", 1.0, seed)
        vs, ds = _wrist_speed("wave", "sad", 1.0, seed)
        assert v1 > 1.25 * v0 and d1 < d0, "angry: faster, larger, shorter"
        assert vs < 0.75 * v0 and ds > d0, "sad: slower, smaller, longer"
    neutral = make_scenario("conversation", seed=0, emotion="neutral", duration=6)
    sad = make_scenario("conversation", seed=0, emotion="sad", strength=1.0, duration=6)
    nod = DOF_INDEX["head_nod"]
    assert sad.poses_a[:, nod].mean() - neutral.poses_a[:, nod].mean() > 0.25, "sad: head down"
    p = make_scenario("push", seed=1, emotion="angry", strength=1.0)
    q = make_scenario("push", seed=1, emotion="angry", strength=0.0)
    back = lambda s: np.ptp(s.poses_a[:, 0] if s.meta["pushed"] == "a" else s.poses_b[:, 0])  # noqa: E731
    assert back(p) > back(q) + 0.1, "angry push: the recoil is larger"


def _conditional_rate(sessions: list, antecedent: str, consequent: str, offset: int) -> tuple[float, int]:
    hits = total = 0
    ia, ic, it = SIGNAL_INDEX[antecedent], SIGNAL_INDEX[consequent], SIGNAL_INDEX["talking"]
    for sc in sessions:
        S = np.stack([sc.signals_a, sc.signals_b])
        for spk in (0, 1):
            t = np.flatnonzero((S[spk, :-offset, ia] == 1) & (S[spk, :-offset, it] == 1))
            hits += int((S[1 - spk, t + offset, ic] == 1).sum())
            total += len(t)
    return hits / max(total, 1), total


@pytest.mark.parametrize("interested", [True, False])
def test_conversation_planted_rules_hold(interested: bool) -> None:
    sessions = [make_scenario("conversation", seed=s, interested=interested, duration=120.0) for s in range(6)]
    assert all(s.meta["interested"] is interested for s in sessions)
    for rule in PLANTED_RULES:
        off = int(round(rule["offset_s"] * 25))
        assert off == rule["offset_frames_at_25fps"]
        rate, n = _conditional_rate(sessions, rule["antecedent"], rule["consequent"], off)
        p = rule["p_interested" if interested else "p_uninterested"]
        assert n > 300, f"too few {rule['antecedent']} frames ({n})"
        assert abs(rate - p) < 0.12, f"{rule}: measured {rate:.2f} over {n} frames, planted {p}"
    # listeners do not mirror at other offsets as strongly (the offset is what is planted)
    wrong, _ = _conditional_rate(sessions, "nod", "nod", 40)
    assert wrong < 0.35


def test_conversation_nods_are_small_head_movements_and_turns_alternate() -> None:
    sc = make_scenario("conversation", seed=3, emotion="neutral", duration=40.0)
    X = sc.joints()
    S = sc.signals_a
    assert S[:, SIGNAL_INDEX["nod"]].sum() > 0
    on = np.flatnonzero(np.diff(np.r_[0, S[:, SIGNAL_INDEX["nod"]], 0]) == 1)
    off = np.flatnonzero(np.diff(np.r_[0, S[:, SIGNAL_INDEX["nod"]], 0]) == -1)
    rel = X[:, 0, J["head"]] - X[:, 0, J["neck"]]
    for a, b in zip(on, off):
        amp = 0.5 * np.ptp(rel[a:b], axis=0).max()
        assert 0.015 < amp < 0.045, f"nod head motion amplitude {amp:.3f} m"
    talk_a, talk_b = sc.signals_a[:, 3], sc.signals_b[:, 3]
    assert not np.any((talk_a == 1) & (talk_b == 1)) and talk_a.any() and talk_b.any()
    assert sc.signals_a[:, SIGNAL_INDEX["gaze_at_other"]].mean() > 0.5


def test_trajectory_and_dataset() -> None:
    sc = make_scenario("handshake", seed=2)
    tr = sc.to_trajectory()
    assert tr.signal_names == sc.signal_names and tr.a.shape == (sc.n_frames, 14, 3)
    assert tr.meta["seed"] == 2 and tr.meta["emotion"] in ("neutral", "happy", "sad", "angry")
    data = generate_dataset(["handshake", "push"], seeds=[0, 1])
    assert [d.label for d in data] == ["handshake", "handshake", "push", "push"]
    assert all(isinstance(d, TwoPersonTrajectory) and d.phase is not None for d in data)
    with pytest.raises(ValueError, match="unknown scenario"):
        generate_dataset(["dance"], seeds=[0])


def test_cmu_pair_as_scenario() -> None:
    a, b = os.path.join(CMU, "18_01.bvh"), os.path.join(CMU, "19_01.bvh")
    if not (os.path.exists(a) and os.path.exists(b)):
        pytest.skip(f"CMU BVH files not found in {CMU} (shared development data)")
    from counterpart.sim.capture import scenario_from_bvh

    sc = scenario_from_bvh(a, b, fps=25)
    X = sc.joints()
    k = int(np.flatnonzero(sc.phase == 1)[0])
    assert _pelvis(X[k, 0])[0] < 0 < _pelvis(X[k, 1])[0], "A left, B right at the handshake"
    assert abs(np.percentile(lowest_point(sc.poses_a, sc.dims_a), 5)) < 1e-6
    d = np.linalg.norm(X[:, 0, J["r_wrist"]] - X[:, 1, J["r_wrist"]], axis=1)
    assert d.min() < 0.4
    assert (sc.signals_a[:, SIGNAL_INDEX["nod"]] == -1).all()
