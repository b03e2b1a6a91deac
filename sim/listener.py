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

    labels: (T, K) int8 of the listener, -1 during the empty start, named ``names``; fps: frames per
    second; size: (width, height) px.
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
        """(BGR image (H, W, 3) uint8, the listener's exact mask (H, W) bool) of every frame."""
        for i in range(len(self)):
            img, truth = self._renderer.render(i)
            yield img, truth.masks[1]


def listener_recording(
    seconds: float = 60.0, seed: int = 0, interested: bool = True, empty_s: float = 1.6
) -> ListenerRecording:
    """A ``conversation`` of ``seconds`` whose speaker is out of view, after ``empty_s`` s of the empty room."""
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
