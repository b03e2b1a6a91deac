"""A folder of numbered frames read as a video (``counterpart.body.image_sequence``), and the offline
commands and the demo taking such a folder wherever they take a video file.
"""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from counterpart.body.image_sequence import ImageSequenceCapture, list_images, read_frames, video_info
from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor
from counterpart.sim.flat_scenes import two_person_sequence
from tests.launching import run_cli


@pytest.fixture(scope="module")
def handshake():
    return two_person_sequence(n_frames=40, empty_frames=20, seed=1)


def _write(folder: Path, frames: np.ndarray, ext: str = "png") -> None:
    folder.mkdir()
    for i, frame in enumerate(frames):
        assert cv2.imwrite(str(folder / f"in{i + 1:06d}.{ext}"), frame)


def test_frames_come_in_name_order_bit_exact_and_counted(handshake, tmp_path: Path) -> None:
    folder = tmp_path / "frames"
    _write(folder, handshake.frames)
    (folder / "readme.txt").write_text("not a frame")
    assert [p.name for p in list_images(folder)][:3] == ["in000001.png", "in000002.png", "in000003.png"]
    frames = read_frames(folder)
    assert frames.shape == handshake.frames.shape and np.array_equal(frames, handshake.frames)  # PNG is lossless
    assert video_info(folder) == (0.0, len(handshake.frames))  # a folder declares no rate
    cap = ImageSequenceCapture(folder, fps=12.5)
    assert cap.get(cv2.CAP_PROP_FPS) == 12.5 and cap.grab() and cap.grab()
    ok, third = cap.read()
    assert ok and np.array_equal(third, handshake.frames[2])
    cap.release()
    assert not cap.isOpened() and not cap.read()[0]


def test_a_bad_image_is_skipped_and_a_bad_folder_named(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="image folder not found: .*missing"):
        ImageSequenceCapture(tmp_path / "missing")
    with pytest.raises(ValueError, match=r"has no file matching '\*\.png\|\*\.jpg'"):
        ImageSequenceCapture(tmp_path)
    cv2.imwrite(str(tmp_path / "0.png"), np.full((10, 10, 3), 1, np.uint8))
    cv2.imwrite(str(tmp_path / "1.png"), np.zeros((12, 10, 3), np.uint8))
    (tmp_path / "2.jpg").write_bytes(b"garbage")
    cv2.imwrite(str(tmp_path / "3.png"), np.full((10, 10, 3), 7, np.uint8))
    frames = read_frames(tmp_path)
    assert [int(f[0, 0, 0]) for f in frames] == [1, 7]  # another size and an undecodable file: skipped
    cap = ImageSequenceCapture(tmp_path)
    while cap.read()[0]:
        pass
    assert cap.skipped == 2


def test_silhouettes_of_a_folder_are_those_of_its_frames(handshake, tmp_path: Path) -> None:
    folder = tmp_path / "frames"
    _write(folder, handshake.frames)
    out = tmp_path / "people.npz"
    r = run_cli("silhouettes", str(folder), "--out", str(out), "--train-frames", "20")
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout.strip().splitlines()[-1])["n_frames"] == len(handshake.frames)
    d = np.load(out)
    # the same frames in memory through the same extractor: the same people, box for box
    ex = SilhouetteExtractor()
    ex.fit_background(handshake.frames[:20], robust=True)
    boxes = [(k, p.id, *p.bbox) for k, f in enumerate(handshake.frames) for p in ex.process(f).people]
    assert len(boxes) >= 30
    assert [tuple(int(v) for v in row) for row in np.column_stack([d["frame"], d["id"], d["bbox"]])] == boxes
    r = run_cli("silhouettes", str(tmp_path / "none"), "--out", str(out), timeout=60)
    assert r.returncode == 2 and "video file or image folder not found" in r.stderr and "none" in r.stderr
