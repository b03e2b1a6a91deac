"""A camera that switches between colour and monochrome while it runs: a day/night camera turning
to infrared as the room gets dark (and back at dawn), or a recording that cuts to grey footage.

The background model learnt in colour holds a colour for every pixel; an infrared frame of the
same room holds none, and its brightness is another (the room lit by the camera's own infrared
lamps, materials reflecting infrared otherwise). Its chromaticity distortion is large on every
pixel, so the whole room would be foreground from then on: no gain of the exposure follower
explains it, and the ghost absorption takes only regions that look like no one. The model must
be learnt again, from the new frames. A frame is told monochrome or colour by how far its
colours spread in chromaticity (``background.chroma_spread_deg``, the test the model's fit uses
to find monochrome footage, against its bound ``ShadowConfig.mono_chroma_deg``, widened both
ways so that a drab scene near the bound never switches back and forth); the switch is taken once
``frames`` frames in a row are of the other kind than the model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .background import chroma_spread_deg

#: pixels of a frame looked at (a regular grid): the spread of a thousand pixels is steady
_SAMPLE_PIXELS = 1_000
#: share of the sampled pixels that must be bright enough to have a colour (``chroma_spread_deg``'s
#: ``min_level``): a dark or fading frame tells neither
_MIN_BRIGHT_SHARE = 0.2
_MIN_LEVEL = 20.0


@dataclass(frozen=True)
class ColourSwitchConfig:
    """When a change between colour and monochrome frames is taken for the camera's.

    Parameters
    ----------
    frames : int, default=5
        Frames in a row of the other kind than the background model before the switch is taken
        (a sixth of a second at 30 fps: the few frames a camera takes to switch, and no single
        odd frame); 0: never.
    margin : float, default=2.0
        How far a frame's spread in chromaticity must lie from the model's bound b
        (``ShadowConfig.mono_chroma_deg``, degrees) to tell its kind: monochrome under b / margin,
        colour from b * margin on, neither between (>= 1). A drab colour scene spreads little more
        than b on some frames, a grey one through a codec a few tenths of a degree: the model learnt
        again from either is of the kind the frames told, so it never switches straight back.
    every : int, default=3
        While the frames are of the model's kind, only every this many-th is looked at (the look
        costs a few per cent of a frame's work otherwise); from one of the other kind on, every
        frame, so the switch is taken ``frames`` to ``frames + every - 1`` frames after it came (>= 1).

    Raises
    ------
    ValueError
        For ``frames`` < 0, ``margin`` < 1 or ``every`` < 1.
    """

    frames: int = 5
    margin: float = 2.0
    every: int = 3

    def __post_init__(self) -> None:
        if self.frames < 0:
            raise ValueError(f"colour switch frames must be >= 0 (0: never), got {self.frames}")
        if self.every < 1:
            raise ValueError(f"colour switch every must be >= 1, got {self.every}")
        if self.margin < 1.0:
            raise ValueError(f"colour switch margin must be >= 1, got {self.margin}")


def frame_kind(frame: np.ndarray, mono_deg: float, margin: float = 2.0) -> bool | None:
    """Whether a frame is monochrome (True), colour (False), or tells neither (None: too dark, or
    its colours spread between the two bounds).

    Parameters
    ----------
    frame : ndarray of shape (H, W, 3), dtype uint8
        BGR frame.
    mono_deg : float
        The background model's bound of monochrome footage, degrees (> 0).
    margin : float, default=2.0
        ``ColourSwitchConfig.margin``.

    Returns
    -------
    bool or None
        True monochrome, False colour, None undecided.
    """
    h, w = frame.shape[:2]
    step = max(1, int(np.sqrt(h * w / _SAMPLE_PIXELS)))
    sample = frame[step // 2 :: step, step // 2 :: step].reshape(-1, 3)
    bright = np.count_nonzero(sample.sum(axis=1, dtype=np.int32) >= 3 * _MIN_LEVEL)
    if bright < _MIN_BRIGHT_SHARE * len(sample):
        return None
    spread = chroma_spread_deg(sample, _MIN_LEVEL, every=1)
    if spread < mono_deg / margin:
        return True
    if spread >= mono_deg * margin:
        return False
    return None


class ColourSwitch:
    """Counts the frames in a row that are of the other kind than the background model, and says
    when the camera has switched (:meth:`update`).

    Parameters
    ----------
    config : ColourSwitchConfig or None, default=None
        The bounds; None: ``ColourSwitchConfig()``.
    """

    def __init__(self, config: ColourSwitchConfig | None = None) -> None:
        self.config = config or ColourSwitchConfig()
        #: frames in a row of the other kind than the model so far
        self.run = 0
        #: frames since the last look, while the run is 0
        self._since = 0
        #: the kind of frames the last switch was to: True monochrome, False colour (None: none yet)
        self.switched_to_mono: bool | None = None

    def update(self, frame: np.ndarray, model_mono: bool, mono_deg: float) -> bool:
        """Look at one frame against the model's kind.

        Parameters
        ----------
        frame : ndarray of shape (H, W, 3), dtype uint8
            BGR frame.
        model_mono : bool
            Whether the background model was learnt from monochrome frames.
        mono_deg : float
            The model's bound of monochrome footage (``ShadowConfig.mono_chroma_deg``, degrees);
            0 (the model is never monochrome): never a switch.

        Returns
        -------
        bool
            True on the ``config.frames``-th frame in a row of the other kind (then the count
            starts again); False otherwise (and on the frames not looked at, ``config.every``),
            and always with ``config.frames`` 0.
        """
        if self.config.frames == 0 or mono_deg <= 0.0:
            return False
        if self.run == 0:
            self._since += 1
            if self._since < self.config.every:
                return False
        self._since = 0
        kind = frame_kind(frame, mono_deg, self.config.margin)
        if kind is None or kind == model_mono:
            # an undecided frame breaks the run too: the switch is taken on clear frames only
            self.run = 0
            return False
        self.run += 1
        if self.run < self.config.frames:
            return False
        self.run = 0
        self.switched_to_mono = kind
        return True

    def reset(self) -> None:
        """Forget the run (a new background model); ``switched_to_mono`` stays."""
        self.run = 0
        self._since = 0
