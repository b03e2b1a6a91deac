"""The hierarchical GPDM responder (Taubert et al.) on a few small simulated hand meetings."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from counterpart.nodes.responder.data import sim_trajectories
from counterpart.nodes.responder.gpdm import GPDM, reach
from counterpart.nodes.responder.models import load_model, save_model
from tests.launching import read_jsonl, run_launch, write_launch

SMALL = dict(points=300, num_inducing=15, n_centres=30, max_iters=40, dyn_points=200, support=1500)


def trials(seeds: range, **kw: object) -> list:
    return sim_trajectories(("handshake",), seeds, max_frames=250, **kw)


@pytest.fixture(scope="module")
def model() -> GPDM:
    """Neutral and angry handshakes (never sad), hands meeting at three heights."""
    data = []
    for seed in range(6):
        for emo in ("neutral", "angry"):
            data += trials(range(seed, seed + 1), emotion=emo, strength=1.0, hand_dy=(-0.1, 0.0, 0.1)[seed % 3])
    said: list[str] = []
    m = GPDM(**SMALL).fit(data, said.append)
    assert any("partner layer" in s for s in said)  # progress is reported layer by layer
    return m


def first_contact(t) -> int:
    return int(np.flatnonzero(t.phase == 1)[0])


def test_the_partner_answers_and_its_hand_meets_the_offered_hand(model: GPDM) -> None:
    t = trials(range(50, 51), emotion="neutral")[0]
    model.set_style("neutral", 0.0)
    pred = model.predict(t.a)
    assert pred.shape == t.b.shape and np.isfinite(pred).all()
    c = first_contact(t)
    # the real partner's hand is there at contact; the generated one is within 10 cm of it
    assert np.linalg.norm(pred[c, 7] - t.b[c, 7]) < 0.10
    # and the partner stands in front of the observed person (facing distance of the real one)
    gap = np.linalg.norm((pred[c, 0] - t.a[c, 0])[[0, 2]])
    assert abs(gap - np.linalg.norm((t.b[c, 0] - t.a[c, 0])[[0, 2]])) < 0.25


def test_the_hand_goes_where_it_is_offered_not_where_training_met(model: GPDM) -> None:
    model.set_style("neutral", 0.0)
    heights = {}
    for dy in (-0.2, 0.2):  # beyond the training's +-0.1 m
        t = trials(range(51, 52), emotion="neutral", hand_dy=dy)[0]
        c = first_contact(t)
        heights[dy] = (model.predict(t.a)[c, 7, 1], t.b[c, 7, 1])
    assert heights[0.2][0] - heights[-0.2][0] > 0.3  # the truth differs by 0.4 m
    assert all(abs(g - r) < 0.1 for g, r in heights.values())


def test_the_style_is_a_continuous_input(model: GPDM) -> None:
    t = trials(range(52, 53), emotion="neutral")[0]
    out = {}
    for s in (0.0, 0.5, 1.0):
        model.set_style("angry", s)
        out[s] = model.predict(t.a)[:, [0, 1, 2, 3, 4, 8, 9, 10, 11, 12, 13]]  # all but the reaching arm
    model.set_style("neutral", 0.0)
    # before the hands reach for each other (the reach, not the style, moves the body later)
    early = slice(0, first_contact(t) - 20)
    full, half = (out[1.0] - out[0.0])[early], (out[0.5] - out[0.0])[early]
    assert np.abs(full).max() > 0.02  # the style moves the body
    # the style amount enters linearly (f = g_0 + s g_angry): half the strength, half the change
    np.testing.assert_allclose(half, 0.5 * full, atol=1e-3)


def test_an_unseen_style_is_refused_with_the_styles_it_knows(model: GPDM) -> None:
    with pytest.raises(ValueError, match=r"style 'sad' was never seen in training \(this model knows neutral, angry\)"):
        model.set_style("sad", 0.5)
    with pytest.raises(ValueError, match="emotion='bored'"):
        model.set_style("bored", 0.5)
    with pytest.raises(ValueError, match="strength=1.5"):
        model.set_style("angry", 1.5)
    with pytest.raises(ValueError, match=r"\(14, 3\)"):
        model.step(np.zeros((13, 3)))


def test_the_model_file_round_trips(model: GPDM, tmp_path: Path) -> None:
    t = trials(range(53, 54), emotion="angry", strength=0.7)[0]
    model.set_style("angry", 0.7)
    path = save_model(tmp_path / "g.npz", model, {"sequences": 12})
    back = load_model(path, expected="gpdm")
    back.set_style("angry", 0.7)
    np.testing.assert_allclose(back.predict(t.a[:60]), model.predict(t.a[:60]), atol=1e-5)
    assert back.styles_ == ["neutral", "angry"] and back.training_ == {"sequences": 12}


def test_reach_keeps_the_bones_and_meets_a_reachable_target() -> None:
    t = trials(range(54, 55))[0]
    J = t.a[0].astype(np.float64)
    target = J[5] + np.array([0.3, 0.2, 0.1])
    R = reach(J, target, 1.0)
    assert np.linalg.norm(R[7] - target) < 1e-6
    for a, b in ((5, 6), (6, 7)):
        assert abs(np.linalg.norm(R[a] - R[b]) - np.linalg.norm(J[a] - J[b])) < 1e-6
    assert np.array_equal(reach(J, target, 0.0), J)


@pytest.mark.slow
def test_the_responder_node_runs_the_gpdm_and_takes_the_style(model: GPDM, tmp_path: Path) -> None:
    d = tmp_path / "models"
    save_model(d / "responder-gpdm.npz", model)
    launch = write_launch(
        tmp_path / "g.yaml",
        {
            "nodes": {
                "source": {"run": "tests.responder_nodes:PoseSource", "params": {"frames": 60, "control_at": 30}},
                # a reliable control queue: the source waits for it to connect, so the control is never lost
                "responder": {
                    "run": "counterpart.nodes.responder",
                    "params": {"model": "gpdm"},
                    "inputs": {"control": {"policy": "reliable"}},
                },
                "sink": {"run": "tests.responder_nodes:PartnerSink", "params": {"path": str(tmp_path / "out.jsonl")}},
            }
        },
    )
    # the emotion model the node loads up front: a fresh default would take a while to build
    from counterpart.nodes.responder.emotion import EmotionModel

    save_model(
        d / "responder-emotion.npz",
        EmotionModel().fit(
            np.random.default_rng(0).normal(size=(8, 7)), ["neutral", "angry"] * 4, [0, 1] * 4, ["g"] * 8
        ),
    )
    code, out = run_launch(launch, timeout=90, env={"COUNTERPART_MODELS": str(d)})
    assert code == 0, out
    rows = read_jsonl(tmp_path / "out.jsonl")
    assert [r["seq"] for r in rows] == list(range(60))
    assert all(r["model"] == "gpdm" and r["shape"] == [14, 3] for r in rows)
    # the control takes effect from some frame k on (when depends on the load; it is sent before 30)
    angry = [r["emotion"] == "angry" and r["strength"] == 1.0 for r in rows]
    k = angry.index(True)
    assert k <= 30 and all(angry[k:])
    # the node's output is the model's own for that observed sequence with the style switched at k,
    # staged, given its arms and kept clear as the node does (Stage.finish) (poses without a rate: 25 fps)
    from tests.responder_fixtures import planted_pair

    obs = planted_pair(7, T=60).a.astype(np.float32)  # as Pose3D carries it
    from counterpart.nodes.responder.staging import Stage

    model.reset()
    stage, expect = Stage(), []
    for t, x in enumerate(obs):
        model.set_style("angry", 1.0) if t >= k else model.set_style("neutral", 0.0)
        expect.append(stage.finish(x, stage(x, model.step(x), 1 / 25))[0])
    model.reset()
    got = np.array([r["joints"] for r in rows])
    bad = np.flatnonzero(np.abs(got - np.array(expect)).max(axis=(1, 2)) > 1e-4)
    assert len(bad) == 0, f"frames differ: {bad}"
    # and the style shows: the angry frames differ from what a neutral partner would do
    model.set_style("neutral", 0.0)
    neutral = model.predict(obs)
    assert np.abs(got[k:] - neutral[k:]).max() > 0.01


@pytest.mark.slow
def test_respond_cli_styles_the_gpdm_and_names_an_unseen_style(model: GPDM, tmp_path: Path) -> None:
    from tests.test_cli import cli

    path = save_model(tmp_path / "g.npz", model)
    t = trials(range(55, 56), emotion="neutral")[0]
    t.save(tmp_path / "in.npz")
    ok = cli(
        "respond",
        "--model",
        str(path),
        "--input",
        str(tmp_path / "in.npz"),
        "--out",
        str(tmp_path / "out.npz"),
        "--emotion",
        "angry",
        "--strength",
        "1",
    )
    assert ok.returncode == 0, ok.stderr
    from counterpart.body.trajectory import TwoPersonTrajectory

    out = TwoPersonTrajectory.load(tmp_path / "out.npz")
    model.set_style("angry", 1.0)
    np.testing.assert_allclose(out.b, model.predict(t.a), atol=1e-4)  # the model's own style, no filter after
    bad = cli(
        "respond",
        "--model",
        str(path),
        "--input",
        str(tmp_path / "in.npz"),
        "--out",
        str(tmp_path / "x.npz"),
        "--emotion",
        "sad",
        "--strength",
        "0.5",
    )
    assert bad.returncode == 2 and "style 'sad' was never seen in training" in bad.stderr
