"""The main process's and its workers' signal handling (`comparisons.stages.signals`), in
this process and in forked children, fast (the whole-run versions, through real `run`
process trees, are in tests/test_shutdown.py, marked slow). Expected values are the POSIX
facts the module promises: a first SIGTERM raises `Terminated`, a second exits 128 + 15 = 143
with its one line on stderr (SIGINT: 130); a worker's SIGTERM is SIG_DFL, its SIGINT
SIG_IGN, its parent-death signal SIGKILL (prctl(PR_GET_PDEATHSIG) reads it back); a blocked
signal waits in sigpending until the block ends."""

from __future__ import annotations

import ctypes
import io
import os
import signal
import sys
import threading

import pytest

from comparisons.stages.signals import (Terminated, blocked, child_init, flush_streams,
                                        install_handlers, raise_terminated, restore_handlers,
                                        terminating)

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux signals")


@pytest.fixture
def defaults():
    """Both signals at Python's defaults and unblocked (a terminal's state), put back after."""
    saved = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    mask = signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    yield
    for s, h in saved.items():
        signal.signal(s, h)
    signal.pthread_sigmask(signal.SIG_SETMASK, mask)


def _send(signum) -> None:
    """The signal to this thread (not to the process: under pytest-xdist another thread could
    take it, and a blocked signal would not wait in this thread's pending set)."""
    signal.pthread_kill(threading.get_ident(), signum)


def _in_child(body) -> tuple[int, str]:
    """Run ``body()`` in a forked child; (its exit status, what it wrote on fd 2)."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:                                   # the child: never back into pytest
        try:
            os.dup2(w, 2)
            body()
            os._exit(0)
        except BaseException:                      # noqa: BLE001
            os._exit(99)
    os.close(w)
    with os.fdopen(r) as err:
        text = err.read()
    _, status = os.waitpid(pid, 0)
    return os.waitstatus_to_exitcode(status), text


def test_the_first_sigterm_raises_terminated_and_restore_puts_the_defaults_back(defaults):
    previous = install_handlers("prog")
    try:
        assert previous == {signal.SIGINT: signal.default_int_handler,
                            signal.SIGTERM: signal.SIG_DFL}
        with pytest.raises(Terminated) as err:
            _send(signal.SIGTERM)
            os.sched_yield()                      # the handler runs here at the latest
        assert str(err.value) == "terminated (SIGTERM)"
        assert isinstance(err.value, KeyboardInterrupt)      # never caught by except Exception
        # after the first, both signals end the process at once: no longer the first handler
        assert signal.getsignal(signal.SIGTERM).__name__ == "again"
        assert signal.getsignal(signal.SIGINT).__name__ == "again"
    finally:
        restore_handlers(previous)
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_the_first_ctrl_c_is_a_keyboard_interrupt_not_terminated(defaults):
    previous = install_handlers("prog")
    try:
        with pytest.raises(KeyboardInterrupt) as err:
            _send(signal.SIGINT)
            os.sched_yield()
        assert not isinstance(err.value, Terminated)
    finally:
        restore_handlers(previous)


@pytest.mark.parametrize("mine", [lambda signum, frame: None, signal.default_int_handler],
                         ids=["a function", "KeyboardInterrupt on SIGTERM"])
def test_a_handler_someone_else_set_is_left_alone(defaults, mine):
    signal.signal(signal.SIGTERM, mine)
    previous = install_handlers("prog")
    try:
        assert signal.getsignal(signal.SIGTERM) is mine
        assert signal.getsignal(signal.SIGINT) is not signal.default_int_handler
    finally:
        restore_handlers(previous)
    assert signal.getsignal(signal.SIGTERM) is mine


def test_restore_puts_the_default_for_a_handler_python_did_not_know():
    saved = signal.getsignal(signal.SIGTERM)
    try:
        restore_handlers({signal.SIGTERM: None})     # getsignal's None: set from C
        assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
    finally:
        signal.signal(signal.SIGTERM, saved)


@pytest.mark.parametrize("signum, status, what", [(signal.SIGTERM, 143, "terminated"),
                                                  (signal.SIGINT, 130, "interrupted")])
def test_a_second_signal_during_the_unwind_exits_at_once_with_one_line(signum, status, what):
    def body():
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})
        install_handlers("prog")
        try:
            _send(signum)
            os.sched_yield()
        except KeyboardInterrupt:                 # the unwind: a second signal arrives
            _send(signum)
            os.sched_yield()
        os._exit(3)                               # not reached when the second one exits
    code, err = _in_child(body)
    assert (code, err) == (status, f"prog: {what} again; stopped at once\n")


def test_terminating_turns_sigterm_into_terminated_inside_the_block_only(defaults):
    with pytest.raises(Terminated, match=r"^terminated \(SIGTERM\)$"):
        with terminating():
            assert signal.getsignal(signal.SIGTERM) is raise_terminated
            _send(signal.SIGTERM)
            os.sched_yield()
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL


def test_terminating_leaves_a_callers_own_handler(defaults):
    seen = []
    signal.signal(signal.SIGTERM, lambda s, f: seen.append(s))
    with terminating():
        _send(signal.SIGTERM)
        os.sched_yield()
    assert seen == [signal.SIGTERM]


def test_a_signal_sent_inside_blocked_waits_until_the_block_ends(defaults):
    seen = []
    signal.signal(signal.SIGTERM, lambda s, f: seen.append(s))
    with blocked():
        _send(signal.SIGTERM)
        assert signal.SIGTERM in signal.sigpending() and seen == []
    os.sched_yield()
    assert seen == [signal.SIGTERM]
    assert signal.SIGTERM not in signal.pthread_sigmask(signal.SIG_BLOCK, [])


def test_a_worker_starts_with_the_default_sigterm_ignored_sigint_and_death_with_its_parent():
    parent = os.getpid()

    def body():
        # as the harness forks: both signals blocked, the parent's handlers inherited
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
        signal.signal(signal.SIGTERM, lambda s, f: None)
        signal.signal(signal.SIGINT, lambda s, f: None)
        child_init(parent)
        got = ctypes.c_int(0)
        ctypes.CDLL(None).prctl(2, ctypes.byref(got))        # PR_GET_PDEATHSIG
        ok = (signal.getsignal(signal.SIGTERM) is signal.SIG_DFL,
              signal.getsignal(signal.SIGINT) is signal.SIG_IGN,
              got.value == signal.SIGKILL,
              not ({signal.SIGINT, signal.SIGTERM} & signal.pthread_sigmask(signal.SIG_BLOCK, [])))
        os._exit(sum(1 << i for i, good in enumerate(ok) if not good))
    code, _ = _in_child(body)
    assert code == 0, f"failed checks (bits): {code:04b}"


def test_a_worker_whose_parent_is_already_gone_exits_with_1():
    code, _ = _in_child(lambda: child_init(parent=os.getppid() + 1))
    assert code == 1


def test_flush_streams_writes_out_and_survives_closed_or_odd_streams(monkeypatch):
    buffered = io.TextIOWrapper(io.BytesIO(), write_through=False)
    buffered.write("kept")
    monkeypatch.setattr(sys, "stdout", buffered)
    closed = io.TextIOWrapper(io.BytesIO())
    closed.close()
    monkeypatch.setattr(sys, "stderr", closed)          # ValueError on flush
    flush_streams()
    assert buffered.buffer.getvalue() == b"kept"
    monkeypatch.setattr(sys, "stdout", object())        # no flush at all: AttributeError
    flush_streams()
