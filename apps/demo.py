"""``counterpart demo``: the whole graph end to end on the built-in scene (or your video, or a camera).

1. builds the default models if they are not cached yet (progress on stderr);
2. launches ``launch/lockstep.yaml`` on the simulator's handshake or on ``--input FILE`` (a recording, a video file or a folder of frames:
   every frame through all six nodes, however slow the machine), ``launch/demo.yaml`` with
   ``--realtime`` or ``--serve`` (real time: a node that cannot keep up drops frames), or
   ``launch/live.yaml`` with ``--live``;
3. writes ``OUT/demo.mp4`` (or ``.avi`` where OpenCV cannot write H.264) at the input's frame rate,
   ``OUT/demo_contact_sheet.png`` and ``OUT/demo_stats.json``, and prints a summary (frames in, with
   people, with a partner; nodes that could not keep up) and the per-node statistics.

Exit codes: 0; 1 when the graph ran but drew no partner on any frame (the reason is printed); the
launcher's code when a node failed; 2 for bad options; 130 on Ctrl-C.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import signal
import sys
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path

from counterpart.bus.run_summary import RunSummary, read_stats, stats_json, stats_table, summarise
from counterpart.messages import INTERACTION_MODELS

#: the one-line help of this command in `counterpart --help`
HELP = "the whole graph end to end on the built-in scene, your video or a camera"

#: the responder's models built before the graph starts (the emotion model styles the others)
RESPONDER_MODELS = ("dual-hmm", "joint-shape", "listener", "emotion")
#: the rest of what the live page offers (``--serve``: every interaction model of the contract)
SERVE_MODELS = tuple(m for m in INTERACTION_MODELS if m not in RESPONDER_MODELS)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Add the ``demo`` options to ``p``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser.
    """
    src = p.add_mutually_exclusive_group()
    src.add_argument(
        "--input",
        metavar="FILE",
        help="run on your own recording instead of the built-in scene: a video file, or a folder of numbered "
        "PNG or JPEG frames (played at 25 fps)",
    )
    src.add_argument("--live", action="store_true", help="use the V4L2 camera (launch/live.yaml)")
    p.add_argument(
        "--realtime",
        action="store_true",
        help="play the file or the built-in scene in real time through the live graph, where a node "
        "that cannot keep up drops frames (default: every frame is processed, in lockstep)",
    )
    p.add_argument("--device", default="/dev/video0", help="camera device for --live")
    p.add_argument(
        "--camera",
        metavar="FILE",
        default="",
        help="calibration file (JSON/YAML, e.g. from counterpart calibrate) for the calibration node; "
        "default: estimated from the people in view (the default camera until then)",
    )
    p.add_argument(
        "--serve",
        action="store_true",
        help="serve the live page (http://127.0.0.1:PORT); the scene or file loops until Ctrl-C",
    )
    p.add_argument("--port", type=int, default=8080, help="port of the live page")
    p.add_argument("--out", default="out", help="output folder (default: out)")
    p.add_argument("--scenario", default="handshake", help="built-in scene when no --input/--live")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--frames", type=int, default=0, help="stop after this many frames (0: the whole scene or file)")
    p.add_argument("--set", action="append", metavar="NODE.PARAM=VALUE", help="override a node parameter")


def _builder_start() -> None:
    """A model-building worker's start: one BLAS/OpenMP thread (two builds on two cores would
    otherwise spin their threads against each other), and Ctrl-C left to the demo, which stops the
    workers and says so once.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    import numpy  # noqa: F401  (loads the BLAS the limit applies to)
    import scipy.linalg  # noqa: F401
    import sklearn.utils  # noqa: F401  (loads OpenMP)
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)


def _build_prior() -> None:
    """Load or build the tracker's default motion prior (in a worker)."""
    from counterpart.nodes.tracker.prior import load_default_prior

    load_default_prior(progress=True)


def _build_responder_model(name: str) -> None:
    """Load or build the responder's default model ``name`` (in a worker)."""
    from counterpart.nodes.responder.models import load_default

    load_default(name, progress=lambda m: print(f"  responder {name}: {m}", file=sys.stderr, flush=True))


def ensure_models(serve: bool = False) -> None:
    """Build the default model files the graph loads (and, with ``serve``, those the live page
    offers), when they are not cached yet, and compile the nodes' kernels on an install's first run.

    Missing models, and the kernels' parts to compile, are built side by side, one process per core
    (they are independent and each is single-threaded for most of its time); cached ones are only
    loaded.

    Parameters
    ----------
    serve : bool, default=False
        Also build the models the live page offers.
    """
    from concurrent.futures import ProcessPoolExecutor
    from multiprocessing import active_children, get_context

    from counterpart.apps.kernel_cache import COMPILE_PARTS, compile_kernels, kernels_cached, remember_kernels
    from counterpart.nodes.responder.models import default_model_path
    from counterpart.nodes.tracker.prior import default_prior_path

    names = RESPONDER_MODELS + (SERVE_MODELS if serve else ())
    # the longest first, so that the short ones fill the other core: the default responder model,
    # the kernels' parts (about half as long each), the tracker's prior (less again)
    jobs = [(_build_responder_model, (n,)) for n in names[:1]]
    # the nodes' numba kernels, compiled on an install's first run (in parts, side by side): the
    # graph's nodes then load them instead of compiling for seconds while the frames go on; then
    # remembered (``kernel_cache``), so that later runs need not load them to find out
    compiling = not kernels_cached()
    if compiling:
        jobs += [(compile_kernels, (part, COMPILE_PARTS)) for part in range(COMPILE_PARTS)]
    jobs += [(_build_prior, ())] + [(_build_responder_model, (n,)) for n in names[1:]]
    if not default_prior_path().exists():
        print("  tracker motion prior (once)...", file=sys.stderr)
    missing = not default_prior_path().exists() or not all(default_model_path(n).exists() for n in names)
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    if not (missing or compiling) or cores < 2:
        for fn, fn_args in jobs:
            fn(*fn_args)
        if compiling:
            remember_kernels()
        return
    # a builder that dies (killed, out of memory) fails its future at once, where a
    # multiprocessing.Pool would wait for its result for ever
    pool = ProcessPoolExecutor(min(cores, len(jobs)), mp_context=get_context("spawn"), initializer=_builder_start)
    try:
        for future in [pool.submit(fn, *fn_args) for fn, fn_args in jobs]:
            future.result()
    except BaseException:
        # Ctrl-C, a SIGINT to this process alone, or a failed build: the other builders would go on
        # for minutes (the pool's shutdown waits for every job given to it): they are stopped (the
        # only processes this one has started so far), and what a stopped one was writing is
        # dropped (the files finished are whole: written by rename)
        pool.shutdown(wait=False, cancel_futures=True)
        for worker in active_children():
            worker.terminate()
            worker.join()
        for folder in {default_prior_path().parent, *(default_model_path(n).parent for n in names)}:
            for part in folder.glob("*.tmp.npz"):
                part.unlink(missing_ok=True)
        raise
    pool.shutdown()
    if compiling:
        remember_kernels()


def contact_sheet(video: Path, out: Path, n: int = 12, cols: int = 4) -> bool:
    """Write a grid of ``n`` frames spread over ``video``, each stamped with its frame number.

    Parameters
    ----------
    video : Path
        The video file.
    out : Path
        The image file to write.
    n : int, default=12
        Number of frames (fewer when the video has fewer).
    cols : int, default=4
        Frames per row.

    Returns
    -------
    bool
        True when the image was written; False when the video has no frames or writing failed.
    """
    import cv2
    import numpy as np

    cap = cv2.VideoCapture(str(video))
    frames = []
    ok, img = cap.read()
    while ok:
        frames.append(img)
        ok, img = cap.read()
    cap.release()
    if not frames:
        return False
    idx = np.linspace(0, len(frames) - 1, min(n, len(frames))).round().astype(int)
    tiles = []
    for i in idx:
        tile = frames[i].copy()
        cv2.putText(tile, f"#{i}", (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
        tiles.append(tile)
    while len(tiles) % cols:
        tiles.append(np.zeros_like(tiles[0]))
    rows = [np.hstack(tiles[r : r + cols]) for r in range(0, len(tiles), cols)]
    return bool(cv2.imwrite(str(out), np.vstack(rows)))


def _graph_file(args: argparse.Namespace) -> tuple[str, list[str]]:
    """The launch file and the ``--set`` overrides of the source for the chosen input: a camera is
    live (the real-time graph); a file or the built-in scene is a recording, processed frame by
    frame in lockstep unless ``--realtime`` (or ``--serve``, whose page loops the scene live) asks
    for real time.
    """
    if args.live:
        return "live.yaml", [f"camera.source={args.device}"]
    if args.input:
        path = Path(args.input).resolve()
        source = f"folder:{path}" if path.is_dir() else str(path)
    else:
        source = f"sim:{args.scenario}?seed={args.seed}"
    return ("demo.yaml" if args.realtime or args.serve else "lockstep.yaml"), [f"camera.source={source}"]


def report(run_dir: Path, out: Path) -> RunSummary:
    """Print the run's summary and per-node statistics; write them to ``OUT/demo_stats.json``.

    Parameters
    ----------
    run_dir : Path
        The launch's run directory.
    out : Path
        The output folder ``OUT``.

    Returns
    -------
    RunSummary
        The run's summary.
    """
    stats = read_stats(run_dir)
    summary = summarise(stats)
    print("\n".join(summary.lines()))
    for line in summary.warnings():
        print(line, file=sys.stderr)
    path = out / "demo_stats.json"
    path.write_text(json.dumps({**summary.to_json(), "nodes": stats_json(stats)}, indent=1))
    print(f"per-node statistics ({path}):")
    print(stats_table(stats))
    return summary


#: name endings of video files: an ``--out`` that ends so names a video, not the demo's folder
VIDEO_SUFFIXES = (".mp4", ".avi", ".mkv", ".mov", ".webm")


def out_folder_problem(out: Path) -> str | None:
    """Why ``out`` cannot be the demo's output folder, or None.

    The demo writes a folder (its video, contact sheet and statistics). A name ending like a
    video file (``--out result.mp4``) would become a folder of that name with the video inside,
    which no one looking for ``result.mp4`` finds; an existing file cannot be made a folder.

    Parameters
    ----------
    out : Path
        The ``--out`` path.

    Returns
    -------
    str or None
        The reason and the way out, or None where the folder can be used (it exists, or can be made).
    """
    if out.exists() and not out.is_dir():
        return (
            "is a file; --out is the folder the demo writes into (its video is demo.mp4 or demo.avi "
            "there): give a folder, e.g. --out out"
        )
    if not out.exists() and out.suffix.lower() in VIDEO_SUFFIXES:
        return (
            "names a video file; --out is the folder the demo writes into (its video is demo.mp4 or "
            f"demo.avi there, with a contact sheet and the statistics): give a folder, e.g. --out {out.with_suffix('').name}"
        )
    return None


def main(args: argparse.Namespace) -> int:
    """``counterpart demo``: run the graph, then write the video's contact sheet and the statistics.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed ``demo`` options.

    Returns
    -------
    int
        Exit status: 0 ok; 2 bad options or launch file; the graph's exit code, or 1 when no video
        was written or the run summary reports a problem.
    """
    from counterpart.bus.cli_launch import load_checked
    from counterpart.bus.launchfile import LaunchError
    from counterpart.bus.params import ParamError
    from counterpart.bus.runner import setup_logging
    from counterpart.bus.supervisor import Launcher, prune_run_dirs

    setup_logging("demo")
    log = logging.getLogger("demo")
    if args.realtime and args.live:
        print(
            "counterpart demo: --live is real time already; --realtime is for a file or the built-in scene",
            file=sys.stderr,
        )
        return 2
    if args.input and not Path(args.input).exists():
        print(f"counterpart demo: --input {args.input}: no such file or folder", file=sys.stderr)
        return 2
    out = Path(args.out).resolve()
    problem = out_folder_problem(out)
    if problem:
        print(f"counterpart demo: --out {args.out}: {problem}", file=sys.stderr)
        return 2
    out.mkdir(parents=True, exist_ok=True)
    print("counterpart demo: preparing the default models (cached after the first run)", file=sys.stderr)
    try:
        ensure_models(serve=args.serve)
    except KeyboardInterrupt:
        print(
            "counterpart demo: interrupted while the default models were built; those finished are kept "
            "and the next run builds the rest",
            file=sys.stderr,
        )
        return 130
    except BrokenProcessPool:
        print(
            "counterpart demo: a process building the default models died (killed, or out of memory); "
            "those finished are kept and the next run builds the rest",
            file=sys.stderr,
        )
        return 1
    video = out / "demo.mp4"
    file, sets = _graph_file(args)
    sets += [
        f"renderer.video={video}",
        f"renderer.serve={'true' if args.serve else 'false'}",
        f"renderer.port={args.port}",
    ]
    if args.camera:
        sets.append(f"calibration.file={Path(args.camera).resolve()}")
    if args.frames:
        sets.append(f"camera.max_frames={args.frames}")
    if args.serve and not args.live:
        sets.append("camera.loop=true")  # keep the page alive until Ctrl-C
    sets += args.set or []
    try:
        graph = load_checked(file, sets, None)
    except (LaunchError, ParamError) as exc:
        print(f"counterpart demo: {exc}", file=sys.stderr)
        return 2
    prune_run_dirs()
    for stale in out.glob("demo.*"):  # a video of an earlier run must not pass for this one's
        if stale.suffix in (".mp4", ".avi"):
            stale.unlink()
    launcher = Launcher(graph)
    log.info(
        "running %s (Ctrl-C to stop)%s",
        graph.file,
        (f"; live page on http://127.0.0.1:{args.port}" if args.port else "; the renderer logs the page's address")
        if args.serve
        else "",
    )
    code = launcher.run()
    launcher.cleanup()
    videos = [p for p in sorted(out.glob("demo.*")) if p.suffix in (".mp4", ".avi")]
    sheet = out / "demo_contact_sheet.png"
    if videos and contact_sheet(videos[0], sheet):
        print(f"video:         {videos[0]}")
        print(f"contact sheet: {sheet}")
    else:
        print("counterpart demo: no video was written", file=sys.stderr)
        code = code or 1
    summary = report(launcher.run_dir, out)
    problem = summary.problem()
    if code in (128 + signal.SIGINT, 128 + signal.SIGTERM):
        kept = "; the video and the statistics hold the frames done" if videos else ""
        print(f"counterpart demo: stopped (Ctrl-C or a stop signal){kept}", file=sys.stderr)
    elif code:
        why = "".join(f"\n  {name}: {reason}" for name, reason in launcher.failures().items())
        print(f"counterpart demo: the graph ended with exit code {code}{why}", file=sys.stderr)
    elif problem:
        print(f"counterpart demo: {problem}", file=sys.stderr)
        code = 1
    return code
