"""The renderer node's package: drawing (:mod:`.draw`), pairing and compositing (:mod:`.compositor`),
video files (:mod:`.video`), run-time controls (:mod:`.controls`), the live web page (:mod:`.web`,
``page.html``) and the thin process wrapper :class:`counterpart.nodes.renderer.node.Renderer` (``run: counterpart.nodes.renderer``).

Everything but ``node`` and ``web`` works without a bus or a server: ``draw.draw_partner_3d(img,
joints, camera)`` in a notebook.
"""

from .compositor import OVERLAYS, STYLES, Bundle, Compositor, ControlState
from .controls import control_to_json, parse_control
from .draw import (
    closed_bspline,
    contact_sheet,
    draw_cones,
    draw_controls,
    draw_partner_3d,
    draw_signal_badges,
    draw_silhouette,
    draw_skeleton,
    draw_spline_outline,
    draw_stats,
    partner_colour,
    partner_cones,
)
from .video import VideoWriter, choose_codec, count_frames, write_png

__all__ = [
    "OVERLAYS",
    "STYLES",
    "Bundle",
    "Compositor",
    "ControlState",
    "control_to_json",
    "parse_control",
    "closed_bspline",
    "contact_sheet",
    "draw_cones",
    "draw_controls",
    "draw_partner_3d",
    "draw_signal_badges",
    "draw_silhouette",
    "draw_skeleton",
    "draw_spline_outline",
    "draw_stats",
    "partner_colour",
    "partner_cones",
    "VideoWriter",
    "choose_codec",
    "count_frames",
    "write_png",
]
