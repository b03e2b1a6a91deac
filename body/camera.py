"""Pinhole camera: world (metres, Y up) to pixels, OpenCV convention.

World to camera: ``X_c = R X_w + t``. Camera axes: x right, y down, z forward (optical axis).
Pixels: ``u = fx * x_c / z_c + cx``, ``v = fy * y_c / z_c + cy`` (Hartley & Zisserman eq. 6.5,
no lens distortion); pixel (0, 0) is the centre of the top-left pixel.

``Camera.look_at`` builds a camera with no roll (image "up" is world +Y projected); its
``fov_deg`` is the horizontal field of view and the pixels are square (fx = fy).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

_DICT_KEYS = ("fx", "fy", "cx", "cy", "width", "height", "R", "t")
_LOOKAT_KEYS = ("eye", "target", "fov_deg", "width", "height")


@dataclass(frozen=True)
class Camera:
    """Pinhole camera.

    Parameters
    ----------
    fx, fy : float
        Focal lengths in pixels (> 0).
    cx, cy : float
        Principal point in pixels.
    width, height : int
        Image size in pixels (positive integers).
    R : ndarray of shape (3, 3), default=identity
        World-to-camera rotation.
    t : ndarray of shape (3,), default=zeros
        World-to-camera translation, metres (``X_c = R X_w + t``).

    Raises
    ------
    ValueError
        If ``R`` is not a rotation, ``t`` does not have 3 elements, a focal length is not
        positive or the image size is not a positive integer.
    """

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int
    R: np.ndarray = field(default_factory=lambda: np.eye(3))
    t: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        R = np.array(self.R, dtype=np.float64)
        t = np.array(self.t, dtype=np.float64).reshape(-1)
        if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
            raise ValueError(f"Camera.R must be a 3x3 rotation matrix, got {R.tolist()}")
        if t.shape != (3,):
            raise ValueError(f"Camera.t must have 3 elements (metres), got shape {t.shape}")
        for name in ("fx", "fy"):
            if not float(getattr(self, name)) > 0:
                raise ValueError(f"Camera.{name}={getattr(self, name)!r}: focal length must be > 0 pixels")
        for name in ("width", "height"):
            v = getattr(self, name)
            if int(v) != v or int(v) <= 0:
                raise ValueError(f"Camera.{name}={v!r}: image size must be a positive integer")
        R.setflags(write=False)
        t.setflags(write=False)
        object.__setattr__(self, "R", R)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "width", int(self.width))
        object.__setattr__(self, "height", int(self.height))
        for name in ("fx", "fy", "cx", "cy"):
            object.__setattr__(self, name, float(getattr(self, name)))

    # -- construction -------------------------------------------------------------------------
    @classmethod
    def look_at(cls, eye: Any, target: Any, fov_deg: float, width: int, height: int) -> Camera:
        """Camera at ``eye`` looking at ``target``, square pixels, principal point at the image centre,
        world +Y up in the image.

        Parameters
        ----------
        eye : array-like of shape (3,)
            Camera centre, metres, world frame.
        target : array-like of shape (3,)
            Point looked at, metres, world frame.
        fov_deg : float
            Horizontal field of view, degrees, in (0, 180).
        width, height : int
            Image size in pixels.

        Returns
        -------
        Camera
            The camera, with no roll.

        Raises
        ------
        ValueError
            If ``fov_deg`` is out of range, ``eye`` and ``target`` coincide, or the view is straight
            up or down.
        """
        eye = np.asarray(eye, dtype=np.float64)
        target = np.asarray(target, dtype=np.float64)
        if not 0 < fov_deg < 180:
            raise ValueError(f"fov_deg={fov_deg!r}: horizontal field of view must be in (0, 180) degrees")
        z = target - eye
        if np.linalg.norm(z) < 1e-9:
            raise ValueError("look_at: eye and target coincide; give a target away from the eye")
        z /= np.linalg.norm(z)
        x = np.cross(z, (0.0, 1.0, 0.0))
        if np.linalg.norm(x) < 1e-9:
            raise ValueError("look_at: viewing straight up or down; world up is undefined for roll")
        x /= np.linalg.norm(x)
        y = np.cross(z, x)
        R = np.stack([x, y, z])
        f = (width / 2.0) / np.tan(np.deg2rad(fov_deg) / 2.0)
        return cls(f, f, (width - 1) / 2.0, (height - 1) / 2.0, width, height, R, -R @ eye)

    # -- geometry -----------------------------------------------------------------------------
    @property
    def centre(self) -> np.ndarray:
        """(3,) camera centre in world coordinates, metres (``-R^T t``)."""
        return -self.R.T @ self.t

    @property
    def K(self) -> np.ndarray:
        """(3, 3) intrinsic matrix."""
        return np.array([[self.fx, 0, self.cx], [0, self.fy, self.cy], [0, 0, 1.0]])

    def to_camera(self, X: np.ndarray) -> np.ndarray:
        """World points to camera coordinates.

        Parameters
        ----------
        X : ndarray of shape (..., 3)
            World points, metres.

        Returns
        -------
        ndarray of shape (..., 3)
            Camera coordinates, metres.
        """
        return np.asarray(X, dtype=np.float64) @ self.R.T + self.t

    def depth(self, X: np.ndarray) -> np.ndarray:
        """Depth of world points along the optical axis.

        Parameters
        ----------
        X : ndarray of shape (..., 3)
            World points, metres.

        Returns
        -------
        ndarray of shape (...)
            Depth ``z_c``, metres.
        """
        return np.asarray(X, dtype=np.float64) @ self.R[2] + self.t[2]

    def project(self, X: np.ndarray) -> np.ndarray:
        """Project world points to pixels.

        Parameters
        ----------
        X : ndarray of shape (..., 3)
            World points, metres.

        Returns
        -------
        ndarray of shape (..., 2)
            Pixels (u, v); NaN for points at depth <= 1 mm (on or behind the camera).
        """
        Xc = self.to_camera(X)
        z = Xc[..., 2]
        zs = np.where(z > 1e-3, z, np.nan)
        return np.stack([self.fx * Xc[..., 0] / zs + self.cx, self.fy * Xc[..., 1] / zs + self.cy], axis=-1)

    def rays(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Viewing directions of pixels.

        Parameters
        ----------
        u, v : ndarray of shape (...)
            Pixel coordinates.

        Returns
        -------
        ndarray of shape (..., 3)
            Unit viewing directions in the world frame.
        """
        u = np.asarray(u, dtype=np.float64)
        v = np.asarray(v, dtype=np.float64)
        d = np.stack([(u - self.cx) / self.fx, (v - self.cy) / self.fy, np.ones_like(u)], axis=-1)
        d = d @ self.R  # R^T d for row vectors
        return d / np.linalg.norm(d, axis=-1, keepdims=True)

    def ground_point(self, u: np.ndarray, v: np.ndarray, ground_y: float = 0.0) -> np.ndarray:
        """Back-project pixels onto the plane y = ground_y.

        Parameters
        ----------
        u, v : ndarray of shape (...)
            Pixel coordinates.
        ground_y : float, default=0.0
            Height of the plane, metres.

        Returns
        -------
        ndarray of shape (..., 3)
            Points on the plane, metres, world frame; NaN where the ray does not hit the plane in
            front of the camera (at or above the horizon).
        """
        d = self.rays(u, v)
        c = self.centre
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (ground_y - c[1]) / d[..., 1]
        s = np.where(np.isfinite(s) & (s > 0), s, np.nan)
        return c + s[..., None] * d

    def in_image(self, uv: np.ndarray) -> np.ndarray:
        """Whether pixels are inside the image bounds.

        Parameters
        ----------
        uv : ndarray of shape (..., 2)
            Pixels (u, v).

        Returns
        -------
        ndarray of shape (...), dtype bool
            True inside the image bounds (NaN is outside).
        """
        uv = np.asarray(uv)
        return (
            (uv[..., 0] >= -0.5)
            & (uv[..., 0] < self.width - 0.5)
            & (uv[..., 1] >= -0.5)
            & (uv[..., 1] < self.height - 0.5)
        )

    # -- parameters ---------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """Plain dict (floats, ints, nested lists) for launch files and message metadata.

        Returns
        -------
        dict
            Keys ``fx, fy, cx, cy, width, height, R, t``.
        """
        return {
            "fx": self.fx,
            "fy": self.fy,
            "cx": self.cx,
            "cy": self.cy,
            "width": self.width,
            "height": self.height,
            "R": self.R.tolist(),
            "t": self.t.tolist(),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Camera:
        """Inverse of ``to_dict``.

        Parameters
        ----------
        d : dict
            The ``to_dict`` form, or the look-at form
            ``{eye: [x, y, z], target: [x, y, z], fov_deg, width, height}``.

        Returns
        -------
        Camera
            The camera.

        Raises
        ------
        ValueError
            If ``d`` is not a mapping, or has unknown or missing keys.
        """
        if not isinstance(d, dict):
            raise ValueError(f"camera parameters must be a mapping, got {type(d).__name__}")
        keys = _LOOKAT_KEYS if "eye" in d else _DICT_KEYS
        unknown = sorted(set(d) - set(keys))
        missing = [k for k in keys if k not in d]
        if unknown:
            raise ValueError(f"camera parameters: unknown key(s) {unknown}; expected {list(keys)}")
        if missing:
            raise ValueError(f"camera parameters: missing key(s) {missing}; expected {list(keys)}")
        if keys is _LOOKAT_KEYS:
            return cls.look_at(d["eye"], d["target"], float(d["fov_deg"]), int(d["width"]), int(d["height"]))
        return cls(**{k: d[k] for k in keys})


def camera_to_info(camera: Camera, stamp: int = 0, seq: int = 0, source: str = "", undecided_from: int = -1) -> Any:
    """The ``messages.CameraInfo`` of a camera (the calibration node publishes it).

    Parameters
    ----------
    camera : Camera
        The camera.
    stamp : int, default=0
        Message time stamp.
    seq : int, default=0
        Message sequence number.
    source : str, default=""
        Message source name.
    undecided_from : int, default=-1
        The first frame seq whose camera is not decided yet; -1: none (``messages.CameraInfo``).

    Returns
    -------
    messages.CameraInfo
        The camera's intrinsics and extrinsics as a message.
    """
    from counterpart.messages import CameraInfo

    return CameraInfo(
        stamp=stamp,
        seq=seq,
        width=camera.width,
        height=camera.height,
        fx=camera.fx,
        fy=camera.fy,
        cx=camera.cx,
        cy=camera.cy,
        R=np.asarray(camera.R, np.float64),
        t=np.asarray(camera.t, np.float64),
        source=source,
        undecided_from=undecided_from,
    )


def camera_from_info(info: Any) -> Camera:
    """The Camera of a ``messages.CameraInfo``.

    Parameters
    ----------
    info : messages.CameraInfo
        The message.

    Returns
    -------
    Camera
        The camera.

    Raises
    ------
    ValueError
        Naming what is wrong in the message.
    """
    if np.size(info.R) != 9 or np.size(info.t) != 3:
        raise ValueError(f"camera info: R must hold 9 values and t 3, got {np.size(info.R)} and {np.size(info.t)}")
    return Camera(
        info.fx,
        info.fy,
        info.cx,
        info.cy,
        info.width,
        info.height,
        np.asarray(info.R, np.float64).reshape(3, 3),
        np.asarray(info.t, np.float64).reshape(3),
    )


def load_camera_file(path: str) -> Camera:
    """A Camera from a JSON or YAML calibration file (``Camera.to_dict`` or the look-at form).

    Parameters
    ----------
    path : str
        The calibration file.

    Returns
    -------
    Camera
        The camera.

    Raises
    ------
    ValueError
        Naming the file and the bad key, or why the file cannot be read.
    """
    import yaml

    try:
        with open(path, encoding="utf-8") as f:
            data = yaml.safe_load(f)
    except OSError as exc:
        raise ValueError(f"calibration file {path!r}: cannot read it ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise ValueError(
            f"calibration file {path!r}: not a text file (a calibration is JSON or YAML text, as "
            "`counterpart calibrate` writes; a video or an image cannot be one)"
        ) from None
    except yaml.YAMLError as exc:
        raise ValueError(f"calibration file {path!r}: not JSON or YAML ({exc})") from None
    if not isinstance(data, dict) or not data:
        raise ValueError(f"calibration file {path!r}: expected a mapping of calibration keys")
    problem = camera_param_problem(data)
    if problem:
        raise ValueError(f"calibration file {path!r}: {problem}")
    return Camera.from_dict(data)


def default_camera(width: int = 320, height: int = 240) -> Camera:
    """The simulator's default view: camera 1.6 m high, 4 m in front of the origin (+Z),
    looking at (0, 0.9, 0), 55 degrees horizontal field of view. Two people of 1.75 m standing
    1 m apart around the origin (and up to about 3 m apart, from z = -1 to +1) are fully in view.

    Parameters
    ----------
    width, height : int, default=320, 240
        Image size in pixels.

    Returns
    -------
    Camera
        The default camera.
    """
    return Camera.look_at((0.0, 1.6, 4.0), (0.0, 0.9, 0.0), 55.0, width, height)


def camera_for_size(calibration: Camera | None, width: int, height: int) -> Camera:
    """The one camera every node uses for frames of ``width`` x ``height`` pixels.

    A calibration for that size is used as it is; one for another size of the same aspect ratio
    (within 1%) is scaled uniformly (the same camera at another resolution).

    Parameters
    ----------
    calibration : Camera or None
        The calibrated camera; None: :func:`default_camera` at that size (square pixels, the same
        55 degrees across the width for every aspect ratio).
    width, height : int
        Frame size in pixels.

    Returns
    -------
    Camera
        The camera for that frame size.

    Raises
    ------
    ValueError
        For another aspect ratio, which no scaling makes right.
    """
    if calibration is None:
        return default_camera(width, height)
    cw, ch = calibration.width, calibration.height
    if (cw, ch) == (width, height):
        return calibration
    if abs((width / height) / (cw / ch) - 1.0) > 0.01:
        raise ValueError(
            f"camera calibrated for {cw}x{ch} but the frames are {width}x{height} (another aspect "
            "ratio); calibrate for the frames' size"
        )
    s = width / cw
    return Camera(
        calibration.fx * s,
        calibration.fy * s,
        (calibration.cx + 0.5) * s - 0.5,
        (calibration.cy + 0.5) * s - 0.5,
        width,
        height,
        calibration.R,
        calibration.t,
    )


class CameraSchedule:
    """The graph's cameras over time, per frame size: each ``camera_info`` holds from its ``seq`` on.

    The calibration node publishes a refined camera for frames from a seq a little ahead of the one
    it was estimated on, so every subscriber switches at the same frame however late the message
    comes to it. A frame before the first camera of its size gets that first camera. In a lockstep
    graph the node also says, on every frame, from which seq the camera is not decided yet
    (``CameraInfo.undecided_from``): a subscriber that holds each frame until :meth:`decided` says so
    uses the same camera for it in every run, however far behind the calibration node runs.
    """

    def __init__(self) -> None:
        self._by_size: dict[tuple[int, int], list[tuple[int, Camera]]] = {}
        #: per size, the first seq whose camera is not decided yet (inf: none)
        self._undecided: dict[tuple[int, int], float] = {}

    def add(self, camera: Camera, from_seq: int = 0, undecided_from: int = -1) -> None:
        """Use ``camera`` for frames of its size from ``from_seq`` on (replaces one from the same seq).

        Parameters
        ----------
        camera : Camera
            The camera.
        from_seq : int, default=0
            First frame sequence number it holds for.
        undecided_from : int, default=-1
            The first frame seq whose camera is not decided yet (``CameraInfo.undecided_from``);
            negative: none, as for a fixed camera or the estimate's last.
        """
        size = (camera.width, camera.height)
        entries = [e for e in self._by_size.get(size, []) if e[0] != from_seq]
        # the same camera again (a lockstep calibration node says every frame how far it has
        # decided): one entry, so that the kept ones reach back as far as the changes do
        if not (entries and entries[-1][0] < from_seq and same_camera(entries[-1][1], camera)):
            entries.append((int(from_seq), camera))
            entries.sort(key=lambda e: e[0])
        self._by_size[size] = entries[-64:]
        before = self._undecided.get(size, 0.0)
        self._undecided[size] = float("inf") if undecided_from < 0 else max(before, float(undecided_from))

    def __contains__(self, size: tuple[int, int]) -> bool:
        return size in self._by_size

    def decided(self, size: tuple[int, int], seq: int) -> bool:
        """Whether the camera of frame ``seq`` of ``size`` is known and no later message can change it.

        Parameters
        ----------
        size : tuple of (int, int)
            Frame (width, height) in pixels.
        seq : int
            Frame sequence number.

        Returns
        -------
        bool
            False before any camera of that size came, or from the seq its camera is undecided.
        """
        return size in self._by_size and seq < self._undecided[size]

    def get(self, size: tuple[int, int], seq: int | None = None) -> Camera | None:
        """The camera for frame ``seq`` of ``size``.

        Parameters
        ----------
        size : tuple of (int, int)
            Frame (width, height) in pixels.
        seq : int or None, default=None
            Frame sequence number; None: the newest camera.

        Returns
        -------
        Camera or None
            The camera; None when none has come for that size.
        """
        entries = self._by_size.get(size)
        if not entries:
            return None
        if seq is None:
            return entries[-1][1]
        held = [c for s, c in entries if s <= seq]
        return held[-1] if held else entries[0][1]


def same_camera(a: Camera, b: Camera) -> bool:
    """Whether two cameras project every point to the same pixel (the same numbers).

    Parameters
    ----------
    a, b : Camera
        The cameras.

    Returns
    -------
    bool
        True when their intrinsics, size, rotation and translation are equal.
    """
    return (
        (a.fx, a.fy, a.cx, a.cy, a.width, a.height) == (b.fx, b.fy, b.cx, b.cy, b.width, b.height)
        and np.array_equal(a.R, b.R)
        and np.array_equal(a.t, b.t)
    )


def camera_param_problem(value: dict[str, Any]) -> str | None:
    """Check a camera node parameter.

    Parameters
    ----------
    value : dict
        Calibration for :meth:`Camera.from_dict`; empty: use the default camera.

    Returns
    -------
    str or None
        None when ``value`` is empty or a valid calibration, else the error naming the bad key.
    """
    if not value:
        return None
    try:
        Camera.from_dict(value)
    except (ValueError, TypeError) as exc:
        return str(exc)
    return None
