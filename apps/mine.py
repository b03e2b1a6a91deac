r"""``counterpart mine``: mine speaker -> listener rules from label files of two scenarios.

    counterpart mine --interested A.npz [B.npz ...] [--not-interested C.npz ...] \\
                     --offset 10 [--bag 0] [--turns talking] --out rules.json

Each input is a label file read by :func:`counterpart.nodes.labeller.mining.read_labels` (``.npz`` with
``signals_a``/``signals_b``/``signal_names``/``fps``, or the documented ``.csv``); ``--speaker``
and ``--listener`` name the two people in it (default ``a`` speaks, ``b`` listens). In a
conversation where the two take turns (the simulator's ``conversation`` trajectory files),
``--turns talking`` makes the speaker of each frame whichever of the two has ``talking`` = 1 there
and the other the listener, both roles pooled (:func:`counterpart.nodes.labeller.mining.turn_transactions`).
The output is a rules file (:func:`counterpart.nodes.labeller.mining.write_rules`) with the rules of each scenario, the
interested / not-interested confidence ratios of rules found in both, and the parameters used.
Progress goes to stderr. The project's CLI dispatcher calls :func:`add_arguments` and :func:`main`.
"""

from __future__ import annotations

import argparse
import sys
import time

import mlxtend
import pandas as pd

from counterpart.nodes.labeller.mining import (
    build_transactions,
    compare_scenarios,
    mine_transactions,
    read_labels,
    turn_transactions,
    write_rules,
)

#: the one-line help of this command in `counterpart --help`
HELP = "mine listener-response association rules from label streams"

SCENARIOS = ("interested", "not_interested")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``mine`` options to ``parser``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's parser.
    """
    parser.add_argument(
        "--interested",
        nargs="+",
        required=True,
        metavar="FILE",
        help="label files (.npz/.csv) of conversations with an interested listener",
    )
    parser.add_argument(
        "--not-interested",
        nargs="*",
        default=[],
        metavar="FILE",
        help="label files of conversations with a not-interested listener",
    )
    parser.add_argument(
        "--offset", type=int, default=10, help="listener response offset s in frames (default 10 = 0.4 s at 25 fps)"
    )
    parser.add_argument(
        "--bag", type=int, default=0, help="half-width of the temporal bag around t+s, frames (default 0)"
    )
    parser.add_argument("--min-support", type=float, default=0.01, help="default 0.01")
    parser.add_argument("--min-confidence", type=float, default=0.1, help="default 0.1")
    parser.add_argument(
        "--max-len", type=int, default=4, help="largest itemset (antecedent + consequent) size, default 4; 0 = no limit"
    )
    parser.add_argument("--algorithm", choices=("apriori", "fpgrowth"), default="apriori")
    parser.add_argument("--speaker", default="a", help="person id of the speaker (default a)")
    parser.add_argument("--listener", default="b", help="person id of the listener (default b)")
    parser.add_argument(
        "--turns",
        metavar="SIGNAL",
        default=None,
        help="the two people take turns: on each frame the speaker is the one with "
        "SIGNAL (e.g. talking) = 1, the other listens; both roles pooled",
    )
    parser.add_argument("--out", required=True, metavar="RULES.json", help="rules file to write")


def _log(msg: str) -> None:
    print(f"[mine] {msg}", file=sys.stderr, flush=True)


def main(args: argparse.Namespace) -> int:
    """Run the mining.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed ``mine`` options.

    Returns
    -------
    int
        The process exit code (0 ok, 2 bad input).
    """
    t0 = time.perf_counter()
    names: tuple[str, ...] | None = None
    fps_seen: set[float] = set()
    inputs: dict[str, list[dict[str, object]]] = {}
    rules = {}
    try:
        for scenario, paths in zip(SCENARIOS, (args.interested, args.not_interested)):
            if not paths:
                continue
            frames = []
            inputs[scenario] = []
            for path in paths:
                st = read_labels(path)
                if names is None:
                    names = st.names
                elif st.names != names:
                    raise ValueError(
                        f"{path}: signal names {list(st.names)} differ from those of "
                        f"the first file {list(names)}; all inputs must share them"
                    )
                for pid in (args.speaker, args.listener):
                    if pid not in st.people:
                        raise ValueError(
                            f"{path}: no person {pid!r} (has {sorted(st.people)}); use --speaker/--listener"
                        )
                if st.fps is not None:
                    fps_seen.add(st.fps)
                sp, li = st.people[args.speaker], st.people[args.listener]
                if args.turns:
                    tx = turn_transactions(sp, li, names, args.turns, args.offset, args.bag)
                else:
                    tx = build_transactions(sp, li, names, args.offset, args.bag)
                _log(
                    f"{scenario}: {path}: {sp.shape[0]} frames, {len(names)} signals, "
                    f"fps {st.fps}, {len(tx)} transactions"
                )
                frames.append(tx)
                inputs[scenario].append({"path": str(path), "frames": int(sp.shape[0]), "transactions": len(tx)})
            tx_all = pd.concat(frames, ignore_index=True)
            t1 = time.perf_counter()
            rules[scenario] = mine_transactions(
                tx_all, args.min_support, args.min_confidence, args.max_len or None, args.algorithm
            )
            _log(
                f"{scenario}: {len(rules[scenario])} speaker->listener rules from "
                f"{len(tx_all)} transactions in {time.perf_counter() - t1:.2f} s"
            )
    except (OSError, ValueError, KeyError) as e:
        _log(f"error: {e}")
        return 2
    if len(fps_seen) > 1:
        _log(
            f"warning: inputs have different fps {sorted(fps_seen)}; --offset {args.offset} "
            "frames is a different time in each"
        )
    comparisons = []
    if "interested" in rules and "not_interested" in rules:
        comparisons = compare_scenarios(rules["interested"], rules["not_interested"])
        _log(f"{len(comparisons)} rules found in both scenarios")
    params = {
        "offset": args.offset,
        "bag": args.bag,
        "min_support": args.min_support,
        "min_confidence": args.min_confidence,
        "max_len": args.max_len or None,
        "algorithm": args.algorithm,
        "speaker": args.speaker,
        "listener": args.listener,
        "turns": args.turns,
        "fps": sorted(fps_seen)[0] if len(fps_seen) == 1 else None,
        "signal_names": list(names or ()),
        "inputs": inputs,
        "mlxtend": mlxtend.__version__,
    }
    try:
        write_rules(args.out, rules, params, comparisons)
    except OSError as e:
        _log(f"error: cannot write {args.out}: {e}")
        return 2
    _log(f"wrote {args.out} in {time.perf_counter() - t0:.2f} s")
    return 0
