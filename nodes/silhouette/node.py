"""The silhouette node: people as regions and B-spline outlines, on topic ``silhouettes``.

Frame (bgr8 or mono8) in, Silhouettes out, exactly one per frame with the frame's ``seq`` and
``stamp`` (lockstep replays and the labeller pair topics by seq). While the background model learns
from the first ``train_frames`` frames the output has no people; with ``replay_training`` (lockstep
replays) those frames are held back instead and their people found once the background is learnt,
from however many frames there are when a short stream ends first. The algorithm is
:class:`counterpart.nodes.silhouette.pipeline.SilhouetteExtractor`; this module only converts messages.

Run in a graph (``run: counterpart.nodes.silhouette``) or alone::

    python -m counterpart.nodes.silhouette --param backend=mog2 --param train_frames=50

Grey (mono8) frames are converted to three equal channels. Chromaticity cannot tell a shadow from
a darker person there: the Horprasert model finds such footage monochrome, as it does any grey or
tinted video however it comes, and bounds its shadows and highlights tightly
(``background.ShadowConfig.mono_min_shadow_brightness``); MOG2 and KNN detect no shadows on them.
A frame of another size or encoding than the ones before (a camera restarted at a new resolution)
starts the background model and the people afresh; so do bgr8 frames turning monochrome, or back to
colour (``colour_switch_frames``: a day/night camera turning to infrared), the new model learnt with
the people last seen kept out of it, and with ``replay_training`` the frames of the new kind held
back until it is learnt (``switch_replay.SwitchReplay``), so that none goes out with the old
model's labels.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

import cv2
import numpy as np

from counterpart.body.camera import Camera, camera_param_problem
from counterpart.bus import Input, Node, Output, Param
from counterpart.messages import Frame, Silhouettes
from counterpart.messages.silhouette import PersonShape

from . import BACKEND_NAMES

if TYPE_CHECKING:
    from .people import PrefetchDetector
    from .pipeline import FrameResult, SilhouetteExtractor
    from .regions import Person
    from .switch_replay import SwitchReplay

_NO_CTRL = np.zeros((0, 2), np.float32)
_NO_POINT = np.full(2, np.nan, np.float32)
#: the smallest side (pixels) of a frame the background model can take
MIN_SIDE = 2
#: the largest person label a uint8 mask can hold (id + 1)
MAX_LABEL = 255


def as_bgr(image: np.ndarray) -> np.ndarray:
    """A BGR image from a bgr8 or mono8 frame image.

    Parameters
    ----------
    image : ndarray of shape (H, W, 3), (H, W) or (H, W, 1), dtype uint8
        bgr8 or mono8 image, at least ``MIN_SIDE`` pixels on each side.

    Returns
    -------
    ndarray of shape (H, W, 3), dtype uint8
        BGR image (``image`` itself when it is already BGR).

    Raises
    ------
    ValueError
        For another dtype, a too small image or another shape.
    """
    if image.dtype != np.uint8:
        raise ValueError(f"frame image must be uint8, got {image.dtype}")
    if image.ndim < 2 or min(image.shape[:2]) < MIN_SIDE:
        raise ValueError(f"frame image of shape {image.shape} is too small: at least {MIN_SIDE}x{MIN_SIDE} pixels")
    if image.ndim == 2 or (image.ndim == 3 and image.shape[2] == 1):
        return cv2.cvtColor(image.reshape(image.shape[:2]), cv2.COLOR_GRAY2BGR)
    if image.ndim == 3 and image.shape[2] == 3:
        return image
    raise ValueError(f"frame image must be (H, W, 3) bgr8 or (H, W) mono8, got shape {image.shape}")


def person_shape(p: Person) -> PersonShape:
    """The message form of one person.

    Parameters
    ----------
    p : Person
        A person from the extractor.

    Returns
    -------
    PersonShape
        The message form (no outline: ``ctrl`` (0, 2) and ``ref_point`` NaN).
    """
    return PersonShape(
        id=int(p.id),
        side=p.side,
        ctrl=_NO_CTRL if p.ctrl is None else np.asarray(p.ctrl, np.float32),
        ref_point=_NO_POINT if p.ref_point is None else np.asarray(p.ref_point, np.float32),
        centroid=np.asarray(p.centroid, np.float32),
        bbox=tuple(int(v) for v in p.bbox),
        height=float(p.height),
        area=int(p.area),
        merged=bool(p.merged),
    )


def label_mask(labels: np.ndarray) -> tuple[np.ndarray, bool]:
    """A uint8 mask from the extractor's labels.

    Parameters
    ----------
    labels : ndarray of shape (H, W), dtype int32
        0 = background, person.id + 1 on each person's pixels.

    Returns
    -------
    mask : ndarray of shape (H, W), dtype uint8
        The labels, clipped to ``MAX_LABEL``.
    clipped : bool
        Whether any id had to be clipped (ids >= 255 share the value 255).
    """
    clipped = bool(labels.max(initial=0) > MAX_LABEL)
    return np.minimum(labels, MAX_LABEL).astype(np.uint8), clipped


class Silhouette(Node):
    """Background subtraction with shadows (Horprasert et al. 1999), people with stable ids, and each
    outline as a closed cubic B-spline from the top of the head (Baumberg & Hogg).
    """

    inputs = {"frame": Input(Frame, doc="bgr8 or mono8 frames")}
    outputs = {"silhouettes": Output(Silhouettes, "one per frame; no people while the background is learnt")}
    params = {
        "backend": Param(str, "horprasert", "background subtractor", choices=BACKEND_NAMES),
        "n_ctrl": Param(
            int, 32, "B-spline control points per outline (the labeller's 2D activity needs 32)", min=4, max=1024
        ),
        "min_area": Param(
            int,
            300,
            "smallest person region (pixels); 0: a person 1.7 m tall at max_distance_m "
            "from the camera, so it scales with the frame size and the lens",
            min=0,
        ),
        "max_distance_m": Param(
            float,
            30.0,
            "with min_area 0: the farthest person to find (metres); 30: 17 px tall at 320x240 with the default camera",
            min=0.1,
        ),
        "camera": Param(
            dict,
            {},
            "with min_area 0: {fx, fy, cx, cy, width, height, R, t} of the camera (scaled "
            "to the frame size); {}: the default camera",
            check=camera_param_problem,
        ),
        "train_frames": Param(
            int,
            30,
            "first frames the background is learnt from; they give no people unless replay_training",
            min=2,
            max=100_000,
        ),
        "robust": Param(bool, True, "horprasert: robust (median) fit, for people in view from the first frame"),
        "people_aware": Param(
            bool,
            True,
            "horprasert: find the people in the training frames (OpenCV's HOG people "
            "detector) and learn the room around them, so that people standing still "
            "from the first frame are not learnt as background",
        ),
        "absorb_frames": Param(
            int,
            -1,
            "horprasert: still frames before a ghost (room uncovered by someone who "
            "stood in the training frames) is absorbed; -1: 10 after a robust fit, "
            "never after a plain one; 0: never",
            min=-1,
            max=100_000,
        ),
        "dynamic": Param(
            bool,
            True,
            "horprasert: a sample-consensus model (ViBe-like, radius from each pixel's own "
            "spread) beside the statistics, so that leaves, water and flicker are background; "
            "false: the statistics alone",
        ),
        "shake": Param(
            bool,
            True,
            "horprasert: follow camera shake (a camera on a pole in the wind, a tripod on a "
            "wooden floor, a hand): each frame's shift against the background is found and "
            "the frame compared on the background's pixels; false: a camera known to be still",
        ),
        "denoise": Param(
            bool,
            True,
            "horprasert: a camera whose noise over the training frames is over 3 grey levels (low "
            "light, a small sensor) has its frames smoothed before they are compared, by a Gaussian "
            "of a third of a pixel per grey level of noise (up to 2 pixels), so that people do not fall "
            "apart into pieces; false: never",
        ),
        "shadow_ncc": Param(
            float,
            0.4,
            "horprasert: shadow pixels on a textured floor that correlate less than "
            "this with its texture are foreground (a dark shirt, not a shadow); -1: off; 0.4 "
            "was tuned on CDnet busStation",
            min=-1.0,
            max=1.0,
        ),
        "body_shadow_px": Param(
            int,
            15,
            "horprasert: a shadow pixel with foreground above and below it within this many "
            "rows, above the lowest fifth of its region, is foreground (dark clothes and hair, "
            "not a cast shadow); 0: off; 15 was tuned on the CDnet tune halves",
            min=0,
            max=1000,
        ),
        "body_shadow_leg_ncc": Param(
            float,
            0.5,
            "horprasert: a shadow pixel hanging from foreground (legs below a torso) whose "
            "neighbourhood correlates less than this with the floor's grey levels is foreground "
            "(trousers; a cast shadow keeps the floor's pattern); -1: off; 0.5 was tuned on the "
            "CDnet tune halves",
            min=-1.0,
            max=1.0,
        ),
        "body_shadow_leg_scale": Param(
            int,
            1,
            "horprasert: the leg step's correlation on blocks of this many pixels a side (2: a "
            "quarter of the pixels, for real-time graphs; the CDnet figures are for 1)",
            min=1,
            max=16,
        ),
        "fit_in_background": Param(
            bool,
            False,
            "horprasert: learn the background from the training frames in a thread of its own, "
            "publishing frames without people meanwhile, instead of in one long call that holds "
            "up the frames behind it (for live graphs; which frames the fit overlaps depends on "
            "timing, so lockstep replays leave it off)",
        ),
        "opencv_threads": Param(
            int,
            0,
            "OpenCV threads of this node's process (cv2.setNumThreads); 0: OpenCV's default (one "
            "per core; 1 in a launched graph, whose launcher sets OPENCV_FOR_THREADS_NUM=1 unless its "
            "environment sets it). 1 with the horprasert backend: its models' worker thread is the second "
            "thread, and OpenCV's pool thread, which busy-waits after each call OpenCV "
            "parallelises (the connected components), stops taking that thread's core; the "
            "results are the same",
            min=0,
            max=256,
        ),
        "mask_every": Param(int, 1, "publish the label mask every N frames by seq (1: every frame, 0: never)", min=0),
        "open_px": Param(int, 3, "opening of the foreground mask (pixels, 0: none)", min=0, max=101),
        "close_px": Param(int, 7, "closing of the foreground mask (pixels, 0: none)", min=0, max=101),
        "fill_holes": Param(bool, True, "fill holes inside each region"),
        "colour_switch_frames": Param(
            int,
            5,
            "horprasert: frames in a row of the other kind than the background model, colour or "
            "monochrome, after which the camera is taken to have switched (a day/night camera "
            "turning to infrared as the room gets dark, and back) and the background is learnt "
            "again from the frames from there, as at the start; 0: never",
            min=0,
            max=100_000,
        ),
        "replay_training": Param(
            bool,
            False,
            "horprasert: hold the training frames back, and once the background "
            "is learnt (or the stream ends first: from the frames there are) find the people "
            "in them too; for recordings in lockstep, where a delay costs nothing",
        ),
    }

    def setup(self) -> None:
        """Start without an extractor: one is made on the first frame, for its size and colour."""
        # the algorithms (numba's kernels, scipy) are loaded as the node starts, not where a launcher
        # imports this module to check the node's parameters (a second and more before every graph)
        from . import pipeline  # noqa: F401

        if self.p["opencv_threads"] > 0:
            cv2.setNumThreads(self.p["opencv_threads"])
        self.extractor: SilhouetteExtractor | None = None
        self.key: tuple[tuple[int, ...], bool] | None = None  # (frame size, mono) of the model
        self.found = 0
        self.frames = 0
        self._warned: set[str] = set()
        #: frames held back while the background is learnt (replay_training), with their images
        self.held: list[tuple[Frame, np.ndarray, bool]] = []
        self.replay = self.p["replay_training"] and self.p["backend"] == "horprasert"
        #: with replay_training, once the background is learnt: the frames around a switch
        #: between colour and monochrome held back until the new model is learnt
        self.switch: SwitchReplay[Frame] | None = None
        #: the people detector of the training frames, started on each as it comes (horprasert,
        #: robust and people_aware; None otherwise)
        self.prefetch: PrefetchDetector | None = None
        #: when the fit in the background (fit_in_background) was started, perf_counter seconds
        self._fit_started: float | None = None

    def _warn_once(self, kind: str, text: str, *args: Any) -> None:
        if kind not in self._warned:
            self._warned.add(kind)
            self.log.warning(text, *args)

    def _say_smoothing(self) -> None:
        """Say, once a background is learnt, whether the camera was found noisy and its frames are smoothed."""
        sub = self.extractor.subtractor
        sigma = getattr(sub, "smoothing_sigma_", 0.0)
        self.figures["camera_noise"] = round(float(getattr(sub, "noise_", 0.0)), 2)
        self.figures["smoothing_px"] = round(float(sigma), 2)
        if sigma > 0:
            self.log.info(
                "a noisy camera (%.1f grey levels over the training frames): each frame is smoothed by a "
                "Gaussian of %.1f pixels before it is compared (silhouette.denoise: false for none)",
                sub.noise_,
                sigma,
            )

    def _new_extractor(self, mono: bool) -> SilhouetteExtractor:
        from .body_shadow import BodyShadowConfig
        from .colour_switch import ColourSwitchConfig
        from .people import PrefetchDetector
        from .pipeline import SilhouetteExtractor

        p = self.p
        backend_params: dict[str, Any] = {}
        if p["backend"] == "horprasert":
            self.prefetch = PrefetchDetector() if p["robust"] and p["people_aware"] else None
            backend_params = {
                "detector": self.prefetch,
                "train_frames": p["train_frames"],
                "robust": p["robust"],
                "people_aware": p["people_aware"],
                "absorb_frames": None if p["absorb_frames"] < 0 else p["absorb_frames"],
                "dynamic": p["dynamic"],
                "shake": None if p["shake"] else False,
                "denoise": None if p["denoise"] else False,
                "shadow_ncc": p["shadow_ncc"],
                "body_shadow": BodyShadowConfig(
                    span_px=p["body_shadow_px"], leg_ncc=p["body_shadow_leg_ncc"], leg_scale=p["body_shadow_leg_scale"]
                ),
                "fit_in_background": p["fit_in_background"] and not self.replay,
            }
        elif p["backend"] in ("mog2", "knn") and mono:
            backend_params = {"detectShadows": False}
        camera = Camera.from_dict(p["camera"]) if p["camera"] else None
        return SilhouetteExtractor(
            colour_switch=ColourSwitchConfig(frames=p["colour_switch_frames"]),
            backend=p["backend"],
            n_ctrl=p["n_ctrl"],
            min_area=p["min_area"] or None,
            camera=camera,
            max_distance_m=p["max_distance_m"],
            open_px=p["open_px"],
            close_px=p["close_px"],
            fill_holes=p["fill_holes"],
            backend_params=backend_params,
        )

    def _key_changed(self, image: np.ndarray, mono: bool) -> bool:
        return self.extractor is None or (image.shape[:2], mono) != self.key

    def _extract(self, image: np.ndarray, mono: bool) -> FrameResult:
        key = (image.shape[:2], mono)
        if self._key_changed(image, mono):
            if self.key is not None:
                self.log.warning(
                    "frames changed from %dx%d %s to %dx%d %s: learning the background again",
                    self.key[0][1],
                    self.key[0][0],
                    "mono8" if self.key[1] else "bgr8",
                    key[0][1],
                    key[0][0],
                    "mono8" if mono else "bgr8",
                )
            self.extractor, self.key = self._new_extractor(mono), key
        ex = self.extractor
        # horprasert trains itself on its first train_frames frames; the online OpenCV models only
        # learn during as many frames, so that every backend reports people from the same frame on
        if self.p["backend"] != "horprasert" and ex.n_frames < self.p["train_frames"] - 1:
            return ex.learn(image)
        training = not ex.subtractor.ready
        if training and self.prefetch is not None and not getattr(ex.subtractor, "fitting", False):
            # the people of the training frames are found while more come, not all after the last
            self.prefetch.submit(image)
        t0 = time.perf_counter()
        result = ex.process(image)
        if training and self._fit_started is None and getattr(ex.subtractor, "fitting", False):
            self._fit_started = t0  # this frame's call started the fit in the background
        if training and ex.subtractor.ready:  # this frame's call learnt the background (or took it up)
            self._say_smoothing()
            now = time.perf_counter()
            self.tally("fit_ms", round((now - t0) * 1e3, 1))
            # from the last training frame to the first frame with the model: the fit's own time
            # when it runs in the background, this call's when in line
            self.tally("fit_elapsed_ms", round((now - (self._fit_started or t0)) * 1e3, 1))
            self._fit_started = None
            if self.prefetch is not None:
                self.prefetch.clear()
        return result

    def on_frame(self, msg: Frame) -> None:
        """Find the people of one frame and publish them (or hold the frame back while the background
        is learnt, with ``replay_training``).

        Parameters
        ----------
        msg : Frame
            A bgr8 or mono8 frame; one that cannot be read gets a Silhouettes without people.
        """
        self.frames += 1
        h, w = msg.image.shape[:2] if msg.image.ndim >= 2 else (0, 0)
        try:
            image = as_bgr(msg.image)
        except ValueError as exc:
            # one output per input all the same, so that downstream stays in step
            self._warn_once("image", "frame %d: %s; publishing no people for such frames", msg.seq, exc)
            self._release_held()
            self.publish("silhouettes", Silhouettes(stamp=msg.stamp, seq=msg.seq, width=w, height=h))
            return
        mono = image.shape != msg.image.shape
        if self.replay and (self.held or self._key_changed(image, mono) or not self.extractor.subtractor.ready):
            self._release_switch()  # frames of the stream before it changed go out first
            if self.held and (image.shape[:2], mono) != (self.held[0][1].shape[:2], self.held[0][2]):
                self._release_held()  # the camera changed its frames: what was held is a stream of its own
            self.held.append((msg, image, mono))
            if len(self.held) >= self.p["train_frames"]:
                self._release_held()
            return
        if self.replay:
            if self.switch is None or self.switch.extractor is not self.extractor:
                from .switch_replay import SwitchReplay

                self.switch = SwitchReplay(self.extractor, self.p["train_frames"])
            for held_msg, result in self.switch.push(msg, image):
                self._publish(held_msg, result)
            return
        result = self._extract(image, mono)
        self._publish(msg, result)

    def _release_switch(self) -> None:
        """Publish the frames held around a switch between colour and monochrome (the stream
        ended or changed), and forget the switch replay.
        """
        if self.switch is not None:
            for held_msg, result in self.switch.flush():
                self._publish(held_msg, result)
            self.switch = None

    def _release_held(self) -> None:
        """Learn the background from the held frames (all of them, however few the stream gave),
        then find the people in each and publish them in order.
        """
        self._release_switch()
        if not self.held:
            return
        held, self.held = self.held, []
        mono = held[0][2]
        if self._key_changed(held[0][1], mono):
            self.extractor, self.key = self._new_extractor(mono), (held[0][1].shape[:2], mono)
        # else the camera switched between colour and monochrome: its extractor was restarted, with
        # the people it last saw as the new fit's hints
        if len(held) >= 2:
            self.extractor.fit_background([img for _, img, _ in held], robust=self.p["robust"])
            self.log.info("background learnt from %d frames", len(held))
            self._say_smoothing()
        else:
            self._warn_once(
                "short",
                "the stream gave %d frame(s) before it ended or changed; a background needs 2: no people in them",
                len(held),
            )
        for msg, image, _ in held:
            if self.extractor.subtractor.ready:
                self._publish(msg, self.extractor.process(image))
            else:
                self._publish(msg, self.extractor.learn(image))

    def _publish(self, msg: Frame, result: FrameResult) -> None:
        if result.relearn:
            self.tally("relearns")
            self.log.warning(
                "frame %d: the camera switched to %s frames (a day/night camera, or a cut in the recording): %s",
                msg.seq,
                "monochrome" if self.extractor.colour_switch.switched_to_mono else "colour",
                "the background learnt again from the frames from here, and their people found with it"
                if self.replay
                else "learning the background again from them, no people until it is learnt",
            )
        h, w = msg.image.shape[:2]
        every = self.p["mask_every"]
        labels = np.zeros(0, np.uint8)
        if every and msg.seq % every == 0:
            labels, clipped = label_mask(result.labels)
            if clipped:
                self._warn_once(
                    "ids",
                    "person ids above %d do not fit the uint8 label mask; their pixels read %d",
                    MAX_LABEL - 1,
                    MAX_LABEL,
                )
        people = [person_shape(p) for p in result.people]
        self.found += bool(people)
        self.tally("frames_with_people", bool(people))
        self.publish(
            "silhouettes", Silhouettes(stamp=msg.stamp, seq=msg.seq, people=people, labels=labels, width=w, height=h)
        )

    def on_end(self) -> None:
        """Publish the frames still held back, and log how many frames had people."""
        self._release_held()
        self.log.info("people found in %d of %d frames", self.found, self.frames)


NODE = Silhouette

if __name__ == "__main__":
    Silhouette.main()
