"""A time budget per frame for the particle filters: fewer layers, then fewer particles, when the
frames come faster than ``layers x particles`` can be searched.

Layers go first: at the same number of likelihood evaluations a few layers of many particles
track better than many layers of few (``bench/tracker.py``: at about 480 evaluations per frame,
3 x 160 beats 5 x 96, 10 x 48 and 6 x 64), as too few particles per layer cannot cover the pose.

The budget holds the tracker node's whole handler per frame, in CPU time (the process's, so that a
machine loaded by other processes does not make each frame look dearer, nor the tracker take more
than its share of the cores when it is idle). The cost of a frame is modelled from what the node
measures on each one::

    seconds = people x overhead + layers run x (a + c x particles)

``overhead``: everything but the annealing layers, per person tracked (the observation maps, the
prediction, the estimate's kinematics, the frame's edges and the message, shared out); each layer
of one person costs ``a`` (the calls: kinematics, projection, the annealing exponent, resampling,
whose cost hardly depends on how many particles they carry at a real-time frame's few dozen) plus
``c`` per particle. ``a`` and ``c`` are fitted to the mean layer cost measured at each particle
count the tracker has run (the full search of the first frames, the plans since); with one count
only, the layer cost is taken as proportional to the particles. Everything is learnt as the
tracker runs (exponential moving averages), so it follows the load and the size of the people.

On a loaded machine the tracker gets less than a core, and a frame's CPU budget can take longer
than a frame interval of wall-clock time, so that frames are dropped however well the budget is
kept. With ``wall_share`` the budget is also held in wall-clock time: the CPU time a frame may
take is at most ``wall_share / fps`` times the share of a core the tracker's frames have been
getting (their CPU time over their wall-clock time), so that under load it searches fewer
particles instead of losing frames; on an idle machine the CPU budget binds, as before.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class BudgetConfig:
    """Settings of a :class:`FrameBudget`.

    Parameters
    ----------
    share : float
        Share of the frame interval (1 / fps) of CPU time that the handling of a frame (all its
        people) may take; 0: no budget (always ``layers x particles``).
    min_layers : int
        The fewest annealing layers it cuts to before it cuts particles.
    min_particles : int
        The fewest particles per layer it cuts to, once the layers are at ``min_layers``; fewer
        leaves too few survivors per layer (half of them at Deutscher's survival rate) to cover
        a 28-DOF pose.
    smoothing : float
        Weight of the newest measurement in the moving averages of the costs, in (0, 1].
    counts_kept : int
        Particle counts whose layer cost is kept for the fit of ``a`` and ``c`` (the most recent).
    wall_share : float
        Share of the frame interval of wall-clock time the handling of a frame may take, at the
        share of a core the tracker has been getting; 0: the CPU budget alone.
    """

    share: float = 0.0
    min_layers: int = 3
    min_particles: int = 32
    smoothing: float = 0.2
    counts_kept: int = 8
    wall_share: float = 0.0


class FrameBudget:
    """Layers and particles per person for the next frame, from the CPU time the last frames took.

    Parameters
    ----------
    layers, particles : int
        The search when time allows (the tracker's ``layers x particles``).
    config : BudgetConfig
        The budget.
    """

    def __init__(self, layers: int, particles: int, config: BudgetConfig) -> None:
        self.layers, self.particles, self.config = int(layers), int(particles), config
        #: seconds per person and frame outside the annealing layers (None until measured)
        self.overhead_s: float | None = None
        #: particle count -> mean seconds of one annealing layer of one person at that count
        self.layer_s: dict[int, float] = {}
        #: the share of a core the frames have been getting: their CPU time over their wall time
        #: (None until measured)
        self.cpu_rate: float | None = None

    def _ema(self, old: float | None, new: float) -> float:
        a = self.config.smoothing
        return new if old is None else (1 - a) * old + a * new

    def layer_cost(self) -> tuple[float, float]:
        """The layer cost model ``a + c x particles`` (seconds per layer of one person).

        Returns
        -------
        a : float
            Seconds per layer whatever its particles (>= 0).
        c : float
            Seconds per particle (> 0).

        Raises
        ------
        ValueError
            Before any layer was measured.
        """
        if not self.layer_s:
            raise ValueError("no layer measured yet")
        n = np.array(list(self.layer_s), np.float64)
        t = np.array(list(self.layer_s.values()), np.float64)
        if len(n) >= 2 and n.max() >= 1.5 * n.min():
            c, a = np.polyfit(n, t, 1)
            if c > 0 and a >= 0:
                return float(a), float(c)
            if c > 0:  # a negative intercept: the proportional model through the fit
                return 0.0, float(t.sum() / n.sum())
        # one count (or no slope seen): the cost taken as proportional to the particles; an
        # overestimate of what more particles cost, an underestimate of what fewer save, so the
        # plan moves by steps that each new measurement corrects
        i = int(np.argmax(n))
        return 0.0, float(t[i] / n[i])

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
        if cfg.share <= 0 or fps <= 0 or n_people < 1 or self.overhead_s is None or not self.layer_s:
            return self.layers, self.particles
        a, c = self.layer_cost()
        # CPU seconds each person's layers may take
        avail = self.frame_cpu_s(fps) / n_people - self.overhead_s
        full = a + c * self.particles
        m = int(avail / full) if avail > 0 else 0
        if m >= self.layers:
            return self.layers, self.particles
        min_m = min(cfg.min_layers, self.layers)
        if m >= min_m:
            return m, self.particles
        n = int((avail / min_m - a) / c) if avail > 0 else 0
        return min_m, max(min(cfg.min_particles, self.particles), min(n, self.particles))

    def frame_cpu_s(self, fps: float) -> float:
        """The CPU seconds the next frame may take: ``share / fps``, and with ``wall_share`` at
        most ``wall_share / fps`` times the share of a core the frames have been getting.

        Parameters
        ----------
        fps : float
            The camera's frame rate, Hz (> 0).

        Returns
        -------
        float
            Seconds of CPU time.
        """
        cfg = self.config
        budget = cfg.share / fps
        if cfg.wall_share > 0 and self.cpu_rate is not None:
            budget = min(budget, cfg.wall_share / fps * self.cpu_rate)
        return budget

    def record(
        self,
        seconds: float,
        people: int,
        layers_run: int,
        particles: int,
        search_seconds: float,
        wall_seconds: float = 0.0,
    ) -> None:
        """Learn the costs from one frame.

        Parameters
        ----------
        seconds : float
            CPU time of the whole frame, s.
        people : int
            People searched on it (0: nothing learnt).
        layers_run : int
            Annealing layers run, summed over its people (a first search runs its own, longer
            schedule).
        particles : int
            Particles per layer.
        search_seconds : float
            CPU time of the layers (the searches), s; the rest of ``seconds`` is the overhead.
        wall_seconds : float, default=0.0
            Wall-clock time of the whole frame, s (0: not measured).
        """
        if wall_seconds > 0 and seconds > 0:
            self.cpu_rate = self._ema(self.cpu_rate, min(seconds / wall_seconds, 1.0))
        if people <= 0 or layers_run <= 0 or particles <= 0:
            return
        self.overhead_s = self._ema(self.overhead_s, max(seconds - search_seconds, 0.0) / people)
        key = int(particles)
        old = self.layer_s.pop(key, None)  # re-inserted last: the dict runs from oldest to newest
        self.layer_s[key] = self._ema(old, search_seconds / layers_run)
        while len(self.layer_s) > self.config.counts_kept:
            del self.layer_s[next(iter(self.layer_s))]


class StampRate:
    """The frame rate of a stream from its messages' capture stamps and frame numbers: the tracker's
    budget needs the camera's rate, which only the Frame carries, and in real time the frames are
    the input a busy tracker loses first (a ``latest`` queue keeps the newest, which then waits for
    silhouettes that come after the tracker has moved on), so that without it the budget would stay
    off exactly while the tracker is too slow.
    """

    def __init__(self) -> None:
        self.first: tuple[int, int] | None = None  # (seq, stamp ns)
        self.fps = 0.0

    def update(self, seq: int, stamp_ns: int) -> float:
        """Take one message; the rate over everything seen since the first (or since a restart).

        Parameters
        ----------
        seq : int
            Its frame number.
        stamp_ns : int
            Its capture stamp, ns (0: none, ignored).

        Returns
        -------
        float
            Frames per second, 0 until two frames apart in time were seen.
        """
        if stamp_ns <= 0:
            return self.fps
        if self.first is None or seq < self.first[0] or stamp_ns < self.first[1]:  # first, or a restart
            self.first, self.fps = (seq, stamp_ns), 0.0
        elif seq > self.first[0] and stamp_ns > self.first[1]:
            self.fps = (seq - self.first[0]) / ((stamp_ns - self.first[1]) / 1e9)
        return self.fps
