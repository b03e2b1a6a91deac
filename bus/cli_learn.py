"""``counterpart learn TARGET ...``: train a model file; each target's trainer lives with its node."""

from __future__ import annotations

import argparse
import importlib

#: target -> (module with add_arguments/main, help)
TARGETS: dict[str, tuple[str, str]] = {
    "tracker-prior": ("counterpart.nodes.tracker.cli_learn", "the tracker's motion prior (PCA + HMM of poses)"),
    "responder": ("counterpart.nodes.responder.cli_learn", "an interaction model of the responder"),
    "avatar": ("counterpart.nodes.responder.cli_avatar", "a video-texture avatar from a recording of a person"),
}


def add_arguments(p: argparse.ArgumentParser) -> None:
    sub = p.add_subparsers(dest="target", metavar="TARGET", required=True)
    for name, (module, help_) in TARGETS.items():
        sp = sub.add_parser(name, help=help_, description=help_)
        try:
            importlib.import_module(module).add_arguments(sp)
        except ModuleNotFoundError as exc:
            sp.set_defaults(_missing=str(exc))
        sp.set_defaults(_target_module=module)


def main(args: argparse.Namespace) -> int:
    if getattr(args, "_missing", None):
        print(f"counterpart learn {args.target}: not available in this installation ({args._missing})")
        return 2
    return importlib.import_module(args._target_module).main(args)
