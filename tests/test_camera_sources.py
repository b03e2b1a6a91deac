"""Camera sources, pacing and conversion on real files, without any process running."""

from __future__ import annotations

import hashlib
import importlib
from pathlib import Path

import cv2
import numpy as np
import pytest

from counterpart.bus import ParamError
from counterpart.nodes.camera.node import Camera
from counterpart.nodes.camera.pacing import Pacer, Prefetch, convert, frames, output_size, replay_progress
from counterpart.nodes.camera.sources import (
    ImageFolderSource,
    SimulatorSource,
    SourceError,
    V4L2Source,
    VideoFileSource,
    make_source,
    parse_uri,
    read_with_retry,
    video_devices,
)
from tests.camera_sink import VTEST, cv2_frames, write_video


def sha(img: np.ndarray) -> str:
    return hashlib.sha1(img.tobytes()).hexdigest()


def read_all(src) -> list[tuple[np.ndarray, float]]:
    out = []
    while True:
        ok, img, t = src.read()
        if not ok:
            return out
        out.append((img, t))


# ---------------------------------------------------------------------------------- video files
def test_video_file_matches_cv2_bit_exact(tmp_path: Path) -> None:
    path = write_video(tmp_path / "clip.avi", n=12, fps=25.0)
    src = VideoFileSource(path)
    src.open()
    assert (src.fps, src.size, src.frame_count) == (25.0, (96, 72), 12)
    got = read_all(src)
    src.close()
    ref = cv2_frames(path)
    assert len(got) == len(ref) == 12
    assert [sha(g) for g, _ in got] == [sha(r) for r in ref]
    assert [t for _, t in got] == pytest.approx([i / 25.0 for i in range(12)])


def test_video_file_skip_and_rewind_are_exact(tmp_path: Path) -> None:
    path = write_video(tmp_path / "clip.avi", n=10)
    ref = [sha(f) for f in cv2_frames(path)]
    src = VideoFileSource(path)
    src.open()
    assert src.skip(3) == 3
    assert [sha(g) for g, _ in read_all(src)] == ref[3:]
    src.rewind()
    assert [sha(g) for g, _ in read_all(src)] == ref
    src.close()


@pytest.mark.skipif(not VTEST.exists(), reason=f"real video {VTEST} absent (see ../shared/data/README.md)")
def test_real_mp43_video_header_and_first_frames() -> None:
    src = VideoFileSource(VTEST)
    src.open()
    assert (src.fps, src.size, src.frame_count) == (10.0, (768, 576), 795)
    cap = cv2.VideoCapture(str(VTEST))
    for i in range(20):
        ok, img, t = src.read()
        assert ok and sha(img) == sha(cap.read()[1]) and t == pytest.approx(i / 10.0)
    src.close()


def test_video_file_errors_name_the_file(tmp_path: Path) -> None:
    missing = tmp_path / "nope.avi"
    with pytest.raises(SourceError, match=r"'.*nope\.avi' does not exist"):
        VideoFileSource(missing).open()
    corrupt = tmp_path / "corrupt.avi"
    corrupt.write_bytes(np.random.default_rng(0).integers(0, 256, 20000, dtype=np.uint8).tobytes())
    with pytest.raises(SourceError, match=r"cannot decode video '.*corrupt\.avi'"):
        VideoFileSource(corrupt).open()
    empty = tmp_path / "empty.avi"
    empty.write_bytes(b"")
    with pytest.raises(SourceError, match=r"empty\.avi'.*empty"):
        VideoFileSource(empty).open()
    # A valid container with no frames opens in OpenCV and yields nothing: caught at open.
    zero = tmp_path / "zero.avi"
    cv2.VideoWriter(str(zero), cv2.VideoWriter_fourcc(*"MJPG"), 25, (64, 48)).release()
    assert cv2.VideoCapture(str(zero)).isOpened()
    with pytest.raises(SourceError, match=r"zero\.avi': it opened but no frame could be decoded"):
        VideoFileSource(zero).open()
    with pytest.raises(SourceError, match="is a directory"):
        VideoFileSource(tmp_path).open()


# ---------------------------------------------------------------------------------- image folders
def test_image_folder_sorted_with_pattern(tmp_path: Path) -> None:
    rng = np.random.default_rng(1)
    imgs = {name: rng.integers(0, 256, (30, 40, 3), dtype=np.uint8) for name in ("b_002.png", "a_010.png", "c_001.png")}
    for name, img in imgs.items():
        cv2.imwrite(str(tmp_path / name), img)
    (tmp_path / "notes.txt").write_text("not an image")
    src = ImageFolderSource(tmp_path, fps=5.0)
    src.open()
    assert (src.size, src.frame_count, src.fps) == ((40, 30), 3, 5.0)
    got = read_all(src)
    assert [sha(g) for g, _ in got] == [sha(imgs[n]) for n in sorted(imgs)]  # PNG is lossless
    assert [t for _, t in got] == pytest.approx([0.0, 0.2, 0.4])
    only_b = ImageFolderSource(tmp_path, pattern="b_*.png", fps=5.0)
    only_b.open()
    assert [sha(g) for g, _ in read_all(only_b)] == [sha(imgs["b_002.png"])]


def test_image_folder_errors(tmp_path: Path) -> None:
    with pytest.raises(SourceError, match=r"image folder '.*missing' does not exist"):
        ImageFolderSource(tmp_path / "missing").open()
    with pytest.raises(SourceError, match=r"no file matching '\*\.png\|\*\.jpg'"):
        ImageFolderSource(tmp_path).open()
    cv2.imwrite(str(tmp_path / "0.png"), np.zeros((10, 10, 3), np.uint8))
    cv2.imwrite(str(tmp_path / "1.png"), np.zeros((12, 10, 3), np.uint8))
    (tmp_path / "2.png").write_bytes(b"garbage")
    cv2.imwrite(str(tmp_path / "3.png"), np.full((10, 10, 3), 7, np.uint8))
    src = ImageFolderSource(tmp_path, fps=10.0)
    src.open()
    assert src.read()[0]
    # an image of another size and one that does not decode are two bad frames: skipped and counted,
    # and the next good image keeps its place in time
    ok, img, t = src.read()
    assert ok and int(img[0, 0, 0]) == 7 and t == pytest.approx(0.3) and src.undecodable == 2
    assert not src.read()[0]


# ---------------------------------------------------------------------------------- V4L2 devices
def test_missing_v4l2_device_names_it_and_lists_present() -> None:
    present = video_devices()
    dev = next(f"/dev/video{i}" for i in range(90, 200) if f"/dev/video{i}" not in present)
    for spec in (dev, int(dev.removeprefix("/dev/video"))):
        with pytest.raises(SourceError) as err:
            V4L2Source(spec).open()
        msg = str(err.value)
        assert f"'{dev}' does not exist" in msg
        if present:
            assert all(d in msg for d in present)
        else:
            assert "no /dev/video* devices exist on this machine" in msg


def test_read_with_retry_backs_off_then_ends() -> None:
    waits: list[float] = []
    results = iter([(False, None), (False, None), (True, "frame")])
    assert read_with_retry(lambda: next(results), sleep=waits.append) == (True, "frame")
    assert waits == [0.1, 0.2]
    waits.clear()
    calls = []
    assert read_with_retry(lambda: calls.append(1) or (False, None), sleep=waits.append) == (False, None)
    assert waits == [0.1, 0.2, 0.4, 0.8] and len(calls) == 5


# ---------------------------------------------------------------------------------- simulator + URIs
class Checkerboard:
    """A tiny rendered stream with the simulator-stream interface: render(i), n_frames, fps."""

    n_frames = 6
    fps = 12.5

    def render(self, i: int) -> tuple[np.ndarray, float]:
        yy, xx = np.mgrid[0:24, 0:32]
        board = (((xx + i) // 4 + yy // 4) % 2 * 255).astype(np.uint8)
        return np.repeat(board[:, :, None], 3, axis=2), i / self.fps


def test_simulator_adapter_renders_in_order() -> None:
    stream = Checkerboard()
    src = SimulatorSource(stream, uri="sim:checker")
    src.open()
    assert (src.size, src.frame_count, src.fps) == ((32, 24), 6, 12.5)
    got = read_all(src)
    assert [sha(g) for g, _ in got] == [sha(stream.render(i)[0]) for i in range(6)]
    assert [t for _, t in got] == pytest.approx([i / 12.5 for i in range(6)])
    with pytest.raises(SourceError, match="has no 'render'"):
        SimulatorSource(object(), uri="sim:x")


def test_sim_uri_opens_the_simulator_or_says_it_is_missing() -> None:
    sim = importlib.import_module("sim")
    if not callable(getattr(sim, "open_stream", None)):
        with pytest.raises(SourceError, match="simulator is not available yet"):
            make_source("sim:handshake?seed=1")
    else:
        src = make_source("sim:handshake?seed=1", width=160, height=120)
        src.open()
        ok, img, _ = src.read()
        assert ok and img.shape == (120, 160, 3) and img.dtype == np.uint8


def test_parse_uri_schemes(tmp_path: Path) -> None:
    assert parse_uri("clip.avi") == ("file", "clip.avi", {})
    assert parse_uri("/data/x.mp4") == ("file", "/data/x.mp4", {})
    assert parse_uri("file:/data/x.mp4") == ("file", "/data/x.mp4", {})
    assert parse_uri("folder:imgs?pattern=*.jpg") == ("folder", "imgs", {"pattern": "*.jpg"})
    assert parse_uri("/dev/video2") == ("v4l2", "/dev/video2", {})
    assert parse_uri("v4l2:/dev/video0") == ("v4l2", "/dev/video0", {})
    assert parse_uri("sim:handshake?seed=3&people=2") == ("sim", "handshake", {"seed": "3", "people": "2"})
    with pytest.raises(SourceError, match="unknown scheme 'rtsp:'"):
        parse_uri("rtsp://host/stream")
    with pytest.raises(SourceError, match="empty source"):
        parse_uri("  ")
    assert isinstance(make_source(str(tmp_path / "a.avi")), VideoFileSource)
    assert isinstance(make_source(f"folder:{tmp_path}"), ImageFolderSource)
    assert make_source(f"folder:{tmp_path}").fps == 25.0
    assert isinstance(make_source("v4l2:3"), V4L2Source) and make_source("v4l2:3").device == "/dev/video3"


def test_camera_params_are_checked_by_name() -> None:
    with pytest.raises(ParamError, match="parameter 'source'.*unknown scheme"):
        Camera.validate_params({"source": "rtsp://x"})
    with pytest.raises(ParamError, match="parameter 'loop'.*live device"):
        Camera.validate_params({"source": "/dev/video0", "loop": True})
    with pytest.raises(ParamError, match="parameter 'pacing'"):
        Camera.validate_params({"pacing": "slow"})
    with pytest.raises(ParamError, match="parameter 'rate'"):
        Camera.validate_params({"rate": 0})
    assert Camera.validate_params({})["source"] == "sim:handshake"


# ---------------------------------------------------------------------------------- pacing & conversion
def test_frames_start_loop_and_limit(tmp_path: Path) -> None:
    for i in range(5):
        cv2.imwrite(str(tmp_path / f"{i}.png"), np.full((8, 8, 3), i * 10, np.uint8))
    src = ImageFolderSource(tmp_path, fps=10.0)
    src.open()
    values = [int(img[0, 0, 0]) // 10 for img, _ in frames(src, start_frame=2, loop=True, max_frames=8)]
    assert values == [2, 3, 4, 2, 3, 4, 2, 3]
    src.rewind()
    assert [t for _, t in frames(src, start_frame=1, max_frames=2)] == pytest.approx([0.1, 0.2])
    src.rewind()
    assert len(list(frames(src))) == 5
    src.rewind()
    with pytest.raises(ValueError, match="start_frame 7 is past the end"):
        list(frames(src, start_frame=7))


def test_pacer_schedule_and_reanchor() -> None:
    now = [100.0]
    pacer = Pacer("rate", fps=10.0, rate=2.0, clock=lambda: now[0])
    assert pacer.wait(0)  # starts the schedule at 100.0
    assert [pacer.due(k) for k in (1, 2, 10)] == pytest.approx([100.05, 100.1, 100.5])
    now[0] = 105.0  # a 5 s stall: far behind; restart the schedule instead of bursting
    assert pacer.wait(3) and pacer.reanchors == 1
    assert pacer.due(4) == pytest.approx(105.05)
    assert Pacer("realtime", fps=25.0).period == pytest.approx(0.04)
    assert not Pacer("fast").paced and not Pacer("lockstep").paced
    with pytest.raises(ValueError, match="set parameter 'fps'"):
        Pacer("realtime", fps=0.0)
    stopped = Pacer("realtime", fps=0.5, clock=lambda: now[0])
    stopped.wait(0)
    assert not stopped.wait(1, should_stop=lambda: True)  # returns at once instead of waiting 2 s


def test_convert_resize_and_gray() -> None:
    img = np.random.default_rng(2).integers(0, 256, (60, 80, 3), dtype=np.uint8)
    assert output_size((80, 60)) == (80, 60)
    assert output_size((80, 60), width=40) == (40, 30)
    assert output_size((80, 60), height=120) == (160, 120)
    assert output_size((80, 60), 33, 17) == (33, 17)
    assert output_size((1920, 1080), max_side=640) == (640, 360)
    assert output_size((1080, 1920), max_side=640) == (360, 640)  # portrait: the height is the longer side
    assert output_size((80, 60), max_side=80) == (80, 60)  # not over it: kept
    assert output_size((1920, 1080), width=1280, max_side=640) == (1280, 720)  # an asked width wins
    out, enc = convert(img, (40, 30), gray=True)
    assert enc == "mono8" and out.shape == (30, 40) and out.dtype == np.uint8
    assert np.array_equal(
        out, cv2.cvtColor(cv2.resize(img, (40, 30), interpolation=cv2.INTER_AREA), cv2.COLOR_BGR2GRAY)
    )
    same, enc = convert(img, (80, 60))
    assert enc == "bgr8" and same is img
    # a small shrink (less than 2 times) and an enlargement are interpolated, a larger shrink averaged
    for size, interp in (((64, 48), cv2.INTER_LINEAR), ((160, 120), cv2.INTER_LINEAR), ((26, 20), cv2.INTER_AREA)):
        out, _ = convert(img, size)
        assert np.array_equal(out, cv2.resize(img, size, interpolation=interp)), size
        other = cv2.INTER_AREA if interp == cv2.INTER_LINEAR else cv2.INTER_LINEAR
        assert not np.array_equal(out, cv2.resize(img, size, interpolation=other)), size


def test_prefetch_keeps_order_forwards_errors_and_stops() -> None:
    assert list(Prefetch(iter(range(100)), depth=3)) == list(range(100))

    def failing():
        yield 1
        yield 2
        raise SourceError("frame 2 is damaged")

    it = Prefetch(failing(), depth=2)
    assert [next(it), next(it)] == [1, 2]
    with pytest.raises(SourceError, match="frame 2 is damaged"):
        next(it)
    produced = []

    def endless():
        while True:
            produced.append(1)
            yield len(produced)

    it = Prefetch(endless(), depth=2)
    assert next(it) == 1
    it.close()  # returns although the producer never ends; it stopped within depth + 2 items
    assert len(produced) <= 5


def test_replay_progress_says_how_far_of_how_many_and_the_time_left() -> None:
    assert replay_progress(300, 1296, 30.6) == (
        "frame 300 of 1296 (23%) published, 9.8 frames/s, about 1 min 42 s left"
    )
    assert replay_progress(300, None, 30.6) == "frame 300 published, 9.8 frames/s"  # a looping replay
    assert replay_progress(40, 40, 4.0) == "frame 40 of 40 (100%) published, 10.0 frames/s"
    assert replay_progress(0, 40, 0.0) == "frame 0 of 40 (0%) published, 0.0 frames/s"
