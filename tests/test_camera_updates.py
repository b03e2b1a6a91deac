"""A refined camera while the graph runs: each camera_info holds from its seq on for every
subscriber (counterpart.body.camera.CameraSchedule), and the tracker's tracks go on through it.
"""

from __future__ import annotations

import numpy as np

from counterpart.body.camera import Camera, CameraSchedule, default_camera
from counterpart.body.kinematics import forward_kinematics
from counterpart.body.raster import rasterise_silhouettes
from counterpart.nodes.calibration.smooth import camera_from_parameters, camera_parameters
from counterpart.nodes.tracker.tracker import APFConfig, Tracker, TrackerConfig
from counterpart.sim.scenarios import make_scenario


def test_each_camera_holds_from_its_seq_whatever_order_it_came_in() -> None:
    a, b, c = (Camera.look_at((0.0, h, 4.0), (0.0, 0.9, 0.0), 55.0, 320, 240) for h in (1.6, 1.7, 1.8))
    s = CameraSchedule()
    assert s.get((320, 240), 0) is None and (320, 240) not in s
    s.add(a, 0)
    s.add(c, 60)  # a later refinement that reached this node first
    s.add(b, 30)
    assert [s.get((320, 240), q) for q in (0, 29, 30, 59, 60, 500)] == [a, a, b, b, c, c]
    assert s.get((320, 240)) is c and s.get((160, 120), 10) is None
    small = default_camera(160, 120)
    s.add(small, 5)
    assert s.get((160, 120), 0) is small  # before the first camera of a size: that first camera


def test_a_camera_is_decided_for_a_frame_once_a_message_says_so_and_a_repeated_one_is_kept_once() -> None:
    a, b = (Camera.look_at((0.0, h, 4.0), (0.0, 0.9, 0.0), 55.0, 320, 240) for h in (1.6, 1.7))
    s = CameraSchedule()
    assert not s.decided((320, 240), 0)  # nothing came
    s.add(a, 0, undecided_from=25)  # a lockstep calibration node's first: frames 0-24 keep it
    assert s.decided((320, 240), 24) and not s.decided((320, 240), 25)
    for seq in range(25, 40):  # the same camera said again on every frame
        s.add(Camera(a.fx, a.fy, a.cx, a.cy, a.width, a.height, a.R.copy(), a.t.copy()), seq, seq + 1)
    assert s.decided((320, 240), 39) and not s.decided((320, 240), 40)
    s.add(b, 40, 41)
    assert len(s._by_size[(320, 240)]) == 2  # the repeats were one camera
    assert [s.get((320, 240), q) for q in (0, 39, 40)] == [a, a, b]
    s.add(b, 41)  # its last: every later frame's
    assert s.decided((320, 240), 10**9) and not s.decided((160, 120), 0)
    fixed = CameraSchedule()
    fixed.add(a)  # a fixed camera (a file's, or from a node that does not say): decided for every frame
    assert fixed.decided((320, 240), 10**6)


def test_the_tracker_keeps_its_track_through_a_refined_camera() -> None:
    cam = default_camera()
    sc = make_scenario("handshake", seed=4)
    P = sc.poses_a[::2][:8]
    masks = rasterise_silhouettes(P, sc.dims_a, cam)
    tr = Tracker(cam, "left", TrackerConfig(apf=APFConfig(n_layers=3, n_particles=64)), seed=0)
    for m in masks[:4]:
        tr.update(None, m)
    # the calibration moved by one bounded step: 2% longer focal length, 2 cm higher
    nudged = Camera(
        cam.fx * 1.02,
        cam.fy * 1.02,
        cam.cx,
        cam.cy,
        cam.width,
        cam.height,
        cam.R,
        cam.t - cam.R @ np.array([0.0, 0.02, 0.0]),
    )
    tr.set_camera(nudged)
    results = [tr.update(None, m) for m in masks[4:]]
    assert tr.camera is nudged and tr.likelihood.views[0].camera is nudged
    assert not any(r.initialised for r in results)  # not started again from the silhouette
    assert np.abs(results[-1].pose[[0, 2]] - P[-1, [0, 2]]).max() < 0.25


def test_a_track_begun_under_a_camera_that_misreads_the_scene_gets_the_persons_size_as_the_camera_is_refined() -> None:
    # the graph starts on the default camera (1.6 m high, 4 m away) while the real one is 3 m high,
    # 3 m away, tilted 20 degrees and wider: the default reads the person as a metre tall (a
    # body of the shortest stature, 1.4 m, is then drawn over them); the calibration then steps
    # the camera to the real one, frame by frame
    wrong = default_camera(320, 240)
    right = camera_from_parameters(
        np.array([np.log(200.0), np.radians(20.0), 0.0, np.log(3.0), np.log(3.0), 0.0]), 320, 240
    )
    sc = make_scenario("handshake", seed=4)
    P = sc.poses_a[::2][:30]
    masks = rasterise_silhouettes(P, sc.dims_a, right)
    config = TrackerConfig(apf=APFConfig(n_layers=3, n_particles=64))
    tr = Tracker(wrong, "left", config, seed=0)
    start = tr.update(None, masks[0])
    misread = tr.dims.height
    a, b = camera_parameters(wrong), camera_parameters(right)
    steps = [camera_from_parameters(a + (b - a) * k / 10, 320, 240) for k in range(1, 11)]
    results = []
    for k, m in enumerate(masks[1:]):
        if k < len(steps):
            tr.set_camera(steps[k])
        results.append(tr.update(None, m))
    assert start.initialised and not any(r.initialised for r in results)
    # the stature the true camera reads, as a track begun under it measures it
    fresh = Tracker(right, "left", config, seed=0)
    fresh.update(None, masks[0])
    assert abs(misread / fresh.dims.height - 1) > 0.15, (misread, fresh.dims.height)
    assert abs(tr.dims.height / fresh.dims.height - 1) < 0.05, (tr.dims.height, fresh.dims.height)
    # and it is drawn over the person: once the camera is the real one, the body's joints lie
    # within 0.15 of the person's height in the picture of the true joints (median over joints and frames)
    errors = []
    for r, pose in zip(results[len(steps) :], P[len(steps) + 1 :]):
        uv, true = (right.project(forward_kinematics(q, d)[0]) for q, d in ((r.pose, tr.dims), (pose, sc.dims_a)))
        errors.append(np.median(np.linalg.norm(uv - true, axis=1)) / np.ptp(true[:, 1]))
    assert np.median(errors) < 0.15, errors
