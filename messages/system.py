"""System messages every node understands: end of stream, per-node statistics, log lines."""

from __future__ import annotations

from .core import message, struct


@message("system.EndOfStream", 1)
class EndOfStream:
    """Sent on every output topic when a node's input is exhausted; ``seq`` is the last seq sent.

    Attributes
    ----------
    node : str
        Name of the node that sends it.
    reason : str
        Why the stream ended (``"end"`` when the input is exhausted).
    """

    node: str = ""
    reason: str = "end"


@struct
class TopicStats:
    """Counters of one input or output topic of a node.

    Attributes
    ----------
    topic : str
        The topic's name.
    port : str
        The node's port the topic is bound to.
    count : int
        Messages over the topic.
    rate_hz : float
        Message rate, Hz.
    drops : int
        Messages dropped.
    queue_depth : int
        Messages waiting in the queue.
    bad : int
        Messages that could not be decoded.
    latency_ms : float
        Of an input: the median of (receive time - stamp) over the period, ms; meaningful on one host.
    """

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

    ``latency_ms`` of an input is the median of (receive time - stamp) over the period, meaningful on
    one host.

    Attributes
    ----------
    node : str
        The node's name.
    pid : int
        The node's process id.
    uptime_s : float
        Time since the node started, seconds.
    inputs : list of TopicStats
        Counters of the node's input topics.
    outputs : list of TopicStats
        Counters of the node's output topics.
    proc_ms_mean : float
        Mean handler time per message over the last period, ms.
    proc_ms_max : float
        Largest handler time per message over the last period, ms.
    decode_errors : dict of str to int
        Decode errors by kind.
    figures : dict of str to float
        The node's own totals since it started, by name (``frames_with_people``, ``partner_drawn``,
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
