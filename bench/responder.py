"""Responder benchmark: the masked-partner protocol on held-out simulator sequences.

For every interaction type, held-out seeds: person A (and then B) is shown to the model, the
partner is generated and compared with the real one. Prints one JSON object as the last line:

  partner_err_mm        dual-hmm, mean per-joint error of the partner (world, mm), all frames
  partner_err_contact_mm   the same over contact frames (phase 1)
  baseline_mirror_mm    the observed person reflected through the mean mid-plane (training mean
                        separation) in the observed frame
  baseline_meanpose_mm  the training mean partner pose placed in the observed frame
  contact_timing_s      handshake: |first frame the right hands meet (< 0.12 m)| generated vs real
  action_acc            a classifier (random forest on pair summary features) trained on real
                        pairs recognises the interaction in generated pairs
  shape_err / shape_mirror_err   joint-shape partner control points (px, 160x120) and mirror baseline
  rank_acc              emotion ranking, held-out pairs of the same interaction
  step_ms               dual-hmm online step; train_s   dual-hmm default training time
  partner_err_staged_mm the partner error after the responder node's stage and hand contact
                        (counterpart.nodes.responder.staging: 0.5-1.2 m from the observed person, at most 2.5 m/s;
                        nodes.responder.reach, Stage.finish: arms in while pushed), as the graph draws it;
                        the simulator's pairs walk up from further apart, where the stage holds
                        the partner nearer than the real one stood
  contact_err_mm        dual-hmm, the partner's right hand at the moment of contact (first frame of
                        phase 1) against the real partner's (mm), handshakes and high fives
  gpdm                  the hierarchical GPDM (Taubert et al.) on the same held-out handshakes and high
                        fives (seeds 200-203; its training seeds 0-7, its settings chosen on seeds
                        100-102): partner_err_mm, contact_err_mm, contact_timing_s (both hand meetings),
                        contact_err_offset_mm (hands meeting 0.15 m above / below the simulator's
                        height, beyond the training's +-0.1 m), style_acc (a random forest on
                        motion features, trained on the simulator's styled partners, labels the
                        partner generated in each of the four styles at strength 1; style_acc_real:
                        the same forest on real held-out styled partners), rank_acc (the emotion
                        ranking orders partners generated at strengths 0, 0.15, 0.45, 0.75, 0.95),
                        step_ms, train_s; and dual-hmm's partner_err_mm, contact_timing_s and
                        contact_err_offset_mm on the same trials

``--quick``: two held-out seeds, no joint-shape, fewer style draws (for development).
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from counterpart.messages import EMOTIONS  # noqa: E402
from counterpart.nodes.responder.data import SIM_SCENARIOS, sim_trajectories  # noqa: E402
from counterpart.nodes.responder.emotion import motion_features  # noqa: E402
from counterpart.nodes.responder.frames import actor_frame, relative_pair, to_local, to_world  # noqa: E402
from counterpart.nodes.responder.pair_features import partner_placement  # noqa: E402
from counterpart.nodes.responder.staging import Stage  # noqa: E402
from counterpart.nodes.responder.training import default_training_data, train  # noqa: E402


def mpjpe(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.linalg.norm(x - y, axis=-1).mean(-1) * 1e3


def pair_features(obs: np.ndarray, par: np.ndarray) -> np.ndarray:
    o, th = actor_frame(obs)
    q, own = partner_placement(par, o, th)
    lo = to_local(obs, o, th)
    f = [
        q[:, :2].mean(0),
        q[:, :2].min(0),
        lo.reshape(len(lo), -1).std(0),
        own.reshape(len(own), -1).std(0),
        lo[:, [4, 7], 1].max(0),
        own[:, [4, 7], 1].max(0),
        [len(obs) / 100.0],
    ]
    return np.concatenate([np.ravel(x) for x in f])


def contact_time(obs: np.ndarray, par: np.ndarray, fps: float) -> float | None:
    d = np.linalg.norm(obs[:, 7] - par[:, 7], axis=-1)
    hit = np.flatnonzero(d < 0.12)
    return None if len(hit) == 0 else hit[0] / fps


MEETINGS = ("handshake", "high_five")


def contact_error(par: np.ndarray, pred: np.ndarray, phase: np.ndarray) -> float:
    """The generated right hand against the real one at the first contact frame, mm."""
    c = int(np.flatnonzero(phase == 1)[0])
    return float(np.linalg.norm(pred[c, 7] - par[c, 7]) * 1e3)


def timing_error(obs: np.ndarray, par: np.ndarray, pred: np.ndarray, fps: float) -> float:
    """|generated - real| time of the first hand contact, s (1 s when either never touches)."""
    a, b = contact_time(obs, par, fps), contact_time(obs, pred, fps)
    return abs(a - b) if a is not None and b is not None else 1.0


def gpdm_figures(test: list, hmm: object, em: object, quick: bool) -> dict[str, float]:
    """The gpdm block of the output (module docstring)."""
    from sklearn.ensemble import RandomForestClassifier

    out: dict[str, float] = {}
    t0 = time.perf_counter()
    data = default_training_data("gpdm")
    g = train("gpdm", data, lambda m: print(f"[bench] {m}", file=sys.stderr, flush=True))
    out["train_s"] = round(time.perf_counter() - t0, 2)
    meet = [t for t in test if t.label in MEETINGS]
    pe, ce, tm, steps, h_pe, h_tm = [], [], [], [], [], []
    for t in meet:
        for obs, par in ((t.a, t.b), (t.b, t.a)):
            g.set_style(t.meta["emotion"], t.meta["strength"])
            s0 = time.perf_counter()
            pred = g.predict(obs)
            steps.append((time.perf_counter() - s0) / len(obs) * 1e3)
            hp = hmm.predict(obs)
            pe.append(mpjpe(pred, par).mean())
            h_pe.append(mpjpe(hp, par).mean())
            ce.append(contact_error(par, pred, t.phase))
            tm.append(timing_error(obs, par, pred, t.fps))
            h_tm.append(timing_error(obs, par, hp, t.fps))
    out.update(
        partner_err_mm=round(float(np.mean(pe)), 1),
        contact_err_mm=round(float(np.mean(ce)), 1),
        contact_timing_s=round(float(np.median(tm)), 3),
        step_ms=round(float(np.median(steps)), 3),
        dual_hmm_partner_err_mm=round(float(np.mean(h_pe)), 1),
        dual_hmm_contact_timing_s=round(float(np.median(h_tm)), 3),
    )
    # the offered hand higher or lower than any training trial's
    seeds = sorted({t.meta["seed"] for t in meet})[:2]
    off, h_off = [], []
    for dy in (-0.15, 0.15):
        for t in sim_trajectories(MEETINGS, seeds, max_frames=300, hand_dy=dy):
            g.set_style(t.meta["emotion"], t.meta["strength"])
            off.append(contact_error(t.b, g.predict(t.a), t.phase))
            h_off.append(contact_error(t.b, hmm.predict(t.a), t.phase))
    out["contact_err_offset_mm"] = round(float(np.mean(off)), 1)
    out["dual_hmm_contact_err_offset_mm"] = round(float(np.mean(h_off)), 1)
    # style: a forest trained on the simulator's styled partners (strength >= 0.5) labels generated ones
    clf = RandomForestClassifier(300, random_state=0).fit(
        [motion_features(t.b, t.fps) for t in data], [t.meta["emotion"] for t in data]
    )
    real = [
        t
        for e in EMOTIONS
        for t in sim_trajectories(MEETINGS, range(300, 301 if quick else 302), max_frames=300, emotion=e, strength=1.0)
    ]
    out["style_acc_real"] = round(
        float(np.mean(clf.predict([motion_features(t.b, t.fps) for t in real]) == [t.meta["emotion"] for t in real])), 3
    )
    hits = []
    for t in meet:
        for e in EMOTIONS:
            g.set_style(e, 1.0)
            hits.append(clf.predict([motion_features(g.predict(t.a), t.fps)])[0] == e)
    out["style_acc"] = round(float(np.mean(hits)), 3)
    ok = tot = 0
    levels = (0.0, 0.15, 0.45, 0.75, 0.95)
    for t in meet[: 2 if quick else None]:
        for e in EMOTIONS[1:]:
            r = []
            for s in levels:
                g.set_style(e, s)
                r.append(float(em.rank(motion_features(g.predict(t.a), t.fps), e)))
            for i, j in itertools.combinations(range(len(levels)), 2):
                ok += int(r[j] > r[i])
                tot += 1
    out["rank_acc"] = round(ok / max(tot, 1), 3)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="two held-out seeds, no joint-shape (development)")
    quick = ap.parse_args().quick
    out: dict[str, float] = {}
    t0 = time.perf_counter()
    data = default_training_data("dual-hmm")
    hmm = train("dual-hmm", data)
    out["train_s"] = round(time.perf_counter() - t0, 2)
    test = sim_trajectories(SIM_SCENARIOS, range(200, 202 if quick else 204), max_frames=300)
    rel = [relative_pair(t.a, t.b) for t in data] + [relative_pair(t.b, t.a) for t in data]
    mean_par = np.concatenate([r[1] for r in rel]).mean(0)
    sep = float(np.mean([(0.5 * (r[1][:, 8] + r[1][:, 11]))[:, 2].mean() for r in rel]))
    errs, errs_c, mir, mean, timing, steps, contact, staged = [], [], [], [], [], [], [], []
    gen_pairs = []
    for t in test:
        for obs, par in ((t.a, t.b), (t.b, t.a)):
            s0 = time.perf_counter()
            pred = hmm.predict(obs)
            steps.append((time.perf_counter() - s0) / len(obs) * 1e3)
            e = mpjpe(pred, par)
            errs.append(e)
            stage = Stage()
            staged.append(
                mpjpe(
                    np.stack([stage.finish(o_t, stage(o_t, p_t, 1.0 / t.fps))[0] for o_t, p_t in zip(obs, pred)]), par
                )
            )
            errs_c.append(e[t.phase == 1])
            o, th = actor_frame(obs)
            lo = to_local(obs, o, th)
            m_loc = lo.copy()
            m_loc[..., 2] = sep - m_loc[..., 2]  # reflection through the mid-plane z = sep / 2
            mir.append(mpjpe(to_world(m_loc, o, th), par))
            mean.append(mpjpe(to_world(np.broadcast_to(mean_par, obs.shape), o, th), par))
            gen_pairs.append((t.label, obs, pred))
            if t.label == "handshake":
                timing.append(timing_error(obs, par, pred, t.fps))
            if t.label in MEETINGS:
                contact.append(contact_error(par, pred, t.phase))
    out["partner_err_mm"] = round(float(np.concatenate(errs).mean()), 1)
    out["partner_err_contact_mm"] = round(float(np.concatenate(errs_c).mean()), 1)
    out["partner_err_staged_mm"] = round(float(np.concatenate(staged).mean()), 1)
    out["baseline_mirror_mm"] = round(float(np.concatenate(mir).mean()), 1)
    out["baseline_meanpose_mm"] = round(float(np.concatenate(mean).mean()), 1)
    out["contact_timing_s"] = round(float(np.median(timing)), 3)
    out["step_ms"] = round(float(np.median(steps)), 3)
    out["contact_err_mm"] = round(float(np.mean(contact)), 1)
    # action recognition: trained on real pairs, tested on generated ones
    from sklearn.ensemble import RandomForestClassifier

    Xr, yr = [], []
    for t in data:
        for obs, par in ((t.a, t.b), (t.b, t.a)):
            Xr.append(pair_features(obs, par))
            yr.append(t.label)
    clf = RandomForestClassifier(200, random_state=0).fit(Xr, yr)
    pred_lab = clf.predict([pair_features(o, p) for _, o, p in gen_pairs])
    out["action_acc"] = round(float(np.mean(pred_lab == [lab for lab, _, _ in gen_pairs])), 3)
    # joint shape
    from counterpart.nodes.responder.shapes import trajectory_shapes

    js = None if quick else train("joint-shape", default_training_data("joint-shape"))
    se, sm = [], []
    for t in test[::2] if js is not None else []:
        a, b = trajectory_shapes(t)
        p = js.predict(a)
        ok = a.valid & b.valid
        se.append(np.linalg.norm(p[ok] - b.ctrl[ok], axis=-1).mean())
        d = np.median([np.median(x.pos[:, 0] - y.pos[:, 0]) for x, y in [trajectory_shapes(data[0])[::-1]]])
        mc = a.ctrl.copy()
        mc[..., 0] = 2 * a.pos[:, None, 0] + d - mc[..., 0]
        sm.append(np.linalg.norm(mc[ok][:, np.r_[0, 31:0:-1]] - b.ctrl[ok], axis=-1).mean())
    if se:
        out["shape_err"], out["shape_mirror_err"] = round(float(np.mean(se)), 2), round(float(np.mean(sm)), 2)
    # emotion ranking on held-out seeds
    em = train("emotion", default_training_data("emotion"))
    held = []
    for e in EMOTIONS:
        for s in (0.0,) if e == "neutral" else (0.15, 0.45, 0.75, 0.95):
            held += sim_trajectories(SIM_SCENARIOS, range(300, 301), max_frames=200, emotion=e, strength=s)
    ok = tot = 0
    for e in ("happy", "sad", "angry"):
        items = [x for x in held if x.meta["emotion"] in (e, "neutral")]
        for x, y in itertools.combinations(items, 2):
            sx = 0.0 if x.meta["emotion"] == "neutral" else x.meta["strength"]
            sy = 0.0 if y.meta["emotion"] == "neutral" else y.meta["strength"]
            if x.label != y.label or abs(sx - sy) < 0.1:
                continue
            rx, ry = em.rank(motion_features(x.a, x.fps), e), em.rank(motion_features(y.a, y.fps), e)
            ok += int((rx > ry) == (sx > sy))
            tot += 1
    out["rank_acc"] = round(ok / max(tot, 1), 3)
    out["gpdm"] = gpdm_figures(test, hmm, em, quick)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
