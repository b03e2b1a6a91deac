"""The built wheel installs one import name, ``counterpart``, and runs from it alone."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


SKIP = {"tests", "bench", "docs", "build", "dist", "counterpart"}


def _package_folders(root: Path) -> set[str]:
    """The source tree's packages, as ``counterpart.`` names (every folder with an ``__init__.py``)."""
    names = {"counterpart"}
    for init in root.glob("*/**/__init__.py"):
        rel = init.parent.relative_to(root)
        if rel.parts[0] not in SKIP and not rel.parts[0].startswith("."):
            names.add(".".join(("counterpart", *rel.parts)))
    return names


@pytest.mark.slow
def test_wheel_installs_only_counterpart_at_the_top_level(tmp_path: Path) -> None:
    wheels, target, src = tmp_path / "wheels", tmp_path / "site", tmp_path / "src"
    # A copy, because an in-tree build leaves build/ and egg-info folders in the checkout.
    shutil.copytree(REPO, src, ignore=shutil.ignore_patterns(".*", "__pycache__", "*.egg-info", "build", "dist"))
    build = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w", str(wheels), str(src)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert build.returncode == 0, build.stderr[-3000:]
    (wheel,) = wheels.glob("counterpart-*.whl")
    inst = subprocess.run(
        [sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target", str(target), str(wheel)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert inst.returncode == 0, inst.stderr[-3000:]
    top = {p.name for p in target.iterdir()} - {"bin"}
    assert {n for n in top if not n.endswith(".dist-info")} == {"counterpart"}, top
    installed = {".".join(p.parent.relative_to(target).parts) for p in (target / "counterpart").rglob("__init__.py")}
    assert installed == _package_folders(src), "pyproject.toml's package list and the repository's folders differ"
    launch_files = {p.name for p in (target / "counterpart" / "launch").glob("*.yaml")}
    assert launch_files == {p.name for p in (REPO / "launch").glob("*.yaml")}
    # The installed copy alone runs: from a folder outside the repository, with it first on the path.
    env = {**os.environ, "PYTHONPATH": str(target)}
    code = (
        "import counterpart, counterpart.nodes.tracker.node, counterpart.bus.launchfile as lf; "
        "print(counterpart.__file__); print(lf.check(lf.load('demo.yaml')).nodes['tracker'].run)"
    )
    run = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120
    )
    assert run.returncode == 0, run.stderr[-3000:]
    first, second = run.stdout.split()
    assert first.startswith(str(target)) and second == "counterpart.nodes.tracker"
