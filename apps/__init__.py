"""The applications: what a user runs that combines nodes' algorithms.

The top layer: an application may import any node, the simulator and the runtime; nothing imports
an application. ``demo`` (the whole graph), and the offline commands ``track``, ``silhouettes``,
``calibrate``, ``respond``, ``learn`` (with ``learn avatar``) and ``mine``, each declared as a
``counterpart`` subcommand through the ``counterpart.commands`` entry points in ``pyproject.toml``.
"""
