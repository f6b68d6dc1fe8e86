"""The NetCDF export in ArviZ's InferenceData layout: `combabc export` writes inference_data.nc
next to the CSVs, History.to_netcdf writes the same file, and its values are the CSVs'. The
posterior holds equally weighted (resampled) draws, so xarray's means are combabc's marginals
within resampling error (ArviZ is not packaged in Debian 12: xarray only)."""

import os
import pathlib
import subprocess

import numpy as np
import pandas as pd
import pytest

import combabc
from test_config import small_config

xr = pytest.importorskip("xarray")
pytest.importorskip("netCDF4")

CLI = os.environ.get("COMBABC_CLI")
GROUPS = ("posterior", "sample_stats", "prior", "posterior_predictive", "observed_data")


def open_groups(path, groups=GROUPS):
    return {g: xr.load_dataset(path, group=g, engine="netcdf4") for g in groups}


def rows_of(draws, particles):
    """For each draw, the row of `particles` (a DataFrame of one wave) it was drawn from."""
    row = {index: k for k, index in enumerate(particles["index"])}
    return np.array([row[i] for i in draws["particle_index"].values[0]])


def assert_means_equal_marginals(posterior, marginals, n):
    """The posterior group's means within 4 binomial standard errors (and 1/n) of marginals."""
    means = posterior["bits"].mean(dim=("chain", "draw")).values
    bound = 4 * np.sqrt(marginals * (1 - marginals) / n) + 1.0 / n
    assert np.all(np.abs(means - marginals) <= bound), np.max(np.abs(means - marginals) - bound)


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    if not CLI:
        pytest.skip("COMBABC_CLI not set (run through ctest)")
    tmp_path = tmp_path_factory.mktemp("netcdf")
    history = combabc.run(small_config(tmp_path), threads=2)
    out = tmp_path / "export"
    done = subprocess.run([CLI, "export", history.path, "-o", str(out)], capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
    return history, out


def test_export_writes_the_inference_data_groups(exported):
    history, out = exported
    groups = open_groups(out / "inference_data.nc")
    posterior = groups["posterior"]
    final = history.waves[-1]
    assert dict(posterior.sizes) == {"chain": 1, "draw": final.accepted, "bit": 36}
    assert list(posterior["bit"].values) == history.bit_names
    assert posterior["bits"].dtype == np.uint8
    stats = groups["sample_stats"]
    assert set(stats.data_vars) == {"weight", "log_weight", "distance", "particle_index"}
    assert list(stats["component"].values) == ["least_squares[48-80cm]"]
    observed = groups["observed_data"]
    assert observed["position"].attrs["units"] == "m"
    for ds in groups.values():
        assert ds.attrs["inference_library"] == "combabc"
        assert ds.attrs["wave"] == len(history.waves)
        assert ds.attrs["seed"] == history.seed
        assert "[sampler]" in ds.attrs["config_text"]


def test_netcdf_values_equal_the_csvs(exported):
    history, out = exported
    groups = open_groups(out / "inference_data.nc")
    particles = pd.read_csv(out / "particles.csv", dtype={"bits": str},
                            float_precision="round_trip")
    final = particles[particles["wave"] == particles["wave"].max()].reset_index(drop=True)
    assert list(final.columns[3:3 + 36]) == history.bit_names  # the bits' columns by name
    stats = groups["sample_stats"]
    rows = rows_of(stats, final)
    np.testing.assert_array_equal(groups["posterior"]["bits"].values[0],
                                  final[history.bit_names].to_numpy()[rows])
    # Exact: the CSV holds the shortest text that reads back to the same double.
    np.testing.assert_array_equal(stats["weight"].values[0], final["weight"].to_numpy()[rows])
    np.testing.assert_array_equal(stats["log_weight"].values[0],
                                  final["log_weight"].to_numpy()[rows])
    np.testing.assert_array_equal(stats["distance"].values[0, :, 0],
                                  final["d_least_squares_48_80cm"].to_numpy()[rows])
    measured = pd.read_csv(out / "measured.csv", float_precision="round_trip")
    np.testing.assert_array_equal(groups["observed_data"]["position"].values,
                                  measured["position_m"].to_numpy())
    np.testing.assert_array_equal(groups["observed_data"]["measured"].values,
                                  measured["value"].to_numpy())
    # The posterior predictive: the same draws' curves.
    curves = pd.read_csv(out / "curves.csv", float_precision="round_trip")
    curves = curves[curves["wave"] == final["wave"].iloc[0]].set_index("index")
    (name,) = groups["posterior_predictive"].data_vars
    np.testing.assert_array_equal(
        groups["posterior_predictive"][name].values[0],
        curves.loc[stats["particle_index"].values[0]].drop(columns="wave").to_numpy())


def test_posterior_means_equal_the_marginals(exported, tmp_path):
    """The issue's failure: with the importance estimator, unweighted means of the weighted draws
    differed from combabc's marginals by up to 0.122 on this example."""
    history, out = exported
    groups = open_groups(out / "inference_data.nc")
    final = history.waves[-1]
    # The example's own estimator, paper: equally weighted particles, resampled as they are.
    assert history.estimator == "paper"
    assert groups["posterior"].attrs["resampling_weights"] == "equal"
    assert_means_equal_marginals(groups["posterior"], final.marginals_paper, final.accepted)
    # Wave 1 has infinite thresholds: its particles are prior draws.
    assert groups["prior"].attrs["source"].startswith("wave 1")
    np.testing.assert_array_equal(groups["prior"]["bits"].values[0], history.waves[0].bits)
    # The importance estimator, with enough particles for its weights to matter.
    config = small_config(tmp_path, waves=3)
    config.write_text(config.read_text().replace('estimator = "paper"', 'estimator = "importance"')
                      .replace("accepted_per_wave = 20", "accepted_per_wave = 300"))
    weighted = combabc.run(config, threads=2)
    final = weighted.waves[-1]
    directory = combabc.export(weighted.path, tmp_path / "export")
    posterior = xr.load_dataset(os.path.join(directory, "inference_data.nc"), group="posterior")
    assert posterior.attrs["resampling"] == "systematic"
    assert posterior.attrs["resampling_weights"] == "weight"
    assert_means_equal_marginals(posterior, final.marginals_importance, final.accepted)
    assert np.max(np.abs(final.bits.mean(axis=0) - final.marginals_importance)) > 0.02


def test_posterior_means_equal_the_marginals_on_the_tutorial_toy():
    weights = np.random.default_rng(1).integers(0, 4, size=(4, 10)).astype(float)
    truth = np.array([1, 0, 1, 1, 0, 0, 1, 0, 0, 1], dtype=np.uint8)
    space = combabc.BinarySpace(dimension=10, names=[f"switch {k + 1}" for k in range(10)])
    problem = combabc.Problem(space, lambda bits: bits @ weights.T, observed=weights @ truth,
                              batch=True)
    history = combabc.run(problem, combabc.make_options(
        num_waves=3, accepted_per_wave=2000, thresholds=[8.0, 5.0, 3.0], seed=7, threads=2))
    final = history.waves[-1]
    groups = history.to_inference_data()
    assert_means_equal_marginals(groups["posterior"], final.marginals_importance, final.accepted)
    # The weighted particles' plain mean is not the marginal: the resampling matters here.
    assert np.max(np.abs(final.bits.mean(axis=0) - final.marginals_importance)) > 0.02
    # Reproducible: the same draws again.
    again = history.to_inference_data()
    xr.testing.assert_identical(groups["posterior"], again["posterior"])


def test_history_to_netcdf_equals_the_export(exported, tmp_path):
    history, out = exported
    history.to_netcdf(tmp_path / "mine.nc")
    mine = open_groups(tmp_path / "mine.nc")
    theirs = open_groups(out / "inference_data.nc")
    for group in GROUPS:
        xr.testing.assert_identical(mine[group], theirs[group])


def test_problem_history_has_the_layout_with_reals(tmp_path):
    space = combabc.BinarySpace(dimension=3, names=["a", "b", "c"])
    problem = combabc.Problem(space, lambda bits, reals: np.array([bits.sum() + reals[0]]),
                              observed=[1.5], reals=[combabc.ContinuousParameter("k")])
    options = combabc.make_options(num_waves=2, accepted_per_wave=30, seed=3,
                                   thresholds=[2.0, 1.0])
    history = combabc.run(problem, options)
    groups = history.to_inference_data()
    final = history.waves[-1]
    rows = rows_of(groups["sample_stats"], {"index": final.index})
    np.testing.assert_array_equal(groups["posterior"]["k"].values[0], final.reals[rows, 0])
    assert list(groups["posterior"]["bit"].values) == ["a", "b", "c"]
    np.testing.assert_array_equal(groups["observed_data"]["measured"].values, [1.5])
    # Wave 1's threshold is finite: the prior group holds draws from the stated prior.
    prior = groups["prior"]
    assert prior.attrs["source"] == "stated prior"
    assert prior["k"].shape == (1, 30) and 0 <= prior["k"].min() and prior["k"].max() <= 1
    # The outputs lie at the data's positions (the index): one name in both groups.
    np.testing.assert_array_equal(groups["posterior_predictive"]["measured"].values[0],
                                  final.output[rows])
    history.to_netcdf(tmp_path / "p.nc")
    assert open_groups(tmp_path / "p.nc")["posterior"].attrs["seed"] == 3


@pytest.mark.skipif(not CLI, reason="COMBABC_CLI not set (run through ctest)")
def test_all_waves(exported, tmp_path):
    history, _ = exported
    out = tmp_path / "all"
    done = subprocess.run([CLI, "export", history.path, "-o", str(out), "--all-waves"],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    names = [f"{g}_wave_{w.number}" for w in history.waves for g in ("posterior", "sample_stats")]
    groups = open_groups(out / "inference_data.nc", GROUPS + tuple(names))
    mine = history.to_inference_data(all_waves=True)
    for name in names:
        xr.testing.assert_identical(groups[name], mine[name])
    for w in history.waves:
        assert groups[f"posterior_wave_{w.number}"].attrs["wave"] == w.number
        assert_means_equal_marginals(groups[f"posterior_wave_{w.number}"],
                                     w.marginals_importance, w.accepted)
    xr.testing.assert_identical(groups[f"posterior_wave_{len(history.waves)}"],
                                groups["posterior"])


def test_export_without_xarray_writes_the_csvs_and_says_why(exported, tmp_path):
    history, _ = exported
    fake = tmp_path / "fake"
    fake.mkdir()
    (fake / "xarray.py").write_text('raise ImportError("No module named \'xarray\'")\n')
    out = tmp_path / "export"
    env = dict(os.environ, PYTHONPATH=str(fake))
    done = subprocess.run([CLI, "export", history.path, "-o", str(out)], capture_output=True,
                          text=True, env=env)
    assert done.returncode == 0, done.stderr
    assert "no inference_data.nc" in done.stderr and "python3-xarray" in done.stderr
    assert (out / "particles.csv").is_file() and not (out / "inference_data.nc").exists()
    assert not [p for p in out.iterdir() if p.name.startswith(".combabc-tmp-")]


def test_no_netcdf_flag_skips_it(exported, tmp_path):
    history, _ = exported
    out = tmp_path / "export"
    done = subprocess.run([CLI, "export", history.path, "-o", str(out), "--no-netcdf"],
                          capture_output=True, text=True)
    assert done.returncode == 0 and done.stderr == ""
    assert (out / "waves.csv").is_file() and not (out / "inference_data.nc").exists()


def test_export_from_python_writes_the_clis_files(exported, tmp_path):
    history, out = exported
    directory = combabc.export(history.path, tmp_path / "py")
    assert directory == str(tmp_path / "py")
    for name in ("particles.csv", "waves.csv", "marginals.csv", "measured.csv"):
        assert (tmp_path / "py" / name).read_bytes() == (out / name).read_bytes(), name
    mine = open_groups(tmp_path / "py" / "inference_data.nc")
    theirs = open_groups(out / "inference_data.nc")
    for group in GROUPS:
        xr.testing.assert_identical(mine[group], theirs[group])
    # A directory it did not write is refused with the CLI's message.
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    with pytest.raises(combabc.Error, match=r"was not written by combabc"):
        combabc.export(history.path, foreign)
    assert sorted(p.name for p in foreign.iterdir()) == ["notes.txt"]


def test_a_failing_netcdf_script_fails_the_export_and_writes_nothing(exported, tmp_path):
    history, _ = exported
    script = tmp_path / "broken.py"
    script.write_text('import sys\nprint("combabc_netcdf: broken on purpose", file=sys.stderr)\n'
                      "sys.exit(65)\n")
    out = tmp_path / "export"
    env = dict(os.environ, COMBABC_NETCDF_SCRIPT=str(script))
    done = subprocess.run([CLI, "export", history.path, "-o", str(out)], capture_output=True,
                          text=True, env=env)
    assert done.returncode == 65
    assert done.stderr == "combabc: data error: inference_data.nc: broken on purpose\n"
    assert not out.exists()  # no CSV without its NetCDF file, no temporaries


def test_a_budget_stopped_runs_posterior_is_its_last_complete_wave_and_says_so(tmp_path):
    from test_smc import options, problem
    whole = combabc.run(problem(), options(accepted_per_wave=200, batch_size=50))
    complete = whole.to_inference_data()
    for group in complete.values():
        assert group.attrs["posterior_note"] == "" and group.attrs["incomplete_wave_left_out"] == 0
    assert complete["posterior"].attrs["wave"] == 3
    # Stopped halfway through wave 3: the posterior is wave 2's, as history.posterior.
    budget = sum(w.candidates for w in whole.waves[:2]) + whole.waves[2].candidates // 2
    stopped = combabc.run(problem(), options(accepted_per_wave=200, batch_size=50,
                                             max_simulations=budget),
                          output_directory=tmp_path)
    assert [w.complete for w in stopped.waves] == [True, True, False]
    groups = stopped.to_inference_data()
    for name, group in groups.items():
        assert group.attrs["wave"] == 2, name
        assert group.attrs["incomplete_wave_left_out"] == 3, name
        assert group.attrs["posterior_note"] == stopped.posterior_note == \
            "the numbers are wave 2's: wave 3 is incomplete (budget_exhausted)", name
    second = stopped.waves[1]
    rows = rows_of(groups["sample_stats"], {"index": second.index})
    np.testing.assert_array_equal(groups["posterior"]["bits"].values[0], second.bits[rows])
    np.testing.assert_array_equal(groups["posterior_predictive"]["measured"].values[0],
                                  second.output[rows])
    assert_means_equal_marginals(groups["posterior"], second.marginals_importance,
                                 second.accepted)
    # The export's file (built from its CSVs) says the same.
    out = combabc.export(stopped, tmp_path / "export")
    exported = open_groups(os.path.join(out, "inference_data.nc"))
    for group in GROUPS:
        xr.testing.assert_identical(exported[group], groups[group])
    # Every wave, the incomplete one too, with all_waves.
    every = stopped.to_inference_data(all_waves=True)
    assert every["posterior_wave_3"].attrs["wave"] == 3
    xr.testing.assert_identical(every["posterior_wave_2"], groups["posterior"])
