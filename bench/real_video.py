"""The demo on real two-person video: ``counterpart demo --input CLIP`` over UT-Interaction clips.

Each clip goes through the real command (six node processes, the lockstep graph
``launch/lockstep.yaml``) with a time limit; the figures come from the run's own summary
(``OUT/demo_stats.json``) and from the video it wrote:

- ``partner_present``: share of output frames with a partner drawn in the picture, per clip and
  pooled; ``partner_present_after_1s`` the same without each clip's first second (the background
  is learnt and the tracks start there); ``clips_partner_95``: clips whose after-1s share is at
  least 0.95 (the target: every clip with two people, which every UT-Interaction clip has);
- ``hangs``: runs (clips and the short-input cases) that did not end within the limit;
- ``fps_match``: clips whose output video plays at the input's frame rate (the file's own header
  read back with OpenCV, beside the demo's ``fps_in``/``fps_out``);
- the short inputs: the first clip cut to 1 and 5 frames (``--frames``), and started past its end
  (a source that fails before its first frame), each must end by itself;
- reference in the same run: the real-time graph (``--realtime``) on the first ``--reference``
  clips, where the nodes that cannot keep up on this machine drop frames (``partner_present_realtime``).

The clips: ``../shared/data/ut_interaction/set1`` (read its README). Nothing is tuned here; the
default picks every fifth clip of the 60 (12 clips, all six interaction classes), ``--clips all``
runs every one. Usage: ``python bench/real_video.py [--clips all|N] [--timeout S] [--reference K]``.
Last stdout line: one JSON object.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

REPO = Path(__file__).resolve().parents[1]
CLIPS = REPO.parent / "shared" / "data" / "ut_interaction" / "set1"


def clip_list(which: str) -> list[Path]:
    clips = sorted(CLIPS.glob("*.avi"), key=lambda p: int(p.stem.split("_")[0]))
    if which == "all":
        return clips
    return clips[:: max(1, len(clips) // int(which))][: int(which)]


def run_demo(clip: Path, out: Path, timeout: float, *extra: str) -> dict:
    """One ``counterpart demo --input clip``; its summary, exit code, wall time and whether it hung."""
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.monotonic()
    proc = subprocess.Popen([sys.executable, "-m", "bus.cli", "demo", "--input", str(clip), "--out", str(out), *extra],
                            cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        _, err = proc.communicate(timeout=timeout)
        hung = False
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, 9)
        _, err = proc.communicate()
        hung = True
    stats_file = out / "demo_stats.json"
    stats = json.loads(stats_file.read_text()) if stats_file.exists() and not hung else {}
    stats.pop("nodes", None)
    return {"code": proc.returncode, "hung": hung, "wall_s": round(time.monotonic() - t0, 1),
            "reason": err.strip().splitlines()[-1] if err.strip() else "", **stats}


def video_fps(out: Path) -> float:
    videos = [p for p in out.glob("demo.*") if p.suffix in (".mp4", ".avi")]
    if not videos:
        return 0.0
    cap = cv2.VideoCapture(str(videos[0]))
    fps = float(cap.get(cv2.CAP_PROP_FPS))
    cap.release()
    return fps


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--clips", default="12", help="'all' or how many clips, spread over the set (default 12)")
    ap.add_argument("--timeout", type=float, default=300.0, help="seconds a run may take before it counts as hung")
    ap.add_argument("--reference", type=int, default=3, help="clips also run through the real-time graph")
    args = ap.parse_args()
    if not CLIPS.is_dir():
        sys.exit(f"bench/real_video.py: {CLIPS} not found (the shared data, see ../shared/data/README.md)")
    clips = clip_list(args.clips)
    work = Path(tempfile.mkdtemp(prefix="cp-real-"))
    per_clip, hangs = {}, 0
    for i, clip in enumerate(clips):
        r = run_demo(clip, work / clip.stem, args.timeout)
        r["fps_video"] = video_fps(work / clip.stem)
        if i < args.reference:
            rt = run_demo(clip, work / f"{clip.stem}-rt", args.timeout, "--realtime")
            r["partner_present_realtime"] = rt.get("partner_present", 0.0)
            hangs += rt["hung"]
        hangs += r["hung"]
        per_clip[clip.stem] = r
        print(f"{clip.stem}: {json.dumps(r)}", file=sys.stderr, flush=True)
    short = {}
    for name, extra in (("1_frame", ["--frames", "1"]), ("5_frames", ["--frames", "5"]),
                        ("past_end", ["--set", "camera.start_frame=100000"])):
        r = run_demo(clips[0], work / f"short-{name}", min(args.timeout, 120.0), *extra)
        short[name] = {k: r.get(k) for k in ("code", "hung", "wall_s", "frames_in", "reason")}
        hangs += r["hung"]
        print(f"short {name}: {json.dumps(short[name])}", file=sys.stderr, flush=True)
    done = [r for r in per_clip.values() if not r["hung"] and r.get("frames_out")]
    pooled = sum(r["partner_drawn"] for r in done) / max(1, sum(r["frames_out"] for r in done))
    after = [r.get("partner_present_after_1s", 0.0) for r in per_clip.values()]
    ref = [r["partner_present_realtime"] for r in per_clip.values() if "partner_present_realtime" in r]
    result = {
        "clips": len(clips),
        "partner_present": round(pooled, 4),
        "partner_present_after_1s_median": round(float(np.median(after)), 4) if after else 0.0,
        "partner_present_after_1s_min": round(float(min(after)), 4) if after else 0.0,
        "clips_partner_95": sum(a >= 0.95 for a in after),
        "partner_present_realtime": round(float(np.mean(ref)), 4) if ref else None,
        "partner_present_lockstep_same_clips": round(float(np.mean(
            [r.get("partner_present", 0.0) for r in list(per_clip.values())[: len(ref)]])), 4) if ref else None,
        "hangs": hangs,
        "fps_match": sum(abs(r.get("fps_in", -1) - r["fps_video"]) < 0.01 and r.get("fps_in") == r.get("fps_out")
                         for r in per_clip.values()),
        "frames_with_people_share": round(sum(r.get("frames_with_people", 0) for r in done)
                                          / max(1, sum(r["frames_in"] for r in done)), 4),
        "wall_s_median": float(np.median([r["wall_s"] for r in per_clip.values()])),
        "short_inputs": short,
        "per_clip": {k: {f: r.get(f) for f in ("code", "frames_in", "partner_present", "partner_present_after_1s",
                                               "frames_with_people", "fps_in", "fps_video")}
                     for k, r in per_clip.items()},
    }
    print(json.dumps(result))


if __name__ == "__main__":
    main()
