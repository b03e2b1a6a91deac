"""Messages of the social-signal labeller (Okwechime et al.)."""

from __future__ import annotations

import numpy as np

from .core import EMPTY, message, struct


@struct
class PersonSignals:
    """Social signals of one person.

    Attributes
    ----------
    id : int
        The person's id.
    side : str
        The person's side of the scene (``"left"`` by default).
    names : list of str of length K
        The signals' names: the order of ``scores`` and ``labels``.
    scores : ndarray of shape (K,), dtype float32
        Per-signal scores.
    labels : ndarray of shape (K,), dtype int8
        Per-signal labels: 1, 0, or -1 for unknown (the input cannot support the signal).
    source : str
        Where nod/shake came from: ``face`` (a tracked face), ``3d`` (tracker) or ``2d`` (silhouette).
    """

    id: int = 0
    side: str = "left"
    names: list[str] = ()
    scores: np.ndarray = EMPTY
    labels: np.ndarray = EMPTY
    source: str = ""


@message("labeller.SocialSignals", 1)
class SocialSignals:
    """The social signals of the people in one frame.

    Attributes
    ----------
    people : list of PersonSignals
        One entry per person.
    """

    people: list[PersonSignals] = ()
