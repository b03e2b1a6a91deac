"""Talking and laughing from the mouth region of a detected face (Okwechime et al. find the face
with a Viola-Jones detector; here OpenCV's Haar cascade ``haarcascade_frontalface_default.xml``,
found by :func:`find_face_cascade`).

How crude this is, honestly:

- The face is found by a frontal Haar cascade: profiles, tilted heads, small, blurred or dark faces
  are not found, and then both signals are UNKNOWN (never guessed). Faces narrower than
  ``min_face_px`` are refused even when found.
- The mouth region is simply the lower third of the face box (middle two thirds of its width),
  resampled to a fixed ``patch_size`` and divided by its mean intensity. Its motion energy is the
  mean absolute difference between consecutive patches. That energy also rises with head motion,
  detector jitter of the face box, lighting flicker and chewing: it is "the lower face moves", not
  speech recognition.
- ``talking_score = mean motion energy over the window / talk_energy``; talking when >= 1.
- Laughing is talking-like energy that is larger (``laugh_energy``) AND spread over a large vertical
  extent of the mouth region (the fraction of patch rows whose motion exceeds half the strongest
  row's, averaged over the window, >= ``laugh_extent``): a wide-open, shaking mouth.
  ``laughing_score = min(energy / laugh_energy, extent / laugh_extent)``; laughing when >= 1.
  Loud talking with big mouth movements will be called laughing; a silent smile will not.

The thresholds are set by hand, not learned; measure them on your own footage.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import cv2
import numpy as np

from counterpart.nodes.labeller.signals import UNKNOWN

Box = tuple[int, int, int, int]  # x, y, w, h in pixels

CASCADE_NAME = "haarcascade_frontalface_default.xml"
#: OpenCV's profile face cascade (faces turned to one side; the other side by mirroring the image)
PROFILE_CASCADE_NAME = "haarcascade_profileface.xml"
#: environment variable naming the cascade file when OpenCV does not ship it
CASCADE_ENV = "COUNTERPART_FACE_CASCADE"
_SYSTEM_DIRS = (
    "/usr/share/opencv4/haarcascades",
    "/usr/share/opencv/haarcascades",
    "/usr/local/share/opencv4/haarcascades",
    "/opt/homebrew/share/opencv4/haarcascades",
)


def find_face_cascade(name: str = CASCADE_NAME) -> str | None:
    """Path of a Viola-Jones face cascade (by default the frontal one), or None if none is found.

    Looked for, in order: ``$COUNTERPART_FACE_CASCADE`` (the frontal cascade only); OpenCV's
    bundled data (``cv2.data.haarcascades``, shipped by the 4.x wheels; the 5.0 wheels ship no
    cascade files); the usual system folders (Debian/Ubuntu ``opencv-data``, Homebrew).

    Parameters
    ----------
    name : str, default=CASCADE_NAME
        The cascade's file name (e.g. :data:`PROFILE_CASCADE_NAME`).

    Returns
    -------
    str or None
        The first existing file, or None.
    """
    cands = []
    env = os.environ.get(CASCADE_ENV)
    if env and name == CASCADE_NAME:
        cands.append(env)
    data = getattr(getattr(cv2, "data", None), "haarcascades", None)
    if data:
        cands.append(os.path.join(data, name))
    cands += [os.path.join(d, name) for d in _SYSTEM_DIRS]
    return next((c for c in cands if os.path.isfile(c)), None)


def load_face_cascade(path: str | None = None, name: str = CASCADE_NAME) -> cv2.CascadeClassifier:
    """Load a Haar cascade.

    Parameters
    ----------
    path : str or None, default=None
        The cascade file; None: :func:`find_face_cascade` of ``name``.
    name : str, default=CASCADE_NAME
        The cascade looked for when ``path`` is None.

    Returns
    -------
    cv2.CascadeClassifier
        The loaded cascade.

    Raises
    ------
    FileNotFoundError
        When no file is found (saying where it looked and how to provide the file) or the file is
        not a cascade.
    """
    path = path or find_face_cascade(name)
    if path is None:
        raise FileNotFoundError(
            f"no {name} found (looked in ${CASCADE_ENV}, cv2.data.haarcascades and "
            f"{', '.join(_SYSTEM_DIRS)}); install OpenCV's cascade data (e.g. apt install "
            f"opencv-data, or an opencv-contrib-python-headless 4.x wheel) or set {CASCADE_ENV}"
        )
    cc = cv2.CascadeClassifier(path)
    if cc.empty():
        raise FileNotFoundError(f"could not load the Haar cascade {path!r} (missing or not a cascade)")
    return cc


def to_gray(image: np.ndarray) -> np.ndarray:
    """Gray version of an image.

    Parameters
    ----------
    image : ndarray of shape (H, W) or (H, W, 3)
        uint8 gray or BGR.

    Returns
    -------
    ndarray of shape (H, W)
        uint8 gray (``image`` itself when already gray).

    Raises
    ------
    ValueError
        If ``image`` is not uint8 or not of one of these shapes.
    """
    img = np.asarray(image)
    if img.dtype != np.uint8:
        raise ValueError(f"image must be uint8, got {img.dtype}")
    if img.ndim == 2:
        return img
    if img.ndim == 3 and img.shape[2] == 3:
        return cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    raise ValueError(f"image must be (H,W) gray or (H,W,3) BGR, got shape {img.shape}")


def detect_face(
    gray: np.ndarray, cascade: cv2.CascadeClassifier, min_face_px: int = 24, roi: Box | None = None
) -> Box | None:
    """Largest frontal face in an image.

    Parameters
    ----------
    gray : ndarray of shape (H, W)
        uint8 gray image.
    cascade : cv2.CascadeClassifier
        The face cascade.
    min_face_px : int, default=24
        Smallest face size searched for, pixels.
    roi : tuple of int (x, y, w, h) or None, default=None
        Search region, pixels, e.g. the person's silhouette box; None: the whole image.

    Returns
    -------
    tuple of int (x, y, w, h) or None
        The face box in pixels of the full image, or None.
    """
    x0 = y0 = 0
    if roi is not None:
        x, y, w, h = (int(v) for v in roi)
        x0, y0 = max(0, x), max(0, y)
        gray = gray[y0 : max(y0, y + h), x0 : max(x0, x + w)]
    if gray.shape[0] < min_face_px or gray.shape[1] < min_face_px:
        return None
    faces = cascade.detectMultiScale(gray, scaleFactor=1.1, minNeighbors=5, minSize=(min_face_px, min_face_px))
    if len(faces) == 0:
        return None
    fx, fy, fw, fh = max(faces, key=lambda f: int(f[2]) * int(f[3]))
    return int(fx) + x0, int(fy) + y0, int(fw), int(fh)


def mouth_patch(gray: np.ndarray, face: Box, patch_size: tuple[int, int] = (32, 16)) -> np.ndarray | None:
    """Lower third of the face box, middle two thirds of its width, resampled and divided by its
    mean intensity.

    Parameters
    ----------
    gray : ndarray of shape (H, W)
        uint8 gray image.
    face : tuple of int (x, y, w, h)
        Face box, pixels.
    patch_size : tuple of int (w, h), default=(32, 16)
        Size of the resampled patch, pixels.

    Returns
    -------
    ndarray of shape (h, w) or None
        float32 patch, or None if the region leaves the image.
    """
    x, y, w, h = face
    mx0, mx1 = x + w // 6, x + w - w // 6
    my0, my1 = y + (2 * h) // 3, y + h
    if mx0 < 0 or my0 < 0 or mx1 > gray.shape[1] or my1 > gray.shape[0] or mx1 <= mx0 or my1 <= my0:
        return None
    patch = cv2.resize(gray[my0:my1, mx0:mx1], patch_size, interpolation=cv2.INTER_AREA)
    patch = patch.astype(np.float32)
    return patch / max(float(patch.mean()), 1.0)


#: the mouth patch of a tracked face, in face widths from its head point (the box centre): centre
#: below it by MOUTH_DY, size MOUTH_W x MOUTH_H; the upper-face reference patch (eyes, brows) the
#: same with UPPER_*
MOUTH_DY, MOUTH_W, MOUTH_H = 0.28, 0.5, 0.28
UPPER_DY, UPPER_W, UPPER_H = -0.1, 0.6, 0.22


def subpix_patch(
    gray: np.ndarray, center: tuple[float, float], size: tuple[float, float], patch_size: tuple[int, int]
) -> np.ndarray | None:
    """A region at a sub-pixel position, resampled and divided by its mean.

    Parameters
    ----------
    gray : ndarray of shape (H, W)
        uint8 gray image.
    center : tuple of float (x, y)
        Centre of the region, pixels (sub-pixel).
    size : tuple of float (w, h)
        Size of the region, pixels.
    patch_size : tuple of int (w, h)
        Size of the resampled patch, pixels.

    Returns
    -------
    ndarray of shape (h, w) or None
        float32 patch, or None when the region leaves the image.
    """
    w, h = size
    cx, cy = center
    if cx - w / 2 < 0 or cy - h / 2 < 0 or cx + w / 2 > gray.shape[1] or cy + h / 2 > gray.shape[0]:
        return None
    iw, ih = max(2, int(round(w))), max(2, int(round(h)))
    patch = cv2.getRectSubPix(gray, (iw, ih), (float(cx), float(cy)), patchType=cv2.CV_32F)
    patch = cv2.resize(patch, patch_size, interpolation=cv2.INTER_AREA)
    return patch / max(float(patch.mean()), 1.0)


@dataclass(frozen=True)
class FaceParams:
    """Settings of the talking and laughing detector.

    Parameters
    ----------
    fps : float
        Frame rate, Hz; > 0.
    window_s : float, default=1.0
        Averaging window, seconds.
    min_face_px : int, default=24
        Smallest face width accepted, pixels; at least 12.
    talk_energy, laugh_energy : float, default=0.04, 0.10
        Motion energies (mean |diff| of mean-normalised patches) of the talking and laughing
        thresholds; > 0.
    laugh_extent : float, default=0.3
        Vertical extent fraction for laughing; > 0.
    min_valid : float, default=0.5
        Fraction of the window that must hold measurements.
    detect_every : int, default=1
        Run the cascade every n frames and reuse the last box in between; at least 1.
    patch_size : tuple of int (w, h), default=(32, 16)
        Size of the resampled mouth patch, pixels.
    talk_energy_tracked, laugh_energy_tracked : float, default=0.008, 0.05
        The thresholds of a tracked face's stabilised mouth energy above its upper face's
        (:meth:`FaceSignalDetector.update_track`), in the same unit (laughing from the energy alone).
    talk_gap_s : float, default=0.45
        A tracked face talks (laughs) at the window's centre frame only when its mouth moved (a
        frame's energy >= ``talk_energy_tracked``) within ``talk_gap_s`` seconds before it and within
        as long after it: pauses between syllables and words shorter than that are bridged, and the
        label does not spread past the first and last syllable (the window's mean alone spreads it by
        up to half a window). At most half the window; 0: off.

    Raises
    ------
    ValueError
        If a setting is out of its range.
    """

    fps: float
    window_s: float = 1.0
    min_face_px: int = 24
    talk_energy: float = 0.04
    laugh_energy: float = 0.10
    laugh_extent: float = 0.3
    min_valid: float = 0.5
    detect_every: int = 1
    patch_size: tuple[int, int] = (32, 16)
    talk_energy_tracked: float = 0.008
    laugh_energy_tracked: float = 0.05
    talk_gap_s: float = 0.45

    def __post_init__(self) -> None:
        if not self.fps > 0:
            raise ValueError(f"fps must be > 0, got {self.fps}")
        if self.min_face_px < 12:
            raise ValueError(f"min_face_px must be >= 12 pixels, got {self.min_face_px}")
        for name in ("talk_energy", "laugh_energy", "talk_energy_tracked", "laugh_energy_tracked", "laugh_extent"):
            if not getattr(self, name) > 0:
                raise ValueError(
                    f"{name} must be > 0 (a mean absolute difference of mean-normalised "
                    f"patches), got {getattr(self, name)}"
                )
        if self.detect_every < 1:
            raise ValueError(f"detect_every must be >= 1, got {self.detect_every}")
        if not 0 <= self.talk_gap_s <= self.window_s / 2:
            raise ValueError(
                f"talk_gap_s must be between 0 and half of window_s ({self.window_s / 2:g} s), got {self.talk_gap_s}"
            )

    @property
    def w(self) -> int:
        return max(2, int(round(self.window_s * self.fps)))


class FaceSignalDetector:
    """Streaming talking/laughing for one person.

    ``update(image, roi=None, face_box=None) -> (talk_score, talking, laugh_score, laughing)``;
    both labels are UNKNOWN on any frame without a face of at least ``min_face_px``, and until
    ``min_valid`` of the window holds measurements.

    Parameters
    ----------
    fps : float
        Frame rate, Hz.
    cascade : cv2.CascadeClassifier or None, default=None
        The face cascade; None: loaded by :func:`load_face_cascade` when first needed.
    **params : object
        The other fields of :class:`FaceParams`.
    """

    def __init__(self, fps: float, cascade: cv2.CascadeClassifier | None = None, **params: object) -> None:
        self.params = FaceParams(fps=fps, **params)  # type: ignore[arg-type]
        self._cascade = cascade
        self._energy = np.full(self.params.w, np.nan)
        self._extent = np.full(self.params.w, np.nan)
        self._i = 0
        self._prev: np.ndarray | None = None
        self._prev_ref: np.ndarray | None = None
        self._box: Box | None = None
        self._frame = 0

    @property
    def cascade(self) -> cv2.CascadeClassifier:
        if self._cascade is None:
            self._cascade = load_face_cascade()
        return self._cascade

    @cascade.setter
    def cascade(self, value: cv2.CascadeClassifier) -> None:
        self._cascade = value

    @property
    def face_box(self) -> Box | None:
        """The face box used on the last frame, or None."""
        return self._box

    def reset(self) -> None:
        self._energy.fill(np.nan)
        self._extent.fill(np.nan)
        self._prev = None
        self._prev_ref = None
        self._box = None

    def _record(self, energy: float, extent: float) -> None:
        self._energy[self._i] = energy
        self._extent[self._i] = extent
        self._i = (self._i + 1) % len(self._energy)

    def update(
        self, image: np.ndarray, roi: Box | None = None, face_box: Box | None = None
    ) -> tuple[float, int, float, int]:
        """Talking and laughing of one frame.

        The mouth patch comes from the detected (or given) box as it is: no stabilisation, no
        reference patch. :meth:`update_track` is the stabilised form for a tracked face.

        Parameters
        ----------
        image : ndarray of shape (H, W) or (H, W, 3)
            uint8 gray or BGR frame.
        roi : tuple of int (x, y, w, h) or None, default=None
            Restricts the search, pixels (e.g. to this person's silhouette box).
        face_box : tuple of int (x, y, w, h) or None, default=None
            Bypasses the detector (a box from another face tracker), pixels.

        Returns
        -------
        talk_score : float
            Mean motion energy over the window / ``talk_energy``; nan where the label is UNKNOWN.
        talking : int
            1, 0 or UNKNOWN.
        laugh_score : float
            ``min(energy / laugh_energy, extent / laugh_extent)``; nan where the label is UNKNOWN.
        laughing : int
            1, 0 or UNKNOWN.
        """
        p = self.params
        gray = to_gray(image)
        if face_box is None:
            if self._box is None or self._frame % p.detect_every == 0:
                self._box = detect_face(gray, self.cascade, p.min_face_px, roi)
        else:
            self._box = tuple(int(v) for v in face_box)  # type: ignore[assignment]
        self._frame += 1
        box = self._box
        patch = None
        if box is not None and box[2] >= p.min_face_px and box[3] >= p.min_face_px:
            patch = mouth_patch(gray, box, p.patch_size)
        return self._step(patch, None)

    def update_track(self, gray: np.ndarray, center: np.ndarray, size: float) -> tuple[float, int, float, int]:
        """Talking/laughing of a tracked face (:class:`counterpart.nodes.labeller.face_track.FaceTrack`).

        The mouth patch is cut at the sub-pixel position of the tracked point, which follows the
        face's features (so it does not slide with the detector's jitter), and its motion energy
        is taken *above* that of a patch of the upper face (eyes and brows) cut the same way: head
        motion, residual misalignment, lighting flicker and sensor noise move both; speech moves
        the mouth only. A still, silent face scores about 0.

        Parameters
        ----------
        gray : ndarray of shape (H, W)
            uint8 gray frame.
        center : ndarray of shape (2,)
            The face's head point (x, y), pixels.
        size : float
            The face's smoothed width, pixels.

        Returns
        -------
        talk_score : float
            Window-mean energy / ``talk_energy_tracked``; nan where the label is UNKNOWN.
        talking : int
            1, 0 or UNKNOWN.
        laugh_score : float
            Window-mean energy / ``laugh_energy_tracked``; nan where the label is UNKNOWN.
        laughing : int
            1, 0 or UNKNOWN.
        """
        self._box = (int(center[0] - size / 2), int(center[1] - size / 2), int(size), int(size))
        if size < self.params.min_face_px:
            return self._step(None, None)
        mouth = subpix_patch(
            gray, (center[0], center[1] + MOUTH_DY * size), (MOUTH_W * size, MOUTH_H * size), self.params.patch_size
        )
        upper = subpix_patch(
            gray, (center[0], center[1] + UPPER_DY * size), (UPPER_W * size, UPPER_H * size), self.params.patch_size
        )
        if mouth is None or upper is None:
            return self._step(None, None)
        return self._step(mouth, upper)

    def _step(self, patch: np.ndarray | None, ref: np.ndarray | None) -> tuple[float, int, float, int]:
        p = self.params
        if patch is None:
            self._prev = None
            self._prev_ref = None
            self._record(np.nan, np.nan)
            return float("nan"), UNKNOWN, float("nan"), UNKNOWN
        if self._prev is None:
            self._record(np.nan, np.nan)
        else:
            diff = np.abs(patch - self._prev)
            energy = float(diff.mean())
            if ref is not None and self._prev_ref is not None:
                energy = max(0.0, energy - float(np.abs(ref - self._prev_ref).mean()))
            rows = diff.mean(axis=1)
            peak = float(rows.max())
            extent = float(np.mean(rows > 0.5 * peak)) if peak > 1e-6 else 0.0
            self._record(energy, extent)
        self._prev = patch
        self._prev_ref = ref
        valid = ~np.isnan(self._energy)
        if valid.mean() < p.min_valid:
            return float("nan"), UNKNOWN, float("nan"), UNKNOWN
        energy = float(self._energy[valid].mean())
        extent = float(self._extent[valid].mean())
        tracked = ref is not None
        talk = energy / (p.talk_energy_tracked if tracked else p.talk_energy)
        if tracked:  # the stabilised energy alone: a laugh opens the mouth wide and fast
            laugh = energy / p.laugh_energy_tracked
        else:
            laugh = min(energy / p.laugh_energy, extent / p.laugh_extent)
        moving = self._moving_around_centre() if tracked else True
        return talk, int(talk >= 1.0 and moving), laugh, int(laugh >= 1.0 and moving)

    def _moving_around_centre(self) -> bool:
        """The mouth moved within ``talk_gap_s`` before and after the window's centre frame
        ``(w - 1) // 2`` (the frame the window's mean is centred on; see :class:`FaceParams`).
        """
        p = self.params
        g = int(round(p.talk_gap_s * p.fps))
        if g <= 0:
            return True
        e = np.roll(self._energy, -self._i)  # oldest first
        active = np.nan_to_num(e, nan=0.0) >= p.talk_energy_tracked
        c = (len(e) - 1) // 2
        return bool(active[max(0, c - g) : c + 1].any() and active[c : c + g + 1].any())
