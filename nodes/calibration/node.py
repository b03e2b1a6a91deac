"""The calibration node: the one camera of the graph, on ``camera_info`` (camera.CameraInfo, latched).

Frames in (their size), CameraInfo out: once for the first frame, and again when the frames change
size. The camera is the calibration ``file`` (JSON or YAML, ``Camera.to_dict`` or the look-at form),
scaled to the frames' size where they have its aspect ratio, or, without a file, the default camera
at the frames' size (``counterpart.body.camera.camera_for_size``).

With ``estimate: true`` and no file (the launch files set it) the node also takes the silhouette
node's people and estimates the camera from them and from the straight lines of the scene
(``counterpart.nodes.calibration.estimate``: focal length, tilt, roll and height from the heads and feet of
upright people against a prior on human height; on a frame where the silhouettes hold no upright
person, as when people standing still are absorbed into the background, from the people
detector's boxes and, where it finds no one, the bodies grown from where the frames changed
(``counterpart.nodes.calibration.still``), on ``detect_frames`` frames at most; with ``fov_deg``, the camera's horizontal field
of view where the user knows it, the focal length is held near it). Until an estimate is credible (people seen over
``min_seconds``; uncertainties under the ``max_*_std`` bounds; the estimates from the two halves
of the window near the whole's, ``max_split_*``; the horizon seen, by people at different depths or by scene lines
converging on it) the default camera stays; then the published
camera moves towards the estimate, re-estimated every ``every`` frames, by a bounded step a frame
(``max_step``: never a jump), with ``source: estimated`` and the seq of the frame it holds from
(``lead`` frames after the frame it was estimated on: every subscriber switches at that frame,
however late the message reaches it). With ``lockstep`` (launch/lockstep.yaml) it also says on every
frame from which seq the camera is not decided yet (``CameraInfo.undecided_from``), and the tracker, the
renderer and the responder hold each frame until then: however far behind the others this node
runs (the people detector on its first frames is slow), every frame gets the same camera in every
run, so a lockstep replay stays deterministic; at the end it says that the last camera holds for
every later frame. There, too, the first frames' camera waits for the first credible estimate
(``wait_frames``): one that comes within them holds from the first frame, so a recording replayed
is seen with its own camera from its start, not with the default one and then steps towards it.
With ``cpu_share``
(the real-time graph) the estimates take that share of a core on average after ``cpu_burst_s``, and
between them the camera goes on stepping towards the last credible one; with ``refit_growth``, until
the first credible estimate one is due whenever the people observed have grown by that share, the
share left aside (``pacing``). The tracker, the renderer
and the responder subscribe to it, so the skeleton, the partner and the tracked body are all
projected with the same camera; the tracker's tracks go on through a refined camera. Run in a graph (``run:
counterpart.nodes.calibration``) or alone::

    python -m counterpart.nodes.calibration --param file=camera.yaml
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from counterpart.body.camera import Camera, camera_for_size, camera_to_info, load_camera_file
from counterpart.body.people_detector import PeopleDetector
from counterpart.bus import Input, Node, Output, Param
from counterpart.messages import CameraInfo, Frame, Silhouettes

from .estimate import CalibrationConfig, CameraEstimate
from .observe import PeopleObservations, SceneFrames
from .pacing import EstimatePacing, PacingConfig
from .smooth import CameraSmoother, credible


def _check_file(value: str) -> str | None:
    if not value:
        return None
    try:
        load_camera_file(value)
    except ValueError as exc:
        return str(exc)
    return None


def _check_fov(value: float) -> str | None:
    if value and not value > 1.0:
        return f"{value!r}: a horizontal field of view in degrees, over 1 (0: unknown)"
    return None


class Calibration(Node):
    """Publishes the camera of the frames' size, latched, so that nodes joining later get it too;
    with ``estimate``, refines it from the people in view.
    """

    inputs = {
        "frame": Input(Frame, doc="the camera's frames (their size)"),
        "silhouettes": Input(Silhouettes, doc="the people in view (estimate: true, no file only)"),
    }
    outputs = {
        "camera_info": Output(
            CameraInfo,
            "the camera for the frames' size, once (again when the size changes or the estimate moves); latched",
            latched=True,
        )
    }
    params = {
        "file": Param(
            str,
            "",
            "calibration file (JSON/YAML: fx, fy, cx, cy, width, height, R, t, or eye, "
            "target, fov_deg, width, height); '': the default camera at the frames' size",
            check=_check_file,
        ),
        "estimate": Param(
            bool,
            False,
            "without a file: estimate the camera from the people in view "
            "(subscribes to silhouettes) and refine it while the graph runs",
        ),
        "fov_deg": Param(
            float,
            0.0,
            "estimate: the camera's horizontal field of view in degrees where known (its spec sheet); "
            "the focal length is then kept within about 5% of it; 0: unknown, estimated",
            min=0.0,
            max=169.9,
            check=_check_fov,
        ),
        "every": Param(int, 10, "estimate: frames between two estimates", min=1),
        "cpu_share": Param(
            float,
            0.0,
            "estimate: share of one core the estimates may take on average (after cpu_burst_s at "
            "once); an estimate due beyond it waits (counted as estimates_deferred); 0: no limit "
            "(a lockstep replay stays deterministic)",
            min=0.0,
            max=1.0,
        ),
        "cpu_burst_s": Param(float, 3.0, "estimate: CPU seconds the first estimates may take at once", min=0.0),
        "refit_growth": Param(
            float,
            0.0,
            "estimate: until the first credible estimate, a new one is due whenever the people observed "
            "have grown by this share since the last, whatever cpu_share has spent (then cpu_share, with "
            "a fresh burst); 0: cpu_share from the start",
            min=0.0,
        ),
        "lockstep": Param(
            bool,
            False,
            "estimate: publish on every frame the seq from which the camera is not decided yet, so that the "
            "nodes using it hold each frame until its camera is (a lockstep replay stays deterministic "
            "however far behind this node runs); for graphs in which every frame's silhouettes come",
        ),
        "wait_frames": Param(
            int,
            45,
            "lockstep: while no estimate is credible, only the frames this far behind the newest "
            "silhouettes get the default camera, so a first estimate within them holds from the first "
            "frame (the nodes using the camera hold them meanwhile: fewer than their max_pending); "
            "0: the default camera from the first frame",
            min=0,
        ),
        "lead": Param(
            int,
            25,
            "estimate: a refined camera holds from this many frames after the frame it "
            "was estimated on (its seq), so every node switches at that same frame",
            min=0,
        ),
        "min_seconds": Param(float, 1.0, "estimate: seconds of people in view before the first estimate", min=0.0),
        "max_step": Param(
            float,
            0.03,
            "estimate: largest change of focal length and height from one frame's camera to the "
            "next (relative; tilt and roll: this many radians)",
            min=1e-4,
            max=1.0,
        ),
        "max_height_std": Param(float, 0.15, "estimate: used only when the height's relative std is below", min=0.0),
        "max_focal_std": Param(float, 0.2, "estimate: ... and the focal length's relative std", min=0.0),
        "max_tilt_std_deg": Param(float, 3.0, "estimate: ... and the tilt's std, degrees", min=0.0),
        "min_depth_spread": Param(
            float,
            0.12,
            "estimate: ... and the people seen at depths this much apart "
            "(relative; at one depth the horizon does not show), or",
            min=0.0,
        ),
        "min_horizon_segments": Param(
            int, 12, "estimate: ... this many scene segments converging on the horizon", min=0
        ),
        "max_split_height": Param(
            float,
            0.10,
            "estimate: ... and the estimates from the two halves of the window (and the people's pull "
            "off the scene's lines) within this of the whole: log height",
            min=0.0,
        ),
        "max_split_tilt_deg": Param(float, 1.5, "estimate: ... tilt, degrees", min=0.0),
        "max_split_focal": Param(float, 0.20, "estimate: ... log focal length", min=0.0),
        "detect_frames": Param(
            int,
            60,
            "estimate: on a frame whose silhouettes hold no upright person (people absorbed into the "
            "background), the people detector's boxes give the heads and feet, and where it finds no "
            "one the bodies grown from where the frames changed, on this many frames at most (about "
            "0.15-0.3 s of one core each); 0: never",
            min=0,
        ),
    }

    @classmethod
    def ports(cls, params: dict[str, Any]) -> tuple[dict[str, Input], dict[str, Output]]:
        """The ports for the given parameters: ``silhouettes`` only when estimating without a file.

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
        estimating = params["estimate"] and not params["file"]
        return {k: v for k, v in cls.inputs.items() if k != "silhouettes" or estimating}, dict(cls.outputs)

    def setup(self) -> None:
        self.calibration: Camera | None = load_camera_file(self.p["file"]) if self.p["file"] else None
        self.size: tuple[int, int] | None = None
        self.observations: PeopleObservations | None = None
        self.smoother: CameraSmoother | None = None
        self.latest: CameraEstimate | None = None
        self.n_sil = 0
        #: lockstep: the camera goes out on every frame with the first seq it does not decide yet
        self.promising = self.p["lockstep"] and self.p["estimate"] and not self.p["file"]
        self.last: tuple[int, int] = (0, 0)  # the newest silhouettes' (stamp, seq)
        self.first_seq = 0  # the first frame of this size
        self.undecided = 0  # lockstep: the first frame whose camera is not decided yet
        self.published: Camera | None = None  # the camera last published, and where it came from
        self.source = ""
        self.fps = 0.0  # the frames' rate (their fps field): the people's times are the stream's
        self.scene = SceneFrames()
        self.pacing = self._pacing()
        self.observed = 0  # views of upright people observed on frames of this size
        #: frames kept for the scene's lines and the people detector until their people come (seq -> image)
        self.images: dict[int, np.ndarray] = {}
        self.detector = PeopleDetector() if self.p["estimate"] and self.p["detect_frames"] else None
        fov = self.p["fov_deg"]
        self.config = CalibrationConfig().with_known_fov(fov) if fov else CalibrationConfig()

    def _pacing(self) -> EstimatePacing:
        return EstimatePacing(PacingConfig(self.p["cpu_share"], self.p["cpu_burst_s"], self.p["refit_growth"]))

    def on_frame(self, msg: Frame) -> None:
        """Publish the camera when the frames change size; keep the frames the scene's lines need.

        Parameters
        ----------
        msg : Frame
            A frame of the camera (its size, fps and image).
        """
        self.fps = float(msg.fps or 0.0)
        shape = msg.image.shape
        size = (int(shape[1]), int(shape[0])) if len(shape) >= 2 else (0, 0)
        if size != self.size and min(size) > 0:
            self._new_size(size, msg.stamp, msg.seq)
        detecting = self.detector is not None and (
            self.observations is None or self.observations.detections_run < self.observations.max_detections
        )
        if self.p["estimate"] and not self.p["file"] and (self.scene.wants(msg.seq) or detecting):
            self.images[msg.seq] = msg.image
            for old in sorted(self.images)[:-40]:
                del self.images[old]

    def _new_size(self, size: tuple[int, int], stamp: int, seq: int) -> None:
        try:
            camera = camera_for_size(self.calibration, *size)
        except ValueError as exc:
            # a file for frames of another shape: no camera to agree on, so nothing can go on. Leaving
            # before this first message is handled makes it a failure to start: the launcher ends the
            # whole graph at once with this exit code (ending cleanly, its subscribers would wait)
            self.log.error("parameter 'file': %s", exc)
            raise SystemExit(2) from None
        self.size = size
        self.observations = PeopleObservations(*size, max_detections=self.p["detect_frames"])
        self.scene = SceneFrames()
        self.pacing = self._pacing()
        self.observed = 0
        self.smoother = CameraSmoother(camera, self.p["max_step"])
        self.published, self.source = camera, f"file:{self.p['file']}" if self.p["file"] else "default"
        # a refined camera holds from lead frames after the silhouettes it was estimated on at the
        # soonest, so the frames before then keep this one whatever comes; unless the first frames
        # wait for the first estimate
        self.first_seq = seq
        self.undecided = seq + (0 if self._waiting() else self.p["lead"])
        self.publish(
            "camera_info", camera_to_info(camera, stamp, seq, self.source, self.undecided if self.promising else -1)
        )
        self.log.info(
            "camera for %dx%d frames (%s): f %.1f px, centre %.1f m above the ground",
            *size,
            self.source,
            camera.fx,
            camera.centre[1],
        )

    def on_silhouettes(self, msg: Silhouettes) -> None:
        """Gather the frame's people, and every ``every`` frames publish the camera moved towards a
        credible estimate.

        Parameters
        ----------
        msg : Silhouettes
            The people in view of one frame, with the frame's size.
        """
        size = (int(msg.width), int(msg.height))
        if min(size) <= 0:
            return
        if size != self.size:
            self._new_size(size, msg.stamp, msg.seq)
        assert self.observations is not None and self.smoother is not None
        # stream time, not the capture stamps: a file replayed in lockstep is read faster or slower
        # than it was filmed, and "seconds of people in view" means seconds of the video
        time_s = msg.seq / self.fps if self.fps > 0 else msg.stamp * 1e-9
        labels = msg.labels if np.shape(msg.labels) == (size[1], size[0]) else None
        added = self.observations.add(msg.people, time_s, labels)
        image = self.images.pop(msg.seq, None)
        if image is not None and image.shape[:2] != (size[1], size[0]):
            image = None
        if image is not None:
            added += self.observations.add_frame(image, time_s, added, self.detector)
        self.tally("people_observed", added)
        self.observed += added
        if image is not None and self.scene.wants(msg.seq):
            self.scene.add(image, msg.people)
        self.n_sil += 1
        self.last = (msg.stamp, msg.seq)
        self._step_towards(self._refine(time_s), msg)

    def _refine(self, time_s: float) -> CameraEstimate | None:
        """Estimate the camera every ``every`` frames (the CPU share allowing); the estimate the
        published camera steps towards on this frame (None: it stays).
        """
        assert self.observations is not None
        if self.n_sil % self.p["every"] or self.observations.span_s < self.p["min_seconds"]:
            # the published camera goes on towards the last credible estimate a bounded step a frame:
            # from the default camera, far from a real one (several times lower, say), a step every
            # few frames would take minutes, the people drawn meanwhile at another camera's size
            return self.latest
        if not self.pacing.due(time_s, self.observed):
            self.tally("estimates_deferred")
            return self.latest
        cpu0 = time.thread_time()
        est = self.observations.estimate(self.config, lines=self.scene.families())
        self.pacing.spend(time.thread_time() - cpu0, self.observed)
        if est is None or not credible(
            est,
            self.p["max_height_std"],
            self.p["max_focal_std"],
            self.p["max_tilt_std_deg"],
            self.p["min_depth_spread"],
            self.p["min_horizon_segments"],
            (self.p["max_split_height"], self.p["max_split_tilt_deg"], self.p["max_split_focal"]),
            self.config,
        ):
            self.tally("estimates_not_credible")
            self.log.debug(
                "estimate not credible yet: %s", est.describe() if est else f"{len(self.observations)} observations"
            )
            return None
        if self.latest is None:
            self.log.info("first estimate (frame %d): %s", self.last[1], est.describe())
            self.pacing.credible(time_s)
        self.latest = est
        self.tally("estimates")
        return est

    def _waiting(self) -> bool:
        """Whether the first frames' camera still waits for the first credible estimate (lockstep)."""
        return self.promising and self.p["wait_frames"] > 0 and self.source == "default"

    def _step_towards(self, est: CameraEstimate | None, msg: Silhouettes) -> None:
        """Publish the camera a bounded step nearer ``est`` from ``lead`` frames on, when it moves;
        in lockstep on every frame, with the first seq it does not decide: while the first frames
        wait for the first estimate (``wait_frames``), that estimate itself from the first frame
        when none is decided yet, else a step from the first frame that is not.
        """
        assert self.smoother is not None and self.published is not None
        waiting = self._waiting()
        from_seq = msg.seq + self.p["lead"]
        if est is not None and waiting and self.undecided == self.first_seq:
            # no frame's camera decided yet: the estimate is every frame's, no step from the default
            self.smoother = CameraSmoother(est.camera(), self.p["max_step"])
            camera, moved, from_seq = self.smoother.camera, True, self.first_seq
        else:
            before = self.smoother.params
            camera = self.smoother.step(est) if est is not None else self.published
            moved = not np.array_equal(before, self.smoother.params)
            if moved and waiting:
                from_seq = self.undecided
        if moved:
            self.published, self.source = camera, "estimated"
            self.figures.update(
                {
                    "focal_px": camera.fx,
                    "height_m": float(camera.centre[1]),
                    "tilt_deg": float(np.degrees(np.arcsin(-camera.R[2, 1]))),
                }
            )
        decided = self.undecided
        if self.promising:
            if waiting and not moved:
                # the default camera for the frames wait_frames behind, said as holding from the
                # last of them, before any frame a first estimate could hold from
                self.undecided = max(self.undecided, msg.seq + 1 - self.p["wait_frames"])
                from_seq = self.undecided - 1
            else:
                self.undecided = max(self.undecided, msg.seq + self.p["lead"] + 1)
        if moved or self.undecided > decided:
            self._publish(msg.stamp, from_seq)

    def _publish(self, stamp: int, from_seq: int, final: bool = False) -> None:
        """The published camera from ``from_seq`` on; in lockstep, with the first frame it does not
        decide, unless ``final``.
        """
        assert self.published is not None
        undecided = self.undecided if self.promising and not final else -1
        self.publish("camera_info", camera_to_info(self.published, stamp, from_seq, self.source, undecided))

    def on_end(self) -> None:
        if self.promising and self.published is not None:  # the last camera holds for every later frame
            self._publish(self.last[0], self.last[1] + self.p["lead"], final=True)
        if self.latest is not None:
            self.log.info("last estimate: %s", self.latest.describe())
        elif self.p["estimate"] and not self.p["file"]:
            hint = self.observations.feet_out_hint() if self.observations is not None else ""
            self.log.warning("no credible camera estimate from the people in view; the default camera was used%s", hint)


NODE = Calibration

if __name__ == "__main__":
    Calibration.main()
