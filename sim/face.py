"""Close-up face video with known head and mouth motion: nods, shakes, talking, laughing.

A small synthetic face renderer for the labeller's face path (OpenCV's frontal Haar cascade must
find it): a head ellipsoid with hair, eye sockets, eyes, brows, a nose with nostrils and a mouth
whose jaw drops, rotated about a neck pivot by a yaw (shake) and a pitch (nod), projected
orthographically into a ``width`` x ``height`` frame over a textured background, lit from one side,
supersampled twice, blurred, and with sensor noise and a slight brightness flicker per frame;
the clips add what a camera filming a real face adds to that: blinks (10-25 a minute), slow
lighting changes and JPEG compression (``realistic``, the default).

    clip = conversation_face_clip(seed=3, fps=29.97, duration=60.0)
    for i in range(clip.n_frames):
        img = clip.render(i)                 # (H, W, 3) uint8 BGR
    clip.truth["nod"], clip.truth["shake"], clip.truth["talking"]   # (T,) bool per frame

``conversation_face_clip`` films person A of the simulator's ``conversation`` scenario
(``counterpart.sim.scenarios.conversation``) face-on: head yaw and pitch are the scenario's ``head_turn`` and
``head_nod`` (relative to the torso, so nods, shakes and look-aways), the head's sway its joint's
motion, and the mouth moves through each of the person's talking turns in syllables (3-6 per
second, with short pauses). The labels are the scenario's own.

Not a face model: a frontal Haar cascade finds this face (mostly; it loses it during look-aways
beyond about 30 degrees, as it does on real faces), which is what it is for.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from counterpart.body.pose import DOF_INDEX
from counterpart.sim.scenarios import SIGNAL_INDEX, conversation

#: half-axes of the head ellipsoid (m): x across the face, y up, z towards the camera at yaw 0
HEAD_RADII = (0.08, 0.102, 0.095)
#: the neck pivot of nods and shakes, relative to the head centre (m)
PIVOT = np.array([0.0, -0.10, -0.03])
#: how far the sensor noise field reaches beyond the frame (px): its per-frame shifts
NOISE_PAD = 64
#: the width of the face across the cheeks (m): what sets the pixel scale
FACE_WIDTH_M = 0.15


def _ring(c: tuple[float, float, float], rx: float, ry: float, n: int = 24) -> np.ndarray:
    """(n, 3) points of an ellipse in the plane z = c[2] (m, head frame)."""
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.stack([c[0] + rx * np.cos(a), c[1] + ry * np.sin(a), np.full(n, c[2])], axis=1)


def _sphere(radii: tuple[float, float, float], n: int = 24) -> np.ndarray:
    """(n*n, 3) points on an ellipsoid surface (m)."""
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, n, endpoint=False), np.linspace(0.02, np.pi - 0.02, n))
    return np.stack(
        [radii[0] * np.sin(v) * np.cos(u), radii[1] * np.cos(v), radii[2] * np.sin(v) * np.sin(u)], axis=-1
    ).reshape(-1, 3)


def rotation(yaw: float, pitch: float) -> np.ndarray:
    """Head rotation: ``pitch`` about x, then ``yaw`` about y.

    Parameters
    ----------
    yaw : float
        Radians, positive turns the face to the image's left.
    pitch : float
        Radians, positive chin down.

    Returns
    -------
    ndarray of shape (3, 3)
        The rotation matrix.
    """
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    ry = np.array([[cy, 0.0, -sy], [0.0, 1.0, 0.0], [sy, 0.0, cy]])
    # y up, z towards the camera: chin down takes the front of the face (z > 0) down, as the
    # body's ``head_nod`` does (the opposite sign drew a chin-down head looking up, and a nod's
    # rotation then cancelled the head joint's own dip at the eyes)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cp, -sp], [0.0, sp, cp]])
    return ry @ rx


@dataclass(frozen=True)
class FaceLook:
    """Colours (BGR 0-255) and the seed of the background texture.

    Parameters
    ----------
    skin, hair, lips, shirt : tuple of (float, float, float)
        Colours, BGR 0-255.
    background_seed : int, default=0
        Seed of the background texture.
    """

    skin: tuple[float, float, float] = (120.0, 150.0, 195.0)
    hair: tuple[float, float, float] = (30.0, 40.0, 55.0)
    lips: tuple[float, float, float] = (95.0, 95.0, 165.0)
    shirt: tuple[float, float, float] = (120.0, 80.0, 60.0)
    background_seed: int = 0


def random_look(rng: np.random.Generator) -> FaceLook:
    """A seeded skin tone (light to dark), hair, shirt and background.

    Parameters
    ----------
    rng : numpy.random.Generator
        The draws.

    Returns
    -------
    FaceLook
        The look.
    """
    tone = float(rng.uniform(0.45, 1.0))
    skin = (125.0 * tone + 10, 155.0 * tone + 10, 200.0 * tone + 15)
    hair = tuple(float(v) * float(rng.uniform(0.2, 1.0)) for v in (40.0, 55.0, 75.0))
    shirt = tuple(float(v) for v in rng.uniform(40, 200, 3))
    lips = (skin[0] * 0.7, skin[1] * 0.6, skin[2] * 0.85)
    return FaceLook(skin, hair, lips, shirt, int(rng.integers(1 << 30)))  # type: ignore[arg-type]


class FaceRenderer:
    """Draws one face per call (see the module docstring).

    Parameters
    ----------
    width, height : int, default=640, 360
        Frame size, pixels (at least 64 each).
    face_px : float, default=130.0
        Face width across the cheeks, pixels (16 to the frame's smaller side).
    look : FaceLook or None, default=None
        Colours and background; None: the default look.
    noise : float, default=2.5
        Sensor noise sigma, grey levels.
    center : tuple of (float, float) or None, default=None
        (x, y) of the head centre at rest, pixels; None: the frame's centre a little above the middle.

    Raises
    ------
    ValueError
        For a frame smaller than 64 x 64 or a ``face_px`` out of range.
    """

    def __init__(
        self,
        width: int = 640,
        height: int = 360,
        face_px: float = 130.0,
        look: FaceLook | None = None,
        noise: float = 2.5,
        center: tuple[float, float] | None = None,
    ) -> None:
        if width < 64 or height < 64:
            raise ValueError(f"frame size {width}x{height}: need at least 64x64 pixels")
        if not 16 <= face_px <= min(width, height):
            raise ValueError(f"face_px={face_px}: must be between 16 and the frame's smaller side")
        self.width, self.height = int(width), int(height)
        self.scale = 2.0 * face_px / FACE_WIDTH_M  # supersampled px per metre
        self.look = look or FaceLook()
        self.noise = float(noise)
        self.center = center or (width / 2.0, height * 0.45)
        brng = np.random.default_rng(self.look.background_seed)
        base = brng.uniform(70, 190, (9, 16, 1)).astype(np.float32)
        tint = brng.uniform(-25, 25, (9, 16, 3)).astype(np.float32)
        bg = cv2.resize(base + tint, (2 * width, 2 * height), interpolation=cv2.INTER_CUBIC)
        bg += cv2.GaussianBlur(brng.normal(0, 12, (2 * height, 2 * width, 3)).astype(np.float32), (0, 0), 3)
        self._background = np.clip(bg, 0, 255).astype(np.uint8)
        # side lighting, fixed in the image: brighter on the left
        ramp = np.linspace(1.12, 0.85, 2 * width, dtype=np.float32)
        self._light = np.ascontiguousarray(np.broadcast_to(ramp[None, :, None], (2 * height, 2 * width, 3)))
        # sensor noise: a field drawn once, read at a random shift per frame (a new draw of
        # every pixel per frame cost more than the rest of the frame)
        nrng = np.random.default_rng([self.look.background_seed, 5])
        self._noise = nrng.normal(0.0, self.noise, (height + NOISE_PAD, width + NOISE_PAD, 3)).astype(np.float32)
        self._skull = _sphere(HEAD_RADII)
        self._hair = _sphere(tuple(1.06 * r for r in HEAD_RADII))
        self._hair = self._hair[(self._hair[:, 1] > 0.035) | (self._hair[:, 2] < -0.02)]

    def _project(self, pts: np.ndarray, R: np.ndarray, origin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Head-frame points (N,3) m -> (N,2) supersampled pixel coordinates and (N,) depth."""
        w = (pts - PIVOT) @ R.T + PIVOT
        uv = np.stack([origin[0] + self.scale * w[:, 0], origin[1] - self.scale * w[:, 1]], axis=1)
        return uv, w[:, 2]

    def render(
        self,
        yaw: float = 0.0,
        pitch: float = 0.0,
        mouth: float = 0.0,
        offset_px: tuple[float, float] = (0.0, 0.0),
        smile: float = 0.0,
        rng: np.random.Generator | None = None,
        blink: float = 0.0,
        light: float = 1.0,
        jpeg_quality: int = 0,
    ) -> np.ndarray:
        """One frame.

        Parameters
        ----------
        yaw, pitch : float, default=0.0
            Head rotation, radians (see :func:`rotation`).
        mouth : float, default=0.0
            Jaw opening in [0, 1] (1: about 2 cm).
        offset_px : tuple of (float, float), default=(0.0, 0.0)
            Head translation (x right, y down), pixels.
        smile : float, default=0.0
            Widens the mouth, [0, 1].
        rng : numpy.random.Generator or None, default=None
            Sensor noise draws (None: no noise).
        blink : float, default=0.0
            Eyelid closure in [0, 1] (1: shut).
        light : float, default=1.0
            Brightness gain of the scene (slow illumination changes).
        jpeg_quality : int, default=0
            1-100 to pass the frame through JPEG compression (a camera's or a codec's artefacts), 0 not.

        Returns
        -------
        ndarray of shape (H, W, 3), dtype uint8
            BGR frame.
        """
        lk = self.look
        img = self._background.copy()
        origin = np.array([2 * (self.center[0] + offset_px[0]), 2 * (self.center[1] + offset_px[1])])
        R = rotation(yaw, pitch)
        sh = 16  # fixed-point bits: sub-pixel outlines, so that small motions move the image smoothly

        def poly(uv: np.ndarray, colour: tuple[float, ...], hull: bool = False) -> None:
            p = np.round(uv * sh).astype(np.int32)
            if hull:
                p = cv2.convexHull(p)
            cv2.fillPoly(img, [p.reshape(-1, 1, 2)], colour, cv2.LINE_AA, shift=4)

        s = self.scale
        # shoulders and neck: fixed below the head, they do not turn with it
        neck_top = origin + np.array([0.0, s * 0.06])
        cv2.rectangle(
            img,
            (int(neck_top[0] - s * 0.05), int(neck_top[1])),
            (int(neck_top[0] + s * 0.05), int(origin[1] + s * 0.2)),
            tuple(0.7 * c for c in lk.skin),
            -1,
        )
        cv2.ellipse(
            img, (int(origin[0]), int(origin[1] + s * 0.21)), (int(s * 0.24), int(s * 0.09)), 0, 0, 360, lk.shirt, -1
        )
        cv2.rectangle(
            img,
            (int(origin[0] - s * 0.24), int(origin[1] + s * 0.21)),
            (int(origin[0] + s * 0.24), 2 * self.height + 1),
            lk.shirt,
            -1,
        )
        poly(self._project(self._hair, R, origin)[0], lk.hair, hull=True)
        skull = self._skull.copy()
        drop = 0.02 * float(np.clip(mouth, 0, 1.5))
        chin = skull[:, 1] < -0.04
        skull[chin, 1] -= drop * np.clip((-0.04 - skull[chin, 1]) / 0.04, 0, 1) ** 0.5
        face = skull[(skull[:, 2] > -0.01) & (skull[:, 1] < 0.06)]
        poly(self._project(face, R, origin)[0], tuple(0.8 * c for c in lk.skin), hull=True)
        # the front of the face is lit, its sides fall off: a brighter inner oval
        inner = face[face[:, 2] > 0.55 * HEAD_RADII[2]]
        poly(self._project(inner, R, origin)[0], lk.skin, hull=True)
        # features, back to front by their normals (a feature turned away is not drawn)
        skin = np.array(lk.skin)
        my = -0.052 - 0.5 * drop
        mw = 0.026 * (1.0 + 0.25 * smile)
        feats: list[tuple[np.ndarray, tuple[float, ...]]] = []
        lid = 1.0 - float(np.clip(blink, 0.0, 1.0))  # the open part of the eye
        for sx in (-1.0, 1.0):
            feats += [
                (_ring((sx * 0.033, 0.030, 0.072), 0.024, 0.019), tuple(0.62 * skin)),  # socket
                (_ring((sx * 0.034, 0.046, 0.080), 0.020, 0.0055), lk.hair),  # brow
                (_ring((sx * 0.033, 0.022, 0.079), 0.013, 0.0055), tuple(0.8 * skin)),  # closed lid
                (_ring((sx * 0.033, 0.022, 0.0795), 0.013, 0.0055 * lid), (215.0, 215.0, 220.0)),  # eye white
                (_ring((sx * 0.033, 0.022, 0.080), 0.0055, 0.0055 * lid), (40.0, 35.0, 30.0)),  # iris
                (_ring((sx * 0.012, -0.012, 0.095), 0.006, 0.014), tuple(0.85 * skin)),  # nose side
                (_ring((sx * 0.008, -0.030, 0.098), 0.0045, 0.0025), tuple(0.35 * skin)),  # nostril
            ]
        feats += [
            (_ring((0.0, -0.005, 0.100), 0.007, 0.022), tuple(np.minimum(1.12 * skin, 255))),  # bridge
            (_ring((0.0, my, 0.083), mw, 0.007 + 0.5 * drop), lk.lips),
            (_ring((0.0, my, 0.085), 0.85 * mw, 0.0015 + 0.45 * drop), (35.0, 30.0, 60.0)),  # opening
        ]
        if drop > 0.004:
            feats.append((_ring((0.0, my + 0.3 * drop, 0.086), 0.6 * mw, 0.12 * drop), (225.0, 225.0, 230.0)))
        for pts, colour in feats:
            uv, z = self._project(pts, R, origin)
            normal = (
                R @ np.array([pts[0, 0] / HEAD_RADII[0] ** 2, pts[0, 1] / HEAD_RADII[1] ** 2, 0.5 / HEAD_RADII[2]])
            )[2]
            if normal > 0.15:
                poly(uv, colour)
        out = cv2.multiply(img, self._light, scale=float(light), dtype=cv2.CV_32F)
        out = cv2.GaussianBlur(out, (0, 0), 1.2)
        out = cv2.resize(out, (self.width, self.height), interpolation=cv2.INTER_AREA)
        if rng is not None:
            out *= float(1.0 + rng.normal(0.0, 0.004))
            dy, dx = rng.integers(0, NOISE_PAD, 2)
            out += self._noise[dy : dy + self.height, dx : dx + self.width]
        out8 = np.clip(out, 0, 255).astype(np.uint8)
        if jpeg_quality:
            ok, buf = cv2.imencode(".jpg", out8, [cv2.IMWRITE_JPEG_QUALITY, int(jpeg_quality)])
            out8 = cv2.imdecode(buf, cv2.IMREAD_COLOR)
        return out8


def syllables(
    talking: np.ndarray,
    fps: float,
    rng: np.random.Generator,
    rate_hz: tuple[float, float] = (3.0, 6.0),
) -> np.ndarray:
    """Jaw opening of speech: raised-cosine syllables of 0.1-0.25 s, amplitudes 0.35-1, a pause of
    0.2-0.4 s now and then (between words); closed elsewhere.

    Parameters
    ----------
    talking : ndarray of shape (T,), dtype bool
        The frames of speech.
    fps : float
        Frames per second.
    rng : numpy.random.Generator
        The draws.
    rate_hz : tuple of (float, float), default=(3.0, 6.0)
        Range of the syllable rate, per second.

    Returns
    -------
    ndarray of shape (T,)
        Jaw opening in [0, 1].
    """
    t_n = talking.shape[0]
    out = np.zeros(t_n)
    t = 0.0
    while t * fps < t_n:
        i = int(t * fps)
        if not talking[i]:
            t += 1.0 / fps
            continue
        d = float(rng.uniform(0.1, 0.25))
        k = np.arange(int(np.ceil(d * fps)) + 1)
        idx = i + k
        ok = idx < t_n
        bump = float(rng.uniform(0.35, 1.0)) * 0.5 * (1 - np.cos(2 * np.pi * np.clip(k / (d * fps), 0, 1)))
        out[idx[ok]] = np.maximum(out[idx[ok]], bump[ok])
        t += 1.0 / float(rng.uniform(*rate_hz))
        if rng.random() < 0.12:
            t += float(rng.uniform(0.2, 0.4))
    return out * talking


def blinks(n: int, fps: float, rng: np.random.Generator, rate_hz: tuple[float, float] = (0.2, 0.4)) -> np.ndarray:
    """Eyelid closure of blinks, each 0.1-0.25 s, closing and opening as a raised cosine.

    Parameters
    ----------
    n : int
        Frames.
    fps : float
        Frames per second.
    rng : numpy.random.Generator
        The draws.
    rate_hz : tuple of (float, float), default=(0.2, 0.4)
        Range of the seeded blink rate, per second (people blink 10-25 times a minute).

    Returns
    -------
    ndarray of shape (n,)
        Eyelid closure in [0, 1].
    """
    out = np.zeros(n)
    rate = float(rng.uniform(*rate_hz))
    t = float(rng.exponential(1.0 / rate))
    while t * fps < n:
        d = float(rng.uniform(0.1, 0.25))
        k = np.arange(int(np.ceil(d * fps)) + 1)
        idx = int(t * fps) + k
        ok = idx < n
        lid = 0.5 * (1 - np.cos(2 * np.pi * np.clip(k / (d * fps), 0, 1)))
        out[idx[ok]] = np.maximum(out[idx[ok]], lid[ok])  # a blink may run past the clip's end
        t += d + float(rng.exponential(1.0 / rate))
    return out


def lighting(n: int, fps: float, rng: np.random.Generator, depth: float = 0.08) -> np.ndarray:
    """Slow brightness gain around 1 (clouds, auto exposure): a sum of a few sinusoids of
    periods 4-20 s.

    Parameters
    ----------
    n : int
        Frames.
    fps : float
        Frames per second.
    rng : numpy.random.Generator
        The draws.
    depth : float, default=0.08
        Peak change, about.

    Returns
    -------
    ndarray of shape (n,)
        Brightness gain.
    """
    t = np.arange(n) / fps
    g = np.zeros(n)
    for _ in range(3):
        g += np.sin(2 * np.pi * t / float(rng.uniform(4.0, 20.0)) + float(rng.uniform(0, 2 * np.pi)))
    return 1.0 + depth / 3.0 * g


@dataclass
class FaceClip:
    """A face video with per-frame truth (see :meth:`FaceRenderer.render`).

    Attributes
    ----------
    renderer : FaceRenderer
        Draws the frames.
    fps : float
        Frames per second.
    yaw, pitch : ndarray of shape (T,)
        Head rotation, radians.
    mouth : ndarray of shape (T,)
        Jaw opening.
    offset : ndarray of shape (T, 2)
        Head translation, pixels.
    truth : dict of str to ndarray of shape (T,), dtype bool
        "nod", "shake", "talking", "laughing".
    smile : ndarray of shape (T,) or None
        Mouth widening (None: none).
    seed : int
        Seed of the sensor noise.
    meta : dict of str to object
        Where the clip comes from.
    blink : ndarray of shape (T,) or None
        Eyelid closure (None: none).
    light : ndarray of shape (T,) or None
        Scene brightness gain (None: 1).
    jpeg_quality : int
        Per-frame JPEG compression (0: none).
    """

    renderer: FaceRenderer
    fps: float
    yaw: np.ndarray
    pitch: np.ndarray
    mouth: np.ndarray
    offset: np.ndarray
    truth: dict[str, np.ndarray]
    smile: np.ndarray | None = None
    seed: int = 0
    meta: dict[str, object] = field(default_factory=dict)
    blink: np.ndarray | None = None
    light: np.ndarray | None = None
    jpeg_quality: int = 0

    @property
    def n_frames(self) -> int:
        return int(self.yaw.shape[0])

    def render(self, i: int) -> np.ndarray:
        """One frame; its sensor noise depends on (seed, i) only.

        Parameters
        ----------
        i : int
            Frame index.

        Returns
        -------
        ndarray of shape (H, W, 3), dtype uint8
            BGR frame.
        """
        rng = np.random.default_rng([self.seed, 77, i])
        sm = 0.0 if self.smile is None else float(self.smile[i])
        return self.renderer.render(
            float(self.yaw[i]),
            float(self.pitch[i]),
            float(self.mouth[i]),
            (float(self.offset[i, 0]), float(self.offset[i, 1])),
            sm,
            rng,
            0.0 if self.blink is None else float(self.blink[i]),
            1.0 if self.light is None else float(self.light[i]),
            self.jpeg_quality,
        )


#: JPEG quality of the rendered clips (a webcam's or a video codec's compression)
JPEG_QUALITY = 80


def _camera(n: int, fps: float, seed: int, realistic: bool) -> dict[str, object]:
    """The FaceClip fields of a real camera and face: blinks, slow lighting changes, compression
    (none when not ``realistic``); drawn from their own seeded stream, so the motion stays that of
    ``seed``.
    """
    if not realistic:
        return {}
    rng = np.random.default_rng([seed, 1014])
    return {"blink": blinks(n, fps, rng), "light": lighting(n, fps, rng), "jpeg_quality": JPEG_QUALITY}


def conversation_face_clip(
    seed: int = 0,
    fps: float = 25.0,
    duration: float = 60.0,
    width: int = 640,
    height: int = 360,
    face_px: float | None = None,
    person: str = "a",
    realistic: bool = True,
) -> FaceClip:
    """One person of ``counterpart.sim.scenarios.conversation(seed, fps, duration=duration)`` filmed
    face-on (see the module docstring).

    Parameters
    ----------
    seed : int, default=0
        Seed of the scenario and the clip.
    fps : float, default=25.0
        Frames per second.
    duration : float, default=60.0
        Length, seconds.
    width, height : int, default=640, 360
        Frame size, pixels.
    face_px : float or None, default=None
        Face width, pixels; None: seeded 100-170 at 640x360 (scaled with the frame height).
    person : {"a", "b"}, default="a"
        The person filmed.
    realistic : bool, default=True
        Blinks, slow lighting changes and JPEG compression (:data:`JPEG_QUALITY`) on top of the
        sensor noise.

    Returns
    -------
    FaceClip
        The clip with the scenario's labels as truth.

    Raises
    ------
    ValueError
        For a ``person`` other than "a" or "b".
    """
    if person not in ("a", "b"):
        raise ValueError(f"person={person!r}: use 'a' or 'b'")
    sc = conversation(seed=seed, fps=fps, duration=duration)
    rng = np.random.default_rng([seed, 1013])
    poses = sc.poses_a if person == "a" else sc.poses_b
    sig = sc.signals_a if person == "a" else sc.signals_b
    yaw = poses[:, DOF_INDEX["head_turn"]].copy()
    pitch = poses[:, DOF_INDEX["head_nod"]].copy()
    face_px = float(face_px if face_px is not None else rng.uniform(100, 170) * height / 360)
    px_per_m = face_px / FACE_WIDTH_M
    head = sc.joints()[:, 0 if person == "a" else 1, 0]
    # the person faces along x: their sideways sway is world z, image y is world up
    off = np.stack([(head[:, 2] - head[:, 2].mean()), -(head[:, 1] - head[:, 1].mean())], axis=1) * px_per_m
    talking = sig[:, SIGNAL_INDEX["talking"]] == 1
    mouth = syllables(talking, fps, rng)
    truth = {
        "nod": sig[:, SIGNAL_INDEX["nod"]] == 1,
        "shake": sig[:, SIGNAL_INDEX["shake"]] == 1,
        "talking": talking,
        "laughing": np.zeros_like(talking),
    }
    r = FaceRenderer(
        width,
        height,
        face_px,
        random_look(rng),
        center=(width / 2 + float(rng.uniform(-0.15, 0.15)) * width, height * 0.45),
    )
    return FaceClip(
        r,
        float(fps),
        yaw,
        pitch,
        mouth,
        off,
        truth,
        seed=seed,
        meta={"scenario": "conversation", "seed": seed, "person": person, "face_px": face_px},
        **_camera(len(yaw), fps, seed, realistic),
    )


def gesture_face_clip(
    kind: str,
    fps: float = 25.0,
    duration: float = 6.0,
    seed: int = 0,
    width: int = 640,
    height: int = 360,
    face_px: float = 130.0,
    realistic: bool = True,
) -> FaceClip:
    """A short clip of one behaviour throughout (after 1 s of rest): ``still``, ``nod`` (2 Hz,
    8 degrees), ``shake`` (2.5 Hz, 15 degrees), ``talk`` or ``laugh`` (mouth wide open at about
    5 per second, with a smile), for tests. Truth is True from the behaviour's start to its end.

    Parameters
    ----------
    kind : {"still", "nod", "shake", "talk", "laugh"}
        The behaviour.
    fps : float, default=25.0
        Frames per second.
    duration : float, default=6.0
        Length, seconds.
    seed : int, default=0
        Seed of the clip.
    width, height : int, default=640, 360
        Frame size, pixels.
    face_px : float, default=130.0
        Face width, pixels.
    realistic : bool, default=True
        As in :func:`conversation_face_clip`.

    Returns
    -------
    FaceClip
        The clip.

    Raises
    ------
    ValueError
        For an unknown ``kind``.
    """
    kinds = ("still", "nod", "shake", "talk", "laugh")
    if kind not in kinds:
        raise ValueError(f"kind={kind!r}: use one of {kinds}")
    rng = np.random.default_rng([seed, 31])
    n = int(round(duration * fps))
    t = np.arange(n) / fps
    on = t >= 1.0
    yaw = np.zeros(n)
    pitch = np.zeros(n)
    mouth = np.zeros(n)
    smile = np.zeros(n)
    if kind == "nod":
        pitch = np.radians(8.0) * np.sin(2 * np.pi * 2.0 * (t - 1.0)) * on
    elif kind == "shake":
        yaw = np.radians(15.0) * np.sin(2 * np.pi * 2.5 * (t - 1.0)) * on
    elif kind == "talk":
        mouth = syllables(on, fps, rng)
    elif kind == "laugh":
        mouth = (0.3 + 1.0 * np.abs(np.sin(2 * np.pi * 2.5 * (t - 1.0)))) * on
        smile = 1.0 * on
        pitch = np.radians(1.5) * np.sin(2 * np.pi * 5.0 * (t - 1.0)) * on
    truth = {k: np.zeros(n, bool) for k in ("nod", "shake", "talking", "laughing")}
    key = {"nod": "nod", "shake": "shake", "talk": "talking", "laugh": "laughing"}.get(kind)
    if key:
        truth[key] = on.copy()
    r = FaceRenderer(width, height, face_px, random_look(rng))
    return FaceClip(
        r,
        float(fps),
        yaw,
        pitch,
        mouth,
        np.zeros((n, 2)),
        truth,
        smile,
        seed=seed,
        meta={"kind": kind},
        **_camera(n, fps, seed, realistic),
    )
