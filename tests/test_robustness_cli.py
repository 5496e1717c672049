"""Command-line limits and hostile options: one line, the right exit status, nothing run that
the user did not mean (issue 14's report-side and CLI cases; docs/robustness.md)."""

import pytest

from comparisons.cli import main


def _err(capsys) -> list[str]:
    return capsys.readouterr().err.strip().splitlines()


@pytest.mark.parametrize("args, needle", [
    (["run", "--jobs", "64"], "--jobs must be between 1 and 8"),
    (["diagnose", "--model", "thesis", "--states", "2000000"], "--states must be an integer from 4 to 2000"),
    (["eigenvalues", "--out", "e.csv", "--figure", "fig.xyz"], "ending in .png"),
    (["simulate", "--scenario", "stability-psid5", "--out", "x.csv", "--rtol", "1e-300"],
     "--rtol must be in [2.3e-14, 1)"),
    (["simulate", "--engine", "exudyn", "--scenario", "stability-psid5", "--out", "x.csv",
      "--step", "0.003"], "must divide the output interval 0.01 s"),
    (["simulate", "--engine", "nosuch.mod:Cls", "--scenario", "stability-psid5", "--out", "x.csv"],
     "nosuch"),
])
def test_usage_errors_are_one_line_exit_2(tmp_path, monkeypatch, capsys, args, needle):
    monkeypatch.chdir(tmp_path)
    assert main(args) == 2
    err = _err(capsys)
    assert len(err) == 1 and needle in err[0], err
    assert not list(tmp_path.iterdir())          # nothing written


def test_negative_speeds_parse(tmp_path, capsys):
    """argparse would read '-5:5:1' as an option; the CLI reads it as the speeds it is."""
    out = tmp_path / "e.csv"
    assert main(["eigenvalues", "--speeds", "-5:5:1", "--out", str(out)]) == 0
    assert out.read_text().count("\n") == 12        # header + 11 speeds


@pytest.mark.parametrize("command", [["run", "--quick"], ["sweep", "--vary", "m3=80:90:2"],
                                     ["diagnose", "thesis"]])
def test_a_broken_tolerance_file_stops_before_anything_runs(tmp_path, capsys, command):
    """``--tolerances`` is read once, first: a malformed file is one line naming the option and
    the field, exit 2, nothing written (run, sweep and diagnose alike)."""
    bad = tmp_path / "tol.toml"
    bad.write_text("[mass_matrix]\ntolerance = 'tight'\n")
    assert main([*command, "--tolerances", str(bad), "--out", str(tmp_path / "r")]
                if command[0] != "diagnose" else [*command, "--tolerances", str(bad)]) == 2
    err = _err(capsys)
    assert len(err) == 1 and "--tolerances" in err[0] and "mass_matrix" in err[0]
    assert not (tmp_path / "r").exists()


def test_jobs_never_more_workers_than_stages(monkeypatch):
    """--jobs 64 for 3 stages starts 3 workers, not 64."""
    from comparisons.stages import pool
    started = []
    real = pool._Workers.fork

    def recording(self):
        started.append(1)
        return real(self)
    monkeypatch.setattr(pool._Workers, "fork", recording)
    assert pool.default_workers(3) <= 3
    done = pool.run_tasks([pool.Task(k, abs, (-k,)) for k in range(3)], workers=64)
    assert {k: r.value for k, r in done.items()} == {0: 0, 1: 1, 2: 2}
    assert len(started) == 3
