"""Offline camera calibration of a video file from the people in it (``counterpart calibrate``).

The same algorithms as the graph ``camera -> silhouette -> calibration``: the silhouette node's
extractor (``counterpart.nodes.silhouette.pipeline.iter_video``: background fitted on the first frames, people
with ids and outlines), the head and foot points of the upright people
(``counterpart.nodes.calibration.observe``) and the estimate from all of them at once
(``counterpart.nodes.calibration.estimate``), without the bus.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

from counterpart.body.camera import Camera
from counterpart.nodes.calibration.estimate import CalibrationConfig, CameraEstimate
from counterpart.nodes.calibration.observe import PeopleObservations, SceneFrames

#: progress(frames done, frames the file declares or 0)
Progress = Callable[[int, int], None]


def calibrate_video(
    path: str | os.PathLike[str],
    max_frames: int | None = None,
    train_frames: int = 30,
    config: CalibrationConfig | None = None,
    progress: Progress | None = None,
    **silhouette_params: Any,
) -> tuple[CameraEstimate, dict[str, Any]]:
    """Estimate the camera of a video from the people in it.

    Args:
        path: the video file.
        max_frames: frames to use at most (None: all).
        train_frames: first frames the background is fitted on (people may be in view).
        config: priors and noise model of the estimate.
        progress: called after every frame with (frames done, frames the file declares or 0).
        silhouette_params: keyword parameters of ``SilhouetteExtractor`` (backend, min_area, ...).

    Returns
    -------
        (the estimate, a summary: n_frames, observations, fps, frame_size [H, W]).
    Raises FileNotFoundError / ValueError for a missing or undecodable video, and ValueError when
    too few upright people were seen to estimate anything (the message says how many).
    """
    from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor, iter_video, video_info

    config = config or CalibrationConfig()

    fps, declared = video_info(path)
    extractor = SilhouetteExtractor(**silhouette_params)
    obs: PeopleObservations | None = None
    scene = SceneFrames()
    n = 0
    shape = (0, 0)
    for frame, result in iter_video(path, extractor, max_frames, train_frames):
        if obs is None:
            shape = frame.shape[:2]
            obs = PeopleObservations(frame.shape[1], frame.shape[0], max_observations=4000)
        obs.add(result.people, n / (fps or 25.0))
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
            f"{config.min_observations} needed to estimate the camera; use a longer video in which "
            "people stand or walk fully in view, or give a calibration file"
        )
    return est, {"n_frames": n, "observations": len(obs), "fps": fps, "frame_size": list(shape)}


def camera_file_text(camera: Camera, est: CameraEstimate, video: str) -> str:
    """A calibration file (YAML, ``Camera.to_dict``, which ``counterpart.body.camera.load_camera_file`` reads),
    with the estimate and its uncertainty as comments.
    """
    import yaml

    head = [
        f"# camera estimated by `counterpart calibrate` from the people in {video}",
        f"# {est.describe()}",
        f"# one std: focal {100 * est.focal_std:.0f}%, tilt {est.tilt_std_deg:.1f} deg, roll "
        f"{est.roll_std_deg:.1f} deg, height {100 * est.height_std:.0f}%; people's heights "
        + ", ".join(f"{h:.2f} m" for h in est.people_heights),
    ]
    d = camera.to_dict()
    return "\n".join(head) + "\n" + yaml.safe_dump(d, default_flow_style=None, sort_keys=False)


__all__ = ["calibrate_video", "camera_file_text"]
