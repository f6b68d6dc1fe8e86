"""Config-file runs from Python: the same run as `combabc run`, its history as DataFrames equal to
what `combabc export` writes, and the CLI's error messages."""

import os
import pathlib
import re
import subprocess

import numpy as np
import pandas as pd
import pytest

import combabc

SOURCE = pathlib.Path(__file__).resolve().parents[2]
EXAMPLE = SOURCE / "examples" / "sensor-45cm"
CLI = os.environ.get("COMBABC_CLI")


def small_config(tmp_path, waves=2):
    """The 45 cm example, cut down to a run of a few seconds, writing into tmp_path."""
    text = (EXAMPLE / "least_squares.toml").read_text()
    replacements = [(r"(?m)^waves = \d+", f"waves = {waves}"),
                    (r"(?m)^accepted_per_wave = \d+", "accepted_per_wave = 20"),
                    (r"(?m)^threads = \d+", "threads = 1"),
                    (r'(?m)^csv = "data.csv"', f'csv = "{EXAMPLE / "data.csv"}"'),
                    (r'(?m)^directory = "[^"]*"', f'directory = "{tmp_path / "out"}"'),
                    (r"(?m)^elements_per_section = \d+", "elements_per_section = 4"),
                    (r"(?m)^elements_across_width = \d+", "elements_across_width = 2")]
    for pattern, replacement in replacements:
        text, count = re.subn(pattern, replacement, text)
        assert count == 1, pattern
    path = tmp_path / "config.toml"
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory):
    tmp_path = tmp_path_factory.mktemp("run")
    history = combabc.run(small_config(tmp_path), threads=2)
    return tmp_path, history


def test_config_run_returns_its_history(finished_run):
    _, history = finished_run
    assert os.path.isfile(history.path)
    assert history.status == "finished"
    assert history.dimension == 36 and len(history.waves) == 2
    assert all(w.accepted == 20 for w in history.waves)
    assert history.waves[0].bits.shape == (20, 36)
    assert history.components == ["least_squares[48-80cm]"]
    # Wave 2 accepts only within its threshold.
    assert np.all(history.waves[1].distance[:, 0] <= history.waves[1].thresholds[0])
    assert history.report_directory is None  # report=False by default


def test_load_history_equals_the_run(finished_run):
    _, history = finished_run
    loaded = combabc.load_history(history.path)
    pd.testing.assert_frame_equal(loaded.particles(), history.particles())
    pd.testing.assert_frame_equal(loaded.marginals(), history.marginals())
    pd.testing.assert_frame_equal(loaded.pair_correlations(), history.pair_correlations(),
                                  check_exact=True)


def test_same_history_for_any_thread_count(finished_run, tmp_path):
    _, history = finished_run
    one = combabc.run(small_config(tmp_path), threads=1)
    pd.testing.assert_frame_equal(one.particles(), history.particles())


@pytest.mark.skipif(not CLI, reason="needs the combabc CLI (COMBABC_CLI)")
def test_dataframes_equal_combabc_export(finished_run):
    tmp_path, history = finished_run
    out = tmp_path / "export"
    subprocess.run([CLI, "export", history.path, "-o", str(out)], check=True,
                   capture_output=True)
    # The CSV holds shortest round-trip numbers: read back exactly, compared exactly.
    particles = pd.read_csv(out / "particles.csv", dtype={"bits": str},
                            float_precision="round_trip")
    mine = history.particles()
    assert list(mine.columns) == list(particles.columns)
    pd.testing.assert_frame_equal(mine, particles, check_exact=True)
    marginals = pd.read_csv(out / "marginals.csv", float_precision="round_trip")
    pd.testing.assert_frame_equal(history.marginals(), marginals, check_exact=True)
    pairs = pd.read_csv(out / "pair_correlations.csv", float_precision="round_trip")
    pd.testing.assert_frame_equal(history.pair_correlations(), pairs, check_exact=True)
    waves = pd.read_csv(out / "waves.csv", float_precision="round_trip")
    mine = history.wave_table()
    for column in ("wave", "eps_least_squares_48_80cm", "phi", "candidates", "accepted",
                   "acceptance_rate", "ess", "distinct", "complete", "ess_bits"):
        np.testing.assert_array_equal(mine[column].to_numpy(), waves[column].to_numpy(),
                                      err_msg=column)


@pytest.mark.skipif(not CLI, reason="needs the combabc CLI (COMBABC_CLI)")
@pytest.mark.parametrize("bad", [("waves = 2", "waves = -1"),
                                 ('estimator = "paper"', 'estimator = "papr"')])
def test_bad_config_raises_the_clis_message(tmp_path, bad):
    path = small_config(tmp_path)
    path.write_text(path.read_text().replace(*bad))
    cli = subprocess.run([CLI, "run", str(path), "--no-report"], capture_output=True, text=True)
    assert cli.returncode == 78
    with pytest.raises(combabc.Error) as raised:
        combabc.run(path)
    assert "combabc: " + str(raised.value) == cli.stderr.strip()
    assert raised.value.exit_code == cli.returncode
    assert not (tmp_path / "out").exists()


def test_missing_history_is_an_input_error(tmp_path):
    with pytest.raises(combabc.Error, match="input error: .*missing.sqlite"):
        combabc.load_history(tmp_path / "missing.sqlite")
