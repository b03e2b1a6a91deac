"""Bus benchmark: our publish/subscribe against raw pyzmq PUB/SUB carrying the same payloads.

Each measurement runs a publisher and a subscriber in two processes over ipc:// on this host:
- latency: 400 messages paced 2 ms apart; one-way latency = receive time - send stamp
  (CLOCK_MONOTONIC is shared by processes); medians compared as ours / raw;
- throughput: 3,000 messages of 76,800 B sent as fast as possible; messages per second at the
  receiver, ours / raw (raw PUB may drop under load; it is counted at the receiver all the same);
- reliable_drops: 10,000 messages through our reliable policy to a slower subscriber.
Repeated ``--repeats`` times in alternation; ratios of medians. Last stdout line: one JSON object.
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

from bus.endpoints import ipc_endpoints  # noqa: E402
from bus.transport import RELIABLE, Publisher, Subscriber  # noqa: E402
from messages import message  # noqa: E402


@message("bench.Blob", 1)
class Blob:
    data: np.ndarray = np.zeros(0, np.uint8)


SIZES = (64, 76800, 921600)


def _raw_pub(ep: str, n: int, size: int, gap: float, ready) -> None:
    ctx = zmq.Context()
    s = ctx.socket(zmq.PUB)
    s.setsockopt(zmq.SNDHWM, 1000)
    s.bind(ep)
    ready.wait()
    time.sleep(0.3)  # PUB has no barrier: give the subscription time to arrive
    payload = np.zeros(size, np.uint8)
    for i in range(n):
        s.send_multipart([b"blob", time.monotonic_ns().to_bytes(8, "little"), i.to_bytes(4, "little"), payload], copy=size > 10000)
        if gap:
            time.sleep(gap)
    s.send_multipart([b"blob", b"\0" * 8, b"\xff\xff\xff\xff", b""])
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
        now = time.monotonic_ns()
        if parts[2].bytes == b"\xff\xff\xff\xff":
            break
        np.frombuffer(parts[3].buffer, np.uint8)
        lat.append(now - int.from_bytes(parts[1].bytes, "little"))
        t_first = t_first or now
        t_last = now
        n += 1
    q.put((lat, n, (t_last - t_first) / 1e9 if n > 1 else 0.0, []))
    s.close()
    ctx.term()


def _our_pub(root: str, n: int, size: int, gap: float, ready) -> None:
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


def _our_sub(root: str, q, ready, delay: float = 0.0) -> None:
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


def run_pair(kind: str, n: int, size: int, gap: float, delay: float = 0.0):
    root = tempfile.mkdtemp(prefix="cpb-", dir="/tmp")
    ready = mp.Event()
    q = mp.Queue()
    if kind == "raw":
        ep = f"ipc://{root}/raw"
        sub = mp.Process(target=_raw_sub, args=(ep, q, ready))
        pub = mp.Process(target=_raw_pub, args=(ep, n, size, gap, ready))
    else:
        sub = mp.Process(target=_our_sub, args=(root, q, ready, delay))
        pub = mp.Process(target=_our_pub, args=(root, n, size, gap, ready))
    sub.start()
    pub.start()
    result = q.get(timeout=120)
    pub.join(30)
    sub.join(30)
    return result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="fewer messages (smoke run)")
    args = ap.parse_args()
    n_lat, n_thr, n_rel = (100, 500, 2000) if args.quick else (400, 3000, 10000)
    out: dict[str, float | int] = {}
    for size in SIZES:
        ours, raw = [], []
        for _ in range(args.repeats):
            raw.append(statistics.median(run_pair("raw", n_lat, size, 0.002)[0]) / 1e3)
            ours.append(statistics.median(run_pair("ours", n_lat, size, 0.002)[0]) / 1e3)
        out[f"latency_us_raw_{size}B"] = round(statistics.median(raw), 1)
        out[f"latency_us_ours_{size}B"] = round(statistics.median(ours), 1)
        out[f"latency_ratio_{size}B"] = round(statistics.median(ours) / statistics.median(raw), 3)
        print(f"{size:>7} B  one-way median: raw {out[f'latency_us_raw_{size}B']} us, ours {out[f'latency_us_ours_{size}B']} us", file=sys.stderr)
    thr_ours, thr_raw = [], []
    for _ in range(args.repeats):
        _, n, dt, _ = run_pair("raw", n_thr, 76800, 0.0)
        thr_raw.append(n / dt)
        _, n, dt, _ = run_pair("ours", n_thr, 76800, 0.0)
        thr_ours.append(n / dt)
    out["throughput_msgs_raw_76800B"] = round(statistics.median(thr_raw))
    out["throughput_msgs_ours_76800B"] = round(statistics.median(thr_ours))
    out["throughput_ratio_76800B"] = round(statistics.median(thr_ours) / statistics.median(thr_raw), 3)
    _, n, _, seqs = run_pair("ours", n_rel, 64, 0.0, delay=0.00005)
    out["reliable_messages"] = n_rel
    out["reliable_drops"] = n_rel - len(set(seqs))
    out["reliable_in_order"] = seqs == sorted(seqs)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
