"""Rendering a :class:`counterpart.sim.scenarios.Scenario` to video frames with exact ground truth.

Image formation, per frame ``i`` at time ``t = i / fps``::

    background  B(x)    procedural room: a wooden plank floor (y = 0) and a plaster wall at
                        z = ``wall_z`` with a skirting board, a rail and a poster; fixed per seed
    lighting    g(t)    global gain 1 + a sin(2 pi t / period + phi), a in [0.02, 0.04]: a slow drift
    shadows     S(x)    each body part's surface points projected onto y = 0 along the light
                        direction, convex hulls filled; floor pixels in S are multiplied by
                        ``shadow_factor`` (0.55-0.7, the same for all channels: chromaticity kept)
    people              every part's projected convex hull filled in painter's order (far to near
                        by mean camera depth, both people together) into a part-id image, then
                        coloured by a per-frame look-up table (clothing colour x back-side shade)
    noise               i.i.d. Gaussian, sigma ``noise_sigma`` grey levels (default 2), drawn from
                        ``numpy.random.default_rng([seed, 99, i])``: the same frame is the same bytes

    I(x) = round(clip(g(t) * (person colour | B(x) * (shadow_factor if x in S else 1)) + noise))

Ground truth (``FrameTruth``) is read off the same drawing: person masks are the pixels whose
final part id belongs to that person (what is visible after occlusion), the shadow mask is S on
floor pixels not covered by a person. Without noise, a pixel differs from ``background(i)``
exactly where a mask or the shadow mask is set.

Drawing is vectorised: one numpy pass per chunk of frames builds every part's 3D points and
projections; per frame a loop over the ~40 parts calls ``cv2.convexHull`` and
``cv2.fillConvexPoly`` (no per-pixel Python).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from counterpart.body.camera import Camera, default_camera
from counterpart.sim.appearance import Appearance, PartTable, body_clouds, part_table, random_appearance
from counterpart.sim.scenarios import Scenario

_SHIFT = 4
_CHUNK = 32


@dataclass(frozen=True)
class Lighting:
    """Light direction, gain drift and shadow strength.

    Parameters
    ----------
    direction : tuple of float
        Unit vector (x, y, z) from the light towards the scene, world frame.
    gain_amp : float
        Amplitude a of the global gain's drift.
    gain_period_s : float
        Period of the drift, seconds.
    gain_phase : float
        Phase phi of the drift, radians.
    shadow_factor : float
        Factor applied to floor pixels in shadow (the same for all channels).
    """

    direction: tuple[float, float, float]
    gain_amp: float
    gain_period_s: float
    gain_phase: float
    shadow_factor: float

    def gain(self, t: float) -> float:
        """The global gain g(t) = 1 + a sin(2 pi t / period + phi).

        Parameters
        ----------
        t : float
            Scene time, seconds.

        Returns
        -------
        float
            The gain.
        """
        return 1.0 + self.gain_amp * float(np.sin(2 * np.pi * t / self.gain_period_s + self.gain_phase))


def random_lighting(rng: np.random.Generator) -> Lighting:
    """A lighting drawn from ``rng``: the light shines down, towards -z, tilted sideways in x.

    Parameters
    ----------
    rng : numpy.random.Generator
        The random source.

    Returns
    -------
    Lighting
        Gain amplitude in [0.02, 0.04], period 15-40 s, shadow factor 0.55-0.7.
    """
    d = np.array([rng.uniform(0.2, 0.5) * rng.choice([-1, 1]), -1.0, -rng.uniform(0.3, 0.6)])
    d /= np.linalg.norm(d)
    return Lighting(
        tuple(float(v) for v in d),
        float(rng.uniform(0.02, 0.04)),
        float(rng.uniform(15.0, 40.0)),
        float(rng.uniform(0, 2 * np.pi)),
        float(rng.uniform(0.55, 0.7)),
    )


def _noise_texture(rng: np.random.Generator, n: int, blur: float) -> np.ndarray:
    t = rng.standard_normal((n, n)).astype(np.float32)
    pad = int(np.ceil(4 * blur))
    t = cv2.GaussianBlur(np.pad(t, pad, mode="wrap"), (0, 0), blur)[pad:-pad, pad:-pad]  # tileable
    return t / max(float(t.std()), 1e-6)


def make_background(camera: Camera, rng: np.random.Generator, wall_z: float = -2.5) -> tuple[np.ndarray, np.ndarray]:
    """Procedural room seen by ``camera``.

    Parameters
    ----------
    camera : Camera
        The camera.
    rng : numpy.random.Generator
        The random source of the room's colours and textures.
    wall_z : float, default=-2.5
        z of the wall plane, metres, world frame.

    Returns
    -------
    bg : ndarray of shape (H, W, 3), dtype float32
        The room, BGR in [35, 235].
    floor : ndarray of shape (H, W), dtype bool
        Pixels that see the floor (where shadows can fall).
    """
    H, W = camera.height, camera.width
    v, u = np.mgrid[0:H, 0:W].astype(np.float64)
    G = camera.ground_point(u, v)
    floor = np.isfinite(G[..., 0]) & (G[..., 2] > wall_z)
    d = camera.rays(u, v)
    c = camera.centre
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (wall_z - c[2]) / d[..., 2]
    Wp = c + s[..., None] * d
    fine = _noise_texture(rng, 256, 1.0)
    coarse = _noise_texture(rng, 256, 6.0)

    def tex(t: np.ndarray, a: np.ndarray, b: np.ndarray, res: float) -> np.ndarray:
        ia = np.floor(np.nan_to_num(a) / res).astype(np.int64) % t.shape[1]
        ib = np.floor(np.nan_to_num(b) / res).astype(np.int64) % t.shape[0]
        return t[ib, ia]

    # floor: planks along z, 0.16 m wide, with per-plank tone, grain and end joints
    wood = np.array([rng.uniform(60, 90), rng.uniform(100, 130), rng.uniform(140, 175)])
    gx, gz = G[..., 0], G[..., 2]
    plank = np.floor(np.nan_to_num(gx) / 0.16).astype(np.int64)
    tones = rng.uniform(0.8, 1.15, 512)
    offs = rng.uniform(0, 1.5, 512)
    tone = tones[plank % 512]
    grain = 0.05 * np.sin(np.nan_to_num(gz) * 35.0 + 3.0 * tex(coarse, gx, gz, 0.02)) + 0.05 * tex(fine, gx, gz, 0.005)
    joint = (((np.nan_to_num(gz) + offs[plank % 512]) % 1.5) < 0.012) | ((np.nan_to_num(gx) % 0.16) < 0.006)
    fl = wood * (tone * (1 + grain) * np.where(joint, 0.7, 1.0))[..., None]
    depth_fade = np.clip(1.0 - 0.05 * (4.0 - np.nan_to_num(gz)), 0.75, 1.0)
    fl *= depth_fade[..., None]
    # wall: plaster with noise, skirting board, rail, a poster
    paint = np.array([rng.uniform(150, 215), rng.uniform(150, 215), rng.uniform(150, 215)])
    wx, wy = Wp[..., 0], Wp[..., 1]
    wl = paint * (1 + 0.04 * tex(coarse, wx, wy, 0.01) + 0.025 * tex(fine, wx, wy, 0.004))[..., None]
    skirting = wy < 0.12
    wl[skirting] = np.array([215.0, 215, 210]) * (1 + 0.02 * tex(fine, wx, wy, 0.004))[skirting][:, None]
    rail = np.abs(wy - 0.95) < 0.02
    wl[rail] *= 0.8
    px = rng.uniform(-2.0, 1.0)
    poster = (wx > px) & (wx < px + rng.uniform(0.5, 0.9)) & (wy > 1.2) & (wy < 1.2 + rng.uniform(0.4, 0.7))
    pcol = rng.uniform(40, 220, 3)
    wl[poster] = pcol * (1 + 0.15 * tex(coarse, wx, wy, 0.004))[poster][:, None]
    wl *= np.clip(1.0 - 0.08 * (wy - 1.0), 0.8, 1.1)[..., None]
    bg = np.where(floor[..., None], fl, wl)
    r2 = ((u - W / 2) / W) ** 2 + ((v - H / 2) / H) ** 2
    bg *= (1.0 - 0.25 * r2)[..., None]
    return np.clip(bg, 35, 235).astype(np.float32), floor


@dataclass
class FrameTruth:
    """Ground truth of one frame.

    Attributes
    ----------
    joints3d : ndarray of shape (2, 14, 3)
        Joints, metres, world frame, A then B.
    joints2d : ndarray of shape (2, 14, 2)
        Projected joints, pixels (u, v).
    masks : ndarray of shape (2, H, W), dtype bool
        Visible pixels of A and B.
    shadow : ndarray of shape (H, W), dtype bool
        Cast-shadow pixels on the floor not covered by a person.
    signals : ndarray of shape (2, K), dtype int8
        Social signals (``Scenario.signal_names``).
    phase : int
        Phase code (``counterpart.sim.scenarios.PHASES``).
    label : str
        Interaction label.
    time_s : float
        Scene time, seconds.
    """

    joints3d: np.ndarray
    joints2d: np.ndarray
    masks: np.ndarray
    shadow: np.ndarray
    signals: np.ndarray
    phase: int
    label: str
    time_s: float


class Renderer:
    """Renders one scenario; every frame is a pure function of (scenario, seed, frame index).

    Parameters
    ----------
    scenario : Scenario
        The motion.
    camera : Camera or None, default=None
        The camera; None for ``counterpart.body.camera.default_camera(width, height)``.
    seed : int, default=0
        Seeds the room, lighting, clothing and sensor noise.
    noise_sigma : float, default=2.0
        Sensor noise standard deviation, grey levels.
    appearances : tuple of (Appearance, Appearance) or None, default=None
        The two people's looks; None draws them from ``seed``.
    width, height : int, default=320, 240
        Frame size of the default camera, pixels (unused with ``camera``).

    Raises
    ------
    ValueError
        A negative ``noise_sigma``, or more than 254 body parts in all.
    """

    def __init__(
        self,
        scenario: Scenario,
        camera: Camera | None = None,
        seed: int = 0,
        noise_sigma: float = 2.0,
        appearances: tuple[Appearance, Appearance] | None = None,
        width: int = 320,
        height: int = 240,
    ) -> None:
        if not noise_sigma >= 0:
            raise ValueError(f"noise_sigma={noise_sigma!r}: must be >= 0 grey levels")
        self.scenario = scenario
        self.camera = camera if camera is not None else default_camera(width, height)
        self.seed = int(seed)
        self.noise_sigma = float(noise_sigma)
        rng = np.random.default_rng([self.seed, 4242])
        self.lighting = random_lighting(rng)
        self.bg, self.floor = make_background(self.camera, rng)
        if appearances is None:
            appearances = (random_appearance(rng), random_appearance(rng))
        self.appearances = appearances
        self.tables: tuple[PartTable, PartTable] = (part_table(appearances[0]), part_table(appearances[1]))
        Ma, Mb = len(self.tables[0].names), len(self.tables[1].names)
        self.n_parts = Ma + Mb
        if self.n_parts > 254:
            raise ValueError("too many parts for a uint8 id image")
        self.owner = np.zeros(self.n_parts + 1, np.uint8)
        self.owner[1 : Ma + 1] = 1
        self.owner[Ma + 1 :] = 2
        self.colours = np.concatenate([self.tables[0].colours, self.tables[1].colours])
        self.base = np.concatenate([self.tables[0].base, self.tables[1].base + Ma])
        self.casts = np.concatenate([self.tables[0].casts_shadow, self.tables[1].casts_shadow])
        self.is_torso = np.array([n == "torso" for t in self.tables for n in t.names])
        self.person = np.r_[np.zeros(Ma, int), np.ones(Mb, int)]
        self.joints = scenario.joints()
        self._cache: dict[int, tuple[np.ndarray, ...]] = {}
        L = np.array(self.lighting.direction)
        to_cam = self.camera.centre - np.array([0.0, 1.0, 0.0])
        lit = -L / np.linalg.norm(L) + to_cam / np.linalg.norm(to_cam)
        self._lit = lit / np.linalg.norm(lit)

    @property
    def n_frames(self) -> int:
        """Number of frames of the scenario."""
        return self.scenario.n_frames

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) of the frames, pixels."""
        return (self.camera.width, self.camera.height)

    # -- geometry, chunk by chunk ------------------------------------------------------------
    def _geometry(self, i: int) -> tuple[np.ndarray, ...]:
        c = i // _CHUNK
        if c not in self._cache:
            if len(self._cache) > 4:
                self._cache.clear()
            sl = slice(c * _CHUNK, min((c + 1) * _CHUNK, self.n_frames))
            sc = self.scenario
            clouds = np.concatenate(
                [
                    body_clouds(sc.poses_a[sl], sc.dims_a, self.appearances[0], self._lit),
                    body_clouds(sc.poses_b[sl], sc.dims_b, self.appearances[1], self._lit),
                ],
                axis=1,
            )
            uv = self.camera.project(clouds)  # (n, M, K, 2)
            depth = self.camera.depth(clouds).mean(axis=-1)  # (n, M)
            L = np.array(self.lighting.direction)
            caster = clouds[:, self.casts]
            on_ground = caster - (caster[..., 1:2] / L[1]) * L  # along the light to y = 0
            suv = self.camera.project(on_ground)
            fix = lambda a: np.round(np.nan_to_num(a, nan=-1e4) * (1 << _SHIFT)).astype(np.int32)  # noqa: E731
            ok = np.isfinite(uv).all(axis=(-1, -2))
            sok = np.isfinite(suv).all(axis=(-1, -2))
            self._cache[c] = (fix(uv), depth, ok, fix(np.clip(suv, -1e4, 1e4)), sok)
        uv, depth, ok, suv, sok = self._cache[c]
        k = i - c * _CHUNK
        return uv[k], depth[k], ok[k], suv[k], sok[k]

    def _draw(self, i: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Part-id image (H, W) uint8, shadow coverage (H, W) bool and per-part shade (M,)."""
        uv, depth, ok, suv, sok = self._geometry(i)
        H, W = self.camera.height, self.camera.width
        ids = np.zeros((H, W), np.uint8)
        key = depth[self.base] - 1e-4 * (np.arange(self.n_parts) != self.base)
        for m in np.argsort(-key, kind="stable"):
            if ok[m]:
                cv2.fillConvexPoly(ids, cv2.convexHull(uv[m]), int(m + 1), cv2.LINE_8, _SHIFT)
        sh = np.zeros((H, W), np.uint8)
        for m in np.flatnonzero(sok):
            cv2.fillConvexPoly(sh, cv2.convexHull(suv[m]), 1, cv2.LINE_8, _SHIFT)
        torso_depth = np.array([depth[self.is_torso & (self.person == p)][0] for p in (0, 1)])
        far = depth[self.base] > torso_depth[self.person] + 0.04
        shade = np.where(far, 0.8, 1.0).astype(np.float32)
        return ids, sh.astype(bool), shade

    # -- frames -------------------------------------------------------------------------------
    def time(self, i: int) -> float:
        """Scene time of frame ``i``, seconds.

        Parameters
        ----------
        i : int
            Frame index.

        Returns
        -------
        float
            ``i / fps``.
        """
        return i / self.scenario.fps

    def _check(self, i: int) -> int:
        i = int(i)
        if not 0 <= i < self.n_frames:
            raise IndexError(
                f"frame {i} out of range: the scenario has {self.n_frames} frames (0..{self.n_frames - 1})"
            )
        return i

    def background(self, i: int) -> np.ndarray:
        """The room at frame ``i``'s lighting, no people, no shadows, no noise.

        Parameters
        ----------
        i : int
            Frame index.

        Returns
        -------
        ndarray of shape (H, W, 3), dtype uint8
            The background, BGR.

        Raises
        ------
        IndexError
            ``i`` is outside the scenario's frames.
        """
        i = self._check(i)
        return np.clip(np.rint(self.bg * self.lighting.gain(self.time(i))), 0, 255).astype(np.uint8)

    def render(self, i: int, noise: bool = True) -> tuple[np.ndarray, FrameTruth]:
        """Frame ``i`` and its ground truth.

        Parameters
        ----------
        i : int
            Frame index.
        noise : bool, default=True
            Whether to add the sensor noise.

        Returns
        -------
        frame : ndarray of shape (H, W, 3), dtype uint8
            The image, BGR.
        truth : FrameTruth
            Its ground truth.

        Raises
        ------
        IndexError
            ``i`` is outside the scenario's frames.
        """
        i = self._check(i)
        ids, cover, shade = self._draw(i)
        g = self.lighting.gain(self.time(i))
        person = ids > 0
        shadow = cover & self.floor & ~person
        img = self.bg * np.float32(g)
        img[shadow] *= np.float32(self.lighting.shadow_factor)
        lut = np.zeros((self.n_parts + 1, 3), np.float32)
        lut[1:] = self.colours * shade[self.base, None] * np.float32(g)
        img[person] = lut[ids[person]]
        if noise and self.noise_sigma > 0:
            rng = np.random.default_rng([self.seed, 99, i])
            img += rng.standard_normal(img.shape, dtype=np.float32) * np.float32(self.noise_sigma)
        frame = np.clip(np.rint(img), 0, 255).astype(np.uint8)
        own = self.owner[ids]
        sc = self.scenario
        J = self.joints[i]
        truth = FrameTruth(
            joints3d=J,
            joints2d=self.camera.project(J),
            masks=np.stack([own == 1, own == 2]),
            shadow=shadow,
            signals=np.stack([sc.signals_a[i], sc.signals_b[i]]),
            phase=int(sc.phase[i]),
            label=sc.label,
            time_s=self.time(i),
        )
        return frame, truth
