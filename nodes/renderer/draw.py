"""Drawing the partner and the overlays into BGR images: plain functions over numpy arrays.

The 3D partner is drawn as in Zheng et al. 2006 ("Virtual friend"): the 16 truncated cones of
``counterpart.body.skeleton`` are projected with the camera calibration and shaded. Each cone is cut into
``n_rim`` side facets (quads between its two rim circles) plus its two flat ends; facets facing
away from the camera are culled, the rest are shaded by Lambert's law

    I = colour * (ambient + (1 - ambient) * max(0, n . l))

(n the facet's outward unit normal, l the unit direction towards the light) and painted far to
near by the mean camera depth of their corners (painter's algorithm), so a nearer cone covers a
farther one. The joint-shape partner of Johnson, Galata & Hogg 1998 is a closed uniform cubic
B-spline in image pixels, filled and outlined.

Images are (H, W, 3) uint8 BGR and are drawn into in place; every function also returns the image.
Pixel coordinates are (x = column, y = row); world coordinates are metres (Y up).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from functools import lru_cache
from typing import Any

import cv2
import numpy as np

from counterpart.body.camera import Camera
from counterpart.body.ik import dims_from_joints, inverse_kinematics
from counterpart.body.kinematics import cone_endpoints, cross3, norm3
from counterpart.body.raster import cone_rims
from counterpart.body.skeleton import BONES, JOINT_INDEX, N_JOINTS
from counterpart.body.spline import evaluate_closed_bspline

_SHIFT = 4  # fixed-point bits: sub-pixel accurate polygon edges in OpenCV
_SCALE = float(1 << _SHIFT)

Colour = tuple[int, int, int]

#: BGR colour of each emotion at full strength; the partner's colour blends from "neutral" to it
EMOTION_COLOURS: dict[str, Colour] = {
    "neutral": (200, 170, 140),
    "happy": (40, 200, 250),
    "sad": (190, 90, 30),
    "angry": (40, 40, 220),
}
#: colours of people's overlays by id (cycled)
PERSON_COLOURS: tuple[Colour, ...] = ((0, 220, 0), (255, 120, 0), (0, 140, 255), (220, 0, 220), (0, 220, 220))
UNKNOWN_GREY: Colour = (128, 128, 128)
_FONT = cv2.FONT_HERSHEY_SIMPLEX


def person_colour(pid: int) -> Colour:
    """The overlay colour of person ``pid`` (cycled over :data:`PERSON_COLOURS`).

    Parameters
    ----------
    pid : int
        The person's id.

    Returns
    -------
    tuple of (int, int, int)
        BGR colour.
    """
    return PERSON_COLOURS[int(pid) % len(PERSON_COLOURS)]


def partner_colour(emotion: str = "neutral", strength: float = 0.0) -> Colour:
    """BGR colour of the partner: the neutral colour blended towards ``emotion``'s colour.

    Parameters
    ----------
    emotion : str
        A key of :data:`EMOTION_COLOURS`; unknown emotions count as neutral.
    strength : float
        Blend towards the emotion's colour, in [0, 1] (clipped; not finite: 0).

    Returns
    -------
    tuple of (int, int, int)
        BGR colour.
    """
    s = float(strength)
    return _blend(emotion, s if math.isfinite(s) else 0.0)


@lru_cache(maxsize=256)
def _blend(emotion: str, strength: float) -> Colour:
    """:func:`partner_colour` of a finite strength, kept: the renderer asks for the same colours on
    every frame, and numpy's calls on three numbers cost more than the arithmetic.
    """
    s = min(max(strength, 0.0), 1.0)
    base = EMOTION_COLOURS["neutral"]
    target = EMOTION_COLOURS.get(emotion, base)
    return tuple(int(round(b + s * (t - b))) for b, t in zip(base, target))  # type: ignore[return-value]


# ------------------------------------------------------------------------------ 3D partner (cones)
def partner_cones(joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The 16 truncated cones of a body given by its 14 joints.

    The joints are turned into a pose vector by ``counterpart.body.ik.inverse_kinematics`` and into body
    dimensions by ``counterpart.body.ik.dims_from_joints``; forward kinematics of both gives cones whose limb
    directions follow the joints, with head, hands and feet added.

    Parameters
    ----------
    joints : ndarray of shape (14, 3)
        Metres, world frame, ``counterpart.body.skeleton.JOINTS`` order.

    Returns
    -------
    ends : ndarray of shape (16, 2, 3)
        Start and end centre of each cone, metres, world frame.
    radii : ndarray of shape (16, 2)
        The matching radii, metres.

    Raises
    ------
    ValueError
        If the joints are not (14, 3) or not finite.
    """
    X = np.asarray(joints, np.float64)
    if X.shape != (N_JOINTS, 3):
        raise ValueError(f"partner joints have shape {X.shape}; expected ({N_JOINTS}, 3) metres")
    if not np.isfinite(X).all():
        raise ValueError("partner joints contain NaN or inf; expected finite positions in metres")
    ends, radii = _cones_of(X.tobytes())
    return ends.copy(), radii.copy()


@lru_cache(maxsize=4)
def _cones_of(joints: bytes) -> tuple[np.ndarray, np.ndarray]:
    """:func:`partner_cones` of (14, 3) float64 joints given as bytes: the renderer draws a held
    partner on every frame until the next one comes, and the inverse kinematics is its dearest part.
    """
    X = np.frombuffer(joints, np.float64).reshape(N_JOINTS, 3)
    P = inverse_kinematics(X)
    ends, radii = cone_endpoints(P, dims_from_joints(X))
    return ends[0], radii


@lru_cache(maxsize=8)
def _quad_index(n_rim: int) -> np.ndarray:
    """(n_rim, 4, 2) (rim, point) indices of each side facet: a0, a1, b1, b0."""
    k = np.arange(n_rim)
    k1 = (k + 1) % n_rim
    return np.stack(
        [
            np.stack([np.zeros_like(k), k], 1),
            np.stack([np.zeros_like(k), k1], 1),
            np.stack([np.ones_like(k), k1], 1),
            np.stack([np.ones_like(k), k], 1),
        ],
        1,
    )


def default_light(camera: Camera) -> np.ndarray:
    """The unit world direction towards a light above, slightly right of and behind the camera.

    Parameters
    ----------
    camera : Camera
        The camera.

    Returns
    -------
    ndarray of shape (3,)
        The direction, world frame.
    """
    d = camera.R.T @ np.array([0.3, -0.6, -1.0])
    return d / np.linalg.norm(d)


def cone_facets(
    ends: np.ndarray,
    radii: np.ndarray,
    camera: Camera,
    light: np.ndarray | None = None,
    n_rim: int = 16,
    ambient: float = 0.35,
) -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
    """Visible facets of the cones, shaded and sorted far to near.

    Parameters
    ----------
    ends : ndarray of shape (S, 2, 3)
        Start and end centre of each cone, metres, world frame.
    radii : ndarray of shape (S, 2)
        The matching radii, metres.
    camera : Camera
        The projection.
    light : ndarray of shape (3,) or None
        World direction towards the light (default :func:`default_light`).
    n_rim : int
        Facets around each cone.
    ambient : float
        Shade of a facet turned away from the light, in [0, 1].

    Returns
    -------
    polygons : list of ndarray of shape (k, 2)
        Float pixel polygons (4 corners for sides, n_rim for ends), far to near.
    shade : ndarray of shape (F,)
        Intensities in [ambient, 1].
    depth : ndarray of shape (F,)
        Mean camera depth, metres.

    Raises
    ------
    ValueError
        If ``ends`` is not (S, 2, 3) or ``radii`` not (S, 2).
    """
    quad_px, cap_px, keep, shade, depth = _facets(ends, radii, camera, light, n_rim, ambient)
    nq = len(quad_px)
    polys = [quad_px[i] if i < nq else cap_px[i - nq] for i in keep]
    return polys, shade, depth


def _facets(
    ends: np.ndarray, radii: np.ndarray, camera: Camera, light: np.ndarray | None, n_rim: int, ambient: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`cone_facets` as arrays: the quads' (S n_rim, 4, 2) and the caps' (2 S, n_rim, 2) pixel
    corners, the visible facets far to near (indices into the quads, then the caps), their shades
    and their depths.
    """
    ends = np.asarray(ends, np.float64)
    radii = np.asarray(radii, np.float64)
    if ends.ndim != 3 or ends.shape[1:] != (2, 3) or radii.shape != ends.shape[:2]:
        raise ValueError(f"cones: ends {ends.shape} must be (S, 2, 3) and radii {radii.shape} (S, 2)")
    l_dir = default_light(camera) if light is None else np.asarray(light, np.float64) / np.linalg.norm(light)
    rims = cone_rims(ends[None], radii, n_rim)[0]  # (S, 2, n, 3)
    eye = camera.centre
    # side facets
    qi = _quad_index(n_rim)
    quads = rims[:, qi[..., 0], qi[..., 1]]  # (S, n, 4, 3)
    centroid = quads.mean(axis=2)
    normal = cross3(quads[:, :, 1] - quads[:, :, 0], quads[:, :, 3] - quads[:, :, 0])
    radial = centroid - ends.mean(axis=1)[:, None]  # facet centroids sit at mid-axis
    normal *= np.where((normal * radial).sum(-1, keepdims=True) < 0, -1.0, 1.0)
    # flat ends: outward normals along -axis (start) and +axis (end)
    axis = ends[:, 1] - ends[:, 0]
    axis /= np.maximum(norm3(axis), 1e-12)
    cap_normal = np.stack([-axis, axis], 1)  # (S, 2, 3)
    cap_centroid = ends
    # one flat list of facets: S*n quads then S*2 caps
    normals = np.concatenate([normal.reshape(-1, 3), cap_normal.reshape(-1, 3)])
    centroids = np.concatenate([centroid.reshape(-1, 3), cap_centroid.reshape(-1, 3)])
    normals /= np.maximum(norm3(normals), 1e-12)
    facing = (normals * (eye - centroids)).sum(-1) > 0
    shade = ambient + (1.0 - ambient) * np.clip(normals @ l_dir, 0.0, None)
    # the quads' corners are rim points: each rim point is projected once
    rim_px, rim_z = camera.project(rims), camera.depth(rims)  # (S, 2, n, 2), (S, 2, n)
    quad_px = rim_px[:, qi[..., 0], qi[..., 1]].reshape(-1, 4, 2)
    cap_px = rim_px.reshape(-1, n_rim, 2)
    quad_z = rim_z[:, qi[..., 0], qi[..., 1]].reshape(-1, 4).mean(-1)
    cap_z = rim_z.reshape(-1, n_rim).mean(-1)
    depth = np.concatenate([quad_z, cap_z])
    finite = np.concatenate([np.isfinite(quad_px).all(axis=(1, 2)), np.isfinite(cap_px).all(axis=(1, 2))])
    keep = np.flatnonzero(facing & finite)
    keep = keep[np.argsort(-depth[keep], kind="stable")]
    return quad_px, cap_px, keep, shade[keep], depth[keep]


def _facet_corners(quad_px: np.ndarray, cap_px: np.ndarray, keep: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The corners of the facets ``keep`` (indices into the quads, then the caps), in that order,
    as one (K, 2) array, and each facet's first corner (F + 1 offsets, the last one K): what the
    list of :func:`cone_facets` concatenates, without a Python step per facet.
    """
    n_rim = cap_px.shape[1]
    corners = np.concatenate([quad_px.reshape(-1, 2), cap_px.reshape(-1, 2)])
    nq = len(quad_px)
    count = np.where(keep < nq, 4, n_rim)
    first = np.where(keep < nq, 4 * keep, 4 * nq + n_rim * (keep - nq))
    starts = np.concatenate([[0], np.cumsum(count)])
    at = np.repeat(first - starts[:-1], count) + np.arange(starts[-1])
    return corners[at], starts


def draw_cones(
    image: np.ndarray,
    ends: np.ndarray,
    radii: np.ndarray,
    camera: Camera,
    colour: Colour = EMOTION_COLOURS["neutral"],
    light: np.ndarray | None = None,
    n_rim: int = 16,
    ambient: float = 0.35,
) -> np.ndarray:
    """Paint shaded truncated cones into ``image``, far to near (see :func:`cone_facets`).

    Parameters
    ----------
    image : ndarray of shape (H, W, 3), dtype uint8
        BGR image, drawn into in place.
    ends : ndarray of shape (S, 2, 3)
        Start and end centre of each cone, metres, world frame.
    radii : ndarray of shape (S, 2)
        The matching radii, metres.
    camera : Camera
        The camera calibration of the image.
    colour : tuple of (int, int, int)
        BGR colour at full light.
    light : ndarray of shape (3,) or None
        World direction towards the light (default :func:`default_light`).
    n_rim : int
        Facets around each cone.
    ambient : float
        Shade of a facet turned away from the light, in [0, 1].

    Returns
    -------
    ndarray of shape (H, W, 3), dtype uint8
        ``image``.

    Raises
    ------
    ValueError
        If ``image`` is not a writable (H, W, 3) uint8 array.
    """
    _check_image(image)
    return _paint(image, _split(_cone_fill(ends, radii, camera, colour, light, n_rim, ambient)))


#: the facets to paint: fixed-point polygon corners (K, 2) int32, each facet's first corner (F + 1
#: offsets into them, the last one K) and colours (F BGR lists), far to near
_Fill = tuple[np.ndarray, list[int], list[list[int]]]


def _cone_fill(
    ends: np.ndarray,
    radii: np.ndarray,
    camera: Camera,
    colour: Colour,
    light: np.ndarray | None,
    n_rim: int,
    ambient: float,
) -> _Fill:
    """What :func:`draw_cones` paints (see :data:`_Fill`), from :func:`cone_facets`."""
    quad_px, cap_px, keep, shade, _ = _facets(ends, radii, camera, light, n_rim, ambient)
    if not len(keep):
        return np.empty((0, 2), np.int32), [0], []
    # fixed point and colours of all facets at once: per facet, these small numpy calls cost more
    # than OpenCV's fill
    corners, starts = _facet_corners(quad_px, cap_px, keep)
    fixed = np.round(corners * _SCALE).astype(np.int32)
    starts = starts.tolist()
    colours = np.clip(np.asarray(colour, np.float64) * shade[:, None], 0, 255).astype(np.int64).tolist()
    return fixed, starts, colours


#: the facets to paint one by one, far to near: each one's fixed-point corners (k, 2) int32 and BGR colour
_Facets = list[tuple[np.ndarray, list[int]]]


def _split(fill: _Fill) -> _Facets:
    """The facets of ``fill`` (:data:`_Fill`) one by one (views into its corners)."""
    fixed, starts, colours = fill
    return [(fixed[a:b], c) for a, b, c in zip(starts[:-1], starts[1:], colours)]


def _paint(image: np.ndarray, facets: _Facets) -> np.ndarray:
    """Paint ``facets`` (:data:`_Facets`) into ``image`` in their order; returns ``image``."""
    for corners, colour in facets:
        cv2.fillConvexPoly(image, corners, colour, lineType=cv2.LINE_AA, shift=_SHIFT)
    return image


#: the partners' facets last painted (:func:`draw_partner_3d`), by what they are made of, split
#: (a held partner's facets are not sliced out of its corners again on every frame)
_PARTNER_FILLS: dict[tuple, _Facets] = {}
#: how many of them are kept (the renderer draws a held partner on every frame until the next one)
_PARTNER_FILLS_KEPT = 4


def draw_partner_3d(
    image: np.ndarray, joints: np.ndarray, camera: Camera, colour: Colour = EMOTION_COLOURS["neutral"], **kw: Any
) -> np.ndarray:
    """Draw a partner given by its joints as shaded cones.

    The renderer draws a held partner on every frame until the next one comes: the facets of the
    last few partners drawn (the same joints, camera, colour and shading) are kept, so that such a
    frame only paints them.

    Parameters
    ----------
    image : ndarray of shape (H, W, 3), dtype uint8
        BGR image, drawn into in place.
    joints : ndarray of shape (14, 3)
        Metres, world frame (:func:`partner_cones`).
    camera : Camera
        The camera calibration of the image.
    colour : tuple of (int, int, int)
        BGR colour at full light.
    **kw : Any
        ``light``, ``n_rim``, ``ambient`` of :func:`draw_cones`.

    Returns
    -------
    ndarray of shape (H, W, 3), dtype uint8
        ``image``.

    Raises
    ------
    ValueError
        If the joints are not (14, 3) and finite, or the image is not a writable (H, W, 3) uint8 array.
    """
    _check_image(image)
    if set(kw) - {"light", "n_rim", "ambient"}:
        raise TypeError(
            f"draw_partner_3d: unexpected keyword arguments {sorted(set(kw) - {'light', 'n_rim', 'ambient'})}"
        )
    X = np.asarray(joints, np.float64)
    light = kw.get("light")
    key = (
        X.tobytes(),
        X.shape,
        camera.fx,
        camera.fy,
        camera.cx,
        camera.cy,
        camera.width,
        camera.height,
        np.asarray(camera.R, np.float64).tobytes(),
        np.asarray(camera.t, np.float64).tobytes(),
        tuple(np.asarray(colour, np.float64).tolist()),
        None if light is None else np.asarray(light, np.float64).tobytes(),
        kw.get("n_rim", 16),
        kw.get("ambient", 0.35),
    )
    fill = _PARTNER_FILLS.get(key)
    if fill is None:
        # a held partner (drawn on every frame until the next one comes) is projected and shaded once
        ends, radii = partner_cones(X)
        fill = _split(_cone_fill(ends, radii, camera, colour, light, kw.get("n_rim", 16), kw.get("ambient", 0.35)))
        if len(_PARTNER_FILLS) >= _PARTNER_FILLS_KEPT:
            del _PARTNER_FILLS[next(iter(_PARTNER_FILLS))]
        _PARTNER_FILLS[key] = fill
    return _paint(image, fill)


# ------------------------------------------------------------------------- 2D silhouettes (splines)
#: points on a closed uniform cubic B-spline (the silhouettes' curve, shared through body/)
closed_bspline = evaluate_closed_bspline


def draw_silhouette(
    image: np.ndarray,
    ctrl: np.ndarray,
    colour: Colour = EMOTION_COLOURS["neutral"],
    outline: Colour | None = (40, 40, 40),
    thickness: int = 1,
) -> np.ndarray:
    """Fill the closed B-spline of ``ctrl`` with ``colour`` and outline it.

    Parameters
    ----------
    image : ndarray of shape (H, W, 3), dtype uint8
        BGR image, drawn into in place.
    ctrl : ndarray of shape (n, 2)
        Control points, pixels.
    colour : tuple of (int, int, int)
        BGR fill colour.
    outline : tuple of (int, int, int) or None
        BGR outline colour (None: no outline).
    thickness : int
        Outline thickness, pixels (0: no outline).

    Returns
    -------
    ndarray of shape (H, W, 3), dtype uint8
        ``image``.

    Raises
    ------
    ValueError
        If the control points are not finite, or the image is not a writable (H, W, 3) uint8 array.
    """
    _check_image(image)
    pts = closed_bspline(ctrl)
    if not np.isfinite(pts).all():
        raise ValueError("silhouette control points contain NaN or inf; expected finite pixels")
    fixed = [np.round(pts * _SCALE).astype(np.int32)]
    # LINE_8 fills exactly the pixels whose centres are inside; OpenCV's anti-aliased fill grows the
    # shape by about half a pixel, and the outline smooths the edge anyway
    cv2.fillPoly(image, fixed, colour, lineType=cv2.LINE_8, shift=_SHIFT)
    if outline is not None and thickness > 0:
        cv2.polylines(image, fixed, True, outline, thickness, cv2.LINE_AA, _SHIFT)
    return image


# --------------------------------------------------------------------------------------- overlays
#: lines of the skeleton overlay: the bones plus the hip line and the pelvis-to-neck spine
_EXTRA_LINES = ((JOINT_INDEX["l_hip"], JOINT_INDEX["r_hip"]),)
SKELETON_LINES: tuple[tuple[int, int], ...] = tuple(BONES) + _EXTRA_LINES


def draw_skeleton(
    image: np.ndarray,
    joints: np.ndarray,
    camera: Camera,
    colour: Colour = (0, 220, 0),
    thickness: int = 2,
    radius: int = 3,
) -> np.ndarray:
    """Tracked skeleton: joints projected, bones as lines, the spine from the neck to the mid-hip
    point, joints as dots. Joints behind the camera are left out.

    Parameters
    ----------
    image : ndarray of shape (H, W, 3), dtype uint8
        BGR image, drawn into in place.
    joints : ndarray of shape (14, 3)
        Metres, world frame.
    camera : Camera
        The camera calibration of the image.
    colour : tuple of (int, int, int)
        BGR colour.
    thickness : int
        Line thickness, pixels.
    radius : int
        Joint dot radius, pixels.

    Returns
    -------
    ndarray of shape (H, W, 3), dtype uint8
        ``image``.

    Raises
    ------
    ValueError
        If the joints are not (14, 3), or the image is not a writable (H, W, 3) uint8 array.
    """
    _check_image(image)
    X = np.asarray(joints, np.float64)
    if X.shape != (N_JOINTS, 3):
        raise ValueError(f"skeleton joints have shape {X.shape}; expected ({N_JOINTS}, 3) metres")
    pelvis = 0.5 * (X[JOINT_INDEX["l_hip"]] + X[JOINT_INDEX["r_hip"]])
    uv = camera.project(np.vstack([X, pelvis]))
    ok = np.isfinite(uv).all(-1)
    fixed = np.round(np.nan_to_num(uv) * _SCALE).astype(np.int32)
    lines = SKELETON_LINES + ((JOINT_INDEX["neck"], N_JOINTS),)
    pts, ok = fixed.tolist(), ok.tolist()  # OpenCV takes Python ints at less cost than numpy's
    for a, b in lines:
        if ok[a] and ok[b]:
            cv2.line(image, pts[a], pts[b], colour, thickness, cv2.LINE_AA, _SHIFT)
    for j in range(N_JOINTS):
        if ok[j]:
            cv2.circle(image, pts[j], radius << _SHIFT, colour, -1, cv2.LINE_AA, _SHIFT)
    return image


def draw_spline_outline(
    image: np.ndarray,
    ctrl: np.ndarray,
    colour: Colour = (0, 220, 0),
    thickness: int = 1,
    ref_point: np.ndarray | None = None,
    label: str = "",
    show_ctrl: bool = True,
) -> np.ndarray:
    """A person's B-spline boundary as a closed curve, its control points as dots, its reference
    point (top of the head) as a ring and an optional label above it.

    Parameters
    ----------
    image : ndarray of shape (H, W, 3), dtype uint8
        BGR image, drawn into in place.
    ctrl : ndarray of shape (n, 2)
        Control points, pixels.
    colour : tuple of (int, int, int)
        BGR colour.
    thickness : int
        Curve thickness, pixels.
    ref_point : ndarray of shape (2,) or None
        The reference point, pixels (None or not finite: not drawn).
    label : str
        Text above the reference point ('' : none).
    show_ctrl : bool
        Draw the control points.

    Returns
    -------
    ndarray of shape (H, W, 3), dtype uint8
        ``image``.

    Raises
    ------
    ValueError
        If ``image`` is not a writable (H, W, 3) uint8 array.
    """
    _check_image(image)
    pts = closed_bspline(ctrl)
    fixed = np.round(pts * _SCALE).astype(np.int32)
    cv2.polylines(image, [fixed], True, colour, thickness, cv2.LINE_AA, _SHIFT)
    if show_ctrl:
        for p in np.round(np.asarray(ctrl, np.float64) * _SCALE).astype(np.int32).tolist():
            cv2.circle(image, p, 1 << _SHIFT, colour, -1, cv2.LINE_AA, _SHIFT)
    ref = None if ref_point is None or np.size(ref_point) != 2 else np.asarray(ref_point, np.float64).reshape(2)
    if ref is not None and np.isfinite(ref).all():
        cv2.circle(image, tuple(np.round(ref * _SCALE).astype(np.int32)), 4 << _SHIFT, colour, 1, cv2.LINE_AA, _SHIFT)
        if label:
            put_text(image, label, (int(ref[0]) + 6, int(ref[1]) - 4), colour)
    return image


def put_text(
    image: np.ndarray,
    text: str,
    org: tuple[int, int],
    colour: Colour = (255, 255, 255),
    scale: float = 0.4,
    thickness: int = 1,
    background: Colour | None = None,
) -> tuple[int, int]:
    """Text with its baseline-left corner at ``org``, optionally on a filled box.

    Parameters
    ----------
    image : ndarray of shape (H, W, 3), dtype uint8
        BGR image, drawn into in place.
    text : str
        The text.
    org : tuple of (int, int)
        Baseline-left corner, pixels.
    colour : tuple of (int, int, int)
        BGR text colour.
    scale : float
        Font scale.
    thickness : int
        Stroke thickness, pixels.
    background : tuple of (int, int, int) or None
        BGR colour of the box behind the text (None: no box).

    Returns
    -------
    tuple of (int, int)
        The text's (width, height) in pixels.
    """
    (w, h), base = cv2.getTextSize(text, _FONT, scale, thickness)
    x, y = org
    if background is not None:
        cv2.rectangle(image, (x - 2, y - h - 2), (x + w + 2, y + base), background, -1)
    cv2.putText(image, text, (x, y), _FONT, scale, colour, thickness, cv2.LINE_AA)
    return w, h + base


def _badge_boxes(
    shape: tuple[int, ...], anchor: tuple[float, float], names: Sequence[str], scale: float
) -> list[tuple[int, int, int, int, str, int]]:
    """Where the badges of ``names`` go: (x, y, width, height, text, baseline) each, in a row from
    ``anchor`` that wraps at the image's right edge.
    """
    h_img, w_img = shape[:2]
    x, y = int(anchor[0]), int(anchor[1])
    boxes = []
    for name in names:
        text = _short(name)
        (tw, th), base = cv2.getTextSize(text, _FONT, scale, 1)
        bw, bh = tw + 6, th + base + 4
        if x + bw > w_img:  # wrap to the next row instead of running off the image
            x, y = int(anchor[0]), y + bh + 2
        if y > h_img:
            break
        boxes.append((x, y, bw, bh, text, base))
        x += bw + 2
    return boxes


def signal_badges_rect(
    image: np.ndarray, anchor: tuple[float, float], names: Sequence[str], scale: float | None = None
) -> tuple[int, int, int, int]:
    """The box that ``draw_signal_badges`` with the same arguments covers.

    Parameters
    ----------
    image : ndarray of shape (H, W, 3), dtype uint8
        The image the badges go into (its size).
    anchor : tuple of (float, float)
        Top-left of the first badge, pixels.
    names : sequence of str
        The signals' names.
    scale : float or None
        Font scale (None: :func:`text_scale` of 0.35).

    Returns
    -------
    tuple of (int, int, int, int)
        (x0, y0, x1, y1), pixels.
    """
    scale = text_scale(image, 0.35) if scale is None else scale
    boxes = _badge_boxes(image.shape, anchor, names, scale)
    if not boxes:
        return int(anchor[0]), int(anchor[1]), int(anchor[0]), int(anchor[1])
    return (
        min(b[0] for b in boxes),
        min(b[1] for b in boxes),
        max(b[0] + b[2] for b in boxes),
        max(b[1] + b[3] for b in boxes),
    )


def draw_signal_badges(
    image: np.ndarray,
    anchor: tuple[float, float],
    names: Sequence[str],
    labels: np.ndarray,
    scores: np.ndarray | None = None,
    scale: float | None = None,
) -> np.ndarray:
    """Social-signal badges of one person: a row of small labelled boxes starting at ``anchor``
    (x, y pixels, top-left). Label 1 (present): a bright box; 0 (absent): a dark box; -1
    (unknown): grey.

    Parameters
    ----------
    image : ndarray of shape (H, W, 3), dtype uint8
        BGR image, drawn into in place.
    anchor : tuple of (float, float)
        Top-left of the first badge, (x, y) pixels.
    names : sequence of str of length K
        The signals' names.
    labels : ndarray of shape (K,)
        1 (present), 0 (absent) or -1 (unknown).
    scores : ndarray of shape (K,) or None
        Scores in [0, 1]; when given, a white bar along the bottom of each known badge.
    scale : float or None
        Font scale (None: :func:`text_scale` of 0.35).

    Returns
    -------
    ndarray of shape (H, W, 3), dtype uint8
        ``image``.

    Raises
    ------
    ValueError
        If names and labels differ in number, or the image is not a writable (H, W, 3) uint8 array.
    """
    _check_image(image)
    scale = text_scale(image, 0.35) if scale is None else scale
    labels = np.asarray(labels).reshape(-1)
    if len(labels) != len(names):
        raise ValueError(f"signal badges: {len(names)} names but {len(labels)} labels; they must match")
    for i, (x, y, bw, bh, text, base) in enumerate(_badge_boxes(image.shape, anchor, names, scale)):
        lab = int(labels[i])
        if lab < 0:
            fill, fg = UNKNOWN_GREY, (220, 220, 220)
        elif lab > 0:
            fill, fg = (0, 200, 255), (0, 0, 0)
        else:
            fill, fg = (60, 60, 60), (200, 200, 200)
        cv2.rectangle(image, (x, y), (x + bw, y + bh), fill, -1)
        cv2.rectangle(image, (x, y), (x + bw, y + bh), (255, 255, 255) if lab > 0 else (0, 0, 0), 1)
        cv2.putText(image, text, (x + 3, y + bh - base - 2), _FONT, scale, fg, 1, cv2.LINE_AA)
        if scores is not None and lab >= 0 and i < np.size(scores) and np.isfinite(scores[i]):
            # the detector's score as a bar along the badge's bottom edge
            sw = int(round(float(np.clip(scores[i], 0.0, 1.0)) * (bw - 2)))
            if sw > 0:
                cv2.line(image, (x + 1, y + bh - 1), (x + sw, y + bh - 1), (255, 255, 255), 1)
    return image


def place_apart(rects: Sequence[tuple[int, int, int, int]], height: int, gap: int = 2) -> list[int]:
    """Vertical shifts (pixels) that keep boxes (x0, y0, x1, y1) inside ``height`` rows and from
    overlapping, placed in order: each box moves down below the boxes already placed that it would
    overlap, or, where that runs past ``height``, up above them (not past the top). Where no
    such place is free the last one tried is kept: the frame is too crowded.

    Parameters
    ----------
    rects : sequence of tuple of (int, int, int, int)
        Boxes (x0, y0, x1, y1), pixels, in placing order.
    height : int
        Image rows.
    gap : int
        Pixels kept between boxes.

    Returns
    -------
    list of int
        Vertical shift of each box, pixels (positive: down).
    """
    placed: list[tuple[int, int, int, int]] = []
    shifts = []
    for x0, y0, x1, y1 in rects:
        h = y1 - y0
        dy = min(0, height - y1)
        for _ in range(len(placed) + 1):
            hit = [r for r in placed if r[0] < x1 and x0 < r[2] and r[1] < y1 + dy and y0 + dy < r[3]]
            if not hit:
                break
            down = max(r[3] for r in hit) + gap - y0
            dy = down if y0 + down + h <= height else max(min(r[1] for r in hit) - gap - h - y0, -y0)
        shifts.append(dy)
        placed.append((x0, y0 + dy, x1, y1 + dy))
    return shifts


_SHORT = {"gaze_at_other": "gaze", "talking": "talk", "laughing": "laugh", "activity": "act"}


def _short(name: str) -> str:
    return _SHORT.get(name, name[:6])


def stats_lines(stats: Mapping[str, Any]) -> list[str]:
    """One text line per node from its latest ``messages.NodeStats``: the rate (Hz) of its first
    output (else of its first input), input drops summed, the largest input latency (ms) and the
    mean handler time (ms).

    Parameters
    ----------
    stats : mapping of str to NodeStats
        Node name -> its latest statistics.

    Returns
    -------
    list of str
        One line per node, by name.
    """
    lines = []
    for node in sorted(stats):
        s = stats[node]
        ports = list(s.outputs) or list(s.inputs)
        rate = ports[0].rate_hz if ports else 0.0
        drops = sum(t.drops for t in s.inputs)
        lat = max((t.latency_ms for t in s.inputs), default=0.0)
        lines.append(f"{node[:12]:<12}{rate:5.1f}Hz drop {drops:<3d} lat{lat:5.1f}ms proc{s.proc_ms_mean:5.1f}ms")
    return lines


def text_scale(image: np.ndarray, base: float) -> float:
    """Font scale ``base`` for a 320-pixel-wide image, grown with wider images (up to 3x).

    Parameters
    ----------
    image : ndarray of shape (H, W, ...)
        The image (its width).
    base : float
        Font scale at 320 pixels wide.

    Returns
    -------
    float
        The font scale.
    """
    return base * min(max(image.shape[1] / 320.0, 1.0), 3.0)


def draw_stats(
    image: np.ndarray, stats: Mapping[str, Any], origin: tuple[int, int] = (4, 4), scale: float | None = None
) -> np.ndarray:
    """Per-node statistics (:func:`stats_lines`) as text on a dark box.

    Parameters
    ----------
    image : ndarray of shape (H, W, 3), dtype uint8
        BGR image, drawn into in place.
    stats : mapping of str to NodeStats
        Node name -> its latest statistics.
    origin : tuple of (int, int)
        Top-left of the box, pixels.
    scale : float or None
        Font scale (None: :func:`text_scale` of 0.3).

    Returns
    -------
    ndarray of shape (H, W, 3), dtype uint8
        ``image``.

    Raises
    ------
    ValueError
        If ``image`` is not a writable (H, W, 3) uint8 array.
    """
    _check_image(image)
    scale = text_scale(image, 0.3) if scale is None else scale
    lines = stats_lines(stats)
    if not lines:
        return image
    sizes = [cv2.getTextSize(t, _FONT, scale, 1) for t in lines]
    lh = max(h + b for (_, h), b in sizes) + 2
    w = max(w for (w, _), _ in sizes) + 6
    x, y = origin
    roi = image[y : y + lh * len(lines) + 4, x : x + w]
    roi[...] = (roi.astype(np.uint16) * 2 // 5).astype(np.uint8)  # darken: text stays readable on any frame
    for i, t in enumerate(lines):
        cv2.putText(image, t, (x + 3, y + (i + 1) * lh), _FONT, scale, (255, 255, 255), 1, cv2.LINE_AA)
    return image


def draw_controls(image: np.ndarray, controls: Mapping[str, Any], scale: float | None = None) -> np.ndarray:
    """The run-time controls in force along the bottom edge: model, speaker, interest, emotion and
    a bar of the emotion strength (its filled length is ``strength`` of the bar, in [0, 1]).

    Parameters
    ----------
    image : ndarray of shape (H, W, 3), dtype uint8
        BGR image, drawn into in place.
    controls : mapping of str to Any
        ``model``, ``speaker``, ``interest``, ``emotion`` and ``strength`` (missing: '-' or 0).
    scale : float or None
        Font scale (None: :func:`text_scale` of 0.35).

    Returns
    -------
    ndarray of shape (H, W, 3), dtype uint8
        ``image``.

    Raises
    ------
    ValueError
        If ``image`` is not a writable (H, W, 3) uint8 array.
    """
    _check_image(image)
    scale = text_scale(image, 0.35) if scale is None else scale
    h, w = image.shape[:2]
    text = (
        f"{controls.get('model') or '-'}  speaker {controls.get('speaker') or '-'}  "
        f"interest {controls.get('interest') or '-'}  {controls.get('emotion') or '-'}"
    )
    (tw, th), base = cv2.getTextSize(text, _FONT, scale, 1)
    bar_h = 6
    top = h - th - base - bar_h - 8
    roi = image[max(top, 0) :, :]
    roi[...] = (roi.astype(np.uint16) * 2 // 5).astype(np.uint8)
    cv2.putText(image, text, (4, h - bar_h - 6 - base), _FONT, scale, (255, 255, 255), 1, cv2.LINE_AA)
    s = controls.get("strength")
    s = float(np.clip(s, 0.0, 1.0)) if isinstance(s, (int, float)) and np.isfinite(s) else 0.0
    x0, x1, y0 = 4, w - 5, h - bar_h - 3
    cv2.rectangle(image, (x0, y0), (x1, y0 + bar_h), (90, 90, 90), -1)
    fill = partner_colour(str(controls.get("emotion") or "neutral"), 1.0)
    xs = x0 + int(round(s * (x1 - x0)))
    if xs > x0:
        cv2.rectangle(image, (x0, y0), (xs, y0 + bar_h), fill, -1)
    return image


def contact_sheet(
    frames: Iterable[np.ndarray], cols: int = 4, pad: int = 2, background: Colour = (0, 0, 0)
) -> np.ndarray:
    """Tile images row by row into one BGR image; every tile is resized to the first one's size.

    Parameters
    ----------
    frames : iterable of ndarray
        Images of shape (H, W, 3) or (H, W), dtype uint8.
    cols : int
        Tiles per row (>= 1).
    pad : int
        Pixels between tiles.
    background : tuple of (int, int, int)
        BGR colour of the padding.

    Returns
    -------
    ndarray of shape (rows H + (rows - 1) pad, cols W + (cols - 1) pad, 3), dtype uint8
        The sheet (fewer columns when fewer frames than ``cols`` are given).

    Raises
    ------
    ValueError
        Without frames, for ``cols`` < 1, or for a frame that is not uint8.
    """
    tiles = [np.asarray(f) for f in frames]
    if not tiles:
        raise ValueError("contact_sheet: no frames given; pass at least one image")
    if cols < 1:
        raise ValueError(f"contact_sheet: cols={cols}; must be >= 1")
    h, w = tiles[0].shape[:2]
    rows = -(-len(tiles) // cols)
    ncols = min(cols, len(tiles))
    sheet = np.empty((rows * h + (rows - 1) * pad, ncols * w + (ncols - 1) * pad, 3), np.uint8)
    sheet[...] = background
    for i, t in enumerate(tiles):
        if t.dtype != np.uint8:
            raise ValueError(f"contact_sheet: frame {i} has dtype {t.dtype}; expected uint8")
        if t.ndim == 2:
            t = cv2.cvtColor(t, cv2.COLOR_GRAY2BGR)
        if t.shape[:2] != (h, w):
            t = cv2.resize(t, (w, h), interpolation=cv2.INTER_AREA)
        r, c = divmod(i, cols)
        sheet[r * (h + pad) : r * (h + pad) + h, c * (w + pad) : c * (w + pad) + w] = t
    return sheet


def _check_image(image: np.ndarray) -> None:
    if not (isinstance(image, np.ndarray) and image.dtype == np.uint8 and image.ndim == 3 and image.shape[2] == 3):
        got = f"{image.dtype} {image.shape}" if isinstance(image, np.ndarray) else type(image).__name__
        raise ValueError(f"expected an (H, W, 3) uint8 BGR image to draw into, got {got}")
    if not image.flags.writeable:
        raise ValueError("the image to draw into is read-only; pass a copy (image.copy())")


__all__ = [
    "EMOTION_COLOURS",
    "PERSON_COLOURS",
    "UNKNOWN_GREY",
    "SKELETON_LINES",
    "person_colour",
    "partner_colour",
    "partner_cones",
    "default_light",
    "cone_facets",
    "draw_cones",
    "draw_partner_3d",
    "closed_bspline",
    "text_scale",
    "draw_silhouette",
    "draw_skeleton",
    "draw_spline_outline",
    "put_text",
    "draw_signal_badges",
    "signal_badges_rect",
    "place_apart",
    "stats_lines",
    "draw_stats",
    "draw_controls",
    "contact_sheet",
]
