"""What the installed packages declare to each other, through entry points.

The runtime hard-wires no node and no application: the ``counterpart`` command's subcommands
(group ``counterpart.commands``), the targets of ``counterpart learn`` (``counterpart.learn``) and the
built-in simulator that the camera's ``sim:`` source and the default models use
(``counterpart.simulator``) are looked up here by name. Counterpart declares its own in
``pyproject.toml``; another installed package can add commands or learn targets the same way.
"""

from __future__ import annotations

from importlib.metadata import EntryPoint, entry_points
from typing import Any

COMMANDS = "counterpart.commands"
LEARN_TARGETS = "counterpart.learn"
SIMULATOR = "counterpart.simulator"


class PluginError(LookupError):
    """A name that no installed package declares; the message lists the ones that are."""


def declared(group: str) -> dict[str, EntryPoint]:
    """The entry points of ``group`` by name, in the order the packages declare them.

    Parameters
    ----------
    group : str
        The entry-point group, e.g. :data:`COMMANDS`.

    Returns
    -------
    dict of str to EntryPoint
        The declared entry points by name.
    """
    return {ep.name: ep for ep in entry_points(group=group)}


def load(group: str, name: str) -> Any:
    """The object the entry point ``name`` of ``group`` names (imported now).

    Parameters
    ----------
    group : str
        The entry-point group, e.g. :data:`LEARN_TARGETS`.
    name : str
        The entry point's name in that group.

    Returns
    -------
    object
        The loaded object.

    Raises
    ------
    PluginError
        No installed package declares ``name`` in ``group`` (for example a source checkout that was
        never installed: ``pip install -e .`` declares Counterpart's own).
    """
    found = declared(group)
    if name not in found:
        known = ", ".join(found) or "none"
        raise PluginError(
            f"no installed package declares {name!r} in {group} (declared: {known}); "
            f"install Counterpart with `pip install -e .` (or the package that provides it)"
        )
    return found[name].load()


def simulator() -> Any:
    """The built-in world (``counterpart.sim``), found through its entry point: a node reaches the
    simulator this way, not by importing it (nodes and the simulator are on one layer).

    Its interface: ``open_stream(scenario, seed, width, height, fps, **options)`` (frames, truth),
    ``make_scenario(name, seed, fps, **options)`` (poses, joints, labels of two people) and
    ``listener_recording(seconds, seed, interested, empty_s)`` (one person rendered alone with masks).

    Returns
    -------
    module
        The simulator's module, loaded from the ``builtin`` entry point of :data:`SIMULATOR`.

    Raises
    ------
    PluginError
        Counterpart is not installed, so the entry point is not declared.
    """
    return load(SIMULATOR, "builtin")


__all__ = ["COMMANDS", "LEARN_TARGETS", "SIMULATOR", "PluginError", "declared", "load", "simulator"]
