"""The tracker's learned motion prior: training, files, prediction, CLI."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pytest

from counterpart.body.pose import DOF, LOWER, UPPER, YAW
from counterpart.nodes.tracker import cli_learn
from counterpart.nodes.tracker.prior import (
    MAX_FRAME_STEPS,
    PRIOR_FPS,
    MotionPrior,
    default_prior_path,
    frame_steps,
    load_sequences,
    train_prior,
    transitions_over,
)
from tests.shared_data import DATA


@pytest.fixture(scope="module")
def prior() -> MotionPrior:
    return train_prior(["sim:wave?seed=7", "sim:handshake?seed=7"], n_states=5)


def test_prior_trains_with_95_percent_energy(prior: MotionPrior) -> None:
    assert prior.fitted and prior.n_states == 5
    seqs, names = load_sequences(["sim:wave?seed=7"])
    assert len(seqs) == 2 and seqs[0].shape[1] == DOF and names[0].endswith("#a")
    X = np.concatenate(seqs)
    Y = prior.to_latent(X)
    rec = prior.from_latent(Y)
    A = X[:, 4:]
    kept = 1 - ((rec - A) ** 2).sum() / ((A - A.mean(0)) ** 2).sum()
    assert kept > 0.85  # 95% of the training set's energy overall
    np.testing.assert_allclose(prior.transmat.sum(1), 1.0, atol=1e-6)


def test_prior_saves_loads_and_rejects_other_versions(prior: MotionPrior, tmp_path: Path) -> None:
    path = prior.save(tmp_path / "p.npz")
    q = MotionPrior.load(path)
    np.testing.assert_allclose(q.means, prior.means)
    assert q.meta()["sources"] == prior.sources
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays["meta"]))
    meta["version"] = 99
    arrays["meta"] = json.dumps(meta)
    np.savez(tmp_path / "old.npz", **arrays)
    with pytest.raises(ValueError, match="version 99.*retrain"):
        MotionPrior.load(tmp_path / "old.npz")
    with pytest.raises(FileNotFoundError, match="learn tracker-prior"):
        MotionPrior.load(tmp_path / "missing.npz")


def test_predictor_follows_the_hmm(prior: MotionPrior) -> None:
    seqs, _ = load_sequences(["sim:wave?seed=7"])
    pred = prior.predictor()
    for pose in seqs[0][:30]:
        alpha = pred.update(pose)
    assert abs(alpha.sum() - 1) < 1e-9
    rng = np.random.default_rng(0)
    P = np.repeat(seqs[0][30][None], 500, axis=0)
    out = pred(P, rng)
    inside = (out >= LOWER) & (out <= UPPER)
    inside[:, YAW] = True
    assert out.shape == P.shape and inside.all()
    moved = np.abs(out - P).max(axis=1)
    # most particles take a small random-walk step; about hmm_weight of them jump to an HMM sample
    assert 0.1 < np.mean(np.abs(out[:, 12:] - P[:, 12:]).max(axis=1) > 0.2) < 0.35
    assert np.median(moved) < 0.2


def test_a_slower_video_is_searched_over_its_longer_steps(prior: MotionPrior) -> None:
    """The prior is learnt at 25 fps; a video at a third of that moves three of its frames
    between two of its own. Told the rate, the random walk's 2-std band holds the true steps
    between frames as often as at the prior's own rate; told nothing, it misses many more.
    """
    seqs, _ = load_sequences(["sim:push?seed=8", "sim:pull?seed=8"])  # 25 fps, unseen by the prior

    def covered(fps: float, step: int) -> float:
        steps = np.concatenate([np.abs(np.diff(s[::step], axis=0)) for s in seqs])
        return float(np.mean(steps <= 2 * prior.predictor(fps).std))

    at_rate, slow_told, slow_untold = covered(PRIOR_FPS, 1), covered(PRIOR_FPS / 3, 3), covered(0.0, 3)
    assert slow_told >= at_rate - 0.01, (slow_told, at_rate)
    assert slow_untold < at_rate - 0.04, (slow_untold, at_rate)
    # a faster video keeps the prior's own search (the UT clips' 30 fps, where it was tuned)
    for fps in (30.0, 60.0, 0.0):
        np.testing.assert_array_equal(prior.predictor(fps).std, prior.predictor(PRIOR_FPS).std)
        np.testing.assert_array_equal(prior.predictor(fps).transmat, prior.transmat)
    # the chain's transitions: three of its steps, and a fractional number between whole ones
    A = prior.transmat
    slow = prior.predictor(PRIOR_FPS / 3)
    np.testing.assert_allclose(slow.transmat, A @ A @ A, atol=1e-12)
    half = transitions_over(A, 1.5)
    np.testing.assert_allclose(half, 0.5 * A + 0.5 * A @ A, atol=1e-12)
    np.testing.assert_allclose(half.sum(axis=1), 1.0, atol=1e-9)
    assert (half >= 0).all()
    assert frame_steps(25.0, 10.0) == 2.5 and frame_steps(25.0, 30.0) == 1.0 and frame_steps(25.0, 0.0) == 1.0
    assert frame_steps(25.0, 1.0) == MAX_FRAME_STEPS  # a header's wrong rate does not blow the search up


def test_frames_dropped_before_the_tracker_are_a_longer_step(prior: MotionPrior) -> None:
    """Two frames dropped at 25 fps make the next step one of three frames, as at a third of the
    rate; the step after is one frame again; the cap holds for a long gap.
    """
    pred, slow = prior.predictor(PRIOR_FPS), prior.predictor(PRIOR_FPS / 3)
    base = pred.std.copy()
    pred.set_gap(3)
    np.testing.assert_allclose(pred.std, slow.std)
    np.testing.assert_allclose(pred.transmat, slow.transmat)
    pred.set_gap(1)
    np.testing.assert_array_equal(pred.std, base)
    np.testing.assert_allclose(pred.transmat, prior.transmat)
    pred.set_gap(100)
    np.testing.assert_allclose(pred.std, base * MAX_FRAME_STEPS)
    slow.set_gap(2)  # at a third of the rate, two frames are six of the prior's: capped at five
    np.testing.assert_allclose(slow.std, base * MAX_FRAME_STEPS)


def test_the_priors_frame_rate_is_kept_in_its_file(prior: MotionPrior, tmp_path: Path) -> None:
    assert prior.fps == PRIOR_FPS
    q = train_prior(["sim:wave?seed=7"], n_states=3, fps=12.5)
    assert MotionPrior.load(q.save(tmp_path / "slow.npz")).fps == 12.5
    # a file written before the rate was kept is the default's 25 fps
    with np.load(tmp_path / "slow.npz") as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays["meta"]))
    del meta["fps"]
    arrays["meta"] = json.dumps(meta)
    np.savez(tmp_path / "older.npz", **arrays)
    assert MotionPrior.load(tmp_path / "older.npz").fps == PRIOR_FPS
    with pytest.raises(ValueError, match="fps"):
        MotionPrior(fps=0.0)


def test_cli_trains_a_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    p = argparse.ArgumentParser()
    cli_learn.add_arguments(p)
    out = tmp_path / "prior.npz"
    args = p.parse_args(["--data", "sim:push?seed=3", "--states", "4", "--out", str(out)])
    assert cli_learn.main(args) == 0
    assert MotionPrior.load(out).n_states == 4
    assert "tracker prior" in capsys.readouterr().err
    bad = p.parse_args(["--data", str(tmp_path / "nothing.bvh"), "--out", str(out)])
    assert cli_learn.main(bad) == 2
    assert "does not exist" in capsys.readouterr().err


def test_a_small_recording_trains_a_prior_or_says_what_to_change(capsys: pytest.CaptureFixture[str]) -> None:
    """One simulated handshake (466 frames): hmmlearn's fit with the fixed covariance floor fails on
    it (a state's covariance not positive definite); the floor scaled to the data's spread gives a
    usable 10-state prior, and 30 states, too many for so few frames, are refused with what to change.
    """
    seqs, names = load_sequences(["sim:handshake"])
    prior = MotionPrior(n_states=10).fit(seqs, names)
    assert np.isfinite(prior.means).all() and (np.linalg.eigvalsh(prior.covars) > 0).all()
    np.testing.assert_allclose(prior.transmat.sum(1), 1.0, atol=1e-6)
    with pytest.raises(ValueError, match=r"30-state HMM could not be fitted to 466 frames .*fewer states"):
        MotionPrior(n_states=30).fit(seqs, names)


def test_default_path_follows_env(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("COUNTERPART_MODELS", str(tmp_path))
    assert default_prior_path() == tmp_path / "tracker_prior.npz"


def test_prior_from_cmu_bvh() -> None:
    bvh = DATA / "cmu" / "18_01.bvh"
    if not bvh.exists():
        pytest.skip(f"{bvh} absent (the CMU handshake of ../shared/data)")
    seqs, _ = load_sequences([str(bvh)])
    assert abs(len(seqs[0]) - 303 / 120 * 25) <= 2 and np.isfinite(seqs[0]).all()
