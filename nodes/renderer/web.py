"""The live web page: standard-library HTTP server in a thread, serving the composited video.

Routes::

    GET  /              the page (``page.html``, shipped with the package)
    GET  /stream.mjpg   the video as Motion-JPEG (multipart/x-mixed-replace), one part per new frame
    GET  /frame.jpg     the newest frame as one JPEG
    GET  /snapshot.png  the newest frame as PNG
    GET  /stats         JSON: the newest NodeStats of every node, by node name
    GET  /state         JSON: controls and overlays in force, choices for the page, newest frame seq
    POST /control       JSON object of controls (``counterpart.nodes.renderer.controls.parse_control``);
                        answers the accepted control, or 400 with {"error": ...}

The server binds ``127.0.0.1`` unless told otherwise. Bound to loopback it also refuses requests
whose Host header is not a loopback name (a web page elsewhere cannot reach it by DNS
rebinding), and ``/control`` takes only ``application/json`` (cross-site forms cannot post it
without a CORS preflight, which this server never grants).

Threads: handlers run in server threads and never touch the bus. The node pushes images with
:meth:`LiveServer.push`; controls go back through the ``on_control`` callback, which must be
thread-safe (the node queues them and publishes from its own thread).
"""

from __future__ import annotations

import ipaddress
import json
import logging
import threading
from collections.abc import Callable
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from typing import Any

import numpy as np

from .video import encode_image

log = logging.getLogger(__name__)

BOUNDARY = "cpframe"
MAX_BODY = 64 * 1024
LOOPBACK_NAMES = ("localhost", "127.0.0.1", "::1", "[::1]")


def page_html() -> str:
    """The page template shipped in the package (``nodes/renderer/page.html``).

    Returns
    -------
    str
        The page's HTML.
    """
    return resources.files(__package__).joinpath("page.html").read_text(encoding="utf-8")


def is_loopback(host: str) -> bool:
    """Whether a host name or address is loopback only.

    Parameters
    ----------
    host : str
        ``localhost`` or an IPv4/IPv6 address (brackets allowed).

    Returns
    -------
    bool
        True for ``localhost`` and loopback addresses; False for anything else, names included.
    """
    if host in ("localhost",):
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


class LiveServer:
    """The web page of one renderer.

    Parameters
    ----------
    host : str
        Where to listen.
    port : int
        Port to listen on (0: a free port, see :attr:`port` after :meth:`start`).
    on_control : callable
        Called with the request's JSON object; returns the accepted control as a dict or raises
        ValueError (answered 400). Runs in a server thread.
    state : callable
        Returns the JSON-able state for ``/state``.
    stats : callable
        Returns the JSON-able stats for ``/stats``.
    jpeg_quality : int, default=80
        JPEG quality of the stream, 1-100.
    """

    def __init__(
        self,
        host: str,
        port: int,
        on_control: Callable[[Any], dict[str, Any]],
        state: Callable[[], dict[str, Any]],
        stats: Callable[[], dict[str, Any]],
        jpeg_quality: int = 80,
    ) -> None:
        self.host = host
        self.requested_port = port
        self.on_control = on_control
        self.state = state
        self.stats = stats
        self.jpeg_quality = jpeg_quality
        self.page = page_html()
        self.cond = threading.Condition()
        self.seq = -1
        self.image: np.ndarray | None = None
        self._jpeg: tuple[int, bytes] | None = None
        self.closing = False
        self.httpd: ThreadingHTTPServer | None = None
        self.thread: threading.Thread | None = None
        self.clients = 0

    # ------------------------------------------------------------------------------- life cycle
    def start(self) -> LiveServer:
        """Bind and serve in a daemon thread.

        Returns
        -------
        LiveServer
            self.

        Raises
        ------
        OSError
            Naming the address, when it cannot be bound (port in use, bad host).
        """
        handler = type("Handler", (_Handler,), {"live": self})
        try:
            self.httpd = ThreadingHTTPServer((self.host, self.requested_port), handler)
        except OSError as exc:
            raise OSError(
                f"cannot serve the web page on {self.host}:{self.requested_port}: {exc.strerror or exc}"
            ) from None
        self.httpd.daemon_threads = True
        self.thread = threading.Thread(
            target=self.httpd.serve_forever, kwargs={"poll_interval": 0.2}, name="renderer-web", daemon=True
        )
        self.thread.start()
        return self

    @property
    def port(self) -> int:
        return self.httpd.server_address[1] if self.httpd else self.requested_port

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}/"

    def close(self) -> None:
        """Stop serving; open streams end within about a second."""
        with self.cond:
            self.closing = True
            self.cond.notify_all()
        if self.httpd is not None:
            self.httpd.shutdown()
            self.httpd.server_close()
            self.httpd = None

    # ----------------------------------------------------------------------------------- frames
    def push(self, image: np.ndarray, seq: int) -> None:
        """Make ``image`` the newest frame.

        Parameters
        ----------
        image : ndarray of shape (H, W, 3), dtype uint8
            BGR frame, kept by reference: do not modify it.
        seq : int
            The frame's sequence number.
        """
        with self.cond:
            self.image, self.seq = image, int(seq)
            self.cond.notify_all()

    def jpeg(self) -> tuple[int, bytes] | None:
        """The newest frame as JPEG, encoded once per frame.

        Returns
        -------
        tuple of (int, bytes) or None
            (seq, JPEG bytes) of the newest frame, or None before the first.
        """
        with self.cond:
            image, seq, cached = self.image, self.seq, self._jpeg
        if image is None:
            return None
        if cached is not None and cached[0] == seq:
            return cached
        data = encode_image(image, ".jpg", self.jpeg_quality)
        with self.cond:
            if self.seq == seq:
                self._jpeg = (seq, data)
        return seq, data

    def wait_newer(self, seq: int, timeout: float) -> bool:
        """Wait until a frame newer than ``seq`` is pushed.

        Parameters
        ----------
        seq : int
            Sequence number of the frame the caller has.
        timeout : float
            Longest wait, seconds.

        Returns
        -------
        bool
            True when a newer frame came; False on timeout or closing.
        """
        with self.cond:
            self.cond.wait_for(lambda: self.seq != seq or self.closing, timeout)
            return self.seq != seq and not self.closing


class _Handler(BaseHTTPRequestHandler):
    live: LiveServer
    server_version = "counterpart-renderer"
    protocol_version = "HTTP/1.1"

    def log_message(self, fmt: str, *args: Any) -> None:
        log.debug("%s %s", self.address_string(), fmt % args)

    # ----------------------------------------------------------------------------------- helpers
    def _send(self, status: int, body: bytes, ctype: str, extra: dict[str, str] | None = None) -> None:
        self.send_response(status)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        for k, v in (extra or {}).items():
            self.send_header(k, v)
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def _json(self, status: int, obj: Any) -> None:
        self._send(status, json.dumps(obj).encode(), "application/json")

    def _host_ok(self) -> bool:
        if not is_loopback(self.live.host):
            return True
        host = (self.headers.get("Host") or "").strip()
        name = host[: host.index("]") + 1] if host.startswith("[") and "]" in host else host.split(":", 1)[0]
        return name in LOOPBACK_NAMES or is_loopback(name)

    def _refuse_host(self) -> bool:
        if self._host_ok():
            return False
        self._json(HTTPStatus.FORBIDDEN, {"error": f"this page is served on loopback only; open it as {self.live.url}"})
        return True

    # ------------------------------------------------------------------------------------ routes
    def do_HEAD(self) -> None:
        self.do_GET()

    def do_GET(self) -> None:
        if self._refuse_host():
            return
        path = self.path.split("?", 1)[0]
        live = self.live
        if path in ("/", "/index.html"):
            self._send(HTTPStatus.OK, live.page.encode("utf-8"), "text/html; charset=utf-8")
        elif path == "/stream.mjpg":
            self._stream()
        elif path == "/frame.jpg":
            got = live.jpeg()
            if got is None:
                return self._json(HTTPStatus.SERVICE_UNAVAILABLE, {"error": "no frame rendered yet"})
            self._send(HTTPStatus.OK, got[1], "image/jpeg", {"X-Frame-Seq": str(got[0])})
        elif path == "/snapshot.png":
            with live.cond:
                image, seq = live.image, live.seq
            if image is None:
                return self._json(HTTPStatus.SERVICE_UNAVAILABLE, {"error": "no frame rendered yet"})
            self._send(
                HTTPStatus.OK,
                encode_image(image, ".png"),
                "image/png",
                {"X-Frame-Seq": str(seq), "Content-Disposition": f'inline; filename="frame{seq:06d}.png"'},
            )
        elif path == "/stats":
            self._json(HTTPStatus.OK, live.stats())
        elif path == "/state":
            self._json(HTTPStatus.OK, live.state())
        else:
            self._json(HTTPStatus.NOT_FOUND, {"error": f"no page {path!r}; try / "})

    def do_POST(self) -> None:
        if self._refuse_host():
            return
        if self.path.split("?", 1)[0] != "/control":
            return self._json(HTTPStatus.NOT_FOUND, {"error": f"cannot POST to {self.path!r}; use /control"})
        if (self.headers.get("Content-Type") or "").split(";")[0].strip().lower() != "application/json":
            return self._json(HTTPStatus.UNSUPPORTED_MEDIA_TYPE, {"error": "POST /control takes application/json"})
        try:
            n = int(self.headers.get("Content-Length") or 0)
        except ValueError:
            n = -1
        if not 0 < n <= MAX_BODY:
            return self._json(HTTPStatus.BAD_REQUEST, {"error": f"Content-Length must be 1..{MAX_BODY} bytes"})
        try:
            data = json.loads(self.rfile.read(n))
            accepted = self.live.on_control(data)
        except (ValueError, UnicodeDecodeError) as exc:  # JSONDecodeError is a ValueError
            return self._json(HTTPStatus.BAD_REQUEST, {"error": str(exc)})
        self._json(HTTPStatus.OK, accepted)

    def _stream(self) -> None:
        live = self.live
        self.send_response(HTTPStatus.OK)
        self.send_header("Content-Type", f"multipart/x-mixed-replace; boundary={BOUNDARY}")
        self.send_header("Cache-Control", "no-store")
        self.send_header("Connection", "close")
        self.end_headers()
        self.close_connection = True
        last = -1
        with live.cond:
            live.clients += 1
        try:
            while not live.closing:
                got = live.jpeg()
                if got is None or got[0] == last:
                    live.wait_newer(last, 1.0)
                    continue
                last, data = got
                self.wfile.write(
                    f"--{BOUNDARY}\r\nContent-Type: image/jpeg\r\nContent-Length: {len(data)}\r\n"
                    f"X-Frame-Seq: {last}\r\n\r\n".encode()
                    + data
                    + b"\r\n"
                )
                self.wfile.flush()
        except (BrokenPipeError, ConnectionResetError, TimeoutError):
            pass  # the viewer went away
        finally:
            with live.cond:
                live.clients -= 1


__all__ = ["LiveServer", "page_html", "is_loopback", "BOUNDARY"]
