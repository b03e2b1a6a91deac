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

    ``speaker`` and ``interest`` were added with defaults, as were the video-texture avatar's fields,
    so senders and readers of the other fields are unaffected.

    Parameters
    ----------
    model : str, default=""
        The model that made the partner.
    joints : ndarray of shape (14, 3), dtype float32
        Metres (world frame) for 3D models, empty otherwise; for the video-texture avatar, where it
        stands (and so its scale).
    ctrl : ndarray of shape (n, 2), dtype float32
        Image pixels of the partner's B-spline silhouette for the joint-shape model, empty otherwise.
    observed_id : int, default=-1
        The silhouette/tracker id of the person it responds to.
    behaviour : str, default=""
        A short label of what it does (e.g. ``handshake``, ``nod``).
    emotion : str, default="neutral"
        The style in force.
    strength : float, default=0.0
        The style's strength in force.
    confidence : float, default=0.0
        Confidence in [0, 1].
    avatar_file : str, default=""
        The avatar file holding the recording's masked frames (video-texture avatar).
    avatar_frames : ndarray of shape (n,), dtype int32
        Indices of the recording frames to show (two during a cut's cross-fade); empty for the other
        models.
    avatar_weights : ndarray of shape (n,), dtype float32
        Blend weights of ``avatar_frames``, summing to 1; empty for the other models.
    speaker : str, default=""
        The listener setting in force when the partner was made ("" from senders that do not say), so
        that a reader sees every control take effect.
    interest : int, default=0
        The listener interest level in force (0 from senders that do not say).
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

    Parameters
    ----------
    model : str or None, default=None
        One of ``INTERACTION_MODELS``.
    speaker : str or None, default=None
        One of ``SPEAKERS``.
    interest : int or None, default=None
        One of ``INTEREST_LEVELS``.
    emotion : str or None, default=None
        One of ``EMOTIONS``.
    strength : float or None, default=None
        Style strength in [0, 1].
    overlays : dict of str to bool or None, default=None
        Overlay name -> on/off for the renderer.

    Raises
    ------
    ValueError
        For any other value, naming the field and what it takes, when the message is made and when it is
        decoded (a ``bad_field`` there).
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
