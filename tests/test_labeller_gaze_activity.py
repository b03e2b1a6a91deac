"""Gaze, activity, face (talking/laughing) and the combined SocialLabeller."""

from __future__ import annotations

import warnings

import cv2
import numpy as np
import pytest

from counterpart.nodes.labeller.activity import ActivityDetector, activity_2d, activity_3d
from counterpart.nodes.labeller.face import FaceSignalDetector, find_face_cascade, load_face_cascade
from counterpart.nodes.labeller.gaze import facing_yaw_from_shoulders, gaze_accuracy, gaze_at_other
from counterpart.nodes.labeller.labeller import PersonObservation, SocialLabeller, label_pair_3d
from counterpart.nodes.labeller.signals import JOINT_INDEX, SIGNALS, UNKNOWN
from counterpart.sim.planted_signals import conversation, standing_pose
from tests.shared_data import VTEST

FPS = 25.0
H, LS, RS = JOINT_INDEX["head"], JOINT_INDEX["l_shoulder"], JOINT_INDEX["r_shoulder"]
needs_cascade = pytest.mark.skipif(
    find_face_cascade() is None,
    reason="no haarcascade_frontalface_default.xml installed (OpenCV 5 wheels ship none); set "
    "COUNTERPART_FACE_CASCADE or install opencv-data to run the Haar detector tests",
)


# ------------------------------------------------------------------ gaze


@pytest.mark.parametrize("yaw", [0.0, 0.7, -1.2, 2.9, -np.pi / 2])
def test_facing_yaw_from_shoulders(yaw: float) -> None:
    j = standing_pose((1.0, 0.0, -2.0), yaw)
    assert np.isclose(np.angle(np.exp(1j * (facing_yaw_from_shoulders(j[LS], j[RS]) - yaw))), 0.0, atol=1e-9)


def test_gaze_at_and_away_on_constructed_geometry() -> None:
    a = standing_pose((0, 0, 0), 0.0)  # faces +Z
    angles = np.radians([0.0, 20.0, -25.0, 40.0, -90.0, 180.0])
    others = np.stack([2.0 * np.sin(angles), np.full(6, 1.62), 2.0 * np.cos(angles)], axis=-1)
    g = gaze_at_other(np.tile(a[H], (6, 1)), np.tile(a[LS], (6, 1)), np.tile(a[RS], (6, 1)), others)
    np.testing.assert_array_equal(g.label, [1, 1, 1, 0, 0, 0])
    assert g.score[0] > 0.99 and g.score[-1] < 0.01
    np.testing.assert_allclose(np.abs(g.delta), np.abs(angles), atol=0.02)


def test_head_yaw_input_turns_the_gaze() -> None:
    a = standing_pose((0, 0, 0), 0.0)
    other = np.array([2.0 * np.sin(np.radians(60)), 1.6, 2.0 * np.cos(np.radians(60))])  # to A's left
    assert gaze_at_other(a[H], a[LS], a[RS], other).label[0] == 0
    assert gaze_at_other(a[H], a[LS], a[RS], other, head_yaw_rel=np.radians(60)).label[0] == 1
    assert gaze_at_other(a[H], a[LS], a[RS], other, head_yaw_rel=np.radians(-60)).label[0] == 0


def test_gaze_unknown_without_geometry() -> None:
    a = standing_pose()
    bad = a[LS].copy()
    bad[0] = np.nan
    assert gaze_at_other(a[H], bad, a[RS], [0, 1.6, 2]).label[0] == UNKNOWN
    assert gaze_at_other(a[H], a[LS], a[RS], a[H]).label[0] == UNKNOWN  # other at own head
    assert gaze_accuracy(np.array([UNKNOWN, 1, 0]), np.array([1, 1, 1])) == 0.5


def test_gaze_accuracy_on_conversation() -> None:
    c = conversation(40.0, FPS, seed=3)
    _, la, _, lb = label_pair_3d(c.joints_a, c.joints_b, FPS)
    assert (~c.truth_a["gaze_at_other"]).sum() > 25  # the sequence has looking away
    for lab, tr in ((la, c.truth_a), (lb, c.truth_b)):
        assert gaze_accuracy(lab[:, 2], tr["gaze_at_other"].astype(np.int8)) > 0.97


# ------------------------------------------------------------------ activity


def _still_joints(t: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return standing_pose() + rng.normal(0, 0.002, (t, 14, 3))


def test_activity_low_when_still_high_when_torso_moves() -> None:
    t = 200
    tt = np.arange(t) / FPS
    still = _still_joints(t, 0)
    s_still, l_still = activity_3d(still, FPS)
    known = l_still != UNKNOWN
    assert known.sum() > 150 and not (l_still[known] == 1).any()

    wave = still.copy()
    sway = 0.05 * np.sin(2 * np.pi * 1.0 * tt)
    upper = [
        JOINT_INDEX[j]
        for j in (
            "head",
            "neck",
            "l_shoulder",
            "l_elbow",
            "l_wrist",
            "r_shoulder",
            "r_elbow",
            "r_wrist",
            "l_hip",
            "r_hip",
        )
    ]
    wave[:, upper, 0] += sway[:, None]
    wave[:, [LS, RS], 2] += 0.05 * np.sin(2 * np.pi * 1.3 * tt)[:, None] * np.array([1, -1])
    s_wave, l_wave = activity_3d(wave, FPS)
    assert (l_wave[known] == 1).all()
    assert np.nanmin(s_wave) > 3 * np.nanmax(s_still)


def test_activity_ignores_head_and_legs() -> None:
    t = 200
    tt = np.arange(t) / FPS
    j = _still_joints(t, 1)
    j[:, H, 1] += 0.03 * np.sin(2 * np.pi * 2.0 * tt)  # nodding
    j[:, JOINT_INDEX["l_ankle"], 2] += 0.2 * np.sin(2 * np.pi * 1.0 * tt)  # swinging a leg
    j[:, JOINT_INDEX["l_knee"], 2] += 0.1 * np.sin(2 * np.pi * 1.0 * tt)
    _, lab = activity_3d(j, FPS)
    assert not (lab == 1).any()


def test_activity_streaming_matches_batch_and_2d() -> None:
    t = 120
    tt = np.arange(t) / FPS
    j = _still_joints(t, 2)
    j[60:, [LS, RS, JOINT_INDEX["l_hip"], JOINT_INDEX["r_hip"]], 0] += 0.05 * np.sin(2 * np.pi * tt[60:])[:, None]
    s_b, l_b = activity_3d(j, FPS)
    det = ActivityDetector(FPS)
    out = np.array([det.update_3d(j[i]) for i in range(t)])
    np.testing.assert_allclose(out[:, 0], s_b, atol=1e-9, equal_nan=True)
    np.testing.assert_array_equal(out[:, 1].astype(int), l_b)

    # silhouette spline: upper-body control points rocking sideways vs. still
    rng = np.random.default_rng(3)
    ang = np.linspace(0, 2 * np.pi, 32, endpoint=False)
    cp = np.stack([40 * np.sin(ang), -150 * np.cos(ang)], axis=-1) + [320, 240]
    still = cp + rng.normal(0, 0.3, (t, 32, 2))
    moving = still.copy()
    moving[:, :, 0] += (12 * np.sin(2 * np.pi * tt))[:, None]
    _, l_still = activity_2d(still, 300.0, FPS)
    _, l_moving = activity_2d(moving, 300.0, FPS)
    known = l_still != UNKNOWN
    assert not (l_still[known] == 1).any() and (l_moving[known] == 1).all()


# ------------------------------------------------------------------ face


def _face_frames(kind: str, n: int = 50, seed: int = 0) -> list[np.ndarray]:
    """Frames with a drawn mouth (dark ellipse) in a textured face box at (50, 40, 96, 96)."""
    rng = np.random.default_rng(seed)
    base = rng.normal(150, 8, (240, 320))
    half_h = {
        "static": lambda t: 6.0,
        "talk": lambda t: 5 + 3 * np.sin(2 * np.pi * 4 * t),
        "laugh": lambda t: 9 + 7 * np.sin(2 * np.pi * 5 * t),
    }[kind]
    frames = []
    for i in range(n):
        im = (base + rng.normal(0, 2.0, base.shape)).clip(0, 255).astype(np.uint8)  # sensor noise
        cv2.ellipse(im, (98, 120), (20, int(round(half_h(i / FPS)))), 0, 0, 360, 40, -1)
        frames.append(im)
    return frames


BOX = (50, 40, 96, 96)


@pytest.mark.parametrize("kind,talking,laughing", [("static", 0, 0), ("talk", 1, 0), ("laugh", 1, 1)])
def test_mouth_motion_energy(kind: str, talking: int, laughing: int) -> None:
    det = FaceSignalDetector(FPS)
    out = [det.update(f, face_box=BOX) for f in _face_frames(kind)]
    assert out[0][1] == UNKNOWN  # no motion history yet
    last = out[-1]
    assert (last[1], last[3]) == (talking, laughing), last


def test_face_too_small_is_unknown() -> None:
    det = FaceSignalDetector(FPS, min_face_px=24)
    for f in _face_frames("talk", 20):
        out = det.update(f, face_box=(90, 110, 20, 20))
        assert out[1] == UNKNOWN and out[3] == UNKNOWN and np.isnan(out[0])


@needs_cascade
def test_no_face_gives_unknown() -> None:
    det = FaceSignalDetector(FPS, cascade=load_face_cascade())
    rng = np.random.default_rng(0)
    x = np.linspace(0, 1, 640)
    scene = (100 + 80 * np.outer(np.linspace(0, 1, 480), x)).astype(np.uint8)  # smooth gradient
    cv2.rectangle(scene, (200, 150), (400, 300), 220, -1)
    small = rng.integers(0, 256, (40, 60), dtype=np.uint8)  # small noise frame
    for _ in range(30):
        for img in (scene, small, cv2.cvtColor(scene, cv2.COLOR_GRAY2BGR)):
            out = det.update(img)
            assert out[1] == UNKNOWN and out[3] == UNKNOWN
    assert det.face_box is None


@pytest.mark.skipif(not VTEST.exists(), reason=f"real pedestrian video {VTEST} is absent")
@needs_cascade
def test_pedestrian_video_faces_below_min_size_are_unknown() -> None:
    """vtest.avi's pedestrians have faces of ~10 px: refused at min_face_px=24 everywhere their
    heads are (the cascade's false positives elsewhere in the scene are not faces we can test).
    """
    cap = cv2.VideoCapture(str(VTEST))
    ok, frame = cap.read()
    cap.release()
    assert ok
    det = FaceSignalDetector(10.0, cascade=load_face_cascade(), min_face_px=24)
    # the pedestrians near the top of the frame, whose heads are smallest
    out = det.update(frame, roi=(0, 0, 768, 200))
    assert out[1] == UNKNOWN


# ------------------------------------------------------------------ combined labeller


def test_social_labeller_3d_two_people() -> None:
    c = conversation(30.0, FPS, seed=5)
    lab = SocialLabeller(FPS)
    labels = {s: [] for s in SIGNALS}
    for t in range(c.joints_a.shape[0]):
        out = lab.update(
            {
                "a": PersonObservation(joints=c.joints_a[t], head_yaw=c.head_yaw_a[t]),
                "b": PersonObservation(joints=c.joints_b[t], head_yaw=c.head_yaw_b[t]),
            }
        )
        assert set(out) == {"a", "b"} and set(out["a"]) == set(SIGNALS)
        for s in SIGNALS:
            labels[s].append(out["a"][s][1])
    lab_a = {s: np.array(v) for s, v in labels.items()}
    assert (lab_a["talking"] == UNKNOWN).all() and (lab_a["laughing"] == UNKNOWN).all()
    assert gaze_accuracy(lab_a["gaze_at_other"], c.truth_a["gaze_at_other"].astype(np.int8)) > 0.97
    # causal nods: every nod detection lies within a true nod or the window after it
    nod_true = c.truth_a["nod"]
    near = np.convolve(nod_true, np.ones(int(1.7 * FPS)), mode="full")[: len(nod_true)] > 0
    assert (lab_a["nod"] == 1).sum() > 0.5 * nod_true.sum()
    assert not ((lab_a["nod"] == 1) & ~near).any()


def test_social_labeller_chooses_inputs_and_restarts_on_switch() -> None:
    lab = SocialLabeller(FPS)
    t = 120
    tt = np.arange(t) / FPS
    rng = np.random.default_rng(0)
    cp = np.stack(
        [
            40 * np.sin(np.linspace(0, 2 * np.pi, 32, endpoint=False)),
            -150 * np.cos(np.linspace(0, 2 * np.pi, 32, endpoint=False)),
        ],
        -1,
    ) + [320, 240]
    results = []
    for i in range(t):
        head_px = np.array([320.0, 90.0 + 4.4 * np.sin(2 * np.pi * 2 * tt[i])]) + rng.normal(0, 0.2, 2)
        sil = PersonObservation(
            head_px=head_px,
            ref_px=np.array([320.0, 240.0]),
            height_px=300.0,
            control_points=cp + rng.normal(0, 0.3, (32, 2)),
        )
        results.append(lab.update({7: sil})[7])
    assert results[-1]["nod"][1] == 1  # 2D nod from the silhouette head point
    assert results[-1]["activity"][1] == 0
    assert results[-1]["gaze_at_other"][1] == UNKNOWN  # a silhouette cannot say where it looks
    # now the tracker takes over: the 3D windows start empty, so nod is UNKNOWN for a while
    out = lab.update({7: PersonObservation(joints=standing_pose())})[7]
    assert out["nod"][1] == UNKNOWN and out["gaze_at_other"][1] == UNKNOWN  # nobody else to look at
    # nothing usable at all: everything UNKNOWN
    out = lab.update({7: PersonObservation()})[7]
    assert all(v[1] == UNKNOWN for v in out.values())


def test_social_labeller_targets_override() -> None:
    lab = SocialLabeller(FPS)
    out = lab.update({"a": PersonObservation(joints=standing_pose())}, targets={"a": np.array([0.0, 1.6, 2.0])})
    assert out["a"]["gaze_at_other"][1] == 1
    out = lab.update({"a": PersonObservation(joints=standing_pose())}, targets={"a": np.array([0.0, 1.6, -2.0])})
    assert out["a"]["gaze_at_other"][1] == 0


def test_social_labeller_image_without_face_is_unknown() -> None:
    lab = SocialLabeller(FPS)
    img = np.full((120, 160), 128, np.uint8)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        outs = [lab.update({"a": PersonObservation(joints=standing_pose())}, image=img)["a"] for _ in range(3)]
    assert all(o["talking"][1] == UNKNOWN and o["laughing"][1] == UNKNOWN for o in outs)
    if find_face_cascade() is None:  # no detector: said once, not on every frame
        assert sum(issubclass(w.category, RuntimeWarning) for w in caught) == 1
