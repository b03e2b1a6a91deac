"""The stamp that spares ``counterpart demo`` loading the nodes' numba kernels to find out whether
they are compiled (``counterpart.apps.kernel_cache``), on the real kernels and their real cache.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

from counterpart.apps import kernel_cache


@pytest.fixture
def stamp(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """The stamp in a folder of the test's own (the kernels' cache stays the real one)."""
    path = tmp_path / "stamp.json"
    monkeypatch.setattr(kernel_cache, "stamp_path", lambda: path)
    return path


def test_the_kernels_count_as_compiled_once_loaded_and_until_their_cache_or_source_changes(stamp: Path) -> None:
    assert not kernel_cache.kernels_cached()  # no stamp yet
    for part in range(kernel_cache.COMPILE_PARTS):  # loads them (the session compiled them first)
        kernel_cache.compile_kernels(part, kernel_cache.COMPILE_PARTS)
    kernel_cache.remember_kernels()
    assert kernel_cache.kernels_cached()
    state = json.loads(stamp.read_text())
    names = [Path(f[0]).name for f in state["files"]]
    # every kernel module's source and at least one of its cache's index files
    for module in kernel_cache.KERNEL_MODULES:
        stem = module.rsplit(".", 1)[1]
        assert f"{stem}.py" in names and any(n.startswith(f"{stem}.") and n.endswith(".nbi") for n in names)
    # a kernel's cache written again since (or its source edited): no longer taken as compiled
    state["files"][-1][1] += 1
    stamp.write_text(json.dumps(state))
    assert not kernel_cache.kernels_cached()
    stamp.write_text("{not json")
    assert not kernel_cache.kernels_cached()
    kernel_cache.remember_kernels()
    assert kernel_cache.kernels_cached()
    # another Python's index files (numba names them by its version) say nothing of this one's
    source = Path(importlib.util.find_spec(kernel_cache.KERNEL_MODULES[0]).origin)
    other = source.parent / "__pycache__" / f"{source.stem}.not_a_kernel-1.py20.nbi"
    other.write_bytes(b"")
    try:
        assert kernel_cache.kernels_cached()
    finally:
        other.unlink()


def test_a_cache_kept_elsewhere_is_never_taken_as_compiled(stamp: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    kernel_cache.remember_kernels()
    assert kernel_cache.kernels_cached()
    # numba then caches in that folder, not beside the modules, where the stamp looks
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(stamp.parent / "numba"))
    assert kernel_cache.cache_state() is None and not kernel_cache.kernels_cached()
    kernel_cache.remember_kernels()  # writes nothing it could later match
    monkeypatch.delenv("NUMBA_CACHE_DIR")
    assert kernel_cache.kernels_cached()


def test_a_stamp_that_cannot_be_written_is_left_out(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # a folder the demo cannot write in (here: one that is not there): the kernels load on every run
    monkeypatch.setattr(kernel_cache, "stamp_path", lambda: tmp_path / "not-there" / "stamp.json")
    kernel_cache.remember_kernels()
    assert not kernel_cache.kernels_cached() and not (tmp_path / "not-there").exists()
