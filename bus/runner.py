"""Process entry points: find a node class by module name and run it (under the launcher or alone)."""

from __future__ import annotations

import argparse
import atexit
import importlib
import importlib.util
import inspect
import logging
import os
import sys
import traceback
from pathlib import Path
from typing import Any

from .logs import RepeatFilter
from .node import Node, load_spec, standalone_spec
from .params import ParamError, parse_assignments


class NodeLookupError(ImportError):
    """The ``run:`` module of a node cannot be imported or holds no node class."""


# The top-level names the project's packages had before they moved under ``counterpart``.
_OLD_TOP_LEVEL = ("messages", "bus", "body", "sim", "nodes", "launch", "apps")


def moved_module(module_name: str) -> str | None:
    """The ``counterpart.`` path of a module named by its old top-level path, else None.

    ``nodes.tracker`` is ``counterpart.nodes.tracker`` now; importing the old name from a source
    checkout would load a second copy of the project whose message classes are not the bus's.

    Parameters
    ----------
    module_name : str
        A module path, optionally ``module:Class``.

    Returns
    -------
    str or None
        ``counterpart.`` + ``module_name`` when its first part is an old top-level name and the new
        module exists, else None.
    """
    mod_name = module_name.partition(":")[0]
    if mod_name.split(".")[0] not in _OLD_TOP_LEVEL:
        return None
    new = f"counterpart.{module_name}"
    try:
        found = importlib.util.find_spec(f"counterpart.{mod_name}") is not None
    except ModuleNotFoundError:
        found = False
    return new if found else None


def find_node_class(module_name: str) -> type[Node]:
    """The Node subclass of ``module_name`` (or of ``module_name.node``).

    A module names its node with ``NODE = TheClass``, or defines exactly one Node subclass.
    A ``module:Class`` form picks a class explicitly.

    Parameters
    ----------
    module_name : str
        The ``run:`` module, ``module`` or ``module:Class``.

    Returns
    -------
    type of Node
        The node class.

    Raises
    ------
    NodeLookupError
        The module has an old top-level path, fails to import, does not exist, holds no (or not the
        named) Node class, or defines several without ``NODE``.
    """
    new = moved_module(module_name)
    if new is not None:
        raise NodeLookupError(
            f"{module_name!r} is the old module path: the project's modules are under 'counterpart' now; write {new!r}"
        )
    mod_name, _, cls_name = module_name.partition(":")
    candidates = [mod_name, f"{mod_name}.node"]
    errors = []
    for name in candidates:
        try:
            mod = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name and (name == exc.name or name.startswith(exc.name + ".")):
                errors.append(f"no module {name!r}")
                continue
            raise NodeLookupError(f"module {name!r} failed to import: {exc}") from exc
        if cls_name:
            cls = getattr(mod, cls_name, None)
            if not (inspect.isclass(cls) and issubclass(cls, Node)):
                raise NodeLookupError(f"{name!r} has no Node class {cls_name!r}")
            return cls
        explicit = getattr(mod, "NODE", None)
        if inspect.isclass(explicit) and issubclass(explicit, Node):
            return explicit
        found = [
            c
            for c in vars(mod).values()
            if inspect.isclass(c) and issubclass(c, Node) and c is not Node and c.__module__ == mod.__name__
        ]
        if len(found) == 1:
            return found[0]
        if len(found) > 1:
            raise NodeLookupError(
                f"module {name!r} defines several nodes ({', '.join(c.__name__ for c in found)}); "
                f"set NODE = <class> in it or write {name}:ClassName"
            )
        errors.append(f"module {name!r} defines no Node subclass")
    raise NodeLookupError(f"cannot find a node in {module_name!r}: {'; '.join(errors)}")


def setup_logging(name: str) -> None:
    """Log lines on stderr, prefixed with the time and ``name``; a line that repeats is rate-limited
    (:class:`counterpart.bus.logs.RepeatFilter`: a few per kind and 10 s, then a count).

    The level comes from the ``COUNTERPART_LOG`` environment variable (default ``INFO``).

    Parameters
    ----------
    name : str
        The node's name, in every line's prefix.
    """
    level = os.environ.get("COUNTERPART_LOG", "INFO").upper()
    logging.basicConfig(
        level=getattr(logging, level, logging.INFO),
        format=f"[%(asctime)s.%(msecs)03d {name}] %(levelname)s %(message)s",
        datefmt="%H:%M:%S",
        stream=sys.stderr,
    )
    for handler in logging.getLogger().handlers:
        if not any(isinstance(f, RepeatFilter) for f in handler.filters):
            repeats = RepeatFilter()
            handler.addFilter(repeats)
            atexit.register(repeats.flush_held)


def failure_file(stats_file: str | Path) -> Path:
    """The file beside a node's statistics (``NODE.json``) where it leaves why it failed
    (``NODE.error``: its last error line), for the launcher and the summary to say.

    Parameters
    ----------
    stats_file : str or Path
        The node's ``stats_file``.

    Returns
    -------
    Path
        ``NODE.error`` in the same folder.
    """
    return Path(stats_file).with_suffix(".error")


class _LastError(logging.Handler):
    """Keeps the last error line a node logged (a traceback's last line: the exception)."""

    def __init__(self) -> None:
        super().__init__(logging.ERROR)
        self.message = ""

    def emit(self, record: logging.LogRecord) -> None:
        lines = [line.strip() for line in self.format(record).strip().splitlines() if line.strip()]
        if lines:
            self.message = lines[-1]


def _leave_failure(spec: dict[str, Any], code: int, last: _LastError) -> None:
    """Write why the node failed (its last error line) beside its statistics, where the launcher
    names a statistics file; nothing for a clean end, an interrupt or a failure it logged no error for.
    """
    if code in (0, 130) or not last.message or not spec.get("stats_file"):
        return
    try:
        failure_file(spec["stats_file"]).write_text(last.message, encoding="utf-8")
    except OSError:  # the run folder is gone: the log line above said it all the same
        pass


def run_spec(spec: dict[str, Any]) -> int:
    """Run a node from a launcher spec.

    Parameters
    ----------
    spec : dict of str to object
        The launcher's spec of the node (``name``, ``module``, parameters, ports).

    Returns
    -------
    int
        Exit code: the node's own after a clean end (0), 2 for bad parameters or a node class not
        found, 1 for an exception, 130 when interrupted.
    """
    setup_logging(spec["name"])
    log = logging.getLogger(spec["name"])
    last = _LastError()
    logging.getLogger().addHandler(last)
    code = _run_node(spec, log)
    _leave_failure(spec, code, last)
    return code


def _run_node(spec: dict[str, Any], log: logging.Logger) -> int:
    """:func:`run_spec`'s node: made and run, its exit code."""
    try:
        cls = find_node_class(spec["module"])
        node = cls(spec)
    except (ParamError, NodeLookupError) as exc:
        log.error("%s", exc)
        return 2
    try:
        return node.run()
    except KeyboardInterrupt:
        return 130
    except ParamError as exc:  # a parameter found bad only in setup (a port in use): said, not a crash
        log.error("%s", exc)
        return 2
    except Exception:
        log.error("crashed:\n%s", traceback.format_exc())
        return 1


def run_standalone(cls: type[Node] | str, argv: list[str] | None = None) -> int:
    """``counterpart run MODULE --param k=v --remap port=topic --policy port=latest``.

    Parameters
    ----------
    cls : type of Node or str
        The node class, or its module path (``module`` or ``module:Class``).
    argv : list of str or None, default=None
        The command line's options; ``None`` for ``sys.argv[1:]``.

    Returns
    -------
    int
        Exit code: 2 for bad options or parameters, else as :func:`run_spec`.
    """
    ap = argparse.ArgumentParser(prog="counterpart run", description="Run one node alone.")
    if isinstance(cls, str):
        module = cls
    else:
        module = f"{cls.__module__}:{cls.__name__}"
    ap.add_argument("--name", default=None, help="node name (default: the module's last part)")
    ap.add_argument("--param", "-p", action="append", metavar="KEY=VALUE", help="set a parameter")
    ap.add_argument("--remap", "-r", action="append", metavar="PORT=TOPIC", help="connect a port to a topic")
    ap.add_argument("--policy", action="append", metavar="PORT=POLICY", help="reliable or latest per input")
    args = ap.parse_args(argv)
    try:
        node_cls = find_node_class(module)
        parts = [p for p in module.split(":")[0].split(".") if p not in ("node", "__main__")]
        name = args.name or (parts[-1] if parts else node_cls.__name__.lower())
        spec = standalone_spec(
            name,
            node_cls,
            parse_assignments(args.param),
            parse_assignments(args.remap, "--remap"),
            parse_assignments(args.policy, "--policy"),
        )
    except (ParamError, NodeLookupError, ValueError) as exc:
        print(f"counterpart run: {exc}", file=sys.stderr)
        return 2
    spec["module"] = module
    return run_spec(spec)


def main() -> None:
    """``python -m counterpart.bus.runner SPEC.json`` (what the launcher starts)."""
    if len(sys.argv) != 2:
        print("usage: python -m counterpart.bus.runner SPEC.json", file=sys.stderr)
        sys.exit(2)
    sys.exit(run_spec(load_spec(sys.argv[1])))


if __name__ == "__main__":
    main()
