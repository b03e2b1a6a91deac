"""The tracker node: Frame + Silhouettes (paired by seq) -> Pose3D, one message per frame.

Run in a graph (``run: counterpart.nodes.tracker``) or alone::

    python -m counterpart.nodes.tracker --param people='[left, right]' --param prior=none

Each person named in ``people`` (a side of the frame, as the silhouette node labels them) has its
own :class:`counterpart.nodes.tracker.tracker.Tracker`. A frame with nobody in view gives a Pose3D with no
people (the tracks wait); a merged region is still tracked, with the mask the silhouette node
split by its labels. Frame and silhouettes are paired by seq by the runtime
(:class:`~counterpart.bus.pairing.Pairing`): a frame whose silhouettes never come is dropped once
the silhouettes went past it, or once ``max_pending`` frames wait; silhouettes whose frame never
comes (a real-time queue dropped it) are tracked on their mask alone (the ``paired_*`` figures of
the node's stats count both: ``paired_dropped``, ``paired_partial``).

With ``frame_budget`` (the real-time graph, ``launch/demo.yaml``) the search of each frame is cut so
that the node's handling of the frame fits that share of the camera's frame interval in CPU time
(:class:`counterpart.nodes.tracker.budget.FrameBudget`: fewer annealing layers, then fewer
particles, from the CPU time the last frames took); the stats give the mean layers and particles
per person and frame (``budget_layers``, ``budget_particles`` over ``budget_frames``), the tracks
started (``budget_starts``: first searches, on the longer schedule) and CPU times summed over the
frames: ``search_cpu_ms`` (the people's tracking, the node's messaging aside), ``layers_cpu_ms``
(the annealing layers alone) and ``handler_cpu_ms`` (the whole frame, its message included);
``budget_over`` counts the frames whose handling took more than the budget (at the floors of the
search, or on a track's first search). Under a budget a track's first search is spread over frames
(``start_layers``): in one frame its 20 layers, against 3 at the budget's floors, held that frame up
and the real-time queues dropped the frames behind it.
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

import cv2
import numpy as np

from counterpart.body.camera import Camera, CameraSchedule, camera_for_size, camera_from_info, camera_param_problem
from counterpart.bus import Input, Node, Output, PairedSet, Pairing, Param, ParamError
from counterpart.messages import CameraInfo, Frame, Pose3D, Silhouettes, TrackedBody

from .budget import BudgetConfig, FrameBudget, StampRate
from .likelihood import frame_edges, warm_kernels
from .prior import LOADING_DEFAULT_PRIOR, resolve_prior
from .tracker import (
    SIDES,
    APFConfig,
    Search,
    Tracker,
    TrackerConfig,
    joints_jointly,
    people_problem,
    search_jointly,
)


def _check_prior(v: str) -> str | None:
    if v in ("default", "none", ""):
        return None
    from .prior import MotionPrior

    try:
        MotionPrior.load(v)
    except (ValueError, FileNotFoundError, OSError) as exc:
        return str(exc)
    return None


def person_mask(shape: Any, labels: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """The mask of one PersonShape: its label where the silhouette node sent labels, else the polygon
    of its B-spline control points.

    Parameters
    ----------
    shape : PersonShape
        The person (``id``, ``ctrl`` (n, 2) image pixels).
    labels : ndarray of shape (H, W), dtype uint8
        The silhouette node's label image (empty when it sent none).
    size : tuple of int
        (W, H) frame size, pixels, for the polygon.

    Returns
    -------
    ndarray of shape (H, W), dtype bool
        The person's pixels.
    """
    if labels.size:
        return labels == shape.id + 1
    mask = np.zeros((size[1], size[0]), np.uint8)
    if len(shape.ctrl) >= 3:
        cv2.fillPoly(mask, [np.round(shape.ctrl).astype(np.int32)], 1)
    return mask.astype(bool)


class TrackerNode(Node):
    """3D poses of the people of each frame (annealed particle filter, Deutscher et al. 2000)."""

    inputs = {
        "frame": Input(Frame, doc="the video frames (edge term)"),
        "silhouettes": Input(Silhouettes, doc="the people's masks (silhouette term)"),
        # awaited to its end: the calibration node publishes after it has seen a frame, so on a
        # short stream the frames' end can overtake the camera their tracking waits for
        "camera_info": Input(CameraInfo, doc="the graph's camera (the calibration node's; latched)"),
    }
    outputs = {"pose": Output(Pose3D, "one per frame: the tracked people (empty when nobody is in view)")}
    # the frame is optional: in real time its queue keeps only the newest, and a frame it dropped
    # while the tracker was busy leaves the silhouettes that come for it later without their frame;
    # they are tracked on the mask alone (no edge term) rather than not at all (``paired_partial``
    # counts them). In lockstep every frame comes, so every set is whole.
    pairing = Pairing(required=("silhouettes",), optional=("frame",), max_pending=4)
    params = {
        "layers": Param(int, 10, "annealing layers per frame", min=1, max=100),
        "particles": Param(int, 256, "particles per layer", min=8, max=100000),
        "people": Param(list, ["left"], "sides of the frame to track, one or two of left/right", check=people_problem),
        "camera_info": Param(
            bool,
            True,
            "take the camera from topic camera_info (the calibration node, so that "
            "every node projects with the same one); false: from 'camera'",
        ),
        "camera": Param(
            dict,
            {},
            "without camera_info only: {fx, fy, cx, cy, width, height, R, t} or {eye, target, "
            "fov_deg, width, height}, scaled to a frame size of the same aspect ratio; empty: the default "
            "camera at the frame size",
            check=camera_param_problem,
        ),
        "prior": Param(
            str,
            "default",
            "motion prior: 'default' (built from the simulator when missing), 'none' (random walk), or a .npz path",
            check=_check_prior,
        ),
        "frame_budget": Param(
            float,
            0.0,
            "share of the frame interval (1/fps) of CPU time the handling of a frame (all its people) "
            "may take: beyond it the layers, then the particles, are cut (to min_layers and 32 at least; the "
            "costs measured as it runs; the means in the stats as budget_particles / budget_layers "
            "over budget_frames); 0: always layers x particles",
            min=0.0,
            max=100.0,
        ),
        "frame_wall": Param(
            float,
            0.0,
            "with frame_budget only: share of the frame interval of wall-clock time the handling of a "
            "frame may take at the share of a core the tracker has been getting (its frames' CPU time over "
            "their wall time): on a loaded machine it cuts the search further instead of dropping frames; "
            "0: the CPU budget alone",
            min=0.0,
            max=100.0,
        ),
        "min_layers": Param(
            int,
            3,
            "with frame_budget only: the fewest annealing layers a frame is cut to before its particles are",
            min=1,
            max=100,
        ),
        "start_layers": Param(
            float,
            3.0,
            "with frame_budget only: a track's first search (20 layers) runs at most this many times "
            "the frame's planned layers on one frame, and the rest on the next frames, so that a start "
            "does not hold up the frames behind it (at the budget's floors, 9 of its 20 layers a "
            "frame); 0: all on its first frame",
            min=0.0,
            max=100.0,
        ),
        "seed": Param(int, 0, "seed of the particle filters"),
        "max_pending": Param(
            int,
            100,
            "frames kept while waiting for the other input or for their camera to be decided (a lockstep "
            "calibration node's wait_frames for its first estimate, and the frames read meanwhile)",
            min=1,
        ),
    }

    @classmethod
    def validate_params(cls, given: dict[str, Any], where: str = "") -> dict[str, Any]:
        """The node's parameters, checked, with the defaults filled in.

        Parameters
        ----------
        given : dict
            Parameters as given.
        where : str, default=""
            Where they were given, prefixed to error messages.

        Returns
        -------
        dict
            The resolved parameters.

        Raises
        ------
        ParamError
            For a bad parameter, or ``camera`` given while the camera comes from topic camera_info.
        """
        p = super().validate_params(given, where)
        if p["camera_info"] and p["camera"]:
            prefix = f"{where}: " if where else ""
            raise ParamError(
                f"{prefix}parameter 'camera': the camera comes from topic camera_info; give the "
                "calibration file to the calibration node (calibration.file), or set camera_info: false"
            )
        return p

    @classmethod
    def ports(cls, params: dict[str, Any]) -> tuple[dict[str, Input], dict[str, Output]]:
        """The ports: ``camera_info`` only with the ``camera_info`` parameter on.

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
        ins = {k: v for k, v in cls.inputs.items() if k != "camera_info" or params["camera_info"]}
        return ins, dict(cls.outputs)

    @classmethod
    def paired_inputs(cls, params: dict[str, Any]) -> Pairing | None:
        """The pairing of frames and silhouettes, keeping at most ``max_pending`` frames ahead.

        Parameters
        ----------
        params : dict
            Validated parameters.

        Returns
        -------
        Pairing or None
            The pairing.
        """
        return replace(super().paired_inputs(params), max_ahead=params["max_pending"])

    def setup(self) -> None:
        if self.p["prior"] == "default":
            self.log.info(LOADING_DEFAULT_PRIOR)
        self.prior = resolve_prior(self.p["prior"])
        warm_kernels()  # compiled (an install's first run) or loaded now, not on the first frame
        self.calibration: Camera | None = Camera.from_dict(self.p["camera"]) if self.p["camera"] else None
        #: frame size (w, h) and seq -> the camera for it (camera_info, or the "camera" parameter's)
        self.cameras = CameraSchedule()
        self.camera: Camera | None = None  # the one the trackers use
        self.trackers: dict[str, Tracker] = {}
        #: waiting for the camera of their size (the frame None where it was dropped)
        self.paired: dict[int, tuple[Frame | None, Silhouettes]] = {}
        self.warned: set[str] = set()
        self.fps = 0.0  # the camera's frame rate, from the newest frame (or the silhouettes' stamps)
        self.rate = StampRate()
        self.fps_known = False  # a frame gave the rate
        #: the seq of the last frame tracked: frames dropped before this node (a live camera faster
        #: than the graph) are a longer step for the tracks (``Tracker.set_gap``)
        self.last_seq: int | None = None
        self.budget = FrameBudget(
            self.p["layers"],
            self.p["particles"],
            BudgetConfig(
                share=self.p["frame_budget"], min_layers=self.p["min_layers"], wall_share=self.p["frame_wall"]
            ),
        )

    def _camera(self, size: tuple[int, int], seq: int) -> Camera | None:
        """The camera for frame ``seq`` of ``size``; None while the graph's camera_info has not
        decided it (in lockstep the calibration node says how far it has).
        """
        if not self.p["camera_info"] and size not in self.cameras:
            try:  # made once per size: the trackers start again only when the camera changes
                self.cameras.add(camera_for_size(self.calibration, *size))
            except ValueError as exc:
                raise ValueError(f"parameter 'camera': {exc}") from None
        return self.cameras.get(size, seq) if self.cameras.decided(size, seq) else None

    def _tracker(self, side: str, camera: Camera) -> Tracker:
        if camera is not self.camera:
            same_view = self.camera is not None and (camera.width, camera.height) == (
                self.camera.width,
                self.camera.height,
            )
            # a refined camera of the same frames (the calibration's estimate, by small steps) keeps the
            # tracks going; frames of another size are another view: the tracks start again
            for tr in self.trackers.values() if same_view else ():
                tr.set_camera(camera)
            self.camera, self.trackers = camera, (self.trackers if same_view else {})
        if side not in self.trackers:
            config = TrackerConfig(apf=APFConfig(n_layers=self.p["layers"], n_particles=self.p["particles"]))
            self.trackers[side] = Tracker(
                camera, side, config, prior=self.prior, seed=self.p["seed"] + SIDES.index(side), fps=self.fps
            )
        return self.trackers[side]

    def on_camera_info(self, msg: CameraInfo) -> None:
        """Take a camera (a refined one holds from its seq on) and track the frames waiting for it.

        Parameters
        ----------
        msg : CameraInfo
            The camera; one that cannot be read is dropped with a warning.
        """
        try:
            camera = camera_from_info(msg)
        except ValueError as exc:
            self._warn_once("info", f"camera_info dropped: {exc}")
            return
        self.cameras.add(camera, msg.seq, msg.undecided_from)  # a refined camera holds from its seq on
        self._drain()

    def on_paired(self, paired: PairedSet) -> None:
        """Queue a frame with its silhouettes and track what the known cameras allow.

        Parameters
        ----------
        paired : PairedSet
            ``silhouettes`` of one seq, with its ``frame`` (None when the frame was dropped).
        """
        frame, sil = paired.get("frame"), paired["silhouettes"]
        rate = self.rate.update(sil.seq, sil.stamp)
        if frame is not None and frame.fps > 0:
            self.fps, self.fps_known = frame.fps, True
        elif not self.fps_known:  # no frame has come with its silhouettes yet: the rate of their stamps
            self.fps = rate
        self.paired[paired.seq] = (frame, sil)
        self._drain()

    def on_end(self) -> None:
        """Publish the frames still waiting for a camera without people, so that downstream stays in
        step, and report the regions that could not be tracked.
        """
        if self.paired:  # the camera never came: one empty pose per frame keeps downstream in step
            self.log.error(
                "no camera_info came for %d frame(s); published them without people (is a calibration "
                "node in the graph?)",
                len(self.paired),
            )
            for seq in sorted(self.paired):
                self._publish_empty(self.paired.pop(seq)[1])
        n = self.figures.get("regions_not_tracked", 0)
        if n:
            self.log.warning("%d person region(s) could not be tracked (see the first warning)", n)

    def _drain(self) -> None:
        """Track the paired frames in seq order, as far as the camera of their size is decided;
        beyond ``max_pending`` waiting frames the oldest is tracked with the camera at hand
        (counted as ``camera_not_waited``), or goes out without people where none has come.
        """
        for seq in sorted(self.paired):
            frame, sil = self.paired[seq]
            image = frame.image if frame is not None and frame.image.size else None
            size = (
                sil.width or (image.shape[1] if image is not None else 0),
                sil.height or (image.shape[0] if image is not None else 0),
            )
            try:
                camera = self._camera(size, seq)
                give_up = len(self.paired) > self.p["max_pending"]
            except ValueError as exc:  # a calibration for frames of another shape: nobody can be placed
                self._warn_once("camera", f"frame {seq}: {exc}")
                camera, give_up = None, True
            if camera is None and not give_up:
                return
            del self.paired[seq]
            if camera is None:
                camera = self.cameras.get(size, seq)
                self.tally("camera_not_waited", camera is not None)
            if camera is None:
                self._publish_empty(sil)
            else:
                self._process(sil, image, camera)

    def _publish_empty(self, sil: Silhouettes) -> None:
        """A pose without people for the frame of ``sil`` (nobody could be placed)."""
        self.publish("pose", Pose3D(stamp=sil.stamp, seq=sil.seq, fps=self.fps))

    def _warn_once(self, key: str, text: str) -> None:
        if key not in self.warned:
            self.warned.add(key)
            self.log.warning("%s (further ones are only counted in the stats)", text)

    def _process(self, sil: Silhouettes, image: np.ndarray | None, camera: Camera) -> None:
        size = (camera.width, camera.height)
        people: list[TrackedBody] = []
        in_view = [s for s in self.p["people"] if any(p.side == s for p in sil.people)]
        gap = sil.seq - self.last_seq if self.last_seq is not None and sil.seq > self.last_seq else 1
        self.last_seq = sil.seq
        if gap > 1:  # frames that never reached this node: the tracks step over them
            self.tally("frames_stepped_over", gap - 1)
        layers, particles = self.budget.plan(len(in_view), self.fps)
        cap = self.p["start_layers"]
        budgeted = self.budget.config.share > 0 and self.fps > 0
        max_start_layers = max(1, round(cap * layers)) if budgeted and cap > 0 else None
        # the budget holds the whole handler, in the process's CPU time (module budget)
        cpu0, wall0 = time.process_time(), time.perf_counter()
        # the frame's edges once for all its people
        edges = frame_edges(image) if image is not None and len(in_view) > 1 else None
        begun: list[tuple[str, Any, Tracker, Search, int]] = []
        for side in in_view:
            shape = next(s for s in sil.people if s.side == side)
            try:
                tr = self._tracker(side, camera)
                tr.filter.n_layers, tr.filter.n_particles = layers, particles
                tr.set_gap(gap)
                self.tally("budget_starts", not tr.tracking)
                self.tally("budget_frames")
                self.tally("budget_layers", layers)
                self.tally("budget_particles", particles)
                mask = person_mask(shape, sil.labels, size)
                if shape.merged:
                    self._warn_once(
                        "merged",
                        f"frame {sil.seq}: {side} person merged with another; "
                        "tracking the part the silhouette node assigned to it",
                    )
                other = next((s for s in sil.people if s.side != side and s.side in SIDES), None)
                search = tr.begin(
                    image, mask, tuple(other.bbox) if other is not None else None, edges, max_start_layers
                )
            except ValueError as exc:  # one bad region (PlacementError) is one bad frame: counted, logged
                self.tally("regions_not_tracked")
                self._warn_once(f"error:{side}", f"frame {sil.seq}: {side} person not tracked: {exc}")
                continue
            if search is not None:
                # a track's first search runs its own, longer schedule (spread over frames in real time)
                begun.append((side, shape, tr, search, search.layers or layers))
        # the people's searches side by side: their particles weighed at once, layer by layer
        cpu1 = time.process_time()
        ests = search_jointly([b[2] for b in begun], [b[3] for b in begun])
        layers_cpu = time.process_time() - cpu1
        joints = joints_jointly([b[2] for b in begun], ests)  # one kinematics for all the estimates
        for (side, shape, tr, search, _), est, j in zip(begun, ests, joints):
            r = tr.end(search, est, j)
            people.append(
                TrackedBody(
                    id=shape.id,
                    side=side,
                    joints=r.joints,
                    pose=r.pose,
                    best_pose=r.best,
                    ess=float(r.ess),
                    log_likelihood=float(r.log_likelihood),
                    lost=bool(r.lost),
                )
            )
        searched, layers_run = len(begun), sum(b[4] for b in begun)
        search_cpu = time.process_time() - cpu0
        self.publish("pose", Pose3D(stamp=sil.stamp, seq=sil.seq, fps=self.fps, people=people))
        cpu = time.process_time() - cpu0
        self.budget.record(cpu, searched, layers_run, particles, layers_cpu, time.perf_counter() - wall0)
        self.tally("search_cpu_ms", search_cpu * 1e3)
        self.tally("layers_cpu_ms", layers_cpu * 1e3)
        self.tally("handler_cpu_ms", cpu * 1e3)
        share = self.budget.config.share
        # frames whose handling overran the budget: at its floors, or on a track's first search
        self.tally("budget_over", bool(share > 0 and self.fps > 0 and cpu > share / self.fps))


NODE = TrackerNode

if __name__ == "__main__":
    TrackerNode.main()
