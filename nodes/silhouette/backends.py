"""Background subtractors behind one interface: ours (Horprasert) and OpenCV's.

``make_subtractor(name, **params)`` returns an object with

* ``apply(frame) -> (H, W) bool`` foreground mask for a uint8 BGR frame (H, W, 3); the model
  learns from every frame it is given (online, like ``cv2.BackgroundSubtractor.apply``);
* ``labels``: the class labels of the last frame, (H, W) uint8 with the codes of
  ``background`` (BACKGROUND 0, SHADOW 1, HIGHLIGHT 2, FOREGROUND 3), or None before the first
  frame; ``provides_shadows`` says whether the backend ever labels shadows (otherwise
  every pixel is BACKGROUND or FOREGROUND);
* ``name`` and ``ready`` (False while the model is still warming up and reports no foreground).

Shadows and highlights always count as background in the mask.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any, Protocol

import cv2
import numpy as np

from . import BACKEND_NAMES, kernels
from .background import BACKGROUND, FOREGROUND, SHADOW, HorprasertBackground, as_frame_stack
from .body_shadow import BodyShadowConfig, reclaim_body_shadow
from .deferred import DeferredStep
from .denoise import DenoiseConfig, frame_noise, smooth, smoothing_sigma
from .people import fit_around_people
from .samples import SampleConsensus
from .shake import ShakeConfig, ShakeEstimator, align, align_stack, unalign_labels


class Subtractor(Protocol):
    name: str
    provides_shadows: bool
    labels: np.ndarray | None

    @property
    def ready(self) -> bool: ...

    def apply(self, frame: np.ndarray) -> np.ndarray: ...


class HorprasertSubtractor:
    """Online wrapper of ``HorprasertBackground``.

    The first ``train_frames`` frames are collected (no foreground is reported for them) and the
    model is fitted on them, robustly by default because people may already be in view, and with
    ``people_aware`` around the people that ``detector`` finds in them, so that people who
    stand still through training are not learnt as the room (``people.fit_around_people``);
    after that each frame is classified and then blended into the model (``update``).
    ``fit(frames)`` instead trains at once, e.g. from a recording of the empty scene.

    Parameters
    ----------
    train_frames : int, default=30
        Number of frames collected before the model is fitted; at least 2.
    robust : bool, default=True
        Fit robustly (people may already be in view).
    people_aware : bool, default=True
        With ``robust``, fit around the people the detector finds (``people.fit_around_people``).
    detector : object or None, default=None
        People detector; None: ``people.people_detector()``, OpenCV's HOG people detector.
    dynamic : bool, default=True
        A ``samples.SampleConsensus`` model (ViBe-like sample sets with a blink-adapted radius) sits
        beside the statistics, and a pixel they call foreground is background when its colour is one
        the pixel has shown as background before (leaves, water, flicker); the shadow and highlight
        classes are the statistics' own.
    sample_params : dict or None, default=None
        Parameters of the ``samples.SampleConsensus`` model.
    threaded : bool, default=True
        Blend each frame into the model (``HorprasertBackground.update``, which that frame's labels
        do not need) in a worker thread while the caller goes on with the labels; the next frame
        (and a read of ``model``) waits for it first, so the results are the same as without. On
        two cores this hides most of the update's cost.
    body_shadow : BodyShadowConfig or None, default=None
        Which shadow labels inside a body (dark clothes, hair) are published as foreground
        (``body_shadow.reclaim_body_shadow``); None: ``BodyShadowConfig()`` (the node's default),
        ``BodyShadowConfig(span_px=0)``: none. The model learns from the labels before this step.
    shake : ShakeConfig or None, default=None
        Follow camera shake (``shake.ShakeEstimator``): each frame's shift against the model is
        estimated, with the pixels of the last frame's foreground left out, and the frame is
        resampled onto the model's pixels before it is classified (the labels are moved back onto
        the frame's); the training frames are aligned on one another (``shake.align_stack``).
        None: ``ShakeConfig()``;
        ``False``: off (a camera known to be still).
    denoise : DenoiseConfig or None or bool, default=None
        Smooth the frames of a noisy camera before they are compared (``denoise``): the noise is
        measured on the training frames, and frames noisier than its floor are smoothed, at the fit
        and after it, by ``smoothing_sigma_`` pixels. None: ``DenoiseConfig()``; ``False``: never.
    fit_in_background : bool, default=False
        Fit on the collected training frames in a thread of its own and return at once: the
        frames that come while it runs get no foreground (``ready`` False) and are not learnt; the
        first frame after it has finished is classified. For a live graph, which then keeps
        publishing through the training instead of stalling on one long call; the frames the
        fit overlaps depend on timing, so replays that must repeat exactly leave it off.
    **model_params : Any
        Go to ``HorprasertBackground.from_params`` (the names of its configs' fields).

    Raises
    ------
    ValueError
        If ``train_frames < 2`` or a model or sample parameter is unknown or invalid.
    """

    name = "horprasert"
    provides_shadows = True

    def __init__(
        self,
        train_frames: int = 30,
        robust: bool = True,
        people_aware: bool = True,
        detector: Any = None,
        dynamic: bool = True,
        sample_params: dict[str, Any] | None = None,
        threaded: bool = True,
        body_shadow: BodyShadowConfig | None = None,
        shake: ShakeConfig | None | bool = None,
        denoise: DenoiseConfig | None | bool = None,
        fit_in_background: bool = False,
        **model_params: Any,
    ) -> None:
        if train_frames < 2:
            raise ValueError(f"horprasert: train_frames must be >= 2, got {train_frames}")
        try:
            self._model = HorprasertBackground.from_params(**model_params)
        except ValueError as exc:
            raise ValueError(f"horprasert: {exc}") from None
        self.train_frames = train_frames
        self.robust = robust
        self.people_aware = people_aware
        self.detector = detector
        try:
            self.samples = SampleConsensus(**(sample_params or {})) if dynamic else None
        except TypeError as exc:
            raise ValueError(f"horprasert: unknown sample_params parameter ({exc})") from None
        self.labels: np.ndarray | None = None
        #: boxes (K, 4) of people known to stand in the first training frame (``fit_around_people``)
        self.hints: np.ndarray | None = None
        self._unseen_fg: np.ndarray | None = None  # FOREGROUND where the fit filled the room in
        self._buffer: list[np.ndarray] = []
        self.fit_in_background = fit_in_background
        self._fitting: Future | None = None  # the fit running in the background, until collected
        self.threaded = threaded
        self.body_shadow = BodyShadowConfig() if body_shadow is None else body_shadow
        if shake is True:
            shake = None
        self.shake = None if shake is False else ShakeEstimator(shake)
        self.denoise = None if denoise is False else (DenoiseConfig() if denoise in (None, True) else denoise)
        #: the camera's noise over the training frames (grey levels, ``denoise.frame_noise``) and the
        #: Gaussian (pixels) every frame is smoothed by before it is compared (0: none), set by the fit
        self.noise_ = 0.0
        self.smoothing_sigma_ = 0.0
        #: model pixels to leave out of the next frame's shift (:func:`moving_pixels`)
        self._moving: np.ndarray | None = None
        self._deferred = DeferredStep("horprasert-update")
        if self.samples is not None:
            # one worker thread learns for both models, the update first (the next frame's
            # labels wait for it), the samples after (the next frame's veto waits for them)
            self.samples.share_worker(self._deferred)

    @property
    def model(self) -> HorprasertBackground:
        """The statistical model, once the last frame's update is done."""
        self._deferred.join()
        return self._model

    def __getstate__(self) -> dict[str, Any]:
        self._collect_fit()
        self._deferred.join()  # before any array it writes is copied
        return self.__dict__.copy()

    @property
    def ready(self) -> bool:
        return self._model.is_fitted and self._fitting is None

    @property
    def colour_kind(self) -> tuple[bool, float]:
        """Whether the fitted model is of monochrome footage, and its bound of such footage
        (``ShadowConfig.mono_chroma_deg``, degrees); both are set by the fit alone, so no pending
        update is waited for.
        """
        return self._model.monochrome_, self._model.shadows.mono_chroma_deg

    @property
    def fitting(self) -> bool:
        """Whether a background fit (``fit_in_background``) was started and its model is not in
        use yet (it may have finished: the next frame takes it up).
        """
        return self._fitting is not None

    def _collect_fit(self) -> None:
        """Wait for a background fit, if any, and re-raise its error."""
        if self._fitting is not None:
            fut, self._fitting = self._fitting, None
            fut.result()

    def fit(self, frames: np.ndarray | list[np.ndarray], robust: bool | None = None) -> HorprasertSubtractor:
        """Fit the model on training frames.

        Robust (people may be in view) and ``people_aware``: the people are detected and the room
        around them learnt (``people.fit_around_people``); robust alone: the per-pixel median.

        Parameters
        ----------
        frames : ndarray of shape (N, H, W, 3) or list of ndarray of shape (H, W, 3)
            uint8 BGR training frames.
        robust : bool or None, default=None
            Fit robustly; None: the ``robust`` given at construction.

        Returns
        -------
        HorprasertSubtractor
            self, fitted.
        """
        stack = as_frame_stack(frames)
        if self.shake is not None:
            stack = align_stack(stack, self.shake.config)
            self.shake.last, self._moving = None, None
        # measured on the aligned frames: a shake left in them would pass for noise at every edge
        self.noise_ = frame_noise(stack)
        self.smoothing_sigma_ = 0.0 if self.denoise is None else smoothing_sigma(self.noise_, self.denoise)
        if self.smoothing_sigma_ > 0:
            stack = np.stack([smooth(f, self.smoothing_sigma_) for f in stack])
        robust = self.robust if robust is None else robust
        if robust and self.people_aware:
            fit_around_people(self.model, stack, detector=self.detector, hints=self.hints)
        else:
            self.model.fit(stack, robust=robust)
        if self.samples is not None:
            # only what the fitted model calls plain background enters the samples: people, and
            # the dark clothes it takes for shadows, stay out
            fg = np.stack([self.model.apply(f) != BACKGROUND for f in stack])
            unseen = self.model.unseen_
            if unseen is not None and unseen.any():
                # where someone stood through training the room was filled in: no sample there
                # shows it, and the person who most likely still stands there must not be learnt
                fg |= unseen[None]
            self.samples.fit(stack, self.model.mean_, fg)
            self._unseen_fg = (
                np.where(unseen, FOREGROUND, 0).astype(np.uint8) if unseen is not None and unseen.any() else None
            )
        self._buffer = []
        kernels.warm()  # here (in the fit's thread when in the background), not on the first frames
        return self

    def apply(self, frame: np.ndarray) -> np.ndarray:
        """Classify a frame and learn from it (collect it while training).

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3)
            uint8 BGR frame.

        Returns
        -------
        ndarray of shape (H, W)
            bool foreground mask; all False while training frames are still being collected.

        Raises
        ------
        ValueError
            If ``frame`` is not uint8 (H, W, 3).
        """
        if self._fitting is not None:
            if not self._fitting.done():
                self.labels = np.full(frame.shape[:2], BACKGROUND, np.uint8)
                return np.zeros(frame.shape[:2], bool)
            self._collect_fit()
        if not self.model.is_fitted:
            if frame.dtype != np.uint8 or frame.ndim != 3 or frame.shape[2] != 3:
                raise ValueError(f"frame must be uint8 (H, W, 3) BGR, got {frame.shape} {frame.dtype}")
            self._buffer.append(frame.copy())
            if len(self._buffer) < self.train_frames:
                self.labels = np.full(frame.shape[:2], BACKGROUND, np.uint8)
                return np.zeros(frame.shape[:2], bool)
            if self.fit_in_background:
                # the model and the buffer are the fit's alone until it is collected: this thread
                # only looks at the future until then
                pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="horprasert-fit")
                self._fitting = pool.submit(self.fit, self._buffer)
                pool.shutdown(wait=False)
                self.labels = np.full(frame.shape[:2], BACKGROUND, np.uint8)
                return np.zeros(frame.shape[:2], bool)
            self.fit(self._buffer)
        if self.smoothing_sigma_ > 0:
            frame = smooth(frame, self.smoothing_sigma_)  # a new array, the worker's own
        elif self.threaded:
            # the worker reads the frame after this returns, when the caller may have reused it;
            # the same copy goes to apply, whose per-frame terms update reuses (they are keyed
            # by the frame object)
            frame = frame.copy()
        # the last frame's update (in the worker) writes the arrays the classes are computed from
        self._deferred.join()
        shift = None
        if self.shake is not None:
            shift = self.shake.shift(self._model.mean_, frame, self._moving)
            if shift is not None:
                frame = align(frame, shift)  # a new array: the copy above is not needed for it
        if self._model.follow_exposure(frame) is not None and self.shake is not None:
            self.shake.renew()  # its reference is the model's brightness as it was
        if self.samples is None:
            stats = self._model.apply(frame)
            labels = stats
        else:
            stats = self._model.classify(frame)
            labels, fg_idx = self._veto_and_texture_test(frame, stats)
            if self._unseen_fg is not None:
                # no veto where the room was filled in (see ``HorprasertBackground.unseen_``)
                cv2.max(labels, cv2.bitwise_and(stats, self._unseen_fg), dst=labels)
        # the FOREGROUND pixels of these labels, found once for the update and the body-shadow
        # step: the veto's own where the labels are the vetoed ones unchanged
        learns = self._model.learns_next
        if self.samples is not None and self._unseen_fg is None:
            labels_fg = fg_idx
        elif learns or self.body_shadow.span_px > 0:
            labels_fg = np.flatnonzero(labels.reshape(-1) == FOREGROUND)  # on bool: faster than 0 / 255
        else:
            labels_fg = None
        # the leg step compares with the background grey levels this frame was classified against:
        # the update replaces that array (it does not write into it), so it is taken before
        grey = self._model.grey_
        if self.threaded and learns:
            self._deferred.submit(self._model.update, frame, labels.copy(), labels_fg)
        else:
            # in line too when the model does not learn from this frame (it only counts it)
            self._model.update(frame, labels, labels_fg)
        if self.samples is not None:
            # the frame is this call's own copy when threaded, and the statistics' labels are
            # not changed again: the samples' worker may read both as they are
            self.samples.learn(frame, stats, fg_idx, copy=not self.threaded)
        labels = reclaim_body_shadow(labels, self.body_shadow, frame, grey, self._model.unseen_, labels_fg)
        if self.shake is not None:
            self._moving = moving_pixels(labels)
            if shift is not None:
                labels = unalign_labels(labels, shift, BACKGROUND)
        self.labels = labels
        return labels == FOREGROUND

    def _veto_and_texture_test(self, frame: np.ndarray, stats: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The statistics' texture test (``HorprasertBackground.shadow_texture_mismatch``) and the
        samples' veto (``SampleConsensus.veto``) of ``stats``, the frame's classes before the
        texture test; ``stats`` gets the texture test's FOREGROUND pixels in place.

        The veto of the classes' own foreground does not depend on the texture test, which only
        turns shadows into foreground: the few pixels the test turns are vetoed after. The match
        of a pixel does not depend on which other pixels are tested with it, so the labels are
        those of the veto after the test.

        Returns
        -------
        labels : ndarray of shape (H, W), dtype uint8
            The vetoed labels (a new array).
        fg_idx : ndarray of shape (K,), dtype int64
            Ascending flat indices of their FOREGROUND pixels, for ``SampleConsensus.learn``.
        """
        # The test runs in this thread, before the veto: the veto waits for the samples' learning
        # from the last frame, which the worker thread is most likely still busy with. (In the
        # worker, the test queued behind that learning, and this thread waited for both in turn.)
        turned = self._model.shadow_texture_mismatch(stats)
        labels, fg_idx = self.samples.veto(frame, stats)
        if turned.size:
            stats.reshape(-1)[turned] = FOREGROUND
            ok = self.samples.explained(frame, turned)
            labels.reshape(-1)[turned] = np.where(ok, BACKGROUND, FOREGROUND)
            fg_idx = np.sort(np.concatenate([fg_idx, turned[~ok]]))
        return labels, fg_idx


#: the opening of :func:`moving_pixels`
_OPEN = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))


def moving_pixels(labels: np.ndarray) -> np.ndarray | None:
    """The pixels a frame's shift is not estimated on (grown there by ``ShakeConfig.grow_px``): the
    last frame's FOREGROUND regions, opened (the thin lines along the room's edges that a frame
    classified against a shifted room shows are not people); None when there are none.
    """
    fg = (labels == FOREGROUND).view(np.uint8)
    fg = cv2.morphologyEx(fg, cv2.MORPH_OPEN, _OPEN)
    return fg.view(bool) if cv2.countNonZero(fg) else None


class OpenCVSubtractor:
    """Any ``cv2.BackgroundSubtractor``; its 255 / 127 / 0 output becomes FOREGROUND / SHADOW /
    BACKGROUND.

    Parameters
    ----------
    name : str
        Backend name.
    subtractor : cv2.BackgroundSubtractor
        The OpenCV subtractor.
    provides_shadows : bool
        Whether the subtractor labels shadows (127).
    learning_rate : float, default=-1.0
        Passed to ``apply`` (-1: the subtractor's own schedule).
    """

    def __init__(self, name: str, subtractor: Any, provides_shadows: bool, learning_rate: float = -1.0) -> None:
        self.name = name
        self.subtractor = subtractor
        self.provides_shadows = provides_shadows
        self.learning_rate = learning_rate
        self.labels: np.ndarray | None = None
        self._lut = np.full(256, BACKGROUND, np.uint8)
        self._lut[255] = FOREGROUND
        if provides_shadows:
            self._lut[127] = SHADOW

    @property
    def ready(self) -> bool:
        return self.labels is not None

    def apply(self, frame: np.ndarray) -> np.ndarray:
        """Classify a frame and learn from it.

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3)
            uint8 BGR frame.

        Returns
        -------
        ndarray of shape (H, W)
            bool foreground mask.

        Raises
        ------
        ValueError
            If ``frame`` is not a uint8 (H, W, 3) array.
        """
        if not isinstance(frame, np.ndarray) or frame.dtype != np.uint8 or frame.ndim != 3:
            raise ValueError(f"frame must be uint8 (H, W, 3) BGR, got {getattr(frame, 'shape', None)}")
        raw = self.subtractor.apply(frame, learningRate=self.learning_rate)
        self.labels = self._lut[raw]
        return raw == 255


def _create(name: str, fn: Callable[..., Any], params: dict[str, Any]) -> Any:
    try:
        return fn(**params)
    except (TypeError, cv2.error) as exc:
        raise ValueError(
            f"{name}: cannot create the subtractor with parameters {sorted(params)}; use the "
            f"keyword names of cv2 {fn.__name__} ({exc})"
        ) from None


def make_subtractor(name: str, **params: Any) -> Subtractor:
    """Build a background subtractor by name.

    Parameters
    ----------
    name : str
        One of ``BACKEND_NAMES`` (any case). ``horprasert``: our ``HorprasertSubtractor``.
        ``mog2`` / ``knn``: cv2.createBackgroundSubtractorMOG2 / KNN with ``detectShadows=True``
        unless given. ``cnt`` / ``gsoc``: cv2.bgsegm.createBackgroundSubtractorCNT / GSOC (no shadow
        class).
    **params : Any
        ``horprasert``: train_frames, robust and any ``HorprasertBackground`` parameter; the OpenCV
        backends: OpenCV's keyword names (e.g. history, varThreshold, dist2Threshold) plus
        learning_rate.

    Returns
    -------
    Subtractor
        The subtractor.

    Raises
    ------
    ValueError
        For an unknown name or parameter, or when ``cnt`` / ``gsoc`` lack cv2.bgsegm.
    """
    key = name.lower() if isinstance(name, str) else name
    if key not in BACKEND_NAMES:
        raise ValueError(f"unknown background subtractor {name!r}; valid names: {', '.join(BACKEND_NAMES)}")
    if key == "horprasert":
        return HorprasertSubtractor(**params)
    params = dict(params)
    lr = float(params.pop("learning_rate", -1.0))
    if key in ("mog2", "knn"):
        params.setdefault("detectShadows", True)
        fn = cv2.createBackgroundSubtractorMOG2 if key == "mog2" else cv2.createBackgroundSubtractorKNN
        sub = _create(key, fn, params)
        return OpenCVSubtractor(key, sub, provides_shadows=bool(params["detectShadows"]), learning_rate=lr)
    if not hasattr(cv2, "bgsegm"):
        raise ValueError(f"{key} needs cv2.bgsegm: install opencv-contrib-python-headless")
    fn = cv2.bgsegm.createBackgroundSubtractorCNT if key == "cnt" else cv2.bgsegm.createBackgroundSubtractorGSOC
    return OpenCVSubtractor(key, _create(key, fn, params), provides_shadows=False, learning_rate=lr)
