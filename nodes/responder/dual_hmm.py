"""Dual HMM interaction model (Zheng et al. 2006 "Virtual friend"; Cosker et al. 2004).

Training. Both people are expressed in the observed person's actor-centred frame
(:mod:`counterpart.nodes.responder.frames`), so the model does not depend on where the pair stands. Each
person's own pose (14 joints x 3 = 42 numbers, in their own actor frame) is reduced by its own PCA
keeping 95% of the energy (whitened). The observed block o_t is the observed person's PCA pose plus
their ground velocity in their own frame (3 numbers, m/s, scaled by ``velocity_weight``), which
tells walking towards from standing. The partner block p_t is the partner's placement in the
observed frame (ground position x, z in metres; cos, sin of the relative heading), the partner's
ground velocity (x, z, m/s, observed frame), all standardised, and the partner's PCA pose. ONE
Gaussian HMM (hmmlearn, full covariances) emits the concatenation x_t = [o_t, p_t], so the two
people share one hidden state sequence and one transition matrix A (N x N)::

    x_t | s_t = k  ~  N(mu_k, Sigma_k),   mu_k = [mu_o,k; mu_p,k],
    Sigma_k = [[S_oo,k, S_op,k], [S_po,k, S_pp,k]].

The states are fitted per interaction label (``TwoPersonTrajectory.label``): Baum-Welch on each
label's sequences with its share of the N states, in proportion to the label's number of phases
(a three-phase interaction gets three times the states of a conversation). Where the label's
trajectories carry phase labels with more than one phase (approach, contact, retreat),
Baum-Welch starts from a time-ordered model (:meth:`DualHMM._init_ordered`): the states are
shared out between the phases and along time within each phase, the first state is the start and
the transitions run forward (mixed with ``order_mix`` of uniform). The states then follow the
interaction's course, so the standing of the start (partner far away, about to walk in) and the
standing of the end (partner still, after stepping back) are different states. Other labels (one
phase all through, e.g. a conversation, or no phase labels) start from hmmlearn's k-means
initialisation. The blocks are joined into the one HMM with a block-diagonal A, start
probabilities weighted by each label's share of the data and a small ``leak`` towards the start
distribution so that a change of interaction is followed. With ``both_roles`` every training
pair is used twice (A observed / B partner and the reverse).

Generation, online (one frame at a time). Only the observed block is seen, so the state is
filtered with the observed block's marginal Gaussians (forward algorithm, Rabiner eq. 19)::

    alpha_t(k) ∝ [sum_j alpha_{t-1}(j) A_jk] N(o_t; mu_o,k, S_oo,k)^w

with the evidence weight w = ``evidence_weight`` (< 1): successive frames are far from
independent given the state and the full-covariance Gaussians are sharp, so with w = 1 the
posterior snaps onto one interaction from the first few frames of standing, which look alike in
every interaction; tempering keeps it spread until the interaction shows. The partner is the
state-conditional Gaussian of the partner block given the observed block (Gaussian conditioning),
mixed by the state posterior::

    E[p_t | o_t, s_t = k] = mu_p,k + S_po,k S_oo,k^{-1} (o_t - mu_o,k)
    p_t = sum_k alpha_t(k) E[p_t | o_t, k]                      (decode="filter")

``decode="viterbi"`` uses a fixed-lag trellis instead: the Viterbi recursion (max-product) over
the last ``lag`` frames, started from the filtered posterior at t - lag, and the conditional mean
of the best path's state at t: a hard, path-consistent state that changes less often.

Placement. With ``placement="relative"`` the partner's ground position is the conditional mean
above, frame by frame. With ``placement="tracked"`` (default) it is kept in the world by a Kalman
filter: predicted with the conditional partner velocity (and its conditional covariance),
corrected with the conditional position and its covariance (the state mixture's moments of the
conditional covariances S_pp - S_po S_oo^-1 S_op). The partner keeps walking or stepping back
where the observed person gives no cue, and snaps to the observed person where the state pins
the position down (hands joined).

Placement correction. While the two people are still walking up or standing, the interaction,
and with it where the partner stands (a wave's partner 2.5 m away, a push's 1.3 m and walking in),
is ambiguous; the tracked placement then mixes the labels' placements in the proportions of the
tempered posterior, which is not calibrated for this. A regression forest (extremely randomised
trees) learns the error of the placement (true minus generated ground position x, z, metres) from
causal features of each frame: the placement, each label's posterior mass and its own conditional
distance, the time since the sequence started, and the observed person's recent and fastest ground
speed and the path walked so far (:meth:`DualHMM._correction_features`); the forest's prediction
is added to the placement. It is fitted by cross-fitting (``correction_folds``): models fitted
without one fold of the training sequences are run online on that fold, so that the errors learnt
are those of unseen sequences. Validation seeds 100-103 / 104-107 / 108-111 / 112-115 (trained on
the default seeds 0-7): 231.3 / 262.6 / 258.7 / 282.4 mm -> 223.7 / 248.1 / 229.9 / 255.6 mm; most of
the gain in the approach phase (handshake approach 205 -> 144 mm).

The partner's own pose is mapped back through its PCA and placed with the placement and
relative heading in the observed person's frame: world joints (14, 3), metres.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from counterpart.body.trajectory import TwoPersonTrajectory
from scipy.special import logsumexp
from sklearn.decomposition import PCA

from .frames import actor_frame, to_local, to_world

DECODES = ("filter", "viterbi")
#: the partner block: placement x, z (metres), cos, sin of the relative heading, ground velocity
#: x, z (m/s), all in the observed frame; then the partner's own-pose PCA
_NQ = 6
_POS, _VEL = np.array([0, 1]), np.array([4, 5])


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


def partner_velocity(partner: np.ndarray, theta: np.ndarray, fps: float) -> np.ndarray:
    """The partner's ground velocity (T, 2) (x, z in m/s) in the observed frame of heading theta (T,).

    A backward difference, v_t = (r_t - r_{t-1}) fps (v_0 = 0), so that r_t = r_{t-1} + v_t / fps
    integrates it exactly.
    """
    po, _ = actor_frame(partner)
    d = np.diff(po, axis=0, prepend=po[:1]) * fps
    return to_local(d[:, None, :], np.zeros_like(po), theta)[:, 0][:, [0, 2]]


def _ground_rot(theta: float) -> np.ndarray:
    """(2, 2) rotation of ground vectors (x, z) from the frame of heading theta to the world."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, s], [-s, c]])


PLACEMENTS = ("tracked", "relative")
#: how far (standard deviations of a state's partner marginal) a state's conditional partner block
#: may lie from the state's mean
CLIP_SD = 3.0
#: the observed person's motion summaries in the placement correction's features: seconds since the
#: sequence started, mean ground speed over the last frames, its maximum so far (m/s), the ground path
#: walked so far (m); capped where longer histories tell nothing more about the approach
_T_CAP_S, _PATH_CAP_M, _SPEED_FRAMES = 6.0, 2.0, 5


class _Forest:
    """A fitted regression forest (scikit-learn's tree arrays, padded to one width) as plain arrays.

    feature, threshold, left, right: (n_trees, n_nodes) split feature index, threshold, child nodes
    (-1 at a leaf); value: (n_trees, n_nodes, n_out) the node means. A sample goes left where
    x[feature] <= threshold; the prediction is the mean over trees of the leaf values.
    """

    def __init__(
        self, feature: np.ndarray, threshold: np.ndarray, left: np.ndarray, right: np.ndarray, value: np.ndarray
    ) -> None:
        self.feature, self.threshold = np.asarray(feature, np.intp), np.asarray(threshold, np.float64)
        self.left, self.right, self.value = np.asarray(left, np.intp), np.asarray(right, np.intp), np.asarray(value)
        self._rows = np.arange(len(self.feature))

    @classmethod
    def from_sklearn(cls, forest: Any) -> _Forest:
        trees = [e.tree_ for e in forest.estimators_]
        n, d = max(t.node_count for t in trees), trees[0].value.shape[1]
        F, L, R = (
            np.zeros((len(trees), n), np.int32),
            np.full((len(trees), n), -1, np.int32),
            np.full((len(trees), n), -1, np.int32),
        )
        th, V = np.zeros((len(trees), n)), np.zeros((len(trees), n, d))
        for i, t in enumerate(trees):
            k = t.node_count
            F[i, :k], th[i, :k] = np.maximum(t.feature, 0), t.threshold
            L[i, :k], R[i, :k], V[i, :k] = t.children_left, t.children_right, t.value[:, :, 0]
        return cls(F, th, L, R, V)

    def arrays(self) -> dict[str, np.ndarray]:
        return {
            "feature": self.feature.astype(np.int32),
            "threshold": self.threshold,
            "left": self.left.astype(np.int32),
            "right": self.right.astype(np.int32),
            "value": self.value,
        }

    def predict(self, x: np.ndarray) -> np.ndarray:
        """(d,) features -> (n_out,) the forest's mean prediction; all trees walked together."""
        # scikit-learn splits on float32 features: compare the same rounded values
        x = np.asarray(x, np.float32).astype(np.float64)
        idx = np.zeros(len(self._rows), np.intp)
        while True:
            left = self.left[self._rows, idx]
            inner = left >= 0
            if not inner.any():
                return self.value[self._rows, idx].mean(0)
            go_left = x[self.feature[self._rows, idx]] <= self.threshold[self._rows, idx]
            idx = np.where(inner, np.where(go_left, left, self.right[self._rows, idx]), idx)


class DualHMM:
    """One Gaussian HMM over [observed, partner] PCA poses; the partner by Gaussian conditioning.

    Parameters: ``n_states`` N hidden states in all (shared out between the interaction labels in
    proportion to their number of phases, at least 2 each); ``energy`` PCA energy kept per person
    (0-1);
    ``velocity_weight`` scale of the observed ground velocity (m/s) in the observed block (0 drops
    it); ``n_iter`` Baum-Welch iterations; ``decode`` "filter" or "viterbi"; ``lag`` frames of the
    fixed-lag trellis; ``placement`` "tracked" (the partner's ground position kept in the world by a
    Kalman filter, see the module docstring) or "relative" (the per-frame conditional alone);
    ``process_noise`` q, m^2 per frame added to the partner's position variance (keeps the
    Kalman covariances invertible where the partner's placement is certain); ``evidence_weight``
    w in (0, 1], the exponent of the observation likelihood in the state filter; ``leak`` the
    probability per frame of leaving an interaction's block of states; ``both_roles`` train on A->B and B->A;
    ``order_mix`` the uniform share mixed into the time-ordered start of a block's transitions
    and start probabilities (1 uses hmmlearn's k-means start for every block);
    ``min_covar`` ridge added to the state covariances (whitened units); ``random_state`` seed;
    ``correction_folds`` folds of the cross-fitted placement correction (0: no correction; see the
    module docstring), ``correction_trees`` its number of trees and ``correction_leaf`` the
    fewest training frames in one of their leaves.
    """

    name = "dual-hmm"

    def __init__(
        self,
        n_states: int = 48,
        energy: float = 0.95,
        velocity_weight: float = 2.0,
        n_iter: int = 25,
        decode: str = "filter",
        lag: int = 8,
        placement: str = "tracked",
        process_noise: float = 1e-4,
        evidence_weight: float = 0.05,
        leak: float = 1e-5,
        both_roles: bool = True,
        order_mix: float = 0.2,
        min_covar: float = 1e-2,
        random_state: int = 0,
        correction_folds: int = 2,
        correction_trees: int = 30,
        correction_leaf: int = 20,
    ) -> None:
        if decode not in DECODES:
            raise ValueError(f"decode={decode!r}; choose one of {', '.join(DECODES)}")
        if placement not in PLACEMENTS:
            raise ValueError(f"placement={placement!r}; choose one of {', '.join(PLACEMENTS)}")
        if not 0 < energy <= 1:
            raise ValueError(f"energy={energy!r}: the PCA energy fraction must be in (0, 1]")
        if n_states < 1 or lag < 1:
            raise ValueError(f"n_states={n_states}, lag={lag}: both must be >= 1")
        self.n_states, self.energy, self.velocity_weight = int(n_states), float(energy), float(velocity_weight)
        self.n_iter, self.decode, self.lag = int(n_iter), decode, int(lag)
        if not process_noise > 0:
            raise ValueError(f"process_noise={process_noise!r} must be > 0")
        self.placement, self.process_noise = placement, float(process_noise)
        if not 0 < evidence_weight <= 1 or not 0 <= leak < 1:
            raise ValueError(f"evidence_weight={evidence_weight!r} must be in (0, 1] and leak={leak!r} in [0, 1)")
        self.evidence_weight, self.leak = float(evidence_weight), float(leak)
        self.both_roles, self.min_covar, self.random_state = bool(both_roles), float(min_covar), int(random_state)
        if not 0 <= order_mix <= 1:
            raise ValueError(f"order_mix={order_mix!r} must be in [0, 1]")
        self.order_mix = float(order_mix)
        if correction_folds == 1 or correction_folds < 0 or correction_trees < 1 or correction_leaf < 1:
            raise ValueError(
                f"correction_folds={correction_folds!r} must be 0 (no correction) or >= 2, "
                f"correction_trees={correction_trees!r} and correction_leaf={correction_leaf!r} >= 1"
            )
        self.correction_folds, self.correction_trees = int(correction_folds), int(correction_trees)
        self.correction_leaf = int(correction_leaf)
        self._forest: _Forest | None = None
        self._feature_labels: np.ndarray | None = None

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

    def _pairs(self, trajs: Sequence[TwoPersonTrajectory]) -> list[tuple[np.ndarray, ...]]:
        """Per role: (observed local pose (T,14,3), observed velocity (T,3), partner placement (T,4),
        partner ground velocity (T,2), partner own-frame pose (T,14,3), interaction label,
        phase labels (T,) or None).
        """
        out = []
        for t in trajs:
            roles = [(t.a, t.b), (t.b, t.a)] if self.both_roles else [(t.a, t.b)]
            for obs, par in roles:
                o, th = actor_frame(obs)
                q, own = partner_placement(par, o, th)
                out.append(
                    (
                        to_local(obs, o, th),
                        self._velocity(obs, t.fps),
                        q,
                        partner_velocity(par, th, t.fps),
                        own,
                        t.label,
                        t.phase,
                    )
                )
        return out

    # ------------------------------------------------------------------ fitting
    def fit(self, trajectories: Sequence[TwoPersonTrajectory]) -> DualHMM:
        """Fit PCAs and the joint HMM to two-person trajectories (observed = A, and B if both_roles).

        Runs with one BLAS thread: the matrices are small, and threads contending for a few busy
        cores made Baum-Welch several times slower.
        """
        from threadpoolctl import threadpool_limits

        with threadpool_limits(1):
            self._fit(trajectories)
            self._forest = None
            if self.correction_folds >= 2:
                self._fit_correction(trajectories)
        return self

    def _config(self) -> dict[str, Any]:
        """The constructor parameters."""
        return {
            "n_states": self.n_states,
            "energy": self.energy,
            "velocity_weight": self.velocity_weight,
            "n_iter": self.n_iter,
            "decode": self.decode,
            "lag": self.lag,
            "placement": self.placement,
            "process_noise": self.process_noise,
            "evidence_weight": self.evidence_weight,
            "leak": self.leak,
            "both_roles": self.both_roles,
            "order_mix": self.order_mix,
            "min_covar": self.min_covar,
            "random_state": self.random_state,
            "correction_folds": self.correction_folds,
            "correction_trees": self.correction_trees,
            "correction_leaf": self.correction_leaf,
        }

    def _fit_correction(self, trajectories: Sequence[TwoPersonTrajectory]) -> None:
        """The placement correction, by cross-fitting: the trajectories of each label are dealt to
        ``correction_folds`` folds; a model fitted without a fold (no correction) is run online on
        it, recording each frame's features (:meth:`_correction_features`) and the error of its
        placement (true minus generated ground position, observed frame, metres). A forest of
        extremely randomised trees (scikit-learn, ``correction_trees`` trees, leaves of at least
        ``correction_leaf`` frames) learns the error from the features. Held-out runs, not the
        model's own training sequences, so that the errors are those of sequences it has not seen.
        """
        from sklearn.ensemble import ExtraTreesRegressor

        trajs = list(trajectories)
        labels = np.array([t.label for t in trajs])
        fold = np.zeros(len(trajs), int)
        for g in np.unique(labels):
            idx = np.flatnonzero(labels == g)
            fold[idx] = np.arange(len(idx)) % self.correction_folds
        X, Y = [], []
        for k in range(self.correction_folds):
            held, rest = [trajs[i] for i in np.flatnonzero(fold == k)], [trajs[i] for i in np.flatnonzero(fold != k)]
            if not held or not rest:
                continue
            sub = DualHMM(**{**self._config(), "correction_folds": 0})._fit(rest)
            sub._feature_labels = np.unique(self.block_labels_)
            for t in held:
                for obs, par in [(t.a, t.b), (t.b, t.a)] if self.both_roles else [(t.a, t.b)]:
                    f, q = sub._record(obs)
                    o, th = actor_frame(obs)
                    X.append(f)
                    Y.append(partner_placement(par, o, th)[0][:, :2] - q)
        if not X:
            return
        forest = ExtraTreesRegressor(
            self.correction_trees,
            min_samples_leaf=self.correction_leaf,
            max_features=1.0,
            random_state=self.random_state,
        ).fit(np.concatenate(X), np.concatenate(Y))
        self._forest = _Forest.from_sklearn(forest)

    def _record(self, observed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Run a sequence (T, 14, 3) online; returns each frame's correction features (T, d_f) and
        uncorrected placement (T, 2) (x, z, observed frame, metres).
        """
        self.reset()
        self._rec = []
        for x in np.asarray(observed, np.float64):
            self.step(x)
        f, q = (np.array(v) for v in zip(*self._rec))
        self.reset()
        return f, q

    def _fit(self, trajectories: Sequence[TwoPersonTrajectory]) -> DualHMM:
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
        # the placement (metres, cos/sin of the relative heading) and the partner's ground velocity
        # (m/s) are standardised like a whitened PCA block
        Q = np.concatenate([np.concatenate([p[2], p[3]], axis=1) for p in pairs])
        P = np.concatenate([p[4] for p in pairs]).reshape(-1, 42)
        self.pca_o_ = _Linear(**_pca_state(PCA(self.energy, whiten=True, svd_solver="full").fit(O)))
        self.pca_p_ = _Linear(**_pca_state(PCA(self.energy, whiten=True, svd_solver="full").fit(P)))
        self.place_mean_, self.place_scale_ = Q.mean(0), np.maximum(Q.std(0), 1e-3)
        X = np.concatenate(
            [
                self._observed_features(O.reshape(-1, 14, 3), V),
                (Q - self.place_mean_) / self.place_scale_,
                self.pca_p_.forward(P),
            ],
            axis=1,
        )
        self.d_o_ = X.shape[1] - _NQ - len(self.pca_p_.scale)
        lengths = np.array([len(p[0]) for p in pairs])
        labels = [p[5] for p in pairs]
        groups = sorted(set(labels))
        members = {g: [i for i, lab in enumerate(labels) if lab == g] for g in groups}
        phases = {g: [pairs[i][6] for i in members[g]] for g in groups}
        # a label's phases: the distinct phase labels of its sequences (one where any has none)
        n_phases = {
            g: 1 if any(ph is None for ph in phases[g]) else len(np.unique(np.concatenate(phases[g]))) for g in groups
        }
        total = sum(n_phases.values())
        starts, ends = np.cumsum(lengths) - lengths, np.cumsum(lengths)

        def new_hmm(n: int, ordered: bool) -> Any:
            # the priors (a ridge of one pseudo-frame, a vanishing pull of the means to 0) keep the
            # M-step finite and positive definite for a state that Baum-Welch leaves (almost) empty
            d = X.shape[1]
            return GaussianHMM(
                n_components=n,
                covariance_type="full",
                n_iter=self.n_iter,
                min_covar=self.min_covar,
                covars_prior=self.min_covar * np.eye(d),
                covars_weight=d + 1,
                means_weight=1e-3,
                random_state=self.random_state,
                tol=1e-3,
                init_params="" if ordered else "stmc",
            )

        blocks = []
        for g in groups:
            idx = members[g]
            Xg = np.concatenate([X[starts[i] : ends[i]] for i in idx])
            # the state budget is shared out by phases: a three-phase interaction gets three times
            # the states of a one-phase one (a conversation)
            n = min(max(2, self.n_states * n_phases[g] // total), len(Xg))
            ordered = self.order_mix < 1 and n_phases[g] > 1
            hmm = new_hmm(n, ordered)
            if ordered:
                self._init_ordered(hmm, [X[starts[i] : ends[i]] for i in idx], phases[g])
            hmm.fit(Xg, lengths[idx])
            blocks.append((hmm, len(idx) / len(pairs)))
        # one HMM: block-diagonal transitions (one block per interaction type), weighted start
        # probabilities, a small leak between blocks so a changed interaction is picked up
        N = sum(h.n_components for h, _ in blocks)
        A = np.zeros((N, N))
        pi, means, covars = np.zeros(N), [], []
        k = 0
        for hmm, w in blocks:
            n = hmm.n_components
            # a state that Baum-Welch left empty has no transitions out (a zero row): it stays
            T = np.nan_to_num(hmm.transmat_)
            empty = T.sum(1) <= 0
            T[empty] = np.eye(n)[empty]
            A[k : k + n, k : k + n] = T
            pi[k : k + n] = w * hmm.startprob_
            means.append(np.nan_to_num(hmm.means_))
            # states that collapsed onto a few frames (e.g. standing still: zero velocity) get a ridge
            # so that every S_oo,k stays invertible
            covars.append(hmm.covars_ + self.min_covar * np.eye(X.shape[1]))
            k += n
        if len(blocks) > 1:
            A = (1 - self.leak) * A + self.leak * np.broadcast_to(pi, A.shape)
        self.block_labels_ = np.repeat(groups, [h.n_components for h, _ in blocks])  # the label of each state
        self._set_params(pi / pi.sum(), A / A.sum(1, keepdims=True), np.concatenate(means), np.concatenate(covars))
        self.reset()
        return self

    def _init_ordered(self, hmm: Any, seqs: list[np.ndarray], phases: list[np.ndarray]) -> None:
        """Time-ordered start for one block: the states are shared out between the interaction's
        phases in proportion to their frames, and within a phase each sequence's frames are cut into
        equal time segments; state k's Gaussian is fitted to its segments. Start in the first state,
        stay or move one state on (A banded), both mixed with ``order_mix`` of uniform so that
        Baum-Welch can still learn other transitions.
        """
        n, d = hmm.n_components, seqs[0].shape[1]
        names = sorted(set(np.concatenate(phases).tolist()))
        counts = np.array([sum(int((ph == p).sum()) for ph in phases) for p in names], float)
        share = np.maximum(1, np.floor(n * counts / counts.sum())).astype(int)
        while share.sum() < n:
            share[np.argmax(n * counts / counts.sum() - share)] += 1
        while share.sum() > n:
            share[np.argmax(share)] -= 1
        first = np.cumsum(share) - share
        assign = []
        for ph in phases:
            a = np.zeros(len(ph), int)
            for p, f, c in zip(names, first, share):
                idx = np.flatnonzero(ph == p)
                a[idx] = f + (np.arange(len(idx)) * c) // max(len(idx), 1)
            assign.append(a)
        Xc, ac = np.concatenate(seqs), np.concatenate(assign)
        means, covars = np.zeros((n, d)), np.zeros((n, d, d))
        for k in range(n):
            sk = Xc[ac == k] if (ac == k).sum() > d else Xc
            means[k], covars[k] = sk.mean(0), np.cov(sk.T) + self.min_covar * np.eye(d)
        stay = 1.0 - n / np.mean([len(x) for x in seqs])
        A = np.eye(n) * stay + np.eye(n, k=1) * (1 - stay)
        A[-1, -1] = 1.0
        hmm.means_, hmm.covars_ = means, covars
        hmm.transmat_ = (1 - self.order_mix) * A + self.order_mix / n
        hmm.startprob_ = (1 - self.order_mix) * np.eye(n)[0] + self.order_mix / n

    def _set_params(self, startprob: np.ndarray, transmat: np.ndarray, means: np.ndarray, covars: np.ndarray) -> None:
        self.startprob_, self.transmat_ = np.asarray(startprob, float), np.asarray(transmat, float)
        self.means_, self.covars_ = np.asarray(means, float), np.asarray(covars, float)
        do = self.d_o_
        S_oo = self.covars_[:, :do, :do]
        S_po = self.covars_[:, do:, :do]
        self._inv_oo = np.linalg.inv(S_oo)
        self._logdet_oo = np.linalg.slogdet(S_oo)[1]
        self._gain = S_po @ self._inv_oo  # (N, d_p, d_o)
        # the conditional mean is linear in the observed block, so an observed person unlike any
        # of training (a tracker's bad frame, a pose no pair showed) extrapolates it without bound
        # into poses no body takes: keep each state's conditional within CLIP_SD standard deviations
        # of that state's own partner marginal
        sd = np.sqrt(np.maximum(np.diagonal(self.covars_[:, do:, do:], axis1=1, axis2=2), 0.0))
        self._cond_lo = self.means_[:, do:] - CLIP_SD * sd
        self._cond_hi = self.means_[:, do:] + CLIP_SD * sd
        # conditional covariances S_pp - S_po S_oo^-1 S_op of the ground position and velocity, metres
        cond = self.covars_[:, do:, do:] - self._gain @ np.swapaxes(S_po, 1, 2)
        sc = self.place_scale_
        self._cov_pos = cond[:, _POS][:, :, _POS] * np.outer(sc[_POS], sc[_POS])
        self._cov_vel = cond[:, _VEL][:, :, _VEL] * np.outer(sc[_VEL], sc[_VEL])
        self._log_A = np.log(np.maximum(self.transmat_, 1e-300))
        self._log_pi = np.log(np.maximum(self.startprob_, 1e-300))

    # ------------------------------------------------------------------ online generation
    def reset(self) -> None:
        """Forget the past: the next frame starts a new sequence."""
        self._alpha: np.ndarray | None = None
        self._prev_origin: np.ndarray | None = None
        self._lls: list[np.ndarray] = []
        self._alphas: list[np.ndarray] = []
        self._track: tuple[np.ndarray, np.ndarray] | None = None  # partner ground (x, z) world, (2, 2) cov
        self.posterior_ = None
        # the observed person's motion so far (correction features): frames, last ground speeds
        # (m/s), fastest smoothed speed (m/s), path walked (m)
        self._n_seen, self._speeds, self._top_speed, self._path = 0, [], 0.0, 0.0
        self._rec: list[tuple[np.ndarray, np.ndarray]] | None = None
        # (L, N) which states belong to each label of the correction's features: fixed per model,
        # built once per sequence rather than per frame
        self._label_member: np.ndarray | None = None
        if hasattr(self, "block_labels_"):
            labels = self._feature_labels if self._feature_labels is not None else np.unique(self.block_labels_)
            self._label_member = (np.asarray(labels)[:, None] == self.block_labels_[None, :]).astype(float)

    def _obs_loglik(self, o: np.ndarray) -> np.ndarray:
        """(d_o,) observed block -> (N,) log N(o; mu_o,k, S_oo,k)."""
        d = o[None, :] - self.means_[:, : self.d_o_]
        maha = np.einsum("ni,nij,nj->n", d, self._inv_oo, d)
        return -0.5 * (maha + self._logdet_oo + self.d_o_ * np.log(2 * np.pi))

    def _conditional(self, o: np.ndarray) -> np.ndarray:
        """(d_o,) -> (N, d_p) E[p | o, s = k] for every state k, each dimension kept within
        ``CLIP_SD`` standard deviations of the state's partner marginal.
        """
        d = o[None, :] - self.means_[:, : self.d_o_]
        cond = self.means_[:, self.d_o_ :] + np.einsum("npo,no->np", self._gain, d)
        return np.clip(cond, self._cond_lo, self._cond_hi)

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
        ll = self.evidence_weight * self._obs_loglik(o)
        prior = self._log_pi if self._alpha is None else logsumexp(self._alpha[:, None] + self._log_A, axis=0)
        la = prior + ll
        self._alpha = la - logsumexp(la)
        self.posterior_ = np.exp(self._alpha)
        cond = self._conditional(o)
        if self.decode == "filter":
            w = self.posterior_
        else:
            self._lls.append(ll)
            self._alphas.append(self._alpha)
            if len(self._lls) > self.lag:
                self._lls.pop(0)
                self._alphas.pop(0)
            w = np.zeros(len(cond))
            w[self._viterbi_end()] = 1.0
        z = w @ cond
        q = z[:_NQ] * self.place_scale_ + self.place_mean_
        if self.placement == "tracked":
            q[_POS] = self._track_position(cond, w, origin, theta)
        if self._forest is not None or self._rec is not None:
            f = self._correction_features(q[_POS], cond, float(np.hypot(vel[0], vel[2])))
            if self._rec is not None:
                self._rec.append((f, q[_POS].copy()))
            if self._forest is not None:
                q[_POS] = q[_POS] + self._forest.predict(f)
        return self._partner_world(q, z[_NQ:], origin, theta).astype(np.float32)

    def _correction_features(self, pos: np.ndarray, cond: np.ndarray, speed: float) -> np.ndarray:
        """The placement correction's features at this frame, (2 + 3 L + 4,) for L labels.

        pos (2,) the model's placement (x, z, observed frame, metres); cond (N, d_p) the states'
        conditional partner blocks; speed the observed ground speed (m/s). Features: pos; the
        posterior mass of each label's states; each label's posterior-weighted conditional distance
        z (metres; 0 where the label has no mass) and its difference to pos; the seconds since the
        sequence started, the speed averaged over the last frames, its maximum so far and the path
        walked (capped). While the interaction is unclear the tracked placement mixes the labels'
        placements in the proportions of a tempered posterior; these let the correction reweigh
        them by how far into the sequence, and how far and fast the observed person has come.
        """
        self._n_seen += 1
        self._speeds = (self._speeds + [speed])[-_SPEED_FRAMES:]
        mean_speed = float(np.mean(self._speeds))
        self._top_speed = max(self._top_speed, mean_speed)
        self._path += speed / self.fps_
        member = self._label_member
        mass = member @ self.posterior_
        z_k = cond[:, _POS[1]] * self.place_scale_[_POS[1]] + self.place_mean_[_POS[1]]
        z_l = (member @ (self.posterior_ * z_k)) / np.maximum(mass, 1e-12)
        motion = [
            min((self._n_seen - 1) / self.fps_, _T_CAP_S),
            mean_speed,
            self._top_speed,
            min(self._path, _PATH_CAP_M),
        ]
        return np.concatenate([pos, mass, motion, z_l, z_l - pos[1]])

    def _track_position(self, cond: np.ndarray, w: np.ndarray, origin: np.ndarray, theta: float) -> np.ndarray:
        """Kalman filter of the partner's ground position in the world; returns it in the observed
        frame (x, z), metres.

        Predict with the state-weighted conditional partner velocity v (observed frame, m/s) and
        its covariance; correct with the conditional placement m and its covariance C. Moments of
        the state mixture: m = sum_k w_k m_k, C = sum_k w_k (C_k + m_k m_k^T) - m m^T.
        """
        sc, mu = self.place_scale_, self.place_mean_
        m_k = cond[:, _POS] * sc[_POS] + mu[_POS]  # (N, 2) metres, observed frame
        v_k = cond[:, _VEL] * sc[_VEL] + mu[_VEL]  # (N, 2) m/s
        m, v = w @ m_k, w @ v_k
        C = np.einsum("n,nij->ij", w, self._cov_pos) + np.einsum("n,ni,nj->ij", w, m_k - m, m_k - m)
        Cv = np.einsum("n,nij->ij", w, self._cov_vel) + np.einsum("n,ni,nj->ij", w, v_k - v, v_k - v)
        R = _ground_rot(theta)
        g = origin[[0, 2]]
        meas, meas_cov = g + R @ m, R @ C @ R.T
        if self._track is None:
            pos, cov = meas, meas_cov
        else:
            pos, cov = self._track
            pos = pos + R @ v / self.fps_
            cov = cov + R @ Cv @ R.T / self.fps_**2 + self.process_noise * np.eye(2)
            K = cov @ np.linalg.inv(cov + meas_cov)
            pos = pos + K @ (meas - pos)
            cov = (np.eye(2) - K) @ cov
        self._track = (pos, 0.5 * (cov + cov.T))
        return R.T @ (pos - g)

    def _partner_world(self, q: np.ndarray, zp: np.ndarray, origin: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Placement q (x, z, cos, sin; metres) and pose block zp (d_p,) -> partner world joints (14, 3)."""
        own = self.pca_p_.inverse(zp).reshape(14, 3)
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
        arrays = {
            "startprob": self.startprob_,
            "transmat": self.transmat_,
            "means": self.means_,
            "covars": self.covars_,
        }
        for tag, lin in (("pca_o", self.pca_o_), ("pca_p", self.pca_p_)):
            arrays.update({f"{tag}_mean": lin.mean, f"{tag}_components": lin.components, f"{tag}_scale": lin.scale})
        arrays.update(place_mean=self.place_mean_, place_scale=self.place_scale_, block_labels=self.block_labels_)
        if self._forest is not None:
            arrays.update({f"correction_{k}": v for k, v in self._forest.arrays().items()})
        config = {**self._config(), "fps": self.fps_, "d_o": self.d_o_}
        return arrays, config

    @classmethod
    def from_state(cls, arrays: dict[str, np.ndarray], config: dict[str, Any]) -> DualHMM:
        c = dict(config)
        fps, d_o = float(c.pop("fps")), int(c.pop("d_o"))
        m = cls(**c)
        m.fps_, m.d_o_ = fps, d_o
        m.pca_o_ = _Linear(arrays["pca_o_mean"], arrays["pca_o_components"], arrays["pca_o_scale"])
        m.pca_p_ = _Linear(arrays["pca_p_mean"], arrays["pca_p_components"], arrays["pca_p_scale"])
        m.place_mean_, m.place_scale_ = arrays["place_mean"], arrays["place_scale"]
        m.block_labels_ = arrays["block_labels"]
        m._set_params(arrays["startprob"], arrays["transmat"], arrays["means"], arrays["covars"])
        if "correction_value" in arrays:
            parts = ("feature", "threshold", "left", "right", "value")
            m._forest = _Forest(*(arrays[f"correction_{k}"] for k in parts))
        m.reset()
        return m
