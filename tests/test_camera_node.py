"""The camera node in real graphs: ``counterpart launch`` (bus.cli) of a camera and a recording sink."""

from __future__ import annotations

import hashlib
import json
import os
import re
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest
import yaml

from counterpart.nodes.camera.node import EXIT_SOURCE_ERROR
from counterpart.nodes.camera.sources import video_devices
from tests.camera_sink import VTEST, cv2_frames, write_video

REPO = Path(__file__).resolve().parents[1]


def launch(tmp_path: Path, camera: dict[str, Any], timeout: float = 60) -> tuple[int, str, list[dict[str, Any]]]:
    """Run camera -> sink to its end; return (launcher exit code, its output, the sink's records)."""
    out = tmp_path / "sink.jsonl"
    out.unlink(missing_ok=True)
    doc = {
        "nodes": {
            "camera": {"run": "counterpart.nodes.camera", "params": camera},
            "sink": {"run": "tests.camera_sink", "params": {"path": str(out)}, "policy": "reliable"},
        }
    }
    file = tmp_path / "graph.yaml"
    file.write_text(yaml.safe_dump(doc, sort_keys=False))
    proc = subprocess.Popen(
        [sys.executable, "-m", "counterpart.bus.cli", "launch", str(file)],
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )
    try:
        text, _ = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        text, _ = proc.communicate()
        pytest.fail(f"the graph did not end by itself within {timeout} s:\n{text}")
    records = [json.loads(line) for line in out.read_text().splitlines()] if out.exists() else []
    return proc.returncode, text, records


def frame_records(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    assert records and records[-1] == {"event": "end", "drops": 0}, "the sink did not get end of stream"
    return records[:-1]


def sha(img: np.ndarray) -> str:
    return hashlib.sha1(np.ascontiguousarray(img).tobytes()).hexdigest()


@pytest.mark.parametrize("prefetch", [4, 0])
def test_lockstep_delivers_every_frame_bit_exact(tmp_path: Path, prefetch: int) -> None:
    path = write_video(tmp_path / "clip.avi", n=40, size=(160, 120), fps=25.0)
    code, text, records = launch(tmp_path, {"source": str(path), "pacing": "lockstep", "prefetch": prefetch})
    assert code == 0, text
    got = frame_records(records)
    ref = cv2_frames(path)
    assert [r["seq"] for r in got] == list(range(40))
    assert [r["sha1"] for r in got] == [sha(f) for f in ref]
    assert all(r["shape"] == [120, 160, 3] and r["encoding"] == "bgr8" for r in got)
    assert [r["source_time"] for r in got] == pytest.approx([i / 25.0 for i in range(40)])
    stamps = [r["stamp"] for r in got]
    assert stamps == sorted(stamps) and all(r["received"] >= r["stamp"] for r in got)


def test_a_long_replay_logs_its_progress(tmp_path: Path) -> None:
    """A lockstep replay says how far it has come, of how many, and how long is left (here after
    every frame, as ``progress_s`` is tiny, of which the node's log lets the first 10 through); a
    short one at the default every 10 s says nothing of it.
    """
    path = write_video(tmp_path / "clip.avi", n=40, size=(160, 120), fps=25.0)
    code, text, records = launch(
        tmp_path, {"source": str(path), "pacing": "lockstep", "progress_s": 1e-6, "start_frame": 10}
    )
    assert code == 0, text
    assert len(frame_records(records)) == 30
    done = [int(k) for k in re.findall(r"frame (\d+) of 30 \(\d+%\) published, [\d.]+ frames/s", text)]
    assert done[:10] == list(range(1, 11)), text  # more only where 30 frames took over 10 s
    assert "frame 3 of 30 (10%) published" in text and re.search(r"about \d+ s left", text)
    code, text, _ = launch(tmp_path, {"source": str(path), "pacing": "lockstep"})
    assert code == 0 and "frames/s" not in text, text


@pytest.mark.skipif(not VTEST.exists(), reason=f"real video {VTEST} absent (see ../shared/data/README.md)")
def test_lockstep_real_video_first_100_frames_bit_exact(tmp_path: Path) -> None:
    code, text, records = launch(tmp_path, {"source": f"file:{VTEST}", "pacing": "lockstep", "max_frames": 100})
    assert code == 0, text
    got = frame_records(records)
    cap = cv2.VideoCapture(str(VTEST))
    ref = [sha(cap.read()[1]) for _ in range(100)]
    assert [r["seq"] for r in got] == list(range(100))
    assert [r["sha1"] for r in got] == ref
    assert got[0]["shape"] == [576, 768, 3] and got[-1]["source_time"] == pytest.approx(9.9)


def test_image_folder_gray_resized_with_start_and_loop(tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    folder = tmp_path / "frames"
    folder.mkdir()
    imgs = [rng.integers(0, 256, (48, 64, 3), dtype=np.uint8) for _ in range(4)]
    for i, img in enumerate(imgs):
        cv2.imwrite(str(folder / f"f{i:03d}.png"), img)
    code, text, records = launch(
        tmp_path,
        {
            "source": f"folder:{folder}",
            "pacing": "fast",
            "gray": True,
            "width": 32,
            "start_frame": 1,
            "loop": True,
            "max_frames": 7,
        },
    )
    assert code == 0, text
    got = frame_records(records)
    order = [1, 2, 3, 1, 2, 3, 1]
    want = [
        sha(cv2.cvtColor(cv2.resize(imgs[i], (32, 24), interpolation=cv2.INTER_AREA), cv2.COLOR_BGR2GRAY))
        for i in order
    ]
    assert [r["sha1"] for r in got] == want
    assert [r["seq"] for r in got] == list(range(7))
    assert all(r["shape"] == [24, 32] and r["encoding"] == "mono8" for r in got)
    assert [r["source_time"] for r in got] == pytest.approx([i / 25.0 for i in order])


def test_max_side_scales_a_large_source_down_and_says_so(tmp_path: Path) -> None:
    folder = tmp_path / "frames"
    folder.mkdir()
    img = np.random.default_rng(5).integers(0, 256, (48, 64, 3), dtype=np.uint8)
    for i in range(3):
        cv2.imwrite(str(folder / f"f{i:03d}.png"), img)
    for max_side, shape in ((32, [24, 32, 3]), (64, [48, 64, 3])):
        code, text, records = launch(tmp_path, {"source": f"folder:{folder}", "pacing": "fast", "max_side": max_side})
        assert code == 0, text
        got = frame_records(records)
        assert len(got) == 3 and all(r["shape"] == shape for r in got), (max_side, got)
        assert ("scaled down to camera.max_side 32" in text) == (max_side == 32), text


def test_corrupt_file_logs_clear_error_and_graph_ends(tmp_path: Path) -> None:
    bad = tmp_path / "broken.avi"
    bad.write_bytes(np.random.default_rng(4).integers(0, 256, 50_000, dtype=np.uint8).tobytes())
    code, text, records = launch(tmp_path, {"source": str(bad), "pacing": "lockstep"})
    assert code == EXIT_SOURCE_ERROR, text
    assert f"parameter 'source': cannot decode video '{bad}'" in text
    assert frame_records(records) == []  # end of stream reached the sink: it ended by itself
    assert "camera exited with 3" in text and "sink exited with 0" in text


def test_missing_v4l2_device_names_it_and_lists_present(tmp_path: Path) -> None:
    present = video_devices()
    dev = next(f"/dev/video{i}" for i in range(90, 200) if f"/dev/video{i}" not in present)
    code, text, records = launch(tmp_path, {"source": dev})
    assert code == EXIT_SOURCE_ERROR, text
    assert f"V4L2 device '{dev}' does not exist" in text
    if present:
        assert all(d in text for d in present)
    else:
        assert "no /dev/video* devices exist on this machine" in text
    assert frame_records(records) == []


@pytest.mark.parametrize("pacing,rate,period_s", [("realtime", 1.0, 1 / 25), ("rate", 2.5, 1 / 62.5)])
def test_paced_replay_keeps_the_file_rate(tmp_path: Path, pacing: str, rate: float, period_s: float) -> None:
    path = write_video(tmp_path / "clip.avi", n=24, size=(64, 48), fps=25.0)
    code, text, records = launch(tmp_path, {"source": str(path), "pacing": pacing, "rate": rate})
    assert code == 0, text
    got = frame_records(records)
    assert [r["seq"] for r in got] == list(range(24))
    since_first = (np.array([r["stamp"] for r in got]) - got[0]["stamp"]) / 1e9
    # never ahead of the file's schedule (up to the first frame's own lateness)...
    assert np.all(since_first >= np.arange(24) * period_s - period_s / 2)
    # ...and at its spacing: a loaded machine makes single frames late (the next one catches up),
    # which moves the median interval a little, never to half the rate
    assert 0.8 * period_s <= np.median(np.diff(since_first)) <= 1.5 * period_s


def test_bad_parameter_is_refused_before_start(tmp_path: Path) -> None:
    code, text, records = launch(tmp_path, {"source": "clip.avi", "pacing": "slow"})
    assert code == 2 and "node 'camera': params: parameter 'pacing': 'slow' is not one of" in text
    assert records == []


def test_module_runs_alone(tmp_path: Path) -> None:
    """``python -m counterpart.nodes.camera`` (no launcher): a missing file ends with exit code 3 and the reason."""
    r = subprocess.run(
        [sys.executable, "-m", "counterpart.nodes.camera", "--param", f"source={tmp_path / 'gone.mp4'}"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert r.returncode == EXIT_SOURCE_ERROR and "gone.mp4' does not exist" in r.stderr


def test_example_launch_file_checks() -> None:
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "counterpart.bus.cli",
            "launch",
            "camera_file.yaml",
            "--check",
            "--set",
            "camera.source=folder:frames",
            "--set",
            "camera.pacing=lockstep",
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert r.returncode == 0 and "1 nodes, 2 topics: OK" in r.stdout, r.stderr
