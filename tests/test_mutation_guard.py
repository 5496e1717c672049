"""tests/mutation_guard.py, the guard of a mutant's test run under mutmut: its own process group
and a wall-clock deadline shared by every process it forks. Each test runs the guard in a child
Python (it moves its process into a new group and arms signals: never in this pytest process).
Expected outcomes come from POSIX semantics: ``kill(0, sig)`` signals the caller's process
group; a process ended by SIGXCPU has exit status -SIGXCPU, which mutmut reads as a timeout.
"""

from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from mutation_guard import FALLBACK, SHARE, deadline_from_cpu_limit

TESTS = Path(__file__).resolve().parent


def _child(body: str, cpu_limit: int, timeout: float = 30.0) -> subprocess.CompletedProcess:
    """Run ``body`` after the guard's `register` in a child Python with the CPU limit
    ``cpu_limit`` s (as mutmut's worker sets it)."""
    code = textwrap.dedent(f"""
        import os, resource, sys, time
        sys.path.insert(0, {str(TESTS)!r})
        resource.setrlimit(resource.RLIMIT_CPU, ({cpu_limit}, {cpu_limit} + 1))
        from mutation_guard import register
        register(None)
        print(os.getpid(), os.getpgid(0), flush=True)
    """) + textwrap.dedent(body)
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=timeout, check=False)


def test_the_deadline_is_a_share_of_the_cpu_limit_left():
    """0.45 of the CPU seconds left (mutmut's fork server times out at half its limit, so the
    guard's group-wide signal comes first); no limit: the fallback. Planted: the spent CPU
    time not subtracted; the whole limit given as wall time."""
    assert deadline_from_cpu_limit(100.0, 40, 10.0) == pytest.approx(100.0 + SHARE * 30.0)
    assert SHARE < 0.5
    assert deadline_from_cpu_limit(5.0, resource.RLIM_INFINITY, 3.0) == 5.0 + FALLBACK
    assert deadline_from_cpu_limit(5.0, 10, 20.0) == pytest.approx(5.0 + SHARE * 1.0)


def test_a_run_waiting_forever_ends_by_sigxcpu_with_its_whole_group():
    """A run that starts a process of another program (no guard thread of its own) and both
    wait without spending CPU (a lost worker pid, a pipe nobody writes): at the deadline
    (0.45 x 1 s) the run ends with -SIGXCPU, mutmut's timeout, and the other process is gone
    too. Planted: the signal sent to the run's process alone (the other keeps waiting)."""
    t0 = time.monotonic()
    res = _child("""
        import subprocess
        other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(120)"])
        print(other.pid, flush=True)
        time.sleep(120)
    """, cpu_limit=1)
    assert res.returncode == -signal.SIGXCPU
    assert time.monotonic() - t0 < 20.0
    _, other = res.stdout.split("\n")[:2]
    assert _ended(int(other))


def test_a_forked_copy_left_alone_carries_the_deadline():
    """A run that forks a copy and ends at once (the copy returned into pytest's code, as a
    mutant of the pool's fork does, and waits on a pipe): the copy, alone in the group, still
    ends at the run's deadline. Planted: the deadline not armed in forked processes."""
    res = _child("""
        pid = os.fork()
        if pid == 0:
            time.sleep(120)
            os._exit(0)
        print(pid, flush=True)
        os._exit(0)
    """, cpu_limit=1)
    assert res.returncode == 0
    _, copy = res.stdout.split("\n")[:2]
    assert _ended(int(copy), wait=15.0)


def _ended(pid: int, wait: float = 5.0) -> bool:
    """Whether process ``pid`` has ended (gone, or a zombie nobody has reaped yet: an
    orphan's new parent may not reap at once)."""
    t_end = time.monotonic() + wait
    while time.monotonic() < t_end:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except (FileNotFoundError, ProcessLookupError):
            return True
        if state in ("Z", "X"):
            return True
        time.sleep(0.05)
    return False


def test_a_kill_of_group_zero_stays_inside_the_run():
    """A mutant's stray copy calling ``os.kill(0, SIGKILL)`` (a worker pid of 0) kills its
    own run's group, not the processes that started it: this test's process is alive after
    it, and the run ended by SIGKILL (mutmut's 'segfault', counted as killed). Planted: no
    group of its own (the kill would end this pytest)."""
    res = _child("""
        os.kill(0, 9)
        time.sleep(60)
    """, cpu_limit=30)
    pid, pgid = map(int, res.stdout.split())
    assert pid == pgid != os.getpgid(0)
    assert res.returncode == -signal.SIGKILL
