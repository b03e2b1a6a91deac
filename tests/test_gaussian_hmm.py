"""The faster full-covariance Gaussian HMM fits the model hmmlearn fits."""

from __future__ import annotations

import numpy as np
import pytest
from hmmlearn.hmm import GaussianHMM

from counterpart.body.gaussian_hmm import FullGaussianHMM, full_gaussian_hmm, outer_statistic


def _sequences(seed: int = 0, n: int = 6, d: int = 4) -> tuple[np.ndarray, list[int]]:
    """Sequences that walk through three well-apart Gaussian clusters, of random lengths."""
    rng = np.random.default_rng(seed)
    centres = rng.normal(0.0, 4.0, (3, d))
    seqs = []
    for _ in range(n):
        states = np.repeat(rng.integers(0, 3, 8), rng.integers(5, 20, 8))
        seqs.append(centres[states] + rng.normal(0.0, 0.5 + 0.3 * states[:, None], (len(states), d)))
    return np.concatenate(seqs), [len(s) for s in seqs]


def _params(hmm: GaussianHMM) -> list[np.ndarray]:
    return [hmm.startprob_, hmm.transmat_, hmm.means_, hmm.covars_]


@pytest.mark.parametrize("frames", [200, 5000])  # one block, and several with a short last one
def test_the_outer_statistic_is_hmmlearns(frames: int) -> None:
    rng = np.random.default_rng(3)
    post, X = rng.dirichlet(np.ones(5), frames), rng.normal(size=(frames, 7))
    want = np.einsum("ij,ik,il->jkl", post, X, X)  # hmmlearn's
    np.testing.assert_allclose(outer_statistic(post, X), want, rtol=1e-12, atol=1e-10)


def test_the_fit_is_hmmlearns_in_log_space() -> None:
    X, lengths = _sequences()
    ours = full_gaussian_hmm(n_components=3, n_iter=30, random_state=1, tol=1e-6).fit(X, lengths)
    theirs = GaussianHMM(n_components=3, covariance_type="full", n_iter=30, random_state=1, tol=1e-6)
    theirs.fit(X, lengths)
    assert ours.implementation == "scaling" and ours.monitor_.iter == theirs.monitor_.iter > 2
    for a, b in zip(_params(ours), _params(theirs)):
        np.testing.assert_allclose(a, b, rtol=1e-7, atol=1e-9)
    assert abs(ours.score(X, lengths) - theirs.score(X, lengths)) < 1e-6 * abs(theirs.score(X, lengths))


def test_frames_whose_probabilities_underflow_are_fitted_again_in_log_space_from_the_same_start() -> None:
    X, lengths = _sequences(seed=2)
    # a frame a thousand spreads from every cluster: its density is exp(-1e5) or less in every state
    X[5] = 2000.0

    def started(hmm: GaussianHMM) -> GaussianHMM:
        hmm.startprob_ = np.full(3, 1 / 3)
        hmm.transmat_ = np.full((3, 3), 1 / 3)
        hmm.means_ = X[[0, 40, 80]]
        hmm.covars_ = np.stack([np.eye(X.shape[1])] * 3)
        return hmm

    ours = started(full_gaussian_hmm(n_components=3, n_iter=10, init_params="", random_state=0))
    ours.fit(X, lengths)
    theirs = started(GaussianHMM(n_components=3, covariance_type="full", n_iter=10, init_params="", random_state=0))
    theirs.fit(X, lengths)
    assert isinstance(ours, FullGaussianHMM) and ours.implementation == "log"
    for a, b in zip(_params(ours), _params(theirs)):
        np.testing.assert_allclose(a, b, rtol=1e-7, atol=1e-9)
