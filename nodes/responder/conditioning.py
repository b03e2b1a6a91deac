"""The dual HMM's emissions split into the observed and the partner block (Gaussian conditioning).

Each state k emits x = [o, p] from N(mu_k, Sigma_k), Sigma_k = [[S_oo,k, S_op,k], [S_po,k, S_pp,k]].
Online only o is seen: the state is filtered with the observed block's marginal N(o; mu_o,k, S_oo,k)
and the partner is the state-conditional Gaussian of p given o::

    E[p | o, s = k] = mu_p,k + S_po,k S_oo,k^{-1} (o - mu_o,k)
    Cov[p | o, s = k] = S_pp,k - S_po,k S_oo,k^{-1} S_op,k
"""

from __future__ import annotations

import numpy as np

from .pair_features import POS, VEL

#: how far (standard deviations of a state's partner marginal) a state's conditional partner block
#: may lie from the state's mean
CLIP_SD = 3.0


class ConditionalGaussians:
    """The states' Gaussians over [o, p], read as p given o.

    Parameters
    ----------
    means : ndarray of shape (N, d)
        The states' means, encoded units (:class:`~counterpart.nodes.responder.pair_features.PairEncoder`).
    covars : ndarray of shape (N, d, d)
        Their covariances.
    d_o : int
        Numbers in the observed block (the first d_o of d).
    place_scale : ndarray of shape (NQ,)
        The standardisation scale of the partner's placement numbers, so that ``cov_pos`` and
        ``cov_vel`` are given in metres.

    Attributes
    ----------
    cov_pos : ndarray of shape (N, 2, 2)
        Each state's conditional covariance of the partner's ground position, m^2.
    cov_vel : ndarray of shape (N, 2, 2)
        Each state's conditional covariance of the partner's ground velocity, (m/s)^2.
    """

    def __init__(self, means: np.ndarray, covars: np.ndarray, d_o: int, place_scale: np.ndarray) -> None:
        self.means, self.covars, self.d_o = means, covars, int(d_o)
        do = self.d_o
        S_oo = covars[:, :do, :do]
        S_po = covars[:, do:, :do]
        self._inv_oo = np.linalg.inv(S_oo)
        self._logdet_oo = np.linalg.slogdet(S_oo)[1]
        self._gain = S_po @ self._inv_oo  # (N, d_p, d_o)
        # the conditional mean is linear in the observed block, so an observed person unlike any
        # of training (a tracker's bad frame, a pose no pair showed) extrapolates it without bound
        # into poses no body takes: keep each state's conditional within CLIP_SD standard deviations
        # of that state's own partner marginal
        sd = np.sqrt(np.maximum(np.diagonal(covars[:, do:, do:], axis1=1, axis2=2), 0.0))
        self._cond_lo = means[:, do:] - CLIP_SD * sd
        self._cond_hi = means[:, do:] + CLIP_SD * sd
        # conditional covariances S_pp - S_po S_oo^-1 S_op of the ground position and velocity, metres
        cond = covars[:, do:, do:] - self._gain @ np.swapaxes(S_po, 1, 2)
        sc = place_scale
        self.cov_pos = cond[:, POS][:, :, POS] * np.outer(sc[POS], sc[POS])
        self.cov_vel = cond[:, VEL][:, :, VEL] * np.outer(sc[VEL], sc[VEL])

    def obs_loglik(self, o: np.ndarray) -> np.ndarray:
        """The observed block's log-likelihood under each state's marginal, log N(o; mu_o,k, S_oo,k).

        Parameters
        ----------
        o : ndarray of shape (d_o,)
            The observed block, encoded units.

        Returns
        -------
        ndarray of shape (N,)
            Log-likelihood per state.
        """
        d = o[None, :] - self.means[:, : self.d_o]
        maha = np.einsum("ni,nij,nj->n", d, self._inv_oo, d)
        return -0.5 * (maha + self._logdet_oo + self.d_o * np.log(2 * np.pi))

    def conditional(self, o: np.ndarray) -> np.ndarray:
        """E[p | o, s = k] for every state k, each dimension kept within ``CLIP_SD`` standard deviations
        of the state's partner marginal.

        Parameters
        ----------
        o : ndarray of shape (d_o,)
            The observed block, encoded units.

        Returns
        -------
        ndarray of shape (N, d_p)
            The partner block's conditional mean per state, encoded units.
        """
        d = o[None, :] - self.means[:, : self.d_o]
        cond = self.means[:, self.d_o :] + np.einsum("npo,no->np", self._gain, d)
        return np.clip(cond, self._cond_lo, self._cond_hi)


__all__ = ["ConditionalGaussians", "CLIP_SD"]
