"""A ScenarioFileError crosses process boundaries (the worker pool, comparisons/stages/pool.py,
sends a worker's exception to the parent pickled), so it must survive pickling with every
field and its message as they were; its ``__reduce__`` rebuilds it from (file, key, problem,
fix), since the four-argument constructor cannot be called with the one message that
Exception's default pickling would pass. Expected values: the class's documented message form
``<file>: <key>: <problem>; fix: <fix>`` on one line, written out by hand. Planted bugs each
test was seen failing on are named in it."""

import pickle

import pytest

from reference_model.scenarios.files import ScenarioFileError


@pytest.mark.parametrize("protocol", [0, pickle.DEFAULT_PROTOCOL, pickle.HIGHEST_PROTOCOL])
def test_a_scenario_file_error_survives_pickling(protocol):
    """pickle.loads(pickle.dumps(err)) gives a ScenarioFileError (still a ValueError) with the
    same file, key, problem and fix and the same one-line message. Planted: __reduce__
    rebuilding the error with type(None) instead of its own class."""
    err = ScenarioFileError("scenarios/lean.toml", "grid.step", "must be > 0, got -0.01",
                            "write a positive step in s, e.g. 0.01")
    back = pickle.loads(pickle.dumps(err, protocol=protocol))
    assert type(back) is ScenarioFileError
    assert isinstance(back, ValueError)
    assert (back.file, back.key, back.problem, back.fix) == (
        "scenarios/lean.toml", "grid.step", "must be > 0, got -0.01",
        "write a positive step in s, e.g. 0.01")
    assert str(back) == ("scenarios/lean.toml: grid.step: must be > 0, got -0.01; fix: write a "
                         "positive step in s, e.g. 0.01")
    assert str(back) == str(err)


def test_a_pickled_error_keeps_its_one_line_message_and_can_be_raised():
    """A problem written over several lines is one line in the message, before and after the
    round trip; the unpickled error is raised and caught as a ScenarioFileError. Planted:
    __reduce__ rebuilding the error with type(None)."""
    err = ScenarioFileError("a.toml", "inputs.csv", "no such file\n  'x.csv'", "check the path")
    back = pickle.loads(pickle.dumps(err))
    assert back.problem == "no such file\n  'x.csv'"
    assert str(back) == "a.toml: inputs.csv: no such file 'x.csv'; fix: check the path"
    with pytest.raises(ScenarioFileError, match=r"^a\.toml: inputs\.csv: no such file"):
        raise back
