"""The responder node in a real launch: Pose3D in, Partner out, Control switches take effect."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from counterpart.body.skeleton import JOINT_INDEX
from counterpart.nodes.responder.frames import actor_frame
from tests.launching import read_jsonl, run_launch, write_launch
from tests.responder_fixtures import planted_pair
from tests.responder_nodes import bearing_camera


def graph(tmp: Path, switch: str = "", responder: dict | None = None, **source: float) -> Path:
    return write_launch(
        tmp / "g.yaml",
        {
            "nodes": {
                "source": {
                    "run": "tests.responder_nodes:PoseSource",
                    "params": {"frames": 60, "control_at": 30, "switch": switch, **source},
                },
                # a reliable control queue: the source waits for it to connect, so the control is never lost
                "responder": {
                    "run": "counterpart.nodes.responder",
                    "params": {"model": "dual-hmm", "hold_frames": 5, **(responder or {})},
                    "inputs": {"control": {"policy": "reliable"}},
                },
                "sink": {"run": "tests.responder_nodes:PartnerSink", "params": {"path": str(tmp / "out.jsonl")}},
            }
        },
    )


def switch_at(values: list, before: object, after: object) -> int:
    """The index k where ``values`` switch once from ``before`` (values[:k]) to ``after`` (values[k:]).

    The control and the poses travel on separate sockets and a responder takes a side input as
    soon as it comes, so one still working through queued poses (a loaded machine: it loads its
    models first) takes the control before poses that were sent ahead of it: the switch must
    happen once and for good, not at one exact pose.
    """
    k = values.index(after) if after in values else len(values)
    assert values[:k] == [before] * k and values[k:] == [after] * (len(values) - k), values
    assert k < len(values), f"no switch from {before!r} to {after!r}: {values}"
    return k


def test_partner_per_pose_and_control_takes_effect(tmp_path: Path, models_dir: Path) -> None:
    code, out = run_launch(graph(tmp_path), timeout=90, env={"COUNTERPART_MODELS": str(models_dir)})
    assert code == 0, out
    rows = read_jsonl(tmp_path / "out.jsonl")
    assert [r["seq"] for r in rows] == list(range(60))
    assert all(r["shape"] == [14, 3] and r["model"] == "dual-hmm" for r in rows)
    switch_at([(r["emotion"], r["strength"]) for r in rows], ("neutral", 0.0), ("angry", 1.0))
    # the partner answers A's arm: its left wrist (joint 4) rises with A (the angry style amplifies
    # the motion about its running mean, which keeps it correlated)
    truth = planted_pair(7, T=60)
    pred = np.array([r["joints"] for r in rows])
    assert np.corrcoef(pred[:, 4, 1], truth.b[:, 4, 1])[0, 1] > 0.8
    # the pair stands 1.3 m apart: the partner is staged at most max_distance_m (1.2 m) from A
    gap = np.linalg.norm((actor_frame(pred)[0] - actor_frame(truth.a)[0])[:, [0, 2]], axis=1)
    assert np.all((gap > 0.5 - 1e-4) & (gap < 1.2 + 1e-4)) and gap.max() > 1.15


def test_the_partner_stands_across_the_view_of_the_graphs_camera(tmp_path: Path, models_dir: Path) -> None:
    # the graph's camera looks at the pair from 50 degrees round: with camera_info the partner stands
    # at the observed person's depth in that camera, to their right in its picture
    g = graph(tmp_path, responder={"camera_info": True}, bearing_deg=50.0)
    code, out = run_launch(g, timeout=90, env={"COUNTERPART_MODELS": str(models_dir)})
    assert code == 0, out
    rows = read_jsonl(tmp_path / "out.jsonl")
    assert [r["seq"] for r in rows] == list(range(60))
    truth = planted_pair(7, T=60)
    cam = bearing_camera(truth.a[0], 50.0)
    hips = [JOINT_INDEX["l_hip"], JOINT_INDEX["r_hip"]]
    # the camera is a side input: the last half of the frames, however late it came (the partner
    # walks round at max_speed_m_s)
    pred = np.array([r["joints"] for r in rows])[30:, hips].mean(axis=1)
    obs = truth.a[30:, hips].mean(axis=1)
    assert np.abs(cam.depth(pred) - cam.depth(obs)).max() < 0.05
    assert np.all(cam.project(pred)[:, 0] - cam.project(obs)[:, 0] > 20.0)


def test_the_partner_holds_through_a_short_dropout_of_the_observed_person(tmp_path: Path, models_dir: Path) -> None:
    # the person is missing on frames 10-17: the partner stays for 5 frames (hold_frames), then goes
    code, out = run_launch(graph(tmp_path, gap_at=10, gap=8), timeout=90, env={"COUNTERPART_MODELS": str(models_dir)})
    assert code == 0, out
    rows = read_jsonl(tmp_path / "out.jsonl")
    assert [r["seq"] for r in rows] == list(range(60))
    assert all(r["shape"] == [14, 3] and r["joints"] == rows[9]["joints"] for r in rows[10:15])  # held
    assert all(r["shape"] != [14, 3] for r in rows[15:18])  # gone
    assert all(r["shape"] == [14, 3] for r in rows[18:])  # back


def test_control_switches_the_model(tmp_path: Path, models_dir: Path) -> None:
    code, out = run_launch(graph(tmp_path, switch="listener"), timeout=90, env={"COUNTERPART_MODELS": str(models_dir)})
    assert code == 0, out
    rows = read_jsonl(tmp_path / "out.jsonl")
    switch_at([r["model"] for r in rows], "dual-hmm", "listener")
    assert all(r["shape"] == [14, 3] for r in rows)


def test_inputs_follow_the_use_params(tmp_path: Path) -> None:
    from counterpart.bus.launchfile import LaunchError, check, load
    from counterpart.nodes.responder.node import Responder

    p = Responder.validate_params({"use_pose": False, "use_silhouettes": True, "use_control": False})
    assert set(Responder.ports(p)[0]) == {"silhouettes"}
    # a graph without a tracker: the pose input is switched off and the graph validates
    f = write_launch(
        tmp_path / "g2.yaml",
        {
            "nodes": {
                "source": {"run": "tests.responder_nodes:PoseSource", "remap": {"pose": "unused"}},
                "responder": {"run": "counterpart.nodes.responder", "params": {"model": "listener", "use_pose": False}},
            }
        },
    )
    assert "responder" in check(load(f)).nodes
    # with the pose input on, the missing publisher is named
    f = write_launch(
        tmp_path / "g3.yaml",
        {
            "nodes": {
                "source": {"run": "tests.responder_nodes:PoseSource", "remap": {"pose": "unused"}},
                "responder": {"run": "counterpart.nodes.responder"},
            }
        },
    )
    with pytest.raises(LaunchError, match="inputs.pose"):
        check(load(f))


def listeners(tmp_path: Path, models_dir: Path, sources: dict[str, dict]) -> dict[str, list[dict]]:
    """One PoseSource (with ``sources[name]``'s parameters; A nods at 1 s, 75 frames), listener
    responder and sink per name, all in one graph: each chain's partners.
    """
    nodes: dict[str, dict] = {}
    for name, params in sources.items():
        topics = {port: f"{name}/{port}" for port in ("pose", "control", "signals", "partner", "camera_info")}
        nodes[f"{name}_source"] = {
            "run": "tests.responder_nodes:PoseSource",
            "params": {"frames": 75, "control_at": 1000, "nod_s": 1.0, **params},
            "remap": {port: t for port, t in topics.items() if port != "partner"},
        }
        nodes[name] = {
            "run": "counterpart.nodes.responder",
            "params": {"model": "listener", "use_signals": True},
            "remap": {port: t for port, t in topics.items() if port != "camera_info"},
        }
        nodes[f"{name}_sink"] = {
            "run": "tests.responder_nodes:PartnerSink",
            "params": {"path": str(tmp_path / f"{name}.jsonl")},
            "remap": {"partner": topics["partner"]},
        }
    g = write_launch(tmp_path / "g.yaml", {"policy": "reliable", "nodes": nodes})
    code, out = run_launch(g, timeout=90, env={"COUNTERPART_MODELS": str(models_dir)})
    assert code == 0, out
    return {name: read_jsonl(tmp_path / f"{name}.jsonl") for name in sources}


def test_the_model_keeps_its_own_frame_rate_whatever_the_cameras(tmp_path: Path, models_dir: Path) -> None:
    # A nods at 1 s, seen at the model's 25 fps and at 50 fps: the listener answers 0.4 s later
    # (offset_s) for 1 s (response_s) at both (stepped once per input frame, 50 fps would halve both)
    partners = listeners(tmp_path, models_dir, {"at25": {"fps": 0.0}, "at50": {"fps": 50.0}})
    for name, fps in (("at25", 25.0), ("at50", 50.0)):
        rows = partners[name]
        nodding = [r["seq"] / fps for r in rows if r["behaviour"] == "nod"]
        assert len(rows) == round(3 * fps) - (fps == 50) and nodding, (name, [r["behaviour"] for r in rows])
        # within a frame of the model's (it reads the signals on its own frames) and one of the input's
        # (the signals and the poses travel on separate sockets)
        late = 1 / 25 + 1 / fps + 1e-6
        assert -1e-6 <= nodding[0] - 1.4 <= late and -1e-6 <= nodding[-1] + 1 / fps - 2.4 <= late, (name, nodding)


def test_the_listener_answers_each_pose_with_its_own_frames_signals_however_late_they_come(
    tmp_path: Path, models_dir: Path
) -> None:
    # A nods at 1 s; one source sends each frame's signals before its pose, the other 20 ms after
    # it, as a labeller does (it waits for the pose): the partners are the same, frame by frame
    partners = listeners(tmp_path, models_dir, {"before": {}, "after": {"signals_after": True}})
    before, after = partners["before"], partners["after"]
    assert [r["seq"] for r in before] == list(range(75)) and any(r["behaviour"] == "nod" for r in before)
    assert after == before
