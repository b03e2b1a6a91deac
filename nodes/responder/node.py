"""The responder node: the observed person in, the generated partner out (``partner``, one per frame).

Inputs (each optional by parameter, so a graph without a tracker still validates): ``pose``
(tracker.Pose3D, ``use_pose``), ``silhouettes`` (silhouette.Silhouettes, ``use_silhouettes``),
``signals`` (labeller.SocialSignals, ``use_signals``), ``control`` (control.Control, latest
policy, a side input that does not hold the node open) and ``camera_info`` (camera.CameraInfo, the
calibration node's, ``camera_info``; a side input too: the partner stands across that camera's view,
clear of the observed person's silhouette in its picture). The model in force decides which input
drives the output: dual-hmm, gpdm, listener and video-texture produce one Partner per ``pose``
(listener, video-texture: per ``signals`` when there is no pose input), joint-shape one per
``silhouettes``; the others are
paired by ``seq`` (the latest of each kept; the silhouettes and signals of the pose's own frame). A
pose waits for its frame's silhouettes, for its signals where the model in force answers them
(listener, video-texture) and, in a lockstep graph, for the calibration node to decide its frame's
camera (``CameraInfo.undecided_from``), so that a replay answers every frame alike in every run.
Control messages switch model, speaker, interest, emotion and strength at run time; ``None``
fields leave a setting unchanged.
"""

from __future__ import annotations

import os
from collections import deque
from dataclasses import replace
from typing import Any

import numpy as np

from counterpart.body.camera import Camera, CameraSchedule, camera_from_info
from counterpart.bus import Input, Node, Output, Param, SeqHistory
from counterpart.messages import (
    EMOTIONS,
    INTERACTION_MODELS,
    INTEREST_LEVELS,
    SPEAKERS,
    CameraInfo,
    Control,
    Partner,
    Pose3D,
    Silhouettes,
    SocialSignals,
)

from .emotion import StyleFilter
from .model_clock import AtModelRate
from .reach import ReachConfig, reach
from .staging import BONES, Stage, StageConfig, observed_silhouette

#: frames per second assumed for poses that do not carry their source's rate
DEFAULT_FPS = 25.0
#: poses held back for their frame's silhouettes and camera at most (a node that sends neither
#: does not stop the partner): in lockstep the labeller's max_pending frames
MAX_HELD = 100


class Responder(Node):
    """Generates the partner with the selected interaction model."""

    inputs = {
        "pose": Input(Pose3D, doc="tracked 3D people"),
        "silhouettes": Input(Silhouettes, doc="people's B-spline silhouettes"),
        "signals": Input(SocialSignals, doc="the people's social signals"),
        "control": Input(Control, policy="latest", doc="run-time controls", awaits_end=False),
        # every refined camera is kept (they hold from their seq on); in real time the calibration
        # node sends few (in lockstep one a frame, on a reliable queue)
        "camera_info": Input(
            CameraInfo, policy="latest", queue=64, doc="the graph's camera (latched)", awaits_end=False
        ),
    }
    outputs = {"partner": Output(Partner, "the generated partner, one per frame of the driving input")}
    params = {
        "model": Param(str, "dual-hmm", "interaction model", choices=INTERACTION_MODELS),
        "model_file": Param(
            str,
            "default",
            "model file for the selected model, or 'default' (built from the "
            "simulator into ~/.cache/counterpart/models when missing)",
            check=lambda v: (
                None
                if v == "default" or os.path.isfile(v)
                else f"no model file {v!r}; make one with 'counterpart learn responder' (an avatar: 'counterpart "
                "learn avatar') or use 'default'"
            ),
        ),
        "use_pose": Param(bool, True, "subscribe to 'pose'"),
        "use_silhouettes": Param(bool, False, "subscribe to 'silhouettes'"),
        "use_signals": Param(bool, False, "subscribe to 'signals'"),
        "use_control": Param(bool, True, "subscribe to 'control'"),
        "camera_info": Param(
            bool,
            False,
            "subscribe to 'camera_info' (the calibration node's camera): the partner stands across that "
            "camera's view and, with use_silhouettes, clear of the observed person's silhouette in its picture; "
            "false: across the view of a camera looking along -Z with no yaw (the default camera's)",
        ),
        "speaker": Param(str, "person", "who speaks (listener model)", choices=SPEAKERS),
        "interest": Param(int, 3, "listener interest level", choices=INTEREST_LEVELS),
        "emotion": Param(str, "neutral", "partner emotion", choices=EMOTIONS),
        "strength": Param(float, 0.0, "emotion strength", min=0.0, max=1.0),
        "observed": Param(str, "left", "which person the partner responds to", choices=("left", "right")),
        "hold_frames": Param(
            int,
            15,
            "frames the partner stays where it was while the observed person is lost "
            "or missing (a tracker's dropout is not the person leaving); 0: it vanishes at once",
            min=0,
        ),
        "stage": Param(
            bool,
            True,
            "keep the 3D partner standing where a partner would: on the ground, "
            "between min_distance_m and max_distance_m from the observed person, moving at most "
            "max_speed_m_s (false: where the model puts it)",
        ),
        "min_distance_m": Param(
            float,
            0.5,
            "nearest the partner stands to the observed person (m, ground distance between the mid-hips)",
            min=0.0,
        ),
        "max_distance_m": Param(float, 1.2, "farthest the partner stands from the observed person (m)", min=0.0),
        "max_speed_m_s": Param(float, 2.5, "fastest the partner's placement moves (m/s)", min=0.01),
        "beside": Param(
            bool,
            True,
            "the partner stands beside the observed person across the camera's view, at their depth, on "
            "the real second person's side (else towards the middle of the picture); false: in the model's direction",
        ),
        "bones": Param(
            str,
            "observed",
            "the partner's bone lengths: the observed person's (one body of their build, drawn at their size "
            "beside them whatever the camera's error) or the model's as it generates them",
            choices=BONES,
        ),
        "contact_m": Param(
            float,
            0.2,
            "the observed person's reach (tracked arms, or their silhouette's extent with use_silhouettes) "
            "this near the partner's torso axis is a push (m)",
            min=0.0,
        ),
        "offer_m": Param(
            float,
            0.45,
            "a silhouette reaching this far towards the partner from its centre is a hand held out, which "
            "the partner takes when within its arm's reach (m; needs use_silhouettes)",
            min=0.0,
        ),
        "recoil_m": Param(
            float,
            0.3,
            "how far the partner gives way while the observed person pushes it (their hand on its chest, "
            "or their silhouette driving a hand held out into someone), the room it keeps for its recoil "
            "when the push is released (m, within max_distance_m; 0: it does not recoil)",
            min=0.0,
        ),
        "reach_m": Param(
            float,
            0.45,
            "the partner's hand that the model brings within this distance of the "
            "observed person's hand is pulled onto it (m; hand contact by inverse kinematics, "
            "complete at 0.1 m); 0: the model's hand as it is",
            min=0.0,
        ),
    }

    @classmethod
    def ports(cls, params: dict[str, Any]) -> tuple[dict[str, Input], dict[str, Output]]:
        """The ports: each input only with its ``use_*`` parameter on.

        Parameters
        ----------
        params : dict
            Validated parameters.

        Returns
        -------
        inputs : dict of str to Input
            The input ports.
        outputs : dict of str to Output
            The output ports.
        """
        use = {
            "pose": params["use_pose"],
            "silhouettes": params["use_silhouettes"],
            "signals": params["use_signals"],
            "control": params["use_control"],
            "camera_info": params["camera_info"],
        }
        return {k: v for k, v in cls.inputs.items() if use[k]}, dict(cls.outputs)

    def setup(self) -> None:
        """Load the selected model and the emotion model, and set up staging and reaching.

        Raises
        ------
        SystemExit
            For staging or reach parameters the stage or reach configuration refuses.
        """
        self.models: dict[str, Any] = {}
        self.model = self.p["model"]
        self.speaker, self.interest = self.p["speaker"], self.p["interest"]
        self.emotion, self.strength = self.p["emotion"], self.p["strength"]
        self._load(self.model, self.p["model_file"])
        # the emotion model is small and built in seconds; load it up front so control switches are instant
        self.style = StyleFilter(self._model("emotion"))
        self.latest: dict[str, Any] = {}
        self.count = 0
        self.last: Partner | None = None  # the last partner that responded to someone
        self.stage: Stage | None = None
        self.reach: ReachConfig | None = None
        try:
            if self.p["stage"]:
                self.stage = Stage(
                    StageConfig(
                        self.p["min_distance_m"],
                        self.p["max_distance_m"],
                        self.p["max_speed_m_s"],
                        contact_m=self.p["contact_m"],
                        recoil_m=self.p["recoil_m"],
                        beside=self.p["beside"],
                        offer_m=self.p["offer_m"],
                        bones=self.p["bones"],
                    )
                )
            if self.p["reach_m"] > 0:
                self.reach = ReachConfig(r_engage=self.p["reach_m"])
        except ValueError as e:
            raise SystemExit(f"responder: {e}; set responder.min_distance_m, max_distance_m or reach_m") from None
        self._unseen: set[str] = set()  # styles the gpdm model never saw, already reported
        self.cameras = CameraSchedule()  # the graph's cameras from camera_info, each from its seq on
        self._view: tuple[int, int] | None = None  # the frame size of the newest camera_info
        self._rate: AtModelRate | None = None  # the model stepped on its own frames; None: afresh on the next
        self.held: deque[Pose3D] = deque()  # poses waiting for their frame's silhouettes and camera
        # the silhouettes and signals by seq, for each pose its own frame's: from the last pose
        # answered on (a lockstep tracker may hold its poses many frames behind them)
        self.silhouettes = SeqHistory(MAX_HELD + 64)
        self.signals = SeqHistory(MAX_HELD + 64)

    # ------------------------------------------------------------------ models
    def _load(self, name: str, file: str = "default") -> Any:
        from .models import load_default, load_model

        if name not in self.models:
            self.log.info("loading model %s (%s)", name, file)
            self.models[name] = load_default(name) if file == "default" else load_model(file, expected=name)
        return self.models[name]

    def _model(self, name: str) -> Any:
        try:
            return self._load(name)
        except (ValueError, FileNotFoundError) as e:
            self.log.error("model %s unavailable: %s", name, e)
            return None

    # ------------------------------------------------------------------ inputs
    def on_control(self, msg: Control) -> None:
        """Apply a run-time control; its None fields leave their settings unchanged.

        Parameters
        ----------
        msg : Control
            The control; a model that cannot be loaded is logged and not switched to.
        """
        # every name in a Control is one of the contract's (the message refuses others when made
        # or decoded), and every one of them is a setting of this node
        if msg.model is not None and self._model(msg.model) is not None:
            self.model = msg.model
            self.models[msg.model].reset()
            self._reset_stage()
            self._rate = None
        if msg.speaker is not None:
            self.speaker = msg.speaker
        if msg.interest is not None:
            self.interest = msg.interest
        if msg.emotion is not None:
            self.emotion = msg.emotion
        if msg.strength is not None:
            self.strength = float(msg.strength)
        self.log.info(
            "control: model=%s speaker=%s interest=%d emotion=%s strength=%.2f",
            self.model,
            self.speaker,
            self.interest,
            self.emotion,
            self.strength,
        )

    def on_camera_info(self, msg: CameraInfo) -> None:
        """Keep the graph's camera (a refined one holds from its seq on).

        Parameters
        ----------
        msg : CameraInfo
            The camera; one that cannot be read is dropped with a warning, and the last one holds.
        """
        try:
            camera = camera_from_info(msg)
        except ValueError as exc:
            self.log.warning("camera_info dropped: %s", exc)
            return
        self.cameras.add(camera, msg.seq, msg.undecided_from)
        self._view = (camera.width, camera.height)
        self._release()

    def _camera(self, seq: int) -> Camera | None:
        """The graph's camera for frame ``seq``; None before any camera_info came."""
        return None if self._view is None else self.cameras.get(self._view, seq)

    def _reset_stage(self) -> None:
        if self.stage is not None:
            self.stage.reset()

    def _scene(self, body: Any, seq: int) -> dict[str, Any]:
        """What the stage knows of the scene besides the observed ``body`` (a TrackedBody) on frame
        ``seq``: the real second person tracked in the same poses, the side to stand on (towards the
        middle of the picture), the observed person's silhouette extent towards the partner and its
        box, and the graph's camera.
        """
        people = list(getattr(self.latest.get("pose"), "people", ()))
        other = next((q for q in people if q.id != body.id and not q.lost and np.shape(q.joints) == (14, 3)), None)
        side = {"left": 1.0, "right": -1.0}.get(body.side, 0.0)
        silhouettes = self.silhouettes.at_or_before(seq)
        direction = (self.stage.side if self.stage is not None else 0.0) or side
        camera = self._camera(seq)
        silhouette, box = observed_silhouette(
            list(getattr(silhouettes, "people", ())),
            body.id,
            body.side,
            body.joints,
            direction,
            camera,
            int(getattr(silhouettes, "height", 0)),
        )
        return {
            "other": None if other is None else np.asarray(other.joints),
            "side": side,
            "silhouette": silhouette,
            "camera": camera,
            "box": box,
        }

    def _at_model_rate(self, m: Any, step: Any, observed: np.ndarray | None, driver: Any) -> Any:
        """The model ``m``'s output for this input frame, ``step`` (observed joints in, partner out)
        run on the model's own frames since the last input (:class:`AtModelRate`).
        """
        if self._rate is None:
            self._rate = AtModelRate.for_model(m, DEFAULT_FPS)
        return self._rate(step, observed, driver.seq / float(getattr(driver, "fps", 0.0) or DEFAULT_FPS))

    def _staged(self, body: Any, joints: np.ndarray, driver: Any) -> np.ndarray:
        """The model's partner moved to where a partner stands beside the observed ``body`` (``stage``)
        and its hand onto the observed hand it comes near or that is held out (``reach_m``), its arms
        drawn in while pushed, clear of the person in the picture (``Stage.finish``); counted when they act.
        """
        pull = 0.0
        if self.stage is not None:
            fps = float(getattr(driver, "fps", 0.0) or DEFAULT_FPS)
            gap = driver.seq - self.last.seq if self.last is not None and self.last.seq < driver.seq else 1
            before = self.stage.corrected, self.stage.pushes
            joints = self.stage(body.joints, joints, gap / fps, **self._scene(body, driver.seq))
            if self.stage.corrected > before[0]:
                self.tally("partner_placed")
            if self.stage.pushes > before[1]:
                self.tally("pushes")
            # its arms (guarding while pushed, else the hand contact with the hand offered), kept clear last
            joints, pull = self.stage.finish(body.joints, joints, self.reach)
        elif self.reach is not None:
            joints, pull = reach(body.joints, joints, self.reach)
        if pull > 0:
            self.tally("hand_reached")
        return joints

    def _avatar(self, texture: Any, listener: Any, driver: Any) -> dict[str, Any]:
        """The video-texture avatar's Partner fields, driven by the listener rules
        (:func:`counterpart.nodes.responder.avatar_driver.avatar_partner`) on the listener's frames.
        """
        from .avatar_driver import avatar_partner
        from .models import default_model_path

        body = self._pick(list(self.latest["pose"].people)) if "pose" in self.latest else None
        signals = self.signals.at_or_before(driver.seq)
        who = self._pick(list(signals.people)) if signals is not None else None
        heard = {} if who is None else {n: bool(v == 1) for n, v in zip(who.names, np.asarray(who.labels))}
        file = (
            self.p["model_file"]
            if self.p["model"] == "video-texture" and self.p["model_file"] != "default"
            else default_model_path("video-texture")
        )
        fields = dict(
            self._at_model_rate(
                listener,
                lambda x: avatar_partner(
                    texture, listener, heard, x, self.speaker, self.interest, os.path.abspath(file)
                ),  # the renderer may run from another folder
                None if body is None else body.joints,
                driver,
            )
        )  # a copy: the model's output may be held for the next frame
        if body is not None:  # the avatar stands where a partner stands, as the listener's body does
            fields["joints"] = self._staged(body, fields["joints"], self.latest["pose"])
        return dict(fields, observed_id=-1 if body is None else body.id)

    def _gpdm_style(self, m: Any) -> None:
        """Set the gpdm's style variables from the emotion and strength; a style the model never saw
        is reported once and generated as neutral.
        """
        try:
            m.set_style(self.emotion, self.strength)
        except ValueError as e:
            if self.emotion not in self._unseen:
                self._unseen.add(self.emotion)
                self.log.warning("%s; generating neutral", e)
            m.set_style("neutral", 0.0)

    def _pick(self, people: list[Any]) -> Any:
        if not people:
            return None
        side = [p for p in people if getattr(p, "side", "") == self.p["observed"]]
        return side[0] if side else people[0]

    def on_pose(self, msg: Pose3D) -> None:
        """Keep the latest poses; they drive the 3D models' partner (once :meth:`_release` lets them).

        Parameters
        ----------
        msg : Pose3D
            Tracked 3D people.
        """
        self.held.append(msg)
        self._release()

    def _release(self, end: bool = False) -> None:
        """Answer the poses held back, in order, as far as each has what its partner depends on:
        its frame's silhouettes (with ``use_silhouettes``), its signals (with ``use_signals``, for
        the models that answer them) and, in lockstep, its frame's camera decided
        (``CameraSchedule.decided``); at the ``end``, or beyond ``MAX_HELD``, whatever has come.
        Every run of a lockstep replay then answers each frame with the same inputs.
        """
        while self.held:
            seq = self.held[0].seq
            signals = "signals" in self._in and self.model in ("listener", "video-texture")
            ready = (
                (self._view is None or self.cameras.decided(self._view, seq))
                and ("silhouettes" not in self._in or self.silhouettes.max_seq >= seq)
                and (not signals or self.signals.max_seq >= seq)
            )
            if not (ready or end or len(self.held) > MAX_HELD):
                return
            msg = self.held.popleft()
            self.latest["pose"] = msg
            if self.model in ("dual-hmm", "listener", "video-texture", "gpdm"):
                self._emit(msg)
            self.silhouettes.forget_before(msg.seq)
            self.signals.forget_before(msg.seq)

    def on_end(self) -> None:
        """Answer the poses still held back."""
        self._release(end=True)

    def on_silhouettes(self, msg: Silhouettes) -> None:
        """Keep the silhouettes by seq (each pose's own frame's); they drive the joint-shape model's partner.

        Parameters
        ----------
        msg : Silhouettes
            The people's B-spline silhouettes.
        """
        self.silhouettes.add(msg)
        if self.model == "joint-shape":
            self._emit(msg)
        self._release()

    def on_signals(self, msg: SocialSignals) -> None:
        """Keep the social signals by seq; they drive the listener and video-texture models' partner when
        the node has no pose input.

        Parameters
        ----------
        msg : SocialSignals
            The people's social signals.
        """
        self.signals.add(msg)
        if self.model in ("listener", "video-texture") and "pose" not in self._in:
            self._emit(msg)
        self._release()

    # ------------------------------------------------------------------ output
    def _emit(self, driver: Any) -> None:
        """One Partner per driving message; an empty one (no joints, no ctrl) when there is nobody to
        respond to, so that downstream nodes pairing by seq never wait for a partner that won't come.
        """
        out = dict(
            model=self.model,
            emotion=self.emotion,
            strength=self.strength,
            speaker=self.speaker,
            interest=self.interest,
        )

        def nobody() -> None:
            last = self.last
            if last is not None and 0 < driver.seq - last.seq <= self.p["hold_frames"] and last.model == self.model:
                self.tally("partner_held")  # counted: the partner holds through the observed person's dropout
                self.publish("partner", replace(last, stamp=driver.stamp, seq=driver.seq, behaviour="hold"))
                return
            self.tally("partner_none")
            self.publish("partner", Partner(stamp=driver.stamp, seq=driver.seq, behaviour="none", **out))

        m = self._model(self.model)
        if m is None:
            return nobody()
        if self.model in ("dual-hmm", "gpdm"):
            body = self._pick(list(driver.people))
            if body is None or body.lost or np.asarray(body.joints).shape != (14, 3):
                return nobody()
            if self.last is not None and self.last.observed_id != body.id:
                # another person than the one answered so far: the model's state belongs to that one
                m.reset()
                self._reset_stage()
                self._rate = None
                self.tally("observed_switches")
            if self.model == "gpdm":  # the style is the model's own input (Taubert et al.), not a filter
                self._gpdm_style(m)
            joints = self._staged(body, self._at_model_rate(m, m.step, body.joints, driver), driver)
            if self.model == "dual-hmm":
                joints = self.style(joints, self.emotion, self.strength)
            out.update(joints=joints, observed_id=body.id, behaviour="respond", confidence=float(np.max(m.posterior_)))
        elif self.model == "listener":
            m.interest = self.interest
            sig = self.signals.at_or_before(driver.seq)
            body = self._pick(list(self.latest["pose"].people)) if "pose" in self.latest else None
            person = self._pick(list(sig.people)) if sig is not None else None  # the newest signals
            speaking = {}
            if person is not None and self.speaker == "person":
                speaking = {n: bool(v == 1) for n, v in zip(person.names, np.asarray(person.labels))}
            joints = self._at_model_rate(
                m, lambda x: m.step(speaking, x), None if body is None else body.joints, driver
            )
            if body is not None and np.shape(joints) == (14, 3):
                joints = self._staged(body, joints, self.latest["pose"])
            out.update(
                joints=self.style(joints, self.emotion, self.strength),
                observed_id=-1 if body is None else body.id,
                behaviour=m.behaviour_ or "listen",
                confidence=1.0,
            )
        elif self.model == "video-texture":
            lm = self._model("listener")
            if lm is None:
                return nobody()
            out.update(self._avatar(m, lm, driver))
        else:  # joint-shape
            shape = self._pick(list(driver.people))
            if shape is None or shape.height <= 0:
                return nobody()
            ctrl = m.step(shape.ctrl, shape.height, shape.centroid, mirrored=shape.side == "right")
            out.update(ctrl=ctrl, observed_id=shape.id, behaviour=f"b{m.mode_}", confidence=m.confidence_)
        self.last = Partner(stamp=driver.stamp, seq=driver.seq, **out)
        self.publish("partner", self.last)
        self.count += 1
