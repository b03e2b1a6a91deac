"""Renderer building blocks on real pixels: cones, silhouettes, overlays, pairing, video, controls."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import replace

import cv2
import numpy as np
import pytest

from counterpart.body.camera import Camera, camera_for_size, default_camera
from counterpart.body.raster import rasterise_cones
from counterpart.bus import SeqHistory
from counterpart.messages import (
    Control,
    Frame,
    NodeStats,
    Partner,
    PersonShape,
    PersonSignals,
    Pose3D,
    Silhouettes,
    SocialSignals,
    TopicStats,
    TrackedBody,
)
from counterpart.nodes.renderer import draw
from counterpart.nodes.renderer.compositor import Bundle, Compositor
from counterpart.nodes.renderer.controls import parse_control
from counterpart.nodes.renderer.video import VideoWriter, choose_codec, count_frames, raw_mjpeg_works
from tests.camera_sink import cv2_frames
from tests.renderer_nodes import partner_joints, scene_frame

CAM = default_camera(320, 240)
BG = 70


def blank(h: int = 240, w: int = 320) -> np.ndarray:
    return np.full((h, w, 3), BG, np.uint8)


def changed(img: np.ndarray) -> np.ndarray:
    return (img != BG).any(-1)


def cylinder(x: float, z: float, r: float = 0.15, y0: float = 0.3, y1: float = 1.5) -> tuple[np.ndarray, np.ndarray]:
    return np.array([[[x, y0, z], [x, y1, z]]], float), np.array([[r, r]])


# ------------------------------------------------------------------------------------------ cones
def test_partner_cones_of_a_held_partner_are_the_same_and_not_shared() -> None:
    joints = partner_joints(3)
    ends, radii = draw.partner_cones(joints)
    ends[:] = 0.0  # a caller's changes must not reach the next frame's cones
    again, radii_again = draw.partner_cones(joints.copy())
    assert np.abs(again).max() > 0.5 and np.array_equal(radii, radii_again)
    other, _ = draw.partner_cones(partner_joints(20))
    assert not np.allclose(other, again)  # another pose, other cones


def test_a_held_partner_is_painted_the_same_and_a_new_camera_or_colour_repaints_it() -> None:
    """The facets of the partners last drawn are kept: drawing a held partner again paints the
    same pixels as drawing it the first time (as :func:`draw.draw_cones` does), on any image;
    another camera or colour is drawn as itself, not as the kept one.
    """
    joints = partner_joints(5)
    ends, radii = draw.partner_cones(joints)
    first = draw.draw_partner_3d(blank(), joints, CAM, (0, 200, 255))
    assert np.array_equal(first, draw.draw_cones(blank(), ends, radii, CAM, (0, 200, 255)))
    assert np.array_equal(draw.draw_partner_3d(blank(), joints.copy(), CAM, (0, 200, 255)), first)
    bg = np.random.default_rng(0).integers(0, 255, (240, 320, 3), dtype=np.uint8)
    assert np.array_equal(
        draw.draw_partner_3d(bg.copy(), joints, CAM, (0, 200, 255)),
        draw.draw_cones(bg.copy(), ends, radii, CAM, (0, 200, 255)),
    )
    moved = replace(CAM, t=CAM.t + np.array([0.3, 0.0, 0.0]))
    want = draw.draw_cones(blank(), ends, radii, moved, (0, 200, 255))
    assert not np.array_equal(want, first)
    assert np.array_equal(draw.draw_partner_3d(blank(), joints, moved, (0, 200, 255)), want)
    blue = draw.draw_partner_3d(blank(), joints, CAM, (255, 0, 0))
    assert np.array_equal(blue, draw.draw_cones(blank(), ends, radii, CAM, (255, 0, 0)))
    with pytest.raises(TypeError):
        draw.draw_partner_3d(blank(), joints, CAM, (255, 0, 0), shade=0.5)


def test_partner_pixels_cover_the_projected_cones_and_nothing_far_away() -> None:
    joints = partner_joints(0)
    ends, radii = draw.partner_cones(joints)
    img = draw.draw_partner_3d(blank(), joints, CAM, (0, 200, 255))
    got = changed(img)
    ref = rasterise_cones(ends[None], radii, CAM)[0].astype(np.uint8)
    inner = cv2.erode(ref, np.ones((3, 3), np.uint8)).astype(bool)
    near = cv2.dilate(ref, np.ones((5, 5), np.uint8)).astype(bool)
    assert ref.sum() > 1500  # the partner is a sizeable figure in view
    assert got[inner].mean() > 0.97  # every cone interior is painted
    assert not got[~near].any()  # nothing painted away from the cones
    # the partner stands right of centre (x = +0.6 m): the left half of the image is untouched
    assert not got[:, :130].any()


def test_draw_cones_painter_order_on_real_pixels() -> None:
    near_e, r = cylinder(0.0, 0.8, r=0.12)
    far_e, _ = cylinder(0.0, -0.8, r=0.3, y0=-1.0, y1=2.5)  # wider and taller: behind all of the near one
    far_only = draw.draw_cones(blank(), far_e, r * 2.5, CAM, (0, 0, 255))
    both_a = draw.draw_cones(draw.draw_cones(blank(), far_e, r * 2.5, CAM, (0, 0, 255)), near_e, r, CAM, (255, 0, 0))
    near_mask = changed(draw.draw_cones(blank(), near_e, r, CAM, (255, 0, 0)))
    core = cv2.erode(near_mask.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)
    assert core.sum() > 200 and changed(far_only)[core].all()  # the far cone is behind the near one there
    # one call with both cones, in either order: the near one is on top over its whole core
    for order in ((0, 1), (1, 0)):
        ends = np.concatenate([(near_e, far_e)[i] for i in order])
        radii = np.concatenate([(r, r * 2.5)[i] for i in order])
        polys, _, depth = draw.cone_facets(ends, radii, CAM)
        assert len(polys) == len(depth) and np.all(np.diff(depth) <= 1e-9)  # far to near
        both = draw.draw_cones(blank(), ends, radii, CAM, (255, 0, 0))
        assert np.array_equal(both[core], both_a[core])


def test_shading_follows_the_light() -> None:
    e, r = cylinder(0.0, 0.0, r=0.3)
    light_from_left = np.array([-1.0, 0.0, 0.3])  # world -X is image left for this camera
    img = draw.draw_cones(blank(), e, r, CAM, (200, 200, 200), light=light_from_left)
    mask = changed(img)
    cols = np.flatnonzero(mask.any(0))
    mid_row = int(np.round(CAM.project(np.array([0.0, 0.9, 0.0]))[1]))
    left = img[mid_row, cols[0] + 3 : cols[0] + 8, 0].mean()
    right = img[mid_row, cols[-1] - 7 : cols[-1] - 2, 0].mean()
    assert left > right + 60


def test_cones_behind_the_camera_are_skipped() -> None:
    e = np.array([[[0.0, 1.6, 4.5], [0.0, 1.6, 5.5]]])  # behind the camera at z = 4
    img = draw.draw_cones(blank(), e, np.array([[0.2, 0.2]]), CAM)
    assert not changed(img).any()


# -------------------------------------------------------------------------------------- silhouette
def ellipse_ctrl(cx: float = 100, cy: float = 120, ax: float = 40, ay: float = 70, n: int = 32) -> np.ndarray:
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.stack([cx + ax * np.cos(a), cy + ay * np.sin(a)], 1)


def test_silhouette_fill_covers_the_curve_interior() -> None:
    ctrl = ellipse_ctrl()
    img = draw.draw_silhouette(blank(), ctrl, (0, 255, 0), outline=(0, 0, 0))
    fill_only = draw.draw_silhouette(blank(), ctrl, (0, 255, 0), outline=None)
    curve = draw.closed_bspline(ctrl, 16).astype(np.float32)
    inside = np.zeros((240, 320), np.uint8)
    cv2.fillPoly(inside, [np.round(curve).astype(np.int32)], 1)
    interior = cv2.erode(inside, np.ones((5, 5), np.uint8)).astype(bool)
    outside = ~cv2.dilate(inside, np.ones((5, 5), np.uint8)).astype(bool)
    assert (img[interior] == (0, 255, 0)).all()
    assert (img[outside] == BG).all()
    coverage = (fill_only[..., 1].astype(float) - BG) / (255 - BG)  # anti-aliased edges count partly
    assert coverage.sum() == pytest.approx(cv2.contourArea(curve), rel=0.02)
    assert (changed(img) & ~changed(fill_only)).sum() > 100  # the outline rims the fill


# ----------------------------------------------------------------------------------------- overlays
def test_skeleton_marks_each_projected_joint() -> None:
    joints = partner_joints(0)
    img = draw.draw_skeleton(blank(), joints, CAM, (0, 255, 0))
    uv = np.round(CAM.project(joints.astype(float))).astype(int)
    assert all((img[v, u] != BG).any() for u, v in uv)
    far = np.ones((240, 320), bool)
    x0, y0 = uv.min(0) - 6
    x1, y1 = uv.max(0) + 6
    far[max(y0, 0) : y1, max(x0, 0) : x1] = False
    assert not changed(img)[far].any()
    with pytest.raises(ValueError, match=r"\(14, 3\)"):
        draw.draw_skeleton(blank(), joints[:5], CAM)


def test_spline_outline_and_badges() -> None:
    img = draw.draw_spline_outline(blank(), ellipse_ctrl(), (0, 255, 0), ref_point=np.array([100, 50.0]), label="1")
    assert changed(img)[120, 58:64].any() and not changed(img)[120, 80:120].any()  # outline only, hollow
    img = draw.draw_signal_badges(blank(), (10, 10), ["nod", "shake", "gaze_at_other"], np.array([1, 0, -1]))
    row = img[14]  # through the boxes
    assert ((row == (0, 200, 255)).all(-1)).any()  # a present signal: bright badge
    assert ((row == draw.UNKNOWN_GREY).all(-1)).any()  # unknown: grey
    assert ((row == (60, 60, 60)).all(-1)).any()  # absent: dark
    with pytest.raises(ValueError, match="names but"):
        draw.draw_signal_badges(blank(), (0, 0), ["nod"], np.array([1, 0]))


def test_badges_of_people_standing_close_are_drawn_apart() -> None:
    names = ["nod", "shake", "gaze_at_other", "activity", "talking", "laughing"]
    img = np.zeros((240, 160, 3), np.uint8)
    anchors = [(40.0, 20.0), (52.0, 24.0), (45.0, 220.0)]  # two heads side by side, one low down
    rects = [draw.signal_badges_rect(img, a, names) for a in anchors]
    assert rects[0][1] < rects[1][3] and rects[1][1] < rects[0][3]  # as anchored they overlap
    shifts = draw.place_apart(rects, img.shape[0])
    moved = [(x0, y0 + d, x1, y1 + d) for (x0, y0, x1, y1), d in zip(rects, shifts)]
    for i in range(3):
        for j in range(i):
            a, b = moved[i], moved[j]
            assert not (a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]), (moved, i, j)
    assert shifts[0] == 0 and shifts[1] > 0 and all(r[3] <= img.shape[0] for r in moved)
    # what is drawn stays inside the rectangle the layout was given
    for (x, y), d in zip(anchors, shifts):
        one = draw.draw_signal_badges(np.zeros_like(img), (x, y + d), names, np.ones(len(names)))
        ys, xs = np.nonzero(one.any(-1))
        r = draw.signal_badges_rect(img, (x, y + d), names)
        assert r[0] <= xs.min() and xs.max() <= r[2] and r[1] <= ys.min() and ys.max() <= r[3]


def test_stats_text_and_control_bar() -> None:
    st = NodeStats(
        node="camera",
        outputs=[TopicStats(topic="frame", port="frame", rate_hz=25.0)],
        inputs=[TopicStats(topic="x", drops=3, latency_ms=4.5)],
        proc_ms_mean=1.25,
    )
    assert draw.stats_lines({"camera": st}) == ["camera       25.0Hz drop 3   lat  4.5ms proc  1.2ms"]
    (w, _), _ = cv2.getTextSize(
        draw.stats_lines({"camera": st})[0], cv2.FONT_HERSHEY_SIMPLEX, draw.text_scale(blank(), 0.3), 1
    )
    assert w < 310  # fits a 320-pixel frame
    assert changed(draw.draw_stats(blank(), {"camera": st}))[:20, :100].any()
    widths = []
    for s in (0.25, 0.75):
        img = draw.draw_controls(blank(), {"emotion": "happy", "strength": s})
        bar = img[-6]
        widths.append(int((bar == draw.partner_colour("happy", 1.0)).all(-1).sum()))
    assert widths[1] == pytest.approx(3 * widths[0], rel=0.05)


def test_partner_colour_blends_by_strength() -> None:
    assert draw.partner_colour("happy", 0.0) == draw.EMOTION_COLOURS["neutral"]
    assert draw.partner_colour("angry", 1.0) == draw.EMOTION_COLOURS["angry"]
    assert draw.partner_colour("angry", 7.0) == draw.EMOTION_COLOURS["angry"]
    # every strength gives the blend, rounded half to even (np.float32 and bad values included)
    base = np.array(draw.EMOTION_COLOURS["neutral"], float)
    for emotion in (*draw.EMOTION_COLOURS, "bored"):
        target = np.array(draw.EMOTION_COLOURS.get(emotion, draw.EMOTION_COLOURS["neutral"]), float)
        for s in [*np.linspace(-0.5, 1.5, 81), np.float32(0.3), float("nan"), float("inf"), -float("inf")]:
            w = float(np.clip(s if np.isfinite(s) else 0.0, 0.0, 1.0))
            assert draw.partner_colour(emotion, s) == tuple(int(np.rint(c)) for c in base + w * (target - base))


def test_contact_sheet_tiles_in_rows() -> None:
    frames = [np.full((20, 30, 3), 40 * i, np.uint8) for i in range(5)]
    sheet = draw.contact_sheet(frames, cols=3, pad=2)
    assert sheet.shape == (42, 94, 3)
    assert (sheet[21 + 5, 32 + 5] == 160).all()  # frame 4: row 1, column 1
    assert (sheet[20, 0] == 0).all()  # padding
    with pytest.raises(ValueError, match="no frames"):
        draw.contact_sheet([])


# --------------------------------------------------------------------------------------- compositor
def _frame(seq: int) -> Frame:
    return Frame(seq=seq, image=scene_frame(seq, 160, 120))


def _partner(seq: int, strength: float = 0.0) -> Partner:
    return Partner(seq=seq, joints=partner_joints(seq), emotion="happy", strength=strength)


def test_pairing_waits_for_partner_or_newer_seq_or_timeout() -> None:
    comp = Compositor(CAM, timeout=0.5)
    for s in range(5):
        comp.add_frame(_frame(s), now=0.0)
    comp.add_partner(_partner(0))
    comp.add_partner(_partner(1))
    got = comp.ready(now=0.1)
    assert [b.frame.seq for b in got] == [0, 1] and all(b.partner_exact for b in got)
    comp.add_partner(_partner(3))  # partner 2 will not come
    got = comp.ready(now=0.1)
    assert [(b.frame.seq, b.partner.seq, b.partner_exact) for b in got] == [(2, 1, False), (3, 3, True)]
    assert comp.ready(now=0.2) == []  # frame 4 still waits
    assert comp.next_deadline() == 0.5  # its arrival plus the timeout: the node's timer wakes then
    assert [b.frame.seq for b in comp.ready(now=0.6)] == [4]
    assert comp.next_deadline() is None  # nothing waits
    assert comp.counts == {
        "rendered": 0,
        "partner_exact": 3,
        "partner_held": 2,
        "partner_missing": 0,
        "forced": 0,
        "partner_drawn": 0,
    }


def test_frames_that_wait_long_for_their_partners_keep_their_own_overlays_and_what_they_pass_goes() -> None:
    # lockstep: the silhouettes and poses of 100 frames come before the first partner (a responder
    # holding its poses until their camera is decided); every frame still gets its own overlays
    comp = Compositor(CAM, timeout=100.0)
    for s in range(100):
        comp.add_frame(_frame(s), now=0.0)
        comp.add_side("silhouettes", Silhouettes(seq=s))
        if s % 10:  # and a pose on most frames: the others show the newest before them
            comp.add_side("pose", Pose3D(seq=s))
    got = []
    for s in range(100):
        comp.add_partner(_partner(s), now=1.0)
        got += comp.ready(now=1.0)
    # frame 0 has no pose at or before it
    assert [(b.frame.seq, b.silhouettes.seq, b.pose.seq if b.pose else None) for b in got] == [
        (s, s, s if s % 10 else s - 1 if s else None) for s in range(100)
    ]
    assert len(comp.side["silhouettes"].items) == 1 and len(comp.side["pose"].items) == 1


def test_adaptive_wait_renders_at_once_while_partners_are_late_and_waits_again_when_they_keep_up() -> None:
    comp = Compositor(CAM, timeout=0.1, adaptive=True, delay_window=5)
    # partners on time (20 ms after their frame): each frame waits for its own
    for s in range(5):
        comp.add_frame(_frame(s), now=s * 0.04)
        assert comp.ready(now=s * 0.04) == []
        comp.add_partner(_partner(s), now=s * 0.04 + 0.02)
        assert [(b.frame.seq, b.partner_exact) for b in comp.ready(now=s * 0.04 + 0.02)] == [(s, True)]
    assert not comp.partners_late
    # a slow node: a partner for every third frame only, 0.3 s late
    rendered = []
    for s in range(5, 35):
        t = 0.2 + (s - 5) * 0.04
        comp.add_frame(_frame(s), now=t)
        if s % 3 == 0 and s >= 8:
            comp.add_partner(_partner(s - 7), now=t)  # the partner of the frame 0.28 s ago
        rendered += [(b.frame.seq, t) for b in comp.ready(now=t)]
    assert comp.partners_late
    late = [(seq, 0.2 + (seq - 5) * 0.04) for seq in range(20, 35)]
    assert [r for r in rendered if r[0] >= 20] == late  # rendered on arrival, no wait
    assert comp.counts["partner_held"] > 20
    # the node keeps up again: after a few partners on time the frames wait for their own again
    t = 0.2 + 30 * 0.04
    for s in range(35, 45):
        comp.add_frame(_frame(s), now=t)
        comp.ready(now=t)
        comp.add_partner(_partner(s), now=t + 0.01)
        comp.ready(now=t + 0.01)
        t += 0.04
    assert not comp.partners_late
    comp.add_frame(_frame(45), now=t)
    assert comp.ready(now=t + 0.05) == []  # waits (within the timeout) for partner 45
    comp.add_partner(_partner(45), now=t + 0.06)
    assert [(b.frame.seq, b.partner_exact) for b in comp.ready(now=t + 0.06)] == [(45, True)]


def test_without_adaptive_wait_every_frame_waits_for_the_timeout() -> None:
    comp = Compositor(CAM, timeout=0.1, adaptive=False, delay_window=5)
    for s in range(20):
        comp.add_frame(_frame(s), now=s * 0.04)
    comp.add_partner(_partner(0), now=0.5)  # very late; frames 1.. never get theirs
    assert comp.partners_late  # measured, but not acted on
    assert [b.frame.seq for b in comp.ready(now=0.51)] == list(range(0, 11))  # 0 paired, 1..10 past the timeout
    assert comp.ready(now=0.52) == []


def _at_or_before(kept: dict, q: int) -> object:
    older = [s for s in kept if s <= q]
    return kept[max(older)] if older else None


def test_overlay_history_finds_the_newest_older_message_as_a_scan_of_what_it_keeps() -> None:
    """The overlays' lookup (exact seq, else the highest seq below it) bisects a sorted list of
    the seqs kept; in any order of arrival, repeats and a restart from 0 included, it finds what
    a scan of the kept messages finds.
    """
    rng = np.random.default_rng(3)
    hist = SeqHistory(8)
    arrivals = [*range(20), *rng.integers(0, 40, 30).tolist(), *range(5)]  # a restart at the end
    for k, seq in enumerate(arrivals):
        hist.add(Pose3D(seq=seq, stamp=k))
        assert sorted(hist.items) == hist.seqs and len(hist.seqs) <= 8
        for q in range(-1, 45):
            assert hist.at_or_before(q) is _at_or_before(hist.items, q)
    kept = dict(hist.items)
    for q in (-1, 2, 3, max(kept) - 1, 50):
        # a consumer past frame q forgets what no lookup from q on can return, and only that
        hist = SeqHistory(8)
        for msg in kept.values():
            hist.add(msg)
        hist.forget_before(q)
        newest = max([s for s in kept if s <= q], default=min(kept))
        assert hist.items == {s: m for s, m in kept.items() if s >= newest} and hist.seqs == sorted(hist.items)
        assert all(hist.at_or_before(r) is _at_or_before(kept, r) for r in range(q, 45))


def test_pairing_without_partner_and_max_pending() -> None:
    comp = Compositor(CAM, want_partner=False)
    comp.add_frame(_frame(0))
    assert [b.partner for b in comp.ready()] == [None]
    comp = Compositor(CAM, timeout=100.0, max_pending=3)
    for s in range(5):
        comp.add_frame(_frame(s), now=0.0)
    assert [b.frame.seq for b in comp.ready(now=0.0)] == [0, 1]
    assert comp.counts["forced"] == 2 and comp.counts["partner_missing"] == 2
    assert [b.frame.seq for b in comp.ready(now=0.0, flush=True)] == [2, 3, 4]


def test_render_draws_partner_at_the_scaled_camera_and_follows_strength() -> None:
    comp = Compositor(CAM, overlays={"controls": False, "stats": False})
    comp.add_frame(_frame(0))
    comp.add_partner(_partner(0, strength=0.0))
    img0 = comp.render(comp.ready()[0])
    mask = (img0 != scene_frame(0, 160, 120)).any(-1)
    small = camera_for_size(CAM, 160, 120)
    ref = changed(draw.draw_partner_3d(blank(120, 160), partner_joints(0), small))
    assert (mask == ref).mean() > 0.99  # drawn with the calibration scaled to the 160x120 frame
    comp.add_frame(_frame(1))
    comp.add_partner(_partner(1, strength=1.0))
    img1 = comp.render(comp.ready()[0])
    both = mask & (img1 != scene_frame(1, 160, 120)).any(-1)
    b0, r0 = img0[both][:, 0].mean(), img0[both][:, 2].mean()
    b1, r1 = img1[both][:, 0].mean(), img1[both][:, 2].mean()
    assert b0 > r0 and r1 > b1 + 50  # neutral blue-grey turned happy orange


def test_frames_wait_until_the_graphs_camera_is_decided_for_them_and_are_drawn_with_it() -> None:
    comp = Compositor(None, wait_camera=True, overlays={"controls": False, "stats": False})
    for s in range(5):
        comp.add_frame(_frame(s), now=0.0)
        comp.add_partner(_partner(s))
    assert comp.ready(now=0.0) == []  # no camera yet
    low = camera_for_size(CAM, 160, 120)
    high = Camera.look_at((1.0, 3.0, 3.5), (0.0, 0.9, 0.0), 55.0, 160, 120)
    comp.set_camera(low, 0, undecided_from=2)  # a lockstep calibration node: frames 0-1 decided
    assert [b.frame.seq for b in comp.ready(now=0.0)] == [0, 1]
    comp.set_camera(high, 2, undecided_from=3)  # refined from frame 2 on, decided to frame 2
    got = comp.ready(now=0.0)
    assert [b.frame.seq for b in got] == [2]
    drawn = (comp.render(got[0]) != scene_frame(2, 160, 120)).any(-1)
    iou = {}
    for name, cam in (("high", high), ("low", low)):
        ref = changed(draw.draw_partner_3d(blank(120, 160), partner_joints(2), cam))
        iou[name] = (drawn & ref).sum() / (drawn | ref).sum()
    assert iou["high"] > 0.95 and iou["low"] < 0.85, iou
    comp.set_camera(high, 3)  # its last: every later frame's
    assert [b.frame.seq for b in comp.ready(now=0.0)] == [3, 4]


def test_control_overlay_shows_the_control_values() -> None:
    comp = Compositor(CAM, want_partner=False)
    comp.set_control(Control(strength=0.2, emotion="sad"))
    comp.add_frame(_frame(0))
    a = comp.render(comp.ready()[0])
    comp.set_control(Control(strength=0.9))
    comp.add_frame(_frame(0))
    b = comp.render(comp.ready()[0])
    assert comp.controls.as_dict()["emotion"] == "sad"
    diff = (a != b).any(-1)
    assert diff[-12:].any() and not diff[:-12].any()  # only the control bar at the bottom changed
    comp.set_control(Control(overlays={"controls": False}))
    comp.add_frame(_frame(0))
    c = comp.render(comp.ready()[0])
    assert np.array_equal(c, scene_frame(0, 160, 120))


def test_scaled_camera_projects_proportionally() -> None:
    X = np.array([[0.3, 1.2, 0.1], [-0.5, 0.2, -0.4]])
    half = camera_for_size(CAM, 160, 120)
    np.testing.assert_allclose((CAM.project(X) + 0.5) / 2, half.project(X) + 0.5, atol=1e-9)


# ------------------------------------------------------------------------------------------- video
def test_video_writer_output_decodes_with_every_frame(tmp_path) -> None:
    for name in ("clip.mp4", "clip2.avi"):
        with VideoWriter(tmp_path / name, fps=10) as w:
            for s in range(12):
                w.write(scene_frame(s))
        assert w.path.exists() and w.path.suffix in (".mp4", ".avi")
        assert count_frames(w.path) == 12
        cap = cv2.VideoCapture(str(w.path))
        ok, first = cap.read()
        assert ok and first.shape == (120, 160, 3)
        assert np.abs(first.astype(int) - scene_frame(0)).mean() < 4  # lossy, but the same picture
    with pytest.raises(ValueError, match=r"\.mp4"):
        choose_codec(tmp_path / "x.mkv")
    # Motion-JPEG frames encoded by libjpeg-turbo where OpenCV's FFmpeg takes them as they are:
    # every row of an odd-height frame kept, the picture as close as FFmpeg's own encoder keeps it
    odd = [cv2.GaussianBlur(scene_frame(s, 160, 121), (5, 5), 0) for s in range(6)]
    with VideoWriter(tmp_path / "odd.avi", fps=30) as w:
        for img in odd:
            w.write(img)
    back = cv2_frames(w.path)
    if raw_mjpeg_works():
        assert [f.shape for f in back] == [(121, 160, 3)] * 6
    assert len(back) == 6 and all(np.abs(f.astype(int) - o[: f.shape[0]]).mean() < 2 for f, o in zip(back, odd))
    w = VideoWriter(tmp_path / "c.avi")
    w.write(scene_frame(0))
    with pytest.raises(ValueError, match="same size"):
        w.write(scene_frame(0, 80, 60))
    w.close()


# ---------------------------------------------------------------------------------------- controls
def test_parse_control_accepts_valid_and_names_bad_keys() -> None:
    c = parse_control(
        {
            "strength": 0.7,
            "emotion": "happy",
            "interest": "3",
            "speaker": "partner",
            "overlays": {"stats": False},
            "model": "listener",
        },
        models=["dual-hmm", "listener"],
    )
    assert (c.strength, c.emotion, c.interest, c.speaker, c.overlays, c.model) == (
        0.7,
        "happy",
        3,
        "partner",
        {"stats": False},
        "listener",
    )
    for bad, msg in [
        ({"strength": 1.5}, "strength"),
        ({"strength": "x"}, "strength"),
        ({"interest": 4}, "interest"),
        ({"emotion": "bored"}, "emotion"),
        ({"speaker": "dog"}, "speaker"),
        ({"volume": 1}, "volume"),
        ({"overlays": {"fog": True}}, "overlays"),
        ({"model": "gpdm"}, "model"),  # a model of the contract the page does not offer
        ({"model": "emotion"}, "model"),  # the style model is not an interaction model
        ([1], "JSON object"),
    ]:
        with pytest.raises(ValueError, match=msg):
            parse_control(bad, models=["dual-hmm", "listener"])


def test_badges_show_only_signals_that_are_on_for_tracked_people_above_the_head() -> None:
    """One row per tracked person with the signals that are on, above the head's box (beside it at the
    top of the picture); an untracked
    region (a fragment, a ghost) and a person with no signal on get no badge.
    """
    names = ["nod", "shake", "gaze", "act", "talk", "laugh"]
    people = [
        PersonShape(id=0, side="left", bbox=(40, 100, 50, 120)),  # tracked, nodding and talking
        PersonShape(id=1, side="right", bbox=(240, 100, 50, 120)),  # a region nobody tracks
        PersonShape(id=2, side="right", bbox=(120, 2, 40, 100)),
    ]  # tracked, head at the top
    signals = [
        PersonSignals(id=i, side=p.side, names=names, labels=np.array(lab, np.int8), scores=np.full(6, 0.5, np.float32))
        for i, (p, lab) in enumerate(zip(people, [[1, 0, 0, 0, 1, 0], [1, 1, 1, 1, 1, 1], [0, 0, 1, 0, 0, 0]]))
    ]
    pose = Pose3D(people=[TrackedBody(id=0, side="left"), TrackedBody(id=2, side="right")])
    comp = Compositor(CAM, overlays={"signals": True})
    b = Bundle(
        frame=Frame(image=blank()),
        silhouettes=Silhouettes(people=people, width=320, height=240),
        pose=pose,
        signals=SocialSignals(people=signals),
    )
    got = changed(comp.render(b))
    bright = (comp.render(b) == (0, 200, 255)).all(-1)
    ys, xs = np.nonzero(bright[:100, :120])
    # person 0: its two badges in one row just above its box (y 100), none over it
    assert ys.size and ys.max() < 100 and ys.min() > 100 - 30 and 20 <= xs.min() and xs.max() < 120
    assert not bright[100:220, 40:90].any()
    # person 1 is not tracked: nothing drawn over or above its region
    assert not got[:, 230:300].any()
    # person 2's head is at the top of the picture: its badge goes beside the head, not over its face
    assert bright[2:30, 163:200].any() and not bright[2:102, 120:160].any()
    # a person with nothing on gets no badge at all
    off = Bundle(
        frame=Frame(image=blank()),
        silhouettes=b.silhouettes,
        pose=pose,
        signals=SocialSignals(people=[replace(signals[0], labels=np.zeros(6, np.int8))]),
    )
    assert not changed(comp.render(off)).any()


def test_the_partner_painted_is_its_facets_far_to_near_in_fixed_point() -> None:
    # what _cone_fill gathers for the painting in one go is cone_facets' list of polygons, each in
    # order, in fixed point, with its shade: a partner half out of the picture too (facets dropped)
    for joints in (partner_joints(), partner_joints() + [1.4, 0.0, 0.0]):
        ends, radii = draw.partner_cones(joints)
        polys, shade, _ = draw.cone_facets(ends, radii, CAM)
        fixed, starts, colours = draw._cone_fill(ends, radii, CAM, (200, 150, 100), None, 16, 0.35)
        assert starts == np.cumsum([0] + [len(p) for p in polys]).tolist()
        assert np.array_equal(fixed, np.round(np.concatenate(polys) * draw._SCALE).astype(np.int32))
        assert colours == np.clip(np.array([200.0, 150.0, 100.0]) * shade[:, None], 0, 255).astype(int).tolist()


def test_codec_probe_keeps_ffmpeg_messages_off_stderr_and_passes_other_lines(tmp_path) -> None:
    # the file descriptor is the process's own, so the probe runs in a fresh interpreter; its real
    # H.264 probes too, whatever their outcome on this machine's OpenCV
    script = tmp_path / "probe.py"
    script.write_text(
        "import logging, os, sys\n"
        "from counterpart.nodes.renderer import video\n"
        f"logging.basicConfig(level=logging.DEBUG, format='%(message)s', filename={str(tmp_path / 'debug.log')!r})\n"
        "def probe(tmp):\n"
        "    os.write(2, b'[h264_v4l2m2m @ 0x55d0c0] Could not find a valid device\\n')\n"
        "    os.write(2, b'OpenCV: FFMPEG: fallback to use tag avc1\\n')\n"
        "    os.write(2, b'another thread said this\\n')\n"
        "    return True\n"
        "print(video._probed('made-up', probe), video.codec_works('avc1', '.mp4'), video.codec_works('H264', '.mp4'))\n"
        "print('after', file=sys.stderr)\n"
    )
    run = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert run.stdout.split()[0] == "True"
    assert run.stderr.splitlines() == ["another thread said this", "after"], run.stderr
    debug = (tmp_path / "debug.log").read_text()
    assert "codec probe: [h264_v4l2m2m @ 0x55d0c0] Could not find a valid device" in debug
    assert "codec probe: OpenCV: FFMPEG: fallback to use tag avc1" in debug
