"""``counterpart learn tracker-prior --data SOURCE... --out FILE``: train the tracker's motion prior.

SOURCE: ``sim:NAME[?seed=S]`` (a simulator scenario), a ``.bvh`` file, a two-person trajectory or
simulator ``truth.npz``, or a folder of those (see ``counterpart.nodes.tracker.prior.load_sequences``).
Progress goes to stderr; the exit code is 0 on success, 2 on bad input.
"""

from __future__ import annotations

import argparse
import sys

from .prior import DEFAULT_TRAINING, default_prior_path, train_prior

#: the one-line help of this command in `counterpart --help`
HELP = "the tracker's motion prior (PCA + HMM of poses)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--data",
        nargs="+",
        metavar="SOURCE",
        default=list(DEFAULT_TRAINING),
        help="training sources: sim:NAME[?seed=S], .bvh, .npz, folders (default: simulator scenarios)",
    )
    p.add_argument("--out", default=None, help=f"output .npz (default {default_prior_path()})")
    p.add_argument("--states", type=int, default=30, help="HMM states (Zheng: 20-40)")
    p.add_argument("--energy", type=float, default=0.95, help="PCA variance fraction kept")
    p.add_argument("--fps", type=float, default=25.0, help="frame rate the tracker runs at")
    p.add_argument("--seed", type=int, default=0, help="seed of the HMM fit")


def main(args: argparse.Namespace) -> int:
    out = args.out or str(default_prior_path())
    try:
        prior = train_prior(
            args.data, n_states=args.states, energy=args.energy, fps=args.fps, seed=args.seed, progress=True
        )
    except (ValueError, FileNotFoundError) as exc:
        print(f"counterpart learn tracker-prior: {exc}", file=sys.stderr)
        return 2
    path = prior.save(out)
    print(
        f"tracker prior: {prior.n_states} states over {prior.n_components} PCA dimensions from "
        f"{prior.n_frames} frames -> {path}",
        file=sys.stderr,
    )
    return 0


if __name__ == "__main__":
    ap = argparse.ArgumentParser(prog="counterpart learn tracker-prior", description=__doc__)
    add_arguments(ap)
    sys.exit(main(ap.parse_args()))
