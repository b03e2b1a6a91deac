"""A published camera that follows the estimates without jumps (the calibration node's).

The camera is held as (log focal, tilt, roll, log height, distance, lateral offset); each update
moves every parameter towards the new estimate by at most ``max_step`` (log units for the focal
length, the height and the distance; radians for tilt and roll; ``max_step`` times the distance for
the offset), so the projections every node makes change smoothly however the estimate moves.
"""

from __future__ import annotations

import numpy as np

from counterpart.body.camera import Camera

from .estimate import CalibrationConfig, CameraEstimate, rotation


def camera_parameters(camera: Camera) -> np.ndarray:
    """The smoothed parameters of a camera looking roughly along -Z with the ground y = 0.

    Parameters
    ----------
    camera : Camera
        The camera.

    Returns
    -------
    ndarray of shape (6,)
        [log f, tilt, roll, log height, log distance, offset]: f in pixels, tilt and roll in radians,
        height and distance in metres (the distance and offset are those of the world origin).
    """
    R = camera.R
    tilt = float(np.arcsin(np.clip(-R[2, 1], -1, 1)))
    roll = float(np.arctan2(R[0, 1], -R[1, 1])) if abs(np.cos(tilt)) > 1e-6 else 0.0
    c = camera.centre
    return np.array([np.log(camera.fx), tilt, roll, np.log(max(c[1], 1e-3)), np.log(max(c[2], 1e-3)), -c[0]])


def camera_from_parameters(p: np.ndarray, width: int, height: int) -> Camera:
    """Inverse of :func:`camera_parameters` (principal point at the image centre, no yaw).

    Parameters
    ----------
    p : ndarray of shape (6,)
        [log f, tilt, roll, log height, log distance, offset], as :func:`camera_parameters` gives.
    width : int
        Image width, pixels.
    height : int
        Image height, pixels.

    Returns
    -------
    Camera
        The camera.
    """
    R = rotation(p[1], p[2])
    centre = np.array([-p[5], np.exp(p[3]), np.exp(p[4])])
    f = float(np.exp(p[0]))
    return Camera(f, f, (width - 1) / 2.0, (height - 1) / 2.0, width, height, R, -R @ centre)


def credible(
    est: CameraEstimate,
    max_height_std: float,
    max_focal_std: float,
    max_tilt_std_deg: float,
    min_depth_spread: float,
    min_horizon_segments: int = 12,
    max_split: tuple[float, float, float] = (0.10, 1.5, 0.20),
    config: CalibrationConfig | None = None,
) -> bool:
    """Whether an estimate is sure enough to move the published camera: its uncertainties under the
    bounds, the halves of its window in agreement with it, and the horizon seen, by people at
    different depths (``CameraEstimate.depth_spread``) or by scene lines converging on it
    (``horizon_segments``). Without it the lean of people
    reaching to each other passes for tilt. A tilt on the fit's lower bound is not credible either
    (a camera looking up: the sign of that lean).

    Parameters
    ----------
    est : CameraEstimate
        The estimate.
    max_height_std : float
        Largest standard deviation of the camera height.
    max_focal_std : float
        Largest standard deviation of the focal length.
    max_tilt_std_deg : float
        Largest standard deviation of the tilt, degrees.
    min_depth_spread : float
        Least ``est.depth_spread`` that shows the horizon (unless enough horizon segments do).
    min_horizon_segments : int
        Least ``est.horizon_segments`` that show the horizon (unless the depth spread does).
    max_split : tuple of (float, float, float), default=(0.10, 1.5, 0.20)
        Largest ``est.split_height``, ``split_tilt_deg`` and ``split_focal``: how far the estimates
        from the two halves of the window may land from the whole (log height, degrees, log focal);
        the uncertainty alone is too small where one cue (a line family, the right-angle prior)
        fixes a parameter that the people disagree with.
    config : CalibrationConfig or None, default=None
        The settings the estimate was made with: every person's fitted height must be plausible
        under its prior on people's height (:func:`statures_plausible`). None: the defaults.

    Returns
    -------
    bool
        True when the estimate may move the published camera.
    """
    return (
        np.isfinite([est.height_std, est.focal_std, est.tilt_std_deg]).all()
        and est.height_std <= max_height_std
        and est.focal_std <= max_focal_std
        and est.tilt_std_deg <= max_tilt_std_deg
        and est.distance > 0
        and (est.depth_spread >= min_depth_spread or est.horizon_segments >= min_horizon_segments)
        and est.tilt_deg > CalibrationConfig().min_tilt_deg + 0.5  # on its bound: the fit wanted further
        and est.split_height <= max_split[0]
        and est.split_tilt_deg <= max_split[1]
        and est.split_focal <= max_split[2]
        and statures_plausible(est, config)
    )


def statures_plausible(est: CameraEstimate, config: CalibrationConfig | None = None) -> bool:
    """Whether every person of an estimate has a fitted height within ``config.max_stature_sd`` prior
    stds of the prior's centre (``config.person_height``, ``person_height_std``).

    A fit keeps such a person when the others are too few to go on without them
    (``CalibrationConfig.max_stature_sd``). People of 1.3 and 2.7 m in one scene are fragments of
    people (an upper half, a head and shoulders) at the ground where the region ends, not people
    standing there; the camera's height then rests on the one whose fitted height is the prior's,
    whatever their views, and the fit's uncertainty, which takes the observations as they come,
    does not say so.

    Parameters
    ----------
    est : CameraEstimate
        The estimate (``people_heights``, metres).
    config : CalibrationConfig or None, default=None
        The prior on people's height and the bound, in its stds (None: the defaults).

    Returns
    -------
    bool
        True when every fitted height is within the bound (or no bound is set).
    """
    config = config or CalibrationConfig()
    if config.max_stature_sd is None:
        return True
    h = np.asarray(est.people_heights, np.float64)
    return bool((np.abs(h - config.person_height) <= config.max_stature_sd * config.person_height_std).all())


class CameraSmoother:
    """The published camera, moved towards each estimate by bounded steps.

    Parameters
    ----------
    start : Camera
        The camera published before any estimate (the default or a file's).
    max_step : float
        The bound per update (see the module docstring): log units for the focal length, the height
        and the distance; radians for tilt and roll; ``max_step`` times the distance for the offset.
    """

    def __init__(self, start: Camera, max_step: float = 0.03) -> None:
        self.size = (start.width, start.height)
        self.params = camera_parameters(start)
        self.max_step = float(max_step)

    @property
    def camera(self) -> Camera:
        return camera_from_parameters(self.params, *self.size)

    def step(self, est: CameraEstimate) -> Camera:
        """Move towards ``est``.

        Parameters
        ----------
        est : CameraEstimate
            The new estimate.

        Returns
        -------
        Camera
            The camera to publish.
        """
        target = camera_parameters(est.camera())
        bound = np.full(6, self.max_step)
        bound[5] = self.max_step * np.exp(self.params[4])
        self.params = self.params + np.clip(target - self.params, -bound, bound)
        return self.camera


__all__ = ["CameraSmoother", "camera_from_parameters", "camera_parameters", "credible", "statures_plausible"]
