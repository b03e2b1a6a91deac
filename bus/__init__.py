"""The runtime: nodes, publish/subscribe, launch files, supervisor, bags and the CLI."""

from .node import LATEST, RELIABLE, Input, Node, Output, stats_topic
from .params import Param, ParamError

__all__ = ["Node", "Input", "Output", "Param", "ParamError", "RELIABLE", "LATEST", "stats_topic"]
