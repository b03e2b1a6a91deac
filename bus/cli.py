"""The ``counterpart`` command: a thin dispatcher over subcommand modules.

Each subcommand module exposes ``add_arguments(parser)`` and ``main(args) -> int``; it is imported
only when its command runs, so ``counterpart topic list`` does not pay for OpenCV or scikit-learn.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

#: command -> (module, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "demo": ("counterpart.bus.cli_demo", "the whole graph end to end on the built-in scene, your video or a camera"),
    "launch": ("counterpart.bus.cli_launch", "run a graph from a launch file"),
    "run": ("counterpart.bus.cli_run", "run one node alone"),
    "node": ("counterpart.bus.cli_introspect", "list the nodes of a running launch"),
    "topic": ("counterpart.bus.cli_introspect", "list, echo or measure the rate of topics of a running launch"),
    "mine": ("counterpart.nodes.labeller.cli_mine", "mine listener-response association rules from label streams"),
    "learn": ("counterpart.bus.cli_learn", "train a model file (tracker-prior, responder, avatar)"),
    "respond": ("counterpart.nodes.responder.cli_respond", "offline: generate the partner for one person's trajectory"),
    "silhouettes": ("counterpart.nodes.silhouette.cli_extract", "offline: the people's silhouettes of a video file"),
    "calibrate": (
        "counterpart.nodes.calibration.cli_calibrate",
        "offline: the camera of a video file, estimated from the people in it",
    ),
    "track": ("counterpart.nodes.tracker.cli_track", "offline: the 3D body of the people of a video file"),
    "sim": ("counterpart.sim.cli", "render a simulated two-person scene with ground truth"),
    "bag": ("counterpart.bus.cli_bag", "record, play, inspect and export bags"),
}


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser; only ``command``'s module is imported (all of them with None, for --help)."""
    ap = argparse.ArgumentParser(
        prog="counterpart", description="Counterpart: virtual interaction partners on a node graph."
    )
    sub = ap.add_subparsers(dest="command", metavar="COMMAND")
    for name, (module, help_) in COMMANDS.items():
        p = sub.add_parser(name, help=help_, description=help_)
        if command is None or name == command:
            mod = importlib.import_module(module)
            add = getattr(mod, f"add_arguments_{name}", None) or mod.add_arguments
            add(p)
        p.set_defaults(_module=module, _command=name)
    return ap


def main(argv: list[str] | None = None) -> None:
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
    command = argv[0] if argv and argv[0] in COMMANDS else ""
    ap = build_parser(command)
    if not command and argv and argv[0] not in ("-h", "--help"):
        ap.error(f"unknown command {argv[0]!r}; commands: {', '.join(COMMANDS)}")
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
