"""Hostile input for one topic: what a broken or malicious publisher can put on the wire.

:func:`hostile_messages` yields multipart messages ``[topic, header, buffers...]`` for a topic of
message class ``msg_type``, going round the kinds of damage in :data:`KINDS`: random bytes, no
header, truncated and deeply nested msgpack, bad array specs (dtype, shape, buffer count), oversized
headers and arrays, wrong field types, well-formed messages of every other registered type, forged
end-of-stream messages and forged send counters, and, in between, well-formed messages of the
right type with odd contents (random shapes and dtypes, NaN, huge integers, random ``seq``), which a
node must handle. Each item says whether a correct subscriber delivers it (``valid``) or drops and
counts it as bad, so a test can check that every message sent was counted one way or the other.

The fault tests (``tests/test_faults.py``) and ``bench/faults.py`` send them to real node processes
through :class:`HostilePublisher`, an XPUB socket bound where the node expects the topic's publisher
(an ``external`` topic of its launch file, declared with ``publisher:`` so that end of stream is
authenticated).
"""

from __future__ import annotations

import dataclasses
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import types
import typing
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import msgpack
import numpy as np
import zmq

from counterpart.messages import REGISTRY, EndOfStream, encode
from counterpart.messages.codec import ALLOWED_DTYPES
from counterpart.messages.core import field_types

#: kinds of damage, in the order they are cycled through; "valid" ones are delivered to the node
KINDS = (
    "random_bytes",
    "valid",
    "no_header",
    "truncated",
    "nested",
    "valid",
    "bad_array",
    "oversize",
    "bad_field",
    "valid",
    "other_type",
    "forged_eos",
    "bad_counter",
)
_INTS = (0, 1, -1, 7, 2**31, -(2**31), 2**63 - 1, -(2**63))
_FLOATS = (0.0, -0.0, 1.5, float("nan"), float("inf"), float("-inf"), 1e308, -1e-308)
_DTYPES = sorted(ALLOWED_DTYPES)


@dataclass(frozen=True)
class Hostile:
    """One multipart message (topic frame first) and whether a correct subscriber delivers it.

    Parameters
    ----------
    kind : str
        The kind of damage, one of :data:`KINDS`.
    frames : list of bytes
        The multipart message, topic frame first.
    valid : bool
        Whether a correct subscriber delivers it (else it drops and counts it as bad).
    """

    kind: str
    frames: list[bytes]
    valid: bool


class OddValues:
    """Values of declared field types that are well-formed on the wire but odd: extreme numbers,
    NaN, random strings, arrays of random dtype and shape (each side ``min_dim`` to 5), up to 30
    list items (people in a frame).

    Parameters
    ----------
    rng : random.Random
        The source of the values.
    min_dim : int
        The smallest side of arrays (the largest is 5).
    """

    def __init__(self, rng: random.Random, min_dim: int = 0) -> None:
        self.rng = rng
        self.min_dim = min_dim

    def value(self, tp: Any, depth: int = 0) -> Any:
        """A value of declared type ``tp``.

        Parameters
        ----------
        tp : Any
            A resolved field type.
        depth : int
            Nesting depth (long lists only at depth 0).

        Returns
        -------
        Any
            The value (None for a type it does not know).
        """
        rng = self.rng
        origin, args = typing.get_origin(tp), typing.get_args(tp)
        if tp is bool:
            return rng.random() < 0.5
        if tp is int:
            return rng.choice(_INTS) if rng.random() < 0.5 else rng.randint(-1000, 10**6)
        if tp is float:
            return rng.choice(_FLOATS) if rng.random() < 0.5 else rng.uniform(-1e4, 1e4)
        if tp is str:
            return "".join(rng.choice("ab z\u00e9\u4e2d/\x00") for _ in range(rng.randint(0, 12)))
        if tp is bytes:
            return rng.randbytes(rng.randint(0, 16))
        if tp is np.ndarray:
            dtype = np.dtype(rng.choice(_DTYPES))
            shape = tuple(rng.randint(self.min_dim, 5) for _ in range(rng.randint(0, 3)))
            return np.frombuffer(rng.randbytes(dtype.itemsize * int(np.prod(shape))), dtype).reshape(shape)
        if origin in (typing.Union, types.UnionType):
            return self.value(rng.choice(args), depth)
        if origin is tuple and args and args[-1] is not Ellipsis:
            return tuple(self.value(a, depth + 1) for a in args)
        if origin in (list, tuple):
            n = rng.choice((0, 1, 2, 3, 22, 30)) if depth == 0 else rng.randint(0, 3)
            return [self.value(args[0] if args else int, depth + 1) for _ in range(n)]
        if origin is dict:
            kt, vt = args if args else (str, int)
            return {self.value(kt, depth + 1): self.value(vt, depth + 1) for _ in range(rng.randint(0, 3))}
        if dataclasses.is_dataclass(tp):
            return self.instance(tp, depth + 1)
        return None

    def instance(self, cls: type, depth: int = 0) -> Any:
        """An instance of message or struct class ``cls``, every field from :meth:`value`.

        Parameters
        ----------
        cls : type
            A message or struct class.
        depth : int
            Nesting depth.

        Returns
        -------
        Any
            The instance (built past the class's own checks when they refuse the values).
        """
        values = {name: self.value(tp, depth) for name, tp in field_types(cls).items()}
        try:
            return cls(**values)
        except ValueError:  # the class checks its values (Control's names): a hostile sender does not
            obj = object.__new__(cls)
            obj.__dict__.update(values)
            return obj


def _pack(head: dict[str, Any]) -> bytes:
    return msgpack.packb(head, use_bin_type=True)


def _nested(depth: int) -> bytes:
    """A header whose ``seq`` is a list nested ``depth`` deep (msgpack's own packer refuses to
    write that deep, which is the point).
    """
    return (
        b"\x83"
        + _pack("s")
        + _pack("x")
        + _pack("f")
        + b"\x81"
        + _pack("seq")
        + b"\x91" * depth
        + b"\xc0"
        + _pack("a")
        + b"\x90"
    )


def hostile_messages(
    topic: str, msg_type: type, n: int, publisher: str, seed: int = 0, min_dim: int = 0
) -> Iterator[Hostile]:
    """``n`` messages for ``topic`` (of ``msg_type``, published by node ``publisher``), cycling
    through :data:`KINDS`; the valid ones carry the send counter a real publisher would.

    Parameters
    ----------
    topic : str
        The topic.
    msg_type : type
        The topic's message class.
    n : int
        Messages to yield.
    publisher : str
        The node that publishes the topic (forged end-of-stream messages name another).
    seed : int
        Seed of the random damage and contents.
    min_dim : int
        The smallest side of arrays of well-formed messages (the largest is 5).

    Yields
    ------
    Hostile
        One message and whether a correct subscriber delivers it.
    """
    rng = random.Random(seed)
    odd = OddValues(rng, min_dim)
    t = topic.encode()
    others = [c for sid, c in sorted(REGISTRY.items()) if c is not msg_type and c is not EndOfStream]
    counter = 0
    for i in range(n):
        kind = KINDS[i % len(KINDS)]
        good = encode(odd.instance(msg_type), counter=counter)
        head = msgpack.unpackb(good[0], raw=False, strict_map_key=False)
        valid = False
        if kind == "valid":
            frames, valid = [t, *good], True
            counter += 1
        elif kind == "random_bytes":
            frames = [t] + [rng.randbytes(rng.randint(0, 200)) for _ in range(rng.randint(1, 4))]
        elif kind == "no_header":
            frames = [t]
        elif kind == "truncated":
            frames = [t, bytes(good[0])[: rng.randint(0, max(0, len(good[0]) - 1))], *good[1:]]
        elif kind == "nested":
            frames = [t, _nested(rng.choice((10, 100, 900, 5000)))]
        elif kind == "bad_array":
            frames = _bad_array(t, head, good, rng)
        elif kind == "oversize":
            frames = _oversize(t, head, rng, big=i % (100 * len(KINDS)) == KINDS.index("oversize"))
        elif kind == "bad_field":
            name = rng.choice(sorted(head["f"]))
            # a string where anything but a string is declared, a list where a string is
            head["f"][name] = [1, 2] if field_types(msg_type)[name] is str else "text"
            frames = [t, _pack(head), *good[1:]]
        elif kind == "other_type":
            frames = [t, *encode(odd.instance(rng.choice(others)), counter=counter)]
        elif kind == "forged_eos":
            frames = [t, *encode(EndOfStream(seq=rng.randint(0, 99), node=f"{publisher}-not"), counter=counter)]
        else:  # bad_counter: far beyond what the publisher can have sent
            frames = [t, *encode(odd.instance(msg_type), counter=counter + 10**12 + rng.randint(0, 2**40))]
        yield Hostile(kind, [bytes(f) for f in frames], valid)


def _bad_array(t: bytes, head: dict[str, Any], good: list[Any], rng: random.Random) -> list[bytes]:
    specs = head.get("a") or [["|u1", [1]]]
    bufs = [bytes(b) for b in good[1:]] or [b"x"]
    which = rng.randrange(4)
    if which == 0:
        specs[0] = ["|O", [1]]  # an object array would run pickle code
    elif which == 1:
        specs[0] = [specs[0][0], [-1, 3]]
    elif which == 2:
        specs[0] = [specs[0][0], [len(bufs[0]) + 1]]
    else:
        bufs = bufs + [b"extra"]
    head["a"] = specs
    return [t, _pack(head), *bufs]


def _oversize(t: bytes, head: dict[str, Any], rng: random.Random, big: bool) -> list[bytes]:
    if big:  # a header beyond the header limit (rarely: it costs a MiB on the wire)
        return [t, _pack({"s": head["s"], "f": {"pad": "x" * (2 << 20)}, "a": []})]
    which = rng.randrange(4)
    if which < 2:
        head["a"] = [["|u1", [1 << 40]]]
        return [t, _pack(head), b"x"]
    if which == 2:  # each array within the limit, together beyond it
        head["a"] = [["|u1", [200 << 20]]] * 3
        return [t, _pack(head), b"x", b"x", b"x"]
    head["a"] = [["|u1", [1]]] * 1000  # more arrays than any message of these types holds
    return [t, _pack(head), *([b"x"] * 1000)]


class HostilePublisher:
    """An XPUB socket bound on a free loopback port (``endpoint``: where the node under test
    connects for its topic), sending without loss: every message sent reaches the subscriber.

    Parameters
    ----------
    ctx : zmq.Context
        The context the socket is made in.
    """

    def __init__(self, ctx: zmq.Context) -> None:
        self.sock = ctx.socket(zmq.XPUB)
        self.sock.setsockopt(zmq.XPUB_NODROP, 1)
        self.sock.setsockopt(zmq.LINGER, 0)
        self.sock.bind("tcp://127.0.0.1:*")
        self.endpoint: str = self.sock.getsockopt_string(zmq.LAST_ENDPOINT)

    def wait_subscriber(self, deadline: float, alive: Callable[[], bool]) -> bool:
        """Wait for a subscriber to join.

        Parameters
        ----------
        deadline : float
            When to give up, on the ``time.monotonic()`` clock, seconds.
        alive : callable
            Waiting goes on only while it returns True (the node's process still runs).

        Returns
        -------
        bool
            True once a subscriber has joined; False at the deadline or when ``alive()`` is False.
        """
        while time.monotonic() < deadline and alive():
            if self.sock.poll(100) and self.sock.recv()[:1] == b"\x01":
                return True
        return False

    def send(self, frames: list[bytes], deadline: float) -> None:
        """Send one multipart message, waiting while the subscriber's queue is full.

        Parameters
        ----------
        frames : list of bytes
            The multipart message, topic frame first.
        deadline : float
            How long to wait, on the ``time.monotonic()`` clock, seconds.

        Raises
        ------
        TimeoutError
            When the subscriber stopped reading past ``deadline``.
        """
        while True:
            try:
                self.sock.send_multipart(frames, zmq.NOBLOCK)
                return
            except zmq.Again:
                if time.monotonic() > deadline:
                    raise TimeoutError("the subscriber stopped reading") from None
                self.sock.poll(5, zmq.POLLOUT)

    def close(self) -> None:
        self.sock.close(0)


@dataclass
class FuzzTarget:
    """One node input to fuzz: node ``node``'s port ``port`` takes topic ``topic`` of ``type_name``.

    Attributes
    ----------
    node : str
        The node's name in the launch declarations.
    port : str
        The node's input port.
    topic : str
        The topic the port is remapped to.
    type_name : str
        The topic's message type, as in launch files (``camera.Frame``).
    min_dim : int
        The smallest side of arrays in well-formed messages (see OddValues).
    sent : int
        Messages sent.
    valid : int
        Of them, those a correct subscriber delivers.
    received : int
        Decoded and handed to the node, from its stats.
    bad : int
        Dropped and counted as bad, from its stats.
    """

    node: str
    port: str
    topic: str
    type_name: str
    min_dim: int = 0  # the smallest side of arrays in well-formed messages (see OddValues)
    sent: int = 0
    valid: int = 0
    received: int = 0  # decoded and handed to the node, from its stats
    bad: int = 0  # dropped and counted as bad, from its stats

    @property
    def uncounted(self) -> int:
        return self.sent - self.received - self.bad


def run_fuzz(
    nodes: dict[str, dict[str, Any]],
    targets: list[FuzzTarget],
    n: int,
    workdir: Path,
    seed: int = 0,
    timeout: float = 120.0,
) -> tuple[int | None, str]:
    """Launch ``nodes`` (launch-file declarations, the targets' inputs remapped to their topics),
    send ``n`` hostile messages to each target (interleaved), then end the topics as their publisher
    would and wait for the graph to end (or ``timeout``). Fills each target's counts from its node's
    last statistics (a node that crashed counted what it had until about a second before).

    Parameters
    ----------
    nodes : dict of str to dict
        Launch-file node declarations, the targets' inputs remapped to their topics.
    targets : list of FuzzTarget
        The inputs to fuzz; their counts are filled in.
    n : int
        Hostile messages per target.
    workdir : Path
        Folder for the launch file (``fuzz.yaml``) and the launcher's output (``fuzz.log``).
    seed : int
        Seed of the hostile messages.
    timeout : float
        Seconds for the whole run.

    Returns
    -------
    code : int or None
        The launcher's exit code (None when it had to be killed).
    output : str
        The launcher's output.
    """
    import yaml

    home = Path(tempfile.mkdtemp(prefix="cpz", dir="/tmp"))  # short: unix socket paths are limited
    ctx = zmq.Context()
    pubs = {t.topic: HostilePublisher(ctx) for t in targets}
    doc = {
        "external": {
            t.topic: {"type": t.type_name, "endpoint": pubs[t.topic].endpoint, "publisher": "fuzzer"} for t in targets
        },
        "nodes": nodes,
    }
    (workdir / "fuzz.yaml").write_text(yaml.safe_dump(doc, sort_keys=False))
    log = open(workdir / "fuzz.log", "w+")
    proc = subprocess.Popen(
        [sys.executable, "-m", "counterpart.bus.cli", "launch", str(workdir / "fuzz.yaml")],
        env={**os.environ, "COUNTERPART_HOME": str(home)},
        stdout=log,
        stderr=subprocess.STDOUT,
        start_new_session=True,
    )
    deadline = time.monotonic() + timeout
    code: int | None = None
    try:
        if all(p.wait_subscriber(deadline, lambda: proc.poll() is None) for p in pubs.values()):
            _send(pubs, targets, n, seed, deadline)
            for t in targets:  # the end of the stream, from its publisher: the nodes end after the rest
                pubs[t.topic].send([t.topic.encode(), *encode(EndOfStream(node="fuzzer", reason="end"))], deadline)
        code = proc.wait(max(5.0, deadline - time.monotonic()))
    except (subprocess.TimeoutExpired, TimeoutError):
        pass
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        for pub in pubs.values():
            pub.close()
        ctx.term()
        _read_counts(targets, home / "latest")
        shutil.rmtree(home, ignore_errors=True)
    log.seek(0)
    out = log.read()
    log.close()
    return code, out


def _send(pubs: dict[str, HostilePublisher], targets: list[FuzzTarget], n: int, seed: int, deadline: float) -> None:
    from counterpart.messages import by_name

    streams = {
        t.topic: hostile_messages(t.topic, by_name(t.type_name), n, "fuzzer", seed + i, t.min_dim)
        for i, t in enumerate(targets)
    }
    for _ in range(n):
        for t in targets:
            item = next(streams[t.topic])
            pubs[t.topic].send(item.frames, deadline)
            t.sent += 1
            t.valid += item.valid


def _read_counts(targets: list[FuzzTarget], run: Path) -> None:
    """Each target's input counts from its node's statistics file (its last stats, written on
    every publish and at the end).
    """
    import json

    from .launchfile import stats_dir

    for t in targets:
        try:
            stats = json.loads((stats_dir(run) / f"{t.node}.json").read_text())
        except (OSError, ValueError):
            continue  # the node never published stats: nothing counted
        for port in stats.get("inputs", []):
            if port.get("port") == t.port:
                t.received, t.bad = int(port["count"]), int(port["bad"])


__all__ = ["FuzzTarget", "Hostile", "HostilePublisher", "KINDS", "OddValues", "hostile_messages", "run_fuzz"]
