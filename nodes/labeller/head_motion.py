"""Head nod and head shake by frequency analysis of head motion (Okwechime et al., Sec. "head nod
and shake": FFT of the head's vertical and horizontal motion over a short sliding window).

Where the head's motion comes from, best first (chosen per call by what is given):

- **the tracker's head angles** (``head_pitch`` / ``head_yaw``: the ``head_nod`` / ``head_turn``
  degrees of freedom of the pose vector, ``counterpart.body.pose``, relative to the torso): the nod channel is
  ``pitch_radius * pitch`` (the arc the head centre travels about the neck joint, in metres, the
  same motion the head point shows) and the shake channel ``head_radius * yaw`` (the arc the face
  travels about the neck's vertical axis). A head shake is a rotation about the neck's vertical axis that hardly moves the head
  centre (in the simulator's body model it does not move it at all), so its yaw velocity, not a
  head point, is the natural shake signal. A given angle *replaces* the head-point channels of its
  kind, because those are then redundant and a nod made with the head turned away would otherwise
  leak into the lateral (shake) channel.
- **the 3D head point relative to the neck** (tracker joints without angles): ``up`` (world Y) and
  ``forward`` (along the facing direction) for nods, ``lateral`` (towards the person's left) for
  shakes; relative to the neck so that walking and whole-body motion (gait bob, sway) cancel.
- **the silhouette's head reference point** relative to a body reference point, in pixels scaled
  to metres by the person's height (:func:`head_channels_2d`).

Each window of ``N = round(window_s * fps)`` frames of every channel is first reduced to its
*oscillation*: the running median of width ``K = median_s * fps`` (odd, edges replicated inside
the window) is subtracted. A running median follows any monotone movement exactly (a look away
and the hold after it, a slow drift) and removes back-and-forth movement shorter than about ``K``
frames, so the residual keeps nods and shakes but not head turns. The nod channels use
``nod_median_s`` = 1 s, one period of the band's lowest frequency, so that slow nods pass whole;
the shake channels a shorter ``shake_median_s`` = 0.44 s, so that a quick glance away and back (a
single excursion of half a second or more) is followed by the median and not taken for a shake. A
quicker glance stays in the residual but is no oscillation: a shake swings back against its
largest excursion, before it and after it, while a glance aside and back swings back only by how
far it overshoots the rest on its way back (:func:`counter_swings`, on the lateral motion less its
running median of width ``swing_median_s`` = 0.8 s, twice a quick glance, which keeps the glance
whole): a window whose swings back add up to under ``shake_swing`` of its largest excursion has
shake score 0. The residual has its window mean
removed, is multiplied by a Hann window ``w`` and transformed with a real FFT. With one-sided
energies ``P_k`` scaled by Parseval so that ``sum_k P_k = sum_n (w_n x_n)^2``, the scores are::

    nod_score   = sum_{k in band, c in nod}   P_ck / max(E_total, E_floor)
    shake_score = sum_{k in band, c in shake} P_ck / max(E_total, E_floor)
    E_total     = sum_{k >= 1, all c} P_ck          (all oscillating head motion)
    E_floor     = a_floor^2 / 2 * sum_n w_n^2       (energy of a sinusoid of amplitude a_floor)

with ``a_floor`` one of four floors: nod / shake, from the head point or from the tracker's angles
(a difference of two tracked joints is the noisier measurement of the two, so its floors are
higher).

so a score is the fraction of all oscillating head motion that is band-limited nod (resp. shake)
motion, scaled down when the motion is smaller than the amplitude floor ``a_floor``. Scores are in
[0, 1]; the label is ``score >= threshold``. Windows that contain a missing (nan) sample give
``nan`` / UNKNOWN, as do the frames before the first full window. A median width of 0 turns
the median stage off for its channels (the plain FFT of the motion).

Timing: ``center=False`` (the streaming default) labels frame ``t`` from the window that ends at
``t`` (causal: the labels are those of ``center=True`` delayed by ``N // 2`` frames, 0.8 s at the
defaults); ``center=True`` (offline) from the window centred on ``t``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from counterpart.nodes.labeller.signals import UNKNOWN, threshold_labels

#: channel order inside the detectors: (nod_a, nod_b, shake_a, shake_b); from positions these are
#: (up, forward, lateral, 0), from the tracker's angles (pitch_radius * pitch, 0, 0,
#: head_radius * yaw)
_NOD_CHANNELS = (0, 1)
_SHAKE_CHANNELS = (2, 3)
#: the channel kind of a tracked face's head point (its floors are in face widths)
FACE = 2


@dataclass(frozen=True)
class HeadMotionParams:
    """Parameters of nod/shake detection.

    Parameters
    ----------
    fps : float
        Frames per second of the input, Hz; > 0.
    window_s : float, default=1.6
        FFT window length, seconds; 1.5-2 s is typical (at least 8 frames).
    band_hz : tuple of float (low, high), default=(1.0, 4.0)
        Frequency band of nods and shakes, Hz; must hold an FFT bin.
    nod_floor_m, shake_floor_m : float, default=0.01
        Amplitude floors (m) of head-point motion under which it is scaled down.
    pitch_floor_m, yaw_floor_m : float, default=0.005, 0.0075
        The same for the arcs of the tracker's head angles (nods are smaller movements than
        shakes: a 5-10 degree nod moves the head centre 1.5-3 cm, a 15-20 degree shake the face 3 cm).
    threshold : float, default=0.5
        Score threshold of the label, in (0, 1].
    head_radius_m : float, default=0.1
        Converts a head yaw (rad) to the arc the face travels about the neck's vertical axis (m).
    pitch_radius_m : float, default=0.18
        Converts a head pitch (rad) to the arc the head centre travels about the neck joint (m; the
        neck-to-head distance), so angle and head-point nods share a scale.
    nod_median_s, shake_median_s : float, default=1.0, 0.44
        Width (s) of the running median whose residual is analysed, on the nod / shake channels
        (0: no median stage); movements that go one way and stay are removed, back-and-forth ones
        up to about this long kept.
    face_nod_floor, face_shake_floor : float, default=0.06
        The amplitude floors of a tracked face's head point (:class:`HeadMotionDetectorFace`), in
        units of the face's own width (a 10 degree nod moves the eyes about 0.15 face widths, a 5
        degree one 0.075; detector jitter left after tracking is about 0.005; a body bouncing on its
        knees moves the face about 0.03).
    local_s : float, default=0.25
        Localisation of an event inside its window (see :meth:`_Spectral.local`): the width (s) of
        the moving mean of band-passed motion energy.
    event_on, event_off : float, default=0.6, 0.3
        The hysteresis thresholds on the local amplitude as a fraction of the window's largest local
        amplitude (an event is a run of frames >= event_off that reaches event_on). ``event_on`` 0
        labels every frame of a detected window (no localisation).
    shake_swing : float, default=0.3
        The least swing back against a window's largest lateral excursion, before and after it
        together, as a fraction of that excursion (unitless, in [0, 2]; :func:`counter_swings`):
        a shake is an oscillation and swings back by about 0.5-1.2, a glance aside and back only
        by its overshoot of the rest, so a window under it has shake score 0. 0 turns the test off.
    swing_median_s : float, default=0.8
        Width (s) of the running median removed from the lateral motion before
        :func:`counter_swings`: at least twice a quick glance (0.37 s), so that the glance is kept
        whole (under a median about as long as the glance only its tip is left, and an overshoot
        after it looks larger); shorter than a look-away, whose hold it follows (1 s let the ramps
        of a look-away into the test).

    Raises
    ------
    ValueError
        If a parameter is out of its range (the message names it).
    """

    fps: float
    window_s: float = 1.6
    band_hz: tuple[float, float] = (1.0, 4.0)
    nod_floor_m: float = 0.01
    shake_floor_m: float = 0.01
    pitch_floor_m: float = 0.005
    yaw_floor_m: float = 0.0075
    threshold: float = 0.5
    head_radius_m: float = 0.1
    pitch_radius_m: float = 0.18
    nod_median_s: float = 1.0
    shake_median_s: float = 0.44
    face_nod_floor: float = 0.06
    face_shake_floor: float = 0.06
    local_s: float = 0.25
    event_on: float = 0.6
    event_off: float = 0.3
    shake_swing: float = 0.3
    swing_median_s: float = 0.8

    def __post_init__(self) -> None:
        if not self.fps > 0:
            raise ValueError(f"fps must be > 0, got {self.fps}")
        n = self.n
        if n < 8:
            raise ValueError(
                f"window_s * fps = {self.window_s} * {self.fps} gives {n} frames; need >= 8 (use a longer window_s)"
            )
        lo, hi = self.band_hz
        if not 0 < lo < hi:
            raise ValueError(f"band_hz must be (low, high) with 0 < low < high, got {self.band_hz}")
        freqs = np.fft.rfftfreq(n, 1.0 / self.fps)
        if not ((freqs >= lo) & (freqs <= hi)).any():
            raise ValueError(
                f"band_hz {self.band_hz} holds no FFT bin for a {n}-frame window at {self.fps} fps "
                f"(bins are {freqs[1]:.3g} Hz apart): widen the band or lengthen window_s"
            )
        floors = {
            k: getattr(self, k)
            for k in (
                "nod_floor_m",
                "shake_floor_m",
                "pitch_floor_m",
                "yaw_floor_m",
                "face_nod_floor",
                "face_shake_floor",
            )
        }
        for k, v in floors.items():
            if not v > 0:
                raise ValueError(f"{k} must be > 0 ({'face widths' if k.startswith('face') else 'metres'}), got {v}")
        if not 0 < self.threshold <= 1:
            raise ValueError(
                f"threshold must be in (0, 1] (a fraction of the head's oscillating motion), got {self.threshold}"
            )
        if self.event_on != 0 and not 0 <= self.event_off <= self.event_on <= 1:
            raise ValueError(
                f"event_on and event_off must satisfy 0 <= event_off <= event_on <= 1 (fractions of "
                f"the window's largest local amplitude; event_on 0: no localisation), got event_on={self.event_on}, event_off={self.event_off}"
            )
        if not 0 <= self.shake_swing <= 2:
            raise ValueError(
                f"shake_swing must be in [0, 2] (the least swing back before and after a shake's largest "
                f"lateral excursion together, a fraction of it; 0: no test), got {self.shake_swing}"
            )
        if not self.local_s > 0 or 2 * (self.local_k // 2) + 1 > n:
            raise ValueError(
                f"local_s must be > 0 s and its width in frames ({self.local_k}) at most the window's ({n}), "
                f"got local_s={self.local_s} at {self.fps} fps"
            )
        for name in ("nod_median_s", "shake_median_s", "swing_median_s"):
            v = getattr(self, name)
            if not v >= 0 or self.median_k(v) > n:
                raise ValueError(
                    f"{name} must be >= 0 s and its width in frames ({self.median_k(v)}) at most "
                    f"the window's ({n}), got {name}={v} at {self.fps} fps"
                )

    def median_k(self, seconds: float) -> int:
        """A running-median width in frames.

        Parameters
        ----------
        seconds : float
            The width in seconds (0: no median stage).

        Returns
        -------
        int
            The width in frames, odd; 1 = no median stage.
        """
        return (max(int(round(seconds * self.fps)), 1) | 1) if seconds > 0 else 1

    @property
    def local_k(self) -> int:
        """Width in frames (odd, >= 1) of the moving mean of local motion energy."""
        return max(int(round(self.local_s * self.fps)), 1) | 1

    @property
    def n(self) -> int:
        """Window length in frames."""
        return int(round(self.window_s * self.fps))


class _Spectral:
    """Precomputed Hann window, band mask and Parseval weights for one parameter set."""

    def __init__(self, p: HeadMotionParams) -> None:
        n = p.n
        self.p = p
        self.w = np.hanning(n + 2)[1:-1]  # no zero end-points: every sample contributes
        freqs = np.fft.rfftfreq(n, 1.0 / p.fps)
        # one-sided Parseval weights: sum_k wt_k |X_k|^2 = sum_n (w x)^2
        wt = np.full(freqs.shape, 2.0 / n)
        wt[0] = 1.0 / n
        if n % 2 == 0:
            wt[-1] = 1.0 / n
        wt[0] = 0.0  # DC is removed: it is the head's mean offset, not motion
        self.wt = wt
        lo, hi = p.band_hz
        in_band = (freqs >= lo) & (freqs <= hi)
        self.band = wt * in_band
        self.band_pass = in_band.astype(np.float64)
        # the band's analytic signal on the full FFT (Gabor 1946): in-band positive frequencies
        # doubled (a Nyquist bin kept once), negative ones dropped; its modulus is the envelope
        an = 2.0 * self.band_pass
        if n % 2 == 0:
            an[-1] = self.band_pass[-1]
        self.analytic = np.concatenate([an, np.zeros(n - an.shape[0])])
        sw2 = float(np.sum(self.w**2))
        # floors: [nod, shake] x [head point (m), angle arc (m), tracked face (face widths)]
        self.e_floor = (
            np.array(
                [
                    [p.nod_floor_m, p.pitch_floor_m, p.face_nod_floor],
                    [p.shake_floor_m, p.yaw_floor_m, p.face_shake_floor],
                ]
            )
            ** 2
            / 2.0
            * sw2
        )

    def scores(
        self,
        win: np.ndarray,
        angles: tuple[int, int] = (False, False),
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Scores of channel windows and the local amplitude at their centres.

        Parameters
        ----------
        win : (..., 4, N) channel windows (m, or face widths).
        angles : the kind of the (nod, shake) channels, which picks the floors: 0 (False) a head
            point (m), 1 (True) a tracker's angle (m of arc), :data:`FACE` a tracked face (face widths).

        Returns
        -------
        nod_score, shake_score : (...,) in [0, 1], nan where the window's second half (from its
            centre sample on) holds a missing sample; missing samples before the centre are filled
            (:func:`fill_window_start`), so a track that starts again is labelled from its first frame.
        nod_inside, shake_inside : (...,) 1.0 where the window's centre sample ``N // 2`` is part
            of the window's nod (shake) event by its local band-passed motion (:meth:`local`), else 0.0.
        """
        p = self.p
        win, bad = fill_window_start(win)
        # the swing test sees whole glances: under the shake median (about a glance's length) a
        # glance keeps only its tip while an overshoot after it stays whole (swing_median_s)
        lateral = win[..., _SHAKE_CHANNELS[0], :] + win[..., _SHAKE_CHANNELS[1], :]
        swing = oscillation_residual(lateral, p.median_k(p.swing_median_s)) if p.shake_swing > 0 else None
        win = np.concatenate(
            [
                oscillation_residual(win[..., :2, :], p.median_k(p.nod_median_s)),
                oscillation_residual(win[..., 2:, :], p.median_k(p.shake_median_s)),
            ],
            axis=-2,
        )
        win = win - win.mean(axis=-1, keepdims=True)
        spec = np.fft.rfft(win * self.w, axis=-1)
        if angles[1] == FACE:
            win, spec = without_pitch_leak(win, spec, self.band, self.e_floor[0, FACE])
        pw = spec.real**2 + spec.imag**2  # (..., 4, F)
        total = pw @ self.wt  # (..., 4)
        band = pw @ self.band  # (..., 4)
        e_all = total.sum(axis=-1)
        nod_b = band[..., _NOD_CHANNELS[0]] + band[..., _NOD_CHANNELS[1]]
        shake_b = band[..., _SHAKE_CHANNELS[0]] + band[..., _SHAKE_CHANNELS[1]]
        nod = nod_b / np.maximum(e_all, self.e_floor[0, int(angles[0])])
        shake = shake_b / np.maximum(e_all, self.e_floor[1, int(angles[1])])
        if p.shake_swing > 0:
            shake = np.where(counter_swings(swing).sum(axis=-1) >= p.shake_swing, shake, 0.0)  # type: ignore[arg-type]
        nod = np.where(bad, np.nan, nod)
        shake = np.where(bad, np.nan, shake)
        local = self.local(win)
        return nod, shake, local[..., 0], local[..., 1]

    def local(self, res: np.ndarray) -> np.ndarray:
        """(..., 4, N) zero-mean oscillation residuals -> (..., 2) float, 1.0 where the window's
        centre sample is part of the (nod, shake) event in the window, else 0.0 (see :meth:`scores`).

        The residual is band-passed with the FFT (no taper: the window's ends keep their weight)
        into its analytic signal ``z = x_b + i H(x_b)`` (``H`` the Hilbert transform, Gabor 1946),
        whose squared modulus ``|z|^2`` is the instantaneous energy of the oscillation without the
        ripple at twice its frequency that ``x_b^2`` has (``x_b^2`` drops to 0 at every zero
        crossing, so a threshold on it cuts into an event's weak first and last swings). The
        energies are summed over each channel pair and averaged over ``local_k`` frames, giving the
        local amplitude ``a_j = sqrt(E_j / max_j E_j)`` relative to the window's largest. The centre
        is in the event when it lies in a run of positions with ``a >= event_off`` that reaches
        ``a >= event_on`` somewhere (hysteresis both ways in time: the window sees the centre's past
        and future, so an event is not labelled late). ``event_on`` 0: always 1.0.
        """
        p = self.p
        if p.event_on <= 0:
            return np.ones((*res.shape[:-2], 2))
        n, k = p.n, p.local_k
        z = np.fft.ifft(np.fft.fft(res, axis=-1) * self.analytic, axis=-1)
        e2 = z.real**2 + z.imag**2
        e = np.stack([e2[..., 0, :] + e2[..., 1, :], e2[..., 2, :] + e2[..., 3, :]], axis=-2)  # (..., 2, N)
        c = np.cumsum(np.concatenate([np.zeros((*e.shape[:-1], 1)), e], axis=-1), axis=-1)
        mov = c[..., k:] - c[..., :-k]  # (..., 2, P): k * mean energy around position j + k // 2
        peak = mov.max(axis=-1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            amp = np.sqrt(np.where(peak > 0, mov / peak, 0.0))
        ci = n // 2 - k // 2  # the centre sample's position
        pos = np.arange(amp.shape[-1])
        low = amp < p.event_off
        left = np.where(low[..., : ci + 1], pos[: ci + 1], -1).max(axis=-1)  # last low position <= ci
        right = np.where(low[..., ci:], pos[ci:], amp.shape[-1]).min(axis=-1)  # first low position >= ci
        strong = (amp >= p.event_on) & (pos > left[..., None]) & (pos < right[..., None])
        return (~low[..., ci] & strong.any(axis=-1)).astype(np.float64)


def localise_labels(score: np.ndarray, inside: np.ndarray, p: HeadMotionParams) -> np.ndarray:
    """Labels of frames from their windows' scores and events. The streaming detectors give the same.

    Parameters
    ----------
    score : ndarray of shape (T,)
        Window scores (:meth:`_Spectral.scores`), nan where unknown.
    inside : ndarray of shape (T,)
        Centre-in-event flags (:meth:`_Spectral.scores`), 1.0 or 0.0.
    p : HeadMotionParams
        The parameters (``threshold``).

    Returns
    -------
    ndarray of shape (T,)
        int8 labels: 1 where the frame's window is detected (``score >= threshold``) and the frame
        is part of the window's event; UNKNOWN where the score is nan; else 0.
    """
    lab = threshold_labels(score, p.threshold)
    return np.where(lab == 1, (inside > 0).astype(np.int8), lab).astype(np.int8)


def without_pitch_leak(
    win: np.ndarray, spec: np.ndarray, band: np.ndarray, ridge: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """A tracked face's windows with the lateral motion that moves in step with the nod's rotation
    cue taken out of the shake channel.

    A nod of a head turned to the side moves the face sideways in the image as well as down: the
    head dips forward about the neck, and its forward is then partly across the image (at 40
    degrees of yaw the sideways part is about two thirds of the dip). That sideways motion has a
    nod's frequency, so it scored as a shake and, in the score's denominator, pushed the nod under
    its threshold. A rotation about the neck's vertical axis (a shake) leaves the rotation cue
    (:attr:`counterpart.nodes.labeller.face_track.FaceTrack.tilt`, channel ``nod_b``) still, so
    the part of the lateral channel ``x`` proportional to the cue ``c`` is removed:
    ``x - beta c`` with the least-squares gain over the band's frequencies,
    ``beta = sum_k b_k Re(X_k conj(C_k)) / sum_k b_k |C_k|^2`` (``X``, ``C`` the windowed
    spectra, ``b`` the band's Parseval weights, ``ridge`` added to the denominator). The fit is
    made in the band, where nods and shakes are (both channels accumulate frame-to-frame motion, so
    their noise is a random walk, strong below the band). The band holds few frequencies, so a
    plain least-squares fit to a cue that is only noise would take out a chance share of a real
    shake; the ridge, the band energy of a nod at the face's amplitude floor, gives a cue well under
    that floor (not a rotation the detector would count) little weight.

    Parameters
    ----------
    win : ndarray of shape (..., 4, N)
        Zero-mean oscillation residuals of the channels (nod_a, nod_b, shake_a, shake_b), face widths.
    spec : ndarray of shape (..., 4, F)
        Their real FFTs after the taper, ``F = N // 2 + 1``.
    band : ndarray of shape (F,)
        The band's one-sided Parseval weights (0 outside the band).
    ridge : float, default=0.0
        Added to the cue's band energy in the gain's denominator, (face widths)^2.

    Returns
    -------
    win, spec : ndarray
        Copies with ``shake_a`` (and its spectrum) replaced by ``x - beta c``.
    """
    c, x = spec[..., _NOD_CHANNELS[1], :], spec[..., _SHAKE_CHANNELS[0], :]
    cc = (c.real**2 + c.imag**2) @ band + ridge
    xc = (x.real * c.real + x.imag * c.imag) @ band
    with np.errstate(invalid="ignore", divide="ignore"):
        beta = np.where(cc > 0, xc / cc, 0.0)[..., None]
    win, spec = win.copy(), spec.copy()
    win[..., _SHAKE_CHANNELS[0], :] -= beta * win[..., _NOD_CHANNELS[1], :]
    spec[..., _SHAKE_CHANNELS[0], :] -= beta * c
    return win, spec


def counter_swings(res: np.ndarray) -> np.ndarray:
    """How far a window's motion swings back against its largest excursion, before and after it.

    A shake is an oscillation: its largest swing is flanked by swings the other way (a
    Hann-enveloped shake of 1.5 cycles, the shortest the simulator plants, swings about 0.25, -1,
    0.25; one of 2 cycles 0.15, -0.85, 0.85, -0.15), so the two add up to about 0.5-1.2 of it. A
    glance aside and back reverses once; if it overshoots the rest on its way back it swings back
    by the overshoot's fraction of the glance, after it only. Excursions are about the head's rest,
    the window's median: with ``x`` the residual less its median, mirrored so that its largest
    excursion ``x_i = peak`` is positive, ``before = max(0, max_{n < i} -x_n) / peak`` and
    ``after = max(0, max_{n > i} -x_n) / peak``.

    Parameters
    ----------
    res : ndarray of shape (..., N)
        Oscillation residuals of the lateral motion (any unit), long enough a median that a glance
        is kept whole (a median about as long as the glance keeps only its tip, and so makes an
        overshoot after it look larger).

    Returns
    -------
    ndarray of shape (..., 2)
        ``(before, after)``, unitless, >= 0; 0 for a window without motion.
    """
    x = res - np.median(res, axis=-1, keepdims=True)
    hi, lo = x.max(axis=-1), -x.min(axis=-1)
    x = np.where((lo > hi)[..., None], -x, x)  # the largest excursion made positive
    peak = np.maximum(hi, lo)[..., None]
    i = np.argmax(x, axis=-1)[..., None]
    pos = np.arange(x.shape[-1])
    against = np.stack([np.where(pos < i, -x, 0.0).max(axis=-1), np.where(pos > i, -x, 0.0).max(axis=-1)], axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(peak > 0, against / np.where(peak > 0, peak, 1.0), 0.0)


def fill_window_start(win: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Windows with missing samples before their centre filled.

    A track that was lost is then scored again once half a window has been seen since (its
    centre frame known), instead of a whole window, and the first half's gap adds no motion.

    Parameters
    ----------
    win : ndarray of shape (..., C, N)
        Channel windows; nan (in any channel) where a sample is missing.

    Returns
    -------
    filled : ndarray of shape (..., C, N)
        The windows with missing samples before their centre ``N // 2`` filled with the next known
        sample of their channel (as if the head had held still until it was seen); those from the
        centre on filled with 0.
    bad : ndarray of shape (...,)
        bool: the windows with a missing sample from the centre on (unknown).
    """
    miss = np.isnan(win).any(axis=-2)  # (..., N): a sample is missing when any channel is
    if not miss.any():
        return win, np.zeros(win.shape[:-2], bool)
    n = win.shape[-1]
    bad = miss[..., n // 2 :].any(axis=-1)
    idx = np.where(miss, n - 1, np.arange(n))
    nxt = np.flip(np.minimum.accumulate(np.flip(idx, axis=-1), axis=-1), axis=-1)
    filled = np.take_along_axis(win, np.broadcast_to(nxt[..., None, :], win.shape), axis=-1)
    return np.where(np.isnan(filled), 0.0, filled), bad


def oscillation_residual(win: np.ndarray, k: int) -> np.ndarray:
    """``win - running_median(win, k)`` along the last axis.

    The median is centred; the window's end samples are replicated ``k // 2`` times so every sample
    has a full neighbourhood (a monotone window stays monotone, so its residual is exactly 0).
    Vectorised over all leading axes.

    Parameters
    ----------
    win : ndarray of shape (..., N)
        Windows, any unit.
    k : int
        Median width in frames, odd; ``k <= 1`` returns ``win`` unchanged.

    Returns
    -------
    ndarray of shape (..., N)
        The residual, in the unit of ``win``.
    """
    if k <= 1:
        return win
    h = k // 2
    padded = np.concatenate([np.repeat(win[..., :1], h, axis=-1), win, np.repeat(win[..., -1:], h, axis=-1)], axis=-1)
    return win - np.median(sliding_window_view(padded, k, axis=-1), axis=-1)


def facing_vectors(facing_yaw: np.ndarray | float, t: int) -> tuple[np.ndarray, np.ndarray]:
    """Forward and left unit vectors for a facing yaw.

    Parameters
    ----------
    facing_yaw : ndarray of shape (T,) or float
        Yaw, radians about +Y, 0 faces +Z.
    t : int
        Number of frames T.

    Returns
    -------
    forward, left : ndarray of shape (T, 3)
        Unit vectors in the ground plane.
    """
    yaw = np.broadcast_to(np.asarray(facing_yaw, dtype=np.float64), (t,))
    s, c = np.sin(yaw), np.cos(yaw)
    z = np.zeros_like(s)
    fwd = np.stack([s, z, c], axis=-1)
    left = np.stack([c, z, -s], axis=-1)
    return fwd, left


def _angle_arc(angle: np.ndarray | None, t: int, name: str, radius_m: float) -> np.ndarray | None:
    """(T,) arc (m) of a head angle (rad), unwrapped over its known samples; None if not given."""
    if angle is None:
        return None
    a = np.asarray(angle, dtype=np.float64)
    if a.shape != (t,):
        raise ValueError(f"{name} must be (T,) = ({t},) radians, got {a.shape}")
    ok = ~np.isnan(a)
    un = a.copy()
    if ok.any():
        un[ok] = np.unwrap(a[ok])
    return radius_m * un


def head_channels_3d(
    head: np.ndarray,
    neck: np.ndarray,
    facing_yaw: np.ndarray | float | None = None,
    head_yaw: np.ndarray | None = None,
    head_radius_m: float = 0.1,
    head_pitch: np.ndarray | None = None,
    pitch_radius_m: float = 0.18,
) -> np.ndarray:
    """Head motion channels (T,4), metres: (nod_a, nod_b, shake_a, shake_b).

    From positions: (up, forward, lateral, 0) of the head relative to the neck in the body frame.
    With the tracker's head angles (relative to the torso, ``counterpart.body.pose`` ``head_turn`` and
    ``head_nod``): ``head_yaw`` makes the shake channels (0, head_radius_m * yaw) and
    ``head_pitch`` the nod channels (pitch_radius_m * pitch, 0); a given angle replaces the position channels of its
    kind (see the module docstring).

    Parameters
    ----------
    head, neck : ndarray of shape (T, 3)
        World positions, metres, Y up.
    facing_yaw : ndarray of shape (T,) or float or None, default=None
        Body yaw, radians, 0 faces +Z; None means 0.
    head_yaw : ndarray of shape (T,) or None, default=None
        Head yaw relative to the torso, radians (any zero; unwrapped here).
    head_radius_m : float, default=0.1
        Radius converting the head yaw to an arc, metres.
    head_pitch : ndarray of shape (T,) or None, default=None
        Head pitch relative to the torso, radians (any zero; unwrapped here).
    pitch_radius_m : float, default=0.18
        Radius converting the head pitch to an arc, metres.

    Returns
    -------
    ndarray of shape (T, 4)
        The channels (nod_a, nod_b, shake_a, shake_b), metres.

    Raises
    ------
    ValueError
        If ``head`` and ``neck`` are not both (T, 3), or an angle is not (T,).
    """
    head = np.asarray(head, dtype=np.float64)
    neck = np.asarray(neck, dtype=np.float64)
    if head.ndim != 2 or head.shape[1] != 3 or neck.shape != head.shape:
        raise ValueError(f"head and neck must both be (T,3) metres; got {head.shape} and {neck.shape}")
    t = head.shape[0]
    rel = head - neck
    fwd, left = facing_vectors(0.0 if facing_yaw is None else facing_yaw, t)
    ch = np.zeros((t, 4))
    yaw_arc = _angle_arc(head_yaw, t, "head_yaw", head_radius_m)
    pitch_arc = _angle_arc(head_pitch, t, "head_pitch", pitch_radius_m)
    if pitch_arc is None:
        ch[:, 0] = rel[:, 1]
        ch[:, 1] = np.einsum("ij,ij->i", rel, fwd)
    else:
        ch[:, 0] = pitch_arc
        ch[np.isnan(rel).any(axis=1), 1] = np.nan  # missing joints stay missing
    if yaw_arc is None:
        ch[:, 2] = np.einsum("ij,ij->i", rel, left)
    else:
        ch[:, 3] = yaw_arc
        ch[np.isnan(rel).any(axis=1), 2] = np.nan
    return ch


def head_channels_2d(
    head_px: np.ndarray,
    ref_px: np.ndarray,
    height_px: np.ndarray | float,
    person_height_m: float = 1.7,
) -> np.ndarray:
    """Channels (T,4) from image points: the silhouette's head reference point relative to a body
    reference point (e.g. the silhouette centroid), converted to metres by the person's height.

    Image up is the nod channel, image x the lateral (shake) channel; depth is not seen, so
    the forward and yaw channels are 0. Crude: a shake that only rotates the head moves the top of the
    head very little in the image, so 2D shakes are found only when they move the head sideways.

    Parameters
    ----------
    head_px, ref_px : ndarray of shape (T, 2)
        Head and body reference points, pixels (x right, y down).
    height_px : ndarray of shape (T,) or float
        Silhouette height, pixels; frames where it is not > 0 are missing (nan).
    person_height_m : float, default=1.7
        The person's height, metres.

    Returns
    -------
    ndarray of shape (T, 4)
        The channels (nod_a, nod_b, shake_a, shake_b), metres.

    Raises
    ------
    ValueError
        If ``head_px`` and ``ref_px`` are not both (T, 2).
    """
    head_px = np.asarray(head_px, dtype=np.float64)
    ref_px = np.asarray(ref_px, dtype=np.float64)
    if head_px.ndim != 2 or head_px.shape[1] != 2 or ref_px.shape != head_px.shape:
        raise ValueError(f"head_px and ref_px must both be (T,2) pixels; got {head_px.shape} and {ref_px.shape}")
    t = head_px.shape[0]
    h = np.broadcast_to(np.asarray(height_px, dtype=np.float64), (t,))
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(h > 0, person_height_m / h, np.nan)
    rel = (head_px - ref_px) * scale[:, None]
    ch = np.zeros((t, 4))
    ch[:, 0] = -rel[:, 1]
    ch[:, 2] = rel[:, 0]
    ch[np.isnan(scale)] = np.nan
    return ch


@dataclass(frozen=True)
class HeadMotionResult:
    """Per-frame nod/shake scores and labels.

    Attributes
    ----------
    nod_score, shake_score : ndarray of shape (T,)
        Scores in [0, 1] (nan = unknown).
    nod, shake : ndarray of shape (T,)
        int8 labels (1 / 0 / UNKNOWN).
    """

    nod_score: np.ndarray
    nod: np.ndarray
    shake_score: np.ndarray
    shake: np.ndarray


def scores_from_channels(
    channels: np.ndarray,
    params: HeadMotionParams,
    center: bool = False,
    angles: tuple[bool, bool] = (False, False),
) -> HeadMotionResult:
    """Batch nod/shake over a whole (T,4) channel trajectory, vectorised over all windows.

    Frame ``t`` is scored from window ``[t-N+1, t]`` (causal) or ``[t-N//2, t-N//2+N)`` (center);
    the samples before the sequence count as missing (:func:`fill_window_start`: a window is scored
    once its centre sample is), later frames without a full window are UNKNOWN.

    Parameters
    ----------
    channels : ndarray of shape (T, 4)
        The channels (nod_a, nod_b, shake_a, shake_b), metres (or face widths).
    params : HeadMotionParams
        The parameters.
    center : bool, default=False
        Centred (offline) windows instead of causal ones.
    angles : tuple of bool, default=(False, False)
        (nod channels from the tracker's pitch, shake channels from its yaw), which picks the
        amplitude floors.

    Returns
    -------
    HeadMotionResult
        (T,) scores and labels.

    Raises
    ------
    ValueError
        If ``channels`` is not (T, 4).
    """
    ch = np.asarray(channels, dtype=np.float64)
    if ch.ndim != 2 or ch.shape[1] != 4:
        raise ValueError(f"channels must be (T,4), got {ch.shape}")
    t, n = ch.shape[0], params.n
    nod = np.full(t, np.nan)
    shake = np.full(t, np.nan)
    loc_nod = np.zeros(t)
    loc_shake = np.zeros(t)
    # window i ends at frame i (the n - 1 before the sequence are missing)
    padded = np.concatenate([np.full((n - 1, 4), np.nan), ch])
    win = sliding_window_view(padded.T, n, axis=1).transpose(1, 0, 2)  # (T, 4, N)
    s_nod, s_shake, l_nod, l_shake = _Spectral(params).scores(win, angles)
    first = -(n - 1 - n // 2) if center else 0  # frame of window 0
    lo, hi = max(first, 0), min(t, t + first)
    for dst, src in ((nod, s_nod), (shake, s_shake), (loc_nod, l_nod), (loc_shake, l_shake)):
        dst[lo:hi] = src[lo - first : hi - first]
    return HeadMotionResult(
        nod, localise_labels(nod, loc_nod, params), shake, localise_labels(shake, loc_shake, params)
    )


def head_motion(
    head: np.ndarray,
    neck: np.ndarray,
    fps: float,
    window_s: float = 1.6,
    facing_yaw: np.ndarray | float | None = None,
    head_yaw: np.ndarray | None = None,
    center: bool = False,
    head_pitch: np.ndarray | None = None,
    **params: object,
) -> HeadMotionResult:
    """Nod and shake over a whole 3D trajectory.

    Parameters
    ----------
    head, neck : ndarray of shape (T, 3)
        Metres, world frame, Y up.
    fps : float
        Frame rate, Hz.
    window_s : float, default=1.6
        FFT window, seconds.
    facing_yaw : ndarray of shape (T,) or float or None, default=None
        Body yaw, radians (e.g. from :func:`counterpart.nodes.labeller.gaze.facing_yaw_from_shoulders`);
        None = 0.
    head_yaw : ndarray of shape (T,) or None, default=None
        Head yaw relative to the torso (rad) from the tracker's pose (:func:`head_channels_3d`).
    center : bool, default=False
        Centred (offline) windows instead of causal ones.
    head_pitch : ndarray of shape (T,) or None, default=None
        Head pitch relative to the torso (rad) from the tracker's pose.
    **params : object
        Other fields of :class:`HeadMotionParams`.

    Returns
    -------
    HeadMotionResult
        (T,) scores and labels.
    """
    p = HeadMotionParams(fps=fps, window_s=window_s, **params)  # type: ignore[arg-type]
    ch = head_channels_3d(head, neck, facing_yaw, head_yaw, p.head_radius_m, head_pitch, p.pitch_radius_m)
    return scores_from_channels(ch, p, center, (head_pitch is not None, head_yaw is not None))


def head_motion_2d(
    head_px: np.ndarray,
    ref_px: np.ndarray,
    height_px: np.ndarray | float,
    fps: float,
    window_s: float = 1.6,
    center: bool = False,
    person_height_m: float = 1.7,
    **params: object,
) -> HeadMotionResult:
    """Nod and shake from the silhouette's head reference point (pixels); see :func:`head_channels_2d`.

    Parameters
    ----------
    head_px, ref_px : ndarray of shape (T, 2)
        Head and body reference points, pixels (x right, y down).
    height_px : ndarray of shape (T,) or float
        Silhouette height, pixels.
    fps : float
        Frame rate, Hz.
    window_s : float, default=1.6
        FFT window, seconds.
    center : bool, default=False
        Centred (offline) windows instead of causal ones.
    person_height_m : float, default=1.7
        The person's height, metres.
    **params : object
        Other fields of :class:`HeadMotionParams`.

    Returns
    -------
    HeadMotionResult
        (T,) scores and labels.
    """
    p = HeadMotionParams(fps=fps, window_s=window_s, **params)  # type: ignore[arg-type]
    ch = head_channels_2d(head_px, ref_px, height_px, person_height_m)
    return scores_from_channels(ch, p, center)


class _StreamingChannels:
    """Ring buffer of (4,) channel samples with a contiguous view of the last N (double-write)."""

    def __init__(self, params: HeadMotionParams) -> None:
        self.params = params
        self._spec = _Spectral(params)
        n = params.n
        self._buf = np.full((4, 2 * n), np.nan)
        self._i = 0
        self._count = 0
        self._angles = (False, False)  # (nod from a pitch, shake from a yaw) in the buffer

    def reset(self) -> None:
        """Forget the history (e.g. after the person was lost)."""
        self._buf.fill(np.nan)
        self._i = 0
        self._count = 0

    def push(self, sample: np.ndarray) -> None:
        """Append a sample without scoring.

        Parameters
        ----------
        sample : ndarray of shape (4,)
            The channels (nod_a, nod_b, shake_a, shake_b) of one frame (nan for a missing frame).
        """
        n = self.params.n
        self._buf[:, self._i] = sample
        self._buf[:, self._i + n] = sample
        self._i = (self._i + 1) % n
        self._count += 1

    def score(self) -> tuple[float, int, float, int]:
        """Scores and labels of the window ending at the newest sample.

        Returns
        -------
        nod_score : float
            In [0, 1]; nan where the label is UNKNOWN.
        nod : int
            1, 0 or UNKNOWN.
        shake_score : float
            In [0, 1]; nan where the label is UNKNOWN.
        shake : int
            1, 0 or UNKNOWN.
        """
        n = self.params.n
        if self._count < n - n // 2:  # the window's centre not seen yet
            return float("nan"), UNKNOWN, float("nan"), UNKNOWN
        win = self._buf[:, self._i : self._i + n]
        s_nod, s_shake, l_nod, l_shake = self._spec.scores(win, self._angles)
        sn, ss = float(s_nod), float(s_shake)
        return (sn, self._label(sn, float(l_nod)), ss, self._label(ss, float(l_shake)))

    def _label(self, score: float, inside: float) -> int:
        """The label of :func:`localise_labels` for the newest window."""
        if score != score:
            return UNKNOWN
        return int(score >= self.params.threshold and inside > 0)


class HeadMotionDetector(_StreamingChannels):
    """Streaming nod/shake for one person from 3D head and neck positions (causal windows).

    Gives exactly the values of :func:`head_motion` with ``center=False`` frame by frame; cost per
    update is one (4,N) real FFT.

    Parameters
    ----------
    fps : float
        Frame rate, Hz.
    window_s : float, default=1.6
        FFT window, seconds.
    **params : object
        Other fields of :class:`HeadMotionParams`.

    Examples
    --------
    >>> det = HeadMotionDetector(fps=25.0, window_s=1.6)
    >>> nod_score, nod, shake_score, shake = det.update(head_xyz, neck_xyz)
    """

    def __init__(self, fps: float, window_s: float = 1.6, **params: object) -> None:
        super().__init__(HeadMotionParams(fps=fps, window_s=window_s, **params))  # type: ignore[arg-type]

    def _arc(self, angle: float, channel: int, r: float) -> float:
        """Arc (m) of a head angle (rad) at radius ``r`` (m), unwrapped against the channel's
        previous sample so that an angle crossing +-pi is not a 2 pi jump.
        """
        prev = self._buf[channel, (self._i - 1) % self.params.n] / r
        a = float(angle)
        if prev == prev:
            a = prev + (a - prev + np.pi) % (2 * np.pi) - np.pi
        return a * r

    def update(
        self,
        head_xyz: np.ndarray,
        neck_xyz: np.ndarray,
        facing_yaw: float | None = None,
        head_yaw: float | None = None,
        head_pitch: float | None = None,
    ) -> tuple[float, int, float, int]:
        """Add one frame and score the window that ends at it.

        An angle given on some frames and not on others restarts the windows at every change (the
        channels change kind), so give an angle on every frame or never.

        Parameters
        ----------
        head_xyz, neck_xyz : ndarray of shape (3,)
            Metres, world frame (nan if missing).
        facing_yaw : float or None, default=None
            Body yaw, radians; None = 0.
        head_yaw, head_pitch : float or None, default=None
            The tracker's head angles relative to the torso, radians (see :func:`head_channels_3d`).

        Returns
        -------
        nod_score : float
            In [0, 1]; nan where the label is UNKNOWN.
        nod : int
            1, 0 or UNKNOWN.
        shake_score : float
            In [0, 1]; nan where the label is UNKNOWN.
        shake : int
            1, 0 or UNKNOWN.

        Raises
        ------
        ValueError
            If ``head_xyz`` or ``neck_xyz`` is not (3,).
        """
        h = np.asarray(head_xyz, dtype=np.float64)
        nk = np.asarray(neck_xyz, dtype=np.float64)
        if h.shape != (3,) or nk.shape != (3,):
            raise ValueError(f"head_xyz and neck_xyz must be (3,) metres, got {h.shape}, {nk.shape}")
        rx, ry, rz = h - nk
        yaw = 0.0 if facing_yaw is None else float(facing_yaw)
        s, c = np.sin(yaw), np.cos(yaw)
        missing = np.nan if np.isnan(rx + ry + rz) else 0.0
        angles = (head_pitch is not None, head_yaw is not None)
        if angles != self._angles:
            self.reset()  # the channels change kind: no window mixes two kinds
            self._angles = angles
        if head_pitch is None:
            nod = (ry, rx * s + rz * c)
        else:
            nod = (self._arc(head_pitch, 0, self.params.pitch_radius_m), missing)
        if head_yaw is None:
            shake = (rx * c - rz * s, 0.0)
        else:
            shake = (missing, self._arc(head_yaw, 3, self.params.head_radius_m))
        self.push(np.array([*nod, *shake]))
        return self.score()


class HeadMotionDetector2D(_StreamingChannels):
    """Streaming nod/shake from the silhouette's head reference point (pixels), scaled by the
    person's height in pixels; see :func:`head_channels_2d` for what it can and cannot see.

    Parameters
    ----------
    fps : float
        Frame rate, Hz.
    window_s : float, default=1.6
        FFT window, seconds.
    person_height_m : float, default=1.7
        The person's height, metres.
    **params : object
        Other fields of :class:`HeadMotionParams`.
    """

    def __init__(self, fps: float, window_s: float = 1.6, person_height_m: float = 1.7, **params: object) -> None:
        super().__init__(HeadMotionParams(fps=fps, window_s=window_s, **params))  # type: ignore[arg-type]
        self.person_height_m = person_height_m

    def update(self, head_px: np.ndarray, ref_px: np.ndarray, height_px: float) -> tuple[float, int, float, int]:
        """Add one frame and score the window that ends at it.

        Parameters
        ----------
        head_px, ref_px : ndarray of shape (2,)
            Head and body reference points, pixels.
        height_px : float
            Silhouette height, pixels (not > 0: a missing frame).

        Returns
        -------
        nod_score : float
            In [0, 1]; nan where the label is UNKNOWN.
        nod : int
            1, 0 or UNKNOWN.
        shake_score : float
            In [0, 1]; nan where the label is UNKNOWN.
        shake : int
            1, 0 or UNKNOWN.

        Raises
        ------
        ValueError
            If ``head_px`` or ``ref_px`` is not (2,).
        """
        h = np.asarray(head_px, dtype=np.float64)
        r = np.asarray(ref_px, dtype=np.float64)
        if h.shape != (2,) or r.shape != (2,):
            raise ValueError(f"head_px and ref_px must be (2,) pixels, got {h.shape}, {r.shape}")
        sc = self.person_height_m / height_px if height_px > 0 else float("nan")
        self.push(np.array([-(h[1] - r[1]) * sc, 0.0, (h[0] - r[0]) * sc, 0.0]))
        return self.score()


class HeadMotionDetectorFace(_StreamingChannels):
    """Streaming nod/shake from a tracked face's head point (:mod:`counterpart.nodes.labeller.face_track`),
    in units of the face's own width: the channels integrate the point's frame-to-frame motion
    divided by the face width of that frame (so a face that slowly grows as the person leans in
    adds no motion), image up for nods, image x for shakes. The second nod channel is the face's
    rotation cue (:attr:`counterpart.nodes.labeller.face_track.FaceTrack.tilt`: its features' motion
    relative to the top of the head, in face widths, up), which a nod moves and a translation of the
    whole head (a knee bounce, a lean) does not: so a small nod of a tilted head scores above the
    floor that keeps a bouncing face still. The lateral motion in step with that cue (a nod of a
    head turned aside, which moves the face across the image too) is taken out of the shake
    channel (:func:`without_pitch_leak`). Floors: ``face_nod_floor`` / ``face_shake_floor`` (face
    widths).

    Parameters
    ----------
    fps : float
        Frame rate, Hz.
    window_s : float, default=1.6
        FFT window, seconds.
    **params : object
        Other fields of :class:`HeadMotionParams`.
    """

    def __init__(self, fps: float, window_s: float = 1.6, **params: object) -> None:
        super().__init__(HeadMotionParams(fps=fps, window_s=window_s, **params))  # type: ignore[arg-type]
        self._angles = (FACE, FACE)
        self._last: np.ndarray | None = None
        self._pos = np.zeros(3)

    def reset(self) -> None:
        super().reset()
        self._last = None
        self._pos = np.zeros(3)

    def update(self, center_px: np.ndarray, size_px: float, tilt_px: float = 0.0) -> tuple[float, int, float, int]:
        """Add one frame and score the window that ends at it.

        Parameters
        ----------
        center_px : ndarray of shape (2,)
            Head point, pixels (y down).
        size_px : float
            Face width, pixels; > 0.
        tilt_px : float, default=0.0
            The face's accumulated rotation cue (:attr:`counterpart.nodes.labeller.face_track.FaceTrack.tilt`,
            px, down); a constant (the default) adds nothing.

        Returns
        -------
        nod_score : float
            In [0, 1]; nan where the label is UNKNOWN.
        nod : int
            1, 0 or UNKNOWN.
        shake_score : float
            In [0, 1]; nan where the label is UNKNOWN.
        shake : int
            1, 0 or UNKNOWN.

        Raises
        ------
        ValueError
            If ``center_px`` is not (2,) or ``size_px`` is not > 0.
        """
        c = np.asarray(center_px, dtype=np.float64)
        if c.shape != (2,) or not size_px > 0:
            raise ValueError(f"center_px must be (2,) pixels and size_px > 0, got {c.shape}, {size_px}")
        c = np.append(c, float(tilt_px))
        if self._last is not None:
            self._pos += (c - self._last) / size_px
        self._last = c
        self.push(np.array([-self._pos[1], -self._pos[2], self._pos[0], 0.0]))
        return self.score()
