"""Nodes that fail on purpose, for the fault tests: one that cannot start, one slow to set up."""

from __future__ import annotations

import time

from counterpart.bus import Input, Node, Output, Param
from tests.graph_nodes import Number


class FailAtStart(Node):
    """A source that fails before its first message, as a camera that cannot open its device:
    ``how`` ``exit`` ends with ``code`` (after logging why), ``raise`` crashes in setup. Appends the
    wall-clock time of the failure to ``mark`` first, one line per start.
    """

    outputs = {"out": Output(Number)}
    params = {
        "how": Param(str, "exit", "exit (with code) or raise (in setup)", choices=("exit", "raise")),
        "code": Param(int, 3, "exit code for how=exit", min=1, max=125),
        "mark": Param(str, "", "file that gets the time of each failure"),
        "delay": Param(float, 0.0, "seconds to wait before failing (the other nodes start meanwhile)", min=0),
    }

    def _mark(self) -> None:
        time.sleep(self.p["delay"])
        if self.p["mark"]:
            with open(self.p["mark"], "a") as f:
                f.write(f"{time.time()}\n")

    def setup(self) -> None:
        if self.p["how"] == "raise":
            self._mark()
            raise RuntimeError("the model file is corrupt")

    def generate(self) -> None:
        self._mark()
        self.log.error("cannot open the device")
        self.exit_code = self.p["code"]


class SlowSetup(Node):
    """A node whose setup takes ``seconds`` (a model loading) and ignores the first stop signal
    meanwhile, as a node busy in a long library call would.
    """

    inputs = {"in": Input(Number)}
    params = {"seconds": Param(float, 60.0, "setup time", min=0)}

    def setup(self) -> None:
        end = time.monotonic() + self.p["seconds"]
        while time.monotonic() < end:
            time.sleep(0.05)

    def on_in(self, msg: Number) -> None:
        pass
