"""``counterpart learn TARGET ...``: train a model file.

The targets are declared by the packages that train them (entry points ``counterpart.learn``).
"""

from __future__ import annotations

import argparse
import importlib

from counterpart.bus import plugins

#: the one-line help of this command in `counterpart --help`
HELP = "train a model file (tracker-prior, responder, avatar)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    sub = p.add_subparsers(dest="target", metavar="TARGET", required=True)
    for name, ep in plugins.declared(plugins.LEARN_TARGETS).items():
        try:
            mod = importlib.import_module(ep.value)
        except ModuleNotFoundError as exc:
            sp = sub.add_parser(name, help=f"(not available: {exc})")
            sp.set_defaults(_missing=str(exc), _target_module=ep.value)
            continue
        help_ = getattr(mod, "HELP", None)
        sp = sub.add_parser(name, help=help_, description=help_)
        mod.add_arguments(sp)
        sp.set_defaults(_target_module=ep.value)


def main(args: argparse.Namespace) -> int:
    if getattr(args, "_missing", None):
        print(f"counterpart learn {args.target}: not available in this installation ({args._missing})")
        return 2
    return importlib.import_module(args._target_module).main(args)
