"""Collect the latest ``NODE/stats`` of a running launch in a background thread (demo, e2e bench)."""
from __future__ import annotations

import json
import threading
import time
from pathlib import Path
from typing import Any

import zmq

from messages import NodeStats

from .endpoints import TopicEndpoints
from .transport import LATEST, Subscriber


class StatsWatcher(threading.Thread):
    """Subscribes (latest policy) to every ``*/stats`` topic in ``run_dir/registry.json`` once it
    appears, and keeps the newest :class:`NodeStats` per node in :attr:`latest`."""

    def __init__(self, run_dir: Path) -> None:
        super().__init__(daemon=True, name="stats-watch")
        self.run_dir = Path(run_dir)
        self.latest: dict[str, NodeStats] = {}
        self._stop_event = threading.Event()

    def stop(self) -> None:
        self._stop_event.set()
        self.join(timeout=2)

    def _topics(self) -> dict[str, TopicEndpoints]:
        path = self.run_dir / "registry.json"
        while not self._stop_event.is_set():
            try:
                reg = json.loads(path.read_text())
                return {t: TopicEndpoints.from_dict(info["endpoints"]) for t, info in reg["topics"].items()
                        if t.endswith("/stats") and info.get("endpoints")}
            except (OSError, ValueError, KeyError):
                time.sleep(0.05)
        return {}

    def run(self) -> None:
        ctx = zmq.Context()
        subs = [Subscriber(ctx, t, ep, LATEST) for t, ep in self._topics().items()]
        poller = zmq.Poller()
        owner = {}
        for s in subs:
            for sock in s.sockets:  # the end-of-stream socket too: publishers wait for it to be read
                poller.register(sock, zmq.POLLIN)
                owner[sock] = s
        while not self._stop_event.is_set():
            for sock, _ in poller.poll(100):
                msg = owner[sock].receive()
                if isinstance(msg, NodeStats):
                    self.latest[msg.node] = msg
        for s in subs:
            s.close()
        ctx.term()


def stats_table(stats: dict[str, NodeStats]) -> str:
    """A plain-text table: per node, messages in/out, rates, drops, latency and handler time."""
    rows = [f"{'node':12s} {'in':>7s} {'out':>7s} {'in Hz':>7s} {'drops':>6s} {'lat ms':>7s} {'proc ms':>8s} {'bad':>4s}"]
    for name, st in sorted(stats.items()):
        n_in = sum(t.count for t in st.inputs)
        n_out = sum(t.count for t in st.outputs)
        hz = max((t.rate_hz for t in st.inputs), default=0.0)
        drops = sum(t.drops for t in st.inputs)
        lat = max((t.latency_ms for t in st.inputs), default=0.0)
        rows.append(f"{name:12s} {n_in:7d} {n_out:7d} {hz:7.1f} {drops:6d} {lat:7.1f} {st.proc_ms_mean:8.2f} "
                    f"{sum(st.decode_errors.values()):4d}")
    return "\n".join(rows)


def stats_json(stats: dict[str, NodeStats]) -> dict[str, Any]:
    from .cli_introspect import summarise

    return {name: summarise(st) for name, st in stats.items()}
