"""The renderer node: draws the partner into each camera frame, writes a video, serves a live page.

Run in a graph (``run: counterpart.nodes.renderer``)::

    renderer:
      run: counterpart.nodes.renderer
      params: {video: out.mp4, serve: true, port: 8080, pose: true, stats_topics: [camera/stats]}

Inputs: ``frame`` (camera.Frame) always; ``partner`` (responder.Partner) unless ``partner: false``;
``silhouettes``, ``pose``, ``signals`` when their params are true; ``camera_info`` (camera.CameraInfo,
the calibration node's, latched; frames wait for it) unless ``camera_info: false``; one input per entry of
``stats_topics`` (system.NodeStats, port named like the topic, policy latest, not awaited at end).
Outputs: ``rendered`` (camera.Frame, the composited image, same stamp and seq as the frame) and
``control`` (control.Control, the controls in force as set on the web page; latched).

Pairing by seq, overlays and drawing are in :mod:`.compositor` and :mod:`.draw`; the video in
:mod:`.video`; the page in :mod:`.web`. The video is closed at end of stream and in teardown, so a
Ctrl-C leaves a playable file with every frame rendered so far.
"""

from __future__ import annotations

import queue
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from counterpart.body.camera import Camera, camera_from_info, camera_param_problem
from counterpart.bus import LATEST, RELIABLE, Input, Node, Output, Param, ParamError
from counterpart.messages import (
    EMOTIONS,
    INTERACTION_MODELS,
    INTEREST_LEVELS,
    SPEAKERS,
    CameraInfo,
    Control,
    Frame,
    NodeStats,
    Partner,
    Pose3D,
    Silhouettes,
    SocialSignals,
)

from .compositor import OVERLAYS, STYLES, Bundle, Compositor
from .controls import control_to_json, parse_control
from .video import VideoWriter, write_png
from .web import LiveServer, is_loopback

SIDE_INPUTS = {"silhouettes": Silhouettes, "pose": Pose3D, "signals": SocialSignals}
#: seconds between the timer's calls while no frame waits for its partner (at most pair_timeout):
#: how soon a control set on the web page takes effect
IDLE_PERIOD_S = 0.05
#: the timer's shortest period, seconds: the resolution of pair_timeout
MIN_PERIOD_S = 0.01
#: seconds the timer comes after a waiting frame's deadline: the loop's poll wakes to the
#: millisecond, and a call a little early would find the frame still waiting
DEADLINE_SLACK_S = 0.001
#: seconds of the stream at its start that the ``*_after_1s`` figures leave out
SETTLE_S = 1.0


def _check_video(value: str) -> str | None:
    if value and Path(value).suffix.lower() not in (".mp4", ".avi"):
        return f"{value!r}: use a .mp4 (H.264 where OpenCV has it, else Motion-JPEG .avi) or .avi file, or '' for none"
    return None


def _check_topics(value: list[Any]) -> str | None:
    bad = [t for t in value if not isinstance(t, str) or not t or t in ("frame", "partner", *SIDE_INPUTS)]
    if bad:
        return f"{bad}: each entry must be a stats topic name such as 'camera/stats'"
    if len(set(value)) != len(value):
        return f"{value}: a topic is listed twice"
    return None


class Renderer(Node):
    """Composites the partner and overlays into every frame; video file, live page and controls."""

    inputs = {"frame": Input(Frame, RELIABLE, "the camera frames: the renderer's clock")}
    outputs = {
        "rendered": Output(Frame, "the composited image of each frame (bgr8; the frame's stamp and seq)"),
        "control": Output(
            Control,
            "the run-time controls in force, set on the web page (latched: a node that "
            "joins or restarts later gets them)",
            latched=True,
        ),
    }
    params = {
        "partner": Param(bool, True, "subscribe to the partner (responder.Partner) and wait for it per frame"),
        "silhouettes": Param(bool, False, "subscribe to silhouettes (B-spline overlay, badge placement)"),
        "pose": Param(bool, False, "subscribe to the tracked 3D pose (skeleton overlay)"),
        "signals": Param(bool, False, "subscribe to social signals (badge overlay)"),
        "stats_topics": Param(
            list, [], "NodeStats topics to show, e.g. [camera/stats, tracker/stats]", check=_check_topics
        ),
        "video": Param(
            str,
            "",
            "output video: .mp4 (H.264, else written as .avi) or .avi (Motion-JPEG); '' none",
            check=_check_video,
        ),
        "fps": Param(
            float,
            0.0,
            "frame rate written into the video file (0: the input's, from the camera's "
            "frames; 25 when they do not say)",
            min=0.0,
            max=1000.0,
        ),
        "serve": Param(bool, False, "serve the live web page"),
        "host": Param(
            str, "127.0.0.1", "address of the web page; anything but loopback exposes the controls to the network"
        ),
        "port": Param(
            int, 8080, "port of the web page (0: any free port, logged and written to port_file)", min=0, max=65535
        ),
        "port_file": Param(str, "", "file to write the web page's port number to once it listens ('' none)"),
        "jpeg_quality": Param(int, 80, "JPEG quality of the live stream", min=10, max=100),
        "overlay_skeleton": Param(bool, True, "draw the tracked skeleton"),
        "overlay_splines": Param(bool, True, "draw the people's B-spline silhouettes"),
        "overlay_signals": Param(bool, True, "draw social-signal badges"),
        "overlay_stats": Param(bool, True, "draw per-node statistics"),
        "overlay_controls": Param(bool, True, "draw the controls in force (model, speaker, interest, emotion bar)"),
        "camera_info": Param(
            bool,
            True,
            "take the camera from topic camera_info (the calibration node, so that "
            "every node projects with the same one; frames wait for it); false: from 'camera'",
        ),
        "camera": Param(
            dict,
            {},
            "without camera_info only: calibration (counterpart.body.camera.Camera.to_dict or look-at "
            "form), scaled to a frame size of the same aspect ratio; empty: the default camera at the "
            "frame size",
            check=camera_param_problem,
        ),
        "style": Param(
            str,
            "auto",
            "partner drawing: cones (3D joints), silhouette (B-spline), avatar (the "
            "video-texture avatar's frames), auto",
            choices=STYLES,
        ),
        "avatar_file": Param(
            str, "", "avatar file of the video-texture partner ('': the one the partner message names)"
        ),
        "pair_timeout": Param(
            float,
            0.1,
            "seconds a frame waits for its partner at most (lockstep replay: long, "
            "so that every frame gets its own partner)",
            min=0.0,
        ),
        "adaptive_wait": Param(
            bool,
            True,
            "render at once, with the newest partner, while the recent partners "
            "came later than pair_timeout (waiting would only delay every frame)",
        ),
        "max_pending": Param(int, 128, "frames held waiting for partners at most", min=1, max=10000),
        "snapshot_every": Param(int, 0, "save every Nth rendered frame as PNG in snapshot_dir (0: never)", min=0),
        "snapshot_dir": Param(str, "", "folder of the PNG snapshots"),
        "models": Param(
            list,
            list(INTERACTION_MODELS),
            f"interaction models offered on the page, of {', '.join(INTERACTION_MODELS)}",
        ),
    }
    #: the timer's first period, seconds; then :meth:`on_timer` sets the next one
    timer_period = MIN_PERIOD_S

    @classmethod
    def validate_params(cls, given: dict[str, Any], where: str = "") -> dict[str, Any]:
        """The node's parameters, validated, with the checks that involve several of them.

        Parameters
        ----------
        given : dict
            The parameters as given.
        where : str, default=""
            Prefix of the error messages (e.g. the launch file and node).

        Returns
        -------
        dict
            Every parameter, defaults filled in.

        Raises
        ------
        ParamError
            If ``snapshot_every`` is set without ``snapshot_dir``, ``camera`` is given with
            ``camera_info``, or ``models`` names no known interaction model.
        """
        p = super().validate_params(given, where)
        prefix = f"{where}: " if where else ""
        if p["snapshot_every"] and not p["snapshot_dir"]:
            raise ParamError(f"{prefix}parameter 'snapshot_dir': needed when snapshot_every > 0")
        if p["camera_info"] and p["camera"]:
            raise ParamError(
                f"{prefix}parameter 'camera': the camera comes from topic camera_info; give the "
                "calibration file to the calibration node (calibration.file), or set camera_info: false"
            )
        if not p["models"] or not all(m in INTERACTION_MODELS for m in p["models"]):
            raise ParamError(
                f"{prefix}parameter 'models': expected a list of some of {', '.join(INTERACTION_MODELS)}, got {p['models']!r}"
            )
        return p

    @classmethod
    def ports(cls, params: dict[str, Any]) -> tuple[dict[str, Input], dict[str, Output]]:
        """The ports for the given parameters (see the module docstring).

        Parameters
        ----------
        params : dict
            The node's validated parameters.

        Returns
        -------
        inputs : dict of str to Input
            The input ports by name.
        outputs : dict of str to Output
            The output ports by name.
        """
        ins = dict(cls.inputs)
        if params["partner"]:
            ins["partner"] = Input(Partner, RELIABLE, "the partner of each frame (paired by seq)")
        for name, tp in SIDE_INPUTS.items():
            if params[name]:
                ins[name] = Input(tp, RELIABLE, f"{name} overlay (paired by seq)")
        if params["camera_info"]:
            # awaited to its end, as the tracker does: the frames' end can overtake the camera
            ins["camera_info"] = Input(CameraInfo, RELIABLE, "the graph's camera (latched)")
        for topic in params["stats_topics"]:
            ins[topic] = Input(NodeStats, LATEST, "statistics of a node", awaits_end=False)
        return ins, dict(cls.outputs)

    # ------------------------------------------------------------------------------ life cycle
    def setup(self) -> None:
        p = self.p
        overlays = {k: p[f"overlay_{k}"] for k in OVERLAYS}
        self.comp = Compositor(
            Camera.from_dict(p["camera"]) if p["camera"] else None,
            want_partner=p["partner"],
            style=p["style"],
            overlays=overlays,
            timeout=p["pair_timeout"],
            max_pending=p["max_pending"],
            adaptive=p["adaptive_wait"],
            wait_camera=p["camera_info"],
            avatar_file=p["avatar_file"],
        )
        self.video: VideoWriter | None = VideoWriter(p["video"], p["fps"]) if p["video"] else None
        self.controls: queue.Queue[Control] = queue.Queue()
        self.stats_ports = set(p["stats_topics"])
        self.finished = False
        # the timer wakes the loop for the frames whose wait for their partner is over: waking it
        # every MIN_PERIOD_S whether a frame waits or not cost more CPU (the loop's socket polls and
        # stats checks) than some of the drawing; between deadlines it only takes the controls
        self.idle_period = min(IDLE_PERIOD_S, max(p["pair_timeout"], MIN_PERIOD_S))
        self.last_seq = -1
        self.last_partner: Partner | None = None
        self.server: LiveServer | None = None
        if p["serve"]:
            if not is_loopback(p["host"]):
                self.log.warning("serving on %s: anyone who can reach it can watch and change the controls", p["host"])
            try:
                self.server = LiveServer(
                    p["host"], p["port"], self._on_web_control, self._state, self._stats, p["jpeg_quality"]
                ).start()
            except OSError as exc:  # a port in use (another demo's page, another program): said, not a crash
                raise ParamError(
                    f"parameter 'port': {exc}; choose another port (counterpart demo --port N), or 0 for any free one"
                ) from None
            self.log.info("live page at %s", self.server.url)
            if p["port_file"]:
                Path(p["port_file"]).write_text(f"{self.server.port}\n")

    def on_message(self, port: str, msg: Any) -> None:
        """Hand a message to the compositor, then render the frames that are ready.

        Parameters
        ----------
        port : str
            The input port it came on.
        msg : Any
            The message.
        """
        if port == "frame":
            self.comp.add_frame(msg)
        elif port == "partner":
            self.comp.add_partner(msg)
        elif port in SIDE_INPUTS:
            self.comp.add_side(port, msg)
        elif port == "camera_info":
            try:
                self.comp.set_camera(camera_from_info(msg), msg.seq, msg.undecided_from)
            except ValueError as exc:
                self.log.warning("camera_info dropped: %s", exc)
        elif port in self.stats_ports:
            self.comp.add_stats(msg)
            return
        self._render_ready()

    def on_timer(self) -> None:
        self._apply_controls()
        self._render_ready()
        # the next call: when the first waiting frame times out, at most the idle period away; the
        # idle period is at most pair_timeout, so a frame that arrives meanwhile is not overslept
        deadline = self.comp.next_deadline()
        wait = self.idle_period if deadline is None else deadline + DEADLINE_SLACK_S - time.monotonic()
        self.timer_period = min(self.idle_period, max(wait, DEADLINE_SLACK_S))

    def on_end(self) -> None:
        self._finish()

    def teardown(self) -> None:
        try:
            if not self.finished and hasattr(self, "comp"):
                self._finish(publish=False)  # Ctrl-C: what arrived still goes into the video
        finally:
            if getattr(self, "server", None) is not None:
                self.server.close()

    # ----------------------------------------------------------------------------------- work
    def _finish(self, publish: bool = True) -> None:
        self.finished = True
        self._apply_controls(publish)
        self._render_ready(flush=True, publish=publish)
        if self.video is not None:
            n = self.video.close()
            self.log.info("wrote %d frames to %s", n, self.video.path)
        c = self.comp.counts
        if self.p["partner"]:
            self.log.info(
                "rendered %d frames: partner exact %d, held %d, missing %d, forced by max_pending %d",
                c["rendered"],
                c["partner_exact"],
                c["partner_held"],
                c["partner_missing"],
                c["forced"],
            )

    def _render_ready(self, flush: bool = False, publish: bool = True) -> None:
        for b in self.comp.ready(time.monotonic(), flush=flush):
            self._output(b, self.comp.render(b), publish)

    def _output(self, b: Bundle, image: Any, publish: bool) -> None:
        f = b.frame
        if publish:
            self.publish(
                "rendered",
                Frame(
                    stamp=f.stamp, seq=f.seq, image=image, encoding="bgr8", source=f.source, source_time=f.source_time
                ),
            )
        if self.video is not None:
            self.video.write(image, f.fps)
            self.figures["video_fps"] = self.video.fps
        self.figures.update({k: float(v) for k, v in self.comp.counts.items()})
        self.figures.update(self.comp.sync.stats.figures())
        # the first second (background learnt, tracks started) is left out of the settled figures
        t = f.seq / f.fps if f.fps > 0 else f.source_time
        if t >= SETTLE_S:
            self.tally("rendered_after_1s")
            self.tally("partner_drawn_after_1s", self.comp.partner_drawn)
        if self.server is not None:
            self.server.push(image, f.seq)
        n = self.p["snapshot_every"]
        if n and self.comp.counts["rendered"] % n == 0:
            write_png(Path(self.p["snapshot_dir"]) / f"frame{f.seq:06d}.png", image)
        self.last_seq = f.seq
        self.last_partner = b.partner

    def _apply_controls(self, publish: bool = True) -> None:
        while True:
            try:
                msg = self.controls.get_nowait()
            except queue.Empty:
                return
            self.comp.set_control(msg)
            if publish:  # all the controls in force, so the latched copy alone restores them
                self.publish(
                    "control", replace(msg, **{k: v for k, v in self.comp.controls.as_dict().items() if v is not None})
                )

    # ------------------------------------------------------------------- web (server threads)
    def _on_web_control(self, data: Any) -> dict[str, Any]:
        msg = parse_control(data, self.p["models"])
        self.controls.put(
            Control(
                stamp=time.monotonic_ns(),
                seq=max(self.last_seq, 0),
                model=msg.model,
                speaker=msg.speaker,
                interest=msg.interest,
                emotion=msg.emotion,
                strength=msg.strength,
                overlays=msg.overlays,
            )
        )
        return control_to_json(msg)

    def _state(self) -> dict[str, Any]:
        return {
            "controls": self.comp.controls_shown(self.last_partner),
            "overlays": dict(self.comp.overlays),
            "models": list(self.p["models"]),
            "emotions": list(EMOTIONS),
            "speakers": list(SPEAKERS),
            "interest_levels": list(INTEREST_LEVELS),
            "seq": self.last_seq,
        }

    def _stats(self) -> dict[str, Any]:
        out = {}
        for node, s in sorted(dict(self.comp.stats).items()):
            ports = list(s.outputs) or list(s.inputs)
            out[node] = {
                "rate_hz": ports[0].rate_hz if ports else 0.0,
                "drops": sum(t.drops for t in s.inputs),
                "latency_ms": max((t.latency_ms for t in s.inputs), default=0.0),
                "proc_ms_mean": s.proc_ms_mean,
                "proc_ms_max": s.proc_ms_max,
                "uptime_s": s.uptime_s,
                "inputs": [
                    {
                        "topic": t.topic,
                        "rate_hz": t.rate_hz,
                        "count": t.count,
                        "drops": t.drops,
                        "latency_ms": t.latency_ms,
                    }
                    for t in s.inputs
                ],
                "outputs": [{"topic": t.topic, "rate_hz": t.rate_hz, "count": t.count} for t in s.outputs],
            }
        return out


NODE = Renderer

if __name__ == "__main__":
    Renderer.main()
