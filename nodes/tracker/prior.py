"""The learned motion prior of the tracker (Zheng et al. 2006, "Virtual friend", sect. 3).

Training: pose vectors (``counterpart.body.pose``, T x 28) of motion capture are reduced to their joint angles
(``ANGLE_DOFS``: everything but the root position and heading), projected by PCA onto the
components that keep ``energy`` (95%) of the variance, and a Gaussian HMM with ``n_states``
states (hmmlearn ``GaussianHMM``, full covariances) is fitted to the PCA coefficient sequences.
The per-DOF standard deviation of frame-to-frame changes gives the random walk.

Prediction (``PriorPredictor``): the tracker feeds each frame's estimate back, keeping the filtered
state posterior ``a_t(k) ~ N(y_t | mu_k, S_k) * sum_j a_{t-1}(j) A_jk`` (forward algorithm). For
the next frame the predicted state mixture is ``a_t A``; a fraction ``hmm_weight`` of the particles
get their joint angles drawn from that mixture (state k, then y ~ N(mu_k, S_k), back-projected),
the rest diffuse by the random walk ``x + N(0, diag(rw_std^2))``. Root position and heading always
follow the random walk.

Files: ``.npz`` with the arrays and a ``meta`` JSON string (``version``, ``n_states``, ``energy``,
``n_components``, ``dofs``, ``sources``, ``n_frames``). ``load`` refuses other versions.
"""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from counterpart.body.pose import DOF, YAW, clip_to_limits, wrap_angle

VERSION = 1
#: joint angles modelled by PCA + HMM: root pitch and roll, torso, head, arms, legs
ANGLE_DOFS: np.ndarray = np.arange(4, DOF)
#: floor of the random walk per frame: 5 mm for positions, 0.01 rad for angles, 0.02 rad (about
#: 30 degrees per second at 25 fps) for the heading: training scenes where nobody turns must not
#: stop the tracker from following a person who does
RW_FLOOR = np.where(np.arange(DOF) < 3, 0.005, 0.01)
RW_FLOOR[YAW] = 0.02
#: frame rate (Hz) of a prior file that does not say its own (the training default)
PRIOR_FPS = 25.0
#: the most prior frames one frame of a video is taken to span: a slower video (under 5 fps at
#: 25), or a file whose header gives a wrong rate, is searched as at this many (the walk's
#: spread grows with the steps, and over a fifth of a second people no longer move smoothly)
MAX_FRAME_STEPS = 5.0
#: simulator scenarios and seeds of the default prior (the benches use seeds 0-9: kept apart)
DEFAULT_TRAINING = tuple(
    f"sim:{n}?seed={s}"
    for n in ("handshake", "high_five", "push", "pull", "wave", "conversation")
    for s in (100, 101, 102)
)


@dataclass
class MotionPrior:
    """PCA + Gaussian HMM of joint angles, with a random walk for the rest.

    Parameters
    ----------
    n_states : int, default=30
        HMM states (Zheng: 20-40), 1..500.
    energy : float, default=0.95
        Fraction of variance the PCA keeps, in (0, 1].
    hmm_weight : float, default=0.2
        Share of particles predicted from the HMM (the rest: random walk), in [0, 1].
    rw_scale : float, default=1.5
        Multiplier of the learned per-frame std of the random walk.
    seed : int, default=0
        Seed of the HMM fit.
    fps : float, default=PRIOR_FPS
        Frame rate of the training sequences, Hz: the random walk's per-frame std and the HMM's
        transitions are per frame at this rate (``predictor`` carries them to another).

    Attributes
    ----------
    pca_mean : ndarray of shape (len(ANGLE_DOFS),)
        Mean joint angles (radians).
    components : ndarray of shape (d, len(ANGLE_DOFS))
        PCA components.
    startprob : ndarray of shape (K,)
        HMM start probabilities.
    transmat : ndarray of shape (K, K)
        HMM transition matrix A.
    means : ndarray of shape (K, d)
        HMM state means in PCA coefficients.
    covars : ndarray of shape (K, d, d)
        HMM state covariances (floored to stay positive definite).
    rw_std : ndarray of shape (28,)
        Per-frame std of the random walk per DOF (metres, radians).
    sources : list of str
        Names of the training sequences.
    n_frames : int
        Training frames.

    Raises
    ------
    ValueError
        For ``n_states``, ``energy`` or ``hmm_weight`` out of range.
    """

    n_states: int = 30
    energy: float = 0.95
    hmm_weight: float = 0.2
    rw_scale: float = 1.5
    seed: int = 0
    fps: float = PRIOR_FPS
    # learned
    pca_mean: np.ndarray = field(default_factory=lambda: np.zeros(0))
    components: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    startprob: np.ndarray = field(default_factory=lambda: np.zeros(0))
    transmat: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    means: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    covars: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 0)))
    rw_std: np.ndarray = field(default_factory=lambda: RW_FLOOR.copy())
    sources: list[str] = field(default_factory=list)
    n_frames: int = 0

    def __post_init__(self) -> None:
        if not 1 <= int(self.n_states) <= 500:
            raise ValueError(f"n_states={self.n_states!r}: expected 1..500 HMM states (Zheng: 20-40)")
        if not 0 < self.energy <= 1:
            raise ValueError(f"energy={self.energy!r}: the PCA variance fraction must lie in (0, 1]")
        if not 0 <= self.hmm_weight <= 1:
            raise ValueError(f"hmm_weight={self.hmm_weight!r}: must lie in [0, 1]")
        if not self.fps > 0:
            raise ValueError(f"fps={self.fps!r}: the training sequences' frame rate must be > 0 Hz")

    @property
    def fitted(self) -> bool:
        return self.means.size > 0

    @property
    def n_components(self) -> int:
        return int(self.components.shape[0])

    # -------------------------------------------------------------------------------- learning
    def fit(self, sequences: list[np.ndarray], sources: Iterable[str] = (), progress: bool = False) -> MotionPrior:
        """Fit PCA, HMM and random walk to pose sequences.

        Parameters
        ----------
        sequences : list of ndarray of shape (T_i, 28)
            Pose sequences at the tracker's frame rate, T_i >= 2.
        sources : iterable of str, default=()
            One name per sequence, kept in ``sources``.
        progress : bool, default=False
            Print progress to stderr.

        Returns
        -------
        MotionPrior
            self, fitted.

        Raises
        ------
        ValueError
            When no sequences are given, one has the wrong shape, or there are fewer than
            ``2 * n_states`` frames.
        """
        from sklearn.decomposition import PCA

        seqs = [np.asarray(s, dtype=np.float64) for s in sequences]
        bad = [i for i, s in enumerate(seqs) if s.ndim != 2 or s.shape[1] != DOF or len(s) < 2]
        if not seqs or bad:
            raise ValueError(
                f"MotionPrior.fit: need pose sequences of shape (T >= 2, {DOF}); bad ones at positions {bad}"
                if seqs
                else "MotionPrior.fit: no sequences given"
            )
        X = np.concatenate([s[:, ANGLE_DOFS] for s in seqs])
        if len(X) < 2 * self.n_states:
            raise ValueError(f"MotionPrior.fit: {len(X)} frames are too few for {self.n_states} states")
        pca = PCA(n_components=self.energy if self.energy < 1 else None, svd_solver="full").fit(X)
        self.pca_mean, self.components = pca.mean_, pca.components_
        Y = self.to_latent(np.concatenate(seqs))
        if progress:
            print(
                f"tracker prior: {len(X)} frames, PCA keeps {self.n_components} of {X.shape[1]} "
                f"dimensions ({pca.explained_variance_ratio_.sum():.3f} of the variance); fitting "
                f"a {self.n_states}-state HMM",
                file=sys.stderr,
            )
        hmm = _fit_hmm(Y, [len(s) for s in seqs], self.n_states, self.seed)
        self.startprob, self.transmat = hmm.startprob_, hmm.transmat_
        # a state fitted to few frames can end with a singular covariance; a floor keeps every state
        # usable for sampling and scoring (Cholesky needs positive definite matrices)
        floor = max(1e-6, 1e-3 * float(Y.var(axis=0).mean()))
        self.means, self.covars = hmm.means_, hmm.covars_ + floor * np.eye(Y.shape[1])
        d = np.concatenate([np.diff(s, axis=0) for s in seqs])
        d[:, YAW] = wrap_angle(d[:, YAW])
        self.rw_std = np.maximum(d.std(axis=0), RW_FLOOR)
        self.sources = list(sources)
        self.n_frames = int(len(X))
        return self

    def to_latent(self, P: np.ndarray) -> np.ndarray:
        """PCA coefficients of the poses' joint angles.

        Parameters
        ----------
        P : ndarray of shape (N, 28)
            Poses.

        Returns
        -------
        ndarray of shape (N, d)
            PCA coefficients of the joint angles.
        """
        return (np.asarray(P)[..., ANGLE_DOFS] - self.pca_mean) @ self.components.T

    def from_latent(self, Y: np.ndarray) -> np.ndarray:
        """Joint angles from PCA coefficients.

        Parameters
        ----------
        Y : ndarray of shape (N, d)
            PCA coefficients.

        Returns
        -------
        ndarray of shape (N, len(ANGLE_DOFS))
            Joint angles (radians).
        """
        return Y @ self.components + self.pca_mean

    def state_loglik(self, Y: np.ndarray) -> np.ndarray:
        """Log density log N(y | mu_k, S_k) of every state.

        Parameters
        ----------
        Y : ndarray of shape (N, d)
            PCA coefficients.

        Returns
        -------
        ndarray of shape (N, K)
            Log density of each row under each HMM state.

        Raises
        ------
        RuntimeError
            When the prior is not fitted.
        """
        self._require()
        L = np.linalg.cholesky(self.covars)  # (K, d, d)
        diff = Y[:, None, :] - self.means[None]  # (N, K, d)
        z = np.linalg.solve(L[None], diff[..., None])[..., 0]
        logdet = 2 * np.log(np.diagonal(L, axis1=1, axis2=2)).sum(-1)
        d = Y.shape[1]
        return -0.5 * ((z**2).sum(-1) + logdet + d * np.log(2 * np.pi))

    def predictor(self, fps: float = 0.0) -> PriorPredictor:
        """A fresh per-track predictor (its own state posterior).

        Parameters
        ----------
        fps : float, default=0.0
            Frame rate of the video tracked, Hz (0: unknown, taken as the prior's own).

        Returns
        -------
        PriorPredictor
            A predictor over this prior.

        Raises
        ------
        RuntimeError
            When the prior is not fitted.
        """
        self._require()
        return PriorPredictor(self, fps)

    def _require(self) -> None:
        if not self.fitted:
            raise RuntimeError("MotionPrior is not fitted; call fit() or MotionPrior.load(path)")

    # -------------------------------------------------------------------------------- files
    def meta(self) -> dict[str, Any]:
        """The metadata stored with the prior's arrays.

        Returns
        -------
        dict
            JSON-able version, kind, parameters, modelled DOFs, sources and frame count.
        """
        return {
            "version": VERSION,
            "kind": "counterpart.tracker_prior",
            "n_states": int(self.n_states),
            "energy": float(self.energy),
            "n_components": self.n_components,
            "dofs": [int(i) for i in ANGLE_DOFS],
            "hmm_weight": float(self.hmm_weight),
            "rw_scale": float(self.rw_scale),
            "fps": float(self.fps),
            "sources": list(self.sources),
            "n_frames": self.n_frames,
        }

    def save(self, path: str | os.PathLike) -> Path:
        """Write the ``.npz`` (arrays + ``meta`` JSON).

        Parameters
        ----------
        path : str or os.PathLike
            The file to write (its folder is created).

        Returns
        -------
        Path
            The path written.

        Raises
        ------
        RuntimeError
            When the prior is not fitted.
        """
        self._require()
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.name + ".tmp.npz")
        np.savez(
            tmp,
            meta=json.dumps(self.meta()),
            pca_mean=self.pca_mean,
            components=self.components,
            startprob=self.startprob,
            transmat=self.transmat,
            means=self.means,
            covars=self.covars,
            rw_std=self.rw_std,
        )
        os.replace(tmp, path)
        return path

    @classmethod
    def load(cls, path: str | os.PathLike) -> MotionPrior:
        """Read a prior file.

        Parameters
        ----------
        path : str or os.PathLike
            A file written by :meth:`save`.

        Returns
        -------
        MotionPrior
            The fitted prior.

        Raises
        ------
        FileNotFoundError
            When ``path`` does not exist.
        ValueError
            Naming the file, when it is not a tracker prior, is of another version or models other DOFs.
        """
        path = Path(path)
        if not path.exists():
            raise FileNotFoundError(
                f"tracker prior {path} does not exist; train one with 'counterpart learn tracker-prior --out {path}'"
            )
        with np.load(path, allow_pickle=False) as z:
            if "meta" not in z:
                raise ValueError(f"{path}: not a tracker prior (no 'meta' entry)")
            meta = json.loads(str(z["meta"]))
            if meta.get("kind") != "counterpart.tracker_prior":
                raise ValueError(f"{path}: not a tracker prior (kind {meta.get('kind')!r})")
            if meta.get("version") != VERSION:
                raise ValueError(
                    f"{path}: tracker prior version {meta.get('version')!r}, this program reads "
                    f"version {VERSION}; retrain it with 'counterpart learn tracker-prior'"
                )
            if meta.get("dofs") != [int(i) for i in ANGLE_DOFS]:
                raise ValueError(f"{path}: prior models DOFs {meta.get('dofs')}, expected {list(ANGLE_DOFS)}")
            arrays = {k: z[k] for k in ("pca_mean", "components", "startprob", "transmat", "means", "covars", "rw_std")}
        return cls(
            n_states=meta["n_states"],
            energy=meta["energy"],
            hmm_weight=meta["hmm_weight"],
            rw_scale=meta["rw_scale"],
            fps=float(meta.get("fps", PRIOR_FPS)),
            sources=meta["sources"],
            n_frames=meta["n_frames"],
            **arrays,
        )


class PriorPredictor:
    """Per-track state of the prior: the filtered HMM posterior and the ``predict_fn`` of the APF.

    Call ``update(pose)`` with each frame's estimate, and use the object as
    ``predict_fn(particles (N, 28), rng) -> (N, 28)``.

    A video slower than the prior's frame rate moves further between its frames: with ``r`` the
    prior's frames per frame of the video (``frame_steps``), the random walk's std is ``r`` times
    the prior's (people move smoothly over a tenth of a second, so a step grows with the interval)
    and the transitions are those of ``r`` of the prior's frames (``transitions_over``). A faster
    video keeps the prior's own: its search is never narrower than at the rate it was tuned at.

    Parameters
    ----------
    prior : MotionPrior
        A fitted prior.
    fps : float, default=0.0
        Frame rate of the video tracked, Hz (0: unknown, taken as the prior's own).

    Attributes
    ----------
    alpha : ndarray of shape (K,)
        Filtered HMM state posterior.
    std : ndarray of shape (28,)
        Random-walk std per DOF (``rw_std`` floored, times ``rw_scale`` and the frame steps).
    transmat : ndarray of shape (K, K)
        The HMM's transitions from one frame of the video to the next.
    """

    def __init__(self, prior: MotionPrior, fps: float = 0.0) -> None:
        self.prior = prior
        #: the prior's frames one frame of the video spans (``frame_steps``)
        self.frame_steps = frame_steps(prior.fps, fps)
        self.alpha = prior.startprob.copy()
        self._chol = np.linalg.cholesky(prior.covars)
        # Mahalanobis distances of all states as matmuls (``log_prior``):
        # (y - mu_k)' S_k^-1 (y - mu_k) = vec(y y') . vec(S_k^-1) - 2 y . S_k^-1 mu_k + mu_k' S_k^-1 mu_k
        Sinv = np.linalg.inv(prior.covars)  # (K, d, d)
        d = Sinv.shape[1]
        self._q2 = Sinv.reshape(len(Sinv), d * d).T  # (d*d, K)
        Smu = np.einsum("kij,kj->ki", Sinv, prior.means)  # (K, d)
        self._q1 = -2 * Smu.T  # (d, K)
        self._q0 = np.einsum("ki,ki->k", Smu, prior.means)  # (K,)
        self._logdet = 2 * np.log(np.diagonal(self._chol, axis1=1, axis2=2)).sum(-1)
        self._rw_std = np.maximum(prior.rw_std, RW_FLOOR) * prior.rw_scale
        #: (alpha, uniform, log state weights) of ``log_prior``, for the frame's alpha
        self._logw: tuple[np.ndarray, float, np.ndarray] | None = None
        self._steps: float | None = None
        self.set_gap(1)

    def set_gap(self, frames: int) -> None:
        """The next frame comes ``frames`` frames of the video after the last one tracked (more than
        one where frames were dropped): the random walk and the transitions span as many of the
        prior's frames (``frame_steps`` times ``frames``, at most ``MAX_FRAME_STEPS``).

        Parameters
        ----------
        frames : int
            Frames of the video since the last one tracked, >= 1.
        """
        steps = gap_steps(self.frame_steps, frames)
        if steps == self._steps:
            return
        self._steps = steps
        self.std = self._rw_std * steps
        self.transmat = transitions_over(self.prior.transmat, steps)
        self._logw = None

    def reset(self) -> None:
        self.alpha = self.prior.startprob.copy()

    def update(self, pose: np.ndarray) -> np.ndarray:
        """Forward-algorithm step with the frame's estimate.

        Parameters
        ----------
        pose : ndarray of shape (28,)
            The frame's pose estimate.

        Returns
        -------
        ndarray of shape (K,)
            The filtered state posterior ``alpha``.
        """
        ll = self.prior.state_loglik(self.prior.to_latent(np.asarray(pose)[None]))[0]
        a = np.log(np.maximum(self.alpha @ self.transmat, 1e-300)) + ll
        a = np.exp(a - a.max())
        self.alpha = a / a.sum()
        return self.alpha

    def predicted_states(self) -> np.ndarray:
        """Predicted state mixture of the next frame, alpha_t A.

        Returns
        -------
        ndarray of shape (K,)
            State weights.
        """
        return self.alpha @ self.transmat

    def log_prior(self, P: np.ndarray, resid_std: float = 0.15, uniform: float = 0.5) -> np.ndarray:
        """Log density of the poses' joint angles under the prior, per angle DOF.

        ``log p(x) = log sum_k w_k N(y | mu_k, S_k) + log N(r | 0, resid_std^2 I)`` with y the PCA
        coefficients and r the residual off the PCA subspace (radians); the state weights w are
        the predicted mixture ``alpha_t A`` blended with ``uniform`` of a flat one (a wrong state
        estimate must not forbid a pose). Divided by ``len(ANGLE_DOFS)``; constants dropped.
        This is the pose prior p(x_t | x_{t-1}) of the posterior the annealing layers sharpen.

        Parameters
        ----------
        P : ndarray of shape (N, 28)
            Poses.
        resid_std : float, default=0.15
            Std of the residual off the PCA subspace (radians).
        uniform : float, default=0.5
            Weight of the flat state mixture blended with the predicted one, in [0, 1].

        Returns
        -------
        ndarray of shape (N,)
            Log density per angle DOF, constants dropped.
        """
        A = np.asarray(P, dtype=np.float64)[:, ANGLE_DOFS]
        Y = (A - self.prior.pca_mean) @ self.prior.components.T  # (N, d)
        R = A - (Y @ self.prior.components + self.prior.pca_mean)
        maha = (Y[:, :, None] * Y[:, None, :]).reshape(len(Y), -1) @ self._q2 + Y @ self._q1 + self._q0
        if self._logw is None or self._logw[0] is not self.alpha or self._logw[1] != uniform:  # once a frame
            w = (1 - uniform) * self.predicted_states() + uniform / len(self._logdet)
            self._logw = (self.alpha, uniform, np.log(np.maximum(w, 1e-300)))
        lk = self._logw[2] - 0.5 * (maha + self._logdet)  # (N, K)
        m = lk.max(axis=1)
        lse = m + np.log(np.exp(lk - m[:, None]).sum(axis=1))
        return (lse - 0.5 * np.einsum("ni,ni->n", R, R) / resid_std**2) / len(ANGLE_DOFS)

    def __call__(self, P: np.ndarray, rng: np.random.Generator, scale: float = 1.0) -> np.ndarray:
        """Predict particles (N, 28) -> (N, 28); ``scale`` widens the random walk (re-initialisation)."""
        out = P + rng.normal(size=P.shape) * (self.std * scale)
        n_hmm = int(round(self.prior.hmm_weight * len(P)))
        if n_hmm:
            rows = rng.choice(len(P), size=n_hmm, replace=False)
            mix = self.predicted_states()
            k = rng.choice(len(mix), size=n_hmm, p=mix / mix.sum())
            z = rng.normal(size=(n_hmm, self.prior.means.shape[1]))
            Y = self.prior.means[k] + np.einsum("nij,nj->ni", self._chol[k], z)
            out[rows[:, None], ANGLE_DOFS[None]] = self.prior.from_latent(Y)
        return clip_to_limits(out)


def frame_steps(prior_fps: float, fps: float) -> float:
    """How many of a prior's frames one frame of a video spans, never under one nor over
    ``MAX_FRAME_STEPS``.

    Parameters
    ----------
    prior_fps : float
        The prior's frame rate, Hz.
    fps : float
        The video's, Hz (0 or less: unknown).

    Returns
    -------
    float
        ``prior_fps / fps`` in [1, ``MAX_FRAME_STEPS``]; 1 for an unknown rate.
    """
    return min(MAX_FRAME_STEPS, max(1.0, prior_fps / fps)) if fps > 0 else 1.0


def gap_steps(frame_steps: float, frames: int) -> float:
    """The prior's frames a step of ``frames`` video frames spans, each ``frame_steps`` of them
    (:func:`frame_steps`), at most ``MAX_FRAME_STEPS``.

    Parameters
    ----------
    frame_steps : float
        Prior frames per video frame, >= 1.
    frames : int
        Video frames the step spans (1 without a gap; less counts as 1).

    Returns
    -------
    float
        ``min(MAX_FRAME_STEPS, frame_steps * max(1, frames))``.
    """
    return min(MAX_FRAME_STEPS, frame_steps * max(1, int(frames)))


def transitions_over(transmat: np.ndarray, steps: float) -> np.ndarray:
    """A Markov chain's transitions over ``steps`` of its frames, a fractional number of them taken
    between the whole numbers on either side: ``(1 - f) A^n + f A^(n+1)`` with ``n + f = steps``
    (a stochastic matrix, as a fractional matrix power need not be).

    Parameters
    ----------
    transmat : ndarray of shape (K, K)
        Row-stochastic transition matrix A of one frame.
    steps : float
        Frames, >= 0.

    Returns
    -------
    ndarray of shape (K, K)
        The row-stochastic transitions over ``steps`` frames.
    """
    n = int(np.floor(steps))
    f = steps - n
    An = np.linalg.matrix_power(transmat, n)
    return An if f == 0 else (1.0 - f) * An + f * (An @ transmat)


# ------------------------------------------------------------------------------------ data
def _resample(P: np.ndarray, fps_in: float, fps_out: float) -> np.ndarray:
    """Pose sequence at fps_in -> fps_out by nearest frames (motion capture at 120 Hz -> 25 Hz)."""
    if abs(fps_in - fps_out) < 1e-6:
        return P
    t = np.arange(0, len(P) / fps_in, 1.0 / fps_out)
    return P[np.minimum(np.rint(t * fps_in).astype(int), len(P) - 1)]


def load_sequences(sources: Iterable[str], fps: float = 25.0) -> tuple[list[np.ndarray], list[str]]:
    """Pose sequences (T, 28) at ``fps`` from training sources.

    A source is ``sim:NAME[?seed=S]`` (both people of a simulator scenario), a ``.bvh`` file (one
    person), a ``.npz`` two-person trajectory (``counterpart.body.trajectory``; both people through
    ``counterpart.body.ik.inverse_kinematics``) or a simulator ``truth.npz`` holding ``poses_a``/``poses_b``,
    or a folder of such files.

    Parameters
    ----------
    sources : iterable of str
        Training sources as above.
    fps : float, default=25.0
        Frame rate of the returned sequences (Hz); files at other rates are resampled by nearest frames.

    Returns
    -------
    seqs : list of ndarray of shape (T, 28)
        Pose sequences.
    names : list of str
        One name per sequence (``#a``/``#b`` for the person of a two-person source).

    Raises
    ------
    FileNotFoundError
        When a source path does not exist.
    ValueError
        For a folder without ``.npz``/``.bvh`` files or a source of unknown kind.
    """
    seqs: list[np.ndarray] = []
    names: list[str] = []
    for src in sources:
        src = str(src)
        if src.startswith("sim:"):
            from counterpart.bus.plugins import simulator

            name, _, query = src[4:].partition("?")
            seed = int(query.split("=", 1)[1]) if query.startswith("seed=") else 0
            sc = simulator().make_scenario(name, seed=seed, fps=fps)
            seqs += [sc.poses_a, sc.poses_b]
            names += [f"{src}#a", f"{src}#b"]
            continue
        p = Path(src)
        if p.is_dir():
            files = sorted([*p.glob("*.npz"), *p.glob("*.bvh")])
            if not files:
                raise ValueError(f"training data folder {p} holds no .npz or .bvh file")
            s, n = load_sequences([str(f) for f in files], fps)
            seqs += s
            names += n
        elif not p.exists():
            raise FileNotFoundError(f"training data {p} does not exist (give sim:NAME, a .bvh, a .npz or a folder)")
        elif p.suffix.lower() == ".bvh":
            from counterpart.body.bvh import bvh_to_joints14, read_bvh
            from counterpart.body.ik import inverse_kinematics

            b = read_bvh(p)
            seqs.append(_resample(inverse_kinematics(bvh_to_joints14(b)), b.fps, fps))
            names.append(str(p))
        elif p.suffix.lower() == ".npz":
            with np.load(p, allow_pickle=False) as z:
                keys = set(z.files)
                if {"poses_a", "poses_b"} <= keys:
                    f_in = float(z["fps"]) if "fps" in keys else fps
                    for who in ("a", "b"):
                        seqs.append(_resample(np.asarray(z[f"poses_{who}"], np.float64), f_in, fps))
                        names.append(f"{p}#{who}")
                    continue
            from counterpart.body.ik import inverse_kinematics
            from counterpart.body.trajectory import TwoPersonTrajectory

            tr = TwoPersonTrajectory.load(p)
            for who, X in (("a", tr.a), ("b", tr.b)):
                seqs.append(_resample(inverse_kinematics(X), tr.fps, fps))
                names.append(f"{p}#{who}")
        else:
            raise ValueError(f"training data {p}: unknown kind; give sim:NAME, a .bvh, a .npz or a folder")
    return seqs, names


#: floors on the HMM's covariances tried in turn (:func:`_fit_hmm`): an absolute one, then shares of
#: the mean variance of the PCA coefficients
_MIN_COVAR = 1e-4
_MIN_COVAR_SHARES = (0.02, 0.1)


def _fit_hmm(Y: np.ndarray, lengths: list[int], n_states: int, seed: int) -> Any:
    """The ``GaussianHMM`` of hmmlearn (full covariances, 25 EM iterations) fitted to the PCA
    coefficients ``Y`` (N, d) of sequences of ``lengths`` frames.

    On a small recording a state can gather a few frames along one smooth stretch of motion, and
    its covariance becomes one that hmmlearn refuses as not positive definite; the fit is then tried
    again with a floor on the covariances scaled to the data's spread (``_MIN_COVAR_SHARES`` of its
    mean variance). Data on which the first fit succeeds get the same model as before.

    Raises
    ------
    ValueError
        When no floor gives a fit: what to change (more frames, fewer states).
    """
    from counterpart.body.gaussian_hmm import full_gaussian_hmm

    spread = float(Y.var(axis=0).mean())
    floors = (_MIN_COVAR, *(share * spread for share in _MIN_COVAR_SHARES))
    for min_covar in floors:
        hmm = full_gaussian_hmm(n_components=n_states, n_iter=25, min_covar=min_covar, random_state=seed)
        try:
            return hmm.fit(Y, lengths=lengths)
        except ValueError as exc:
            why = str(exc)
    raise ValueError(
        f"MotionPrior.fit: a {n_states}-state HMM could not be fitted to {len(Y)} frames ({why}); "
        "give more frames of motion, or fewer states (counterpart learn tracker-prior --states)"
    )


def train_prior(
    sources: Iterable[str],
    n_states: int = 30,
    energy: float = 0.95,
    fps: float = 25.0,
    seed: int = 0,
    progress: bool = False,
) -> MotionPrior:
    """Load ``sources`` (see ``load_sequences``) and fit a MotionPrior.

    Parameters
    ----------
    sources : iterable of str
        Training sources (see :func:`load_sequences`).
    n_states : int, default=30
        HMM states.
    energy : float, default=0.95
        Fraction of variance the PCA keeps.
    fps : float, default=25.0
        Frame rate the sequences are resampled to (Hz).
    seed : int, default=0
        Seed of the HMM fit.
    progress : bool, default=False
        Print progress to stderr.

    Returns
    -------
    MotionPrior
        The fitted prior.
    """
    sources = list(sources)
    seqs, names = load_sequences(sources, fps)
    if progress:
        print(f"tracker prior: {len(seqs)} sequences from {len(sources)} source(s)", file=sys.stderr)
    return MotionPrior(n_states=n_states, energy=energy, seed=seed, fps=fps).fit(seqs, names, progress=progress)


#: what the tracker node and ``counterpart track`` say before they load the default prior
LOADING_DEFAULT_PRIOR = "loading the default motion prior (built from the simulator on first use, about 10 s)"


def default_prior_path() -> Path:
    """``$COUNTERPART_MODELS/tracker_prior.npz``, default ``~/.cache/counterpart/models/``.

    Returns
    -------
    Path
        Path of the default prior file.
    """
    root = os.environ.get("COUNTERPART_MODELS") or os.path.join(Path.home(), ".cache", "counterpart", "models")
    return Path(root) / "tracker_prior.npz"


def load_default_prior(progress: bool = False) -> MotionPrior:
    """The default prior, trained from the simulator (``DEFAULT_TRAINING``) and cached when missing
    or of another version.

    Parameters
    ----------
    progress : bool, default=False
        Print progress to stderr while rebuilding.

    Returns
    -------
    MotionPrior
        The default prior.
    """
    path = default_prior_path()
    if path.exists():
        try:
            return MotionPrior.load(path)
        except ValueError as exc:
            if progress:
                print(f"tracker prior: {exc}; rebuilding it", file=sys.stderr)
    prior = train_prior(DEFAULT_TRAINING, progress=progress)
    prior.save(path)
    return prior


def resolve_prior(spec: str | None) -> MotionPrior | None:
    """The prior a parameter names.

    Parameters
    ----------
    spec : str or None
        ``"default"``: the default prior; ``"none"``, empty or None: no prior (random walk only); else
        the path of a prior file.

    Returns
    -------
    MotionPrior or None
        The prior, or None.
    """
    if spec is None or spec in ("", "none"):
        return None
    if spec == "default":
        return load_default_prior()
    return MotionPrior.load(spec)


__all__ = [
    "MotionPrior",
    "PriorPredictor",
    "VERSION",
    "ANGLE_DOFS",
    "DEFAULT_TRAINING",
    "load_sequences",
    "train_prior",
    "default_prior_path",
    "load_default_prior",
    "resolve_prior",
]
