"""Random cameras for the simulator: a camera of random height, tilt and field of view that keeps
both people of a scenario fully in view (``open_stream(..., camera="random")``, ``counterpart sim
--camera random``).

The camera stands in front of the scene (+Z), centred on the people, with no roll; it looks down by
the tilt. Height, tilt and horizontal field of view are drawn uniformly from their ranges
(:class:`RandomCameraConfig`); the distance is then the smallest one (to 0.1 m) at which every
joint of both people over the whole scenario, the top of the head included, projects inside the
image with a margin. A draw for which no distance up to ``max_distance`` keeps the people in view
(a camera low and steeply tilted with a narrow view sees no heads) is drawn again: the accepted
cameras are uniform over the feasible part of the ranges.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from counterpart.body.camera import Camera

#: metres above the head joint (the head's centre) that the image must include: the crown and hair
HEAD_TOP = 0.16


@dataclass(frozen=True)
class RandomCameraConfig:
    """Ranges of the random camera (metres, degrees) and the framing.

    Parameters
    ----------
    height : tuple of (float, float)
        Camera centre above the floor, metres (low, high).
    tilt_deg : tuple of (float, float)
        Downward pitch of the optical axis, degrees (low, high).
    fov_deg : tuple of (float, float)
        Horizontal field of view, degrees (low, high).
    margin : float
        Share of the image size kept free at every border.
    max_distance : float
        Farthest camera distance tried, metres from the people's centre.
    tries : int
        Draws before giving up.
    """

    height: tuple[float, float] = (1.0, 3.0)
    tilt_deg: tuple[float, float] = (0.0, 35.0)
    fov_deg: tuple[float, float] = (40.0, 75.0)
    margin: float = 0.03
    max_distance: float = 25.0
    tries: int = 200


def _camera_at(eye: np.ndarray, tilt: float, fov_deg: float, width: int, height: int) -> Camera:
    direction = np.array([0.0, -np.sin(tilt), -np.cos(tilt)])
    return Camera.look_at(eye, eye + direction, fov_deg, width, height)


def frame_people(
    points: np.ndarray,
    cam_height: float,
    tilt_deg: float,
    fov_deg: float,
    width: int,
    height: int,
    margin: float = 0.03,
    max_distance: float = 25.0,
) -> Camera | None:
    """The nearest camera of this height, tilt and field of view (no roll, looking along -Z) that
    keeps ``points`` in view; None when none within ``max_distance`` does.

    Parameters
    ----------
    points : ndarray of shape (N, 3)
        World points (metres) that must be seen: the people's joints and head tops.
    cam_height : float
        Camera centre above the floor y = 0, metres.
    tilt_deg : float
        Downward pitch of the optical axis, degrees.
    fov_deg : float
        Horizontal field of view, degrees.
    width, height : int
        Image size, pixels.
    margin : float
        Share of the image size kept free at each border.
    max_distance : float
        Farthest camera distance tried (in steps of 0.1 m from 1 m), metres from the points' centre.

    Returns
    -------
    Camera or None
        The nearest such camera, or None when none within ``max_distance`` keeps the points in view.
    """
    P = np.asarray(points, np.float64).reshape(-1, 3)
    centre = np.array([0.5 * (P[:, 0].min() + P[:, 0].max()), 0.0, 0.5 * (P[:, 2].min() + P[:, 2].max())])
    lo = np.array([margin * width, margin * height]) - 0.5
    hi = np.array([(1 - margin) * width, (1 - margin) * height]) - 0.5
    tilt = np.deg2rad(tilt_deg)
    for d in np.arange(1.0, max_distance + 1e-9, 0.1):
        cam = _camera_at(np.array([centre[0], cam_height, centre[2] + d]), tilt, fov_deg, width, height)
        uv = cam.project(P)
        if np.isfinite(uv).all() and (uv >= lo).all() and (uv <= hi).all():
            return cam
    return None


def scene_points(joints: np.ndarray) -> np.ndarray:
    """The points to keep in view: every joint, the head tops (``HEAD_TOP`` above each joint) and the
    floor under each joint.

    Parameters
    ----------
    joints : ndarray of shape (T, P, J, 3)
        Joints of P people over T frames, metres, world frame.

    Returns
    -------
    ndarray of shape (N, 3)
        The points, metres (N = 3 T P J).
    """
    J = np.asarray(joints, np.float64).reshape(-1, 3)
    top = J + np.array([0.0, HEAD_TOP, 0.0])
    floor = J * np.array([1.0, 0.0, 1.0])
    return np.concatenate([J, top, floor])


def random_camera(
    joints: np.ndarray,
    rng: np.random.Generator,
    width: int,
    height: int,
    config: RandomCameraConfig = RandomCameraConfig(),
) -> tuple[Camera, dict[str, float]]:
    """A random camera that sees the people of ``joints`` fully.

    Parameters
    ----------
    joints : ndarray of shape (T, P, J, 3)
        Joints of P people over T frames, metres, world frame.
    rng : numpy.random.Generator
        The source of the draws.
    width, height : int
        Image size, pixels.
    config : RandomCameraConfig
        Ranges of the draws and the framing.

    Returns
    -------
    camera : Camera
        The camera.
    drawn : dict of str to float
        Its drawn parameters: ``height`` (m), ``tilt_deg``, ``fov_deg``, ``distance`` (m, horizontal,
        from the camera to the people's centre).

    Raises
    ------
    ValueError
        When ``config.tries`` draws find no feasible camera.
    """
    pts = scene_points(joints)
    for _ in range(config.tries):
        h = float(rng.uniform(*config.height))
        tilt = float(rng.uniform(*config.tilt_deg))
        fov = float(rng.uniform(*config.fov_deg))
        cam = frame_people(pts, h, tilt, fov, width, height, config.margin, config.max_distance)
        if cam is not None:
            zc = 0.5 * (pts[:, 2].min() + pts[:, 2].max())
            return cam, {"height": h, "tilt_deg": tilt, "fov_deg": fov, "distance": float(cam.centre[2] - zc)}
    raise ValueError(f"no camera in the ranges {config} keeps both people in view; widen the ranges")


__all__ = ["RandomCameraConfig", "frame_people", "random_camera", "scene_points"]
