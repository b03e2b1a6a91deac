"""Publish/subscribe over ZeroMQ with the two queue policies of Counterpart.

A :class:`Publisher` owns a topic's sockets (see :mod:`counterpart.bus.endpoints`). Messages are encoded once
and sent on each socket that has subscribers; on the reliable socket the send waits (checking
``should_stop``) while a reliable subscriber lags, on the latest and queued sockets it never waits. End of stream is also sent on the reliable
socket under the topic prefix ``EOS_PREFIX`` so that latest subscribers, which listen for that prefix
alone there, can never miss it.

A :class:`Subscriber` is one input: ``reliable`` reads every message in order; ``latest`` drains what
is queued and keeps the newest, counting what it dropped (both in its own queue and, from gaps in the
publisher's send counter, in ZeroMQ's); ``latest`` with a ``queue`` (recorders) reads the queued
socket in order and counts the gaps.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from time import monotonic as _monotonic
from typing import Any

import zmq

from counterpart.messages import REGISTRY, EndOfStream, encode, schema_id
from counterpart.messages.codec import (
    DEFAULT_LIMITS,
    DecodeError,
    Limits,
    check_array_count,
    decode_any,
    decode_counted,
    read_header,
)

from .endpoints import TopicEndpoints, bind_address

EOS_PREFIX = b"\x00eos:"
RELIABLE = "reliable"
LATEST = "latest"
POLICIES = (RELIABLE, LATEST)
#: send high-water mark of a publisher's queued socket: the longest queue a ``latest`` subscriber may keep
QUEUED_HWM = 64
#: a publisher's send counter cannot run ahead of the last one seen by more than this many messages
#: plus MAX_SEND_RATE per second since then (far above what a Python publisher sends); a larger jump
#: is a forged or corrupt counter, not a loss
COUNTER_SLACK = 10_000
MAX_SEND_RATE = 1_000_000
#: milliseconds an end of stream that came ahead of the lossy socket's messages waits for them
EOS_GRACE_MS = 20
#: the same when none of them has come yet (:meth:`Subscriber._eos_grace_ms`)
EOS_GRACE_FIRST_MS = 2000
#: bytes: frames below this are copied into ZeroMQ, larger ones go out zero-copy. A zero-copy frame
#: costs pyzmq a wake-up of its garbage-collector thread (which takes the GIL) once ZeroMQ has sent
#: it; that outweighs copying a 320x240 gray image (76,800 B) but not a 640x480 BGR one (921,600 B).
ZERO_COPY_MIN = 262144


#: pyzmq's frame send without the Python layer of ``zmq.Socket`` (not a promised API: where a pyzmq
#: lacks it, ``send_multipart`` does the same). It saved 2-4 % of a one-way latency at 64 B and
#: 76,800 B in interleaved bus bench runs, which kept the latency ratios of bench/bus_latency.py
#: where they were; the codec's shortcuts are in counterpart.messages.fastpath.
_socket_send = getattr(getattr(zmq, "backend", None), "Socket", None)
_socket_send = getattr(_socket_send, "send", None)


def _send_multipart(sock: zmq.Socket, topic: bytes, parts: Sequence[Any], flags: int) -> None:
    """``[topic, *parts]`` as one multipart message, like ``send_multipart(copy=False)``: pyzmq
    copies each part below the socket's ``copy_threshold`` and sends larger ones zero-copy. ZeroMQ
    queues a multipart message whole or not at all (zmq.Again comes from the first part).
    """
    if _socket_send is None:
        sock.send_multipart([topic, *parts], flags, copy=False)
        return
    _socket_send(sock, topic, flags | zmq.SNDMORE, False)
    last = len(parts) - 1
    for i, part in enumerate(parts):
        _socket_send(sock, part, flags if i == last else flags | zmq.SNDMORE, False)


class Publisher:
    """Both sockets of one topic. ``expected`` reliable subscribers, and ``expected_latest`` lossy ones
    that wait for the end of stream, are awaited before the first send (the startup barrier), for
    at most ``barrier_timeout`` seconds: a short stream could otherwise end before a slow-starting
    lossy subscriber connects, and that one would wait for an end of stream it never gets.

    Parameters
    ----------
    ctx : zmq.Context
        The ZeroMQ context.
    topic : str
        The topic's name.
    endpoints : TopicEndpoints
        Addresses of the reliable, latest and (optional) queued sockets, bound here.
    expected : int, default=0
        Reliable subscribers awaited before the first send.
    expected_latest : int, default=0
        Lossy subscribers (waiting for the end of stream) awaited before the first send.
    hwm : int, default=16
        Send high-water mark of the reliable socket, messages.
    latest_hwm : int, default=2
        Send high-water mark of the latest socket, messages.
    queued_hwm : int, default=QUEUED_HWM
        Send high-water mark of the queued socket, messages.
    barrier_timeout : float, default=30.0
        Longest wait for the expected subscribers, seconds.
    should_stop : callable, default=lambda: False
        Returns True when the node is asked to stop (ends waits early).
    latched : bool, default=False
        The last message sent is sent again to every ``latest`` subscriber that joins later (ROS's
        latched topics), once :meth:`poll_subscriptions` or a send sees it join. A lossy subscriber
        that connects after a rare message (a run-time control), or restarts, still gets the one in
        force; the subscribers already there get it twice. Reliable subscribers are not sent it again:
        the startup barrier gives them every message once. The parts are kept by reference.

    Attributes
    ----------
    count : int
        Messages sent (the send counter).
    subscribers : int
        Reliable subscribers connected now.
    """

    def __init__(
        self,
        ctx: zmq.Context,
        topic: str,
        endpoints: TopicEndpoints,
        expected: int = 0,
        expected_latest: int = 0,
        hwm: int = 16,
        latest_hwm: int = 2,
        queued_hwm: int = QUEUED_HWM,
        barrier_timeout: float = 30.0,
        should_stop: Callable[[], bool] = lambda: False,
        latched: bool = False,
    ) -> None:
        self.topic = topic
        self.topic_b = topic.encode()
        self.endpoints = endpoints
        self.expected = expected
        self.expected_latest = expected_latest
        self.barrier_timeout = barrier_timeout
        self.should_stop = should_stop
        self.count = 0
        self.subscribers = 0
        self.eos_listeners = 0
        self._last_sub_read = 0.0
        self._barrier_done = expected <= 0 and expected_latest <= 0
        self._barrier_passed = False  # every expected subscriber has been seen (wait_for_subscribers)
        self.latched = latched
        self._latched_parts: Sequence[Any] | None = None
        self._eos_parts: Sequence[Any] | None = None
        self.reliable = ctx.socket(zmq.XPUB)
        self.reliable.setsockopt(zmq.SNDHWM, hwm)
        self.reliable.setsockopt(zmq.XPUB_NODROP, 1)
        self.reliable.setsockopt(zmq.XPUB_VERBOSER, 1)
        self.reliable.setsockopt(zmq.SNDTIMEO, 100)
        self.reliable.copy_threshold = ZERO_COPY_MIN  # pyzmq decides per frame (send with copy=False)
        self.reliable.bind(bind_address(endpoints.reliable))
        self.latest_subscribers = 0
        self.latest = ctx.socket(zmq.XPUB)  # lossy; XPUB only to know whether anyone listens
        self.latest.setsockopt(zmq.XPUB_VERBOSER, 1)
        self.latest.setsockopt(zmq.SNDHWM, latest_hwm)
        self.latest.setsockopt(zmq.LINGER, 0)
        self.latest.copy_threshold = ZERO_COPY_MIN
        self.latest.bind(bind_address(endpoints.latest))
        self.queued_subscribers = 0
        self.queued: zmq.Socket | None = None
        if endpoints.queued:  # lossy with a deep queue: recorders (see Subscriber's ``queue``)
            self.queued = ctx.socket(zmq.XPUB)
            self.queued.setsockopt(zmq.XPUB_VERBOSER, 1)
            self.queued.setsockopt(zmq.SNDHWM, queued_hwm)
            self.queued.setsockopt(zmq.LINGER, 0)
            self.queued.copy_threshold = ZERO_COPY_MIN
            self.queued.bind(bind_address(endpoints.queued))

    # XPUB sockets tell who subscribed: b"\x01" + prefix, and b"\x00" + prefix on leave.
    def _read_subscriptions(self, timeout_ms: int = 0) -> bool:
        """Count who joined or left; True when a subscriber joined the reliable socket."""
        joined_reliable = False
        while self.reliable.poll(timeout_ms, zmq.POLLIN):
            ev = self.reliable.recv()
            step = 1 if ev[:1] == b"\x01" else -1
            if ev[1:] == b"":  # full subscribers (the startup barrier counts these)
                self.subscribers += step
            elif ev[1:] == EOS_PREFIX:  # latest subscribers listening for end of stream here
                self.eos_listeners += step
            joined_reliable |= step > 0
            self._check_barrier()
            timeout_ms = 0
        joined = False
        while self.latest.poll(0, zmq.POLLIN):
            ev = self.latest.recv()
            joined |= ev[:1] == b"\x01"
            self.latest_subscribers += 1 if ev[:1] == b"\x01" else -1
            self._check_barrier()
        while self.queued is not None and self.queued.poll(0, zmq.POLLIN):
            self.queued_subscribers += 1 if self.queued.recv()[:1] == b"\x01" else -1
            self._check_barrier()
        if joined and self._latched_parts is not None:
            self._send_latest(self._latched_parts)
        return joined_reliable

    def _check_barrier(self) -> None:
        """Once every expected subscriber has been here the barrier is passed, even if one has left
        since (a node that ended before this one's first message: a latched topic's first send).
        """
        if not self._barrier_done and self._barrier_met():
            self._barrier_done = self._barrier_passed = True

    def _barrier_met(self) -> bool:
        return (
            self.subscribers >= self.expected
            and self.eos_listeners >= self.expected_latest
            # a lossy subscriber with a queue reads the queued socket instead of the latest one
            and self.latest_subscribers + self.queued_subscribers >= self.expected_latest
        )

    def poll_subscriptions(self) -> None:
        """Read who joined or left now (a latched publisher's node loop calls this between sends)."""
        self._last_sub_read = _monotonic()
        self._read_subscriptions()

    def wait_for_subscribers(self) -> bool:
        """Block until ``expected`` reliable and ``expected_latest`` lossy subscribers are connected
        (or timeout/stop).

        Returns
        -------
        bool
            True when the barrier is passed; False on timeout or stop.
        """
        deadline = time.monotonic() + self.barrier_timeout
        while not self._barrier_passed and not self._barrier_met():
            if self.should_stop() or time.monotonic() > deadline:
                return False
            self._read_subscriptions(50)
        self._barrier_done = True
        return True

    def send(self, msg: Any) -> None:
        """Encode once, send on both sockets.

        Parameters
        ----------
        msg : Any
            A registered message.
        """
        parts = encode(msg, counter=self.count)
        self.count += 1
        self.send_parts(parts)

    def send_parts(self, parts: Sequence[Any], eos: bool = False) -> None:
        """Send an encoded message on the sockets that have subscribers (all of them for an end of stream).

        Parameters
        ----------
        parts : sequence
            The encoded message: [header, buffers...].
        eos : bool, default=False
            It is an end of stream: also sent under ``EOS_PREFIX`` on the reliable socket.
        """
        if not self._barrier_done:
            self.wait_for_subscribers()
            self._barrier_done = True
        # subscriptions change rarely: look at them every 20 ms (two polls per send would cost more
        # than the rest of the send)
        now = _monotonic()
        if eos or now - self._last_sub_read > 0.02:
            self._last_sub_read = now
            self._read_subscriptions()
        if self.subscribers > 0 or eos:
            self._send_reliable(self.topic_b, parts)
        if eos:
            self._send_reliable(EOS_PREFIX + self.topic_b, parts)
        elif self.latched:
            self._latched_parts = parts
        if self.latest_subscribers > 0 or eos:
            self._send_latest(parts)
        if self.queued is not None and (self.queued_subscribers > 0 or eos):
            self._send_latest(parts, self.queued)

    def _send_latest(self, parts: Sequence[Any], sock: zmq.Socket | None = None) -> None:
        try:
            _send_multipart(self.latest if sock is None else sock, self.topic_b, parts, zmq.NOBLOCK)
        except zmq.Again:  # a lossy socket: a full queue drops (the subscriber counts the gap)
            pass

    def _send_reliable(self, topic: bytes, parts: Sequence[Any]) -> None:
        while True:
            try:
                _send_multipart(self.reliable, topic, parts, 0)
                return
            except zmq.Again:  # a reliable subscriber lags: keep waiting unless asked to stop
                self._read_subscriptions()
                if self.should_stop():
                    return

    def send_eos(self, node: str, seq: int, reason: str = "end") -> None:
        """Send an ``EndOfStream`` on every socket.

        Parameters
        ----------
        node : str
            The publishing node's name.
        seq : int
            Sequence number of the message.
        reason : str, default="end"
            Why the stream ends.
        """
        parts = encode(EndOfStream(stamp=time.monotonic_ns(), seq=seq, node=node, reason=reason), counter=self.count)
        self.count += 1
        self._eos_parts = parts
        self.send_parts(parts, eos=True)

    def wait_delivered(self, timeout: float) -> bool:
        """After end of stream: wait until every reliable subscriber has left (they unsubscribe on
        end of stream). ZeroMQ loses what is still in flight when a publisher closes its socket, so
        a finite stream is complete only once its readers say they have read to the end.

        A subscriber that connects after end of stream went out (a node still starting when its
        source failed at once) gets it again: it would otherwise wait for an end that never comes,
        and this publisher for its confirmation.

        Parameters
        ----------
        timeout : float
            Longest wait, seconds.

        Returns
        -------
        bool
            True when every reliable subscriber has left; False on timeout or stop.
        """
        deadline = time.monotonic() + timeout
        resend = self._read_subscriptions()
        while self.subscribers > 0 or self.eos_listeners > 0:
            if self.should_stop() or time.monotonic() > deadline:
                return False
            if resend and self._eos_parts is not None:
                resend = not self._try_send_eos_again()
            resend |= self._read_subscriptions(50)
        return True

    def _try_send_eos_again(self) -> bool:
        """End of stream once more on the reliable socket, without waiting (a lagging subscriber's
        full queue makes it fail: try again later). Subscribers that have it already ignore it.
        """
        try:
            for topic in (self.topic_b, EOS_PREFIX + self.topic_b):
                _send_multipart(self.reliable, topic, self._eos_parts, zmq.NOBLOCK)
        except zmq.Again:
            return False
        return True

    def close(self, linger_ms: int = -1) -> None:
        """Close; by default wait (in ``Context.term``) until reliable subscribers got everything.
        Dead subscribers do not hold this up: ZeroMQ drops the pipes of closed peers.

        Parameters
        ----------
        linger_ms : int, default=-1
            Linger of the reliable socket, milliseconds (-1: until delivered).
        """
        self.reliable.close(linger=linger_ms)
        self.latest.close(linger=0)
        if self.queued is not None:
            self.queued.close(linger=0)


@dataclass(frozen=True)
class RawMessage:
    """A received message left encoded.

    Attributes
    ----------
    topic : str
        The topic it came on.
    parts : list
        [header, buffers...] as received.
    header : dict
        The decoded header (``s`` the schema, ``f`` the scalar fields).
    """

    topic: str
    parts: list[Any]
    header: dict[str, Any]

    @property
    def schema(self) -> str:
        return self.header["s"]

    @property
    def stamp(self) -> int:
        stamp = self.header["f"].get("stamp", 0)
        return stamp if type(stamp) is int else 0

    @property
    def seq(self) -> int:
        seq = self.header["f"].get("seq", -1)
        return seq if type(seq) is int else -1


_EOS_SCHEMA = EndOfStream.__schema_id__


def decode_raw(parts: Sequence[Any], limits: Limits = DEFAULT_LIMITS) -> tuple[Any, int | None]:
    """Check the header and the number of buffers, leave the arrays encoded; the schema need not be
    registered. End of stream is decoded as usual so that subscribers see the end.

    Parameters
    ----------
    parts : sequence
        The multipart message without its topic: [header, buffers...].
    limits : Limits, default=DEFAULT_LIMITS
        Size limits the codec enforces.

    Returns
    -------
    msg : RawMessage or EndOfStream
        The message.
    counter : int or None
        The publisher's send counter, when the header carries one.

    Raises
    ------
    DecodeError
        If the header is bad or the buffers do not match it.
    """
    header = read_header(parts[0], limits)
    if header["s"] == _EOS_SCHEMA:
        return decode_counted(parts, limits)
    check_array_count(len(header.get("a", [])), REGISTRY.get(header["s"]), limits)
    if len(header.get("a", [])) != len(parts) - 1:
        raise DecodeError(
            "bad_array", f"header names {len(header.get('a', []))} arrays, {len(parts) - 1} buffers arrived"
        )
    counter = header.get("n")
    return RawMessage("", list(parts), header), counter if type(counter) is int else None


class Subscriber:
    """One input. ``receive()`` returns the next message (reliable) or the newest one (latest), or
    None when nothing is ready. Decode failures are counted per kind in ``bad`` and reported through
    ``on_bad(kind, detail)`` the first time each kind occurs.

    Besides what the codec refuses, a subscriber drops (and counts as bad) a message of another type
    than ``msg_type`` (``wrong_type``), an end of stream that does not name ``publisher``, the node
    publishing the topic (``forged_eos``), and a send counter that jumps further ahead than the
    publisher can have sent since the last message (``bad_counter``: a forged counter must not turn
    into billions of drops). A counter that goes back is a restarted publisher: counting starts again.

    Parameters
    ----------
    ctx : zmq.Context
        The ZeroMQ context.
    topic : str
        The topic's name.
    endpoints : TopicEndpoints
        The publisher's socket addresses.
    policy : str, default=RELIABLE
        Queue policy, one of ``POLICIES``.
    hwm : int, default=16
        Receive high-water mark of a reliable subscriber, messages.
    limits : Limits, default=DEFAULT_LIMITS
        Size limits the codec enforces.
    on_bad : callable or None, default=None
        Called as ``on_bad(kind, detail)`` the first time each kind of bad message occurs.
    untyped : bool, default=False
        Messages of schemas not registered here arrive as UntypedMessage instead of being dropped
        (tools that show any topic).
    raw : bool, default=False
        Messages arrive as :class:`RawMessage`, header checked but arrays left undecoded (recorders).
    msg_type : type or None, default=None
        The only message class accepted (None: any).
    publisher : str or None, default=None
        The node name an end of stream must carry (None: any, for topics whose publisher is not
        known here).
    queue : int, default=0
        Latest policy only: keep up to this many messages in order instead of only the newest, read
        from the publisher's queued socket (recorders that must never hold a publisher back but
        should lose nothing while they keep up; a real-time node that is late now and then and
        catches up): each take keeps the newest ``queue`` of what has come, the older ones are
        dropped and counted in ``drops``, so the lag stays bounded.

    Attributes
    ----------
    count : int
        Data messages received.
    drops : int
        Messages lost (lossy policy, counted from the send counter).
    bad : dict of str to int
        Decode failures per kind.
    ended : bool
        End of stream has been received.

    Raises
    ------
    ValueError
        If ``policy`` is not one of ``POLICIES``.
    """

    def __init__(
        self,
        ctx: zmq.Context,
        topic: str,
        endpoints: TopicEndpoints,
        policy: str = RELIABLE,
        hwm: int = 16,
        limits: Limits = DEFAULT_LIMITS,
        on_bad: Callable[[str, str], None] | None = None,
        untyped: bool = False,
        raw: bool = False,
        msg_type: type | None = None,
        publisher: str | None = None,
        queue: int = 0,
    ) -> None:
        if policy not in POLICIES:
            raise ValueError(f"queue policy {policy!r}: expected one of {', '.join(POLICIES)}")
        self.topic = topic
        self.policy = policy
        self.limits = limits
        self.on_bad = on_bad
        self._decoder = decode_raw if raw else decode_any if untyped else decode_counted
        self._type_id = None if msg_type is None else schema_id(msg_type)
        self._schemas = None if msg_type is None else frozenset((self._type_id, _EOS_SCHEMA))
        self.publisher = publisher
        self.queued = policy == LATEST and queue > 0
        self.count = 0
        self.drops = 0
        self.bad: dict[str, int] = {}
        self.ended = False
        self._pending_eos: EndOfStream | None = None
        self._eos_counter: int | None = None
        self._last_counter: int | None = None
        self._last_counter_time = self._eos_time = 0.0
        self.socket = ctx.socket(zmq.SUB)
        self.socket.setsockopt(zmq.LINGER, 0)
        # a queue is kept here, newest last (the oldest pushed out are counted by the send counter's
        # gap): the socket's own queue is as long as the publisher's queued one, so that a drain takes
        # most of what came while the node was busy
        self._backlog: deque[list[Any]] = deque(maxlen=max(queue, 1))
        self.socket.setsockopt(zmq.RCVHWM, hwm if policy == RELIABLE else QUEUED_HWM if self.queued else 2)
        self.socket.setsockopt(zmq.SUBSCRIBE, b"")
        if policy == RELIABLE:
            self.socket.connect(endpoints.reliable)
        else:  # a launcher older than the queued socket offers the latest one only
            self.socket.connect(endpoints.queued if self.queued and endpoints.queued else endpoints.latest)
        self.eos_socket: zmq.Socket | None = None
        if policy == LATEST:
            self.eos_socket = ctx.socket(zmq.SUB)
            self.eos_socket.setsockopt(zmq.LINGER, 0)
            self.eos_socket.setsockopt(zmq.SUBSCRIBE, EOS_PREFIX)
            self.eos_socket.connect(endpoints.reliable)

    @property
    def sockets(self) -> list[zmq.Socket]:
        return [self.socket] + ([self.eos_socket] if self.eos_socket is not None else [])

    def _bad(self, kind: str, detail: str) -> None:
        self.bad[kind] = self.bad.get(kind, 0) + 1
        if self.bad[kind] == 1 and self.on_bad is not None:
            self.on_bad(kind, detail)

    def _decode(self, frames: list[Any], track: bool = True) -> Any | None:
        if len(frames) < 2:
            self._bad("malformed", f"{len(frames)} frame(s); need topic and header")
            return None
        try:
            msg, counter = self._decoder(frames[1:], self.limits)
            if isinstance(msg, RawMessage):
                msg = RawMessage(self.topic, msg.parts, msg.header)
        except DecodeError as exc:
            self._bad(exc.kind, exc.detail)
            return None
        except Exception as exc:  # noqa: BLE001 - anything can connect to a socket; no input may kill the node
            self._bad("malformed", f"{type(exc).__name__}: {exc}")
            return None
        if not self._accepted(msg):
            return None
        if counter is not None and track:
            gap = self._counter_gap(counter)
            if gap is None:
                return None
            self.drops += gap
        return msg

    def _accepted(self, msg: Any) -> bool:
        """The declared type, and an end of stream only from the topic's publisher."""
        if self._schemas is not None:
            sid = msg.schema if isinstance(msg, RawMessage) else getattr(type(msg), "__schema_id__", None)
            if sid not in self._schemas:
                self._bad("wrong_type", f"a {sid} message on a topic of {self._type_id}")
                return False
        if self.publisher is not None and isinstance(msg, EndOfStream) and msg.node != self.publisher:
            self._bad("forged_eos", f"end of stream from {msg.node!r}; the topic's publisher is {self.publisher!r}")
            return False
        return True

    def _counter_gap(self, counter: int) -> int | None:
        """Messages lost before this one by the publisher's send counter; None for an impossible
        jump (more than the publisher can have sent since the last message), which is dropped.
        """
        now = _monotonic()
        last = self._last_counter
        gap = 0
        if last is not None and counter > last:
            gap = counter - last - 1
            if gap > COUNTER_SLACK + (now - self._last_counter_time) * MAX_SEND_RATE:
                self._bad("bad_counter", f"send counter jumped from {last} to {counter}")
                return None
        # a counter that goes back (or the first one) starts counting again: the publisher restarted
        self._last_counter, self._last_counter_time = counter, now
        return gap

    def _recv(self, flags: int) -> list[Any]:
        """One multipart message as zmq.Frame objects (array buffers are viewed by ``np.frombuffer``
        without a copy). A frame's ``more`` flag is read from the message itself, where asking the
        socket for RCVMORE after each part cost 0.7 us per part.
        """
        sock = self.socket
        frame = sock.recv(flags, copy=False)
        frames = [frame]
        while frame.more:
            frame = sock.recv(0, copy=False)
            frames.append(frame)
        return frames

    def _next_queued(self) -> list[Any]:
        """The oldest message of the queue, after taking in everything the socket holds (the
        oldest beyond ``queue`` are dropped). Raises zmq.Again when there is none.
        """
        while True:
            try:
                frames = self._recv(zmq.NOBLOCK)
            except zmq.Again:
                break
            if len(self._backlog) == self._backlog.maxlen and self._last_counter is None:
                self.drops += 1  # before the first message taken no send counter shows the gap
            self._backlog.append(frames)
        if not self._backlog:
            raise zmq.Again()
        return self._backlog.popleft()

    @property
    def pending(self) -> bool:
        """End of stream has arrived and will be returned once nothing more is in flight: call
        :meth:`receive` again even when no socket is readable.
        """
        return self._pending_eos is not None or bool(self._backlog)

    def receive(self) -> Any | None:
        """The next message (reliable) or the newest one (latest).

        Returns
        -------
        Any or None
            The message (an ``EndOfStream`` once, at the end), or None when nothing is ready.
        """
        if self.eos_socket is not None and self._pending_eos is None and self.eos_socket.poll(0, zmq.POLLIN):
            frames = self.eos_socket.recv_multipart(copy=False)
            msg = self._decode(frames, track=False)
            if isinstance(msg, EndOfStream) and not self.ended:
                # end of stream overtook the lossy socket: deliver what is still in flight there first
                self._pending_eos = msg
                self._eos_counter = read_header(frames[1], self.limits).get("n")
                self._eos_time = _monotonic()
        try:
            frames = self._next_queued() if self.queued else self._recv(zmq.NOBLOCK)
        except zmq.Again:
            if self._pending_eos is not None and not self.socket.poll(self._eos_grace_ms(), zmq.POLLIN):
                msg, self._pending_eos = self._pending_eos, None
                last, n = self._last_counter, self._eos_counter
                # the end may have been read before the messages still queued ahead of it: no time
                # between them then, and the gap is bounded by the slack alone (never by a negative time)
                if (
                    type(n) is int
                    and last is not None
                    and n > last + 1
                    and n - last - 1
                    <= COUNTER_SLACK + max(0.0, self._eos_time - self._last_counter_time) * MAX_SEND_RATE
                ):
                    self.drops += n - last - 1  # lost on the lossy socket after the last one received
                self._finish()
                return msg
            return None
        if self.policy == LATEST and not self.queued:
            stale = 0
            while True:  # keep the newest; every older message still queued is a drop
                try:
                    newer = self._recv(zmq.NOBLOCK)
                except zmq.Again:
                    break
                frames = newer
                stale += 1
            self.drops += stale
            if self._last_counter is not None:
                self._last_counter += stale  # the drained ones are counted already, not as gaps
        msg = self._decode(frames)
        if msg is None:
            return None
        if isinstance(msg, EndOfStream):  # not counted: ``count`` is the data messages received
            self._pending_eos = None
            if self.ended:
                return None
            self._finish()
            return msg
        self.count += 1
        return msg

    def _eos_grace_ms(self) -> int:
        """How long an end of stream that overtook the lossy socket waits for what is in flight there:
        ``EOS_GRACE_MS``; ``EOS_GRACE_FIRST_MS`` when nothing came on it yet though the end says
        messages were sent (the first of a burst is always queued for a subscriber that was there
        before it, so it is on its way, late only on a loaded machine).
        """
        n = self._eos_counter
        return EOS_GRACE_FIRST_MS if self._last_counter is None and type(n) is int and n > 0 else EOS_GRACE_MS

    def _finish(self) -> None:
        """End of stream: unsubscribing tells the publisher we read to the end (it waits for that)."""
        self.ended = True
        self.socket.setsockopt(zmq.UNSUBSCRIBE, b"")
        if self.eos_socket is not None:
            self.eos_socket.setsockopt(zmq.UNSUBSCRIBE, EOS_PREFIX)

    def close(self) -> None:
        for s in self.sockets:
            s.close()


__all__ = ["Publisher", "Subscriber", "RawMessage", "decode_raw", "RELIABLE", "LATEST", "POLICIES", "EOS_PREFIX"]
