"""Offline 3D tracking of a video file, without the bus (``counterpart track``).

The same algorithms as the graph ``camera -> silhouette -> tracker``: the silhouette node's
extractor (``counterpart.nodes.silhouette.pipeline.iter_video``: background fitted on the first seconds, people
with sides and ids) and one :class:`counterpart.nodes.tracker.tracker.Tracker` per tracked side, each fed the
frame and its person's pixels of the label mask, frame by frame. For batch work on a corpus.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Iterable, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from counterpart.body.camera import Camera, camera_for_size
from counterpart.body.pose import DOF
from counterpart.nodes.tracker.init import PlacementError
from counterpart.nodes.tracker.prior import MotionPrior
from counterpart.nodes.tracker.tracker import SIDES, Tracker, TrackerConfig, people_problem

if TYPE_CHECKING:
    from counterpart.nodes.silhouette.pipeline import FrameResult

#: progress(frames done, frames the file declares or 0)
Progress = Callable[[int, int], None]


def track_video(
    path: str | os.PathLike[str],
    out_npz: str | os.PathLike[str],
    people: Sequence[str] = SIDES,
    camera: Camera | None = None,
    prior: MotionPrior | None = None,
    layers: int = 10,
    particles: int = 256,
    max_frames: int | None = None,
    train_frames: int = 30,
    seed: int = 0,
    progress: Progress | None = None,
    tracker: TrackerConfig | None = None,
    camera_source: str | None = None,
    fps: float | None = None,
    frames: Iterable[tuple[np.ndarray, FrameResult]] | None = None,
    **silhouette_params: Any,
) -> dict[str, Any]:
    """Track the people of a video in 3D and save every frame's estimate.

    Args:
        path: the video file.
        out_npz: the output (np.savez_compressed); written also when the run is interrupted
            (KeyboardInterrupt) or a frame fails, with the frames done so far (``complete`` False).
        people: sides of the frame to track, one or two of "left" / "right" (as the tracker node;
            default both).
        camera: the calibration; None: the simulator's default camera at the video's frame size.
        camera_source: where the camera came from ("file", "estimated", "default"), kept in the
            file's ``params`` (None: "default" without a camera, "given" with one).
        prior: the motion prior (None: random walk).
        layers, particles: annealing layers and particles per layer; ``seed``: of the filters
            (side k gets seed + k, as in the node).
        max_frames, train_frames: frames to track at most; frames the background is fitted on.
        progress: called after every frame with (frames done, frames the file declares or 0).
        tracker: the trackers' settings (None: the defaults); its annealing layers and particles
            are ``layers`` and ``particles``.
        fps: the frame rate the trackers are told, Hz (None: the video's; 0: unknown, taken as the
            motion prior's): a slower video is searched wider between frames (``Tracker``'s fps).
        frames: the video's frames from its first, with the silhouette extractor's results (a pass
            shared with another reader: ``counterpart.apps.shared_pass``); None: the extractor is
            run here.
        silhouette_params: keyword parameters of ``SilhouetteExtractor`` (backend, min_area, ...),
            where ``frames`` is None.

    Returns
    -------
        A summary: n_frames, tracked (frames with an estimate, per side), not_placed (frames whose
        region could not be placed, per side), fps, frame_size, camera_source, out_npz.

    The file holds T frames x P sides: ``sides`` (P,) str, ``joints`` (T, P, 14, 3) float32 metres
    (NaN where the side is not tracked), ``poses`` and ``best_poses`` (T, P, 28), ``ess``,
    ``log_likelihood`` (T, P) float64, ``lost`` (T, P) bool, ``ids`` (T, P) int32 (the silhouette
    node's person id, -1 when absent), ``not_placed`` (T, P) bool (the person's region could not be
    placed in the scene: bottom above the horizon; that frame is skipped for that side), ``n_frames``, ``frame_size`` (2,) [H, W], ``fps``,
    ``complete`` (bool), ``camera`` and ``params`` (JSON strings).

    Raises FileNotFoundError / ValueError (a missing or undecodable video, bad people, a camera
    calibrated for another frame size) before anything is written.
    """
    from counterpart.body.image_sequence import video_info

    from .shared_pass import video_silhouettes

    problem = people_problem(list(people))
    if problem:
        raise ValueError(f"people={problem}")
    sides = list(people)
    source = camera_source or ("given" if camera is not None else "default")
    video_fps, declared = video_info(path)
    frames = video_silhouettes(path, frames, max_frames, train_frames, **silhouette_params)
    told_fps = video_fps if fps is None else fps
    trackers: dict[str, Tracker] = {}
    rows: list[dict[str, np.ndarray]] = []
    size: tuple[int, int] | None = None
    complete = False
    try:
        for frame, result in frames:
            if size is None:
                camera = camera_for_size(camera, frame.shape[1], frame.shape[0])
                size = frame.shape[:2]
                base = tracker or TrackerConfig()
                config = replace(base, apf=replace(base.apf, n_layers=layers, n_particles=particles))
                trackers = {
                    s: Tracker(camera, s, config, prior=prior, seed=seed + SIDES.index(s), fps=told_fps) for s in sides
                }
            rows.append(_track_frame(frame, result, sides, trackers))
            if progress is not None:
                progress(len(rows), declared)
        complete = True
    finally:
        if size is not None:
            _save(
                out_npz,
                rows,
                sides,
                size,
                video_fps,
                complete,
                camera,
                {
                    "people": sides,
                    "layers": layers,
                    "particles": particles,
                    "seed": seed,
                    "train_frames": train_frames,
                    "max_frames": max_frames,
                    "prior": prior is not None,
                    "camera_source": source,
                    "tracker_fps": told_fps,
                    **silhouette_params,
                },
            )
    tracked = {s: int(sum(np.isfinite(r["joints"][k, 0, 0]) for r in rows)) for k, s in enumerate(sides)}
    not_placed = {s: int(sum(r["not_placed"][k] for r in rows)) for k, s in enumerate(sides)}
    return {
        "n_frames": len(rows),
        "tracked": tracked,
        "not_placed": not_placed,
        "fps": video_fps,
        "frame_size": list(size or (0, 0)),
        "camera_source": source,
        "out_npz": os.fspath(out_npz),
    }


def _empty_row(P: int) -> dict[str, np.ndarray]:
    """One frame's arrays for P sides, as if nobody were tracked."""
    return {
        "joints": np.full((P, 14, 3), np.nan, np.float32),
        "poses": np.full((P, DOF), np.nan),
        "best_poses": np.full((P, DOF), np.nan),
        "ess": np.zeros(P),
        "log_likelihood": np.full(P, -np.inf),
        "lost": np.zeros(P, bool),
        "ids": np.full(P, -1, np.int32),
        "not_placed": np.zeros(P, bool),
    }


def _track_frame(
    frame: np.ndarray, result: FrameResult, sides: list[str], trackers: dict[str, Tracker]
) -> dict[str, np.ndarray]:
    """One frame's row: every side's estimate from its person's pixels of the label mask."""
    row = _empty_row(len(sides))
    for k, side in enumerate(sides):
        person = next((p for p in result.people if p.side == side), None)
        if person is None:
            continue
        row["ids"][k] = person.id
        try:
            other = next((p for p in result.people if p.side != side and p.side in SIDES), None)
            towards = tuple(other.bbox) if other is not None else None
            r = trackers[side].update(frame, result.labels == person.id + 1, towards)
        except PlacementError:  # one bad region is one bad frame: counted in the file, the run goes on
            row["not_placed"][k] = True
            continue
        if r is None:
            continue
        row["joints"][k], row["poses"][k], row["best_poses"][k] = r.joints, r.pose, r.best
        row["ess"][k], row["log_likelihood"][k], row["lost"][k] = r.ess, r.log_likelihood, r.lost
    return row


def _save(
    out_npz: str | os.PathLike[str],
    rows: list[dict[str, np.ndarray]],
    sides: list[str],
    size: tuple[int, int],
    fps: float,
    complete: bool,
    camera: Camera | None,
    params: dict[str, Any],
) -> None:
    stacked = {
        k: np.stack([r[k] for r in rows]) if rows else np.zeros((0,) + v.shape, v.dtype)
        for k, v in _empty_row(len(sides)).items()
    }
    np.savez_compressed(
        out_npz,
        sides=np.array(sides, dtype="<U5"),
        n_frames=np.int64(len(rows)),
        frame_size=np.array(size, np.int64),
        fps=np.float64(fps),
        complete=np.bool_(complete),
        camera=json.dumps(camera.to_dict() if camera is not None else {}),
        params=json.dumps(params, default=str),
        **stacked,
    )


__all__ = ["track_video"]
