"""The CLI's other jobs from Python: the sensor's profiles (`combabc simulate`), enumeration
(`combabc enumerate`) and resume (`combabc resume`, after a Ctrl-C in Python)."""

import os
import pathlib
import re
import signal
import sqlite3
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pytest

import combabc
from test_config import EXAMPLE, small_config

CLI = os.environ.get("COMBABC_CLI")
needs_cli = pytest.mark.skipif(not CLI, reason="needs the combabc CLI (COMBABC_CLI)")


def replaced(text, replacements):
    for pattern, replacement in replacements:
        text, count = re.subn(pattern, replacement, text)
        assert count == 1, pattern
    return text


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    config = small_config(tmp_path_factory.mktemp("sensor"))
    return config, combabc.SensorModel(config)


@needs_cli
@pytest.mark.parametrize("clamps", ["0" * 36, "1" * 36, "0" * 10 + "1" * 16 + "0" * 10,
                                    "101100111000101010111100001101010011"])
def test_profile_equals_combabc_simulate(model, tmp_path, clamps):
    config, sensor = model
    csv = tmp_path / "profile.csv"
    subprocess.run([CLI, "simulate", str(config), "--clamps", clamps, "-o", str(csv)],
                   check=True, capture_output=True)
    table = pd.read_csv(csv, dtype=str)
    # The CSV holds 10 significant digits (%.10g): the same text is the same value.
    text = lambda values: [f"{v:.10g}" for v in values]  # noqa: E731
    assert text(sensor.positions) == list(table["position_m"])
    assert text(sensor.profile(clamps)) == list(table["displacement_m"])
    assert text(sensor.profile(clamps, normalised=True)) == list(table["normalised"])
    bits = np.array([c == "1" for c in clamps], dtype=np.uint8)
    np.testing.assert_array_equal(sensor.profile(bits), sensor.profile(clamps))


def test_profiles_batch_equals_one_at_a_time(model):
    _, sensor = model
    rng = np.random.default_rng(5)
    bits = rng.integers(0, 2, size=(6, sensor.dimension)).astype(np.uint8)
    batch = sensor.profiles(bits)
    assert batch.shape == (6, len(sensor.positions))
    for row, b in zip(batch, bits):
        np.testing.assert_array_equal(row, sensor.profile(b))
    # Different clamps, different profiles: the batch does not repeat one row.
    assert not np.array_equal(batch[0], batch[1])


def test_bad_clamps_are_the_clis_messages(model):
    _, sensor = model
    with pytest.raises(combabc.Error, match=r"--clamps: has 3 characters; the model has 36"):
        sensor.profile("010")
    with pytest.raises(combabc.Error, match=r"character 2 is 'x'; must be 0 or 1"):
        sensor.profile("0x" + "0" * 34)
    with pytest.raises(ValueError, match=r"every value must be 0 or 1"):
        sensor.profile(np.full(36, 2))
    with pytest.raises(ValueError, match=r"shape \(36,\)"):
        sensor.profile(np.zeros(35))


def enumeration_config(tmp_path):
    text = replaced((EXAMPLE / "area.toml").read_text(), [
        (r"(?m)^per_edge = \d+", "per_edge = 5"),
        (r"(?m)^quantile = [0-9.]+", "threshold = [0.5, 0.3]"),
        (r"(?m)^waves = \d+", "waves = 2"),
        (r"(?m)^threads = \d+", "threads = 2"),
        (r'(?m)^csv = "data.csv"', f'csv = "{EXAMPLE / "data.csv"}"'),
        (r'(?m)^directory = "[^"]*"', f'directory = "{tmp_path / "out"}"')])
    path = tmp_path / "enumerate.toml"
    path.write_text(text)
    return path


@needs_cli
def test_enumerate_equals_combabc_enumerate(tmp_path):
    config = enumeration_config(tmp_path)
    history = combabc.enumerate(config, threads=1)
    assert history.termination == "enumerated" and len(history.waves) == 1
    assert history.enumeration["configurations"] == 1024
    assert history.enumeration["accepted"] == history.waves[0].accepted > 0
    assert list(history.waves[0].thresholds) == [0.3]
    assert os.path.isfile(os.path.join(history.enumeration["directory"],
                                       "top_configurations.csv"))
    cli_out = tmp_path / "cli"
    subprocess.run([CLI, "enumerate", str(config), "-o", str(cli_out), "--no-report", "-q"],
                   check=True, capture_output=True)
    theirs = combabc.load_history(cli_out / "history.sqlite")
    pd.testing.assert_frame_equal(history.particles(), theirs.particles(), check_exact=True)
    np.testing.assert_array_equal(history.posterior, theirs.posterior)
    # At another threshold: fewer accepted.
    strict = combabc.enumerate(config, thresholds=[0.2], output_directory=tmp_path / "strict")
    assert 0 < strict.enumeration["accepted"] < history.enumeration["accepted"]
    # The threshold as a NumPy array or scalar: the same enumeration.
    for thresholds in (np.array([0.2]), [np.float32(0.2)]):
        again = combabc.enumerate(config, thresholds=thresholds, output_directory=tmp_path / "np",
                                  overwrite=True)
        assert again.enumeration["accepted"] == strict.enumeration["accepted"]


def test_resume_of_a_finished_run_is_a_usage_error(tmp_path):
    history = combabc.run(small_config(tmp_path))
    with pytest.raises(combabc.Error) as raised:
        combabc.resume(history.path)
    assert raised.value.kind == "usage error"


def test_a_run_stopped_on_its_budget_resumes_with_a_raised_limit(tmp_path):
    (tmp_path / "whole").mkdir()
    (tmp_path / "stopped").mkdir()
    whole = combabc.run(small_config(tmp_path / "whole", waves=3))
    total = int(whole.summary["simulations"])
    assert total > 60  # the budget below falls inside a wave after the first
    config = small_config(tmp_path / "stopped", waves=3)
    config.write_text(config.read_text().replace("[sampler]\n",
                                                 f"[sampler]\nmax_simulations = {total - 5}\n"))
    stopped = combabc.run(config)
    assert stopped.termination == "budget_exhausted"
    with pytest.raises(combabc.Error) as raised:  # the same limit would stop it again at once
        combabc.resume(stopped.path)
    # Named as the keyword that raises it.
    assert raised.value.kind == "usage error" and "max_simulations=" in str(raised.value)
    resumed = combabc.resume(stopped.path, max_simulations=total + 1000)
    assert resumed.termination == whole.termination
    pd.testing.assert_frame_equal(resumed.particles(), whole.particles(), check_exact=True)


CHILD = """
import sys
import combabc
try:
    combabc.run(sys.argv[1], threads=2)
except KeyboardInterrupt as e:
    print("interrupted:", *getattr(e, "__notes__", []))
    sys.exit(130)
print("finished")
"""


def particles_committed(path):
    try:
        with sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=0.1) as con:
            return con.execute("SELECT count(*) FROM particle").fetchone()[0] > 0
    except sqlite3.Error:
        return False  # not created yet, or its schema not yet written


def test_ctrl_c_stops_a_config_run_resumably(tmp_path):
    """SIGINT to a Python process in combabc.run: KeyboardInterrupt, the history resumable, and
    resume gives the uninterrupted run's history."""
    config = tmp_path / "long.toml"
    config.write_text(replaced(small_config(tmp_path).read_text(), [
        (r"(?m)^waves = \d+", "waves = 3"),
        (r"(?m)^accepted_per_wave = \d+", "accepted_per_wave = 3000")]))
    path = tmp_path / "out" / "history.sqlite"
    child = subprocess.Popen([sys.executable, "-c", CHILD, str(config)], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True, env=os.environ.copy())
    deadline = time.monotonic() + 120
    while not particles_committed(path) and child.poll() is None:
        assert time.monotonic() < deadline, "no batch committed in 120 s"
        time.sleep(0.01)
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=120)
    assert child.returncode == 130, (out, err)
    assert "continue with combabc.resume" in out and str(path) in out
    interrupted = combabc.load_history(path)
    assert interrupted.status == "interrupted"
    resumed = combabc.resume(path, threads=1)
    assert resumed.status == "finished" and len(resumed.waves) == 3
    straight = combabc.run(config, threads=2, output_directory=tmp_path / "straight")
    pd.testing.assert_frame_equal(resumed.particles(), straight.particles(), check_exact=True)
