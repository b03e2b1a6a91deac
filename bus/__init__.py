"""The runtime: nodes, publish/subscribe, pairing by seq, launch files, supervisor, bags and the CLI."""

from .node import LATEST, RELIABLE, Input, Node, Output, stats_topic
from .pairing import PairedSet, Pairing, PairingStats, SeqSynchronizer
from .params import Param, ParamError
from .seq_history import SeqHistory

__all__ = [
    "Node",
    "Input",
    "Output",
    "Param",
    "ParamError",
    "Pairing",
    "PairedSet",
    "PairingStats",
    "SeqSynchronizer",
    "SeqHistory",
    "RELIABLE",
    "LATEST",
    "stats_topic",
]
