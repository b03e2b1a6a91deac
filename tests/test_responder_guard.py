"""The partner's arms and its final place (``Stage.finish``): it guards while pushed instead of
reaching for the pusher's hand, and as drawn, after its arms are set, it keeps clear of the observed
person's box in the picture however fast they come at it.
"""

from __future__ import annotations

import numpy as np

from counterpart.body.skeleton import JOINT_INDEX
from counterpart.nodes.responder.frames import actor_frame
from counterpart.nodes.responder.reach import reach
from counterpart.nodes.responder.staging import Stage, guard_arms
from tests.pose_source import facing
from tests.responder_fixtures import CAM, box_overlap

ARMS = [(JOINT_INDEX[f"{s}_shoulder"], JOINT_INDEX[f"{s}_elbow"], JOINT_INDEX[f"{s}_wrist"]) for s in "lr"]
NECK, HIPS = JOINT_INDEX["neck"], [JOINT_INDEX["l_hip"], JOINT_INDEX["r_hip"]]


def person(x: float, z: float, yaw: float = np.pi / 2) -> np.ndarray:
    return facing(yaw) + [x, 0.0, z]


def ground(X: np.ndarray) -> np.ndarray:
    return actor_frame(X)[0][[0, 2]]


def box_of(X: np.ndarray, right_m: float = 0.0) -> tuple[float, float, float, float]:
    """The box ``(x, y, w, h)`` in ``CAM`` of joints X (14, 3), ``right_m`` metres wider towards image right."""
    uv = CAM.project(X)
    x0, y0, x1, y1 = uv[:, 0].min(), uv[:, 1].min(), uv[:, 0].max(), uv[:, 1].max()
    at = X[NECK]
    extra = CAM.project(np.array([at + [right_m, 0.0, 0.0]]))[0, 0] - CAM.project(at[None])[0, 0]
    return (x0, y0, x1 - x0 + extra, y1 - y0)


def bones(X: np.ndarray) -> np.ndarray:
    return np.array([[np.linalg.norm(X[e] - X[s]), np.linalg.norm(X[w] - X[e])] for s, e, w in ARMS])


def test_a_pushed_partner_holds_its_arms_in_instead_of_reaching_for_the_pushing_hand() -> None:
    obs, par = person(0.0, 2.0), person(0.7, 2.0, -np.pi / 2)  # face to face, 0.7 m apart
    pushing = obs.copy()
    pushing[JOINT_INDEX["r_wrist"]] = [0.6, 1.3, 2.0]  # the right wrist on the partner's chest
    stage = Stage()
    stage(obs, par, 0.04)
    staged = stage(pushing, par, 0.04)
    assert stage.pushed and stage.guarding
    # the cause: the hand contact alone pulls the pushed partner's hand onto the pushing hand
    assert reach(pushing, staged)[1] > 0
    out, pull = stage.finish(pushing, staged)
    assert pull == 0.0
    np.testing.assert_allclose(bones(out), bones(staged), atol=1e-6)  # the arms bent, not stretched
    chest = out[NECK] + 0.35 * (out[HIPS].mean(axis=0) - out[NECK])
    towards = ground(obs) - ground(out)
    for s, e, w in ARMS:
        assert np.linalg.norm(out[w] - chest) < 0.3  # the hands before the chest
        assert out[e, 1] < out[s, 1]  # the elbows down
        # no arm joint further towards the pusher than a hand's breadth before its chest
        assert ((out[[e, w]][:, [0, 2]] - ground(out)) @ towards / np.linalg.norm(towards)).max() < 0.2
    # it guards while thrown back and returning, and reaches again once back
    guarding = []
    for _ in range(120):
        staged = stage(obs, par, 0.04)
        guarding.append(stage.guarding)
    assert guarding[0] and not guarding[-1] and np.diff(np.array(guarding, int)).max() <= 0  # one spell
    assert np.array_equal(stage.finish(obs, staged)[0], reach(obs, staged)[0])


def test_guard_arms_keeps_the_body_and_the_bones() -> None:
    P = person(0.0, 0.0, 0.3)
    out = guard_arms(P, np.array([1.0, 0.0]))
    moved = np.flatnonzero(np.abs(out - P).max(axis=1) > 1e-9)
    assert set(moved) <= {e for _, e, _ in ARMS} | {w for _, _, w in ARMS}
    np.testing.assert_allclose(bones(out), bones(P), atol=1e-6)


def test_the_drawn_partner_keeps_clear_of_a_person_coming_at_it_faster_than_it_walks() -> None:
    obs, par = person(0.0, 0.0, 0.0), person(0.6, 0.0, 0.0)  # both facing the camera
    stage = Stage()
    first = stage.finish(obs, stage(obs, par, 0.04, side=1.0, camera=CAM, box=box_of(obs)), None)[0]
    assert box_overlap(first, box_of(obs))[0] <= 0.15
    # their silhouette grows 0.5 m its way in one frame (an arm swung out), faster than the partner walks
    box = box_of(obs, 0.5)
    staged = stage(obs, par, 0.01, side=1.0, camera=CAM, box=box)
    iou, inside = box_overlap(staged, box)
    assert iou > 0.15 or inside > 0.6  # the speed limit left it in them
    out, _ = stage.finish(obs, staged, None)  # the model's arms (a hand taken is where two touch: not counted)
    iou, inside = box_overlap(out, box)
    assert iou <= 0.15 and inside <= 0.6  # as drawn, it is not
    gap = float(np.hypot(*(ground(out) - ground(obs))))
    assert gap <= 1.2 + 1e-9
    # and it walks on from there, not back into them
    again = stage(obs, par, 0.01, side=1.0, camera=CAM, box=box)
    iou, inside = box_overlap(again, box)
    assert iou <= 0.15 and inside <= 0.6
