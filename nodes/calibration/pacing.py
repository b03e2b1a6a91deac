"""A share of one core for the calibration's estimates: the refinement waits when it has used more.

An estimate (the lines' and people's fits, several starts each) takes a large part of a second of
CPU, and on a scene where none is ever credible the node would re-estimate every ``every`` frames
for as long as the graph runs: most of a core on a small machine, taken from the nodes that keep up
with the camera. :class:`EstimatePacing` is a token bucket over the stream's time: an estimate is due
while the CPU time spent on estimates is at most ``share`` of the stream's seconds since the first
frame plus ``burst_s`` (so the first few estimates, which matter most, come at once).

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
    """

    share: float = 0.0
    burst_s: float = 3.0


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

    def due(self, time_s: float) -> bool:
        """Whether an estimate may run now.

        Parameters
        ----------
        time_s : float
            The stream's time of the current frame, seconds.

        Returns
        -------
        bool
            True without a share, or while the CPU spent is within the share of the time since the
            first call plus the burst.
        """
        if self.start_s is None:
            self.start_s = time_s
        if self.config.share <= 0:
            return True
        return self.spent_s <= self.config.share * (time_s - self.start_s) + self.config.burst_s

    def spend(self, cpu_s: float) -> None:
        """Count the CPU time of an estimate.

        Parameters
        ----------
        cpu_s : float
            Seconds of CPU it took.
        """
        self.spent_s += max(0.0, float(cpu_s))


__all__ = ["EstimatePacing", "PacingConfig"]
