"""Bus benchmark: our publish/subscribe against raw pyzmq PUB/SUB carrying the same payloads.

Each measurement runs a publisher and a subscriber in two processes over ipc:// on this host:
- latency: 400 messages paced 2 ms apart, the first 50 discarded as warm-up; one-way latency =
  time the receiver holds a usable message (ours: the decoded typed message; raw: the payload as a
  numpy view and the stamp as an int) - send stamp taken just before encoding/sending
  (CLOCK_MONOTONIC is shared by processes);
- throughput: 3,000 messages of 76,800 B sent as fast as possible; messages per second at the
  receiver, ours / raw (raw PUB may drop under load; it is counted at the receiver all the same);
- reliable_drops: 10,000 messages through our reliable policy to a slower subscriber.
The raw reference uses the same frames per message as ours (topic, a small header, the payload) and
the same per-frame copy policy (pyzmq ``copy_threshold`` = ``counterpart.bus.transport.ZERO_COPY_MIN``, sent with
``copy=False``), so the ratio is what our codec and transport add, not a different copy choice.
A third kind, plain, is ours with the codec's fast path off (``counterpart.messages.codec.use_fast_path``):
``codec_fast_vs_plain_*`` = median(ours) / median(plain), what the fast path
(``counterpart.messages.fastpath``) saves end to end (below 1: it pays).
The publisher and the subscriber are pinned to two different CPUs, the same two for raw and ours
(``--no-pin`` leaves placement to the scheduler, which on a 2-core machine puts the pair on one core
in some runs and on two in others: that changes the wake-up time by more than the whole difference
being measured). The kinds alternate ``--repeats`` times (their order reverses every other repeat); a figure is the
median over repeats of each run's median. ``*_ratio_*`` = median(ours) / median(raw); the spread
fields give the per-repeat paired ratios (ours / raw of the same repeat) as [min, median, max].
Last stdout line: one JSON object.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import zmq

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from counterpart.bus.endpoints import ipc_endpoints  # noqa: E402
from counterpart.bus.transport import RELIABLE, ZERO_COPY_MIN, Publisher, Subscriber  # noqa: E402
from counterpart.messages import codec, message  # noqa: E402


@message("bench.Blob", 1)
class Blob:
    data: np.ndarray = np.zeros(0, np.uint8)


SIZES = (64, 76800, 921600)
#: raw pyzmq; ours (the codec's fast path, as nodes run); ours with the plain codec path alone
KINDS = ("raw", "ours", "plain")
#: pin the publisher and the subscriber to two CPUs (``--no-pin`` clears it)
PIN = True
WARMUP = 50  # first messages of a latency run: connection set-up, first calls of every code path


def _raw_pub(ep: str, n: int, size: int, gap: float, ready) -> None:
    ctx = zmq.Context()
    s = ctx.socket(zmq.PUB)
    s.setsockopt(zmq.SNDHWM, 1000)
    s.copy_threshold = ZERO_COPY_MIN  # the same per-frame copy policy as our publisher
    s.bind(ep)
    ready.wait()
    time.sleep(0.3)  # PUB has no barrier: give the subscription time to arrive
    payload = np.zeros(size, np.uint8)
    for i in range(n):
        s.send_multipart(
            [b"blob", time.monotonic_ns().to_bytes(8, "little") + i.to_bytes(4, "little"), payload], copy=False
        )
        if gap:
            time.sleep(gap)
    s.send_multipart([b"blob", b"\0" * 8 + b"\xff\xff\xff\xff", b""])
    time.sleep(0.5)
    s.close(linger=0)
    ctx.term()


def _raw_sub(ep: str, q, ready) -> None:
    ctx = zmq.Context()
    s = ctx.socket(zmq.SUB)
    s.setsockopt(zmq.RCVHWM, 1000)
    s.setsockopt(zmq.SUBSCRIBE, b"")
    s.connect(ep)
    ready.set()
    lat, t_first, n = [], None, 0
    while True:
        if not s.poll(10000):
            break
        parts = s.recv_multipart(copy=False)
        head = parts[1].bytes
        if head[8:] == b"\xff\xff\xff\xff":
            break
        np.frombuffer(parts[2].buffer, np.uint8)
        stamp = int.from_bytes(head[:8], "little")
        now = time.monotonic_ns()
        lat.append(now - stamp)
        t_first = t_first or now
        t_last = now
        n += 1
    q.put((lat, n, (t_last - t_first) / 1e9 if n > 1 else 0.0, []))
    s.close()
    ctx.term()


def _paths(fast: bool) -> None:
    """The codec's fast path on (ours, as nodes run) or off (plain), in this process."""
    codec.use_fast_path(fast)


def _our_pub(root: str, n: int, size: int, gap: float, ready, fast: bool = True) -> None:
    _paths(fast)
    ctx = zmq.Context()
    pub = Publisher(ctx, "blob", ipc_endpoints(Path(root), "blob"), expected=1)
    payload = np.zeros(size, np.uint8)
    pub.wait_for_subscribers()
    for i in range(n):
        pub.send(Blob(stamp=time.monotonic_ns(), seq=i, data=payload))
        if gap:
            time.sleep(gap)
    pub.send_eos("bench", n - 1)
    pub.wait_delivered(30)
    pub.close()
    ctx.term()


def _our_sub(root: str, q, ready, delay: float = 0.0, fast: bool = True) -> None:
    _paths(fast)
    ctx = zmq.Context()
    sub = Subscriber(ctx, "blob", ipc_endpoints(Path(root), "blob"), RELIABLE)
    ready.set()
    lat, seqs, t_first, n = [], [], None, 0
    sock = sub.socket
    while True:
        if not sock.poll(10000):
            break
        msg = sub.receive()
        now = time.monotonic_ns()
        if msg is None:
            continue
        if not isinstance(msg, Blob):
            break
        lat.append(now - msg.stamp)
        seqs.append(msg.seq)
        t_first = t_first or now
        t_last = now
        n += 1
        if delay:
            time.sleep(delay)
    q.put((lat, n, (t_last - t_first) / 1e9 if n > 1 else 0.0, seqs))
    sub.close()
    ctx.term()


def _pinned(target, cpu: int | None, *args) -> None:
    """Run ``target(*args)`` on one CPU (with ZeroMQ's I/O thread, created later, inheriting it)."""
    if cpu is not None:
        os.sched_setaffinity(0, {cpu})
    target(*args)


def _placement() -> tuple[int | None, int | None]:
    """CPUs for the publisher and the subscriber: two different ones where there are two, so that
    every run, raw and ours, has the same placement (the scheduler otherwise puts the pair on one
    core in some runs and on two in others, which changes the wake-up time more than anything
    measured here).
    """
    cpus = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else []
    return (cpus[0], cpus[1]) if len(cpus) >= 2 and PIN else (None, None)


def run_pair(kind: str, n: int, size: int, gap: float, delay: float = 0.0):
    pub_cpu, sub_cpu = _placement()
    with tempfile.TemporaryDirectory(prefix="cpb-", dir="/tmp") as root:
        ready = mp.Event()
        q = mp.Queue()
        if kind == "raw":
            ep = f"ipc://{root}/raw"
            sub = mp.Process(target=_pinned, args=(_raw_sub, sub_cpu, ep, q, ready))
            pub = mp.Process(target=_pinned, args=(_raw_pub, pub_cpu, ep, n, size, gap, ready))
        else:
            fast = kind == "ours"
            sub = mp.Process(target=_pinned, args=(_our_sub, sub_cpu, root, q, ready, delay, fast))
            pub = mp.Process(target=_pinned, args=(_our_pub, pub_cpu, root, n, size, gap, ready, fast))
        sub.start()
        pub.start()
        result = q.get(timeout=120)
        pub.join(30)
        sub.join(30)
    return result


def _spread(ours: list[float], raw: list[float]) -> list[float]:
    paired = sorted(o / r for o, r in zip(ours, raw))
    return [round(paired[0], 3), round(statistics.median(paired), 3), round(paired[-1], 3)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--quick", action="store_true", help="fewer messages (smoke run)")
    ap.add_argument("--no-pin", action="store_true", help="let the scheduler place the two processes")
    args = ap.parse_args()
    global PIN
    PIN = not args.no_pin
    n_lat, n_thr, n_rel = (150, 500, 2000) if args.quick else (400, 3000, 10000)
    out: dict[str, object] = {"repeats": args.repeats}
    for size in SIZES:
        res: dict[str, list[float]] = {"raw": [], "ours": [], "plain": []}
        for r in range(args.repeats):
            for kind in KINDS if r % 2 == 0 else KINDS[::-1]:
                lat = run_pair(kind, n_lat, size, 0.002)[0][WARMUP:]
                res[kind].append(statistics.median(lat) / 1e3)
        ours, raw = statistics.median(res["ours"]), statistics.median(res["raw"])
        out[f"latency_us_raw_{size}B"] = round(raw, 1)
        out[f"latency_us_ours_{size}B"] = round(ours, 1)
        out[f"latency_ratio_{size}B"] = round(ours / raw, 3)
        out[f"latency_ratio_{size}B_spread"] = _spread(res["ours"], res["raw"])
        plain = statistics.median(res["plain"])
        out[f"latency_us_plain_{size}B"] = round(plain, 1)
        out[f"codec_fast_vs_plain_{size}B"] = round(ours / plain, 3)
        out[f"codec_fast_vs_plain_{size}B_spread"] = _spread(res["ours"], res["plain"])
        print(
            f"{size:>7} B  one-way median: raw {raw:.1f} us, ours {ours:.1f} us, plain {plain:.1f} us; per repeat "
            f"raw {[round(x) for x in res['raw']]}, ours {[round(x) for x in res['ours']]}, "
            f"plain {[round(x) for x in res['plain']]}",
            file=sys.stderr,
        )
    thr: dict[str, list[float]] = {"raw": [], "ours": [], "plain": []}
    for r in range(args.repeats):
        for kind in KINDS if r % 2 == 0 else KINDS[::-1]:
            _, n, dt, _ = run_pair(kind, n_thr, 76800, 0.0)
            thr[kind].append(n / dt)
    out["throughput_msgs_raw_76800B"] = round(statistics.median(thr["raw"]))
    out["throughput_msgs_ours_76800B"] = round(statistics.median(thr["ours"]))
    out["throughput_ratio_76800B"] = round(statistics.median(thr["ours"]) / statistics.median(thr["raw"]), 3)
    out["throughput_ratio_76800B_spread"] = _spread(thr["ours"], thr["raw"])
    out["throughput_msgs_plain_76800B"] = round(statistics.median(thr["plain"]))
    out["codec_fast_vs_plain_throughput_76800B"] = round(
        statistics.median(thr["ours"]) / statistics.median(thr["plain"]), 3
    )
    _, n, _, seqs = run_pair("ours", n_rel, 64, 0.0, delay=0.00005)
    out["reliable_messages"] = n_rel
    out["reliable_drops"] = n_rel - len(set(seqs))
    out["reliable_in_order"] = seqs == sorted(seqs)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
