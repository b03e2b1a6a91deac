"""Projecting the 16 truncated cones into an image: sample points, silhouettes, edge maps.

Two kinds of helpers:

* Point samplers (``cone_outline_points``, ``cone_interior_points``) are fully vectorised over
  N poses; the annealed particle filter (Deutscher, Blake & Reid 2000, eqs. 4-5: edge and
  foreground sums over points sampled on the projected model) calls them for every particle of
  every layer. They use the standard approximation of a projected truncated cone as a
  trapezoid: axis from ``p1`` to ``p2`` (projected end centres), half-widths
  ``rho_i = f * r_i / z_i`` perpendicular to the image axis.
* Rasterisers (``rasterise_silhouettes``, ``render_edge_maps``) draw a few poses with OpenCV.
  They draw each cone exactly as the convex hull of its two projected rim circles, which is
  the true outline of a truncated cone under perspective.

Points behind the camera come out as NaN (from ``Camera.project``); callers treat NaN as
"outside the image".
"""

from __future__ import annotations

import cv2
import numpy as np

from counterpart.body.camera import Camera
from counterpart.body.kinematics import cone_endpoints, cross3, norm3
from counterpart.body.skeleton import N_SEGMENTS, BodyDims

_SHIFT = 4  # fixed-point bits for sub-pixel accurate OpenCV drawing


def project_cones(ends: np.ndarray, radii: np.ndarray, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """Project cones to image trapezoids.

    Parameters
    ----------
    ends : ndarray of shape (N, S, 2, 3)
        Cone end centres, metres (from ``cone_endpoints``).
    radii : ndarray of shape (S, 2) or (N, S, 2)
        End radii, metres.
    camera : Camera
        The camera.

    Returns
    -------
    centres : ndarray of shape (N, S, 2, 2)
        Pixel positions of the two end centres.
    half_widths : ndarray of shape (N, S, 2)
        Projected radii in pixels (NaN behind the camera).
    """
    centres = camera.project(ends)
    z = camera.depth(ends)
    f = 0.5 * (camera.fx + camera.fy)
    with np.errstate(divide="ignore", invalid="ignore"):
        rho = np.where(z > 1e-3, f * np.asarray(radii) / z, np.nan)
    return centres, rho


def _image_normals(centres: np.ndarray) -> np.ndarray:
    """(N, S, 2, 2) -> (N, S, 2) unit image normals to each cone axis ((1, 0) if degenerate)."""
    a = centres[..., 1, :] - centres[..., 0, :]
    n = np.stack([-a[..., 1], a[..., 0]], axis=-1)
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    ok = length > 1e-9
    return np.where(ok, n / np.where(ok, length, 1.0), np.array([1.0, 0.0]))


def cone_outline_points_from_cones(
    ends: np.ndarray, radii: np.ndarray, camera: Camera, per_side: int = 4
) -> np.ndarray:
    """Points along the two long sides of every projected cone.

    Parameters
    ----------
    ends : ndarray of shape (N, S, 2, 3)
        Cone end centres, metres (from ``cone_endpoints``).
    radii : ndarray of shape (S, 2) or (N, S, 2)
        End radii, metres.
    camera : Camera
        The camera.
    per_side : int, default=4
        Points on each side of each cone.

    Returns
    -------
    ndarray of shape (N, S * 2 * per_side, 2)
        Pixels, ordered cone-major, then side (+normal, -normal), then position along the axis at
        fractions (k + 0.5) / per_side.
    """
    centres, rho = project_cones(ends, radii, camera)
    n = _image_normals(centres)  # (N,S,2)
    s = (np.arange(per_side) + 0.5) / per_side  # (K,)
    p = centres[..., 0, None, :] + s[:, None] * (centres[..., 1, None, :] - centres[..., 0, None, :])
    r = rho[..., 0, None] + s * (rho[..., 1, None] - rho[..., 0, None])  # (N,S,K)
    side = np.array([1.0, -1.0])[:, None, None]  # (2,1,1)
    pts = p[:, :, None] + side * r[:, :, None, :, None] * n[:, :, None, None, :]
    return pts.reshape(pts.shape[0], -1, 2)


def cone_outline_points(P: np.ndarray, dims: BodyDims, camera: Camera, per_side: int = 4) -> np.ndarray:
    """Pixel samples on the cone outlines of N poses. Vectorised over N.

    Parameters
    ----------
    P : ndarray of shape (N, DOF)
        Poses.
    dims : BodyDims
        Body dimensions.
    camera : Camera
        The camera.
    per_side : int, default=4
        Points on each side of each cone.

    Returns
    -------
    ndarray of shape (N, 16 * 2 * per_side, 2)
        Pixels; see ``cone_outline_points_from_cones`` for the ordering.
    """
    ends, radii = cone_endpoints(P, dims)
    return cone_outline_points_from_cones(ends, radii, camera, per_side)


def cone_interior_points_from_cones(
    ends: np.ndarray, radii: np.ndarray, camera: Camera, n_along: int = 4, n_across: int = 3
) -> np.ndarray:
    """Grid of points inside every projected cone.

    Parameters
    ----------
    ends : ndarray of shape (N, S, 2, 3)
        Cone end centres, metres (from ``cone_endpoints``).
    radii : ndarray of shape (S, 2) or (N, S, 2)
        End radii, metres.
    camera : Camera
        The camera.
    n_along : int, default=4
        Grid points along each cone's axis.
    n_across : int, default=3
        Grid points across each cone.

    Returns
    -------
    ndarray of shape (N, S * n_along * n_across, 2)
        Pixels, ordered cone-major, then along the axis at fractions (k + 0.5) / n_along, then
        across at (2 j + 1) / n_across - 1 of the half-width.
    """
    centres, rho = project_cones(ends, radii, camera)
    n = _image_normals(centres)
    s = (np.arange(n_along) + 0.5) / n_along
    t = (2 * np.arange(n_across) + 1) / n_across - 1.0
    p = centres[..., 0, None, :] + s[:, None] * (centres[..., 1, None, :] - centres[..., 0, None, :])
    r = rho[..., 0, None] + s * (rho[..., 1, None] - rho[..., 0, None])  # (N,S,A)
    pts = p[:, :, :, None] + (r[..., None] * t)[..., None] * n[:, :, None, None, :]
    return pts.reshape(pts.shape[0], -1, 2)


def cone_interior_points(
    P: np.ndarray, dims: BodyDims, camera: Camera, n_along: int = 4, n_across: int = 3
) -> np.ndarray:
    """Pixel samples inside the cones of N poses.

    Parameters
    ----------
    P : ndarray of shape (N, DOF)
        Poses.
    dims : BodyDims
        Body dimensions.
    camera : Camera
        The camera.
    n_along : int, default=4
        Grid points along each cone's axis.
    n_across : int, default=3
        Grid points across each cone.

    Returns
    -------
    ndarray of shape (N, 16 * n_along * n_across, 2)
        Pixels; see ``cone_interior_points_from_cones`` for the ordering.
    """
    ends, radii = cone_endpoints(P, dims)
    return cone_interior_points_from_cones(ends, radii, camera, n_along, n_across)


def cone_rims(ends: np.ndarray, radii: np.ndarray, n_rim: int = 12) -> np.ndarray:
    """3D points on the two end circles of every cone.

    Parameters
    ----------
    ends : ndarray of shape (N, S, 2, 3)
        Cone end centres, metres.
    radii : ndarray of shape (S, 2) or (N, S, 2)
        End radii, metres.
    n_rim : int, default=12
        Points on each circle.

    Returns
    -------
    ndarray of shape (N, S, 2, n_rim, 3)
        Metres.
    """
    axis = ends[..., 1, :] - ends[..., 0, :]
    length = norm3(axis)  # cross3 / norm3: numpy's bits for less overhead on 16 cones
    a = np.where(length > 1e-12, axis / np.maximum(length, 1e-12), np.array([0.0, 1.0, 0.0]))
    # Any vector not parallel to the axis gives a basis of the rim plane.
    helper = np.where(np.abs(a[..., :1]) < 0.9, np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
    u = cross3(a, helper)
    u /= norm3(u)
    v = cross3(a, u)
    ang = np.linspace(0.0, 2 * np.pi, n_rim, endpoint=False)
    # (N, S, n_rim, 3) unit circle in each cone's rim plane
    circle = np.cos(ang)[None, None, :, None] * u[:, :, None, :] + np.sin(ang)[None, None, :, None] * v[:, :, None, :]
    r = np.broadcast_to(np.asarray(radii, dtype=np.float64), ends.shape[:-1])  # (N,S,2)
    return ends[..., None, :] + r[..., None, None] * circle[:, :, None]


def _hull_polygons(ends: np.ndarray, radii: np.ndarray, camera: Camera, n_rim: int) -> np.ndarray:
    """(N, S, 2 * n_rim, 2) fixed-point pixel rims (NaN rows behind the camera)."""
    rims = cone_rims(ends, radii, n_rim)
    uv = camera.project(rims)
    return uv.reshape(*uv.shape[:2], 2 * n_rim, 2)


def rasterise_cones(ends: np.ndarray, radii: np.ndarray, camera: Camera, n_rim: int = 12) -> np.ndarray:
    """Silhouettes of cones: the union of the convex hulls of each cone's projected rims.

    Cones with any point behind the camera are skipped.

    Parameters
    ----------
    ends : ndarray of shape (N, S, 2, 3)
        Cone end centres, metres.
    radii : ndarray of shape (S, 2) or (N, S, 2)
        End radii, metres.
    camera : Camera
        The camera (its image is H x W).
    n_rim : int, default=12
        Points on each rim circle.

    Returns
    -------
    ndarray of shape (N, H, W)
        bool silhouettes.
    """
    uv = _hull_polygons(ends, radii, camera, n_rim)
    out = np.zeros((uv.shape[0], camera.height, camera.width), dtype=np.uint8)
    valid = np.isfinite(uv).all(axis=(-1, -2))
    fixed = np.round(np.nan_to_num(uv) * (1 << _SHIFT)).astype(np.int32)
    for i in range(uv.shape[0]):
        for s in np.flatnonzero(valid[i]):
            hull = cv2.convexHull(fixed[i, s])
            cv2.fillConvexPoly(out[i], hull, 1, lineType=cv2.LINE_8, shift=_SHIFT)
    return out.astype(bool)


def rasterise_silhouettes(P: np.ndarray, dims: BodyDims, camera: Camera) -> np.ndarray:
    """Silhouettes of the 16 cones of a few poses (a Python loop over poses and cones draws with
    OpenCV).

    Parameters
    ----------
    P : ndarray of shape (N, DOF)
        Poses.
    dims : BodyDims
        Body dimensions.
    camera : Camera
        The camera (its image is H x W).

    Returns
    -------
    ndarray of shape (N, H, W)
        bool silhouettes.
    """
    ends, radii = cone_endpoints(P, dims)
    return rasterise_cones(ends, radii, camera)


def render_edge_maps(
    P: np.ndarray, dims: BodyDims, camera: Camera, mode: str = "silhouette", thickness: int = 1
) -> np.ndarray:
    """Edge maps of N poses.

    Parameters
    ----------
    P : ndarray of shape (N, DOF)
        Poses.
    dims : BodyDims
        Body dimensions.
    camera : Camera
        The camera (its image is H x W).
    mode : {"silhouette", "cones"}, default="silhouette"
        "silhouette": the outer boundary of the union silhouette (what an edge detector sees
        against a plain background). "cones": every cone's outline, hidden parts included.
    thickness : int, default=1
        Edge thickness, pixels.

    Returns
    -------
    ndarray of shape (N, H, W)
        bool edge maps.

    Raises
    ------
    ValueError
        If ``mode`` is neither "silhouette" nor "cones".
    """
    if mode == "silhouette":
        sil = rasterise_silhouettes(P, dims, camera).astype(np.uint8)
        kernel = np.ones((2 * thickness + 1, 2 * thickness + 1), np.uint8)
        eroded = (
            np.stack([cv2.erode(s, kernel, borderType=cv2.BORDER_CONSTANT, borderValue=0) for s in sil])
            if len(sil)
            else sil
        )
        return (sil > 0) & (eroded == 0)
    if mode != "cones":
        raise ValueError(f"render_edge_maps: mode={mode!r}; use 'silhouette' or 'cones'")
    ends, radii = cone_endpoints(P, dims)
    uv = _hull_polygons(ends, radii, camera, 12)
    out = np.zeros((uv.shape[0], camera.height, camera.width), dtype=np.uint8)
    valid = np.isfinite(uv).all(axis=(-1, -2))
    fixed = np.round(np.nan_to_num(uv) * (1 << _SHIFT)).astype(np.int32)
    for i in range(uv.shape[0]):
        for s in np.flatnonzero(valid[i]):
            hull = cv2.convexHull(fixed[i, s])
            cv2.polylines(out[i], [hull], True, 1, thickness, cv2.LINE_8, _SHIFT)
    return out.astype(bool)


__all__ = [
    "project_cones",
    "cone_outline_points",
    "cone_outline_points_from_cones",
    "cone_interior_points",
    "cone_interior_points_from_cones",
    "cone_rims",
    "rasterise_cones",
    "rasterise_silhouettes",
    "render_edge_maps",
    "N_SEGMENTS",
]
