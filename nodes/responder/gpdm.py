"""Hierarchical Gaussian-process dynamical model with style and target (Taubert et al. 2013).

Data. Both people of a trial are expressed in the observed person's actor frame
(:mod:`counterpart.nodes.responder.frames`). The human block h_t (8,) is the observed person's right hand
(wrist position, metres, and velocity, m/s, in their own frame) and their ground velocity (x, z,
m/s, own frame). The partner block p_t (47,) is the partner's placement in the observed frame
(ground x, z in metres; cos, sin of the relative heading), the partner's 14 joints in their own
frame (42, metres) and a contact indicator (1 where the two right hands are within
``contact_m``). Each trial carries a style vector s (3,): the amounts of happy, sad and angry
(the trial's emotion strength in its column, 0 elsewhere; neutral is s = 0).

Hierarchy (each layer a back-constrained sparse GP-LVM, :mod:`counterpart.nodes.responder.gp_layers`)::

    h_t = f_h(x_h,t)                        human layer,       x_h (q_h,),  x_h = g_h(h) (back constraint)
    y_t = f_p(x_p,t, s)                     partner layer,     the partner's own pose y (42,), x_p (q_p,),
                                            kernel k_RBF(x) (1 + s^T W s')
    [x_h,t; x_p,t; q_t; c_t] = f_i(z_t)     interaction layer, z (q_z,); q the placement (4,), c contact
    z_t = z_t-1 + f_d(z_t-1, z_t-1 - z_t-2) + e_t     second-order GPDM (Wang, Fleet & Hertzmann 2008)

The interaction layer couples both actors' latents with what belongs to the pair (where the
partner stands, whether the hands touch). The style enters only the partner layer's kernel (the
style factorisation): f_p(x, s) = g_0(x) + sum_e s_e g_e(x), so the emotion and its strength are
continuous inputs set at run time, and the latent trajectory (the interaction's course) is shared
by all styles. The dynamics f_d is a GP regression (scikit-learn, ARD RBF + white noise) on the
interaction latents of the training sequences at the frame rate, which GPy has no model for; its
residual variance on transitions it was not fitted on is the process noise Q.

Online (one frame, no optimisation): the observed hand is back-projected to x_h = g_h(h_t); the
dynamics predict z_t with covariance P + ``process_gain`` Q; the latent point is then
back-projected onto the training frames' interaction latents z_n, each weighted by
N(x_h; x_h,n, R) N(z_n; z_pred, P) (R from ``bandwidth``): z_t is their weighted mean, P their
weighted spread, so z_t stays on the training manifold and the dynamics settle
which of the places that share this hand position (standing before or after) it is. Then
[x_p, q, c] = f_i(z_t) and the pose f_p(x_p, s). The partner's joints are placed in the world from
q and low-passed (``smooth_s``), and the right arm is bent by two-bone inverse kinematics so that the hand meets the observed
hand (plus the mean contact offset of the training trials) in proportion to the predicted contact
c: the target is where the hand is offered, not where the training trials met.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from counterpart.body.skeleton import JOINT_INDEX
from counterpart.body.trajectory import TwoPersonTrajectory
from counterpart.messages import EMOTIONS

from .dual_hmm import DualHMM
from .frames import actor_frame, to_local, to_world
from .gp_layers import GPLayer, fit_layer, rbf
from .pair_features import partner_placement, partner_velocity, partner_world
from .reach import two_bone_ik

_RS, _RE, _RW = JOINT_INDEX["r_shoulder"], JOINT_INDEX["r_elbow"], JOINT_INDEX["r_wrist"]
#: the style columns: amounts of these emotions (neutral is no amount)
STYLES: tuple[str, ...] = EMOTIONS[1:]
_NQ = 4  # placement numbers at the start of the partner block


@dataclass(frozen=True)
class GPDMConfig:
    """Latent sizes and training budget (the paper leaves them open).

    ``bandwidth``, ``process_gain`` and ``smooth_s`` were chosen on simulator seeds 100-102, away from
    the training seeds 0-7 and the bench's held-out 200-203.

    Parameters
    ----------
    q_h, q_p, q_z : int, default=2, 4, 4
        Latent dimensions of the human, partner and interaction layers.
    num_inducing : int, default=50
        Inducing inputs per layer.
    n_centres : int, default=80
        Back-constraint centres.
    points : int, default=1000
        Frames each GP-LVM is fitted on (drawn at random from all training frames).
    dyn_points : int, default=400
        Transitions the dynamics GP is fitted on.
    max_iters : int, default=175
        L-BFGS iterations per layer.
    contact_m : float, default=0.15
        Hand distance that counts as contact, metres.
    support : int, default=3000
        Training frames the online back-projection weighs.
    bandwidth : float, default=0.08
        The back-projection's kernel width on the human latent, in standard deviations of the
        training latents.
    process_gain : float, default=10.0
        Multiplies the dynamics' held-out residual variance in the prediction's covariance, so that
        the hand can move the latent point off the mean flow.
    smooth_s : float, default=1.5
        Time constant of the low-pass of the partner's joints in the world before the hand's reach,
        seconds.
    both_roles : bool, default=True
        Train on A observed / B partner and the reverse.
    seed : int, default=0
        Seed of the draws.
    """

    q_h: int = 2
    q_p: int = 4
    q_z: int = 4
    num_inducing: int = 50
    n_centres: int = 80
    points: int = 1000
    dyn_points: int = 400
    max_iters: int = 175
    contact_m: float = 0.15
    support: int = 3000
    bandwidth: float = 0.08
    process_gain: float = 10.0
    smooth_s: float = 1.5
    both_roles: bool = True
    seed: int = 0


def style_vector(emotion: str, strength: float) -> np.ndarray:
    """The style vector of an emotion.

    Parameters
    ----------
    emotion : str
        One of ``EMOTIONS``.
    strength : float
        Its strength, in [0, 1].

    Returns
    -------
    ndarray of shape (3,)
        Amounts of happy, sad, angry (neutral: zeros).

    Raises
    ------
    ValueError
        For an unknown emotion or a strength outside [0, 1].
    """
    if emotion not in EMOTIONS:
        raise ValueError(f"emotion={emotion!r}; choose one of {', '.join(EMOTIONS)}")
    if not 0.0 <= float(strength) <= 1.0:
        raise ValueError(f"strength={strength!r}: must be in [0, 1]")
    s = np.zeros(len(STYLES))
    if emotion != "neutral":
        s[STYLES.index(emotion)] = float(strength)
    return s


def human_features(observed: np.ndarray, fps: float) -> np.ndarray:
    """The human block (module docstring).

    Parameters
    ----------
    observed : ndarray of shape (T, 14, 3)
        The observed person's joints, metres, world frame.
    fps : float
        Frames per second.

    Returns
    -------
    ndarray of shape (T, 8)
        Right wrist position (metres) and velocity (m/s) in their own frame, ground velocity x, z (m/s).
    """
    o, th = actor_frame(observed)
    w = to_local(observed, o, th)[:, _RW]
    wv = np.diff(w, axis=0, prepend=w[:1]) * fps
    return np.hstack([w, wv, partner_velocity(observed, th, fps)])


def partner_features(observed: np.ndarray, partner: np.ndarray, contact_m: float) -> np.ndarray:
    """The partner block (module docstring).

    Parameters
    ----------
    observed, partner : ndarray of shape (T, 14, 3)
        Joints, metres, world frame.
    contact_m : float
        Right-hand distance that counts as contact, metres.

    Returns
    -------
    ndarray of shape (T, 47)
        Placement (4), the partner's own-frame joints (42, metres) and the contact indicator (1).
    """
    o, th = actor_frame(observed)
    q, own = partner_placement(partner, o, th)
    touch = np.linalg.norm(observed[:, _RW] - partner[:, _RW], axis=-1) < contact_m
    return np.hstack([q, own.reshape(len(own), -1), touch[:, None].astype(float)])


def reach(joints: np.ndarray, target: np.ndarray, weight: float) -> np.ndarray:
    """Two-bone inverse kinematics of the right arm towards a target.

    The bone lengths are kept and the elbow stays in its bending plane; for a target beyond 95% of
    the arm's length the whole body first steps towards it along the floor by the shortfall (times
    ``weight``).

    Parameters
    ----------
    joints : ndarray of shape (14, 3)
        Joints, metres, world frame.
    target : ndarray of shape (3,)
        Where the hand goes, metres, world frame.
    weight : float
        Blend in [0, 1] (0 returns ``joints`` itself).

    Returns
    -------
    ndarray of shape (14, 3)
        New joints, metres.
    """
    if weight <= 0:
        return joints
    J = joints.copy()
    arm = np.linalg.norm(J[_RE] - J[_RS]) + np.linalg.norm(J[_RW] - J[_RE])
    v = (target - J[_RS]) * np.array([1.0, 0.0, 1.0])
    excess = np.linalg.norm(target - J[_RS]) - 0.95 * arm
    if excess > 0 and np.linalg.norm(v) > 1e-6:
        # out of reach: the partner steps towards the offered hand (on the floor) by the shortfall
        J = J + float(min(weight, 1.0)) * excess * v / np.linalg.norm(v)
    S, E, W = J[_RS], J[_RE], J[_RW]
    E2, W2 = two_bone_ik(S, E, W, target)
    w = float(min(weight, 1.0))
    J[_RE], J[_RW] = (1 - w) * E + w * E2, (1 - w) * W + w * W2
    return J


class GPDM:
    """The hierarchical GPDM responder (module docstring); ``step`` one frame at a time.

    Parameters
    ----------
    **params : Any
        Fields of :class:`GPDMConfig`.

    Attributes
    ----------
    style_ : ndarray of shape (3,)
        The style variables (:meth:`set_style`).
    posterior_ : ndarray of shape (1,)
        The largest back-projection weight of the last frame (the node reports it as confidence).
    contact_ : float
        The predicted contact of the last frame, in [0, 1].
    styles_ : list of str
        The emotions seen in training.
    """

    name = "gpdm"

    def __init__(self, **params: Any) -> None:
        self.config = GPDMConfig(**params)
        self.style_ = np.zeros(len(STYLES))
        self.posterior_ = np.ones(1)  # the node reports max(posterior_) as confidence
        self.reset()

    # ------------------------------------------------------------------ fitting
    def fit(self, trajectories: Sequence[TwoPersonTrajectory], progress: Callable[[str], None] | None = None) -> GPDM:
        """Learn the hierarchy from two-person trajectories.

        Parameters
        ----------
        trajectories : sequence of TwoPersonTrajectory
            Training trials; ``meta['emotion']``, ``meta['strength']`` label each trial's style
            (missing: neutral).
        progress : callable or None, default=None
            Receives progress messages.

        Returns
        -------
        GPDM
            self, fitted.

        Raises
        ------
        ValueError
            With no trajectories, or none of at least 3 frames.
        """
        from threadpoolctl import threadpool_limits

        if not trajectories:
            raise ValueError("gpdm: no training trajectories")
        with threadpool_limits(1):  # small matrices: BLAS threads on busy cores only slow GPy down
            return self._fit(trajectories, progress or (lambda s: None))

    def _fit(self, trajectories: Sequence[TwoPersonTrajectory], say: Callable[[str], None]) -> GPDM:
        c = self.config
        fps = float(np.median([t.fps for t in trajectories]))
        H, P, S, offsets, seen = [], [], [], [], set()
        for t in trajectories:
            emo = str(t.meta.get("emotion", "neutral"))
            strength = 0.0 if emo == "neutral" else float(t.meta.get("strength", 1.0))
            s = style_vector(emo, strength)
            seen.add(emo)
            for obs, par in ((t.a, t.b), (t.b, t.a))[: 2 if c.both_roles else 1]:
                if len(obs) < 3:
                    continue
                H.append(human_features(obs, t.fps))
                P.append(partner_features(obs, par, c.contact_m))
                o, th = actor_frame(obs)
                offsets.append(to_local(par[:, None, _RW], o, th)[:, 0] - to_local(obs[:, None, _RW], o, th)[:, 0])
                S.append(np.broadcast_to(s, (len(obs), len(s))))
        if not H:
            raise ValueError("gpdm: every training trajectory is shorter than 3 frames")
        lengths = np.array([len(h) for h in H])
        Ha, Pa, Sa = np.concatenate(H), np.concatenate(P), np.concatenate(S)
        rng = np.random.default_rng(c.seed)
        idx = np.sort(rng.choice(len(Ha), size=min(c.points, len(Ha)), replace=False))
        say(f"gpdm: {len(H)} sequences, {len(Ha)} frames; styles {', '.join(e for e in EMOTIONS if e in seen)}")
        kw = dict(num_inducing=c.num_inducing, n_centres=c.n_centres, max_iters=c.max_iters, seed=c.seed, progress=say)
        self.human_ = fit_layer(Ha[idx], c.q_h, name="human layer", **kw)
        self.partner_ = fit_layer(Pa[idx, _NQ:-1], c.q_p, S=Sa[idx], name="partner layer", **kw)
        Xh = self.human_.project(Ha)
        # the interaction layer couples both actors' latents with what belongs to the pair: where the
        # partner stands relative to the observed person, and whether their hands touch
        U = np.hstack([Xh, self.partner_.project(Pa[:, _NQ:-1]), Pa[:, :_NQ], Pa[:, -1:]])
        self.inter_ = fit_layer(U[idx], c.q_z, name="interaction layer", **kw)
        Z = self.inter_.project(U)
        # second-order dynamics on every sequence's interaction latents, at the frame rate
        seqs = np.split(Z, np.cumsum(lengths)[:-1])
        Xd = np.concatenate([np.hstack([z[1:-1], z[1:-1] - z[:-2]]) for z in seqs])
        Yd = np.concatenate([z[2:] - z[1:-1] for z in seqs])
        say(f"gpdm: second-order dynamics GP on {min(c.dyn_points, len(Xd))} of {len(Xd)} transitions")
        held = self._fit_dynamics(Xd, Yd, rng)
        firsts = np.stack([z[0] for z in seqs])
        self.z0_ = firsts.mean(0)
        self.P0_ = np.cov(firsts.T).reshape(c.q_z, c.q_z) + 1e-4 * np.eye(c.q_z)
        # process noise: the dynamics' residuals on transitions it was not fitted on
        self.Q_ = np.diag(np.maximum((Yd[held] - self._dynamics(Xd[held])).var(0), 1e-6))
        # the back-projection's support: training frames' (x_h, z) pairs
        sup = np.sort(rng.choice(len(Ha), size=min(c.support, len(Ha)), replace=False))
        self.support_h_, self.support_z_ = Xh[sup], Z[sup]
        self.R_ = np.diag((c.bandwidth * Xh.std(0)) ** 2)
        touch = Pa[:, -1] > 0.5
        self.contact_offset_ = np.concatenate(offsets)[touch].mean(0) if touch.any() else np.zeros(3)
        self.fps_ = fps
        self.styles_ = [e for e in EMOTIONS if e in seen]
        self.reset()
        return self

    def _fit_dynamics(self, X: np.ndarray, Y: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Fit the dynamics GP on ``dyn_points`` random transitions; returns (up to 5000 of) the others."""
        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

        c = self.config
        sel = rng.choice(len(X), size=min(c.dyn_points, len(X)), replace=False)
        # inputs in units of their spread: the latent's change per frame is ~100 times smaller than
        # the latent itself, and the lengthscale search starts from and is bounded around 1
        sd = np.maximum(X.std(0), 1e-9)
        kern = ConstantKernel(1.0) * RBF(np.ones(X.shape[1]), (1e-2, 1e3)) + WhiteKernel(1e-3)
        gp = GaussianProcessRegressor(kern, normalize_y=True, random_state=c.seed).fit(X[sel] / sd, Y[sel])
        k = gp.kernel_
        self.dyn_X_, self.dyn_alpha_ = X[sel], gp.alpha_
        self.dyn_ls_ = np.asarray(k.k1.k2.length_scale, float) * sd
        self.dyn_var_ = float(k.k1.k1.constant_value)
        self.dyn_ymean_, self.dyn_ysd_ = np.asarray(gp._y_train_mean, float), np.asarray(gp._y_train_std, float)
        rest = np.setdiff1d(np.arange(len(X)), sel)
        return rest if len(rest) <= 5000 else rng.choice(rest, 5000, replace=False)

    def _dynamics(self, X: np.ndarray) -> np.ndarray:
        """Mean change of the interaction latent (N, q_z) for inputs [z_t-1, z_t-1 - z_t-2] (N, 2 q_z)."""
        return (
            rbf(np.atleast_2d(X), self.dyn_X_, self.dyn_ls_, self.dyn_var_) @ self.dyn_alpha_ * self.dyn_ysd_
            + self.dyn_ymean_
        )

    # ------------------------------------------------------------------ style
    def set_style(self, emotion: str, strength: float) -> None:
        """Set the style variables from an emotion and its strength (continuous).

        Neutral, no style amount, is the content function itself and always available.

        Parameters
        ----------
        emotion : str
            One of ``EMOTIONS``.
        strength : float
            Its strength, in [0, 1].

        Raises
        ------
        ValueError
            For a style the model never saw in training (naming the styles it knows), an unknown
            emotion or a strength outside [0, 1].
        """
        if emotion in EMOTIONS and emotion != "neutral" and emotion not in self.styles_:
            raise ValueError(
                f"gpdm: style {emotion!r} was never seen in training (this model knows "
                f"{', '.join(self.styles_)}); retrain with trials of that emotion, e.g. "
                f"'counterpart learn responder --model gpdm --data sim --out FILE'"
            )
        self.style_ = style_vector(emotion, strength)

    # ------------------------------------------------------------------ online generation
    def reset(self) -> None:
        """Forget the past: the next frame starts a new sequence."""
        self._prev: np.ndarray | None = None  # the observed joints of the previous frame
        self._z: np.ndarray | None = None
        self._z_prev: np.ndarray | None = None
        self._P: np.ndarray | None = None
        self.contact_ = 0.0
        self._out: np.ndarray | None = None  # the last partner joints before the reach
        if hasattr(self, "R_"):
            self._r_sd = np.sqrt(np.diag(self.R_))

    def step(self, observed: np.ndarray) -> np.ndarray:
        """One frame of the partner.

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
            If ``observed`` is not of shape (14, 3).
        """
        X = np.asarray(observed, np.float64)
        if X.shape != (14, 3):
            raise ValueError(f"observed joints must be (14, 3) metres, got shape {X.shape}")
        pair = np.stack([X if self._prev is None else self._prev, X])
        self._prev = X
        h = human_features(pair, self.fps_)[-1]
        xh = self.human_.project(h)[0]
        if self._z is None:
            z, P = self.z0_, self.P0_
        else:
            z = self._z + self._dynamics(np.concatenate([self._z, self._z - self._z_prev]))[0]
            P = self._P + self.config.process_gain * self.Q_
        # back-projection onto the training latents: each support frame n weighs
        # N(x_h; x_h,n, R) N(z_n; z_pred, P); the posterior is their weighted mean and spread
        dh = (xh - self.support_h_) / self._r_sd
        dz = self.support_z_ - z
        e = (dh * dh).sum(1) + ((dz @ np.linalg.inv(P)) * dz).sum(1)
        w = np.exp(-0.5 * (e - e.min()))
        w /= w.sum()
        z_new = w @ self.support_z_
        d = self.support_z_ - z_new
        self._P = (w[:, None] * d).T @ d + self.Q_
        self._z_prev = z_new if self._z is None else self._z
        self._z = z_new
        self.posterior_ = np.array([w.max()])
        u = self.inter_.mean(z_new[None])[0]
        qh, qp = self.config.q_h, self.config.q_p
        pose = self.partner_.mean(u[None, qh : qh + qp], self.style_[None])[0]
        p = np.concatenate([u[qh + qp : qh + qp + _NQ], pose, u[-1:]])
        origin, theta = actor_frame(X)
        joints = partner_world(p[:_NQ], p[_NQ:-1].reshape(14, 3), origin, float(theta))
        if self._out is not None and self.config.smooth_s > 0:
            # one-pole low-pass in the world (time constant smooth_s): where the back-projection
            # jumps between places of the training data the partner glides instead of hopping
            a = 1.0 - np.exp(-1.0 / (self.config.smooth_s * self.fps_))
            joints = self._out + a * (joints - self._out)
        self._out = joints
        self.contact_ = float(np.clip(p[-1], 0.0, 1.0))
        target = X[_RW] + to_world(self.contact_offset_[None, None], np.zeros(3), float(theta))[0, 0]
        # the hand goes to the offered hand as the model expects contact (indicator 0.2 -> 0.7)
        w = float(np.clip((self.contact_ - 0.2) / 0.5, 0.0, 1.0))
        return reach(joints, target, w).astype(np.float32)

    #: a whole sequence, frame by frame as online: (T, 14, 3) -> (T, 14, 3): the dual HMM's loop over step()
    predict = DualHMM.predict

    # ------------------------------------------------------------------ persistence
    def get_state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """The fitted model as arrays and a configuration, for a model file.

        Returns
        -------
        arrays : dict of str to ndarray
            The three layers' arrays, the dynamics GP, the initial state, the noise covariances,
            the back-projection's support and the contact offset.
        config : dict of str to Any
            The :class:`GPDMConfig` fields, ``fps``, ``dyn_var`` and ``styles``.
        """
        arrays = {**self.human_.arrays("human"), **self.partner_.arrays("partner"), **self.inter_.arrays("inter")}
        arrays.update(
            dyn_X=self.dyn_X_,
            dyn_alpha=self.dyn_alpha_,
            dyn_ls=self.dyn_ls_,
            dyn_ymean=self.dyn_ymean_,
            dyn_ysd=self.dyn_ysd_,
            z0=self.z0_,
            P0=self.P0_,
            Q=self.Q_,
            R=self.R_,
            support_h=self.support_h_,
            support_z=self.support_z_,
            contact_offset=self.contact_offset_,
        )
        config = {**asdict(self.config), "fps": self.fps_, "dyn_var": self.dyn_var_, "styles": list(self.styles_)}
        return arrays, config

    @classmethod
    def from_state(cls, arrays: dict[str, np.ndarray], config: dict[str, Any]) -> GPDM:
        """The inverse of :meth:`get_state`.

        Parameters
        ----------
        arrays : dict of str to ndarray
            The arrays of a model file.
        config : dict of str to Any
            Its configuration.

        Returns
        -------
        GPDM
            The fitted model, reset.
        """
        c = dict(config)
        fps, dyn_var, styles = float(c.pop("fps")), float(c.pop("dyn_var")), list(c.pop("styles"))
        m = cls(**c)
        m.fps_, m.dyn_var_, m.styles_ = fps, dyn_var, styles
        m.human_, m.partner_, m.inter_ = (GPLayer.from_arrays(arrays, k) for k in ("human", "partner", "inter"))
        m.dyn_X_, m.dyn_alpha_, m.dyn_ls_ = arrays["dyn_X"], arrays["dyn_alpha"], arrays["dyn_ls"]
        m.dyn_ymean_, m.dyn_ysd_ = arrays["dyn_ymean"], arrays["dyn_ysd"]
        m.z0_, m.P0_, m.Q_, m.R_ = arrays["z0"], arrays["P0"], arrays["Q"], arrays["R"]
        m.support_h_, m.support_z_ = arrays["support_h"], arrays["support_z"]
        m.contact_offset_ = arrays["contact_offset"]
        m.reset()
        return m
