"""The camera node's package: frame sources (:mod:`.sources`), pacing and frame conversion
(:mod:`.pacing`), and the thin process wrapper :class:`counterpart.nodes.camera.node.Camera` (``run: counterpart.nodes.camera``).

The modules other than ``node`` need no bus: ``make_source("clip.avi")`` works in a notebook.
"""

from .pacing import PACING_MODES, Pacer, convert, frames, output_size
from .sources import (
    ImageFolderSource,
    SimulatorSource,
    SourceError,
    V4L2Source,
    VideoFileSource,
    make_source,
    parse_uri,
)

__all__ = [
    "PACING_MODES",
    "Pacer",
    "convert",
    "frames",
    "output_size",
    "ImageFolderSource",
    "SimulatorSource",
    "SourceError",
    "V4L2Source",
    "VideoFileSource",
    "make_source",
    "parse_uri",
]
