"""The camera node: a frame source (file, folder, V4L2 device, simulator), paced, on topic ``frame``.

Run in a graph (``run: counterpart.nodes.camera``) or alone::

    python -m counterpart.nodes.camera --param source=clip.avi --param pacing=realtime

Exit codes: 0 after the source ends (end of stream sent); 3 when the source cannot be opened or
read (the error is logged and end of stream is sent first, so the rest of the graph ends cleanly);
2 for bad parameters (the launcher refuses the graph before anything starts).

``stamp`` of each Frame is CLOCK_MONOTONIC ns when the frame goes out: for a live device right after
capture, for a replay when its pacing releases it, so a replay looks like a camera running now.
An unpaced replay (``fast``, ``lockstep``) decodes in a prefetch thread a few frames ahead.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

import numpy as np

from counterpart.bus import Node, Output, Param, ParamError
from counterpart.messages import Frame

from .pacing import PACING_MODES, Pacer, Prefetch, convert, frames, output_size, replay_progress
from .sources import SourceError, make_source, parse_uri

#: exit code of a camera whose source failed (after logging it and sending end of stream)
EXIT_SOURCE_ERROR = 3
DEFAULT_SOURCE = "sim:handshake"


def _check_uri(value: str) -> str | None:
    try:
        parse_uri(value)
    except SourceError as exc:
        return str(exc)
    return None


class Camera(Node):
    """Publishes the frames of ``source`` on ``frame`` (messages.Frame), paced by ``pacing``."""

    outputs = {
        "frame": Output(
            Frame,
            "every frame, bgr8 or mono8; stamp: monotonic ns when the frame is released "
            "(live: right after capture; replay: after pacing)",
        )
    }
    params = {
        "source": Param(
            str,
            DEFAULT_SOURCE,
            "file:PATH or a path, folder:DIR[?pattern=*.png], v4l2:/dev/videoN, sim:SCENARIO[?seed=S]",
            check=_check_uri,
        ),
        "pacing": Param(
            str,
            "realtime",
            "realtime | rate (x rate) | fast | lockstep (fast; reliable consumers block it so nothing is dropped)",
            choices=PACING_MODES,
        ),
        "rate": Param(float, 1.0, "speed factor of pacing 'rate' (2.0: twice real time)", min=1e-3, max=1e3),
        "fps": Param(
            float, 0.0, "frame rate of the source, overriding its own (0: the source's; folders: 25)", min=0.0
        ),
        "width": Param(int, 0, "output width in pixels (0: the source's, or scaled with height)", min=0, max=16384),
        "height": Param(int, 0, "output height in pixels (0: the source's, or scaled with width)", min=0, max=16384),
        "max_side": Param(
            int,
            0,
            "with width and height 0: a source whose longer side is over this many pixels is scaled down to it, "
            "keeping its aspect ratio (0: never)",
            min=0,
            max=16384,
        ),
        "gray": Param(bool, False, "publish mono8 instead of bgr8"),
        "loop": Param(bool, False, "start again at start_frame at the end of a replay"),
        "max_frames": Param(int, 0, "stop after this many frames (0: no limit)", min=0),
        "start_frame": Param(int, 0, "skip this many frames of the source first", min=0),
        "prefetch": Param(
            int, 4, "frames an unpaced replay decodes ahead in a thread (0: decode inline)", min=0, max=64
        ),
        "progress_s": Param(
            float,
            10.0,
            "an unpaced replay (lockstep, fast) logs the frames published so far, of how many, the rate and "
            "the time left, every this many seconds (0: never)",
            min=0.0,
        ),
    }

    @classmethod
    def validate_params(cls, given: dict[str, Any], where: str = "") -> dict[str, Any]:
        """Check the parameters as :class:`Node` does, and that a live device is not asked to loop or skip.

        Parameters
        ----------
        given : dict
            The parameters given (launch file and overrides).
        where : str, default=""
            Where they come from, prefixed to error messages.

        Returns
        -------
        dict
            Every parameter, defaults filled in.

        Raises
        ------
        ParamError
            Naming the bad parameter.
        """
        p = super().validate_params(given, where)
        prefix = f"{where}: " if where else ""
        scheme = parse_uri(p["source"])[0]
        if p["loop"] and scheme == "v4l2":
            raise ParamError(f"{prefix}parameter 'loop': source {p['source']!r} is a live device and cannot loop")
        if p["start_frame"] and scheme == "v4l2":
            raise ParamError(f"{prefix}parameter 'start_frame': source {p['source']!r} is a live device")
        return p

    def setup(self) -> None:
        self.source = None
        self.prefetch: Prefetch | None = None
        self.published = 0

    def _fail(self, msg: str) -> None:
        self.log.error("%s", msg)
        self.exit_code = EXIT_SOURCE_ERROR

    def generate(self) -> None:
        p = self.p
        try:
            self.source = make_source(p["source"], fps=p["fps"] or None, width=p["width"], height=p["height"])
            self.source.open()
        except SourceError as exc:
            return self._fail(f"parameter 'source': {exc}")
        src = self.source
        size = output_size(src.size, p["width"], p["height"], p["max_side"])
        mode = "fast" if src.live and p["pacing"] in ("realtime", "rate") else p["pacing"]
        try:
            pacer = Pacer(mode, src.fps, p["rate"])
        except ValueError as exc:
            return self._fail(f"source {src.uri}: {exc}")
        if p["pacing"] == "lockstep" and not int(self.spec["outputs"]["frame"].get("reliable_subscribers", 0)):
            self.log.warning(
                "pacing 'lockstep' but no reliable subscriber on topic %r: consumers with the "
                "'latest' policy drop frames when they lag",
                self.spec["outputs"]["frame"]["topic"],
            )
        self.figures["source_fps"] = float(src.fps)
        self.log.info(
            "%s: %dx%d at %.3g fps (%s frames) -> %dx%d %s, pacing %s%s",
            src.uri,
            *src.size,
            src.fps,
            src.frame_count if src.frame_count is not None else "?",
            *size,
            "mono8" if p["gray"] else "bgr8",
            mode,
            f" (scaled down to camera.max_side {p['max_side']}; 0 keeps the source's size)"
            if size != output_size(src.size, p["width"], p["height"])
            else "",
        )
        stream: Iterator[tuple[np.ndarray, str, float]] = (
            (*convert(image, size, p["gray"]), t)
            for image, t in frames(src, p["start_frame"], p["loop"], p["max_frames"])
        )
        if p["prefetch"] and not src.live and not pacer.paced:
            # unpaced replay: decode (and convert) ahead in a thread so that it overlaps sending
            stream = self.prefetch = Prefetch(stream, p["prefetch"])
        seq = 0
        every_s = p["progress_s"] if not src.live and not pacer.paced else 0.0
        total = None if p["loop"] or src.frame_count is None else max(0, src.frame_count - p["start_frame"])
        if total is not None and p["max_frames"]:
            total = min(total, p["max_frames"])
        started = due = time.monotonic()
        try:
            while not self.stopping:
                if not pacer.wait(seq, lambda: self.stopping):
                    break
                item = next(stream, None)
                if item is None:
                    break
                image, encoding, source_time = item
                self.publish(
                    "frame",
                    Frame(
                        stamp=time.monotonic_ns(),
                        seq=seq,
                        image=image,
                        encoding=encoding,
                        source=src.uri,
                        source_time=source_time,
                        fps=float(src.fps),
                    ),
                )
                seq += 1
                if every_s and time.monotonic() >= due + every_s:
                    due = time.monotonic()
                    self.log.info("%s: %s", src.uri, replay_progress(seq, total, due - started))
        except (SourceError, ValueError) as exc:
            return self._fail(f"source {src.uri} failed at frame {seq}: {exc}")
        finally:
            self.published = seq
        bad = getattr(src, "undecodable", 0)
        self.figures["frames_undecodable"] = bad
        if bad:
            self.log.warning("%s: %d frame(s) did not decode and were skipped", src.uri, bad)
        if pacer.reanchors:
            self.log.warning("fell behind real time %d time(s); the schedule restarted each time", pacer.reanchors)
        self.log.info("%s: published %d frames", src.uri, seq)

    def teardown(self) -> None:
        if getattr(self, "prefetch", None) is not None:
            self.prefetch.close()  # before the source: the thread may be inside read()
        if getattr(self, "source", None) is not None:
            self.source.close()


NODE = Camera

if __name__ == "__main__":
    Camera.main()
