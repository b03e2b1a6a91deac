"""Bags: MCAP round trips, crash recovery after a real SIGKILL, record and replay in real launched
graphs (compared byte for byte), and the ``counterpart bag`` commands.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest
import yaml

from counterpart.bus.bag import BagReader, BagWriter, decode_fields, pack_parts, unpack_parts
from counterpart.bus.bag_nodes import Player, Recorder
from counterpart.bus.cli_bag import export_bag
from counterpart.bus.params import ParamError
from counterpart.messages import Frame, encode
from tests.graph_nodes import Number

REPO = Path(__file__).resolve().parents[1]
N = "tests.graph_nodes:"


# ------------------------------------------------------------------------------------ helpers


@pytest.fixture
def home() -> Iterator[Path]:
    """A private COUNTERPART_HOME (short, for ipc paths) so that 'latest' and the standalone folder
    are this test's own, whatever else runs on the machine.
    """
    d = Path(tempfile.mkdtemp(prefix="cpbag"))
    try:
        yield d
    finally:
        shutil.rmtree(d, ignore_errors=True)


def _env(home: Path) -> dict[str, str]:
    return {**os.environ, "COUNTERPART_HOME": str(home)}


def _start(args: list[str], home: Path, **kw: Any) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "counterpart.bus.cli", *args], cwd=REPO, env=_env(home), start_new_session=True, **kw
    )


def _kill(proc: subprocess.Popen) -> None:
    """Last-resort cleanup: the process group of a test's child (launch: its nodes too)."""
    if proc.poll() is None:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    try:
        proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        pass


def _launch(doc: dict, tmp: Path, home: Path, name: str = "g.yaml", timeout: float = 60) -> str:
    """Run a launch file to its end; returns its output, asserting exit code 0."""
    f = tmp / name
    f.write_text(yaml.safe_dump(doc, sort_keys=False))
    proc = _start(["launch", str(f)], home, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        out, _ = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        _kill(proc)
        out, _ = proc.communicate()
        pytest.fail(f"the launch of {name} did not end within {timeout} s:\n{out}")
    finally:
        _kill(proc)
    assert proc.returncode == 0, out
    return out


def _wait(pred: Any, timeout: float = 30.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if pred():
            return True
        time.sleep(0.05)
    return False


def _numbers(n: int, size: int = 37) -> list[Number]:
    rng = np.random.default_rng(0)
    return [
        Number(
            stamp=1_000_000 + 1000 * i,
            seq=i,
            value=float(i) * 0.5,
            payload=rng.integers(0, 256, size + i, dtype=np.uint8),
        )
        for i in range(n)
    ]


def _payload(i: int, size: int) -> np.ndarray:
    return np.arange(size, dtype=np.uint64).astype(np.uint8)  # what tests.graph_nodes.Counter sends


def _parts_bytes(parts: list[Any]) -> list[bytes]:
    return [bytes(p) for p in parts]


# ---------------------------------------------------------------------------------- in process


def test_pack_parts_round_trip_and_rejects_damage() -> None:
    parts = [b"head", np.arange(5, dtype=np.float64).data, b"", memoryview(b"xyz")]
    blob = pack_parts(parts)
    assert _parts_bytes(unpack_parts(blob)) == [b"head", np.arange(5, dtype=np.float64).tobytes(), b"", b"xyz"]
    with pytest.raises(ValueError, match="parts"):
        unpack_parts(blob[:-1])


@pytest.mark.parametrize("compression", ["zstd", "lz4", "none"])
def test_write_read_round_trip_is_bit_exact(tmp_path: Path, compression: str) -> None:
    nums = _numbers(60)
    frames = [
        Frame(stamp=5_000 + i, seq=i, image=np.random.default_rng(i).integers(0, 256, (24, 32, 3), np.uint8))
        for i in range(20)
    ]
    wire: list[tuple[str, list[bytes]]] = []
    with BagWriter(tmp_path / "b.mcap", compression=compression, chunk_size=4096) as w:
        for i, m in enumerate(nums):
            parts = _parts_bytes(encode(m, counter=i))
            w.write("numbers", parts, log_time=10_000 + i)
            wire.append(("numbers", parts))
            if i % 3 == 0:
                f = frames[i // 3]
                fparts = _parts_bytes(encode(f, counter=i // 3))
                w.write("cam/frames", fparts, log_time=10_000 + i)
                wire.append(("cam/frames", fparts))
    r = BagReader(tmp_path / "b.mcap")
    recs = list(r.records())
    assert r.complete and r.recovered == len(wire)
    assert [(x.topic, _parts_bytes(x.parts)) for x in recs] == wire
    assert [x.publish_time for x in recs if x.topic == "numbers"] == [m.stamp for m in nums]
    assert [x.sequence for x in recs if x.topic == "numbers"] == list(range(60))
    decoded = [m for t, _, m in r.messages(["numbers"], decode_messages=True)]
    assert [m.seq for m in decoded] == list(range(60))
    assert all(np.array_equal(a.payload, b.payload) and a.value == b.value for a, b in zip(decoded, nums))
    got_frames = [m for _, _, m in r.messages(["cam/frames"], decode_messages=True)]
    assert all(np.array_equal(a.image, b.image) for a, b in zip(got_frames, frames))

    info = r.info()
    assert info["complete"] and info["messages"] == 80
    assert info["topics"] == {
        "numbers": {"type": "test.Number/1", "count": 60},
        "cam/frames": {"type": "camera.Frame/1", "count": 20},
    }
    assert (info["start_ns"], info["end_ns"]) == (10_000, 10_059)
    assert info["schemas"]["camera.Frame/1"]["fields"]["image"] == "ndarray"
    assert r.topics() == {"numbers": "test.Number/1", "cam/frames": "camera.Frame/1"}


def test_truncated_file_reads_up_to_the_last_flushed_chunk(tmp_path: Path) -> None:
    path = tmp_path / "b.mcap"
    w = BagWriter(path)
    for i, m in enumerate(_numbers(30)):
        w.write_message("numbers", m)
        if i in (9, 19):
            w.flush()
    w.close()
    data = path.read_bytes()
    sizes_at = {}  # flushed message count -> smallest prefix holding them
    for cut in range(0, len(data), 97):
        (tmp_path / "cut.mcap").write_bytes(data[:cut])
        r = BagReader(tmp_path / "cut.mcap")
        seqs = [int(decode_fields(x.parts)[1]["seq"]) for x in r.records()]
        assert r.truncated and r.error
        assert seqs == list(range(len(seqs))) and len(seqs) in (0, 10, 20, 30)
        sizes_at.setdefault(len(seqs), cut)
        assert r.info()["messages"] == len(seqs)
    assert set(sizes_at) >= {0, 10, 20}


def test_export_writes_jsonl_npy_and_png(tmp_path: Path) -> None:
    img = np.random.default_rng(1).integers(0, 256, (20, 30, 3), np.uint8)
    mono = np.random.default_rng(2).integers(0, 256, (16, 12), np.uint8)
    with BagWriter(tmp_path / "b.mcap") as w:
        w.write_message("cam", Frame(stamp=7, seq=0, image=img, source="sim"))
        w.write_message("cam", Frame(stamp=8, seq=1, image=mono, encoding="mono8"))
        for m in _numbers(3):
            w.write_message("num/bers", m)
    counts = export_bag(tmp_path / "b.mcap", tmp_path / "out")
    assert counts == {"cam": 2, "num/bers": 3}
    cam = [json.loads(line) for line in (tmp_path / "out" / "cam.jsonl").read_text().splitlines()]
    assert [c["seq"] for c in cam] == [0, 1] and cam[0]["source"] == "sim" and cam[1]["encoding"] == "mono8"
    assert cam[0]["_type"] == "camera.Frame/1" and cam[0]["image"].endswith(".png")
    assert np.array_equal(cv2.imread(str(tmp_path / "out" / cam[0]["image"]), cv2.IMREAD_UNCHANGED), img)
    assert np.array_equal(cv2.imread(str(tmp_path / "out" / cam[1]["image"]), cv2.IMREAD_UNCHANGED), mono)
    nums = [json.loads(line) for line in (tmp_path / "out" / "num_bers.jsonl").read_text().splitlines()]
    assert [n["value"] for n in nums] == [0.0, 0.5, 1.0]
    for n, m in zip(nums, _numbers(3)):
        assert n["payload"].endswith(".npy")
        assert np.array_equal(np.load(tmp_path / "out" / n["payload"]), m.payload)


def test_player_names_an_unregistered_schema(tmp_path: Path) -> None:
    with BagWriter(tmp_path / "b.mcap") as w:
        w.write_message("numbers", _numbers(1)[0])
        parts = _parts_bytes(encode(_numbers(1)[0]))
        # the same wire message under a schema id that no module registers
        import msgpack

        head = msgpack.unpackb(parts[0], raw=False)
        head["s"] = "nowhere.Thing/3"
        w.write("things", [msgpack.packb(head, use_bin_type=True), *parts[1:]])
    with pytest.raises(ParamError, match=r"nowhere\.Thing/3.*modules"):
        Player.ports(Player.validate_params({"path": str(tmp_path / "b.mcap")}))
    params = Player.validate_params(
        {"path": str(tmp_path / "b.mcap"), "topics": ["numbers"], "remap": {"numbers": "n2"}}
    )
    _, outs = Player.ports(params)
    assert list(outs) == ["n2"] and outs["n2"].type is Number
    with pytest.raises(ParamError, match=r"'topics': nothing not in bag"):
        Player.ports(Player.validate_params({"path": str(tmp_path / "b.mcap"), "topics": ["nothing"]}))
    with pytest.raises(ParamError, match="'topics': name at least one topic"):
        Recorder.ports(Recorder.validate_params({"path": "x.mcap"}))
    info = BagReader(tmp_path / "b.mcap").info()
    assert info["schemas"]["nowhere.Thing/3"]["inferred"] is True
    assert info["schemas"]["nowhere.Thing/3"]["fields"]["payload"].startswith("ndarray[uint8")


# ------------------------------------------------------------------------------- real processes


def test_launched_recorder_then_player_replays_bit_exact(tmp_path: Path, home: Path) -> None:
    count, size = 250, 300
    bag1, bag2 = tmp_path / "one.mcap", tmp_path / "two.mcap"
    _launch(
        {
            "nodes": {
                "source": {
                    "run": N + "Counter",
                    "params": {"count": count, "payload_bytes": size},
                    "remap": {"out": "numbers"},
                },
                "rec": {
                    "run": "counterpart.bus.bag_nodes:Recorder",
                    "params": {"path": str(bag1), "topics": ["numbers"], "flush_period": 0.05},
                },
            }
        },
        tmp_path,
        home,
        "record.yaml",
    )
    r1 = BagReader(bag1)
    first = list(r1.records())
    assert r1.complete and len(first) == count
    values = [decode_fields(x.parts)[1] for x in first]
    assert [v["seq"] for v in values] == list(range(count)) and [v["value"] for v in values] == [
        float(i) for i in range(count)
    ]
    assert all(np.array_equal(v["payload"], _payload(i, size)) for i, v in enumerate(values))
    # the recorder does not import tests.graph_nodes: the schema was described from the wire
    assert BagReader(bag1).info()["schemas"]["test.Number/1"]["inferred"] is True

    sink = tmp_path / "sink.jsonl"
    _launch(
        {
            "nodes": {
                "play": {
                    "run": "counterpart.bus.bag_nodes:Player",
                    "params": {
                        "path": str(bag1),
                        "lockstep": True,
                        "modules": ["tests.graph_nodes"],
                        "remap": {"numbers": "replayed"},
                    },
                },
                "sink": {"run": N + "Sink", "params": {"path": str(sink)}, "remap": {"in": "replayed"}},
                "rec": {
                    "run": "counterpart.bus.bag_nodes:Recorder",
                    "params": {"path": str(bag2), "topics": ["replayed"]},
                },
            }
        },
        tmp_path,
        home,
        "replay.yaml",
    )
    rows = [json.loads(line) for line in sink.read_text().splitlines()]
    got = [r for r in rows if "seq" in r]
    expected_sum = int(_payload(0, size).sum())
    assert [(r["seq"], r["value"], r["sum"]) for r in got] == [(i, float(i), expected_sum) for i in range(count)]
    assert rows[-1] == {"event": "end", "drops": 0}
    second = list(BagReader(bag2).records())
    assert [x.topic for x in second] == ["replayed"] * count
    assert [_parts_bytes(x.parts) for x in second] == [_parts_bytes(x.parts) for x in first]


def test_sigkilled_recorder_leaves_a_readable_bag(tmp_path: Path, home: Path) -> None:
    size = 2000
    f = tmp_path / "g.yaml"
    f.write_text(
        yaml.safe_dump(
            {
                "nodes": {
                    "source": {
                        "run": N + "Counter",
                        "params": {"count": 100000, "rate": 200.0, "payload_bytes": size},
                        "remap": {"out": "numbers"},
                    }
                }
            }
        )
    )
    launch = _start(["launch", str(f)], home, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    bag = tmp_path / "killed.mcap"
    rec = None
    try:
        assert _wait(lambda: (home / "latest" / "registry.json").is_file()), "the launch did not start"
        with open(tmp_path / "rec.log", "w") as log:
            rec = _start(["bag", "record", "-t", "numbers", "-o", str(bag)], home, stdout=log, stderr=log)
        # read the bag while it is being written until flushed messages show up, then a bit more
        seen = [0]

        def flushed(minimum: int) -> bool:
            seen[0] = sum(1 for _ in BagReader(bag).records()) if bag.exists() else 0
            return seen[0] >= minimum

        assert _wait(lambda: flushed(1)), (tmp_path / "rec.log").read_text()
        first_seen = seen[0]
        assert _wait(lambda: flushed(first_seen + 100)), (tmp_path / "rec.log").read_text()
        before = seen[0]
        os.kill(rec.pid, signal.SIGKILL)
        rec.wait(timeout=10)
        assert rec.returncode == -signal.SIGKILL
    finally:
        if rec is not None:
            _kill(rec)
        os.killpg(launch.pid, signal.SIGINT)
        try:
            launch.wait(timeout=15)
        finally:
            _kill(launch)
    r = BagReader(bag)
    values = [decode_fields(x.parts)[1] for x in r.records()]
    assert r.truncated and r.recovered == len(values) >= before
    seqs = [v["seq"] for v in values]
    assert seqs == list(range(seqs[0], seqs[0] + len(seqs)))  # contiguous: nothing lost before the cut
    assert all(np.array_equal(v["payload"], _payload(0, size)) for v in values)
    info = BagReader(bag).info()
    assert not info["complete"] and info["topics"]["numbers"]["count"] == len(values)


def test_cli_record_until_end_of_stream_then_info_and_play(tmp_path: Path, home: Path) -> None:
    count = 500
    f = tmp_path / "g.yaml"
    f.write_text(
        yaml.safe_dump(
            {
                "nodes": {
                    "source": {
                        "run": N + "Counter",
                        "params": {"count": count, "rate": 100.0, "payload_bytes": 16},
                        "remap": {"out": "numbers"},
                    }
                }
            }
        )
    )
    launch = _start(["launch", str(f)], home, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    bag = tmp_path / "cli.mcap"
    rec = None
    try:
        assert _wait(lambda: (home / "latest" / "registry.json").is_file()), "the launch did not start"
        rec = _start(
            ["bag", "record", "--all", "-o", str(bag)],
            home,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        out, _ = rec.communicate(timeout=30)
        assert rec.returncode == 0, out
        assert "end of stream on every topic" in out
        launch.wait(timeout=20)
    finally:
        if rec is not None:
            _kill(rec)
        _kill(launch)
    r = BagReader(bag)
    seqs = [decode_fields(x.parts)[1]["seq"] for x in r.records()]
    assert r.complete and seqs and seqs == list(range(seqs[0], count))  # joined late, then every message

    info = subprocess.run(
        [sys.executable, "-m", "counterpart.bus.cli", "bag", "info", str(bag), "--json"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert info.returncode == 0, info.stderr
    data = json.loads(info.stdout)
    assert data["topics"] == {"numbers": {"type": "test.Number/1", "count": len(seqs)}}  # --all skips stats
    assert data["complete"] and data["duration_s"] > 0

    # play on the standalone endpoints, lockstep, into a node started with `counterpart run`
    sink = tmp_path / "sink.jsonl"
    node = _start(
        ["run", "tests.graph_nodes:Sink", "--param", f"path={sink}", "--remap", "in=again"],
        home,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    player = None
    try:
        player = _start(
            ["bag", "play", str(bag), "--lockstep", "--remap", "numbers=again", "--module", "tests.graph_nodes"],
            home,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        out, _ = player.communicate(timeout=40)
        assert player.returncode == 0, out
        node.wait(timeout=20)
        assert node.returncode == 0
    finally:
        if player is not None:
            _kill(player)
        _kill(node)
    rows = [json.loads(line) for line in sink.read_text().splitlines()]
    assert [r["seq"] for r in rows if "seq" in r] == seqs
    assert rows[-1]["event"] == "end"


def test_player_paces_loops_and_resends_exact_parts(
    tmp_path: Path, home: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import threading

    import zmq

    from counterpart.bus.endpoints import TopicEndpoints
    from counterpart.bus.node import standalone_spec
    from counterpart.bus.transport import Subscriber

    monkeypatch.setenv("COUNTERPART_HOME", str(home))
    bag = tmp_path / "b.mcap"
    with BagWriter(bag) as w:
        for i, m in enumerate(_numbers(20)):
            w.write("numbers", _parts_bytes(encode(m, counter=i)), log_time=10_000_000 * i)  # 10 ms apart
    recorded = [_parts_bytes(x.parts) for x in BagReader(bag).records()]
    spec = standalone_spec("player", Player, {"path": str(bag), "rate": 4.0, "loop": True}, {}, {})
    spec["outputs"]["numbers"]["reliable_subscribers"] = 1  # start once the subscriber below is there
    player = Player(spec)
    ctx = zmq.Context()
    sub = Subscriber(ctx, "numbers", TopicEndpoints.from_dict(spec["outputs"]["numbers"]["endpoints"]), raw=True)
    thread = threading.Thread(target=player.run)
    thread.start()
    got: list[list[bytes]] = []
    try:
        deadline = time.monotonic() + 20
        while len(got) < 45 and time.monotonic() < deadline:
            if sub.socket.poll(100):
                msg = sub.receive()
                if msg is not None:
                    got.append(_parts_bytes(msg.parts))
    finally:
        player.stopping = True
        thread.join(timeout=10)
        sub.close()
        ctx.term()
    assert not thread.is_alive()
    assert got[:45] == (recorded * 3)[:45]
