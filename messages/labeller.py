"""Messages of the social-signal labeller (Okwechime et al.)."""

from __future__ import annotations

import numpy as np

from .core import EMPTY, message, struct


@struct
class PersonSignals:
    """Per-signal ``scores`` (K,) float32 and ``labels`` (K,) int8: 1, 0, or -1 for unknown (the
    input cannot support the signal); ``names`` (K,) gives the order; ``source`` is where nod/shake came
    from: ``face`` (a tracked face), ``3d`` (tracker) or ``2d`` (silhouette).
    """

    id: int = 0
    side: str = "left"
    names: list[str] = ()
    scores: np.ndarray = EMPTY
    labels: np.ndarray = EMPTY
    source: str = ""


@message("labeller.SocialSignals", 1)
class SocialSignals:
    people: list[PersonSignals] = ()
