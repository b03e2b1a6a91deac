"""The ``counterpart`` command: every subcommand answers --help; nodes run alone find each other."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from counterpart.bus import plugins
from counterpart.bus.cli import RUNTIME_COMMANDS, commands
from tests.launching import REPO, kill_tree, read_jsonl, wait_for


def cli(*args: str, env: dict[str, str] | None = None, timeout: float = 60) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "counterpart.bus.cli", *args],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=timeout,
        env={**os.environ, **(env or {})},
    )


@pytest.mark.parametrize("command", sorted(commands()))
def test_every_command_has_help(command: str) -> None:
    res = cli(command, "--help")
    assert res.returncode == 0, res.stderr
    assert "usage: counterpart" in res.stdout


@pytest.mark.parametrize("command", sorted(commands()))
def test_every_command_is_in_the_readme(command: str) -> None:
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    assert f"`counterpart {command}" in readme, f"README.md documents no `counterpart {command} ...`"


def test_the_command_is_assembled_from_the_runtime_and_the_declared_applications() -> None:
    declared = plugins.declared(plugins.COMMANDS)
    assert {"demo", "track", "silhouettes", "calibrate", "respond", "learn", "mine", "sim"} <= set(declared)
    assert all(ep.value.startswith(("counterpart.apps.", "counterpart.sim.")) for ep in declared.values())
    res = cli("--help")
    listed = set(re.findall(r"^    (\w+)\s", res.stdout, flags=re.M))
    assert listed == set(RUNTIME_COMMANDS) | set(declared), res.stdout
    learn = cli("learn", "--help")
    assert all(t in learn.stdout for t in plugins.declared(plugins.LEARN_TARGETS)), learn.stdout


def test_an_undeclared_plugin_is_named_with_the_declared_ones() -> None:
    with pytest.raises(
        plugins.PluginError, match=r"no installed package declares 'nope' in counterpart.learn \(declared: "
    ):
        plugins.load(plugins.LEARN_TARGETS, "nope")


def test_unknown_command_is_named() -> None:
    res = cli("frobnicate")
    assert res.returncode == 2 and "unknown command 'frobnicate'" in res.stderr


def test_nodes_run_alone_find_each_other_by_topic(tmp_path: Path) -> None:
    home = tempfile.mkdtemp(prefix="cp-", dir="/tmp")
    env = {**os.environ, "COUNTERPART_HOME": home}
    out = tmp_path / "sink.jsonl"
    sink = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "counterpart.bus.cli",
            "run",
            "tests.graph_nodes:Sink",
            "--param",
            f"path={out}",
            "--remap",
            "in=numbers",
        ],
        cwd=REPO,
        env=env,
        start_new_session=True,
    )
    try:
        assert wait_for(lambda: out.exists(), 20)
        src = subprocess.run(
            [
                sys.executable,
                "-m",
                "counterpart.bus.cli",
                "run",
                "tests.graph_nodes:Counter",
                "--param",
                "count=50",
                "--param",
                "rate=100",
                "--remap",
                "out=numbers",
            ],
            cwd=REPO,
            env=env,
            timeout=60,
        )
        assert src.returncode == 0
        assert sink.wait(20) == 0  # end of stream ended the sink too
        rows = [r for r in read_jsonl(out) if "seq" in r]
        assert rows and [r["seq"] for r in rows] == list(range(rows[0]["seq"], 50))
    finally:
        kill_tree(sink)


def test_run_reports_a_bad_parameter() -> None:
    res = cli("run", "tests.graph_nodes:Counter", "--param", "count=lots")
    assert res.returncode == 2 and "parameter 'count': expected int" in res.stderr


def test_a_file_of_the_wrong_kind_is_named_as_such(tmp_path: Path) -> None:
    """A video where a bag, a launch file or the simulator's output folder belongs: each command
    says what the file is not, exits with its error code, and prints no traceback.
    """
    from tests.launching import run_cli

    video = tmp_path / "clip.avi"
    video.write_bytes(b"RIFF\x5e\x7b\x01\x00AVI LIST" + bytes(range(256)) * 8)
    for args, code, says in (
        (("bag", "info", str(video)), 1, "is not a bag: bags are MCAP files"),
        (("launch", str(video)), 2, "not a launch file: not text"),
        (("sim", "--scenario", "handshake", "--frames", "3", "--out", str(video)), 2, "is a file; --out is the folder"),
    ):
        r = run_cli(*args, timeout=60)
        assert r.returncode == code and says in r.stderr and "Traceback" not in r.stderr, (args, r.stderr[-2000:])
    assert video.read_bytes()[:4] == b"RIFF"  # nothing written over it
