"""``counterpart learn responder --model M --data SPEC... --out FILE``: train a responder model.

Data specs: trajectory files (``.npz``), BVH pairs ``a.bvh:b.bvh``, ``sim`` or ``sim:handshake,push``
(see :mod:`counterpart.nodes.responder.data`); for ``--model listener`` also a labeller rules file (``.json``).
Progress goes to stderr; exit 0 on success, 2 on bad input.
"""

from __future__ import annotations

import argparse
import sys
import time

from .models import MODEL_NAMES, save_model

#: the one-line help of this command in `counterpart --help`
HELP = "an interaction model of the responder"


def add_arguments(p: argparse.ArgumentParser) -> None:
    # the video-texture avatar learns from a video of a person: 'counterpart learn avatar'
    p.add_argument(
        "--model",
        required=True,
        choices=[m for m in MODEL_NAMES if m != "video-texture"],
        help="which interaction model (the video-texture avatar: 'counterpart learn avatar')",
    )
    p.add_argument(
        "--data",
        nargs="+",
        default=["sim"],
        metavar="SPEC",
        help="PATH.npz, A.bvh:B.bvh, sim, sim:NAME,NAME (listener: also RULES.json); default sim",
    )
    p.add_argument("--seeds", type=int, default=6, help="simulator seeds per scenario (default 6)")
    p.add_argument("--out", required=True, help="model file to write (.npz)")


def main(args: argparse.Namespace) -> int:
    def say(msg: str) -> None:
        print(f"[learn responder] {msg}", file=sys.stderr, flush=True)

    t0 = time.perf_counter()
    try:
        from .data import load_data, summary
        from .training import default_training_data, train

        if args.model == "listener" and any(d.endswith(".json") for d in args.data):
            from .listener import ListenerModel

            rules = [d for d in args.data if d.endswith(".json")]
            if len(rules) > 1:
                raise ValueError("give one rules file")
            say(f"reading rules {rules[0]}")
            model = ListenerModel.from_rules_file(rules[0])
            info = {"rules_file": rules[0]}
        else:
            if args.data == ["sim"] and args.seeds == 6:
                data = default_training_data(args.model, say)
            else:
                data = load_data(args.data, seeds=range(args.seeds), progress=say)
            model = train(args.model, data, say)
            info = dict(summary(data), source=list(args.data))
        info["seconds"] = round(time.perf_counter() - t0, 2)
        path = save_model(args.out, model, info)
    except (ValueError, FileNotFoundError) as e:
        print(f"counterpart learn responder: {e}", file=sys.stderr)
        return 2
    say(f"wrote {path} in {time.perf_counter() - t0:.1f} s")
    return 0
