"""``counterpart bag record|play|info|export``.

- ``record`` subscribes to topics of a running launch, found through its registry, and writes them
  to a bag until Ctrl-C, ``--duration``, end of stream on every recorded topic, or the launch going
  away; the bag is always finished (a SIGKILL leaves it readable up to the last flush). It never
  holds a publisher back: it reads each topic's lossy socket with a queue of ``--queue`` messages,
  so it loses nothing while it keeps up and counts what it could not keep when it lags (a slow
  disk, Ctrl-Z). ``--lossless`` subscribes reliably instead (lockstep replays: every message, the
  publishers wait for the recorder).
- ``play`` publishes a bag on the *standalone* endpoints (the folder ``counterpart run`` uses), so
  nodes started with ``counterpart run`` find the topics by name. It does not inject into a running
  launch: there every topic already has its publisher bound; to replay inside a graph, put
  ``counterpart.bus.bag_nodes:Player`` in the launch file instead.
- ``info`` prints topics, types, counts, time range and schemas (``--json`` for the raw dict).
- ``export`` writes ``DIR/<topic>.jsonl`` (one line per message: its scalar fields, ``_log_time``
  and ``_type``) and each array as ``DIR/<topic>/<index>_<field>.npy``, or ``.png`` for uint8 images
  (H x W or H x W x 3, both sides >= 8 pixels), referenced by file name relative to DIR.
"""

from __future__ import annotations

import argparse
import json
import re
import signal
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from . import registry
from .cli_introspect import quiet_broken_pipe
from .params import ParamError

MIN_IMAGE_SIDE = 8
#: messages per topic a recorder keeps while it lags (live graphs), before it drops and counts them
RECORD_QUEUE = 64


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Add the ``record``, ``play``, ``info`` and ``export`` sub-commands and their options.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The ``counterpart bag`` parser.
    """
    sub = p.add_subparsers(dest="action", required=True)
    r = sub.add_parser("record", help="record topics of a running launch to a bag")
    r.add_argument("-t", "--topic", action="append", default=[], metavar="TOPIC", help="topic to record (repeatable)")
    r.add_argument("--all", action="store_true", help="record every topic but the nodes' stats topics")
    r.add_argument("-o", "--output", required=True, metavar="FILE", help="bag file to write (.mcap)")
    r.add_argument("--run", default=None, help="run directory of the launch (default: the newest)")
    r.add_argument("--duration", type=float, default=0.0, metavar="S", help="stop after S seconds (0: no limit)")
    r.add_argument(
        "--queue",
        type=int,
        default=RECORD_QUEUE,
        metavar="N",
        help=f"messages kept per topic while the recorder lags; beyond it they are dropped and counted "
        f"(default {RECORD_QUEUE})",
    )
    r.add_argument(
        "--lossless",
        action="store_true",
        help="subscribe reliably: nothing is lost, but a lagging or paused recorder holds the publishers "
        "back (for lockstep replays)",
    )
    r.add_argument("--compression", default="zstd", choices=("zstd", "lz4", "none"))
    r.add_argument("--overwrite", action="store_true", help="replace an existing bag file")
    r.add_argument(
        "--module",
        action="append",
        default=[],
        metavar="MODULE",
        help="import MODULE so its message schemas are described from their classes",
    )

    pl = sub.add_parser("play", help="publish a bag on the standalone endpoints (see counterpart run)")
    pl.add_argument("file")
    speed = pl.add_mutually_exclusive_group()
    speed.add_argument("--rate", type=float, default=1.0, metavar="R", help="playback speed (1: real time)")
    speed.add_argument("--fast", action="store_true", help="as fast as possible")
    speed.add_argument(
        "--lockstep",
        action="store_true",
        help="wait for a reliable subscriber per topic, then go as fast as they consume",
    )
    pl.add_argument("--loop", action="store_true", help="play again from the start at the end")
    pl.add_argument("--remap", action="append", default=[], metavar="A=B", help="publish recorded topic A as B")
    pl.add_argument("--topics", nargs="+", default=[], metavar="TOPIC", help="recorded topics to play (default: all)")
    pl.add_argument(
        "--module",
        action="append",
        default=[],
        metavar="MODULE",
        help="import MODULE so the bag's message classes are registered",
    )

    i = sub.add_parser("info", help="topics, types, counts, duration and schemas of a bag")
    i.add_argument("file")
    i.add_argument("--json", action="store_true", help="print the information as one JSON object")

    e = sub.add_parser("export", help="write a bag's messages as JSON lines, .npy and .png files")
    e.add_argument("file")
    e.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder")
    e.add_argument("--topics", nargs="+", default=[], metavar="TOPIC", help="topics to export (default: all)")


@quiet_broken_pipe
def main(args: argparse.Namespace) -> int:
    """Run the sub-command ``args.action``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (:func:`add_arguments`).

    Returns
    -------
    int
        The sub-command's exit status.
    """
    return {"record": record, "play": play, "info": info, "export": export}[args.action](args)


def _err(msg: str) -> int:
    print(f"counterpart bag: {msg}", file=sys.stderr)
    return 1


# ---------------------------------------------------------------------------------------- record


def record(args: argparse.Namespace) -> int:
    """``counterpart bag record``: record topics of a running launch to a bag (module docstring).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (:func:`add_arguments`).

    Returns
    -------
    int
        Exit status: 0 on success, 1 with the error on stderr.
    """
    import zmq

    from counterpart.messages import EndOfStream

    from .bag import BagWriter
    from .bag_nodes import import_modules
    from .transport import LATEST, RELIABLE, Subscriber

    try:
        import_modules(args.module, "--module")
        reg = registry.read(args.run)
    except (registry.RegistryError, ParamError) as exc:
        return _err(str(exc))
    if not reg["alive"]:
        return _err(f"the launch in {reg['run_dir']} is not running")
    topics = list(dict.fromkeys(args.topic))
    if args.all:
        topics += [
            t for t in sorted(reg["topics"]) if t not in topics and reg["topics"][t]["type"] != "system.NodeStats/1"
        ]
    if not topics:
        return _err("name topics with -t TOPIC or pass --all; topics: " + ", ".join(sorted(reg["topics"])))
    try:
        endpoints = {t: registry.topic_endpoints(reg, t) for t in topics}
        writer = BagWriter(
            args.output,
            compression=args.compression,
            overwrite=args.overwrite,
            metadata={
                "recorder": "counterpart bag record",
                "launch": str(reg.get("launch_file", "")),
                "topics": ",".join(topics),
            },
        )
    except (registry.RegistryError, FileExistsError, OSError) as exc:
        return _err(str(exc))

    stop: list[str] = []

    def on_signal(signum: int, frame: Any) -> None:
        if stop:  # a second Ctrl-C: leave now, the finally block still finishes the bag
            raise KeyboardInterrupt
        stop.append(signal.Signals(signum).name)

    old = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    ctx = zmq.Context.instance()
    if args.queue < 1:
        return _err(f"--queue {args.queue}: keep at least 1 message")
    policy = RELIABLE if args.lossless else LATEST
    subs = {
        t: Subscriber(ctx, t, ep, policy, raw=True, queue=args.queue, publisher=reg["topics"][t].get("node"))
        for t, ep in endpoints.items()
    }
    poller = zmq.Poller()
    owner = {}
    for t, s in subs.items():
        for sock in s.sockets:
            poller.register(sock, zmq.POLLIN)
            owner[sock] = t
    print(f"recording {', '.join(topics)} to {writer.path} (Ctrl-C to stop)", file=sys.stderr)
    start = last_report = time.monotonic()
    reason = "stopped"
    try:
        while not stop:
            for sock, _ in poller.poll(100):
                sub = subs[owner[sock]]
                while True:  # drain what is queued so progress keeps up with fast topics
                    msg = sub.receive()
                    if msg is None:
                        break
                    if not isinstance(msg, EndOfStream):
                        writer.write(msg.topic, msg.parts, time.monotonic_ns(), msg.header)
            writer.tick()
            now = time.monotonic()
            if all(s.ended for s in subs.values()):
                reason = "end of stream on every topic"
                break
            if args.duration and now - start >= args.duration:
                reason = f"{args.duration:g} s elapsed"
                break
            if now - last_report >= 1.0:
                last_report = now
                _progress(writer, now - start, subs)
                try:
                    gone = not registry.read(args.run)["alive"]
                except registry.RegistryError:
                    gone = True
                if gone:
                    reason = "the launch ended"
                    break
        else:
            reason = f"{stop[0]} received"
    except KeyboardInterrupt:
        reason = "interrupted"
    finally:
        for s in subs.values():
            s.close()
        writer.close()
        for s, h in old.items():
            signal.signal(s, h)
    _progress(writer, time.monotonic() - start, subs)
    dropped = sum(s.drops for s in subs.values())
    lost = f"; {dropped} could not be kept (the recorder lagged; --lossless keeps all)" if dropped else ""
    print(f"done ({reason}): {writer.count} messages in {writer.path}{lost}", file=sys.stderr)
    return 0


def _progress(writer: Any, elapsed: float, subs: dict[str, Any]) -> None:
    per_topic = "  ".join(f"{t} {n}" for t, n in writer.counts.items()) or "-"
    dropped = sum(s.drops for s in subs.values())
    print(
        f"[{elapsed:6.1f} s] {writer.count} messages, {writer.bytes / 2**20:.1f} MiB, {dropped} dropped  {per_topic}",
        file=sys.stderr,
        flush=True,
    )


# ------------------------------------------------------------------------------------------ play


def play(args: argparse.Namespace) -> int:
    """``counterpart bag play``: publish a bag on the standalone endpoints (module docstring).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (:func:`add_arguments`).

    Returns
    -------
    int
        Exit status: the player's, or 1 with the error on stderr.
    """
    from .bag_nodes import Player
    from .node import standalone_spec
    from .params import parse_assignments
    from .runner import setup_logging

    setup_logging("bag play")
    try:
        remap = parse_assignments(args.remap, "--remap")
        params = {
            "path": args.file,
            "rate": 0.0 if args.fast or args.lockstep else args.rate,
            "lockstep": args.lockstep,
            "loop": args.loop,
            "topics": args.topics,
            "remap": remap,
            "modules": args.module,
        }
        spec = standalone_spec("bag_play", Player, params, {}, {})
    except (ParamError, ValueError) as exc:
        return _err(str(exc))
    spec["module"] = "counterpart.bus.bag_nodes:Player"
    outs = [f"{t}" for t in spec["outputs"] if t != "stats"]
    print(f"playing {args.file} on {', '.join(outs)} (standalone endpoints)", file=sys.stderr)
    return Player(spec).run()


# ------------------------------------------------------------------------------------------ info


def info(args: argparse.Namespace) -> int:
    """``counterpart bag info``: print a bag's topics, types, counts, time range and schemas.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (:func:`add_arguments`).

    Returns
    -------
    int
        Exit status: 0 on success, 1 with the error on stderr.
    """
    from .bag import BagReader

    try:
        data = BagReader(args.file).info()
    except (FileNotFoundError, ValueError) as exc:
        return _err(str(exc))
    if args.json:
        print(json.dumps(data))
        return 0
    state = "complete" if data["complete"] else f"TRUNCATED ({data['error']}; {data['messages']} messages recovered)"
    meta = data["metadata"]
    print(f"path:       {data['path']}")
    print(f"size:       {data['size_bytes'] / 2**20:.2f} MiB, {state}")
    if meta.get("start_wall_time"):
        print(f"recorded:   {meta['start_wall_time']} on {meta.get('host', '?')} by {meta.get('recorder', '?')}")
    print(f"duration:   {data['duration_s']:.3f} s  (monotonic ns {data['start_ns']} .. {data['end_ns']})")
    print(f"messages:   {data['messages']}")
    print("topics:")
    width = max((len(t) for t in data["topics"]), default=0)
    for topic, t in data["topics"].items():
        rate = t["count"] / data["duration_s"] if data["duration_s"] > 0 else 0.0
        print(f"  {topic:{width}s}  {t['count']:8d} msgs  {rate:8.2f} Hz  {t['type']}")
    print("schemas:")
    for sid, d in data["schemas"].items():
        fields = ", ".join(f"{k}: {v}" for k, v in (d.get("fields") or {}).items())
        print(f"  {sid}{' (inferred from the wire)' if d.get('inferred') else ''}: {fields}")
    return 0


# ---------------------------------------------------------------------------------------- export


def safe_name(topic: str) -> str:
    """A file name for a topic: characters other than letters, digits, ``_.-`` become ``_``.

    Parameters
    ----------
    topic : str
        Topic name.

    Returns
    -------
    str
        The file name (``_`` for an empty topic).
    """
    return re.sub(r"[^A-Za-z0-9_.-]", "_", topic) or "_"


def is_image(a: np.ndarray) -> bool:
    """Whether an array is exported as an image.

    Parameters
    ----------
    a : ndarray
        A message's array.

    Returns
    -------
    bool
        True for uint8 H x W or H x W x 3 with both sides at least ``MIN_IMAGE_SIDE`` pixels.
    """
    return (
        a.dtype == np.uint8
        and (a.ndim == 2 or (a.ndim == 3 and a.shape[2] == 3))
        and min(a.shape[:2]) >= MIN_IMAGE_SIDE
    )


def _jsonable(value: Any, out_dir: Path, rel: str, stem: str, written: list[int]) -> Any:
    """``value`` with arrays (and bytes) replaced by the names of the files they were written to."""
    if isinstance(value, np.ndarray):
        if value.size == 0:
            return []
        if is_image(value):
            import cv2

            name = f"{rel}/{stem}.png"
            if not cv2.imwrite(str(out_dir / name), value):
                raise OSError(f"cv2.imwrite failed for {out_dir / name}")
        else:
            name = f"{rel}/{stem}.npy"
            np.save(out_dir / name, value)
        written[0] += 1
        return name
    if isinstance(value, bytes):
        name = f"{rel}/{stem}.bin"
        (out_dir / name).write_bytes(value)
        written[0] += 1
        return name
    if isinstance(value, dict):
        return {k: _jsonable(v, out_dir, rel, f"{stem}_{safe_name(str(k))}", written) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v, out_dir, rel, f"{stem}_{i}", written) for i, v in enumerate(value)]
    return value


def export_bag(path: str | Path, out_dir: str | Path, topics: list[str] | None = None) -> dict[str, int]:
    """Export a bag (see the module docstring). Needs no message class: fields are decoded from the
    self-describing wire header.

    Parameters
    ----------
    path : str or Path
        The bag file.
    out_dir : str or Path
        Output folder (created when missing).
    topics : list of str or None, default=None
        Topics to export (None or empty: all).

    Returns
    -------
    dict of str to int
        Messages written per topic.

    Raises
    ------
    ValueError
        For topics not in the bag.
    OSError
        When an image cannot be written.
    """
    from .bag import BagReader, decode_fields

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    reader = BagReader(path)
    recorded = reader.topics()
    missing = [t for t in topics or [] if t not in recorded]
    if missing:
        raise ValueError(f"topics {', '.join(missing)} are not in bag {path}; it holds {', '.join(recorded)}")
    files: dict[str, Any] = {}
    counts: dict[str, int] = {}
    written = [0]
    try:
        for rec in reader.records(topics or None):
            rel = safe_name(rec.topic)
            if rec.topic not in files:
                (out / rel).mkdir(exist_ok=True)
                files[rec.topic] = open(out / f"{rel}.jsonl", "w")
            i = counts.get(rec.topic, 0)
            sid, fields = decode_fields(rec.parts)
            line = {"_log_time": rec.log_time, "_type": sid}
            line.update({k: _jsonable(v, out, rel, f"{i:06d}_{safe_name(k)}", written) for k, v in fields.items()})
            files[rec.topic].write(json.dumps(line) + "\n")
            counts[rec.topic] = i + 1
    finally:
        for f in files.values():
            f.close()
    for rel in {safe_name(t) for t in files}:
        if not any((out / rel).iterdir()):
            (out / rel).rmdir()
    return counts


def export(args: argparse.Namespace) -> int:
    """``counterpart bag export``: write a bag's messages as JSON lines, ``.npy`` and ``.png`` files.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line (:func:`add_arguments`).

    Returns
    -------
    int
        Exit status: 0 on success, 1 with the error on stderr.
    """
    try:
        counts = export_bag(args.file, args.output, args.topics or None)
    except (FileNotFoundError, ValueError, OSError) as exc:
        return _err(str(exc))
    for topic, n in counts.items():
        print(f"{topic}: {n} messages -> {Path(args.output) / (safe_name(topic) + '.jsonl')}")
    return 0
