"""Two-person trajectory files: round trip, resampling, clear errors, BVH conversion."""

import json

import numpy as np
import pytest

from counterpart.body.kinematics import forward_kinematics
from counterpart.body.pose import neutral_pose
from counterpart.body.skeleton import JOINTS
from counterpart.body.trajectory import FORMAT_VERSION, TwoPersonTrajectory
from tests.shared_data import CMU as DATA


def make(T: int = 50, fps: float = 25.0, signals: bool = True) -> TwoPersonTrajectory:
    t = np.arange(T) / fps
    a = np.repeat(forward_kinematics(neutral_pose(x=-0.5, yaw=np.pi / 2)), T, axis=0)
    b = np.repeat(forward_kinematics(neutral_pose(x=0.5, yaw=-np.pi / 2)), T, axis=0)
    a[:, :, 0] += 0.2 * t[:, None]  # A walks towards B at 0.2 m/s
    kw = {}
    if signals:
        kw = dict(
            signals_a=(np.arange(T)[:, None] % np.array([2, 5]) == 0).astype(np.uint8),
            signals_b=np.zeros((T, 2), np.uint8),
            signal_names=("nod", "shake"),
            phase=(np.arange(T) >= T // 2).astype(np.int32),
        )
    return TwoPersonTrajectory(a=a, b=b, fps=fps, label="approach", meta={"source": "test"}, **kw)


def test_save_load_round_trip(tmp_path):
    tr = make()
    path = tmp_path / "x.npz"
    tr.save(path)
    back = TwoPersonTrajectory.load(path)
    np.testing.assert_array_equal(back.a, tr.a)
    np.testing.assert_array_equal(back.b, tr.b)
    assert back.a.dtype == np.float32 and back.a.shape == (50, 14, 3)
    assert back.fps == 25.0 and back.label == "approach" and back.meta == {"source": "test"}
    assert back.signal_names == ("nod", "shake")
    np.testing.assert_array_equal(back.signals_a, tr.signals_a)
    np.testing.assert_array_equal(back.phase, tr.phase)
    # The file is plain npz with the documented keys.
    with np.load(path) as z:
        assert int(z["format_version"]) == FORMAT_VERSION
        assert tuple(z["joint_names"]) == JOINTS
        assert json.loads(str(z["meta"])) == {"source": "test"}
    plain = make(signals=False)
    plain.save(tmp_path / "p.npz")
    again = TwoPersonTrajectory.load(tmp_path / "p.npz")
    assert again.signals_a is None and again.phase is None and again.signal_names == ()


def test_hand_written_file_loads(tmp_path):
    a = np.zeros((3, 14, 3), np.float32)
    np.savez(
        tmp_path / "mine.npz",
        format_version=1,
        a=a,
        b=a + 1,
        fps=30.0,
        joint_names=np.array(JOINTS),
        label="wave",
        extra_future_key=np.arange(3),
    )
    tr = TwoPersonTrajectory.load(tmp_path / "mine.npz")
    assert tr.n_frames == 3 and tr.label == "wave" and tr.meta == {}


def _write(path, **over):
    a = np.zeros((4, 14, 3), np.float32)
    d = dict(format_version=1, a=a, b=a, fps=25.0, joint_names=np.array(JOINTS), label="x")
    d.update(over)
    d = {k: v for k, v in d.items() if v is not None}
    np.savez(path, **d)
    return path


@pytest.mark.parametrize(
    "over, match",
    [
        (dict(b=None), r"missing key\(s\) \['b'\]"),
        (dict(a=np.zeros((4, 13, 3), np.float32)), r"key 'a': shape \(4, 13, 3\)"),
        (dict(b=np.zeros((5, 14, 3), np.float32)), r"key 'b': 5 frames"),
        (dict(fps=-1.0), r"key 'fps'"),
        (dict(joint_names=np.array(JOINTS[::-1])), r"key 'joint_names'"),
        (dict(format_version=7), r"key 'format_version': 7"),
        (dict(signals_a=np.zeros((4, 2)), signals_b=np.zeros((4, 2))), r"signal_names"),
        (
            dict(signals_a=np.zeros((4, 2)), signals_b=np.zeros((3, 2)), signal_names=np.array(["n", "s"])),
            r"key 'signals_b': shape \(3, 2\)",
        ),
        (dict(phase=np.zeros(9, int)), r"key 'phase'"),
        (dict(a=np.full((4, 14, 3), np.nan, np.float32)), r"key 'a': contains NaN"),
    ],
)
def test_load_errors_name_file_and_key(tmp_path, over, match):
    path = _write(tmp_path / "bad.npz", **over)
    with pytest.raises(ValueError, match=rf"bad\.npz.*{match}"):
        TwoPersonTrajectory.load(path)


def test_not_npz_and_missing_file(tmp_path):
    p = tmp_path / "text.npz"
    p.write_text("hello")
    with pytest.raises(ValueError, match="text.npz"):
        TwoPersonTrajectory.load(p)
    with pytest.raises(FileNotFoundError, match="nothere.npz"):
        TwoPersonTrajectory.load(tmp_path / "nothere.npz")


def test_resample():
    tr = make(T=51, fps=50.0)
    half = tr.resample(25.0)
    assert half.fps == 25.0 and half.n_frames == 26 and half.duration == pytest.approx(tr.duration)
    np.testing.assert_allclose(half.a, tr.a[::2], atol=1e-6)
    np.testing.assert_array_equal(half.signals_a, tr.signals_a[::2])
    np.testing.assert_array_equal(half.phase, tr.phase[::2])
    up = tr.resample(100.0)
    assert up.n_frames == 101
    # Linear motion is reproduced exactly between frames.
    np.testing.assert_allclose(up.a[1], 0.5 * (tr.a[0] + tr.a[1]), atol=1e-6)
    assert set(np.unique(up.signals_a)) <= {0, 1}
    with pytest.raises(ValueError, match="fps"):
        tr.resample(0.0)


def test_constructor_checks():
    a = np.zeros((4, 14, 3))
    with pytest.raises(ValueError, match="signals_b"):
        TwoPersonTrajectory(a=a, b=a, fps=25, signals_a=np.zeros((4, 1)), signal_names=("n",))
    with pytest.raises(ValueError, match="meta"):
        TwoPersonTrajectory(a=a, b=a, fps=25, meta={"x": object()})


@pytest.mark.skipif(not (DATA / "18_01.bvh").exists(), reason=f"CMU BVH files not found under {DATA}")
def test_from_bvh_pair(tmp_path):
    tr = TwoPersonTrajectory.from_bvh_pair(DATA / "18_01.bvh", DATA / "19_01.bvh", label="handshake")
    assert tr.n_frames == 303 and tr.fps == pytest.approx(120.0, rel=1e-4)
    low = TwoPersonTrajectory.from_bvh_pair(DATA / "18_01.bvh", DATA / "19_01.bvh", fps=25.0, label="handshake")
    assert low.fps == 25.0 and low.n_frames == int(302 / 120.0 * 25.0) + 1
    # Wrists approach in the handshake (measured 0.38 m at 25 fps), from 1.68 m apart.
    w = [JOINTS.index("l_wrist"), JOINTS.index("r_wrist")]
    gap = np.linalg.norm(low.a[:, w, None] - low.b[:, None, w], axis=-1).min(axis=(1, 2))
    assert gap.min() < 0.45 and gap[0] > 1.5
    low.save(tmp_path / "hs.npz")
    back = TwoPersonTrajectory.load(tmp_path / "hs.npz")
    assert back.meta["source"] == ["18_01.bvh", "19_01.bvh"] and back.label == "handshake"
