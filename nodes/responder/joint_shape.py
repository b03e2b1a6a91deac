"""Joint-shape interaction model (Johnson, Galata & Hogg 1998, "The acquisition and use of
interaction behaviour models").

Shapes. Each frame's joint shape is the combined shape vector of the observed person (first half)
and the partner (second half), ``counterpart.body.spline.combined_shape_vector``: both B-spline
silhouettes (n control points) actor-centred and height-normalised, their relative separation and
log relative scale, x_t (4n + 3,). A PCA keeping ``energy`` of the variance gives y_t (m,). The
observed person is always the first half; a right-hand observed person is mirrored left-right
(:func:`~counterpart.nodes.responder.shapes.mirror_ctrl`), so with ``both_roles`` each pair trains both ways.

Prototypes. The state is v_t = [y_t, w dy_t] with the first derivative dy_t = y_t - y_{t-1}
(per frame, weighted by ``deriv_weight``); K state prototypes by vector quantisation (k-means),
s_t = argmin_k |v_t - c_k|. Behaviour vectors by the conditional decay operator (decay gamma)::

    h_t(k) = 1 if k = s_t,   h_t(k) = gamma h_{t-1}(k) otherwise          (h_0 = 0)

which remembers which prototypes were visited recently and in which order. B behaviour prototypes
by k-means over h_t give b_t. Runs of equal b_t are segments; each behaviour prototype j has a key
shape P_j (mean y over its frames), a key velocity D_j (mean dy) and a mean duration d_j (frames).
A first-order Markov chain over behaviour prototypes, pi (start) and A (B x (B + 1), last column
the end state), is counted from successive segments.

Generation. A hypothesis is (i, j, tau): moving from key i to key j, tau frames into the d_j
frames of the segment. Its shape is the cubic Hermite interpolation at u = tau / d_j::

    y(u) = h00(u) P_i + h10(u) d_j D_i + h01(u) P_j + h11(u) d_j D_j,
    h00 = 2u^3 - 3u^2 + 1, h10 = u^3 - 2u^2 + u, h01 = -2u^3 + 3u^2, h11 = u^3 - u^2.

Online, CONDENSATION (Isard & Blake 1998) propagates ``n_hypotheses`` of them: predict (tau += a
rate drawn around 1; at the end of a segment i <- j and j is drawn from A, the end state
restarting from pi), weigh by the Gaussian likelihood of the real person's shape z_t (2n,)
against the observed half H x(y) of each hypothesis' joint shape::

    w ∝ exp(-|z_t - H x|^2 / (2 sigma^2 2n)),

and resample. The partner is the second half of the weighted mean over the hypotheses of the
dominant target behaviour j, mapped back to pixels with the observed person's position and height.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .shapes import ShapeTrack, mirror_ctrl


def combined_vectors(obs: ShapeTrack, par: ShapeTrack) -> np.ndarray:
    """Combined shape vectors (the layout of spline.combined_shape_vector), vectorised.

    Parameters
    ----------
    obs : ShapeTrack
        The observed person's track: control points (T, n, 2), positions (T, 2) and heights (T,), pixels.
    par : ShapeTrack
        The partner's track, likewise.

    Returns
    -------
    ndarray of shape (T, 4n + 3)
        The combined shape vectors.
    """
    n = obs.ctrl.shape[1]
    va = ((obs.ctrl - obs.pos[:, None]) / obs.height[:, None, None]).reshape(-1, 2 * n)
    vb = ((par.ctrl - par.pos[:, None]) / par.height[:, None, None]).reshape(-1, 2 * n)
    sep = (par.pos - obs.pos) / (0.5 * (obs.height + par.height))[:, None]
    return np.concatenate([va, vb, sep, np.log(par.height / obs.height)[:, None]], axis=1)


def _mirrored(t: ShapeTrack) -> ShapeTrack:
    pos = t.pos.copy()
    pos[:, 0] *= -1
    return ShapeTrack(mirror_ctrl(t.ctrl), pos, t.height, t.valid)


def hermite(p0: np.ndarray, m0: np.ndarray, p1: np.ndarray, m1: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Cubic Hermite interpolation, row by row.

    Parameters
    ----------
    p0, p1 : ndarray of shape (N, m)
        Start and end points.
    m0, m1 : ndarray of shape (N, m)
        Start and end tangents.
    u : ndarray of shape (N,)
        Interpolation parameter in [0, 1].

    Returns
    -------
    ndarray of shape (N, m)
        The interpolated points.
    """
    u = u[:, None]
    u2, u3 = u * u, u * u * u
    return (2 * u3 - 3 * u2 + 1) * p0 + (u3 - 2 * u2 + u) * m0 + (-2 * u3 + 3 * u2) * p1 + (u3 - u2) * m1


class JointShapeModel:
    """Johnson et al.'s joint behaviour model over two silhouettes (see the module docstring).

    Parameters
    ----------
    energy : float
        PCA variance kept.
    n_states : int
        K, the state prototypes (>= 2).
    n_behaviours : int
        B, the behaviour prototypes (>= 2).
    gamma : float
        Decay constant, in (0, 1).
    deriv_weight : float
        w, the weight of the derivative in the state.
    n_hypotheses : int
        CONDENSATION sample size (>= 1).
    sigma : float
        Likelihood width (height-normalised units per coordinate).
    rate_noise : float
        Std of the frame rate of a hypothesis (frames per frame).
    both_roles : bool
        Train each pair both ways (each person as the observed one).
    random_state : int
        Seed of k-means and of the CONDENSATION sample.

    Attributes
    ----------
    mean_ : ndarray of shape (4n + 3,)
        PCA mean of the joint shapes.
    components_ : ndarray of shape (m, 4n + 3)
        PCA components.
    keys_ : ndarray of shape (B, m)
        Key shapes P_j.
    key_velocity_ : ndarray of shape (B, m)
        Key velocities D_j, per frame.
    durations_ : ndarray of shape (B,)
        Mean segment durations d_j, frames.
    start_ : ndarray of shape (B,)
        Start probabilities pi.
    transitions_ : ndarray of shape (B, B + 1)
        Transitions A, the last column the end state.

    Raises
    ------
    ValueError
        If ``gamma`` is not in (0, 1), or ``n_hypotheses`` < 1, ``n_states`` < 2 or ``n_behaviours`` < 2.
    """

    name = "joint-shape"

    def __init__(
        self,
        energy: float = 0.98,
        n_states: int = 40,
        n_behaviours: int = 24,
        gamma: float = 0.8,
        deriv_weight: float = 5.0,
        n_hypotheses: int = 200,
        sigma: float = 0.03,
        rate_noise: float = 0.3,
        both_roles: bool = True,
        random_state: int = 0,
    ) -> None:
        if not 0 < gamma < 1:
            raise ValueError(f"gamma={gamma!r}: the decay constant must be in (0, 1)")
        if n_hypotheses < 1 or n_states < 2 or n_behaviours < 2:
            raise ValueError("n_hypotheses >= 1, n_states >= 2 and n_behaviours >= 2 are required")
        self.energy, self.n_states, self.n_behaviours, self.gamma = (
            float(energy),
            int(n_states),
            int(n_behaviours),
            float(gamma),
        )
        self.deriv_weight, self.n_hypotheses, self.sigma = float(deriv_weight), int(n_hypotheses), float(sigma)
        self.rate_noise, self.both_roles, self.random_state = float(rate_noise), bool(both_roles), int(random_state)

    # ------------------------------------------------------------------ learning
    @staticmethod
    def decay_vectors(states: np.ndarray, k: int, gamma: float) -> np.ndarray:
        """Conditional decay operator over a state-prototype sequence.

        Parameters
        ----------
        states : ndarray of shape (T,), dtype int
            State prototype indices, in [0, k).
        k : int
            Number of state prototypes.
        gamma : float
            Decay constant, in (0, 1).

        Returns
        -------
        ndarray of shape (T, k)
            Behaviour vectors h_t.
        """
        h = np.zeros((len(states), k))
        cur = np.zeros(k)
        for t, s in enumerate(states):  # a recursion over time; vectorised over prototypes
            cur = gamma * cur
            cur[s] = 1.0
            h[t] = cur
        return h

    def fit(self, pairs: Sequence[tuple[ShapeTrack, ShapeTrack]]) -> JointShapeModel:
        """Learn from (observed, partner) shape tracks, A = left person as observed.

        Parameters
        ----------
        pairs : sequence of tuple of (ShapeTrack, ShapeTrack)
            (observed, partner) shape tracks of each training sequence.

        Returns
        -------
        JointShapeModel
            self, fitted.

        Raises
        ------
        ValueError
            If no pair has frames where both people are in view.
        """
        seqs = []
        for a, b in pairs:
            roles = [(a, b), (_mirrored(b), _mirrored(a))] if self.both_roles else [(a, b)]
            for o, p in roles:
                ok = o.valid & p.valid
                if ok.sum() >= 3:
                    seqs.append(combined_vectors(o, p)[ok])
        if not seqs:
            raise ValueError("JointShapeModel.fit: no frames where both people are in view")
        self.n_ctrl_ = (seqs[0].shape[1] - 3) // 4
        X = np.concatenate(seqs)
        from sklearn.cluster import KMeans  # here: a loaded model needs only its arrays; sklearn is slow to import
        from sklearn.decomposition import PCA

        pca = PCA(self.energy, svd_solver="full").fit(X)
        self.mean_, self.components_ = pca.mean_, pca.components_
        Y = [(s - self.mean_) @ self.components_.T for s in seqs]
        dY = [np.diff(y, axis=0, prepend=y[:1]) for y in Y]
        V = np.concatenate([np.concatenate([y, self.deriv_weight * d], 1) for y, d in zip(Y, dY)])
        K = min(self.n_states, len(V))
        km = KMeans(K, n_init=2, random_state=self.random_state).fit(V)
        self.state_prototypes_ = km.cluster_centers_
        lens = np.cumsum([0] + [len(y) for y in Y])
        S = [km.labels_[lens[i] : lens[i + 1]] for i in range(len(Y))]
        H = np.concatenate([self.decay_vectors(s, K, self.gamma) for s in S])
        Bn = min(self.n_behaviours, len(H))
        kb = KMeans(Bn, n_init=2, random_state=self.random_state).fit(H)
        self.behaviour_prototypes_ = kb.cluster_centers_
        Yall, dYall = np.concatenate(Y), np.concatenate(dY)
        m = Yall.shape[1]
        keys, vel, dur = np.zeros((Bn, m)), np.zeros((Bn, m)), np.ones(Bn)
        start = np.full(Bn, 1e-3)
        trans = np.full((Bn, Bn + 1), 1e-3)
        runs: dict[int, list[int]] = {j: [] for j in range(Bn)}
        for i in range(len(Y)):
            b = kb.labels_[lens[i] : lens[i + 1]]
            cut = np.flatnonzero(np.diff(b)) + 1
            bounds = np.r_[0, cut, len(b)]
            labels = b[bounds[:-1]]
            for j, (s0, s1) in zip(labels, zip(bounds[:-1], bounds[1:])):
                runs[int(j)].append(int(s1 - s0))
            start[labels[0]] += 1
            for u, v in zip(labels[:-1], labels[1:]):
                trans[u, v] += 1
            trans[labels[-1], Bn] += 1
        for j in range(Bn):
            sel = kb.labels_ == j
            if sel.any():
                keys[j], vel[j] = Yall[sel].mean(0), dYall[sel].mean(0)
            if runs[j]:
                dur[j] = max(1.0, float(np.mean(runs[j])))
        self.keys_, self.key_velocity_, self.durations_ = keys, vel, dur
        self.start_ = start / start.sum()
        self.transitions_ = trans / trans.sum(1, keepdims=True)
        self.reset()
        return self

    # ------------------------------------------------------------------ generation
    def reset(self) -> None:
        """Start the CONDENSATION sample afresh (prior: pi, then A)."""
        self._rng = np.random.default_rng(self.random_state)
        self._i = self._j = self._tau = None

    def _draw_next(self, i: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Next behaviour for each hypothesis after behaviour i; the end state restarts from pi."""
        Bn = len(self.keys_)
        cdf = np.cumsum(self.transitions_[i], axis=1)
        j = np.minimum((self._rng.random((len(i), 1)) > cdf).sum(1), Bn)
        ended = j == Bn
        if ended.any():
            new_i = self._rng.choice(Bn, ended.sum(), p=self.start_)
            i = i.copy()
            i[ended] = new_i
            cdf = np.cumsum(self.transitions_[new_i, :Bn], axis=1)
            cdf /= cdf[:, -1:]
            j[ended] = np.minimum((self._rng.random((ended.sum(), 1)) > cdf).sum(1), Bn - 1)
        return i, j

    def _init_sample(self) -> None:
        N, Bn = self.n_hypotheses, len(self.keys_)
        # a broad prior: any behaviour, anywhere in its segment
        self._i = self._rng.choice(Bn, N, p=self.start_ * 0.5 + 0.5 / Bn)
        self._i, self._j = self._draw_next(self._i)
        self._tau = self._rng.random(N) * self.durations_[self._j]

    def _shapes(self) -> np.ndarray:
        """(N, 4n + 3) joint shapes of the hypotheses."""
        d = self.durations_[self._j]
        u = np.clip(self._tau / d, 0.0, 1.0)
        y = hermite(
            self.keys_[self._i],
            d[:, None] * self.key_velocity_[self._i],
            self.keys_[self._j],
            d[:, None] * self.key_velocity_[self._j],
            u,
        )
        return self.mean_ + y @ self.components_

    def _predict(self) -> None:
        N = self.n_hypotheses
        self._tau = self._tau + np.maximum(0.1, 1.0 + self.rate_noise * self._rng.standard_normal(N))
        done = self._tau >= self.durations_[self._j]
        if done.any():
            i, j = self._draw_next(self._j[done])
            self._tau[done] = self._tau[done] - self.durations_[self._j[done]]
            self._i[done], self._j[done] = i, j
            self._tau[done] = np.minimum(self._tau[done], self.durations_[j] - 1e-6)
        # a few hypotheses restart anywhere, so a lost track can recover
        k = max(1, N // 50)
        idx = self._rng.choice(N, k, replace=False)
        Bn = len(self.keys_)
        self._i[idx] = self._rng.choice(Bn, k)
        self._i[idx], self._j[idx] = self._draw_next(self._i[idx])
        self._tau[idx] = self._rng.random(k) * self.durations_[self._j[idx]]

    def step(self, ctrl: np.ndarray, height: float, pos: np.ndarray, mirrored: bool = False) -> np.ndarray:
        """One frame: the observed person's silhouette -> the partner's.

        Parameters
        ----------
        ctrl : ndarray of shape (n, 2)
            The observed person's control points, pixels.
        height : float
            The observed person's height, pixels (> 0).
        pos : ndarray of shape (2,)
            The observed person's position, pixels.
        mirrored : bool
            For an observed person on the right (the model was trained with the observed person on
            the left).

        Returns
        -------
        ndarray of shape (n, 2), dtype float32
            The partner's control points, pixels.

        Raises
        ------
        ValueError
            If ``ctrl`` is not (n, 2) for this model's n, or ``height`` is not > 0.
        """
        c = np.asarray(ctrl, np.float64)
        n = self.n_ctrl_
        if c.shape != (n, 2):
            raise ValueError(f"ctrl must be ({n}, 2) pixels for this model, got shape {c.shape}")
        if not height > 0:
            raise ValueError(f"height must be > 0 pixels, got {height}")
        pos = np.asarray(pos, np.float64).reshape(2)
        if mirrored:
            c, pos = mirror_ctrl(c), pos * [-1.0, 1.0]
        z = ((c - pos) / height).ravel()
        if self._i is None:
            self._init_sample()
        else:
            self._predict()
        X = self._shapes()
        d2 = ((X[:, : 2 * n] - z) ** 2).sum(1)
        logw = -d2 / (2 * self.sigma**2 * 2 * n)
        w = np.exp(logw - logw.max())
        w /= w.sum()
        self.weights_ = w
        # the dominant target behaviour, and the weighted mean of its hypotheses
        mode = int(np.argmax(np.bincount(self._j, weights=w, minlength=len(self.keys_))))
        sel = self._j == mode
        x = (w[sel, None] * X[sel]).sum(0) / w[sel].sum()
        self.mode_, self.confidence_ = mode, float(w[sel].sum())
        self.fit_error_ = float(np.sqrt(d2 @ w / (2 * n)))
        # systematic resampling
        u = (self._rng.random() + np.arange(self.n_hypotheses)) / self.n_hypotheses
        idx = np.minimum(np.searchsorted(np.cumsum(w), u), self.n_hypotheses - 1)
        self._i, self._j, self._tau = self._i[idx], self._j[idx], self._tau[idx]
        vb = x[2 * n : 4 * n].reshape(n, 2)
        sep, scale = x[4 * n : 4 * n + 2], x[4 * n + 2]
        h_b = height * np.exp(scale)
        pos_b = pos + sep * 0.5 * (height + h_b)
        out = vb * h_b + pos_b
        if mirrored:
            out = mirror_ctrl(out)
        return out.astype(np.float32)

    def predict(self, observed: ShapeTrack, mirrored: bool = False) -> np.ndarray:
        """A whole track frame by frame.

        Parameters
        ----------
        observed : ShapeTrack
            The observed person's track of T frames.
        mirrored : bool
            For an observed person on the right (see :meth:`step`).

        Returns
        -------
        ndarray of shape (T, n, 2), dtype float32
            Partner control points, pixels (NaN where not valid).
        """
        self.reset()
        out = np.full(observed.ctrl.shape, np.nan, np.float32)
        for t in np.flatnonzero(observed.valid):
            out[t] = self.step(observed.ctrl[t], observed.height[t], observed.pos[t], mirrored)
        self.reset()
        return out

    # ------------------------------------------------------------------ persistence
    _ARRAYS = (
        "mean_",
        "components_",
        "state_prototypes_",
        "behaviour_prototypes_",
        "keys_",
        "key_velocity_",
        "durations_",
        "start_",
        "transitions_",
    )

    def get_state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """The fitted model for saving.

        Returns
        -------
        arrays : dict of str to ndarray
            The fitted arrays, named without their trailing underscore.
        config : dict of str to Any
            The constructor's parameters and ``n_ctrl``, the control points per silhouette.
        """
        config = {
            k: getattr(self, k)
            for k in (
                "energy",
                "n_states",
                "n_behaviours",
                "gamma",
                "deriv_weight",
                "n_hypotheses",
                "sigma",
                "rate_noise",
                "both_roles",
                "random_state",
            )
        }
        config["n_ctrl"] = self.n_ctrl_
        return {k.rstrip("_"): getattr(self, k) for k in self._ARRAYS}, config

    @classmethod
    def from_state(cls, arrays: dict[str, np.ndarray], config: dict[str, Any]) -> JointShapeModel:
        """A fitted model from what :meth:`get_state` gave.

        Parameters
        ----------
        arrays : dict of str to ndarray
            The fitted arrays, named without their trailing underscore.
        config : dict of str to Any
            The constructor's parameters and ``n_ctrl``.

        Returns
        -------
        JointShapeModel
            The fitted model, its CONDENSATION sample reset.
        """
        c = dict(config)
        n = int(c.pop("n_ctrl"))
        m = cls(**c)
        m.n_ctrl_ = n
        for k in cls._ARRAYS:
            setattr(m, k, arrays[k.rstrip("_")])
        m.reset()
        return m
