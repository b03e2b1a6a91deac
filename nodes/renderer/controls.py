"""Run-time controls from the web page: JSON checked and turned into ``messages.Control``.

The names the controls allow are the contract's (``counterpart.messages.INTERACTION_MODELS``,
``EMOTIONS``, ``SPEAKERS``, ``INTEREST_LEVELS``); this module only reads JSON into them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from counterpart.messages import EMOTIONS, INTERACTION_MODELS, INTEREST_LEVELS, SPEAKERS, Control

from .compositor import OVERLAYS

CONTROL_KEYS = ("model", "speaker", "interest", "emotion", "strength", "overlays")


def parse_control(data: Any, models: Sequence[str] = INTERACTION_MODELS) -> Control:
    """A ``Control`` from a JSON object such as ``{"strength": 0.7, "emotion": "happy"}``.

    Parameters
    ----------
    data : Any
        The decoded JSON. Keys (all optional): ``model`` (one of ``models``), ``speaker`` (one of
        ``SPEAKERS``), ``interest`` (one of ``INTEREST_LEVELS``, a digit string accepted),
        ``emotion`` (one of ``EMOTIONS``), ``strength`` (number in [0, 1]), ``overlays`` (overlay
        name -> bool).
    models : sequence of str, default=INTERACTION_MODELS
        The interaction models offered (a subset of ``INTERACTION_MODELS``).

    Returns
    -------
    Control
        The control, with stamp and seq 0.

    Raises
    ------
    ValueError
        Naming the bad key and what it takes.
    """
    if not isinstance(data, dict):
        raise ValueError(f"control must be a JSON object, got {type(data).__name__}")
    unknown = sorted(set(data) - set(CONTROL_KEYS))
    if unknown:
        raise ValueError(f"unknown control key(s) {unknown}; expected some of {list(CONTROL_KEYS)}")
    out: dict[str, Any] = {}
    if data.get("model") is not None:
        m = data["model"]
        if not isinstance(m, str) or m not in models:
            raise ValueError(f"model {m!r}: expected one of {list(models)}")
        out["model"] = m
    if data.get("speaker") is not None:
        if data["speaker"] not in SPEAKERS:
            raise ValueError(f"speaker {data['speaker']!r}: expected one of {list(SPEAKERS)}")
        out["speaker"] = data["speaker"]
    if data.get("interest") is not None:
        i = data["interest"]
        if isinstance(i, str) and i.strip().isdigit():
            i = int(i)
        if isinstance(i, bool) or i not in INTEREST_LEVELS:
            raise ValueError(f"interest {data['interest']!r}: expected one of {list(INTEREST_LEVELS)}")
        out["interest"] = int(i)
    if data.get("emotion") is not None:
        if data["emotion"] not in EMOTIONS:
            raise ValueError(f"emotion {data['emotion']!r}: expected one of {list(EMOTIONS)}")
        out["emotion"] = data["emotion"]
    if data.get("strength") is not None:
        s = data["strength"]
        try:
            s = float(s) if not isinstance(s, bool) else math.nan
        except (TypeError, ValueError):
            s = math.nan
        if not 0.0 <= s <= 1.0:
            raise ValueError(f"strength {data['strength']!r}: expected a number in [0, 1]")
        out["strength"] = s
    if data.get("overlays") is not None:
        ov = data["overlays"]
        if not isinstance(ov, dict) or not all(k in OVERLAYS and isinstance(v, bool) for k, v in ov.items()):
            raise ValueError(
                f"overlays {ov!r}: expected an object of overlay name -> true/false, names {list(OVERLAYS)}"
            )
        out["overlays"] = dict(ov)
    return Control(**out)


def control_to_json(msg: Control) -> dict[str, Any]:
    """The set fields of a Control as a JSON-able dict.

    Parameters
    ----------
    msg : Control
        The control.

    Returns
    -------
    dict
        The fields of ``CONTROL_KEYS`` that are not None.
    """
    return {k: getattr(msg, k) for k in CONTROL_KEYS if getattr(msg, k) is not None}


__all__ = ["parse_control", "control_to_json", "CONTROL_KEYS"]
