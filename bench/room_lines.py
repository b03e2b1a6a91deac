"""The straight lines of the simulator's room, from its geometry (for ``bench/self_calibration.py``):
what the camera estimate reaches with the scene's true line families, against what it reaches with
the families found in the image.

The room of ``counterpart.sim.render.make_background``: a floor of boards 0.16 m wide running along
z (their edges: the world's Z direction), their end joints and the wall's lines along x (the
foot of the wall at z = -2.5 m, the skirting board's top at 0.12 m, the rail's edges at 0.93 and
0.97 m, the poster's top and bottom) and the poster's sides (the vertical). Each line is projected,
cut to the image (people do not hide it), kept from 20 pixels long (the detector's least), and its
ends moved by half a pixel of noise.
"""

from __future__ import annotations

import numpy as np

from counterpart.body.camera import Camera
from counterpart.nodes.calibration.lines import LineFamilies
from counterpart.sim.render import _noise_texture, random_lighting

WALL_Z = -2.5
BOARD = 0.16
#: the world's X, Z and vertical directions, in the order of the families
DIRECTIONS = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])


def _room_draws(seed: int) -> tuple[np.ndarray, tuple[float, float, float]]:
    """The end-joint offsets of the boards and the poster (left x, width, height), metres, drawn as
    the renderer draws them for ``seed`` (the same calls on the same generator, in order).
    """
    rng = np.random.default_rng([int(seed), 4242])
    random_lighting(rng)
    _noise_texture(rng, 256, 1.0)
    _noise_texture(rng, 256, 6.0)
    rng.uniform(60, 90), rng.uniform(100, 130), rng.uniform(140, 175)  # wood colour
    rng.uniform(0.8, 1.15, 512)  # board tones
    offs = rng.uniform(0, 1.5, 512)
    rng.uniform(150, 215), rng.uniform(150, 215), rng.uniform(150, 215)  # paint
    px = float(rng.uniform(-2.0, 1.0))
    pw = float(rng.uniform(0.5, 0.9))
    ph = float(rng.uniform(0.4, 0.7))
    return offs, (px, pw, ph)


def _in_view(cam: Camera, a: np.ndarray, b: np.ndarray, n: int) -> np.ndarray | None:
    """The image of the world segment a-b cut to the frame (x1, y1, x2, y2), or None."""
    P = a + np.linspace(0.0, 1.0, n)[:, None] * (b - a)
    uv = cam.project(P)
    ok = np.isfinite(uv).all(1) & (uv >= 0).all(1) & (uv[:, 0] <= cam.width - 1) & (uv[:, 1] <= cam.height - 1)
    if not ok.any():
        return None
    i = np.flatnonzero(ok)
    return np.r_[uv[i[0]], uv[i[-1]]]


def room_lines(cam: Camera, seed: int, noise_px: float = 0.5, min_length: float = 20.0) -> LineFamilies:
    """The room's true line families as ``cam`` sees them.

    Parameters
    ----------
    cam : Camera
        The scene's true camera.
    seed : int
        The renderer's seed (the room's draws).
    noise_px : float, default=0.5
        Std of the noise on each segment end, pixels.
    min_length : float, default=20.0
        Shortest segment kept, pixels.

    Returns
    -------
    LineFamilies
        The families present (X, Z, vertical, in that order) with their true vanishing points.
    """
    offs, (px, pw, ph) = _room_draws(seed)
    v, u = np.mgrid[0 : cam.height : 4, 0 : cam.width : 4].astype(np.float64)
    G = cam.ground_point(u, v)
    floor = np.isfinite(G[..., 0]) & (G[..., 2] > WALL_Z)
    segs: list[np.ndarray | None] = []
    fam: list[int] = []

    def add(s: np.ndarray | None, f: int) -> None:
        if s is not None:
            segs.append(s)
            fam.append(f)

    if floor.any():
        gx, gz = G[..., 0][floor], G[..., 2][floor]
        near = float(gz.max()) + 0.5
        for p in range(int(np.floor(gx.min() / BOARD)) - 1, int(np.ceil(gx.max() / BOARD)) + 2):
            add(_in_view(cam, np.array([BOARD * p, 0.0, WALL_Z]), np.array([BOARD * p, 0.0, near]), 600), 1)
            for z in 1.5 * np.arange(-3, 30) - offs[p % 512]:
                if WALL_Z < z < near:
                    add(_in_view(cam, np.array([BOARD * p, 0.0, z]), np.array([BOARD * (p + 1), 0.0, z]), 40), 0)
    for y in (0.0, 0.12, 0.93, 0.97):
        add(_in_view(cam, np.array([-60.0, y, WALL_Z]), np.array([60.0, y, WALL_Z]), 4000), 0)
    for y in (1.2, 1.2 + ph):
        add(_in_view(cam, np.array([px, y, WALL_Z]), np.array([px + pw, y, WALL_Z]), 200), 0)
    for x in (px, px + pw):
        add(_in_view(cam, np.array([x, 1.2, WALL_Z]), np.array([x, 1.2 + ph, WALL_Z]), 200), 2)
    S = np.array(segs, np.float64).reshape(-1, 4)
    F = np.array(fam, int)
    keep = np.hypot(S[:, 2] - S[:, 0], S[:, 3] - S[:, 1]) >= min_length
    S, F = S[keep], F[keep]
    S = S + np.random.default_rng(seed).normal(0.0, noise_px, S.shape)
    vp = DIRECTIONS @ (cam.K @ cam.R).T
    vp /= np.linalg.norm(vp, axis=1, keepdims=True)
    present = np.unique(F)
    remap = np.full(3, -1)
    remap[present] = np.arange(len(present))
    return LineFamilies(S, remap[F], present == 2, vp[present], square=True)
