"""Dynamic backgrounds and small people: the sample-consensus model beside the Horprasert
statistics (``samples.SampleConsensus``) and the frame-scaled minimum person area, on synthetic
frames; and on real CDnet footage with per-pixel ground truth when ``../shared/data`` has it.

The dynamic scene: a static textured room with sensor noise, and a patch of "leaves": a texture
of two very different colours (leaf green and sky blue) that shifts by up to 3 pixels at random
every frame, so each of its pixels flips between the two colours.
"""

from __future__ import annotations

import pickle
import sys
import threading

import numpy as np
import pytest

from counterpart.nodes.silhouette.backends import make_subtractor
from counterpart.nodes.silhouette.background import FOREGROUND, SHADOW, HorprasertBackground, ShadowConfig
from counterpart.nodes.silhouette.body_shadow import BodyShadowConfig
from counterpart.nodes.silhouette.deferred import SWITCH_INTERVAL_S, DeferredStep
from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor, person_min_area
from counterpart.nodes.silhouette.samples import SampleConsensus
from counterpart.sim.flat_scenes import textured_background
from tests.shared_data import DATA

H, W = 240, 320
ROOM = textured_background(H, W)
LEAVES = (slice(20, 100), slice(180, 300))
_LEAF_RNG = np.random.default_rng(7)
#: a leaf / sky texture larger than the patch, cut at a random shift each frame
_LEAF_TEX = np.where(
    (_LEAF_RNG.random((LEAVES[0].stop - LEAVES[0].start + 8, LEAVES[1].stop - LEAVES[1].start + 8)) < 0.5)[..., None],
    np.float32([40, 150, 60]),
    np.float32([210, 170, 120]),
)


def frame(rng: np.random.Generator, person: tuple[int, int, int, int] | None = None, wind: bool = True) -> np.ndarray:
    """One frame: room + noise (sigma 2.5) + leaves, shifted at random when ``wind`` blows;
    ``person`` (x, y, w, h) a flat magenta box (a small, distant person).
    """
    f = ROOM + rng.normal(0.0, 2.5, ROOM.shape).astype(np.float32)
    dy, dx = rng.integers(0, 7, size=2) if wind else (3, 3)
    ph, pw = LEAVES[0].stop - LEAVES[0].start, LEAVES[1].stop - LEAVES[1].start
    f[LEAVES] = _LEAF_TEX[dy : dy + ph, dx : dx + pw]
    if person is not None:
        x, y, w, h = person
        f[y : y + h, x : x + w] = (170.0, 40.0, 190.0)
    return np.clip(np.rint(f), 0, 255).astype(np.uint8)


def leaves_foreground(dynamic: bool) -> float:
    """Share of the leaf patch called foreground over the last 50 of 150 frames, the leaves still
    in the 30 training frames (no wind) and waving after.
    """
    rng = np.random.default_rng(0)
    sub = make_subtractor("horprasert", train_frames=30, robust=False, dynamic=dynamic)
    fg = []
    for k in range(180):
        m = sub.apply(frame(rng, wind=k >= 30))
        if k >= 130:
            fg.append(m[LEAVES].mean())
    return float(np.mean(fg))


def test_waving_leaves_are_background_with_the_sample_model() -> None:
    with_samples = leaves_foreground(dynamic=True)
    without = leaves_foreground(dynamic=False)
    # the single-mode statistics learnt the still leaves and see the waving ones as foreground;
    # the samples learn the second colour where the labels blink
    assert with_samples < 0.06, with_samples
    assert without > 5 * with_samples, (without, with_samples)


def test_sample_consensus_keeps_a_person_and_the_shadow_class() -> None:
    rng = np.random.default_rng(1)
    sub = make_subtractor("horprasert", train_frames=30, robust=False, dynamic=True)
    for _ in range(30):
        sub.apply(frame(rng))
    person = (60, 120, 30, 80)
    f = frame(rng, person)
    y0, x0 = 200, 20
    f[y0 : y0 + 20, x0 : x0 + 100] = np.clip(ROOM[y0 : y0 + 20, x0 : x0 + 100] * 0.6, 0, 255).astype(np.uint8)
    m = sub.apply(f)
    x, y, w, h = person
    assert m[y : y + h, x : x + w].mean() > 0.99
    assert (sub.labels[y0 + 2 : y0 + 18, x0 + 2 : x0 + 98] == SHADOW).mean() > 0.95


def test_the_match_radius_follows_each_pixel_own_spread() -> None:
    """A shirt a little off the wall's colour (+12 blue, -12 red: L1 24 grey levels, a change of
    chromaticity the statistics flag) stays foreground on the plain, low-noise wall: the radius
    comes from the wall's own spread. A radius that grows with brightness alone (10 + 6% of
    |S|_1, the first version) took it for the wall. The waving leaves' spread is far wider.
    """

    def run(**sample_params: float) -> tuple[float, np.ndarray]:
        rng = np.random.default_rng(4)
        sub = make_subtractor("horprasert", train_frames=30, robust=False, sample_params=sample_params)
        for k in range(150):
            sub.apply(frame(rng, wind=k >= 30))
        x, y, w, h = 40, 130, 30, 80
        f = frame(rng)
        shirt = ROOM[y : y + h, x : x + w] + np.float32([12.0, 0.0, -12.0])
        f[y : y + h, x : x + w] = np.clip(np.rint(shirt), 0, 255).astype(np.uint8)
        return float(sub.apply(f)[y : y + h, x : x + w].mean()), sub.samples.spread_

    kept, spread = run()
    assert kept > 0.95, kept
    assert np.median(spread[LEAVES]) > 3 * np.median(spread[150:, :100]), (spread[LEAVES].mean(), spread.mean())
    eaten, _ = run(radius=10.0, relative_radius=0.06, spread_k=0.0)
    assert eaten < 0.5, eaten


def test_sample_consensus_validates_and_learns_only_background() -> None:
    with pytest.raises(ValueError, match="min_matches"):
        SampleConsensus(n_samples=5, min_matches=6)
    with pytest.raises(ValueError, match="radius"):
        SampleConsensus(radius=0)
    model = SampleConsensus(n_samples=4, min_matches=1, subsampling=1, random_state=0)
    frames = np.full((4, 8, 8, 3), 100, np.uint8)
    model.fit(frames, np.full((8, 8, 3), 100.0))
    labels = np.full((8, 8), FOREGROUND, np.uint8)
    new = np.full((8, 8, 3), 30, np.uint8)
    out = model.apply(new, labels)
    # a colour far from every sample stays foreground, and foreground is never learnt
    assert (out == FOREGROUND).all()
    assert (model.samples_ == 100).all()


def test_dynamic_regions_update_their_samples_twice_as_often_as_quiet_ones() -> None:
    """``quiet_subsampling`` (2 x ``subsampling``) at quiet pixels, ``subsampling`` where the label
    blinks: counted as the samples replaced by a new background colour.
    """
    h, w = 64, 64
    sc = SampleConsensus(threaded=False, random_state=1)
    assert sc.quiet_subsampling == 2 * sc.subsampling
    sc.fit(np.full((20, h, w, 3), 100, np.uint8), np.full((h, w, 3), 100.0))
    new = np.full((h, w, 3), 120, np.uint8)
    yy, xx = np.mgrid[0:h, 0:w]
    for k in range(80):
        # single-pixel foreground speckle that switches every frame in the top rows: a blinking region
        speckle = (yy < 24) & ((yy + xx + k) % 2 == 0)
        labels = np.where(speckle, FOREGROUND, 0).astype(np.uint8)
        sc.learn(new, labels, np.flatnonzero(speckle))
    replaced = (sc.samples_.reshape(h, w, 3, -1)[..., 0, :] == 120).mean(axis=-1)
    dynamic, quiet = replaced[2:22].mean(), replaced[34:].mean()
    assert 1.6 < dynamic / quiet < 2.5, (dynamic, quiet)
    with pytest.raises(ValueError, match="quiet_subsampling"):
        SampleConsensus(subsampling=16, quiet_subsampling=8)


def test_learning_in_worker_threads_gives_the_same_labels_and_models() -> None:
    # the leaves blink (so the blink levels and the learning of dynamic pixels are exercised), a
    # person walks in; the caller overwrites its frame buffer as soon as each call returns
    runs = []
    for threaded in (True, False):
        rng = np.random.default_rng(3)
        sub = make_subtractor(
            "horprasert", train_frames=20, robust=False, threaded=threaded, sample_params={"threaded": threaded}
        )
        buf = np.empty((H, W, 3), np.uint8)
        labels = []
        for k in range(45):
            buf[:] = frame(rng, (20 + 4 * k, 120, 30, 80) if k >= 25 else None)
            sub.apply(buf)
            buf[:] = 0
            labels.append(sub.labels.copy())
        runs.append((np.stack(labels), sub.samples.samples_.copy(), sub.samples.radius_.copy(), sub.model.mean_.copy()))
    (lab_t, smp_t, rad_t, mean_t), (lab_s, smp_s, rad_s, mean_s) = runs
    assert (lab_t[20:] == FOREGROUND).any(axis=(1, 2)).sum() >= 20
    assert np.array_equal(lab_t, lab_s)
    assert np.array_equal(smp_t, smp_s)
    assert np.array_equal(rad_t, rad_s) and rad_t.max() > 1.0
    assert np.array_equal(mean_t, mean_s)


def test_both_models_learn_in_one_worker_thread_and_a_pickled_copy_keeps_that() -> None:
    # two learning steps a frame (the statistics' update, then the samples') in one spare thread:
    # three threads would contend for two cores
    rng = np.random.default_rng(5)
    before = set(threading.enumerate())
    sub = make_subtractor("horprasert", train_frames=10, robust=False)
    for _ in range(14):
        sub.apply(frame(rng))
    new = set(threading.enumerate()) - before
    assert [t.name.split("_")[0] for t in new] == ["horprasert-update"]
    twin = pickle.loads(pickle.dumps(sub))
    before = set(threading.enumerate())
    for k in range(6):
        f = frame(rng, (60 + 8 * k, 120, 30, 80))
        assert np.array_equal(sub.apply(f), twin.apply(f))
    assert len(set(threading.enumerate()) - before) == 1  # the copy's one worker
    assert np.array_equal(sub.samples.samples_, twin.samples.samples_)
    assert np.array_equal(sub.model.mean_, twin.model.mean_)


def test_min_area_scales_with_the_frame_and_the_camera() -> None:
    small = person_min_area(320, 240)
    assert person_min_area(640, 480) == pytest.approx(4 * small, rel=0.05)
    # the floor: 16 px tall whatever the frame
    assert person_min_area(160, 120) == 64
    # a person 20 px tall (about 0.25 * 20^2 = 100 px of region) is above the threshold
    assert small < 100
    from counterpart.body.camera import default_camera

    cam = default_camera(320, 240)
    tele = type(cam)(cam.fx * 2, cam.fy * 2, cam.cx, cam.cy, 320, 240, cam.R, cam.t)
    assert person_min_area(320, 240, camera=tele) == pytest.approx(4 * small, rel=0.05)


def test_a_person_20_px_tall_is_found_and_keeps_one_id() -> None:
    rng = np.random.default_rng(2)
    ex = SilhouetteExtractor(min_area=None, backend_params={"train_frames": 30, "robust": False, "dynamic": True})
    for _ in range(30):
        ex.process(frame(rng))
    ids, found = set(), 0
    for k in range(40):
        r = ex.process(frame(rng, (30 + 4 * k, 150, 8, 20)))
        found += len(r.people) == 1
        ids.update(p.id for p in r.people)
        for p in r.people:
            assert p.height <= 22
    assert found >= 38, found
    assert len(ids) == 1, ids


CDNET = DATA / "cdnet"


def cdnet_f1(seq: str, backend: str, first: int, last: int) -> float:
    """CDnet-protocol F1 of the extractor's published mask on frames ``first``..``last``, the
    extractor fed from 30 frames before ``first`` (ours fits on those 30).
    """
    import cv2

    d = CDNET / seq
    ex = SilhouetteExtractor(
        backend=backend,
        min_area=None,
        backend_params={"train_frames": 30, "dynamic": True, "shadow_ncc": 0.4} if backend == "horprasert" else {},
    )
    tp = fp = fn = 0
    for n in range(first - 30, last + 1):
        r = ex.process(cv2.imread(str(d / "input" / f"in{n:06d}.jpg")))
        if n < first:
            continue
        g = cv2.imread(str(d / "groundtruth" / f"gt{n:06d}.png"), cv2.IMREAD_GRAYSCALE)
        m = r.labels > 0
        pos, neg = g == 255, (g == 0) | (g == 50)
        tp += int((m & pos).sum())
        fp += int((m & neg).sum())
        fn += int((pos & ~m).sum())
    return 2 * tp / max(2 * tp + fp + fn, 1)


@pytest.mark.skipif(
    not (CDNET / "pedestrians" / "input").is_dir() or not (CDNET / "busStation" / "input").is_dir(),
    reason=f"CDnet sequences not found under {CDNET} (see ../shared/data/README.md)",
)
@pytest.mark.parametrize("seq", ["pedestrians", "busStation"])
def test_cdnet_f1_beats_mog2(seq: str) -> None:
    # 100 frames of the report half (the bench: the whole second half of the evaluated frames),
    # both models fed from 30 frames before
    first = {"pedestrians": 860, "busStation": 880}[seq]  # windows with people in every frame
    ours = cdnet_f1(seq, "horprasert", first, first + 100)
    mog2 = cdnet_f1(seq, "mog2", first, first + 100)
    # 30 frames to learn from, with people in them (the bench's models have had hundreds of
    # frames by the report half), so the floor is below the bench's 0.90. busStation: the
    # short-trained model calls the glass doors' reflections shadow, and where they lie between
    # two people the body-shadow rule takes them back (0.801 without it, 0.792 with it; over the
    # bench's whole report half the rule gains); pedestrians: 0.922 without it, 0.943 with it,
    # 0.955 with its leg step (grey trousers below a torso; 0.7919 -> 0.7927 on busStation)
    assert ours >= {"pedestrians": 0.95, "busStation": 0.78}[seq], (ours, mog2)
    assert ours > mog2, (ours, mog2)


def test_shadow_texture_test_tells_a_dark_shirt_from_a_shadow() -> None:
    """On a textured floor a cast shadow keeps the floor's pattern (same colour, darker); a dark
    shirt of the floor's colour does not: with ``shadow_ncc`` on it is foreground, off a shadow.
    """
    rng = np.random.default_rng(3)
    floor = np.repeat(np.repeat(rng.uniform(80, 200, (30, 40)), 4, 0), 4, 1)[..., None] * np.float32([0.9, 1.0, 1.1])

    def shot(patch: np.ndarray | None = None) -> np.ndarray:
        f = floor + rng.normal(0.0, 2.0, floor.shape)
        if patch is not None:
            f[40:80, 40:100] = patch
        return np.clip(np.rint(f), 0, 255).astype(np.uint8)

    train = [shot() for _ in range(20)]
    shadow = floor[40:80, 40:100] * 0.6
    shirt = np.full_like(shadow, 0.6 * floor[40:80, 40:100].mean(axis=(0, 1)))
    inner = (slice(44, 76), slice(44, 96))
    for ncc, want_shirt in ((0.4, FOREGROUND), (-1.0, SHADOW)):
        model = HorprasertBackground(shadows=ShadowConfig(shadow_ncc=ncc)).fit(train)
        assert (model.apply(shot(shadow))[inner] == SHADOW).mean() > 0.9
        assert (model.apply(shot(shirt))[inner] == want_shirt).mean() > 0.7


def test_texture_test_over_a_frame_in_shadow_checks_only_its_textured_pixels() -> None:
    """When shadow covers much of the frame the background's texture is measured with box filters
    over the frame, and the frame's side of the correlation only at the textured shadow pixels:
    the pixels turned are those of the box filters over the whole frame (up to float32 rounding
    at the threshold): the dark shirt, not the shadow over the rest of the floor.
    """
    import cv2

    rng = np.random.default_rng(4)
    floor = np.full((H, W, 3), 140.0, np.float32)
    # a plain floor with a textured rug: only the rug's pixels are textured, too few to filter
    # the whole frame for
    rug = (slice(80, 108), slice(120, 156))
    tex = np.repeat(np.repeat(rng.uniform(80, 200, (7, 9)), 4, 0), 4, 1)
    floor[rug] = tex[..., None] * np.float32([0.9, 1.0, 1.1])

    def shot(shirt: bool) -> np.ndarray:
        f = 0.6 * floor + rng.normal(0.0, 2.0, floor.shape)
        if shirt:
            # plain, with the camera's noise (an exactly flat patch has no correlation to measure)
            f[84:104, 124:148] = 0.6 * floor[84:104, 124:148].mean(axis=(0, 1)) + rng.normal(0.0, 2.0, (20, 24, 3))
        return np.clip(np.rint(f), 0, 255).astype(np.uint8)

    train = [np.clip(np.rint(floor + rng.normal(0.0, 2.0, floor.shape)), 0, 255).astype(np.uint8) for _ in range(20)]
    model = HorprasertBackground(shadows=ShadowConfig(shadow_ncc=0.4)).fit(train)
    f = shot(shirt=True)
    labels = model.classify(f)
    sh = labels == SHADOW
    assert sh.mean() > 0.5  # the frame-wide path
    got = model.shadow_texture_mismatch(labels)
    # the reference: every moment by box filters over the frame
    k = (7, 7)

    def box(a: np.ndarray) -> np.ndarray:
        return cv2.boxFilter(a, -1, k, normalize=False, borderType=cv2.BORDER_REFLECT)

    fl = f.astype(np.float32)
    grey = fl[..., 0] + fl[..., 1] + fl[..., 2]
    e = model.grey_
    m = sh.astype(np.float32)
    inv_n = 1.0 / np.maximum(box(m), 1.0)
    me, mi = box(e * m) * inv_n, box(grey * m) * inv_n
    ve, vi = box(e * e * m) * inv_n - me * me, box(grey * grey * m) * inv_n - mi * mi
    cov = box(grey * e * m) * inv_n - mi * me
    ncc = cov / np.sqrt(np.maximum(vi, 0.0) * np.maximum(ve, 0.0) + 1e-6)
    floor_var = (model.spread_**2).sum(axis=2) * model.shadows.shadow_texture_k**2
    want = sh & (ve > floor_var) & (ncc < 0.4)
    near = np.abs(ncc - 0.4) < 1e-3
    mask = np.zeros(H * W, bool)
    mask[got] = True
    assert np.array_equal(mask.reshape(H, W)[~near], want[~near])
    assert 0 < want.sum() and (sh & (ve > floor_var)).sum() * 49 < H * W  # the textured pixels alone
    assert mask.reshape(H, W)[88:100, 128:144].mean() > 0.5
    assert mask.sum() < 24 * 20


def test_texture_prefilter_is_the_background_windows_variance_and_drops_no_turned_pixel_here() -> None:
    """``texture_prefilter``: the model keeps, per pixel, whether the variance of E's grey sum over
    the whole window exceeds that fraction of the texture floor (the brute-force windowed variance,
    reflect-padded); only the shadow pixels there are tested. On a plain floor with a textured rug
    that is the rug (and its rim) alone, and the shirt on the rug is turned as without the prefilter.
    """
    from numpy.lib.stride_tricks import sliding_window_view

    rng = np.random.default_rng(5)
    floor = np.full((H, W, 3), 140.0, np.float32)
    rug = (slice(80, 108), slice(120, 156))
    tex = np.repeat(np.repeat(rng.uniform(80, 200, (7, 9)), 4, 0), 4, 1)
    floor[rug] = tex[..., None] * np.float32([0.9, 1.0, 1.1])
    train = [np.clip(np.rint(floor + rng.normal(0.0, 2.0, floor.shape)), 0, 255).astype(np.uint8) for _ in range(20)]
    f = 0.6 * floor + rng.normal(0.0, 2.0, floor.shape)
    f[84:104, 124:148] = 0.6 * floor[84:104, 124:148].mean(axis=(0, 1)) + rng.normal(0.0, 2.0, (20, 24, 3))
    f = np.clip(np.rint(f), 0, 255).astype(np.uint8)
    turned = {}
    for c in (0.5, 0.0):
        model = HorprasertBackground(shadows=ShadowConfig(shadow_ncc=0.4, texture_prefilter=c)).fit(train)
        labels = model.classify(f)
        turned[c] = set(model.shadow_texture_mismatch(labels).tolist())
        if c == 0.0:
            assert model._bg_textured is None
            continue
        e = np.pad(model.grey_.astype(np.float64), 3, mode="symmetric")  # BORDER_REFLECT
        var = sliding_window_view(e, (7, 7)).var(axis=(2, 3))
        floor_var = (model.spread_.astype(np.float64) ** 2).sum(axis=2) * model.shadows.shadow_texture_k**2 * c
        near = np.abs(var - floor_var) < 1e-3 * floor_var + 1e-2
        assert np.array_equal(model._bg_textured[~near], (var > floor_var)[~near])
        assert model._bg_textured[84:104, 124:152].all() and not model._bg_textured[:70].any()
    assert len(turned[0.5]) > 100 and turned[0.5] == turned[0.0]


def test_texture_test_beside_the_veto_gives_the_labels_and_models_of_the_veto_after_it() -> None:
    """The subtractor runs the shadows' texture test and the samples' veto of the other foreground,
    then vetoes the pixels the test turned (threaded or not): labels, samples, blink radius and
    statistics equal those of ``apply`` followed by ``veto`` and ``learn`` (the order the steps
    depend on), on a textured floor where a dark shirt is turned from shadow.
    """
    rng = np.random.default_rng(3)
    floor = np.repeat(np.repeat(rng.uniform(80, 200, (60, 80)), 4, 0), 4, 1)[..., None] * np.float32([0.9, 1.0, 1.1])
    shirt_colour = 0.6 * floor[100:180, 100:160].mean(axis=(0, 1))

    def shot(x: int | None = None) -> np.ndarray:
        f = floor + rng.normal(0.0, 2.0, floor.shape)
        if x is not None:
            f[100:180, x : x + 60] = shirt_colour
            f[100:180, x + 60 : x + 90] *= 0.6  # its cast shadow keeps the floor's pattern
        return np.clip(np.rint(f), 0, 255).astype(np.uint8)

    train = [shot() for _ in range(20)]
    frames = [shot(40 + 6 * k) for k in range(8)]
    params = {"train_frames": 20, "robust": False, "body_shadow": BodyShadowConfig(span_px=0), "shadow_ncc": 0.4}
    for threaded in (True, False):
        sub = make_subtractor("horprasert", threaded=threaded, sample_params={"threaded": threaded}, **params)
        for f in train:
            sub.apply(f)
        ref = pickle.loads(pickle.dumps(sub))
        turned = 0
        for f in frames:
            model, samples = ref.model, ref.samples
            raw = model.classify(f)
            stats = model.apply(f)
            turned += int(((raw == SHADOW) & (stats == FOREGROUND)).sum())
            labels, fg_idx = samples.veto(f, stats)
            model.update(f, labels)
            samples.learn(f, stats, fg_idx)
            sub.apply(f)
            assert np.array_equal(sub.labels, labels)
        assert turned > 1000  # the texture test did turn the shirt
        assert (sub.labels[110:170, 100:130] == FOREGROUND).mean() > 0.6
        assert np.array_equal(sub.samples.samples_, ref.samples.samples_)
        assert np.array_equal(sub.samples.radius_, ref.samples.radius_)
        assert np.array_equal(sub.model.mean_, ref.model.mean_)


def test_the_match_test_reads_the_samples_as_they_are_after_learning() -> None:
    """ViBe's test with the brightness-relative radius, worked out here from the public samples,
    blink gain and spread, equals ``explained`` at every pixel after the lights went up and the
    samples learnt the brighter room (``subsampling=1``: each draw covers the frame, with repeats).
    """
    rng = np.random.default_rng(11)
    sc = SampleConsensus(subsampling=1, random_state=0, threaded=False)
    sc.fit(np.stack([frame(rng, wind=False) for _ in range(20)]), ROOM)

    def bright(person: tuple[int, int, int, int] | None = None, up: int = 60) -> np.ndarray:
        return np.clip(frame(rng, person, wind=False).astype(np.int16) + up, 0, 255).astype(np.uint8)

    for _ in range(12):
        sc.apply(bright(), np.zeros((H, W), np.uint8))
    # a little brighter still: the distances to the new samples lie near the radius, which
    # grows with the samples' brightness
    f = bright((170, 120, 30, 80), up=66)
    rows = sc.samples_.astype(np.float64)  # (H * W, 3, N)
    dist = np.abs(rows - f.reshape(-1, 3, 1)).sum(axis=1)
    norm = rows.sum(axis=1)
    gain = sc.radius_.reshape(-1, 1).astype(np.float64)
    base = np.maximum(sc.radius, sc.spread_k * sc.spread_.reshape(-1, 1).astype(np.float64))
    margin = dist / gain - sc.relative_radius * norm - base
    want = (margin < 0).sum(axis=1) >= sc.min_matches
    got = sc.explained(f, np.arange(H * W))
    # float32 rounding in the model: only pixels within a hair of the radius may differ
    close = (np.abs(margin) < 1e-3).any(axis=1)
    assert np.array_equal(got[~close], want[~close])
    assert want.sum() > 1000 and (~want).sum() > 1000


def test_the_sample_box_follows_the_samples_and_rules_out_only_pixels_that_match_none() -> None:
    """``explained`` first rules out the pixels whose colour lies far from the box of their samples
    (most of a person): after fitting and after learning with ``subsampling=1`` (every pixel
    rewritten, some twice) each pixel's box is its samples' minimum and maximum, and the pixels
    ruled out are among those with no sample within reach, while a person's pixels are tested.
    """
    from counterpart.nodes.silhouette.samples import _box_bytes

    rng = np.random.default_rng(5)
    sc = SampleConsensus(subsampling=1, random_state=0, threaded=False)
    sc.fit(np.stack([frame(rng) for _ in range(20)]), ROOM)

    def box_is_exact() -> bool:
        b, s = _box_bytes(sc._box), sc.samples_
        return bool(np.array_equal(b[:, :3], s.min(axis=2)) and np.array_equal(b[:, 4:7], s.max(axis=2)))

    assert box_is_exact()
    for _ in range(5):
        sc.apply(frame(rng), np.zeros((H, W), np.uint8))
    assert box_is_exact()
    f = frame(rng, person=(100, 60, 40, 120))
    rows = sc.samples_.astype(np.int32)
    dist = np.abs(rows - f.reshape(-1, 3, 1)).sum(axis=1)  # (H * W, N)
    reach = sc.radius_.reshape(-1, 1) * (
        np.maximum(sc.radius, sc.spread_k * sc.spread_.reshape(-1, 1)) + sc.relative_radius * rows.sum(axis=1)
    )
    matches = (dist < reach + 1e-2).sum(axis=1) >= 1
    b = _box_bytes(sc._box).astype(np.int32)
    c = f.reshape(-1, 3).astype(np.int32)
    lower = (np.maximum(b[:, :3] - c, 0) + np.maximum(c - b[:, 4:7], 0)).sum(axis=1)
    assert (lower <= dist.min(axis=1)).all()
    got = sc.explained(f, np.arange(H * W))
    assert not (got & ~matches).any()
    person = np.zeros((H, W), bool)
    person[60:180, 100:140] = True
    assert not got[person.reshape(-1)].any() and got[~person.reshape(-1)].mean() > 0.9


def test_a_learning_worker_lowers_the_switch_interval_and_never_raises_it() -> None:
    """Python's default 5 ms switch interval made the caller's short calls queue behind the
    worker's Python (see ``deferred``): the first step a worker runs lowers it to
    ``SWITCH_INTERVAL_S``; an interval already lower is kept, and the step's result comes back.
    """
    before = sys.getswitchinterval()
    try:
        for start, expected in ((0.005, SWITCH_INTERVAL_S), (SWITCH_INTERVAL_S / 4, SWITCH_INTERVAL_S / 4)):
            sys.setswitchinterval(start)
            step = DeferredStep("switch-interval-test")
            step.submit(sum, [1, 2, 3])
            assert step.join() == 6
            assert sys.getswitchinterval() == pytest.approx(expected)
    finally:
        sys.setswitchinterval(before)
