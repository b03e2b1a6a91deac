"""The responder node with model video-texture in a real launch: a nodding speaker in, Partner messages
that carry the avatar's recording frames out, and the avatar nods back as the listener rules say.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from counterpart.nodes.responder.avatar_recording import sim_recording
from counterpart.nodes.responder.listener import ListenerModel
from counterpart.nodes.responder.models import load_model, save_model
from counterpart.nodes.responder.video_texture import fit_recording
from tests.launching import read_jsonl, run_launch, write_launch

FRAMES, NOD_FROM = 90, 30


@pytest.fixture(scope="module")
def models(tmp_path_factory) -> tuple[Path, Path]:
    """(models folder with a listener whose rule answers a nod with a nod, an avatar file)."""
    d = tmp_path_factory.mktemp("models")
    save_model(
        d / "responder-listener.npz",
        ListenerModel(offset_s=0.2, response_s=1.5).fit({"interested": [(("S:nod",), ("L:nod",), 1.0)]}),
    )
    rec, _ = sim_recording(12.0, seed=4)
    avatar = save_model(d / "me.npz", fit_recording(rec, required=("nod",)))
    return d, avatar


@pytest.mark.slow
def test_the_avatar_answers_a_nodding_speaker(tmp_path: Path, models: tuple[Path, Path]) -> None:
    folder, avatar = models
    g = write_launch(
        tmp_path / "g.yaml",
        {
            "nodes": {
                "speaker": {
                    "run": "tests.avatar_nodes:NoddingSpeaker",
                    "params": {"frames": FRAMES, "nod_from": NOD_FROM},
                },
                "responder": {
                    "run": "counterpart.nodes.responder",
                    "params": {
                        "model": "video-texture",
                        "model_file": str(avatar),
                        "use_signals": True,
                        "use_control": False,
                    },
                },
                "sink": {"run": "tests.responder_nodes:PartnerSink", "params": {"path": str(tmp_path / "out.jsonl")}},
            }
        },
    )
    code, out = run_launch(g, timeout=120, env={"COUNTERPART_MODELS": str(folder)})
    assert code == 0, out
    rows = read_jsonl(tmp_path / "out.jsonl")
    assert [r["seq"] for r in rows] == list(range(FRAMES))  # one partner per pose
    m = load_model(avatar, expected="video-texture")
    nod = m.names_.index("nod")
    for r in rows:
        assert r["model"] == "video-texture" and r["file"] == str(avatar)
        assert 1 <= len(r["frames"]) <= 2 and abs(sum(r["weights"]) - 1) < 1e-5
        assert all(m.alive_[f] for f in r["frames"][:1])
        assert np.shape(r["joints"]) == (14, 3)  # where the avatar stands: facing the speaker
    # the rule answers the nod 0.2 s later; the avatar shows a nod within a second of that
    start = NOD_FROM + 5
    shown = [m.labels_[r["frames"][0], nod] == 1 for r in rows]
    assert any(shown[start : start + 25]), [r["behaviour"] for r in rows[start : start + 25]]
    assert any("nod" in r["behaviour"] for r in rows[start : start + 25])
    # consecutive partners play the recording on, or cut (and then cross-fade from the frame left)
    for a, b in zip(rows, rows[1:]):
        if b["frames"][0] != a["frames"][0] + 1:
            assert b["frames"][1:] == [a["frames"][0] + 1] or not m.alive_[a["frames"][0] + 1]
