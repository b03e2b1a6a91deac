"""A camera switching between colour and monochrome mid-stream (a day/night camera turning to
infrared): the switch is seen on clear frames only, and the background is learnt again from the
frames after it, on the simulator's rendered room and on a real clip.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from counterpart.nodes.silhouette.colour_switch import ColourSwitch, ColourSwitchConfig, frame_kind
from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor, process_frames
from counterpart.nodes.silhouette.switch_replay import SwitchReplay
from counterpart.sim.infrared import infrared_frames
from counterpart.sim.stream import open_stream
from tests.real_clips import UT_CLIP, clip_with_keypoints

TRAIN = 20
SWITCH = 40


@pytest.fixture(scope="module")
def handshake() -> tuple[np.ndarray, np.ndarray]:
    """The simulator's handshake (seed 0, people in view from frame 0): frames (N, H, W, 3) and
    the people's true masks (N, H, W) bool.
    """
    st = open_stream("handshake", seed=0, frames=100)
    frames, masks = zip(*((f, t.masks.any(axis=0)) for f, t in (st.renderer.render(i) for i in range(st.n_frames))))
    return np.stack(frames), np.stack(masks)


def grey(frames: np.ndarray) -> np.ndarray:
    return np.stack([cv2.cvtColor(cv2.cvtColor(f, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR) for f in frames])


def run(frames: np.ndarray, config: ColourSwitchConfig | None = None) -> tuple[list[int], list[np.ndarray]]:
    """The frames through ``process_frames`` (the background fitted on the first ``TRAIN``): the
    indices of the frames marked ``relearn`` and every frame's people labels.
    """
    ex = SilhouetteExtractor(backend_params={"train_frames": TRAIN}, colour_switch=config)
    ex.fit_background(list(frames[:TRAIN]))
    out = list(process_frames(ex, frames, TRAIN))
    assert len(out) == len(frames) and all(np.array_equal(f, g) for (f, _), g in zip(out, frames))  # in order
    assert [r.index for _, r in out] == list(range(len(frames)))  # held back and given again, each its own
    return [i for i, (_, r) in enumerate(out) if r.relearn], [r.labels for _, r in out]


def iou(labels: list[np.ndarray], masks: np.ndarray) -> np.ndarray:
    """Per frame, the intersection over union of the people's regions and the true people."""
    fg = np.stack(labels) > 0
    return (fg & masks).sum(axis=(1, 2)) / np.maximum((fg | masks).sum(axis=(1, 2)), 1)


def test_frames_are_told_monochrome_or_colour_only_when_clear(handshake):
    frame = handshake[0][0]
    assert frame_kind(frame, 1.0) is False
    assert frame_kind(grey(frame[None])[0], 1.0) is True
    # through a codec a grey picture stays grey; a tinted one (sepia, an infrared camera's cast) too
    jpeg = cv2.imdecode(cv2.imencode(".jpg", grey(frame[None])[0], [cv2.IMWRITE_JPEG_QUALITY, 70])[1], 1)
    assert frame_kind(jpeg, 1.0) is True
    tinted = np.clip(grey(frame[None])[0] * np.float32([0.8, 0.9, 1.0]), 0, 255).astype(np.uint8)
    assert frame_kind(tinted, 1.0) is True
    # a dark frame (a fade to black, lights out) tells neither
    assert frame_kind((frame // 16).astype(np.uint8), 1.0) is None
    # colours washed out to just over the bound: neither, so a drab room never switches back and forth
    g = grey(frame[None])[0].astype(np.float32)
    drab = frame.astype(np.float32)
    washed = [frame_kind(np.clip(g + a * (drab - g), 0, 255).astype(np.uint8), 1.0) for a in np.linspace(0, 1, 41)]
    assert washed[0] is True and washed[-1] is False
    assert None in washed
    first_colour = washed.index(False)
    assert all(k is None for k in washed[washed.index(None) : first_colour])


def test_the_switch_is_taken_on_the_fifth_clear_frame_in_a_row(handshake):
    colour, mono = handshake[0][10], grey(handshake[0][10:11])[0]
    sw = ColourSwitch(ColourSwitchConfig(every=1))
    assert [sw.update(mono, False, 1.0) for _ in range(4)] == [False] * 4
    assert sw.update(colour, False, 1.0) is False  # one frame of the model's kind starts the count again
    assert [sw.update(mono, False, 1.0) for _ in range(5)] == [False] * 4 + [True]
    assert sw.switched_to_mono is True
    # back to colour, against a monochrome model
    assert [sw.update(colour, True, 1.0) for _ in range(5)] == [False] * 4 + [True]
    assert sw.switched_to_mono is False
    # the default looks at every third frame of the model's kind, then at every frame: the switch
    # is taken 5 to 7 frames after it came
    sw = ColourSwitch()
    assert not any(sw.update(colour, False, 1.0) for _ in range(7))
    taken = [sw.update(mono, False, 1.0) for _ in range(8)]
    assert taken.count(True) == 1 and 4 <= taken.index(True) <= 6
    assert not any(ColourSwitch(ColourSwitchConfig(frames=0)).update(mono, False, 1.0) for _ in range(10))
    assert not any(ColourSwitch().update(mono, False, 0.0) for _ in range(10))
    with pytest.raises(ValueError, match="frames"):
        ColourSwitchConfig(frames=-1)
    with pytest.raises(ValueError, match="margin"):
        ColourSwitchConfig(margin=0.5)
    with pytest.raises(ValueError, match="every"):
        ColourSwitchConfig(every=0)


def test_a_room_turning_infrared_is_learnt_again_and_its_people_found(handshake):
    frames, masks = handshake
    ir = np.concatenate([frames[:SWITCH], infrared_frames(frames[SWITCH:])])
    relearns, labels = run(ir)
    # seen once (on the fifth to seventh infrared frame), the infrared frames held back from the
    # first looked at (every third frame is, while they are of the model's kind) get the new model's people
    assert len(relearns) == 1 and SWITCH <= relearns[0] <= SWITCH + 2
    late = slice(SWITCH + 7, None)  # the frames the new model was learnt from and those after
    after = np.median(iou(labels, masks)[late])
    # those before the switch was taken too, where the colour model's labels went out before
    assert np.median(iou(labels, masks)[SWITCH + 3 : SWITCH + 7]) > after - 0.1
    # as well as on footage infrared from the first frame (brightness alone tells people there)
    assert after > np.median(iou(run(infrared_frames(frames))[1], masks)[late]) - 0.15
    # kept as it was: the colour model calls much of the infrared room foreground, not the people
    relearns, kept = run(ir, ColourSwitchConfig(frames=0))
    assert relearns == []
    assert np.median(iou(kept, masks)[late]) < 0.2 and after > 0.4
    assert np.mean([(lab > 0).mean() for lab in kept[late]]) > 0.3
    # the scene as it is: never a switch
    assert run(frames)[0] == []


def test_a_room_turning_back_to_colour_is_learnt_again(handshake):
    frames, masks = handshake
    back = np.concatenate([infrared_frames(frames[:SWITCH]), frames[SWITCH:]])
    relearns, labels = run(back)
    assert len(relearns) == 1 and SWITCH <= relearns[0] <= SWITCH + 2
    # the infrared model kept finds the colour room changed, not the people
    after = np.median(iou(labels, masks)[SWITCH + 7 :])
    assert after > 0.6 and after > np.median(iou(run(back, ColourSwitchConfig(frames=0))[1], masks)[SWITCH + 7 :]) + 0.4


@pytest.mark.skipif(not UT_CLIP.exists(), reason=f"{UT_CLIP} not found (the shared real data is absent)")
def test_a_real_clip_turning_infrared_keeps_its_people():
    frames, kp, vis = clip_with_keypoints()
    ir = np.concatenate([frames[:50], infrared_frames(frames[50:])])

    def inside(fr: np.ndarray, config: ColourSwitchConfig | None = None) -> float:
        """Share of the visible reference keypoints of frames 60 on inside some person's region."""
        labels = run(fr, config)[1]
        hits = []
        for i in range(60, min(len(labels), len(kp))):
            xy = np.rint(kp[i][vis[i] >= 0.5]).astype(int)
            ok = (xy[:, 0] >= 0) & (xy[:, 0] < fr.shape[2]) & (xy[:, 1] >= 0) & (xy[:, 1] < fr.shape[1])
            hits.extend(labels[i][xy[ok, 1], xy[ok, 0]] > 0)
        return float(np.mean(hits))

    followed = inside(ir)
    # near footage infrared from the first frame, and far above the colour model kept
    assert followed > 0.75 and followed > inside(infrared_frames(frames)) - 0.15
    assert followed > 2 * inside(ir, ColourSwitchConfig(frames=0))


def test_a_few_grey_frames_are_held_and_then_go_out_as_they_were(handshake):
    """Three grey frames amid colour ones (too few for a switch) are held back while they could
    start one, then go out, in order, with the colour model's people as if never held.
    """
    frames, _ = handshake
    blip = frames.copy()
    blip[SWITCH : SWITCH + 3] = grey(frames[SWITCH : SWITCH + 3])
    ex = SilhouetteExtractor(backend_params={"train_frames": TRAIN})
    ex.fit_background(list(blip[:TRAIN]))
    replay: SwitchReplay[int] = SwitchReplay(ex, TRAIN)
    out = [replay.push(i, f) for i, f in enumerate(blip[: SWITCH + 6])]
    held = [i for i, done in enumerate(out) if not done]
    assert held and set(held) <= set(range(SWITCH, SWITCH + 3))  # from the first grey frame looked at
    released = [r for done in out for r in done]
    assert [i for i, _ in released] == list(range(SWITCH + 6)) and not any(r.relearn for _, r in released)
    assert [r.index for _, r in released] == list(range(SWITCH + 6)) and replay.flush() == []
    plain = SilhouetteExtractor(backend_params={"train_frames": TRAIN})
    plain.fit_background(list(blip[:TRAIN]))
    for (_, r), f in zip(released, blip):
        assert np.array_equal(r.labels, plain.process(f).labels)
    with pytest.raises(ValueError, match="cannot take back"):
        ex.rewind(ex.n_frames + 1)
