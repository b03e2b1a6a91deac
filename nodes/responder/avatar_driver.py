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
    """Goal name -> strength for the texture graph from the listener's behaviours (module docstring)."""
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
    """One frame of the avatar: the Partner fields (``joints`` (14, 3) metres: where the listener
    stands, facing the speaker, for the renderer's place and scale; ``avatar_frames`` (n,) int32 and
    ``avatar_weights`` (n,) float32: the recording frames to blend; ``avatar_file``; ``behaviour``:
    the signals of the frame shown, or ``listen``).
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
