"""A time budget per frame for the particle filters: fewer layers, then fewer particles, when the
frames come faster than ``layers x particles`` can be searched.

Layers go first: at the same number of likelihood evaluations a few layers of many particles
track better than many layers of few (``bench/tracker.py``: at about 480 evaluations per frame,
3 x 160 beats 5 x 96, 10 x 48 and 6 x 64), as too few particles per layer cannot cover the pose.

The cost of a frame is taken as proportional to the likelihood evaluations it makes
(``layers x particles`` per person tracked); the cost of one evaluation is learnt as the tracker
runs (an exponential moving average of the measured wall time per evaluation, so it follows the
load of the machine as well as the size of the frames). The per-frame overhead (observation maps,
kinematics of the estimate) is folded into that cost: the fixed point of ``evals = budget / cost``
with ``cost = (overhead + c * evals) / evals`` is ``evals = (budget - overhead) / c``, what fits.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class BudgetConfig:
    """Settings of a :class:`FrameBudget`.

    Parameters
    ----------
    share : float
        Share of the frame interval (1 / fps) that the search of all people of a frame may take;
        0: no budget (always ``layers x particles``).
    min_layers : int
        The fewest annealing layers it cuts to before it cuts particles.
    min_particles : int
        The fewest particles per layer it cuts to, once the layers are at ``min_layers``; fewer
        leaves too few survivors per layer (half of them at Deutscher's survival rate) to cover
        a 28-DOF pose.
    smoothing : float
        Weight of the newest measurement in the moving average of the cost, in (0, 1].
    """

    share: float = 0.0
    min_layers: int = 3
    min_particles: int = 32
    smoothing: float = 0.2


class FrameBudget:
    """Layers and particles per person for the next frame, from the time the last frames took.

    Parameters
    ----------
    layers, particles : int
        The search when time allows (the tracker's ``layers x particles``).
    config : BudgetConfig
        The budget.
    """

    def __init__(self, layers: int, particles: int, config: BudgetConfig) -> None:
        self.layers, self.particles, self.config = int(layers), int(particles), config
        #: seconds per likelihood evaluation (None until a frame was measured)
        self.cost_s: float | None = None

    def plan(self, n_people: int, fps: float) -> tuple[int, int]:
        """The search of each person on the next frame.

        Parameters
        ----------
        n_people : int
            People to track on it.
        fps : float
            The camera's frame rate, Hz (<= 0: unknown, no budget).

        Returns
        -------
        layers : int
            Annealing layers, in [min(min_layers, layers), layers].
        particles : int
            Particles per layer, in [min(min_particles, particles), particles], below
            ``particles`` only at ``min_layers`` layers.
        """
        cfg = self.config
        if cfg.share <= 0 or fps <= 0 or n_people < 1 or self.cost_s is None:
            return self.layers, self.particles
        evals = cfg.share / fps / self.cost_s / n_people  # per person
        if evals >= self.layers * self.particles:
            return self.layers, self.particles
        min_m = min(cfg.min_layers, self.layers)
        m = int(evals / self.particles)
        if m >= min_m:
            return m, self.particles
        return min_m, max(min(cfg.min_particles, self.particles), int(evals / min_m))

    def record(self, seconds: float, evals: int) -> None:
        """Learn the cost from one frame's search.

        Parameters
        ----------
        seconds : float
            Its wall time, s.
        evals : int
            The likelihood evaluations it made (layers x particles x people); 0: nothing learnt.
        """
        if evals <= 0:
            return
        c = seconds / evals
        a = self.config.smoothing
        self.cost_s = c if self.cost_s is None else (1 - a) * self.cost_s + a * c
