"""Every kind of launch-file error is caught before any process starts, naming file, node and key."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from counterpart.bus.launchfile import LaunchError, check, load
from tests.launching import run_launch, write_launch

N = "tests.graph_nodes:"
GOOD = {
    "source": {"run": N + "Counter", "params": {"count": 3}, "remap": {"out": "numbers"}},
    "sink": {"run": N + "Sink", "params": {"path": "/dev/null"}, "remap": {"in": "numbers"}},
}


def with_node(name: str, **changes) -> dict:
    nodes = {k: dict(v) for k, v in GOOD.items()}
    nodes[name].update(changes)
    return {"nodes": nodes}


CASES = [
    ("missing run", with_node("sink", run=None), "node 'sink': run: missing"),
    (
        "unknown module",
        with_node("sink", run="no.such.module"),
        "node 'sink': run: cannot find a node in 'no.such.module'",
    ),
    (
        "old module path",
        with_node("sink", run="nodes.tracker"),
        "node 'sink': run: 'nodes.tracker' is the old module path: the project's modules are under 'counterpart' now; "
        "write 'counterpart.nodes.tracker'",
    ),
    (
        "unknown class",
        with_node("sink", run="tests.graph_nodes:Nope"),
        "node 'sink': run: 'tests.graph_nodes' has no Node class 'Nope'",
    ),
    ("unknown param", with_node("source", params={"cuont": 3}), "node 'source': params: unknown parameter(s) 'cuont'"),
    ("wrong type", with_node("source", params={"count": "many"}), "parameter 'count': expected int"),
    ("below minimum", with_node("source", params={"count": -1}), "parameter 'count': -1 is below the minimum 0"),
    ("failing check", with_node("sink", params={"path": ""}), "parameter 'path': must name a file"),
    (
        "no publisher",
        with_node("sink", remap={"in": "nobody"}),
        "node 'sink': inputs.in: no node publishes topic 'nobody'",
    ),
    ("bad remap port", with_node("sink", remap={"inn": "numbers"}), "node 'sink': remap.inn: Sink has no port 'inn'"),
    (
        "bad policy",
        with_node("sink", policy="sometimes"),
        "node 'sink': policy: 'sometimes' is not one of reliable, latest",
    ),
    ("bad input policy", with_node("sink", inputs={"in": {"policy": "x"}}), "node 'sink': inputs.in.policy"),
    (
        "queue not a count",
        with_node("sink", inputs={"in": {"policy": "latest", "queue": 100}}),
        "node 'sink': inputs.in.queue: 100 is not an integer in 0..64",
    ),
    (
        "unknown input key",
        with_node("sink", inputs={"in": {"policy": "latest", "queu": 3}}),
        "node 'sink': inputs.in.queu: unknown key; expected policy, queue",
    ),
    (
        "queue on a reliable input",
        with_node("sink", inputs={"in": {"policy": "reliable", "queue": 3}}),
        "node 'sink': inputs.in.queue: a queue applies to a latest input only",
    ),
    (
        "bad restart",
        with_node("sink", restart="maybe"),
        "node 'sink': restart: 'maybe' is not one of never, on-failure, always",
    ),
    ("unknown key", with_node("sink", colour="red"), "node 'sink': colour: unknown key"),
    ("negative nice", with_node("sink", nice=-5), "node 'sink': nice: -5 is not an integer in 0..19"),
    ("nice not a number", with_node("sink", nice="low"), "node 'sink': nice: 'low' is not an integer in 0..19"),
    ("unknown top key", {**with_node("sink"), "nodez": {}}, "nodez: unknown key"),
    (
        "two publishers",
        {"nodes": {**GOOD, "source2": {"run": N + "Counter", "remap": {"out": "numbers"}}}},
        "node 'source2': outputs.out: topic 'numbers' is already published by node 'source'",
    ),
    (
        "bad external",
        {**with_node("sink"), "external": {"x": {"type": "test.Number", "endpoint": "udp://a"}}},
        "external.x.endpoint: tcp endpoint 'udp://a': expected tcp://HOST:PORT",
    ),
    (
        "unknown external type",
        {
            "external": {"numbers": {"type": "no.Type", "endpoint": "tcp://127.0.0.1:7999"}},
            "nodes": {"sink": GOOD["sink"]},
        },
        "external.numbers.type: unknown message type 'no.Type'",
    ),
]


@pytest.mark.parametrize("label, doc, expected", CASES, ids=[c[0] for c in CASES])
def test_launch_error_names_file_node_and_key(tmp_path: Path, label: str, doc: dict, expected: str) -> None:
    if doc["nodes"].get("sink", {}).get("run", "") is None:
        del doc["nodes"]["sink"]["run"]
    f = write_launch(tmp_path / "bad.yaml", doc)
    with pytest.raises(LaunchError) as err:
        check(load(f))
    assert str(f) in str(err.value) and expected in str(err.value), str(err.value)


def test_type_mismatch_is_reported(tmp_path: Path) -> None:
    doc = {
        "nodes": {
            "source": {"run": N + "Counter", "remap": {"out": "numbers"}},
            "recorder": {"run": "tests.graph_nodes:FrameSink", "remap": {"in": "numbers"}},
        }
    }
    f = write_launch(tmp_path / "mismatch.yaml", doc)
    with pytest.raises(
        LaunchError,
        match=r"node 'recorder': inputs.in: type mismatch on topic 'numbers': "
        r"source.out publishes test.Number/1, this input takes camera.Frame/1",
    ):
        check(load(f))


def test_invalid_yaml_and_include_errors(tmp_path: Path) -> None:
    (tmp_path / "broken.yaml").write_text("nodes: [unclosed\n")
    with pytest.raises(LaunchError, match="broken.yaml: not valid YAML"):
        load(tmp_path / "broken.yaml")
    write_launch(tmp_path / "top.yaml", {"include": ["missing.yaml"], "nodes": GOOD})
    with pytest.raises(LaunchError, match="include missing.yaml: launch file missing.yaml not found"):
        load(tmp_path / "top.yaml")
    write_launch(tmp_path / "loop.yaml", {"include": ["loop.yaml"], "nodes": GOOD})
    with pytest.raises(LaunchError, match="include cycle"):
        load(tmp_path / "loop.yaml")


def test_include_set_and_overrides(tmp_path: Path) -> None:
    write_launch(tmp_path / "part.yaml", {"nodes": {"source": GOOD["source"]}})
    write_launch(
        tmp_path / "top.yaml",
        {"include": [{"file": "part.yaml", "set": {"source.count": 9}}], "nodes": {"sink": GOOD["sink"]}},
    )
    g = check(load(tmp_path / "top.yaml", sets={"sink.delay_ms": "2.5"}))
    assert g.params["source"]["count"] == 9 and g.params["sink"]["delay_ms"] == 2.5
    with pytest.raises(LaunchError, match="--set nope.x: no node 'nope'"):
        load(tmp_path / "top.yaml", sets={"nope.x": 1})
    g = check(load(tmp_path / "top.yaml", replace={"sink": "tests.graph_nodes:Sink"}))
    assert g.nodes["sink"].run == "tests.graph_nodes:Sink"


def test_cli_reports_the_error_and_starts_nothing(tmp_path: Path) -> None:
    f = write_launch(tmp_path / "bad.yaml", with_node("source", params={"count": "many"}))
    code, out = run_launch(f, timeout=30)
    assert code == 2 and "parameter 'count': expected int" in out and "started" not in out


def test_replace_with_an_old_module_path_names_the_new_one(tmp_path: Path) -> None:
    f = write_launch(tmp_path / "g.yaml", {"nodes": GOOD})
    with pytest.raises(LaunchError, match="write 'counterpart.nodes.camera'"):
        check(load(f, replace={"sink": "nodes.camera"}))


def test_checking_the_shipped_graphs_loads_no_algorithm_library() -> None:
    # the check imports every node's module for its parameters, before any node starts: in a process
    # of its own, so that what this test session loaded before does not count
    code = (
        "import sys\n"
        "from counterpart.bus.launchfile import check, find_launch_file, load\n"
        "for name in ('lockstep.yaml', 'demo.yaml', 'live.yaml'):\n"
        "    check(load(find_launch_file(name)))\n"
        "print(' '.join(m for m in ('numba', 'scipy', 'sklearn', 'hmmlearn') if m in sys.modules))\n"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert res.returncode == 0, res.stderr[-2000:]
    assert res.stdout.strip() == "", f"loaded by the check: {res.stdout.strip()}"
