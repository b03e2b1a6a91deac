"""Run-time controls from the web page: JSON checked and turned into ``messages.Control``."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from counterpart.messages import Control

from .compositor import OVERLAYS

SPEAKERS = ("person", "partner")
EMOTIONS = ("neutral", "happy", "sad", "angry")
INTEREST_LEVELS = (1, 2, 3)
CONTROL_KEYS = ("model", "speaker", "interest", "emotion", "strength", "overlays")


def parse_control(data: Any, models: Sequence[str] = ()) -> Control:
    """A ``Control`` from a JSON object such as ``{"strength": 0.7, "emotion": "happy"}``.

    Keys (all optional): ``model`` (one of ``models`` when given), ``speaker`` (person/partner),
    ``interest`` (1-3), ``emotion`` (neutral/happy/sad/angry), ``strength`` (number in [0, 1]),
    ``overlays`` (overlay name -> bool). Raises ValueError naming the bad key and what it takes.
    """
    if not isinstance(data, dict):
        raise ValueError(f"control must be a JSON object, got {type(data).__name__}")
    unknown = sorted(set(data) - set(CONTROL_KEYS))
    if unknown:
        raise ValueError(f"unknown control key(s) {unknown}; expected some of {list(CONTROL_KEYS)}")
    out: dict[str, Any] = {}
    if data.get("model") is not None:
        m = data["model"]
        if not isinstance(m, str) or (models and m not in models):
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
            raise ValueError(f"interest {data['interest']!r}: expected 1, 2 or 3")
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
    """The set fields of a Control as a JSON-able dict."""
    return {k: getattr(msg, k) for k in CONTROL_KEYS if getattr(msg, k) is not None}


__all__ = ["parse_control", "control_to_json", "SPEAKERS", "EMOTIONS", "INTEREST_LEVELS", "CONTROL_KEYS"]
