"""What the long offline commands (``counterpart track``, ``silhouettes``, ``calibrate``, ``learn avatar``)
share: the video arguments, progress lines, argument checks, the output path checked before the work,
and one way to end (exit 0 and a JSON summary, 2 on bad input with the reason, 130 on Ctrl-C saying
what was kept).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections.abc import Callable
from typing import Any


class FrameProgress:
    """A ``progress(done, declared)`` callback that prints ``[label] frame i/N, x fps`` on stderr.

    N is the file's declared frame count, or ``limit`` where that is fewer; left out when neither
    is known.

    Parameters
    ----------
    label : str
        Name printed in brackets.
    every : float, default=2.0
        Least time between two lines, seconds.
    limit : int or None, default=None
        The most frames the command will take (its ``--max-frames``); None: the whole file.
    """

    def __init__(self, label: str, every: float = 2.0, limit: int | None = None) -> None:
        self.label = label
        self.every = every
        self.limit = limit
        self.t0: float | None = None
        self.first = 0
        self.last = 0.0

    def __call__(self, done: int, declared: int) -> None:
        now = time.monotonic()
        if self.t0 is None:  # the rate counts from the first frame, not from the set-up before it
            self.t0 = self.last = now
            self.first = done
            return
        if now - self.last >= self.every:
            self.last = now
            total = min(t for t in (declared, self.limit) if t) if declared or self.limit else 0
            of = f"/{total}" if total else ""
            fps = (done - self.first) / (now - self.t0)
            print(f"[{self.label}] frame {done}{of}, {fps:.1f} fps", file=sys.stderr, flush=True)


def add_video_arguments(p: argparse.ArgumentParser, out_help: str, max_frames_help: str) -> None:
    """Add the arguments of a command over one recording (a video file or a folder of frames): ``video``, ``--out``, ``--train-frames``, ``--max-frames``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser.
    out_help : str
        Help text of ``--out``.
    max_frames_help : str
        Help text of ``--max-frames``.
    """
    p.add_argument("video", help="the video file (anything OpenCV decodes), or a folder of numbered PNG or JPEG frames")
    p.add_argument("--out", required=True, help=out_help)
    p.add_argument(
        "--train-frames",
        type=int,
        default=30,
        help="first frames the background model is fitted on (people may be in view)",
    )
    p.add_argument("--max-frames", type=int, default=None, help=max_frames_help)


def add_fov_argument(p: argparse.ArgumentParser) -> None:
    """Add ``--fov DEG``, the camera's horizontal field of view where the user knows it, to a parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The parser (of the subcommand).
    """
    p.add_argument(
        "--fov",
        type=float,
        default=0.0,
        metavar="DEG",
        help="the camera's horizontal field of view in degrees where known (its spec sheet): the focal length "
        "is then kept within about 5%% of it, where people alone cannot fix it (default 0: estimated)",
    )


def positive(args: argparse.Namespace, names: tuple[str, ...], command: str) -> bool:
    """Check that every named option that is set is at least 1.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments.
    names : tuple of str
        Attribute names of the options to check.
    command : str
        The command's name, for the message.

    Returns
    -------
    bool
        True when all are at least 1, else False after printing which is not on stderr.
    """
    for name in names:
        value = getattr(args, name)
        if value is not None and value < 1:
            print(f"counterpart {command}: --{name.replace('_', '-')} must be at least 1", file=sys.stderr)
            return False
    return True


def npz_name(out: str) -> str:
    """``out`` as numpy's ``savez`` writes it: with ``.npz`` added where it does not end so (the
    summary and the messages then name the file that is written); an existing folder as it is
    (:func:`out_problem` refuses it: ``results/`` is not a wish for ``results.npz``).
    """
    return out if out.endswith(".npz") or os.path.isdir(out) else out + ".npz"


def out_problem(out: str) -> str | None:
    """Why the output file ``out`` cannot be written, or None: said before a long run, which would
    otherwise be lost when it ends.

    Parameters
    ----------
    out : str
        The ``--out`` path.

    Returns
    -------
    str or None
        The reason and the way out.
    """
    path = os.path.abspath(out)
    folder = os.path.dirname(path)
    if os.path.isdir(path):
        return f"--out {out}: is a folder; give the name of a file (in it, or elsewhere) to write"
    if not os.path.isdir(folder):
        return (
            f"--out {out}: its folder {folder} does not exist; make it first (mkdir -p {folder}) or give another path"
        )
    if not os.access(folder, os.W_OK):
        return f"--out {out}: the folder {folder} is not writable; give a path in a folder you can write to"
    return None


def run_offline(command: str, out: str, work: Callable[[], dict[str, Any]]) -> int:
    """Run ``work`` (it writes ``out``) and print its summary as JSON; an ``out`` that cannot be
    written (:func:`out_problem`) is refused first.

    Parameters
    ----------
    command : str
        The command's name, for messages.
    out : str
        The output path ``work`` writes.
    work : callable
        Does the work and returns a JSON-serialisable summary.

    Returns
    -------
    int
        Exit status: 0 on success; 2 with the reason on a ValueError or OSError, or an ``out`` that
        cannot be written; 130 on Ctrl-C, saying whether ``out`` holds the frames done.
    """
    problem = out_problem(out)
    if problem:
        print(f"counterpart {command}: {problem}", file=sys.stderr)
        return 2
    try:
        summary = work()
    except (ValueError, OSError) as exc:
        print(f"counterpart {command}: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        saved = f"the frames done so far are in {out}" if os.path.exists(out) else "nothing written"
        print(f"counterpart {command}: interrupted; {saved}", file=sys.stderr)
        return 130
    print(json.dumps(summary))
    return 0
