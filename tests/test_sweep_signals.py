"""`deferred_signals` (comparisons/stages/sweep_signals.py): a signal inside the block is noted
and raised at `StopRequest.check`, and one the process was started ignoring stays ignored (a
shell's background job starts with SIGINT ignored: Ctrl-C at the terminal is not for it), as
`run` leaves it (`signals.install_handlers`). Planted: the block taking over an ignored SIGINT
(it did, unlike `run`), so a backgrounded sweep stopped on the terminal's Ctrl-C."""

import os
import signal
import time

import pytest

from comparisons.stages.signals import Terminated
from comparisons.stages.sweep_signals import deferred_signals


@pytest.fixture
def sigint_restored():
    """Whatever a test sets SIGINT to, the worker gets its own handler and mask back."""
    handler = signal.getsignal(signal.SIGINT)
    mask = signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, handler)
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)


def _deliver(sig):
    """Send ``sig`` to this process and give the interpreter the chance to run its handler."""
    os.kill(os.getpid(), sig)
    for _ in range(100):
        time.sleep(0.001)


@pytest.mark.parametrize("sig, raised", [(signal.SIGINT, KeyboardInterrupt),
                                         (signal.SIGTERM, Terminated)])
def test_a_signal_in_the_block_is_noted_and_raised_at_the_check(sigint_restored, sig, raised):
    signal.signal(signal.SIGINT, signal.default_int_handler)
    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    with deferred_signals("prog") as stop:
        stop.check()                          # nothing yet: returns
        _deliver(sig)
        assert stop.signum == sig
        with pytest.raises(raised):
            stop.check()
    # after a stop, a second signal during the unwind ends the process at once
    assert signal.getsignal(sig) not in (before[sig], signal.SIG_DFL, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, before[signal.SIGTERM])


def test_without_a_signal_the_handlers_are_given_back(sigint_restored):
    signal.signal(signal.SIGINT, signal.default_int_handler)
    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    with deferred_signals("prog") as stop:
        assert signal.getsignal(signal.SIGINT) is not before[signal.SIGINT]
    stop.check()
    assert {s: signal.getsignal(s) for s in before} == before


def test_an_ignored_sigint_stays_ignored(sigint_restored):
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    with deferred_signals("prog") as stop:
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        _deliver(signal.SIGINT)
        assert stop.signum is None
        stop.check()
    assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN


def test_the_terminated_stop_names_its_signal(sigint_restored):
    """SIGTERM's stop is `Terminated` saying what stopped the sweep (the message `run` and
    `sweep` print: "terminated (SIGTERM)"). Planted: the message lost or changed."""
    with deferred_signals("prog") as stop:
        _deliver(signal.SIGTERM)
        with pytest.raises(Terminated) as err:
            stop.check()
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    assert str(err.value) == "terminated (SIGTERM)"


@pytest.mark.parametrize("sig, word", [(signal.SIGINT, "interrupted"),
                                       (signal.SIGTERM, "terminated")])
def test_a_second_signal_writes_one_line_and_exits_with_the_shells_status(
        sigint_restored, monkeypatch, sig, word):
    """The second signal inside the block (module docstring): one line on standard error,
    "<program>: <what> again; stopped at once", then the process ends at once with the status
    a shell gives a process killed by that signal, 128 + its number (130 for Ctrl-C, 143 for
    SIGTERM: POSIX shells' convention). os.write and os._exit are recorded, not done.
    Planted: another descriptor than stderr; the status 128 - n or 129 + n; the line lost."""
    written, exits = [], []
    monkeypatch.setattr("comparisons.stages.sweep_signals.os.write",
                        lambda fd, data: written.append((fd, data)))
    monkeypatch.setattr("comparisons.stages.sweep_signals.os._exit", exits.append)
    signal.signal(signal.SIGINT, signal.default_int_handler)   # not left ignored by another test
    before = signal.getsignal(signal.SIGTERM)
    with deferred_signals("prog") as stop:
        _deliver(sig)
        _deliver(sig)
    signal.signal(signal.SIGTERM, before)
    assert stop.signum == sig
    assert written == [(2, f"prog: {word} again; stopped at once\n".encode())]
    assert exits == [{signal.SIGINT: 130, signal.SIGTERM: 143}[sig]]
