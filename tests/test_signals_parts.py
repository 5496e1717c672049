"""Parts of the signal handling (comparisons/stages/signals.py) that run only in a forked
worker or at the very end of the process, issue 24: `child_init`, the second-signal handler
of `install_handlers` and `exit_at_once`. They are tested in this process with every system
call replaced by a recorder: no signal is sent, no handler installed, nothing exits (the
recorded ``os._exit`` raises instead). Expected values are the module's documented contract
and POSIX / Linux constants: a worker's SIGTERM at SIG_DFL and SIGINT at SIG_IGN, then
prctl(PR_SET_PDEATHSIG = 1 from <linux/prctl.h>, SIGKILL = 9) on Linux, exit status 1 when
the parent is already gone, and only then SIGINT and SIGTERM unblocked; a second signal
writes one line to fd 2 (stderr) and exits with the status a shell reports for a death by
that signal, 128 + its number (SIGINT 2 -> 130, SIGTERM 15 -> 143). Planted bugs each test
was seen failing on are named in it."""

import ctypes
import os
import signal
import sys

import pytest

from comparisons.stages.signals import Terminated, child_init, exit_at_once, install_handlers

PARENT = 4242


class _Exited(Exception):
    """What the recorded os._exit raises instead of ending the process."""


@pytest.fixture
def log(monkeypatch):
    """os._exit, os.write, signal.signal, signal.pthread_sigmask, os.getppid and ctypes.CDLL
    replaced by recorders appending to one list (in call order); the parent is PARENT."""
    calls = []

    def _exit(status):
        calls.append(("exit", status))
        raise _Exited(status)

    def write(fd, data):
        calls.append(("write", fd, data))
        return len(data)

    def set_handler(signum, handler):
        calls.append(("signal", signum, handler))

    def sigmask(how, signals):
        calls.append(("sigmask", how, frozenset(signals)))
        return set()

    class _Libc:
        def prctl(self, option, arg2):
            calls.append(("prctl", option, arg2))
            return 0

    def cdll(name, mode=0, handle=None, use_errno=False, use_last_error=False, winmode=None):
        calls.append(("CDLL", name))
        return _Libc()

    monkeypatch.setattr(os, "_exit", _exit)
    monkeypatch.setattr(os, "write", write)
    monkeypatch.setattr(os, "getppid", lambda: PARENT)
    monkeypatch.setattr(signal, "signal", set_handler)
    monkeypatch.setattr(signal, "pthread_sigmask", sigmask)
    monkeypatch.setattr(ctypes, "CDLL", cdll)
    monkeypatch.setattr(sys, "platform", "linux")
    return calls


UNBLOCK_BOTH = ("sigmask", signal.SIG_UNBLOCK, frozenset({signal.SIGINT, signal.SIGTERM}))


# -- child_init ---------------------------------------------------------------------------------

def test_a_linux_worker_sets_its_handlers_asks_for_sigkill_then_unblocks(log):
    """A worker whose parent is alive, on Linux: SIGTERM back to SIG_DFL, SIGINT SIG_IGN, the
    process's own symbols (CDLL(None): libc) asked prctl(PR_SET_PDEATHSIG=1, SIGKILL=9), no
    exit, and last both signals unblocked (SIG_UNBLOCK of SIGINT and SIGTERM). Planted: SIGTERM
    set to None / left out, SIGINT's handler None, prctl's option None or its signal None
    or missing, CDLL without the library name, the platform test on 'LINUX', the parent test
    inverted (the worker exited with its parent alive), the unblock with how=None or no
    signal set."""
    child_init(PARENT)
    assert log == [("signal", signal.SIGTERM, signal.SIG_DFL),
                   ("signal", signal.SIGINT, signal.SIG_IGN),
                   ("CDLL", None),
                   ("prctl", 1, 9),
                   UNBLOCK_BOTH]


def test_a_worker_whose_parent_is_gone_exits_1_with_its_signals_still_blocked(log, monkeypatch):
    """os.getppid() no longer the parent (it died before the request reached the kernel, the
    worker was re-parented): the worker exits with status 1 at once, before unblocking
    anything (a pending SIGINT or SIGTERM must not reach it). Planted: os._exit(None),
    os._exit(2)."""
    monkeypatch.setattr(os, "getppid", lambda: 1)
    with pytest.raises(_Exited):
        child_init(PARENT)
    assert log[-1] == ("exit", 1)
    assert not [c for c in log if c[0] == "sigmask"]


def test_without_prctl_a_worker_still_sets_its_handlers_and_unblocks(log, monkeypatch):
    """No usable libc (CDLL raises OSError) or a platform other than Linux: no parent-death
    signal, but the handlers are set and the signals unblocked all the same. Planted: the
    platform test made to hold everywhere, OSError no longer caught."""
    def no_libc(*args, **kwargs):
        raise OSError("no libc")

    monkeypatch.setattr(ctypes, "CDLL", no_libc)
    child_init(PARENT)
    assert log == [("signal", signal.SIGTERM, signal.SIG_DFL),
                   ("signal", signal.SIGINT, signal.SIG_IGN), UNBLOCK_BOTH]
    log.clear()
    monkeypatch.setattr(sys, "platform", "darwin")
    monkeypatch.setattr(ctypes, "CDLL", lambda *a, **k: pytest.fail("CDLL on darwin"))
    child_init(PARENT)
    assert log == [("signal", signal.SIGTERM, signal.SIG_DFL),
                   ("signal", signal.SIGINT, signal.SIG_IGN), UNBLOCK_BOTH]


# -- install_handlers: the second signal ---------------------------------------------------------

def _raised(handler, signum) -> BaseException | None:
    """What ``handler(signum, None)`` raised (caught here, so that a wrong KeyboardInterrupt
    fails the test instead of stopping pytest)."""
    try:
        handler(signum, None)
    except BaseException as err:                    # noqa: BLE001
        return err
    return None


def _second(log, monkeypatch, first_signal, second_signal):
    """install_handlers('prog') over Python's defaults, its first handler run for
    ``first_signal`` (it raises), then the handler it put in place run for ``second_signal``;
    returns what that second handler did (the calls after the first handler's)."""
    defaults = {signal.SIGINT: signal.default_int_handler, signal.SIGTERM: signal.SIG_DFL}
    monkeypatch.setattr(signal, "getsignal", defaults.__getitem__)
    install_handlers("prog")
    (first,) = {c[2] for c in log if c[0] == "signal"}
    log.clear()
    with pytest.raises(KeyboardInterrupt):          # Terminated is one
        first(first_signal, None)
    handlers = {c[1]: c[2] for c in log if c[0] == "signal"}
    assert set(handlers) == {signal.SIGINT, signal.SIGTERM}
    log.clear()
    with pytest.raises(_Exited):
        handlers[second_signal](second_signal, None)
    return list(log)


def test_a_second_sigterm_writes_one_line_to_stderr_and_exits_143(log, monkeypatch):
    """SIGTERM during the unwind of a first SIGTERM: 'prog: terminated again; stopped at
    once' and a newline on fd 2, then exit 128 + 15 = 143 (what a shell reports for a death
    by SIGTERM). Planted: the line written to fd None or fd 3, no text / None written,
    os._exit(None), 128 - signum, 129 + signum."""
    assert _second(log, monkeypatch, signal.SIGTERM, signal.SIGTERM) == [
        ("write", 2, b"prog: terminated again; stopped at once\n"), ("exit", 143)]


def test_a_second_ctrl_c_after_a_sigterm_says_interrupted_and_exits_130(log, monkeypatch):
    """Ctrl-C during the unwind of a SIGTERM: the line names the second signal
    ('interrupted'), the status is 128 + 2 = 130. Planted: 129 + signum, 128 - signum."""
    assert _second(log, monkeypatch, signal.SIGTERM, signal.SIGINT) == [
        ("write", 2, b"prog: interrupted again; stopped at once\n"), ("exit", 130)]


def test_the_first_sigterm_raises_terminated_and_the_first_ctrl_c_keyboardinterrupt(
        log, monkeypatch):
    """The first handler: SIGTERM -> Terminated('terminated (SIGTERM)'), SIGINT -> a plain
    KeyboardInterrupt (as Python's own default handler raises). Planted: the test of the
    signal on SIGINT instead of SIGTERM (each raised the other's exception)."""
    defaults = {signal.SIGINT: signal.default_int_handler, signal.SIGTERM: signal.SIG_DFL}
    monkeypatch.setattr(signal, "getsignal", defaults.__getitem__)
    install_handlers("prog")
    (first,) = {c[2] for c in log if c[0] == "signal"}
    on_term, on_int = _raised(first, signal.SIGTERM), _raised(first, signal.SIGINT)
    assert type(on_term) is Terminated and str(on_term) == "terminated (SIGTERM)"
    assert type(on_int) is KeyboardInterrupt


# -- exit_at_once -------------------------------------------------------------------------------

def test_exit_at_once_flushes_both_streams_then_exits_with_the_status(log, monkeypatch):
    """stdout and stderr flushed (os._exit skips the interpreter's own flush), then os._exit
    with the status given. Planted: os._exit(None)."""
    class _Stream:
        def __init__(self, name):
            self.name = name

        def flush(self):
            log.append(("flush", self.name))

    monkeypatch.setattr(sys, "stdout", _Stream("stdout"))
    monkeypatch.setattr(sys, "stderr", _Stream("stderr"))
    with pytest.raises(_Exited):
        exit_at_once(3)
    assert log == [("flush", "stdout"), ("flush", "stderr"), ("exit", 3)]
