"""The calibration node: the one camera of the graph, on ``camera_info`` (camera.CameraInfo, latched).

Frames in (their size), CameraInfo out: once for the first frame, and again only when
the frames change size. The camera is the calibration ``file`` (JSON or YAML, ``Camera.to_dict`` or
the look-at form), scaled to the frames' size where they have its aspect ratio, or, without a file,
the default camera at the frames' size (``body.camera.camera_for_size``). The tracker and the
renderer subscribe to it, so the skeleton, the partner and the tracked body are all projected with
the same camera. Run in a graph (``run: nodes.calibration``) or alone::

    python -m nodes.calibration --param file=camera.yaml
"""
from __future__ import annotations

from bus import Input, Node, Output, Param
from body.camera import Camera, camera_for_size, camera_to_info, load_camera_file
from messages import CameraInfo, Frame


def _check_file(value: str) -> str | None:
    if not value:
        return None
    try:
        load_camera_file(value)
    except ValueError as exc:
        return str(exc)
    return None


class Calibration(Node):
    """Publishes the camera of the frames' size, latched, so that nodes joining later get it too."""

    inputs = {"frame": Input(Frame, doc="the camera's frames (their size)")}
    outputs = {"camera_info": Output(CameraInfo, "the camera for the frames' size, once (again when the size "
                                                 "changes); latched", latched=True)}
    params = {"file": Param(str, "", "calibration file (JSON/YAML: fx, fy, cx, cy, width, height, R, t, or eye, "
                                     "target, fov_deg, width, height); '': the default camera at the frames' size",
                            check=_check_file)}

    def setup(self) -> None:
        self.calibration: Camera | None = load_camera_file(self.p["file"]) if self.p["file"] else None
        self.size: tuple[int, int] | None = None

    def on_frame(self, msg: Frame) -> None:
        shape = msg.image.shape
        size = (int(shape[1]), int(shape[0])) if len(shape) >= 2 else (0, 0)
        if size == self.size or min(size) <= 0:
            return
        try:
            camera = camera_for_size(self.calibration, *size)
        except ValueError as exc:
            # a file for frames of another shape: no camera to agree on, so nothing can go on. Leaving
            # before this first message is handled makes it a failure to start: the launcher ends the
            # whole graph at once with this exit code (ending cleanly, its subscribers would wait)
            self.log.error("parameter 'file': %s", exc)
            raise SystemExit(2) from None
        self.size = size
        source = f"file:{self.p['file']}" if self.p["file"] else "default"
        self.publish("camera_info", camera_to_info(camera, msg.stamp, msg.seq, source))
        self.log.info("camera for %dx%d frames (%s): f %.1f px, centre %.1f m above the ground", *size, source,
                      camera.fx, camera.centre[1])


NODE = Calibration

if __name__ == "__main__":
    Calibration.main()
