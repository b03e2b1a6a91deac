"""``counterpart sim``: render a simulated two-person scene to a folder, with ground truth.

    counterpart sim --scenario handshake --seed 3 --out out/hs3 [--width 320 --height 240
                    --fps 25 --frames N --emotion angry --strength 0.8]
    counterpart sim --scenario cmu --bvh-a A.bvh --bvh-b B.bvh --out out/cmu
    counterpart sim --list

Writes into ``--out``:

* ``video.avi``: FFV1 (lossless: decodes to exactly the rendered frames) where this OpenCV can
  write it, else MJPG; BGR, ``--fps``.
* ``truth.npz``: ``joints3d`` (T,2,14,3) m, ``joints2d`` (T,2,14,2) px, ``masks`` (T,2,H,W) bool
  (visible pixels of A, B), ``shadow`` (T,H,W) bool, ``signals`` (T,2,K) int8 with
  ``signal_names``, ``phase`` (T,) int32, ``label``, ``fps``, ``times`` (T,) s, ``poses`` (T,2,28),
  ``camera_K`` (3,3), ``camera_R`` (3,3), ``camera_t`` (3,), ``codec``, ``meta`` (JSON string).
* ``trajectory.npz``: ``counterpart.body.trajectory`` format with signals and phase.
* ``contact_sheet.png``: 12 frames in a 4x3 grid, each stamped with its frame number.

The same arguments give the same bytes (all randomness comes from seeded numpy generators).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from typing import Any

import cv2
import numpy as np

from counterpart.messages import EMOTIONS
from counterpart.sim.scenarios import SCENARIOS

#: the one-line help of this command in `counterpart --help`
HELP = "render a simulated two-person scene with ground truth"


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Add the ``sim`` options to ``p``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser.
    """
    p.add_argument("--scenario", default="handshake", help=f"one of {', '.join(SCENARIOS)}, cmu")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", help="output folder (created)")
    p.add_argument("--width", type=int, default=320)
    p.add_argument("--height", type=int, default=240)
    p.add_argument("--fps", type=float, default=25.0)
    p.add_argument("--frames", type=int, default=None, help="render at most this many frames")
    p.add_argument("--emotion", choices=EMOTIONS, default=None, help="default: drawn from the seed")
    p.add_argument("--strength", type=float, default=None, help="emotion strength in [0, 1]")
    p.add_argument("--noise", type=float, default=2.0, help="sensor noise sigma, grey levels")
    p.add_argument("--bvh-a", default=None, help="scenario cmu: person A's BVH (default: shared CMU 18_01)")
    p.add_argument("--bvh-b", default=None, help="scenario cmu: person B's BVH (default: shared CMU 19_01)")
    p.add_argument(
        "--camera",
        choices=("default", "random"),
        default="default",
        help="the simulator's default camera, or a random one drawn from the seed (height 1-3 m, tilt "
        "0-35 degrees, horizontal field of view 40-75 degrees, bearing -60 to 60 degrees about the pair) that "
        "keeps both people in view",
    )
    p.add_argument("--list", action="store_true", help="list the scenarios and exit")


def open_writer(path: str, fps: float, size: tuple[int, int]) -> tuple[cv2.VideoWriter, str]:
    """A cv2 writer for ``path``: FFV1 (lossless) if available, else MJPG.

    Parameters
    ----------
    path : str
        The ``.avi`` file to write.
    fps : float
        Frames per second.
    size : tuple of (int, int)
        Frame (width, height), pixels.

    Returns
    -------
    writer : cv2.VideoWriter
        The opened writer.
    codec : str
        ``"FFV1"`` or ``"MJPG"``.

    Raises
    ------
    RuntimeError
        If OpenCV can write neither codec.
    """
    for codec in ("FFV1", "MJPG"):
        w = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*codec), float(fps), size)
        if w.isOpened():
            return w, codec
        w.release()
    raise RuntimeError(f"{path}: OpenCV can write neither FFV1 nor MJPG AVI files in this build")


def contact_sheet(frames: list[np.ndarray], numbers: list[int], cols: int = 4) -> np.ndarray:
    """Grid of frames, each stamped with its frame number.

    Parameters
    ----------
    frames : list of ndarray of shape (H, W, 3), dtype uint8
        BGR frames, all the same size.
    numbers : list of int
        The frame numbers stamped on them.
    cols : int, default=4
        Frames per row (the last row is padded with black).

    Returns
    -------
    ndarray of shape (rows * H, cols * W, 3), dtype uint8
        The grid.
    """
    tiles = []
    for f, n in zip(frames, numbers):
        t = f.copy()
        cv2.putText(t, f"{n}", (5, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.55, (0, 0, 0), 3, cv2.LINE_AA)
        cv2.putText(t, f"{n}", (5, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.55, (255, 255, 255), 1, cv2.LINE_AA)
        tiles.append(t)
    while len(tiles) % cols:
        tiles.append(np.zeros_like(tiles[0]))
    return np.vstack([np.hstack(tiles[r : r + cols]) for r in range(0, len(tiles), cols)])


def render_to_folder(stream: Any, out: str, progress: bool = True) -> dict[str, str]:
    """Render every frame of ``stream`` into ``out``.

    Parameters
    ----------
    stream : counterpart.sim.stream.SimStream
        The simulated stream.
    out : str
        The output folder (created).
    progress : bool, default=True
        Print progress lines on stderr.

    Returns
    -------
    dict of str to str
        Paths written, by kind: ``video``, ``truth``, ``trajectory``, ``sheet``.
    """
    os.makedirs(out, exist_ok=True)
    T = stream.n_frames
    W, H = stream.size
    paths = {
        k: os.path.join(out, f)
        for k, f in (
            ("video", "video.avi"),
            ("truth", "truth.npz"),
            ("trajectory", "trajectory.npz"),
            ("sheet", "contact_sheet.png"),
        )
    }
    writer, codec = open_writer(paths["video"], stream.fps, (W, H))
    sheet_idx = sorted(set(np.linspace(0, T - 1, min(12, T)).round().astype(int).tolist()))
    sheet: list[np.ndarray] = []
    j3 = np.empty((T, 2, 14, 3))
    j2 = np.empty((T, 2, 14, 2))
    masks = np.empty((T, 2, H, W), bool)
    shadow = np.empty((T, H, W), bool)
    signals = np.empty((T, 2, len(stream.scenario.signal_names)), np.int8)
    try:
        for i in range(T):
            frame, tr = stream.render_with_truth(i)
            writer.write(frame)
            j3[i], j2[i], masks[i], shadow[i], signals[i] = tr.joints3d, tr.joints2d, tr.masks, tr.shadow, tr.signals
            if i in sheet_idx:
                sheet.append(frame)
            if progress and (i % 25 == 0 or i == T - 1):
                print(f"sim: frame {i + 1}/{T}", file=sys.stderr, flush=True)
    finally:
        writer.release()
    sc = stream.scenario
    cam = stream.camera
    meta = json.loads(json.dumps(sc.meta, default=str))
    np.savez_compressed(
        paths["truth"],
        joints3d=j3,
        joints2d=j2,
        masks=masks,
        shadow=shadow,
        signals=signals,
        signal_names=np.array(sc.signal_names),
        phase=sc.phase,
        label=np.array(sc.label),
        fps=np.float64(sc.fps),
        times=sc.times,
        poses=np.stack([sc.poses_a, sc.poses_b], axis=1),
        camera_K=cam.K,
        camera_R=cam.R,
        camera_t=cam.t,
        codec=np.array(codec),
        meta=np.array(json.dumps(meta, sort_keys=True)),
    )
    stream.trajectory.save(paths["trajectory"])
    cv2.imwrite(paths["sheet"], contact_sheet(sheet, sheet_idx))
    return paths


def main(args: argparse.Namespace) -> int:
    """``counterpart sim``: list the scenarios, or render one into ``--out``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed ``sim`` options.

    Returns
    -------
    int
        Exit status: 0 ok, 2 bad input.
    """
    if args.list:
        for name, fn in SCENARIOS.items():
            print(f"{name:13s} {(fn.__doc__ or '').strip().splitlines()[0]}")
        print(f"{'cmu':13s} a BVH pair (--bvh-a, --bvh-b; default: the shared CMU handshake 18_01/19_01)")
        return 0
    if not args.out:
        print("counterpart sim: --out DIR is required (or --list)", file=sys.stderr)
        return 2
    if os.path.exists(args.out) and not os.path.isdir(args.out):
        print(
            f"counterpart sim: --out {args.out}: is a file; --out is the folder the scene is written into",
            file=sys.stderr,
        )
        return 2
    from counterpart.sim.stream import open_stream

    kw: dict[str, Any] = {
        "emotion": args.emotion,
        "strength": args.strength,
        "frames": args.frames,
        "noise": args.noise,
        "camera": args.camera,
    }
    if args.scenario == "cmu":
        kw = {
            "frames": args.frames,
            "noise": args.noise,
            "bvh_a": args.bvh_a,
            "bvh_b": args.bvh_b,
            "camera": args.camera,
        }
    try:
        stream = open_stream(args.scenario, seed=args.seed, width=args.width, height=args.height, fps=args.fps, **kw)
    except (ValueError, FileNotFoundError) as e:
        print(f"counterpart sim: {e}", file=sys.stderr)
        return 2
    paths = render_to_folder(stream, args.out)
    print(f"sim: wrote {stream.n_frames} frames to {paths['video']}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    ap = argparse.ArgumentParser(prog="python -m counterpart.sim.cli")
    add_arguments(ap)
    sys.exit(main(ap.parse_args()))
