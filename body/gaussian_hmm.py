"""The Gaussian HMM of hmmlearn with full covariances, fitted faster.

Shared by the tracker's motion prior and the responder's dual HMM, so it lives below the nodes
(import it where a model is fitted: it imports hmmlearn). Two changes to how hmmlearn fits, neither
to what it fits (the models agree with hmmlearn's to rounding):

- the E-step's forward-backward runs on scaled probabilities (hmmlearn's ``implementation="scaling"``)
  rather than in log space, whose log-sum-exp over every pair of states costs several times as much;
  where a frame is so far from every state that its probabilities underflow, the fit starts again
  in log space;
- hmmlearn accumulates ``sum_t gamma_t(k) x_t x_t^T`` with a three-operand ``np.einsum``, which numpy
  runs as a plain loop over every (t, k, i, j); here it is ``(gamma^T * x^T) @ x`` per state, on BLAS.
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
from hmmlearn.hmm import GaussianHMM

__all__ = ["FullGaussianHMM", "full_gaussian_hmm", "outer_statistic"]

#: frames of :func:`outer_statistic`'s blocks
_BLOCK = 2048


def outer_statistic(posteriors: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Posterior-weighted outer products of the frames, per state (the full-covariance M-step's
    second moment; Rabiner 1989, eq. 53 with the mean left out).

    Parameters
    ----------
    posteriors : ndarray of shape (T, K)
        State posteriors gamma_t(k) of each frame.
    X : ndarray of shape (T, d)
        The frames.

    Returns
    -------
    ndarray of shape (K, d, d)
        ``sum_t gamma_t(k) x_t x_t^T`` for each state k.
    """
    out = np.zeros((posteriors.shape[1], X.shape[1], X.shape[1]))
    # by blocks of frames: the weighted frames (K, d, block) of a long recording stay small
    for a in range(0, len(X), _BLOCK):
        x = X[a : a + _BLOCK]
        out += np.einsum("tk,ti->kit", posteriors[a : a + _BLOCK], x) @ x
    return out


class FullGaussianHMM(GaussianHMM):
    """hmmlearn's ``GaussianHMM`` whose E-step adds :func:`outer_statistic` (with
    ``covariance_type="full"``, the only type it is made with: :func:`full_gaussian_hmm`), and whose
    fit on scaled probabilities falls back to log space where they underflow.
    """

    _outer_elsewhere = False

    def fit(self, X: np.ndarray, lengths: Any = None) -> FullGaussianHMM:
        """Fit as hmmlearn does; on scaled probabilities that underflow, again in log space from the
        same start (the parameters set before it, and the same seed).
        """
        if self.implementation != "scaling":
            return super().fit(X, lengths)
        # the start the caller set (init_params "" keeps it), for a fit again from it
        start = copy.deepcopy(self.__dict__)
        try:
            return super().fit(X, lengths)
        except ValueError as exc:
            if "underflow" not in str(exc):
                raise
        self.__dict__.update(start)
        self.implementation = "log"
        return super().fit(X, lengths)

    def _needs_sufficient_statistics_for_covars(self) -> bool:
        return not self._outer_elsewhere and super()._needs_sufficient_statistics_for_covars()

    def _accumulate_sufficient_statistics(
        self,
        stats: dict,
        X: np.ndarray,
        lattice: np.ndarray,
        posteriors: np.ndarray,
        fwdlattice: np.ndarray,
        bwdlattice: np.ndarray,
    ) -> None:
        own = self.covariance_type == "full" and super()._needs_sufficient_statistics_for_covars()
        # hmmlearn's own accumulation then does everything but the outer products
        self._outer_elsewhere = own
        try:
            super()._accumulate_sufficient_statistics(stats, X, lattice, posteriors, fwdlattice, bwdlattice)
        finally:
            self._outer_elsewhere = False
        if own:
            stats["obs*obs.T"] += outer_statistic(posteriors, X)


def full_gaussian_hmm(**params: Any) -> FullGaussianHMM:
    """An unfitted hmmlearn ``GaussianHMM`` with full covariances and the faster E-step.

    Parameters
    ----------
    **params
        hmmlearn ``GaussianHMM`` parameters other than ``covariance_type`` (``n_components``,
        ``n_iter``, ``min_covar``, ``random_state``, ...); ``implementation`` defaults to
        "scaling".

    Returns
    -------
    FullGaussianHMM
        The model; it fits, scores and pickles as hmmlearn's ``GaussianHMM``.
    """
    return FullGaussianHMM(covariance_type="full", **{"implementation": "scaling", **params})
