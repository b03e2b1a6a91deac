"""The simulator's random camera (counterpart.sim.camera, ``camera=random``): drawn from the seed within its
stated ranges, at a bearing about the pair so the two people stand at different depths, with every
joint and head top of the scene in view; the default camera unchanged.
"""

from __future__ import annotations

import numpy as np
import pytest

from counterpart.body.camera import default_camera
from counterpart.body.skeleton import JOINT_INDEX
from counterpart.sim.camera import HEAD_TOP, RandomCameraConfig, frame_people, scene_points
from counterpart.sim.stream import open_stream


def _depths(stream) -> np.ndarray:
    """(T, 2) depth of each person's mid-hip along the optical axis, metres."""
    J = stream.scenario.joints()
    hip = 0.5 * (J[:, :, JOINT_INDEX["l_hip"]] + J[:, :, JOINT_INDEX["r_hip"]])
    return (hip @ stream.camera.R.T + stream.camera.t)[..., 2]


@pytest.mark.parametrize("seed", [0, 3, 7, 11])
def test_random_camera_in_ranges_with_everyone_in_view(seed: int) -> None:
    stream = open_stream("handshake", seed=seed, camera="random", frames=10)
    drawn = stream.scenario.meta["camera"]
    cfg = RandomCameraConfig()
    for key, rng in (("height", cfg.height), ("tilt_deg", cfg.tilt_deg), ("fov_deg", cfg.fov_deg)):
        assert rng[0] <= drawn[key] <= rng[1]
    assert cfg.azimuth_deg[0] <= drawn["azimuth_deg"] <= cfg.azimuth_deg[1]
    assert drawn["azimuth_range_deg"] == list(cfg.azimuth_deg)
    cam = stream.camera
    assert cam.centre[1] == pytest.approx(drawn["height"], abs=1e-9)
    tilt = np.degrees(np.arcsin(cam.R[2, 1] * -1))
    assert tilt == pytest.approx(drawn["tilt_deg"], abs=1e-6)
    # the bearing: the camera looks horizontally along -(sin a, cos a), from the side the bearing names
    assert np.degrees(np.arctan2(-cam.R[2, 0], -cam.R[2, 2])) == pytest.approx(drawn["azimuth_deg"], abs=1e-6)
    pts = scene_points(stream.scenario.joints())
    uv = cam.project(pts)
    w, h = stream.size
    assert (uv >= 0).all() and (uv[:, 0] <= w - 1).all() and (uv[:, 1] <= h - 1).all()


def test_bearings_spread_and_people_stand_at_different_depths() -> None:
    az, gap = [], []
    for seed in range(12):
        stream = open_stream("handshake", seed=seed, camera="random", frames=5)
        az.append(stream.scenario.meta["camera"]["azimuth_deg"])
        z = _depths(stream)[0]
        gap.append(abs(z[0] - z[1]))
    az, gap = np.array(az), np.array(gap)
    # drawn on both sides of square-on, over much of the range
    assert az.min() < -20 and az.max() > 20
    # the depth difference of the two people follows the bearing: about their distance apart times
    # sin(bearing) (square-on: one depth)
    oblique = np.abs(az) > 20
    assert gap[oblique].min() > 0.15
    assert np.all(gap[np.abs(az) < 5] < 0.3)


def test_square_on_bearing_keeps_one_depth_and_default_camera_unchanged() -> None:
    stream = open_stream("handshake", seed=0, frames=5)
    ref = default_camera(*stream.size)
    assert np.allclose(stream.camera.K, ref.K) and np.allclose(stream.camera.R, ref.R)
    assert np.allclose(stream.camera.t, ref.t)
    assert "camera" not in stream.scenario.meta
    cam = frame_people(scene_points(stream.scenario.joints()), 2.0, 10.0, 55.0, *stream.size, azimuth_deg=0.0)
    assert cam is not None and abs(cam.R[2, 0]) < 1e-12  # looks along -Z: no yaw
    head_top = stream.scenario.joints()[0, :, JOINT_INDEX["head"]] + [0.0, HEAD_TOP, 0.0]
    assert np.isfinite(cam.project(head_top)).all()


def test_random_camera_is_reproducible() -> None:
    a = open_stream("push", seed=5, camera="random", frames=3)
    b = open_stream("push", seed=5, camera="random", frames=3)
    assert a.scenario.meta["camera"] == b.scenario.meta["camera"]
    assert np.array_equal(a.render(1)[0], b.render(1)[0])
