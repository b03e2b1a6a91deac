"""The per-person tracker: observation model + annealed particle filter + motion prior.

Per frame (Deutscher et al. 2000 with the prior of Zheng et al. 2006), ``Tracker.update``'s steps:

1. maps of the person's mask and the frame (``likelihood.make_observation``), one per camera when
   several calibrated cameras see the scene (``likelihood.MultiViewLikelihood`` sums their costs);
2. no track yet, or the track was lost (``Tracker._first_search``): particles around the
   silhouette's guess (``init``: placed from the bounding box, neutral pose, heading from the side
   of the frame, spread by ``InitConfig.spread`` x ``INIT_STD``) and a longer first search
   (``InitConfig.layers`` layers, diffusion bounded by [min_std, max_std] x that spread);
3. otherwise (``Tracker._follow``) the prediction is the prior (HMM mixture + random walk; widened
   by ``APFConfig.predict_scale`` for the annealed filter) and ``APFConfig.n_layers`` layers;
4. the annealed density is the posterior (``Tracker._density``): the image log-likelihood (with
   its ground-contact term), the prior's pose density ``w_prior * log p(x)``
   (``PriorPredictor.log_prior``) and a Gaussian temporal term
   ``-w_temporal / 2 * mean(((x - c) / s)^2)``: around the previous estimate with
   s = ``temporal_sigma`` x the random walk's std, or, on a track's first frame, around the
   silhouette's guess with s = its spread; it keeps the search out of the silhouette's
   ambiguities (mirror-image limbs, depth, heading) (weights in ``PosteriorConfig``);
5. the estimate (weighted mean of the last layer) updates the HMM posterior and the lost detector
   (``Tracker._finish``).
"""

from __future__ import annotations

import time
from collections.abc import Generator, Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from counterpart.body.camera import Camera
from counterpart.body.kinematics import anchor_points, forward_kinematics, row_dims
from counterpart.body.pose import DOF, YAW, wrap_angle
from counterpart.body.skeleton import DEFAULT_DIMS, N_JOINTS, BodyDims

from .apf import AnnealedParticleFilter, Estimate, ParticleFilter, run_steps
from .camera_change import ground_move
from .init import (
    INIT_STD,
    STATURE_RANGE,
    LostDetector,
    PlacementError,
    bbox_from_mask,
    boxes_below,
    camera_yaw,
    cut_off_below,
    guess_pose,
    initial_particles,
    place_from_bbox,
)
from .likelihood import LikelihoodConfig, MultiViewLikelihood, Observation, evaluate_joint, make_observation
from .prior import PRIOR_FPS, RW_FLOOR, MotionPrior, PriorPredictor, frame_steps, gap_steps


@dataclass
class TrackResult:
    """One frame of one person.

    Attributes
    ----------
    pose : ndarray of shape (28,)
        The estimate: the weighted mean of the last layer (metres, radians).
    best : ndarray of shape (28,)
        The best particle.
    joints : ndarray of shape (14, 3), dtype float32
        Joints of the mean pose, metres, world frame.
    ess : float
        Effective sample size of the particle set.
    log_likelihood : float
        Image term of the best particle.
    cost : float
        Its S_r + S_e + S_c, per view seen (0 best, 3 worst).
    lost : bool
        The lost detector dropped the track on this frame.
    initialised : bool
        This frame started the track.
    """

    pose: np.ndarray
    best: np.ndarray
    joints: np.ndarray
    ess: float
    log_likelihood: float
    cost: float
    lost: bool
    initialised: bool


@dataclass
class Search:
    """One person's search of one frame, begun (:meth:`Tracker.begin`) and not yet run.

    Attributes
    ----------
    obs : list of Observation
        The frame's observations, one per camera.
    start : bool
        The search starts the track (the first search's schedule).
    steps : generator
        The filter's ``steps``: yields (N, 28) particles, is sent their log-density
        (:meth:`Tracker.posterior`), returns the Estimate.
    centre, sig : ndarray of shape (28,) or None
        The temporal term's centre and width on a track's first frame and the frames that continue
        its first search (None: around the previous estimate).
    layers : int
        Annealing layers the search runs (0: as the filter's ``n_layers``).
    """

    obs: list[Observation]
    start: bool
    steps: Generator[np.ndarray, np.ndarray, Estimate]
    centre: np.ndarray | None = None
    sig: np.ndarray | None = None
    layers: int = 0


class _RandomWalk:
    """predict_fn of a tracker without a learned prior: x + N(0, diag(std^2)), ``std`` per frame at
    ``PRIOR_FPS`` times the frames of that rate since the last one tracked (``frame_steps`` per
    frame of the video, times the frames ``set_gap`` gives, at most ``prior.MAX_FRAME_STEPS``: ``prior.gap_steps``).
    """

    def __init__(self, std: np.ndarray, frame_steps: float = 1.0) -> None:
        self._rw_std, self.frame_steps = std, frame_steps
        self.set_gap(1)

    def set_gap(self, frames: int) -> None:
        self.std = self._rw_std * gap_steps(self.frame_steps, frames)

    def update(self, pose: np.ndarray) -> None:
        pass

    def reset(self) -> None:
        pass

    def __call__(self, P: np.ndarray, rng: np.random.Generator, scale: float = 1.0) -> np.ndarray:
        return P + rng.normal(size=P.shape) * self.std * scale


#: the sides of the frame a tracker can follow (as the silhouette node labels its people)
SIDES = ("left", "right")


def people_problem(people: list) -> str | None:
    """Check a list of sides to track.

    Parameters
    ----------
    people : list of str
        The sides, out of SIDES.

    Returns
    -------
    str or None
        None when ``people`` names one or two distinct sides out of SIDES, else what is wrong.
    """
    if not 1 <= len(people) <= 2 or any(s not in SIDES for s in people) or len(set(people)) != len(people):
        return f"{people!r}: expected one or two distinct sides out of {list(SIDES)}"
    return None


def _per_camera(x: object, n: int) -> bool:
    """True when ``x`` is a list/tuple of ``n`` entries or an array stacked over ``n`` cameras."""
    if isinstance(x, np.ndarray):
        return x.ndim >= 3 and len(x) == n
    return isinstance(x, (list, tuple)) and len(x) == n


#: the headings a person cut off by the frame is tried at (``Tracker._whole_person``): these
#: fractions of the turn from their side's heading to facing the camera
TURNS = np.linspace(0.0, 1.0, 5)


@dataclass(frozen=True)
class APFConfig:
    """The search of each frame of a running track: the annealed particle filter (``apf``).

    Parameters
    ----------
    n_layers : int
        Annealing layers M per frame (Deutscher et al. 2000: 10).
    n_particles : int
        Particles N per layer (Deutscher et al.: 256).
    plain : bool
        Use a plain particle filter of ``n_layers * n_particles`` particles instead (the baseline
        of Deutscher et al.'s comparison).
    predict_scale : float
        The annealed filter's prediction widens the prior's random walk by this factor (Deutscher:
        the first layer searches widest, the layers narrow it); the plain filter predicts with
        the random walk itself.
    diffusion : float
        Diffusion std after each layer's resampling as a fraction of the particle set's spread per
        DOF (Deutscher & Reid 2005).
    min_std, max_std : float
        Bounds of that std in multiples of the random walk's std per DOF (metres, radians).
    shrink : float
        Factor by which the diffusion shrinks per layer (1: it does not).
    """

    n_layers: int = 10
    n_particles: int = 256
    plain: bool = False
    predict_scale: float = 3.0
    diffusion: float = 0.5
    min_std: float = 0.05
    max_std: float = 3.0
    shrink: float = 1.0


@dataclass(frozen=True)
class InitConfig:
    """The first search of a track, from the silhouette's guess (``init.initial_particles``).

    Parameters
    ----------
    layers : int
        Annealing layers of the first search (longer than a running track's).
    spread : float
        Spread of the particles around the guess, in multiples of ``init.INIT_STD`` (metres,
        radians); the same width sets the temporal term of the first frame.
    min_std, max_std : float
        Bounds of the first search's diffusion std in multiples of that spread.
    cut_off : bool
        A person cut off by the frame's bottom edge starts from the whole person's box that fits
        the part in view best (``Tracker._whole_person``); False: from the box in view, as if it
        ended at the feet.
    """

    layers: int = 20
    spread: float = 0.5
    min_std: float = 0.01
    max_std: float = 1.0
    cut_off: bool = True


@dataclass(frozen=True)
class PosteriorConfig:
    """The terms the annealed density adds to the image log-likelihood (module docstring, step 4).

    Parameters
    ----------
    w_temporal : float
        Weight of the Gaussian temporal term ``-w_temporal / 2 * mean(((x - c) / s)^2)`` (0: off).
    temporal_sigma : float
        Its width s in multiples of the random walk's std per DOF.
    w_prior : float
        Weight of the motion prior's pose density ``w_prior * log p(x)``. At 1.0 the prior, fitted
        to few training sequences, outweighed the image for poses it had seen little of (the
        wave's raised arm); 0.5 was chosen on simulator seeds 5-8.
    resid_std : float
        Std (radians) of the joint angles off the prior's PCA subspace
        (``PriorPredictor.log_prior``).
    """

    w_temporal: float = 1.0
    temporal_sigma: float = 3.0
    w_prior: float = 0.5
    resid_std: float = 0.15


@dataclass(frozen=True)
class TrackerConfig:
    """Every setting of a :class:`Tracker`, grouped by job.

    Parameters
    ----------
    apf : APFConfig
        The search of each frame of a running track (annealed or plain particle filter).
    init : InitConfig
        The first search of a track from the silhouette's guess.
    posterior : PosteriorConfig
        The temporal and prior terms of the annealed density.
    likelihood : LikelihoodConfig
        The observation model's sample points and cost weights (``likelihood.ConeLikelihood``).
    """

    apf: APFConfig = APFConfig()
    init: InitConfig = InitConfig()
    posterior: PosteriorConfig = PosteriorConfig()
    likelihood: LikelihoodConfig = LikelihoodConfig()


class Tracker:
    """Tracks one person through frames + masks of one camera, or of several calibrated cameras.

    Parameters
    ----------
    camera : Camera or sequence of Camera
        Calibrated camera of the frames, or cameras that see the same scene at the same instants
        (``update`` then takes one frame and one mask per camera; the first camera is the
        reference view: the track starts from its silhouette).
    side : str
        "left" / "right": the person's side of the frame (sets the initial heading).
    config : TrackerConfig
        The filter, first search, posterior and likelihood settings.
    prior : MotionPrior or None
        Learned motion prior, or None for a plain random walk.
    dims : BodyDims or None
        Body dimensions (default: scaled to the stature measured at initialisation).
    seed : int
        Seed of all random numbers.
    fps : float
        Frame rate of the frames, Hz (0: unknown): a video slower than the prior's is searched
        wider, and its prior steps over as many of the prior's frames
        (``prior.PriorPredictor``; without a prior, the random walk alike).

    Raises
    ------
    ValueError
        If ``camera`` is not a Camera or a non-empty sequence of Cameras.
    TypeError
        If ``config`` is not a TrackerConfig.
    """

    def __init__(
        self,
        camera: Camera | Sequence[Camera],
        side: str = "left",
        config: TrackerConfig = TrackerConfig(),
        prior: MotionPrior | None = None,
        dims: BodyDims | None = None,
        seed: int = 0,
        fps: float = 0.0,
    ) -> None:
        self.cameras = [camera] if isinstance(camera, Camera) else list(camera)
        if not self.cameras or not all(isinstance(c, Camera) for c in self.cameras):
            raise ValueError(f"camera={camera!r}: expected a Camera or a non-empty sequence of Cameras")
        if not isinstance(config, TrackerConfig):
            raise TypeError(f"config={config!r}: expected a TrackerConfig (e.g. TrackerConfig(apf=APFConfig(...)))")
        self.camera = self.cameras[0]
        self.side = side
        self.config = config
        self.rng = np.random.default_rng(seed)
        self.predictor: PriorPredictor | _RandomWalk = (
            prior.predictor(fps) if prior is not None else _RandomWalk(RW_FLOOR * 3.0, frame_steps(PRIOR_FPS, fps))
        )
        self.fixed_dims = dims
        self.dims: BodyDims = dims or DEFAULT_DIMS
        #: the stature the track's first box measured, unbounded, carried through refined cameras
        #: (``set_camera``): a body bounded under a camera that misread the picture gets the
        #: person's size back once the camera reads it right
        self.stature_seen = self.dims.height
        self.likelihood = self._likelihood()
        apf = config.apf
        self.filter = (
            ParticleFilter(int(apf.n_layers) * int(apf.n_particles), seed=self.rng)
            if apf.plain
            else AnnealedParticleFilter(
                int(apf.n_layers),
                int(apf.n_particles),
                seed=self.rng,
                max_std=self.predictor.std * apf.max_std,
                diffusion=apf.diffusion,
                min_std=self.predictor.std * apf.min_std,
                shrink=apf.shrink,
            )
        )
        self.lost_detector = LostDetector()
        self.prev: np.ndarray | None = None
        #: a first search spread over frames (``begin``'s ``max_layers``): its layers still to run,
        #: and its temporal term's centre and width
        self.first_left = 0
        self._first_prior: tuple[np.ndarray, np.ndarray] | None = None
        self.n_frames = 0
        #: CPU seconds of the last frame's search (the prediction and the annealing layers)
        self.search_cpu_s = 0.0
        #: (poses, image costs, ground costs) of the density's last evaluation
        self._scored: tuple[np.ndarray, np.ndarray, np.ndarray] = (np.zeros((0, DOF)), np.zeros((0, 3)), np.zeros(0))

    @property
    def tracking(self) -> bool:
        return self.prev is not None

    def _likelihood(self) -> MultiViewLikelihood:
        """The observation model of the current cameras and body dimensions."""
        return MultiViewLikelihood(self.cameras, self.dims, self.config.likelihood)

    def set_gap(self, frames: int) -> None:
        """The next frame comes ``frames`` frames after the last one given (more than one where the
        frames between were dropped before the tracker): the prediction and the search's bounds
        span them (``PriorPredictor.set_gap``).

        Parameters
        ----------
        frames : int
            Frames since the last one given, >= 1.
        """
        self.predictor.set_gap(frames)
        if isinstance(self.filter, AnnealedParticleFilter):
            apf = self.config.apf
            self.filter.max_std = self.predictor.std * apf.max_std
            self.filter.min_std = self.predictor.std * apf.min_std

    def set_camera(self, camera: Camera) -> None:
        """A refined calibration of the same single view (the calibration node's estimate moving by
        small steps): the track goes on, projected with the new camera from the next frame, its
        body moved to where the new camera sees the same picture (``camera_change``): its feet
        to the ground point of the same pixel, turned with the line of sight, and (unless ``dims``
        were given) its stature the one its first box measured, unbounded, scaled as the new
        camera reads its head and foot rows over the old one, then held within ``STATURE_RANGE``
        as at the start. A body whose feet the new camera puts at or above its horizon is let go
        (the next frame starts it again).

        Parameters
        ----------
        camera : Camera
            The refined camera.
        """
        old = self.camera
        self.cameras, self.camera = [camera], camera
        if self.tracking and camera is not old:
            try:
                move = ground_move(self.prev, self.dims, old, camera)
            except PlacementError:
                self.reset()
            else:
                scale = 1.0
                if self.fixed_dims is None:
                    self.stature_seen *= move.stature_ratio
                    height = float(np.clip(self.stature_seen, *STATURE_RANGE))
                    scale = height / self.dims.height
                    self.dims = self.dims.scaled(height)
                self.prev = move.apply(self.prev, scale)
                self.filter.particles = move.apply(self.filter.particles, scale)
                if self._first_prior is not None:
                    self._first_prior = (move.apply(self._first_prior[0], scale), self._first_prior[1])
        self.likelihood = self._likelihood()

    def reset(self) -> None:
        """Forget the track; the next frame with a person re-initialises it."""
        self.prev = None
        self.first_left = 0
        self.predictor.reset()
        self.lost_detector.reset()

    def _temporal(self, X: np.ndarray, centre: np.ndarray | None = None, sig: np.ndarray | None = None) -> np.ndarray:
        """Gaussian term around the previous estimate, or (first frame) around the initial guess
        ``centre`` with its uncertainty ``sig``: the heading and depth barely show in one
        silhouette, so without it the first search wanders along them.
        """
        post = self.config.posterior
        centre = self.prev if centre is None else centre
        if centre is None or not post.w_temporal:
            return np.zeros(len(X))
        sig = post.temporal_sigma * self.predictor.std if sig is None else sig
        d = (X - centre) / sig
        d[:, YAW] = wrap_angle(X[:, YAW] - centre[YAW]) / sig[YAW]
        return -0.5 * post.w_temporal * (d * d).mean(axis=1)

    def _pose_prior(self, X: np.ndarray) -> np.ndarray:
        post = self.config.posterior
        if not post.w_prior or not hasattr(self.predictor, "log_prior"):
            return np.zeros(len(X))
        return post.w_prior * self.predictor.log_prior(X, post.resid_std)

    def _observations(
        self,
        image: np.ndarray | None | Sequence[np.ndarray | None],
        mask: np.ndarray | Sequence[np.ndarray],
        edges: np.ndarray | None = None,
    ) -> list[Observation]:
        """One Observation per camera from one frame and mask (one camera) or sequences of them."""
        n = len(self.cameras)
        past = self.config.likelihood.past_border
        if n == 1 and not _per_camera(mask, 1):
            return [make_observation(image, mask, rng=self.rng, edges=edges, past_border=past)]
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
        return [make_observation(im, m, rng=self.rng, past_border=past) for im, m in zip(images, mask)]

    def update(
        self,
        image: np.ndarray | None | Sequence[np.ndarray | None],
        mask: np.ndarray | Sequence[np.ndarray],
        towards: tuple[int, int, int, int] | None = None,
        edges: np.ndarray | None = None,
    ) -> TrackResult | None:
        """Track one frame (the steps of the module docstring).

        Parameters
        ----------
        image : ndarray of shape (H, W) or (H, W, 3), dtype uint8, or None
            The frame; with several cameras, a list of them in the cameras' order.
        mask : ndarray of shape (H, W), dtype bool
            This person's mask; with several cameras, a list of them in the cameras' order.
        towards : tuple of int (x, y, w, h) or None
            The bounding box, in the reference view, of the person this one interacts with:
            a track that starts on this frame faces that person (``init.facing_yaw``); None:
            the heading of the person's side of the frame.
        edges : ndarray of shape (H, W), dtype bool, or None
            One camera only: the frame's Canny edges (``likelihood.frame_edges``) when the trackers
            of several people of the frame share them; None: computed from ``image``.

        Returns
        -------
        TrackResult or None
            None (the track kept) when the reference view's mask is empty; another view with an
            empty mask (the person out of its sight) is left out of this frame's likelihood.

        Raises
        ------
        ValueError
            With several cameras, when the masks or frames are not one per camera; for a mask that
            is not 2-D or a frame of another size than its mask.
        """
        search = self.begin(image, mask, towards, edges)
        if search is None:
            return None
        cpu0 = time.process_time()
        est = run_steps(search.steps, lambda X: self.posterior(search, X, *self.likelihood.evaluate(X, search.obs)))
        self.search_cpu_s = time.process_time() - cpu0
        return self.end(search, est)

    def begin(
        self,
        image: np.ndarray | None | Sequence[np.ndarray | None],
        mask: np.ndarray | Sequence[np.ndarray],
        towards: tuple[int, int, int, int] | None = None,
        edges: np.ndarray | None = None,
        max_layers: int | None = None,
    ) -> Search | None:
        """:meth:`update` in parts, for a caller that weighs several people's particles at once
        (``likelihood.evaluate_joint``): the frame's observations and the search, not yet run.
        Drive ``steps`` (``apf.run_steps``) with the image costs of each yielded set through
        :meth:`posterior`, then :meth:`end` with its Estimate.

        Parameters
        ----------
        image, mask, towards, edges
            As :meth:`update`.
        max_layers : int or None, default=None
            At most this many annealing layers for a track's first search on this frame (a frame
            budget in real time); the rest of its ``InitConfig.layers`` run on the next frames,
            continuing its schedule on their observations before the track is followed with the
            prior. None: the whole first search on this frame (the annealed filter only: the
            plain one has a single layer).

        Returns
        -------
        Search or None
            The search; None (the track kept) when the reference view's mask is empty.

        Raises
        ------
        ValueError
            As :meth:`update`.
        """
        obs = self._observations(image, mask, edges)
        if obs[0].empty:
            return None
        if self.tracking and self.first_left > 0:
            return self._continue_first_search(obs, max_layers)
        if self.tracking:
            apf = self.config.apf
            scale = 1.0 if apf.plain else apf.predict_scale
            steps = self.filter.steps(lambda P, rng: self.predictor(P, rng, scale=scale))
            return Search(obs, False, steps)
        return self._first_search(obs, mask, towards, max_layers)

    def posterior(self, search: Search, X: np.ndarray, terms: np.ndarray, ground: np.ndarray) -> np.ndarray:
        """The annealed density of the search's frame from the image costs of the poses.

        Parameters
        ----------
        search : Search
            The search (:meth:`begin`).
        X : ndarray of shape (N, 28)
            The poses it yielded.
        terms, ground : ndarray
            Their costs (``MultiViewLikelihood.evaluate``): (N, 3) and (N,).

        Returns
        -------
        ndarray of shape (N,)
            The image log-likelihood + the temporal term + the prior's pose density.
        """
        # the last layer's costs: its best particle's are the frame's score (``_finish``)
        self._scored = (X, terms, ground)
        return (
            self.likelihood.combine(terms, ground) + self._temporal(X, search.centre, search.sig) + self._pose_prior(X)
        )

    def end(self, search: Search, est: Estimate, joints: np.ndarray | None = None) -> TrackResult:
        """Finish a search begun by :meth:`begin`.

        Parameters
        ----------
        search : Search
            The search.
        est : Estimate
            What its steps returned.
        joints : ndarray of shape (14, 3), dtype float32, or None
            The joints of ``est.mean`` with this tracker's body when the caller computed them (of
            several people at once, :func:`joints_jointly`); None: computed here.

        Returns
        -------
        TrackResult
            The frame's result, as :meth:`update`'s.
        """
        return self._finish(est, search.obs, search.start, joints)

    def _first_search(
        self,
        obs: list[Observation],
        mask: np.ndarray | Sequence[np.ndarray],
        towards: tuple[int, int, int, int] | None = None,
        max_layers: int | None = None,
    ) -> Search:
        """Start a track: particles around the reference view's silhouette guess (the body scaled
        to its stature unless ``dims`` was given), searched with the first search's longer schedule
        (its first ``max_layers`` layers on this frame when given: :meth:`begin`). A person cut off
        by the frame's bottom edge starts from their whole box (:meth:`_whole_person`).
        """
        ref_mask = np.asarray(mask[0] if _per_camera(mask, len(self.cameras)) else mask, bool)
        bbox = bbox_from_mask(ref_mask)
        init = self.config.init
        yaw = None
        if init.cut_off and cut_off_below(bbox, ref_mask.shape[0]):
            bbox, yaw = self._whole_person(ref_mask, obs, towards)
        P0, dims = initial_particles(
            bbox,
            self.side,
            self.camera,
            self.filter.n_particles,
            self.rng,
            spread=init.spread,
            towards=towards,
            yaw=yaw,
        )
        if self.fixed_dims is None:
            self.dims = dims
            self.likelihood = self._likelihood()
            self.stature_seen = self._stature_seen(bbox, dims)
        self.filter.initialise(P0)
        self.predictor.reset()
        wide = INIT_STD * init.spread
        n = init.layers
        if max_layers is not None and not self.config.apf.plain:
            n = max(1, min(n, int(max_layers)))
        self.first_left, self._first_prior = init.layers - n, (P0[0], wide)
        steps = self.filter.steps(None, n_layers=n, min_std=init.min_std * wide, max_std=init.max_std * wide)
        return Search(obs, True, steps, P0[0], wide, n)

    def _stature_seen(self, bbox: tuple[int, int, int, int], dims: BodyDims) -> float:
        """The unbounded stature of a first search's box (``dims.height`` where none can be read)."""
        try:
            _, height = place_from_bbox(bbox, self.camera, bounds=None)
        except PlacementError:
            return dims.height
        return height if np.isfinite(height) and height > 0 else dims.height

    def _whole_person(
        self, mask: np.ndarray, obs: list[Observation], towards: tuple[int, int, int, int] | None
    ) -> tuple[tuple[int, int, int, int], float | None]:
        """The whole box of a person cut off by the frame's bottom edge, and their heading.

        The box's bottom is then not the feet, and the body placed on it would be squeezed into
        the part in view. Each box of ``init.boxes_below`` places a standing body at headings from
        the one the side gives (``towards``) to facing the camera (someone at a webcam; ``TURNS``);
        the body whose part in view fits the observation best (the likelihood, its window continued
        past the frame: ``make_observation``) gives the box and the heading (None: the side's).
        """
        boxes = boxes_below(mask)
        best: tuple[float, tuple[int, int, int, int], float | None] = (-np.inf, boxes[0], None)
        dims = self.fixed_dims
        for box in boxes:
            try:
                P, body = guess_pose(box, self.side, self.camera, dims or DEFAULT_DIMS, towards)
            except PlacementError:
                continue
            # headings from the side's to the camera's, by the shorter way round
            turn = wrap_angle(camera_yaw(P, self.camera) - P[YAW])
            X = np.repeat(P[None], len(TURNS), axis=0)
            X[:, YAW] = wrap_angle(P[YAW] + TURNS * turn)
            likelihood = MultiViewLikelihood(self.cameras, dims or body, self.config.likelihood)
            ll = likelihood.combine(*likelihood.evaluate(X, obs))
            k = int(np.argmax(ll))
            if ll[k] > best[0]:
                best = (float(ll[k]), box, None if k == 0 else float(X[k, YAW]))
        return best[1], best[2]

    def _continue_first_search(self, obs: list[Observation], max_layers: int | None) -> Search:
        """The next layers of a first search begun on an earlier frame (:meth:`begin`): no
        prediction (the particles go on from its last layer; the person moved a frame's worth,
        well within the first search's spread), the first search's diffusion bounds and temporal
        term, its schedule continued.
        """
        init = self.config.init
        centre, wide = self._first_prior
        n = self.first_left if max_layers is None else max(1, min(self.first_left, int(max_layers)))
        done = init.layers - self.first_left
        self.first_left -= n
        steps = self.filter.steps(
            None, n_layers=n, min_std=init.min_std * wide, max_std=init.max_std * wide, first_layer=done
        )
        return Search(obs, False, steps, centre, wide, n)

    def _finish(
        self, est: Estimate, obs: list[Observation], start: bool, joints: np.ndarray | None = None
    ) -> TrackResult:
        """Score the estimate's best particle, update the prior's posterior and the lost detector."""
        X, terms, ground = self._scored
        row = np.flatnonzero((X == est.best).all(axis=1))[:1]  # the best particle of the last layer
        if len(row):
            terms, ground = terms[row], ground[row]
        else:  # not one of the particles scored last
            terms, ground = self.likelihood.evaluate(est.best[None], obs)
        cost = float(terms.sum()) / sum(not o.empty for o in obs)  # per view seen: 0 best, 3 worst
        image_ll = float(self.likelihood.combine(terms, ground)[0])
        self.predictor.update(est.mean)
        self.prev = est.mean.copy()
        # the silhouette terms S_r + S_c alone decide a collapse (``LostDetector``)
        lost = self.lost_detector.update(float(terms[0, [0, 2]].sum()) / sum(not o.empty for o in obs))
        if lost:
            self.reset()
        self.n_frames += 1
        return TrackResult(
            est.mean,
            est.best,
            forward_kinematics(est.mean, self.dims)[0].astype(np.float32) if joints is None else joints,
            est.ess,
            image_ll,
            cost,
            lost,
            start,
        )


def search_jointly(trackers: Sequence[Tracker], searches: Sequence[Search]) -> list[Estimate]:
    """Run several people's searches of one frame side by side, each layer's particles of all of
    them weighed at once (``likelihood.evaluate_joint``: one kinematics, projection and gather for
    all, where one person's search makes the same calls for its particles alone).

    Each search runs its own schedule (a first search's layers go on alone once the others are
    done) and draws its own random numbers, so each person's estimate is the one its own
    :meth:`Tracker.update` gives, up to the rounding of the batched image costs.

    Parameters
    ----------
    trackers : sequence of Tracker
        The people's trackers.
    searches : sequence of Search
        What their :meth:`Tracker.begin` returned, in the same order.

    Returns
    -------
    list of Estimate
        Each search's estimate (for :meth:`Tracker.end`).
    """
    ests: list[Estimate | None] = [None] * len(searches)
    todo = {i: next(s.steps) for i, s in enumerate(searches)}  # the first layer's particles of each
    while todo:
        ids = list(todo)
        costs = evaluate_joint(
            [trackers[i].likelihood for i in ids], [todo[i] for i in ids], [searches[i].obs for i in ids]
        )
        for i, (terms, ground) in zip(ids, costs):
            try:
                todo[i] = searches[i].steps.send(trackers[i].posterior(searches[i], todo[i], terms, ground))
            except StopIteration as stop:
                ests[i] = stop.value
                del todo[i]
    return ests  # type: ignore[return-value]


def joints_jointly(trackers: Sequence[Tracker], ests: Sequence[Estimate]) -> list[np.ndarray]:
    """The joints of several people's estimates (their means, each with its tracker's body) from one
    forward kinematics: what each :meth:`Tracker.end` computes alone, the same numbers.

    Parameters
    ----------
    trackers : sequence of Tracker
        The people's trackers (after their searches: a first search sets the body).
    ests : sequence of Estimate
        Their searches' estimates.

    Returns
    -------
    list of ndarray of shape (14, 3), dtype float32
        Each person's joints, metres, for :meth:`Tracker.end`.
    """
    if not ests:
        return []
    means = np.stack([e.mean for e in ests])
    pts = anchor_points(means, row_dims(tuple(t.dims for t in trackers), (1,) * len(ests)))
    return list(pts[:, :N_JOINTS].astype(np.float32))


def track_sequence(
    frames: Iterable[np.ndarray | None | Sequence[np.ndarray | None]],
    masks: Iterable[np.ndarray | Sequence[np.ndarray]],
    camera: Camera | Sequence[Camera],
    side: str = "left",
    **tracker_kw,
) -> dict[str, np.ndarray]:
    """Track one person offline.

    Parameters
    ----------
    frames : iterable of ndarray or None
        T images (H, W) or (H, W, 3) uint8, or None entries for mask-only tracking; with several
        cameras each entry is a list of one image (or None) per camera.
    masks : iterable of ndarray
        T (H, W) bool masks of the person (several cameras: T lists of one per camera).
    camera : Camera or sequence of Camera
        The camera, or the cameras.
    side : str
        "left" / "right": the person's side of the frame (:class:`Tracker`).
    **tracker_kw
        ``config``, ``prior``, ``dims``, ``seed`` of :class:`Tracker`.

    Returns
    -------
    dict of str to Any
        ``poses`` (T, 28), ``joints`` (T, 14, 3) float32 metres (NaN where nobody was in view),
        ``ess`` (T,), ``log_likelihood`` (T,), ``lost`` (T,) bool, ``dims`` (BodyDims).
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


__all__ = [
    "Tracker",
    "TrackerConfig",
    "APFConfig",
    "InitConfig",
    "PosteriorConfig",
    "LikelihoodConfig",
    "TrackResult",
    "Search",
    "search_jointly",
    "joints_jointly",
    "track_sequence",
    "SIDES",
    "people_problem",
]
