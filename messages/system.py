"""System messages every node understands: end of stream, per-node statistics, log lines."""

from __future__ import annotations

from .core import message, struct


@message("system.EndOfStream", 1)
class EndOfStream:
    """Sent on every output topic when a node's input is exhausted; ``seq`` is the last seq sent."""

    node: str = ""
    reason: str = "end"


@struct
class TopicStats:
    """Counters of one input or output topic of a node."""

    topic: str = ""
    port: str = ""
    count: int = 0
    rate_hz: float = 0.0
    drops: int = 0
    queue_depth: int = 0
    bad: int = 0
    latency_ms: float = 0.0


@message("system.NodeStats", 1)
class NodeStats:
    """Published by every node on ``<node>/stats`` about once per second.

    ``proc_ms_*`` is the handler time per message over the last period; ``latency_ms`` of an input is
    the median of (receive time - stamp) over the period, meaningful on one host. ``figures`` are
    the node's own totals since it started, by name (``frames_with_people``, ``partner_drawn``,
    ``source_fps``, ...): what its work gave, beyond the traffic of its ports.
    """

    node: str = ""
    pid: int = 0
    uptime_s: float = 0.0
    inputs: list[TopicStats] = ()
    outputs: list[TopicStats] = ()
    proc_ms_mean: float = 0.0
    proc_ms_max: float = 0.0
    decode_errors: dict[str, int] = {}  # kind -> count
    figures: dict[str, float] = {}
