"""A share of one core for the calibration's estimates: the refinement waits when it has used more.

An estimate (the lines' and people's fits, several starts each) takes a large part of a second of
CPU, and on a scene where none is ever credible the node would re-estimate every ``every`` frames
for as long as the graph runs: most of a core on a small machine, taken from the nodes that keep up
with the camera. :class:`EstimatePacing` is a token bucket over the stream's time: an estimate is due
while the CPU time spent on estimates is at most ``share`` of the stream's seconds since the first
frame plus ``burst_s`` (so the first few estimates, which matter most, come at once).

Until the first credible estimate the camera the graph draws with is a default one, and an estimate
then is what matters most: with ``growth``, an estimate is due then whenever the people observed
have grown by that share since the last one, whatever the CPU spent (each has new evidence; one
without it would be a refit of what was not credible, the waste the share is there against, and the
node runs at a lower priority, ``nice``, in the real-time graph); from the first credible one the share
applies, counted from there with its burst.

The stream's time, not the wall clock, so a file replayed faster than it was filmed is paced by the
video; the CPU time measured, so the same graph can run a different number of estimates from run to
run: the real-time graph only (``launch/demo.yaml``); share 0 (the default) never waits, so a
lockstep replay stays deterministic.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class PacingConfig:
    """Settings of an :class:`EstimatePacing`.

    Parameters
    ----------
    share : float
        Share of one core the estimates may take on average, in (0, 1]; 0: no limit.
    burst_s : float
        CPU seconds the estimates may take at once before the share applies.
    growth : float
        Until the first credible estimate (:meth:`EstimatePacing.credible`), an estimate is due
        whenever the people observed have grown by this share since the last one, the share left
        aside; 0: the share alone from the start.
    """

    share: float = 0.0
    burst_s: float = 3.0
    growth: float = 0.0


class EstimatePacing:
    """Whether the next estimate is due, from the CPU time the earlier ones took.

    Parameters
    ----------
    config : PacingConfig
        The share and the burst.
    """

    def __init__(self, config: PacingConfig) -> None:
        self.config = config
        self.start_s: float | None = None
        self.spent_s = 0.0
        self.growing = config.growth > 0  # no credible estimate yet: the growth rule
        self.observed_at_last = 0  # the people observed at the last estimate

    def due(self, time_s: float, observed: int = 0) -> bool:
        """Whether an estimate may run now.

        Parameters
        ----------
        time_s : float
            The stream's time of the current frame, seconds.
        observed : int
            The people observed so far (views of upright people, all of them counted).

        Returns
        -------
        bool
            Before the first credible estimate with a ``growth``: whether ``observed`` is that share
            over the count at the last estimate. Otherwise True without a share, or while the CPU
            spent is within the share of the time since the first call (or the first credible
            estimate) plus the burst.
        """
        if self.start_s is None:
            self.start_s = time_s
        if self.growing:
            return observed >= (1.0 + self.config.growth) * self.observed_at_last
        if self.config.share <= 0:
            return True
        return self.spent_s <= self.config.share * (time_s - self.start_s) + self.config.burst_s

    def spend(self, cpu_s: float, observed: int = 0) -> None:
        """Count the CPU time of an estimate.

        Parameters
        ----------
        cpu_s : float
            Seconds of CPU it took.
        observed : int
            The people observed when it ran.
        """
        self.spent_s += max(0.0, float(cpu_s))
        self.observed_at_last = int(observed)

    def credible(self, time_s: float) -> None:
        """Say that an estimate was credible: from the first, the share applies, counted from
        ``time_s`` (the stream's seconds) with a fresh burst.

        Parameters
        ----------
        time_s : float
            The stream's time of the frame of that estimate, seconds.
        """
        if self.growing:
            self.growing = False
            self.start_s, self.spent_s = time_s, 0.0


__all__ = ["EstimatePacing", "PacingConfig"]
