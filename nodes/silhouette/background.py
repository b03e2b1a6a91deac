"""Statistical colour background model with shadow and highlight detection.

Horprasert, Harwood & Davis, "A statistical approach for real-time robust background subtraction
and shadow detection" (ICCV Frame-Rate Workshop, 1999). Each pixel i has an expected colour
E_i = (mu_R, mu_G, mu_B) and a per-channel spread s_i = (s_R, s_G, s_B). For an observed colour
I_i the model splits the difference from E_i into

* brightness distortion (eq. 5)
      alpha_i = sum_c (I_c mu_c / s_c^2) / sum_c (mu_c / s_c)^2
  i.e. the scale of E_i closest to I_i in the spread-normalised colour space, and
* chromaticity distortion (eq. 6)
      CD_i = sqrt( sum_c ((I_c - alpha_i mu_c) / s_c)^2 ),
  the distance of I_i from the line through the origin and E_i.

Both are normalised by their per-pixel RMS over the training frames (eqs. 7, 8):
a_i = RMS(alpha_i - 1), b_i = RMS(CD_i), alpha_hat = (alpha - 1) / a_i, CD_hat = CD / b_i.
A pixel is then (eq. 9)

* foreground   if CD_hat > tau_CD or alpha_hat < tau_alpha_lo, else
* background   if tau_alpha2 < alpha_hat < tau_alpha1, else
* shadow       if alpha_hat < 0 (darker, same chromaticity), else
* highlight    (brighter, same chromaticity).

The thresholds come from the distribution of the normalised distortions over the training frames
for a target detection rate r: tau_CD is the r-quantile of CD_hat and [tau_alpha2, tau_alpha1] the
central r-interval of alpha_hat. tau_alpha_lo keeps near-black pixels from being explained as a
very deep shadow. Chosen automatically it is per pixel, (min_shadow_brightness - 1) / a_i, i.e. a
pixel darker than ``min_shadow_brightness`` times its background is foreground: a single global
value on alpha_hat (the paper's form, used when tau_alpha_lo is given) would put that limit at
very different brightnesses in bright, low-noise pixels (small a_i) and dark, noisy ones.

Bounds on the shadow and highlight classes: a pixel more than ``max_highlight_brightness`` times
brighter than its background is foreground, not a highlight (a change of light brightens a
surface by tens of percent; a white shirt on a grey floor, which has the floor's chromaticity
too, by far more), just as one darker than ``min_shadow_brightness`` is not a shadow.

Monochrome footage (a grey or infrared camera, a tinted black-and-white video, three equal
channels however it comes) has no chromaticity to tell with: every colour lies on one line through
the origin, CD is noise, and any person darker than the room down to ``min_shadow_brightness`` would
be a shadow, any lighter one up to ``max_highlight_brightness`` a highlight. Training frames whose
colours spread less than ``mono_chroma_deg`` in chromaticity (:func:`chroma_spread_deg`) are taken
as monochrome (``monochrome_``): their shadows and highlights are then bounded by the much tighter
``mono_min_shadow_brightness`` and ``mono_max_highlight_brightness`` (a cast shadow that is deeper
is foreground with its person, a price that colour footage does not pay), and a still region is
absorbed as a ghost only when it matches the room's brightness closely.

Shadows keep the texture of the surface they fall on; clothing does not (Jacques, Jung & Musse,
"Background subtraction and shadow detection in grayscale video sequences", SIBGRAPI 2005, eq. 4).
A pixel labelled shadow whose background neighbourhood is textured (its local standard deviation
above ``shadow_texture_k`` spreads: only there can a pattern be checked) and whose local normalised cross-correlation
with the background is under ``shadow_ncc`` is foreground: a dark shirt that is darker than the
floor in the floor's colour, but not the floor's pattern. On a plain floor under a plain shirt
both are flat, the test cannot tell, and the pixel stays a shadow.

People in view while learning (``fit(..., exclude=...)``, driven by ``people.fit_around_people``):
the samples known to show a person are left out of every statistic. A pixel with too few samples
left (someone stood on it through most of the training frames) has never been seen: its E and s
are filled in from the room around it (``cv2.inpaint``), s widened, and it is marked in
``unseen_``. There a darker shade of the floor is more likely the grey shirt of the person who
still stands there than a shadow: shadows must be brighter than ``unseen_min_shadow_brightness``,
shadow and highlight pixels are not learnt, and a ghost is absorbed only when it matches the room
around it closely.

Adaptation (``update``). Background pixels blend the frame into E at ``learning_rate``, shadow and
highlight pixels at ``shadow_learning_rate``; foreground pixels are never blended in but follow the
scene-wide lighting drift (the mean brightness distortion of the background pixels), so the room
behind a person who stands for seconds is still right when they leave. After a robust start
(people in view in the training frames) the median can hold a person who stood still there; when
they leave, the room they uncover is foreground, a "ghost". Foreground that stays still for
``absorb_frames`` frames and matches the room around it (chromaticity and brightness of a
normalised local average of E) is absorbed into E; a still person, who does not match the room
around them, is not.

Frames are uint8 BGR, H x W x 3; all arithmetic is float32 and vectorised over pixels.
"""

from __future__ import annotations

from collections.abc import Iterable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, fields
from typing import Any

import cv2
import numpy as np

from . import kernels

BACKGROUND: int = 0
SHADOW: int = 1
HIGHLIGHT: int = 2
FOREGROUND: int = 3
CLASS_NAMES: tuple[str, str, str, str] = ("background", "shadow", "highlight", "foreground")

# 1.4826 * MAD estimates the standard deviation of a Gaussian.
_MAD_TO_SIGMA = 1.4826
# Smallest automatic threshold on a normalised distortion.
_MIN_TAU = 2.0
# Still frames before a foreground pixel is absorbed, after a robust (people in view) start.
_AUTO_ABSORB_FRAMES = 10
# Largest L1 distance of normalised colour (r, g, b sum to 1) and range of brightness ratio
# between a still run and the surrounding background for it to be taken as uncovered background.
_GHOST_CHROMA = 0.06
_GHOST_BRIGHTNESS = (0.7, 1.4)
# The same where the room was filled in around someone who stood there (``unseen_``): the guess
# is good to a few percent, while a grey shirt on a grey floor is within the wide limits above.
_UNSEEN_GHOST_CHROMA = 0.03
_UNSEEN_GHOST_BRIGHTNESS = (0.88, 1.12)
# An excluded sample in the robust median pass: above every (doubled) grey level or deviation.
_EXCLUDED = np.uint16(np.iinfo(np.uint16).max)
#: pixels of the room sampled for the scene-wide exposure (``follow_exposure``); the share of
#: them that must be left when the last frame's foreground is taken out, else all count
_EXPOSURE_SAMPLES = 4096
_EXPOSURE_MIN_LEFT = 0.3
#: the mean levels a sampled pixel's background may have: away from black and from saturation
_EXPOSURE_LEVELS = (20.0, 235.0)
#: the least level of a sample's background in every channel for the channels' own gains: a dark
#: channel's ratio is mostly its noise
_EXPOSURE_CHANNEL_LEVEL = 10.0
# Bytes of float32 work memory per row block in the robust median pass.
_BLOCK_BYTES = 64 * 1024 * 1024


def as_frame_stack(frames: np.ndarray | Iterable[np.ndarray]) -> np.ndarray:
    """Return training frames as one contiguous array.

    Parameters
    ----------
    frames : ndarray of shape (N, H, W, 3), dtype uint8, or iterable of ndarray
        Such an array, or an iterable of (H, W, 3) uint8 BGR frames of one size.

    Returns
    -------
    ndarray of shape (N, H, W, 3), dtype uint8
        The contiguous stack.

    Raises
    ------
    ValueError
        Naming the offending frame when a shape or dtype does not fit, or for no frames.
    """
    if isinstance(frames, np.ndarray):
        stack = frames
    else:
        items = list(frames)
        if not items:
            raise ValueError("frames is empty: pass at least 2 frames of shape (H, W, 3) uint8")
        first = np.asarray(items[0])
        for k, f in enumerate(items):
            f = np.asarray(f)
            if f.shape != first.shape or f.dtype != np.uint8:
                raise ValueError(
                    f"frame {k} has shape {f.shape} dtype {f.dtype}; every frame must be "
                    f"uint8 with the shape of frame 0 {first.shape}"
                )
        stack = np.stack(items)
    if stack.ndim != 4 or stack.shape[-1] != 3 or stack.dtype != np.uint8:
        raise ValueError(f"frames must be (N, H, W, 3) uint8 BGR, got shape {stack.shape} dtype {stack.dtype}")
    return np.ascontiguousarray(stack)


def _check_frame(frame: np.ndarray, shape: tuple[int, int]) -> None:
    if not isinstance(frame, np.ndarray) or frame.dtype != np.uint8 or frame.shape != (*shape, 3):
        got = (getattr(frame, "shape", None), getattr(frame, "dtype", None))
        raise ValueError(f"frame must be a uint8 BGR array of shape {(*shape, 3)} (the training size), got {got}")


class NoRoomSeen(ValueError):
    """The samples left out of a fit (``exclude``) leave no pixel seen as the room in enough frames."""


@dataclass(frozen=True)
class ThresholdConfig:
    """How the classification thresholds of eq. 9 are chosen.

    Parameters
    ----------
    detection_rate : float, default 0.9999
        Target fraction r of training (background) samples accepted as background; sets tau_CD
        (r-quantile of CD_hat) and tau_alpha1/2 (central r-interval of alpha_hat), in (0.5, 1).
    tau_cd, tau_alpha1, tau_alpha2, tau_alpha_lo : float or None, default None
        Fixed thresholds on the normalised distortions (eq. 9); None chooses them from the
        training frames (tau_alpha_lo then per pixel from ``ShadowConfig.min_shadow_brightness``).
    max_threshold_samples : int, default 2_000_000
        Normalised distortion samples drawn to set the thresholds.
    random_state : int or None, default 0
        Seed of that subsample.
    """

    detection_rate: float = 0.9999
    tau_cd: float | None = None
    tau_alpha1: float | None = None
    tau_alpha2: float | None = None
    tau_alpha_lo: float | None = None
    max_threshold_samples: int = 2_000_000
    random_state: int | None = 0

    def __post_init__(self) -> None:
        if not 0.5 < self.detection_rate < 1.0:
            raise ValueError(f"detection_rate must be in (0.5, 1), got {self.detection_rate}")


@dataclass(frozen=True)
class AdaptationConfig:
    """Running-average rates of ``HorprasertBackground.update``, per frame.

    Parameters
    ----------
    learning_rate : float, default 0.05
        Rate r of E <- (1 - r) E + r I at BACKGROUND pixels; 0 disables adaptation. Lighting drift
        slower than about ``learning_rate`` * tau_alpha1 * a per frame keeps pixels in the
        background class.
    spread_learning_rate : float, default 0.0
        The same for the per-channel variance s^2. Off by default: single-frame variance
        estimates are noisy, the thresholds were set for the trained spreads, and adapting only E
        keeps ``update`` about twice as fast.
    shadow_learning_rate : float, default 0.01
        Rate at SHADOW and HIGHLIGHT pixels (FOREGROUND: never).
    update_every : int, default 2
        The model learns from one frame in this many (the first after the fit, then every n-th), at
        n times the rates (at most 1): behind a steady lighting drift it then lags, on the last
        frame before it learns again, as far as learning every frame at r (and less on the others),
        with about the same memory (1 - n r against (1 - r)^n over n frames). The ghost runs
        (``GhostConfig.absorb_frames``) count the frames learnt from. 1: every frame. With 2 the
        update costs half as much per frame.
    exposure_step : float, default 0.05
        A frame whose room is brighter or darker than the model by more than this share, all over
        (the median ratio of their brightness on a sample of the room's pixels, the last frame's
        foreground left out: a light switched, the sun out from a cloud, the camera's exposure
        changed), re-exposes the model at once (``HorprasertBackground.follow_exposure``): a
        change that sudden outruns any learning rate, and left alone it would make the whole room
        foreground for good. 0: never.
    white_balance_step : float, default 0.03
        A frame whose room's colour balance differs from the model's by more than this share (one
        channel's gain over the three channels' together: a camera's automatic white balance
        turning as someone in a coloured coat comes in, a lamp of another colour switched on)
        re-exposes each channel of the model by its own gain. A cast that is slight but all over
        shifts every pixel's chromaticity by about as much as the room's noise, too little for
        the exposure step and too much for the learning rate, which learns only what stays
        background. 0: the channels only together (``exposure_step``; with that 0, neither is
        followed).
    """

    learning_rate: float = 0.05
    spread_learning_rate: float = 0.0
    shadow_learning_rate: float = 0.01
    update_every: int = 2
    exposure_step: float = 0.05
    white_balance_step: float = 0.03

    def __post_init__(self) -> None:
        for name in ("learning_rate", "spread_learning_rate", "shadow_learning_rate"):
            v = getattr(self, name)
            if not 0.0 <= v <= 1.0:
                raise ValueError(f"{name} must be in [0, 1], got {v}")
        if self.update_every < 1:
            raise ValueError(f"update_every must be >= 1 frame, got {self.update_every}")
        if not 0.0 <= self.exposure_step < 1.0:
            raise ValueError(f"exposure_step must be in [0, 1) (0: never), got {self.exposure_step}")
        if not 0.0 <= self.white_balance_step < 1.0:
            raise ValueError(f"white_balance_step must be in [0, 1) (0: never), got {self.white_balance_step}")

    def rate(self, name: str) -> float:
        """The rate ``name`` (``learning_rate``, ``spread_learning_rate`` or ``shadow_learning_rate``)
        per learnt frame: update_every r, at most 1.

        Parameters
        ----------
        name : str
            The field.

        Returns
        -------
        float
            The rate, in [0, 1].
        """
        return min(1.0, self.update_every * float(getattr(self, name)))


@dataclass(frozen=True)
class ShadowConfig:
    """Bounds on the shadow and highlight classes and the shadow texture test.

    Parameters
    ----------
    min_shadow_brightness : float, default 0.4
        Darkest shadow accepted, as a fraction of the background brightness (raw alpha, eq. 5);
        darker pixels are foreground. Sets the automatic tau_alpha_lo per pixel. In [0, 1).
    max_highlight_brightness : float, default 1.5
        Brightest highlight accepted, as a multiple of the background brightness (raw alpha);
        brighter pixels are foreground. A change of light brightens a surface by tens of
        percent; a white shirt on a grey floor has the floor's chromaticity too, and is far
        brighter. > 1.
    unseen_min_shadow_brightness : float, default 0.6
        ``min_shadow_brightness`` at the ``unseen_`` pixels: where someone stood through the
        training frames they most likely still stand, and a grey shirt there is a darker shade of
        the grey floor filled in around them, not a shadow (``people.fit_around_people`` keeps
        their cast shadow, on the ground at their feet, out of those pixels).
    shadow_ncc : float, default 0.4
        A shadow pixel whose ``shadow_window`` neighbourhood correlates less than this
        (normalised cross-correlation of grey levels; Jacques, Jung & Musse 2005, eq. 4) with the
        background's is foreground, when the neighbourhood is textured; -1 turns the texture test
        off; 0.4 was tuned on CDnet busStation (the first half of its evaluated frames).
    shadow_texture_k : float, default 8.0
        Textured: the local standard deviation of the background exceeds this many times the
        pixel's noise (grey sum of the channels, spread s). A shadow edge on a plain floor
        correlates badly with it but is not checked. 4 is best on CDnet's tune halves, but moves
        cast shadows on the simulator's wooden floor (its grain is weak against its noise) into
        the foreground; 8 leaves them shadows.
    shadow_window : int, default 7
        Side of the square window of the texture test, pixels (odd, >= 3).
    texture_prefilter : float, default 0.5
        When shadow covers much of the frame (more pixels than the frame over the window's area: a
        sunlit street, the real clips), only the shadow pixels whose whole window of the
        background is textured too, its variance above this fraction of the texture floor
        (``shadow_texture_k``), are tested: that variance only changes when the model learns, so
        it is kept with the model (worked out with each update while such frames come), and the
        test's windows are gathered at those pixels alone instead of box-filtered over the frame.
        The variance over a window's shadow pixels alone exceeds the whole window's mostly at a
        shadow's edge; 0.5 keeps nearly every pixel that the full test finds textured. Sparse
        shadow is tested in full. 0: no prefilter.
    mono_chroma_deg : float, default 1.0
        Training frames whose colours spread less than this in chromaticity
        (:func:`chroma_spread_deg`, degrees) are monochrome; 0: never. Colour footage of a drab scene spreads a few degrees;
        grey frames, even through a codec, a few tenths.
    mono_min_shadow_brightness, mono_max_highlight_brightness : float, default 0.85, 1.08
        ``min_shadow_brightness`` and ``max_highlight_brightness`` (and at least the former for
        ``unseen_min_shadow_brightness``) on monochrome footage, where brightness alone tells a
        shadow from a person. In [0, 1) and > 1.
    """

    min_shadow_brightness: float = 0.4
    max_highlight_brightness: float = 1.5
    unseen_min_shadow_brightness: float = 0.6
    shadow_ncc: float = 0.4
    shadow_texture_k: float = 8.0
    shadow_window: int = 7
    texture_prefilter: float = 0.5
    mono_chroma_deg: float = 1.0
    mono_min_shadow_brightness: float = 0.85
    mono_max_highlight_brightness: float = 1.08

    def __post_init__(self) -> None:
        if self.mono_chroma_deg < 0.0:
            raise ValueError(f"mono_chroma_deg must be >= 0 (0: never monochrome), got {self.mono_chroma_deg}")
        if not 0.0 <= self.mono_min_shadow_brightness < 1.0:
            raise ValueError(f"mono_min_shadow_brightness must be in [0, 1), got {self.mono_min_shadow_brightness}")
        if self.mono_max_highlight_brightness <= 1.0:
            raise ValueError(f"mono_max_highlight_brightness must be > 1, got {self.mono_max_highlight_brightness}")
        if self.texture_prefilter < 0.0:
            raise ValueError(f"texture_prefilter must be >= 0 (0: off), got {self.texture_prefilter}")
        if not 0.0 <= self.min_shadow_brightness < 1.0:
            raise ValueError(f"min_shadow_brightness must be in [0, 1), got {self.min_shadow_brightness}")
        if self.max_highlight_brightness <= 1.0:
            raise ValueError(f"max_highlight_brightness must be > 1, got {self.max_highlight_brightness}")
        if not self.min_shadow_brightness <= self.unseen_min_shadow_brightness < 1.0:
            raise ValueError(
                "unseen_min_shadow_brightness must be in [min_shadow_brightness, 1), got "
                f"{self.unseen_min_shadow_brightness}"
            )
        if not -1.0 <= self.shadow_ncc <= 1.0:
            raise ValueError(f"shadow_ncc must be in [-1, 1] (-1: no texture test), got {self.shadow_ncc}")
        if self.shadow_texture_k < 0 or self.shadow_window < 3 or self.shadow_window % 2 == 0:
            raise ValueError(
                "shadow_texture_k must be >= 0 and shadow_window odd >= 3, got "
                f"{self.shadow_texture_k}, {self.shadow_window}"
            )


@dataclass(frozen=True)
class TrainingConfig:
    """How E and s are learnt from the training frames (eqs. 1-4, or their robust forms).

    Parameters
    ----------
    min_spread : float, default 1.5
        Lower bound on each channel's spread s_c, grey levels; keeps the normalisation finite for
        pixels that were constant in training (saturated, black, codec-flattened). > 0.
    robust_inlier_k : float, default 3.5
        In ``fit(robust=True)``, a training sample counts towards a, b and the thresholds only if
        every channel lies within k robust spreads of the median. > 0.
    min_free_frac : float, default 0.5
        In ``fit(exclude=...)``, a pixel with fewer training samples left than this fraction of the
        frames (and at least 3) is taken as not seen: its E and s are filled in from the pixels
        around it. A person the detector missed in some frames is in the samples left there; over
        half of the frames they would be the median. In [0, 1].
    unseen_spread_gain : float, default 2.0
        Those pixels' filled-in spread is widened by this factor (a guess from the surroundings
        is less certain than a measurement). >= 1.
    """

    min_spread: float = 1.5
    robust_inlier_k: float = 3.5
    min_free_frac: float = 0.5
    unseen_spread_gain: float = 2.0

    def __post_init__(self) -> None:
        if self.min_spread <= 0:
            raise ValueError(f"min_spread must be > 0 grey levels, got {self.min_spread}")
        if self.robust_inlier_k <= 0:
            raise ValueError(f"robust_inlier_k must be > 0, got {self.robust_inlier_k}")
        if not 0.0 <= self.min_free_frac <= 1.0:
            raise ValueError(f"min_free_frac must be in [0, 1], got {self.min_free_frac}")
        if self.unseen_spread_gain < 1.0:
            raise ValueError(f"unseen_spread_gain must be >= 1, got {self.unseen_spread_gain}")


@dataclass(frozen=True)
class GhostConfig:
    """Ghost removal: still foreground that matches the room around it is absorbed into E.

    Parameters
    ----------
    absorb_frames : int or None, default None
        A foreground pixel whose colour stays within ``absorb_k`` spreads of the colour it had
        when its still run began, for this many consecutive frames, is taken to be background that
        a person uncovered and becomes the model's E there (counted in the frames the model learns
        from, ``AdaptationConfig.update_every``: one in that many, rounded up). None: 10 frames (0.4 s at 25 fps)
        after ``fit(robust=True)``, whose median can hold people who stood still in the training
        frames, and 0 (never) after a plain fit from empty frames, whose model is trusted. A still
        person is absorbed this way too; that is the price of learning with people in view.
    absorb_k : float, default 4.0
        Tolerance of the still test, in spreads s per channel (noise, slow drift). > 0.
    """

    absorb_frames: int | None = None
    absorb_k: float = 4.0

    def __post_init__(self) -> None:
        if self.absorb_frames is not None and self.absorb_frames < 0:
            raise ValueError(f"absorb_frames must be >= 0 frames (0: never) or None (auto), got {self.absorb_frames}")
        if self.absorb_k <= 0:
            raise ValueError(f"absorb_k must be > 0 spreads, got {self.absorb_k}")


#: the configuration groups of ``HorprasertBackground``, by constructor keyword
_CONFIGS: dict[str, type] = {
    "thresholds": ThresholdConfig,
    "adaptation": AdaptationConfig,
    "shadows": ShadowConfig,
    "training": TrainingConfig,
    "ghosts": GhostConfig,
}


def chroma_spread_deg(image: np.ndarray, min_level: float = 20.0, every: int = 7) -> float:
    """How far the colours of an image spread in chromaticity: the 90th percentile of the angle
    between each pixel's colour vector and the median direction, degrees.

    Parameters
    ----------
    image : ndarray of shape (..., 3)
        BGR pixels: a frame (H, W, 3) or a stack of them (N, H, W, 3).
    min_level : float, default=20.0
        Pixels whose mean level is under this are left out: near black, a colour's direction is noise.
    every : int, default=7
        Every this many-th pixel is looked at (1: all, for pixels already sampled).

    Returns
    -------
    float
        Degrees; 0 for three equal channels (and for an image with no pixel bright enough), a
        few tenths for a grey image through a codec, several degrees for colour footage.
    """
    c = np.asarray(image).reshape(-1, 3)[::every].astype(np.float32)
    c = c[c.mean(axis=1) >= min_level]
    if not len(c):
        return 0.0
    u = c / np.linalg.norm(c, axis=1, keepdims=True)
    m = np.median(u, axis=0)
    m /= max(float(np.linalg.norm(m)), 1e-12)
    return float(np.degrees(np.arccos(np.clip(np.percentile(u @ m, 10.0), -1.0, 1.0))))


def distortions(
    planes: list[np.ndarray], w: np.ndarray, inv_var: np.ndarray, inv_den: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Horprasert's brightness and chromaticity distortions of a frame against the model.

    Parameters
    ----------
    planes : list of 3 ndarray of shape (H, W), dtype float32
        The frame's B, G, R planes.
    w : ndarray of shape (3, H, W), dtype float32
        E_c / s_c^2 per channel (the model's means over its variances).
    inv_var : ndarray of shape (3, H, W), dtype float32
        1 / s_c^2 per channel.
    inv_den : ndarray of shape (H, W), dtype float32
        1 / sum_c (E_c / s_c)^2.

    Returns
    -------
    alpha, cd2 : ndarray of shape (H, W), dtype float32
        The brightness distortion alpha (eq. 5) and the squared chromaticity distortion CD^2
        (eq. 6), not yet normalised by a and b.
    """
    # S = sum_c I_c E_c / s_c^2, alpha = S / sum_c (E_c / s_c)^2 (eq. 5). Expanding the square
    # of eq. 6, CD^2 = sum_c ((I_c - alpha E_c) / s_c)^2 = sum_c I_c^2 / s_c^2 - alpha S: six
    # array passes fewer than forming the three differences.
    # OpenCV's float ops (the same IEEE products and sums as numpy's) into reused buffers:
    # fewer whole-frame temporaries, which cost more than the arithmetic
    mul, add = cv2.multiply, cv2.add
    s = mul(planes[0], w[0])
    t = mul(planes[1], w[1])
    add(s, t, dst=s)
    add(s, mul(planes[2], w[2], dst=t), dst=s)
    alpha = mul(s, inv_den)
    cd2 = mul(planes[0], planes[0])
    mul(cd2, inv_var[0], dst=cd2)
    for c in (1, 2):
        mul(planes[c], planes[c], dst=t)
        mul(t, inv_var[c], dst=t)
        add(cd2, t, dst=cd2)
    mul(s, alpha, dst=s)
    cv2.subtract(cd2, s, dst=cd2)
    # float32 rounding of the difference can dip just below 0 where the colour matches exactly
    cv2.max(cd2, 0.0, dst=cd2)
    return alpha, cd2


class HorprasertBackground:
    """Per-pixel colour background model with shadow/highlight classes (Horprasert et al. 1999).

    Parameters
    ----------
    thresholds : ThresholdConfig
        How the thresholds of eq. 9 are set (detection rate, fixed values).
    adaptation : AdaptationConfig
        Learning rates of ``update``.
    shadows : ShadowConfig
        Brightness bounds of the shadow and highlight classes; the shadow texture test.
    training : TrainingConfig
        Spread floor and the robust / people-aware fit.
    ghosts : GhostConfig
        Absorbing uncovered background (ghosts) into the model.

    ``HorprasertBackground.from_params(**flat)`` builds the groups from the configs' field names
    (the node's parameter names, e.g. ``learning_rate=0.02, shadow_ncc=0.4``).

    Attributes
    ----------
    mean_ : ndarray of shape (H, W, 3), dtype float32
        Expected colour E, grey levels.
    spread_ : ndarray of shape (H, W, 3), dtype float32
        Per-channel spread s, grey levels.
    a_, b_ : ndarray of shape (H, W), dtype float32
        RMS brightness / chromaticity distortion (eqs. 7, 8).
    thresholds_ : dict of str to float
        tau_cd, tau_alpha1, tau_alpha2, tau_alpha_lo as fitted.
    unseen_ : ndarray of shape (H, W), dtype bool
        Pixels no training sample showed (``fit(exclude=...)``), filled in.
    monochrome_ : bool
        The training frames had no colour to tell shadows by (``ShadowConfig.mono_chroma_deg``):
        :meth:`shadow_bounds` gives the tighter monochrome bounds.

    Raises
    ------
    TypeError
        If a configuration group is not of its config class.
    """

    def __init__(
        self,
        thresholds: ThresholdConfig = ThresholdConfig(),  # noqa: B008 (frozen: safe to share)
        adaptation: AdaptationConfig = AdaptationConfig(),  # noqa: B008
        shadows: ShadowConfig = ShadowConfig(),  # noqa: B008
        training: TrainingConfig = TrainingConfig(),  # noqa: B008
        ghosts: GhostConfig = GhostConfig(),  # noqa: B008
    ) -> None:
        for name, cls in _CONFIGS.items():
            value = locals()[name]
            if not isinstance(value, cls):
                raise TypeError(f"{name} must be a {cls.__name__}, got {type(value).__name__}")
        self.thresholds = thresholds
        self.adaptation = adaptation
        self.shadows = shadows
        self.training = training
        self.ghosts = ghosts
        self.unseen_: np.ndarray | None = None  # (H, W) bool pixels filled in from their surroundings
        self.monochrome_ = False
        self._exposure_idx: np.ndarray | None = None  # flat indices of the room's exposure sample
        self._exposure_fg: np.ndarray | None = None  # which of them the last update's labels call foreground
        self._exposure_bytes: np.ndarray | None = None  # (3, n) their B, G, R positions in a flat frame
        self._unseen_u8: np.ndarray | None = None
        self.absorb_frames_: int = 0
        self._absorb_runs = 0  # absorb_frames_ in frames learnt from (one in adaptation.update_every)
        self._updates = 0  # update calls since the fit (one in adaptation.update_every learns)
        self._still: np.ndarray | None = None  # (H, W) uint16 length of each pixel's still foreground run
        self._still_ref: np.ndarray | None = None  # (3, H * W) float32 mean colour of that run
        # (frame, its alpha, its float32 channel planes or None until made) of the last apply
        self._last_alpha: tuple[np.ndarray, np.ndarray, list[np.ndarray] | None] | None = None
        self._w: np.ndarray | None = None
        # (H + 2 r, W + 2 r) float32 grey sum of E, reflect-padded by r = shadow_window // 2
        self._e_pad: np.ndarray | None = None
        self._pad_flat: np.ndarray | None = None  # padded flat index -> frame flat index (texture test)
        # (H, W) bool: E's whole shadow_window is textured (``ShadowConfig.texture_prefilter``),
        # for the E of colour-terms refresh number ``_bg_textured_at`` (None: not worked out)
        self._bg_textured: np.ndarray | None = None
        self._bg_textured_at = -1
        self._terms_refreshed = 0  # calls of ``_refresh_colour_terms``: E's version
        # whether the last texture test found shadow over much of the frame (its prefilter's
        # mask is then kept up to date by the updates)
        self._texture_wide = False
        self._mu: np.ndarray | None = None  # (3, H, W) float32 expected colour planes E
        self._var: np.ndarray | None = None  # (3, H, W) float32 variance planes s^2
        self.a_: np.ndarray | None = None
        self.b_: np.ndarray | None = None
        self.thresholds_: dict[str, float] = {}

    @classmethod
    def from_params(cls, **params: Any) -> HorprasertBackground:
        """A model from flat parameters named as the configs' fields (``learning_rate=0.02``,
        ``shadow_ncc=0.4``, ...), each routed to its group; others go to their defaults.

        Parameters
        ----------
        **params : Any
            Fields of ``ThresholdConfig``, ``AdaptationConfig``, ``ShadowConfig``, ``TrainingConfig``
            and ``GhostConfig``.

        Returns
        -------
        HorprasertBackground
            The (unfitted) model.

        Raises
        ------
        ValueError
            Naming an unknown parameter and the valid names, or a config's bad value.
        """
        groups: dict[str, dict[str, Any]] = {name: {} for name in _CONFIGS}
        owner = {f.name: name for name, c in _CONFIGS.items() for f in fields(c)}
        for key, value in params.items():
            if key not in owner:
                raise ValueError(
                    f"unknown parameter {key!r} of the background model; valid names: {', '.join(sorted(owner))}"
                )
            groups[owner[key]][key] = value
        return cls(**{name: _CONFIGS[name](**kw) for name, kw in groups.items()})

    # ------------------------------------------------------------------ fitting
    @property
    def is_fitted(self) -> bool:
        return self.a_ is not None

    @property
    def mean_(self) -> np.ndarray:
        """(H, W, 3) float32 expected colour E, grey levels (a view of the model)."""
        self._require_fitted()
        return np.moveaxis(self._mu, 0, -1)

    @property
    def spread_(self) -> np.ndarray:
        """(H, W, 3) float32 per-channel spread s, grey levels (>= min_spread)."""
        self._require_fitted()
        return np.moveaxis(np.sqrt(self._var), 0, -1)

    @property
    def grey_(self) -> np.ndarray | None:
        """(H, W) float32 sum of E's three channels, grey levels, as the shadow texture test reads
        it; None when that test is off. ``update`` replaces the array rather than writing into it,
        so one taken before an update stays the one the frame was classified against.
        """
        if self._e_pad is None:
            return None
        r = self.shadows.shadow_window // 2
        return self._e_pad[r:-r, r:-r] if r else self._e_pad

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W) of the frames the model was fitted on."""
        self._require_fitted()
        return self._mu.shape[1:]

    def fit(
        self, frames: np.ndarray | Iterable[np.ndarray], robust: bool = False, exclude: np.ndarray | None = None
    ) -> HorprasertBackground:
        """Learn the background from training frames.

        Parameters
        ----------
        frames : ndarray of shape (N, H, W, 3), dtype uint8, or iterable of ndarray
            BGR training frames, N >= 2 (or an iterable of (H, W, 3) frames).
        robust : bool, default=False
            False: the frames are empty of people; E and s are the sample mean and standard
            deviation (Horprasert eqs. 1-4). True: people may be present; E is the per-pixel
            temporal median and s = 1.4826 * MAD, and a, b and the thresholds use only the samples
            within ``robust_inlier_k`` spreads of the median. Pixels covered by a person in more
            than half of the frames cannot be recovered this way: pass ``exclude``.
        exclude : ndarray of shape (N, H, W), dtype bool, or None, default=None
            True where a sample is known not to show the background (a detected person, see
            ``people.fit_around_people``). Every statistic then uses only the other samples; a
            pixel with fewer than ``min_free_frac`` of the frames left was not seen (someone stood
            on it throughout) and its E and s are filled in from the pixels around it
            (``cv2.inpaint``), s widened by ``unseen_spread_gain``; ``unseen_`` marks those pixels.

        Returns
        -------
        HorprasertBackground
            self, fitted.

        Raises
        ------
        ValueError
            For fewer than 2 frames, frames or ``exclude`` of the wrong shape or dtype, an ``exclude``
            that leaves no pixel to learn from, or thresholds that come out inconsistent.
        """
        stack = as_frame_stack(frames)
        if stack.shape[0] < 2:
            raise ValueError(f"fit needs at least 2 frames, got {stack.shape[0]}")
        free = None
        if exclude is not None:
            exclude = np.asarray(exclude, bool)
            if exclude.shape != stack.shape[:3]:
                raise ValueError(f"exclude must be (N, H, W) bool of shape {stack.shape[:3]}, got {exclude.shape}")
            free = ~exclude
        # the frames' own colours (a mean filled in around people who stood still has fewer)
        self.monochrome_ = chroma_spread_deg(stack[:: max(1, len(stack) // 4)]) < self.shadows.mono_chroma_deg
        mean, spread, unseen = self._colour_statistics(stack, robust, free)
        self._start_model(mean, spread, unseen, robust)
        inliers = self._fit_distortion_rms(stack, robust, free, unseen)
        self._fit_thresholds(stack, inliers)
        return self

    def _colour_statistics(
        self, stack: np.ndarray, robust: bool, free: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """E and s (H, W, 3) float32 of the training stack (eqs. 1-4, or median and MAD when
        ``robust``) over the ``free`` (N, H, W) samples, with the pixels seen in too few samples
        filled in from around them; returns E, s and those pixels (H, W) bool.
        """
        n = stack.shape[0]
        if robust:
            mean, spread, n_free = _median_mad(stack, free)
        else:
            mean, spread, n_free = _mean_std(stack, free)
        unseen = n_free < min(max(3.0, self.training.min_free_frac * n), n)
        if unseen.all():
            raise NoRoomSeen("exclude leaves no pixel with enough background samples to learn from")
        if unseen.any():
            mean, spread = _fill_unseen(mean, spread, unseen, self.training.unseen_spread_gain)
        return mean, spread, unseen

    def _start_model(self, mean: np.ndarray, spread: np.ndarray, unseen: np.ndarray, robust: bool) -> None:
        """Set E, s^2 (floored at ``min_spread``) and the per-frame state from the statistics; the
        ghost runs start empty and ``absorb_frames_`` is resolved for this kind of fit.
        """
        self.unseen_ = unseen
        # 255 where seen, 0 where filled in: the mask of the shadow-learning step (None: all seen)
        self._unseen_u8 = np.where(unseen, 0, 255).astype(np.uint8) if unseen.any() else None
        self._mu = np.ascontiguousarray(np.moveaxis(mean, -1, 0), np.float32)
        s2 = np.maximum(np.moveaxis(spread, -1, 0), self.training.min_spread).astype(np.float32) ** 2
        self._var = np.ascontiguousarray(s2)
        self._w = None
        frames = (
            (_AUTO_ABSORB_FRAMES if robust else 0) if self.ghosts.absorb_frames is None else self.ghosts.absorb_frames
        )
        # the runs count the frames learnt from: one in update_every
        self.absorb_frames_ = int(frames)
        self._absorb_runs = -(-self.absorb_frames_ // self.adaptation.update_every)
        self._updates = 0  # update calls since the fit
        self._last_alpha = None
        level = mean.mean(axis=-1)
        room = (~unseen & (level >= _EXPOSURE_LEVELS[0]) & (level <= _EXPOSURE_LEVELS[1])).reshape(-1)
        candidates = np.flatnonzero(room)
        n = min(_EXPOSURE_SAMPLES, candidates.size)
        pick = np.random.default_rng(0).choice(candidates.size, n, replace=False) if n else np.zeros(0, np.int64)
        self._exposure_idx = np.sort(candidates[pick])
        self._exposure_bytes = 3 * self._exposure_idx + np.arange(3)[:, None]  # (3, n) into a flat BGR frame
        self._exposure_fg = None
        self._still = np.zeros(self._mu.shape[1:], np.uint16)
        self._still_ref = np.zeros((3, self._mu[0].size), np.float32)
        self.a_ = None
        self._refresh_colour_terms(spread_changed=True)

    def _fit_distortion_rms(
        self, stack: np.ndarray, robust: bool, free: np.ndarray | None, unseen: np.ndarray
    ) -> list[np.ndarray | None]:
        """Set ``a_`` and ``b_``, the per-pixel RMS of the distortions (eqs. 7, 8) over the (inlier)
        samples; returns each frame's inlier mask (H, W) bool, None where every sample counts.
        """
        h, w = self.shape
        sum_a = np.zeros((h, w), np.float64)
        sum_b = np.zeros((h, w), np.float64)
        count = np.zeros((h, w), np.float64)
        inliers = []
        for k, f in enumerate(stack):
            alpha, cd2, planes = self._distortions(f)
            inl = self._inlier_mask(planes) if robust else None
            if free is not None:
                # an unseen pixel's few samples are compared with a filled-in E: they would
                # inflate its a and b; it takes the typical ones instead
                ok = free[k] & ~unseen
                inl = ok if inl is None else inl & ok
            wgt = np.ones((h, w), np.float32) if inl is None else inl.astype(np.float32)
            inliers.append(inl)
            sum_a += wgt * (alpha - 1.0) ** 2
            sum_b += wgt * cd2
            count += wgt
        valid = count > 0
        a = np.sqrt(sum_a / np.maximum(count, 1.0))
        b = np.sqrt(sum_b / np.maximum(count, 1.0))
        # A pixel whose few training samples happened to agree would get a near-zero RMS and
        # flag all later noise. Floor a and b at half the RMS that Gaussian noise of spread s
        # would give (var(alpha) = 1 / sum (E/s)^2, E[CD^2] = 2 degrees of freedom) and at a
        # quarter of their typical value.
        a_noise = 0.5 * np.sqrt(self._inv_den)
        b_noise = 0.5 * np.sqrt(2.0)
        med_a = float(np.median(a[valid])) if valid.any() else 0.0
        med_b = float(np.median(b[valid])) if valid.any() else 0.0
        a = np.maximum(np.where(valid, np.maximum(a, 0.25 * med_a), med_a), a_noise)
        b = np.maximum(np.where(valid, np.maximum(b, 0.25 * med_b), med_b), b_noise)
        self.a_ = np.maximum(a, 1e-6).astype(np.float32)
        self.b_ = np.maximum(b, 1e-6).astype(np.float32)
        return inliers

    def _fit_thresholds(self, stack: np.ndarray, inliers: list[np.ndarray | None]) -> None:
        """Set ``thresholds_`` (eq. 9) from the distribution of the normalised distortions of a
        random subsample of the (inlier) training samples, unless given in ``ThresholdConfig``.
        """
        cfg = self.thresholds
        med_a = float(np.median(self.a_))
        rng = np.random.default_rng(cfg.random_state)
        per_frame = max(1, cfg.max_threshold_samples // stack.shape[0])
        ah_s, cd_s = [], []
        for f, inl in zip(stack, inliers, strict=True):
            alpha, cd2, _ = self._distortions(f)
            ah = ((alpha - 1.0) / self.a_).ravel()
            ch = (np.sqrt(cd2) / self.b_).ravel()
            idx = np.flatnonzero(inl) if inl is not None else None
            pool = idx.size if idx is not None else ah.size
            if pool == 0:
                continue
            pick = rng.integers(0, pool, size=min(per_frame, pool))
            if idx is not None:
                pick = idx[pick]
            ah_s.append(ah[pick])
            cd_s.append(ch[pick])
        ah_all = np.concatenate(ah_s)
        cd_all = np.concatenate(cd_s)
        r = cfg.detection_rate
        # Each automatic threshold is at least _MIN_TAU normalised units: training frames that
        # are nearly noise-free (synthetic, a frozen stream) would otherwise give thresholds of
        # zero. With real sensor noise the quantiles are 3-4 and the floor does not bind.
        lo_q, hi_q = np.quantile(ah_all, [(1.0 - r) / 2.0, 1.0 - (1.0 - r) / 2.0])
        auto_cd = max(float(np.quantile(cd_all, r)), _MIN_TAU)
        tau_cd = auto_cd if cfg.tau_cd is None else float(cfg.tau_cd)
        tau_a1 = max(float(hi_q), _MIN_TAU) if cfg.tau_alpha1 is None else float(cfg.tau_alpha1)
        tau_a2 = min(float(lo_q), -_MIN_TAU) if cfg.tau_alpha2 is None else float(cfg.tau_alpha2)
        if cfg.tau_alpha_lo is None:
            # Reported at the median a; applied per pixel (see _refresh_thresholds).
            tau_lo = min((self.shadow_bounds()[0] - 1.0) / med_a, tau_a2 - 1.0)
        else:
            tau_lo = float(cfg.tau_alpha_lo)
        if not (tau_lo < tau_a2 < 0.0 < tau_a1) or tau_cd <= 0.0:
            raise ValueError(
                "thresholds must satisfy tau_alpha_lo < tau_alpha2 < 0 < tau_alpha1 and tau_cd > 0; "
                f"got tau_alpha_lo={tau_lo}, tau_alpha2={tau_a2}, tau_alpha1={tau_a1}, tau_cd={tau_cd}"
            )
        self.thresholds_ = {
            "tau_cd": tau_cd,
            "tau_alpha1": tau_a1,
            "tau_alpha2": tau_a2,
            "tau_alpha_lo": tau_lo,
        }
        self._refresh_thresholds()

    # ------------------------------------------------------------------ per frame
    def distortions(self, frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Normalised distortions (eqs. 5-8).

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3), dtype uint8
            BGR frame of the training size.

        Returns
        -------
        alpha_hat, cd_hat : ndarray of shape (H, W), dtype float32
            Normalised brightness and chromaticity distortions.

        Raises
        ------
        RuntimeError
            If the model is not fitted.
        ValueError
            For a frame of another shape or dtype.
        """
        self._require_fitted()
        _check_frame(frame, self.shape)
        alpha, cd2, _ = self._distortions(frame)
        return (alpha - 1.0) / self.a_, np.sqrt(cd2) / self.b_

    def apply(self, frame: np.ndarray) -> np.ndarray:
        """Classify each pixel of a frame (eq. 9).

        Does not change the model; call ``update`` for that. The same as ``classify`` followed by
        ``shadow_texture_mismatch`` with its pixels set to FOREGROUND.

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3), dtype uint8
            BGR frame of the training size.

        Returns
        -------
        ndarray of shape (H, W), dtype uint8
            Labels: BACKGROUND 0, SHADOW 1, HIGHLIGHT 2, FOREGROUND 3.

        Raises
        ------
        RuntimeError
            If the model is not fitted.
        ValueError
            For a frame of another shape or dtype.
        """
        labels = self.classify(frame)
        labels.reshape(-1)[self.shadow_texture_mismatch(labels)] = FOREGROUND
        return labels

    def classify(self, frame: np.ndarray) -> np.ndarray:
        """The classes of eq. 9 before the shadows' texture test: ``apply``'s first half.

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3), dtype uint8
            BGR frame of the training size; the errors are ``apply``'s.

        Returns
        -------
        ndarray of shape (H, W), dtype uint8
            Labels as ``apply``'s, the textured shadows not yet checked (``shadow_texture_mismatch``).
        """
        self._require_fitted()
        _check_frame(frame, self.shape)
        # One compiled pass (``kernels.classify``, the distortions of ``_distortions`` and the
        # thresholds, precomputed per pixel in raw alpha / CD^2 units): SHADOW 1 where darker than
        # the background, HIGHLIGHT 2 where brighter, BACKGROUND 0 inside the brightness band,
        # FOREGROUND 3 where the chromaticity or the darkening is too large.
        h, w = self.shape
        labels = np.empty((h, w), np.uint8)
        alpha = np.empty((h, w), np.float32)
        flat = [a.reshape(-1) for a in cv2.split(frame)]  # uint8 planes: SIMD-friendly loads
        flat += [a.reshape(-1) for a in (*self._w, *self._inv_var)]
        th = (self._inv_den, self._alpha_hi, self._alpha_lo, self._alpha_min, self._alpha_max, self._cd2_max)
        kernels.classify(*flat, *(a.reshape(-1) for a in th), labels.reshape(-1), alpha.reshape(-1))
        # for ``update`` and the texture test on this frame: alpha for the global-drift step; the
        # float channel planes are made when one of them (in the worker thread) needs them
        self._last_alpha = (frame, alpha, None)
        return labels

    def _last_planes(self) -> list[np.ndarray]:
        """The float32 channel planes (H, W) of the last classified frame, made once."""
        frame, alpha, planes = self._last_alpha
        if planes is None:
            planes = _float_planes(frame)
            self._last_alpha = (frame, alpha, planes)
        return planes

    def shadow_texture_mismatch(self, labels: np.ndarray) -> np.ndarray:
        """The SHADOW pixels of the last ``classify`` that are textured and do not correlate with the
        background's texture (``apply``'s second half, see the module docstring). Local moments
        over a ``shadow_window`` box of the window's shadow pixels: NCC = (m(IE) - m(I) m(E)) /
        sqrt(var(I) var(E)) on grey levels (Jacques, Jung & Musse 2005, eq. 4).

        Over the window's shadow pixels only: at a shadow's edge the lit pixels beside it would
        make the ratio of frame to background a step, and the correlation low. Reads ``labels`` and
        the model and writes neither (the texture table's cache aside), so it may run in another
        thread while the caller reads them too.

        Parameters
        ----------
        labels : ndarray of shape (H, W), dtype uint8
            The labels ``classify`` returned for the last frame.

        Returns
        -------
        ndarray of shape (K,), dtype int64
            Ascending flat indices of the pixels to relabel FOREGROUND (none when the test is off:
            ``shadow_ncc`` -1).
        """
        none = np.zeros(0, np.int64)
        if self.shadows.shadow_ncc <= -1.0:
            return none
        is_sh = labels == SHADOW
        r = self.shadows.shadow_window // 2
        h, w = is_sh.shape
        wide = np.count_nonzero(is_sh) * (2 * r + 1) ** 2 > h * w
        self._texture_wide = wide
        bg_textured = self._textured_background() if wide else None
        # with shadow over much of the frame, only where the background's whole window is
        # textured (``texture_prefilter``)
        idx = np.flatnonzero(is_sh if bg_textured is None else is_sh & bg_textured)  # on bool: several times faster
        if idx.size == 0:
            return none
        if idx.size * (2 * r + 1) ** 2 > h * w:
            # shadow over much of the frame (a change of light): filtering the frame is cheaper
            # than gathering each pixel's window
            return self._shadow_texture_mismatch(self._last_planes(), is_sh.view(np.uint8), bg_textured)
        # The shadow pixels are a few percent of the frame (and speckle): one compiled pass over
        # each one's window, the background's texture first and the frame's only where that is
        # textured (a few hundred pixels). It reads the uint8 frame itself: the float planes are
        # left to the update (in the worker thread).
        k2 = np.float32(self.shadows.shadow_texture_k**2)
        frame = np.ascontiguousarray(self._last_alpha[0])
        ncc = kernels.texture_ncc(
            idx, np.ascontiguousarray(labels), np.uint8(SHADOW), self._e_pad, self._var, k2, frame, r
        )
        return idx[ncc < self.shadows.shadow_ncc]

    def _frame_ncc(
        self,
        planes: list[np.ndarray],
        win: np.ndarray,
        m: np.ndarray,
        e: np.ndarray,
        me: np.ndarray,
        ve: np.ndarray,
        inv_n: np.ndarray,
    ) -> np.ndarray:
        """The texture test's correlation (K,) float32 at K pixels, from their windows ``win``
        (K, window) flat indices into the frame padded by the window's half side, the shadow
        indicator ``m`` and background grey levels ``e`` (K, window) float32 there, the
        background's windowed mean ``me`` and variance ``ve`` (K,) and one over the shadow
        count ``inv_n`` (K,).
        """
        h, w = planes[0].shape
        r = self.shadows.shadow_window // 2
        # the frame's grey levels at those windows only, read from the unpadded planes at the
        # reflected pixels (the same sums as over the padded frame)
        if self._pad_flat is None or self._pad_flat.size != (h + 2 * r) * (w + 2 * r):
            # padded frame's flat index -> the unpadded frame's flat index that the padding copies
            ry, rx = _reflect(np.arange(-r, h + r), h), _reflect(np.arange(-r, w + r), w)
            self._pad_flat = (ry[:, None] * w + rx[None, :]).reshape(-1)
        at = np.take(self._pad_flat, win)
        flat = [p.reshape(-1) for p in planes]
        grey = np.take(flat[0], at) + np.take(flat[1], at)
        grey += np.take(flat[2], at)
        gm = grey * m
        mi = np.einsum("ij->i", gm) * inv_n
        vi = np.einsum("ij,ij->i", gm, grey) * inv_n - mi * mi
        cov = np.einsum("ij,ij->i", gm, e) * inv_n - mi * me
        return cov / np.sqrt(np.maximum(vi, 0.0) * np.maximum(ve, 0.0) + 1e-6)

    def _shadow_texture_mismatch(
        self, planes: list[np.ndarray], sh: np.ndarray, bg_textured: np.ndarray | None
    ) -> np.ndarray:
        """The texture test of ``shadow_texture_mismatch`` with box filters over the frame, for
        shadow ``sh`` (H, W) 0 / 1 over much of it, at the pixels of ``bg_textured`` (H, W) bool
        alone (None: all); returns the ascending flat indices of the pixels to relabel (K,) int64.
        """
        k = (self.shadows.shadow_window, self.shadows.shadow_window)
        e = self.grey_  # E's grey sum, the same sums as the sparse path's
        m = sh.astype(np.float32)
        box = lambda a: cv2.boxFilter(a, -1, k, normalize=False, borderType=cv2.BORDER_REFLECT)  # noqa: E731
        inv_n = 1.0 / np.maximum(box(m), 1.0)
        em = e * m
        me = box(em) * inv_n
        ve = box(em * e) * inv_n - me * me
        var = self._var
        floor = var[0] + var[1]
        floor += var[2]
        floor *= np.float32(self.shadows.shadow_texture_k**2)
        textured = (sh > 0) & (ve > floor)
        if bg_textured is not None:
            textured &= bg_textured
        idx = np.flatnonzero(textured)
        h, w = sh.shape
        r = self.shadows.shadow_window // 2
        if idx.size * (2 * r + 1) ** 2 <= h * w:
            # Shadow over much of the frame, on a textured background at a few hundred pixels of
            # it (a sunlit street: a person's shadow and the pavement's own dark patches): the
            # frame's side of the correlation only there, from their windows, as the sparse path
            # does. Its window sums agree with the box filter's to float32 rounding.
            wp = w + 2 * r
            ys, xs = np.divmod(idx, w)
            off = (np.arange(2 * r + 1)[:, None] * wp + np.arange(2 * r + 1)[None, :]).reshape(-1)
            win = (ys * wp + xs)[:, None] + off[None, :]
            m_win = np.take(cv2.copyMakeBorder(m, r, r, r, r, cv2.BORDER_REFLECT).reshape(-1), win)
            e_win = np.take(self._e_pad, win)  # E's grey sum, padded alike (``_refresh_colour_terms``)
            at = (idx,)
            ncc = self._frame_ncc(
                planes, win, m_win, e_win, me.reshape(-1)[at], ve.reshape(-1)[at], inv_n.reshape(-1)[at]
            )
            return idx[ncc < self.shadows.shadow_ncc]
        grey = planes[0] + planes[1]
        grey += planes[2]
        gm = grey * m
        mi = box(gm) * inv_n
        vi = box(gm * grey) * inv_n - mi * mi
        cov = box(gm * e) * inv_n - mi * me
        ncc = cov / np.sqrt(np.maximum(vi, 0.0) * np.maximum(ve, 0.0) + 1e-6)
        return np.flatnonzero(textured & (ncc < self.shadows.shadow_ncc))

    def update(self, frame: np.ndarray, labels: np.ndarray, fg_idx: np.ndarray | None = None) -> None:
        """Blend the frame into the model, never where ``labels == FOREGROUND``.

        E <- (1 - r) E + r I and s^2 <- (1 - r_s) s^2 + r_s (I - E)^2 per pixel, with
        r = ``learning_rate`` at BACKGROUND pixels and ``shadow_learning_rate`` at SHADOW and
        HIGHLIGHT pixels (r_s likewise scaled from ``spread_learning_rate``), and r = 0 at
        FOREGROUND. People never enter the model; slow lighting drift is followed. Shadow and
        highlight pixels must adapt too: under a global drift the pixels that noise pushes out of
        the background band would otherwise stop adapting and lag further every frame. Absorbing
        a person's cast shadow this way is harmless, as shadow and background are both "not
        foreground". a, b and the thresholds stay as trained. Foreground pixels follow the
        scene-wide drift (``_follow_global_drift``), and after a robust fit still foreground that
        matches the surrounding room is absorbed (``absorb_frames``). Only one call in
        ``adaptation.update_every`` learns (``learns_next``), at the rates per learnt frame
        (``AdaptationConfig.rate``); the others only count the frame.

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3), dtype uint8
            BGR frame of the training size.
        labels : ndarray of shape (H, W), dtype uint8
            Its labels, as ``apply`` returns them.
        fg_idx : ndarray of shape (K,), dtype int, optional
            Ascending flat indices of the FOREGROUND pixels of ``labels``, where the caller has
            them already (None: found here).

        Raises
        ------
        RuntimeError
            If the model is not fitted.
        ValueError
            For a frame or labels of another shape.
        """
        self._require_fitted()
        _check_frame(frame, self.shape)
        if labels.shape != self.shape:
            raise ValueError(f"labels must have shape {self.shape}, got {labels.shape}")
        labels = np.asarray(labels, np.uint8)  # apply's own labels pass through without a copy
        self._exposure_fg = labels.reshape(-1)[self._exposure_idx] == FOREGROUND
        learns = self.learns_next
        self._updates += 1
        if not learns:
            return
        ad = self.adaptation
        lr, slr = ad.rate("learning_rate"), ad.rate("spread_learning_rate")
        fg = labels == FOREGROUND
        # the foreground is a few percent of the frame: its flat indices serve both steps below
        if fg_idx is None:
            fg_idx = np.flatnonzero(fg)
        absorbed = self._absorb_still(frame, fg, fg_idx) if self.absorb_frames_ > 0 else False
        if lr == 0.0 and slr == 0.0:
            if absorbed:
                self._refresh_colour_terms(spread_changed=False)
            return
        bg = cv2.compare(labels, BACKGROUND, cv2.CMP_EQ)  # 0 / 255 masks
        sh = cv2.inRange(labels, SHADOW, HIGHLIGHT)
        if self._unseen_u8 is not None:
            # where someone stood through training, a shade of the filled-in floor is more likely
            # their clothing than a shadow: learn only what is plainly background there
            cv2.bitwise_and(sh, self._unseen_u8, dst=sh)
        k = ad.rate("shadow_learning_rate") / lr if lr > 0.0 else 0.0
        # cv2.accumulateWeighted is dst <- (1 - r) dst + r src under a mask, in place.
        last = self._last_alpha
        planes = self._last_planes() if last is not None and last[0] is frame else _float_planes(frame)
        for c, f in enumerate(planes):
            if slr > 0.0:
                d = cv2.subtract(f, self._mu[c])
                d2 = cv2.multiply(d, d)
                cv2.accumulateWeighted(d2, self._var[c], slr, mask=bg)
                if k > 0.0:
                    cv2.accumulateWeighted(d2, self._var[c], slr * k, mask=sh)
            if lr > 0.0:
                cv2.accumulateWeighted(f, self._mu[c], lr, mask=bg)
                if k > 0.0:
                    cv2.accumulateWeighted(f, self._mu[c], lr * k, mask=sh)
        if slr > 0.0:
            np.maximum(self._var, np.float32(self.training.min_spread**2), out=self._var)
        if lr > 0.0:
            self._follow_global_drift(frame, fg_idx, bg)
        self._refresh_colour_terms(spread_changed=slr > 0.0)

    @property
    def learns_next(self) -> bool:
        """Whether the next ``update`` call learns from its frame (one in
        ``adaptation.update_every``, from the first after the fit); the others only count.
        """
        return self._updates % self.adaptation.update_every == 0

    def _follow_global_drift(self, frame: np.ndarray, fg_idx: np.ndarray, bg: np.ndarray) -> None:
        """Foreground pixels are never blended in, so under a lighting drift the model behind a
        person who stands for seconds would lag, and the uncovered room would show as speckle.
        Their E follows the scene-wide brightness change instead: the mean brightness
        distortion alpha (eq. 5) over the background pixels, at the background's rate,
        E <- E (1 + r (mean alpha - 1)). ``fg_idx``: flat indices of the foreground pixels.
        """
        last = self._last_alpha
        if last is None or last[0] is not frame or fg_idx.size == 0:
            return
        alpha = last[1]
        n_bg = int(np.count_nonzero(bg))
        if n_bg < 0.05 * bg.size:
            return
        g = float(cv2.mean(alpha, mask=bg)[0])
        step = np.float32(1.0 + self.adaptation.rate("learning_rate") * (g - 1.0))
        if step != 1.0:
            for c in range(3):  # flat gathers beat a masked pass over the whole frame
                mu = self._mu[c].reshape(-1)
                mu[fg_idx] = mu[fg_idx] * step

    def _absorb_still(self, frame: np.ndarray, fg: np.ndarray, idx: np.ndarray) -> bool:
        """Ghost removal (see ``GhostConfig``). ``fg`` (H, W) bool foreground, ``idx`` its flat
        indices. Returns whether any pixel was absorbed.

        Each foreground pixel keeps the mean colour of its current still run and the run's
        length (``_advance_still_runs``). A run of ``absorb_frames`` is absorbed only where the
        colour also matches the model of the surrounding background (``_matches_surround``):
        uncovered background continues the room around it, a person standing still does not.
        Deep inside a large ghost there is no such support yet; it is peeled from its rim
        inwards, frame by frame.
        """
        if idx.size == 0:
            self._still.fill(0)
            return False
        n, refs = self._advance_still_runs(frame, idx)
        ripe = n >= self._absorb_runs
        if not ripe.any():
            return False
        ys, xs = np.divmod(idx[ripe], self.shape[1])
        run = refs[:, ripe]  # (3, K') the runs' mean colours
        sel = self._matches_surround(run, ys, xs, fg)
        if not sel.any():
            return False
        ys, xs = ys[sel], xs[sel]
        for c in range(3):
            self._mu[c][ys, xs] = run[c, sel]
        self._still[ys, xs] = 0
        return True

    def _advance_still_runs(self, frame: np.ndarray, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Extend or restart the still run of each foreground pixel (flat indices ``idx`` (K,)):
        a frame more than ``absorb_k`` spreads (any channel) from the run's mean colour restarts
        it. Runs off the foreground end. Returns the runs' lengths (K,) uint16 and their mean
        colours (3, K) float32.
        """
        # one compiled pass over the foreground pixels (``kernels.advance_still``)
        return kernels.advance_still(
            self._still.reshape(-1),
            self._still_ref,
            frame.reshape(-1, 3),
            self._inv_s.reshape(3, -1),
            idx,
            np.float32(self.ghosts.absorb_k),
        )

    def _matches_surround(self, run: np.ndarray, ys: np.ndarray, xs: np.ndarray, fg: np.ndarray) -> np.ndarray:
        """Whether each ripe run's mean colour ``run`` (3, K) at pixels (``ys``, ``xs``) matches the
        surrounding background: a normalised box average of E over the pixels not in ``fg``
        (H, W) bool, compared in chromaticity and, loosely, brightness (tighter at ``unseen_``
        pixels). Returns (K,) bool.
        """
        # The surround is a local average: computed on 4 x 4 block means (16x fewer pixels) and
        # read at the candidates only, as it only has to be smooth.
        h = self.shape[0]
        k = max(5, (h // 32) | 1)
        cnt, near = _surround_near_candidates(self._mu, fg, ys // 4, xs // 4, k)
        near /= np.maximum(cnt, 1e-3)
        # Chromaticity (normalised colour) and brightness of the run's mean against the surround.
        s_run = run.sum(axis=0) + 1.0
        s_near = near.sum(axis=0) + 1.0
        chroma = np.abs(run / s_run - near / s_near).sum(axis=0)
        ratio = s_run / s_near
        # without colour, brightness alone tells a still person from the room they hide
        lo, hi = _UNSEEN_GHOST_BRIGHTNESS if self.monochrome_ else _GHOST_BRIGHTNESS
        sel = (cnt >= 0.1) & (chroma <= _GHOST_CHROMA) & (ratio > lo) & (ratio < hi)
        if self.unseen_ is not None:
            tight = self.unseen_[ys, xs]
            sel &= ~tight | (
                (chroma <= _UNSEEN_GHOST_CHROMA)
                & (ratio > _UNSEEN_GHOST_BRIGHTNESS[0])
                & (ratio < _UNSEEN_GHOST_BRIGHTNESS[1])
            )
        return sel

    def apply_update(self, frame: np.ndarray) -> np.ndarray:
        """``follow_exposure``, ``apply``, then ``update`` with its labels: one frame of a stream.

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3), dtype uint8
            BGR frame of the training size.

        Returns
        -------
        ndarray of shape (H, W), dtype uint8
            The labels of ``apply``.
        """
        self.follow_exposure(frame)
        labels = self.apply(frame)
        self.update(frame, labels)
        return labels

    def follow_exposure(self, frame: np.ndarray) -> float | None:
        """Re-expose the model when the whole room of a frame is brighter or darker than it by more
        than ``AdaptationConfig.exposure_step`` (see there): E times the gain g, and s too where
        g > 1 (a camera's gain amplifies its noise; in the dark a sensor's noise does not fall
        with the signal); a, b and the thresholds are relative and stay; the ghost runs' colours
        times g. g is the median of frame over model brightness (sum of the channels) at a fixed
        sample of the room's pixels, those the last update's labels called foreground left out
        (all counted where that leaves too few: a change of light makes the whole room foreground
        until it is followed). Where a channel's own gain g_c (the median of its ratio, at the
        samples where none of the model's channels is dark) differs from g by more than
        ``AdaptationConfig.white_balance_step``, each channel is re-exposed by its g_c instead (a
        change of white balance). Call it on each frame of a stream before it is classified
        (``apply_update`` and the node's subtractor do), not on training frames.

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3), dtype uint8
            BGR frame of the training size.

        Returns
        -------
        float or None
            The gain applied (of the three channels together); None when the frame's exposure and
            colour balance are the model's (or following is off).
        """
        self._require_fitted()
        _check_frame(frame, self.shape)
        idx = self._exposure_idx
        if self.adaptation.exposure_step <= 0.0 or idx is None or idx.size == 0:
            return None
        # one gather of the three channels: reductions over a last axis of 3 cost more than the rest here
        channels = frame.reshape(-1)[self._exposure_bytes]  # (3, n) B, G, R
        b, gr, r = channels
        keep = np.maximum(np.maximum(b, gr), r) < 250  # a saturated pixel says only that it got brighter
        if self._exposure_fg is not None:
            room = keep & ~self._exposure_fg
            if np.count_nonzero(room) >= _EXPOSURE_MIN_LEFT * idx.size:
                keep = room
        if np.count_nonzero(keep) < _EXPOSURE_MIN_LEFT * idx.size:
            return None
        seen = b.astype(np.float32) + gr + r
        mu = self._mu.reshape(3, -1)[:, idx]
        model = mu[0] + mu[1] + mu[2]
        g = float(np.median(seen[keep] / model[keep]))
        gains = np.full(3, g, np.float32)
        cast = False
        if self.adaptation.white_balance_step > 0.0:
            step = np.log1p(self.adaptation.white_balance_step)
            lit = keep & (mu.min(axis=0) >= _EXPOSURE_CHANNEL_LEVEL)
            frame_bgr = channels.astype(np.float32)
            # the channels' mean gains first (two sums a channel): a steady colour balance stops here
            rough = (frame_bgr @ lit) / np.maximum(mu @ lit, 1e-6)
            if np.count_nonzero(lit) >= _EXPOSURE_MIN_LEFT * idx.size and (
                np.abs(np.log(np.maximum(rough, 1e-6) / g)).max() > 0.5 * step
            ):
                gains = np.median(frame_bgr[:, lit] / mu[:, lit], axis=1).astype(np.float32)
                cast = bool(np.abs(np.log(gains / g)).max() > step)
        if not cast:
            if abs(np.log(g)) <= np.log1p(self.adaptation.exposure_step):
                return None
            gains[:] = g
        self._mu *= gains[:, None, None]
        self._var *= np.maximum(gains, 1.0)[:, None, None] ** 2
        self._still_ref *= gains[:, None]
        self._refresh_colour_terms(spread_changed=True)
        return g

    def shadow_bounds(self) -> tuple[float, float, float]:
        """The brightness bounds of the shadow and highlight classes for this footage, as multiples
        of the background's brightness (raw alpha): ``ShadowConfig``'s, or on monochrome footage
        (``monochrome_``) its tighter ``mono_`` ones.

        Returns
        -------
        darkest, darkest_unseen, brightest : float
            Darkest shadow, darkest shadow at the ``unseen_`` pixels, brightest highlight.
        """
        s = self.shadows
        if not self.monochrome_:
            return s.min_shadow_brightness, s.unseen_min_shadow_brightness, s.max_highlight_brightness
        darkest = max(s.min_shadow_brightness, s.mono_min_shadow_brightness)
        brightest = min(s.max_highlight_brightness, s.mono_max_highlight_brightness)
        return darkest, max(s.unseen_min_shadow_brightness, darkest), brightest

    def get_params(self) -> dict[str, Any]:
        """The constructor's parameters (scikit-learn style).

        Returns
        -------
        dict of str to config
            The configuration groups by keyword.
        """
        return {name: getattr(self, name) for name in _CONFIGS}

    # ------------------------------------------------------------------ internals
    def _require_fitted(self) -> None:
        if self._mu is None:
            raise RuntimeError("HorprasertBackground is not fitted: call fit(frames) first")

    def _refresh_colour_terms(self, spread_changed: bool) -> None:
        """Per-pixel constants of eqs. 5-6 (channel planes): 1/s, E/s^2, 1/sum (E/s)^2."""
        if self._w is None or self._w.shape != self._mu.shape:
            self._w = np.empty_like(self._mu)
            self._inv_var = np.empty_like(self._mu)
            self._inv_s = np.empty_like(self._mu)
            self._inv_den = np.empty(self._mu.shape[1:], np.float32)
            spread_changed = True
        if spread_changed:
            np.divide(np.float32(1.0), self._var, out=self._inv_var)
            np.sqrt(self._inv_var, out=self._inv_s)
        mu, w, den, inv_var = self._mu, self._w, self._inv_den, self._inv_var
        # every frame, after ``update``: OpenCV's float ops into the model's own buffers
        mul, add = cv2.multiply, cv2.add
        for c in range(3):
            mul(mu[c], inv_var[c], dst=w[c])
        mul(mu[0], w[0], dst=den)
        t = mul(mu[1], w[1])
        add(den, t, dst=den)
        add(den, mul(mu[2], w[2], dst=t), dst=den)
        # A black background pixel has no brightness direction: 1/den -> 0 makes alpha 0 there
        # and all of the observed colour shows up as chromaticity distortion.
        # (one pass finds whether there is any: almost never, and then the clamp is a no-op;
        # numpy's 1 / x is the same IEEE quotient as OpenCV's and several times faster)
        if cv2.minMaxLoc(den)[0] > 1e-6:
            np.divide(np.float32(1.0), den, out=den)
        else:
            black = cv2.compare(den, 1e-6, cv2.CMP_LE)
            cv2.max(den, 1e-6, dst=den)
            cv2.divide(1.0, den, dst=den)
            den[black > 0] = 0.0
        if self.shadows.shadow_ncc > -1.0:
            # the texture test's background grey levels, padded as its windows read them: E is
            # fixed until the next update, so this runs with the update (in its worker thread)
            r = self.shadows.shadow_window // 2
            self._e_pad = cv2.copyMakeBorder(cv2.add(cv2.add(mu[0], mu[1]), mu[2]), r, r, r, r, cv2.BORDER_REFLECT)
        self._terms_refreshed += 1
        if self._texture_wide:
            # the next frame most likely has shadow over much of it too: its texture test's
            # prefilter, worked out here (in the update's worker thread) rather than by it
            self._textured_background()

    def _textured_background(self) -> np.ndarray | None:
        """(H, W) bool: the variance of E's grey sum over each pixel's whole ``shadow_window``
        exceeds ``texture_prefilter`` times the texture test's floor there; None with no
        prefilter. Kept until E changes (``_refresh_colour_terms``).
        """
        if self.shadows.texture_prefilter <= 0.0:
            return None
        if self._bg_textured_at == self._terms_refreshed:
            return self._bg_textured
        e = self.grey_
        k = (self.shadows.shadow_window, self.shadows.shadow_window)
        # centred on the frame's mean: the variance is a difference of float32 means, exact
        # enough only near zero
        c = cv2.subtract(e, float(cv2.mean(e)[0]))
        mean = cv2.boxFilter(c, -1, k, borderType=cv2.BORDER_REFLECT)
        var = cv2.boxFilter(cv2.multiply(c, c), -1, k, borderType=cv2.BORDER_REFLECT)
        var -= cv2.multiply(mean, mean)
        floor = cv2.add(cv2.add(self._var[0], self._var[1]), self._var[2])
        floor *= np.float32(self.shadows.shadow_texture_k**2 * self.shadows.texture_prefilter)
        self._bg_textured, self._bg_textured_at = var > floor, self._terms_refreshed
        return self._bg_textured

    def _refresh_thresholds(self) -> None:
        t = self.thresholds_
        self._alpha_hi = (1.0 + t["tau_alpha1"] * self.a_).astype(np.float32)
        self._alpha_lo = (1.0 + t["tau_alpha2"] * self.a_).astype(np.float32)
        darkest, darkest_unseen, brightest = self.shadow_bounds()
        if self.thresholds.tau_alpha_lo is None:
            floor = np.full(self.a_.shape, np.float32(darkest))
            if self.unseen_ is not None:
                floor[self.unseen_] = darkest_unseen
            self._alpha_min = np.minimum(floor, self._alpha_lo)
        else:
            self._alpha_min = (1.0 + t["tau_alpha_lo"] * self.a_).astype(np.float32)
        self._cd2_max = ((t["tau_cd"] * self.b_) ** 2).astype(np.float32)
        self._alpha_max = np.maximum(np.float32(brightest), self._alpha_hi)

    def _distortions(self, frame: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
        """Raw alpha (eq. 5) and CD^2 (eq. 6), each (H, W) float32, and the frame's three float32
        channel planes (H, W), left unchanged for ``update`` (:func:`distortions`).
        """
        planes = _float_planes(frame)
        alpha, cd2 = distortions(planes, self._w, self._inv_var, self._inv_den)
        return alpha, cd2, planes

    def _inlier_mask(self, planes: list[np.ndarray]) -> np.ndarray:
        """(H, W) bool: every channel of the frame (its float32 planes, ``_distortions``'s) within
        ``robust_inlier_k`` spreads of E.
        """
        # OpenCV's float ops (the same IEEE differences and products as numpy's), one plane at a time
        z = cv2.multiply(cv2.absdiff(planes[0], self._mu[0]), self._inv_s[0])
        t = np.empty_like(z)
        for c in (1, 2):
            cv2.max(z, cv2.multiply(cv2.absdiff(planes[c], self._mu[c], dst=t), self._inv_s[c], dst=t), dst=z)
        return z <= np.float32(self.training.robust_inlier_k)


def _reflect(i: np.ndarray, n: int) -> np.ndarray:
    """Indices ``i`` (any shape, int) into an axis of length ``n``, out-of-range ones mirrored as
    ``cv2.BORDER_REFLECT`` pads (-1 -> 0, n -> n - 1; at most n beyond either end).
    """
    return np.where(i < 0, -1 - i, np.where(i >= n, 2 * n - 1 - i, i))


def _surround_near_candidates(
    mu: np.ndarray, fg: np.ndarray, sy: np.ndarray, sx: np.ndarray, k: int
) -> tuple[np.ndarray, np.ndarray]:
    """The background support and E sums around candidate cells, for ``_matches_surround``.

    On the 4 x 4 block means (``cv2.INTER_AREA`` at an exact factor of 4: each cell from its own
    block) of the background mask (not ``fg``) and of E times it, a k x k normalised box filter
    (``BORDER_REFLECT``) read at the candidates' cells. Only the cells within k // 2 of a
    candidate's are computed: the candidates (a still person or a ghost) cover a small part of
    the frame. The box filter of float32 input sums in float64, exactly for grey levels, so a
    cell's value does not depend on the crop (and a crop edge on the frame's edge reflects as the
    frame's does). A side that is not a multiple of 4 ends in a part cell: the crop is extended
    to whole blocks by reflecting its last rows or columns (``BORDER_REFLECT``), so the last
    cell is the mean of its pixels and their mirror images; a full-frame area resize to a
    non-integer factor instead costs several times the whole update (frames 237 rows high).

    Parameters
    ----------
    mu : ndarray of shape (3, H, W), dtype float32
        E planes, grey levels.
    fg : ndarray of shape (H, W), dtype bool
        The foreground.
    sy, sx : ndarray of shape (K,), dtype int
        The candidates' cells (pixel row and column // 4).
    k : int
        Box side, cells (odd).

    Returns
    -------
    cnt : ndarray of shape (K,), dtype float32
        Fraction of background pixels around each candidate.
    near : ndarray of shape (3, K), dtype float32
        Sum of E over those pixels, per channel, over the same area (divide by ``cnt``).
    """
    h, w = mu.shape[1:]
    sh, sw = -(-h // 4), -(-w // 4)  # cells, the last one part of a block where a side is not a multiple of 4
    r = k // 2
    y0, y1 = max(0, int(sy.min()) - r), min(sh, int(sy.max()) + r + 1)
    x0, x1 = max(0, int(sx.min()) - r), min(sw, int(sx.max()) + r + 1)
    ch, cw = y1 - y0, x1 - x0
    # rows and columns short of whole blocks at the frame's far edges (0 unless the crop reaches them)
    pb, pr = 4 * y1 - min(4 * y1, h), 4 * x1 - min(4 * x1, w)
    crop = (~fg[4 * y0 : 4 * y1, 4 * x0 : 4 * x1]).view(np.uint8)  # 1 on the background
    mus = mu[:, 4 * y0 : 4 * y1, 4 * x0 : 4 * x1]
    if pb or pr:
        crop = cv2.copyMakeBorder(crop, 0, pb, 0, pr, cv2.BORDER_REFLECT)
        mus = [cv2.copyMakeBorder(m, 0, pb, 0, pr, cv2.BORDER_REFLECT) for m in mus]
    cropf = crop.astype(np.float32)
    support = cv2.resize(cropf, (cw, ch), interpolation=cv2.INTER_AREA)
    cy, cx = sy - y0, sx - x0
    cnt = cv2.boxFilter(support, -1, (k, k), borderType=cv2.BORDER_REFLECT)[cy, cx]
    # the three planes stacked as one (3 ch, cw) image: one area resize (block means never
    # straddle two planes); the products plane by plane with OpenCV into it (the same IEEE
    # products as numpy's mixed-type broadcast, at a fraction of its cost)
    prod = np.empty((3 * 4 * ch, 4 * cw), np.float32)
    for c in range(3):
        cv2.multiply(mus[c], cropf, dst=prod[c * 4 * ch : (c + 1) * 4 * ch])
    small3 = cv2.resize(prod, (cw, 3 * ch), interpolation=cv2.INTER_AREA)
    near = np.empty((3, sy.size), np.float32)
    for c in range(3):
        near[c] = cv2.boxFilter(small3[c * ch : (c + 1) * ch], -1, (k, k), borderType=cv2.BORDER_REFLECT)[cy, cx]
    return cnt, near


def _float_planes(frame: np.ndarray) -> list[np.ndarray]:
    """The three channel planes of a uint8 (H, W, 3) frame as float32 (H, W)."""
    return [p.astype(np.float32) for p in cv2.split(frame)]


def _median_mad(stack: np.ndarray, free: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-pixel temporal median and 1.4826 * MAD of (N, H, W, 3) uint8, row block by row block.

    ``free`` (N, H, W) bool: only those samples count (None: all). Returns median (H, W, 3) and
    spread (H, W, 3) float32, and the number of samples used (H, W) int (0: both are 0 there).
    """
    n, h, w, _ = stack.shape
    if free is None:
        rows = max(1, int(_BLOCK_BYTES // (n * w * 3 * 4)))
        med = np.empty((h, w, 3), np.float32)
        mad = np.empty((h, w, 3), np.float32)
        for y0 in range(0, h, rows):
            blk = stack[:, y0 : y0 + rows].astype(np.float32)
            m = np.median(blk, axis=0)
            med[y0 : y0 + rows] = m
            mad[y0 : y0 + rows] = np.median(np.abs(blk - m), axis=0) * _MAD_TO_SIGMA
        return med, mad, np.full((h, w), n, np.int64)
    count = free.sum(axis=0)
    # In integers, twice the grey levels (uint16): the median of two middle values and the
    # deviations from it are then whole, and exact, as the float32 halves they stand for.
    # Excluded samples become _EXCLUDED and sort last: the median of the c free ones is the mean
    # of the sorted values at (c - 1) // 2 and c // 2, gathered per pixel (no Python loop).
    med = np.zeros((h, w, 3), np.float32)
    mad = np.zeros((h, w, 3), np.float32)

    def block(sl: slice) -> None:
        blk2 = stack[:, sl].astype(np.int16)
        blk2 <<= 1
        out = np.broadcast_to(~free[:, sl, :, None], blk2.shape)
        c = np.broadcast_to(count[None, sl, :, None], (1, *blk2.shape[1:]))
        m2 = _masked_median2(np.where(out, _EXCLUDED, blk2.view(np.uint16)), c)  # lo + hi of the doubled values
        # the deviations in quarter grey levels (within int16): 4 |v - median| = |4 v - m2|
        blk2 <<= 1
        blk2 -= m2.astype(np.int16)[None]
        np.abs(blk2, out=blk2)
        dev = np.where(out, _EXCLUDED, blk2.view(np.uint16))
        med[sl] = m2.astype(np.float32) * np.float32(0.25)
        mad[sl] = (_masked_median2(dev, c).astype(np.float32) * np.float32(0.125)) * _MAD_TO_SIGMA

    # each pixel's median is its own: the row blocks (at least two) go to two threads, as numpy's
    # sort lets go of the GIL
    rows = max(1, min(int(_BLOCK_BYTES // (3 * n * w * 3 * 4)), -(-h // 2)))
    with ThreadPoolExecutor(max_workers=2, thread_name_prefix="fit") as pool:
        list(pool.map(block, [slice(y0, y0 + rows) for y0 in range(0, h, rows)]))
    seen = count > 0
    med[~seen] = 0.0
    mad[~seen] = 0.0
    return med, mad, count


def _masked_median2(values: np.ndarray, count: np.ndarray) -> np.ndarray:
    """Twice the median along axis 0 of (N, ...) uint16 values whose excluded entries are
    ``_EXCLUDED``: the sum (int32) of the sorted values at (c - 1) // 2 and c // 2, with ``count``
    (1, ...) the c free entries per position (>= 1 where the result is used).
    """
    srt = np.sort(values, axis=0)
    last = values.shape[0] - 1
    lo = np.take_along_axis(srt, np.clip((count - 1) // 2, 0, last), axis=0)[0]
    hi = np.take_along_axis(srt, np.clip(count // 2, 0, last), axis=0)[0]
    return np.add(lo, hi, dtype=np.int32)


def _mean_std(stack: np.ndarray, free: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-pixel sample mean and standard deviation of (N, H, W, 3) uint8 over the ``free``
    (N, H, W) bool samples (None: all); returns mean, std (H, W, 3) float32 and counts (H, W).
    """
    n = stack.shape[0]
    acc = np.zeros(stack.shape[1:], np.float64)
    acc2 = np.zeros(stack.shape[1:], np.float64)
    for k, f in enumerate(stack):
        ff = f.astype(np.float64)
        if free is not None:
            ff *= free[k][..., None]
        acc += ff
        acc2 += ff * ff
    count = np.full(stack.shape[1:3], n, np.int64) if free is None else free.sum(axis=0)
    c = np.maximum(count, 1)[..., None].astype(np.float64)
    m = acc / c
    var = np.maximum(acc2 / c - m * m, 0.0) * c / np.maximum(c - 1.0, 1.0)
    return m.astype(np.float32), np.sqrt(var).astype(np.float32), count


def _fill_unseen(
    mean: np.ndarray, spread: np.ndarray, unseen: np.ndarray, spread_gain: float
) -> tuple[np.ndarray, np.ndarray]:
    """E and s (H, W, 3) float32 with the ``unseen`` (H, W) pixels filled in from around them.

    Telea inpainting (``cv2.inpaint``) continues the colours of the surrounding room into the
    hole, channel by channel; the spread likewise, times ``spread_gain``: a guess is less certain
    than a measurement, and the floor's texture is not continued.
    """
    hole = unseen.astype(np.uint8)
    # radius: a few pixels of support around each point of the hole's front
    radius = 5
    planes = [a[..., c] for a in (mean, spread) for c in range(3)]
    # six independent fills, on two threads (OpenCV lets go of the GIL)
    with ThreadPoolExecutor(max_workers=2, thread_name_prefix="fit") as pool:
        filled = list(pool.map(lambda p: cv2.inpaint(p, hole, radius, cv2.INPAINT_TELEA), planes))
    mean = mean.copy()
    spread = spread.copy()
    for c in range(3):
        mean[..., c] = filled[c]
        spread[..., c] = np.where(unseen, filled[3 + c] * np.float32(spread_gain), spread[..., c])
    return mean, spread
