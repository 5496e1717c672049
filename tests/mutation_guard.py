"""Under mutmut only, in a mutant's test run: keep what the mutant does to processes inside that
run, and end a run that waits forever.

mutmut's limit on a mutant is CPU time (``RLIMIT_CPU``), and its fork server adds a wall-clock
timer that signals the mutant's process alone. Two kinds of mutant of the process pool
(`comparisons/stages/pool.py`) escaped both and stopped the whole measurement at 359 of 393
(2026-12-06, the 2-core Intel Xeon):

* a mutant that lets a forked worker return into the caller's code (``if pid == 1``) leaves a
  second copy of pytest whose "worker" pid is 0, and ``os.kill(0, SIGKILL)`` kills the calling
  process's whole group: mutmut's own processes with it;
* a mutant that loses a worker's pid waits forever in ``os.waitpid`` or on a pipe: no CPU is
  spent, so no CPU limit ends it, and a copy forked from it has no timer at all.

So each mutant's run becomes the leader of a process group of its own (its workers and any
stray copy inherit it: a kill of "group 0" stays inside), and every process of the group
carries the same wall-clock deadline, a little before mutmut's own (its fork server's wall
timeout is half the CPU limit it sets): at the deadline the whole group gets SIGXCPU, which
mutmut counts as a timeout (a killed mutant), as it would count the CPU limit.
"""

from __future__ import annotations

import os
import resource
import signal
import threading
import time

__all__ = ["register", "deadline_from_cpu_limit"]

#: the share of mutmut's CPU limit given as wall time: its fork server times out at 1/2
SHARE = 0.45
#: when no CPU limit is set (a run outside mutmut's workers): wall seconds
FALLBACK = 600.0


def deadline_from_cpu_limit(now: float, soft: int, used: float) -> float:
    """The wall-clock deadline (``time.monotonic`` scale) of a run with the CPU limit ``soft``
    (s, ``resource.RLIM_INFINITY`` for none) of which ``used`` is spent."""
    if soft == resource.RLIM_INFINITY or soft <= 0:
        return now + FALLBACK
    return now + SHARE * max(soft - used, 1.0)


def _arm(deadline: float) -> None:
    """A daemon thread that sends SIGXCPU to this process's group at ``deadline``."""
    def fire() -> None:
        time.sleep(max(deadline - time.monotonic(), 0.0))
        try:
            os.killpg(os.getpgid(0), signal.SIGXCPU)
        except OSError:
            os.kill(os.getpid(), signal.SIGXCPU)
    threading.Thread(target=fire, name="mutation-guard", daemon=True).start()


def register(config) -> None:
    """Make this mutant's run a process group of its own with a wall-clock deadline, carried
    into every process it forks (module docstring)."""
    try:
        os.setpgid(0, 0)
    except OSError:       # already a group leader (a session leader cannot move)
        pass
    soft, _ = resource.getrlimit(resource.RLIMIT_CPU)
    deadline = deadline_from_cpu_limit(time.monotonic(), soft, time.process_time())
    os.register_at_fork(after_in_child=lambda: _arm(deadline))
    _arm(deadline)
