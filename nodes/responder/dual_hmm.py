"""Dual HMM interaction model (Zheng et al. 2006 "Virtual friend"; Cosker et al. 2004).

The model composes parts that each have one job, as hmmlearn splits its base, emissions and
models:

* features (:mod:`.pair_features`): both people in the observed person's actor-centred frame, each
  pose reduced by its own whitened PCA (95% of the energy), the observed block o_t (pose and
  ground velocity) and the partner block p_t (placement, ground velocity and pose);
* fitting (:mod:`.hmm_blocks`): ONE Gaussian HMM (hmmlearn, full covariances) emits
  x_t = [o_t, p_t], so the two people share one hidden state sequence and one transition matrix A
  (N x N)::

      x_t | s_t = k  ~  N(mu_k, Sigma_k),   mu_k = [mu_o,k; mu_p,k],
      Sigma_k = [[S_oo,k, S_op,k], [S_po,k, S_pp,k]],

  its states fitted per interaction label (time-ordered where the label has phases) and joined
  block-diagonally. With ``both_roles`` every training pair is used twice (A observed / B partner
  and the reverse);
* emissions read online (:mod:`.conditioning`): the observed block's marginal likelihoods and the
  state-conditional partner block E[p_t | o_t, s_t = k];
* the state estimate (:mod:`.forward_filter`): the forward algorithm with the evidence tempered by
  w = ``evidence_weight`` (< 1)::

      alpha_t(k) ∝ [sum_j alpha_{t-1}(j) A_jk] N(o_t; mu_o,k, S_oo,k)^w

  successive frames are far from independent given the state and the full-covariance Gaussians
  are sharp, so with w = 1 the posterior snaps onto one interaction from the first few frames of
  standing, which look alike in every interaction; tempering keeps it spread until the interaction
  shows. The partner is p_t = sum_k alpha_t(k) E[p_t | o_t, k] (``decode="filter"``), or the
  conditional of the fixed-lag Viterbi path's state (``decode="viterbi"``);
* placement (:mod:`.placement_kalman`): with ``placement="relative"`` the partner's ground position
  is the conditional mean, frame by frame; with ``"tracked"`` (default) a Kalman filter keeps it in
  the world, predicted with the conditional partner velocity and corrected with the conditional
  position, both with their mixture covariances;
* placement correction (:mod:`.placement_correction`): a cross-fitted regression forest adds the
  expected error of the placement, learnt from causal features of each frame. Validation seeds
  100-103 / 104-107 / 108-111 / 112-115 (trained on the default seeds 0-7): 231.3 / 262.6 / 258.7 /
  282.4 mm -> 223.7 / 248.1 / 229.9 / 255.6 mm; most of the gain in the approach phase (handshake
  approach 205 -> 144 mm).

The partner's own pose is mapped back through its PCA and placed with the placement and relative
heading in the observed person's frame: world joints (14, 3), metres.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from counterpart.body.trajectory import TwoPersonTrajectory

from .conditioning import ConditionalGaussians
from .forward_filter import DECODES, ForwardFilter
from .frames import actor_frame, to_local
from .hmm_blocks import HMMParams, fit_blocks, join_blocks
from .pair_features import NQ, POS, VEL, PairEncoder, partner_placement, role_pairs
from .placement_correction import CorrectionFeatures, ForestArrays, deal_folds, fit_forest
from .placement_kalman import PlacementKalman

PLACEMENTS = ("tracked", "relative")


def _coerce(config: Any) -> None:
    """Cast each field of a frozen config to its default's type (an int ``energy=1`` would make
    scikit-learn's PCA keep one component instead of all the variance).
    """
    for f in fields(config):
        object.__setattr__(config, f.name, type(f.default)(getattr(config, f.name)))


@dataclass(frozen=True)
class FeatureConfig:
    """The features (:mod:`.pair_features`).

    Parameters
    ----------
    energy : float
        Fraction of each person's pose variance their PCA keeps, in (0, 1] (default 0.95).
    velocity_weight : float
        Scale of the observed person's ground velocity (m/s) in the observed block (0 drops it).
    """

    energy: float = 0.95
    velocity_weight: float = 2.0

    def __post_init__(self) -> None:
        _coerce(self)
        if not 0 < self.energy <= 1:
            raise ValueError(f"energy={self.energy!r}: the PCA energy fraction must be in (0, 1]")


@dataclass(frozen=True)
class FitConfig:
    """The states and their fitting (:mod:`.hmm_blocks`).

    Parameters
    ----------
    n_states : int
        N hidden states in all, shared out between the interaction labels in proportion to their
        number of phases (at least 2 each).
    n_iter : int
        Baum-Welch iterations per label.
    both_roles : bool
        Train on A observed / B partner and the reverse.
    order_mix : float
        The uniform share mixed into the time-ordered start of a block's transitions and start
        probabilities, in [0, 1] (1 uses hmmlearn's k-means start for every block).
    min_covar : float
        Ridge added to the state covariances (whitened units).
    leak : float
        Probability per frame of leaving an interaction's block of states, in [0, 1).
    random_state : int
        Seed of Baum-Welch's start and of the correction forest.
    """

    n_states: int = 48
    n_iter: int = 25
    both_roles: bool = True
    order_mix: float = 0.2
    min_covar: float = 1e-2
    leak: float = 1e-5
    random_state: int = 0

    def __post_init__(self) -> None:
        _coerce(self)
        if self.n_states < 1:
            raise ValueError(f"n_states={self.n_states}: must be >= 1")
        if not 0 <= self.order_mix <= 1:
            raise ValueError(f"order_mix={self.order_mix!r} must be in [0, 1]")
        if not 0 <= self.leak < 1:
            raise ValueError(f"leak={self.leak!r} must be in [0, 1)")


@dataclass(frozen=True)
class DecodeConfig:
    """The online state estimate (:mod:`.forward_filter`).

    Parameters
    ----------
    decode : str
        "filter" (the posterior) or "viterbi" (the fixed-lag best path's state).
    lag : int
        Frames of the fixed-lag Viterbi trellis.
    evidence_weight : float
        w in (0, 1], the exponent of the observation likelihood in the state filter.
    """

    decode: str = "filter"
    lag: int = 8
    evidence_weight: float = 0.05

    def __post_init__(self) -> None:
        _coerce(self)
        if self.decode not in DECODES:
            raise ValueError(f"decode={self.decode!r}; choose one of {', '.join(DECODES)}")
        if self.lag < 1:
            raise ValueError(f"lag={self.lag}: must be >= 1")
        if not 0 < self.evidence_weight <= 1:
            raise ValueError(f"evidence_weight={self.evidence_weight!r} must be in (0, 1]")


@dataclass(frozen=True)
class PlacementConfig:
    """Where the partner stands (:mod:`.placement_kalman`).

    Parameters
    ----------
    mode : str
        "tracked" (the partner's ground position kept in the world by a Kalman filter) or
        "relative" (the per-frame conditional alone).
    process_noise : float
        q > 0, m^2 per frame added to the partner's position variance (keeps the Kalman
        covariances invertible where the partner's placement is certain).
    """

    mode: str = "tracked"
    process_noise: float = 1e-4

    def __post_init__(self) -> None:
        _coerce(self)
        if self.mode not in PLACEMENTS:
            raise ValueError(f"placement={self.mode!r}; choose one of {', '.join(PLACEMENTS)}")
        if not self.process_noise > 0:
            raise ValueError(f"process_noise={self.process_noise!r} must be > 0")


@dataclass(frozen=True)
class CorrectionConfig:
    """The cross-fitted placement correction (:mod:`.placement_correction`).

    Parameters
    ----------
    folds : int
        Folds of the cross-fitting (0: no correction, else >= 2).
    trees : int
        Trees of the forest.
    leaf : int
        Fewest training frames in one of their leaves.
    """

    folds: int = 2
    trees: int = 30
    leaf: int = 20

    def __post_init__(self) -> None:
        _coerce(self)
        if self.folds == 1 or self.folds < 0 or self.trees < 1 or self.leaf < 1:
            raise ValueError(
                f"correction_folds={self.folds!r} must be 0 (no correction) or >= 2, "
                f"correction_trees={self.trees!r} and correction_leaf={self.leaf!r} >= 1"
            )


#: the model file's flat "config" names (format version 4) -> (group, field) of DualHMMConfig
_FLAT = {
    "n_states": ("fit", "n_states"),
    "energy": ("features", "energy"),
    "velocity_weight": ("features", "velocity_weight"),
    "n_iter": ("fit", "n_iter"),
    "decode": ("decode", "decode"),
    "lag": ("decode", "lag"),
    "placement": ("placement", "mode"),
    "process_noise": ("placement", "process_noise"),
    "evidence_weight": ("decode", "evidence_weight"),
    "leak": ("fit", "leak"),
    "both_roles": ("fit", "both_roles"),
    "order_mix": ("fit", "order_mix"),
    "min_covar": ("fit", "min_covar"),
    "random_state": ("fit", "random_state"),
    "correction_folds": ("correction", "folds"),
    "correction_trees": ("correction", "trees"),
    "correction_leaf": ("correction", "leaf"),
}


@dataclass(frozen=True)
class DualHMMConfig:
    """Every setting of a :class:`DualHMM`, grouped by job.

    Parameters
    ----------
    features : FeatureConfig
        PCA energy and the weight of the observed velocity.
    fit : FitConfig
        States, Baum-Welch and the joining of the labels' blocks.
    decode : DecodeConfig
        The online state estimate.
    placement : PlacementConfig
        Where the partner stands.
    correction : CorrectionConfig
        The placement correction.
    """

    features: FeatureConfig = FeatureConfig()
    fit: FitConfig = FitConfig()
    decode: DecodeConfig = DecodeConfig()
    placement: PlacementConfig = PlacementConfig()
    correction: CorrectionConfig = CorrectionConfig()

    def flat(self) -> dict[str, Any]:
        """The settings under the model file's flat names (``n_states``, ``correction_folds``, ...).

        Returns
        -------
        dict of str to object
            Flat name -> value, for every setting.
        """
        return {name: getattr(getattr(self, group), key) for name, (group, key) in _FLAT.items()}

    @classmethod
    def from_flat(cls, flat: dict[str, Any]) -> DualHMMConfig:
        """The inverse of :meth:`flat`; missing names keep their defaults, an unknown one is an error.

        Parameters
        ----------
        flat : dict of str to object
            Flat name -> value.

        Returns
        -------
        DualHMMConfig
            The grouped settings.

        Raises
        ------
        ValueError
            An unknown name (the message lists the known ones), or a value a group rejects.
        """
        unknown = sorted(set(flat) - set(_FLAT))
        if unknown:
            raise ValueError(f"unknown dual-hmm setting(s) {unknown}; known: {', '.join(_FLAT)}")
        groups: dict[str, dict[str, Any]] = {}
        for name, value in flat.items():
            group, key = _FLAT[name]
            groups.setdefault(group, {})[key] = value
        default = cls()
        return cls(**{g: replace(getattr(default, g), **kw) for g, kw in groups.items()})


class DualHMM:
    """One Gaussian HMM over [observed, partner] PCA poses; the partner by Gaussian conditioning.

    Parameters
    ----------
    config : DualHMMConfig
        The features, fitting, decoding, placement and correction settings.

    Attributes
    ----------
    fps_ : float
        Frame rate of the training trajectories, frames per second (after :meth:`fit` or
        :meth:`from_state`, as are the following).
    encoder_ : PairEncoder
        The features.
    startprob_ : ndarray of shape (N,)
        Start probabilities of the states.
    transmat_ : ndarray of shape (N, N)
        Transition matrix A.
    means_ : ndarray of shape (N, d)
        State means over [o, p], encoded units.
    covars_ : ndarray of shape (N, d, d)
        State covariances.
    block_labels_ : ndarray of shape (N,)
        Each state's interaction label.
    forest_ : ForestArrays or None
        The placement correction, or None.
    posterior_ : ndarray of shape (N,) or None
        While generating, the state posterior of the last frame.

    Raises
    ------
    TypeError
        ``config`` is not a :class:`DualHMMConfig`.
    """

    name = "dual-hmm"

    def __init__(self, config: DualHMMConfig = DualHMMConfig()) -> None:
        if not isinstance(config, DualHMMConfig):
            raise TypeError(f"config={config!r}: expected a DualHMMConfig (e.g. DualHMMConfig(fit=FitConfig(...)))")
        self.config = config
        self.forest_: ForestArrays | None = None
        #: the labels of the correction's features (a cross-fitting sub-model takes its parent's)
        self._feature_labels: np.ndarray | None = None
        self._recording: list[tuple[np.ndarray, np.ndarray]] | None = None
        self.reset()

    # ------------------------------------------------------------------ fitting
    def fit(self, trajectories: Sequence[TwoPersonTrajectory]) -> DualHMM:
        """Fit PCAs, the joint HMM and the placement correction to two-person trajectories
        (observed = A, and B if ``both_roles``).

        Runs with one BLAS thread: the matrices are small, and threads contending for a few busy
        cores made Baum-Welch several times slower.

        Parameters
        ----------
        trajectories : sequence of TwoPersonTrajectory
            The training pairs, joints in metres, all at one frame rate.

        Returns
        -------
        DualHMM
            This model, fitted.

        Raises
        ------
        ValueError
            No trajectories, or trajectories at different frame rates.
        """
        from threadpoolctl import threadpool_limits

        with threadpool_limits(1):
            self._fit(trajectories)
            self.forest_ = None
            if self.config.correction.folds >= 2:
                self._fit_correction(trajectories)
        return self

    def _fit(self, trajectories: Sequence[TwoPersonTrajectory]) -> DualHMM:
        """The features and the HMM, without the correction."""
        self.fps_ = _frame_rate(trajectories)
        fc = self.config.fit
        pairs = role_pairs(trajectories, fc.both_roles)
        self.encoder_ = PairEncoder.fit(pairs, self.config.features.energy, self.config.features.velocity_weight)
        X = self.encoder_.encode(pairs)
        blocks = fit_blocks(
            X,
            np.array([len(p.local) for p in pairs]),
            [p.label for p in pairs],
            [p.phase for p in pairs],
            fc.n_states,
            fc.n_iter,
            fc.order_mix,
            fc.min_covar,
            fc.random_state,
        )
        self._set_params(join_blocks(blocks, fc.min_covar, fc.leak))
        self.reset()
        return self

    def _fit_correction(self, trajectories: Sequence[TwoPersonTrajectory]) -> None:
        """The placement correction, by cross-fitting: the trajectories of each label are dealt to
        the folds; a model fitted without a fold (no correction) is run online on it, recording each
        frame's features and the error of its placement (true minus generated ground position,
        observed frame, metres); a forest learns the error from the features.
        """
        cc = self.config.correction
        trajs = list(trajectories)
        fold = deal_folds([t.label for t in trajs], cc.folds)
        X, Y = [], []
        for k in range(cc.folds):
            held, rest = [trajs[i] for i in np.flatnonzero(fold == k)], [trajs[i] for i in np.flatnonzero(fold != k)]
            if not held or not rest:
                continue
            sub = DualHMM(replace(self.config, correction=replace(cc, folds=0)))
            sub._feature_labels = np.unique(self.block_labels_)
            sub._fit(rest)
            for pair in _roles(held, self.config.fit.both_roles):
                f, q, err = sub._placement_errors(*pair)
                X.append(f)
                Y.append(err)
        if X:
            self.forest_ = fit_forest(
                np.concatenate(X), np.concatenate(Y), cc.trees, cc.leaf, self.config.fit.random_state
            )

    def _placement_errors(self, observed: np.ndarray, partner: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Run a sequence (T, 14, 3) online; returns each frame's correction features (T, d_f), its
        uncorrected placement (T, 2) and that placement's error against the partner's (T, 2)
        (x, z, observed frame, metres).
        """
        self.reset()
        self._recording = []
        for x in np.asarray(observed, np.float64):
            self.step(x)
        f, q = (np.array(v) for v in zip(*self._recording))
        self.reset()
        o, th = actor_frame(observed)
        return f, q, partner_placement(partner, o, th)[0][:, :2] - q

    def _set_params(self, params: HMMParams) -> None:
        """Take the joined HMM's parameters and build the online parts from them."""
        self.startprob_, self.transmat_ = np.asarray(params.startprob, float), np.asarray(params.transmat, float)
        self.means_, self.covars_ = np.asarray(params.means, float), np.asarray(params.covars, float)
        self.block_labels_ = params.block_labels
        self.emissions_ = ConditionalGaussians(self.means_, self.covars_, self.encoder_.d_o, self.encoder_.place_scale)
        dc = self.config.decode
        self.filter_ = ForwardFilter(self.startprob_, self.transmat_, dc.decode, dc.lag)

    # ------------------------------------------------------------------ online generation
    def reset(self) -> None:
        """Forget the past: the next frame starts a new sequence."""
        self._prev_origin: np.ndarray | None = None
        self.posterior_: np.ndarray | None = None
        self._recording = None
        if not hasattr(self, "filter_"):
            return
        self.filter_.reset()
        self.kalman_ = PlacementKalman(self.config.placement.process_noise, self.fps_)
        labels = self._feature_labels if self._feature_labels is not None else np.unique(self.block_labels_)
        # (L, N) which states belong to each label: fixed per model, built once per sequence
        member = (np.asarray(labels)[:, None] == self.block_labels_[None, :]).astype(float)
        self.features_ = CorrectionFeatures(member, self.fps_)

    def step(self, observed: np.ndarray) -> np.ndarray:
        """One frame: the partner of the observed person.

        Parameters
        ----------
        observed : ndarray of shape (14, 3)
            The observed person's joints, metres, world frame.

        Returns
        -------
        ndarray of shape (14, 3), dtype float32
            The partner's joints, metres, world frame.

        Raises
        ------
        ValueError
            ``observed`` is not of shape (14, 3).
        """
        X = np.asarray(observed, np.float64)
        if X.shape != (14, 3):
            raise ValueError(f"observed joints must be (14, 3) metres, got shape {X.shape}")
        origin, theta = actor_frame(X)
        vel = self._observed_velocity(origin, theta)
        o = self.encoder_.observed(to_local(X, origin, theta)[None], vel[None])[0]
        w = self.filter_.update(self.config.decode.evidence_weight * self.emissions_.obs_loglik(o))
        self.posterior_ = self.filter_.posterior
        cond = self.emissions_.conditional(o)
        z = w @ cond
        q = self.encoder_.placement(z[:NQ])  # the mixture's placement: metres, cos/sin, m/s
        q_k = self.encoder_.placement(cond[:, :NQ])  # (N, NQ) each state's
        if self.config.placement.mode == "tracked":
            em = self.emissions_
            q[POS] = self.kalman_.update(w, q_k[:, POS], em.cov_pos, q_k[:, VEL], em.cov_vel, origin, theta)
        if self.forest_ is not None or self._recording is not None:
            f = self.features_(q[POS], q_k[:, POS[1]], self.posterior_, float(np.hypot(vel[0], vel[2])))
            if self._recording is not None:
                self._recording.append((f, q[POS].copy()))
            if self.forest_ is not None:
                q[POS] = q[POS] + self.forest_.predict(f)
        return self.encoder_.partner(q, z[NQ:], origin, theta).astype(np.float32)

    def _observed_velocity(self, origin: np.ndarray, theta: float) -> np.ndarray:
        """(3,) the observed person's ground velocity in their own frame, m/s (0 on a first frame)."""
        if self._prev_origin is None:
            vel = np.zeros(3)
        else:
            vel = to_local(((origin - self._prev_origin) * self.fps_)[None], np.zeros(3), theta)[0]
        self._prev_origin = origin
        return vel

    def predict(self, observed: np.ndarray) -> np.ndarray:
        """A whole sequence, frame by frame as online (the model is reset before and after).

        Parameters
        ----------
        observed : ndarray of shape (T, 14, 3)
            The observed person's joints, metres, world frame.

        Returns
        -------
        ndarray of shape (T, 14, 3), dtype float32
            The partner's joints, metres, world frame.

        Raises
        ------
        ValueError
            ``observed`` is not of shape (T, 14, 3).
        """
        X = np.asarray(observed, np.float64)
        if X.ndim != 3 or X.shape[1:] != (14, 3):
            raise ValueError(f"observed must be (T, 14, 3) metres, got shape {X.shape}")
        self.reset()
        out = np.stack([self.step(x) for x in X])
        self.reset()
        return out

    # ------------------------------------------------------------------ persistence
    def get_state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """The model file's arrays and its flat config (format version 4).

        Returns
        -------
        arrays : dict of str to ndarray
            HMM parameters, the encoder's arrays, ``block_labels`` and the correction's
            ``correction_*`` arrays when there is one.
        config : dict of str to object
            :meth:`DualHMMConfig.flat` with ``fps`` and ``d_o``.
        """
        arrays = {
            "startprob": self.startprob_,
            "transmat": self.transmat_,
            "means": self.means_,
            "covars": self.covars_,
            **self.encoder_.arrays(),
            "block_labels": self.block_labels_,
        }
        if self.forest_ is not None:
            arrays.update({f"correction_{k}": v for k, v in self.forest_.arrays().items()})
        config = {**self.config.flat(), "fps": self.fps_, "d_o": self.encoder_.d_o}
        return arrays, config

    @classmethod
    def from_state(cls, arrays: dict[str, np.ndarray], config: dict[str, Any]) -> DualHMM:
        """A model from :meth:`get_state`'s arrays and flat config.

        Parameters
        ----------
        arrays : dict of str to ndarray
            The arrays of :meth:`get_state`.
        config : dict of str to object
            The flat config of :meth:`get_state` (``d_o`` is ignored: derived again).

        Returns
        -------
        DualHMM
            The fitted model, reset.
        """
        c = dict(config)
        fps = float(c.pop("fps"))
        c.pop("d_o")  # derived from the PCA and the velocity weight
        m = cls(DualHMMConfig.from_flat(c))
        m.fps_ = fps
        m.encoder_ = PairEncoder.from_arrays(arrays, m.config.features.velocity_weight)
        params = HMMParams(
            arrays["startprob"], arrays["transmat"], arrays["means"], arrays["covars"], arrays["block_labels"]
        )
        m._set_params(params)
        if "correction_value" in arrays:
            parts = ("feature", "threshold", "left", "right", "value")
            m.forest_ = ForestArrays(*(arrays[f"correction_{k}"] for k in parts))
        m.reset()
        return m


def _frame_rate(trajectories: Sequence[TwoPersonTrajectory]) -> float:
    """The trajectories' common frame rate; a clear error when there are none or they differ."""
    if not trajectories:
        raise ValueError("DualHMM.fit: no trajectories")
    fps = {round(t.fps, 3) for t in trajectories}
    if len(fps) > 1:
        raise ValueError(f"DualHMM.fit: trajectories have different frame rates {sorted(fps)}; resample them")
    return float(trajectories[0].fps)


def _roles(trajectories: Sequence[TwoPersonTrajectory], both_roles: bool) -> list[tuple[np.ndarray, np.ndarray]]:
    """(observed, partner) joints of each trajectory: A / B, and (``both_roles``) B / A."""
    return [p for t in trajectories for p in ([(t.a, t.b), (t.b, t.a)] if both_roles else [(t.a, t.b)])]


__all__ = [
    "DualHMM",
    "DualHMMConfig",
    "FeatureConfig",
    "FitConfig",
    "DecodeConfig",
    "PlacementConfig",
    "CorrectionConfig",
    "PLACEMENTS",
    "DECODES",
]
