"""The runtime with real processes and sockets: the real launcher, real nodes, real signals."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import msgpack
import numpy as np
import psutil
import pytest
import zmq

from counterpart.bus.endpoints import tcp_endpoints
from counterpart.messages import EndOfStream, encode_frames
from tests.graph_nodes import Number
from tests.launching import (
    REPO,
    descendants,
    free_port_pair,
    kill_tree,
    read_jsonl,
    run_launch,
    start_launch,
    stop_launch,
    wait_for,
    write_launch,
)

N = "tests.graph_nodes:"


def chain(tmp: Path, count: int = 300, **sink_params) -> dict:
    return {
        "nodes": {
            "source": {
                "run": N + "Counter",
                "params": {"count": count, "payload_bytes": 64},
                "remap": {"out": "numbers"},
            },
            "relay": {"run": N + "Relay", "params": {"gain": 2.0}, "remap": {"in": "numbers", "out": "doubled"}},
            "sink": {
                "run": N + "Sink",
                "params": {"path": str(tmp / "sink.jsonl"), **sink_params},
                "remap": {"in": "doubled"},
            },
        }
    }


def received(path: Path) -> list[dict]:
    return [r for r in read_jsonl(path) if "seq" in r]


def test_reliable_chain_delivers_every_message_in_order_and_ends_by_itself(tmp_path: Path) -> None:
    f = write_launch(tmp_path / "g.yaml", chain(tmp_path, count=400, delay_ms=1.0))
    code, out = run_launch(f, timeout=60)
    assert code == 0, out
    rows = received(tmp_path / "sink.jsonl")
    assert [r["seq"] for r in rows] == list(range(400))
    assert [r["value"] for r in rows] == [2.0 * i for i in range(400)]
    expected_sum = int(np.arange(64, dtype=np.uint64).astype(np.uint8).sum())
    assert all(r["sum"] == expected_sum for r in rows)
    assert read_jsonl(tmp_path / "sink.jsonl")[-1] == {"event": "end", "drops": 0}


def test_a_node_given_nice_runs_at_that_much_lower_priority(tmp_path: Path) -> None:
    doc = chain(tmp_path, count=50)
    doc["nodes"]["sink"]["nice"] = 7
    f = write_launch(tmp_path / "g.yaml", doc)
    code, out = run_launch(f, timeout=60)
    assert code == 0, out
    starts = [r for r in read_jsonl(tmp_path / "sink.jsonl") if r.get("event") == "start"]
    assert [r["nice"] for r in starts] == [min(os.nice(0) + 7, 19)]
    assert len(received(tmp_path / "sink.jsonl")) == 50


def test_each_node_gets_one_blas_and_opencv_thread_unless_the_environment_sets_another(tmp_path: Path) -> None:
    f = write_launch(tmp_path / "g.yaml", chain(tmp_path, count=5))
    unset = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OPENCV_FOR_THREADS_NUM")
    env = {k: v for k, v in os.environ.items() if k not in unset}
    for given, seen in ((None, ("1", 1)), ("3", ("3", 3))):
        given_env = {} if given is None else {"OMP_NUM_THREADS": given, "OPENCV_FOR_THREADS_NUM": given}
        code, out = run_launch(f, timeout=60, env={**env, **given_env})
        assert code == 0, out
        starts = [r for r in read_jsonl(tmp_path / "sink.jsonl") if r.get("event") == "start"]
        assert (starts[-1]["omp"], starts[-1]["opencv"]) == seen  # (the sink appends: the last start is this run's)


def test_latest_policy_drops_under_a_slow_consumer_and_counts_the_drops(tmp_path: Path) -> None:
    doc = chain(tmp_path, count=600, delay_ms=20.0)
    doc["nodes"]["source"]["params"]["rate"] = 300.0
    doc["nodes"]["sink"]["inputs"] = {"in": {"policy": "latest"}}
    f = write_launch(tmp_path / "g.yaml", doc)
    code, out = run_launch(f, timeout=60)
    assert code == 0, out
    rows = received(tmp_path / "sink.jsonl")
    end = read_jsonl(tmp_path / "sink.jsonl")[-1]
    seqs = [r["seq"] for r in rows]
    assert seqs == sorted(seqs) and len(set(seqs)) == len(seqs)  # newest first never goes backwards
    assert 10 < len(rows) < 400  # a 20 ms consumer cannot take 300 Hz
    # every message published after the first one received was delivered or counted as dropped
    # (the count may also include a few that reached the socket before the first one delivered)
    assert end["event"] == "end" and 600 - seqs[0] <= len(rows) + end["drops"] <= 600
    assert end["drops"] > 200


def test_a_latest_input_with_a_queue_keeps_the_newest_in_order_and_joins_the_startup_barrier(tmp_path: Path) -> None:
    # a burst of 40 at once into a 50 ms consumer: with the newest message only it keeps a few; with a
    # queue of 3 (launch file: inputs.in.queue) the 3 newest of what came while it was busy, in order,
    # down to the last one; with a queue of 48 every one
    for queue in (0, 3, 48):
        doc = chain(tmp_path, count=40, delay_ms=50.0)
        doc["nodes"]["sink"]["inputs"] = {"in": {"policy": "latest", "queue": queue}}
        # the queued subscriber counts at the startup barrier: without it the relay would wait out this
        # timeout for a reader that never joins its latest socket, and the run would not end in time
        doc["barrier_timeout"] = 600
        (tmp_path / "sink.jsonl").unlink(missing_ok=True)
        code, out = run_launch(write_launch(tmp_path / "g.yaml", doc), timeout=90)
        assert code == 0, out
        seqs = [r["seq"] for r in received(tmp_path / "sink.jsonl")]
        end = read_jsonl(tmp_path / "sink.jsonl")[-1]
        assert seqs == sorted(set(seqs)), seqs
        # every message after the first one received was delivered or counted as dropped (the count may
        # also include a few that reached the socket before the first one delivered)
        assert end["event"] == "end" and 40 - seqs[0] <= len(seqs) + end["drops"] <= 40, (seqs, end)
        if queue == 48:
            assert seqs == list(range(40)) and end["drops"] == 0
        else:
            assert len(seqs) < 30, (seqs, end)
        if queue == 3:  # the newest kept at every take (a full latest socket drops the newest instead)
            assert seqs[-1] == 39, seqs


def test_killed_node_with_restart_policy_comes_back(tmp_path: Path) -> None:
    doc = chain(tmp_path, count=100000)
    doc["nodes"]["source"]["params"]["rate"] = 200.0
    doc["nodes"]["sink"]["restart"] = "on-failure"
    f = write_launch(tmp_path / "g.yaml", doc)
    proc = start_launch(f)
    try:
        assert wait_for(lambda: len(received(tmp_path / "sink.jsonl")) > 20, 20)
        starts = [r for r in read_jsonl(tmp_path / "sink.jsonl") if r.get("event") == "start"]
        os.kill(starts[0]["pid"], signal.SIGKILL)
        assert wait_for(
            lambda: len([r for r in read_jsonl(tmp_path / "sink.jsonl") if r.get("event") == "start"]) == 2, 20
        )
        n = len(received(tmp_path / "sink.jsonl"))
        assert wait_for(lambda: len(received(tmp_path / "sink.jsonl")) > n + 20, 20)  # it receives again
    finally:
        stop_launch(proc)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGKILL])
def test_stopping_the_launcher_leaves_no_process(tmp_path: Path, sig: int) -> None:
    doc = chain(tmp_path, count=100000)
    doc["nodes"]["source"]["params"]["rate"] = 100.0
    f = write_launch(tmp_path / "g.yaml", doc)
    proc = start_launch(f)
    try:
        assert wait_for(lambda: len(received(tmp_path / "sink.jsonl")) > 5, 20)
        kids = descendants(proc.pid)
        assert len(kids) >= 3
        t0 = time.monotonic()
        proc.send_signal(sig)
        proc.wait(10)
        gone = wait_for(lambda: not any(k.is_running() and k.status() != psutil.STATUS_ZOMBIE for k in kids), 6)
        assert gone, [k.pid for k in kids if k.is_running()]
        assert time.monotonic() - t0 < 5.5
    finally:
        kill_tree(proc)


def test_required_node_exit_stops_the_graph_with_its_code(tmp_path: Path) -> None:
    doc = chain(tmp_path, count=100000)
    doc["nodes"]["source"]["params"]["rate"] = 100.0
    doc["nodes"]["sink"].update(
        required=True, params={**doc["nodes"]["sink"]["params"], "exit_after": 20, "exit_code": 7}
    )
    doc["nodes"]["relay"]["restart"] = "always"  # a required node's exit wins over restart policies
    f = write_launch(tmp_path / "g.yaml", doc)
    proc = start_launch(f)
    try:
        kids = []
        assert wait_for(lambda: kids.extend(descendants(proc.pid)) or len(kids) >= 3, 20)
        assert proc.wait(20) == 7
        assert len(received(tmp_path / "sink.jsonl")) == 20
        assert wait_for(lambda: not any(k.is_running() and k.status() != psutil.STATUS_ZOMBIE for k in kids), 5)
    finally:
        kill_tree(proc)


def test_rogue_publisher_does_not_stop_the_sink(tmp_path: Path) -> None:
    """Garbage, an unknown schema, a wrong field type and an oversized header reach a sink over tcp;
    it drops and counts them, keeps the good messages and ends normally.
    """
    port = free_port_pair()
    doc = {
        "external": {"numbers": {"type": "test.Number", "endpoint": f"tcp://127.0.0.1:{port}"}},
        "nodes": {
            "sink": {"run": N + "Sink", "params": {"path": str(tmp_path / "sink.jsonl")}, "remap": {"in": "numbers"}}
        },
    }
    f = write_launch(tmp_path / "g.yaml", doc)
    ctx = zmq.Context()
    rogue = ctx.socket(zmq.XPUB)
    rogue.setsockopt(zmq.XPUB_NODROP, 1)
    rogue.bind(tcp_endpoints(f"tcp://127.0.0.1:{port}").reliable)
    proc = start_launch(f)
    try:
        assert rogue.poll(20000), "the sink never subscribed"
        rogue.recv()
        good = lambda i: encode_frames("numbers", Number(seq=i, value=float(i)))  # noqa: E731
        bad = [
            [b"numbers", b"\xc1\xc1 not msgpack"],
            [b"numbers"],
            [b"numbers", msgpack.packb({"s": "nobody.Knows/9", "f": {}, "a": []})],
            [b"numbers", msgpack.packb({"s": "test.Number/1", "f": {"value": "NaN?"}, "a": []})],
            [b"numbers", b"\x81\xa1s" + msgpack.packb("x" * (3 << 20))],
            [b"numbers", msgpack.packb({"s": "test.Number/1", "f": {}, "a": [["<u1", [1 << 40]]]}), b"x"],
        ]
        for i in range(3):
            rogue.send_multipart(good(i))
            for b in bad:
                rogue.send_multipart(b)
        rogue.send_multipart(good(3))
        rogue.send_multipart(encode_frames("numbers", EndOfStream(seq=3)))
        code = proc.wait(20)
        out = proc.stdout.read()
        assert code == 0, out
        assert [r["seq"] for r in received(tmp_path / "sink.jsonl")] == [0, 1, 2, 3]
        assert "dropped a bad message" in out
        assert out.count("dropped a bad message") <= 5  # logged once per kind, not per message
    finally:
        kill_tree(proc)
        rogue.close()
        ctx.term()


def test_graph_split_over_two_launchers_delivers_over_tcp(tmp_path: Path) -> None:
    port = free_port_pair()
    a = write_launch(
        tmp_path / "a.yaml",
        {
            "endpoints": {"numbers": f"tcp://127.0.0.1:{port}"},
            "nodes": {
                "source": {
                    "run": N + "Counter",
                    "params": {"count": 200},
                    "remap": {"out": "numbers"},
                    "wait_subscribers": {"out": 1},
                }
            },
        },
    )
    b = write_launch(
        tmp_path / "b.yaml",
        {
            "external": {"numbers": {"type": "test.Number", "endpoint": f"tcp://127.0.0.1:{port}"}},
            "nodes": {
                "relay": {"run": N + "Relay", "params": {"gain": 3.0}, "remap": {"in": "numbers", "out": "tripled"}},
                "sink": {
                    "run": N + "Sink",
                    "params": {"path": str(tmp_path / "sink.jsonl")},
                    "remap": {"in": "tripled"},
                },
            },
        },
    )
    pa, pb = start_launch(a), start_launch(b)
    try:
        assert pa.wait(40) == 0, pa.stdout.read()
        assert pb.wait(40) == 0, pb.stdout.read()
        rows = received(tmp_path / "sink.jsonl")
        assert [r["value"] for r in rows] == [3.0 * i for i in range(200)]
        listening = [
            c for c in psutil.net_connections("tcp") if c.status == "LISTEN" and c.laddr.port in (port, port + 1)
        ]
        assert all(c.laddr.ip == "127.0.0.1" for c in listening)
    finally:
        kill_tree(pa)
        kill_tree(pb)


def test_introspection_lists_nodes_and_topics_and_echoes(tmp_path: Path) -> None:
    doc = chain(tmp_path, count=100000)
    doc["nodes"]["source"]["params"]["rate"] = 50.0
    f = write_launch(tmp_path / "g.yaml", doc)
    home = tempfile.mkdtemp(prefix="cp-", dir="/tmp")  # short: unix socket paths are limited to 107 bytes
    env = {"COUNTERPART_HOME": home}
    proc = start_launch(f, env=env)

    def cli(*a: str) -> subprocess.CompletedProcess:
        return subprocess.run(
            [sys.executable, "-m", "counterpart.bus.cli", *a],
            cwd=REPO,
            capture_output=True,
            text=True,
            timeout=30,
            env={**os.environ, **env},
        )

    try:
        assert wait_for(lambda: len(received(tmp_path / "sink.jsonl")) > 5, 20)
        nodes = cli("node", "list")
        assert nodes.returncode == 0 and all(n in nodes.stdout for n in ("source", "relay", "sink")), nodes.stderr
        topics = cli("topic", "list")
        assert "doubled" in topics.stdout and "test.Number/1" in topics.stdout and "sink/stats" in topics.stdout
        echo = cli("topic", "echo", "doubled", "-n", "3", "--timeout", "10")
        lines = [json.loads(x) for x in echo.stdout.splitlines()]
        assert len(lines) == 3 and all(x["type"] == "test.Number/1" for x in lines)
        assert all(x["msg"]["value"] == 2 * x["msg"]["seq"] for x in lines)
        hz = cli("topic", "hz", "numbers", "--window", "1.5", "-n", "1")
        rate = float(hz.stdout.split()[1])
        assert 35 < rate < 65, hz.stdout
        stats = cli("topic", "echo", "sink/stats", "-n", "1", "--timeout", "5")
        st = json.loads(stats.stdout)["msg"]
        assert st["node"] == "sink" and st["inputs"][0]["topic"] == "doubled" and st["inputs"][0]["count"] > 0
    finally:
        stop_launch(proc)
    gone = cli("topic", "echo", "doubled", "-n", "1")
    assert gone.returncode != 0 and "not running" in gone.stderr
    shutil.rmtree(home, ignore_errors=True)
