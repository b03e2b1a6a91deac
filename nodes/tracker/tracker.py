"""The per-person tracker: observation model + annealed particle filter + motion prior.

Per frame (Deutscher et al. 2000 with the prior of Zheng et al. 2006):

1. maps of the person's mask and the frame (``likelihood.make_observation``);
2. no track yet, or the track was lost: particles from the silhouette (``init``) and a wider
   first search (``init_layers`` layers with the prior's random walk x ``init_spread``);
3. otherwise ``predict_fn`` = the prior (HMM mixture + random walk) and ``n_layers`` layers;
4. the annealed density is the posterior: image log-likelihood plus a Gaussian temporal term
   ``-w_temporal / 2 * mean(((x - x_prev) / (c * rw_std))^2)`` around the previous estimate, which
   keeps the search out of the silhouette's ambiguities (mirror-image limbs, depth);
5. the estimate updates the HMM posterior and the lost detector.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable

import numpy as np

from body.camera import Camera
from body.kinematics import forward_kinematics
from body.pose import DOF, YAW, wrap_angle
from body.skeleton import DEFAULT_DIMS, BodyDims

from .apf import AnnealedParticleFilter, ParticleFilter
from .init import LostDetector, bbox_from_mask, initial_particles
from .likelihood import ConeLikelihood, make_observation
from .prior import RW_FLOOR, MotionPrior, PriorPredictor


@dataclass
class TrackResult:
    """One frame of one person: ``pose``/``best`` (28,), ``joints`` (14, 3) float32 metres of the
    mean pose, ``ess``, ``log_likelihood`` (image term of the best particle), ``cost`` (its
    S_r + S_e + S_c), ``lost`` and ``initialised`` (this frame started the track)."""

    pose: np.ndarray
    best: np.ndarray
    joints: np.ndarray
    ess: float
    log_likelihood: float
    cost: float
    lost: bool
    initialised: bool


class _RandomWalk:
    """predict_fn of a tracker without a learned prior: x + N(0, diag(std^2))."""

    def __init__(self, std: np.ndarray) -> None:
        self.std = std

    def update(self, pose: np.ndarray) -> None:
        pass

    def reset(self) -> None:
        pass

    def __call__(self, P: np.ndarray, rng: np.random.Generator, scale: float = 1.0) -> np.ndarray:
        return P + rng.normal(size=P.shape) * self.std * scale


class Tracker:
    """Tracks one person through frames + masks.

    Args:
        camera: calibrated camera of the frames.
        side: "left" / "right": the person's side of the frame (sets the initial heading).
        n_layers, n_particles: annealing layers and particles per layer (Deutscher: 10 x 256).
        prior: learned MotionPrior, or None for a plain random walk.
        plain: use a plain particle filter of ``n_layers * n_particles`` particles instead (baseline).
        w_temporal, temporal_sigma: weight and width (x rw_std) of the temporal term.
        init_layers, init_spread: the wider first search.
        dims: body dimensions (default: scaled to the stature measured at initialisation).
        seed: seed of all random numbers.
    """

    def __init__(self, camera: Camera, side: str = "left", n_layers: int = 10, n_particles: int = 256,
                 prior: MotionPrior | None = None, plain: bool = False, w_temporal: float = 1.0,
                 temporal_sigma: float = 3.0, init_layers: int = 20, init_spread: float = 1.0,
                 dims: BodyDims | None = None, seed: int = 0, likelihood_kw: dict | None = None,
                 apf_min: float = 0.5, apf_max: float = 1.0, apf_shrink: float = 0.8) -> None:
        self.camera = camera
        self.side = side
        self.n_layers = int(n_layers)
        self.n_particles = int(n_particles)
        self.plain = bool(plain)
        self.rng = np.random.default_rng(seed)
        self.predictor: PriorPredictor | _RandomWalk = (
            prior.predictor() if prior is not None else _RandomWalk(RW_FLOOR * 3.0))
        self.w_temporal = float(w_temporal)
        self.temporal_sigma = float(temporal_sigma)
        self.init_layers = int(init_layers)
        self.init_spread = float(init_spread)
        self.fixed_dims = dims
        self.dims: BodyDims = dims or DEFAULT_DIMS
        self.likelihood_kw = dict(likelihood_kw or {})
        self.likelihood = ConeLikelihood(camera, self.dims, **self.likelihood_kw)
        self.filter = (ParticleFilter(self.n_layers * self.n_particles, seed=self.rng) if self.plain else
                       AnnealedParticleFilter(self.n_layers, self.n_particles, seed=self.rng,
                                              max_std=self.predictor.std * apf_max, diffusion=1.0,
                                              min_std=self.predictor.std * apf_min, shrink=apf_shrink))
        self.lost_detector = LostDetector()
        self.prev: np.ndarray | None = None
        self.n_frames = 0

    @property
    def tracking(self) -> bool:
        return self.prev is not None

    def reset(self) -> None:
        """Forget the track; the next frame with a person re-initialises it."""
        self.prev = None
        self.predictor.reset()
        self.lost_detector.reset()

    def _temporal(self, X: np.ndarray) -> np.ndarray:
        if self.prev is None or not self.w_temporal:
            return np.zeros(len(X))
        sig = self.temporal_sigma * self.predictor.std
        d = (X - self.prev) / sig
        d[:, YAW] = wrap_angle(X[:, YAW] - self.prev[YAW]) / sig[YAW]
        return -0.5 * self.w_temporal * (d * d).mean(axis=1)

    def update(self, image: np.ndarray | None, mask: np.ndarray) -> TrackResult | None:
        """Track one frame. ``image`` (H, W[, 3]) uint8 or None; ``mask`` (H, W) bool of this
        person. Returns None (and keeps the track) when the mask is empty."""
        obs = make_observation(image, mask, rng=self.rng)
        if obs.empty:
            return None
        start = not self.tracking
        if start:
            bbox = bbox_from_mask(np.asarray(mask, bool))
            P0, dims = initial_particles(bbox, self.side, self.camera, self.filter.n_particles,
                                         self.rng, spread=self.init_spread)
            if self.fixed_dims is None:
                self.dims = dims
                self.likelihood = ConeLikelihood(self.camera, dims, **self.likelihood_kw)
            self.filter.initialise(P0)
            self.predictor.reset()

        def loglik(X: np.ndarray) -> np.ndarray:
            return self.likelihood(X, obs) + self._temporal(X)

        if start:
            est = self.filter.step(loglik, None, n_layers=self.init_layers)
        else:
            est = self.filter.step(loglik, self.predictor)
        cost = float(self.likelihood.terms(est.best[None], obs).sum())
        self.predictor.update(est.mean)
        self.prev = est.mean.copy()
        lost = self.lost_detector.update(cost)
        if lost:
            self.reset()
        self.n_frames += 1
        return TrackResult(est.mean, est.best, forward_kinematics(est.mean, self.dims)[0].astype(np.float32),
                           est.ess, float(self.likelihood(est.best[None], obs)[0]), cost, lost, start)


def track_sequence(frames: Iterable[np.ndarray | None], masks: Iterable[np.ndarray], camera: Camera,
                   side: str = "left", **tracker_kw) -> dict[str, np.ndarray]:
    """Track one person offline.

    Args:
        frames: T images (H, W[, 3]) uint8, or None entries for mask-only tracking.
        masks: T (H, W) bool masks of the person.
        camera: the camera; ``side`` and ``tracker_kw`` go to :class:`Tracker`.
    Returns:
        dict with ``poses`` (T, 28), ``joints`` (T, 14, 3) float32 (NaN where nobody was in
        view), ``ess`` (T,), ``log_likelihood`` (T,), ``lost`` (T,) bool, ``dims`` (BodyDims).
    """
    tr = Tracker(camera, side, **tracker_kw)
    poses, joints, ess, ll, lost = [], [], [], [], []
    for image, mask in zip(frames, masks):
        r = tr.update(image, mask)
        if r is None:
            poses.append(np.full(DOF, np.nan))
            joints.append(np.full((14, 3), np.nan, np.float32))
            ess.append(0.0)
            ll.append(-np.inf)
            lost.append(False)
            continue
        poses.append(r.pose)
        joints.append(r.joints)
        ess.append(r.ess)
        ll.append(r.log_likelihood)
        lost.append(r.lost)
    return {"poses": np.array(poses), "joints": np.array(joints), "ess": np.array(ess),
            "log_likelihood": np.array(ll), "lost": np.array(lost, bool), "dims": tr.dims}


__all__ = ["Tracker", "TrackResult", "track_sequence"]
