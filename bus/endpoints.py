"""Where topics live: run directories and the two endpoints of every topic.

Each topic is published on three sockets: a *reliable* one (XPUB with ZMQ_XPUB_NODROP: the publisher
waits when a reliable subscriber lags), a *latest* one (lossy, a queue of two, for live subscribers
that only want the newest message) and a *queued* one (lossy with a deep queue, for recorders that
must never hold the publisher back but should lose nothing while they keep up). With ``ipc://`` they
live in a per-run directory of mode 0700; with ``tcp://host:port`` they take ``port``, ``port + 1``
and ``port + 2``.
"""

from __future__ import annotations

import hashlib
import os
import re
import stat
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

_IPC_MAX = 100  # sun_path is 108 bytes on Linux, keep a margin


class RunDirError(ValueError):
    """A folder for sockets and run directories that is not safely the user's own; the message says
    why and what to do (a ValueError, as the other set-up errors that commands report).
    """


def private_dir(path: Path) -> Path:
    """``path`` as a folder of mode 0700 owned by this user: created so, or checked.

    Anyone who can write into the folder can replace a node's socket or the ``latest`` link that
    ``topic``, ``node`` and ``bag`` follow, so a folder owned by another user, a symbolic link, or a
    folder others may write to is refused (RunDirError); read and search bits for others on a
    folder of one's own are only taken away.

    Parameters
    ----------
    path : Path
        The folder (created with its parents when missing).

    Returns
    -------
    Path
        ``path``, mode 0700.

    Raises
    ------
    RunDirError
        For a symbolic link or non-folder, a folder owned by another user, or one others may write to.
    """
    path.mkdir(mode=0o700, parents=True, exist_ok=True)
    st = os.lstat(path)
    fix = "remove it, or set COUNTERPART_HOME to a folder of your own (e.g. mkdir -m 700 ~/.counterpart)"
    if stat.S_ISLNK(st.st_mode) or not stat.S_ISDIR(st.st_mode):
        raise RunDirError(
            f"{path} is {'a symbolic link' if stat.S_ISLNK(st.st_mode) else 'not a folder'}, "
            f"not a folder of your own for the graph's sockets: {fix}"
        )
    if st.st_uid != os.getuid():
        raise RunDirError(
            f"{path} belongs to user id {st.st_uid}, not to you ({os.getuid()}): whoever owns it can "
            f"read and replace the graph's sockets; {fix}"
        )
    if st.st_mode & 0o022:
        raise RunDirError(
            f"{path} is writable by others (mode {stat.S_IMODE(st.st_mode):04o}): anyone could plant "
            f"sockets or a 'latest' link there; check what it holds and chmod 700 it, or {fix}"
        )
    if stat.S_IMODE(st.st_mode) != 0o700:
        os.chmod(path, 0o700)
    return path


def base_dir() -> Path:
    """Per-user folder holding run directories (``$COUNTERPART_HOME``, ``$XDG_RUNTIME_DIR/counterpart``
    or ``/tmp/counterpart-UID``), mode 0700 and the user's own (:func:`private_dir`).

    Returns
    -------
    Path
        The folder.

    Raises
    ------
    RunDirError
        As :func:`private_dir`.
    """
    env = os.environ.get("COUNTERPART_HOME")
    if env:
        root = Path(env)
    elif os.environ.get("XDG_RUNTIME_DIR") and Path(os.environ["XDG_RUNTIME_DIR"]).is_dir():
        root = Path(os.environ["XDG_RUNTIME_DIR"]) / "counterpart"
    else:
        root = Path(tempfile.gettempdir()) / f"counterpart-{os.getuid()}"
    return private_dir(root)


def new_run_dir() -> Path:
    """A fresh run directory, mode 0700, named by time and pid.

    Returns
    -------
    Path
        The new folder, under :func:`base_dir`.
    """
    path = base_dir() / f"run-{time.strftime('%Y%m%d-%H%M%S')}-{os.getpid()}"
    path.mkdir(mode=0o700)
    os.chmod(path, 0o700)
    return path


def standalone_dir() -> Path:
    """Shared folder for nodes started alone (``counterpart run``) so they find each other by topic.

    Returns
    -------
    Path
        ``base_dir() / standalone``, mode 0700.
    """
    return private_dir(base_dir() / "standalone")


@dataclass(frozen=True)
class TopicEndpoints:
    """The endpoints of one topic (what publishers bind and subscribers connect).

    Parameters
    ----------
    reliable : str
        Endpoint of the reliable stream.
    latest : str
        Endpoint of the latest-only stream.
    queued : str, default=""
        Endpoint of the queued stream; empty in the registry of a launcher older than it.
    """

    reliable: str
    latest: str
    queued: str = ""

    def to_dict(self) -> dict[str, str]:
        """The registry's form of the endpoints.

        Returns
        -------
        dict of str to str
            ``reliable``, ``latest`` and ``queued``.
        """
        return {"reliable": self.reliable, "latest": self.latest, "queued": self.queued}

    @staticmethod
    def from_dict(d: dict[str, str]) -> TopicEndpoints:
        """The endpoints from their registry form.

        Parameters
        ----------
        d : dict of str to str
            ``reliable``, ``latest`` and (optional) ``queued``, as :meth:`to_dict` writes.

        Returns
        -------
        TopicEndpoints
            The endpoints (``queued`` empty when absent).
        """
        return TopicEndpoints(d["reliable"], d["latest"], d.get("queued", ""))


def _file_stem(topic: str) -> str:
    stem = re.sub(r"[^A-Za-z0-9_.-]", "~", topic)
    if len(stem) > 40:
        stem = stem[:24] + "-" + hashlib.sha1(topic.encode()).hexdigest()[:12]
    return stem


def ipc_endpoints(run_dir: Path, topic: str) -> TopicEndpoints:
    """The unix-socket endpoints of a topic in a run directory.

    Parameters
    ----------
    run_dir : Path
        The run directory holding the sockets.
    topic : str
        The topic (characters unsafe in a file name replaced, long names shortened with a hash).

    Returns
    -------
    TopicEndpoints
        ``ipc://`` endpoints ``STEM.r``, ``STEM.l`` and ``STEM.q``.

    Raises
    ------
    ValueError
        When the socket path is too long for a unix socket.
    """
    stem = _file_stem(topic)
    rel, lat = run_dir / f"{stem}.r", run_dir / f"{stem}.l"
    if len(str(rel)) > _IPC_MAX:
        raise ValueError(f"ipc path {rel} is too long for a unix socket; set COUNTERPART_HOME to a shorter folder")
    return TopicEndpoints(f"ipc://{rel}", f"ipc://{lat}", f"ipc://{run_dir / f'{stem}.q'}")


def tcp_endpoints(address: str) -> TopicEndpoints:
    """The endpoints of a topic on TCP: reliable on port, latest on port + 1, queued on port + 2.

    Parameters
    ----------
    address : str
        ``tcp://HOST:PORT``.

    Returns
    -------
    TopicEndpoints
        The three endpoints.

    Raises
    ------
    ValueError
        For an address of another form, or a port out of range.
    """
    m = re.fullmatch(r"tcp://([^:/]+):(\d+)", address)
    if not m:
        raise ValueError(f"tcp endpoint {address!r}: expected tcp://HOST:PORT")
    host, port = m.group(1), int(m.group(2))
    if not 0 < port < 65534:
        raise ValueError(f"tcp endpoint {address!r}: port out of range (it takes port to port + 2)")
    return TopicEndpoints(f"tcp://{host}:{port}", f"tcp://{host}:{port + 1}", f"tcp://{host}:{port + 2}")


def bind_address(endpoint: str) -> str:
    """What a publisher binds for ``endpoint``: a named host is bound as given, ``*`` is refused
    unless spelled out as ``0.0.0.0`` (so nothing listens beyond loopback by accident).

    Parameters
    ----------
    endpoint : str
        A ZeroMQ endpoint.

    Returns
    -------
    str
        ``endpoint`` unchanged.

    Raises
    ------
    ValueError
        For ``tcp://*``.
    """
    if endpoint.startswith("tcp://*"):
        raise ValueError(f"endpoint {endpoint}: bind to an explicit host (127.0.0.1, or 0.0.0.0 to listen everywhere)")
    return endpoint
