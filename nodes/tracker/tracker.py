"""The per-person tracker: observation model + annealed particle filter + motion prior.

Per frame (Deutscher et al. 2000 with the prior of Zheng et al. 2006):

1. maps of the person's mask and the frame (``likelihood.make_observation``), one per camera when
   several calibrated cameras see the scene (``likelihood.MultiViewLikelihood`` sums their costs);
2. no track yet, or the track was lost: particles around the silhouette's guess (``init``: placed
   from the bounding box, neutral pose, heading from the side of the frame, spread by
   ``init_spread`` x ``INIT_STD``) and a longer first search (``init_layers`` layers, diffusion
   bounded by [init_min, init_max] x that spread);
3. otherwise ``predict_fn`` = the prior (HMM mixture + random walk; widened by ``predict_scale``
   for the annealed filter) and ``n_layers`` layers;
4. the annealed density is the posterior: the image log-likelihood (with its ground-contact term),
   the prior's pose density ``w_prior * log p(x)`` (``PriorPredictor.log_prior``) and a Gaussian
   temporal term ``-w_temporal / 2 * mean(((x - c) / s)^2)``: around the previous estimate with
   s = ``temporal_sigma`` x the random walk's std, or, on a track's first frame, around the
   silhouette's guess with s = its spread; it keeps the search out of the silhouette's
   ambiguities (mirror-image limbs, depth, heading);
5. the estimate (weighted mean of the last layer) updates the HMM posterior and the lost detector.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from counterpart.body.camera import Camera
from counterpart.body.kinematics import forward_kinematics
from counterpart.body.pose import DOF, YAW, wrap_angle
from counterpart.body.skeleton import DEFAULT_DIMS, BodyDims

from .apf import AnnealedParticleFilter, ParticleFilter
from .init import INIT_STD, LostDetector, bbox_from_mask, initial_particles
from .likelihood import MultiViewLikelihood, Observation, make_observation
from .prior import RW_FLOOR, MotionPrior, PriorPredictor


@dataclass
class TrackResult:
    """One frame of one person: ``pose``/``best`` (28,), ``joints`` (14, 3) float32 metres of the
    mean pose, ``ess``, ``log_likelihood`` (image term of the best particle), ``cost`` (its
    S_r + S_e + S_c), ``lost`` and ``initialised`` (this frame started the track).
    """

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


#: the sides of the frame a tracker can follow (as the silhouette node labels its people)
SIDES = ("left", "right")


def people_problem(people: list) -> str | None:
    """None when ``people`` names one or two distinct sides out of SIDES, else what is wrong."""
    if not 1 <= len(people) <= 2 or any(s not in SIDES for s in people) or len(set(people)) != len(people):
        return f"{people!r}: expected one or two distinct sides out of {list(SIDES)}"
    return None


def _per_camera(x: object, n: int) -> bool:
    """True when ``x`` is a list/tuple of ``n`` entries or an array stacked over ``n`` cameras."""
    if isinstance(x, np.ndarray):
        return x.ndim >= 3 and len(x) == n
    return isinstance(x, (list, tuple)) and len(x) == n


class Tracker:
    """Tracks one person through frames + masks of one camera, or of several calibrated cameras.

    Args:
        camera: calibrated camera of the frames, or a sequence of cameras that see the same scene
            at the same instants (``update`` then takes one frame and one mask per camera; the
            first camera is the reference view: the track starts from its silhouette).
        side: "left" / "right": the person's side of the frame (sets the initial heading).
        n_layers, n_particles: annealing layers and particles per layer (Deutscher: 10 x 256).
        prior: learned MotionPrior, or None for a plain random walk.
        plain: use a plain particle filter of ``n_layers * n_particles`` particles instead (baseline).
        w_temporal, temporal_sigma: weight and width (x the random walk's std) of the temporal term.
        w_prior, resid_std: weight of the prior's pose density in the annealed density, and the
            std (radians) of the joint angles off its PCA subspace (``PriorPredictor.log_prior``).
            At 1.0 the prior, fitted to few training sequences, outweighed the image for poses
            it had seen little of (the wave's raised arm); 0.5 gave 6-13 mm lower errors on
            simulator seeds 5-8.
        init_layers, init_spread: layers of the first search of a track and the spread of its
            particles around the silhouette's guess (x ``init.INIT_STD``).
        predict_scale: the annealed filter's prediction widens the random walk by this factor
            (Deutscher: the first layer searches widest, the layers narrow it); the plain filter
            predicts with the random walk itself.
        apf_diffusion, apf_min, apf_max, apf_shrink: the annealed filter's diffusion: std =
            ``apf_diffusion`` x the particle set's spread per DOF, clipped to [apf_min, apf_max] x
            the random walk's std (the first search: [init_min, init_max] x its spread), x
            ``apf_shrink`` per layer.
        dims: body dimensions (default: scaled to the stature measured at initialisation).
        seed: seed of all random numbers.
        likelihood_kw: keyword arguments of ``ConeLikelihood``.
    """

    def __init__(
        self,
        camera: Camera | Sequence[Camera],
        side: str = "left",
        n_layers: int = 10,
        n_particles: int = 256,
        prior: MotionPrior | None = None,
        plain: bool = False,
        w_temporal: float = 1.0,
        temporal_sigma: float = 3.0,
        w_prior: float = 0.5,
        resid_std: float = 0.15,
        init_layers: int = 20,
        init_spread: float = 0.5,
        predict_scale: float = 3.0,
        apf_diffusion: float = 0.5,
        apf_min: float = 0.05,
        apf_max: float = 3.0,
        apf_shrink: float = 1.0,
        init_min: float = 0.01,
        init_max: float = 1.0,
        dims: BodyDims | None = None,
        seed: int = 0,
        likelihood_kw: dict | None = None,
    ) -> None:
        self.cameras = [camera] if isinstance(camera, Camera) else list(camera)
        if not self.cameras or not all(isinstance(c, Camera) for c in self.cameras):
            raise ValueError(f"camera={camera!r}: expected a Camera or a non-empty sequence of Cameras")
        self.camera = self.cameras[0]
        self.side = side
        self.n_layers = int(n_layers)
        self.n_particles = int(n_particles)
        self.plain = bool(plain)
        self.rng = np.random.default_rng(seed)
        self.predictor: PriorPredictor | _RandomWalk = (
            prior.predictor() if prior is not None else _RandomWalk(RW_FLOOR * 3.0)
        )
        self.w_temporal = float(w_temporal)
        self.temporal_sigma = float(temporal_sigma)
        self.w_prior = float(w_prior)
        self.resid_std = float(resid_std)
        self.init_layers = int(init_layers)
        self.init_spread = float(init_spread)
        self.predict_scale = float(predict_scale)
        self.init_min, self.init_max = float(init_min), float(init_max)
        self.fixed_dims = dims
        self.dims: BodyDims = dims or DEFAULT_DIMS
        self.likelihood_kw = dict(likelihood_kw or {})
        self.likelihood = MultiViewLikelihood(self.cameras, self.dims, **self.likelihood_kw)
        self.filter = (
            ParticleFilter(self.n_layers * self.n_particles, seed=self.rng)
            if self.plain
            else AnnealedParticleFilter(
                self.n_layers,
                self.n_particles,
                seed=self.rng,
                max_std=self.predictor.std * apf_max,
                diffusion=apf_diffusion,
                min_std=self.predictor.std * apf_min,
                shrink=apf_shrink,
            )
        )
        self.lost_detector = LostDetector()
        self.prev: np.ndarray | None = None
        self.n_frames = 0

    @property
    def tracking(self) -> bool:
        return self.prev is not None

    def set_camera(self, camera: Camera) -> None:
        """A refined calibration of the same single view (the calibration node's estimate moving by
        small steps): the track goes on, projected with the new camera from the next frame.
        """
        self.cameras, self.camera = [camera], camera
        self.likelihood = MultiViewLikelihood(self.cameras, self.dims, **self.likelihood_kw)

    def reset(self) -> None:
        """Forget the track; the next frame with a person re-initialises it."""
        self.prev = None
        self.predictor.reset()
        self.lost_detector.reset()

    def _temporal(self, X: np.ndarray, centre: np.ndarray | None = None, sig: np.ndarray | None = None) -> np.ndarray:
        """Gaussian term around the previous estimate, or (first frame) around the initial guess
        ``centre`` with its uncertainty ``sig``: the heading and depth barely show in one
        silhouette, so without it the first search wanders along them.
        """
        centre = self.prev if centre is None else centre
        if centre is None or not self.w_temporal:
            return np.zeros(len(X))
        sig = self.temporal_sigma * self.predictor.std if sig is None else sig
        d = (X - centre) / sig
        d[:, YAW] = wrap_angle(X[:, YAW] - centre[YAW]) / sig[YAW]
        return -0.5 * self.w_temporal * (d * d).mean(axis=1)

    def _pose_prior(self, X: np.ndarray) -> np.ndarray:
        if not self.w_prior or not hasattr(self.predictor, "log_prior"):
            return np.zeros(len(X))
        return self.w_prior * self.predictor.log_prior(X, self.resid_std)

    def _observations(
        self, image: np.ndarray | None | Sequence[np.ndarray | None], mask: np.ndarray | Sequence[np.ndarray]
    ) -> list[Observation]:
        """One Observation per camera from one frame and mask (one camera) or sequences of them."""
        n = len(self.cameras)
        if n == 1 and not _per_camera(mask, 1):
            return [make_observation(image, mask, rng=self.rng)]
        if not _per_camera(mask, n):
            raise ValueError(
                f"the tracker has {n} cameras: give a list of {n} masks, one per camera "
                f"(got {type(mask).__name__} of shape {np.shape(mask)})"
            )
        images = [None] * n if image is None else image
        if not _per_camera(images, n):
            raise ValueError(
                f"the tracker has {n} cameras: give a list of {n} frames (or None), one per "
                f"camera (got {type(image).__name__})"
            )
        return [make_observation(im, m, rng=self.rng) for im, m in zip(images, mask)]

    def update(
        self, image: np.ndarray | None | Sequence[np.ndarray | None], mask: np.ndarray | Sequence[np.ndarray]
    ) -> TrackResult | None:
        """Track one frame. ``image`` (H, W[, 3]) uint8 or None; ``mask`` (H, W) bool of this
        person; with several cameras, lists of them in the cameras' order. Returns None (and keeps
        the track) when the reference view's mask is empty; another view with an empty mask (the
        person out of its sight) is left out of this frame's likelihood.
        """
        obs = self._observations(image, mask)
        if obs[0].empty:
            return None
        start = not self.tracking
        if start:
            ref_mask = mask[0] if _per_camera(mask, len(self.cameras)) else mask
            bbox = bbox_from_mask(np.asarray(ref_mask, bool))
            P0, dims = initial_particles(
                bbox, self.side, self.camera, self.filter.n_particles, self.rng, spread=self.init_spread
            )
            if self.fixed_dims is None:
                self.dims = dims
                self.likelihood = MultiViewLikelihood(self.cameras, dims, **self.likelihood_kw)
            self.filter.initialise(P0)
            self.predictor.reset()

        guess = P0[0] if start else None
        wide = INIT_STD * self.init_spread if start else None

        def loglik(X: np.ndarray) -> np.ndarray:
            return self.likelihood(X, obs) + self._temporal(X, guess, wide) + self._pose_prior(X)

        if start:
            est = self.filter.step(
                loglik, None, n_layers=self.init_layers, min_std=self.init_min * wide, max_std=self.init_max * wide
            )
        else:
            scale = 1.0 if self.plain else self.predict_scale
            est = self.filter.step(loglik, lambda P, rng: self.predictor(P, rng, scale=scale))
        terms, ground = self.likelihood.evaluate(est.best[None], obs)
        cost = float(terms.sum()) / sum(not o.empty for o in obs)  # per view seen: 0 best, 3 worst
        image_ll = float(self.likelihood.combine(terms, ground)[0])
        self.predictor.update(est.mean)
        self.prev = est.mean.copy()
        lost = self.lost_detector.update(cost)
        if lost:
            self.reset()
        self.n_frames += 1
        return TrackResult(
            est.mean,
            est.best,
            forward_kinematics(est.mean, self.dims)[0].astype(np.float32),
            est.ess,
            image_ll,
            cost,
            lost,
            start,
        )


def track_sequence(
    frames: Iterable[np.ndarray | None | Sequence[np.ndarray | None]],
    masks: Iterable[np.ndarray | Sequence[np.ndarray]],
    camera: Camera | Sequence[Camera],
    side: str = "left",
    **tracker_kw,
) -> dict[str, np.ndarray]:
    """Track one person offline.

    Args:
        frames: T images (H, W[, 3]) uint8, or None entries for mask-only tracking; with several
            cameras each entry is a list of one image (or None) per camera.
        masks: T (H, W) bool masks of the person (several cameras: T lists of one per camera).
        camera: the camera, or the cameras; ``side`` and ``tracker_kw`` go to :class:`Tracker`.

    Returns
    -------
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
    return {
        "poses": np.array(poses),
        "joints": np.array(joints),
        "ess": np.array(ess),
        "log_likelihood": np.array(ll),
        "lost": np.array(lost, bool),
        "dims": tr.dims,
    }


__all__ = ["Tracker", "TrackResult", "track_sequence", "SIDES", "people_problem"]
