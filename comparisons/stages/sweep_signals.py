"""Ctrl-C and SIGTERM while a sweep talks to Dask: noted, then acted on at one place.

    with deferred_signals() as stop:
        ... start the cluster, compute (calling stop.check() while waiting), close ...
    stop.check()          # KeyboardInterrupt or `signals.Terminated`, raised from the sweep's code

Raised from a signal handler, a ``KeyboardInterrupt`` lands in whatever Python code the main
thread runs at that moment: inside Dask's client, its event-loop callbacks or a garbage
collector callback, which printed tracebacks (seven on main) or swallowed it (measured: a
``KeyboardInterrupt`` "ignored" in ``distributed.gc``, the sweep running on to the end). Inside
the block the first SIGINT or SIGTERM only records itself; the sweep's loop polls
`StopRequest.check`, which raises the matching exception between two futures, so the client and
the local cluster are closed by the sweep's own ``finally`` and the finished chunk files stay
(each was renamed into place complete). A second signal writes one line and ends the process
at once (as `signals.install_handlers`' second signal does); after a stop the block leaves that
"at once" handler in place for the rest of the unwind.
"""

from __future__ import annotations

import os
import signal
import threading
from contextlib import contextmanager
from typing import Iterator

from .signals import SIGNALS, WHAT, Terminated

__all__ = ["StopRequest", "deferred_signals"]


class StopRequest:
    """The first SIGINT or SIGTERM received inside `deferred_signals` (``signum``, or None)."""

    def __init__(self) -> None:
        self.signum: int | None = None

    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` (SIGINT) or `Terminated` (SIGTERM) if one arrived."""
        if self.signum == signal.SIGTERM:
            raise Terminated("terminated (SIGTERM)")
        if self.signum is not None:
            raise KeyboardInterrupt


def _at_once(program: str):
    def again(signum, frame):
        os.write(2, f"{program}: {WHAT[signum]} again; stopped at once\n".encode())
        os._exit(128 + signum)
    return again


@contextmanager
def deferred_signals(program: str = "bicycle-xval") -> Iterator[StopRequest]:
    """SIGINT and SIGTERM noted in a `StopRequest` inside the block (module docstring); outside
    the main thread, where no handler can be set, a request that never fires."""
    stop = StopRequest()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return
    again = _at_once(program)

    def note(signum, frame):
        if stop.signum is not None:
            again(signum, frame)
        stop.signum = signum

    # a signal the process was started ignoring (a background job's SIGINT) stays ignored,
    # as `run` leaves it (signals.install_handlers)
    previous = {s: signal.getsignal(s) for s in SIGNALS}
    noted = [s for s in SIGNALS if previous[s] is not signal.SIG_IGN]
    for s in noted:
        signal.signal(s, note)
    try:
        yield stop
    finally:
        for s in noted:
            signal.signal(s, again if stop.signum is not None else
                          previous[s] if previous[s] is not None else signal.SIG_DFL)
