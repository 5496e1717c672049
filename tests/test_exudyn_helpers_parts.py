"""Three small helpers of the Exudyn adapter (engines/exudyn/engine.py) called directly, in
process: ``_duration`` (how long a run takes, in the run monitor's announcements),
``_stderr_line`` (the default ``notify`` of ``simulate``: one line on stderr) and
``_python_load`` (the Python load user function a torque function of time becomes when it is
no spline on the grid).

Expected values: the wording the engine's messages promise (a duration in whole seconds below
LONG_RUN_SECONDS = 120 s = 2 min, whole minutes below 2 h = 7200 s, hours to a tenth beyond;
arithmetic by hand: 7199 s = 119.98 min, 9000 s = 2.5 h), the CLI's stderr prefix
'bicycle-xval: ' (comparisons/cli/main.py), and the module docstring's torque targets (torque
k lands on one body axis, the other two components of the load vector are zero) with torque
functions whose values at t are known by hand. Planted bugs each test was seen failing on are
named in it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("exudyn")

from engines.exudyn.engine import (LONG_RUN_SECONDS, TORQUE_TARGETS, _duration,  # noqa: E402
                                   _python_load, _stderr_line)


# -- _duration ----------------------------------------------------------------------------------

@pytest.mark.parametrize("seconds, text", [
    (0.4, "0 s"),
    (119.4, "119 s"),           # just below 2 min: still seconds
    (120.0, "2 min"),           # 2 min exactly: minutes
    (120.6, "2 min"),           # between 120 and 121: minutes (a boundary moved to 121 shows)
    (1800.0, "30 min"),
    (7199.0, "120 min"),        # 119.98 min, rounded to whole minutes
    (7200.0, "2.0 h"),          # 2 h exactly: hours
    (7200.5, "2.0 h"),          # between 7200 and 7201: hours
    (9000.0, "2.5 h"),
    (36000.0, "10.0 h"),
])
def test_a_duration_is_whole_seconds_whole_minutes_or_tenths_of_hours(seconds, text):
    """Below 120 s whole seconds, from 120 s to below 7200 s whole minutes, from 7200 s on hours
    to a tenth; the boundaries 120 s and 7200 s themselves already belong to the larger unit.
    Expected: the arithmetic by hand (1800 s = 30 min, 7199 s = 119.98 min, 9000 s = 2.5 h).
    Planted: a boundary taken as <= (120 s as '120 s', 7200 s as '120 min') or moved by one
    (120.6 s as '121 s', 7200.5 s as '120 min'), minutes or hours multiplied instead of
    divided (1800 s as '108000 min'), minutes divided by 61 (7199 s as '118 min')."""
    assert _duration(seconds) == text


def test_the_long_run_threshold_reads_as_two_minutes():
    """The engine announces a run estimated longer than LONG_RUN_SECONDS; that threshold itself
    reads '2 min' (the unit changes exactly there), a second less '119 s'. Planted: the first
    boundary taken as <= 120 or < 121."""
    assert LONG_RUN_SECONDS == 120.0
    assert _duration(LONG_RUN_SECONDS) == "2 min"
    assert _duration(LONG_RUN_SECONDS - 1.0) == "119 s"


def test_minutes_and_hours_use_60_and_3600():
    """Durations where a divisor off by one changes the rounded number: 7140 s = 119 min
    (7140/61 = 117.05), 719640 s = 199.9 h (719640/3601 = 199.84). Planted: minutes divided by
    61, hours by 3601, either multiplied instead of divided."""
    assert _duration(7140.0) == "119 min"
    assert _duration(719640.0) == "199.9 h"


# -- _stderr_line -------------------------------------------------------------------------------

def test_a_notice_is_one_prefixed_line_on_stderr(capsys):
    """The default notify of ``simulate`` writes the text as one line on stderr, prefixed
    'bicycle-xval: ' as every other line the tool writes there, nothing on stdout. Planted:
    None written instead of the line."""
    _stderr_line("exudyn tree on stability-psid10: 5000 steps, estimated 3 min")
    out, err = capsys.readouterr()
    assert out == ""
    assert err == "bicycle-xval: exudyn tree on stability-psid10: 5000 steps, estimated 3 min\n"


def test_a_notice_is_flushed_after_it_is_written(monkeypatch):
    """A notice announces a long run before it starts, so it must be out at once: the line is
    written, then the stream flushed. Expected: the stream's calls, in order. Planted: None
    written instead of the line."""
    calls = []

    class Stream:
        def write(self, text):
            calls.append(("write", text))

        def flush(self):
            calls.append(("flush",))

    monkeypatch.setattr("sys.stderr", Stream())
    _stderr_line("t = 1.0000 of 5.0000 s (20%), about 4 min left")
    assert calls == [("write", "bicycle-xval: t = 1.0000 of 5.0000 s (20%), about 4 min left\n"),
                     ("flush",)]


# -- _python_load -------------------------------------------------------------------------------

def _torque(t):
    """A torque function of time with values known by hand: [2 t, 5 - t, -3 t^2]."""
    return np.array([2.0 * t, 5.0 - t, -3.0 * t * t])


@pytest.mark.parametrize("j, axis", [(0, 0), (0, 2), (1, 1), (1, 0), (2, 2), (2, 1)]
                         + [(j, a) for j, (_, a) in enumerate(TORQUE_TARGETS)])
def test_a_python_load_puts_torque_j_on_its_axis_and_zero_elsewhere(j, axis):
    """The load user function Exudyn calls as uf(mbs, t, loadVector) returns a list of three
    floats: component j of the torque at t on the given axis, 0 on the other two (the fake mbs
    and the load vector Exudyn passes are not used). At t = 1.5: [3.0, 3.5, -6.75]. Planted:
    the vector not made (None), a 1 left on one of the axes, the value None, the torque taken
    at None instead of t, the torque reshaped to 4 values."""
    uf = _python_load(_torque, j, axis)
    got = uf(object(), 1.5, [9.0, 9.0, 9.0])
    expected = [0.0, 0.0, 0.0]
    expected[axis] = [3.0, 3.5, -6.75][j]
    assert got == expected
    assert all(type(v) is float for v in got)


def test_a_python_load_follows_the_torque_in_time():
    """The same user function called at several times gives the torque at each of them (it is
    evaluated per call, not once): the pedal torque 5 - t on axis 1 at t = 0, 0.25, 2 gives
    5, 4.75, 3; the steer torque sin(40 t) on axis 2 at t = 0.1 gives sin(4). Planted: the
    torque taken at None, no torque at all."""
    uf = _python_load(_torque, 1, 1)
    assert [uf(None, t, [0.0] * 3)[1] for t in (0.0, 0.25, 2.0)] == [5.0, 4.75, 3.0]

    def steer(t):
        return [math.sin(40.0 * t), 0.0, 0.0]

    assert _python_load(steer, 0, 2)(None, 0.1, [0.0] * 3) == [0.0, 0.0, math.sin(4.0)]


def test_a_python_load_takes_plain_lists_of_integers():
    """A torque function may return a plain list, integers included (a constant pedal torque
    written [0, 2, 0]): the load is still floats. Planted: the value None, the torque
    reshaped to 4 values."""
    uf = _python_load(lambda t: [0, 2, 0], 1, 1)
    got = uf(None, 0.3, [0.0] * 3)
    assert got == [0.0, 2.0, 0.0]
    assert type(got[1]) is float
