"""A recording sink for launch tests: subscribes to any one topic and writes a JSON line per message.

In a launch file::

    sink:
      run: tests.topic_sink
      params: {topic: silhouettes, path: /tmp/out.jsonl}
      policy: reliable

The input port is named after ``topic`` (so no remap is needed) and takes any message type. Each
line is :func:`summarise` of the message plus ``"type"`` (schema id) and ``"received"`` (monotonic
ns); at end of stream a last line ``{"event": "end", "count", "drops"}``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import time
from typing import Any

import numpy as np

from counterpart.bus import Input, Node, Param
from counterpart.messages import schema_id

#: arrays up to this many elements are written out in full, larger ones as a summary
SMALL_ARRAY = 256


def _number(v: float) -> float | None:
    return None if isinstance(v, float) and not math.isfinite(v) else v


def summarise(value: Any) -> Any:
    """A JSON-able form of a message: dataclass fields by name, small arrays as (nested) lists with
    NaN/inf as null, larger ones as ``{"shape", "dtype", "sha1", "nonzero", "max"}``.
    """
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: summarise(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, np.ndarray):
        if value.size <= SMALL_ARRAY:
            flat = [_number(v) for v in value.ravel().tolist()]
            return np.array(flat, dtype=object).reshape(value.shape).tolist() if value.ndim else flat[0]
        return {
            "shape": list(value.shape),
            "dtype": str(value.dtype),
            "sha1": hashlib.sha1(np.ascontiguousarray(value).tobytes()).hexdigest(),
            "nonzero": int(np.count_nonzero(value)),
            "max": _number(value.max().item()),
        }
    if isinstance(value, (list, tuple)):
        return [summarise(v) for v in value]
    if isinstance(value, dict):
        return {str(k): summarise(v) for k, v in value.items()}
    if isinstance(value, np.generic):
        return _number(value.item())
    if isinstance(value, float):
        return _number(value)
    return value


class TopicSink(Node):
    """Appends one JSON line per message of ``topic`` to ``path``, then an end line."""

    params = {
        "topic": Param(
            str,
            "",
            "the topic to record (also the input port's name)",
            check=lambda v: None if v else "must name a topic",
        ),
        "path": Param(str, "", "output file (JSON lines)", check=lambda v: None if v else "must name a file"),
    }

    @classmethod
    def ports(cls, params: dict[str, Any]) -> tuple[dict[str, Input], dict]:
        return {params["topic"]: Input(None, doc="any message")}, {}

    def setup(self) -> None:
        self.f = open(self.p["path"], "a", buffering=1)
        self.count = 0

    def on_message(self, port: str, msg: Any) -> None:
        rec = summarise(msg)
        rec["type"] = schema_id(msg)
        rec["received"] = time.monotonic_ns()
        self.f.write(json.dumps(rec) + "\n")
        self.count += 1

    def on_end(self) -> None:
        self.f.write(json.dumps({"event": "end", "count": self.count, "drops": self._in[self.p["topic"]].drops}) + "\n")

    def teardown(self) -> None:
        if getattr(self, "f", None) is not None:
            self.f.close()


NODE = TopicSink
