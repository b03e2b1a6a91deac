"""What a finished run of the graph gave, from every node's last statistics: the summary a person
reads at the end of ``counterpart demo`` and the figures of ``OUT/demo_stats.json``.

Each node of a launch keeps its newest ``NodeStats`` in ``RUN_DIR/stats/NODE.json`` (written by
:class:`counterpart.bus.node.Node` with every stats message and once more as it ends), so the summary reads
files rather than a lossy subscription that can miss a node's last word.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from counterpart.messages import NodeStats, TopicStats

from .launchfile import stats_dir
from .runner import failure_file

#: share of output frames without a partner above which the summary warns
MISSING_WARN = 0.1


def read_failure(run_dir: Path, node: str) -> str:
    """Why ``node`` failed in the run ``run_dir``, as it left it (its last error line), or "".

    Parameters
    ----------
    run_dir : Path
        The launch's run directory.
    node : str
        The node's name.

    Returns
    -------
    str
        The reason, or "" where the node left none.
    """
    try:
        return failure_file(stats_dir(run_dir) / f"{node}.json").read_text(encoding="utf-8").strip()
    except OSError:
        return ""


def read_stats(run_dir: Path) -> dict[str, NodeStats]:
    """Every node's last :class:`NodeStats`, for every node that wrote one in ``run_dir``.

    Parameters
    ----------
    run_dir : Path
        The launch's run directory.

    Returns
    -------
    dict of str to NodeStats
        Node name -> its last statistics; an unreadable file gives empty statistics whose
        ``decode_errors`` say why.
    """
    out: dict[str, NodeStats] = {}
    for path in sorted(stats_dir(run_dir).glob("*.json")):
        try:
            d = json.loads(path.read_text())
            d["inputs"] = [TopicStats(**t) for t in d.get("inputs", [])]
            d["outputs"] = [TopicStats(**t) for t in d.get("outputs", [])]
            out[path.stem] = NodeStats(**d)
        except (OSError, ValueError, TypeError) as exc:  # a node killed mid-write leaves no .json: rare
            out.setdefault(path.stem, NodeStats(node=path.stem, decode_errors={f"unreadable stats: {exc}": 1}))
    return out


@dataclass(frozen=True)
class PortLoad:
    """One input of a node: messages it handled of those offered to it (handled + dropped).

    Parameters
    ----------
    node : str
        The node's name.
    port : str
        The input port.
    handled : int
        Messages the node handled on the port.
    offered : int
        Messages offered to it (handled + dropped).
    """

    node: str
    port: str
    handled: int
    offered: int


@dataclass(frozen=True)
class RunSummary:
    """The figures of one run. Shares are in [0, 1]; frame rates in frames per second (0: unknown).

    Parameters
    ----------
    frames_in : int, default=0
        Frames the camera gave.
    frames_with_people : int, default=0
        Frames in which the silhouette node found people.
    frames_out : int, default=0
        Frames the renderer wrote.
    partner_drawn : int, default=0
        Output frames with a partner drawn.
    frames_out_after_1s : int, default=0
        Output frames after the first second of the stream.
    partner_drawn_after_1s : int, default=0
        Of those, the frames with a partner drawn.
    fps_in : float, default=0.0
        Frame rate of the source, frames per second.
    fps_out : float, default=0.0
        Frame rate of the output video, frames per second.
    loads : list of PortLoad
        The load of each node's clock input (:data:`CLOCK_PORTS`).
    """

    frames_in: int = 0
    frames_with_people: int = 0
    frames_out: int = 0
    partner_drawn: int = 0
    frames_out_after_1s: int = 0
    partner_drawn_after_1s: int = 0
    fps_in: float = 0.0
    fps_out: float = 0.0
    loads: list[PortLoad] = field(default_factory=list)

    @property
    def partner_present(self) -> float:
        """Share of the output frames with a partner drawn in the picture."""
        return self.partner_drawn / self.frames_out if self.frames_out else 0.0

    @property
    def partner_present_after_1s(self) -> float:
        """The same share over the frames after the first second of the stream (while the
        background is learnt and the tracks start, a partner may still be missing).
        """
        return self.partner_drawn_after_1s / self.frames_out_after_1s if self.frames_out_after_1s else 0.0

    def to_json(self) -> dict[str, Any]:
        """The figures as a JSON-ready dict (the shares rounded to 4 places, loads under ``handled``).

        Returns
        -------
        dict of str to object
            The figures by name.
        """
        return {
            "frames_in": self.frames_in,
            "frames_with_people": self.frames_with_people,
            "frames_out": self.frames_out,
            "partner_drawn": self.partner_drawn,
            "partner_present": round(self.partner_present, 4),
            "partner_present_after_1s": round(self.partner_present_after_1s, 4),
            "fps_in": self.fps_in,
            "fps_out": self.fps_out,
            "handled": {f"{p.node}.{p.port}": {"handled": p.handled, "offered": p.offered} for p in self.loads},
        }

    def problem(self) -> str | None:
        """Why the run failed its purpose (no partner at all), or None.

        Returns
        -------
        str or None
            The reason, or None when a partner was drawn at least once.
        """
        if self.frames_in == 0:
            return "the input gave no frames"
        if self.frames_out == 0:
            return f"the renderer wrote none of the {self.frames_in} frames"
        if self.partner_drawn == 0:
            people = (
                f"people were found in {self.frames_with_people} of {self.frames_in} frames"
                if self.frames_with_people
                else "no person was found in any frame"
            )
            return f"no partner was drawn on any of the {self.frames_out} frames ({people})"
        return None

    def warnings(self) -> list[str]:
        """Lines a person should read: a partner missing on many frames, nodes that did not keep up.

        Returns
        -------
        list of str
            One line per warning: the partner missing on more than :data:`MISSING_WARN` of the output
            frames, and each input that handled fewer messages than it was offered.
        """
        out = []
        missing = self.frames_out - self.partner_drawn
        if self.frames_out and missing > MISSING_WARN * self.frames_out:
            out.append(
                f"warning: no partner on {missing} of {self.frames_out} frames "
                f"({100 * missing / self.frames_out:.0f}%; people found in {self.frames_with_people} "
                f"of {self.frames_in})"
            )
        for p in self.loads:
            if p.handled < p.offered:
                out.append(
                    f"warning: {p.node} handled {p.handled} of {p.offered} frames offered on {p.port} "
                    "(it could not keep up in real time; without --realtime every frame is processed)"
                )
        return out

    def lines(self) -> list[str]:
        """The summary as a person reads it.

        Returns
        -------
        list of str
            The lines of the summary.
        """
        return [
            f"frames in:          {self.frames_in}" + (f" at {self.fps_in:.3g} fps" if self.fps_in else ""),
            f"frames with people: {self.frames_with_people}",
            f"frames out:         {self.frames_out}" + (f" at {self.fps_out:.3g} fps" if self.fps_out else ""),
            f"partner drawn on:   {self.partner_drawn} ({100 * self.partner_present:.0f}%; "
            f"{100 * self.partner_present_after_1s:.0f}% after the first second)",
        ]


#: the input of each node whose load the summary reports (its frame clock)
CLOCK_PORTS = {
    "silhouette": "frame",
    "tracker": "silhouettes",
    "labeller": "pose",
    "responder": "pose",
    "renderer": "frame",
}


def summarise(
    stats: dict[str, NodeStats], camera: str = "camera", silhouette: str = "silhouette", renderer: str = "renderer"
) -> RunSummary:
    """The run's figures from the nodes' last statistics (nodes named as in the demo's graphs).

    Parameters
    ----------
    stats : dict of str to NodeStats
        Every node's last statistics, as :func:`read_stats` returns them.
    camera : str, default="camera"
        The name of the camera node.
    silhouette : str, default="silhouette"
        The name of the silhouette node.
    renderer : str, default="renderer"
        The name of the renderer node.

    Returns
    -------
    RunSummary
        The figures; those of a node missing from ``stats`` are 0.
    """

    def fig(node: str, name: str) -> float:
        st = stats.get(node)
        return float(st.figures.get(name, 0)) if st is not None else 0.0

    cam = stats.get(camera)
    frames_in = sum(t.count for t in cam.outputs if t.port == "frame") if cam is not None else 0
    loads = []
    for node, port in CLOCK_PORTS.items():
        st = stats.get(node)
        for t in st.inputs if st is not None else []:
            if t.port == port:
                loads.append(PortLoad(node, port, t.count, t.count + t.drops))
    return RunSummary(
        frames_in=frames_in,
        frames_with_people=int(fig(silhouette, "frames_with_people")),
        frames_out=int(fig(renderer, "rendered")),
        partner_drawn=int(fig(renderer, "partner_drawn")),
        frames_out_after_1s=int(fig(renderer, "rendered_after_1s")),
        partner_drawn_after_1s=int(fig(renderer, "partner_drawn_after_1s")),
        fps_in=fig(camera, "source_fps"),
        fps_out=fig(renderer, "video_fps"),
        loads=loads,
    )


def stats_table(stats: dict[str, NodeStats]) -> str:
    """A plain-text table: per node, messages in/out, rates, drops, latency and handler time.

    Parameters
    ----------
    stats : dict of str to NodeStats
        Every node's last statistics.

    Returns
    -------
    str
        The table, a header line then one line per node in name order.
    """
    rows = [
        f"{'node':12s} {'in':>7s} {'out':>7s} {'in Hz':>7s} {'drops':>6s} {'lat ms':>7s} {'proc ms':>8s} {'bad':>4s}"
    ]
    for name, st in sorted(stats.items()):
        n_in = sum(t.count for t in st.inputs)
        n_out = sum(t.count for t in st.outputs)
        hz = max((t.rate_hz for t in st.inputs), default=0.0)
        drops = sum(t.drops for t in st.inputs)
        lat = max((t.latency_ms for t in st.inputs), default=0.0)
        rows.append(
            f"{name:12s} {n_in:7d} {n_out:7d} {hz:7.1f} {drops:6d} {lat:7.1f} {st.proc_ms_mean:8.2f} "
            f"{sum(st.decode_errors.values()):4d}"
        )
    return "\n".join(rows)


def stats_json(stats: dict[str, NodeStats]) -> dict[str, Any]:
    """Every node's statistics as JSON-ready dicts.

    Parameters
    ----------
    stats : dict of str to NodeStats
        Every node's last statistics.

    Returns
    -------
    dict of str to dict
        Node name -> its statistics (``counterpart.bus.cli_introspect.summarise``).
    """
    from .cli_introspect import summarise as as_json

    return {name: as_json(st) for name, st in stats.items()}


__all__ = ["read_stats", "summarise", "stats_table", "stats_json", "RunSummary", "PortLoad", "MISSING_WARN"]
