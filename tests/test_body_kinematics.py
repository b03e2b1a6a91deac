"""Forward kinematics, pose limits, cones and rasterised silhouettes of the body model."""

import numpy as np
import pytest

from counterpart.body.camera import default_camera
from counterpart.body.kinematics import (
    anchor_points,
    cone_endpoints,
    forward_kinematics,
    frames,
    lowest_point,
    rot_x,
    rot_y,
    rot_z,
)
from counterpart.body.pose import DOF, DOF_INDEX, DOF_NAMES, LOWER, UPPER, clip_to_limits, neutral_pose, within_limits
from counterpart.body.raster import (
    cone_interior_points,
    cone_outline_points,
    rasterise_silhouettes,
    render_edge_maps,
)
from counterpart.body.skeleton import (
    ANCHOR_INDEX,
    BONES,
    DEFAULT_DIMS,
    JOINT_INDEX,
    JOINTS,
    N_SEGMENTS,
    PARENT,
    SEGMENTS,
    BodyDims,
    bone_lengths,
    with_bone_lengths,
)

J = JOINT_INDEX
D = DEFAULT_DIMS


def zero_pose(y: float = 1.0) -> np.ndarray:
    P = np.zeros(DOF)
    P[DOF_INDEX["root_y"]] = y
    return P


def random_poses(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    lo, hi = LOWER.copy(), UPPER.copy()
    lo[:3], hi[:3] = (-2, 0.5, -2), (2, 1.2, 2)
    return rng.uniform(lo, hi, size=(n, DOF))


def test_skeleton_tables():
    assert JOINTS == (
        "head",
        "neck",
        "l_shoulder",
        "l_elbow",
        "l_wrist",
        "r_shoulder",
        "r_elbow",
        "r_wrist",
        "l_hip",
        "l_knee",
        "l_ankle",
        "r_hip",
        "r_knee",
        "r_ankle",
    )
    assert len(PARENT) == 14 and len(SEGMENTS) == N_SEGMENTS == 16
    assert all(p < j for j, p in enumerate(PARENT) if p >= 0 and j != 0) and PARENT[0] == 1
    assert len(DOF_NAMES) == DOF == 28 and LOWER.shape == UPPER.shape == (DOF,)
    assert np.all(LOWER < UPPER)


def test_neutral_pose_heights():
    X = forward_kinematics(neutral_pose(D))[0]
    assert X.shape == (14, 3)
    np.testing.assert_allclose(X[J["l_ankle"], 1], D.ankle_height, atol=1e-12)
    np.testing.assert_allclose(X[J["l_knee"], 1], D.ankle_height + D.shin, atol=1e-12)
    np.testing.assert_allclose(X[J["l_hip"], 1], 0.93, atol=1e-12)
    np.testing.assert_allclose(X[J["neck"], 1], 1.45, atol=1e-12)
    np.testing.assert_allclose(X[J["head"], 1], 1.64, atol=1e-12)
    # Left side is +X when facing +Z.
    assert X[J["l_hip"], 0] == pytest.approx(D.hip_width / 2)
    assert X[J["r_shoulder"], 0] == pytest.approx(-D.shoulder_width / 2)
    # Stature 1.75 m: crown of the head cone; soles touch the ground.
    ends, radii = cone_endpoints(neutral_pose(D))
    assert ends[0, 0, 1, 1] == pytest.approx(1.75)
    assert lowest_point(neutral_pose(D))[0] == pytest.approx(0.0, abs=0.005)


def test_elbow_bend_90_puts_wrist_forward():
    P = zero_pose()
    P[DOF_INDEX["l_elbow_flex"]] = np.pi / 2
    X = forward_kinematics(P)[0]
    np.testing.assert_allclose(X[J["l_wrist"]] - X[J["l_elbow"]], (0, 0, D.forearm), atol=1e-12)
    np.testing.assert_allclose(
        X[J["l_elbow"]], (D.shoulder_width / 2, 1.0 + D.torso_length - D.shoulder_drop - D.upper_arm, 0), atol=1e-12
    )
    # Shoulder abduction 90 degrees: the left arm points to +X (its own left), horizontally.
    P = zero_pose()
    P[DOF_INDEX["l_shoulder_abd"]] = np.pi / 2
    P[DOF_INDEX["r_shoulder_abd"]] = np.pi / 2
    X = forward_kinematics(P)[0]
    np.testing.assert_allclose(X[J["l_wrist"]] - X[J["l_shoulder"]], (D.upper_arm + D.forearm, 0, 0), atol=1e-12)
    np.testing.assert_allclose(X[J["r_wrist"]] - X[J["r_shoulder"]], (-D.upper_arm - D.forearm, 0, 0), atol=1e-12)
    # Shoulder flexion 90 degrees: arm points forward (+Z).
    P = zero_pose()
    P[DOF_INDEX["r_shoulder_flex"]] = np.pi / 2
    X = forward_kinematics(P)[0]
    np.testing.assert_allclose(X[J["r_elbow"]] - X[J["r_shoulder"]], (0, 0, D.upper_arm), atol=1e-12)


def test_knee_hip_torso_head_signs():
    P = zero_pose()
    P[DOF_INDEX["l_hip_flex"]] = np.pi / 2
    P[DOF_INDEX["l_knee_flex"]] = np.pi / 2
    X = forward_kinematics(P)[0]
    # Thigh forward, shin hanging straight down from the knee.
    np.testing.assert_allclose(X[J["l_knee"]] - X[J["l_hip"]], (0, 0, D.thigh), atol=1e-12)
    np.testing.assert_allclose(X[J["l_ankle"]] - X[J["l_knee"]], (0, -D.shin, 0), atol=1e-12)
    P = zero_pose()
    P[DOF_INDEX["torso_flex"]] = np.pi / 2
    X = forward_kinematics(P)[0]
    np.testing.assert_allclose(X[J["neck"]], (0, 1.0, D.torso_length), atol=1e-12)
    P = zero_pose()
    P[DOF_INDEX["head_turn"]] = np.pi / 2
    P[DOF_INDEX["head_nod"]] = np.pi / 2
    X = forward_kinematics(P)[0]
    # Nodding by 90 degrees after turning left puts the head out to the person's left (+X).
    np.testing.assert_allclose(X[J["head"]] - X[J["neck"]], (D.neck_to_head, 0, 0), atol=1e-12)


def test_yaw_rotates_body_about_vertical():
    P = neutral_pose(D, x=0.3, z=-0.2)
    Q = P.copy()
    Q[DOF_INDEX["root_yaw"]] = np.pi / 2
    X, Y = forward_kinematics(np.stack([P, Q]))
    root = np.array([0.3, D.hip_height, -0.2])
    # Ry(90): (x, y, z) -> (z, y, -x) about the root.
    rel = X - root
    np.testing.assert_allclose(Y - root, np.stack([rel[:, 2], rel[:, 1], -rel[:, 0]], axis=1), atol=1e-12)
    # The toes point along +Z at yaw 0 and along +X at yaw +90 degrees.
    pts = frames(np.stack([P, Q]))[0]
    from counterpart.body.skeleton import ANCHOR_INDEX

    toe = pts[:, ANCHOR_INDEX["l_toe"]] - pts[:, J["l_ankle"]]
    assert toe[0, 2] > 0.1 and abs(toe[0, 0]) < 1e-9
    assert toe[1, 0] > 0.1 and abs(toe[1, 2]) < 1e-9


def test_bone_lengths_preserved_and_vectorised_equals_per_pose():
    P = random_poses(200)
    X = forward_kinematics(P)
    X0 = forward_kinematics(neutral_pose(D))[0]
    for j, p in BONES:
        lengths = np.linalg.norm(X[:, j] - X[:, p], axis=-1)
        np.testing.assert_allclose(lengths, np.linalg.norm(X0[j] - X0[p]), atol=1e-10)
    hips = np.linalg.norm(X[:, J["l_hip"]] - X[:, J["r_hip"]], axis=-1)
    np.testing.assert_allclose(hips, D.hip_width, atol=1e-10)
    single = np.stack([forward_kinematics(p)[0] for p in P[:20]])
    np.testing.assert_array_equal(single, X[:20])
    ends, radii = cone_endpoints(P)
    assert ends.shape == (200, 16, 2, 3) and radii.shape == (16, 2)


def test_clip_to_limits():
    P = random_poses(50) * 3.0
    C = clip_to_limits(P)
    assert within_limits(C).all()
    assert not within_limits(P).all()
    inside = random_poses(10)
    inside[:, DOF_INDEX["root_yaw"]] = np.clip(inside[:, DOF_INDEX["root_yaw"]], -3.0, 3.0)
    np.testing.assert_allclose(clip_to_limits(inside), inside)
    # Elbow hyper-extension is clipped to straight; yaw wraps rather than clips.
    Q = zero_pose()
    Q[DOF_INDEX["l_elbow_flex"]] = -0.5
    Q[DOF_INDEX["root_yaw"]] = 3 * np.pi / 2
    C = clip_to_limits(Q)
    assert C[DOF_INDEX["l_elbow_flex"]] == 0.0
    assert C[DOF_INDEX["root_yaw"]] == pytest.approx(-np.pi / 2)
    with pytest.raises(ValueError, match="28"):
        clip_to_limits(np.zeros(5))


def test_scaled_dims():
    small = D.scaled(1.5)
    assert small.height == 1.5
    assert small.thigh == pytest.approx(D.thigh * 1.5 / 1.75)
    ends, _ = cone_endpoints(neutral_pose(small), small)
    assert ends[0, 0, 1, 1] == pytest.approx(1.5)
    with pytest.raises(ValueError, match="height"):
        D.scaled(-1)
    with pytest.raises(ValueError, match="thigh"):
        BodyDims(thigh=float("nan"))


def test_silhouettes_contain_projected_joints_and_sample_points():
    cam = default_camera()
    P = np.stack([neutral_pose(D, x=-0.5, yaw=0.4), neutral_pose(D, x=0.5, yaw=-0.4), random_poses(1, 3)[0]])
    P[2, :3] = (0.0, 0.9, 0.0)
    S = rasterise_silhouettes(P, D, cam)
    assert S.shape == (3, cam.height, cam.width) and S.dtype == bool
    uv = np.round(cam.project(forward_kinematics(P))).astype(int)
    assert cam.in_image(uv).all()
    for i in range(3):
        assert S[i, uv[i, :, 1], uv[i, :, 0]].all(), f"pose {i}: a joint falls outside its silhouette"
    # A standing person 4 m away covers a plausible area and is taller than wide.
    ys, xs = np.nonzero(S[0])
    assert 1000 < S[0].sum() < 8000
    assert (ys.max() - ys.min()) > 2 * (xs.max() - xs.min())
    # Interior sample points fall inside the silhouette, nearly all of them.
    inner = np.round(cone_interior_points(P, D, cam)).astype(int)
    assert inner.shape == (3, 16 * 4 * 3, 2)
    frac = np.mean([S[i, inner[i, :, 1], inner[i, :, 0]].mean() for i in range(3)])
    assert frac > 0.97
    # Outline points lie near the edge map.
    out = cone_outline_points(P, D, cam)
    assert out.shape == (3, 16 * 2 * 4, 2)
    E = render_edge_maps(P, D, cam, mode="cones")
    import cv2

    dist = cv2.distanceTransform((~E[0]).astype(np.uint8), cv2.DIST_L2, 3)
    o = np.round(out[0]).astype(int)
    assert np.median(dist[o[:, 1], o[:, 0]]) <= 1.5
    edges = render_edge_maps(P[:1], D, cam)
    assert edges[0].sum() < S[0].sum() and (edges[0] <= S[0]).all()


def test_vectorised_samplers_match_per_pose():
    cam = default_camera()
    P = random_poses(64, 7)
    P[:, 1] = 0.9
    P[:, [0, 2]] = 0.0
    out = cone_outline_points(P, D, cam)
    inn = cone_interior_points(P, D, cam, n_along=3, n_across=2)
    for i in (0, 17, 63):
        np.testing.assert_allclose(cone_outline_points(P[i], D, cam)[0], out[i])
        np.testing.assert_allclose(cone_interior_points(P[i], D, cam, n_along=3, n_across=2)[0], inn[i])


def test_inverse_kinematics_round_trip():
    from counterpart.body.ik import dims_from_joints, inverse_kinematics

    P = random_poses(300, 11)
    # What 14 joints cannot show is fixed by the solver: pelvis pitch and head turn.
    P[:, DOF_INDEX["root_pitch"]] = 0.0
    P[:, DOF_INDEX["head_turn"]] = 0.0
    X = forward_kinematics(P)
    Q = inverse_kinematics(X)
    assert Q.shape == (300, DOF)
    err = np.linalg.norm(forward_kinematics(Q) - X, axis=-1)
    assert err.max() < 1e-3
    # With elbows and knees clearly bent and limbs away from the gimbal poles (abduction of
    # +-90 degrees), the angles themselves come back.
    rng = np.random.default_rng(5)
    P[:, [15, 19, 23, 27]] = rng.uniform(0.3, 2.5, (300, 4))
    P[:, [13, 17, 21, 25]] = rng.uniform(-0.3, 1.2, (300, 4))
    Q = inverse_kinematics(forward_kinematics(P))
    np.testing.assert_allclose(Q[:, 3:], P[:, 3:], atol=1e-9)
    d = dims_from_joints(forward_kinematics(random_poses(20, 2)))
    for name in ("thigh", "shin", "upper_arm", "forearm", "hip_width", "shoulder_width", "torso_length"):
        assert getattr(d, name) == pytest.approx(getattr(D, name), abs=1e-9)


def test_frames_follow_the_documented_matrix_chain() -> None:
    """The column-wise chain equals the module docstring's products of rot_x/rot_y/rot_z
    matrices, and anchor_points equals frames' points.
    """
    P = random_poses(40, seed=7)
    dims = D.scaled(1.7)
    pts, R = frames(P, dims)
    g = {n: P[:, i] for n, i in DOF_INDEX.items()}
    pel = rot_y(g["root_yaw"]) @ rot_x(g["root_pitch"]) @ rot_z(-g["root_roll"])
    tor = pel @ rot_y(g["torso_twist"]) @ rot_x(g["torso_flex"]) @ rot_z(-g["torso_lateral"])
    head = tor @ rot_y(g["head_turn"]) @ rot_x(g["head_nod"]) @ rot_z(-g["head_tilt"])
    expect = {"pelvis": pel, "torso": tor, "head": head}
    for s, sign in (("l", 1.0), ("r", -1.0)):
        ua = (
            tor
            @ rot_x(-g[f"{s}_shoulder_flex"])
            @ rot_z(sign * g[f"{s}_shoulder_abd"])
            @ rot_y(-sign * g[f"{s}_shoulder_rot"])
        )
        th = pel @ rot_x(-g[f"{s}_hip_flex"]) @ rot_z(sign * g[f"{s}_hip_abd"]) @ rot_y(-sign * g[f"{s}_hip_rot"])
        expect.update(
            {
                f"{s}_upper_arm": ua,
                f"{s}_forearm": ua @ rot_x(-g[f"{s}_elbow_flex"]),
                f"{s}_thigh": th,
                f"{s}_shin": th @ rot_x(g[f"{s}_knee_flex"]),
            }
        )
    assert sorted(R) == sorted(expect)
    for name, M in expect.items():
        np.testing.assert_allclose(R[name], M, atol=1e-12, err_msg=name)
    sn = expect["l_shin"]
    toe = pts[:, J["l_ankle"]] + sn @ np.array([0.0, -(dims.ankle_height - dims.r_toe), dims.foot_length])
    np.testing.assert_allclose(pts[:, ANCHOR_INDEX["l_toe"]], toe, atol=1e-12)
    neck = P[:, :3] + tor @ np.array([0.0, dims.torso_length, 0.0])
    np.testing.assert_allclose(pts[:, J["neck"]], neck, atol=1e-12)
    np.testing.assert_allclose(anchor_points(P, dims), pts, atol=0)


def test_compiled_anchor_points_equal_the_numpy_chain_for_one_body_and_rows_of_several() -> None:
    """The compiled kernel gives the numpy chain's points to the last bit, for one body and for
    a batch of several people's poses (RowDims), any angle (beyond the joints' limits too).
    """
    from counterpart.body.kinematics import KERNEL_MIN_POSES, _chain, row_dims

    rng = np.random.default_rng(11)
    P = np.vstack([random_poses(50, seed=8), rng.uniform(-7, 7, (30, DOF))])
    for dims in (D, D.scaled(1.55)):
        assert np.array_equal(anchor_points(P, dims), _chain(P, dims, rotations=False)[0])
    rows = row_dims((D.scaled(1.6), D, D.scaled(1.9)), (20, 35, 25))
    got = anchor_points(P, rows)
    assert np.array_equal(got, _chain(P, rows, rotations=False)[0])
    assert np.array_equal(got[20:55], anchor_points(P[20:55], D))  # each row its own person's body
    assert np.array_equal(anchor_points(P[3]), anchor_points(P[3:4]))  # a single pose is N = 1
    # a few poses (the numpy chain) and a batch (the kernel) agree row for row
    few = P[: KERNEL_MIN_POSES - 1]
    assert np.array_equal(anchor_points(few, D), anchor_points(P, D)[: len(few)])


def test_inverse_kinematics_of_one_frame_is_the_batch_row_and_the_limbs_one_at_a_time() -> None:
    # the four limbs go through ik._limb as one batch of rows, and dims_from_joints skips the median
    # of a single frame: each must give the numbers of the per-limb, per-frame computation exactly
    from counterpart.body.ik import _limb, _median0, dims_from_joints, inverse_kinematics

    rng = np.random.default_rng(3)
    X = forward_kinematics(random_poses(6, 4)) + rng.normal(0, 0.02, (6, 14, 3))
    Q = inverse_kinematics(X)
    for n in range(6):
        assert np.array_equal(inverse_kinematics(X[n]), Q[n : n + 1])
    # one limb at a time (scalar side and knee), under the torso and pelvis frames of the batch
    R = rng.normal(size=(6, 3, 3))
    top, mid, end = (X[:, JOINT_INDEX[j]] for j in ("l_hip", "l_knee", "l_ankle"))
    for sign in (1.0, -1.0):
        for knee in (False, True):
            one = _limb(R, top, mid, end, sign, knee)
            rows = _limb(
                np.concatenate([R, R]), np.concatenate([top, top]), np.concatenate([mid, mid]),
                np.concatenate([end, end]), np.full(12, sign), np.full(12, knee),
            )  # fmt: skip
            assert all(np.array_equal(a, b[6:]) for a, b in zip(one, rows))
    lengths = np.linalg.norm(X[:1, :, None] - X[:1, None], axis=-1).reshape(1, -1)
    assert np.array_equal(_median0(lengths), np.median(lengths, axis=0))
    assert np.array_equal(_median0(lengths[:, :3].T), np.median(lengths[:, :3].T, axis=0))
    assert dims_from_joints(X[2]).height > 1.0


def test_cross3_norm3_and_the_ankle_percentile_are_numpys_to_the_bit() -> None:
    """The body fit of every partner (renderer, responder) and the partner's facets use
    hand-written cross products, norms and a one-frame percentile, cheaper than numpy's calls on so
    few numbers; the partner's pixels stay the same only while they give numpy's bits.
    """
    from counterpart.body import ik
    from counterpart.body.kinematics import cross3, norm3

    rng = np.random.default_rng(7)
    for shape in ((5000, 3), (16, 16, 3), (1, 13, 3)):
        a = rng.normal(size=shape) * rng.uniform(1e-3, 1e3, (*shape[:-1], 1))
        b = rng.normal(size=shape)
        assert np.array_equal(cross3(a, b), np.cross(a, b))
        assert np.array_equal(norm3(a), np.linalg.norm(a, axis=-1, keepdims=True))
    y = rng.normal(size=(5000, 1, 2)) * rng.uniform(1e-3, 10, (5000, 1, 1))
    assert all(ik._low_ankle(v) == float(np.percentile(v, 5)) for v in y)
    many = rng.normal(size=(7, 2))
    assert ik._low_ankle(many) == float(np.percentile(many, 5))


def test_a_pose_put_on_another_body_keeps_its_bone_directions_and_takes_that_bodys_lengths() -> None:
    rng = np.random.default_rng(3)
    P = np.tile(neutral_pose(x=0.4, z=-1.0, yaw=0.7), (6, 1))
    P[:, DOF_INDEX["r_shoulder_flex"]] = rng.uniform(0.0, 2.0, 6)
    P[:, DOF_INDEX["l_knee_flex"]] = rng.uniform(0.0, 1.2, 6)
    small, tall = forward_kinematics(P, D.scaled(1.5)), forward_kinematics(P, D.scaled(1.9))
    # the poses of the small body on the tall body's bones: the tall body, joint for joint
    target = bone_lengths(tall)[0]
    np.testing.assert_allclose(with_bone_lengths(small, target), tall, atol=1e-9)
    # limbs that stretch and shrink from frame to frame (a generated pose) get one body
    stretched = small * rng.uniform(0.9, 1.1, (6, 1, 1))
    out = with_bone_lengths(stretched, target)
    np.testing.assert_allclose(bone_lengths(out), np.tile(target, (6, 1)), atol=1e-9)
    for j, parent in BONES:  # each bone points where it pointed
        a, b = stretched[:, j] - stretched[:, parent], out[:, j] - out[:, parent]
        cos = (a * b).sum(-1) / np.linalg.norm(a, axis=-1) / np.linalg.norm(b, axis=-1)
        assert cos.min() > 1 - 1e-9, JOINTS[j]
    # the pelvis (mid-hip) stays where it was
    mid = lambda X: 0.5 * (X[:, J["l_hip"]] + X[:, J["r_hip"]])  # noqa: E731
    np.testing.assert_allclose(mid(out), mid(stretched), atol=1e-9)
