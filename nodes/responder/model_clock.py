"""Steps a per-frame interaction model at the frame rate it was trained at, whatever the input's.

The dual HMM, the GPDM and the listener rules learn their dynamics one frame at a time at the rate
of their training data (25 fps by default). Stepped once per input frame, a 30 fps camera would
play their responses 20% fast and a 15 fps one 40% slow. :class:`ModelClock` says at which moments
within each input interval the model's own frames fall, so that the node steps the model on those
moments with the observed person interpolated to them; :class:`AtModelRate` does both.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass
class ModelClock:
    """The model's frames that fall within each input interval.

    Parameters
    ----------
    fps : float
        The model's frame rate (frames per second), above 0.
    max_steps : int, default=4
        The most model frames one input frame steps; beyond it the rest of the interval is let go
        (after a dropout or while the node is behind, catching up would only delay it further).

    Raises
    ------
    ValueError
        ``fps`` not above 0 or ``max_steps`` below 1.
    """

    fps: float
    max_steps: int = 4
    _phase: float | None = field(default=None, init=False)  # model frames since its last step; None: none yet

    def __post_init__(self) -> None:
        if not self.fps > 0 or self.max_steps < 1:
            raise ValueError(f"ModelClock: fps must be > 0 and max_steps >= 1, got {self.fps} and {self.max_steps}")

    def reset(self) -> None:
        """Forget the time: the next input steps the model once, at once."""
        self._phase = None

    def advance(self, dt_s: float) -> np.ndarray:
        """The model's frames within the ``dt_s`` seconds since the previous input.

        Parameters
        ----------
        dt_s : float
            Seconds since the previous input frame (ignored for the first input after a reset).

        Returns
        -------
        ndarray of shape (k,)
            Where each model frame falls, as fractions in (0, 1] of the interval from the previous
            input (0) to this one (1), ascending; ``[1.0]`` for the first input; empty where no model
            frame falls within the interval (input faster than the model).
        """
        if self._phase is None:
            self._phase = 0.0
            return np.ones(1)
        if not dt_s > 0:
            return np.empty(0)
        span = dt_s * self.fps  # the interval in model frames
        # a model frame falls at 1 - phase, 2 - phase, ... model frames into the interval; the
        # tolerance keeps equal rates at exactly one step per input despite rounding
        k = int(np.floor(self._phase + span + 1e-9))
        at = np.arange(1, k + 1) - self._phase
        self._phase = max(self._phase + span - k, 0.0)
        return np.clip(at[-self.max_steps :] / span, 0.0, 1.0)


def interpolated(previous: np.ndarray | None, current: np.ndarray, at: np.ndarray) -> np.ndarray:
    """The observed joints at the model's frames within one input interval.

    Parameters
    ----------
    previous : ndarray of shape (J, 3) or None
        The joints of the previous input frame (metres); None: the current ones throughout.
    current : ndarray of shape (J, 3)
        The joints of this input frame, metres.
    at : ndarray of shape (k,)
        Fractions of the interval (:meth:`ModelClock.advance`).

    Returns
    -------
    ndarray of shape (k, J, 3)
        Linear interpolation from ``previous`` (0) to ``current`` (1).
    """
    cur = np.asarray(current, np.float64)
    prev = cur if previous is None or np.shape(previous) != cur.shape else np.asarray(previous, np.float64)
    a = np.asarray(at, np.float64)[:, None, None]
    return prev[None] + a * (cur - prev)[None]


@dataclass
class AtModelRate:
    """A per-frame model stepped on its own frames (:class:`ModelClock`) from input at any rate.

    Parameters
    ----------
    clock : ModelClock
        The model's frame rate and the most steps one input may take.
    """

    clock: ModelClock
    _last: tuple[float, np.ndarray | None, Any] | None = field(default=None, init=False)  # time, joints, output

    @classmethod
    def for_model(cls, model: Any, default_fps: float) -> AtModelRate:
        """The stepper of a loaded model at its training frame rate (its ``fps_``, the listener's
        ``fps``), ``default_fps`` where it has none.
        """
        return cls(ModelClock(float(getattr(model, "fps_", 0.0) or getattr(model, "fps", 0.0) or default_fps)))

    def reset(self) -> None:
        """Forget the time and the last input: the next one steps the model once, at once."""
        self.clock.reset()
        self._last = None

    def __call__(self, step: Callable[[np.ndarray | None], Any], observed: np.ndarray | None, t_s: float) -> Any:
        """The model's output for the input frame at ``t_s``.

        Parameters
        ----------
        step : callable
            One frame of the model: the observed joints (ndarray of shape (J, 3), metres, or None)
            in, its output out.
        observed : ndarray of shape (J, 3) or None
            The observed person's joints on this input frame, metres; None: nobody observed.
        t_s : float
            The input frame's time, seconds; one not after the last input's starts afresh.

        Returns
        -------
        object
            What ``step`` returned on the last of the model's frames up to ``t_s`` (they are stepped
            on ``observed`` interpolated from the last input's joints), or the last output where no
            model frame fell since the last input.
        """
        if self._last is not None and t_s <= self._last[0]:
            self.reset()
        last = self._last
        at = self.clock.advance(0.0 if last is None else t_s - last[0])
        out = None if last is None else last[2]
        if observed is None:
            for _ in at:
                out = step(None)
        else:
            for x in interpolated(None if last is None else last[1], observed, at):
                out = step(x)
        self._last = (t_s, None if observed is None else np.array(observed, np.float64), out)
        return out
