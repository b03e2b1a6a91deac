"""BVH reader: a hand-written file with a known answer, error messages, and the CMU handshake."""

import numpy as np
import pytest

from counterpart.body.bvh import CMU_SCALE, CMU_TO_JOINTS14, bvh_to_joints14, read_bvh
from counterpart.body.skeleton import JOINT_INDEX, JOINTS
from tests.shared_data import CMU as DATA

CMU_A, CMU_B = DATA / "18_01.bvh", DATA / "19_01.bvh"

TINY = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation
  JOINT Arm
  {
    OFFSET 1 0 0
    CHANNELS 3 Xrotation Zrotation Yrotation
    End Site
    {
      OFFSET 0 2 0
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.5
1 2 3  0 0 0   0 0 0
1 2 3  90 0 0  0 0 0
0 0 0  90 0 0  90 90 0
"""


@pytest.fixture
def tiny(tmp_path):
    p = tmp_path / "tiny.bvh"
    p.write_text(TINY)
    return p


def test_tiny_known_answer(tiny):
    b = read_bvh(tiny, scale=1.0)
    assert b.joint_names == ["Hips", "Arm"] and list(b.parents) == [-1, 0]
    assert b.channels[1] == ("Xrotation", "Zrotation", "Yrotation")
    assert b.n_frames == 3 and b.frame_time == 0.5 and b.fps == 2.0
    assert b.end_site_names == ["Arm_End"]
    X = b.world_positions(include_end_sites=True)
    assert X.shape == (3, 3, 3)
    # Frame 0: rest pose, translated.
    np.testing.assert_allclose(X[0], [[1, 2, 3], [2, 2, 3], [2, 4, 3]], atol=1e-12)
    # Frame 1: root Z-rotation by 90 degrees turns +X into +Y and +Y into -X.
    np.testing.assert_allclose(X[1], [[1, 2, 3], [1, 3, 3], [-1, 3, 3]], atol=1e-12)
    # Frame 2: Arm = Rx(90) Rz(90) (declared order), applied to (0, 2, 0):
    # Rz(90): (0,2,0) -> (-2,0,0); Rx(90) leaves it; root Rz(90): (-2,0,0) -> (0,-2,0).
    np.testing.assert_allclose(X[2], [[0, 0, 0], [0, 1, 0], [0, -1, 0]], atol=1e-12)
    # Scale converts units.
    np.testing.assert_allclose(read_bvh(tiny).world_positions()[0, 1], np.array([2, 2, 3]) * CMU_SCALE)


@pytest.mark.parametrize(
    "broken, line, what",
    [
        (TINY.replace("OFFSET 1 0 0", "OFFSET 1 zero 0"), 8, "number"),
        (TINY.replace("Xrotation Zrotation", "Xrotation Wrotation"), 9, "unknown channel"),
        (TINY.replace("1 2 3  90 0 0  0 0 0", "1 2 3  90 0 0  0 0"), 20, "8 values"),
        (TINY.replace("Frames: 3", "Frames: 4"), 21, "4 frames"),
        (TINY.replace("HIERARCHY", "HIERACHY"), 1, "not a BVH"),
        (TINY.split("MOTION")[0].rstrip().rstrip("}"), 14, "end of file"),
    ],
)
def test_corrupt_file_names_file_and_line(tmp_path, broken, line, what):
    p = tmp_path / "broken.bvh"
    p.write_text(broken)
    with pytest.raises(ValueError, match=rf"broken\.bvh: line {line}: .*{what}"):
        read_bvh(p)


def test_binary_file_is_rejected(tmp_path):
    p = tmp_path / "image.bvh"
    p.write_bytes(b"\x89PNG\r\n\x1a\n\x00\xff\xfe")
    with pytest.raises(ValueError, match="image.bvh"):
        read_bvh(p)


def test_mapping_errors(tiny):
    with pytest.raises(ValueError, match="Head"):
        bvh_to_joints14(read_bvh(tiny))


needs_cmu = pytest.mark.skipif(
    not (CMU_A.exists() and CMU_B.exists()), reason=f"CMU handshake BVH files not found under {DATA}"
)


@pytest.fixture(scope="module")
def cmu():
    return read_bvh(CMU_A), read_bvh(CMU_B)


@needs_cmu
def test_cmu_structure(cmu):
    for b in cmu:
        assert b.n_frames == 304 and len(b.joint_names) == 31 and b.motion.shape == (304, 96)
        assert b.fps == pytest.approx(120.0, rel=1e-4)
        assert all(c == ("Zrotation", "Yrotation", "Xrotation") for c in b.channels[1:])
        assert set(CMU_TO_JOINTS14.values()) <= set(b.joint_names)


@needs_cmu
def test_cmu_handshake_facts(cmu):
    a, b = cmu
    pa, pb = a.world_positions(True)[1:], b.world_positions(True)[1:]  # drop the T-pose
    hips = a.index("Hips")
    d = np.linalg.norm(pa[:, hips] - pb[:, hips], axis=-1)
    assert d[0] == pytest.approx(1.98, abs=0.1)  # measured 1.980 m
    assert d.min() == pytest.approx(0.74, abs=0.1)  # measured 0.738 m
    tips = [a.index(n) for n in ("LeftHandIndex1_End", "LThumb_End", "RightHandIndex1_End", "RThumb_End")]
    gap = np.linalg.norm(pa[:, tips, None] - pb[:, None, tips], axis=-1).min(axis=(1, 2))
    assert gap.min() == pytest.approx(0.23, abs=0.05)  # measured 0.227 m
    assert abs(int(gap.argmin()) + 1 - 124) <= 10  # measured at file frame 124
    feet = [
        a.index(n)
        for n in ("LeftFoot", "RightFoot", "LeftToeBase", "RightToeBase", "LeftToeBase_End", "RightToeBase_End")
    ]
    for p in (pa, pb):
        lowest = p[:, feet, 1].min(axis=1)
        # Typical lowest foot point: measured 3.0 cm (18_01) and 2.2 cm (19_01).
        assert abs(np.median(lowest)) < 0.04
        # Extremes: measured -3.6 to 6.0 cm.
        assert lowest.min() > -0.05 and lowest.max() < 0.08


@needs_cmu
def test_cmu_joints14(cmu):
    a, b = cmu
    J = bvh_to_joints14(a)
    assert J.shape == (303, 14, 3)
    np.testing.assert_array_equal(J, bvh_to_joints14(a, drop_first=False)[1:])
    j = JOINT_INDEX
    # Anatomical order from top to bottom, left on the person's left.
    y = np.median(J[..., 1], axis=0)
    assert y[j["head"]] > y[j["neck"]] > y[j["l_elbow"]] > y[j["l_hip"]] > y[j["l_knee"]] > y[j["l_ankle"]]
    # Bone lengths are rigid across frames (mocap skeleton: fixed offsets).
    for c, p in (("l_elbow", "l_shoulder"), ("r_knee", "r_hip"), ("l_ankle", "l_knee")):
        L = np.linalg.norm(J[:, j[c]] - J[:, j[p]], axis=-1)
        assert L.std() < 1e-9 and 0.2 < L.mean() < 0.5
    assert len(JOINTS) == J.shape[1]


@needs_cmu
def test_cmu_left_is_own_left(cmu):
    # forward = (left hip - right hip) x up, under our convention (left +X when facing +Z).
    # The two walk towards each other, so each one's forward must point at the other.
    a, b = cmu
    Ja, Jb = bvh_to_joints14(a), bvh_to_joints14(b)
    j = JOINT_INDEX
    for me, other in ((Ja, Jb), (Jb, Ja)):
        fwd = np.cross(me[:, j["l_hip"]] - me[:, j["r_hip"]], (0.0, 1.0, 0.0))
        to_other = other[:, j["l_hip"]] + other[:, j["r_hip"]] - me[:, j["l_hip"]] - me[:, j["r_hip"]]
        cos = (fwd * to_other).sum(-1) / np.linalg.norm(fwd, axis=-1) / np.linalg.norm(to_other, axis=-1)
        assert np.median(cos) > 0.8


@needs_cmu
def test_cmu_inverse_kinematics(cmu):
    # Mocap -> pose vectors -> our cone body with fitted dimensions: joints come back within
    # a few cm (measured max 4.9 cm, at the shoulders, which are rigid in our model).
    from counterpart.body.ik import dims_from_joints, inverse_kinematics
    from counterpart.body.kinematics import forward_kinematics, lowest_point
    from counterpart.body.pose import within_limits

    for b in cmu:
        X = bvh_to_joints14(b)
        dims = dims_from_joints(X)
        assert 1.4 < dims.height < 1.8  # measured 1.58 m and 1.61 m
        P = inverse_kinematics(X)
        assert within_limits(P).all()
        err = np.linalg.norm(forward_kinematics(P, dims) - X, axis=-1)
        assert err.max() < 0.07 and np.median(err) < 0.01
        assert abs(np.median(lowest_point(P, dims))) < 0.05
