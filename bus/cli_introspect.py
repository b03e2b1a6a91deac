"""``counterpart node list`` and ``counterpart topic list|echo|hz`` against a running launch."""

from __future__ import annotations

import argparse
import dataclasses
import functools
import json
import os
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from . import registry


def quiet_broken_pipe(main: Callable[[argparse.Namespace], int]) -> Callable[[argparse.Namespace], int]:
    """``main`` ending quietly when its reader goes away (``counterpart topic list | head``), as
    command-line tools do, instead of with a BrokenPipeError traceback.

    Parameters
    ----------
    main : callable
        A command's entry point taking the parsed arguments and returning the exit status.

    Returns
    -------
    callable
        The wrapped entry point; it returns 1 on a broken pipe.
    """

    @functools.wraps(main)
    def wrapper(args: argparse.Namespace) -> int:
        try:
            return main(args)
        except BrokenPipeError:
            # what is still buffered would raise again when Python flushes stdout at exit
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
            os.close(devnull)
            return 1

    return wrapper


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--run", default=None, help="run directory of the launch (default: the newest)")


def add_arguments_node(p: argparse.ArgumentParser) -> None:
    """Add the ``counterpart node`` actions (``list``) to ``p``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser.
    """
    sub = p.add_subparsers(dest="action", required=True)
    _common(sub.add_parser("list", help="nodes, pids, restarts and ports"))


def add_arguments_topic(p: argparse.ArgumentParser) -> None:
    """Add the ``counterpart topic`` actions (``list``, ``echo``, ``hz``) to ``p``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser.
    """
    sub = p.add_subparsers(dest="action", required=True)
    _common(sub.add_parser("list", help="topics with their types, publishers and subscribers"))
    e = sub.add_parser("echo", help="print messages of a topic (arrays summarised)")
    _common(e)
    e.add_argument("topic")
    e.add_argument("-n", "--count", type=int, default=0, help="stop after N messages (0: until Ctrl-C)")
    e.add_argument("--timeout", type=float, default=0, help="give up after this many seconds without a message")
    h = sub.add_parser("hz", help="message rate of a topic")
    _common(h)
    h.add_argument("topic")
    h.add_argument("--window", type=float, default=2.0, help="seconds per report")
    h.add_argument("-n", "--reports", type=int, default=0, help="stop after N reports (0: until Ctrl-C)")


@quiet_broken_pipe
def main_node(args: argparse.Namespace) -> int:
    """``counterpart node list``: print the launch's nodes, pids, restarts and ports.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments (``run``).

    Returns
    -------
    int
        Exit status: 0, or 1 when the launch's registry cannot be read.
    """
    try:
        reg = registry.read(args.run)
    except registry.RegistryError as exc:
        print(f"counterpart node: {exc}", file=sys.stderr)
        return 1
    print(f"# {reg['launch_file']} ({'running' if reg['alive'] else 'ended'}, run dir {reg['run_dir']})")
    for name, n in reg["nodes"].items():
        state = f"pid {n['pid']}" if n["pid"] else f"exited {n['exit_code']}"
        ins = ", ".join(f"{p}<-{v['topic']}({v['policy']})" for p, v in n["inputs"].items()) or "-"
        outs = ", ".join(f"{p}->{v['topic']}" for p, v in n["outputs"].items() if p != "stats") or "-"
        print(f"{name:16s} {n['module']:32s} {state:12s} restarts {n['restarts']}  in: {ins}  out: {outs}")
    return 0


def summarise(value: Any) -> Any:
    """A JSON-able view of a message: arrays become their dtype, shape and a few statistics.

    Parameters
    ----------
    value : Any
        A message, or a field of one (arrays, dataclasses, lists, tuples, dicts, bytes, scalars).

    Returns
    -------
    Any
        The same structure with arrays as ``{dtype, shape, min, max, mean[, values]}`` and bytes as
        ``"<n bytes>"``.
    """
    if isinstance(value, np.ndarray):
        info: dict[str, Any] = {"dtype": str(value.dtype), "shape": list(value.shape)}
        if value.size and value.dtype.kind in "biuf":
            info.update(min=float(value.min()), max=float(value.max()), mean=float(value.mean()))
        if value.size and value.size <= 16:
            info["values"] = value.tolist()
        return info
    if dataclasses.is_dataclass(value):
        return {f.name: summarise(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, (list, tuple)):
        return [summarise(v) for v in value]
    if isinstance(value, dict):
        return {k: summarise(v) for k, v in value.items()}
    if isinstance(value, bytes):
        return f"<{len(value)} bytes>"
    return value


def _subscriber(args: argparse.Namespace):
    import zmq

    from .transport import LATEST, Subscriber

    reg = registry.read(args.run)
    if not reg["alive"]:
        raise registry.RegistryError(f"the launch in {reg['run_dir']} is not running")
    return Subscriber(
        zmq.Context.instance(), args.topic, registry.topic_endpoints(reg, args.topic), LATEST, untyped=True
    )


@quiet_broken_pipe
def main_topic(args: argparse.Namespace) -> int:
    """``counterpart topic list|echo|hz``: list the topics, print a topic's messages or its rate.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments (``action``, ``run``, and ``topic``, ``count``, ``timeout``,
        ``window``, ``reports`` as the action takes them).

    Returns
    -------
    int
        Exit status: 0 when done, at the end of the stream or after the counts asked for; 1 when the
        launch's registry cannot be read, the launch is not running, or ``echo`` timed out.
    """
    try:
        if args.action == "list":
            reg = registry.read(args.run)
            print(f"# {reg['launch_file']} ({'running' if reg['alive'] else 'ended'}, run dir {reg['run_dir']})")
            for topic, t in sorted(reg["topics"].items()):
                subs = ", ".join(t["subscribers"]) or "-"
                print(f"{topic:28s} {t['type']:28s} from {t['publisher']:20s} to {subs}")
            return 0
        sub = _subscriber(args)
    except registry.RegistryError as exc:
        print(f"counterpart topic: {exc}", file=sys.stderr)
        return 1
    from counterpart.messages import EndOfStream, schema_id
    from counterpart.messages.codec import UntypedMessage

    start = last = time.monotonic()
    n = 0
    window: list[float] = []
    reports = 0
    while True:
        ready = any(s.poll(100) for s in sub.sockets)
        now = time.monotonic()
        msg = sub.receive() if ready else None
        if msg is None:
            if args.action == "echo" and args.timeout and now - last > args.timeout:
                print(f"counterpart topic: no message on {args.topic} for {args.timeout:.1f} s", file=sys.stderr)
                return 1
        elif isinstance(msg, EndOfStream):
            print(f"# end of stream on {args.topic}", file=sys.stderr)
            return 0
        else:
            last = now
            n += 1
            if args.action == "echo":
                if isinstance(msg, UntypedMessage):
                    kind, body = msg.schema, summarise(msg.fields)
                else:
                    kind, body = schema_id(msg), summarise(msg)
                print(json.dumps({"topic": args.topic, "type": kind, "msg": body}), flush=True)
                if args.count and n >= args.count:
                    return 0
            else:
                window.append(now)
        if args.action == "hz" and now - start >= args.window:
            if len(window) >= 2:
                dt = np.diff(window)
                print(
                    f"{args.topic}: {1.0 / np.mean(dt):.2f} Hz  min {dt.min() * 1e3:.1f} ms  max {dt.max() * 1e3:.1f} ms  "
                    f"n={len(window)} drops={sub.drops}",
                    flush=True,
                )
            else:
                print(f"{args.topic}: no messages in {args.window:.1f} s", flush=True)
            window, start = [], now
            reports += 1
            if args.reports and reports >= args.reports:
                return 0
