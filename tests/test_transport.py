"""Publisher/Subscriber in one process over real ipc sockets: policies and end of stream."""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import zmq

from counterpart.bus.endpoints import ipc_endpoints
from counterpart.bus.transport import LATEST, RELIABLE, Publisher, Subscriber
from counterpart.messages import EndOfStream
from tests.graph_nodes import Number


def _pump(sub: Subscriber, timeout: float = 5.0, until: int | None = None) -> list:
    """What a node loop does: poll the subscriber's sockets, receive, also while an end is pending;
    until the end of stream (or ``until`` messages).
    """
    got, deadline = [], time.monotonic() + timeout
    while not sub.ended and time.monotonic() < deadline and (until is None or len(got) < until):
        if any(s.poll(20) for s in sub.sockets) or sub.pending:
            msg = sub.receive()
            if msg is not None:
                got.append(msg)
    return got


def test_latest_subscriber_ends_and_the_publisher_sees_it_has_read_to_the_end() -> None:
    root = Path(tempfile.mkdtemp(dir="/tmp"))
    ctx = zmq.Context()
    pub = Publisher(ctx, "n", ipc_endpoints(root, "n"))
    subs = {pol: Subscriber(ctx, "n", ipc_endpoints(root, "n"), pol) for pol in (RELIABLE, LATEST)}
    time.sleep(0.3)  # let the subscriptions arrive (no barrier in this test)
    # a first message read by both: losses are counted from the publisher's send counter, and a
    # subscriber can only count gaps after the first message it has seen
    pub.send(Number(seq=0, value=0.0))
    got = {pol: _pump(s, until=1) for pol, s in subs.items()}
    for i in range(1, 5):
        pub.send(Number(seq=i, value=float(i)))
    pub.send_eos("test", 4)
    for pol, s in subs.items():
        got[pol] += _pump(s)
    assert [m.seq for m in got[RELIABLE]] == [0, 1, 2, 3, 4, 4]  # the last one is the end of stream
    assert all(s.ended for s in subs.values())
    latest = [m.seq for m in got[LATEST][:-1]]
    assert isinstance(got[LATEST][-1], EndOfStream) and latest == sorted(latest)
    assert len(latest) + subs[LATEST].drops == 5  # what the lossy socket lost is counted
    assert pub.wait_delivered(5.0), (pub.subscribers, pub.eos_listeners)
    for s in subs.values():
        s.close()
    pub.close(0)
    ctx.term()


def test_a_latched_topic_gives_its_last_message_to_a_latest_subscriber_that_joins_later() -> None:
    root = Path(tempfile.mkdtemp(dir="/tmp"))
    ctx = zmq.Context()
    pubs = {
        latched: Publisher(ctx, f"t{latched:d}", ipc_endpoints(root, f"t{latched:d}"), latched=latched)
        for latched in (True, False)
    }
    for pub in pubs.values():
        pub.send(Number(seq=0, value=1.0))
        pub.send(Number(seq=1, value=2.0))  # sent while nobody listens
    subs = {latched: Subscriber(ctx, pub.topic, pub.endpoints, LATEST) for latched, pub in pubs.items()}
    deadline = time.monotonic() + 5.0
    while time.monotonic() < deadline and min(p.latest_subscribers for p in pubs.values()) < 1:
        for pub in pubs.values():
            pub.poll_subscriptions()  # what the node loop does between sends
        time.sleep(0.01)
    got = {latched: _pump(s, timeout=1.0, until=1) for latched, s in subs.items()}
    assert [(m.seq, m.value) for m in got[True]] == [(1, 2.0)]  # the newest one, once
    assert got[False] == [] and pubs[False].latest_subscribers == 1  # the lossy socket alone keeps nothing
    pubs[True].send(Number(seq=2, value=3.0))  # and the topic goes on as usual
    assert [m.seq for m in _pump(subs[True], timeout=2.0, until=1)] == [2] and subs[True].drops == 0
    for s in subs.values():
        s.close()
    for pub in pubs.values():
        pub.close(0)
    ctx.term()
