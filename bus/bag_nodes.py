"""Bag nodes: :class:`Recorder` writes topics to a bag, :class:`Player` publishes a bag's topics.

In a launch file::

    nodes:
      record:
        run: counterpart.bus.bag_nodes:Recorder
        params: {path: run.mcap, topics: [camera/frames, tracker/pose]}
      play:
        run: counterpart.bus.bag_nodes:Player
        params: {path: run.mcap, lockstep: true, modules: [tests.graph_nodes]}

The recorder stores the wire parts exactly as received, without decoding arrays and without needing
the message classes (a schema it does not know is described from the wire header). The player
re-sends those parts byte for byte, then end of stream on every output.
"""

from __future__ import annotations

import importlib
import time
from pathlib import Path
from typing import Any

from counterpart.messages import REGISTRY
from counterpart.messages.codec import DEFAULT_LIMITS, DecodeError, read_header

from .bag import COMPRESSIONS, DEFAULT_CHUNK_SIZE, BagReader, BagWriter
from .node import STATS_PORT, Input, Node, Output
from .params import Param, ParamError
from .transport import RELIABLE, RawMessage


def _nonempty(v: Any) -> str | None:
    return None if v else "must not be empty"


def import_modules(modules: list[str], param: str = "modules") -> None:
    """Import the modules that register message classes.

    Parameters
    ----------
    modules : list of str
        Dotted module names.
    param : str
        The node parameter that named them, for the error message.

    Raises
    ------
    ParamError
        Naming the module that fails to import.
    """
    for name in modules:
        try:
            importlib.import_module(str(name))
        except ImportError as exc:
            raise ParamError(f"parameter {param!r}: cannot import module {name!r}: {exc}") from None


class Recorder(Node):
    """Writes every message of ``topics`` to the bag ``path`` (one input port per topic, named like
    the topic, of any type).

    Its inputs are reliable unless the launch file says ``policy: latest``: in a lockstep replay the
    recorder keeps every message (and the publishers wait for it); in a live graph (``latest``) it
    never holds a publisher back: it keeps up to ``queue`` messages per topic in order while the
    disk lags, and drops and counts (``drops`` in its stats) what does not fit.

    The bag is finished (summary and footer written) on end of stream and on every stop; a crash
    leaves it readable up to the last flush (at most ``flush_period`` seconds lost).

    Parameters
    ----------
    path : str
        Bag file to write (.mcap).
    topics : list of str
        Topics to record (at least one; not ``stats``).
    compression : str
        Chunk compression, one of ``COMPRESSIONS`` (default ``"zstd"``).
    chunk_size : int
        Bytes per chunk before it is written.
    flush_period : float
        Seconds between flushes (bounds what a crash loses).
    overwrite : bool
        Replace an existing file.
    modules : list of str
        Modules to import so that schemas are described from their classes.
    queue : int
        Latest policy: messages per topic kept while the recorder lags; the rest are dropped and counted.
    """

    params = {
        "path": Param(str, "", "bag file to write (.mcap)", check=_nonempty),
        "topics": Param(list, None, "topics to record", check=_nonempty),
        "compression": Param(str, "zstd", "chunk compression", choices=tuple(COMPRESSIONS)),
        "chunk_size": Param(int, DEFAULT_CHUNK_SIZE, "bytes per chunk before it is written", min=1024),
        "flush_period": Param(float, 0.5, "seconds between flushes (bounds what a crash loses)", min=0.01),
        "overwrite": Param(bool, False, "replace an existing file"),
        "modules": Param(list, [], "modules to import so that schemas are described from their classes"),
        "queue": Param(
            int,
            64,
            "latest policy: messages per topic kept while the recorder lags; the rest are dropped and counted",
            min=1,
            max=100_000,
        ),
    }
    timer_period = 0.1

    @classmethod
    def ports(cls, params: dict[str, Any]) -> tuple[dict[str, Input], dict[str, Output]]:
        topics = params.get("topics") or []
        if not topics:
            raise ParamError("parameter 'topics': name at least one topic to record")
        if any(not isinstance(t, str) or not t for t in topics):
            raise ParamError(f"parameter 'topics': expected a list of topic names, got {topics!r}")
        if STATS_PORT in topics:
            raise ParamError(f"parameter 'topics': {STATS_PORT!r} is reserved; record a node's stats as NODE/stats")
        return {t: Input(None, RELIABLE, f"recorded topic {t}", raw=True, queue=params["queue"]) for t in topics}, {}

    def setup(self) -> None:
        import_modules(self.p["modules"])
        self.writer = BagWriter(
            self.p["path"],
            compression=self.p["compression"],
            chunk_size=self.p["chunk_size"],
            flush_period=self.p["flush_period"],
            overwrite=self.p["overwrite"],
            metadata={"recorder": self.name, "topics": ",".join(self.p["topics"])},
        )
        self.log.info("recording %s to %s", ", ".join(self.p["topics"]), self.writer.path)

    def on_message(self, port: str, msg: RawMessage) -> None:
        self.writer.write(msg.topic, msg.parts, time.monotonic_ns(), msg.header)

    def on_timer(self) -> None:
        self.writer.tick()

    def teardown(self) -> None:
        writer = getattr(self, "writer", None)
        if writer is not None:
            writer.close()
            self.log.info(
                "wrote %d messages (%.1f MiB) to %s: %s",
                writer.count,
                writer.bytes / 2**20,
                writer.path,
                ", ".join(f"{t} {n}" for t, n in writer.counts.items()) or "-",
            )
            dropped = {t: sub.drops for t, sub in self._in.items() if sub.drops}
            if dropped:
                self.log.warning(
                    "could not keep %s message(s) while lagging (raise 'queue' to keep more)",
                    ", ".join(f"{t} {n}" for t, n in dropped.items()),
                )


def _rate_ok(v: float) -> str | None:
    return None if v >= 0 else "must be >= 0 (1 real time, N for xN, 0 as fast as possible)"


class Player(Node):
    """Publishes the messages of the bag ``path`` with their recorded timing, exactly as recorded.

    Outputs: one per recorded topic (after ``topics`` selection and ``remap``), named like the topic,
    typed by the recorded schema, which must be registered (name its module in ``modules``).
    End of stream goes out at the end.

    Parameters
    ----------
    path : str
        Bag file to play.
    rate : float
        Playback speed: 1 real time, N for N times faster, 0 as fast as possible.
    lockstep : bool
        Ignore timing and send as fast as the reliable subscribers take messages, nothing dropped; run
        alone (not launched), it also waits for one reliable subscriber per output before the first
        message.
    loop : bool
        Start again at the end (until stopped).
    topics : list of str
        Recorded topics to play (default: all).
    remap : dict of str to str
        Recorded topic -> published topic.
    modules : list of str
        Modules to import so that the bag's message classes are registered.
    """

    params = {
        "path": Param(str, "", "bag file to play", check=_nonempty),
        "rate": Param(float, 1.0, "playback speed: 1 real time, N for xN, 0 as fast as possible", check=_rate_ok),
        "lockstep": Param(bool, False, "as fast as reliable subscribers go, nothing dropped"),
        "loop": Param(bool, False, "play again from the start at the end"),
        "topics": Param(list, [], "recorded topics to play (default: all)"),
        "remap": Param(dict, {}, "recorded topic -> published topic"),
        "modules": Param(list, [], "modules to import so that the bag's message classes are registered"),
    }

    @classmethod
    def selection(cls, params: dict[str, Any]) -> dict[str, tuple[str, str]]:
        """The topics to play for the given parameters.

        Parameters
        ----------
        params : dict of str to Any
            The node's parameters (``path``, ``topics``, ``remap``).

        Returns
        -------
        dict of str to tuple of (str, str)
            Recorded topic -> (published topic, schema id).

        Raises
        ------
        ParamError
            If the bag does not exist or cannot be read, a selected or remapped topic is not in it, or
            the published topics are not distinct (or one is ``stats``).
        """
        path = Path(params["path"])
        if not path.is_file():
            raise ParamError(f"parameter 'path': bag {path} does not exist")
        try:
            recorded = BagReader(path).topics()
        except ValueError as exc:
            raise ParamError(f"parameter 'path': {exc}") from None
        wanted = params.get("topics") or list(recorded)
        missing = [t for t in wanted if t not in recorded]
        if missing:
            raise ParamError(
                f"parameter 'topics': {', '.join(missing)} not in bag {path}; it holds {', '.join(recorded) or 'nothing'}"
            )
        remap = {str(k): str(v) for k, v in (params.get("remap") or {}).items()}
        unknown = sorted(set(remap) - set(recorded))
        if unknown:
            raise ParamError(
                f"parameter 'remap': {', '.join(unknown)} not in bag {path}; it holds {', '.join(recorded)}"
            )
        out = {t: (remap.get(t, t), recorded[t]) for t in wanted}
        published = [p for p, _ in out.values()]
        if len(set(published)) != len(published) or STATS_PORT in published:
            raise ParamError(f"parameter 'remap': published topics {published} must be distinct and not {STATS_PORT!r}")
        return out

    @classmethod
    def ports(cls, params: dict[str, Any]) -> tuple[dict[str, Input], dict[str, Output]]:
        import_modules(params.get("modules") or [])
        outputs = {}
        for topic, (port, sid) in cls.selection(params).items():
            msg_cls = REGISTRY.get(sid)
            if msg_cls is None:
                raise ParamError(
                    f"parameter 'modules': bag {params['path']} holds topic {topic!r} of message schema {sid!r}, "
                    f"which no imported module registers; name the module defining it in 'modules' "
                    f"(e.g. modules: [tests.graph_nodes]) or leave the topic out with 'topics'"
                )
            outputs[port] = Output(msg_cls, f"played from {topic}")
        return {}, outputs

    def setup(self) -> None:
        self.plan = self.selection(self.p)

    def _send_raw(self, port: str, parts: list[Any]) -> None:
        try:
            seq = read_header(parts[0], DEFAULT_LIMITS)["f"].get("seq", -1)
        except DecodeError:
            seq = -1
        self.publish_parts(port, parts, seq)

    def _wait_subscribers(self) -> None:
        for port, pub in self._out.items():
            if port == STATS_PORT:
                continue
            pub.expected = max(pub.expected, 1)
            if not pub.wait_for_subscribers() and not self.stopping:
                self.log.warning(
                    "no reliable subscriber on %s after %.0f s; playing anyway", pub.topic, pub.barrier_timeout
                )

    def _sleep_until(self, t: float) -> None:
        while not self.stopping:
            left = t - time.monotonic()
            if left <= 0:
                return
            time.sleep(min(left, 0.1))
            self._maybe_stats()

    def generate(self) -> None:
        lockstep, rate = self.p["lockstep"], self.p["rate"]
        if lockstep and not self.spec.get("supervised", False):
            self._wait_subscribers()
        reader = BagReader(self.p["path"])
        passes = 0
        while not self.stopping:
            first: int | None = None
            wall0 = time.monotonic()
            sent = 0
            for rec in reader.records(list(self.plan)):
                if self.stopping:
                    return
                if not lockstep and rate > 0:
                    if first is None:
                        first = rec.log_time
                    self._sleep_until(wall0 + (rec.log_time - first) / 1e9 / rate)
                    if self.stopping:
                        return
                self._send_raw(self.plan[rec.topic][0], rec.parts)
                sent += 1
            passes += 1
            if reader.truncated:
                self.log.warning(
                    "bag %s is truncated (%s); played the %d messages before the cut",
                    reader.path,
                    reader.error,
                    reader.recovered,
                )
            self.log.info("played %d messages (pass %d)", sent, passes)
            if not self.p["loop"] or sent == 0:
                return


__all__ = ["Recorder", "Player", "import_modules"]
