"""Helpers for multi-process tests: run the real launcher on a YAML graph and clean up after it."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import psutil
import yaml

REPO = Path(__file__).resolve().parents[1]


def write_launch(path: Path, doc: dict[str, Any]) -> Path:
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def start_launch(file: Path, *extra: str, env: dict[str, str] | None = None) -> subprocess.Popen:
    """``python -m counterpart.bus.cli launch FILE`` in its own session, from the repository root."""
    e = dict(os.environ)
    e.update(env or {})
    return subprocess.Popen(
        [sys.executable, "-m", "counterpart.bus.cli", "launch", str(file), *extra],
        cwd=REPO,
        env=e,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )


def run_launch(file: Path, *extra: str, timeout: float = 60, env: dict[str, str] | None = None) -> tuple[int, str]:
    """Run a graph to its end; return (exit code, combined output)."""
    proc = start_launch(file, *extra, env=env)
    try:
        out, _ = proc.communicate(timeout=timeout)
    finally:
        kill_tree(proc)
    return proc.returncode, out


def run_cli(*args: str, timeout: float = 600) -> subprocess.CompletedProcess:
    """``counterpart ARGS...`` in a process of its own, from the repository root, output captured
    as text (``timeout`` is a hang guard only).
    """
    return subprocess.run(
        [sys.executable, "-m", "counterpart.bus.cli", *args], cwd=REPO, capture_output=True, text=True, timeout=timeout
    )


def descendants(pid: int) -> list[psutil.Process]:
    try:
        return psutil.Process(pid).children(recursive=True)
    except psutil.NoSuchProcess:
        return []


def kill_tree(proc: subprocess.Popen) -> None:
    """Last-resort cleanup so that a failing test never leaves processes behind."""
    kids = descendants(proc.pid)
    if proc.poll() is None:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    for k in kids:
        try:
            k.kill()
        except psutil.NoSuchProcess:
            pass
    try:
        proc.wait(timeout=5)
    except subprocess.TimeoutExpired:
        pass


def free_port_pair() -> int:
    """A port p with p and p + 1 free on 127.0.0.1 (a tcp topic takes both)."""
    import socket

    for _ in range(50):
        with socket.socket() as a:
            a.bind(("127.0.0.1", 0))
            port = a.getsockname()[1]
            if port >= 65534:
                continue
            with socket.socket() as b:
                try:
                    b.bind(("127.0.0.1", port + 1))
                except OSError:
                    continue
        return port
    raise RuntimeError("no two adjacent free ports found")


def stop_launch(proc: subprocess.Popen, timeout: float = 10) -> None:
    """Ctrl-C the launcher as a user would, then make sure nothing is left."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
    try:
        proc.wait(timeout)
    except subprocess.TimeoutExpired:
        pass
    finally:
        kill_tree(proc)


def wait_for(pred, timeout: float = 20.0, interval: float = 0.05) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if pred():
            return True
        time.sleep(interval)
    return False


def read_jsonl(path: Path) -> list[dict[str, Any]]:
    import json

    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
