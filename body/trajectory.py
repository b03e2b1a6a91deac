"""The two-person interaction file format (``.npz``), and the ``TwoPersonTrajectory`` class.

One file holds one interaction between two people, A and B, frame for frame on one clock, as 3D
positions of our 14 joints. It is the format the simulator replays, the responder learns from
and users bring their own data in. Write it with ``TwoPersonTrajectory(...).save(path)`` or with
plain ``numpy.savez`` using the keys below.

Keys (format_version 1)::

    key             dtype / shape          meaning
    format_version  int scalar             1
    a, b            float32 (T, 14, 3)     joint positions of person A and B, metres, world frame:
                                           Y up, ground plane y = 0, right-handed; joints in
                                           ``counterpart.body.skeleton.JOINTS`` order (head, neck, l_shoulder,
                                           l_elbow, l_wrist, r_shoulder, r_elbow, r_wrist, l_hip,
                                           l_knee, l_ankle, r_hip, r_knee, r_ankle; l_ = the
                                           person's own left). T >= 1. NaN is not allowed.
    fps             float scalar           frames per second (> 0); frame t is at t / fps seconds
    joint_names     str (14,)              must equal ``counterpart.body.skeleton.JOINTS``
    label           str scalar             interaction name, e.g. "handshake"
  optional:
    signals_a/_b    uint8 or float32 (T, K) per-frame social-signal labels of A / B (both or
                                           neither), e.g. 1 where A nods
    signal_names    str (K,)               names of the K signal columns (required with signals)
    phase           int32 (T,)             per-frame phase index of the interaction (e.g.
                                           0 approach, 1 handshake, 2 retreat)
    meta            str scalar             JSON object: free-form provenance (source files,
                                           subject ids, licence, ...)

Unknown extra keys are ignored on load (additive evolution). ``load`` raises ValueError naming
the file and the key for a missing key, a wrong shape or dtype, or a joint-name mismatch.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from counterpart.body.bvh import CMU_SCALE, bvh_to_joints14, read_bvh
from counterpart.body.skeleton import JOINTS, N_JOINTS

FORMAT_VERSION = 1
_REQUIRED = ("format_version", "a", "b", "fps", "joint_names", "label")


@dataclass
class TwoPersonTrajectory:
    """Two people's 14-joint trajectories, frame-aligned. See the module docstring for units.

    Attributes
    ----------
    a, b : ndarray of shape (T, 14, 3), dtype float32
        Joint positions of person A and B, metres, world frame.
    fps : float
        Frames per second (> 0).
    label : str, default=""
        Interaction name.
    signals_a, signals_b : ndarray of shape (T, K) or None, default=None
        Per-frame signal labels (uint8, else float32); both or neither.
    signal_names : tuple of str, default=()
        The K signal names (empty without signals).
    phase : ndarray of shape (T,), dtype int32, or None, default=None
        Per-frame phase index.
    meta : dict, default={}
        Free-form JSON-serialisable provenance.

    Raises
    ------
    ValueError
        Naming the field, when :meth:`validate` finds it malformed.
    """

    a: np.ndarray
    b: np.ndarray
    fps: float
    label: str = ""
    signals_a: np.ndarray | None = None
    signals_b: np.ndarray | None = None
    signal_names: tuple[str, ...] = ()
    phase: np.ndarray | None = None
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.validate()

    # -- checks -------------------------------------------------------------------------------
    def validate(self, source: str = "TwoPersonTrajectory") -> None:
        """Coerce dtypes and check shapes.

        Parameters
        ----------
        source : str, default="TwoPersonTrajectory"
            Name of where the data came from (a file path), for the error messages.

        Raises
        ------
        ValueError
            Naming ``source`` and the field that is malformed.
        """

        def err(key: str, msg: str) -> ValueError:
            return ValueError(f"{source}: key {key!r}: {msg}")

        for key in ("a", "b"):
            x = np.asarray(getattr(self, key))
            if x.ndim != 3 or x.shape[1:] != (N_JOINTS, 3) or x.shape[0] < 1:
                raise err(key, f"shape {x.shape}; expected (T, {N_JOINTS}, 3) metres")
            if not np.issubdtype(x.dtype, np.number):
                raise err(key, f"dtype {x.dtype}; expected float32")
            x = x.astype(np.float32)
            if not np.isfinite(x).all():
                raise err(key, "contains NaN or inf; fill or drop those frames")
            setattr(self, key, x)
        T = self.a.shape[0]
        if self.b.shape[0] != T:
            raise err("b", f"{self.b.shape[0]} frames but 'a' has {T}; both people need the same clock")
        try:
            self.fps = float(self.fps)
        except (TypeError, ValueError):
            raise err("fps", f"{self.fps!r} is not a number") from None
        if not (np.isfinite(self.fps) and self.fps > 0):
            raise err("fps", f"{self.fps!r}; expected frames per second > 0")
        self.label = str(self.label)
        self.signal_names = tuple(str(s) for s in self.signal_names)
        if (self.signals_a is None) != (self.signals_b is None):
            raise err(
                "signals_a" if self.signals_a is None else "signals_b", "give signals for both people or for neither"
            )
        if self.signals_a is not None:
            K = len(self.signal_names)
            for key in ("signals_a", "signals_b"):
                s = np.asarray(getattr(self, key))
                if s.ndim != 2 or s.shape != (T, K):
                    raise err(key, f"shape {s.shape}; expected (T={T}, K={K}) with K = len(signal_names)")
                if s.dtype != np.uint8:
                    s = s.astype(np.float32)
                setattr(self, key, s)
        elif self.signal_names:
            raise err("signal_names", "given without signals_a/signals_b")
        if self.phase is not None:
            p = np.asarray(self.phase)
            if p.shape != (T,) or not (np.issubdtype(p.dtype, np.integer) or np.all(p == np.round(p))):
                raise err("phase", f"shape {p.shape}, dtype {p.dtype}; expected ({T},) integers")
            self.phase = p.astype(np.int32)
        try:
            json.dumps(self.meta)
        except TypeError as e:
            raise err("meta", f"not JSON-serialisable: {e}") from None

    # -- properties ---------------------------------------------------------------------------
    @property
    def n_frames(self) -> int:
        return int(self.a.shape[0])

    @property
    def duration(self) -> float:
        """Seconds from the first to the last frame."""
        return (self.n_frames - 1) / self.fps

    @property
    def times(self) -> np.ndarray:
        """(T,) seconds of each frame from the first."""
        return np.arange(self.n_frames) / self.fps

    # -- I/O ----------------------------------------------------------------------------------
    def save(self, path: str | os.PathLike) -> None:
        """Write a compressed ``.npz`` in the documented format.

        Parameters
        ----------
        path : str or path-like
            The file (numpy adds ``.npz`` if absent).
        """
        arrays: dict[str, Any] = {
            "format_version": np.int64(FORMAT_VERSION),
            "a": self.a,
            "b": self.b,
            "fps": np.float64(self.fps),
            "joint_names": np.array(JOINTS),
            "label": np.array(self.label),
            "meta": np.array(json.dumps(self.meta)),
        }
        if self.signals_a is not None:
            arrays.update(
                signals_a=self.signals_a, signals_b=self.signals_b, signal_names=np.array(self.signal_names, dtype=str)
            )
        if self.phase is not None:
            arrays["phase"] = self.phase
        np.savez_compressed(path, **arrays)

    @classmethod
    def load(cls, path: str | os.PathLike) -> TwoPersonTrajectory:
        """Read a file written by ``save`` or by hand in the documented format.

        Parameters
        ----------
        path : str or path-like
            The ``.npz`` file.

        Returns
        -------
        TwoPersonTrajectory
            The trajectory.

        Raises
        ------
        FileNotFoundError
            If the file does not exist.
        ValueError
            Naming the file and key for anything missing or malformed.
        """
        path = os.fspath(path)
        try:
            z = np.load(path, allow_pickle=False)
        except (OSError, ValueError) as e:
            if not os.path.exists(path):
                raise FileNotFoundError(f"{path}: no such trajectory file") from None
            raise ValueError(f"{path}: not a .npz trajectory file ({e})") from None
        with z:
            keys = set(z.files)
            missing = [k for k in _REQUIRED if k not in keys]
            if missing:
                raise ValueError(
                    f"{path}: missing key(s) {missing}; a trajectory file needs {list(_REQUIRED)} (see body.trajectory)"
                )
            version = int(z["format_version"])
            if version != FORMAT_VERSION:
                raise ValueError(f"{path}: key 'format_version': {version}; this reader reads version {FORMAT_VERSION}")
            names = tuple(str(n) for n in np.atleast_1d(z["joint_names"]))
            if names != JOINTS:
                raise ValueError(f"{path}: key 'joint_names': {list(names)}; expected {list(JOINTS)} in that order")
            if ("signals_a" in keys or "signals_b" in keys) and "signal_names" not in keys:
                raise ValueError(f"{path}: missing key 'signal_names' needed with signals_a/signals_b")
            for k in ("fps", "label", "format_version", "meta"):
                if k in keys and z[k].shape != ():
                    raise ValueError(f"{path}: key {k!r}: shape {z[k].shape}; expected a scalar")
            meta = json.loads(str(z["meta"])) if "meta" in keys else {}
            traj = cls.__new__(cls)
            traj.a, traj.b = z["a"], z["b"]
            traj.fps = z["fps"].item()
            traj.label = str(z["label"])
            traj.signals_a = z["signals_a"] if "signals_a" in keys else None
            traj.signals_b = z["signals_b"] if "signals_b" in keys else None
            traj.signal_names = tuple(str(s) for s in z["signal_names"]) if "signal_names" in keys else ()
            traj.phase = z["phase"] if "phase" in keys else None
            traj.meta = meta
        traj.validate(source=path)
        return traj

    # -- transforms ---------------------------------------------------------------------------
    def resample(self, fps: float) -> TwoPersonTrajectory:
        """Resample over the same time span: joints by linear interpolation, signals and phase by
        nearest earlier-or-equal frame (labels must not be blended).

        Parameters
        ----------
        fps : float
            The new frame rate, frames per second (> 0).

        Returns
        -------
        TwoPersonTrajectory
            A new trajectory of ``floor(duration * fps) + 1`` frames.

        Raises
        ------
        ValueError
            If ``fps`` is not a positive number.
        """
        if not (np.isfinite(fps) and fps > 0):
            raise ValueError(f"resample: fps={fps!r}; expected frames per second > 0")
        t_old = self.times
        n_new = int(np.floor(self.duration * fps + 1e-9)) + 1
        t_new = np.arange(n_new) / fps
        pos = np.interp(t_new, t_old, np.arange(self.n_frames))
        lo = np.floor(pos).astype(np.intp)
        hi = np.minimum(lo + 1, self.n_frames - 1)
        w = (pos - lo)[:, None, None].astype(np.float32)
        interp = lambda x: (1 - w) * x[lo] + w * x[hi]  # noqa: E731
        nearest = np.minimum(np.floor(pos + 1e-6).astype(np.intp), self.n_frames - 1)
        return TwoPersonTrajectory(
            a=interp(self.a),
            b=interp(self.b),
            fps=float(fps),
            label=self.label,
            signals_a=None if self.signals_a is None else self.signals_a[nearest],
            signals_b=None if self.signals_b is None else self.signals_b[nearest],
            signal_names=self.signal_names,
            phase=None if self.phase is None else self.phase[nearest],
            meta=dict(self.meta),
        )

    @classmethod
    def from_bvh_pair(
        cls,
        path_a: str | os.PathLike,
        path_b: str | os.PathLike,
        fps: float | None = None,
        label: str = "",
        scale: float = CMU_SCALE,
        drop_first: bool = True,
        mapping: dict[str, str] | None = None,
    ) -> TwoPersonTrajectory:
        """Two BVH files of one take (same world frame and clock) -> trajectory.

        Parameters
        ----------
        path_a, path_b : str or path-like
            The two people's BVH files.
        fps : float or None, default=None
            Resample to this rate (e.g. 25.0), or keep the files' rate (None).
        label : str, default=""
            Interaction name.
        scale : float, default=CMU_SCALE
            Metres per BVH unit (CMU default).
        drop_first : bool, default=True
            Drop frame 0 (CMU T-pose).
        mapping : dict of str to str or None, default=None
            BVH joint names for our 14 (default ``counterpart.body.bvh.CMU_TO_JOINTS14``).

        Returns
        -------
        TwoPersonTrajectory
            The trajectory, cut to the shorter file's frame count.

        Raises
        ------
        ValueError
            If the two files' frame times differ.
        """
        ba, bb = read_bvh(path_a, scale), read_bvh(path_b, scale)
        if abs(ba.frame_time - bb.frame_time) > 1e-6:
            raise ValueError(
                f"{os.fspath(path_b)}: Frame Time {bb.frame_time} differs from "
                f"{os.fspath(path_a)}'s {ba.frame_time}; the two people need one clock"
            )
        ja = bvh_to_joints14(ba, drop_first, mapping)
        jb = bvh_to_joints14(bb, drop_first, mapping)
        T = min(len(ja), len(jb))
        meta = {
            "source": [os.path.basename(os.fspath(path_a)), os.path.basename(os.fspath(path_b))],
            "scale": scale,
            "dropped_first_frame": bool(drop_first),
        }
        traj = cls(a=ja[:T], b=jb[:T], fps=ba.fps, label=label, meta=meta)
        return traj if fps is None else traj.resample(fps)
