"""The dual HMM's online state estimate: the forward algorithm, or a fixed-lag Viterbi trellis.

Only the observed block is seen, so the state is filtered with its (tempered) likelihoods
(Rabiner 1989, eq. 19)::

    alpha_t(k) ∝ [sum_j alpha_{t-1}(j) A_jk] l_t(k),   alpha_1(k) ∝ pi_k l_1(k)

``decode="filter"`` weighs the states by alpha_t; ``decode="viterbi"`` runs the Viterbi recursion
(max-product) over the last ``lag`` frames, started from the filtered posterior at t - lag, and
puts all the weight on the best path's state at t: a hard, path-consistent state that changes less
often.
"""

from __future__ import annotations

import numpy as np

DECODES = ("filter", "viterbi")


def logsumexp(a: np.ndarray, axis: int | None = None) -> np.ndarray | float:
    """``log(sum(exp(a)))`` along ``axis`` (None: all of ``a``), as ``scipy.special.logsumexp``
    computes it for real arrays (the largest terms separated out of the shifted sum, the same
    operations in the same order, so the same numbers) without its array-API dispatch, which
    cost the filter most of its time per frame.

    Parameters
    ----------
    a : ndarray of float
        The terms (log-weights).
    axis : int or None, default=None
        The axis summed over.

    Returns
    -------
    ndarray or float
        ``a``'s shape less ``axis`` (a float for a whole array).
    """
    a = np.asarray(a, np.float64)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        a_max = a.max(axis=axis, keepdims=True)
        top = a == a_max
        m = top.sum(axis=axis, keepdims=True, dtype=np.float64)
        s = np.exp(np.where(top, -np.inf, a) - a_max).sum(axis=axis, keepdims=True)
        s = np.where(s == 0, s, s / m)
        out = np.log1p(s) + np.log(m) + a_max
        if not np.isfinite(out).all():  # infinite or empty terms: the direct sum says what it is
            out = np.where(np.isfinite(out), out, np.log(np.exp(a).sum(axis=axis, keepdims=True)))
    out = out.squeeze(axis=axis) if axis is not None else out.reshape(())
    return out[()] if out.ndim == 0 else out


class ForwardFilter:
    """Online state weights of an HMM from per-frame log-likelihoods.

    Parameters
    ----------
    startprob : (N,) array
        Start probabilities pi.
    transmat : (N, N) array
        Transitions A (rows: from, columns: to).
    decode : str
        "filter" (the posterior) or "viterbi" (the fixed-lag best path's state).
    lag : int
        Frames of the Viterbi trellis.

    Raises
    ------
    ValueError
        If ``decode`` is not one of ``DECODES``.
    """

    def __init__(self, startprob: np.ndarray, transmat: np.ndarray, decode: str = "filter", lag: int = 8) -> None:
        if decode not in DECODES:
            raise ValueError(f"decode={decode!r}; choose one of {', '.join(DECODES)}")
        self.decode, self.lag = decode, int(lag)
        self.log_A = np.log(np.maximum(transmat, 1e-300))
        self.log_pi = np.log(np.maximum(startprob, 1e-300))
        self.reset()

    def reset(self) -> None:
        """Forget the past: the next frame starts a new sequence."""
        self.alpha: np.ndarray | None = None  # log alpha_t, normalised
        self.posterior: np.ndarray | None = None  # alpha_t
        self._lls: list[np.ndarray] = []
        self._alphas: list[np.ndarray] = []

    def update(self, ll: np.ndarray) -> np.ndarray:
        """One frame's state log-likelihoods -> state weights.

        Parameters
        ----------
        ll : ndarray of shape (N,)
            The frame's (tempered) state log-likelihoods.

        Returns
        -------
        ndarray of shape (N,)
            State weights (sum 1): the posterior (``decode="filter"``) or one on the fixed-lag best
            path's state (``"viterbi"``).
        """
        prior = self.log_pi if self.alpha is None else logsumexp(self.alpha[:, None] + self.log_A, axis=0)
        la = prior + ll
        self.alpha = la - logsumexp(la)
        self.posterior = np.exp(self.alpha)
        if self.decode == "filter":
            return self.posterior
        self._lls.append(ll)
        self._alphas.append(self.alpha)
        if len(self._lls) > self.lag:
            self._lls.pop(0)
            self._alphas.pop(0)
        w = np.zeros(len(ll))
        w[self._viterbi_end()] = 1.0
        return w

    def _viterbi_end(self) -> int:
        """Best-path state at the newest frame over the fixed-lag trellis."""
        delta = self._alphas[0]
        for ll in self._lls[1:]:
            delta = np.max(delta[:, None] + self.log_A, axis=0) + ll
        return int(np.argmax(delta))


__all__ = ["ForwardFilter", "DECODES"]
