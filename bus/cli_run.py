"""``counterpart run MODULE``: handled by :func:`counterpart.bus.runner.run_standalone` (see counterpart.bus.cli.main)."""

from __future__ import annotations

import argparse


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("module", help="module (or module:Class) holding the node, e.g. counterpart.nodes.camera")
    p.add_argument("rest", nargs=argparse.REMAINDER, help="--param K=V, --remap PORT=TOPIC, --policy PORT=latest")


def main(args: argparse.Namespace) -> int:
    from .runner import run_standalone

    return run_standalone(args.module, args.rest)
