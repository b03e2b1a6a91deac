"""The labeller on the simulator's conversation scenario, fed what the tracker publishes (joints and
the pose vector's head angles), and the node's reading of those angles from Pose3D.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from counterpart.apps import mine as cli_mine
from counterpart.body.pose import DOF, DOF_INDEX
from counterpart.messages import Pose3D, Silhouettes
from counterpart.messages.tracker import TrackedBody
from counterpart.nodes.labeller.head_motion import HeadMotionParams, head_motion
from counterpart.nodes.labeller.labeller import PersonObservation, SocialLabeller
from counterpart.nodes.labeller.mining import mine_transactions, read_rules, turn_transactions
from counterpart.nodes.labeller.node import head_angles, observations
from counterpart.nodes.labeller.signals import SIGNALS
from counterpart.sim.scenarios import PLANTED_RULES, SIGNAL_INDEX, SIGNAL_NAMES, Scenario, conversation

FPS = 25.0
NOD, SHAKE = SIGNALS.index("nod"), SIGNALS.index("shake")


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    d = np.diff(np.r_[0, mask.astype(np.int8), 0])
    return list(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist()))


def _overlaps(a: tuple[int, int], runs: list[tuple[int, int]]) -> bool:
    return any(s < a[1] and a[0] < e for s, e in runs)


def _stream(sc: Scenario, angles: bool) -> dict[str, np.ndarray]:
    """Streaming labels (T,6) per person, shifted back by the detector's latency (half a window)."""
    joints = sc.joints().astype(np.float32)
    lab = SocialLabeller(FPS)
    out = {"a": [], "b": []}
    for t in range(sc.n_frames):
        people = {}
        for k, (p, poses) in enumerate((("a", sc.poses_a), ("b", sc.poses_b))):
            yaw = float(poses[t, DOF_INDEX["head_turn"]]) if angles else None
            pitch = float(poses[t, DOF_INDEX["head_nod"]]) if angles else None
            people[p] = PersonObservation(joints=joints[t, k], head_yaw=yaw, head_pitch=pitch)
        res = lab.update(people)
        for p in out:
            out[p].append([res[p][s][1] for s in SIGNALS])
    lat = HeadMotionParams(FPS).n // 2
    return {p: np.asarray(v)[lat:] for p, v in out.items()}


@pytest.mark.parametrize("seed", [30, 32])
def test_nods_and_shakes_of_a_simulator_conversation_are_found(seed: int) -> None:
    sc = conversation(seed=seed, fps=FPS, duration=20.0)
    labels = _stream(sc, angles=True)
    n_true = {"nod": 0, "shake": 0}
    for p, truth in (("a", sc.signals_a), ("b", sc.signals_b)):
        for name, col in (("nod", NOD), ("shake", SHAKE)):
            true_runs = _runs(truth[:, SIGNAL_INDEX[name]] == 1)
            pred_runs = _runs(labels[p][:, col] == 1)
            n_true[name] += len(true_runs)
            # every planted event is detected, and every detection is a planted event
            assert all(_overlaps(r, pred_runs) for r in true_runs), (p, name, true_runs, pred_runs)
            assert all(_overlaps(r, true_runs) for r in pred_runs), (p, name, true_runs, pred_runs)
    assert n_true["nod"] >= 5 and n_true["shake"] >= 2, n_true  # the snippet has both


def test_without_the_head_angles_shakes_are_not_seen_but_nods_are() -> None:
    """The simulator's shake turns the head about the neck's vertical axis and leaves the head joint
    where it is: from joints alone no shake is found (which is why the node reads the yaw).
    """
    sc = conversation(seed=30, fps=FPS, duration=20.0)
    labels = _stream(sc, angles=False)
    truth = sc.signals_a
    assert (truth[:, SIGNAL_INDEX["shake"]] == 1).any()
    assert not (labels["a"][:, SHAKE] == 1).any()
    nods = _runs(truth[:, SIGNAL_INDEX["nod"]] == 1)
    assert all(_overlaps(r, _runs(labels["a"][:, NOD] == 1)) for r in nods)


def test_a_look_away_and_a_glance_are_not_shakes_but_a_shake_on_a_turn_is() -> None:
    t = 250
    tt = np.arange(t) / FPS
    neck = np.tile([0.0, 1.45, 0.0], (t, 1))
    head = neck + [0.0, 0.17, 0.02]
    rng = np.random.default_rng(0)
    away = 0.7 * np.clip((tt - 4.0) / 0.25, 0, 1) - 0.7 * np.clip((tt - 6.0) / 0.25, 0, 1)
    glance = 0.5 * np.clip((tt - 4.0) / 0.2, 0, 1) - 0.5 * np.clip((tt - 4.6) / 0.2, 0, 1)
    for yaw in (away, glance):
        r = head_motion(head, neck, FPS, head_yaw=yaw + rng.normal(0, 0.002, t), head_pitch=np.zeros(t), center=True)
        assert not (r.shake == 1).any() and not (r.nod == 1).any()
    # a shake made while turning away is still a shake
    on = (tt >= 3.8) & (tt < 4.8)
    shake = np.where(on, 0.25 * np.sin(2 * np.pi * 2.5 * (tt - 3.8)) * np.sin(np.pi * (tt - 3.8)) ** 2, 0.0)
    r = head_motion(head, neck, FPS, head_yaw=away + shake, head_pitch=np.zeros(t), center=True)
    assert (r.shake[(tt > 4.1) & (tt < 4.5)] == 1).all()
    assert not (r.shake[(tt < 3.0) | (tt > 5.6)] == 1).any()


def test_node_reads_head_angles_from_the_pose_vector() -> None:
    pose = np.zeros(DOF)
    pose[DOF_INDEX["head_turn"]], pose[DOF_INDEX["head_nod"]] = 0.3, -0.1
    assert head_angles(pose) == (pytest.approx(0.3), pytest.approx(-0.1))
    assert head_angles(np.zeros(0)) == (None, None)  # a tracker without a pose vector
    joints = np.tile(np.array([0.0, 1.5, 0.0], np.float32), (14, 1))
    bodies = [
        TrackedBody(id=1, side="left", joints=joints, pose=pose),
        TrackedBody(id=2, side="right", joints=joints + 1.0),
    ]
    obs, _ = observations(Silhouettes(stamp=0, seq=0, people=[]), Pose3D(stamp=0, seq=0, people=bodies))
    assert obs[1].head_yaw == pytest.approx(0.3) and obs[1].head_pitch == pytest.approx(-0.1)
    assert obs[2].has_3d() and obs[2].head_yaw is None and obs[2].head_pitch is None


def test_turn_taking_transactions_recover_the_planted_listener_rules() -> None:
    """Speaker = whoever holds the turn; the simulator's planted nod -> nod response (probability
    0.8 for an interested listener) comes back from its ground-truth labels within sampling error.
    """
    names = list(SIGNAL_NAMES)
    off = PLANTED_RULES[0]["offset_frames_at_25fps"]
    parts = []
    for seed in range(500, 506):
        sc = conversation(seed=seed, fps=FPS, duration=60.0, interested=True)
        tx = turn_transactions(sc.signals_a, sc.signals_b, names, offset=off)
        talk = sc.signals_a[:-off, SIGNAL_INDEX["talking"]].sum() + sc.signals_b[:-off, SIGNAL_INDEX["talking"]].sum()
        assert len(tx) == talk and tx["S:talking"].all()
        parts.append(tx)
    rules = {r.key: r for r in mine_transactions(pd.concat(parts, ignore_index=True), 0.005, 0.1)}
    for r in PLANTED_RULES:
        hit = rules[((f"S:{r['antecedent']}",), (f"L:{r['consequent']}",))]
        # about 100 nod and 50 shake events: 3 standard errors of the simulator's coin flips
        assert abs(hit.confidence - r["p_interested"]) < 0.15, (r, hit)
    with pytest.raises(ValueError, match="talking"):
        turn_transactions(sc.signals_a[:, :2], sc.signals_b[:, :2], names[:2])


def test_cli_mine_with_turns_on_simulator_trajectory_files(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``counterpart mine --turns talking`` on the simulator's conversation files: the interested /
    not-interested confidence ratio of the planted nod -> nod rule (0.8 / 0.3) comes back.
    """
    files: dict[str, list[str]] = {"interested": [], "not_interested": []}
    for scen, seeds in (("interested", range(600, 604)), ("not_interested", range(700, 704))):
        for s in seeds:
            path = tmp_path / f"{scen}_{s}.npz"
            conversation(seed=s, fps=FPS, duration=60.0, interested=scen == "interested").to_trajectory().save(path)
            files[scen].append(str(path))
    parser = argparse.ArgumentParser()
    cli_mine.add_arguments(parser)
    out = tmp_path / "rules.json"
    args = parser.parse_args(
        [
            "--interested",
            *files["interested"],
            "--not-interested",
            *files["not_interested"],
            "--turns",
            "talking",
            "--min-support",
            "0.005",
            "--out",
            str(out),
        ]
    )
    assert cli_mine.main(args) == 0
    rf = read_rules(out)
    assert rf.params["turns"] == "talking"
    comp = {(c.antecedent, c.consequent): c for c in rf.comparisons}
    nod = comp[(("S:nod",), ("L:nod",))]
    assert abs(nod.confidence_a - 0.8) < 0.15 and abs(nod.confidence_b - 0.3) < 0.15, nod
    bad = parser.parse_args(["--interested", files["interested"][0], "--turns", "speaking", "--out", str(out)])
    assert cli_mine.main(bad) == 2
    assert "speaking" in capsys.readouterr().err
