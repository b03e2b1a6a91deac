"""A noisy camera's frames smoothed before they are compared with the background (``denoise``):
the noise measured on the training frames, the Gaussian it sets, and the people found whole on a
noisy simulated camera where without it they fall apart.
"""

from __future__ import annotations

import numpy as np
import pytest

from counterpart.nodes.silhouette.denoise import DenoiseConfig, frame_noise, smooth, smoothing_sigma
from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor
from counterpart.sim.stream import open_stream
from tests.real_clips import clip_with_keypoints
from tests.shared_data import DATA


def _scene(n: int, noise: float, seed: int = 0) -> np.ndarray:
    """Frames (n) of a still textured room with a bright block crossing it, Gaussian noise added."""
    rng = np.random.default_rng(seed)
    room = rng.integers(40, 200, (60, 80, 3)).repeat(4, 0).repeat(4, 1).astype(np.float32)  # 240 x 320
    frames = []
    for t in range(n):
        f = room.copy()
        f[80:200, 10 + 12 * t : 50 + 12 * t] = 230.0  # a person walking across
        frames.append(np.clip(f + rng.normal(0, noise, f.shape), 0, 255).astype(np.uint8))
    return np.stack(frames)


def test_the_noise_is_measured_whatever_moves_or_the_exposure_does() -> None:
    for noise in (1.0, 6.0):
        frames = _scene(20, noise)
        assert frame_noise(frames) == pytest.approx(noise, rel=0.15)
        ramp = np.linspace(0.85, 1.15, 20)[:, None, None, None]  # the exposure settling
        assert frame_noise(np.clip(frames * ramp, 0, 255).astype(np.uint8)) == pytest.approx(noise, rel=0.25)
    with pytest.raises(ValueError, match="2 or more frames"):
        frame_noise(frames[:1])


def test_the_gaussian_grows_with_the_noise_over_the_floor_up_to_its_cap() -> None:
    c = DenoiseConfig()
    assert smoothing_sigma(c.floor, c) == 0.0 and smoothing_sigma(1.95, c) == 0.0  # the simulator's sensor
    assert smoothing_sigma(6.0, c) == pytest.approx(6.0 / c.noise_per_sigma)
    assert smoothing_sigma(40.0, c) == c.max_sigma
    frames = _scene(2, 6.0)
    first = frames[0]
    assert smooth(first, 0.0) is first
    assert frame_noise(np.stack([smooth(f, 2.0) for f in frames])) < 0.3 * frame_noise(frames)
    with pytest.raises(ValueError, match="noise_per_sigma"):
        DenoiseConfig(noise_per_sigma=0.0)


def _whole(labels: np.ndarray, kp: np.ndarray, vis: np.ndarray) -> bool:
    """Whether most of each reference person's visible keypoints (half) fall in one region of their
    own, the two regions apart.
    """
    ids = []
    for k in range(2):
        xy = np.rint(kp[k][vis[k] >= 0.5]).astype(int)
        xy = xy[(xy[:, 0] >= 0) & (xy[:, 0] < labels.shape[1]) & (xy[:, 1] >= 0) & (xy[:, 1] < labels.shape[0])]
        hit = labels[xy[:, 1], xy[:, 0]]
        if len(hit) == 0 or not hit.any():
            return False
        best = np.bincount(hit[hit > 0]).argmax()
        if np.mean(hit == best) < 0.5:
            return False
        ids.append(best)
    return ids[0] != ids[1]


def _apart(kp: np.ndarray, vis: np.ndarray) -> bool:
    """Whether the two reference people's visible keypoints lie apart across the frame (their
    spans of x do not overlap): one region each is then the right answer.
    """
    spans = sorted(
        (kp[k][vis[k] >= 0.5, 0].min(), kp[k][vis[k] >= 0.5, 0].max()) for k in range(2) if (vis[k] >= 0.5).sum() >= 4
    )
    return len(spans) == 2 and spans[0][1] < spans[1][0]


@pytest.mark.skipif(not (DATA / "ut_interaction").is_dir(), reason=f"no UT-Interaction clips in {DATA}")
def test_two_real_people_on_a_noisy_camera_stay_whole() -> None:
    # a tuning clip of bench/real_silhouettes.py with a low-light camera's noise added (6 grey levels)
    frames, kp, vis = clip_with_keypoints(DATA / "ut_interaction" / "set1" / "0_1_4.avi")
    rng = np.random.default_rng(1)
    noisy = np.clip(frames + rng.normal(0, 6.0, frames.shape), 0, 255).astype(np.uint8)
    share = {}
    for denoise in (True, False):
        ex = SilhouetteExtractor(backend_params={"train_frames": 20, "denoise": None if denoise else False})
        ex.fit_background(list(noisy[:20]))
        labels = [ex.process(f).labels for f in noisy]
        share[denoise] = np.mean(
            [_whole(labels[i], kp[i], vis[i]) for i in range(10, min(len(labels), len(kp))) if _apart(kp[i], vis[i])]
        )
        if denoise:
            assert ex.subtractor.noise_ == pytest.approx(6.0, abs=0.6) and ex.subtractor.smoothing_sigma_ == 2.0
    assert share[True] >= 0.9 and share[False] <= 0.3, share


def test_the_simulators_own_noise_is_left_alone() -> None:
    stream = open_stream("handshake", seed=0, frames=40)
    frames = [stream.render(i)[0] for i in range(40)]
    out = []
    for denoise in (True, False):
        ex = SilhouetteExtractor(backend_params={"train_frames": 20, "denoise": None if denoise else False})
        ex.fit_background(frames[:20])
        out.append([ex.process(f).labels for f in frames])
    assert ex.subtractor.noise_ < DenoiseConfig().floor
    assert all(np.array_equal(a, b) for a, b in zip(*out))


@pytest.mark.skipif(not (DATA / "ut_interaction").is_dir(), reason=f"no UT-Interaction clips in {DATA}")
def test_people_whose_boxes_fill_the_frame_give_the_plain_robust_fit_not_an_error() -> None:
    # two people standing still across a frame 244 pixels wide, noise of 6 grey levels: the people
    # detector's grown boxes leave no pixel seen as the room in enough training frames (this raised
    # "exclude leaves no pixel ..." from the fit)
    frames, _, _ = clip_with_keypoints(DATA / "ut_interaction" / "set1" / "58_10_1.avi")
    noisy = np.stack(
        [
            np.clip(f + np.random.default_rng([58, 10, 1, t]).normal(0.0, 6.0, f.shape), 0, 255).astype(np.uint8)
            for t, f in enumerate(frames[:40])
        ]
    )
    ex = SilhouetteExtractor(backend_params={"train_frames": 30})
    ex.fit_background(list(noisy[:30]))
    assert ex.subtractor.ready and not ex.subtractor.model.unseen_.any()  # the plain robust fit
    assert all(ex.process(f).labels.shape == f.shape[:2] for f in noisy[30:])
