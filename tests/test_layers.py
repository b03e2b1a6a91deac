"""The layers of the design map hold: an import graph of the whole package, checked module by module.

From the bottom: ``messages`` (imports nothing of the project) < ``body``, ``bus`` < ``sim``,
``nodes/<name>`` < ``apps``. A node imports ``messages``, ``bus``, ``body`` and its own package, never
another node's package nor the simulator (which it reaches through ``counterpart.bus.plugins``).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]

#: unit -> the units it may import besides itself
ALLOWED: dict[str, set[str]] = {
    "counterpart": set(),
    "messages": set(),
    "launch": set(),
    "body": {"messages"},
    "bus": {"messages", "launch"},
    "sim": {"messages", "body", "bus"},
    "node": {"messages", "body", "bus"},
    "apps": {"messages", "body", "bus", "sim", "node", "launch"},
}
FOLDERS = ("counterpart", "messages", "launch", "body", "bus", "sim", "nodes", "apps")


def unit_of(module: str) -> str | None:
    """The layer unit of a ``counterpart.`` module name: ``nodes.tracker`` for a node's package."""
    parts = module.split(".")
    if parts[0] != "counterpart":
        return None
    if len(parts) == 1:
        return "counterpart"
    if parts[1] == "nodes":
        return f"nodes.{parts[2]}" if len(parts) > 2 else "nodes"
    return parts[1]


def imports_of(path: Path, root: Path = REPO) -> list[tuple[int, str]]:
    """(line, absolute module) of every import in ``path``, relative ones resolved, and of every
    ``importlib.import_module("counterpart...")`` with a constant name.
    """
    rel = path.relative_to(root).with_suffix("")
    package = ["counterpart", *rel.parts[:-1]] if rel.parts[0] != "counterpart" else list(rel.parts[:-1])
    if rel.parts[-1] == "__init__":
        package = ["counterpart", *rel.parts[:-1]] if rel.parts[0] != "counterpart" else ["counterpart"]
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                found.append((node.lineno, ".".join([*base, *([node.module] if node.module else [])])))
            else:
                found.append((node.lineno, node.module or ""))
        elif (
            isinstance(node, ast.Call)
            and getattr(node.func, "attr", getattr(node.func, "id", "")) == "import_module"
            and node.args
            and isinstance(node.args[0], ast.Constant)
            and str(node.args[0].value).startswith("counterpart.")
        ):
            found.append((node.lineno, str(node.args[0].value)))
    return found


def violations(root: Path = REPO) -> list[str]:
    bad = []
    for folder in FOLDERS:
        for path in sorted((root / folder).rglob("*.py")):
            rel = path.relative_to(root)
            me = unit_of(
                ".".join(["counterpart", *rel.with_suffix("").parts]) if folder != "counterpart" else "counterpart"
            )
            kind = "node" if me and me.startswith("nodes.") else me
            for line, module in imports_of(path, root):
                them = unit_of(module)
                if them is None or them == me or them == "nodes" and kind == "node":
                    continue
                them_kind = "node" if them.startswith("nodes.") else them
                allowed = ALLOWED[kind]
                if them_kind not in allowed or (kind == "node" and them_kind == "node"):
                    bad.append(f"{rel}:{line}: {me} imports {module}")
    return bad


def test_every_import_follows_the_layers() -> None:
    assert violations() == []


@pytest.mark.parametrize(
    ("module", "unit"),
    [("counterpart.nodes.tracker.node", "nodes.tracker"), ("counterpart.bus", "bus"), ("numpy", None)],
)
def test_units(module: str, unit: str | None) -> None:
    assert unit_of(module) == unit


def test_the_check_finds_what_breaks_the_layers(tmp_path: Path) -> None:
    """The checker itself: a node importing another node (absolutely or relatively), bus importing a node."""
    (tmp_path / "nodes" / "tracker").mkdir(parents=True)
    (tmp_path / "bus").mkdir()
    (tmp_path / "nodes" / "tracker" / "probe.py").write_text(
        "from counterpart.nodes.silhouette import pipeline\nfrom . import tracker\nfrom ..camera import sources\n"
    )
    (tmp_path / "bus" / "cli.py").write_text("import importlib\nimportlib.import_module('counterpart.nodes.camera')\n")
    assert violations(tmp_path) == [
        "bus/cli.py:2: bus imports counterpart.nodes.camera",
        "nodes/tracker/probe.py:1: nodes.tracker imports counterpart.nodes.silhouette",
        "nodes/tracker/probe.py:3: nodes.tracker imports counterpart.nodes.camera",
    ]
