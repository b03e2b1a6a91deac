"""Pinhole camera: projection, look-at, ground back-projection, parameter dicts."""

import numpy as np
import pytest

from counterpart.body.camera import Camera, default_camera
from counterpart.body.kinematics import forward_kinematics
from counterpart.body.pose import neutral_pose
from counterpart.body.raster import rasterise_silhouettes
from counterpart.body.skeleton import DEFAULT_DIMS


def test_project_hand_computed():
    cam = Camera(fx=100.0, fy=200.0, cx=50.0, cy=40.0, width=100, height=80, R=np.eye(3), t=np.array([0.0, 0.0, 2.0]))
    X = np.array([[0.0, 0.0, 0.0], [1.0, 0.5, 2.0], [-0.2, -0.1, 0.0]])
    uv = cam.project(X)
    np.testing.assert_allclose(
        uv, [[50.0, 40.0], [50 + 100 * 1 / 4, 40 + 200 * 0.5 / 4], [50 - 100 * 0.1, 40 - 200 * 0.05]]
    )
    np.testing.assert_allclose(cam.depth(X), [2.0, 4.0, 2.0])
    # Broadcasting over leading axes; behind the camera is NaN.
    assert cam.project(np.zeros((4, 5, 3))).shape == (4, 5, 2)
    assert np.isnan(cam.project(np.array([0.0, 0.0, -3.0]))).all()


def test_look_at_axes():
    cam = Camera.look_at(eye=(0, 1, 5), target=(0, 1, 0), fov_deg=90.0, width=200, height=100)
    # Looking towards -Z: image x right is world +X, image y down is world -Y.
    np.testing.assert_allclose(cam.R, [[1, 0, 0], [0, -1, 0], [0, 0, -1]], atol=1e-12)
    np.testing.assert_allclose(cam.centre, (0, 1, 5), atol=1e-12)
    assert cam.fx == pytest.approx(100.0)  # tan(45 deg) = 1: half width / 1
    np.testing.assert_allclose(cam.project(np.array([0.0, 1.0, 0.0])), (99.5, 49.5))
    # A point 1 m right and 1 m up at 5 m depth: 100 * 1/5 = 20 px right and up.
    np.testing.assert_allclose(cam.project(np.array([1.0, 2.0, 0.0])), (119.5, 29.5))
    with pytest.raises(ValueError, match="fov"):
        Camera.look_at((0, 1, 5), (0, 1, 0), 190.0, 10, 10)
    with pytest.raises(ValueError, match="straight up"):
        Camera.look_at((0, 1, 0), (0, 0, 0), 60.0, 10, 10)


def test_ground_point_round_trip():
    cam = default_camera()
    rng = np.random.default_rng(1)
    G = np.stack([rng.uniform(-2, 2, 50), np.zeros(50), rng.uniform(-2, 2, 50)], axis=1)
    uv = cam.project(G)
    back = cam.ground_point(uv[:, 0], uv[:, 1])
    np.testing.assert_allclose(back, G, atol=1e-9)
    # Above the horizon there is no ground.
    assert np.isnan(cam.ground_point(160.0, -1000.0)).all()


def test_default_camera_sees_two_people():
    cam = default_camera()
    assert (cam.width, cam.height) == (320, 240)
    assert 1.4 < cam.centre[1] < 1.8 and 4.0 <= np.hypot(cam.centre[0], cam.centre[2]) <= 5.0
    P = np.stack([neutral_pose(x=-0.5, yaw=np.pi / 2), neutral_pose(x=0.5, yaw=-np.pi / 2)])
    S = rasterise_silhouettes(P, DEFAULT_DIMS, cam)
    # Fully in view: nothing touches the border, and both stand on the lower half of the image.
    for s in S:
        assert s.any() and not (s[0].any() or s[-1].any() or s[:, 0].any() or s[:, -1].any())
    uv = cam.project(forward_kinematics(P))
    assert cam.in_image(uv).all()
    assert uv[0, :, 0].max() < uv[1, :, 0].min()  # person at -X appears on the left


def test_dict_round_trip_and_errors():
    cam = default_camera(640, 480)
    d = cam.to_dict()
    again = Camera.from_dict(d)
    assert again.to_dict() == d
    X = np.array([[0.3, 1.2, -0.4]])
    np.testing.assert_allclose(again.project(X), cam.project(X))
    la = Camera.from_dict({"eye": [0, 1.6, 4.0], "target": [0, 0.9, 0], "fov_deg": 55, "width": 640, "height": 480})
    np.testing.assert_allclose(la.project(X), cam.project(X))
    with pytest.raises(ValueError, match="unknown key.*focal"):
        Camera.from_dict({**d, "focal": 3})
    bad = dict(d)
    del bad["cy"]
    with pytest.raises(ValueError, match="missing key.*cy"):
        Camera.from_dict(bad)
    with pytest.raises(ValueError, match="rotation"):
        Camera.from_dict({**d, "R": [[1, 0, 0], [0, 1, 0], [0, 0, 2]]})
    with pytest.raises(ValueError, match="width"):
        Camera.from_dict({**d, "width": 0})


def test_one_camera_for_a_frame_size_default_scaled_or_refused():
    from counterpart.body.camera import camera_for_size

    # no calibration: the default camera at that size, square pixels at any aspect ratio
    wide = camera_for_size(None, 612, 288)
    assert wide.to_dict() == default_camera(612, 288).to_dict() and wide.fx == wide.fy
    # a calibration for that size is used as it is; one for another size of the same aspect is scaled
    cal = Camera.look_at((0.3, 2.5, 5.0), (0.0, 0.9, 0.0), 50.0, 640, 480)
    assert camera_for_size(cal, 640, 480) is cal
    half = camera_for_size(cal, 320, 240)
    X = np.array([[0.2, 1.0, 0.1], [-0.5, 0.0, 1.0]])
    np.testing.assert_allclose((half.project(X) + 0.5) * 2, cal.project(X) + 0.5, atol=1e-9)
    # another aspect ratio cannot be scaled right: refused with what to do
    with pytest.raises(ValueError, match="calibrated for 640x480 but the frames are 640x360"):
        camera_for_size(cal, 640, 360)
