"""Messages of the responder (the partner) and the run-time controls, with the names the controls
allow: the page, the CLI and the responder read them from here, so they cannot drift apart.
"""

from __future__ import annotations

import numpy as np

from .core import EMPTY, message

#: the interaction models the responder runs (``Control.model``, ``Partner.model``); the emotion
#: model is not one of them: it styles the 3D models' output through ``emotion`` and ``strength``
INTERACTION_MODELS: tuple[str, ...] = ("dual-hmm", "joint-shape", "listener", "video-texture", "gpdm")
#: the partner's emotions (``Control.emotion``, ``Partner.emotion``); "neutral" is strength 0 of any other
EMOTIONS: tuple[str, ...] = ("neutral", "happy", "sad", "angry")
#: who speaks, for the listener models (``Control.speaker``)
SPEAKERS: tuple[str, ...] = ("person", "partner")
#: the listener's interest levels (``Control.interest``), 1 the least
INTEREST_LEVELS: tuple[int, ...] = (1, 2, 3)


@message("responder.Partner", 1)
class Partner:
    """The generated partner for one frame.

    ``joints`` (14, 3) float32 metres (world frame) for 3D models, empty otherwise; ``ctrl`` (n, 2)
    float32 image pixels of the partner's B-spline silhouette for the joint-shape model, empty
    otherwise; ``observed_id`` the silhouette/tracker id of the person it responds to; ``behaviour``
    a short label of what it does (e.g. ``handshake``, ``nod``); ``emotion``/``strength`` the style
    in force; ``confidence`` in [0, 1].

    ``speaker`` and ``interest`` (added with defaults): the listener settings in force when the
    partner was made ("" and 0 from senders that do not say), so that a reader sees every control
    take effect.

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
    speaker: str = ""
    interest: int = 0


@message("control.Control", 1)
class Control:
    """A run-time control from the web page or the CLI; None leaves a setting unchanged.

    ``model``: one of ``INTERACTION_MODELS``; ``speaker``: one of ``SPEAKERS``; ``interest``: one of
    ``INTEREST_LEVELS``; ``emotion``: one of ``EMOTIONS``; ``strength`` in [0, 1]; ``overlays``:
    overlay name -> on/off for the renderer. Any other value raises ValueError naming the field and
    what it takes, when the message is made and when it is decoded (a ``bad_field`` there).
    """

    model: str | None = None
    speaker: str | None = None
    interest: int | None = None
    emotion: str | None = None
    strength: float | None = None
    overlays: dict[str, bool] | None = None

    def __post_init__(self) -> None:
        for name, allowed in (
            ("model", INTERACTION_MODELS),
            ("speaker", SPEAKERS),
            ("interest", INTEREST_LEVELS),
            ("emotion", EMOTIONS),
        ):
            value = getattr(self, name)
            if value is not None and (type(value) is bool or value not in allowed):
                raise ValueError(f"Control.{name}={value!r}: expected one of {', '.join(map(str, allowed))} or None")
        s = self.strength
        if s is not None and (type(s) is bool or not isinstance(s, (int, float)) or not 0.0 <= s <= 1.0):
            raise ValueError(f"Control.strength={s!r}: expected a number in [0, 1] or None")
