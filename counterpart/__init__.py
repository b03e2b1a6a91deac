"""Counterpart: an open system for virtual interaction partners.

One import name for the whole project: the repository's top-level folders are its subpackages
(``counterpart.messages``, ``counterpart.bus``, ``counterpart.body``, ``counterpart.sim``,
``counterpart.nodes``, ``counterpart.apps``, ``counterpart.launch``), mapped in ``pyproject.toml``.
"""

from __future__ import annotations

__version__ = "0.1.0"
