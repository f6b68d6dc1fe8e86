"""Runs of a Problem (a simulator written in Python) that write a history: the file, its export,
resume with the same problem after a failure (the uninterrupted run's history), and the user's own
exception reaching the caller as theirs."""

import math
import os
import shutil
import subprocess
import traceback

import numpy as np
import pandas as pd
import pytest

import combabc
from test_smc import OBSERVED, options, per_sample, problem

CLI = os.environ.get("COMBABC_CLI")
EXAMPLE = os.path.join(os.path.dirname(__file__), "..", "..", "examples", "custom-simulator")


class Flaky:
    """per_sample, raising the user's own error at call number `fail_at` (None: never)."""

    def __init__(self, fail_at=None):
        self.calls = 0
        self.fail_at = fail_at

    def __call__(self, bits):
        self.calls += 1
        if self.calls == self.fail_at:
            raise LookupError(f"sensor unplugged at call {self.calls}")
        return per_sample(bits)


def test_a_problem_run_writes_its_history(tmp_path):
    history = combabc.run(problem(), options(accepted_per_wave=100), output_directory=tmp_path)
    assert history.path == os.path.join(str(tmp_path), "history.sqlite")
    assert os.path.isfile(history.path) and history.status == "finished"
    loaded = combabc.load_history(history.path)
    pd.testing.assert_frame_equal(loaded.particles(), history.particles(), check_exact=True)
    in_memory = combabc.run(problem(), options(accepted_per_wave=100))
    assert in_memory.path is None
    pd.testing.assert_frame_equal(in_memory.particles(), history.particles(), check_exact=True)
    # The outputs' and the data's positions: the index (unit "index"), one experiment.
    np.testing.assert_array_equal(history.output_position, np.arange(len(OBSERVED)))
    np.testing.assert_array_equal(in_memory.output_position, np.arange(len(OBSERVED)))
    np.testing.assert_array_equal(history.measured_value, OBSERVED)
    assert history.position_unit == "index" and len(history.experiments) == 1
    # The mode-loss diagnostic's classes, stored and read back: none in wave 1 (the prior).
    assert loaded.waves[0].pattern_classes == []
    for mine, stored in zip(history.waves, loaded.waves):
        assert [(c["mass"], c["proposal"], c["flagged"]) for c in mine.pattern_classes] == \
            [(c["mass"], c["proposal"], c["flagged"]) for c in stored.pattern_classes]
    # Refused again without overwrite, replaced with it.
    with pytest.raises(combabc.Error):
        combabc.run(problem(), options(accepted_per_wave=100), output_directory=tmp_path)
    combabc.run(problem(), options(accepted_per_wave=100), output_directory=tmp_path,
                overwrite=True)


def test_export_takes_the_path_or_the_history(tmp_path):
    history = combabc.run(problem(), options(accepted_per_wave=50), output_directory=tmp_path)
    out = combabc.export(history.path, tmp_path / "e1", netcdf=False)
    particles = pd.read_csv(os.path.join(out, "particles.csv"), dtype={"bits": str})
    assert list(particles.columns[3:11]) == history.bit_names
    assert combabc.export(history, tmp_path / "e2", netcdf=False) == str(tmp_path / "e2")
    with pytest.raises(ValueError, match="output_directory"):
        combabc.export(combabc.run(problem(), options(accepted_per_wave=50)))


def test_resume_after_the_simulator_failed_equals_the_uninterrupted_run(tmp_path):
    whole = combabc.run(problem(), options(accepted_per_wave=200),
                        output_directory=tmp_path / "whole")
    simulator = Flaky(fail_at=int(whole.summary["simulations"]) // 2)
    flaky = problem(simulator)
    with pytest.raises(LookupError, match="sensor unplugged"):
        combabc.run(flaky, options(accepted_per_wave=200), output_directory=tmp_path / "cut")
    path = tmp_path / "cut" / "history.sqlite"
    cut = combabc.load_history(path)
    assert cut.status == "failed"
    # Failed during wave 2: no termination criterion, and its answer is wave 1's, as the CLI's.
    assert cut.termination == "" and [w.complete for w in cut.waves] == [True, False]
    assert cut.posterior_note == "the numbers are wave 1's: wave 2 is incomplete (stopped)"
    # Other options are refused (threads may change).
    with pytest.raises(combabc.Error, match="options differ"):
        combabc.resume(path, flaky, options(accepted_per_wave=200, seed=12))
    with pytest.raises(combabc.Error, match="written in Python"):
        combabc.resume(path)
    resumed = combabc.resume(path, flaky, options(accepted_per_wave=200), threads=2)
    assert resumed.status == "finished" and resumed.path == str(path)
    pd.testing.assert_frame_equal(resumed.particles(), whole.particles(), check_exact=True)
    with pytest.raises(combabc.Error, match="already finished"):
        combabc.resume(path, flaky, options(accepted_per_wave=200))


@pytest.mark.skipif(not CLI, reason="COMBABC_CLI not set (run through ctest)")
def test_the_cli_refuses_to_resume_a_python_run(tmp_path):
    simulator = Flaky(fail_at=50)
    with pytest.raises(LookupError):
        combabc.run(problem(simulator), options(accepted_per_wave=100), output_directory=tmp_path)
    done = subprocess.run([CLI, "resume", str(tmp_path / "history.sqlite")], capture_output=True,
                          text=True)
    assert done.returncode == 64, done.stderr
    assert "combabc.resume(path, problem, options)" in done.stderr


def test_the_users_exception_is_reported_as_theirs(tmp_path):
    with pytest.raises(LookupError) as raised:
        combabc.run(problem(Flaky(fail_at=3)), options(accepted_per_wave=100))
    notes = " ".join(getattr(raised.value, "__notes__", []))
    assert "internal error" not in notes and "candidate" in notes
    # The traceback ends in the user's function.
    frames = traceback.extract_tb(raised.value.__traceback__)
    assert frames[-1].name == "__call__" and frames[-1].filename == __file__


def test_a_problem_run_draws_its_report(tmp_path):
    pytest.importorskip("matplotlib")
    history = combabc.run(problem(), options(accepted_per_wave=50), output_directory=tmp_path,
                          report=True)
    assert os.path.isfile(os.path.join(history.report_directory, "index.html"))


def test_a_run_stopped_on_its_budget_resumes_with_a_raised_limit(tmp_path):
    whole = combabc.run(problem(), options(accepted_per_wave=200),
                        output_directory=tmp_path / "whole")
    total = int(whole.summary["simulations"])
    stopped = combabc.run(problem(), options(accepted_per_wave=200, max_simulations=total // 2),
                          output_directory=tmp_path / "stopped")
    assert stopped.termination == "budget_exhausted"
    with pytest.raises(combabc.Error, match="max_simulations="):  # it would stop again at once
        combabc.resume(stopped, problem(), options(accepted_per_wave=200,
                                                   max_simulations=total // 2))
    resumed = combabc.resume(stopped, problem(), options(accepted_per_wave=200),
                             max_simulations=total + 1000)
    assert resumed.termination == whole.termination
    pd.testing.assert_frame_equal(resumed.particles(), whole.particles(), check_exact=True)


def quantile_options(**fields):
    """Adaptive thresholds that stay above their target: every run ends on its waves."""
    schedule = combabc.ThresholdSchedule(kind="quantile", quantile=0.9)
    return options(**{"accepted_per_wave": 50, "thresholds": [schedule], **fields})


def test_a_finished_run_given_more_waves_equals_one_longer_run(tmp_path):
    longer = combabc.run(problem(), quantile_options(num_waves=5),
                         output_directory=tmp_path / "five")
    assert longer.termination == "max_waves" and len(longer.waves) == 5
    short = combabc.run(problem(), quantile_options(num_waves=3),
                        output_directory=tmp_path / "three")
    assert short.termination == "max_waves"
    # Finished: the message says how to continue.
    with pytest.raises(combabc.Error, match="give it more waves with waves=N"):
        combabc.resume(short, problem(), quantile_options(num_waves=3))
    with pytest.raises(combabc.Error, match="waves= above 3"):
        combabc.resume(short, problem(), quantile_options(num_waves=3), waves=3)
    more = combabc.resume(short, problem(), quantile_options(num_waves=3), waves=5)
    assert more.termination == "max_waves" and len(more.waves) == 5
    pd.testing.assert_frame_equal(more.particles(), longer.particles(), check_exact=True)
    for a, b in zip(more.waves, longer.waves):
        np.testing.assert_array_equal(a.thresholds, b.thresholds)
        assert a.candidates == b.candidates


def test_a_problem_run_starts_from_a_finished_runs_posterior(tmp_path):
    first = combabc.run(problem(), quantile_options(num_waves=2), output_directory=tmp_path / "a")
    with pytest.raises(ValueError, match="output_directory"):
        combabc.run(problem(), quantile_options(num_waves=2), start_from=first)
    then = combabc.run(problem(), quantile_options(num_waves=2, seed=5),
                       output_directory=tmp_path / "b", start_from=first)
    # Wave 1 is the finished run's last population, simulated again, not a draw from the prior.
    assert sorted(map(tuple, first.waves[-1].bits)) == sorted(map(tuple, then.waves[0].bits))
    # Other bits are refused, naming start_from.
    other = combabc.Problem(combabc.BinarySpace(dimension=8, names=list("abcdefgh")),
                            per_sample, OBSERVED)
    with pytest.raises(combabc.Error, match="start_from"):
        combabc.run(other, quantile_options(num_waves=2), output_directory=tmp_path / "c",
                    start_from=first)


def test_a_problem_stores_the_positions_of_its_outputs(tmp_path):
    positions = np.linspace(0.0, 0.3, len(OBSERVED))
    space = combabc.BinarySpace(dimension=8)
    placed = combabc.Problem(space, per_sample, OBSERVED, positions=positions,
                             position_unit="m")
    history = combabc.run(placed, quantile_options(num_waves=1), output_directory=tmp_path)
    loaded = combabc.load_history(history.path)
    np.testing.assert_array_equal(loaded.output_position, positions)
    np.testing.assert_array_equal(loaded.measured_position, positions)
    assert loaded.position_unit == "m"
    with pytest.raises(ValueError, match="one per output"):
        combabc.Problem(space, per_sample, OBSERVED, positions=positions[:-1])


def supports(bits):
    """examples/custom-simulator/worker.py's model, as its worker computes it."""
    coordinates = [0.03 * j for j in range(21)]
    centres = [0.05 + 0.1 * k for k in range(6)]
    return np.array([0.05 + sum(math.exp(-((x - c) / 0.06) ** 2)
                                for b, c in zip(bits, centres) if b == 0) for x in coordinates])


def least_squares(output, observed):
    """The config's least_squares component on unnormalised data at the outputs' own positions:
    the sum of squared residuals, added in the engine's order."""
    total = 0.0
    for y, o in zip(output.tolist(), observed.tolist()):
        r = y - o
        total += r * r
    return np.array([total])


@pytest.mark.skipif(not CLI, reason="COMBABC_CLI not set (run through ctest)")
def test_a_cli_run_and_a_python_run_of_one_problem_write_the_same_rows(tmp_path):
    for name in ("worker.py", "data.csv"):
        shutil.copy(os.path.join(EXAMPLE, name), tmp_path / name)
    config = (open(os.path.join(EXAMPLE, "worker.toml")).read()
              .replace("waves = 5", "waves = 2").replace("accepted_per_wave = 40",
                                                         "accepted_per_wave = 15")
              .replace('displacement_unit = "m"', 'displacement_unit = "m"\nnormalise = false'))
    (tmp_path / "run.toml").write_text(config)
    done = subprocess.run([CLI, "run", str(tmp_path / "run.toml"), "-o", str(tmp_path / "cli"),
                           "--no-report", "-q", "-j", "1"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    cli = combabc.load_history(tmp_path / "cli" / "history.sqlite")
    data = pd.read_csv(tmp_path / "data.csv", comment="#")
    space = combabc.BinarySpace(dimension=6, names=cli.bit_names)
    mine = combabc.Problem(space, supports, data["deflection"].to_numpy(), distance=least_squares,
                           components=cli.components, positions=data["position_m"].to_numpy(),
                           position_unit="m")
    schedule = combabc.ThresholdSchedule(kind="quantile", quantile=0.3)
    python = combabc.run(mine, combabc.make_options(num_waves=2, accepted_per_wave=15, seed=11,
                                                    threads=1, thresholds=[schedule]),
                         output_directory=tmp_path / "python")
    assert [w.candidates for w in python.waves] == [w.candidates for w in cli.waves]
    pd.testing.assert_frame_equal(python.particles(), cli.particles(), check_exact=True)
    for a, b in zip(python.waves, cli.waves):
        np.testing.assert_array_equal(a.thresholds, b.thresholds)
