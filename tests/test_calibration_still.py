"""People standing still, grown from where they moved (counterpart.nodes.calibration.still): the
head and foot points of people whom the background model absorbed and the people detector misses,
on real rendered frames of the simulator and on drawn frames.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from counterpart.body.people_detector import PeopleDetector
from counterpart.body.skeleton import JOINT_INDEX
from counterpart.nodes.calibration.observe import PeopleObservations, detect_people
from counterpart.nodes.calibration.still import StillConfig, StillPeople


def _conversation() -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
    """Simulator tuning seed 35 (a conversation; the camera 2.4 m high): its 75 frames, and each
    person's crown and ankles' ground point on them, (75, 2, 2) pixels each.
    """
    from counterpart.sim.stream import open_stream

    stream = open_stream("conversation", seed=35, camera="random", frames=75)
    J = stream.scenario.joints()
    crown = stream.camera.project(J[:, :, JOINT_INDEX["head"]] + [0.0, 0.11, 0.0])
    ankles = 0.5 * (J[:, :, JOINT_INDEX["l_ankle"]] + J[:, :, JOINT_INDEX["r_ankle"]]) * [1.0, 0.0, 1.0]
    return [stream.render(i)[0] for i in range(stream.n_frames)], crown, stream.camera.project(ankles)


def _grown(frames: list[np.ndarray], config: StillConfig | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
    still = StillPeople(frames[0].shape[1], frames[0].shape[0], config)
    for i, frame in enumerate(frames):
        still.observe(frame, i / 25.0)
    return still.find(frames[-1], (len(frames) - 1) / 25.0)


def _near_truth(found: list[tuple[np.ndarray, np.ndarray]], crown: np.ndarray, ground: np.ndarray) -> None:
    assert len(found) == 2
    for k, (head, foot) in enumerate(found):
        tall = ground[k, 1] - crown[k, 1]
        assert abs(head[1] - crown[k, 1]) < 0.04 * tall, (k, head, crown[k])
        # the outline's bottom is the toe nearer the camera, a little below the ankles' ground point
        assert -0.02 * tall < foot[1] - ground[k, 1] < 0.06 * tall, (k, foot, ground[k])
        assert abs(foot[0] - ground[k, 0]) < 0.06 * tall


def test_two_people_talking_are_grown_from_their_gestures_to_their_feet() -> None:
    # the two stand still for the whole 3 s; the detector finds neither on the last frame, and
    # their gestures alone moved (hands, heads): the grown bodies reach the crown and the feet
    frames, crown, ground = _conversation()
    assert len(detect_people(PeopleDetector(), frames[-1])[0]) == 0
    _near_truth(_grown(frames), crown[-1], ground[-1])
    # a frame twice the size is worked on shrunk to 240 rows; the points are the big frame's
    big = _grown([cv2.resize(f, None, fx=2, fy=2, interpolation=cv2.INTER_LINEAR) for f in frames])
    _near_truth(big, 2 * crown[-1] + 0.5, 2 * ground[-1] + 0.5)


def _walk(frames: int = 30) -> list[np.ndarray]:
    """A textured block the shape of a person (30 x 100 px) walking 1 px a frame across a textured
    floor and wall: all of it moves.
    """
    rng = np.random.default_rng(0)
    scene = np.zeros((240, 320, 3), np.uint8)
    scene[:120] = (190, 200, 205)
    scene[120:] = (40, 80, 130)
    scene = np.clip(scene + rng.normal(0, 12, scene.shape), 0, 255).astype(np.uint8)
    body = rng.integers(20, 120, (100, 30, 3), dtype=np.uint8)
    out = []
    for i in range(frames):
        f = scene.copy()
        f[100:200, 60 + i : 90 + i] = body
        out.append(f)
    return out


def test_a_body_that_moved_as_a_whole_is_left_to_the_silhouettes() -> None:
    frames = _walk()
    assert _grown(frames) == []
    # without the bound, the walker's trail grows into a standing "person" as wide as the trail
    assert len(_grown(frames, StillConfig(max_moved_share=1.0))) >= 1


def test_still_people_are_looked_for_only_where_no_one_else_was_found() -> None:
    frames, _, _ = _conversation()
    obs = PeopleObservations(320, 240)
    region = type("Region", (), {"id": 0, "bbox": (200, 40, 40, 170), "ctrl": None, "ref_point": None, "merged": False})
    ran = []
    for i, frame in enumerate(frames):
        # an upright region on the first half of the frames: the detector runs on every third of
        # them (its boxes on the region left out), the still people on none
        people = [region()] if i < 40 else []
        obs.add_frame(frame, i / 25.0, obs.add(people, i / 25.0), PeopleDetector())
        assert obs.still is not None
        ran.append(obs.still.runs)
    assert ran[39] == 0 and ran[-1] > 0
    _, _, track, _ = obs.arrays()
    assert (track <= -1_000_000).sum() >= 2


def test_bad_settings_are_refused() -> None:
    with pytest.raises(ValueError, match="window_s"):
        StillConfig(window_s=0.0)
    with pytest.raises(ValueError, match="rows"):
        StillConfig(rows=8)
