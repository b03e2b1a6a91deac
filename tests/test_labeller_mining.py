"""Association-rule mining with temporal bagging (counterpart.nodes.labeller.mining, cli_mine)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from mlxtend.frequent_patterns import apriori, association_rules
from mlxtend.preprocessing import TransactionEncoder

from counterpart.apps import mine as cli_mine
from counterpart.nodes.labeller.mining import (
    LabelStreams,
    Rule,
    build_transactions,
    compare_scenarios,
    mine_rules,
    mine_rules_sessions,
    read_labels,
    read_labels_csv,
    read_labels_npz,
    read_rules,
    write_labels_csv,
    write_rules,
)
from counterpart.nodes.labeller.signals import UNKNOWN
from counterpart.sim.planted_signals import planted_label_streams


def _events(rng: np.random.Generator, t: int, n: int, length: int) -> np.ndarray:
    m = np.zeros(t, dtype=bool)
    for s in rng.choice(np.arange(0, t - length, 3 * length), n, replace=False):
        m[s : s + length] = True
    return m


def test_identical_to_a_direct_mlxtend_run() -> None:
    rng = np.random.default_rng(0)
    names = ["nod", "shake", "gaze_at_other", "activity"]
    sp = rng.random((3000, 4)) < [0.2, 0.1, 0.5, 0.3]
    li = rng.random((3000, 4)) < [0.15, 0.1, 0.6, 0.2]
    li[7:, 0] |= sp[:-7, 0] & (rng.random(2993) < 0.5)
    ours = mine_rules(sp, li, names, offset=7, min_support=0.02, min_confidence=0.2)

    # the same transactions written out by hand, one item list per frame
    tx = [
        [f"S:{n}" for k, n in enumerate(names) if sp[t, k]] + [f"L:{n}" for k, n in enumerate(names) if li[t + 7, k]]
        for t in range(3000 - 7)
    ]
    te = TransactionEncoder()
    df = pd.DataFrame(te.fit(tx).transform(tx), columns=te.columns_)
    freq = apriori(df, min_support=0.02, use_colnames=True, max_len=4)
    ref = association_rules(freq, num_itemsets=len(df), metric="confidence", min_threshold=0.2)
    ref = ref[
        ref.antecedents.map(lambda a: all(x.startswith("S:") for x in a))
        & ref.consequents.map(lambda c: all(x.startswith("L:") for x in c))
    ]
    assert len(ours) == len(ref) > 5
    want = {
        (tuple(sorted(a)), tuple(sorted(c))): (s, cf, lf)
        for a, c, s, cf, lf in zip(ref.antecedents, ref.consequents, ref.support, ref.confidence, ref.lift)
    }
    for r in ours:
        np.testing.assert_allclose((r.support, r.confidence, r.lift), want[r.key], rtol=1e-12)


def test_offset_finds_the_planted_response_and_only_at_its_offset() -> None:
    rng = np.random.default_rng(1)
    t, s = 6000, 10
    names = ["nod", "shake", "activity"]
    sp = np.zeros((t, 3), dtype=bool)
    li = np.zeros((t, 3), dtype=bool)
    sp[:, 0] = _events(rng, t - s, 150, 5).tolist() + [False] * s
    sp[:, 1] = rng.random(t) < 0.1
    li[s:, 0] = sp[:-s, 0]  # listener nods exactly s frames after
    li[:, 2] = rng.random(t) < 0.2
    rules = {r.key: r for r in mine_rules(sp, li, names, offset=s, min_support=0.005, min_confidence=0.5)}
    nod = rules[(("S:nod",), ("L:nod",))]
    assert nod.confidence > 0.99 and nod.lift > 5
    for wrong in (0, 5, 20, 40):
        found = {r.key for r in mine_rules(sp, li, names, offset=wrong, min_support=0.005, min_confidence=0.5)}
        assert (("S:nod",), ("L:nod",)) not in found, wrong


def test_temporal_bagging_catches_a_jittered_response() -> None:
    rng = np.random.default_rng(2)
    t, s = 8000, 10
    sp = np.zeros((t, 1), dtype=bool)
    li = np.zeros((t, 1), dtype=bool)
    starts = rng.choice(np.arange(50, t - 50, 20), 300, replace=False)
    sp[starts, 0] = True
    li[starts + s + rng.integers(-2, 3, len(starts)), 0] = True  # response at s +- 2 frames
    exact = mine_rules(sp, li, ["nod"], offset=s, min_support=0.001, min_confidence=0.0)
    bagged = mine_rules(sp, li, ["nod"], offset=s, bag=2, min_support=0.001, min_confidence=0.0)
    assert 0.1 < exact[0].confidence < 0.35  # about 1 in 5 hit exactly t + s
    assert bagged[0].confidence == 1.0
    tx = build_transactions(sp, li, ["nod"], offset=s, bag=2)
    assert len(tx) == t - s - 2 and list(tx.columns) == ["S:nod", "L:nod"]


def test_planted_confidences_recovered() -> None:
    planted = [(0, 3, 0.9), (1, 0, 0.6), (4, 4, 0.35), (7, 9, 0.75)]
    sp, li, names = planted_label_streams(20000, 12, planted, offset=10, seed=3)
    rules = {r.key: r for r in mine_rules(sp, li, names, offset=10, min_support=0.002, min_confidence=0.2)}
    for x, y, c in planted:
        r = rules[((f"S:{names[x]}",), (f"L:{names[y]}",))]
        assert abs(r.confidence - c) < 0.05, (names[x], names[y], r.confidence, c)
    # no unplanted single-item rule is strong
    others = [
        r
        for k, r in rules.items()
        if len(k[0]) == 1 and (int(k[0][0][5:]), int(k[1][0][5:])) not in {(x, y) for x, y, _ in planted}
    ]
    assert all(r.confidence < 0.2 + 0.05 for r in others)


def test_compare_scenarios_gives_confidence_ratios() -> None:
    a_sp, a_li, names = planted_label_streams(15000, 6, [(0, 0, 0.9), (1, 1, 0.4)], seed=4)
    b_sp, b_li, _ = planted_label_streams(15000, 6, [(0, 0, 0.3), (1, 1, 0.4)], seed=5)
    ra = mine_rules(a_sp, a_li, names, min_support=0.002, min_confidence=0.2)
    rb = mine_rules(b_sp, b_li, names, min_support=0.002, min_confidence=0.2)
    comp = {(c.antecedent, c.consequent): c for c in compare_scenarios(ra, rb)}
    nod = comp[(("S:sig00",), ("L:sig00",))]
    assert abs(nod.ratio - 3.0) < 0.4 and nod.ratio == nod.confidence_a / nod.confidence_b
    assert abs(comp[(("S:sig01",), ("L:sig01",))].ratio - 1.0) < 0.2


def test_sessions_are_bagged_separately() -> None:
    sp = np.zeros((50, 1), dtype=bool)
    li = np.zeros((50, 1), dtype=bool)
    sp[45, 0] = True  # the response would fall in the next file
    li2 = li.copy()
    li2[5, 0] = True
    rules = mine_rules_sessions(
        [(sp, li), (sp & False, li2)], ["nod"], offset=10, min_support=0.001, min_confidence=0.0
    )
    assert rules == []  # no speaker nod is followed by a listener nod in its own file
    glued = mine_rules(np.r_[sp, sp & False], np.r_[li, li2], ["nod"], offset=10, min_support=0.001, min_confidence=0.0)
    assert glued and glued[0].confidence == 1.0  # what gluing the files together would claim


def test_rules_file_round_trip(tmp_path: Path) -> None:
    r1 = Rule(("S:nod",), ("L:nod",), 0.05, 0.9, 4.2, 0.055, 0.2)
    r2 = Rule(("S:activity", "S:nod"), ("L:gaze_at_other",), 0.01, 0.5, 1.1, 0.02, 0.45)
    comp = compare_scenarios([r1], [Rule(("S:nod",), ("L:nod",), 0.02, 0.3, 2.0, 0.06, 0.1)])
    params = {"offset": 10, "bag": 0, "min_support": 0.01, "fps": 25.0}
    path = tmp_path / "rules.json"
    write_rules(path, {"interested": [r1, r2], "not_interested": []}, params, comp)
    back = read_rules(path)
    assert back.version == 1 and back.params == params
    assert back.scenarios == {"interested": [r1, r2], "not_interested": []}
    assert back.comparisons == comp and abs(comp[0].ratio - 3.0) < 1e-12
    doc = json.loads(path.read_text())
    doc["format"] = "something-else"
    path.write_text(json.dumps(doc))
    with pytest.raises(ValueError, match="not a rules file"):
        read_rules(path)
    doc["format"], doc["version"] = "counterpart.labeller.rules", 99
    path.write_text(json.dumps(doc))
    with pytest.raises(ValueError, match="version 99"):
        read_rules(path)


def test_label_readers(tmp_path: Path) -> None:
    rng = np.random.default_rng(6)
    names = ("nod", "shake", "talking")
    a = rng.choice([1, 0, UNKNOWN], (40, 3)).astype(np.int8)
    b = rng.choice([1, 0], (40, 3)).astype(np.int8)
    streams = LabelStreams(names, {"a": a, "b": b}, 25.0)
    csv_path = tmp_path / "labels.csv"
    write_labels_csv(csv_path, streams)
    back = read_labels(csv_path)
    assert back.names == names and back.fps == 25.0
    np.testing.assert_array_equal(back.people["a"], a)
    np.testing.assert_array_equal(back.people["b"], b)
    # rows in any order are sorted by the frame column; empty cells are UNKNOWN
    lines = csv_path.read_text().splitlines()
    body = lines[2:]
    shuffled = [lines[0], lines[1]] + [body[i] for i in rng.permutation(len(body))]
    shuffled[2] = shuffled[2].rsplit(",", 1)[0] + ","
    csv_path.write_text("\n".join(shuffled) + "\n")
    back = read_labels_csv(csv_path)
    row = shuffled[2].split(",")
    assert back.people[row[0]][int(row[1]), 2] == UNKNOWN

    npz = tmp_path / "traj.npz"
    sig_b = b.astype(np.float32)
    sig_b[3, 1] = np.nan  # float label files may mark UNKNOWN as nan
    np.savez(
        npz,
        signals_a=a.astype(np.float32),
        signals_b=sig_b,
        signal_names=np.array(names),
        fps=25.0,
        a=np.zeros((40, 14, 3), np.float32),
    )
    z = read_labels_npz(npz)
    assert z.names == names and z.fps == 25.0 and z.people["b"][3, 1] == UNKNOWN
    np.testing.assert_array_equal(z.people["a"], a)
    np.savez(npz, signals_a=a * 2, signals_b=b, signal_names=np.array(names), fps=25.0)
    with pytest.raises(ValueError, match="1, 0 or -1"):
        read_labels(npz)
    with pytest.raises(ValueError, match="unknown label file type"):
        read_labels(tmp_path / "x.txt")


def test_cli_mine_writes_both_scenarios(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    files = {}
    for name, conf, seed in (("i1", 0.9, 1), ("i2", 0.9, 2), ("n1", 0.3, 3)):
        sp, li, names = planted_label_streams(6000, 5, [(0, 0, conf)], seed=seed)
        files[name] = tmp_path / f"{name}.npz"
        np.savez(
            files[name],
            signals_a=sp.astype(np.uint8),
            signals_b=li.astype(np.uint8),
            signal_names=np.array(names),
            fps=25.0,
        )
    parser = argparse.ArgumentParser()
    cli_mine.add_arguments(parser)
    out = tmp_path / "rules.json"
    args = parser.parse_args(
        [
            "--interested",
            str(files["i1"]),
            str(files["i2"]),
            "--not-interested",
            str(files["n1"]),
            "--offset",
            "10",
            "--min-support",
            "0.002",
            "--out",
            str(out),
        ]
    )
    assert cli_mine.main(args) == 0
    assert "rules found in both" in capsys.readouterr().err
    rf = read_rules(out)
    assert rf.params["offset"] == 10 and rf.params["fps"] == 25.0
    assert [i["transactions"] for i in rf.params["inputs"]["interested"]] == [5990, 5990]
    comp = {(c.antecedent, c.consequent): c for c in rf.comparisons}
    assert abs(comp[(("S:sig00",), ("L:sig00",))].ratio - 3.0) < 0.5
    bad = parser.parse_args(["--interested", str(tmp_path / "missing.npz"), "--out", str(out)])
    assert cli_mine.main(bad) == 2
    assert "missing.npz" in capsys.readouterr().err
