"""Horprasert background model and the subtractor backends on synthetic pixels.

The scene: a smoothly textured background whose chromaticity varies over the image, Gaussian
sensor noise (sigma 2.5 grey levels) in every frame, a person-like ellipse of a colour the
background never has, and a cast shadow that is the background times 0.6 (same chromaticity).
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from counterpart.nodes.silhouette.backends import BACKEND_NAMES, make_subtractor
from counterpart.nodes.silhouette.background import (
    BACKGROUND,
    FOREGROUND,
    HIGHLIGHT,
    SHADOW,
    AdaptationConfig,
    GhostConfig,
    HorprasertBackground,
    ShadowConfig,
    ThresholdConfig,
    _surround_near_candidates,
    chroma_spread_deg,
)
from counterpart.nodes.silhouette.body_shadow import BodyShadowConfig, reclaim_body_shadow
from tests.real_clips import (
    UT_CLIP,
    clip_labels,
    clip_with_keypoints,
    keypoints_inside,
    labels_cover,
    labels_of,
    people_share,
)

H, W = 120, 160
YY, XX = np.mgrid[0:H, 0:W]
BG = np.stack(
    [
        90 + 40 * np.sin(XX / 9.0) + 10 * np.cos(YY / 5.0),
        130 + 40 * np.cos(YY / 11.0 + XX / 23.0),
        110 + 35 * np.sin((XX + YY) / 13.0),
    ],
    axis=-1,
).astype(np.float32)
PERSON_BGR = (200.0, 60.0, 40.0)
SHADOW_BOX = (slice(80, 110), slice(20, 70))


def person_mask(cx: float, cy: float = 60.0, rx: float = 15.0, ry: float = 35.0) -> np.ndarray:
    return ((XX - cx) / rx) ** 2 + ((YY - cy) / ry) ** 2 < 1.0


def render(
    rng: np.random.Generator,
    person_x: float | None = None,
    shadow: bool = False,
    gains: tuple[float, float, float] = (1.0, 1.0, 1.0),
) -> np.ndarray:
    f = BG * np.asarray(gains, np.float32) + rng.normal(0.0, 2.5, BG.shape)
    if shadow:
        f[SHADOW_BOX] *= 0.6
    if person_x is not None:
        f[person_mask(person_x)] = PERSON_BGR
    return np.clip(np.rint(f), 0, 255).astype(np.uint8)


@pytest.fixture(scope="module")
def empty_frames() -> np.ndarray:
    rng = np.random.default_rng(0)
    return np.stack([render(rng) for _ in range(30)])


def class_fractions(labels: np.ndarray, region: np.ndarray) -> np.ndarray:
    return np.bincount(labels[region].ravel(), minlength=4) / region.sum()


def test_person_is_foreground_shadow_is_shadow_background_is_background(empty_frames):
    model = HorprasertBackground().fit(empty_frames)
    rng = np.random.default_rng(1)
    labels = model.apply(render(rng, person_x=110.0, shadow=True))
    assert labels.shape == (H, W) and labels.dtype == np.uint8
    blob = person_mask(110.0)
    shadow = np.zeros((H, W), bool)
    shadow[SHADOW_BOX] = True
    rest = ~blob & ~shadow
    fb, fs, fr = class_fractions(labels, blob), class_fractions(labels, shadow), class_fractions(labels, rest)
    assert fb[FOREGROUND] > 0.99
    assert fs[SHADOW] > 0.97 and fs[FOREGROUND] < 0.02
    assert fr[BACKGROUND] > 0.98 and fr[FOREGROUND] < 0.01


def test_thresholds_are_chosen_from_training_distortions(empty_frames):
    model = HorprasertBackground(ThresholdConfig(detection_rate=0.999)).fit(empty_frames)
    t = model.thresholds_
    assert t["tau_alpha_lo"] < t["tau_alpha2"] < 0.0 < t["tau_alpha1"]
    # On the training frames themselves the detection rate is met by construction.
    alpha_hat, cd_hat = model.distortions(empty_frames[3])
    assert np.mean(cd_hat <= t["tau_cd"]) > 0.99
    # Sensor noise of 2.5 grey levels on ~100-level pixels: RMS brightness distortion ~1-3 %.
    assert 0.005 < float(np.median(model.a_)) < 0.05
    stricter = HorprasertBackground(ThresholdConfig(detection_rate=0.99)).fit(empty_frames)
    assert stricter.thresholds_["tau_cd"] < t["tau_cd"]


def test_brighter_same_chromaticity_is_highlight_darker_is_shadow(empty_frames):
    model = HorprasertBackground().fit(empty_frames)
    rng = np.random.default_rng(2)
    lab_hi = model.apply(render(rng, gains=(1.3, 1.3, 1.3)))
    lab_lo = model.apply(render(rng, gains=(0.7, 0.7, 0.7)))
    assert np.mean(lab_hi == HIGHLIGHT) > 0.95
    assert np.mean(lab_lo == SHADOW) > 0.95


def test_slow_lighting_drift_is_absorbed_not_foreground(empty_frames):
    """A 200-frame drift of brightness and white balance (R +12 %, G +5 %, B -8 %)."""
    adaptive = HorprasertBackground().fit(empty_frames)
    frozen = HorprasertBackground(adaptation=AdaptationConfig(learning_rate=0.0)).fit(empty_frames)
    rng = np.random.default_rng(3)
    worst_fg = 0.0
    for k in range(200):
        t = k / 199.0
        frame = render(rng, gains=(1.0 - 0.08 * t, 1.0 + 0.05 * t, 1.0 + 0.12 * t))
        labels = adaptive.apply_update(frame)
        worst_fg = max(worst_fg, float(np.mean(labels == FOREGROUND)))
    assert worst_fg < 0.01
    assert np.mean(labels == BACKGROUND) > 0.95
    # Without adaptation the same final frame is mostly foreground: the test measures something.
    assert np.mean(frozen.apply(frame) == FOREGROUND) > 0.5
    drifted = BG * np.asarray((0.92, 1.05, 1.12), np.float32)
    assert np.median(np.abs(adaptive.mean_ - drifted)) < 2.0


def test_person_never_enters_the_model_while_standing_still(empty_frames):
    model = HorprasertBackground(adaptation=AdaptationConfig(learning_rate=0.2)).fit(empty_frames)
    rng = np.random.default_rng(4)
    for _ in range(40):
        labels = model.apply_update(render(rng, person_x=80.0))
    assert class_fractions(labels, person_mask(80.0))[FOREGROUND] > 0.99


def test_robust_fit_learns_background_with_a_person_in_every_training_frame():
    rng = np.random.default_rng(5)
    # The person walks across the whole width during training: every frame has them.
    train = np.stack([render(rng, person_x=20.0 + 4.0 * k) for k in range(30)])
    robust = HorprasertBackground().fit(train, robust=True)
    plain = HorprasertBackground().fit(train)
    err_robust = np.abs(robust.mean_ - BG).max(axis=2)
    err_plain = np.abs(plain.mean_ - BG).max(axis=2)
    assert np.percentile(err_robust, 99) < 4.0
    assert np.percentile(err_plain, 99) > 15.0  # the mean is smeared by the walker
    labels = robust.apply(render(rng, person_x=100.0, shadow=True))
    blob = person_mask(100.0)
    assert class_fractions(labels, blob)[FOREGROUND] > 0.99
    assert class_fractions(labels, ~blob)[FOREGROUND] < 0.02
    # The plain fit, polluted by the walker, misses most of the person.
    assert class_fractions(plain.apply(render(rng, person_x=100.0)), blob)[FOREGROUND] < 0.5


def test_fit_rejects_bad_input(empty_frames):
    with pytest.raises(ValueError, match="at least 2"):
        HorprasertBackground().fit(empty_frames[:1])
    with pytest.raises(ValueError, match="uint8"):
        HorprasertBackground().fit(empty_frames.astype(np.float32))
    model = HorprasertBackground().fit(empty_frames)
    with pytest.raises(ValueError, match="shape"):
        model.apply(np.zeros((10, 10, 3), np.uint8))
    with pytest.raises(RuntimeError, match="fit"):
        HorprasertBackground().apply(empty_frames[0])


@pytest.mark.parametrize("name", BACKEND_NAMES)
def test_every_backend_constructs_and_finds_the_person(name):
    params = {"train_frames": 20} if name == "horprasert" else {}
    sub = make_subtractor(name, **params)
    rng = np.random.default_rng(6)
    for _ in range(40):
        mask = sub.apply(render(rng))
    assert sub.ready
    for k in range(3):
        mask = sub.apply(render(rng, person_x=60.0 + 2 * k))
    assert mask.shape == (H, W) and mask.dtype == bool
    assert sub.labels is not None and sub.labels.shape == (H, W)
    assert set(np.unique(sub.labels)) <= {BACKGROUND, SHADOW, HIGHLIGHT, FOREGROUND}
    blob = person_mask(64.0)
    assert mask[blob].mean() > 0.5, f"{name} found {mask[blob].mean():.2f} of the person"
    assert mask[~person_mask(64.0, rx=22, ry=42)].mean() < 0.05


def test_mog2_reports_shadows_as_background_class():
    sub = make_subtractor("mog2")
    rng = np.random.default_rng(7)
    for _ in range(60):
        sub.apply(render(rng))
    mask = sub.apply(render(rng, shadow=True))
    shadow = np.zeros((H, W), bool)
    shadow[SHADOW_BOX] = True
    assert np.mean(sub.labels[shadow] == SHADOW) > 0.5
    assert mask[shadow].mean() < 0.2


def test_unknown_backend_and_parameter_are_value_errors():
    with pytest.raises(ValueError, match="horprasert, mog2, knn, cnt, gsoc"):
        make_subtractor("vibe")
    with pytest.raises(ValueError, match="histroy"):
        make_subtractor("mog2", histroy=100)
    with pytest.raises(ValueError, match="unknown parameter"):
        make_subtractor("horprasert", tau=3.0)


def test_flat_parameters_are_routed_to_their_config_groups():
    model = HorprasertBackground.from_params(learning_rate=0.02, shadow_ncc=0.4, absorb_frames=5, detection_rate=0.99)
    assert model.adaptation == AdaptationConfig(learning_rate=0.02)
    assert model.shadows == ShadowConfig(shadow_ncc=0.4)
    assert model.ghosts == GhostConfig(absorb_frames=5)
    assert model.thresholds == ThresholdConfig(detection_rate=0.99)
    assert set(model.get_params()) == {"thresholds", "adaptation", "shadows", "training", "ghosts"}
    with pytest.raises(ValueError, match="'learning_rat'.*learning_rate"):
        HorprasertBackground.from_params(learning_rat=0.02)
    with pytest.raises(ValueError, match="shadow_window"):
        ShadowConfig(shadow_window=4)
    with pytest.raises(TypeError, match="adaptation must be a AdaptationConfig"):
        HorprasertBackground(adaptation={"learning_rate": 0.02})


def test_dark_clothes_inside_a_body_are_foreground_cast_shadows_stay_shadows():
    # a belt-high band of the person as dark as a shadow with the room's chromaticity (dark
    # trousers on a grey room), a cast shadow at the feet and one far off on the floor
    band = person_mask(110.0) & (YY >= 56) & (YY < 66)
    feet = np.zeros((H, W), bool)
    feet[86:106, 112:146] = True
    feet &= ~person_mask(110.0)
    far = np.zeros((H, W), bool)
    far[SHADOW_BOX] = True

    def run(config: BodyShadowConfig | None) -> np.ndarray:
        sub = make_subtractor("horprasert", train_frames=20, body_shadow=config)
        rng = np.random.default_rng(7)
        for _ in range(20):
            sub.apply(render(rng))
        f = render(rng, person_x=110.0, shadow=True).astype(np.float32)
        f[feet] = BG[feet] * 0.6
        f[band] = BG[band] * 0.6
        sub.apply(np.clip(np.rint(f), 0, 255).astype(np.uint8))
        return sub.labels

    off = run(BodyShadowConfig(span_px=0))  # off: the statistics' own labels
    assert class_fractions(off, band)[SHADOW] > 0.9
    on = run(None)  # the default
    assert class_fractions(on, band)[FOREGROUND] > 0.95
    assert class_fractions(on, feet)[SHADOW] > 0.95
    assert class_fractions(on, far)[SHADOW] > 0.95
    assert class_fractions(on, person_mask(110.0) & ~band)[FOREGROUND] > 0.99


@pytest.mark.parametrize("scale", [1, 2])
def test_legs_below_a_body_are_foreground_a_cast_shadow_there_keeps_the_floor_texture(scale):
    """Trousers of the floor's colour, darker, hang from the torso: shadow by colour, but flat,
    where a cast shadow under the same torso keeps the floor's pattern. The floor's pattern is
    too weak for the model's own texture test (``shadow_texture_k``), not for the leg step's, on
    the pixels or on 2 x 2 blocks (``leg_scale``).
    """
    rng = np.random.default_rng(5)
    hh, ww = 120, 160
    floor = np.repeat(np.repeat(rng.uniform(125, 145, (hh // 4, ww // 4)), 4, 0), 4, 1)[..., None]
    floor = floor * np.float32([0.9, 1.0, 1.1])
    # the trousers reach the shoes (one region with the torso), the cast shadow does not; the
    # leg step takes ``leg_depth`` of the body's height (76 rows) below the torso, 7 rows
    trousers, cast = (slice(60, 90), slice(62, 73)), (slice(60, 65), slice(78, 89))
    legs = (slice(60, 67), trousers[1])

    def shot(person: bool) -> np.ndarray:
        f = floor + rng.normal(0.0, 2.0, floor.shape)
        if person:
            f[20:60, 60:91] = PERSON_BGR  # torso
            f[90:96, 62:89] = PERSON_BGR  # shoes: the body's lowest rows
            f[trousers] = 0.6 * floor[trousers].mean(axis=(0, 1))
            f[cast] = 0.6 * floor[cast]
        return np.clip(np.rint(f), 0, 255).astype(np.uint8)

    def labels(config: BodyShadowConfig) -> np.ndarray:
        sub = make_subtractor("horprasert", train_frames=20, robust=False, dynamic=False, body_shadow=config)
        for _ in range(20):
            sub.apply(shot(False))
        sub.apply(shot(True))
        return sub.labels

    off = labels(BodyShadowConfig(leg_ncc=-1.0))
    assert (off[legs] == SHADOW).mean() > 0.9 and (off[cast] == SHADOW).mean() > 0.9
    on = labels(BodyShadowConfig(leg_scale=scale))
    assert (on[legs] == FOREGROUND).mean() > 0.75  # a flat window correlates by chance now and then
    assert (on[cast] == SHADOW).mean() > 0.9


def test_leg_correlation_on_blocks_is_the_weighted_correlation_of_the_blocks_shadow_means():
    """``leg_scale`` 2: at each candidate, the correlation of the 2 x 2 blocks' mean grey levels over
    their shadow pixels, frame against background, weighted by those pixels' number, over the 3 x 3
    blocks around the candidate's (brute force in float64, away from the box's edges).
    """
    from counterpart.nodes.silhouette.body_shadow import _block_ncc

    rng = np.random.default_rng(3)
    hh, ww = 24, 30
    sh = np.where(rng.random((hh, ww)) < 0.7, 255, 0).astype(np.uint8)  # a 0 / 255 mask, as the step's
    m = sh / 255.0
    e = rng.normal(400.0, 60.0, (hh, ww)).astype(np.float32)
    frame = np.clip(np.rint((0.2 * e + rng.normal(0.0, 15.0, (hh, ww)))[..., None] * [0.3, 0.4, 0.3]), 0, 255)
    frame = frame.astype(np.uint8)
    grey = frame.sum(axis=2)
    ys, xs = np.meshgrid(np.arange(2, hh - 2), np.arange(2, ww - 2), indexing="ij")
    ys, xs = ys.ravel(), xs.ravel()
    got = _block_ncc(sh, frame, e, ys, xs, 2, 3)
    blocks = lambda a: a.astype(np.float64).reshape(hh // 2, 2, ww // 2, 2).sum(axis=(1, 3))  # noqa: E731
    n, g, eb = blocks(m), blocks(grey * m), blocks(e * m)
    want = np.empty(ys.size)
    for i, (y, x) in enumerate(zip(ys // 2, xs // 2)):
        win = (slice(y - 1, y + 2), slice(x - 1, x + 2))
        wgt, has = n[win], n[win] > 0
        gm, em = g[win][has] / wgt[has], eb[win][has] / wgt[has]
        wgt = wgt[has]
        mg, me = np.average(gm, weights=wgt), np.average(em, weights=wgt)
        vg, ve = np.average((gm - mg) ** 2, weights=wgt), np.average((em - me) ** 2, weights=wgt)
        cov = np.average((gm - mg) * (em - me), weights=wgt)
        want[i] = cov / np.sqrt(vg * ve)
    assert np.allclose(got, want, atol=2e-3)
    assert 0.2 < want.mean() < 0.9  # the frame follows the background, with noise


def test_the_leg_step_leaves_unseen_background_and_wide_shadows_alone():
    # where the room was filled in (someone stood there through training) its texture is a
    # guess: a flat shadow hanging from foreground there stays a shadow; so does one wider than
    # a leg
    rng = np.random.default_rng(6)
    background = rng.uniform(300, 420, (60, 40)).astype(np.float32)
    frame = np.clip(rng.normal(70.0, 2.0, (60, 40, 3)), 0, 255).astype(np.uint8)  # flat trousers
    lab = np.zeros((60, 40), np.uint8)
    lab[5:30, 10:30] = FOREGROUND
    lab[30:50, 14:20] = SHADOW  # a leg down to the shoe: one region
    lab[50:55, 14:20] = FOREGROUND
    config = BodyShadowConfig()
    assert (reclaim_body_shadow(lab, config, frame, background)[30:33, 14:20] == FOREGROUND).all()
    unseen = np.zeros((60, 40), bool)
    unseen[28:40] = True
    assert (reclaim_body_shadow(lab, config, frame, background, unseen)[30:33, 14:20] == SHADOW).all()
    assert (reclaim_body_shadow(lab, config)[30:33, 14:20] == SHADOW).all()  # no frame: no leg step
    wide = lab.copy()
    wide[30:50, 2:38] = SHADOW  # spreading over the floor wider than a leg: a cast shadow
    assert (reclaim_body_shadow(wide, config, frame, background)[30:33, 14:20] == SHADOW).all()


def test_foreground_indices_from_the_caller_give_the_same_update_and_body_shadow(empty_frames):
    """``update`` and ``reclaim_body_shadow`` take the FOREGROUND pixels' flat indices from a caller
    that has them (the subtractor's veto): the model and the labels are those of finding them.
    """
    rng = np.random.default_rng(12)
    found = HorprasertBackground().fit(empty_frames, robust=True)
    given = HorprasertBackground().fit(empty_frames, robust=True)
    config = BodyShadowConfig()
    for k in range(6):
        frame = render(rng, person_x=40.0 + 8 * k, shadow=True)
        labels = found.apply(frame)
        np.testing.assert_array_equal(given.apply(frame), labels)
        fg_idx = np.flatnonzero(labels == FOREGROUND)
        assert fg_idx.size > 100
        grey = found.grey_
        np.testing.assert_array_equal(
            reclaim_body_shadow(labels, config, frame, grey, fg_idx=fg_idx),
            reclaim_body_shadow(labels, config, frame, grey),
        )
        found.update(frame, labels)
        given.update(frame, labels, fg_idx)
        np.testing.assert_array_equal(given.mean_, found.mean_)
        np.testing.assert_array_equal(given.spread_, found.spread_)


@pytest.mark.parametrize(
    "bad",
    [
        {"span_px": -1},
        {"foot_fraction": 1.0},
        {"foot_fraction": -0.1},
        {"edge_px": -1},
        {"leg_ncc": 1.5},
        {"leg_depth": 0.0},
        {"leg_foot": 1.0},
        {"leg_width": 0.0},
        {"leg_window": 4},
        {"leg_scale": 0},
    ],
)
def test_body_shadow_config_rejects_bad_values(bad):
    with pytest.raises(ValueError, match=next(iter(bad))):
        BodyShadowConfig(**bad)


def test_a_black_background_pixel_has_no_brightness_direction() -> None:
    # a dead-black patch (a screen that is off, a clipped shadow): alpha is 0 there, so black
    # stays background, and any colour that appears on it is chromaticity, foreground
    rng = np.random.default_rng(11)
    frames = np.stack([render(rng) for _ in range(20)])
    frames[:, 10:30, 100:140] = 0
    model = HorprasertBackground().fit(frames, robust=False)
    still = frames[-1].copy()
    lit = still.copy()
    lit[15:25, 110:130] = 120
    labels = model.apply(still)
    assert (labels[10:30, 100:140] == BACKGROUND).all()
    labels = model.apply(lit)
    assert (labels[15:25, 110:130] == FOREGROUND).all()
    assert np.isfinite(model._inv_den).all() and (model._inv_den[10:30, 100:140] == 0.0).all()
    model.update(lit, labels)  # the per-frame terms are made again after each update
    assert (model.apply(still)[10:30, 100:140] == BACKGROUND).all()


def test_update_every_learns_one_frame_in_n_at_the_same_decay_per_frame(empty_frames):
    """With ``update_every`` 2 the model learns from the first frame of each pair, at the rate 2 r,
    so that after each pair E is about where learning every frame at r puts it ((1 - r)^2 against
    1 - 2 r: 0.25% of the step apart at r = 0.05); the ghost runs count the learnt frames.
    """
    rng = np.random.default_rng(5)
    # each frame twice: learning from both of a pair at r is learning from the first at 1 - (1 - r)^2
    frames = [f for f in (render(rng, gains=(1.02, 1.02, 1.02)) for _ in range(3)) for _ in range(2)]
    every = HorprasertBackground(adaptation=AdaptationConfig(update_every=1)).fit(empty_frames, robust=True)
    halves = HorprasertBackground().fit(empty_frames, robust=True)
    assert halves.adaptation.update_every == 2
    assert every.absorb_frames_ == halves.absorb_frames_ == 10
    for k, f in enumerate(frames):
        assert halves.learns_next == (k % 2 == 0)
        before = halves.mean_.copy()
        labels = every.apply_update(f)
        halves.apply_update(f)
        assert np.mean(labels == BACKGROUND) > 0.9
        if k % 2:
            # the skipped frame leaves E as it was; after the pair both models agree
            np.testing.assert_array_equal(halves.mean_, before)
            gap = np.abs(halves.mean_ - every.mean_)
            # (a few pixels near a class boundary may be classed apart and learnt at another rate)
            assert np.median(gap) < 0.02 and np.percentile(gap, 99) < 0.1, (np.median(gap), np.percentile(gap, 99))
    assert np.abs(halves.mean_ - empty_frames.mean(axis=0)).max() > 0.5  # it did learn
    with pytest.raises(ValueError, match="update_every"):
        AdaptationConfig(update_every=0)


@pytest.mark.parametrize("shape", [(37, 42), (36, 42), (37, 40), (40, 44)])
def test_ghost_surround_on_frames_whose_sides_are_not_multiples_of_4(shape):
    """The surround of ghost candidates, worked out on crops around them, equals the same 4 x 4
    block means and box filter over the whole frame extended to whole blocks by reflection, the
    part cells at the far edges included; the side of a candidate's cell does not matter.
    """
    rng = np.random.default_rng(sum(shape))
    h, w = shape
    mu = rng.uniform(0.0, 255.0, (3, h, w)).astype(np.float32)
    fg = rng.random((h, w)) < 0.4
    k = 5
    ph, pw = -(-h // 4) * 4 - h, -(-w // 4) * 4 - w

    def whole(a: np.ndarray) -> np.ndarray:  # block means and box over the extended frame
        a = cv2.copyMakeBorder(a, 0, ph, 0, pw, cv2.BORDER_REFLECT)
        small = cv2.resize(a, (a.shape[1] // 4, a.shape[0] // 4), interpolation=cv2.INTER_AREA)
        return cv2.boxFilter(small, -1, (k, k), borderType=cv2.BORDER_REFLECT)

    bg = (~fg).astype(np.float32)
    for ys, xs in [
        (np.array([h - 1, 0]), np.array([w - 1, 5])),
        (np.array([h - 1]), np.array([w // 2])),
        (np.array([h // 2, h // 2 + 3]), np.array([w - 2, w - 1])),
        (np.array([9]), np.array([9])),
    ]:
        cnt, near = _surround_near_candidates(mu, fg, ys // 4, xs // 4, k)
        np.testing.assert_allclose(cnt, whole(bg)[ys // 4, xs // 4], rtol=1e-5, atol=1e-6)
        for c in range(3):
            np.testing.assert_allclose(near[c], whole(mu[c] * bg)[ys // 4, xs // 4], rtol=1e-5, atol=1e-3)


def grey3(frames: np.ndarray) -> np.ndarray:
    """Frames (..., H, W, 3) made grey: three equal channels, as a grey or infrared camera's come."""
    g = np.rint(frames.astype(np.float32) @ np.float32([0.114, 0.587, 0.299]))
    return np.repeat(g[..., None], 3, axis=-1).astype(np.uint8)


def test_chroma_spread_tells_grey_and_tinted_footage_from_colour(empty_frames):
    colour = empty_frames[0]
    grey = grey3(colour)
    ok, jpeg = cv2.imencode(".jpg", grey, [cv2.IMWRITE_JPEG_QUALITY, 60])
    through_codec = cv2.imdecode(jpeg, cv2.IMREAD_COLOR)
    # a night-vision camera's green tint: every colour still on one line through black
    tinted = np.clip(grey * np.float32([0.8, 1.0, 0.85]), 0, 255).astype(np.uint8)
    assert chroma_spread_deg(grey) == 0.0
    assert chroma_spread_deg(through_codec) < 0.5
    assert chroma_spread_deg(tinted) < 0.5
    assert chroma_spread_deg(colour) > 5.0
    assert chroma_spread_deg(np.zeros((8, 8, 3), np.uint8)) == 0.0


def grey_scene_labels(mono_chroma_deg: float) -> tuple[np.ndarray, dict[str, np.ndarray], bool]:
    """Labels of a grey frame with a person a quarter darker than the room, another a fifth brighter,
    and a cast shadow that takes off 8% (each keeping the room's texture, as a shadow does), from a
    model fitted on grey frames; the regions; whether the model took the footage as monochrome.
    """
    rng = np.random.default_rng(5)
    frames = grey3(np.stack([render(rng) for _ in range(30)]))
    model = HorprasertBackground(shadows=ShadowConfig(mono_chroma_deg=mono_chroma_deg)).fit(frames)
    dark, light = person_mask(45.0), person_mask(115.0)
    shadow = np.zeros((H, W), bool)
    shadow[100:118, 60:100] = True
    f = BG.copy()
    f[dark] *= 0.75
    f[light] *= 1.2
    f[shadow] *= 0.92
    f = grey3(np.clip(np.rint(f + rng.normal(0.0, 2.5, f.shape)), 0, 255))
    return model.apply(f), {"dark": dark, "light": light, "shadow": shadow}, model.monochrome_


def test_on_grey_footage_people_a_shade_darker_or_lighter_than_the_room_are_foreground():
    labels, regions, monochrome = grey_scene_labels(ShadowConfig().mono_chroma_deg)
    assert monochrome
    assert class_fractions(labels, regions["dark"])[FOREGROUND] > 0.98
    assert class_fractions(labels, regions["light"])[FOREGROUND] > 0.98
    assert class_fractions(labels, regions["shadow"])[SHADOW] > 0.9
    # taken as colour footage, brightness within the shadow and highlight bounds hides them both
    labels, regions, monochrome = grey_scene_labels(0.0)
    assert not monochrome
    assert class_fractions(labels, regions["dark"])[SHADOW] > 0.9
    assert class_fractions(labels, regions["light"])[HIGHLIGHT] > 0.9


def test_colour_footage_keeps_its_shadow_bounds(empty_frames):
    model = HorprasertBackground().fit(empty_frames)
    assert not model.monochrome_
    s = ShadowConfig()
    assert model.shadow_bounds() == (
        s.min_shadow_brightness,
        s.unseen_min_shadow_brightness,
        s.max_highlight_brightness,
    )
    with pytest.raises(ValueError, match="mono_min_shadow_brightness"):
        ShadowConfig(mono_min_shadow_brightness=1.0)
    with pytest.raises(ValueError, match="mono_max_highlight_brightness"):
        ShadowConfig(mono_max_highlight_brightness=0.9)
    with pytest.raises(ValueError, match="mono_chroma_deg"):
        ShadowConfig(mono_chroma_deg=-1.0)


@pytest.mark.skipif(not UT_CLIP.exists(), reason=f"{UT_CLIP} not found (the shared real data is absent)")
def test_a_real_clip_in_grey_keeps_its_people():
    frames, kp, vis = clip_with_keypoints()
    grey = grey3(frames)
    assert keypoints_inside(grey, kp, vis) > 0.93
    # without the monochrome bounds most of the people were shadow and highlight
    assert keypoints_inside(grey, kp, vis, mono_chroma_deg=0.0) < 0.6


def lit_stream_labels(gain: float, exposure_step: float) -> tuple[np.ndarray, np.ndarray, list[float | None]]:
    """Labels of 10 frames after the light changes by ``gain`` all over (a person in view), from a
    model fitted on the empty scene; the person's mask; the gains ``follow_exposure`` applied.
    """
    rng = np.random.default_rng(7)
    model = HorprasertBackground(adaptation=AdaptationConfig(exposure_step=exposure_step))
    model.fit(np.stack([render(rng) for _ in range(30)]))
    applied, labels = [], []
    for _ in range(10):
        frame = render(rng, person_x=80.0, gains=(gain, gain, gain))
        applied.append(model.follow_exposure(frame))
        labels.append(model.apply(frame))
        model.update(frame, labels[-1])
    return np.stack(labels), person_mask(80.0), applied


@pytest.mark.parametrize("gain", [1.6, 0.3])
def test_a_light_switched_on_or_off_re_exposes_the_model_at_once(gain):
    labels, person, applied = lit_stream_labels(gain, AdaptationConfig().exposure_step)
    assert applied[0] == pytest.approx(gain, rel=0.02) and applied[1:] == [None] * 9
    for lab in labels:
        assert class_fractions(lab, person)[FOREGROUND] > 0.98
        assert class_fractions(lab, ~person)[FOREGROUND] < 0.01
    # not followed: the whole room is foreground, frame after frame
    labels, _, applied = lit_stream_labels(gain, 0.0)
    assert applied == [None] * 10
    assert min(class_fractions(lab, ~person)[FOREGROUND] for lab in labels) > 0.9


def test_a_steady_light_is_never_re_exposed_whatever_the_people_do():
    rng = np.random.default_rng(8)
    model = HorprasertBackground().fit(np.stack([render(rng) for _ in range(30)]))
    applied = []
    for k in range(40):
        frame = render(rng, person_x=20.0 + 3 * k, shadow=k % 2 == 0)
        # a second, large person as dark as a coat fills a third of the frame on some frames
        if k % 5 == 0:
            frame[:, :55] = 30
        applied.append(model.follow_exposure(frame))
        model.update(frame, model.apply(frame))
    assert applied == [None] * 40
    with pytest.raises(ValueError, match="exposure_step"):
        AdaptationConfig(exposure_step=1.0)


def white_balance_stream(gains: tuple[float, float, float], white_balance_step: float) -> tuple[float, float, list]:
    """The most of the room and the least of the person called foreground over 10 frames after the
    camera's white balance changes by ``gains`` (B, G, R), a person in view, and what
    ``follow_exposure`` applied.
    """
    rng = np.random.default_rng(7)
    model = HorprasertBackground(adaptation=AdaptationConfig(white_balance_step=white_balance_step))
    model.fit(np.stack([render(rng) for _ in range(30)]))
    person, room, applied = [], [], []
    for _ in range(10):
        frame = render(rng, person_x=80.0, gains=gains)
        applied.append(model.follow_exposure(frame))
        labels = model.apply(frame)
        model.update(frame, labels)
        person.append(class_fractions(labels, person_mask(80.0))[FOREGROUND])
        room.append(class_fractions(labels, ~person_mask(80.0))[FOREGROUND])
    return max(room), min(person), applied


@pytest.mark.parametrize("gains", [(1.06, 1.0, 0.95), (0.94, 1.0, 1.06)])
def test_a_change_of_white_balance_is_followed_channel_by_channel_at_once(gains):
    room, person, applied = white_balance_stream(gains, AdaptationConfig().white_balance_step)
    # the brightness barely changes (under the exposure step): the colour balance is what is followed
    assert applied[0] is not None and applied[1:] == [None] * 9
    assert room < 0.01 and person > 0.98
    # not followed: a slight cast all over turns a third of the room into foreground
    room, person, applied = white_balance_stream(gains, 0.0)
    assert applied == [None] * 10 and room > 0.25


def test_a_steady_colour_balance_is_never_followed():
    room, person, applied = white_balance_stream((1.0, 1.0, 1.0), AdaptationConfig().white_balance_step)
    assert applied == [None] * 10 and room < 0.01 and person > 0.98
    with pytest.raises(ValueError, match="white_balance_step"):
        AdaptationConfig(white_balance_step=-0.1)


@pytest.mark.skipif(not UT_CLIP.exists(), reason=f"{UT_CLIP} not found (the shared real data is absent)")
def test_a_real_clip_whose_white_balance_turns_keeps_the_room_out_of_its_people():
    frames, kp, vis = clip_with_keypoints()
    cast = frames.astype(np.float32)
    cast[50:] *= np.array([1.06, 1.0, 0.95], np.float32)
    cast = np.clip(np.rint(cast), 0, 255).astype(np.uint8)
    followed = labels_of(cast)  # the default white_balance_step
    assert labels_cover(followed, kp, vis) > 0.95
    plain, unfollowed = people_share(clip_labels(), 50), people_share(labels_of(cast, white_balance_step=0.0), 50)
    assert people_share(followed, 50) < 1.1 * plain and unfollowed > 2 * plain


@pytest.mark.skipif(not UT_CLIP.exists(), reason=f"{UT_CLIP} not found (the shared real data is absent)")
def test_a_real_clip_whose_light_is_switched_on_keeps_its_people_and_not_the_room():
    frames, kp, vis = clip_with_keypoints()
    lit = frames.astype(np.float32)
    lit[50:] *= 1.7
    lit = np.clip(np.rint(lit), 0, 255).astype(np.uint8)
    followed = labels_of(lit)  # the default exposure_step
    assert labels_cover(followed, kp, vis) > 0.95
    unfollowed = people_share(labels_of(lit, exposure_step=0.0), 50)
    assert people_share(followed, 50) < 1.5 * people_share(clip_labels(), 50) and unfollowed > 0.9
