"""Emotion strength as a relative attribute (Chan et al.; Parikh & Grauman 2011), and the
continuous style variable that modulates generated motion (Taubert et al.).

Features (:func:`motion_features`, per motion (T, 14, 3) metres, in the person's own frame):
log mean speed of head and wrists (m/s), log movement amplitude (mean std of joints about the
mean pose, m), log mean jerk of the wrists (m/s^3), head drop (neck-to-head height, m), head
forward offset (m), trunk lean (neck ahead of the pelvis, m), vertical bounce of the pelvis (m).

Ranking. For each emotion e a linear ranking function r_e(x) = w_e . z(x) (z: standardised
features) is learnt from motions of emotion e at strengths s in [0, 1] and neutral motions
(s = 0), compared only within the same interaction (label). Ordered pairs O = {(i, j): s_i > s_j +
margin} and similar pairs S = {(i, j): |s_i - s_j| < similar} give the primal RankSVM with
similarity constraints (Parikh & Grauman, eq. 3, squared-hinge form, Chapelle 2007)::

    min_w  1/2 |w|^2 + C sum_O max(0, 1 - w.(z_i - z_j))^2 + C_s sum_S (w.(z_i - z_j))^2

solved with L-BFGS (smooth, convex).

Style. The strength s modulates a generated motion: with slopes learnt by least squares of the
log speed and log amplitude features against s (relative to neutral motions of the same
interaction), amplitude gain a(s) = exp(k_amp s) about the mean pose and time warp (playback rate)
v(s) = exp((k_speed - k_amp) s), so that speed = amplitude x rate follows exp(k_speed s)
(:meth:`EmotionModel.modulate`). Online, :class:`StyleFilter` applies the amplitude gain about a
running mean pose (a time warp needs the future).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from counterpart.body.skeleton import JOINT_INDEX
from counterpart.body.trajectory import TwoPersonTrajectory
from counterpart.messages import EMOTIONS

from .frames import actor_frame, to_local, to_world

FEATURES: tuple[str, ...] = (
    "log_speed",
    "log_amplitude",
    "log_jerk",
    "head_drop",
    "head_forward",
    "trunk_lean",
    "bounce",
)
_H, _N = JOINT_INDEX["head"], JOINT_INDEX["neck"]
_W = [JOINT_INDEX["l_wrist"], JOINT_INDEX["r_wrist"]]


def motion_features(X: np.ndarray, fps: float) -> np.ndarray:
    """The motion features of the module docstring, in the order of ``FEATURES``.

    Parameters
    ----------
    X : ndarray of shape (T, 14, 3)
        One person's motion, metres, world frame; T >= 4.
    fps : float
        Frames per second.

    Returns
    -------
    ndarray of shape (len(FEATURES),)
        The features.

    Raises
    ------
    ValueError
        ``X`` is not of shape (T >= 4, 14, 3).
    """
    X = np.asarray(X, np.float64)
    if X.ndim != 3 or X.shape[1:] != (14, 3) or len(X) < 4:
        raise ValueError(f"motion must be (T >= 4, 14, 3) metres, got shape {X.shape}")
    o, th = actor_frame(X)
    th = np.full_like(th, np.median(th))  # one frame for the motion: keep turning as motion
    L = to_local(X, o[:1].repeat(len(X), 0), th)
    v = np.diff(L, axis=0) * fps
    speed = np.linalg.norm(v[:, [_H] + _W], axis=-1).mean()
    amp = L.std(axis=0).mean()
    jerk = np.linalg.norm(np.diff(L[:, _W], 3, axis=0) * fps**3, axis=-1).mean()
    pelvis = 0.5 * (L[:, 8] + L[:, 11])
    head_drop = (L[:, _H, 1] - L[:, _N, 1]).mean()
    head_fwd = (L[:, _H, 2] - L[:, _N, 2]).mean()
    lean = (L[:, _N, 2] - pelvis[:, 2]).mean()
    bounce = pelvis[:, 1].std()
    return np.array([np.log(speed + 1e-3), np.log(amp + 1e-3), np.log(jerk + 1e-2), head_drop, head_fwd, lean, bounce])


def rank_svm(D: np.ndarray, S: np.ndarray, C: float = 1.0, C_sim: float = 1.0) -> np.ndarray:
    """Solve the ranking problem of the module docstring.

    Parameters
    ----------
    D : ndarray of shape (n_o, F)
        Ordered differences z_i - z_j, i ranked higher.
    S : ndarray of shape (n_s, F)
        Similar differences.
    C : float, default=1.0
        Weight of the ordered pairs' squared hinge.
    C_sim : float, default=1.0
        Weight of the similar pairs' squared score differences.

    Returns
    -------
    ndarray of shape (F,)
        The ranking weights w.
    """
    # here, not at the top: a responder that loads its model never fits one, and scipy.optimize
    # is a good share of a node's start
    from scipy.optimize import minimize

    F = D.shape[1] if len(D) else S.shape[1]

    def f(w: np.ndarray) -> tuple[float, np.ndarray]:
        m = np.maximum(0.0, 1.0 - D @ w)
        q = S @ w
        val = 0.5 * w @ w + C * (m @ m) + C_sim * (q @ q)
        grad = w - 2 * C * (D.T @ m) + 2 * C_sim * (S.T @ q)
        return float(val), grad

    return minimize(f, np.zeros(F), jac=True, method="L-BFGS-B").x


class EmotionModel:
    """Relative-attribute strength of each emotion and the style modulation (module docstring).

    Parameters
    ----------
    C : float, default=1.0
        RankSVM weight of the ordered pairs.
    C_sim : float, default=1.0
        RankSVM weight of the similar pairs.
    margin : float, default=0.1
        Strength difference above which two motions form an ordered pair.
    similar : float, default=0.03
        Strength difference below which two motions form a similar pair.

    Attributes
    ----------
    mu_, sd_ : ndarray of shape (F,)
        Mean and standard deviation of the training features (the standardisation z).
    w_ : ndarray of shape (len(EMOTIONS), F)
        Ranking weights per emotion (zero for neutral and for emotions without ordered pairs).
    k_speed_, k_amp_ : ndarray of shape (len(EMOTIONS),)
        Style slopes of the log speed and log amplitude against strength.
    """

    name = "emotion"

    def __init__(self, C: float = 1.0, C_sim: float = 1.0, margin: float = 0.1, similar: float = 0.03) -> None:
        self.C, self.C_sim, self.margin, self.similar = float(C), float(C_sim), float(margin), float(similar)

    def fit(
        self, X: np.ndarray, emotions: Sequence[str], strengths: Sequence[float], groups: Sequence[str]
    ) -> EmotionModel:
        """Learn the ranking functions and style slopes.

        Parameters
        ----------
        X : ndarray of shape (M, F)
            Features of M motions (:func:`motion_features`).
        emotions : sequence of str, length M
            Each motion's emotion, one of ``EMOTIONS``.
        strengths : sequence of float, length M
            Each motion's strength in [0, 1] (neutral: any, taken as 0).
        groups : sequence of str, length M
            Each motion's group (interaction label: pairs are only formed within a group).

        Returns
        -------
        EmotionModel
            This model, fitted.
        """
        X = np.asarray(X, float)
        emo = np.asarray(emotions)
        s = np.where(emo == "neutral", 0.0, np.asarray(strengths, float))
        g = np.asarray(groups)
        self.mu_, self.sd_ = X.mean(0), np.maximum(X.std(0), 1e-6)
        Z = (X - self.mu_) / self.sd_
        self.w_ = np.zeros((len(EMOTIONS), X.shape[1]))
        self.k_speed_, self.k_amp_ = np.zeros(len(EMOTIONS)), np.zeros(len(EMOTIONS))
        for e_i, e in enumerate(EMOTIONS[1:], start=1):
            idx = np.flatnonzero((emo == e) | (emo == "neutral"))
            i, j = np.meshgrid(idx, idx, indexing="ij")
            i, j = i.ravel(), j.ravel()
            same = g[i] == g[j]
            ordered = same & (s[i] > s[j] + self.margin)
            sim = same & (i < j) & (np.abs(s[i] - s[j]) < self.similar)
            if not ordered.any():
                continue
            self.w_[e_i] = rank_svm(Z[i[ordered]] - Z[j[ordered]], Z[i[sim]] - Z[j[sim]], self.C, self.C_sim)
            # style slopes: log speed / log amplitude against s, relative to each group's neutral mean
            rel_speed, rel_amp, ss = [], [], []
            for grp in np.unique(g[idx]):
                neu = (g == grp) & (emo == "neutral")
                mine = (g == grp) & (emo == e)
                if neu.any() and mine.any():
                    rel_speed += list(X[mine, 0] - X[neu, 0].mean())
                    rel_amp += list(X[mine, 1] - X[neu, 1].mean())
                    ss += list(s[mine])
            if ss:
                ss_ = np.asarray(ss)
                self.k_speed_[e_i] = float(ss_ @ np.asarray(rel_speed) / (ss_ @ ss_))
                self.k_amp_[e_i] = float(ss_ @ np.asarray(rel_amp) / (ss_ @ ss_))
        return self

    def fit_trajectories(self, trajs: Sequence[TwoPersonTrajectory]) -> EmotionModel:
        """Learn from simulator-style trajectories whose ``meta`` has ``emotion`` and ``strength``
        (both people move in that style, so both are samples).

        Parameters
        ----------
        trajs : sequence of TwoPersonTrajectory
            The trajectories; the group of each is its ``label``, a missing strength is 0.

        Returns
        -------
        EmotionModel
            This model, fitted.

        Raises
        ------
        ValueError
            A trajectory has no ``meta["emotion"]``.
        """
        X, e, s, g = [], [], [], []
        for t in trajs:
            if "emotion" not in t.meta:
                raise ValueError(
                    f"trajectory {t.label!r} has no meta['emotion']: emotion training needs labelled motions"
                )
            for person in (t.a, t.b):
                X.append(motion_features(person, t.fps))
                e.append(t.meta["emotion"])
                s.append(float(t.meta.get("strength", 0.0)))
                g.append(t.label)
        return self.fit(np.array(X), e, s, g)

    def _index(self, emotion: str) -> int:
        if emotion not in EMOTIONS:
            raise ValueError(f"emotion={emotion!r}; choose one of {', '.join(EMOTIONS)}")
        return EMOTIONS.index(emotion)

    def rank(self, X: np.ndarray, emotion: str) -> np.ndarray:
        """Ranking scores r_e for ``emotion``.

        Parameters
        ----------
        X : ndarray of shape (M, F) or (F,)
            Features (:func:`motion_features`).
        emotion : str
            One of ``EMOTIONS``.

        Returns
        -------
        ndarray of shape (M,) or ()
            The scores (a scalar array for a single motion).

        Raises
        ------
        ValueError
            An unknown emotion.
        """
        return ((np.asarray(X, float) - self.mu_) / self.sd_) @ self.w_[self._index(emotion)]

    def style_gains(self, emotion: str, strength: float) -> tuple[float, float]:
        """The style gains of an emotion at a strength.

        Parameters
        ----------
        emotion : str
            One of ``EMOTIONS``.
        strength : float
            Strength in [0, 1].

        Returns
        -------
        amp : float
            Amplitude gain a(s) = exp(k_amp s).
        rate : float
            Playback rate v(s) = exp((k_speed - k_amp) s).

        Raises
        ------
        ValueError
            An unknown emotion or a strength outside [0, 1].
        """
        if not 0.0 <= strength <= 1.0:
            raise ValueError(f"strength={strength!r}: must be in [0, 1]")
        e = self._index(emotion)
        amp = float(np.exp(self.k_amp_[e] * strength))
        return amp, float(np.exp((self.k_speed_[e] - self.k_amp_[e]) * strength))

    def modulate(self, X: np.ndarray, emotion: str, strength: float) -> np.ndarray:
        """A motion restyled: time-warped by the playback rate (the motion runs faster or slower,
        holding its last pose) and scaled about its mean pose.

        Parameters
        ----------
        X : ndarray of shape (T, 14, 3)
            The motion, metres, world frame.
        emotion : str
            One of ``EMOTIONS``.
        strength : float
            Strength in [0, 1].

        Returns
        -------
        ndarray of shape (T, 14, 3), dtype float32
            The restyled motion, metres, world frame.

        Raises
        ------
        ValueError
            An unknown emotion or a strength outside [0, 1].
        """
        X = np.asarray(X, np.float64)
        amp, rate = self.style_gains(emotion, strength)
        T = len(X)
        src = np.minimum(np.arange(T) * rate, T - 1)
        lo = np.floor(src).astype(int)
        hi = np.minimum(lo + 1, T - 1)
        w = (src - lo)[:, None, None]
        Y = (1 - w) * X[lo] + w * X[hi]
        o, th = actor_frame(Y)
        L = to_local(Y, o, th)
        # scale the body's motion about its mean shape, keep where it stands and faces
        M = L.mean(0, keepdims=True)
        return to_world(M + amp * (L - M), o, th).astype(np.float32)

    def get_state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """The fitted model as arrays and configuration, for saving.

        Returns
        -------
        arrays : dict of str to ndarray
            ``w``, ``mu``, ``sd``, ``k_speed`` and ``k_amp``.
        config : dict of str to object
            The constructor's parameters.
        """
        return (
            {"w": self.w_, "mu": self.mu_, "sd": self.sd_, "k_speed": self.k_speed_, "k_amp": self.k_amp_},
            {"C": self.C, "C_sim": self.C_sim, "margin": self.margin, "similar": self.similar},
        )

    @classmethod
    def from_state(cls, arrays: dict[str, np.ndarray], config: dict[str, Any]) -> EmotionModel:
        """A fitted model from what :meth:`get_state` gave.

        Parameters
        ----------
        arrays : dict of str to ndarray
            ``w``, ``mu``, ``sd``, ``k_speed`` and ``k_amp``.
        config : dict of str to object
            The constructor's parameters.

        Returns
        -------
        EmotionModel
            The model.
        """
        m = cls(**config)
        m.w_, m.mu_, m.sd_ = arrays["w"], arrays["mu"], arrays["sd"]
        m.k_speed_, m.k_amp_ = arrays["k_speed"], arrays["k_amp"]
        return m


class StyleFilter:
    """Online amplitude gain about a running mean pose in the person's own frame:
    L' = M + a (L - M), M <- M + (L - M) / (tau fps).

    Parameters
    ----------
    model : EmotionModel or None
        The fitted model giving the amplitude gain; None passes poses through.
    fps : float, default=25.0
        Frames per second of the poses.
    tau_s : float, default=2.0
        Time constant of the running mean pose, seconds.
    """

    def __init__(self, model: EmotionModel | None, fps: float = 25.0, tau_s: float = 2.0) -> None:
        self.model, self.alpha = model, 1.0 / max(1.0, tau_s * fps)
        self.mean: np.ndarray | None = None

    def __call__(self, joints: np.ndarray, emotion: str, strength: float) -> np.ndarray:
        """One frame restyled; every frame updates the running mean pose.

        Parameters
        ----------
        joints : ndarray of shape (14, 3)
            The pose, metres, world frame.
        emotion : str
            One of ``EMOTIONS``; ``"neutral"`` passes the pose through.
        strength : float
            Strength, clipped to [0, 1]; 0 or less passes the pose through.

        Returns
        -------
        ndarray of shape (14, 3), dtype float32
            The restyled pose, metres, world frame.
        """
        X = np.asarray(joints, np.float64)
        o, th = actor_frame(X)
        L = to_local(X, o, th)
        self.mean = L.copy() if self.mean is None else self.mean + self.alpha * (L - self.mean)
        if self.model is None or emotion == "neutral" or strength <= 0:
            return np.asarray(joints, np.float32)
        amp, _ = self.model.style_gains(emotion, min(max(strength, 0.0), 1.0))
        return to_world(self.mean + amp * (L - self.mean), o, th).astype(np.float32)
