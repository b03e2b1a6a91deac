"""The runtime's seq synchroniser (counterpart.bus.pairing): alone (no processes, no sockets), and in a real
graph (real launcher, real nodes) through a node that declares paired inputs.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from counterpart.bus import PairedSet, Pairing, SeqSynchronizer
from tests.launching import read_jsonl, run_launch, write_launch


def sync(required=("silhouettes",), optional=("pose",), **kw) -> SeqSynchronizer:
    return SeqSynchronizer(Pairing(tuple(required), tuple(optional), **kw))


def released(items: list[PairedSet]) -> list[tuple[int, list[str], bool]]:
    """(seq, the ports that delivered, restart) of each set."""
    return [(p.seq, sorted(k for k, v in p.msgs.items() if v is not None), p.restart) for p in items]


def test_in_order_and_out_of_order_sets_go_out_complete_and_in_seq_order() -> None:
    pr = sync()
    assert pr.add("silhouettes", 0, "s0") == []
    assert pr.add("silhouettes", 1, "s1") == []
    out = pr.add("pose", 0, "p0")
    assert released(out) == [(0, ["pose", "silhouettes"], False)] and out[0].msgs == {"silhouettes": "s0", "pose": "p0"}
    assert released(pr.add("pose", 1, "p1")) == [(1, ["pose", "silhouettes"], False)]
    # the optional input may also come first
    assert pr.add("pose", 2, "p2") == [] and pr.pending == [2]
    out = pr.add("silhouettes", 2, "s2")
    assert [p.msgs for p in out] == [{"pose": "p2", "silhouettes": "s2"}] and out[0]["pose"] == "p2"
    assert pr.pending == [] and pr.stats.partial == 0 and pr.stats.delivered == 3


def test_missing_optional_goes_out_as_none_and_a_set_without_a_required_input_is_dropped() -> None:
    pr = sync()
    got = []
    got += pr.add("pose", 0, "p0")
    got += pr.add("silhouettes", 0, "s0")
    got += pr.add("silhouettes", 1, "s1")  # pose 1 will never come
    got += pr.add("silhouettes", 2, "s2")
    assert released(got) == [(0, ["pose", "silhouettes"], False)] and pr.pending == [1, 2]
    got += pr.add("pose", 2, "p2")  # a newer pose: set 1 is decided without it
    assert released(got)[1:] == [(1, ["silhouettes"], False), (2, ["pose", "silhouettes"], False)]
    assert got[1].get("pose") is None and got[1]["pose"] is None
    got += pr.add("pose", 3, "p3")  # silhouettes 3 never come
    got += pr.add("pose", 4, "p4")
    got += pr.add("silhouettes", 4, "s4")
    assert [p.seq for p in got] == [0, 1, 2, 4]
    assert pr.stats.dropped == 1 and pr.stats.missing == {"silhouettes": 0, "pose": 1} and pr.stats.delivered == 4
    assert pr.stats.partial == 1


def test_max_pending_bounds_the_wait_late_messages_are_counted_and_an_ended_input_holds_nothing() -> None:
    pr = sync(max_pending=3)
    got = []
    for s in range(6):  # the pose topic stalls
        got += pr.add("silhouettes", s, f"s{s}")
    assert [p.seq for p in got] == [0, 1, 2] and pr.pending == [3, 4, 5]
    assert all(p.msgs["pose"] is None for p in got) and pr.stats.forced == 3
    assert pr.add("pose", 1, "p1") == [] and pr.stats.late == 1  # its set went out already
    out = pr.end("pose")  # the tracker is gone: nothing to wait for
    assert [p.seq for p in out] == [3, 4, 5]
    assert released(pr.add("silhouettes", 6, "s6")) == [(6, ["silhouettes"], False)]
    assert pr.flush() == []


def test_messages_ahead_of_a_required_input_wait_for_it_up_to_max_ahead_memory_stays_bounded() -> None:
    # camera frames come long before their silhouettes: they wait, nothing is forced out
    pr = sync(optional=("frame",), max_pending=2, max_ahead=5)
    for s in range(7):
        assert pr.add("frame", s, f"f{s}") == []
    assert pr.pending == list(range(7)) and pr.stats.forced == 0
    assert [p.msgs for p in pr.add("silhouettes", 0, "s0")] == [{"frame": "f0", "silhouettes": "s0"}]
    assert pr.add("frame", 7, "f7") == [] and pr.add("frame", 8, "f8") == []  # 8 sets ahead: 1 goes
    assert pr.pending == list(range(2, 9)) and pr.stats.overflow == 1
    assert released(pr.add("silhouettes", 1, "s1")) == [(1, ["silhouettes"], False)]
    assert released(pr.add("silhouettes", 2, "s2")) == [(2, ["frame", "silhouettes"], False)]
    assert pr.stats.missing == {"silhouettes": 0, "frame": 1} and pr.stats.dropped == 0
    # a required input that stalls for good: however many messages come, at most 2 + 5 sets are held
    for s in range(9, 10_000):
        pr.add("frame", s, f"f{s}")
        assert len(pr.pending) <= 7
    assert pr.stats.overflow == 1 + 6 + (10_000 - 9) - 7  # sets 3..8 were held before


def test_restart_flags_the_first_set_of_the_new_stream() -> None:
    pr = sync(optional=())
    got = []
    for s in (0, 1, 2, 0, 1):
        got += pr.add("silhouettes", s, s)
    assert released(got) == [
        (0, ["silhouettes"], False),
        (1, ["silhouettes"], False),
        (2, ["silhouettes"], False),
        (0, ["silhouettes"], True),
        (1, ["silhouettes"], False),
    ]
    assert pr.stats.restarts == 1


def replay(pr: SeqSynchronizer, fast: str, slow: str, slow_old: int) -> list[PairedSet]:
    """Both inputs play seqs 0..4 of an old stream ("old", seq), then restart ("new", seq); the
    ``fast`` one restarts before the ``slow`` one has delivered more than seq 0 of the old one.
    """
    got = pr.add(fast, 0, ("old", 0))
    for s in range(1, 5):
        got += pr.add(fast, s, ("old", s))
    got += pr.add(slow, 0, ("old", 0))
    for s in range(3):  # the fast input restarted
        got += pr.add(fast, s, ("new", s))
    for s in range(1, slow_old):  # the old stream's tail on the slow input
        got += pr.add(slow, s, ("old", s))
    for s in range(3):
        got += pr.add(slow, s, ("new", s))
    return got


def test_restart_never_pairs_the_old_stream_with_the_new_one() -> None:
    # tracker: frames (the anchor) restart first, the slower silhouettes still deliver the old tail
    pr = sync(required=("frame", "silhouettes"), optional=())
    got = replay(pr, "frame", "silhouettes", 5)
    assert [(p.seq, p.restart) for p in got] == [(s, False) for s in range(5)] + [(0, True), (1, False), (2, False)]
    assert all(p["frame"] == p["silhouettes"] == (p["frame"][0], p.seq) for p in got)
    assert pr.stats.restarts == 1 and pr.stats.dropped == 0 and pr.stats.late == 0


def test_an_input_that_restarts_before_the_anchor_joins_the_new_stream_when_the_anchor_restarts() -> None:
    # labeller: camera frames (optional) restart long before the silhouettes (the anchor) do
    pr = sync(optional=("frame",))
    got = replay(pr, "frame", "silhouettes", 4)  # the old silhouettes end at 3
    assert [(p.seq, p.restart) for p in got] == [(s, False) for s in range(4)] + [(0, True), (1, False), (2, False)]
    assert all(p["frame"] == p["silhouettes"] == (p["frame"][0], p.seq) for p in got)
    assert pr.stats.dropped == 1 and pr.stats.partial == 0  # old frame 4 never got its silhouettes
    assert pr.flush() == []


def test_an_input_that_replays_and_ends_before_the_anchor_restarts_still_pairs_with_its_own_stream() -> None:
    pr = sync(optional=("frame",))
    got = []
    for loop in ("old", "new"):  # the fast input plays both streams and ends
        for s in range(3):
            got += pr.add("frame", s, (loop, s))
    got += pr.end("frame")
    for loop in ("old", "new"):
        for s in range(3):
            got += pr.add("silhouettes", s, (loop, s))
    got += pr.flush()
    assert [(p.seq, p.restart) for p in got] == [(0, False), (1, False), (2, False), (0, True), (1, False), (2, False)]
    assert all(p["frame"] == p["silhouettes"] for p in got)


def test_a_straggler_that_goes_back_alone_is_late_and_pairing_goes_on() -> None:
    pr = sync(required=("frame",), optional=("partner",))
    got = []
    for s in range(5):
        got += pr.add("frame", s, s)
        got += pr.add("partner", s, s)
    got += pr.add("frame", 5, 5)
    got += pr.add("partner", 2, "again")  # a stray partner: held aside while it may be a restart
    got += pr.add("frame", 6, 6)
    got += pr.add("partner", 5, 5)  # back past where it was: the stray one was late
    got += pr.add("partner", 6, 6)
    assert [(p.seq, p["partner"], p.restart) for p in got] == [(s, s, False) for s in range(7)]
    assert pr.stats.late == 1 and pr.stats.restarts == 0
    # a stray copy of a partner that waits for its frame never replaces it
    got = pr.add("partner", 8, 8) + pr.add("partner", 8, "copy") + pr.add("partner", 9, 9)
    got += pr.add("frame", 7, 7) + pr.add("frame", 8, 8)
    assert [(p.seq, p["partner"]) for p in got] == [(7, None), (8, 8)] and pr.stats.late == 2


def test_timeout_gives_up_on_optional_inputs_from_the_arrival_of_the_required_ones() -> None:
    pr = sync(required=("frame",), optional=("partner",), timeout=0.5)
    for s in range(3):
        assert pr.add("frame", s, s, now=float(s) * 0.1) == []
    assert pr.next_deadline() == pytest.approx(0.5)
    assert pr.poll(now=0.4) == []
    assert [p.seq for p in pr.poll(now=0.65)] == [0, 1]  # frame 1 came at 0.1
    assert pr.stats.timed_out == 2 and pr.stats.missing["partner"] == 2
    pr.timeout = 0.0  # a node may stop waiting altogether
    assert [p.seq for p in pr.poll(now=0.65)] == [2]
    assert pr.next_deadline() is None


def test_random_interleavings_match_the_exact_sets() -> None:
    rng = np.random.default_rng(7)
    for trial in range(200):
        n = int(rng.integers(1, 40))
        have = {
            port: sorted(rng.choice(n, int(rng.integers(0, n + 1)), replace=False).tolist())
            for port in ("silhouettes", "pose", "frame")
        }
        streams = {port: [(port, s) for s in seqs] for port, seqs in have.items()}
        pr = sync(optional=("pose", "frame"), max_pending=10_000)
        got = []
        while any(streams.values()):  # merge the three in-order streams at random
            port = rng.choice([p for p, q in streams.items() if q])
            _, s = streams[port].pop(0)
            got += pr.add(port, s, (port, s))
        got += pr.flush()
        assert [p.seq for p in got] == have["silhouettes"], trial
        for p in got:
            assert {k for k, v in p.msgs.items() if v is not None} == {
                port for port, seqs in have.items() if p.seq in seqs
            }, trial
            assert all(m == (port, p.seq) for port, m in p.msgs.items() if m is not None), trial


def test_stats_as_figures() -> None:
    pr = sync()
    pr.add("silhouettes", 0, "s0")
    pr.flush()
    fig = pr.stats.figures()
    assert fig["paired_delivered"] == 1.0 and fig["paired_partial"] == 1.0 and fig["paired_missing_pose"] == 1.0
    assert fig["paired_late"] == 0.0 and fig["paired_dropped"] == 0.0


def test_bad_declarations_are_refused_naming_the_problem() -> None:
    with pytest.raises(ValueError, match="at least one required"):
        Pairing(())
    with pytest.raises(ValueError, match="both required and optional"):
        Pairing(("pose",), ("pose",))
    with pytest.raises(ValueError, match="max_pending"):
        Pairing(("silhouettes",), max_pending=0)
    with pytest.raises(ValueError, match="max_ahead"):
        Pairing(("silhouettes",), max_ahead=-1)
    with pytest.raises(ValueError, match="timeout"):
        Pairing(("silhouettes",), timeout=-1.0)
    with pytest.raises(KeyError, match="unknown port 'frame'"):
        sync().add("frame", 0, None)
    p = Pairing(("silhouettes",), ("pose", "frame"))
    assert p.restrict(["silhouettes", "frame"]) == Pairing(("silhouettes",), ("frame",))
    assert p.restrict(["pose"]) is None


# ------------------------------------------------------------------------ real launcher, real nodes
@pytest.mark.slow
def test_a_node_declaring_paired_inputs_gets_one_callback_per_complete_set(tmp_path: Path) -> None:
    P = "tests.pairing_nodes:"
    loops = {"count": 100, "loops": 2}
    graph = {
        "nodes": {
            "a": {"run": P + "Frames", "params": loops, "remap": {"out": "a"}},
            "b": {"run": P + "Frames", "params": {**loops, "skip_every": 5}, "remap": {"out": "b"}},
            "c": {"run": P + "Frames", "params": {**loops, "keep_every": 3}, "remap": {"out": "c"}},
            "sink": {"run": P + "PairSink", "params": {"path": str(tmp_path / "sets.jsonl")}},
        }
    }
    code, out = run_launch(write_launch(tmp_path / "g.yaml", graph), timeout=60)
    assert code == 0, out
    rows = read_jsonl(tmp_path / "sets.jsonl")
    sets, figures = rows[:-1], rows[-1]["figures"]
    both = [s for s in range(100) if s % 5]  # b leaves out multiples of 5: those sets never complete
    assert [(r["seq"], r["loop"], r["b"]) for r in sets] == [(s, lp, lp) for lp in (0.0, 1.0) for s in both]
    assert [r["c"] for r in sets] == [lp if s % 3 == 0 else None for lp in (0.0, 1.0) for s in both]
    assert [i for i, r in enumerate(sets) if r["restart"]] == [len(both)]  # the first set of the replay
    partial = 2 * sum(s % 3 != 0 for s in both)
    assert figures["paired_delivered"] == 2 * len(both) and figures["paired_partial"] == partial
    assert figures["paired_missing_c"] == partial and figures["paired_missing_b"] == 0
    assert figures["paired_dropped"] == 2 * 20 and figures["paired_restarts"] == 1
    assert figures["paired_late"] == 0 and figures["paired_forced"] == 0 and figures["paired_overflow"] == 0
