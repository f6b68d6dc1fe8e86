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


# Two named bits and two continuous parameters, batched: y = gain * [1, 2, 3, 4] + offset +
# valve * [3, 0, 0, 3] + pump * [0, 2, 2, 0], observed at valve = 1, pump = 0, gain = 1,
# offset = 0.5. No line a + b x comes within 1.5 of either bit's bend: the final wave has valve
# = 1 and pump = 0.
SLOPE = np.array([1.0, 2.0, 3.0, 4.0])
VALVE, PUMP = np.array([3.0, 0.0, 0.0, 3.0]), np.array([0.0, 2.0, 2.0, 0.0])
MIXED_OBSERVED = SLOPE + 0.5 + VALVE


def mixed_simulator(bits, reals):
    return (reals[:, :1] * SLOPE + reals[:, 1:2] + bits[:, :1] * VALVE + bits[:, 1:2] * PUMP)


def mixed_problem():
    space = combabc.BinarySpace(dimension=2, names=["valve", "pump"])
    reals = [combabc.ContinuousParameter("gain", kind="uniform", low=0.0, high=2.0),
             combabc.ContinuousParameter("offset", kind="normal", mean=0.0, sd=1.0)]
    return combabc.Problem(space, mixed_simulator, MIXED_OBSERVED, reals=reals, batch=True)


def mixed_options():
    return combabc.make_options(num_waves=3, accepted_per_wave=150, seed=5, threads=1,
                                thresholds=[8.0, 3.0, 1.5], estimator="importance")


def test_answer_is_the_terminal_and_summary_json_numbers(tmp_path):
    import json
    history = combabc.run(mixed_problem(), mixed_options(), output_directory=tmp_path)
    answer = history.answer()
    out = combabc.export(history, tmp_path / "export", netcdf=False)
    with open(os.path.join(out, "summary.json"), encoding="utf-8") as f:
        stored = json.load(f)["answer"]
    assert list(answer["name"]) == ["valve", "pump", "gain", "offset"]
    assert list(answer["kind"]) == ["bit", "bit", "real", "real"]
    bits, reals = answer[answer.kind == "bit"], answer[answer.kind == "real"]
    # The same numbers, to the last bit (summary.json writes the shortest round-trip form).
    assert list(bits["P"]) == [b["p_one"] for b in stored["bits"]]
    assert list(bits["se"]) == [b["mc_se"] for b in stored["bits"]]
    assert list(bits["verdict"]) == [b["verdict"] for b in stored["bits"]]
    for column, key in (("mean", "mean"), ("se", "mc_se"), ("sd", "sd"), ("sd_se", "sd_se"),
                        ("ess", "ess"), ("q05", "q05"), ("median", "median"), ("q95", "q95")):
        assert list(reals[column]) == [r[key] for r in stored["reals"]], column
    assert bits[["mean", "q05"]].isna().all().all() and reals["P"].isna().all()
    assert answer.attrs["wave"] == stored["wave"] == 3
    assert answer.attrs["estimator"] == "importance"
    assert [c["bits"] for c in answer.attrs["top_configurations"]] == \
        [c["bits"] for c in stored["top_configurations"]]
    # The terminal's text, as `combabc run` prints it: each bit's P ± its error and verdict, each
    # real's mean ± its error.
    lines = answer.attrs["text"].splitlines()
    for _, row in answer.iterrows():
        (line,) = [line for line in lines if line.startswith(f" {row['name']} ")]
        if row["kind"] == "bit":
            assert f"{row['P']:.2f}±{row['se']:.2f}" in line and line.endswith(row["verdict"])
        else:
            assert f"{row['mean']:.6g} ± {row['se']:.2g}, sd {row['sd']:.4g}" in line
    # The quantiles are those of the answer wave's particles under their weights.
    w = history.posterior_wave
    for j, (_, row) in enumerate(reals.iterrows()):
        order = np.argsort(w.reals[:, j], kind="stable")
        cdf = np.cumsum(w.weight[order]) / np.sum(w.weight)
        for q, column in ((0.05, "q05"), (0.5, "median"), (0.95, "q95")):
            expected = w.reals[order, j][np.searchsorted(cdf, q - 1e-12)]
            assert row[column] == pytest.approx(expected), (row["name"], column)
        assert row["q05"] < row["median"] < row["q95"]
    # The posterior is where the data are: valve fixed, pump free, gain near 1.
    assert list(bits["verdict"]) == ["fixed", "free"]
    assert reals.iloc[0]["q05"] < 1.0 < reals.iloc[0]["q95"]


def test_answer_needs_the_history_file_or_the_runs_answer(tmp_path):
    # A run without output_directory hands its answer over: the answer the same run with a history
    # file reads from it, to the last bit.
    in_memory = combabc.run(problem(), options(accepted_per_wave=50))
    assert in_memory.path is None
    path = combabc.run(problem(), options(accepted_per_wave=50), output_directory=tmp_path).path
    on_file = combabc.load_history(path).answer()
    pd.testing.assert_frame_equal(in_memory.answer(), on_file)
    assert in_memory.answer().attrs["text"] == on_file.attrs["text"]
    assert in_memory.answer().attrs["termination"] == on_file.attrs["termination"]
    # A History with neither a file nor an answer says how to get one.
    data = combabc._core.load_history(path)
    data.update(path=None)
    with pytest.raises(ValueError, match="output_directory"):
        combabc.History(data).answer()
    # A run that hands its answer over (_core.answer's dict) needs no file.
    data.update(path=None, answer=combabc._core.answer(path))
    handed = combabc.History(data).answer()
    pd.testing.assert_frame_equal(handed, combabc.load_history(path).answer())
    assert handed.attrs["text"] == data["answer"]["text"]
