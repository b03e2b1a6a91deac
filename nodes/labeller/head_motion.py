"""Head nod and head shake by frequency analysis of head motion (Okwechime et al., Sec. "head nod
and shake": FFT of the head's vertical and horizontal motion over a short sliding window).

Motion is taken **relative to the neck** (3D) or to a body reference point (2D) so that walking or
whole-body motion (gait bob, sway, translation) cancels out. The relative motion is split into
channels in the person's body frame:

- nod channels: ``up`` (world Y) and ``forward`` (along the facing direction);
- shake channels: ``lateral`` (towards the person's left) and, when the tracker gives a head yaw,
  ``head_radius * yaw`` (the arc the face travels, in metres), because a head centre that sits on the
  yaw axis hardly moves sideways in a real shake.

For each window of ``N = round(window_s * fps)`` frames every channel has its window mean removed,
is multiplied by a Hann window ``w`` and transformed with a real FFT. With one-sided energies
``P_k`` scaled by Parseval so that ``sum_k P_k = sum_n (w_n x_n)^2``, the scores are::

    nod_score   = sum_{k in band, c in nod}   P_ck / max(E_total, E_floor)
    shake_score = sum_{k in band, c in shake} P_ck / max(E_total, E_floor)
    E_total     = sum_{k >= 1, all c} P_ck          (all relative head motion)
    E_floor     = a_floor^2 / 2 * sum_n w_n^2       (energy of a sinusoid of amplitude a_floor)

so a score is the fraction of all relative head motion that is band-limited nod (resp. shake)
motion, scaled down when the motion is smaller than the amplitude floor ``a_floor``. Scores are in
[0, 1]; the label is ``score >= threshold``. Windows that contain a missing (nan) sample give
``nan`` / UNKNOWN, as do the frames before the first full window.

Timing: ``center=False`` (the streaming default) labels frame ``t`` from the window that ends at
``t`` (causal, lags the motion by up to a window); ``center=True`` (offline) from the window
centred on ``t``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from nodes.labeller.signals import UNKNOWN, threshold_labels

#: channel order inside the detectors
_NOD_CHANNELS = (0, 1)      # up, forward
_SHAKE_CHANNELS = (2, 3)    # lateral, head_radius * yaw


@dataclass(frozen=True)
class HeadMotionParams:
    """Parameters of nod/shake detection.

    fps: frames per second of the input (Hz). window_s: FFT window length (s), 1.5-2 s is typical.
    band_hz: (low, high) frequency band of nods and shakes (Hz). nod_floor_m / shake_floor_m:
    amplitude floors (m) under which motion is scaled down. threshold: score threshold of the label.
    head_radius_m: converts a head yaw (rad) to the arc the face travels (m).
    """

    fps: float
    window_s: float = 1.6
    band_hz: tuple[float, float] = (1.0, 4.0)
    nod_floor_m: float = 0.01
    shake_floor_m: float = 0.01
    threshold: float = 0.5
    head_radius_m: float = 0.1

    def __post_init__(self) -> None:
        if not self.fps > 0:
            raise ValueError(f"fps must be > 0, got {self.fps}")
        n = self.n
        if n < 8:
            raise ValueError(
                f"window_s * fps = {self.window_s} * {self.fps} gives {n} frames; need >= 8 "
                "(use a longer window_s)")
        lo, hi = self.band_hz
        if not 0 < lo < hi:
            raise ValueError(f"band_hz must be (low, high) with 0 < low < high, got {self.band_hz}")
        freqs = np.fft.rfftfreq(n, 1.0 / self.fps)
        if not ((freqs >= lo) & (freqs <= hi)).any():
            raise ValueError(
                f"band_hz {self.band_hz} holds no FFT bin for a {n}-frame window at {self.fps} fps "
                f"(bins are {freqs[1]:.3g} Hz apart): widen the band or lengthen window_s")
        if self.nod_floor_m <= 0 or self.shake_floor_m <= 0:
            raise ValueError("nod_floor_m and shake_floor_m must be > 0 (metres)")

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
        self.band = wt * ((freqs >= lo) & (freqs <= hi))
        sw2 = float(np.sum(self.w ** 2))
        self.e_floor_nod = p.nod_floor_m ** 2 / 2.0 * sw2
        self.e_floor_shake = p.shake_floor_m ** 2 / 2.0 * sw2

    def scores(self, win: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """win: (..., 4, N) channel windows (m) -> (nod_score, shake_score), each (...,)."""
        bad = np.isnan(win).any(axis=(-2, -1))
        if bad.any():
            win = np.where(np.isnan(win), 0.0, win)
        x = (win - win.mean(axis=-1, keepdims=True)) * self.w
        spec = np.fft.rfft(x, axis=-1)
        pw = spec.real ** 2 + spec.imag ** 2                        # (..., 4, F)
        total = pw @ self.wt                                        # (..., 4)
        band = pw @ self.band                                       # (..., 4)
        e_all = total.sum(axis=-1)
        nod_b = band[..., _NOD_CHANNELS[0]] + band[..., _NOD_CHANNELS[1]]
        shake_b = band[..., _SHAKE_CHANNELS[0]] + band[..., _SHAKE_CHANNELS[1]]
        nod = nod_b / np.maximum(e_all, self.e_floor_nod)
        shake = shake_b / np.maximum(e_all, self.e_floor_shake)
        nod = np.where(bad, np.nan, nod)
        shake = np.where(bad, np.nan, shake)
        return nod, shake


def facing_vectors(facing_yaw: np.ndarray | float, t: int) -> tuple[np.ndarray, np.ndarray]:
    """Forward and left unit vectors (T,3) for a facing yaw (rad, about +Y, 0 faces +Z)."""
    yaw = np.broadcast_to(np.asarray(facing_yaw, dtype=np.float64), (t,))
    s, c = np.sin(yaw), np.cos(yaw)
    z = np.zeros_like(s)
    fwd = np.stack([s, z, c], axis=-1)
    left = np.stack([c, z, -s], axis=-1)
    return fwd, left


def head_channels_3d(
    head: np.ndarray,
    neck: np.ndarray,
    facing_yaw: np.ndarray | float | None = None,
    head_yaw: np.ndarray | None = None,
    head_radius_m: float = 0.1,
) -> np.ndarray:
    """Relative head motion channels (T,4) = (up, forward, lateral, head_radius * head_yaw), metres.

    head, neck: (T,3) world positions (m, Y up). facing_yaw: (T,) or scalar body yaw (rad, 0 faces
    +Z); None means 0. head_yaw: (T,) head yaw (rad, any zero; unwrapped here) or None (channel 0).
    """
    head = np.asarray(head, dtype=np.float64)
    neck = np.asarray(neck, dtype=np.float64)
    if head.ndim != 2 or head.shape[1] != 3 or neck.shape != head.shape:
        raise ValueError(f"head and neck must both be (T,3) metres; got {head.shape} and {neck.shape}")
    t = head.shape[0]
    rel = head - neck
    fwd, left = facing_vectors(0.0 if facing_yaw is None else facing_yaw, t)
    ch = np.empty((t, 4))
    ch[:, 0] = rel[:, 1]
    ch[:, 1] = np.einsum("ij,ij->i", rel, fwd)
    ch[:, 2] = np.einsum("ij,ij->i", rel, left)
    if head_yaw is None:
        ch[:, 3] = 0.0
    else:
        hy = np.asarray(head_yaw, dtype=np.float64)
        if hy.shape != (t,):
            raise ValueError(f"head_yaw must be (T,) = ({t},) radians, got {hy.shape}")
        ok = ~np.isnan(hy)
        un = hy.copy()
        if ok.any():
            un[ok] = np.unwrap(hy[ok])
        ch[:, 3] = head_radius_m * un
    return ch


def head_channels_2d(
    head_px: np.ndarray,
    ref_px: np.ndarray,
    height_px: np.ndarray | float,
    person_height_m: float = 1.7,
) -> np.ndarray:
    """Channels (T,4) from image points: the silhouette's head reference point relative to a body
    reference point (e.g. the silhouette centroid), converted to metres by the person's height.

    head_px, ref_px: (T,2) pixels (x right, y down). height_px: (T,) or scalar silhouette height in
    pixels. Image up is the nod channel, image x the lateral (shake) channel; depth is not seen, so
    the forward and yaw channels are 0. Crude: a shake that only rotates the head moves the top of the
    head very little in the image, so 2D shakes are found only when they move the head sideways.
    """
    head_px = np.asarray(head_px, dtype=np.float64)
    ref_px = np.asarray(ref_px, dtype=np.float64)
    if head_px.ndim != 2 or head_px.shape[1] != 2 or ref_px.shape != head_px.shape:
        raise ValueError(
            f"head_px and ref_px must both be (T,2) pixels; got {head_px.shape} and {ref_px.shape}")
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
    """Per-frame nod/shake scores (T,) in [0,1] (nan = unknown) and int8 labels (1/0/UNKNOWN)."""

    nod_score: np.ndarray
    nod: np.ndarray
    shake_score: np.ndarray
    shake: np.ndarray


def scores_from_channels(
    channels: np.ndarray, params: HeadMotionParams, center: bool = False
) -> HeadMotionResult:
    """Batch nod/shake over a whole (T,4) channel trajectory, vectorised over all windows.

    Frame ``t`` is scored from window ``[t-N+1, t]`` (causal) or ``[t-N//2, t-N//2+N)`` (center);
    frames without a full window are UNKNOWN.
    """
    ch = np.asarray(channels, dtype=np.float64)
    if ch.ndim != 2 or ch.shape[1] != 4:
        raise ValueError(f"channels must be (T,4), got {ch.shape}")
    t, n = ch.shape[0], params.n
    nod = np.full(t, np.nan)
    shake = np.full(t, np.nan)
    if t >= n:
        win = sliding_window_view(ch.T, n, axis=1).transpose(1, 0, 2)   # (T-N+1, 4, N)
        s_nod, s_shake = _Spectral(params).scores(win)
        first = n // 2 if center else n - 1
        nod[first:first + len(s_nod)] = s_nod
        shake[first:first + len(s_shake)] = s_shake
    return HeadMotionResult(nod, threshold_labels(nod, params.threshold),
                            shake, threshold_labels(shake, params.threshold))


def head_motion(
    head: np.ndarray,
    neck: np.ndarray,
    fps: float,
    window_s: float = 1.6,
    facing_yaw: np.ndarray | float | None = None,
    head_yaw: np.ndarray | None = None,
    center: bool = False,
    **params: object,
) -> HeadMotionResult:
    """Nod and shake over a whole 3D trajectory.

    head, neck: (T,3) metres, world Y up. fps: Hz. window_s: FFT window (s). facing_yaw: body yaw
    (T,) or scalar, rad (e.g. from :func:`nodes.labeller.gaze.facing_yaw_from_shoulders`); None = 0.
    head_yaw: optional (T,) head yaw (rad) from the tracker. center: centred (offline) windows instead
    of causal ones. Other keyword parameters go to :class:`HeadMotionParams`.
    Returns :class:`HeadMotionResult` of (T,) arrays.
    """
    p = HeadMotionParams(fps=fps, window_s=window_s, **params)  # type: ignore[arg-type]
    ch = head_channels_3d(head, neck, facing_yaw, head_yaw, p.head_radius_m)
    return scores_from_channels(ch, p, center)


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
    """Nod and shake from the silhouette's head reference point (pixels); see :func:`head_channels_2d`."""
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

    def reset(self) -> None:
        """Forget the history (e.g. after the person was lost)."""
        self._buf.fill(np.nan)
        self._i = 0
        self._count = 0

    def push(self, sample: np.ndarray) -> None:
        """Append a (4,) sample without scoring (nan for a missing frame)."""
        n = self.params.n
        self._buf[:, self._i] = sample
        self._buf[:, self._i + n] = sample
        self._i = (self._i + 1) % n
        self._count += 1

    def score(self) -> tuple[float, int, float, int]:
        """(nod_score, nod, shake_score, shake) of the window ending at the newest sample."""
        n = self.params.n
        if self._count < n:
            return float("nan"), UNKNOWN, float("nan"), UNKNOWN
        win = self._buf[:, self._i:self._i + n]
        s_nod, s_shake = self._spec.scores(win)
        th = self.params.threshold
        sn, ss = float(s_nod), float(s_shake)
        return (sn, UNKNOWN if sn != sn else int(sn >= th),
                ss, UNKNOWN if ss != ss else int(ss >= th))


class HeadMotionDetector(_StreamingChannels):
    """Streaming nod/shake for one person from 3D head and neck positions (causal windows).

    Gives exactly the values of :func:`head_motion` with ``center=False`` frame by frame; cost per
    update is one (4,N) real FFT.

    >>> det = HeadMotionDetector(fps=25.0, window_s=1.6)
    >>> nod_score, nod, shake_score, shake = det.update(head_xyz, neck_xyz)
    """

    def __init__(self, fps: float, window_s: float = 1.6, **params: object) -> None:
        super().__init__(HeadMotionParams(fps=fps, window_s=window_s, **params))  # type: ignore[arg-type]

    def update(
        self,
        head_xyz: np.ndarray,
        neck_xyz: np.ndarray,
        facing_yaw: float | None = None,
        head_yaw: float | None = None,
    ) -> tuple[float, int, float, int]:
        """head_xyz, neck_xyz: (3,) metres (nan if missing). facing_yaw: body yaw (rad) or None
        (= 0). head_yaw: head yaw (rad) or None. Returns (nod_score, nod, shake_score, shake).

        A head_yaw stream should be given on every frame or never: missing frames count as yaw 0.
        """
        h = np.asarray(head_xyz, dtype=np.float64)
        nk = np.asarray(neck_xyz, dtype=np.float64)
        if h.shape != (3,) or nk.shape != (3,):
            raise ValueError(f"head_xyz and neck_xyz must be (3,) metres, got {h.shape}, {nk.shape}")
        rx, ry, rz = h - nk
        yaw = 0.0 if facing_yaw is None else float(facing_yaw)
        s, c = np.sin(yaw), np.cos(yaw)
        if head_yaw is None:
            hy = 0.0
        else:
            # unwrap against the previous sample so a yaw crossing +-pi is not a jump
            prev = self._buf[3, (self._i - 1) % self.params.n] / self.params.head_radius_m
            hy = float(head_yaw)
            if prev == prev:
                hy = prev + (hy - prev + np.pi) % (2 * np.pi) - np.pi
            hy *= self.params.head_radius_m
        self.push(np.array([ry, rx * s + rz * c, rx * c - rz * s, hy]))
        return self.score()


class HeadMotionDetector2D(_StreamingChannels):
    """Streaming nod/shake from the silhouette's head reference point (pixels), scaled by the
    person's height in pixels; see :func:`head_channels_2d` for what it can and cannot see."""

    def __init__(self, fps: float, window_s: float = 1.6, person_height_m: float = 1.7,
                 **params: object) -> None:
        super().__init__(HeadMotionParams(fps=fps, window_s=window_s, **params))  # type: ignore[arg-type]
        self.person_height_m = person_height_m

    def update(self, head_px: np.ndarray, ref_px: np.ndarray,
               height_px: float) -> tuple[float, int, float, int]:
        """head_px, ref_px: (2,) pixels; height_px: silhouette height (pixels).
        Returns (nod_score, nod, shake_score, shake)."""
        h = np.asarray(head_px, dtype=np.float64)
        r = np.asarray(ref_px, dtype=np.float64)
        if h.shape != (2,) or r.shape != (2,):
            raise ValueError(f"head_px and ref_px must be (2,) pixels, got {h.shape}, {r.shape}")
        sc = self.person_height_m / height_px if height_px > 0 else float("nan")
        self.push(np.array([-(h[1] - r[1]) * sc, 0.0, (h[0] - r[0]) * sc, 0.0]))
        return self.score()
