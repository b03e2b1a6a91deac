"""A refined camera while the graph runs: each camera_info holds from its seq on for every
subscriber (counterpart.body.camera.CameraSchedule), and the tracker's tracks go on through it.
"""

from __future__ import annotations

import numpy as np

from counterpart.body.camera import Camera, CameraSchedule, default_camera
from counterpart.body.raster import rasterise_silhouettes
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
