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
    """The run directory given, or the newest launch's (``base_dir()/latest``)."""
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
    info = reg["topics"].get(topic)
    if info is None or not info.get("endpoints"):
        raise RegistryError(f"no topic {topic!r} in the launch; topics: {', '.join(sorted(reg['topics']))}")
    return TopicEndpoints.from_dict(info["endpoints"])
