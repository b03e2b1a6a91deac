"""A learning step run in a worker thread while the caller goes on, joined before the next one.

A background model's update from frame t (blending it into the model, ViBe's sample updates)
is not needed for frame t's labels, only for frame t + 1's. ``DeferredStep.submit`` runs it in a
single worker thread and returns at once, so on two cores it overlaps the rest of the caller's
work on frame t (clean-up, tracking, splines); ``join`` waits for it and re-raises its error.
The owner joins before each new step and before any read of the state the step writes, so the
results are those of running the steps in line. Before a fork every pending step is joined,
and a child process starts its own worker.

Both threads run numpy and OpenCV calls, which release the GIL, between stretches of Python
that hold it. A thread back from such a call waits for the GIL until the other thread's
stretch ends, or until the interpreter's switch interval (5 ms by default) forces a hand-over:
with the default, the caller's short calls queued behind the worker's Python and the two threads
overlapped poorly. The first worker therefore lowers the process's switch interval to
``SWITCH_INTERVAL_S`` (never raises it).
"""

from __future__ import annotations

import os
import sys
import weakref
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any

_LIVE: weakref.WeakSet[DeferredStep] = weakref.WeakSet()

# seconds: a thread back from a short call soon gets the GIL; 1 ms gained less and 0.05 ms no more
# (bench/silhouette.py's two-core speed figures, ours beside MOG2)
SWITCH_INTERVAL_S = 2e-4


class _Worker:
    """The single worker thread of one or more ``DeferredStep``: their calls run in it one after
    another, in the order submitted. Started on first use, again in a forked child.
    """

    def __init__(self, name: str) -> None:
        self.name = name
        self._pool: ThreadPoolExecutor | None = None
        self._pid = -1

    def submit(self, fn: Callable[..., Any], *args: Any) -> Future:
        if self._pool is None or self._pid != os.getpid():
            if sys.getswitchinterval() > SWITCH_INTERVAL_S:
                sys.setswitchinterval(SWITCH_INTERVAL_S)
            self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix=self.name)
            self._pid = os.getpid()
        return self._pool.submit(fn, *args)

    def __getstate__(self) -> dict[str, Any]:
        return {"name": self.name, "_pool": None, "_pid": -1}


class DeferredStep:
    """One deferred call at a time in a worker thread (see the module docstring).

    Parameters
    ----------
    name : str
        Prefix of the worker thread's name.
    share_with : DeferredStep or None, default=None
        Run in that step's worker thread (after whatever it was given before) instead of a thread
        of its own: two models' steps then take turns on one spare core rather than three
        threads contending for two.
    """

    def __init__(self, name: str, share_with: DeferredStep | None = None) -> None:
        self.name = name
        self._worker = _Worker(name) if share_with is None else share_with._worker
        self._pending: Future | None = None
        _LIVE.add(self)

    def submit(self, fn: Callable[..., Any], *args: Any) -> None:
        """Run ``fn(*args)`` in the worker, after the previous call has finished.

        Parameters
        ----------
        fn : callable
            The step; it must not touch anything the caller changes before the next ``join``.
        *args : Any
            Its arguments.
        """
        self.join()
        self._pending = self._worker.submit(fn, *args)

    def join(self) -> Any:
        """Wait for the pending call, if any; re-raise its exception.

        Returns
        -------
        Any
            What the pending call returned (None when there was none).
        """
        if self._pending is not None:
            pending, self._pending = self._pending, None
            return pending.result()
        return None

    def __getstate__(self) -> dict[str, Any]:
        self.join()
        # a worker shared by two steps stays shared in the copy (pickle keeps shared references)
        return {"name": self.name, "_worker": self._worker, "_pending": None}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        _LIVE.add(self)


def _join_all() -> None:
    for step in list(_LIVE):
        step.join()


os.register_at_fork(before=_join_all)
