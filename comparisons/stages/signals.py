"""SIGTERM and Ctrl-C: how the main process unwinds, and how its worker processes end with it.

The main process turns the first SIGTERM into `Terminated` and the first SIGINT into
``KeyboardInterrupt``, so every ``finally`` and context manager on the way out runs (staging
folders are removed, workers killed); a second signal during that unwind ends the process at
once (`install_handlers`). A worker forked from it (`child_init`) puts SIGTERM back to its
default (it ends the worker, silently), ignores SIGINT (Ctrl-C reaches the whole process group:
the main process decides) and, on Linux, asks the kernel for SIGKILL when its parent dies,
whatever ended the parent. Forks happen with both signals blocked (`blocked`), so no worker
runs a Python handler it inherited, not even between the fork and `child_init`.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
from contextlib import contextmanager
from typing import Iterator

__all__ = ["SIGNALS", "Terminated", "blocked", "child_init", "exit_at_once", "flush_streams",
           "install_handlers", "raise_terminated", "restore_handlers", "terminating"]

SIGNALS = (signal.SIGINT, signal.SIGTERM)
PR_SET_PDEATHSIG = 1    # <linux/prctl.h>
WHAT = {signal.SIGINT: "interrupted", signal.SIGTERM: "terminated"}


class Terminated(KeyboardInterrupt):
    """SIGTERM reached the main process: an interruption like Ctrl-C (never caught by an
    ``except Exception``), so every ``finally`` and context manager on the way out runs."""


def raise_terminated(signum, frame):
    """A SIGTERM handler: turn the signal into `Terminated`."""
    raise Terminated("terminated (SIGTERM)")


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def _is_default(signum: int, handler) -> bool:
    return handler in (signal.SIG_DFL, None) or (
        signum == signal.SIGINT and handler is signal.default_int_handler)


def install_handlers(program: str) -> dict:
    """SIGTERM and SIGINT, where they still have Python's defaults, unwind once: the first
    raises (`Terminated`, ``KeyboardInterrupt``), a second one during the unwind writes one
    line (``program: terminated again; stopped at once``) and exits 128 + the signal's number
    at once. Returns what `restore_handlers` puts back; nothing outside the main thread."""
    if not _main_thread():
        return {}

    def again(signum, frame):
        os.write(2, f"{program}: {WHAT[signum]} again; stopped at once\n".encode())
        os._exit(128 + signum)

    def first(signum, frame):
        for s in SIGNALS:
            signal.signal(s, again)
        if signum == signal.SIGTERM:
            raise Terminated("terminated (SIGTERM)")
        raise KeyboardInterrupt

    previous = {s: signal.getsignal(s) for s in SIGNALS}
    for s, handler in previous.items():
        if _is_default(s, handler):
            signal.signal(s, first)
    return previous


def restore_handlers(previous: dict) -> None:
    for s, handler in previous.items():
        signal.signal(s, handler if handler is not None else signal.SIG_DFL)


@contextmanager
def terminating() -> Iterator[None]:
    """SIGTERM raises `Terminated` inside the block where it would otherwise end the process
    without clean-up (a library caller that set no handler); main thread only."""
    if not _main_thread() or not _is_default(signal.SIGTERM, signal.getsignal(signal.SIGTERM)):
        yield
        return
    previous = signal.signal(signal.SIGTERM, raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


@contextmanager
def blocked() -> Iterator[None]:
    """SIGINT and SIGTERM held back in this thread (delivered when the block ends): around a
    fork, and around clean-up that must not be cut."""
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def child_init(parent: int) -> None:
    """First thing in a process forked (with `blocked` signals) from ``parent``: SIGTERM at its
    default, SIGINT ignored, SIGKILL when the parent dies (Linux); if the parent is already
    gone (it died before the request reached the kernel) the child exits now. Then the
    signals are unblocked."""
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        try:
            import ctypes
            ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
        except (OSError, AttributeError):
            pass
    if os.getppid() != parent:
        os._exit(1)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, SIGNALS)


def exit_at_once(status: int) -> None:
    """End the process now with ``status``, its output flushed: after an interruption, once
    the unwind has cleaned up, the interpreter's own shutdown (unloading Pinocchio, Exudyn,
    MuJoCo, matplotlib) is all that is left, and it took 0.9 s on a loaded 2-core machine."""
    flush_streams()
    os._exit(status)


def flush_streams() -> None:
    """sys.stdout and sys.stderr written out (before a fork, whose child would write an
    inherited buffer again, and before `exit_at_once`)."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (AttributeError, OSError, ValueError):
            pass
