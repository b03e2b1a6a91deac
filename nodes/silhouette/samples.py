"""Sample-consensus background model for dynamic backgrounds, beside the Horprasert statistics.

A single mean colour per pixel (Horprasert's E) cannot hold a background that takes several
colours: leaves that wave in front of the sky, ripples on water, a flickering screen. Here each
pixel also keeps ``n_samples`` colours it has shown as background (ViBe: Barnich & Van Droogenbroeck,
"ViBe: a universal background subtraction algorithm for video sequences", IEEE TIP 2011), and a
pixel the statistical model calls foreground is background after all when its colour lies within
R(x) of at least ``min_matches`` of them (ViBe's consensus, eq. 1 of the paper:
#{S_k : dist(I, S_k) < R} >= #min, distance L1 over the three channels here).

Updates are ViBe's conservative, random and spatially diffused ones: a background pixel replaces
one of its samples, chosen at random, with probability 1 / ``subsampling``, and with the same
probability one sample of a random 8-neighbour (so a ghost at the edge of the background is eaten
from its rim, and a sample set keeps memories of every age with an exponentially decaying
chance). Foreground pixels never enter the samples.

The radius is each pixel's own (SuBSENSE: St-Charles, Bilodeau & Bergevin, IEEE TIP 2015, whose
R(x) follows the pixel's background dynamics D_min(x)): R(x) = max(radius, spread_k d(x)) +
relative_radius |S_k|_1, with d(x) the mean L1 distance between a background observation and the
pixel's samples. A plain wall under a clean camera keeps a tight radius, so a grey head in front of
it is not taken for the wall; leaves, water and compression noise get a wide one. The brightness
term covers a change of light, which moves a colour in proportion to it. A pixel whose foreground
label keeps switching on and off ("blinking", eq. 5 of that paper) is in a dynamic region and its
radius grows by the blink level v(x): it rises by ``blink_gain`` on every switch and decays by
``blink_decay`` per frame.

Only the pixels the statistical model calls foreground are tested (a few percent of a frame), so
the cost per frame is small. Frames are uint8 BGR (H, W, 3).
"""

from __future__ import annotations

from typing import Any

import cv2
import numpy as np

from . import kernels
from .deferred import DeferredStep

#: opening that keeps solid foreground (not speckle) and the dilation around it, for the blinks
_OPEN = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (3, 3))
_NEAR = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (7, 7))
# their offsets (dy, dx) from the centre, as ``kernels.feedback`` takes them
_OFFSETS = tuple(np.nonzero(k)[i].astype(np.int64) - k.shape[i] // 2 for k in (_OPEN, _NEAR) for i in (0, 1))


class SampleConsensus:
    """Per-pixel sample sets with consensus matching (ViBe) and a blink-adapted radius (SuBSENSE).

    Parameters
    ----------
    n_samples : int, default=20
        Colours kept per pixel (ViBe's N, 20 in the paper).
    min_matches : int, default=2
        Samples that must lie within the radius for a match (#min, 2 in the paper), in [1, n_samples].
    radius, relative_radius, spread_k : float, default=0.5, 0.025, 0.75
        Matching radius R = max(radius, spread_k * d(x)) + relative_radius * |S_k|_1 for sample S_k,
        L1 distance over B, G, R in grey levels. d(x) is the pixel's own spread: the mean L1 distance
        between a background observation and its samples (SuBSENSE's D_min idea), initialised from
        consecutive training frames and followed at ``spread_rate`` on the pixels drawn for an update.
        A clean camera on a plain wall gets a tight radius (a grey head in front of a grey wall stays a
        person), leaves or compression noise a wide one. ViBe uses a fixed 20 on grey images;
        ``relative_radius`` models noise that grows with brightness.
    spread_rate : float, default=0.1
        Running-average rate of d(x), per update of the pixel (about every ``subsampling`` frames), in
        (0, 1].
    max_radius_gain : float, default=2.5
        Largest R(x) / radius in blinking regions (>= 1).
    subsampling : int, default=16
        1 / probability of an update at each background pixel in a dynamic region (blink level
        v(x) > 0: its label switched in the last frames), phi (16 in the paper).
    quiet_subsampling : int or None, default=None
        The same at the other (quiet) pixels, >= ``subsampling``: most of a frame, where the
        statistics alone are right and the samples are only a veto. None: twice ``subsampling``
        (32), which halves the update's cost while a dynamic region, where the samples matter,
        still learns at 1 / ``subsampling``.
    blink_gain, blink_decay : float, default=0.1, 0.005
        Rise of the blink level v(x) on a label switch and its decay per frame;
        R(x) = radius * (1 + v(x)), v(x) in [0, max_radius_gain - 1].
    learn_blink : float, default=0.5
        A pixel the statistics call foreground is learnt (and receives its neighbours' colours) only
        where the blink level v(x) is at least this: in a dynamic region. Elsewhere a person whose colour
        happens to match would be learnt and match better the next time.
    random_state : int or None, default=0
        Seed of the random updates.
    threaded : bool, default=True
        Learn from a frame (the sample updates and the blink levels, which the veto of that frame
        does not need) in a worker thread while the caller goes on with the frame; the next call
        (and every attribute read) waits for it first, so the results are the same as without.
        On two cores this hides most of the model's cost.

    Attributes
    ----------
    samples_ : ndarray of shape (H * W, 3, n_samples), dtype uint8
        Per pixel the B, G, R rows of its samples.
    radius_ : ndarray of shape (H, W), dtype float32
        Radius gain 1 + v(x).
    spread_ : ndarray of shape (H, W), dtype float32
        d(x), grey levels (L1).

    Raises
    ------
    ValueError
        For a parameter out of range, naming it.
    """

    def __init__(
        self,
        n_samples: int = 20,
        min_matches: int = 2,
        radius: float = 0.5,
        relative_radius: float = 0.025,
        spread_k: float = 0.75,
        spread_rate: float = 0.1,
        max_radius_gain: float = 2.5,
        subsampling: int = 16,
        quiet_subsampling: int | None = None,
        blink_gain: float = 0.1,
        blink_decay: float = 0.005,
        learn_blink: float = 0.5,
        random_state: int | None = 0,
        threaded: bool = True,
    ) -> None:
        if n_samples < 1:
            raise ValueError(f"n_samples must be >= 1, got {n_samples}")
        if not 1 <= min_matches <= n_samples:
            raise ValueError(f"min_matches must be in [1, n_samples={n_samples}], got {min_matches}")
        if radius <= 0:
            raise ValueError(f"radius must be > 0 grey levels (L1 over 3 channels), got {radius}")
        if max_radius_gain < 1.0:
            raise ValueError(f"max_radius_gain must be >= 1, got {max_radius_gain}")
        if subsampling < 1:
            raise ValueError(f"subsampling must be >= 1 (1 / update probability), got {subsampling}")
        if quiet_subsampling is None:
            quiet_subsampling = 2 * subsampling
        if quiet_subsampling < subsampling:
            raise ValueError(f"quiet_subsampling must be >= subsampling={subsampling}, got {quiet_subsampling}")
        if blink_gain < 0 or blink_decay < 0:
            raise ValueError(f"blink_gain and blink_decay must be >= 0, got {blink_gain}, {blink_decay}")
        self.n_samples = n_samples
        self.min_matches = min_matches
        self.radius = radius
        if relative_radius < 0:
            raise ValueError(f"relative_radius must be >= 0, got {relative_radius}")
        self.relative_radius = relative_radius
        if spread_k < 0 or not 0.0 < spread_rate <= 1.0:
            raise ValueError(f"spread_k must be >= 0 and spread_rate in (0, 1], got {spread_k}, {spread_rate}")
        self.spread_k = spread_k
        self.spread_rate = spread_rate
        self.max_radius_gain = max_radius_gain
        self.subsampling = subsampling
        self.quiet_subsampling = quiet_subsampling
        self.blink_gain = blink_gain
        self.blink_decay = blink_decay
        self.learn_blink = learn_blink
        self.random_state = random_state
        self.threaded = threaded
        self._samples: np.ndarray | None = None
        # (H * W,) uint64: per pixel the bytes B, G, R minimum, 0, B, G, R maximum, 0 over its
        # samples, kept by the update's kernels; one 8-byte word a pixel gathers fast
        self._box: np.ndarray | None = None
        self._shape: tuple[int, int] = (0, 0)
        self._deferred = DeferredStep("sample-consensus")

    def __getstate__(self) -> dict[str, Any]:
        self._deferred.join()  # before any array it writes is copied
        return self.__dict__.copy()

    @property
    def samples_(self) -> np.ndarray | None:
        """Per pixel the B, G, R rows of its samples, (H * W, 3, n_samples) uint8; None before ``fit``."""
        self._deferred.join()
        return self._samples

    @property
    def is_fitted(self) -> bool:
        return self._samples is not None

    @property
    def radius_(self) -> np.ndarray:
        """Gain of the matching radius, R(x) / R (blink feedback).

        Returns
        -------
        ndarray of shape (H, W), dtype float32
            1 + v(x).

        Raises
        ------
        RuntimeError
            When not fitted.
        """
        self._deferred.join()
        if self._samples is None:
            raise RuntimeError("SampleConsensus is not fitted: call fit(frames, background) first")
        return (1.0 + self._blink).reshape(self._shape)

    @property
    def spread_(self) -> np.ndarray:
        """Spread d(x) of each pixel's background.

        Returns
        -------
        ndarray of shape (H, W), dtype float32
            Mean L1 distance in grey levels.

        Raises
        ------
        RuntimeError
            When not fitted.
        """
        self._deferred.join()
        if self._samples is None:
            raise RuntimeError("SampleConsensus is not fitted: call fit(frames, background) first")
        return self._spread.reshape(self._shape)

    def fit(self, frames: np.ndarray, background: np.ndarray, foreground: np.ndarray | None = None) -> SampleConsensus:
        """Fill the sample sets from training frames.

        Sample k comes from frame k mod N; where ``foreground`` marks a pixel that may not show the
        background in that frame (the statistical model's verdict), the background colour is used
        instead, so no one who walked through the training frames is remembered as background.

        Parameters
        ----------
        frames : ndarray of shape (N, H, W, 3), dtype uint8
            BGR training frames.
        background : ndarray of shape (H, W, 3)
            Background colour (e.g. Horprasert's E), grey levels.
        foreground : ndarray of shape (N, H, W), dtype bool, optional
            Pixels that may not show the background in each frame.

        Returns
        -------
        SampleConsensus
            self, fitted.

        Raises
        ------
        ValueError
            For arrays of the wrong shape or dtype.
        """
        self._deferred.join()
        frames = np.asarray(frames)
        if frames.ndim != 4 or frames.shape[-1] != 3 or frames.dtype != np.uint8:
            raise ValueError(f"frames must be (N, H, W, 3) uint8 BGR, got {frames.shape} {frames.dtype}")
        n, h, w, _ = frames.shape
        bg = np.clip(np.rint(np.asarray(background, np.float32)), 0, 255).astype(np.uint8)
        if bg.shape != (h, w, 3):
            raise ValueError(f"background must be (H, W, 3) = {(h, w, 3)}, got {bg.shape}")
        if foreground is not None and np.shape(foreground) != (n, h, w):
            raise ValueError(f"foreground must be (N, H, W) bool = {(n, h, w)}, got {np.shape(foreground)}")
        self._rng = np.random.default_rng(self.random_state)
        self._shape = (h, w)
        # (H * W, 3, N): the test gathers K pixels as K contiguous rows of 3 N bytes (a strided
        # gather from each of 3 N planes took twice as long) and adds the channels as views
        samples = np.empty((h * w, 3, self.n_samples), np.uint8)
        flat_bg = bg.reshape(-1, 3)
        for k in range(self.n_samples):
            j = k % n
            s = frames[j].reshape(-1, 3).copy()
            if foreground is not None:
                s[np.asarray(foreground[j]).reshape(-1)] = flat_bg[np.asarray(foreground[j]).reshape(-1)]
            samples[:, :, k] = s
        self._samples = samples
        self._box = np.zeros(h * w, np.uint64)
        self._set_box(np.arange(h * w))
        # d(x): the mean L1 distance of one background observation from another; consecutive
        # training samples give it (noise and any motion of the background between frames)
        nxt = np.roll(samples, -1, axis=2).astype(np.int16)
        gap = np.abs(nxt - samples).sum(axis=1, dtype=np.float32)  # (H * W, N)
        self._spread = gap[:, : max(1, min(n, self.n_samples) - 1)].mean(axis=1)
        self._blink = np.zeros(h * w, np.float32)
        self._prev_fg = np.zeros(h * w, np.uint8)
        self._prev_idx = np.zeros(0, np.int64)  # flat indices of the nonzero pixels of _prev_fg
        return self

    def explained(self, frame: np.ndarray, idx: np.ndarray) -> np.ndarray:
        """Whether each pixel of flat indices ``idx`` matches its sample set.

        ViBe's test: at least ``min_matches`` of the samples within L1 distance R(x) of the colour.

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3), dtype uint8
            BGR frame.
        idx : ndarray of shape (K,), dtype int
            Flat pixel indices.

        Returns
        -------
        ndarray of shape (K,), dtype bool
            True where the colour matches the pixel's samples.

        Raises
        ------
        RuntimeError
            When not fitted.
        """
        self._deferred.join()
        if self._samples is None:
            raise RuntimeError("SampleConsensus is not fitted: call fit(frames, background) first")
        if idx.size == 0:
            return np.zeros(0, bool)
        # one compiled pass (``kernels.explained``): the box prefilter, then the samples' test
        return kernels.explained(idx, frame.reshape(-1, 3), *self._veto_terms())

    def _veto_terms(self) -> tuple[Any, ...]:
        """The model's arrays and constants as ``kernels.explained`` and ``kernels.veto`` take them."""
        n = self.n_samples
        return (
            self._samples.reshape(-1, 3 * n),
            _box_bytes(self._box),
            self._blink,
            self._spread,
            np.float32(self.radius),
            np.float32(self.spread_k),
            np.float32(self.relative_radius),
            self.min_matches,
        )

    def apply(self, frame: np.ndarray, labels: np.ndarray) -> np.ndarray:
        """Veto the statistical model's foreground where the samples explain the colour, and learn.

        After the veto the samples of BACKGROUND pixels are updated (ViBe's random, diffused update) and
        the blink levels (SuBSENSE feedback) follow the final foreground: ``veto`` then ``learn``.

        Parameters
        ----------
        frame, labels : ndarray
            As for ``veto``: the (H, W, 3) uint8 BGR frame and its (H, W) uint8 Horprasert classes.

        Returns
        -------
        ndarray of shape (H, W), dtype uint8
            The labels with FOREGROUND pixels that match their sample set turned to BACKGROUND (a new
            array). Errors: as ``veto``'s.
        """
        out, fg_idx = self.veto(frame, labels)
        self.learn(frame, labels, fg_idx)
        return out

    def veto(self, frame: np.ndarray, labels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The first half of ``apply``: the labels with the explained foreground turned to
        BACKGROUND, without learning.

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3), dtype uint8
            BGR frame, of the fitted size.
        labels : ndarray of shape (H, W), dtype uint8
            Horprasert classes of ``frame``.

        Returns
        -------
        out : ndarray of shape (H, W), dtype uint8
            The vetoed labels (a new array).
        fg_idx : ndarray of shape (K,), dtype int
            Flat indices of the FOREGROUND pixels left, for ``learn``.

        Raises
        ------
        RuntimeError
            When not fitted.
        ValueError
            When ``frame`` or ``labels`` is not of the fitted size.
        """
        if self._samples is None:
            raise RuntimeError("SampleConsensus is not fitted: call fit(frames, background) first")
        if frame.shape[:2] != self._shape or labels.shape != self._shape:
            raise ValueError(
                f"frame and labels must be {self._shape} (the fitted size), got {frame.shape[:2]} and {labels.shape}"
            )
        self._deferred.join()
        # one compiled pass over the labels: the FOREGROUND pixels, each tested as ``explained`` does
        out, fg_idx = kernels.veto(np.ascontiguousarray(labels).reshape(-1), frame.reshape(-1, 3), *self._veto_terms())
        return out.reshape(self._shape), fg_idx

    def learn(self, frame: np.ndarray, labels: np.ndarray, fg_idx: np.ndarray, copy: bool = True) -> None:
        """The second half of ``apply``: learn from the frame, in the worker thread when ``threaded``.

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3), dtype uint8
            BGR frame, of the fitted size.
        labels : ndarray of shape (H, W), dtype uint8
            Horprasert classes of ``frame`` (before the veto).
        fg_idx : ndarray of shape (K,), dtype int
            The foreground left after the veto, as ``veto`` returns it.
        copy : bool, default=True
            The worker learns from copies of ``frame`` and ``labels``; False when the caller
            changes neither of them again.
        """
        flat = labels.reshape(-1)
        if self.threaded:
            # the caller may reuse its buffers once this returns: the worker learns from copies
            if copy:
                frame, flat = frame.copy(), flat.copy()
            self._deferred.submit(self._learn, frame, flat, fg_idx)
        else:
            self._learn(frame, flat, fg_idx)

    def share_worker(self, step: DeferredStep) -> None:
        """Learn in ``step``'s worker thread, after the calls it was given before (see
        ``deferred.DeferredStep``).

        Parameters
        ----------
        step : DeferredStep
            The step whose worker runs this model's learning.
        """
        self._deferred.join()
        self._deferred = DeferredStep("sample-consensus", share_with=step)

    def _learn(self, frame: np.ndarray, flat_labels: np.ndarray, fg_idx: np.ndarray) -> None:
        """ViBe's update from ``frame`` (H, W, 3) with the statistics' flat labels (H * W,), then the
        blink feedback of the final foreground ``fg_idx`` (flat indices).
        """
        # Learnt: what the statistics call background, and anything in a dynamic (blinking)
        # region, where a colour seen again and again is background whichever model missed it.
        # Elsewhere a person whose colour happens to match would be learnt, match better the
        # next time, and spread.
        self._update(frame, flat_labels)
        self._feedback(fg_idx)

    def _update(self, frame: np.ndarray, flat_labels: np.ndarray) -> None:
        """ViBe's conservative update: each learnable pixel (``kernels.learnable``: BACKGROUND in the
        statistics' ``flat_labels`` (H * W,), or a blink level of at least ``learn_blink``), with
        probability 1/phi, writes its colour over a random sample of its own and, independently, of
        a random 8-neighbour that is learnable too. phi is ``subsampling`` in dynamic regions
        (blink level > 0) and ``quiet_subsampling`` elsewhere.
        """
        h, w = self._shape
        npx = h * w
        m = max(1, npx // self.quiet_subsampling)
        rng = self._rng
        px = frame.reshape(-1, 3)
        # the dynamic region's pixels get draws of their own, up to a rate of 1 / subsampling
        active = np.flatnonzero(self._blink > 0.0) if self.quiet_subsampling > self.subsampling else None
        extra = 0.0 if active is None else active.size * (1.0 / self.subsampling - 1.0 / self.quiet_subsampling)
        # the blink levels are read before this frame's feedback changes them
        labels, blink, level = flat_labels, self._blink, np.float32(self.learn_blink)
        samples, box = self._samples.reshape(h * w, -1), _box_bytes(self._box)
        for own in (True, False):
            # draw phi-subsampled candidates (with replacement: a pixel drawn twice is harmless)
            cand = rng.integers(0, npx, size=m)
            if extra > 0.0:
                more = int(extra) + int(rng.random() < extra - int(extra))
                cand = np.concatenate([cand, active[rng.integers(0, active.size, size=more)]])
            cand = kernels.learnable(cand, labels, blink, level)
            if cand.size == 0:
                continue
            k = rng.integers(0, self.n_samples, size=cand.size)
            # one compiled pass over the drawn pixels each (spread, write, box), without the GIL
            if own:
                rate = np.float32(self.spread_rate)
                kernels.learn_own(samples, box, self._spread, px, cand, k, rate, self.spread_k > 0.0)
                continue
            # only into background neighbours: ViBe's diffusion into foreground eats a person
            # who stands still from their rim; uncovered room (ghosts) is the statistics' job
            j = rng.integers(0, 8, size=cand.size)
            kernels.learn_neighbours(samples, box, px, cand, k, j, h, w, labels, blink, level)

    def _set_box(self, pixels: np.ndarray) -> None:
        """The box of the samples of the flat pixels ``pixels`` (M,), into ``_box``."""
        n = self.n_samples
        # the samples as (N, 3 M) rows (OpenCV's transpose): min and max over the first axis run
        # along rows (numpy's reduction over a short last axis is several times slower)
        rows = cv2.transpose(np.take(self._samples.reshape(-1, 3 * n), pixels, axis=0).reshape(-1, n))
        box = np.zeros((pixels.size, 8), np.uint8)
        box[:, :3] = rows.min(axis=0).reshape(-1, 3)
        box[:, 4:7] = rows.max(axis=0).reshape(-1, 3)
        self._box[pixels] = box.view(np.uint64).reshape(-1)

    def _feedback(self, fg_idx: np.ndarray) -> None:
        """SuBSENSE's blink level: v(x) += blink_gain where the foreground label switched since
        the last frame, v(x) -= blink_decay elsewhere, v in [0, max_radius_gain - 1].

        As in SuBSENSE, switches in and around the solid foreground of the last frame (its
        opening, dilated) do not count: the outline of a person who moves or fidgets switches
        all the time, and a radius grown there would eat them; leaves and flicker give speckle,
        which the opening removes.
        """
        h, w = self._shape
        fg_idx = np.ascontiguousarray(fg_idx, np.int64)
        # one compiled pass (``kernels.feedback``): the opening and its dilation only at the
        # pixels that switched, the levels in one pass over the frame
        self._prev_fg = kernels.feedback(
            self._blink,
            self._prev_fg,
            self._prev_idx,
            fg_idx,
            h,
            w,
            *_OFFSETS,
            np.float32(self.blink_decay),
            np.float32(self.blink_gain + self.blink_decay),
            np.float32(self.max_radius_gain - 1.0),
        )
        self._prev_idx = fg_idx


def _box_bytes(words: np.ndarray) -> np.ndarray:
    """The (K, 8) uint8 bytes of ``_box`` words (K,) uint64: B, G, R minimum at 0-2, maximum at 4-6
    (a view when ``words`` is contiguous, as the kernels that write it need).
    """
    return np.ascontiguousarray(words).view(np.uint8).reshape(-1, 8)
