"""Driving the video-texture avatar with the listener rules (Okwechime et al.).

The listener model (:class:`~counterpart.nodes.responder.listener.ListenerModel`) decides, from the speaker's
signals and the mined rules' confidences at the user's interest level, which listener behaviours
are on (``nod``, ``shake``, ``gaze_at_other``, ...) and where the listener stands (facing the
speaker). The texture motion graph is then asked for them: each behaviour the graph has is a
requested signal (strength 1: the next transitions take the shortest way to it), and the social
state (talking when the partner is the speaker, looking at the speaker when interested or when the
rules say so) a soft goal (``STATE_STRENGTH``) that keeps the avatar in that state's subgraph.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

import numpy as np

from .listener import ListenerModel
from .video_texture import VideoTexture

STATE_STRENGTH = 0.3


def avatar_goals(texture: VideoTexture, behaviours: set[str], speaker: str, interest: int) -> dict[str, float]:
    """Goal name -> strength for the texture graph from the listener's behaviours (module docstring).

    Parameters
    ----------
    texture : VideoTexture
        The texture motion graph.
    behaviours : set of str
        The listener behaviours that are on (``nod``, ``shake``, ``gaze_at_other``, ...).
    speaker : str
        Who speaks: ``"partner"`` or ``"person"``.
    interest : int
        The user's interest level (2 and above: the listener looks at the speaker).

    Returns
    -------
    dict of str to float
        Goal strengths: 1 for each requested behaviour the graph has, ``STATE_STRENGTH`` for the
        social state's goal.
    """
    goals = {b: 1.0 for b in behaviours if texture.goal_index(b) >= 0 and b != "gaze_at_other"}
    wanted = {
        "talking": speaker == "partner",
        "gaze_at_other": "gaze_at_other" in behaviours or interest >= 2,
        "laughing": "laughing" in behaviours,
    }
    state = texture.state_goal(wanted)
    if state is not None:
        goals[state] = STATE_STRENGTH
    return goals


def avatar_partner(
    texture: VideoTexture,
    listener: ListenerModel,
    speaking: Mapping[str, bool],
    observed: np.ndarray | None,
    speaker: str,
    interest: int,
    path: str | os.PathLike[str],
) -> dict[str, Any]:
    """One frame of the avatar: the Partner fields.

    Parameters
    ----------
    texture : VideoTexture
        The texture motion graph.
    listener : ListenerModel
        The listener model; its ``interest`` is set to ``interest``.
    speaking : Mapping of str to bool
        The speaker's signals (used when the speaker is ``"person"``).
    observed : ndarray of shape (14, 3) or None
        The observed person's joints, metres.
    speaker : str
        Who speaks: ``"person"`` or ``"partner"``.
    interest : int
        The user's interest level.
    path : str or os.PathLike
        The avatar's recording.

    Returns
    -------
    dict of str to Any
        ``joints`` (14, 3) metres: where the listener stands, facing the speaker, for the renderer's
        place and scale; ``avatar_frames`` (n,) int32 and ``avatar_weights`` (n,) float32: the
        recording frames to blend; ``avatar_file``; ``behaviour``: the signals of the frame shown, or
        ``listen``; ``confidence``.
    """
    listener.interest = interest
    joints = listener.step(speaking if speaker == "person" else {}, observed)
    on = {b for b in listener.behaviour_.split("+") if b}
    frames, weights = texture.step(avatar_goals(texture, on, speaker, interest))
    shown = sorted(n for n, v in texture.labels_at(int(frames[0])).items() if v and texture.goal_index(n) >= 0)
    return {
        "joints": joints,
        "avatar_frames": frames,
        "avatar_weights": weights,
        "avatar_file": os.fspath(path),
        "behaviour": "+".join(shown) or "listen",
        "confidence": 1.0,
    }
