"""The NetCDF export in ArviZ's InferenceData layout: `combabc export` writes inference_data.nc
next to the CSVs, History.to_netcdf writes the same file, and its values are the CSVs'."""

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
GROUPS = ("posterior", "sample_stats", "observed_data")


def open_groups(path):
    return {g: xr.load_dataset(path, group=g, engine="netcdf4") for g in GROUPS}


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
    _, out = exported
    groups = open_groups(out / "inference_data.nc")
    particles = pd.read_csv(out / "particles.csv", dtype={"bits": str},
                            float_precision="round_trip")
    final = particles[particles["wave"] == particles["wave"].max()]
    bit_columns = [c for c in final.columns if c.startswith("bit_")]
    np.testing.assert_array_equal(groups["posterior"]["bits"].values[0],
                                  final[bit_columns].to_numpy())
    stats = groups["sample_stats"]
    # Exact: the CSV holds the shortest text that reads back to the same double.
    np.testing.assert_array_equal(stats["weight"].values[0], final["weight"].to_numpy())
    np.testing.assert_array_equal(stats["log_weight"].values[0], final["log_weight"].to_numpy())
    np.testing.assert_array_equal(stats["distance"].values[0, :, 0],
                                  final["d_least_squares_48_80cm"].to_numpy())
    np.testing.assert_array_equal(stats["particle_index"].values[0], final["index"].to_numpy())
    measured = pd.read_csv(out / "measured.csv", float_precision="round_trip")
    np.testing.assert_array_equal(groups["observed_data"]["position"].values,
                                  measured["position_m"].to_numpy())
    np.testing.assert_array_equal(groups["observed_data"]["measured"].values,
                                  measured["value"].to_numpy())


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
    np.testing.assert_array_equal(groups["posterior"]["k"].values[0], final.reals[:, 0])
    assert list(groups["posterior"]["bit"].values) == ["a", "b", "c"]
    np.testing.assert_array_equal(groups["observed_data"]["measured"].values, [1.5])
    history.to_netcdf(tmp_path / "p.nc")
    assert open_groups(tmp_path / "p.nc")["posterior"].attrs["seed"] == 3


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
