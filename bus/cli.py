"""The ``counterpart`` command: a thin dispatcher over subcommand modules.

Each subcommand module exposes ``add_arguments(parser)`` and ``main(args) -> int``; it is imported
only when its command runs, so ``counterpart topic list`` does not pay for OpenCV or scikit-learn.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

from . import plugins

#: the runtime's own commands: command -> (module, one-line help)
RUNTIME_COMMANDS: dict[str, tuple[str, str]] = {
    "launch": ("counterpart.bus.cli_launch", "run a graph from a launch file"),
    "run": ("counterpart.bus.cli_run", "run one node alone"),
    "node": ("counterpart.bus.cli_introspect", "list the nodes of a running launch"),
    "topic": ("counterpart.bus.cli_introspect", "list, echo or measure the rate of topics of a running launch"),
    "bag": ("counterpart.bus.cli_bag", "record, play, inspect and export bags"),
}


def commands() -> dict[str, str]:
    """Every command's module: the runtime's, then those the installed packages declare
    (entry points ``counterpart.commands``: the applications demo, track, learn, ...).

    Returns
    -------
    dict of str to str
        Command name -> the dotted name of the module that runs it.
    """
    found = {name: module for name, (module, _) in RUNTIME_COMMANDS.items()}
    for name, ep in plugins.declared(plugins.COMMANDS).items():
        found.setdefault(name, ep.value)
    return found


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser; only ``command``'s module is imported (all of them with None, for --help).

    Parameters
    ----------
    command : str or None
        The command whose module adds its arguments; None imports every command's module.

    Returns
    -------
    argparse.ArgumentParser
        The ``counterpart`` parser with one subparser per command.
    """
    ap = argparse.ArgumentParser(
        prog="counterpart", description="Counterpart: virtual interaction partners on a node graph."
    )
    sub = ap.add_subparsers(dest="command", metavar="COMMAND")
    for name, module in commands().items():
        mod = importlib.import_module(module) if command is None or name == command else None
        help_ = RUNTIME_COMMANDS[name][1] if name in RUNTIME_COMMANDS else getattr(mod, "HELP", None)
        p = sub.add_parser(name, help=help_, description=help_)
        if mod is not None:
            add = getattr(mod, f"add_arguments_{name}", None) or mod.add_arguments
            add(p)
        p.set_defaults(_module=module, _command=name)
    return ap


def main(argv: list[str] | None = None) -> None:
    """Run the ``counterpart`` command; exits with the subcommand's status.

    Parameters
    ----------
    argv : list of str or None
        The command line without the program name; None reads ``sys.argv[1:]``.
    """
    argv = sys.argv[1:] if argv is None else argv
    # like `python -m`: the user's own node modules in the working folder are importable
    if os.getcwd() not in sys.path:
        sys.path.insert(0, os.getcwd())
    if argv and argv[0] == "run":  # node parameters are parsed by the node runner itself
        from .runner import run_standalone

        if len(argv) < 2 or argv[1].startswith("-"):
            asked = len(argv) > 1 and argv[1] in ("-h", "--help")
            print(
                "usage: counterpart run MODULE [--name NAME] [--param K=V ...] [--remap PORT=TOPIC ...] "
                "[--policy PORT=latest]\n\nRun one node alone; MODULE is a module holding one Node, or "
                "module:Class.",
                file=sys.stdout if asked else sys.stderr,
            )
            sys.exit(0 if asked else 2)
        sys.exit(run_standalone(argv[1], argv[2:]))
    known = commands()
    command = argv[0] if argv and argv[0] in known else None  # None: the overview, every command's help
    ap = build_parser(command)
    if not command and argv and argv[0] not in ("-h", "--help"):
        ap.error(f"unknown command {argv[0]!r}; commands: {', '.join(known)}")
    args = ap.parse_args(argv)
    if not getattr(args, "command", None):
        ap.print_help()
        sys.exit(2)
    mod = importlib.import_module(args._module)
    run = getattr(mod, f"main_{args._command}", None) or mod.main
    try:
        sys.exit(run(args))
    except KeyboardInterrupt:
        sys.exit(130)


if __name__ == "__main__":
    main()
