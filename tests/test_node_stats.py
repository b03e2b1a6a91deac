"""A node's statistics as a run's summary reads them: its last word after the stream went quiet."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from counterpart.bus.run_summary import read_stats
from tests.launching import kill_tree, start_launch, write_launch

N = "tests.graph_nodes:"


def test_the_last_statistics_after_an_idle_spell_keep_the_last_busy_ones(tmp_path: Path) -> None:
    """The source sends for a second, then waits 2.5 s before its end of stream: the sink's last
    statistics (written at its end, over a window in which nothing came) still give its rate and
    its processing time per message, as the summary's table shows them, and the run's counts. The
    rate is the run's: a window that held only the stream's last message and then a second of quiet
    once gave 1 Hz here.
    """
    home = Path(tempfile.mkdtemp(prefix="cps", dir="/tmp"))
    doc = {
        "nodes": {
            "source": {
                "run": N + "Counter",
                "params": {"count": 40, "rate": 40.0, "hold_s": 2.5},
                "remap": {"out": "numbers"},
            },
            "sink": {
                "run": N + "Sink",
                "params": {"path": str(tmp_path / "sink.jsonl"), "delay_ms": 5.0},
                "remap": {"in": "numbers"},
            },
        },
    }
    proc = start_launch(write_launch(tmp_path / "g.yaml", doc), env={"COUNTERPART_HOME": str(home)})
    try:
        out, _ = proc.communicate(timeout=60)
        assert proc.returncode == 0, out
        sink = read_stats(home / "latest")["sink"]
        (numbers,) = sink.inputs
        assert numbers.count == 40
        assert 10.0 < numbers.rate_hz < 80.0, sink  # about the source's 40 Hz, not the idle 0
        assert 4.0 < sink.proc_ms_mean < 50.0 and sink.proc_ms_max >= sink.proc_ms_mean, sink
    finally:
        kill_tree(proc)
        shutil.rmtree(home, ignore_errors=True)
