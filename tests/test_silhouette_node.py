"""The silhouette node in real graphs: camera (lockstep replay of a generated video) -> silhouette -> sinks."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

from counterpart.nodes.silhouette.node import Silhouette
from counterpart.sim.flat_scenes import SyntheticSequence, two_person_sequence
from tests.launching import REPO, read_jsonl, run_launch, write_launch

EMPTY_FRAMES = 15
TRAIN = 15
N = 60


def write_clip(path: Path, seq: SyntheticSequence, fps: float = 25.0) -> Path:
    """An MJPG .avi of the frames (lossy, as real recordings are)."""
    h, w = seq.frames.shape[1:3]
    wr = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), fps, (w, h))
    assert wr.isOpened(), f"cv2.VideoWriter cannot write MJPG to {path}"
    for f in seq.frames:
        wr.write(f)
    wr.release()
    return path


def write_folder(folder: Path, seq: SyntheticSequence) -> str:
    """The frames as PNG files (lossless, so the found shapes can be held to the ground truth)."""
    folder.mkdir()
    for i, f in enumerate(seq.frames):
        cv2.imwrite(str(folder / f"f{i:03d}.png"), f)
    return f"folder:{folder}"


@pytest.fixture(scope="module")
def scene(tmp_path_factory: pytest.TempPathFactory) -> tuple[str, SyntheticSequence]:
    """15 frames of the empty textured scene, then two people (with shadows) walk in, shake hands
    and part; as a PNG folder source.
    """
    seq = two_person_sequence(n_frames=N - EMPTY_FRAMES, size=(120, 160), empty_frames=EMPTY_FRAMES)
    return write_folder(tmp_path_factory.mktemp("scene") / "frames", seq), seq


def graph(tmp_path: Path, source: str, silhouette: dict[str, Any], camera: dict[str, Any] | None = None) -> Path:
    return write_launch(
        tmp_path / "graph.yaml",
        {
            "nodes": {
                "camera": {
                    "run": "counterpart.nodes.camera",
                    "params": {"source": source, "pacing": "lockstep", "fps": 25.0, **(camera or {})},
                },
                "silhouette": {"run": "counterpart.nodes.silhouette", "params": silhouette, "policy": "reliable"},
                "frames": {
                    "run": "tests.topic_sink",
                    "params": {"topic": "frame", "path": str(tmp_path / "frames.jsonl")},
                    "policy": "reliable",
                },
                "out": {
                    "run": "tests.topic_sink",
                    "params": {"topic": "silhouettes", "path": str(tmp_path / "sil.jsonl")},
                    "policy": "reliable",
                },
            }
        },
    )


def records(path: Path) -> list[dict[str, Any]]:
    recs = read_jsonl(path)
    assert recs and recs[-1]["event"] == "end" and recs[-1]["drops"] == 0, f"{path.name}: no clean end of stream"
    return recs[:-1]


def truth_box(mask: np.ndarray) -> tuple[int, int, int, int]:
    ys, xs = np.nonzero(mask)
    return int(xs.min()), int(ys.min()), int(xs.max() - xs.min() + 1), int(ys.max() - ys.min() + 1)


def test_lockstep_one_silhouettes_per_frame_people_match_truth(tmp_path: Path, scene) -> None:
    source, seq = scene
    code, text = run_launch(graph(tmp_path, source, {"train_frames": TRAIN}), timeout=60)
    assert code == 0, text
    frames, sils = records(tmp_path / "frames.jsonl"), records(tmp_path / "sil.jsonl")
    assert [r["seq"] for r in frames] == list(range(N))
    # exactly one output per frame, in order, carrying the frame's seq and stamp
    assert [(r["seq"], r["stamp"]) for r in sils] == [(r["seq"], r["stamp"]) for r in frames]
    assert all(r["type"] == "silhouette.Silhouettes/1" and (r["width"], r["height"]) == (160, 120) for r in sils)
    # while learning (and on the empty scene) nobody; the mask still goes out every frame
    assert all(r["people"] == [] for r in sils[:EMPTY_FRAMES])
    assert all(r["labels"]["shape"] == [120, 160] and r["labels"]["dtype"] == "uint8" for r in sils)
    assert all(r["labels"]["nonzero"] == 0 for r in sils[:EMPTY_FRAMES])
    unmerged = 0
    for k in range(EMPTY_FRAMES, N):
        people = sils[k]["people"]
        assert [(p["id"], p["side"]) for p in people] == [(0, "left"), (1, "right")], f"frame {k}: {people}"
        assert sils[k]["labels"]["max"] == 2
        assert sils[k]["labels"]["nonzero"] == pytest.approx(seq.person_masks[k].any(0).sum(), rel=0.1)
        for pid, p in enumerate(people):
            ctrl = np.array(p["ctrl"], float)
            assert ctrl.shape == (32, 2)
            x, y, w, h = truth_box(seq.person_masks[k, pid])
            # the top of the head (box top and the spline's reference point) and the height
            assert abs(p["bbox"][1] - y) <= 1 and abs(p["ref_point"][1] - y) <= 1.5, f"frame {k} person {pid}"
            assert abs(p["height"] - h) <= 2, f"frame {k} person {pid}: height {p['height']} vs {h}"
            if not p["merged"]:  # (a merged region is split by the previous shapes: boxes overlap)
                # the outline lies on the person: every control point inside the (slightly grown) true box
                assert (ctrl[:, 0] >= x - 2).all() and (ctrl[:, 0] <= x + w + 2).all(), f"frame {k} person {pid}"
                assert (ctrl[:, 1] >= y - 2).all() and (ctrl[:, 1] <= y + h + 2).all(), f"frame {k} person {pid}"
                truth_c = np.argwhere(seq.person_masks[k, pid])[:, ::-1].mean(0)
                assert np.abs(np.array(p["centroid"]) - truth_c).max() <= 1, f"frame {k} person {pid}"
                assert p["area"] == pytest.approx(seq.person_masks[k, pid].sum(), rel=0.05)
                assert [abs(a - b) <= 2 for a, b in zip(p["bbox"], (x, y, w, h))] == [True] * 4, (
                    f"frame {k} person {pid}"
                )
                unmerged += 1
    assert unmerged >= 40
    # the one call that learnt the background is timed in the node's stats (bench/e2e.py reads it)
    run_dir = Path(re.search(r"run directory (\S+)", text).group(1))
    figures = json.loads((run_dir / "stats" / "silhouette.json").read_text())["figures"]
    assert figures["fit_ms"] > 0


def assert_grey_walkers(sils: list[dict[str, Any]], seq: SyntheticSequence) -> None:
    """The two walkers of ``seq`` on grey frames, before they meet: the left one (dark red, high
    contrast in grey) within 2 px of the truth's box, the right one at least 0.6 of its height.
    """
    for r in sils:
        k = r["seq"]
        assert [(p["id"], p["side"]) for p in r["people"]] == [(0, "left"), (1, "right")], f"frame {k}"
        x, y, w, h = truth_box(seq.person_masks[k, 0])
        assert [abs(a - b) <= 2 for a, b in zip(r["people"][0]["bbox"], (x, y, w, h))] == [True] * 4, f"frame {k}"
        assert r["people"][1]["height"] >= 0.6 * truth_box(seq.person_masks[k, 1])[3]


def test_mono8_frames_without_shadows_and_thinned_mask(tmp_path: Path) -> None:
    # grey frames: darker people and shadows look alike, so this scene has no cast shadows
    seq = two_person_sequence(n_frames=N - EMPTY_FRAMES, size=(120, 160), empty_frames=EMPTY_FRAMES, shadow_factor=1.0)
    source = write_folder(tmp_path / "frames_in", seq)
    code, text = run_launch(
        graph(tmp_path, source, {"train_frames": TRAIN, "mask_every": 4}, camera={"gray": True}), timeout=60
    )
    assert code == 0, text
    frames, sils = records(tmp_path / "frames.jsonl"), records(tmp_path / "sil.jsonl")
    assert frames[0]["encoding"] == "mono8" and frames[0]["image"]["shape"] == [120, 160]
    assert [(r["seq"], r["stamp"]) for r in sils] == [(r["seq"], r["stamp"]) for r in frames]
    assert all(r["people"] == [] for r in sils[:EMPTY_FRAMES])
    # the mask only on every 4th seq; an empty array otherwise
    assert [r["seq"] for r in sils if r["labels"] != []] == list(range(0, N, 4))
    assert_grey_walkers(sils[EMPTY_FRAMES : EMPTY_FRAMES + 10], seq)


def test_unknown_backend_refused_before_start_naming_it(tmp_path: Path, scene) -> None:
    source, _ = scene
    code, text = run_launch(graph(tmp_path, source, {"backend": "nope"}), timeout=30)
    assert code == 2, text
    assert "silhouette" in text and "'backend'" in text and "'nope'" in text and "horprasert" in text
    assert not (tmp_path / "sil.jsonl").exists(), "nothing may start when a parameter is bad"
    code, text = run_launch(graph(tmp_path, source, {}), "--set", "silhouette.train_frames=1", timeout=30)
    assert code == 2 and "'train_frames'" in text and "minimum" in text, text
    code, text = run_launch(graph(tmp_path, source, {}), "--set", "silhouette.absorb_frames=-2", timeout=30)
    assert code == 2 and "'absorb_frames'" in text and "minimum" in text, text


def test_example_launch_file_runs_on_a_given_mjpg_video(tmp_path: Path, scene) -> None:
    _, seq = scene
    clip = write_clip(tmp_path / "scene.avi", seq)
    code, text = run_launch(
        REPO / "launch" / "silhouette_file.yaml",
        "--set",
        f"camera.source={clip}",
        "--set",
        "camera.pacing=lockstep",
        "--set",
        "silhouette.train_frames=15",
        timeout=60,
    )
    assert code == 0, text
    assert f"published {N} frames" in text and f"people found in {N - EMPTY_FRAMES} of {N} frames" in text
    assert "silhouette exited with 0" in text


def test_opencv_threads_sets_the_process_pool_and_zero_leaves_it() -> None:
    before = cv2.getNumThreads()
    try:
        cv2.setNumThreads(2)
        Silhouette({"name": "silhouette", "params": {"opencv_threads": 1}}).setup()
        assert cv2.getNumThreads() == 1
        cv2.setNumThreads(2)
        Silhouette({"name": "silhouette", "params": {}}).setup()
        assert cv2.getNumThreads() == 2
    finally:
        cv2.setNumThreads(before)


@pytest.mark.parametrize("replay", [True, False])
def test_a_camera_turning_monochrome_mid_stream_is_learnt_again(tmp_path: Path, replay: bool) -> None:
    """A day/night camera turning to infrared (grey frames) in an empty room that two people then
    walk into: the node sees the switch, learns the background again from the frames from there
    (held back meanwhile as at the start with ``replay_training``, published without people in a
    live graph), and finds the people on grey frames as on a grey stream's; with the switch not
    followed the colour model finds neither.
    """
    empty, switch = 40, 20
    seq = two_person_sequence(n_frames=20, size=(120, 160), empty_frames=empty, shadow_factor=1.0)
    folder = tmp_path / "frames_in"
    folder.mkdir()
    for i, f in enumerate(seq.frames):
        grey = cv2.cvtColor(cv2.cvtColor(f, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR)
        cv2.imwrite(str(folder / f"f{i:03d}.png"), f if i < switch else grey)
    n = len(seq.frames)

    def people(params: dict[str, Any], out: Path) -> tuple[list[dict[str, Any]], str]:
        out.mkdir()
        code, text = run_launch(
            graph(out, f"folder:{folder}", {"train_frames": TRAIN, "replay_training": replay, **params}), timeout=60
        )
        assert code == 0, text
        frames, sils = records(out / "frames.jsonl"), records(out / "sil.jsonl")
        assert [(r["seq"], r["stamp"]) for r in sils] == [(r["seq"], r["stamp"]) for r in frames] and len(sils) == n
        return sils, text

    sils, text = people({}, tmp_path / "followed")
    # seen once, on the fifth to seventh grey frame; a replay holds the grey frames back from the
    # first looked at (every third frame is, while they are of the model's kind), so that they all
    # get the new model's people, and names that frame
    seen = [int(k) for k in re.findall(r"frame (\d+): the camera switched to monochrome frames", text)]
    first = (switch, switch + 2) if replay else (switch + 4, switch + 6)
    assert len(seen) == 1 and first[0] <= seen[0] <= first[1], text
    run_dir = Path(re.search(r"run directory (\S+)", text).group(1))
    assert json.loads((run_dir / "stats" / "silhouette.json").read_text())["figures"]["relearns"] == 1
    assert all(r["people"] == [] for r in sils[:empty])
    # the two walkers on the grey frames, before they meet (from frame 44 their hands reach out and
    # their true boxes overlap, where their split depends on the frames the model has seen), as on
    # a grey stream's
    apart = slice(empty, empty + 4)
    assert_grey_walkers(sils[apart], seq)
    if replay:
        # not followed: the colour model finds all of the grey room changed, and no walker in it
        kept, text = people({"colour_switch_frames": 0}, tmp_path / "kept")
        assert "switched" not in text
        assert not any(r["people"] for r in kept[apart])
