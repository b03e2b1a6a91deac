"""One person of a conversation rendered alone: the recording the default video-texture avatar learns from."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from counterpart.body.pose import DOF_INDEX

from .render import Renderer
from .scenarios import Scenario, make_scenario


@dataclass
class ListenerRecording:
    """The right person of a ``conversation`` (who listens and nods half of the time and talks the
    other half) in view alone, after ``n_empty`` frames of the empty room.

    Parameters
    ----------
    scenario : Scenario
        The conversation with the speaker moved out of view and the empty start prepended.
    n_empty : int
        Frames of the empty room at the start.
    labels : ndarray of shape (T, K), dtype int8
        The listener's labels, -1 during the empty start, named ``names``.
    names : tuple of str
        The K label names.
    seed : int
        Seed of the renderer.

    Attributes
    ----------
    fps : float
        Frames per second.
    size : tuple of (int, int)
        Image (width, height), pixels.
    """

    scenario: Scenario
    n_empty: int
    labels: np.ndarray
    names: tuple[str, ...]
    seed: int

    @property
    def fps(self) -> float:
        return float(self.scenario.fps)

    @property
    def size(self) -> tuple[int, int]:
        return self._renderer.size

    def __post_init__(self) -> None:
        self._renderer = Renderer(self.scenario, seed=self.seed)

    def __len__(self) -> int:
        return int(self.scenario.poses_a.shape[0])

    def frames(self) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """Render every frame.

        Yields
        ------
        image : ndarray of shape (H, W, 3), dtype uint8
            The BGR frame.
        mask : ndarray of shape (H, W), dtype bool
            The listener's exact mask.
        """
        for i in range(len(self)):
            img, truth = self._renderer.render(i)
            yield img, truth.masks[1]


def listener_recording(
    seconds: float = 60.0, seed: int = 0, interested: bool = True, empty_s: float = 1.6
) -> ListenerRecording:
    """A ``conversation`` whose speaker is out of view, after an empty room.

    Parameters
    ----------
    seconds : float, default=60.0
        Length of the conversation, seconds.
    seed : int, default=0
        Seed of the scenario and the renderer.
    interested : bool, default=True
        Whether the listener is interested (the scenario's ``interested``).
    empty_s : float, default=1.6
        Seconds of the empty room before the listener comes into view.

    Returns
    -------
    ListenerRecording
        The recording.
    """
    sc = make_scenario(
        "conversation", seed=seed, duration=seconds, emotion="neutral", strength=0.0, interested=interested
    )
    n_empty = int(round(empty_s * sc.fps))
    away = sc.poses_a.copy()
    away[:, DOF_INDEX["root_x"]] -= 40.0  # far out of view: the listener alone in the picture
    gone = np.repeat(sc.poses_b[:1], n_empty, axis=0)
    gone[:, DOF_INDEX["root_x"]] += 40.0
    unknown = np.full((n_empty, len(sc.signal_names)), -1, np.int8)
    labels = np.concatenate([unknown, sc.signals_b])
    sc.poses_a = np.concatenate([np.repeat(away[:1], n_empty, axis=0), away])
    sc.poses_b = np.concatenate([gone, sc.poses_b])
    sc.signals_a, sc.signals_b = np.concatenate([unknown, sc.signals_a]), labels
    sc.phase = np.concatenate([np.zeros(n_empty, np.int32), sc.phase])
    return ListenerRecording(sc, n_empty, labels, tuple(sc.signal_names), seed)
