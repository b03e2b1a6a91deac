"""Signal names and the label model shared by every labeller module.

Every per-frame signal value is a pair ``(score, label)``:

- ``score``: a float whose meaning is given by the module that computes it (documented there);
  ``nan`` where the input cannot support the signal.
- ``label``: ``1`` (present), ``0`` (absent) or :data:`UNKNOWN` (``-1``): the input cannot support
  the signal (no face at enough resolution, window not yet full, joints missing, ...). A module
  never guesses: it says UNKNOWN.

Label arrays are ``int8``; score arrays are ``float64``.
"""

from __future__ import annotations

import numpy as np

from counterpart.body.skeleton import JOINT_INDEX as JOINT_INDEX  # the project's joint order, re-exported
from counterpart.body.skeleton import JOINTS as JOINTS

#: the signals the labeller reports, in this order
SIGNALS: tuple[str, ...] = ("nod", "shake", "gaze_at_other", "activity", "talking", "laughing")

#: label value for "the input cannot support this signal"
UNKNOWN: int = -1


#: the torso joints used for activity (head and limbs excluded)
TORSO_JOINTS: tuple[str, ...] = ("l_shoulder", "r_shoulder", "l_hip", "r_hip")

#: (score, label) of a signal the input cannot support
UNKNOWN_VALUE: tuple[float, int] = (float("nan"), UNKNOWN)


def threshold_labels(score: np.ndarray, threshold: float) -> np.ndarray:
    """Labels from scores: ``1`` where ``score >= threshold``, ``0`` below, UNKNOWN where nan.

    Parameters
    ----------
    score : array_like of float
        Scores, any shape; ``nan`` where the signal is unknown.
    threshold : float
        Presence threshold.

    Returns
    -------
    ndarray of int8
        Labels, same shape as ``score``.
    """
    score = np.asarray(score, dtype=np.float64)
    lab = (score >= threshold).astype(np.int8)
    lab[np.isnan(score)] = UNKNOWN
    return lab


def labels_to_bool(labels: np.ndarray) -> np.ndarray:
    """Presence as bool for mining: ``1 -> True``; ``0`` and UNKNOWN -> False.

    UNKNOWN counts as "not observed present", which can only lower supports and confidences of
    rules that involve the signal; it never invents a co-occurrence.

    Parameters
    ----------
    labels : array_like of int or bool
        Labels ``1``, ``0`` or UNKNOWN, any shape; a bool array is returned as is.

    Returns
    -------
    ndarray of bool
        True where the label is ``1``, same shape as ``labels``.

    Raises
    ------
    ValueError
        If a label is not ``1``, ``0`` or UNKNOWN.
    """
    labels = np.asarray(labels)
    if labels.dtype == bool:
        return labels
    bad = ~np.isin(labels, (1, 0, UNKNOWN))
    if bad.any():
        raise ValueError(f"labels must be 1, 0 or {UNKNOWN} (UNKNOWN); found {np.unique(labels[bad])[:5]}")
    return labels == 1
