"""Offline camera calibration of a video file from the people in it (``counterpart calibrate``).

The same algorithms as the graph ``camera -> silhouette -> calibration``: the silhouette node's
extractor (``counterpart.nodes.silhouette.pipeline.iter_video``: background fitted on the first frames, people
with ids and outlines), the head and foot points of the upright people (of the people detector's
boxes on a frame without any: ``counterpart.nodes.calibration.observe``) and the estimate from all of them at once
(``counterpart.nodes.calibration.estimate``), without the bus.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any

import numpy as np

from counterpart.body.camera import Camera
from counterpart.body.people_detector import PeopleDetector
from counterpart.nodes.calibration.estimate import CalibrationConfig, CameraEstimate
from counterpart.nodes.calibration.observe import PeopleObservations, SceneFrames
from counterpart.nodes.calibration.smooth import credible

if TYPE_CHECKING:
    from counterpart.nodes.silhouette.pipeline import FrameResult

#: progress(frames done, frames the file declares or 0)
Progress = Callable[[int, int], None]


def estimate_config(fov_deg: float = 0.0, **priors: float) -> CalibrationConfig:
    """The estimate's settings for a command's options.

    Parameters
    ----------
    fov_deg : float, default=0.0
        The camera's horizontal field of view, degrees (``--fov``); 0: unknown.
    **priors : float
        Other fields of ``CalibrationConfig`` (``person_height``, ``person_height_std``).

    Returns
    -------
    CalibrationConfig
        The settings.

    Raises
    ------
    ValueError
        Naming ``--fov`` where it is neither 0 nor in (1, 170) degrees.
    """
    config = CalibrationConfig(**priors)
    if not fov_deg:
        return config
    try:
        return config.with_known_fov(fov_deg)
    except ValueError as exc:
        raise ValueError(f"--fov: {exc}") from None


def calibrate_video(
    path: str | os.PathLike[str],
    max_frames: int | None = None,
    train_frames: int = 30,
    config: CalibrationConfig | None = None,
    progress: Progress | None = None,
    frames: Iterable[tuple[np.ndarray, FrameResult]] | None = None,
    **silhouette_params: Any,
) -> tuple[CameraEstimate, dict[str, Any]]:
    """Estimate the camera of a video from the people in it.

    Parameters
    ----------
    path : str or os.PathLike
        The video file.
    max_frames : int or None
        Frames to use at most (None: all).
    train_frames : int
        First frames the background is fitted on (people may be in view).
    config : CalibrationConfig or None
        Priors and noise model of the estimate (None: the defaults).
    progress : callable or None
        Called after every frame with (frames done, frames the file declares or 0).
    frames : iterable of (ndarray, FrameResult) or None, default=None
        The video's frames from its first, with the silhouette extractor's results (a pass shared
        with another reader: ``counterpart.apps.shared_pass``); None: the extractor is run here.
    **silhouette_params : Any
        Keyword parameters of ``SilhouetteExtractor`` (backend, min_area, ...), where ``frames`` is None.

    Returns
    -------
    estimate : CameraEstimate
        The camera estimate.
    summary : dict
        ``n_frames``, ``observations``, ``fps`` and ``frame_size`` [H, W] (pixels).

    Raises
    ------
    FileNotFoundError
        For a missing video.
    ValueError
        For an undecodable video, and when too few upright people were seen to estimate anything
        (the message says how many).
    """
    from counterpart.body.image_sequence import video_info

    from .shared_pass import video_silhouettes

    config = config or CalibrationConfig()

    fps, declared = video_info(path)
    frames = video_silhouettes(path, frames, max_frames, train_frames, **silhouette_params)
    obs: PeopleObservations | None = None
    scene = SceneFrames()
    detector = PeopleDetector()
    n = 0
    shape = (0, 0)
    for frame, result in frames:
        if obs is None:
            shape = frame.shape[:2]
            obs = PeopleObservations(frame.shape[1], frame.shape[0], max_observations=4000)
        time_s = n / (fps or 25.0)
        obs.add_frame(frame, time_s, obs.add(result.people, time_s, result.labels), detector)
        if scene.wants(n):
            scene.add(frame, result.people)
        n += 1
        if progress is not None:
            progress(n, declared)
    est = obs.estimate(config, scene.families()) if obs is not None else None
    if est is None:
        got = len(obs) if obs is not None else 0
        raise ValueError(
            f"{os.fspath(path)!r}: only {got} views of whole upright people in {n} frames, "
            f"{config.min_observations} needed to estimate the camera"
            + (
                (obs.feet_out_hint() if obs is not None else "")
                or "; use a longer video in which people stand or walk fully in view, or give a calibration file"
            )
        )
    return est, {"n_frames": n, "observations": len(obs), "fps": fps, "frame_size": list(shape)}


def graph_would_use(est: CameraEstimate, config: CalibrationConfig | None = None) -> bool:
    """Whether the calibration node, with its default bounds, would publish this estimate (moving
    the graph's camera to it) rather than keep the default camera.

    Parameters
    ----------
    est : CameraEstimate
        The estimate.
    config : CalibrationConfig or None, default=None
        The settings it was made with (its prior on people's height: ``--person-height``); None:
        the defaults, as the node's.

    Returns
    -------
    bool
        ``counterpart.nodes.calibration.smooth.credible`` with the node's default parameters.
    """
    from counterpart.nodes.calibration.node import Calibration

    p = {name: param.default for name, param in Calibration.params.items()}
    return credible(
        est,
        p["max_height_std"],
        p["max_focal_std"],
        p["max_tilt_std_deg"],
        p["min_depth_spread"],
        p["min_horizon_segments"],
        (p["max_split_height"], p["max_split_tilt_deg"], p["max_split_focal"]),
        config,
    )


def camera_file_text(camera: Camera, est: CameraEstimate, video: str, fov_given: float = 0.0) -> str:
    """A calibration file (YAML, ``Camera.to_dict``, which ``counterpart.body.camera.load_camera_file`` reads),
    with the estimate and its uncertainty as comments.

    Parameters
    ----------
    camera : Camera
        The camera to write.
    est : CameraEstimate
        The estimate, written as comments (description and one-std uncertainties).
    video : str
        The video the camera was estimated from, named in the first comment.
    fov_given : float, default=0.0
        The horizontal field of view the user gave (``--fov``), degrees, said in a comment; 0: none.

    Returns
    -------
    str
        The file's text.
    """
    import yaml

    head = [
        f"# camera estimated by `counterpart calibrate` from the people in {video}",
        f"# {est.describe()}",
        f"# one std: focal {100 * est.focal_std:.0f}%, tilt {est.tilt_std_deg:.1f} deg, roll "
        f"{est.roll_std_deg:.1f} deg, height {100 * est.height_std:.0f}%; people's heights "
        + ", ".join(f"{h:.2f} m" for h in est.people_heights),
    ]
    if fov_given:
        head.append(f"# the horizontal field of view given (--fov): {fov_given:g} deg")
    d = camera.to_dict()
    return "\n".join(head) + "\n" + yaml.safe_dump(d, default_flow_style=None, sort_keys=False)


__all__ = ["calibrate_video", "camera_file_text", "graph_would_use"]
