"""The video-texture avatar on a short simulated recording: the graph, its synthesis, the avatar file, the
``counterpart learn avatar`` command on a real video file, and the renderer's compositing.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pytest
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from counterpart.body.camera import default_camera
from counterpart.body.kinematics import forward_kinematics
from counterpart.body.pose import neutral_pose
from counterpart.messages import Partner, decode, encode
from counterpart.nodes.renderer.avatar import AvatarPainter
from counterpart.nodes.responder.avatar_driver import avatar_goals, avatar_partner
from counterpart.nodes.responder.avatar_recording import sim_recording
from counterpart.nodes.responder.listener import ListenerModel
from counterpart.nodes.responder.models import load_model, save_model
from counterpart.nodes.responder.video_texture import STATE_SIGNALS, RecordingError, VideoTexture, fit_recording

SECONDS = 14.0


@pytest.fixture(scope="module")
def recorded(tmp_path_factory) -> tuple:
    """(recording, its labels per video frame, the video file) of a simulated listener."""
    d = tmp_path_factory.mktemp("avatar")
    rec, labels = sim_recording(SECONDS, seed=3, video=d / "person.avi")
    return rec, labels, d / "person.avi"


@pytest.fixture(scope="module")
def texture(recorded) -> VideoTexture:
    return fit_recording(recorded[0], required=("nod",))


def edges(m: VideoTexture) -> csr_matrix:
    T = len(m.alive_)
    return csr_matrix((np.ones(len(m.indices_)), (m.e_src_, m.indices_)), shape=(T, T))


def test_the_graph_is_one_strongly_connected_component_without_dead_ends(texture: VideoTexture) -> None:
    m = texture
    G = edges(m)
    assert m.alive_.sum() > 0.7 * np.isfinite(m.x_[:, 0]).sum()  # of the frames with the person
    # no edge leaves the graph and every frame of it reaches every other one (and so every goal)
    assert m.alive_[m.e_src_].all() and m.alive_[m.indices_].all()
    n, comp = connected_components(G, directed=True, connection="strong")
    assert len(np.unique(comp[m.alive_])) == 1
    assert np.isfinite(m.dist_[:, m.alive_]).all()
    assert "nod" in m.goals_ and any(g.startswith("state:") for g in m.goals_)
    # every frame plays on to the next one or jumps; jumps exist (else it is a loop of the recording)
    assert (np.diff(m.indptr_)[m.alive_] >= 1).all()
    assert (m.indices_ != m.e_src_ + 1).sum() > 100


def test_cut_points_share_their_medoids_social_state(texture: VideoTexture) -> None:
    m = texture
    cols = [m.names_.index(s) for s in STATE_SIGNALS if s in m.names_]
    state = m.labels_[:, cols] == 1
    sizes = [len(c) for c in m.members_]
    assert sum(s >= 2 for s in sizes) >= len(sizes) // 2
    for med, members in zip(m.medoids_, m.members_):
        assert (state[members] == state[med]).all()
    # a cut point may be in more than one cluster
    counts = np.bincount(np.concatenate(m.members_), minlength=len(m.alive_))
    assert (counts >= 2).any()
    # and the jumps join frames of one cluster: the frame shown after the cut follows a member
    jump = m.indices_ != m.e_src_ + 1
    member_sets = [set(c.tolist()) for c in m.members_]
    for i, s in list(zip(m.e_src_[jump], m.indices_[jump]))[::97]:
        assert any(i in c and s - 1 in c for c in member_sets)


def test_a_requested_nod_comes_along_a_shortest_way_of_the_graph(texture: VideoTexture) -> None:
    m = texture
    nod = m.names_.index("nod")
    d = m.dist_[m.goal_index("nod")]
    start = int(np.flatnonzero(m.alive_ & (d >= 10))[0])
    m.reset(start)
    for k in range(1, 200):  # noqa: B007 (k is the step the request took effect at)
        f, _ = m.step({"nod": 1.0})
        if m.labels_[f[0], nod] == 1:
            break
    assert k == d[start]
    # without the request it would have taken the recording's own way
    m.reset(start)
    natural = next(k for k in range(1, 2000) if m.labels_[m.step({})[0][0], nod] == 1)
    assert natural >= k


def test_cuts_cross_fade_and_playback_runs_on(texture: VideoTexture) -> None:
    m = texture
    m.reset()
    prev, fades = m.current, []
    for _ in range(1500):
        f, w = m.step({"nod": 1.0} if len(fades) % 2 else {})
        assert abs(float(w.sum()) - 1.0) < 1e-6 and m.alive_[f[0]]
        if f[0] != prev + 1:  # a cut: the frame that would have come fades out
            assert len(f) == 2 and f[1] == prev + 1 and w[0] < 1
            fades.append([])
        elif len(f) == 2:
            fades[-1].append(float(w[1]))
        prev = int(f[0])
    assert len(fades) >= 3
    assert all(all(a > b for a, b in zip(fade, fade[1:])) for fade in fades)  # the old frames fade out


def test_the_avatar_file_round_trips_with_its_frames(texture: VideoTexture, recorded, tmp_path: Path) -> None:
    rec = recorded[0]
    path = save_model(tmp_path / "avatar.npz", texture)
    m = load_model(path, expected="video-texture")
    assert m.goals_ == texture.goals_ and np.array_equal(m.indices_, texture.indices_)
    m.reset(), texture.reset()
    assert all(np.array_equal(m.step({})[0], texture.step({})[0]) for _ in range(300))
    t = int(np.flatnonzero(rec.valid)[40])
    assert np.array_equal(m.frames.mask(t), rec.masks[t])
    inside = rec.masks[t]
    err = np.abs(m.frames.image(t).astype(int) - rec.crops[t].astype(int))[inside].mean()
    assert err < 6  # JPEG at quality 90
    assert m.frames.geometry.facing == -1.0 and 0.6 * rec.crops.shape[1] < m.frames.geometry.height_px


def test_too_short_a_recording_and_a_signal_that_never_occurs_say_what_is_missing(recorded) -> None:
    rec = recorded[0]
    from counterpart.nodes.responder.video_texture import appearance_features

    feats = appearance_features(rec.crops, rec.masks)
    short = np.zeros(len(feats), bool)
    short[:100] = rec.valid[:100]
    with pytest.raises(RecordingError, match=r"at least 8 s.*record for longer"):
        VideoTexture().fit(feats, rec.labels, rec.names, rec.fps, valid=short)
    never = [n for k, n in enumerate(rec.names) if not (rec.labels[rec.valid, k] == 1).any()]
    assert never, "the simulated listener should lack some signal"
    with pytest.raises(RecordingError, match=rf"signal '{never[0]}' never occurs.*record the person doing it"):
        VideoTexture().fit(feats, rec.labels, rec.names, rec.fps, valid=rec.valid, required=("nod", never[0]))
    with pytest.raises(RecordingError, match=r"'laughing' is not among the labels"):
        VideoTexture().fit(feats, rec.labels, rec.names, rec.fps, valid=rec.valid, required=("laughing",))


@pytest.mark.slow  # the masks are cut out in two worker processes
def test_learn_avatar_from_a_video_file(recorded, tmp_path: Path, capsys) -> None:
    from counterpart.apps import learn_avatar as cli_avatar

    rec, labels, video = recorded
    lab = tmp_path / "labels.npz"
    np.savez(lab, signals_a=np.full_like(labels, -1), signals_b=labels, signal_names=np.array(rec.names), fps=25.0)
    ap = argparse.ArgumentParser()
    cli_avatar.add_arguments(ap)
    out = tmp_path / "me.npz"
    code = cli_avatar.main(
        ap.parse_args(["--video", str(video), "--labels", str(lab), "--person", "b", "--out", str(out)])
    )
    cap = capsys.readouterr()
    assert code == 0, cap.err
    summary = json.loads(cap.out.strip().splitlines()[-1])
    assert summary["frames"] == len(labels) and summary["frames_in_graph"] > 0.7 * len(labels)
    assert "cutting the masks out in 2 processes" in cap.err and "Tarjan" in cap.err  # progress shown
    m = load_model(out, expected="video-texture")
    # the masks the silhouette algorithm cut out of the video agree with the simulator's
    t = int(np.flatnonzero(rec.valid & m.alive_)[50])
    assert m.frames.geometry.h == pytest.approx(rec.masks.shape[1], abs=6)
    a, b = m.frames.mask(t), rec.masks[t]
    assert abs(int(a.sum()) - int(b.sum())) < 0.2 * b.sum()
    # a label that never occurs is named
    code = cli_avatar.main(
        ap.parse_args(
            [
                "--video",
                str(video),
                "--labels",
                str(lab),
                "--person",
                "b",
                "--signals",
                "nod,activity",
                "--out",
                str(tmp_path / "x.npz"),
            ]
        )
    )
    assert code == 2 and "signal 'activity' never occurs" in capsys.readouterr().err
    # a missing person in the label file
    code = cli_avatar.main(
        ap.parse_args(["--video", str(video), "--labels", str(lab), "--person", "c", "--out", str(tmp_path / "y.npz")])
    )
    assert code == 2 and "no person 'c' (it has a, b); choose one with --person" in capsys.readouterr().err


def test_the_driver_nods_when_the_rules_say_a_listener_nods(texture: VideoTexture) -> None:
    m = texture
    lm = ListenerModel(offset_s=0.2, response_s=1.5).fit({"interested": [(("S:nod",), ("L:nod",), 1.0)]})
    m.reset()
    nod = m.names_.index("nod")
    shown = []
    for t in range(100):
        f = avatar_partner(m, lm, {"nod": t >= 40}, None, "person", 3, "avatar.npz")
        shown.append(m.labels_[f["avatar_frames"][0], nod] == 1)
        assert f["joints"].shape == (14, 3) and f["avatar_file"] == "avatar.npz"
    # the rule fires at 40, the response starts 5 frames later and the avatar nods within a second
    assert any(shown[45 : 45 + 25])
    # the goals: the nod firmly, the listening state softly
    goals = avatar_goals(m, {"nod"}, "person", 3)
    assert goals["nod"] == 1.0 and any(k.startswith("state:") and v < 1 for k, v in goals.items())


def test_the_renderer_composites_the_avatar_where_the_partner_stands(texture: VideoTexture, tmp_path: Path) -> None:
    path = save_model(tmp_path / "avatar.npz", texture)
    cam = default_camera(320, 240)

    def partner(x: float, yaw: float, frames=(100,), weights=(1.0,)) -> Partner:
        joints = forward_kinematics(neutral_pose(x=x, z=0.0, yaw=yaw))[0]
        msg = Partner(
            model="video-texture",
            joints=joints.astype(np.float32),
            avatar_file=str(path),
            avatar_frames=np.array(frames, np.int32),
            avatar_weights=np.array(weights, np.float32),
        )
        back = decode(encode(msg))  # as it travels on the bus
        assert np.array_equal(back.avatar_frames, msg.avatar_frames) and back.avatar_file == msg.avatar_file
        return back

    painter = AvatarPainter()
    bg = np.full((240, 320, 3), 255, np.uint8)
    msg = partner(0.5, -np.pi / 2)
    img = bg.copy()
    assert painter.draw(img, msg, cam) is True
    ys, xs = np.nonzero((img != 255).any(axis=2))
    feet = cam.project(np.array([[0.5, 0.0, 0.0]]))[0]
    top = cam.project(np.array([[0.5, float(msg.joints[0, 1]) + 0.12, 0.0]]))[0]
    assert abs(ys.max() - feet[1]) <= 4 and abs(ys.min() - top[1]) <= 0.12 * (feet[1] - top[1])
    assert abs(np.median(xs) - feet[0]) <= 8
    # facing the other way: the same frame mirrored about the foot point
    other = bg.copy()
    assert painter.draw(other, partner(0.5, np.pi / 2), cam) is True
    ys2, xs2 = np.nonzero((other != 255).any(axis=2))
    assert ys2.max() == ys.max() and abs((xs2.mean() - feet[0]) + (xs.mean() - feet[0])) <= 2.5
    # a cross-fade blends two frames: inside both silhouettes the colour is the mean of the two
    a, b = bg.copy(), bg.copy()
    painter.draw(a, partner(0.5, -np.pi / 2, (100,)), cam)
    painter.draw(b, partner(0.5, -np.pi / 2, (160,)), cam)
    mix = bg.copy()
    painter.draw(mix, partner(0.5, -np.pi / 2, (100, 160), (0.5, 0.5)), cam)
    both = (a != 255).all(axis=2) & (b != 255).all(axis=2)
    both[1:-1, 1:-1] &= both[:-2, 1:-1] & both[2:, 1:-1] & both[1:-1, :-2] & both[1:-1, 2:]  # away from edges
    expect = (a.astype(int) + b.astype(int)) / 2
    assert both.sum() > 200 and np.abs(mix[both] - expect[both]).mean() < 3
    # a missing file: nothing drawn, the caller falls back
    assert (
        painter.draw(
            bg.copy(),
            Partner(
                model="video-texture",
                joints=msg.joints,
                avatar_file=str(tmp_path / "none.npz"),
                avatar_frames=np.array([1], np.int32),
            ),
            cam,
        )
        is None
    )


def test_the_compositor_draws_the_avatar_in_auto_style_and_cones_when_asked(
    texture: VideoTexture, tmp_path: Path
) -> None:
    from counterpart.messages import Frame
    from counterpart.nodes.renderer.compositor import Bundle, Compositor

    path = save_model(tmp_path / "avatar.npz", texture)
    joints = forward_kinematics(neutral_pose(x=0.5, z=0.0, yaw=-np.pi / 2))[0].astype(np.float32)
    msg = Partner(
        model="video-texture",
        joints=joints,
        avatar_file=str(path),
        avatar_frames=np.array([120], np.int32),
        avatar_weights=np.ones(1, np.float32),
    )
    frame = Frame(image=np.full((240, 320, 3), 255, np.uint8))
    off = {k: False for k in ("skeleton", "splines", "signals", "stats", "controls")}
    avatar = Compositor(overlays=dict(off)).render(Bundle(frame=frame, partner=msg))
    cones = Compositor(style="cones", overlays=dict(off)).render(Bundle(frame=frame, partner=msg))
    painted = np.full((240, 320, 3), 255, np.uint8)
    AvatarPainter().draw(painted, msg, default_camera(320, 240))
    assert np.array_equal(avatar, painted)  # auto: the avatar's frames
    assert not np.array_equal(cones, painted) and (cones != 255).any()
