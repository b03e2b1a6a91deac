"""The default video-texture avatar, built from the simulator when no avatar file is given."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

#: seconds of simulated recording the default avatar learns from
DEFAULT_SECONDS = 60.0


def build_default_avatar(
    progress: Callable[[str], None] | None = None, seconds: float = DEFAULT_SECONDS, seed: int = 0
) -> tuple[Any, dict[str, Any]]:
    """(model, training summary): the listener of a simulated conversation (``sim_recording``) with the
    simulator's exact masks and labels, learnt with the default configuration.

    Parameters
    ----------
    progress : callable of (str,) or None, default=None
        Receives progress lines while recording and fitting; ``None`` reports nothing.
    seconds : float, default=DEFAULT_SECONDS
        Seconds of simulated conversation to record and learn from.
    seed : int, default=0
        Seed of the simulated conversation.

    Returns
    -------
    model : object
        The fitted video-texture model (``fit_recording``), required to hold a ``"nod"``.
    summary : dict of str to object
        ``source`` (str), ``frames`` (int, frames recorded), ``fps`` (frames per second) and
        ``seconds`` (float, wall time of recording and fitting).
    """
    from .avatar_recording import sim_recording
    from .video_texture import fit_recording

    say = progress or (lambda s: None)
    t0 = time.perf_counter()
    rec, _ = sim_recording(seconds, seed=seed, say=say)
    model = fit_recording(rec, required=("nod",), progress=say)
    return model, {
        "source": f"sim (default): conversation listener, seed {seed}",
        "frames": int(len(rec.crops)),
        "fps": rec.fps,
        "seconds": round(time.perf_counter() - t0, 2),
    }
