"""The Node API: declare inputs, outputs and parameters; handle messages; publish.

A processing node::

    class Relay(Node):
        \"\"\"Forwards every number, scaled.\"\"\"
        inputs = {"in": Input(Number)}
        outputs = {"out": Output(Number)}
        params = {"gain": Param(float, 1.0, "factor applied to each value")}

        def on_message(self, port, msg):
            self.publish("out", replace(msg, value=msg.value * self.p["gain"]))

Inputs paired by ``seq`` (:mod:`.pairing`, as ROS's message_filters synchronisers) are declared with
``pairing``; the node then gets one :meth:`Node.on_paired` per set instead of their messages::

    class Tracker(Node):
        inputs = {"frame": Input(Frame), "silhouettes": Input(Silhouettes)}
        pairing = Pairing(required=("frame", "silhouettes"), max_ahead=50)

        def on_paired(self, s):
            self.publish("pose", track(s["frame"], s["silhouettes"]))

A source node has no inputs and overrides :meth:`Node.generate`, publishing until its data ends
(then end of stream goes out on every output and the process exits 0) or ``self.stopping`` is set.

A node is one process. It gets its wiring from the launcher (a JSON spec in the run directory) or,
run alone, from :func:`standalone_spec`: there every topic lives in a shared per-user folder, so
nodes started by hand with ``counterpart run`` find each other by topic name.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import os
import signal
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import zmq

from counterpart.messages import EndOfStream, NodeStats, TopicStats

from .endpoints import TopicEndpoints, ipc_endpoints, standalone_dir
from .pairing import PairedSet, Pairing, PairingStats, SeqSynchronizer
from .params import Param, resolve_params
from .transport import LATEST, POLICIES, RELIABLE, Publisher, Subscriber

STATS_PORT = "stats"
STATS_PERIOD_S = 1.0
#: seconds a supervised node that failed before its first message waits for end-of-stream confirmations
EARLY_FAILURE_EOS_S = 0.5


@dataclass(frozen=True)
class Input:
    """An input port.

    Parameters
    ----------
    type : type or None
        A message class, or None for any message (recorders, echo).
    policy : {"reliable", "latest"}, default="reliable"
        Delivery policy of the subscription.
    doc : str, default=""
        What the port is for.
    raw : bool, default=False
        Deliver ``transport.RawMessage`` (header checked, arrays not decoded): recorders.
    awaits_end : bool, default=True
        Whether the node waits for this input's end of stream before it ends.
    queue : int, default=0
        With the ``latest`` policy, keep up to this many messages in order instead of the newest only
        (the newest ones; the launch file's ``inputs.PORT.queue`` overrides it).
    """

    type: type | None
    policy: str = RELIABLE
    doc: str = ""
    raw: bool = False  # deliver transport.RawMessage (header checked, arrays not decoded): recorders
    #: whether the node waits for this input's end of stream before it ends; False for side inputs
    #: such as run-time controls, which would otherwise deadlock a graph with a feedback loop
    awaits_end: bool = True
    #: with the ``latest`` policy, keep up to this many messages in order instead of the newest only
    #: (recorders: never hold the publisher back, lose nothing while keeping up, count the rest)
    queue: int = 0


@dataclass(frozen=True)
class Output:
    """An output port publishing messages of ``type``.

    Parameters
    ----------
    type : type
        The message class.
    doc : str, default=""
        What the port is for.
    latched : bool, default=False
        Send the last message again to ``latest`` subscribers that join later.
    """

    type: type
    doc: str = ""
    #: send the last message again to ``latest`` subscribers that join later (run-time settings
    #: such as controls, which are published rarely and must not be lost to a late or restarted node)
    latched: bool = False


def stats_topic(node_name: str) -> str:
    """The topic of a node's statistics.

    Parameters
    ----------
    node_name : str
        The node's name.

    Returns
    -------
    str
        ``NODE/stats``.
    """
    return f"{node_name}/stats"


class _PortStats:
    """Counters of one port over the run and over the current stats period."""

    def __init__(self) -> None:
        self.count = 0
        self.period_count = 0
        self.latencies: list[float] = []
        self._first = self._last = 0.0

    def add(self) -> None:
        """Count one message, now."""
        now = time.monotonic()
        if not self.count:
            self._first = now
        self._last = now
        self.count += 1
        self.period_count += 1

    def run_rate(self) -> float:
        """Messages per second from the run's first message to its last (0 before the second).

        A run's last statistics give this rate: a window's rate understates a stream that ended
        early in the window, and over-states nothing the run did.
        """
        span = self._last - self._first
        return (self.count - 1) / span if self.count > 1 and span > 0 else 0.0

    def snapshot(self, period: float) -> tuple[float, float]:
        rate = self.period_count / period if period > 0 else 0.0
        lat = float(np.median(self.latencies)) if self.latencies else 0.0
        self.period_count = 0
        self.latencies = []
        return rate, lat


class Node:
    """Base class of every node process. Subclasses set ``inputs``, ``outputs``, ``params`` and
    override :meth:`setup`, :meth:`on_message` (or ``on_<port>``), :meth:`on_paired`, :meth:`on_end`,
    :meth:`generate`.

    Parameters
    ----------
    spec : dict of str to object
        The node's wiring: ``name``, ``params``, ``inputs`` and ``outputs`` (port -> topic and
        endpoints), and the launcher's options (``stats_file``, ``running_file``, ``supervised``,
        timeouts).

    Attributes
    ----------
    name : str
        The node's name.
    p : dict of str to object
        The validated parameters.
    log : logging.Logger
        The node's logger.
    stopping : bool
        Set on SIGINT/SIGTERM (or when the launcher is gone): the loop ends.
    exit_code : int
        The process exit code.
    figures : dict of str to float
        The node's own figures, published in its stats (see :meth:`tally`).

    Raises
    ------
    ParamError
        A parameter of ``spec`` is unknown or invalid.
    """

    inputs: ClassVar[dict[str, Input]] = {}
    outputs: ClassVar[dict[str, Output]] = {}
    params: ClassVar[dict[str, Param]] = {}
    #: inputs paired by seq and the policy for late and missing messages (None: every message alone)
    pairing: ClassVar[Pairing | None] = None

    # ------------------------------------------------------------------ declared ports and params
    @classmethod
    def ports(cls, params: dict[str, Any]) -> tuple[dict[str, Input], dict[str, Output]]:
        """The ports for the given (validated) parameters. Override when they depend on parameters.

        Parameters
        ----------
        params : dict of str to object
            The validated parameters.

        Returns
        -------
        inputs : dict of str to Input
            The input ports by name.
        outputs : dict of str to Output
            The output ports by name.
        """
        return dict(cls.inputs), dict(cls.outputs)

    @classmethod
    def paired_inputs(cls, params: dict[str, Any]) -> Pairing | None:
        """The pairing for the given (validated) parameters: ``pairing`` without the inputs that
        :meth:`ports` leaves out. Override when the policy depends on parameters.

        Parameters
        ----------
        params : dict of str to object
            The validated parameters.

        Returns
        -------
        Pairing or None
            The pairing, or None when the node has none.
        """
        return cls.pairing.restrict(list(cls.ports(params)[0])) if cls.pairing is not None else None

    @classmethod
    def validate_params(cls, given: dict[str, Any], where: str = "") -> dict[str, Any]:
        """Defaults of ``params`` overlaid with ``given``, every value coerced and checked.

        Parameters
        ----------
        given : dict of str to object
            The parameters given.
        where : str, default=""
            Where they come from, named in an error (e.g. ``node 'tracker'``).

        Returns
        -------
        dict of str to object
            Every declared parameter's value.

        Raises
        ------
        ParamError
            An unknown parameter or a bad value.
        """
        return resolve_params(cls.params, given, where)

    # ------------------------------------------------------------------------------ life cycle
    def __init__(self, spec: dict[str, Any]) -> None:
        self.name: str = spec["name"]
        self.spec = spec
        self.p: dict[str, Any] = self.validate_params(spec.get("params", {}), f"node {self.name!r}")
        self.log = logging.getLogger(self.name)
        self.stopping = False
        self.ctx = zmq.Context.instance()
        self._started = time.monotonic()
        self._last_seq = -1
        self._in: dict[str, Subscriber] = {}
        self._out: dict[str, Publisher] = {}
        self._latched: list[Publisher] = []  # outputs whose last message new lossy subscribers get
        self._in_stats: dict[str, _PortStats] = {}
        self._out_stats: dict[str, _PortStats] = {}
        self._proc_ms: list[float] = []
        self._last_stats = time.monotonic()
        #: the inputs' stats and (mean, max) processing ms of the last stats window in which the
        #: node did anything (:meth:`_maybe_stats`)
        self._busy_window: tuple[list[TopicStats], tuple[float, float]] | None = None
        self._stats_seq = 0
        self._ppid = os.getppid()
        self._running = False  # set by the first message published or handled
        #: the process exit code; set it non-zero on a failure after which the node still ends cleanly
        #: (end of stream goes out with reason "error")
        self.exit_code = 0
        #: the node's own figures, published in its stats (NodeStats.figures): see :meth:`tally`
        self.figures: dict[str, float] = {}
        self._sync: SeqSynchronizer | None = None

    def setup(self) -> None:
        """Called once after the sockets are up, before any message. Load models here."""

    def on_message(self, port: str, msg: Any) -> None:
        """Handle one message on ``port``. Default: call ``self.on_<port>(msg)``.

        Parameters
        ----------
        port : str
            The input port.
        msg : object
            The message.

        Raises
        ------
        NotImplementedError
            The node has no ``on_<port>`` (and does not override this method).
        """
        handler = getattr(self, f"on_{port}", None)
        if handler is None:
            raise NotImplementedError(f"{type(self).__name__} has no on_message or on_{port}")
        handler(msg)

    @property
    def pairing_stats(self) -> PairingStats | None:
        """The counters of the paired inputs (None without ``pairing``): also in the stats' figures."""
        return self._sync.stats if self._sync is not None else None

    def on_paired(self, paired: PairedSet) -> None:
        """Handle one set of the paired inputs.

        Parameters
        ----------
        paired : PairedSet
            The set: ``paired[port]`` is the message, None for an optional one missing.

        Raises
        ------
        NotImplementedError
            Always, unless a node with paired inputs overrides it.
        """
        raise NotImplementedError(f"{type(self).__name__} declares paired inputs and must implement on_paired()")

    def on_end(self) -> None:
        """Called once when every input has ended (after the last paired set), before end of stream
        goes out downstream.
        """

    def on_timer(self) -> None:
        """Called about every ``timer_period`` seconds when the class sets it (not None)."""

    timer_period: ClassVar[float | None] = None

    def generate(self) -> None:
        """Source nodes (no inputs) publish here until their data ends or ``self.stopping``.

        Raises
        ------
        NotImplementedError
            Always, unless a source node overrides it.
        """
        raise NotImplementedError(f"{type(self).__name__} has no inputs and must implement generate()")

    def teardown(self) -> None:
        """Called on every exit path after the loop; close files and devices here."""

    # ------------------------------------------------------------------------------- publishing
    def publish(self, port: str, msg: Any) -> None:
        """Publish a message on an output port.

        Parameters
        ----------
        port : str
            The output port.
        msg : object
            The message (of the port's type).

        Raises
        ------
        KeyError
            The node has no such output port.
        """
        pub = self._out.get(port)
        if pub is None:
            raise KeyError(f"node {self.name!r} has no output port {port!r}; ports: {', '.join(self._out)}")
        pub.send(msg)
        self._count_out(port, getattr(msg, "seq", -1))

    def publish_parts(self, port: str, parts: list[Any], seq: int = -1) -> None:
        """Publish already encoded parts ``[header, buffers...]`` unchanged (bag players).

        Parameters
        ----------
        port : str
            The output port.
        parts : list
            The encoded parts.
        seq : int, default=-1
            The message's seq, for the node's last seq (-1: none).

        Raises
        ------
        KeyError
            The node has no such output port.
        """
        pub = self._out.get(port)
        if pub is None:
            raise KeyError(f"node {self.name!r} has no output port {port!r}; ports: {', '.join(self._out)}")
        pub.send_parts(parts)
        self._count_out(port, seq)

    def tally(self, name: str, n: float = 1) -> None:
        """Add ``n`` to the figure ``name`` (frames with people, regions not placed, ...), published
        with the node's stats so that a run's summary can say what the node's work gave.

        Parameters
        ----------
        name : str
            The figure.
        n : float, default=1
            The amount added.
        """
        self.figures[name] = self.figures.get(name, 0) + n

    def _count_out(self, port: str, seq: Any) -> None:
        self._out_stats[port].add()
        if not self._running:
            self._mark_running()
        if type(seq) is int and seq > self._last_seq:
            self._last_seq = seq
        self._maybe_stats()

    def _mark_running(self) -> None:
        """The first message is out or handled: from now on a failure is not a failure to start.
        The launcher reads the marker file when the node exits (see bus.supervisor).
        """
        self._running = True
        marker = self.spec.get("running_file")
        if marker:
            try:
                Path(marker).touch()
            except OSError as exc:
                self.log.warning("cannot write %s: %s", marker, exc)

    def _eos_timeout(self) -> float:
        """How long end of stream waits for its readers. A node that failed before its first
        message waits briefly: its launcher stops the whole graph once it exits.
        """
        timeout = float(self.spec.get("eos_timeout", 120.0))
        if self.exit_code and not self._running and self.spec.get("supervised", False):
            timeout = min(timeout, EARLY_FAILURE_EOS_S)
        return timeout

    # ------------------------------------------------------------------------------- internals
    def _open(self) -> None:
        inputs, outputs = self.ports(self.p)
        wiring_in = self.spec.get("inputs", {})
        wiring_out = self.spec.get("outputs", {})
        for port in inputs:
            w = wiring_in[port]
            policy = w.get("policy", inputs[port].policy)
            self._in[port] = Subscriber(
                self.ctx,
                w["topic"],
                TopicEndpoints.from_dict(w["endpoints"]),
                policy,
                raw=inputs[port].raw,
                on_bad=lambda kind, detail, port=port: self.log.warning(
                    "dropped a bad message on %s (%s); further ones of this kind are only counted", port, detail
                ),
                msg_type=inputs[port].type,
                publisher=w.get("publisher"),
                queue=int(w.get("queue", inputs[port].queue)),
            )
            self._in_stats[port] = _PortStats()
        for port in list(outputs) + [STATS_PORT]:
            w = wiring_out[port]
            self._out[port] = Publisher(
                self.ctx,
                w["topic"],
                TopicEndpoints.from_dict(w["endpoints"]),
                expected=int(w.get("reliable_subscribers", 0)),
                expected_latest=int(w.get("latest_subscribers", 0)),
                barrier_timeout=float(self.spec.get("barrier_timeout", 30.0)),
                should_stop=lambda: self.stopping,
                latched=port in outputs and outputs[port].latched,
            )
            self._out_stats[port] = _PortStats()
        self._latched = [self._out[p] for p in outputs if outputs[p].latched]
        pairing = self.paired_inputs(self.p)
        self._sync = SeqSynchronizer(pairing) if pairing is not None else None

    def _close(self) -> None:
        for s in self._in.values():
            s.close()
        for p in self._out.values():
            p.close(linger_ms=200 if self.stopping else -1)
        # term() honours each socket's linger: what is still queued (the tail, end of stream) goes out
        self.ctx.term()

    def _maybe_stats(self, force: bool = False) -> None:
        now = time.monotonic()
        period = now - self._last_stats
        if not force and period < STATS_PERIOD_S:
            return
        self._last_stats = now
        ins, outs = [], []
        for port, sub in self._in.items():
            rate, lat = self._in_stats[port].snapshot(period)
            ins.append(
                TopicStats(
                    topic=sub.topic,
                    port=port,
                    count=sub.count,
                    rate_hz=rate,
                    drops=sub.drops,
                    bad=sum(sub.bad.values()),
                    latency_ms=lat,
                )
            )
        for port, pub in self._out.items():
            if port == STATS_PORT:
                continue
            rate, _ = self._out_stats[port].snapshot(period)
            outs.append(TopicStats(topic=pub.topic, port=port, count=self._out_stats[port].count, rate_hz=rate))
        errors: dict[str, int] = {}
        for sub in self._in.values():
            for k, v in sub.bad.items():
                errors[k] = errors.get(k, 0) + v
        if self._sync is not None:  # what the pairing delivered, dropped and found late
            self.figures.update(self._sync.stats.figures())
        proc = self._proc_ms
        self._proc_ms = []
        proc_ms = (float(np.mean(proc)), float(np.max(proc))) if proc else (0.0, 0.0)
        idle = not proc and all(t.rate_hz == 0 for t in ins + outs)
        if force and idle and self._busy_window is not None:
            # the last word, after an idle spell (the stream ended before the last window), keeps
            # the last busy window's latencies and processing times: a run's summary shows what
            # the node did, not its idle last second
            b_ins, proc_ms = self._busy_window
            ins = [dataclasses.replace(t, latency_ms=b.latency_ms) for t, b in zip(ins, b_ins)]
        elif not idle:
            self._busy_window = (ins, proc_ms)
        if force:  # and its rates are the run's, from each port's first message to its last
            ins = [dataclasses.replace(t, rate_hz=self._in_stats[t.port].run_rate()) for t in ins]
            outs = [dataclasses.replace(t, rate_hz=self._out_stats[t.port].run_rate()) for t in outs]
        msg = NodeStats(
            stamp=time.monotonic_ns(),
            seq=self._stats_seq,
            node=self.name,
            pid=os.getpid(),
            uptime_s=now - self._started,
            inputs=ins,
            outputs=outs,
            proc_ms_mean=proc_ms[0],
            proc_ms_max=proc_ms[1],
            decode_errors=errors,
            figures=dict(self.figures),
        )
        self._stats_seq += 1
        self._out[STATS_PORT].send(msg)
        self._write_stats_file(msg)

    def _write_stats_file(self, msg: NodeStats) -> None:
        """The newest stats also go to the file the launcher names (``stats_file``), replaced whole,
        so that a run's summary has every node's last word even where a lossy subscriber missed it.
        """
        path = self.spec.get("stats_file")
        if not path:
            return
        tmp = f"{path}.tmp"
        try:
            with open(tmp, "w") as f:
                json.dump(dataclasses.asdict(msg), f)
            os.replace(tmp, path)
        except OSError as exc:
            self.log.debug("cannot write %s: %s", path, exc)

    def _parent_gone(self) -> bool:
        return self.spec.get("supervised", False) and os.getppid() != self._ppid

    def _loop(self) -> None:
        poller = zmq.Poller()
        owners: dict[zmq.Socket, str] = {}
        for port, sub in self._in.items():
            for s in sub.sockets:
                poller.register(s, zmq.POLLIN)
                owners[s] = port
        next_timer = time.monotonic() + (self.timer_period or 0)
        awaited = [p for p, inp in self.ports(self.p)[0].items() if inp.awaits_end] or list(self._in)
        while not self.stopping:
            if all(self._in[p].ended for p in awaited):
                break
            timeout = 100
            if self.timer_period is not None:
                timeout = max(0, min(timeout, int((next_timer - time.monotonic()) * 1000)))
            deadline = self._sync.next_deadline() if self._sync is not None else None
            if deadline is not None:
                timeout = max(0, min(timeout, int((deadline - time.monotonic()) * 1000) + 1))
            # inputs with an end of stream or messages already queued here (polling changes neither)
            pending = [p for p, sub in self._in.items() if sub.pending]
            if pending:
                timeout = 0  # messages already queued here wait for no socket
            ready = dict(poller.poll(timeout))
            due = [owners[s] for s in ready] + pending
            for port in dict.fromkeys(due):
                sub = self._in[port]
                msg = sub.receive()
                if msg is None:
                    continue
                paired = self._sync is not None and port in self._sync.ports
                if isinstance(msg, EndOfStream):
                    self.log.debug("end of stream on %s", port)
                    if paired:  # an input that ended holds no set back
                        self._on_sets(self._sync.end(port))
                    continue
                st = self._in_stats[port]
                st.add()
                stamp = getattr(msg, "stamp", 0)
                if stamp:
                    st.latencies.append((time.monotonic_ns() - stamp) / 1e6)
                t0 = time.perf_counter()
                if paired:
                    self._on_sets(self._sync.add(port, msg.seq, msg))
                else:
                    self.on_message(port, msg)
                self._proc_ms.append((time.perf_counter() - t0) * 1e3)
                if not self._running:
                    self._mark_running()
            if self._sync is not None and self._sync.timeout is not None:
                self._on_sets(self._sync.poll())
            if self.timer_period is not None and time.monotonic() >= next_timer:
                self.on_timer()
                next_timer = time.monotonic() + self.timer_period
            for pub in self._latched:
                pub.poll_subscriptions()
            self._maybe_stats()
            if self._parent_gone():
                self.log.warning("launcher is gone; stopping")
                self.stopping = True

    def _on_sets(self, sets: list[PairedSet]) -> None:
        for s in sets:
            self.on_paired(s)

    def _send_eos(self, reason: str) -> None:
        # This node reads nothing more: leave every input first. Two nodes feeding each other (the
        # renderer's controls to the responder, its partner back) would otherwise each wait below
        # for the other to confirm an end of stream that neither reads any longer.
        for sub in self._in.values():
            sub.close()
        timeout = self._eos_timeout()
        for pub in self._out.values():
            pub.barrier_timeout = min(pub.barrier_timeout, timeout)  # nor for readers still starting
            pub.send_eos(self.name, self._last_seq, reason)
        deadline = time.monotonic() + timeout
        for pub in self._out.values():
            if not pub.wait_delivered(max(0.0, deadline - time.monotonic())) and not self.stopping:
                self.log.warning(
                    "%s: %d reliable subscriber(s) did not confirm end of stream", pub.topic, pub.subscribers
                )

    def run(self) -> int:
        """Open sockets, set up, loop until end of stream or stop, send end of stream, clean up.

        Returns
        -------
        int
            The process exit code, :attr:`exit_code`.
        """
        _install_signal_handlers(self)
        self._open()
        try:
            self.setup()
            if self._in:
                self._loop()
                if not self.stopping:
                    if self._sync is not None:  # what still waits goes out with what it has
                        self._on_sets(self._sync.flush())
                    self.on_end()
            else:
                self.generate()
            self._maybe_stats(force=True)
            self._send_eos("stopped" if self.stopping else "error" if self.exit_code else "end")
        finally:
            try:
                self.teardown()
            finally:
                self._close()
        return self.exit_code

    # ------------------------------------------------------------------------------- entry points
    @classmethod
    def main(cls, argv: list[str] | None = None) -> None:
        """Run this node alone from the command line (``python -m counterpart.nodes.x --param k=v``).

        Exits the process with the exit code of :func:`counterpart.bus.runner.run_standalone`.

        Parameters
        ----------
        argv : list of str or None, default=None
            The options; None for ``sys.argv[1:]``.
        """
        from .runner import run_standalone

        sys.exit(run_standalone(cls, argv))


def _install_signal_handlers(node: Node) -> None:
    if threading.current_thread() is not threading.main_thread():
        return

    def stop(signum: int, frame: Any) -> None:
        if node.stopping:  # second signal: the node is stuck; leave now
            os._exit(128 + signum)
        node.stopping = True

    signal.signal(signal.SIGINT, stop)
    signal.signal(signal.SIGTERM, stop)


def standalone_spec(
    name: str, node_cls: type[Node], params: dict[str, Any], remap: dict[str, str], policy: dict[str, str]
) -> dict[str, Any]:
    """Wiring for a node run alone: every topic in the shared standalone folder, no barrier.

    Parameters
    ----------
    name : str
        The node's name.
    node_cls : type of Node
        The node class.
    params : dict of str to object
        The parameters given.
    remap : dict of str to str
        Port -> topic, where it differs from the port's name (stats: ``NAME/stats``).
    policy : dict of str to str
        Input port -> delivery policy, where it differs from the port's own.

    Returns
    -------
    dict of str to object
        The spec: ``name``, ``params``, ``inputs`` and ``outputs``.

    Raises
    ------
    ParamError
        An unknown parameter or a bad value.
    ValueError
        A remapped port the node does not have, or an unknown policy.
    """
    p = node_cls.validate_params(params, f"node {name!r}")
    inputs, outputs = node_cls.ports(p)
    root = standalone_dir()
    unknown = sorted(set(remap) - set(inputs) - set(outputs) - {STATS_PORT})
    if unknown:
        raise ValueError(
            f"--remap: node {name!r} has no port {', '.join(unknown)}; ports: {', '.join([*inputs, *outputs])}"
        )
    spec: dict[str, Any] = {"name": name, "params": params, "inputs": {}, "outputs": {}}
    for port, inp in inputs.items():
        topic = remap.get(port, port)
        pol = policy.get(port, inp.policy)
        if pol not in POLICIES:
            raise ValueError(f"--policy {port}={pol}: expected one of {', '.join(POLICIES)}")
        spec["inputs"][port] = {"topic": topic, "endpoints": ipc_endpoints(root, topic).to_dict(), "policy": pol}
    for port in list(outputs) + [STATS_PORT]:
        topic = remap.get(port, stats_topic(name) if port == STATS_PORT else port)
        spec["outputs"][port] = {"topic": topic, "endpoints": ipc_endpoints(root, topic).to_dict()}
    return spec


def load_spec(path: str | Path) -> dict[str, Any]:
    """A node's spec from the JSON file the launcher wrote.

    Parameters
    ----------
    path : str or Path
        The spec file.

    Returns
    -------
    dict of str to object
        The spec.
    """
    with open(path) as f:
        return json.load(f)


__all__ = [
    "Node",
    "Input",
    "Output",
    "Param",
    "Pairing",
    "PairedSet",
    "RELIABLE",
    "LATEST",
    "stats_topic",
    "standalone_spec",
]
