"""The camera estimate from people (nodes.calibration.estimate) on exact projections of known
cameras: people of known statures walking on the ground at different depths, their head and foot
points projected and perturbed by a pixel of noise."""
from __future__ import annotations

import numpy as np
import pytest

from body.camera import Camera
from nodes.calibration.estimate import estimate_camera, head_foot, rotation, usable
from nodes.calibration.smooth import CameraSmoother, camera_parameters

W, H = 320, 240


def _camera(height: float, tilt_deg: float, fov_deg: float, roll_deg: float = 0.0, distance: float = 6.0) -> Camera:
    R = rotation(np.radians(tilt_deg), np.radians(roll_deg))
    f = (W / 2) / np.tan(np.radians(fov_deg) / 2)
    centre = np.array([0.0, height, distance])
    return Camera(f, f, (W - 1) / 2, (H - 1) / 2, W, H, R, -R @ centre)


def _walkers(cam: Camera, seed: int, n_people: int = 6, frames: int = 100, fps: float = 10.0, noise: float = 1.0):
    """Heads, feet (pixels), person ids and times of people walking in straight lines (in depth too),
    each leaning a little (2% of the stature, to one side for the whole walk)."""
    rng = np.random.default_rng(seed)
    heads, feet, ids = [], [], []
    for p in range(n_people):
        stature = rng.normal(1.70, 0.07)
        start = np.array([rng.uniform(-1.5, 1.5), 0.0, rng.uniform(-2.0, 1.0)])
        heading = rng.uniform(0, 2 * np.pi)
        step = 0.5 * np.array([np.cos(heading), 0.0, np.sin(heading)]) / fps   # 0.5 m/s, to and fro
        lean = np.array([rng.normal(0, 0.02 * stature), 0.0, 0.0])
        for t in range(frames):
            g = start + step * (t % 50 if t % 100 < 50 else 50 - t % 50)
            feet.append(cam.project(g) + rng.normal(0, noise, 2))
            heads.append(cam.project(g + lean + [0.0, stature, 0.0]) + rng.normal(0, noise, 2))
            ids.append(p)
    t = np.tile(np.arange(frames) / fps, n_people)
    return np.array(heads), np.array(feet), np.array(ids), t


@pytest.mark.parametrize("height,tilt,fov,roll", [(2.5, 20.0, 50.0, 0.0), (1.4, 12.0, 70.0, 3.0),
                                                  (3.0, 30.0, 42.0, -2.0)])
def test_a_tilted_camera_is_recovered_within_its_uncertainty(height: float, tilt: float, fov: float,
                                                             roll: float) -> None:
    cam = _camera(height, tilt, fov, roll)
    heads, feet, ids, t = _walkers(cam, seed=int(tilt))
    est = estimate_camera(heads, feet, ids, (W, H), t)
    assert est is not None and est.n_people == 6
    assert abs(est.tilt_deg - tilt) < 2.0 and abs(est.roll_deg - roll) < 1.0, est.describe()
    assert abs(est.focal / cam.fx - 1) < 0.10 and abs(est.height / height - 1) < 0.10, est.describe()
    # the uncertainty says how far off it may be: each error within 3 std, none of them pretended exact
    assert abs(np.log(est.focal / cam.fx)) < 3 * est.focal_std and abs(est.tilt_deg - tilt) < 3 * est.tilt_std_deg
    assert abs(np.log(est.height / height)) < 3 * est.height_std
    assert est.height_std > 0.015  # six people's statures are known only to the prior's 5% each
    # the estimated camera places a foot where the true one does (up to the world's origin and yaw)
    ref = est.camera()
    g_true = cam.ground_point(*feet[:2].T)
    g_est = ref.ground_point(*feet[:2].T)
    assert abs(np.linalg.norm(g_est[0] - g_est[1]) / np.linalg.norm(g_true[0] - g_true[1]) - 1) < 0.15


def test_at_zero_tilt_the_focal_length_is_reported_unknown() -> None:
    # scaling the focal length and every depth together gives the same image: only the prior decides it
    cam = _camera(1.6, 0.0, 45.0)
    heads, feet, ids, t = _walkers(cam, seed=5)
    est = estimate_camera(heads, feet, ids, (W, H), t)
    assert est is not None
    assert abs(est.tilt_deg) < 1.0 and abs(est.height / 1.6 - 1) < 0.10, est.describe()
    assert est.focal_std > 0.25, est.describe()  # the prior's width, not a made-up precision


def test_too_few_observations_give_no_estimate_and_bad_shapes_are_named() -> None:
    cam = _camera(2.0, 15.0, 55.0)
    heads, feet, ids, t = _walkers(cam, seed=1, n_people=1, frames=10)
    assert estimate_camera(heads, feet, ids, (W, H), t) is None
    with pytest.raises(ValueError, match="same length"):
        estimate_camera(heads, feet[:-1], ids, (W, H), t)


def test_head_and_foot_of_a_region_and_which_regions_count() -> None:
    ctrl = np.array([[50, 20], [60, 40], [58, 99], [52, 100], [42, 100], [40, 60]], float)
    head, foot = head_foot((40, 20, 21, 81), ctrl, np.array([50.0, 20.0]))
    np.testing.assert_allclose(head, [50.0, 19.5])
    np.testing.assert_allclose(foot, [(58 + 52 + 42) / 3, 100.5])
    assert usable((40, 20, 21, 81), W, H)
    assert not usable((0, 20, 21, 81), W, H)           # cut by the image border
    assert not usable((40, 20, 70, 81), W, H)          # not upright
    assert not usable((40, 20, 21, 81), W, H, merged=True)


def test_the_published_camera_moves_to_an_estimate_by_bounded_steps() -> None:
    start = _camera(1.6, 10.0, 55.0, distance=4.0)
    cam = _camera(2.8, 25.0, 45.0, roll_deg=2.0)
    heads, feet, ids, t = _walkers(cam, seed=3)
    est = estimate_camera(heads, feet, ids, (W, H), t)
    sm = CameraSmoother(start, max_step=0.03)
    prev = camera_parameters(start)
    for _ in range(60):
        p = camera_parameters(sm.step(est))
        assert np.all(np.abs(p[:5] - prev[:5]) <= 0.03 + 1e-9)
        prev = p
    np.testing.assert_allclose(prev, camera_parameters(est.camera()), atol=1e-6)
