"""Launch files: YAML descriptions of a graph, loaded, merged and checked before any process starts.

Format (every key but ``nodes`` optional)::

    include:                       # other launch files, relative to this one or in launch/
      - base.yaml
      - {file: cam.yaml, set: {camera.fps: 10}}
    policy: latest                 # default queue policy of the inputs of every node (included ones too)
                                   # that does not set its own
    transport: ipc                 # ipc (default: a 0700 run directory) or tcp
    host: 127.0.0.1                # tcp: the host to bind (loopback unless named)
    port_base: 7300                # tcp: first port; each topic takes three (reliable, latest, queued)
    endpoints:                     # fixed tcp endpoints for chosen topics (to span launchers)
      numbers: tcp://127.0.0.1:7400
    external:                      # topics published by another launcher (publisher: its node's
      numbers: {type: test.Number, endpoint: tcp://127.0.0.1:7400, publisher: source}  # name, optional)
    nodes:
      relay:
        run: tests.graph_nodes.relay      # module (or module:Class) holding the node
        params: {gain: 2.0}
        remap: {in: numbers, out: doubled} # port -> topic (default: topic = port name)
        policy: reliable                   # default queue policy of every input
        inputs: {in: {policy: latest}}     # per-input policy; {policy: latest, queue: 3}: keep the
                                           # newest 3 in order (a node that is late at times catches up)
        restart: on-failure                # never | on-failure | always
        max_restarts: 5
        required: false                    # its exit stops the graph with its exit code
        wait_subscribers: {out: 1}         # extra reliable subscribers to await (other launchers)
        nice: 10                           # lower CPU priority (0-19) for background work

Every error is a :class:`LaunchError` naming the file, the node and the key.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import yaml

from counterpart.messages import by_name, schema_id

from .endpoints import TopicEndpoints, ipc_endpoints, tcp_endpoints
from .node import STATS_PORT, Input, Node, Output, stats_topic
from .params import ParamError
from .runner import NodeLookupError, find_node_class
from .transport import LATEST, POLICIES, QUEUED_HWM

RESTART_POLICIES = ("never", "on-failure", "always")
NODE_KEYS = {
    "run",
    "params",
    "remap",
    "policy",
    "inputs",
    "restart",
    "max_restarts",
    "required",
    "wait_subscribers",
    "nice",
}
#: the niceness a launch file may give a node: lower priority only (raising it needs privileges)
NICE_RANGE = (0, 19)
TOP_KEYS = {"include", "policy", "transport", "host", "port_base", "endpoints", "external", "nodes", "barrier_timeout"}


class LaunchError(ValueError):
    """A launch file that cannot run; the message names the file, node and key."""


@dataclass
class NodeDecl:
    """One node as a launch file declares it (see the module docstring for the keys).

    Attributes
    ----------
    name : str
        Node name.
    run : str
        Module (or ``module:Class``) holding the node.
    file : str
        The launch file that declares it.
    params : dict
        Node parameters.
    remap : dict of str to str
        Port -> topic (default: topic = port name).
    policy : str or None
        Default queue policy of every input; None: the node's own.
    input_policies : dict of str to str
        Per-input queue policy.
    input_queues : dict of str to int
        Per-input queue length of a ``latest`` input (0: the newest message only).
    restart : {"never", "on-failure", "always"}
        Restart policy.
    max_restarts : int
        Most restarts.
    required : bool
        Its exit stops the graph with its exit code.
    wait_subscribers : dict of str to int
        Extra reliable subscribers to await per output port (other launchers).
    nice : int
        Added to the process's niceness (0-19): a node whose work may wait (the calibration's
        refinement) yields the cores to the ones that must keep up with the camera.
    """

    name: str
    run: str
    file: str
    params: dict[str, Any] = field(default_factory=dict)
    remap: dict[str, str] = field(default_factory=dict)
    policy: str | None = None
    input_policies: dict[str, str] = field(default_factory=dict)
    input_queues: dict[str, int] = field(default_factory=dict)
    restart: str = "never"
    max_restarts: int = 5
    required: bool = False
    wait_subscribers: dict[str, int] = field(default_factory=dict)
    nice: int = 0


@dataclass
class Graph:
    """A checked graph: nodes with resolved classes, ports, topics and endpoints.

    Attributes
    ----------
    file : str
        The launch file.
    nodes : dict of str to NodeDecl
        The nodes by name, includes' nodes too.
    transport : {"ipc", "tcp"}
        Transport of the topics.
    host : str
        tcp: the host to bind.
    port_base : int
        tcp: first port; each topic takes three.
    fixed_endpoints : dict of str to str
        Fixed tcp endpoints of chosen topics.
    external : dict of str to dict
        Topics published by another launcher: ``type``, ``endpoint``, ``file``, ``publisher``.
    barrier_timeout : float
        Seconds given to the startup barrier.
    classes, params, ports_in, ports_out, topics : dict
        Filled by :func:`check`: each node's class, validated parameters, input and output ports, and
        each topic's ``type``, ``publisher``, ``subscribers`` and publishing ``node``.
    """

    file: str
    nodes: dict[str, NodeDecl]
    transport: str = "ipc"
    host: str = "127.0.0.1"
    port_base: int = 7300
    fixed_endpoints: dict[str, str] = field(default_factory=dict)
    external: dict[str, dict[str, Any]] = field(default_factory=dict)
    barrier_timeout: float = 30.0
    # filled by check()
    classes: dict[str, type[Node]] = field(default_factory=dict)
    params: dict[str, dict[str, Any]] = field(default_factory=dict)
    ports_in: dict[str, dict[str, Input]] = field(default_factory=dict)
    ports_out: dict[str, dict[str, Output]] = field(default_factory=dict)
    topics: dict[str, dict[str, Any]] = field(default_factory=dict)

    def input_topic(self, node: str, port: str) -> str:
        """The topic that input ``port`` of ``node`` subscribes to (its remap, else the port name)."""
        return self.nodes[node].remap.get(port, port)

    def output_topic(self, node: str, port: str) -> str:
        """The topic that output ``port`` of ``node`` publishes on (its remap, else the port name; the
        statistics port: the node's statistics topic).
        """
        if port == STATS_PORT:
            return self.nodes[node].remap.get(port, stats_topic(node))
        return self.nodes[node].remap.get(port, port)


def find_launch_file(name: str | Path, relative_to: Path | None = None) -> Path:
    """A launch file by path, relative to an including file, or by name in the ``launch`` package.

    Parameters
    ----------
    name : str or Path
        File name or path.
    relative_to : Path or None, default=None
        Folder of the including file, searched before the working directory.

    Returns
    -------
    Path
        The file found.

    Raises
    ------
    LaunchError
        If no such file exists in any of these places.
    """
    p = Path(name)
    tries = [p] if p.is_absolute() else ([relative_to / p] if relative_to else []) + [Path.cwd() / p]
    for t in tries:
        if t.is_file():
            return t.resolve()
    packaged = resources.files("counterpart.launch") / str(name)
    if packaged.is_file():
        return Path(str(packaged))
    raise LaunchError(
        f"launch file {name!s} not found (looked in {', '.join(str(t) for t in tries)} and the launch package)"
    )


def _err(file: str, node: str | None, key: str, msg: str) -> LaunchError:
    where = f"{file}: node {node!r}: {key}" if node else f"{file}: {key}"
    return LaunchError(f"{where}: {msg}")


def _queue(value: Any, policy: str, file: str, node: str, key: str) -> int:
    """A ``latest`` input's queue length, checked: an integer in 0..QUEUED_HWM."""
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= QUEUED_HWM:
        raise _err(
            file,
            node,
            key,
            f"{value!r} is not an integer in 0..{QUEUED_HWM} (messages a latest input keeps in order; 0: the newest only)",
        )
    if value and policy != LATEST:
        raise _err(file, node, key, f"a queue applies to a latest input only (this one is {policy}: it loses nothing)")
    return value


def _mapping(value: Any, file: str, node: str | None, key: str) -> dict[str, Any]:
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise _err(file, node, key, f"expected a mapping, got {type(value).__name__}")
    return value


def load(
    path: str | Path,
    sets: dict[str, Any] | None = None,
    replace: dict[str, str] | None = None,
    _seen: tuple[Path, ...] = (),
) -> Graph:
    """Read a launch file (and its includes) and apply the command line's overrides.

    The result still needs :func:`check`.

    Parameters
    ----------
    path : str or Path
        The launch file (see :func:`find_launch_file`).
    sets : dict or None, default=None
        ``--set node.param=value`` overrides: ``"NODE.PARAM"`` -> value (a string is read as YAML).
    replace : dict of str to str or None, default=None
        ``--replace node=module`` overrides: node name -> module.

    Returns
    -------
    Graph
        The unchecked graph.

    Raises
    ------
    LaunchError
        On a missing file, invalid YAML, an include cycle, an unknown or invalid key, a node defined
        twice or an override naming no node.
    """
    file_path = find_launch_file(path)
    file = str(file_path)
    if file_path in _seen:
        raise LaunchError(f"{file}: include cycle through {' -> '.join(map(str, _seen))}")
    try:
        doc = yaml.safe_load(file_path.read_text(encoding="utf-8")) or {}
    except UnicodeDecodeError:
        raise LaunchError(f"{file}: not a launch file: not text (a launch file is YAML, as in launch/)") from None
    except yaml.YAMLError as exc:
        raise LaunchError(f"{file}: not valid YAML: {exc}") from None
    if not isinstance(doc, dict):
        raise LaunchError(f"{file}: the top level must be a mapping with 'nodes'")
    unknown = sorted(set(doc) - TOP_KEYS)
    if unknown:
        raise _err(file, None, unknown[0], f"unknown key; expected one of {', '.join(sorted(TOP_KEYS))}")
    graph = Graph(file=file, nodes={})
    for inc in doc.get("include") or []:
        inc_sets: dict[str, Any] = {}
        if isinstance(inc, dict):
            inc_sets = _mapping(inc.get("set"), file, None, "include.set")
            inc = inc.get("file")
        if not isinstance(inc, str):
            raise _err(file, None, "include", "each entry is a file name or {file: NAME, set: {...}}")
        try:
            sub = load(find_launch_file(inc, file_path.parent), inc_sets, None, _seen + (file_path,))
        except LaunchError as exc:
            raise LaunchError(f"{file}: include {inc}: {exc}") from None
        for name, decl in sub.nodes.items():
            if name in graph.nodes:
                raise _err(file, name, "include", f"node defined twice ({graph.nodes[name].file} and {decl.file})")
            graph.nodes[name] = decl
        graph.external.update(sub.external)
        graph.fixed_endpoints.update(sub.fixed_endpoints)
    graph.transport = doc.get("transport", "ipc")
    if graph.transport not in ("ipc", "tcp"):
        raise _err(file, None, "transport", f"{graph.transport!r} is not ipc or tcp")
    graph.host = str(doc.get("host", "127.0.0.1"))
    graph.port_base = int(doc.get("port_base", 7300))
    graph.barrier_timeout = float(doc.get("barrier_timeout", 30.0))
    for topic, ep in _mapping(doc.get("endpoints"), file, None, "endpoints").items():
        try:
            tcp_endpoints(str(ep))
        except ValueError as exc:
            raise _err(file, None, f"endpoints.{topic}", str(exc)) from None
        graph.fixed_endpoints[topic] = str(ep)
    for topic, ext in _mapping(doc.get("external"), file, None, "external").items():
        ext = _mapping(ext, file, None, f"external.{topic}")
        if "type" not in ext or "endpoint" not in ext:
            raise _err(file, None, f"external.{topic}", "needs 'type' and 'endpoint'")
        extra = sorted(set(ext) - {"type", "endpoint", "publisher"})
        if extra:
            raise _err(file, None, f"external.{topic}.{extra[0]}", "unknown key; expected type, endpoint, publisher")
        try:
            tcp_endpoints(str(ext["endpoint"]))
        except ValueError as exc:
            raise _err(file, None, f"external.{topic}.endpoint", str(exc)) from None
        graph.external[topic] = {
            "type": str(ext["type"]),
            "endpoint": str(ext["endpoint"]),
            "file": file,
            "publisher": None if ext.get("publisher") is None else str(ext["publisher"]),
        }
    nodes = doc.get("nodes")
    if not isinstance(nodes, dict) or (not nodes and not graph.nodes):
        if nodes is None and graph.nodes:
            nodes = {}
        else:
            raise _err(file, None, "nodes", "expected a mapping of node names to node declarations")
    for name, body in nodes.items():
        if name in graph.nodes:
            raise _err(file, name, "nodes", f"node defined twice ({graph.nodes[name].file} and {file})")
        graph.nodes[name] = _node_decl(file, str(name), _mapping(body, file, name, "node"))
    policy = doc.get("policy")
    if policy is not None:
        if policy not in POLICIES:
            raise _err(file, None, "policy", f"{policy!r} is not one of {', '.join(POLICIES)}")
        for decl in graph.nodes.values():
            decl.policy = decl.policy or policy
    _apply_overrides(graph, sets or {}, replace or {})
    return graph


def _node_decl(file: str, name: str, body: dict[str, Any]) -> NodeDecl:
    unknown = sorted(set(body) - NODE_KEYS)
    if unknown:
        raise _err(file, name, unknown[0], f"unknown key; expected one of {', '.join(sorted(NODE_KEYS))}")
    if not isinstance(body.get("run"), str):
        raise _err(file, name, "run", "missing: name the module that holds the node (e.g. counterpart.nodes.camera)")
    decl = NodeDecl(name=name, run=body["run"], file=file)
    decl.params = dict(_mapping(body.get("params"), file, name, "params"))
    decl.remap = {str(k): str(v) for k, v in _mapping(body.get("remap"), file, name, "remap").items()}
    decl.policy = body.get("policy")
    if decl.policy is not None and decl.policy not in POLICIES:
        raise _err(file, name, "policy", f"{decl.policy!r} is not one of {', '.join(POLICIES)}")
    for port, v in _mapping(body.get("inputs"), file, name, "inputs").items():
        entry = _mapping(v, file, name, f"inputs.{port}")
        extra = sorted(set(entry) - {"policy", "queue"})
        if extra:
            raise _err(file, name, f"inputs.{port}.{extra[0]}", "unknown key; expected policy, queue")
        pol = entry.get("policy")
        if pol not in POLICIES:
            raise _err(file, name, f"inputs.{port}.policy", f"{pol!r} is not one of {', '.join(POLICIES)}")
        decl.input_policies[str(port)] = pol
        if "queue" in entry:
            decl.input_queues[str(port)] = _queue(entry["queue"], pol, file, name, f"inputs.{port}.queue")
    decl.restart = body.get("restart", "never")
    if decl.restart not in RESTART_POLICIES:
        raise _err(file, name, "restart", f"{decl.restart!r} is not one of {', '.join(RESTART_POLICIES)}")
    decl.max_restarts = int(body.get("max_restarts", 5))
    decl.required = bool(body.get("required", False))
    decl.wait_subscribers = {
        str(k): int(v) for k, v in _mapping(body.get("wait_subscribers"), file, name, "wait_subscribers").items()
    }
    nice = body.get("nice", 0)
    if isinstance(nice, bool) or not isinstance(nice, int) or not NICE_RANGE[0] <= nice <= NICE_RANGE[1]:
        raise _err(
            file,
            name,
            "nice",
            f"{nice!r} is not an integer in {NICE_RANGE[0]}..{NICE_RANGE[1]} (added to the node's niceness: "
            "higher runs it at lower priority; a launcher cannot raise a node's priority)",
        )
    decl.nice = nice
    return decl


def _apply_overrides(graph: Graph, sets: dict[str, Any], replace: dict[str, str]) -> None:
    for key, value in sets.items():
        node, _, param = key.partition(".")
        if not param:
            raise LaunchError(f"--set {key}: expected NODE.PARAM=VALUE")
        if node not in graph.nodes:
            raise LaunchError(f"--set {key}: no node {node!r} in {graph.file}; nodes: {', '.join(graph.nodes)}")
        if isinstance(value, str):
            try:
                value = yaml.safe_load(value)
            except yaml.YAMLError:
                pass
        graph.nodes[node].params[param] = value
    for node, module in replace.items():
        if node not in graph.nodes:
            raise LaunchError(
                f"--replace {node}={module}: no node {node!r} in {graph.file}; nodes: {', '.join(graph.nodes)}"
            )
        graph.nodes[node].run = module


def check(graph: Graph) -> Graph:
    """Resolve every node class, validate parameters, and check that every input has a publisher
    of the same message type.

    Parameters
    ----------
    graph : Graph
        A graph from :func:`load`; filled in place.

    Returns
    -------
    Graph
        ``graph``, checked.

    Raises
    ------
    LaunchError
        Naming file, node and key.
    """
    publishers: dict[str, tuple[str, str, type]] = {}
    for name, decl in graph.nodes.items():
        try:
            cls = find_node_class(decl.run)
        except NodeLookupError as exc:
            raise _err(decl.file, name, "run", str(exc)) from None
        try:
            params = cls.validate_params(decl.params)
        except ParamError as exc:
            raise _err(decl.file, name, "params", str(exc)) from None
        try:
            ins, outs = cls.ports(params)
        except (ParamError, ValueError, OSError) as exc:
            raise _err(decl.file, name, "params", str(exc)) from None
        for port in decl.remap:
            if port not in ins and port not in outs and port != STATS_PORT:
                raise _err(
                    decl.file,
                    name,
                    f"remap.{port}",
                    f"{cls.__name__} has no port {port!r}; inputs: {', '.join(ins) or '-'}; outputs: {', '.join(outs) or '-'}",
                )
        for port in decl.input_policies:
            if port not in ins:
                raise _err(
                    decl.file,
                    name,
                    f"inputs.{port}",
                    f"{cls.__name__} has no input {port!r}; inputs: {', '.join(ins) or '-'}",
                )
        for port in decl.wait_subscribers:
            if port not in outs:
                raise _err(decl.file, name, f"wait_subscribers.{port}", f"{cls.__name__} has no output {port!r}")
        graph.classes[name], graph.params[name] = cls, params
        graph.ports_in[name], graph.ports_out[name] = ins, outs
        for port, out in list(outs.items()) + [(STATS_PORT, Output(by_name("system.NodeStats")))]:
            topic = graph.output_topic(name, port)
            if topic in publishers:
                other = publishers[topic]
                raise _err(
                    decl.file, name, f"outputs.{port}", f"topic {topic!r} is already published by node {other[0]!r}"
                )
            if topic in graph.external:
                raise _err(decl.file, name, f"outputs.{port}", f"topic {topic!r} is declared external in this graph")
            publishers[topic] = (name, port, out.type)
    for topic, ext in graph.external.items():
        try:  # after the node modules are imported, so that their message types are registered
            ext_type = by_name(ext["type"])
        except KeyError as exc:
            raise _err(ext["file"], None, f"external.{topic}.type", str(exc).strip('"')) from None
        publishers[topic] = ("(external)", topic, ext_type)
    publisher_nodes = {
        t: graph.external[t]["publisher"] if t in graph.external else n for t, (n, _, _) in publishers.items()
    }
    subscribers: dict[str, list[tuple[str, str, str]]] = {t: [] for t in publishers}
    for name, decl in graph.nodes.items():
        for port, inp in graph.ports_in[name].items():
            topic = graph.input_topic(name, port)
            if topic not in publishers:
                raise _err(
                    decl.file,
                    name,
                    f"inputs.{port}",
                    f"no node publishes topic {topic!r}; published topics: {', '.join(sorted(publishers)) or '-'}",
                )
            pub_node, pub_port, pub_type = publishers[topic]
            if inp.type is not None and pub_type is not inp.type:
                raise _err(
                    decl.file,
                    name,
                    f"inputs.{port}",
                    f"type mismatch on topic {topic!r}: {pub_node}.{pub_port} publishes {schema_id(pub_type)}, "
                    f"this input takes {schema_id(inp.type)}",
                )
            policy = decl.input_policies.get(port) or decl.policy or inp.policy
            subscribers[topic].append((name, port, policy))
    graph.topics = {
        topic: {
            "type": schema_id(t),
            "publisher": f"{n}.{p}",
            "subscribers": subscribers[topic],
            "node": publisher_nodes[topic],
        }
        for topic, (n, p, t) in publishers.items()
    }
    return graph


def endpoints_for(graph: Graph, run_dir: Path) -> dict[str, TopicEndpoints]:
    """Every topic's endpoints: fixed or external tcp ones, else ipc in the run dir or tcp ports.

    Parameters
    ----------
    graph : Graph
        A checked graph.
    run_dir : Path
        The run directory (ipc sockets).

    Returns
    -------
    dict of str to TopicEndpoints
        Endpoints by topic.
    """
    out: dict[str, TopicEndpoints] = {}
    port = graph.port_base
    for topic in sorted(graph.topics):
        if topic in graph.external:
            out[topic] = tcp_endpoints(graph.external[topic]["endpoint"])
        elif topic in graph.fixed_endpoints:
            out[topic] = tcp_endpoints(graph.fixed_endpoints[topic])
        elif graph.transport == "tcp":
            out[topic] = tcp_endpoints(f"tcp://{graph.host}:{port}")
            port += 3
        else:
            out[topic] = ipc_endpoints(run_dir, topic)
    return out


def stats_dir(run_dir: Path) -> Path:
    """The folder of a run where each node keeps its newest statistics (``NODE.json``).

    Parameters
    ----------
    run_dir : Path
        The run directory.

    Returns
    -------
    Path
        ``run_dir / "stats"``.
    """
    return Path(run_dir) / "stats"


def node_specs(graph: Graph, run_dir: Path) -> dict[str, dict[str, Any]]:
    """The JSON spec each node process is started with.

    Parameters
    ----------
    graph : Graph
        A checked graph.
    run_dir : Path
        The run directory.

    Returns
    -------
    dict of str to dict
        Spec by node name: name, module, params, inputs and outputs (topics, endpoints, policies,
        subscribers to await), statistics file.
    """
    eps = endpoints_for(graph, run_dir)
    specs = {}
    for name, decl in graph.nodes.items():
        spec: dict[str, Any] = {
            "name": name,
            "module": decl.run,
            "params": copy.deepcopy(decl.params),
            "supervised": True,
            "barrier_timeout": graph.barrier_timeout,
            "inputs": {},
            "outputs": {},
            "stats_file": str(stats_dir(run_dir) / f"{name}.json"),
        }
        for port, inp in graph.ports_in[name].items():
            topic = graph.input_topic(name, port)
            policy = decl.input_policies.get(port) or decl.policy or inp.policy
            # the publisher's name authenticates its end of stream (None: an external one not named)
            spec["inputs"][port] = {
                "topic": topic,
                "endpoints": eps[topic].to_dict(),
                "policy": policy,
                "publisher": graph.topics[topic]["node"],
            }
            if port in decl.input_queues:
                spec["inputs"][port]["queue"] = decl.input_queues[port]
        for port in list(graph.ports_out[name]) + [STATS_PORT]:
            topic = graph.output_topic(name, port)
            subs = graph.topics[topic]["subscribers"]
            reliable = sum(1 for _, _, pol in subs if pol == "reliable")
            # lossy subscribers that wait for the end of stream: the startup barrier waits for them
            # too, or a short stream ends before a slow-starting one has connected and it never ends
            latest = sum(1 for n, p, pol in subs if pol == "latest" and graph.ports_in[n][p].awaits_end)
            spec["outputs"][port] = {
                "topic": topic,
                "endpoints": eps[topic].to_dict(),
                "reliable_subscribers": reliable + decl.wait_subscribers.get(port, 0),
                "latest_subscribers": latest,
            }
        specs[name] = spec
    return specs
