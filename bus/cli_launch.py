"""``counterpart launch FILE [--set node.param=value ...] [--replace node=module] [--check]``."""

from __future__ import annotations

import argparse
import logging
import sys

from .endpoints import RunDirError, base_dir
from .launchfile import Graph, LaunchError, check, load
from .params import ParamError, parse_assignments
from .runner import setup_logging


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Add the options of ``counterpart launch``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser.
    """
    p.add_argument("file", help="launch file: a path, or a name in the launch/ folder (demo.yaml)")
    p.add_argument("--set", action="append", metavar="NODE.PARAM=VALUE", help="override a node parameter")
    p.add_argument("--replace", action="append", metavar="NODE=MODULE", help="run another module for a node")
    p.add_argument("--check", action="store_true", help="check the graph and exit without starting it")


def load_checked(file: str, sets: list[str] | None, replace: list[str] | None) -> Graph:
    """The checked graph of a launch file with ``--set`` and ``--replace`` applied; also
    checks that the folder for run directories is safe to use.

    Parameters
    ----------
    file : str
        The launch file: a path, or a name in the launch/ folder.
    sets : list of str or None
        ``NODE.PARAM=VALUE`` overrides of node parameters.
    replace : list of str or None
        ``NODE=MODULE`` replacements of a node's module.

    Returns
    -------
    Graph
        The checked graph.

    Raises
    ------
    LaunchError
        Naming the problem, for a bad graph or a run-directory folder that cannot be used.
    ParamError
        For a malformed ``--set`` or ``--replace`` assignment.
    """
    graph = check(load(file, parse_assignments(sets, "--set"), parse_assignments(replace, "--replace")))
    try:
        base_dir()
    except RunDirError as exc:
        raise LaunchError(f"{graph.file}: cannot run it here: {exc}") from None
    return graph


def main(args: argparse.Namespace) -> int:
    """Run ``counterpart launch``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options of :func:`add_arguments`.

    Returns
    -------
    int
        Exit code: 2 for a bad launch file or parameter, 0 after ``--check``, else the launcher's.
    """
    from .supervisor import Launcher, prune_run_dirs

    setup_logging("launch")
    try:
        graph = load_checked(args.file, args.set, args.replace)
    except (LaunchError, ParamError) as exc:
        print(f"counterpart launch: {exc}", file=sys.stderr)
        return 2
    if args.check:
        print(f"{graph.file}: {len(graph.nodes)} nodes, {len(graph.topics)} topics: OK")
        return 0
    prune_run_dirs()
    launcher = Launcher(graph)
    logging.getLogger("launch").info("run directory %s", launcher.run_dir)
    code = launcher.run()
    launcher.cleanup()
    return code
