"""Whether the nodes' numba kernels are compiled into numba's on-disk cache already.

``counterpart demo`` compiles them before the graph starts on an install's first run (the nodes
would otherwise compile for seconds while the frames go on). Loading them to find out costs more
than a second on every later run, so what was compiled is remembered in a stamp in the cache's
folder (numba keeps a ``NAME.nbi`` index per kernel in the ``__pycache__`` folder beside its
module): the kernels' source files and those index files, with their sizes and modification
times. Any change to either (a kernel edited, the cache deleted or grown) compiles and loads them
again; a cache elsewhere (``NUMBA_CACHE_DIR``) is never taken as compiled.
"""

from __future__ import annotations

import importlib.metadata
import importlib.util
import json
import os
import sys
from pathlib import Path
from typing import Any

#: the modules whose kernels the graph's nodes run
KERNEL_MODULES = (
    "counterpart.nodes.silhouette.kernels",
    "counterpart.nodes.tracker.kernels",
    "counterpart.body.kinematics_kernel",
)


#: processes an install's first compile of the kernels is shared between (:func:`compile_kernels`)
COMPILE_PARTS = 2


def compile_kernels(part: int = 0, parts: int = 1) -> None:
    """Load the nodes' numba kernels, compiling into their cache those that are not there yet (an
    install's first run): every ``parts``-th of the silhouette node's from the ``part``-th, and with
    the last part the tracker's. Run one part in each of ``parts`` processes, they compile side by
    side (numba compiles on one core; each kernel has its own cache files).

    Parameters
    ----------
    part, parts : int, default=0, 1
        Which part, of how many.

    Raises
    ------
    ValueError
        If ``part`` is not one of ``range(parts)``.
    """
    from counterpart.nodes.silhouette.kernels import warm
    from counterpart.nodes.tracker.likelihood import warm_kernels

    warm(part, parts)
    if part == parts - 1:
        warm_kernels()


def _source(name: str) -> Path | None:
    spec = importlib.util.find_spec(name)
    return None if spec is None or spec.origin is None else Path(spec.origin)


def stamp_path() -> Path | None:
    """The stamp's file, in the cache folder of the first of ``KERNEL_MODULES``."""
    source = _source(KERNEL_MODULES[0])
    return None if source is None else source.parent / "__pycache__" / "counterpart-kernels.json"


def _files(paths: list[Path]) -> list[list[Any]]:
    stats = [(p, p.stat()) for p in sorted(paths)]
    return [[str(p), st.st_mtime_ns, st.st_size] for p, st in stats]


def cache_state() -> dict[str, Any] | None:
    """The version of numba, and each kernel module's source file and this Python's cache index
    files (path, modification time in ns, size); None where a module has no index file beside it
    (never compiled, or cached elsewhere: ``NUMBA_CACHE_DIR``), which no stamp matches.
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return None
    # this Python's index files only (numba names them NAME-LINE.pyXY.nbi)
    tag = f"py{sys.version_info[0]}{sys.version_info[1]}"
    files: list[list[Any]] = []
    for name in KERNEL_MODULES:
        source = _source(name)
        if source is None:
            return None
        index = list((source.parent / "__pycache__").glob(f"{source.stem}.*.{tag}.nbi"))
        if not index:
            return None
        files += _files([source, *index])
    return {"numba": importlib.metadata.version("numba"), "files": files}


def kernels_cached() -> bool:
    """True when the stamp says the kernels were compiled into the cache as it is now."""
    state, path = cache_state(), stamp_path()
    try:
        return state is not None and path is not None and json.loads(path.read_text()) == state
    except (OSError, ValueError):
        return False


def remember_kernels() -> None:
    """Write the stamp for the cache as it is now (after the kernels were loaded or compiled); where
    the folder cannot be written (an install read by others), nothing: the kernels are then loaded
    on every run, as without the stamp.
    """
    state, path = cache_state(), stamp_path()
    if state is None or path is None:
        return
    part = path.with_suffix(".tmp")
    try:
        part.write_text(json.dumps(state))
        part.replace(path)
    except OSError:
        part.unlink(missing_ok=True)
