"""Dual HMM interaction model (Zheng et al. 2006 "Virtual friend"; Cosker et al. 2004).

Training. Both people are expressed in the observed person's actor-centred frame
(:mod:`nodes.responder.frames`), so the model does not depend on where the pair stands. Each
person's local pose (14 joints x 3 = 42 numbers) is reduced by its own PCA keeping 95% of the
energy (whitened): o_t (d_o,) for the observed person, p_t (d_p,) for the partner. The observed
block also carries the person's ground velocity in their own frame (3 numbers, m/s, scaled by
``velocity_weight``), which tells walking towards from standing. ONE Gaussian HMM (hmmlearn)
is fitted to the concatenation x_t = [o_t, p_t], so the two people share one hidden state
sequence and one transition matrix A (N x N)::

    x_t | s_t = k  ~  N(mu_k, Sigma_k),   mu_k = [mu_o,k; mu_p,k],
    Sigma_k = [[S_oo,k, S_op,k], [S_po,k, S_pp,k]].

With ``both_roles`` every training pair is used twice (A observed / B partner and the reverse).

Generation, online (one frame at a time). Only the observed block is seen, so the state is
filtered with the observed block's marginal Gaussians (forward algorithm, Rabiner eq. 19)::

    alpha_t(k) ∝ [sum_j alpha_{t-1}(j) A_jk] N(o_t; mu_o,k, S_oo,k)

and the partner is the state-conditional Gaussian of the partner block given the observed block
(Gaussian conditioning), mixed by the state posterior::

    E[p_t | o_t, s_t = k] = mu_p,k + S_po,k S_oo,k^{-1} (o_t - mu_o,k)
    p_t = sum_k alpha_t(k) E[p_t | o_t, k]                      (decode="filter")

``decode="viterbi"`` uses a fixed-lag trellis instead: the Viterbi recursion (max-product) over
the last ``lag`` frames, started from the filtered posterior at t - lag, and the conditional mean
of the best path's state at t: a hard, path-consistent state that changes less often.

The partner's local pose is mapped back through the PCA and the observed person's frame to world
joints (14, 3), metres.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy.special import logsumexp
from sklearn.decomposition import PCA

from body.trajectory import TwoPersonTrajectory

from .frames import actor_frame, to_local, to_world

DECODES = ("filter", "viterbi")


def _pca_state(p: PCA) -> dict[str, np.ndarray]:
    return {"mean": p.mean_, "components": p.components_, "scale": np.sqrt(p.explained_variance_)}


class _Linear:
    """A fitted whitened PCA as plain arrays: z = (x - mean) C^T / scale, x = mean + (z scale) C."""

    def __init__(self, mean: np.ndarray, components: np.ndarray, scale: np.ndarray) -> None:
        self.mean, self.components, self.scale = mean, components, scale

    def forward(self, x: np.ndarray) -> np.ndarray:
        return ((x - self.mean) @ self.components.T) / self.scale

    def inverse(self, z: np.ndarray) -> np.ndarray:
        return self.mean + (z * self.scale) @ self.components


def partner_placement(partner: np.ndarray, origin: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The partner relative to the observed frame (origin (T,3), theta (T,)).

    Returns (placement (T, 4): partner frame origin x, z in the observed frame (metres) and
    cos, sin of the relative heading; own (T, 14, 3): the partner's pose in their own frame).
    """
    po, pth = actor_frame(partner)
    rel_o = to_local(po[:, None, :], origin, theta)[:, 0]
    d = pth - theta
    return np.stack([rel_o[:, 0], rel_o[:, 2], np.cos(d), np.sin(d)], axis=1), to_local(partner, po, pth)


class DualHMM:
    """One Gaussian HMM over [observed, partner] PCA poses; the partner by Gaussian conditioning.

    Parameters: ``n_states`` N hidden states; ``energy`` PCA energy kept per person (0-1);
    ``velocity_weight`` scale of the observed ground velocity (m/s) in the observed block (0 drops
    it); ``n_iter`` Baum-Welch iterations; ``decode`` "filter" or "viterbi"; ``lag`` frames of the
    fixed-lag trellis; ``both_roles`` train on A->B and B->A; ``random_state`` seed.
    """

    name = "dual-hmm"

    def __init__(self, n_states: int = 32, energy: float = 0.95, velocity_weight: float = 2.0,
                 n_iter: int = 25, decode: str = "filter", lag: int = 8, both_roles: bool = True,
                 min_covar: float = 1e-3, random_state: int = 0) -> None:
        if decode not in DECODES:
            raise ValueError(f"decode={decode!r}; choose one of {', '.join(DECODES)}")
        if not 0 < energy <= 1:
            raise ValueError(f"energy={energy!r}: the PCA energy fraction must be in (0, 1]")
        if n_states < 1 or lag < 1:
            raise ValueError(f"n_states={n_states}, lag={lag}: both must be >= 1")
        self.n_states, self.energy, self.velocity_weight = int(n_states), float(energy), float(velocity_weight)
        self.n_iter, self.decode, self.lag = int(n_iter), decode, int(lag)
        self.both_roles, self.min_covar, self.random_state = bool(both_roles), float(min_covar), int(random_state)

    # ------------------------------------------------------------------ features
    def _observed_features(self, obs_local: np.ndarray, vel: np.ndarray) -> np.ndarray:
        """(T, 14, 3) local pose and (T, 3) ground velocity m/s -> (T, d_o) observed block."""
        z = self.pca_o_.forward(obs_local.reshape(len(obs_local), -1))
        if self.velocity_weight > 0:
            z = np.concatenate([z, vel * self.velocity_weight], axis=1)
        return z

    @staticmethod
    def _velocity(observed: np.ndarray, fps: float) -> np.ndarray:
        """(T, 14, 3) world joints -> (T, 3) ground velocity of the frame origin in its own frame."""
        o, th = actor_frame(observed)
        d = np.diff(o, axis=0, prepend=o[:1]) * fps
        return to_local(d[:, None, :], np.zeros_like(o), th)[:, 0]

    def _pairs(self, trajs: Sequence[TwoPersonTrajectory]) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
        """Per role: (observed local pose (T,14,3), observed velocity (T,3), partner placement (T,4),
        partner own-frame pose (T,14,3))."""
        out = []
        for t in trajs:
            roles = [(t.a, t.b), (t.b, t.a)] if self.both_roles else [(t.a, t.b)]
            for obs, par in roles:
                o, th = actor_frame(obs)
                out.append((to_local(obs, o, th), self._velocity(obs, t.fps), *partner_placement(par, o, th)))
        return out

    # ------------------------------------------------------------------ fitting
    def fit(self, trajectories: Sequence[TwoPersonTrajectory]) -> "DualHMM":
        """Fit PCAs and the joint HMM to two-person trajectories (observed = A, and B if both_roles)."""
        import logging

        from hmmlearn.hmm import GaussianHMM

        logging.getLogger("hmmlearn").setLevel(logging.ERROR)  # EM wobble warnings are not actionable

        if not trajectories:
            raise ValueError("DualHMM.fit: no trajectories")
        fps = {round(t.fps, 3) for t in trajectories}
        if len(fps) > 1:
            raise ValueError(f"DualHMM.fit: trajectories have different frame rates {sorted(fps)}; resample them")
        self.fps_ = float(trajectories[0].fps)
        pairs = self._pairs(trajectories)
        O = np.concatenate([p[0] for p in pairs]).reshape(-1, 42)
        V = np.concatenate([p[1] for p in pairs])
        Q = np.concatenate([p[2] for p in pairs])
        P = np.concatenate([p[3] for p in pairs]).reshape(-1, 42)
        self.pca_o_ = _Linear(**_pca_state(PCA(self.energy, whiten=True, svd_solver="full").fit(O)))
        self.pca_p_ = _Linear(**_pca_state(PCA(self.energy, whiten=True, svd_solver="full").fit(P)))
        # the placement (metres, and cos/sin of the relative heading) is standardised like a PCA block
        self.place_mean_, self.place_scale_ = Q.mean(0), np.maximum(Q.std(0), 1e-3)
        X = np.concatenate([self._observed_features(O.reshape(-1, 14, 3), V),
                            (Q - self.place_mean_) / self.place_scale_, self.pca_p_.forward(P)], axis=1)
        self.d_o_ = X.shape[1] - 4 - len(self.pca_p_.scale)
        lengths = [len(p[0]) for p in pairs]
        n = min(self.n_states, len(X))
        hmm = GaussianHMM(n_components=n, covariance_type="full", n_iter=self.n_iter,
                          min_covar=self.min_covar, random_state=self.random_state, tol=1e-3)
        hmm.fit(X, lengths)
        # states that collapsed onto a few frames (e.g. standing still: zero velocity) get a ridge so
        # that every S_oo,k stays invertible
        covars = hmm.covars_ + self.min_covar * np.eye(X.shape[1])
        self._set_params(hmm.startprob_, hmm.transmat_, np.nan_to_num(hmm.means_), covars)
        self.log_likelihood_ = float(hmm.score(X, lengths)) / len(X)
        self.reset()
        return self

    def _set_params(self, startprob: np.ndarray, transmat: np.ndarray, means: np.ndarray, covars: np.ndarray) -> None:
        self.startprob_, self.transmat_ = np.asarray(startprob, float), np.asarray(transmat, float)
        self.means_, self.covars_ = np.asarray(means, float), np.asarray(covars, float)
        do = self.d_o_
        S_oo = self.covars_[:, :do, :do]
        S_po = self.covars_[:, do:, :do]
        self._inv_oo = np.linalg.inv(S_oo)
        self._logdet_oo = np.linalg.slogdet(S_oo)[1]
        self._gain = S_po @ self._inv_oo                       # (N, d_p, d_o)
        self._log_A = np.log(np.maximum(self.transmat_, 1e-300))
        self._log_pi = np.log(np.maximum(self.startprob_, 1e-300))

    # ------------------------------------------------------------------ online generation
    def reset(self) -> None:
        """Forget the past: the next frame starts a new sequence."""
        self._alpha: np.ndarray | None = None
        self._prev_origin: np.ndarray | None = None
        self._lls: list[np.ndarray] = []
        self._alphas: list[np.ndarray] = []
        self.posterior_ = None

    def _obs_loglik(self, o: np.ndarray) -> np.ndarray:
        """(d_o,) observed block -> (N,) log N(o; mu_o,k, S_oo,k)."""
        d = o[None, :] - self.means_[:, : self.d_o_]
        maha = np.einsum("ni,nij,nj->n", d, self._inv_oo, d)
        return -0.5 * (maha + self._logdet_oo + self.d_o_ * np.log(2 * np.pi))

    def _conditional(self, o: np.ndarray) -> np.ndarray:
        """(d_o,) -> (N, d_p) E[p | o, s = k] for every state k."""
        d = o[None, :] - self.means_[:, : self.d_o_]
        return self.means_[:, self.d_o_ :] + np.einsum("npo,no->np", self._gain, d)

    def step(self, observed: np.ndarray) -> np.ndarray:
        """One frame: the observed person's joints (14, 3) world metres -> the partner's (14, 3)."""
        X = np.asarray(observed, np.float64)
        if X.shape != (14, 3):
            raise ValueError(f"observed joints must be (14, 3) metres, got shape {X.shape}")
        origin, theta = actor_frame(X)
        if self._prev_origin is None:
            vel = np.zeros(3)
        else:
            vel = to_local(((origin - self._prev_origin) * self.fps_)[None], np.zeros(3), theta)[0]
        self._prev_origin = origin
        o = self._observed_features(to_local(X, origin, theta)[None], vel[None])[0]
        ll = self._obs_loglik(o)
        prior = self._log_pi if self._alpha is None else logsumexp(self._alpha[:, None] + self._log_A, axis=0)
        la = prior + ll
        self._alpha = la - logsumexp(la)
        self.posterior_ = np.exp(self._alpha)
        cond = self._conditional(o)
        if self.decode == "filter":
            z = self.posterior_ @ cond
        else:
            self._lls.append(ll)
            self._alphas.append(self._alpha)
            if len(self._lls) > self.lag:
                self._lls.pop(0)
                self._alphas.pop(0)
            z = cond[self._viterbi_end()]
        return self._partner_world(z, origin, theta).astype(np.float32)

    def _partner_world(self, z: np.ndarray, origin: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Partner block (4 + d_p,) -> partner world joints (14, 3) via the observed frame."""
        q = z[:4] * self.place_scale_ + self.place_mean_
        own = self.pca_p_.inverse(z[4:]).reshape(14, 3)
        rel = np.arctan2(q[3], q[2])
        p_origin = to_world(np.array([[q[0], 0.0, q[1]]]), origin, theta)[0]
        return to_world(own, p_origin, theta + rel)

    def _viterbi_end(self) -> int:
        """Best-path state at the newest frame over the fixed-lag trellis."""
        delta = self._alphas[0]
        for ll in self._lls[1:]:
            delta = np.max(delta[:, None] + self._log_A, axis=0) + ll
        return int(np.argmax(delta))

    def predict(self, observed: np.ndarray) -> np.ndarray:
        """A whole sequence, frame by frame as online: (T, 14, 3) -> (T, 14, 3) partner, metres."""
        X = np.asarray(observed, np.float64)
        if X.ndim != 3 or X.shape[1:] != (14, 3):
            raise ValueError(f"observed must be (T, 14, 3) metres, got shape {X.shape}")
        self.reset()
        out = np.stack([self.step(x) for x in X])
        self.reset()
        return out

    # ------------------------------------------------------------------ persistence
    def get_state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        arrays = {"startprob": self.startprob_, "transmat": self.transmat_, "means": self.means_,
                  "covars": self.covars_}
        for tag, lin in (("pca_o", self.pca_o_), ("pca_p", self.pca_p_)):
            arrays.update({f"{tag}_mean": lin.mean, f"{tag}_components": lin.components, f"{tag}_scale": lin.scale})
        arrays.update(place_mean=self.place_mean_, place_scale=self.place_scale_)
        config = {"n_states": self.n_states, "energy": self.energy, "velocity_weight": self.velocity_weight,
                  "n_iter": self.n_iter, "decode": self.decode, "lag": self.lag, "both_roles": self.both_roles,
                  "min_covar": self.min_covar, "random_state": self.random_state, "fps": self.fps_,
                  "d_o": self.d_o_}
        return arrays, config

    @classmethod
    def from_state(cls, arrays: dict[str, np.ndarray], config: dict[str, Any]) -> "DualHMM":
        c = dict(config)
        fps, d_o = float(c.pop("fps")), int(c.pop("d_o"))
        m = cls(**c)
        m.fps_, m.d_o_ = fps, d_o
        m.pca_o_ = _Linear(arrays["pca_o_mean"], arrays["pca_o_components"], arrays["pca_o_scale"])
        m.pca_p_ = _Linear(arrays["pca_p_mean"], arrays["pca_p_components"], arrays["pca_p_scale"])
        m.place_mean_, m.place_scale_ = arrays["place_mean"], arrays["place_scale"]
        m._set_params(arrays["startprob"], arrays["transmat"], arrays["means"], arrays["covars"])
        m.reset()
        return m
