"""The launcher: start every node of a checked graph as its own process group and supervise it.

- Each node runs ``python -m counterpart.bus.runner SPEC`` in a new session (its own process group) with
  PR_SET_PDEATHSIG, so it dies with the launcher even when the launcher is SIGKILLed; nodes also
  watch their parent pid as a second guard.
- Ctrl-C / SIGTERM: SIGINT to every group, then SIGTERM after ``INT_GRACE_S``, then SIGKILL after
  ``TERM_GRACE_S``: everything is gone within 5 s.
- ``restart``: never / on-failure / always, with exponential backoff (0.5 s doubling to 10 s; the
  count resets after 30 s of healthy running) up to ``max_restarts``.
- ``nice``: the node's process starts with its niceness raised by that much (lower priority).
- A ``required`` node's exit stops the graph with its exit code (after a clean 0 exit, the rest of
  the graph gets ``DRAIN_S`` to finish on end of stream).
- A node that fails before its first message (published or handled: the node then writes the
  marker ``nodes/NAME.running``) stops the graph with its exit code, whatever its restart policy:
  a node that cannot start (an unreadable video, a missing camera or model, a crash in setup) would
  fail the same way again, and the nodes waiting for its messages would wait forever. The nodes that
  took its end of stream get ``EARLY_GRACE_S`` to end by themselves; all are gone within 5 s.
- The graph ends by itself when every node has exited; the exit code is 0 when all exited 0.
- The run directory holds ``registry.json`` (nodes, pids, topics, endpoints, types) for the
  introspection commands, and ``base_dir()/latest`` points at it.
"""

from __future__ import annotations

import ctypes
import functools
import json
import logging
import os
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .endpoints import base_dir, new_run_dir
from .launchfile import Graph, node_specs, stats_dir
from .run_summary import read_failure

log = logging.getLogger("launch")

#: one BLAS / OpenMP / OpenCV thread in each node unless the environment sets another number: every
#: node is a process of its own, so the graph is parallel already, and a pool of threads per process
#: (numpy's BLAS and OpenCV size theirs to the machine's cores; OpenCV's spin-waits after each call
#: it runs in parallel) spins on the cores the other nodes need
ONE_THREAD_ENV = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OPENCV_FOR_THREADS_NUM")
INT_GRACE_S = 2.0
TERM_GRACE_S = 1.5
DRAIN_S = 10.0
#: after a node failed before its first message: how long the others get to end by themselves (on
#: its end of stream), then how long they get to stop on SIGINT; with the failed node's own wait for
#: end-of-stream confirmations (counterpart.bus.node.EARLY_FAILURE_EOS_S) and TERM_GRACE_S, all within 5 s
EARLY_GRACE_S = 0.7
EARLY_INT_GRACE_S = 1.0
BACKOFF_START_S = 0.5
BACKOFF_MAX_S = 10.0
HEALTHY_S = 30.0

_PR_SET_PDEATHSIG = 1


def _child_setup(nice: int = 0) -> None:
    """Runs in the child between fork and exec: die with the launcher; lower the priority by ``nice``."""
    try:
        libc = ctypes.CDLL("libc.so.6", use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)
    except OSError:
        pass
    if nice:
        os.nice(nice)


@dataclass
class Proc:
    name: str
    cmd: list[str]
    restart: str
    max_restarts: int
    required: bool
    nice: int = 0
    popen: subprocess.Popen | None = None
    started: float = 0.0
    restarts: int = 0
    next_start: float | None = 0.0
    exit_code: int | None = None
    stopped: bool = False  # ended by the launcher's stop, not by itself
    history: list[int] = field(default_factory=list)
    running_file: Path | None = None

    @property
    def ever_ran(self) -> bool:
        """Whether the node has published or handled a message (in any of its runs)."""
        return self.running_file is not None and self.running_file.exists()


class Launcher:
    """Runs one checked :class:`Graph` until it ends, is stopped, or a required node exits.

    Parameters
    ----------
    graph : Graph
        The checked graph.
    run_dir : Path or None, default=None
        The run directory; None makes a new one.
    env : dict of str to str or None, default=None
        The nodes' environment; None: the launcher's own.

    Attributes
    ----------
    procs : dict of str to Proc
        The node processes by node name.
    """

    def __init__(self, graph: Graph, run_dir: Path | None = None, env: dict[str, str] | None = None) -> None:
        self.graph = graph
        self.run_dir = run_dir or new_run_dir()
        self.env = dict(os.environ if env is None else env)
        for name in ONE_THREAD_ENV:
            self.env.setdefault(name, "1")
        self.procs: dict[str, Proc] = {}
        self._stop_signal: int | None = None
        self._int_grace = INT_GRACE_S
        self.specs = node_specs(graph, self.run_dir)
        spec_dir = self.run_dir / "nodes"
        spec_dir.mkdir(mode=0o700, exist_ok=True)
        stats_dir(self.run_dir).mkdir(mode=0o700, exist_ok=True)
        for name, spec in self.specs.items():
            spec["running_file"] = str(spec_dir / f"{name}.running")
            path = spec_dir / f"{name}.json"
            path.write_text(json.dumps(spec, indent=1))
            decl = graph.nodes[name]
            self.procs[name] = Proc(
                name=name,
                cmd=[sys.executable, "-m", "counterpart.bus.runner", str(path)],
                restart=decl.restart,
                max_restarts=decl.max_restarts,
                required=decl.required,
                nice=decl.nice,
                running_file=Path(spec["running_file"]),
            )

    # ------------------------------------------------------------------------------ registry
    def write_registry(self) -> None:
        reg = {
            "launch_file": self.graph.file,
            "launcher_pid": os.getpid(),
            "run_dir": str(self.run_dir),
            "nodes": {
                name: {
                    "module": self.specs[name]["module"],
                    "pid": p.popen.pid if p.popen and p.popen.poll() is None else None,
                    "restarts": p.restarts,
                    "exit_code": p.exit_code,
                    "params": self.graph.params.get(name, {}),
                    "inputs": {
                        k: {"topic": v["topic"], "policy": v["policy"]} for k, v in self.specs[name]["inputs"].items()
                    },
                    "outputs": {k: {"topic": v["topic"]} for k, v in self.specs[name]["outputs"].items()},
                }
                for name, p in self.procs.items()
            },
            "topics": {
                topic: {
                    "type": info["type"],
                    "publisher": info["publisher"],
                    "node": info.get("node"),
                    "subscribers": [f"{n}.{p} ({pol})" for n, p, pol in info["subscribers"]],
                    "endpoints": next(
                        (
                            s["outputs"][port]["endpoints"]
                            for s in self.specs.values()
                            for port in s["outputs"]
                            if s["outputs"][port]["topic"] == topic
                        ),
                        None,
                    )
                    or _external_endpoints(self.specs, topic),
                }
                for topic, info in self.graph.topics.items()
            },
        }
        tmp = self.run_dir / "registry.json.tmp"
        tmp.write_text(json.dumps(reg, indent=1, default=str))
        os.replace(tmp, self.run_dir / "registry.json")

    def _link_latest(self) -> None:
        link = base_dir() / "latest"
        tmp = base_dir() / f".latest-{os.getpid()}"
        try:
            if tmp.is_symlink():
                tmp.unlink()
            tmp.symlink_to(self.run_dir)
            os.replace(tmp, link)
        except OSError as exc:
            log.debug("cannot update %s: %s", link, exc)

    # ------------------------------------------------------------------------------- processes
    def _start(self, p: Proc) -> None:
        p.popen = subprocess.Popen(
            p.cmd, env=self.env, start_new_session=True, preexec_fn=functools.partial(_child_setup, p.nice)
        )
        p.started = time.monotonic()
        p.next_start = None
        p.exit_code = None
        p.stopped = False
        log.info("started %s (pid %d)", p.name, p.popen.pid)

    def _signal_all(self, sig: int) -> None:
        for p in self.procs.values():
            if p.popen is not None and p.popen.poll() is None:
                try:
                    os.killpg(p.popen.pid, sig)
                except ProcessLookupError:
                    pass

    def _alive(self) -> list[Proc]:
        return [p for p in self.procs.values() if p.popen is not None and p.popen.poll() is None]

    def stop_all(self) -> None:
        """SIGINT, then SIGTERM, then SIGKILL to every process group; returns when all are reaped,
        having logged how each node still running ended.
        """
        alive = self._alive()
        for p in alive:
            p.stopped = True
        stopped = {p.name for p in alive}
        for sig, grace in ((signal.SIGINT, self._int_grace), (signal.SIGTERM, TERM_GRACE_S), (signal.SIGKILL, 1.0)):
            if not self._alive():
                break
            self._signal_all(sig)
            deadline = time.monotonic() + grace
            while self._alive() and time.monotonic() < deadline:
                time.sleep(0.02)
        for p in self.procs.values():
            if p.popen is not None:
                try:
                    p.popen.wait(timeout=1.0)
                except subprocess.TimeoutExpired:
                    log.error("%s (pid %d) did not die", p.name, p.popen.pid)
                if p.exit_code is None:
                    p.exit_code = p.popen.returncode
            if p.name in stopped and p.popen.returncode is not None:
                (log.info if p.popen.returncode == 0 else log.warning)(
                    "%s stopped: exited with %d", p.name, p.popen.returncode
                )
            # a node's own children live in its process group: make sure none is left
            if p.popen is not None:
                try:
                    os.killpg(p.popen.pid, signal.SIGKILL)
                except (ProcessLookupError, PermissionError):
                    pass

    def _on_signal(self, signum: int, frame: Any) -> None:
        self._stop_signal = signum

    def run(self) -> int:
        """Start everything and supervise.

        Returns
        -------
        int
            The launcher's exit code: 0 when all nodes exited 0, a failed node's exit code, or
            128 + N when stopped by signal N.
        """
        old = {s: signal.signal(s, self._on_signal) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)}
        self._link_latest()
        code = 0
        try:
            for p in self.procs.values():
                self._start(p)
            self.write_registry()
            code = self._supervise()
        finally:
            self.stop_all()
            self.write_registry()
            for s, h in old.items():
                signal.signal(s, h)
        return code

    def failures(self) -> dict[str, str]:
        """The nodes that failed (ended by themselves with an exit code other than 0 and 130), each
        with why: the last error line it logged, or its exit code. Nodes the launcher stopped are
        not among them.

        Returns
        -------
        dict of str to str
            Node name -> reason, in the launch file's order.
        """
        return {
            p.name: read_failure(self.run_dir, p.name) or f"exit code {p.exit_code}"
            for p in self.procs.values()
            if p.exit_code is not None and p.exit_code > 0 and p.exit_code != 130 and not p.stopped
        }

    def _why(self, name: str) -> str:
        """'; REASON' where node ``name`` left why it failed, else ''."""
        reason = read_failure(self.run_dir, name)
        return f"; {reason}" if reason else ""

    def _supervise(self) -> int:
        # once the graph is ending (a required node ended, a node failed to start): its exit code,
        # how long the others get to end by themselves on end of stream, and what to say after that
        end_code: int | None = None
        end_deadline: float | None = None
        end_why = ""
        while True:
            if self._stop_signal is not None:
                log.info("stopping on signal %d", self._stop_signal)
                return 128 + self._stop_signal
            now = time.monotonic()
            changed = False
            for p in self.procs.values():
                if p.popen is not None and p.exit_code is None and p.popen.poll() is not None:
                    changed = True
                    rc = p.popen.returncode
                    p.exit_code = rc if rc >= 0 else 128 - rc  # killed by signal N: 128 + N, as shells say
                    p.history.append(p.exit_code)
                    if now - p.started > HEALTHY_S:
                        p.restarts = 0
                    failed = p.exit_code != 0
                    early = failed and not p.ever_ran
                    wants = p.restart == "always" or (p.restart == "on-failure" and failed)
                    if wants and not early and p.restarts < p.max_restarts and end_code is None:
                        delay = min(BACKOFF_MAX_S, BACKOFF_START_S * 2**p.restarts)
                        p.restarts += 1
                        p.next_start = now + delay
                        log.warning(
                            "%s exited with %d; restart %d/%d in %.1f s",
                            p.name,
                            p.exit_code,
                            p.restarts,
                            p.max_restarts,
                            delay,
                        )
                        continue
                    why = self._why(p.name) if failed else ""
                    (log.warning if failed else log.info)("%s exited with %d%s", p.name, p.exit_code, why)
                    if p.required and failed:
                        log.error(
                            "required node %s failed (exit code %d%s): stopping the graph", p.name, p.exit_code, why
                        )
                        return p.exit_code
                    if early and not end_code:
                        # the nodes that took its end of stream end by themselves meanwhile
                        log.error(
                            "%s failed before its first message (exit code %d%s): stopping the graph",
                            p.name,
                            p.exit_code,
                            why,
                        )
                        end_code, end_deadline, end_why = p.exit_code, now + EARLY_GRACE_S, ""
                        self._int_grace = EARLY_INT_GRACE_S
                    elif p.required and end_code is None:
                        end_code, end_deadline = 0, now + DRAIN_S
                        end_why = f"required node ended; the rest did not finish within {DRAIN_S:.0f} s: stopping them"
                if p.next_start is not None and p.popen is not None and now >= p.next_start and end_code is None:
                    self._start(p)
                    changed = True
            if changed:
                self.write_registry()
            pending = [p for p in self.procs.values() if p.next_start is not None and p.popen is not None]
            # a process may exit between the scan above and this check: its code is read on the next pass
            unread = [p for p in self.procs.values() if p.popen is not None and p.exit_code is None]
            if not self._alive() and (not pending or end_code is not None) and not unread:
                failed_nodes = {p.name: p.exit_code for p in self.procs.values() if p.exit_code}
                if failed_nodes:
                    log.warning(
                        "graph ended; failed nodes: %s", ", ".join(f"{n} ({c})" for n, c in failed_nodes.items())
                    )
                    return next(iter(failed_nodes.values())) if end_code is None else end_code
                log.info("graph ended")
                return 0
            if end_deadline is not None and now > end_deadline:
                if end_why:
                    log.warning("%s", end_why)
                return end_code or 0
            time.sleep(0.02)

    def cleanup(self) -> None:
        """Remove the run directory's sockets (the registry stays until the next launch prunes it)."""
        for f in self.run_dir.glob("*"):
            if f.is_socket():
                f.unlink(missing_ok=True)


def _external_endpoints(specs: dict[str, dict[str, Any]], topic: str) -> dict[str, str] | None:
    for s in specs.values():
        for w in s["inputs"].values():
            if w["topic"] == topic:
                return w["endpoints"]
    return None


def prune_run_dirs(keep: int = 10) -> None:
    """Clean up after launchers that are gone (a SIGKILL leaves their run directories behind):
    delete their run directories but the newest ones, the sockets of those kept (their
    registries stay for ``counterpart node list --run``), and their temporary ``latest`` links.

    Parameters
    ----------
    keep : int, default=10
        Run directories of gone launchers kept (the newest).
    """
    base = base_dir()
    # another launcher may be pruning at the same time: what it removed first is simply gone
    gone = sorted(((_mtime(d), d) for d in base.glob("run-*") if not _launcher_alive(d.name)), key=lambda x: x[0])
    for i, (_, d) in enumerate(gone):
        if i < len(gone) - keep:
            shutil.rmtree(d, ignore_errors=True)
            continue
        for f in d.glob("*"):
            try:
                if f.is_socket():
                    f.unlink()
            except FileNotFoundError:
                pass
    for link in base.glob(".latest-*"):
        if not _launcher_alive(link.name):
            link.unlink(missing_ok=True)


def _mtime(path: Path) -> float:
    try:
        return path.stat().st_mtime
    except FileNotFoundError:
        return 0.0


def _launcher_alive(name: str) -> bool:
    """Whether the launcher whose pid ends ``name`` (``run-DATE-TIME-PID``, ``.latest-PID``) runs."""
    try:
        os.kill(int(name.rsplit("-", 1)[1]), 0)
    except PermissionError:
        return True  # someone's process: leave it
    except (ValueError, IndexError, ProcessLookupError):
        return False
    return True
