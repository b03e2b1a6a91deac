"""The responder's stage on real footage: the silhouette node's people on two UT-Interaction clips of the
tune split (a handshake, 52_9_0, and a push, 16_3_5) against their reference keypoints, when present.

The observed person's body is a standing one of the test's own (the tracker is too slow to run here);
what is real is what the stage reads of the picture: the silhouettes' reach, their touching, their
centroids and boxes.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from counterpart.body.skeleton import JOINT_INDEX
from counterpart.nodes.responder.frames import actor_frame
from counterpart.nodes.responder.staging import Stage, StageConfig, silhouette_reach, stature, touching_hand_px
from tests.pose_source import facing
from tests.shared_data import DATA

UT = DATA / "ut_interaction"
HANDSHAKE, PUSH = "52_9_0", "16_3_5"
#: frames the background is learnt on, as the graph and the benches do
TRAIN_FRAMES = 20
WRISTS = [JOINT_INDEX["l_wrist"], JOINT_INDEX["r_wrist"]]
FPS = 30.0

_cache: dict[str, tuple[list[list[Any]], np.ndarray, np.ndarray]] = {}


def clip(name: str) -> tuple[list[list[Any]], np.ndarray, np.ndarray]:
    """The silhouette node's people on every frame of a clip, its reference keypoints (T, 2, 14, 2) and
    visibilities (T, 2, 14); skips when the clip is absent.
    """
    video, ref = UT / "set1" / f"{name}.avi", UT / "keypoints" / f"{name}.npz"
    if not video.is_file() or not ref.is_file():
        pytest.skip(f"real clip {video} or its keypoints not present (../shared/data)")
    if name not in _cache:
        from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor, iter_video

        people = [list(r.people) for _, r in iter_video(video, SilhouetteExtractor(), None, TRAIN_FRAMES)]
        d = np.load(ref)
        _cache[name] = people, d["kp"].astype(np.float64), d["vis"]
    return _cache[name]


def height_px(kp: np.ndarray) -> float:
    """A reference person's height on a frame, head to mid-ankle, pixels; kp (14, 2)."""
    ankles = kp[[JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]]].mean(axis=0)
    return float(np.linalg.norm(kp[JOINT_INDEX["head"]] - ankles))


def reach_of(people: list[Any], side: str, joints: np.ndarray, direction: float) -> tuple[Any, Any]:
    """The reach and box of the silhouette on ``side`` (the other side's nearest region as its other), as
    the responder node finds them; (None, None) without one.
    """
    mine = [q for q in people if q.side == side]
    if not mine:
        return None, None
    shape = mine[0]
    theirs = [q for q in people if q.side != side]
    near = min(theirs, key=lambda q: abs(float(q.centroid[0]) - float(shape.centroid[0])), default=None)
    other = None if near is None else (float(near.centroid[0]), float(near.centroid[1]))
    reach = silhouette_reach(
        shape.bbox, shape.centroid, direction, stature(joints), shape.ctrl, touching=shape.merged, other=other
    )
    return reach, tuple(shape.bbox)


def test_where_real_hands_meet_the_picture_says_where_the_hand_is() -> None:
    people, kp, vis = clip(HANDSHAKE)
    config = StageConfig()
    body = facing(np.pi / 2)
    errors = []
    for t in range(min(len(people), len(kp))):
        needed = [JOINT_INDEX["head"], JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]]
        if not np.isfinite(kp[t][:, needed]).all():
            continue
        h = height_px(kp[t, 0])
        gaps = np.linalg.norm(kp[t, 0, WRISTS][:, None] - kp[t, 1, WRISTS][None], axis=-1)
        seen = (vis[t, 0, WRISTS] >= 0.5)[:, None] & (vis[t, 1, WRISTS] >= 0.5)[None]
        gaps = np.where(seen & np.isfinite(gaps), gaps, np.inf)
        if gaps.min() > 0.1 * h:  # the hands do not meet on this frame (or are not seen)
            continue
        reach, box = reach_of(people[t], "left", body, 1.0)
        if reach is None or not reach.touching:
            continue
        u, v = touching_hand_px(reach, box, config.meet_touch, config.hand_box_frac)
        hand = kp[t, 0, WRISTS[int(np.argmin(gaps.min(axis=1)))]]
        errors.append(np.hypot(u - hand[0], v - hand[1]) / h)
    assert len(errors) >= 5, "the hands meet on a few frames of the handshake"
    assert np.median(errors) <= 0.15 and np.mean(np.array(errors) <= 0.15) >= 0.8


def staged_gaps(name: str, side: str, direction: float) -> tuple[np.ndarray, Stage, int | None, np.ndarray]:
    """The partner's ground distance (T,) from a standing observed person on ``side`` whose silhouettes
    are the clip's, frame by frame; the stage; the frame its first push landed (None: none); and
    per frame (T, 2) whether a hand was offered to the partner and whether a push went on.
    """
    people, _, _ = clip(name)
    obs, par = facing(np.pi / 2), facing(-np.pi / 2) + [0.9 * direction, 0.0, 0.0]
    stage = Stage()
    gaps, landed, offered = [], None, []
    for t in range(len(people)):
        reach, _ = reach_of(people[t], side, obs, direction)
        out = stage(obs, par, 1.0 / FPS, side=direction, silhouette=reach)
        gaps.append(float(np.hypot(*(actor_frame(out)[0] - actor_frame(obs)[0])[[0, 2]])))
        landed = t if landed is None and stage.pushes else landed
        offered.append((stage.offered_ is not None, stage.pushed))
    return np.array(gaps), stage, landed, np.array(offered)


def test_a_real_push_moves_the_partner_back_within_the_range() -> None:
    # 16_3_5: the right person walks in and pushes the left one (the reference shows the other thrown back)
    gaps, stage, landed, offered = staged_gaps(PUSH, "right", -1.0)
    assert landed is not None
    assert gaps.min() >= 0.5 - 1e-9 and gaps.max() <= 1.2 + 1e-9
    # from where the push landed it moves back: at least 0.2 m within the 1.5 s after
    assert gaps[landed : landed + round(1.5 * FPS)].max() - gaps[landed] >= 0.2
    # and takes no hand while the push goes on (the pusher's arm out on it): reaching for the pushing
    # hand, its arm would lie inside the pusher
    assert offered[:, 1].sum() >= 10 and not (offered[:, 0] & offered[:, 1]).any()


def test_real_people_walking_in_to_shake_hands_do_not_push() -> None:
    gaps, stage, _, offered = staged_gaps(HANDSHAKE, "left", 1.0)
    assert stage.pushes == 0 and offered[:, 0].any()  # the hand held out is taken
    assert gaps.min() >= 0.5 - 1e-9 and gaps.max() <= 1.2 + 1e-9
