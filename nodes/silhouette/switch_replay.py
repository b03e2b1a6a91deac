"""A replay's frames around a switch of the camera between colour and monochrome, each given the
people of the background model of its own kind.

The switch is taken on the ``ColourSwitchConfig.frames``-th frame in a row of the other kind than
the model (``FrameResult.relearn``), and a new model is learnt from the frames from there. A live
graph cannot wait: the frames before the switch is taken go out with the old model's labels (of a
room it no longer matches: no one, or everyone), and those the new model learns from without
people. A replay (``process_frames``, the silhouette node's ``replay_training``) can hold them
back: :class:`SwitchReplay` holds the frames of the other kind while their run lasts, and from the
switch on as many as the new model learns from; the new model is fitted on the latter (robustly,
as a recording's first frames are) and they all go out then, in order, with its people. The fit
leaves out the run before the switch, so that the model is learnt from the frames a live graph's
is: learnt mid-interaction, whether it keeps a person who stands still out of the room turns on
a few frames more or less, and starting it earlier traded some clips for others.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Generic, TypeVar

import numpy as np

if TYPE_CHECKING:
    from .pipeline import FrameResult, SilhouetteExtractor

#: what goes out with a frame's result: the frame itself, or the message it came in
Item = TypeVar("Item")


class SwitchReplay(Generic[Item]):
    """Holds frames back around a switch between colour and monochrome (module docstring).

    Parameters
    ----------
    extractor : SilhouetteExtractor
        The extractor, its background already fitted (or an online backend, which never switches).
    train_frames : int, default=30
        Frames the background is fitted on again after a switch, from the one it was taken on.
    """

    def __init__(self, extractor: SilhouetteExtractor, train_frames: int = 30) -> None:
        self.extractor = extractor
        self.train_frames = train_frames
        #: frames of the other kind than the model, processed, while the switch is not taken yet
        self._run: list[tuple[Item, np.ndarray, FrameResult]] = []
        #: frames from the first of the run on, once the switch is taken, for the new model
        self._held: list[tuple[Item, np.ndarray]] = []
        #: how many of the held frames came before the switch was taken (not fitted on)
        self._before = 0

    def push(self, item: Item, frame: np.ndarray) -> list[tuple[Item, FrameResult]]:
        """Process one frame, or hold it back.

        Parameters
        ----------
        item : object
            What goes out with the frame's result.
        frame : ndarray of shape (H, W, 3), dtype uint8
            BGR frame.

        Returns
        -------
        list of (item, FrameResult)
            The frames whose results are final, in order (none while frames are held back); the
            first frame given the new model's people after a switch has ``relearn``.
        """
        if self._held:
            self._held.append((item, frame))
            return self._refitted() if len(self._held) - self._before >= self.train_frames else []
        result = self.extractor.process(frame)
        if result.relearn:
            self._held = [(it, f) for it, f, _ in self._run] + [(item, frame)]
            self._before, self._run = len(self._run), []
            self.extractor.rewind(len(self._held))
            return []
        if self.extractor.colour_switch.run > 0:
            self._run.append((item, frame, result))
            return []
        out = [(it, r) for it, _, r in self._run] + [(item, result)]
        self._run = []
        return out

    def flush(self) -> list[tuple[Item, FrameResult]]:
        """The frames still held back, the stream having ended: a run without a switch as it was
        processed; the frames around a switch with the people of a model fitted on those from it
        (with fewer than 2, only learnt, without people).
        """
        out = [(it, r) for it, _, r in self._run]
        self._run = []
        return out + self._refitted()

    def _refitted(self) -> list[tuple[Item, FrameResult]]:
        held, self._held = self._held, []
        fit = [f for _, f in held[self._before :]]
        if len(fit) >= 2:
            self.extractor.fit_background(fit, robust=True)
        step = self.extractor.process if len(fit) >= 2 else self.extractor.learn
        return [(it, dataclasses.replace(step(f), relearn=i == 0)) for i, (it, f) in enumerate(held)]


__all__ = ["SwitchReplay"]
