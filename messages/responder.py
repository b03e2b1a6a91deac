"""Messages of the responder (the partner) and the run-time controls."""

from __future__ import annotations

import numpy as np

from .core import EMPTY, message


@message("responder.Partner", 1)
class Partner:
    """The generated partner for one frame.

    ``joints`` (14, 3) float32 metres (world frame) for 3D models, empty otherwise; ``ctrl`` (n, 2)
    float32 image pixels of the partner's B-spline silhouette for the joint-shape model, empty
    otherwise; ``observed_id`` the silhouette/tracker id of the person it responds to; ``behaviour``
    a short label of what it does (e.g. ``handshake``, ``nod``); ``emotion``/``strength`` the style
    in force; ``confidence`` in [0, 1].

    The video-texture avatar (fields added with defaults, so senders and readers of the fields above
    are unaffected): ``avatar_file`` the avatar file holding the recording's masked frames;
    ``avatar_frames`` (n,) int32 indices of the recording frames to show, blended with
    ``avatar_weights`` (n,) float32 summing to 1 (two frames during a cut's cross-fade); empty for
    the other models. ``joints`` then says where the avatar stands (and so its scale).
    """

    model: str = ""
    joints: np.ndarray = EMPTY
    ctrl: np.ndarray = EMPTY
    observed_id: int = -1
    behaviour: str = ""
    emotion: str = "neutral"
    strength: float = 0.0
    confidence: float = 0.0
    avatar_file: str = ""
    avatar_frames: np.ndarray = EMPTY
    avatar_weights: np.ndarray = EMPTY


@message("control.Control", 1)
class Control:
    """A run-time control from the web page or the CLI; None leaves a setting unchanged.

    ``model``: interaction model name; ``speaker``: ``person`` or ``partner``; ``interest``: listener
    interest level 1-3; ``emotion``: neutral/happy/sad/angry; ``strength`` in [0, 1]; ``overlays``:
    overlay name -> on/off for the renderer.
    """

    model: str | None = None
    speaker: str | None = None
    interest: int | None = None
    emotion: str | None = None
    strength: float | None = None
    overlays: dict[str, bool] | None = None
