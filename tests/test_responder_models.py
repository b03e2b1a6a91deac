"""Joint-shape CONDENSATION through a decision point, listener rule choices, emotion ranking."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from counterpart.body.camera import default_camera
from counterpart.body.kinematics import forward_kinematics
from counterpart.body.pose import DOF_INDEX, neutral_pose
from counterpart.body.trajectory import TwoPersonTrajectory
from counterpart.nodes.responder.emotion import EmotionModel, rank_svm
from counterpart.nodes.responder.joint_shape import JointShapeModel
from counterpart.nodes.responder.listener import ListenerModel
from counterpart.nodes.responder.shapes import trajectory_shapes


def branch_pair(branch: int, T: int = 60) -> TwoPersonTrajectory:
    """A and B stand; for 25 frames nothing differs; then A raises the right arm (branch 0) and B
    raises its right arm too, or A bends forward (branch 1) and B crouches back with arms out.
    """
    u = np.clip((np.arange(T) - 25) / 15, 0, 1)
    PA = np.tile(neutral_pose(x=-0.7, yaw=np.pi / 2), (T, 1))
    PB = np.tile(neutral_pose(x=0.7, yaw=-np.pi / 2), (T, 1))
    if branch == 0:
        PA[:, DOF_INDEX["r_shoulder_flex"]] = 2.5 * u
        PB[:, DOF_INDEX["r_shoulder_flex"]] = 2.5 * u
    else:
        PA[:, DOF_INDEX["torso_flex"]] = 0.8 * u
        PB[:, DOF_INDEX["l_shoulder_abd"]] = 1.4 * u
        PB[:, DOF_INDEX["r_shoulder_abd"]] = 1.4 * u
    return TwoPersonTrajectory(a=forward_kinematics(PA), b=forward_kinematics(PB), fps=25.0, label=f"b{branch}")


@pytest.fixture(scope="module")
def shape_data():
    cam = default_camera(160, 120)
    return {k: trajectory_shapes(branch_pair(k), cam) for k in (0, 1)}


def test_condensation_keeps_the_correct_mode_through_a_decision_point(shape_data) -> None:
    m = JointShapeModel(n_states=12, n_behaviours=8, both_roles=False, random_state=1)
    m.fit([shape_data[0], shape_data[1]] * 3)
    for k in (0, 1):
        a, b = shape_data[k]
        other = shape_data[1 - k][1]
        pred = m.predict(a)
        late = slice(45, 60)  # after the decision, once the branches differ
        err = np.linalg.norm(pred[late] - b.ctrl[late], axis=-1).mean()
        err_other = np.linalg.norm(pred[late] - other.ctrl[late], axis=-1).mean()
        assert err < 0.5 * err_other, (k, err, err_other)
        assert err < 3.0  # pixels at 160 x 120


def test_decay_operator() -> None:
    h = JointShapeModel.decay_vectors(np.array([0, 1, 1, 2]), 3, 0.5)
    assert np.allclose(h[-1], [0.125, 0.5, 1.0])


RULES = {
    "interested": [(("S:nod",), ("L:nod",), 0.8), (("S:shake",), ("L:shake",), 0.6)],
    "not_interested": [(("S:nod",), ("L:nod",), 0.3), (("S:shake",), ("L:shake",), 0.2)],
}


def test_listener_probabilities_follow_rules_and_interest() -> None:
    m = ListenerModel().fit(RULES)
    assert m.response_probabilities({"nod"}, 3) == pytest.approx({"nod": 0.8})
    assert m.response_probabilities({"nod"}, 1) == pytest.approx({"nod": 0.3})
    assert m.response_probabilities({"nod"}, 2) == pytest.approx({"nod": 0.55})
    assert m.response_probabilities({"shake", "nod"}, 3) == pytest.approx({"nod": 0.8, "shake": 0.6})
    one = ListenerModel().fit({"interested": RULES["interested"]})
    assert one.response_probabilities({"nod"}, 1)["nod"] == pytest.approx(0.8 * 0.4)


@pytest.mark.parametrize("interest,expected", [(3, 0.8), (1, 0.3)])
def test_listener_nods_as_often_as_the_rule_says(interest: int, expected: float) -> None:
    m = ListenerModel(fps=25.0, random_state=3).fit(RULES)
    m.interest = interest
    nods = 0
    n_events = 300
    head = []
    for e in range(n_events):  # speaker nods for 10 frames, then 30 quiet frames
        responded = False
        for t in range(40):
            m.step({"nod": t < 10})
            responded |= "nod" in m.behaviour_
            if e == 0 and interest == 3:
                head.append(m.body({"nod"}, t)[0])
        nods += responded
    assert abs(nods / n_events - expected) < 0.08
    if head:  # a nodding head moves
        assert np.ptp(np.array(head), axis=0).max() > 0.03


def test_rank_svm_learns_a_planted_order() -> None:
    rng = np.random.default_rng(0)
    w_true = np.array([1.0, -2.0, 0.5, 0.0])
    X = rng.normal(size=(80, 4))
    s = X @ w_true
    i, j = np.array(list(itertools.combinations(range(60), 2))).T
    o = s[i] > s[j] + 0.2
    D = np.concatenate([X[i[o]] - X[j[o]], X[j[~o & (s[j] > s[i] + 0.2)]] - X[i[~o & (s[j] > s[i] + 0.2)]]])
    sim = np.abs(s[i] - s[j]) < 0.05
    w = rank_svm(D, X[i[sim]] - X[j[sim]])
    ti, tj = np.array(list(itertools.combinations(range(60, 80), 2))).T
    acc = np.mean(np.sign((X[ti] - X[tj]) @ w) == np.sign(s[ti] - s[tj]))
    assert acc > 0.9


def test_emotion_strength_ranks_and_modulates() -> None:
    rng = np.random.default_rng(1)
    # features: log speed rises with angry strength; neutral = 0
    s = rng.uniform(0, 1, 40)
    X = rng.normal(scale=0.05, size=(40, 7))
    s[:8] = 0.0  # neutral motions: the reference for the style slopes
    X[:, 0] += 0.6 * s
    X[:, 1] += 0.3 * s
    m = EmotionModel().fit(X, ["neutral"] * 8 + ["angry"] * 32, s, ["g"] * 40)
    order = np.argsort(m.rank(X, "angry"))
    assert np.corrcoef(order, np.argsort(s))[0, 1] > 0 and np.corrcoef(m.rank(X, "angry"), s)[0, 1] > 0.9
    amp, rate = m.style_gains("angry", 1.0)
    assert amp == pytest.approx(np.exp(0.3), rel=0.2) and rate == pytest.approx(np.exp(0.3), rel=0.3)
    tr = branch_pair(0)
    y = m.modulate(tr.a, "angry", 1.0)
    wrist = lambda X: np.ptp(X[:, 7, 1])  # noqa: E731
    assert wrist(y) > 1.15 * wrist(tr.a)
    with pytest.raises(ValueError, match="strength"):
        m.style_gains("angry", 1.5)


def test_a_default_models_name_given_as_a_file_is_pointed_to_its_default_form(tmp_path) -> None:
    """``--model dual-hmm`` where no such file is: the message says ``default:dual-hmm`` is the
    default model; a missing file of any other name only says how to train one.
    """
    from counterpart.nodes.responder.models import load_model

    with pytest.raises(
        FileNotFoundError, match=r"dual-hmm: no such model file .*for the default model, default:dual-hmm"
    ):
        load_model("dual-hmm")
    missing = str(tmp_path / "mine.npz")
    with pytest.raises(FileNotFoundError, match="no such model file") as info:
        load_model(missing)
    assert "default:" not in str(info.value)
