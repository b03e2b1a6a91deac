"""Where the partner stands and what it does on real clips: the responder's algorithms over a tracked clip.

Used by ``bench/real_video.py`` (its tracking part writes one ``track_video`` file per clip). For each
clip the observed side's tracked joints go through the default dual-HMM and the responder node's
stage (``counterpart.nodes.responder.staging.Stage``, the node's defaults, with the tracking's camera
as the demo graphs give the node its ``camera_info``) frame by frame as the responder node
runs them, then its arms and final clearance (``Stage.finish``: guarding while pushed, else the hand
contact of ``counterpart.nodes.responder.reach``) (a lost or missing person: the partner holds for ``HOLD_FRAMES``, then none), and the
partner is projected with the camera the tracking recorded. Figures:

- ``partner_distance_ok``: share of frames with a partner whose ground distance from the observed
  person (mid-hips on the floor, metres) lies in [0.5, 1.2] m;
- ``partner_overlap``: share of frames with a partner whose projected box overlaps the observed
  person's reference box (MediaPipe keypoints of vis >= 0.5) by more than ``OVERLAP_IOU``, over the
  frames where the two reference skeletons are two people (where both lie on one person,
  ``real_silhouettes.reference_collapsed``, the reference does not say where the observed person
  is: on the push clips that is about half of the frames of the push);
  ``partner_overlap_all``: the same over every frame with a partner, collapsed ones included;
- ``partner_overlap_real``: for reference, the same share as ``partner_overlap`` for the real second
  person's reference box against the observed person's (same frames);
- ``partner_in_picture``: share of frames with a partner of which some joint is inside the picture;
- ``partner_scale``: median over the frames with a partner of its height as drawn (``drawn_height``:
  the rows from the crown of its head to its soles, projected) over the height of the observed
  person's silhouette box on that frame (where the region is theirs alone): how big the partner
  looks beside the person in the picture; ``partner_scale_real``, the reference in the same run:
  the real second person's silhouette box height over the observed person's (frames where each has
  a region of their own); ``partner_bones_spread``: median over clips of the spread (95th minus 5th
  percentile over frames, over the median) of the partner's body length in metres (the sum of its
  bones from ankle to head, the legs' averaged): 0 for a partner that keeps one body;
- handshake clips (class 0, observed: the left person): at the moment the real hands meet (the
  frame where the two people's reference wrists are nearest), the pixel distance from the partner's
  nearer projected wrist to the observed person's reference wrist nearest the other person, over
  that person's reference height h: ``handshake_hand_h`` (median over clips) and
  ``handshake_hand_ok`` (share of clips within ``HAND_H`` h);
- push clips (class 5, observed: the pusher: the moment is the frame where one person's reference
  wrist comes nearest the other's shoulders and hips, and the pusher is that person unless the other
  is the one who walked towards them over the ``PUSH_LEAD`` frames before (``advance``; in 29_5_5
  the pushee's raised hands lie on the pusher's torso, the pusher walks 1.0 h in, the pushee stands)): the partner's ground distance from the observed person, its largest
  value in the second after that moment minus its value then (metres): ``push_back_m`` (median) and
  ``push_moves_back`` (share of clips where it grows by at least ``BACK_M``). Where the tracker
  lost the observed person on that very frame, the moment is the last frame before it where they
  are tracked, at most ``MOMENT_SLACK`` frames before (the node holds the partner through such a
  dropout); a clip with none is a miss.

The moment of the interaction is looked for only on frames where the two reference skeletons are
two people (``real_silhouettes.reference_collapsed``): where both lie on one person, a wrist is
"on the other's torso" by construction (8 of the 10 push clips had their moment there, often
seconds after the push).

Alone (``python bench/real_partner.py [--tracks DIR] [--clips all|N]``) it runs on the handshake
and push clips of ``../shared/data/ut_interaction/set1``, tracking each clip as
``bench/real_video.py`` does (``track_video``, the lockstep graph's configuration) unless ``DIR``
holds its ``CLIP-track.npz`` already (tracks it writes go there too; so do the silhouette node's people
of each clip, ``CLIP-people.pkl``, the other slow part, reused alike); the last stdout line is one
JSON object: the figures above for the report split (clips whose first number is odd) at the
top level, the tune split (even) under ``tune``, per-clip rows under ``per_clip``.
"""

from __future__ import annotations

import argparse
import json
import pickle
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from real_silhouettes import reference_collapsed  # bench/ is on sys.path as a script

from counterpart.body.camera import Camera
from counterpart.body.skeleton import JOINT_INDEX, bone_lengths
from counterpart.nodes.responder.frames import actor_frame
from counterpart.nodes.responder.model_clock import AtModelRate
from counterpart.nodes.responder.models import load_default
from counterpart.nodes.responder.staging import HEAD_TOP_M, Stage, observed_silhouette

VIS = 0.5
HOLD_FRAMES = 15  # the responder node's default hold_frames
OVERLAP_IOU = 0.25
HAND_H = 0.15
BACK_M = 0.1
MIN_M, MAX_M = 0.5, 1.2
#: frames before the moment of a push whose gap stands for it where the observed person is lost then
MOMENT_SLACK = 3
WRISTS = [JOINT_INDEX["l_wrist"], JOINT_INDEX["r_wrist"]]
HEAD, ANKLES = JOINT_INDEX["head"], [JOINT_INDEX["l_ankle"], JOINT_INDEX["r_ankle"]]
#: each leg's thigh and shin (``bone_lengths``' entries of the knee and the ankle)
LEG_L = [JOINT_INDEX[j] for j in ("l_knee", "l_ankle")]
LEG_R = [JOINT_INDEX[j] for j in ("r_knee", "r_ankle")]
TORSO = [JOINT_INDEX[j] for j in ("l_shoulder", "r_shoulder", "l_hip", "r_hip")]
HANDSHAKE, PUSH = 0, 5
#: the stage has the graph's camera (the responder node's camera_info, as the demo graphs wire it)
CAMERA = True


def interaction_class(clip: Path) -> int:
    """UT-Interaction class of a clip from its name ``{clip}_{sequence}_{class}``."""
    return int(clip.stem.split("_")[2])


def _nearest(a: np.ndarray, va: np.ndarray, b: np.ndarray, vb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per frame the smallest distance between points a (T, A, 2) and b (T, B, 2) that are both
    visible (va (T, A), vb (T, B)), inf where none; and the index of a's point of that pair.
    """
    d = np.linalg.norm(a[:, :, None] - b[:, None], axis=-1)
    d = np.where(va[:, :, None] & vb[:, None] & np.isfinite(d), d, np.inf)
    flat = d.reshape(len(d), -1)
    return flat.min(axis=1), flat.argmin(axis=1) // b.shape[1]


def contact(kp: np.ndarray, vis: np.ndarray, h: np.ndarray, label: int) -> tuple[int, int, int] | None:
    """The moment of the interaction by the reference: (frame, observed person, its wrist joint).

    kp (T, 2, 14, 2) pixels, vis (T, 2, 14), h (T, 2) heights (pixels). Handshake: the frame where
    the two people's wrists are nearest (over their mean height); the observed person is 0 (the
    left one). Push: the frame where one person's wrist is nearest the other's torso; that person
    (the pusher) is observed, unless the other is the one who walked towards them before it
    (``advance``): a pushee's hands raised against the pusher lie on the pusher's torso too. None
    when the reference never shows the joints needed.
    """
    seen = (vis >= VIS) & np.isfinite(kp).all(axis=-1)
    # both reference skeletons on one person: there the reference cannot say where the people are
    # (nor, their wrists on each other's torso by construction, when they touch)
    seen &= ~np.array([reference_collapsed(kp[t], vis[t]) for t in range(len(kp))], dtype=bool)[:, None, None]
    # frames without a reference height (a joint missing) cannot say how near the people are
    scale = np.where(np.isfinite(h).all(axis=1), np.maximum(h.mean(axis=1), 1.0), np.nan)
    if label == HANDSHAKE:
        d, k = _nearest(kp[:, 0, WRISTS], seen[:, 0, WRISTS], kp[:, 1, WRISTS], seen[:, 1, WRISTS])
        d = np.nan_to_num(d / scale, nan=np.inf)
        t = int(np.argmin(d))
        return None if not np.isfinite(d[t]) else (t, 0, WRISTS[int(k[t])])
    best = None
    for p in (0, 1):
        d, k = _nearest(kp[:, p, WRISTS], seen[:, p, WRISTS], kp[:, 1 - p, TORSO], seen[:, 1 - p, TORSO])
        d = np.nan_to_num(d / scale, nan=np.inf)
        t = int(np.argmin(d))
        if np.isfinite(d[t]) and (best is None or d[t] < best[0]):
            best = (d[t], t, p, WRISTS[int(k[t])])
    if best is None:
        return None
    _, t, p, wrist = best
    walked = advance(kp, h, t)
    if walked is not None and walked[1 - p] > walked[p]:
        # the other walked in: a pushee's hands raised against the pusher lie on the pusher's torso too
        p = 1 - p
        wrist = WRISTS[int(np.argmin(np.linalg.norm(kp[t, p, WRISTS] - kp[t, 1 - p, TORSO].mean(0), axis=-1)))]
    return t, p, wrist


#: frames before the moment of a push over which the pusher is the one who walked towards the other
PUSH_LEAD = 30


def advance(kp: np.ndarray, h: np.ndarray, t: int) -> np.ndarray | None:
    """How far each reference person's mid-hips came towards the other's across the picture over the
    ``PUSH_LEAD`` frames before frame ``t``, in their heights (2,); None where the hips are not seen then.

    kp (T, 2, 14, 2) pixels, h (T, 2) heights (pixels).
    """
    a = max(t - PUSH_LEAD, 0)
    hips = kp[[a, t]][:, :, TORSO[2:]].mean(axis=2)[..., 0]  # (2 frames, 2 people) x pixels
    if not np.isfinite(hips).all() or not np.isfinite(h[t]).all():
        return None
    towards = np.sign(hips[1, 1] - hips[1, 0])  # +1: person 1 stands right of person 0
    return np.array([hips[1, 0] - hips[0, 0], hips[0, 1] - hips[1, 1]]) * towards / np.maximum(h[t], 1.0)


#: frames the silhouette background is learnt on, as the lockstep graph and bench/real_video.py do
TRAIN_FRAMES = 20
SIDES = ("left", "right")


def silhouette_people(clip: Path) -> list[list[Any]]:
    """The silhouette node's people on every frame of ``clip`` (``iter_video``, default extractor,
    the background learnt on ``TRAIN_FRAMES`` frames as the tracker's input is made).
    """
    from counterpart.nodes.silhouette.pipeline import SilhouetteExtractor, iter_video

    return [list(result.people) for _, result in iter_video(clip, SilhouetteExtractor(), None, TRAIN_FRAMES)]


def staged_partner(
    track_npz: Path, side: int, people: list[list[Any]] | None = None
) -> tuple[np.ndarray, np.ndarray, Camera, float]:
    """The partner the responder node would draw for the tracked ``side`` of a ``track_video`` file.

    As the node: the other tracked side is the real second person (``other``), the observed
    side's name gives the side to stand on, and the observed person's silhouette on each frame
    (``people``, from ``silhouette_people``; None: none) their reach and offered hand.
    Returns partner (T, 14, 3) world metres (NaN: none), observed (T, 14, 3) (NaN: lost or
    missing), the camera of the tracking, the clip's fps, and the observed person's silhouette box
    (T, 4) (x, y, w, h) pixels as the stage had it (NaN: none, or shared with someone else).
    """
    d = np.load(track_npz)
    camera = Camera.from_dict(json.loads(str(d["camera"])))
    fps = float(d["fps"])
    joints, lost = d["joints"][:, side].astype(np.float64), d["lost"][:, side]
    others = np.where(d["lost"][:, 1 - side, None, None], np.nan, d["joints"][:, 1 - side].astype(np.float64))
    ids = d["ids"][:, side]
    frame_height = int(d["frame_size"][0])
    model, stage = load_default("dual-hmm"), Stage()
    model.reset()
    rate = AtModelRate.for_model(model, fps)  # the node steps the model on its own frames
    partner = np.full_like(joints, np.nan)
    boxes = np.full((len(joints), 4), np.nan)
    observed = np.where(lost[:, None, None], np.nan, joints)
    towards = 1.0 if side == 0 else -1.0  # the left person's partner stands to their right (image right)
    last = -(10**9)
    for t in range(len(joints)):
        if lost[t] or not np.isfinite(joints[t]).all():
            if t - last <= HOLD_FRAMES:
                partner[t] = partner[last]
            continue
        other = others[t] if np.isfinite(others[t]).all() else None
        direction = stage.side or towards
        silhouette, box = (
            observed_silhouette(
                people[t], int(ids[t]), SIDES[side], joints[t], direction, camera if CAMERA else None, frame_height
            )
            if people is not None and t < len(people)
            else (None, None)
        )
        dt = (t - last) / fps if last >= 0 else 1.0 / fps
        if box is not None:
            boxes[t] = box
        staged = stage(
            joints[t],
            rate(model.step, joints[t], t / fps),
            dt,
            other=other,
            side=towards,
            silhouette=silhouette,
            camera=camera if CAMERA else None,
            box=box if CAMERA else None,
        )
        partner[t] = stage.finish(joints[t], staged)[0]  # its arms (guard or reach), kept clear last
        last = t
    return partner, observed, camera, fps, boxes


def drawn_height(camera: Camera, joints: np.ndarray) -> np.ndarray:
    """A body's height as drawn, pixels: the rows from the crown of its head (``HEAD_TOP_M`` above the
    head joint) to its soles (the lowest ankle put on the ground), for joints (T, 14, 3) metres.
    """
    X = np.asarray(joints, np.float64)
    crown = X[:, HEAD] + [0.0, HEAD_TOP_M, 0.0]
    sole = X[np.arange(len(X)), np.asarray(ANKLES)[np.argmin(X[:, ANKLES, 1], axis=1)]] * [1.0, 0.0, 1.0]
    rows = camera.project(np.stack([crown, sole], axis=1))[..., 1]
    return np.abs(rows[:, 1] - rows[:, 0])


def _box(points: np.ndarray) -> np.ndarray | None:
    pts = points[np.isfinite(points).all(axis=-1)]
    return None if len(pts) < 2 else np.r_[pts.min(0), pts.max(0)]


def _iou(a: np.ndarray, b: np.ndarray) -> float:
    w = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    h = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = w * h
    union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
    return inter / union if union > 0 else 0.0


def partner_clip(
    clip: Path,
    track_npz: Path,
    kp: np.ndarray,
    vis: np.ndarray,
    h: np.ndarray,
    people: list[list[Any]] | None = None,
) -> dict[str, Any]:
    """The partner's figures on one clip (counts, to pool; and the clip's interaction figure).

    kp (T, 2, 14, 2), vis (T, 2, 14), h (T, 2): the reference over the frames scored; people:
    the silhouette node's people per frame (None: found here with ``silhouette_people``).
    """
    label = interaction_class(clip)
    moment = contact(kp, vis, h, label) if label in (HANDSHAKE, PUSH) else None
    side = moment[1] if moment is not None and label == PUSH else 0
    people = silhouette_people(clip) if people is None else people
    partner, observed, camera, fps, boxes = staged_partner(track_npz, side, people)
    n = min(len(partner), len(kp))
    partner, observed, boxes = partner[:n], observed[:n], boxes[:n]
    has = np.isfinite(partner).all(axis=(1, 2))
    both = has & np.isfinite(observed).all(axis=(1, 2))
    gap = np.full(n, np.nan)
    if both.any():
        gap[both] = np.linalg.norm((actor_frame(partner[both])[0] - actor_frame(observed[both])[0])[:, [0, 2]], axis=1)
    uv = camera.project(np.where(has[:, None, None], partner, 0.0))
    overlap = overlap_all = in_picture = real_overlap = two = 0
    # how big the partner looks beside the person, and the real second person (alone in their region)
    mine_h = np.full(n, np.nan)
    mine_h[has] = drawn_height(camera, partner[has])
    scale = (mine_h / boxes[:, 3])[has & np.isfinite(boxes[:, 3])].tolist()
    other_id = np.load(track_npz)["ids"][:n, 1 - side]
    other_h = np.array(
        [next((q.bbox[3] for q in people[t] if q.id == other_id[t] and not q.merged), np.nan) for t in range(n)], float
    )
    scale_real = (other_h / boxes[:, 3])[np.isfinite(other_h) & np.isfinite(boxes[:, 3])].tolist()
    for t in np.flatnonzero(has):
        in_picture += bool(camera.in_image(uv[t]).any())
        ref = _box(np.where((vis[t, side] >= VIS)[:, None], kp[t, side], np.nan))
        mine = _box(uv[t])
        real = _box(np.where((vis[t, 1 - side] >= VIS)[:, None], kp[t, 1 - side], np.nan))
        # both reference skeletons on one person: the reference does not say where the observed one is
        apart = not reference_collapsed(kp[t], vis[t])
        hit = ref is not None and mine is not None and _iou(ref, mine) > OVERLAP_IOU
        two += apart
        overlap += hit and apart
        overlap_all += hit
        real_overlap += ref is not None and real is not None and _iou(ref, real) > OVERLAP_IOU and apart
    out: dict[str, Any] = {
        "frames": int(has.sum()),
        "gap_n": int(both.sum()),
        "gap_ok": int(((gap >= MIN_M - 1e-6) & (gap <= MAX_M + 1e-6)).sum()),
        "overlap": int(overlap),
        "overlap_all": int(overlap_all),
        "apart": int(two),
        "real_overlap": int(real_overlap),
        "in_picture": int(in_picture),
        "label": label,
        "scale": scale,
        "scale_real": scale_real,
        "bones_spread": body_length_spread(partner[has]),
    }
    if moment is not None and moment[0] < n:
        t, p, wrist = moment
        if label == HANDSHAKE and has[t]:
            out["hand_h"] = float(np.linalg.norm(uv[t, WRISTS] - kp[t, p, wrist], axis=-1).min() / max(h[t, p], 1.0))
        elif label == HANDSHAKE:
            out["hand_h"] = float("inf")  # no partner at the moment of the handshake: a miss
        if label == PUSH:
            # the observed person lost by the tracker on that very frame (a dropout of a frame or two,
            # through which the node holds the partner): the gap of the last frame before it
            known = [k for k in range(t, max(t - MOMENT_SLACK, -1), -1) if np.isfinite(gap[k])]
            t = known[0] if known else t
            after = gap[t : t + round(fps) + 1]
            out["back_m"] = (
                float(np.nanmax(after) - gap[t]) if np.isfinite(gap[t]) and np.isfinite(after).any() else float("nan")
            )
    return out


def body_length_spread(joints: np.ndarray) -> float | None:
    """The spread of a body's length over frames: (95th - 5th percentile) / median of the sum of its
    bones from ankle to head (legs averaged), for joints (T, 14, 3) metres; None without frames.
    """
    if not len(joints):
        return None
    b = bone_lengths(joints)
    legs = 0.5 * (b[:, LEG_L].sum(axis=1) + b[:, LEG_R].sum(axis=1))
    length = legs + b[:, [JOINT_INDEX["neck"], JOINT_INDEX["head"]]].sum(axis=1)
    lo, mid, hi = np.percentile(length, [5, 50, 95])
    return float((hi - lo) / mid)


def _median(values: list[float]) -> float | None:
    return round(float(np.median(values)), 3) if values else None


def partner_figures(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Pool ``partner_clip`` rows into the bench's figures."""
    frames = sum(r["frames"] for r in rows)
    apart = sum(r["apart"] for r in rows)
    hands = [r["hand_h"] for r in rows if "hand_h" in r]
    backs = [r["back_m"] for r in rows if "back_m" in r]
    return {
        "partner_distance_ok": round(sum(r["gap_ok"] for r in rows) / max(sum(r["gap_n"] for r in rows), 1), 4),
        "partner_overlap": round(sum(r["overlap"] for r in rows) / max(apart, 1), 4),
        "partner_overlap_real": round(sum(r["real_overlap"] for r in rows) / max(apart, 1), 4),
        "partner_overlap_all": round(sum(r["overlap_all"] for r in rows) / max(frames, 1), 4),
        "partner_in_picture": round(sum(r["in_picture"] for r in rows) / max(frames, 1), 4),
        "partner_scale": _median([v for r in rows for v in r["scale"]]),
        "partner_scale_real": _median([v for r in rows for v in r["scale_real"]]),
        "partner_bones_spread": _median([r["bones_spread"] for r in rows if r["bones_spread"] is not None]),
        "handshake_clips": len(hands),
        "handshake_hand_h": round(float(np.median(hands)), 3) if hands else None,
        "handshake_hand_ok": round(float(np.mean([x <= HAND_H for x in hands])), 3) if hands else None,
        "push_clips": len(backs),
        "push_back_m": round(float(np.nanmedian(backs)), 3) if backs and np.isfinite(backs).any() else None,
        "push_moves_back": round(float(np.mean([x >= BACK_M for x in backs])), 3) if backs else None,
    }


def main() -> None:
    """The partner's figures on the handshake and push clips (see the module); one JSON line."""
    import real_video as rv  # bench/ is on sys.path as a script; imported here, it imports this module

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument(
        "--tracks",
        type=Path,
        default=None,
        help="folder of track_video files CLIP-track.npz and silhouette people CLIP-people.pkl to reuse",
    )
    ap.add_argument("--clips", default="all", help="'all' or how many of the handshake and push clips")
    args = ap.parse_args()
    if not rv.CLIPS.is_dir():
        sys.exit(f"bench/real_partner.py: {rv.CLIPS} not found (the shared data, see ../shared/data/README.md)")
    clips = [c for c in rv.clip_list("all") if interaction_class(c) in (HANDSHAKE, PUSH)]
    clips = clips if args.clips == "all" else clips[: int(args.clips)]
    work = args.tracks or Path(tempfile.mkdtemp(prefix="cp-partner-"))
    work.mkdir(parents=True, exist_ok=True)
    rows: dict[str, dict[str, Any]] = {}
    for clip in clips:
        t0 = time.monotonic()
        track = work / f"{clip.stem}-track.npz"
        if not track.exists():
            from counterpart.apps.tracking import track_video
            from counterpart.nodes.tracker.prior import resolve_prior

            track_video(
                clip,
                track,
                people=rv.SIDES,
                camera=None,
                prior=resolve_prior("default"),
                layers=rv.LAYERS,
                particles=rv.PARTICLES,
                train_frames=rv.TRAIN_FRAMES,
            )
        ref = np.load(rv.KEYPOINTS / f"{clip.stem}.npz")
        n = min(len(np.load(track)["joints"]), len(ref["kp"]))
        kp, vis = ref["kp"][:n].astype(np.float64), ref["vis"][:n]
        # the silhouette node's people, the other slow part, cached beside the track
        cached = work / f"{clip.stem}-people.pkl"
        if not cached.exists():
            cached.write_bytes(pickle.dumps(silhouette_people(clip)))
        people = pickle.loads(cached.read_bytes())
        rows[clip.stem] = partner_clip(clip, track, kp, vis, rv.reference_height(kp), people)
        shown = {k: _median(v) if isinstance(v, list) else v for k, v in rows[clip.stem].items()}  # lists: medians
        print(f"partner {clip.stem}: {shown} ({time.monotonic() - t0:.1f} s)", file=sys.stderr, flush=True)
    splits = {s: [rows[c.stem] for c in clips if rv.split_of(c) == s] for s in ("report", "tune")}
    result: dict[str, Any] = {
        "split": "report: clips whose first number is odd (top level); tune: even",
        **(partner_figures(splits["report"]) if splits["report"] else {}),
        "tune": partner_figures(splits["tune"]) if splits["tune"] else None,
        "per_clip": {  # NaN / inf (no figure: the person lost at that moment) as null
            k: {
                f: r[f] if np.isfinite(r[f]) else None
                for f in ("label", "hand_h", "back_m", "overlap", "frames")
                if f in r
            }
            for k, r in rows.items()
        },
        "tracks": str(work),
    }
    print(json.dumps(result))


if __name__ == "__main__":
    main()
