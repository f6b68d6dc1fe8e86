"""A run of two named experiments ([[experiment]] tables) from Python: History.experiments, each
experiment's curves and measured data, to_inference_data() with one observed variable per
experiment, and `combabc export`'s experiments.csv and columns agreeing with them."""

import os
import subprocess

import numpy as np
import pandas as pd
import pytest

import combabc

CLI = os.environ.get("COMBABC_CLI")

# The tiny sensor of the C++ end-to-end tests (tests/e2e/tiny_sensor.hpp), under two loads.
CONFIG = """
[model.clamps]
per_edge = 3

[model.mesh]
elements_per_section = 2
elements_across_width = 2

[[experiment]]
name = "near"
[experiment.load]
x = 0.45
[experiment.data]
csv = "near.csv"
position_column = "position_m"
displacement_column = "displacement_m"
position_unit = "m"
displacement_unit = "m"
[experiment.metric]
[[experiment.metric.component]]
type = "least_squares"
window = [0.31, 0.58]

[[experiment]]
name = "far"
[experiment.load]
x = 0.7
[experiment.data]
csv = "far.csv"
position_column = "position_m"
displacement_column = "displacement_m"
position_unit = "m"
displacement_unit = "m"
[experiment.metric]
[[experiment.metric.component]]
type = "least_squares"
window = [0.61, 0.79]

[sampler]
waves = 2
accepted_per_wave = 20
seed = 5
threads = 1

[output]
directory = "out"
"""


def write_data(path, peak_at, start_cm, stop_cm):
    """A tent peaking at `peak_at` m, every 3 cm from start_cm to stop_cm."""
    positions = np.arange(start_cm, stop_cm, 3) / 100.0
    pd.DataFrame({"position_m": positions,
                  "displacement_m": 1.0 - np.abs(positions - peak_at)}).to_csv(path, index=False)
    return positions


@pytest.fixture(scope="module")
def two(tmp_path_factory):
    tmp_path = tmp_path_factory.mktemp("experiments")
    near = write_data(tmp_path / "near.csv", 0.45, 31, 60)
    far = write_data(tmp_path / "far.csv", 0.7, 61, 80)
    (tmp_path / "config.toml").write_text(CONFIG)
    history = combabc.run(tmp_path / "config.toml", threads=2, report=False)
    return tmp_path, history, near, far


def test_history_lists_each_experiment_with_its_slices(two):
    _, history, near, far = two
    names = [x.name for x in history.experiments]
    assert names == ["near", "far"]
    first, second = history.experiments
    assert first.index == 0 and second.index == 1
    assert "0.45" in first.description and "0.7" in second.description
    np.testing.assert_allclose(first.measured_position, near)
    np.testing.assert_allclose(second.measured_position, far)
    assert first.component_names == ["near/least_squares[31-58cm]"]
    assert second.component_names == ["far/least_squares[61-79cm]"]
    # The slices cut the run's concatenated vectors exactly, in order.
    assert first.outputs.start == 0 and first.outputs.stop == second.outputs.start
    assert second.outputs.stop == len(history.output_position)
    assert second.measured.stop == len(history.measured_position)
    np.testing.assert_array_equal(
        np.concatenate([first.output_position, second.output_position]),
        history.output_position)
    assert history.experiment("far") is second and history.experiment(0) is first
    with pytest.raises(KeyError, match="'near', 'far'"):
        history.experiment("middle")


def test_curves_per_experiment(two):
    _, history, _, _ = two
    final = history.waves[-1]
    for x in history.experiments:
        curves = history.curves(experiment=x.name)
        assert curves.shape == (final.accepted, len(x.output_position))
        np.testing.assert_array_equal(curves, final.output[:, x.outputs])
    np.testing.assert_array_equal(history.curves(1), history.waves[0].output)
    np.testing.assert_array_equal(history.curves(1, experiment=1),
                                  history.waves[0].output[:, history.experiments[1].outputs])
    # The same from the file as from the run.
    loaded = combabc.load_history(history.path)
    assert [x.name for x in loaded.experiments] == ["near", "far"]
    np.testing.assert_array_equal(loaded.curves(experiment="far"),
                                  history.curves(experiment="far"))


def test_inference_data_observes_each_experiment(two):
    pytest.importorskip("xarray")
    _, history, near, far = two
    observed = history.to_inference_data()["observed_data"]
    assert set(observed.data_vars) == {"measured_near", "measured_far"}
    assert observed["measured_near"].dims == ("position_near",)
    np.testing.assert_allclose(observed["position_far"].values, far)
    np.testing.assert_array_equal(observed["measured_far"].values,
                                  history.experiments[1].measured_value)
    assert observed["measured_far"].attrs["experiment"] == "far"
    stats = history.to_inference_data()["sample_stats"]
    assert list(stats["component_experiment"].values) == ["near", "far"]


def test_export_agrees_with_the_history(two):
    if not CLI:
        pytest.skip("COMBABC_CLI not set (run through ctest)")
    tmp_path, history, _, _ = two
    out = tmp_path / "export"
    done = subprocess.run([CLI, "export", history.path, "-o", str(out)], capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stderr
    experiments = pd.read_csv(out / "experiments.csv", keep_default_na=False)
    assert list(experiments["name"]) == ["near", "far"]
    for row, x in zip(experiments.itertuples(), history.experiments):
        assert row.first_output == x.outputs.start
        assert row.outputs == len(x.output_position)
        assert row.first_measured == x.measured.start
        assert row.description == x.description
    positions = pd.read_csv(out / "positions.csv", float_precision="round_trip")
    measured = pd.read_csv(out / "measured.csv", float_precision="round_trip")
    for x in history.experiments:
        assert list(positions.index[positions["experiment"] == x.name]) == list(
            range(x.outputs.start, x.outputs.stop))
        np.testing.assert_array_equal(
            measured.loc[measured["experiment"] == x.name, "value"].to_numpy(), x.measured_value)
    if (out / "inference_data.nc").exists():
        import xarray as xr
        observed = xr.load_dataset(out / "inference_data.nc", group="observed_data",
                                   engine="netcdf4")
        expected = history.to_inference_data()["observed_data"]
        for name in ("measured_near", "measured_far"):
            np.testing.assert_array_equal(observed[name].values, expected[name].values)


def test_a_problem_has_one_unnamed_experiment():
    problem = combabc.Problem(combabc.BinarySpace(dimension=3), lambda bits: bits.astype(float),
                              observed=[1.0, 0.0, 1.0])
    history = combabc.run(problem, combabc.make_options(num_waves=1, accepted_per_wave=5, seed=3,
                                                        thresholds=[2.0]))
    (only,) = history.experiments
    assert only.name == "" and only.description == ""
    np.testing.assert_array_equal(only.measured_value, [1.0, 0.0, 1.0])
    np.testing.assert_array_equal(history.curves(experiment=0), history.waves[-1].output)


def test_start_from_a_finished_run_adds_an_experiment(tmp_path):
    """combabc.run(config, start_from=...) as `combabc run --from`: the near experiment's finished
    run, then both experiments from its posterior; wave 0 re-simulates its last wave."""
    write_data(tmp_path / "near.csv", 0.45, 31, 60)
    write_data(tmp_path / "far.csv", 0.7, 61, 80)
    moving = CONFIG.replace("threads = 1\n", "threads = 1\nmethod = \"resample_move\"\n")
    near_only = moving[:moving.index("[[experiment]]\nname = \"far\"")] + \
        moving[moving.index("[sampler]"):]
    (tmp_path / "near.toml").write_text(near_only.replace('directory = "out"',
                                                          'directory = "near"'))
    (tmp_path / "both.toml").write_text(moving)
    finished = combabc.run(tmp_path / "near.toml")
    both = combabc.run(tmp_path / "both.toml", start_from=finished)
    assert [x.name for x in both.experiments] == ["near", "far"]
    assert both.waves[0].candidates == finished.waves[-1].accepted
    assert both.waves[-1].moves is not None
    with pytest.raises(combabc.Error, match="adds no experiment"):
        combabc.run(tmp_path / "near.toml", output_directory=tmp_path / "again",
                    start_from=finished)
    # A Problem run starts from one too (test_python_runs.py), into a history file of its own.
    with pytest.raises(ValueError, match="output_directory"):
        combabc.run(combabc.Problem(space=combabc.BinarySpace(dimension=2), simulator=lambda b, r: [0.0],
                                    observed=[0.0]), start_from=finished)
