"""Random cameras for the simulator: a camera of random height, tilt, field of view and bearing
that keeps both people of a scenario fully in view (``open_stream(..., camera="random")``,
``counterpart sim --camera random``).

The camera looks at the people's centre from the bearing ``azimuth`` (degrees about the vertical
through that centre: 0 is straight in front of the scene, +Z, square-on to the line between the
two people; positive turns towards +X), with no roll; it looks down by the tilt. Height, tilt,
horizontal field of view and azimuth are drawn uniformly from their ranges
(:class:`RandomCameraConfig`); the distance is then the smallest one (to 0.1 m) at which every
joint of both people over the whole scenario, the top of the head included, projects inside the
image with a margin. A draw for which no distance up to ``max_distance`` keeps the people in view
(a camera low and steeply tilted with a narrow view sees no heads) is drawn again: the accepted
cameras are uniform over the feasible part of the ranges.

Why a bearing of -60 to +60 degrees: a camera filming two people is rarely square-on to the line
between them (a room's corner camera, a camera on a shelf, a phone held by a third person), so the
two stand at different depths; beyond about 60 degrees one person stands behind the other for much
of an interaction (at 90 degrees the line between them points at the camera) and the interaction
itself cannot be seen, which is not a view a user would film it from.
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
    azimuth_deg : tuple of (float, float)
        Bearing of the camera about the people's centre, degrees (low, high); 0 is square-on to the
        line between them (the module docstring says why -60 to 60).
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
    azimuth_deg: tuple[float, float] = (-60.0, 60.0)
    margin: float = 0.03
    max_distance: float = 25.0
    tries: int = 200


def _camera_at(eye: np.ndarray, tilt: float, azimuth: float, fov_deg: float, width: int, height: int) -> Camera:
    direction = np.array([-np.sin(azimuth) * np.cos(tilt), -np.sin(tilt), -np.cos(azimuth) * np.cos(tilt)])
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
    azimuth_deg: float = 0.0,
) -> Camera | None:
    """The nearest camera of this height, tilt, field of view and bearing (no roll) that keeps
    ``points`` in view; None when none within ``max_distance`` does.

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
    azimuth_deg : float, default=0.0
        Bearing of the camera about the points' centre, degrees: 0 looks along -Z, positive puts
        the camera towards +X.

    Returns
    -------
    Camera or None
        The nearest such camera, or None when none within ``max_distance`` keeps the points in view.
    """
    P = np.asarray(points, np.float64).reshape(-1, 3)
    centre = np.array([0.5 * (P[:, 0].min() + P[:, 0].max()), 0.0, 0.5 * (P[:, 2].min() + P[:, 2].max())])
    lo = np.array([margin * width, margin * height]) - 0.5
    hi = np.array([(1 - margin) * width, (1 - margin) * height]) - 0.5
    tilt, az = np.deg2rad(tilt_deg), np.deg2rad(azimuth_deg)
    out = np.array([np.sin(az), 0.0, np.cos(az)])  # from the centre towards the camera
    for d in np.arange(1.0, max_distance + 1e-9, 0.1):
        eye = centre + d * out + [0.0, cam_height, 0.0]
        cam = _camera_at(eye, tilt, az, fov_deg, width, height)
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
        Its drawn parameters: ``height`` (m), ``tilt_deg``, ``fov_deg``, ``azimuth_deg`` (the bearing
        about the people's centre), ``distance`` (m, horizontal, from the camera to the people's
        centre), and the ranges they were drawn from (``azimuth_range_deg`` and the like).

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
        az = float(rng.uniform(*config.azimuth_deg))
        cam = frame_people(pts, h, tilt, fov, width, height, config.margin, config.max_distance, az)
        if cam is not None:
            xc = 0.5 * (pts[:, 0].min() + pts[:, 0].max())
            zc = 0.5 * (pts[:, 2].min() + pts[:, 2].max())
            return cam, {
                "height": h,
                "tilt_deg": tilt,
                "fov_deg": fov,
                "azimuth_deg": az,
                "distance": float(np.hypot(cam.centre[0] - xc, cam.centre[2] - zc)),
                "height_range": list(config.height),
                "tilt_range_deg": list(config.tilt_deg),
                "fov_range_deg": list(config.fov_deg),
                "azimuth_range_deg": list(config.azimuth_deg),
            }
    raise ValueError(f"no camera in the ranges {config} keeps both people in view; widen the ranges")


__all__ = ["RandomCameraConfig", "frame_people", "random_camera", "scene_points"]
