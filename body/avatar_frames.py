"""The video-texture avatar's recorded frames: masked, cropped images of one person, stored compressed.

Shared by the responder (which writes them into the avatar model file when it learns an avatar) and
the renderer (which reads them back by path to composite the partner), so it lives below both.

Storage (the choice, since the paper is silent): one fixed crop box around the person for the whole
recording (the union of the person's boxes, 2nd to 98th percentile, plus a margin), so the person's
own sway stays in the frames and a composited avatar does not jitter; each crop as a JPEG (quality
90; the pixels outside the person filled with the person's own colours spread outwards, so the
feathered edge has no dark fringe) and each mask as packed bits, in the same ``.npz`` as the model:

``frames_jpeg`` (N,) uint8, the JPEG streams one after another; ``frames_offsets`` (T + 1,) int64
where frame t's stream starts and ends; ``frames_masks`` (T, h, ceil(w / 8)) uint8 (``np.packbits``
along x); ``frames_geometry`` float64 ``[h, w, foot_x, foot_y, height_px, facing]``: crop size in
pixels, the person's median foot point (bottom centre of the mask) and height in crop pixels, and
the way they face in the image (+1 right, -1 left).

Decoding one frame costs a JPEG decode of the small crop (well under a millisecond); the
:class:`AvatarFrames` keeps the last decoded frames in a small cache, since consecutive output frames
mostly show consecutive recording frames.
"""

from __future__ import annotations

import os
from collections import OrderedDict
from dataclasses import dataclass

import cv2
import numpy as np

PREFIX = "frames_"
JPEG_QUALITY = 90


@dataclass(frozen=True)
class CropGeometry:
    """Where the person stands inside the crop.

    Parameters
    ----------
    h, w : int
        Crop size, pixels.
    foot : tuple of (float, float)
        The person's median foot point (x, y), crop pixels.
    height_px : float
        The person's median height, crop pixels.
    facing : float
        The way the person faces in the image: +1 right, -1 left.
    """

    h: int
    w: int
    foot: tuple[float, float]
    height_px: float
    facing: float


def foot_and_height(masks: np.ndarray) -> tuple[tuple[float, float], float]:
    """Median foot point and median height of the person in masked crops.

    Parameters
    ----------
    masks : ndarray of shape (T, h, w), dtype bool
        The person's masks (frames with an empty mask are left out).

    Returns
    -------
    foot : tuple of (float, float)
        Median foot point (x, y), pixels: the bottom of the mask, centre of its lowest tenth.
    height : float
        Median height of the person, pixels.

    Raises
    ------
    ValueError
        If no frame has the person in it.
    """
    masks = np.asarray(masks, bool)
    rows = masks.any(axis=2)
    have = rows.any(axis=1)
    if not have.any():
        raise ValueError("no frame with the person in it")
    m, r = masks[have], rows[have]
    h = m.shape[1]
    top = np.argmax(r, axis=1)
    bottom = h - 1 - np.argmax(r[:, ::-1], axis=1)
    # x centre of the lowest tenth of the body (the feet), not of the bottom row alone (one pixel)
    band = np.maximum(((bottom - top) * 0.1).astype(int), 1)
    ys = np.arange(h)[None, :, None]
    sel = m & (ys >= (bottom - band)[:, None, None]) & (ys <= bottom[:, None, None])
    xs = np.arange(m.shape[2])[None, None, :]
    fx = (sel * xs).sum(axis=(1, 2)) / np.maximum(sel.sum(axis=(1, 2)), 1)
    return (float(np.median(fx)), float(np.median(bottom) + 1)), float(np.median(bottom - top + 1))


def _fill_outside(img: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """The crop with the pixels outside the person replaced by the person's own colours spread
    outwards (normalised convolution, sigma 3 px): the feathered edge then blends towards the
    person's colour instead of a dark fringe, and JPEG spends few bits on the smooth surround.
    """
    m = mask.astype(np.float32)
    num = cv2.GaussianBlur(img.astype(np.float32) * m[..., None], (0, 0), 3.0)
    den = cv2.GaussianBlur(m, (0, 0), 3.0)[..., None]
    spread = np.where(den > 1e-3, num / np.maximum(den, 1e-3), 0.0)
    return np.where(mask[..., None], img, np.clip(spread, 0, 255)).astype(np.uint8)


class AvatarFrames:
    """The masked, cropped frames of a recording (module docstring for the layout).

    Build with :meth:`encode` from crops and masks, or :meth:`from_arrays` / :func:`load_avatar_frames`
    from a file. :meth:`image` and :meth:`alpha` decode frame ``t``.

    Parameters
    ----------
    jpeg : ndarray of shape (N,), dtype uint8
        The JPEG streams one after another.
    offsets : ndarray of shape (T + 1,), dtype int64
        Where frame t's stream starts and ends.
    masks : ndarray of shape (T, h, ceil(w / 8)), dtype uint8
        The masks, ``np.packbits`` along x.
    geometry : CropGeometry
        Where the person stands inside the crop.
    cache : int, default=16
        Decoded frames kept.

    Raises
    ------
    ValueError
        If there are not T + 1 offsets for T masks.
    """

    def __init__(
        self, jpeg: np.ndarray, offsets: np.ndarray, masks: np.ndarray, geometry: CropGeometry, cache: int = 16
    ) -> None:
        self.jpeg = np.asarray(jpeg, np.uint8)
        self.offsets = np.asarray(offsets, np.int64)
        self.masks = np.asarray(masks, np.uint8)
        self.geometry = geometry
        if len(self.offsets) != len(self.masks) + 1:
            raise ValueError(f"avatar frames: {len(self.offsets)} offsets for {len(self.masks)} masks")
        self._cache: OrderedDict[int, tuple[np.ndarray, np.ndarray]] = OrderedDict()
        self._cache_size = cache

    def __len__(self) -> int:
        return len(self.masks)

    @classmethod
    def encode(
        cls, crops: np.ndarray, masks: np.ndarray, facing: float = -1.0, quality: int = JPEG_QUALITY
    ) -> AvatarFrames:
        """Frames from crops and masks.

        Parameters
        ----------
        crops : ndarray of shape (T, h, w, 3), dtype uint8
            BGR crops.
        masks : ndarray of shape (T, h, w), dtype bool
            The person's masks.
        facing : float, default=-1.0
            +1 the person faces the image's right, -1 its left.
        quality : int, default=JPEG_QUALITY
            JPEG quality, 0 to 100.

        Returns
        -------
        AvatarFrames
            The compressed frames.

        Raises
        ------
        ValueError
            If the shapes do not match, JPEG encoding fails or no mask has the person in it.
        """
        crops, masks = np.asarray(crops), np.asarray(masks, bool)
        if crops.ndim != 4 or crops.shape[:3] != masks.shape:
            raise ValueError(f"crops {crops.shape} and masks {masks.shape} must be (T, h, w, 3) and (T, h, w)")
        streams = []
        for img, m in zip(crops, masks):
            ok, buf = cv2.imencode(".jpg", _fill_outside(img, m), [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
            if not ok:
                raise ValueError("JPEG encoding of an avatar frame failed")
            streams.append(buf.reshape(-1))
        offsets = np.zeros(len(streams) + 1, np.int64)
        offsets[1:] = np.cumsum([len(s) for s in streams])
        foot, height = foot_and_height(masks)
        geo = CropGeometry(int(masks.shape[1]), int(masks.shape[2]), foot, height, float(np.sign(facing) or -1.0))
        return cls(
            np.concatenate(streams) if streams else np.zeros(0, np.uint8), offsets, np.packbits(masks, axis=2), geo
        )

    # ----------------------------------------------------------------------------- persistence
    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays to store in the ``.npz`` (module docstring for the layout).

        Returns
        -------
        dict of str to ndarray
            ``frames_jpeg``, ``frames_offsets``, ``frames_masks`` and ``frames_geometry``.
        """
        g = self.geometry
        return {
            PREFIX + "jpeg": self.jpeg,
            PREFIX + "offsets": self.offsets,
            PREFIX + "masks": self.masks,
            PREFIX + "geometry": np.array([g.h, g.w, g.foot[0], g.foot[1], g.height_px, g.facing], np.float64),
        }

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray]) -> AvatarFrames:
        """The frames from stored arrays, as :meth:`arrays` returns them.

        Parameters
        ----------
        arrays : dict of str to ndarray
            ``frames_jpeg``, ``frames_offsets``, ``frames_masks`` and ``frames_geometry``.

        Returns
        -------
        AvatarFrames
            The frames.

        Raises
        ------
        ValueError
            Naming the array that is missing.
        """
        try:
            h, w, fx, fy, hp, facing = (float(v) for v in arrays[PREFIX + "geometry"])
            return cls(
                arrays[PREFIX + "jpeg"],
                arrays[PREFIX + "offsets"],
                arrays[PREFIX + "masks"],
                CropGeometry(int(h), int(w), (fx, fy), hp, facing),
            )
        except KeyError as exc:
            raise ValueError(f"not an avatar file: no {exc.args[0]!r} array") from None

    # ---------------------------------------------------------------------------------- access
    def _decode(self, t: int) -> tuple[np.ndarray, np.ndarray]:
        t = int(t)
        hit = self._cache.get(t)
        if hit is not None:
            self._cache.move_to_end(t)
            return hit
        if not 0 <= t < len(self):
            raise IndexError(f"avatar frame {t} out of range 0..{len(self) - 1}")
        g = self.geometry
        img = cv2.imdecode(self.jpeg[self.offsets[t] : self.offsets[t + 1]], cv2.IMREAD_COLOR)
        mask = np.unpackbits(self.masks[t], axis=1, count=g.w).astype(np.float32)
        # a one-pixel feather: a hard binary edge shimmers when the crop is scaled
        alpha = cv2.GaussianBlur(mask, (3, 3), 0)
        self._cache[t] = (img, alpha)
        if len(self._cache) > self._cache_size:
            self._cache.popitem(last=False)
        return img, alpha

    def image(self, t: int) -> np.ndarray:
        """The image of a frame (outside the person: the person's colours spread outwards).

        Parameters
        ----------
        t : int
            Frame index.

        Returns
        -------
        ndarray of shape (h, w, 3), dtype uint8
            BGR image.

        Raises
        ------
        IndexError
            If ``t`` is out of range.
        """
        return self._decode(t)[0]

    def alpha(self, t: int) -> np.ndarray:
        """The person's (feathered) mask of a frame.

        Parameters
        ----------
        t : int
            Frame index.

        Returns
        -------
        ndarray of shape (h, w), dtype float32
            Alpha in [0, 1].

        Raises
        ------
        IndexError
            If ``t`` is out of range.
        """
        return self._decode(t)[1]

    def mask(self, t: int) -> np.ndarray:
        """The person's mask of a frame as stored.

        Parameters
        ----------
        t : int
            Frame index.

        Returns
        -------
        ndarray of shape (h, w), dtype bool
            The mask.
        """
        return np.unpackbits(self.masks[int(t)], axis=1, count=self.geometry.w).astype(bool)


def load_avatar_frames(path: str | os.PathLike[str]) -> AvatarFrames:
    """The frames of an avatar file (a video-texture model ``.npz``).

    Parameters
    ----------
    path : str or os.PathLike
        The avatar file.

    Returns
    -------
    AvatarFrames
        Its frames.

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    ValueError
        Naming the file, when it is not an avatar file or holds no frames.
    """
    p = os.fspath(path)
    if not os.path.isfile(p):
        raise FileNotFoundError(f"{p}: no such avatar file (make one with 'counterpart learn avatar')")
    try:
        with np.load(p, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files if k.startswith(PREFIX)}
    except (OSError, ValueError) as exc:
        raise ValueError(f"{p}: not an avatar file ({exc})") from None
    try:
        return AvatarFrames.from_arrays(arrays)
    except ValueError as exc:
        raise ValueError(f"{p}: {exc}") from None
