"""How the simulated people look: clothing colours, shapes, and their 3D surface point clouds.

The simulator's people are deliberately *not* the tracker's 16 truncated cones: limbs are tubes
whose radius bulges along the limb (muscle profile ``r(s) = r0 + (r1 - r0) s + b sin(pi s)``),
the torso is a loft of ellipses (wider than deep, narrowing at the waist) in shirt colour over a
pelvis loft in trouser colour, the head an ellipsoid with a hair ellipsoid, the feet shoes. Every
part is a cloud of ``N_POINTS`` 3D surface points per frame; the renderer fills the convex hull
of each projected cloud (the exact perspective outline of a convex solid) in depth order.

Each limb and the torso also get a *highlight* part: a thinner copy of the part shifted towards
the light and the camera, drawn in a lighter colour (a cheap stand-in for diffuse shading).

Colours are BGR floats in [0, 255] (OpenCV order).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from counterpart.body.kinematics import frames
from counterpart.body.skeleton import ANCHOR_INDEX, BodyDims

N_POINTS: int = 40  # surface points per part (clouds are padded to this size)
_RING = 8  # points per ring around a tube or ellipsoid

SKIN_TONES: tuple[tuple[float, float, float], ...] = (
    (185, 205, 240),
    (150, 180, 225),
    (110, 150, 200),
    (80, 115, 165),
    (55, 80, 120),
    (170, 195, 235),
)
HAIR_COLOURS: tuple[tuple[float, float, float], ...] = (
    (20, 25, 30),
    (30, 50, 80),
    (60, 100, 150),
    (130, 170, 200),
    (150, 150, 150),
    (25, 30, 60),
)


@dataclass(frozen=True)
class Appearance:
    """One person's look.

    Parameters
    ----------
    skin, hair, shirt, trousers, shoes : tuple of float (B, G, R)
        BGR colours in [0, 255].
    hair_style : {"short", "long", "none"}, default="short"
        Hair style.
    long_sleeves : bool, default=True
        Shirt sleeves down to the wrists (else forearms show skin).
    girth : float, default=1.0
        Radius scale of limbs and torso width (about 0.9-1.3).
    """

    skin: tuple[float, float, float]
    hair: tuple[float, float, float]
    shirt: tuple[float, float, float]
    trousers: tuple[float, float, float]
    shoes: tuple[float, float, float]
    hair_style: str = "short"
    long_sleeves: bool = True
    girth: float = 1.0


def _vivid(rng: np.random.Generator) -> tuple[float, float, float]:
    hsv = np.array([[[rng.uniform(0, 180), rng.uniform(90, 230), rng.uniform(90, 230)]]], np.float32)
    import cv2

    bgr = cv2.cvtColor(hsv.astype(np.uint8), cv2.COLOR_HSV2BGR)[0, 0]
    return tuple(float(v) for v in bgr)


def random_appearance(rng: np.random.Generator) -> Appearance:
    """A seeded random look (draws a fixed number of values from ``rng``).

    Parameters
    ----------
    rng : numpy.random.Generator
        Source of the random values.

    Returns
    -------
    Appearance
        The look.
    """
    skin = SKIN_TONES[int(rng.integers(len(SKIN_TONES)))]
    hair = HAIR_COLOURS[int(rng.integers(len(HAIR_COLOURS)))]
    shirt = _vivid(rng)
    dark = rng.uniform(30, 110)
    trousers = tuple(float(np.clip(dark + v, 15, 200)) for v in rng.uniform(-25, 40, 3))
    shoes = tuple(float(v) for v in rng.uniform(20, 70, 3))
    style = ("short", "long", "none")[int(rng.choice(3, p=[0.55, 0.35, 0.10]))]
    return Appearance(
        skin=tuple(float(v) for v in skin),
        hair=tuple(float(v) for v in hair),
        shirt=shirt,
        trousers=trousers,
        shoes=shoes,
        hair_style=style,
        long_sleeves=bool(rng.random() < 0.6),
        girth=float(rng.uniform(0.9, 1.3)),
    )


# Tube parts: name, start anchor, end anchor, r_start, r_end, bulge (metres for a 1.75 m adult), colour key
_TUBES: tuple[tuple[str, str, str, float, float, float, str], ...] = (
    ("neck", "neck", "chin", 0.05, 0.047, 0.0, "skin"),
    ("l_upper_arm", "l_shoulder", "l_elbow", 0.052, 0.042, 0.012, "shirt"),
    ("l_forearm", "l_elbow", "l_wrist", 0.042, 0.03, 0.008, "sleeve"),
    ("l_hand", "l_wrist", "l_hand_end", 0.03, 0.022, 0.014, "skin"),
    ("r_upper_arm", "r_shoulder", "r_elbow", 0.052, 0.042, 0.012, "shirt"),
    ("r_forearm", "r_elbow", "r_wrist", 0.042, 0.03, 0.008, "sleeve"),
    ("r_hand", "r_wrist", "r_hand_end", 0.03, 0.022, 0.014, "skin"),
    ("l_thigh", "l_hip", "l_knee", 0.085, 0.058, 0.014, "trousers"),
    ("l_shin", "l_knee", "l_ankle", 0.056, 0.042, 0.012, "trousers"),
    ("l_foot", "l_ankle", "l_toe", 0.045, 0.036, 0.004, "shoes"),
    ("r_thigh", "r_hip", "r_knee", 0.085, 0.058, 0.014, "trousers"),
    ("r_shin", "r_knee", "r_ankle", 0.056, 0.042, 0.012, "trousers"),
    ("r_foot", "r_ankle", "r_toe", 0.045, 0.036, 0.004, "shoes"),
)
_LIT_TUBES = {"l_upper_arm", "l_forearm", "r_upper_arm", "r_forearm", "l_thigh", "l_shin", "r_thigh", "r_shin"}

# Torso loft in the torso frame from the neck: (drop below the neck as a fraction of the torso
# length, half-width x, half-depth z) in metres for a 1.75 m adult.
_SHIRT_LOFT = ((0.06, 0.21, 0.085), (0.3, 0.175, 0.115), (0.62, 0.145, 0.1), (0.95, 0.155, 0.105))
# Pelvis loft in the pelvis frame: (height above the pelvis root, half-width, half-depth).
_PELVIS_LOFT = ((0.08, 0.15, 0.1), (0.0, 0.165, 0.11), (-0.1, 0.15, 0.1))


@dataclass(frozen=True)
class PartTable:
    """The parts of one person, in drawing-tie order.

    Parameters
    ----------
    names : tuple of str
        M part names (highlights end in "+lit").
    colours : ndarray of shape (M, 3)
        float32 BGR colours in [0, 255].
    base : ndarray of shape (M,)
        Index of the part a highlight belongs to (its own index for base parts).
    casts_shadow : ndarray of shape (M,)
        bool (highlights cast none).
    """

    names: tuple[str, ...]
    colours: np.ndarray
    base: np.ndarray
    casts_shadow: np.ndarray


def _pad(cloud: np.ndarray) -> np.ndarray:
    """(N, n, 3) -> (N, N_POINTS, 3), repeating the last point."""
    n = cloud.shape[1]
    if n >= N_POINTS:
        return cloud[:, :N_POINTS]
    return np.concatenate([cloud, np.repeat(cloud[:, -1:], N_POINTS - n, axis=1)], axis=1)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def _tube(
    a0: np.ndarray,
    a1: np.ndarray,
    r0: float,
    r1: float,
    bulge: float,
    shift: np.ndarray | None = None,
    scale: float = 1.0,
) -> np.ndarray:
    """(N,3) ends -> (N, N_POINTS, 3) surface points: 4 rings of 8 plus the two tips."""
    ax = a1 - a0
    a = _unit(ax)
    helper = np.where(np.abs(a[:, :1]) < 0.9, np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
    u = _unit(np.cross(a, helper))
    v = np.cross(a, u)
    s = np.linspace(0.0, 1.0, 4)
    r = (r0 + (r1 - r0) * s + bulge * np.sin(np.pi * s)) * scale  # (4,)
    ang = np.linspace(0, 2 * np.pi, _RING, endpoint=False)
    circ = np.cos(ang)[:, None, None] * u + np.sin(ang)[:, None, None] * v  # (8, N, 3)
    centres = a0[:, None] + s[None, :, None] * ax[:, None]  # (N, 4, 3)
    if shift is not None:
        centres = centres + shift[:, None] * r[None, :, None] / scale
    pts = centres[:, :, None] + r[None, :, None, None] * np.moveaxis(circ, 0, 1)[:, None]
    tips = np.stack([a0 - a * r[0] * 0.7, a1 + a * r[-1] * 0.7], axis=1)
    if shift is not None:
        tips = tips + shift[:, None] * np.array([r[0], r[-1]])[None, :, None] / scale
    return _pad(np.concatenate([pts.reshape(len(a0), -1, 3), tips], axis=1))


def _ellipsoid(c: np.ndarray, R: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """(N,3) centres, (N,3,3) rotations, (3,) radii -> (N, N_POINTS, 3): 3 rings of 8 + poles."""
    ang = np.linspace(0, 2 * np.pi, _RING, endpoint=False)
    local = [(0.0, 1.0, 0.0), (0.0, -1.0, 0.0)]
    for lat in (-0.9, 0.0, 0.9):
        for t in ang:
            local.append((np.cos(lat) * np.cos(t), np.sin(lat), np.cos(lat) * np.sin(t)))
    L = np.array(local) * radii
    return _pad(c[:, None] + np.einsum("nij,kj->nki", R, L))


def _loft(origin: np.ndarray, R: np.ndarray, levels: list[tuple[float, float, float]]) -> np.ndarray:
    """Rings of ellipses (y, half-width, half-depth) in frame R at origin -> (N, N_POINTS, 3)."""
    ang = np.linspace(0, 2 * np.pi, 10, endpoint=False)
    local = np.array([(w * np.cos(t), y, d * np.sin(t)) for y, w, d in levels for t in ang])
    return _pad(origin[:, None] + np.einsum("nij,kj->nki", R, local))


def part_table(app: Appearance) -> PartTable:
    """The part names and colours of a person (see ``body_clouds``).

    Parameters
    ----------
    app : Appearance
        The person's look.

    Returns
    -------
    PartTable
        The parts, in the order of ``body_clouds``.
    """
    names, cols, base, shadow = [], [], [], []
    colour = {
        "skin": app.skin,
        "shirt": app.shirt,
        "trousers": app.trousers,
        "shoes": app.shoes,
        "sleeve": app.shirt if app.long_sleeves else app.skin,
        "hair": app.hair,
    }

    def add(name: str, col: tuple[float, ...], lit: bool) -> None:
        i = len(names)
        names.append(name)
        cols.append(col)
        base.append(i)
        shadow.append(True)
        if lit:
            names.append(name + "+lit")
            cols.append(tuple(min(255.0, 1.18 * v + 14) for v in col))
            base.append(i)
            shadow.append(False)

    add("pelvis", colour["trousers"], False)
    add("torso", colour["shirt"], True)
    for name, _, _, _, _, _, key in _TUBES:
        add(name, colour[key], name in _LIT_TUBES)
    add("head", colour["skin"], False)
    if app.hair_style != "none":
        add("hair", colour["hair"], False)
    return PartTable(tuple(names), np.array(cols, dtype=np.float32), np.array(base), np.array(shadow))


def body_clouds(P: np.ndarray, dims: BodyDims, app: Appearance, lit_dir: np.ndarray | None = None) -> np.ndarray:
    """Surface point clouds of every part of ``part_table(app)``.

    Parameters
    ----------
    P : ndarray of shape (N, 28)
        Poses.
    dims : BodyDims
        Body dimensions (sizes scale with ``dims.height / 1.75``).
    app : Appearance
        The person's look.
    lit_dir : ndarray of shape (N, 3) or (3,) or None, default=None
        Unit direction from the body towards where highlights go (light and camera); None:
        straight up.

    Returns
    -------
    ndarray of shape (N, M, N_POINTS, 3)
        Metres, world frame, parts in ``part_table(app).names`` order.
    """
    pts, R = frames(P, dims)
    N = pts.shape[0]
    k = dims.height / 1.75
    g = app.girth
    lit = np.broadcast_to(np.array([0, 1.0, 0]) if lit_dir is None else lit_dir, (N, 3))
    ix = ANCHOR_INDEX
    out = []
    # pelvis and torso
    pel_levels = [(y * k, w * k * (0.6 + 0.4 * g), d * k * g) for y, w, d in _PELVIS_LOFT]
    out.append(_loft(pts[:, ix["pelvis"]], R["pelvis"], pel_levels))
    tl = dims.torso_length
    sh_levels = []
    for i, (f, w, d) in enumerate(_SHIRT_LOFT):
        width = dims.shoulder_width / 2 + 0.03 * k if i == 0 else w * k * (0.6 + 0.4 * g)
        sh_levels.append((-f * tl, width, d * k * g))
    neck = pts[:, ix["neck"]]
    out.append(_loft(neck, R["torso"], sh_levels))
    # torso highlight: the loft shrunk and pushed towards the lit side
    lit_t = _unit(lit - np.einsum("ni,ni->n", lit, R["torso"][:, :, 1])[:, None] * R["torso"][:, :, 1])
    hl = [(y, 0.45 * w, 0.45 * d) for y, w, d in sh_levels[1:]]
    out.append(_loft(neck + 0.1 * k * lit_t, R["torso"], hl))
    for name, s, e, r0, r1, b, _ in _TUBES:
        a0, a1 = pts[:, ix[s]], pts[:, ix[e]]
        gg = g if name not in ("neck", "l_hand", "r_hand", "l_foot", "r_foot") else 1.0
        out.append(_tube(a0, a1, r0 * k * gg, r1 * k * gg, b * k * gg))
        if name in _LIT_TUBES:
            a = _unit(a1 - a0)
            side = _unit(lit - np.einsum("ni,ni->n", lit, a)[:, None] * a)
            out.append(_tube(a0, a1, r0 * k * gg, r1 * k * gg, b * k * gg, shift=0.5 * side, scale=0.42))
    hc = pts[:, ix["head"]]
    Rh = R["head"]
    out.append(
        _ellipsoid(
            hc + np.einsum("nij,j->ni", Rh, np.array([0, -0.005, 0.012]) * k), Rh, np.array([0.074, 0.112, 0.094]) * k
        )
    )
    if app.hair_style == "short":
        out.append(
            _ellipsoid(
                hc + np.einsum("nij,j->ni", Rh, np.array([0, 0.028, -0.02]) * k), Rh, np.array([0.08, 0.095, 0.092]) * k
            )
        )
    elif app.hair_style == "long":
        out.append(
            _ellipsoid(
                hc + np.einsum("nij,j->ni", Rh, np.array([0, -0.01, -0.035]) * k),
                Rh,
                np.array([0.085, 0.14, 0.085]) * k,
            )
        )
    return np.stack(out, axis=1)
