"""BVH (Biovision Hierarchy) motion capture: reading, forward kinematics, mapping to 14 joints.

A BVH file has a HIERARCHY section (a tree of ``ROOT``/``JOINT`` blocks with an ``OFFSET`` from
the parent, a ``CHANNELS`` list and ``End Site`` leaves) and a MOTION section (``Frames: T``,
``Frame Time: dt`` and T lines of channel values in hierarchy order).

Conventions used here:

* Rotation channels are Euler angles in degrees, applied in the order declared per joint: for
  ``Zrotation Yrotation Xrotation`` the local rotation is ``Rz @ Ry @ Rx`` (column vectors), as
  in the Biovision and CMU conventions. Any order, and any subset of channels, is accepted.
* Position channels, where present (the root), replace the joint's OFFSET as its translation
  from the parent; joints without position channels are translated by their OFFSET.
* A joint's world transform is ``G_parent @ [R_local | translation]``.
* Units: file units times ``scale`` give metres. The default ``CMU_SCALE = 0.0254 / 0.45`` is the
  scale of the CMU "MotionBuilder-friendly" conversion (1 unit = 1/0.45 inch). Y is up in the
  CMU files and in our world frame, so no axis change is applied.

Joint mapping onto our 14 joints (``CMU_TO_JOINTS14``, CMU MotionBuilder-friendly names)::

    head -> Head            neck -> Neck1 (lowest neck joint above the shoulder line; CMU's
                                   "Neck" sits at the top of the spine, 4-7 cm below it)
    l_shoulder -> LeftArm   l_elbow -> LeftForeArm   l_wrist -> LeftHand
    r_shoulder -> RightArm  r_elbow -> RightForeArm  r_wrist -> RightHand
    l_hip -> LeftUpLeg      l_knee -> LeftLeg        l_ankle -> LeftFoot
    r_hip -> RightUpLeg     r_knee -> RightLeg       r_ankle -> RightFoot

CMU subjects face +Z in their rest pose with "Left*" joints on +X, which agrees with our
convention (the person's own left is +X when facing +Z).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from counterpart.body.skeleton import JOINTS

CMU_SCALE: float = 0.0254 / 0.45

CMU_TO_JOINTS14: dict[str, str] = {
    "head": "Head",
    "neck": "Neck1",
    "l_shoulder": "LeftArm",
    "l_elbow": "LeftForeArm",
    "l_wrist": "LeftHand",
    "r_shoulder": "RightArm",
    "r_elbow": "RightForeArm",
    "r_wrist": "RightHand",
    "l_hip": "LeftUpLeg",
    "l_knee": "LeftLeg",
    "l_ankle": "LeftFoot",
    "r_hip": "RightUpLeg",
    "r_knee": "RightLeg",
    "r_ankle": "RightFoot",
}

_ROT_CHANNELS = ("Xrotation", "Yrotation", "Zrotation")
_POS_CHANNELS = ("Xposition", "Yposition", "Zposition")


@dataclass
class BVH:
    """A parsed BVH file.

    Attributes
    ----------
    joint_names : list of str
        J joint names in file order (End Sites excluded).
    parents : ndarray of shape (J,), dtype int
        Parent index, -1 for the root.
    offsets : ndarray of shape (J, 3)
        OFFSETs in file units.
    channels : list of tuple of str
        J tuples of channel names, e.g. ("Zrotation", "Yrotation", "Xrotation").
    frame_time : float
        Seconds per frame.
    motion : ndarray of shape (T, C), dtype float64
        Channel values (C = total channel count), file units / degrees.
    end_site_names : list of str
        E names, ``<parent>_End``.
    end_site_parents : ndarray of shape (E,), dtype int
        Joint index of each End Site's parent.
    end_site_offsets : ndarray of shape (E, 3)
        End Site OFFSETs in file units.
    scale : float
        Metres per file unit, used by ``world_positions``.
    path : str
        The file it was read from.
    """

    joint_names: list[str]
    parents: np.ndarray
    offsets: np.ndarray
    channels: list[tuple[str, ...]]
    frame_time: float
    motion: np.ndarray
    end_site_names: list[str] = field(default_factory=list)
    end_site_parents: np.ndarray = field(default_factory=lambda: np.zeros(0, np.intp))
    end_site_offsets: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    scale: float = CMU_SCALE
    path: str = ""

    @property
    def n_frames(self) -> int:
        return int(self.motion.shape[0])

    @property
    def fps(self) -> float:
        return 1.0 / self.frame_time

    @property
    def all_names(self) -> list[str]:
        """Joint names then End Site names: the columns of ``world_positions(True)``."""
        return list(self.joint_names) + list(self.end_site_names)

    def index(self, name: str) -> int:
        """Column of ``name`` in ``all_names``.

        Parameters
        ----------
        name : str
            A joint or End Site name.

        Returns
        -------
        int
            Its column in ``world_positions(True)``.

        Raises
        ------
        KeyError
            Listing the names, when ``name`` is absent.
        """
        names = self.all_names
        if name not in names:
            raise KeyError(f"{name!r} is not a joint of {self.path or 'this BVH'}; joints: {names}")
        return names.index(name)

    def _channel_slices(self) -> list[slice]:
        out, c = [], 0
        for ch in self.channels:
            out.append(slice(c, c + len(ch)))
            c += len(ch)
        return out

    def global_transforms(self) -> tuple[np.ndarray, np.ndarray]:
        """World rotations (T, J, 3, 3) and positions (T, J, 3) in file units.

        Vectorised over frames; a loop over the J joints of the fixed hierarchy.

        Returns
        -------
        rot : ndarray of shape (T, J, 3, 3)
            World rotations.
        pos : ndarray of shape (T, J, 3)
            World positions, file units.
        """
        T, J = self.n_frames, len(self.joint_names)
        rot = np.empty((T, J, 3, 3))
        pos = np.empty((T, J, 3))
        for j, (chans, sl) in enumerate(zip(self.channels, self._channel_slices())):
            vals = self.motion[:, sl]
            R = np.broadcast_to(np.eye(3), (T, 3, 3))
            trans = np.broadcast_to(self.offsets[j], (T, 3)).copy()
            has_pos = False
            for k, name in enumerate(chans):
                if name in _ROT_CHANNELS:
                    R = R @ _axis_rotation(_ROT_CHANNELS.index(name), np.deg2rad(vals[:, k]))
                else:
                    if not has_pos:
                        trans[:] = 0.0
                        has_pos = True
                    trans[:, _POS_CHANNELS.index(name)] = vals[:, k]
            p = self.parents[j]
            if p < 0:
                rot[:, j] = R
                pos[:, j] = trans
            else:
                rot[:, j] = rot[:, p] @ R
                pos[:, j] = pos[:, p] + np.einsum("tij,tj->ti", rot[:, p], trans)
        return rot, pos

    def world_positions(self, include_end_sites: bool = False) -> np.ndarray:
        """World joint positions in metres (``* scale``).

        Parameters
        ----------
        include_end_sites : bool, default=False
            Append the End Sites after the joints.

        Returns
        -------
        ndarray of shape (T, J, 3) or (T, J + E, 3)
            Positions, metres, world frame; with ``include_end_sites`` the columns are named by
            ``all_names``.
        """
        rot, pos = self.global_transforms()
        if include_end_sites and len(self.end_site_names):
            ends = pos[:, self.end_site_parents] + np.einsum(
                "teij,ej->tei", rot[:, self.end_site_parents], self.end_site_offsets
            )
            pos = np.concatenate([pos, ends], axis=1)
        return pos * self.scale


def _axis_rotation(axis: int, a: np.ndarray) -> np.ndarray:
    """(T,) radians -> (T, 3, 3) right-handed rotation about axis 0/1/2 (X/Y/Z)."""
    c, s = np.cos(a), np.sin(a)
    R = np.zeros((a.shape[0], 3, 3))
    i, k = [(1, 2), (2, 0), (0, 1)][axis]
    R[:, axis, axis] = 1.0
    R[:, i, i] = c
    R[:, k, k] = c
    R[:, i, k] = -s
    R[:, k, i] = s
    return R


class _Tokens:
    """Whitespace tokens with their 1-based line numbers, for error messages."""

    def __init__(self, lines: list[str], path: str, start: int = 0) -> None:
        self.items = [(tok, n + 1) for n in range(start, len(lines)) for tok in lines[n].split()]
        self.i = 0
        self.path = path
        self.last_line = len(lines)

    def error(self, msg: str, line: int | None = None) -> ValueError:
        if line is None:
            line = self.items[self.i][1] if self.i < len(self.items) else self.last_line
        return ValueError(f"{self.path}: line {line}: {msg}")

    def next(self, what: str) -> tuple[str, int]:
        if self.i >= len(self.items):
            raise self.error(f"unexpected end of file, expected {what}")
        tok = self.items[self.i]
        self.i += 1
        return tok

    def expect(self, word: str) -> int:
        tok, line = self.next(repr(word))
        if tok != word:
            raise self.error(f"expected {word!r}, found {tok!r}", line)
        return line

    def number(self, what: str) -> float:
        tok, line = self.next(what)
        try:
            return float(tok)
        except ValueError:
            raise self.error(f"expected a number for {what}, found {tok!r}", line) from None

    def peek(self) -> str | None:
        return self.items[self.i][0] if self.i < len(self.items) else None


def read_bvh(path: str | os.PathLike, scale: float = CMU_SCALE) -> BVH:
    """Read a BVH file.

    Args:
        path: the .bvh file.
        scale: metres per file unit (default: CMU MotionBuilder-friendly, 0.0254 / 0.45).

    Returns
    -------
        BVH with J joints, E end sites and T frames.

    Raises
    ------
        ValueError naming the file and line for anything that is not a well-formed BVH.
        FileNotFoundError if the file is missing.
    """
    path = os.fspath(path)
    try:
        with open(path, encoding="utf-8", errors="strict") as f:
            lines = f.read().splitlines()
    except UnicodeDecodeError as e:
        raise ValueError(f"{path}: not a text BVH file ({e})") from None
    if not scale > 0:
        raise ValueError(f"scale={scale!r}: metres per file unit must be > 0")

    motion_line = next((n for n, l in enumerate(lines) if l.strip() == "MOTION"), None)
    toks = _Tokens(lines[:motion_line] if motion_line is not None else lines, path)
    first = toks.peek()
    if first != "HIERARCHY":
        raise toks.error(f"not a BVH file: expected 'HIERARCHY', found {first!r}")
    toks.expect("HIERARCHY")

    names: list[str] = []
    parents: list[int] = []
    offsets: list[list[float]] = []
    channels: list[tuple[str, ...]] = []
    es_names: list[str] = []
    es_parents: list[int] = []
    es_offsets: list[list[float]] = []

    def read_offset() -> list[float]:
        toks.expect("OFFSET")
        return [toks.number("OFFSET x"), toks.number("OFFSET y"), toks.number("OFFSET z")]

    def read_joint(parent: int) -> None:
        name, _ = toks.next("joint name")
        j = len(names)
        names.append(name)
        parents.append(parent)
        toks.expect("{")
        offsets.append(read_offset())
        toks.expect("CHANNELS")
        tok, line = toks.next("channel count")
        if not tok.isdigit():
            raise toks.error(f"expected a channel count, found {tok!r}", line)
        chans = []
        for _ in range(int(tok)):
            c, cl = toks.next("channel name")
            if c not in _ROT_CHANNELS + _POS_CHANNELS:
                raise toks.error(
                    f"unknown channel {c!r} of joint {name!r}; expected one of {_POS_CHANNELS + _ROT_CHANNELS}", cl
                )
            chans.append(c)
        channels.append(tuple(chans))
        while True:
            tok, line = toks.next("'JOINT', 'End Site' or '}'")
            if tok == "JOINT":
                read_joint(j)
            elif tok == "End":
                toks.expect("Site")
                toks.expect("{")
                es_offsets.append(read_offset())
                toks.expect("}")
                es_names.append(f"{name}_End")
                es_parents.append(j)
            elif tok == "}":
                return
            else:
                raise toks.error(f"expected 'JOINT', 'End Site' or '}}' in joint {name!r}, found {tok!r}", line)

    toks.expect("ROOT")
    read_joint(-1)
    if toks.peek() is not None:
        raise toks.error(f"only one ROOT is supported; found {toks.peek()!r} after the root's block")
    if motion_line is None:
        raise toks.error("no MOTION section")

    n_channels = sum(len(c) for c in channels)
    header = _Tokens(lines, path, motion_line + 1)
    header.expect("Frames:")
    n_frames_f = header.number("Frames")
    header.expect("Frame")
    header.expect("Time:")
    frame_time = header.number("Frame Time")
    if n_frames_f != int(n_frames_f) or n_frames_f < 0:
        raise ValueError(f"{path}: line {motion_line + 2}: Frames must be a whole number, got {n_frames_f}")
    if not frame_time > 0:
        raise ValueError(f"{path}: line {motion_line + 3}: Frame Time must be > 0 seconds, got {frame_time}")
    n_frames = int(n_frames_f)
    data_start = motion_line + 3
    rows = [(n + 1, l) for n, l in enumerate(lines[data_start:], start=data_start) if l.strip()]
    if len(rows) != n_frames:
        line = rows[-1][0] if rows else len(lines)
        raise ValueError(f"{path}: line {line}: header says {n_frames} frames, found {len(rows)} data lines")
    motion = np.empty((n_frames, n_channels))
    for t, (line, text) in enumerate(rows):
        vals = text.split()
        if len(vals) != n_channels:
            raise ValueError(f"{path}: line {line}: {len(vals)} values, expected {n_channels} channels")
        try:
            motion[t] = np.array(vals, dtype=np.float64)
        except ValueError:
            raise ValueError(f"{path}: line {line}: non-numeric channel value") from None
    if not np.isfinite(motion).all():
        bad = int(np.argwhere(~np.isfinite(motion))[0, 0])
        raise ValueError(f"{path}: line {rows[bad][0]}: non-finite channel value")

    return BVH(
        joint_names=names,
        parents=np.array(parents, dtype=np.intp),
        offsets=np.array(offsets, dtype=np.float64).reshape(-1, 3),
        channels=channels,
        frame_time=float(frame_time),
        motion=motion,
        end_site_names=es_names,
        end_site_parents=np.array(es_parents, dtype=np.intp),
        end_site_offsets=np.array(es_offsets, dtype=np.float64).reshape(-1, 3),
        scale=float(scale),
        path=path,
    )


def bvh_to_joints14(bvh: BVH, drop_first: bool = True, mapping: dict[str, str] | None = None) -> np.ndarray:
    """Our 14 joints from a BVH.

    Args:
        bvh: a parsed BVH.
        drop_first: drop frame 0 (the T-pose calibration frame of CMU takes).
        mapping: our joint name -> BVH joint name, for all 14 (default ``CMU_TO_JOINTS14``).

    Returns
    -------
        (T', 14, 3) float64 metres in ``counterpart.body.skeleton.JOINTS`` order.
    """
    mapping = CMU_TO_JOINTS14 if mapping is None else mapping
    missing = [j for j in JOINTS if j not in mapping]
    if missing:
        raise ValueError(f"bvh_to_joints14: mapping lacks our joints {missing}")
    absent = [mapping[j] for j in JOINTS if mapping[j] not in bvh.all_names]
    if absent:
        raise ValueError(
            f"{bvh.path or 'BVH'}: has no joint(s) {absent} needed by the mapping; "
            f"its joints are {bvh.all_names}; pass mapping= for other skeletons"
        )
    pos = bvh.world_positions(include_end_sites=True)
    cols = [bvh.index(mapping[j]) for j in JOINTS]
    out = pos[:, cols]
    return out[1:] if drop_first else out
