"""The whole silhouette algorithm on a synthetic handshake and on real footage (vtest.avi)."""

from __future__ import annotations

import os

import numpy as np
import pytest

from counterpart.body.spline import evaluate_closed_bspline
from counterpart.nodes.silhouette.background import FOREGROUND, SHADOW
from counterpart.nodes.silhouette.pipeline import FrameResult, SilhouetteExtractor, extract_video
from counterpart.sim.flat_scenes import two_person_sequence
from tests.shared_data import VTEST


@pytest.fixture(scope="module")
def handshake():
    return two_person_sequence(n_frames=60, empty_frames=20, seed=1)


def test_synthetic_handshake_two_people_with_outlines_ids_and_no_shadows(handshake):
    seq = handshake
    ex = SilhouetteExtractor(n_ctrl=32, backend_params={"train_frames": 20})
    merged_frames = 0
    for k, frame in enumerate(seq.frames):
        r = ex.process(frame)
        assert isinstance(r, FrameResult) and r.index == k
        # The model trains on frames 0-19 and is ready from the 20th frame on (which it also labels).
        assert r.ready == (k >= 19)
        if k < 20:
            assert r.people == []
            continue
        assert [p.id for p in r.people] == [0, 1], f"frame {k}"
        assert [p.side for p in r.people] == ["left", "right"]
        truth = seq.person_masks[k]
        for p, gt, h in zip(r.people, truth, seq.heights):
            assert p.height == pytest.approx(h, abs=3)  # the shadow on the ground is not in it
            assert p.ctrl.shape == (32, 2)
            ys, xs = np.nonzero(gt)
            top_x = xs[ys == ys.min()].mean()
            assert abs(p.ref_point[1] - ys.min()) <= 1.5 and abs(p.ref_point[0] - top_x) <= 3
            curve = evaluate_closed_bspline(p.ctrl, 4)
            assert np.hypot(*(curve[0] - p.ref_point)) < 2.0
        # Foreground matches the drawn people; the cast shadow is labelled shadow.
        fg = r.labels > 0
        people = truth.any(axis=0)
        assert (fg & people).sum() / people.sum() > 0.97
        assert (fg & ~people).sum() / people.sum() < 0.03
        assert np.mean(r.classes[seq.shadow_masks[k]] == SHADOW) > 0.9
        assert np.mean(r.classes[seq.shadow_masks[k]] == FOREGROUND) < 0.05
        merged_frames += r.people[0].merged
    assert merged_frames >= 15


def test_a_fit_in_the_background_publishes_meanwhile_and_learns_the_same_background(handshake):
    """With ``fit_in_background`` the frame that completes the training returns at once, the
    frames that come while the fit runs have no people, and the fitted model is the one the fit
    in line learns from the same frames; people are found once it is taken up.
    """
    frames = handshake.frames
    inline = SilhouetteExtractor(backend_params={"train_frames": 20})
    inline.fit_background(frames[:20])
    bg = SilhouetteExtractor(backend_params={"train_frames": 20, "fit_in_background": True})
    sub = bg.subtractor
    for f in frames[:20]:
        assert not bg.process(f).ready
    assert sub.fitting and not sub.ready
    r = bg.process(frames[20])  # the fit takes longer than a frame that it leaves alone
    assert not r.ready and r.people == [] and not r.labels.any()
    sub._fitting.result()  # the fit is done: the next frame takes its model up
    for name in ("mean_", "spread_", "a_", "b_", "unseen_"):
        np.testing.assert_array_equal(getattr(sub.model, name), getattr(inline.subtractor.model, name))
    assert sub.model.thresholds_ == inline.subtractor.model.thresholds_
    k = 21
    r = bg.process(frames[k])
    assert r.ready and not sub.fitting
    found = [len(bg.process(f).people) for f in frames[k + 1 : k + 11]]
    assert max(found) == 2


@pytest.mark.parametrize("backend", ["mog2", "knn"])
def test_opencv_backends_run_through_the_extractor(handshake, backend):
    ex = SilhouetteExtractor(backend=backend)
    found = [len(ex.process(f).people) for f in handshake.frames[:35]]
    assert max(found[20:]) == 2


def test_bad_parameters_are_value_errors():
    with pytest.raises(ValueError, match="n_ctrl"):
        SilhouetteExtractor(n_ctrl=3)
    with pytest.raises(ValueError, match="valid names"):
        SilhouetteExtractor(backend="nope")
    with pytest.raises(ValueError, match="horprasert"):
        SilhouetteExtractor(backend="mog2").fit_background(np.zeros((3, 8, 8, 3), np.uint8))


def test_extract_video_rejects_missing_and_undecodable_files(tmp_path):
    with pytest.raises(FileNotFoundError, match="not found"):
        extract_video(tmp_path / "missing.avi", tmp_path / "out.npz")
    bad = tmp_path / "bad.avi"
    bad.write_bytes(b"this is not a video" * 100)
    with pytest.raises(ValueError, match="cannot read video"):
        extract_video(bad, tmp_path / "out.npz")


def test_vtest_several_people_in_later_frames_and_saved_rows(tmp_path):
    if not os.path.isfile(VTEST):
        pytest.skip(f"real footage absent: {VTEST} (see shared/data/README.md)")
    out = tmp_path / "vtest_silhouettes.npz"
    summary = extract_video(VTEST, out, max_frames=100, train_frames=30)
    assert summary["n_frames"] == 100 and summary["frame_size"] == [576, 768]
    d = np.load(out)
    assert d["ctrl"].shape == (summary["n_rows"], 32, 2)
    per_frame = np.bincount(d["frame"], minlength=100)
    # Pedestrians are in view throughout; from frame 60 on there are at least three at once.
    assert per_frame[60:].max() >= 4 and np.median(per_frame[60:]) >= 3
    ok = ~np.isnan(d["ctrl"][:, 0, 0])
    assert ok.mean() > 0.95
    # Outlines lie on their person: control points near the bbox, reference point at its top.
    x, y, w, h = d["bbox"][ok].T
    rp = d["ref_point"][ok]
    assert np.all((rp >= np.stack([x, y], 1) - 0.5) & (rp <= np.stack([x + w, y + h], 1)))
    # ... at the top for nearly all (odd-shaped pieces of split regions can have it lower).
    assert np.mean(rp[:, 1] <= y + 0.25 * h) > 0.95
    # Ids are never reused within a frame.
    for f in range(100):
        ids = d["id"][d["frame"] == f]
        assert len(ids) == len(set(ids.tolist()))
    assert set(d["side"].tolist()) <= {"left", "right"}


def test_vtest_lamp_post_is_learnt_as_the_room_from_the_frames_the_real_time_graph_trains_on():
    """The real-time graph's silhouette node, busy as the graph starts, trained on frames 1, 3, 4
    and 8-24 of vtest.avi at 320 pixels (as measured in one run). On frame 20 (the 15th of them)
    OpenCV's detector took the lamp post and its sign for a person while a walker passed it. Before,
    that box was carried to every training frame as a still person's, and from then on the lamp
    post lay in a person region on every frame. The post (5 x 50 pixels of its pole) may be in a
    walker's region now and then, no more.
    """
    if not os.path.isfile(VTEST):
        pytest.skip(f"real footage absent: {VTEST} (see shared/data/README.md)")
    import cv2

    from counterpart.nodes.camera.pacing import convert
    from counterpart.nodes.silhouette.body_shadow import BodyShadowConfig

    cap = cv2.VideoCapture(str(VTEST))
    frames = [convert(cap.read()[1], (320, 240))[0] for _ in range(120)]
    cap.release()
    ex = SilhouetteExtractor(  # launch/demo.yaml's silhouette node
        min_area=300,
        backend_params={"train_frames": 20, "dynamic": False, "body_shadow": BodyShadowConfig(leg_scale=2)},
    )
    ex.fit_background([frames[k] for k in [1, 3, 4, *range(8, 25)]], robust=True)
    pole = np.array([(ex.process(f).labels[30:80, 175:180] > 0).mean() for f in frames[25:]])
    assert np.mean(pole > 0.5) < 0.1


def test_silhouettes_command_on_a_video_and_an_interrupted_run(handshake, tmp_path):
    import json

    from counterpart.sim.cli import open_writer
    from tests.launching import run_cli

    video = tmp_path / "handshake.avi"
    writer, _ = open_writer(str(video), 25.0, (handshake.frames.shape[2], handshake.frames.shape[1]))
    for frame in handshake.frames:
        writer.write(frame)
    writer.release()
    out = tmp_path / "people.npz"
    # the timeout is a hang guard only: the run takes seconds, but once passed 120 s at load 33;
    # --out without .npz: numpy adds it, and the summary names the file written
    r = run_cli("silhouettes", str(video), "--out", str(tmp_path / "people"), "--train-frames", "20")
    assert r.returncode == 0, r.stderr
    summary = json.loads(r.stdout.strip().splitlines()[-1])
    n = len(handshake.frames)
    assert summary["n_frames"] == n and summary["max_people"] == 2 and summary["out_npz"] == str(out)
    d = np.load(out)
    assert bool(d["complete"]) and int(d["n_frames"]) == n
    per_frame = np.bincount(d["frame"], minlength=n)
    assert (per_frame[:20] == 0).all() and np.mean(per_frame[20:] == 2) > 0.9  # the empty room, then two
    r = run_cli("silhouettes", str(video), "--out", str(out), "--train-frames", "0", timeout=60)
    assert r.returncode == 2 and "--train-frames must be at least 1" in r.stderr
    # an output that cannot be written is said before the work, not after it
    for bad, says in ((tmp_path, "is a folder"), (tmp_path / "no" / "people.npz", "does not exist; make it first")):
        r = run_cli("silhouettes", str(video), "--out", str(bad), timeout=60)
        assert r.returncode == 2 and says in r.stderr and "[silhouettes] frame" not in r.stderr, r.stderr

    def stop_after_30(done: int, declared: int) -> None:
        if done == 30:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        extract_video(video, out, train_frames=20, progress=stop_after_30)
    d = np.load(out)
    assert int(d["n_frames"]) == 30 and not bool(d["complete"]) and d["frame"].max() == 29
