"""Pairing the renderer's topics by ``seq`` and compositing one output image per frame.

Frames are the clock. A frame is rendered once its partner has arrived (when a partner is
expected at all), or when a partner with a higher ``seq`` shows that this frame's partner will not
come (topics arrive in order), or after ``timeout`` seconds, or when more than ``max_pending``
frames wait: the runtime's seq synchroniser (:mod:`counterpart.bus.pairing`, frame required,
partner optional) decides, driven here rather than declared on the node because a frame first
waits for the graph's camera (``wait_camera``) and only then for its partner.

With ``adaptive`` waiting a frame does not wait at all while the partners are late: when the
median delay of the recent partners (partner arrival minus its frame's arrival; a partner
that never came counts as infinitely late) exceeds ``timeout``, waiting would only add latency to
every frame, so each frame renders at once with the newest partner. The delays are measured on
every frame, waited for or not, so waiting resumes as soon as the partners keep up again.

Overlays (silhouettes, pose, signals) never hold a frame back: each uses the message of the same
``seq`` when there is one, else the newest older one (an overlay a frame late is better than a
flickering one). A frame whose partner did not come shows the newest older partner.

No processes here: :class:`Compositor` takes messages and returns images, so it runs in a notebook.
"""

from __future__ import annotations

import statistics
import time
from collections import OrderedDict, deque
from dataclasses import dataclass, field
from typing import Any

import cv2
import numpy as np

from counterpart.body.camera import Camera, CameraSchedule, camera_for_size
from counterpart.bus.pairing import PairedSet, Pairing, SeqSynchronizer
from counterpart.bus.seq_history import SeqHistory

from . import draw
from .avatar import AvatarPainter

STYLES = ("auto", "cones", "silhouette", "avatar")
OVERLAYS = ("skeleton", "splines", "signals", "stats", "controls")


@dataclass
class Bundle:
    """Everything one output image is made of.

    Attributes
    ----------
    frame : messages.Frame
        The camera frame.
    partner : object or None
        The partner message of the same seq, else the newest older one, or None.
    silhouettes, pose, signals : object or None
        The overlays' messages of the same seq, else the newest older ones, or None.
    partner_exact : bool
        Whether the partner's seq equals the frame's.
    """

    frame: Any
    partner: Any = None
    silhouettes: Any = None
    pose: Any = None
    signals: Any = None
    partner_exact: bool = False  # the partner's seq equals the frame's


@dataclass
class ControlState:
    """The run-time controls in force (``None``: not set yet).

    Attributes
    ----------
    model : str or None
        The partner model.
    speaker : str or None
        The speaker.
    interest : int or None
        The listener's interest level.
    emotion : str or None
        The partner's emotion.
    strength : float or None
        The emotion's strength.
    """

    model: str | None = None
    speaker: str | None = None
    interest: int | None = None
    emotion: str | None = None
    strength: float | None = None

    def update(self, msg: Any) -> None:
        """Apply a ``messages.Control``: fields that are None stay as they are.

        Parameters
        ----------
        msg : messages.Control
            The control message.
        """
        for k in ("model", "speaker", "interest", "emotion", "strength"):
            v = getattr(msg, k, None)
            if v is not None:
                setattr(self, k, v)

    def as_dict(self) -> dict[str, Any]:
        """The controls by name.

        Returns
        -------
        dict of str to object
            ``model``, ``speaker``, ``interest``, ``emotion`` and ``strength``.
        """
        return {
            "model": self.model,
            "speaker": self.speaker,
            "interest": self.interest,
            "emotion": self.emotion,
            "strength": self.strength,
        }


def _size(frame: Any) -> tuple[int, int]:
    shape = np.shape(frame.image)
    return (int(shape[1]), int(shape[0])) if len(shape) >= 2 else (0, 0)


def _first(a: Any, b: Any) -> Any:
    return a if a is not None else b


@dataclass
class Compositor:
    """Pairs frames with partner, silhouettes, pose and signals by seq and draws them.

    Parameters
    ----------
    camera : Camera or None, default=None
        Calibration of the 3D partner and skeleton projection (``counterpart.body.camera.camera_for_size``
        makes it the frame size's; None: the default camera at the frame size, as the tracker's).
    want_partner : bool, default=True
        Whether a partner topic is subscribed (else frames render at once).
    style : {"auto", "cones", "silhouette", "avatar"}, default="auto"
        ``cones`` (3D joints), ``silhouette`` (B-spline ctrl), ``avatar`` (the video-texture
        avatar's frames, :mod:`.avatar`) or ``auto`` (what the partner message carries: avatar
        frames first, then cones).
    overlays : dict of str to bool, default=all on
        Overlay name (:data:`OVERLAYS`) -> on/off.
    timeout : float, default=0.5
        Seconds a frame waits for its partner at most (from the frame's arrival).
    max_pending : int, default=128
        Frames held at most; beyond it the oldest renders without waiting.
    history : int, default=64
        Partners kept ahead of their frames; messages kept per side topic (and partners) beyond the
        frames rendered: ``history + max_pending``, each frame rendered letting go of the older
        ones that no later frame can use.
    adaptive : bool, default=False
        Skip the wait while the recent partners came later than ``timeout`` (module doc).
    delay_window : int, default=25
        Partners whose delays decide ``adaptive`` waiting.
    wait_camera : bool, default=False
        Hold frames until :meth:`set_camera` gives the graph's camera for their size (the
        calibration node's camera_info) and, in lockstep, has decided it for their seq, so that
        nothing is drawn with another one.
    avatar_file : str, default=""
        The avatar file whose frames the video-texture partner shows ('': the one the partner
        message names).

    Attributes
    ----------
    counts : dict of str to int
        Frames ``rendered``; with a partner of the same seq (``partner_exact``), an older one
        (``partner_held``) or none (``partner_missing``); rendered without waiting out their
        partner (``forced``); with a partner drawn inside the picture (``partner_drawn``).
    delays : deque of float
        The recent partners' delays, seconds (inf: the partner never came).
    partners_late : bool
        Whether the median delay exceeds ``timeout``.
    partner_drawn : bool
        Whether the last rendered frame shows a partner (inside the picture).
    stats : dict of str to messages.NodeStats
        The newest statistics per node.
    controls : ControlState
        The run-time controls in force.

    Raises
    ------
    ValueError
        An unknown ``style`` or overlay name.
    """

    camera: Camera | None = None
    want_partner: bool = True
    style: str = "auto"
    overlays: dict[str, bool] = field(default_factory=lambda: {k: True for k in OVERLAYS})
    timeout: float = 0.5
    max_pending: int = 128
    history: int = 64
    adaptive: bool = False
    delay_window: int = 25
    wait_camera: bool = False
    avatar_file: str = ""

    def __post_init__(self) -> None:
        if self.style not in STYLES:
            raise ValueError(f"style={self.style!r}: expected one of {', '.join(STYLES)}")
        unknown = sorted(set(self.overlays) - set(OVERLAYS))
        if unknown:
            raise ValueError(f"unknown overlay(s) {unknown}; expected some of {list(OVERLAYS)}")
        #: frames with their arrival time (s), waiting for the graph's camera before they are paired
        self.pending: deque[tuple[Any, float]] = deque()
        self.sync = SeqSynchronizer(
            Pairing(
                ("frame",),
                ("partner",) if self.want_partner else (),
                max_pending=self.max_pending,
                max_ahead=self.history,
                timeout=self.timeout,
            )
        )
        self._paired: list[PairedSet] = []  # sets the pairing gave out, not rendered yet
        # a frame may wait for its partner while max_pending frames queue behind it, and the other
        # topics run ahead of it meanwhile: each frame rendered lets go of what no later one can use
        self.partners = SeqHistory(self.history + self.max_pending)
        self.side = {k: SeqHistory(self.history + self.max_pending) for k in ("silhouettes", "pose", "signals")}
        self.stats: dict[str, Any] = {}
        self.controls = ControlState()
        #: partner_drawn: frames on which a partner was drawn with part of it inside the picture
        self.counts = {
            "rendered": 0,
            "partner_exact": 0,
            "partner_held": 0,
            "partner_missing": 0,
            "forced": 0,
            "partner_drawn": 0,
        }
        self._cams = CameraSchedule()
        self._unresolved: OrderedDict[int, float] = OrderedDict()  # seq -> arrival, partner delay unknown yet
        self.delays: deque[float] = deque(maxlen=self.delay_window)  # seconds; inf: the partner never came
        self.partners_late = False
        self._max_frame_seq = -1
        self.partner_drawn = False
        self.avatar = AvatarPainter(self.avatar_file)
        #: ((partner message, camera), :meth:`_plan_partner` of them): the last partner drawn
        self._partner_plan: tuple[tuple[Any, Camera] | None, tuple[str, tuple[int, int, int], bool]] = (
            None,
            ("", (0, 0, 0), False),
        )

    # ---------------------------------------------------------------------------------- input
    def add_frame(self, msg: Any, now: float | None = None) -> None:
        """Take a camera frame; it waits in :attr:`pending` until :meth:`ready` pairs it.

        Parameters
        ----------
        msg : messages.Frame
            The frame.
        now : float or None, default=None
            Its arrival, seconds (monotonic clock); None for now.
        """
        now = time.monotonic() if now is None else now
        seq = int(msg.seq)
        self.pending.append((msg, now))
        self._max_frame_seq = max(self._max_frame_seq, seq)
        if seq > self.partners.max_seq:  # else its partner came first: on time, already counted
            self._unresolved[seq] = now
            if len(self._unresolved) > self.history:
                self._unresolved.popitem(last=False)
                self._record_delay(float("inf"))

    def add_partner(self, msg: Any, now: float | None = None) -> None:
        """Take a partner message, recording the delays of the frames it settles.

        Parameters
        ----------
        msg : object
            The partner message (with ``seq``).
        now : float or None, default=None
            Its arrival, seconds (monotonic clock); None for now.
        """
        seq = int(msg.seq)
        if seq > self.partners.max_seq:
            now = time.monotonic() if now is None else now
            for s in [s for s in self._unresolved if s <= seq]:
                t = self._unresolved.pop(s)
                # frames before this partner's never get one (topics arrive in order)
                self._record_delay(now - t if s == seq else float("inf"))
            if seq > self._max_frame_seq:  # ahead of its frame: on time
                self._record_delay(0.0)
        self.partners.add(msg)
        if self.want_partner:
            self._paired += self.sync.add("partner", seq, msg)

    def _record_delay(self, delay: float) -> None:
        self.delays.append(delay)
        # statistics.median: the same value as np.median, without its overhead on 25 numbers
        self.partners_late = statistics.median(self.delays) > self.timeout

    def _resolve_overdue(self, now: float) -> None:
        """Frames whose partner is later than ``timeout`` count as never partnered: for the decision
        (median delay > timeout) any delay beyond the timeout is the same.
        """
        while self._unresolved:
            s, t = next(iter(self._unresolved.items()))
            if now - t <= self.timeout:
                break
            del self._unresolved[s]
            self._record_delay(float("inf"))

    def add_side(self, kind: str, msg: Any) -> None:
        """Take an overlay's message.

        Parameters
        ----------
        kind : {"silhouettes", "pose", "signals"}
            The overlay topic.
        msg : object
            Its message (with ``seq``).
        """
        self.side[kind].add(msg)

    def add_stats(self, msg: Any) -> None:
        """Keep the newest ``messages.NodeStats`` per node.

        Parameters
        ----------
        msg : messages.NodeStats
            A node's statistics.
        """
        self.stats[msg.node] = msg

    def set_camera(self, camera: Camera, from_seq: int = 0, undecided_from: int = -1) -> None:
        """The graph's camera for frames of its size from ``from_seq`` on (camera_info, whose seq it
        is): every drawing uses it.

        Parameters
        ----------
        camera : Camera
            The graph's camera.
        from_seq : int, default=0
            The first frame seq it applies to.
        undecided_from : int, default=-1
            The first frame seq whose camera is not decided yet (with ``wait_camera``, such frames
            wait); -1: none.
        """
        self._cams.add(camera, from_seq, undecided_from)

    def set_control(self, msg: Any) -> None:
        """Apply a ``messages.Control`` (controls shown in the overlay; overlay switches).

        Parameters
        ----------
        msg : messages.Control
            The control message; its ``overlays`` switch known overlays on or off.
        """
        self.controls.update(msg)
        for k, v in (getattr(msg, "overlays", None) or {}).items():
            if k in OVERLAYS:
                self.overlays[k] = bool(v)

    # --------------------------------------------------------------------------------- pairing
    def ready(self, now: float | None = None, flush: bool = False) -> list[Bundle]:
        """Frames ready to render, oldest first, removed from the pending ones.

        Parameters
        ----------
        now : float or None, default=None
            The time, seconds (monotonic clock); None for now.
        flush : bool, default=False
            All of them (end of stream), without waiting for partners or the camera.

        Returns
        -------
        list of Bundle
            The frames with their partner and overlays.
        """
        now = time.monotonic() if now is None else now
        self._resolve_overdue(now)
        # while the partners come late, waiting would only delay every frame (module doc)
        self.sync.timeout = 0.0 if self.adaptive and self.partners_late else self.timeout
        while self.pending:
            frame, t = self.pending[0]
            if self.wait_camera and not flush and not self._cams.decided(_size(frame), int(frame.seq)):
                break
            self.pending.popleft()
            self._paired += self.sync.add("frame", int(frame.seq), frame, now=t)
            self._paired += self.sync.poll(now)  # a frame that waited for the camera may be past its timeout
        self._paired += self.sync.flush() if flush else self.sync.poll(now)
        self.counts["forced"] = self.sync.stats.forced
        out = [self._bundle(s["frame"], s["partner"] if self.want_partner else None) for s in self._paired]
        self._paired = []
        return out

    def next_deadline(self) -> float | None:
        """When the first frame waiting for its partner stops waiting (:meth:`ready` then gives it).

        Returns
        -------
        float or None
            The time, seconds (monotonic clock); None when no frame waits for a partner (frames
            that wait for the graph's camera wait for a message, not for a time).
        """
        return self.sync.next_deadline()

    def _bundle(self, frame: Any, partner: Any) -> Bundle:
        seq = int(frame.seq)
        exact = partner is not None
        if self.want_partner:
            if partner is None:
                partner = self.partners.at_or_before(seq)
            self.counts["partner_exact" if exact else "partner_held" if partner is not None else "partner_missing"] += 1
        sides = {k: _first(h.exact(seq), h.at_or_before(seq)) for k, h in self.side.items()}
        for h in (self.partners, *self.side.values()):
            h.forget_before(seq)
        return Bundle(frame=frame, partner=partner, partner_exact=exact, **sides)

    # ------------------------------------------------------------------------------- drawing
    def camera_for(self, width: int, height: int, seq: int | None = None) -> Camera:
        """The camera for frame ``seq`` (None: the newest) of that size.

        Parameters
        ----------
        width, height : int
            The frame size, pixels.
        seq : int or None, default=None
            The frame's seq; None for the newest camera.

        Returns
        -------
        Camera
            The graph's camera for that size, else ``camera`` fitted to it (kept from then on).
        """
        cam = self._cams.get((width, height), seq)
        if cam is None:
            cam = camera_for_size(self.camera, width, height)
            self._cams.add(cam)
        return cam

    def render(self, b: Bundle) -> np.ndarray:
        """The composited image of one bundle (a new array).

        Parameters
        ----------
        b : Bundle
            The frame with its partner and overlays.

        Returns
        -------
        ndarray of shape (H, W, 3), dtype uint8
            The image, BGR.

        Raises
        ------
        ValueError
            The frame's image is neither bgr8 nor mono8.
        """
        img = np.asarray(b.frame.image)
        if img.ndim == 2:
            img = cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)
        elif img.ndim != 3 or img.shape[2] != 3 or img.dtype != np.uint8:
            raise ValueError(f"frame {b.frame.seq}: image {img.dtype} {img.shape} is not bgr8 or mono8")
        else:
            img = img.copy()
        cam = self.camera_for(img.shape[1], img.shape[0], b.frame.seq)
        ov = self.overlays
        if ov.get("splines") and b.silhouettes is not None:
            for person in b.silhouettes.people:
                if np.size(person.ctrl) >= 8:
                    draw.draw_spline_outline(
                        img, person.ctrl, draw.person_colour(person.id), 1, person.ref_point, f"{person.id}"
                    )
        #: whether the last rendered frame shows a partner (inside the picture)
        self.partner_drawn = b.partner is not None and self._draw_partner(img, b.partner, cam)
        self.counts["partner_drawn"] += self.partner_drawn
        if ov.get("skeleton") and b.pose is not None:
            for body in b.pose.people:
                if np.shape(body.joints) == (14, 3) and np.isfinite(body.joints).all():
                    draw.draw_skeleton(img, body.joints, cam, draw.person_colour(body.id))
        if ov.get("signals") and b.signals is not None:
            self._draw_signals(img, b, cam)
        if ov.get("stats") and self.stats:
            draw.draw_stats(img, self.stats)
        if ov.get("controls"):
            draw.draw_controls(img, self.controls_shown(b.partner))
        self.counts["rendered"] += 1
        return img

    def controls_shown(self, partner: Any) -> dict[str, Any]:
        """The controls for the overlay: those set here, else what the partner says is in force.

        Parameters
        ----------
        partner : object or None
            The partner message drawn (its ``model``, ``emotion``, ``strength``), or None.

        Returns
        -------
        dict of str to object
            The controls by name (as :meth:`ControlState.as_dict`).
        """
        shown = self.controls.as_dict()
        if partner is not None:
            shown["model"] = shown["model"] or partner.model or None
            if shown["emotion"] is None:
                shown["emotion"] = partner.emotion
            if shown["strength"] is None:
                shown["strength"] = partner.strength
        return shown

    def _draw_partner(self, img: np.ndarray, partner: Any, cam: Camera) -> bool:
        """Draw the partner; whether any of it falls inside the picture."""
        if self.style in ("auto", "avatar") and np.size(partner.avatar_frames):
            drawn = self.avatar.draw(img, partner, cam)
            if drawn is not None:  # else no frames to show: the partner falls back to cones
                return drawn
        # a held partner is drawn on every frame until the next one comes: what to draw of it and
        # whether it is inside the picture are worked out once per partner message and camera
        key = self._partner_plan[0]
        if key is None or key[0] is not partner or key[1] is not cam:
            self._partner_plan = ((partner, cam), self._plan_partner(partner, cam))
        kind, colour, inside = self._partner_plan[1]
        if kind == "cones":
            draw.draw_partner_3d(img, partner.joints, cam, colour)
        elif kind == "silhouette":
            draw.draw_silhouette(img, partner.ctrl, colour)
        return inside

    def _plan_partner(self, partner: Any, cam: Camera) -> tuple[str, tuple[int, int, int], bool]:
        """How ``partner`` is drawn without avatar frames (``"cones"``, ``"silhouette"`` or ``""``:
        not at all), in which colour, and whether any of it falls inside the picture.
        """
        colour = draw.partner_colour(partner.emotion, partner.strength)
        if (
            self.style in ("auto", "cones")
            and np.shape(partner.joints) == (14, 3)
            and np.isfinite(partner.joints).all()
        ):
            return "cones", colour, bool(cam.in_image(cam.project(np.asarray(partner.joints, np.float64))).any())
        has_ctrl = np.ndim(partner.ctrl) == 2 and len(partner.ctrl) >= 4 and np.isfinite(partner.ctrl).all()
        if self.style in ("auto", "silhouette") and has_ctrl:
            return "silhouette", colour, bool(cam.in_image(np.asarray(partner.ctrl, np.float64)).any())
        return "", colour, False

    def _draw_signals(self, img: np.ndarray, b: Bundle, cam: Camera) -> None:
        """One compact row of badges per tracked person with the signals that are on, just above the
        head (below the feet where the head is at the top of the picture), never over the face.
        With a pose input only the tracked people are labelled: other regions (fragments, ghosts)
        are not people to label.
        """
        tracked = None if b.pose is None else {body.id: body for body in b.pose.people if not body.lost}
        boxes = {p.id: p.bbox for p in (b.silhouettes.people if b.silhouettes is not None else [])}
        rows, rects = [], []
        for person in b.signals.people:
            if tracked is not None and person.id not in tracked:
                continue
            on = [k for k, lab in enumerate(np.asarray(person.labels).reshape(-1)) if lab == 1]
            if not on or max(on) >= len(person.names):  # nothing on, or a malformed message
                continue
            box = boxes.get(person.id)
            if box is None and tracked is not None:
                box = _projected_box(tracked[person.id].joints, cam)
            if box is None or box[2] <= 0:
                continue
            names = [person.names[k] for k in on]
            x0, y0, x1, y1 = draw.signal_badges_rect(img, (0, 0), names)
            w, h = x1 - x0, y1 - y0
            x, y = _badge_place(box, w, h, img.shape)
            scores = np.asarray(person.scores).reshape(-1)
            rows.append(((x, y), names, scores[on] if scores.size == len(person.names) else None))
            rects.append((x, y, x + w, y + h))
        # people standing close (a handshake) would have their rows drawn over each other
        for ((x, y), names, scores), dy in zip(rows, draw.place_apart(rects, img.shape[0])):
            draw.draw_signal_badges(img, (x, y + dy), names, np.ones(len(names), np.int8), scores)


def _badge_place(box: tuple[int, int, int, int], w: int, h: int, shape: tuple[int, ...]) -> tuple[int, int]:
    """Top-left (x, y) of a ``w`` x ``h`` row of badges for a person in ``box`` (x, y, w, h): centred
    just above the head; where the head touches the top of the picture, beside the head (right,
    else left); else below the feet. Never over the person's face.
    """
    H, W = shape[:2]
    bx, by, bw, bh = box
    if by - h - 3 >= 0:
        return int(np.clip(bx + bw / 2 - w / 2, 0, max(W - w, 0))), by - h - 3
    if bx + bw + 3 + w <= W:
        return bx + bw + 3, max(by, 0)
    if bx - 3 - w >= 0:
        return bx - 3 - w, max(by, 0)
    return int(np.clip(bx + bw / 2 - w / 2, 0, max(W - w, 0))), min(by + bh + 3, H - h)


def _projected_box(joints: Any, cam: Camera) -> tuple[int, int, int, int] | None:
    """(x, y, w, h) pixels around a body's projected joints, or None where none projects."""
    uv = cam.project(np.asarray(joints, np.float64))
    uv = uv[np.isfinite(uv).all(axis=1)]
    if not len(uv):
        return None
    (u0, v0), (u1, v1) = uv.min(axis=0), uv.max(axis=0)
    return int(u0), int(v0), int(u1 - u0) + 1, int(v1 - v0) + 1


__all__ = ["Compositor", "Bundle", "ControlState", "STYLES", "OVERLAYS"]
