"""Nodes for the multi-process test of paired inputs: a source that skips frames and replays its
stream, and a sink that declares paired inputs and records every set it gets.
"""

from __future__ import annotations

import json

from counterpart.bus import Input, Node, Output, PairedSet, Pairing, Param
from tests.graph_nodes import Number


class Frames(Node):
    """Publishes seqs 0..count-1 that are multiples of ``keep_every`` and not of ``skip_every``,
    ``loops`` times over (seq going back to 0 each time: a stream that restarts).
    """

    outputs = {"out": Output(Number)}
    params = {
        "count": Param(int, 100, "seqs per loop", min=1),
        "keep_every": Param(int, 1, "publish only multiples of this", min=1),
        "skip_every": Param(int, 0, "leave out multiples of this (0: none)", min=0),
        "loops": Param(int, 1, "times the stream is played", min=1),
    }

    def generate(self) -> None:
        p = self.p
        for loop in range(p["loops"]):
            for i in range(p["count"]):
                if self.stopping:
                    return
                if i % p["keep_every"] or (p["skip_every"] and i % p["skip_every"] == 0):
                    continue
                self.publish("out", Number(seq=i, value=float(loop)))


class PairSink(Node):
    """Pairs ``a`` and ``b`` (required) with ``c`` (optional) by seq; one JSON line per set, and the
    node's stats figures once it is done.
    """

    inputs = {"a": Input(Number), "b": Input(Number), "c": Input(Number)}
    params = {"path": Param(str, "", "output file (JSON lines)", check=lambda v: None if v else "must name a file")}
    # bounds above the streams' length: what the sink gets does not depend on how the sources interleave
    pairing = Pairing(required=("a", "b"), optional=("c",), max_pending=1000, max_ahead=1000)

    def setup(self) -> None:
        self.f = open(self.p["path"], "w", buffering=1)

    def on_paired(self, paired: PairedSet) -> None:
        c = paired.get("c")
        row = {"seq": paired.seq, "restart": paired.restart, "loop": paired["a"].value, "b": paired["b"].value}
        self.f.write(json.dumps({**row, "c": None if c is None else c.value}) + "\n")

    def teardown(self) -> None:
        # after the node's last stats went out: the figures they carried
        self.f.write(json.dumps({"figures": self.figures}) + "\n")
        self.f.close()
