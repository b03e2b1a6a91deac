"""The Control contract end to end: every choice the live page offers, posted to the page the way
its script posts it, travels on the bus to the real responder and shows in the partner it makes.
"""

from __future__ import annotations

import json
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from counterpart.body.camera import default_camera
from counterpart.messages import EMOTIONS, INTERACTION_MODELS, INTEREST_LEVELS, SPEAKERS
from counterpart.nodes.responder.avatar_recording import sim_recording
from counterpart.nodes.responder.data import sim_trajectories
from counterpart.nodes.responder.dual_hmm import DualHMM, DualHMMConfig, FitConfig
from counterpart.nodes.responder.emotion import EmotionModel
from counterpart.nodes.responder.gpdm import GPDM
from counterpart.nodes.responder.joint_shape import JointShapeModel
from counterpart.nodes.responder.listener import ListenerModel
from counterpart.nodes.responder.models import save_model
from counterpart.nodes.responder.shapes import trajectory_shapes
from counterpart.nodes.responder.video_texture import fit_recording
from tests.launching import read_jsonl, start_launch, stop_launch, wait_for, write_launch
from tests.responder_fixtures import planted_pair

#: the responder's settings before any control (its parameters' defaults)
START = {"model": "dual-hmm", "speaker": "person", "interest": 3, "emotion": "neutral"}


def small_models(folder: Path) -> Path:
    """A default model of every kind, small enough to fit in seconds."""
    save_model(
        folder / "responder-dual-hmm.npz",
        DualHMM(DualHMMConfig(fit=FitConfig(n_states=8, n_iter=10, both_roles=False))).fit(
            [planted_pair(s) for s in range(4)]
        ),
    )
    cam = default_camera(160, 120)
    save_model(
        folder / "responder-joint-shape.npz",
        JointShapeModel(n_states=8, n_behaviours=4, both_roles=False, random_state=1).fit(
            [trajectory_shapes(planted_pair(s), cam) for s in range(3)]
        ),
    )
    save_model(folder / "responder-listener.npz", ListenerModel().fit({"interested": [(("S:nod",), ("L:nod",), 0.9)]}))
    save_model(
        folder / "responder-emotion.npz",
        EmotionModel().fit(
            np.random.default_rng(0).normal(size=(8, 7)), ["neutral", "angry"] * 4, [0, 1] * 4, ["g"] * 8
        ),
    )
    gpdm = GPDM(points=200, num_inducing=10, n_centres=20, max_iters=20, dyn_points=150, support=1000)
    save_model(folder / "responder-gpdm.npz", gpdm.fit(sim_trajectories(("handshake",), range(2), max_frames=200)))
    rec, _ = sim_recording(8.0, seed=4)
    save_model(folder / "responder-video-texture.npz", fit_recording(rec, required=("nod",)))
    return folder


@pytest.fixture(scope="module")
def live(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    tmp = tmp_path_factory.mktemp("contract")
    models = small_models(tmp_path_factory.mktemp("models"))
    port_file, out = tmp / "port", tmp / "partners.jsonl"
    file = write_launch(
        tmp / "graph.yaml",
        {
            "nodes": {
                "source": {"run": "tests.contract_nodes:PersonSource"},
                "responder": {"run": "counterpart.nodes.responder", "params": {"use_silhouettes": True}},
                "sink": {"run": "tests.responder_nodes:PartnerSink", "params": {"path": str(out)}},
                "renderer": {
                    "run": "counterpart.nodes.renderer",
                    "params": {"serve": True, "port": 0, "port_file": str(port_file), "camera_info": False},
                },
            }
        },
    )
    proc = start_launch(file, env={"COUNTERPART_MODELS": str(models)})
    try:
        assert wait_for(lambda: port_file.exists() and port_file.read_text().strip(), timeout=60), "no port file"
        url = f"http://127.0.0.1:{int(port_file.read_text())}"
        assert wait_for(lambda: len(read_jsonl(out)) > 5, timeout=60), "no partner"
        yield {"url": url, "out": out}
    finally:
        stop_launch(proc)


def _request(url: str, body: Any = None) -> tuple[int, Any]:
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(url, data=data, headers={"Content-Type": "application/json"})
    try:
        with urllib.request.urlopen(req, timeout=10) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read())


def made_by(row: dict[str, Any], model: str) -> bool:
    """The partner of ``row`` is one that ``model`` makes (not an empty or held one)."""
    if row["model"] != model or row["behaviour"] in ("none", "hold"):
        return False
    if model == "joint-shape":
        return row["ctrl_shape"] == [32, 2]
    if model == "video-texture":
        return len(row["frames"]) > 0
    return row["shape"] == [14, 3]


def _settings(row: dict[str, Any]) -> dict[str, Any]:
    return {k: row[k] for k in (*START, "behaviour", "shape", "ctrl_shape")}


def took_effect(rows: list[dict[str, Any]], want: dict[str, Any]) -> bool:
    """A partner among ``rows`` made under the settings ``want``, by the model it names."""
    return any(all(r[k] == v for k, v in want.items()) and made_by(r, want["model"]) for r in rows)


@pytest.mark.slow
def test_every_choice_the_page_offers_takes_effect_in_the_responder(live: dict[str, Any]) -> None:
    status, state = _request(live["url"] + "/state")
    assert status == 200
    # the page offers the contract's names, all of them (the renderer's default), and nothing else
    assert state["models"] == list(INTERACTION_MODELS)
    assert state["emotions"] == list(EMOTIONS) and state["speakers"] == list(SPEAKERS)
    assert state["interest_levels"] == list(INTEREST_LEVELS)
    choices = [("model", v) for v in state["models"]] + [("speaker", v) for v in state["speakers"]]
    choices += [("interest", v) for v in state["interest_levels"]] + [("emotion", v) for v in state["emotions"]]
    current = dict(START)
    # each setting's starting value last, so that every post changes what is in force
    choices.sort(key=lambda kv: (list(START).index(kv[0]), kv[1] == START[kv[0]]))
    for key, value in choices:
        n = len(read_jsonl(live["out"]))
        # the JSON the page's script posts for this control (page.html: postControl({key: value}))
        status, body = _request(live["url"] + "/control", {key: value})
        assert status == 200 and body == {key: value}, body
        current[key] = value

        want = dict(current)
        assert wait_for(lambda n=n, want=want: took_effect(read_jsonl(live["out"])[n:], want), timeout=30), (
            f"{key}={value!r} did not take effect: last partners {[_settings(r) for r in read_jsonl(live['out'])[-3:]]}"
        )


@pytest.mark.slow
def test_a_name_outside_the_contract_is_refused_by_the_page(live: dict[str, Any]) -> None:
    for key, value in (("model", "emotion"), ("emotion", "bored"), ("speaker", "dog"), ("interest", 4)):
        status, body = _request(live["url"] + "/control", {key: value})
        assert status == 400 and key in body["error"], body


def test_control_refuses_a_name_outside_the_contract_when_made_and_when_decoded() -> None:
    import msgpack

    from counterpart.messages import Control, DecodeError, decode, encode

    for key, value in (
        ("model", "emotion"),
        ("emotion", "bored"),
        ("speaker", "dog"),
        ("interest", 4),
        ("strength", 2.0),
    ):
        with pytest.raises(ValueError, match=f"Control.{key}="):
            Control(**{key: value})
        # a forged message on the bus: the receiver counts it as a bad field and drops it
        header = msgpack.unpackb(encode(Control())[0])
        header["f"][key] = value
        with pytest.raises(DecodeError, match=f"Control.{key}=") as err:
            decode([msgpack.packb(header)])
        assert err.value.kind == "bad_field"
    for model in INTERACTION_MODELS:
        assert decode(encode(Control(model=model))).model == model
