"""Finding a running launch and reading its registry (what ``node`` and ``topic`` commands use)."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from .endpoints import RunDirError, TopicEndpoints, base_dir


class RegistryError(RuntimeError):
    """No running launch, or an unreadable registry."""


def find_run(run: str | None = None) -> Path:
    """The run directory given, or the newest launch's (``base_dir()/latest``).

    Parameters
    ----------
    run : str or None, default=None
        A run directory; ``None`` or empty for the newest launch's.

    Returns
    -------
    Path
        The run directory, resolved.

    Raises
    ------
    RegistryError
        The per-user base directory is not safely the user's own, or the directory holds no
        ``registry.json``.
    """
    try:
        path = Path(run) if run else base_dir() / "latest"
    except RunDirError as exc:
        raise RegistryError(str(exc)) from None
    if not (path / "registry.json").is_file():
        raise RegistryError(
            f"no running launch found at {path}: start one with 'counterpart launch FILE' or pass --run RUN_DIR"
        )
    return path.resolve()


def read(run: str | None = None) -> dict[str, Any]:
    """The registry of a launch, with ``alive`` added: whether its launcher process still runs.

    Parameters
    ----------
    run : str or None, default=None
        A run directory; ``None`` or empty for the newest launch's.

    Returns
    -------
    dict of str to object
        The contents of ``registry.json`` and ``alive`` (bool).

    Raises
    ------
    RegistryError
        No launch found (see :func:`find_run`), or ``registry.json`` is unreadable.
    """
    path = find_run(run)
    try:
        reg = json.loads((path / "registry.json").read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise RegistryError(f"{path}/registry.json is unreadable: {exc}") from None
    reg["alive"] = _alive(reg.get("launcher_pid"))
    return reg


def _alive(pid: int | None) -> bool:
    if not pid:
        return False
    try:
        os.kill(pid, 0)
        return True
    except ProcessLookupError:
        return False
    except PermissionError:
        return True


def topic_endpoints(reg: dict[str, Any], topic: str) -> TopicEndpoints:
    """The endpoints of ``topic`` in a launch's registry.

    Parameters
    ----------
    reg : dict of str to object
        A registry, as :func:`read` returns it.
    topic : str
        The topic's name.

    Returns
    -------
    TopicEndpoints
        Where the topic is published.

    Raises
    ------
    RegistryError
        The launch has no topic of that name (or none with endpoints); the message lists its topics.
    """
    info = reg["topics"].get(topic)
    if info is None or not info.get("endpoints"):
        raise RegistryError(f"no topic {topic!r} in the launch; topics: {', '.join(sorted(reg['topics']))}")
    return TopicEndpoints.from_dict(info["endpoints"])
