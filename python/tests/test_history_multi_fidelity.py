"""A multi-fidelity run's history in Python (docs/python.md): each wave's continuation
probabilities and costs, each particle's multiplier, confirmed and cheap distances, in the
DataFrames under export's column names and in the NetCDF sample_stats; none of them for a
single-fidelity run. The histories are tests/history's synthetic runs (combabc_fake_history)."""

import os
import subprocess

import numpy as np
import pytest

import combabc

FAKE = os.environ.get("COMBABC_FAKE_HISTORY")
pytestmark = pytest.mark.skipif(not FAKE, reason="COMBABC_FAKE_HISTORY not set (run through ctest)")

WAVE_COLUMNS = ["continue_if_accepted", "continue_if_rejected", "expensive_simulations",
                "cheap_seconds", "expensive_seconds", "next_continue_if_accepted",
                "next_continue_if_rejected", "cost_ratio"]


def fake(tmp_path, name, *flags):
    path = tmp_path / name
    subprocess.run([FAKE, str(path), "--waves", "2", "--per-wave", "12", "--no-curves", *flags],
                   check=True)
    return combabc.load_history(path)


def test_a_multi_fidelity_history_has_its_columns(tmp_path):
    history = fake(tmp_path, "mf.db", "--multi-fidelity")
    assert history.multi_fidelity
    w = history.waves[0]
    assert w.multi_fidelity["continue_if_accepted"] == 0.8
    assert w.multi_fidelity["continue_if_rejected"] == 0.25
    assert 0 < w.multi_fidelity["expensive_simulations"] <= w.candidates
    assert w.multiplier.shape == (w.accepted,)
    assert w.confirmed.dtype == np.bool_
    assert w.low_distance.shape == w.distance.shape
    # Unconfirmed particles weigh 1; confirmed ones 1, 1/eta_2 or 1 - 1/eta_1.
    assert np.all(w.multiplier[~w.confirmed] == 1.0)
    assert set(np.round(w.multiplier[w.confirmed], 12)) <= {1.0, 4.0, -0.25}

    particles = history.particles()
    components = [c for c in particles.columns if c.startswith("d_")]
    assert list(particles.columns[-(2 + len(components)):]) == \
        ["multiplier", "confirmed"] + ["low_distance_" + c[2:] for c in components]
    assert particles["confirmed"].isin([0, 1]).all()
    first = particles[particles["wave"] == 1]
    assert np.array_equal(first["multiplier"].to_numpy(), w.multiplier)

    table = history.wave_table()
    assert list(table.columns[-len(WAVE_COLUMNS):]) == WAVE_COLUMNS
    assert table["expensive_simulations"].iloc[0] == w.multi_fidelity["expensive_simulations"]
    assert table["cost_ratio"].iloc[0] == 50.0


def test_a_single_fidelity_history_has_none(tmp_path):
    history = fake(tmp_path, "single.db")
    assert not history.multi_fidelity
    assert history.waves[0].multi_fidelity is None and history.waves[0].multiplier is None
    assert "multiplier" not in history.particles().columns
    assert "cost_ratio" not in history.wave_table().columns


def test_the_netcdf_sample_stats_carry_multiplier_and_confirmed(tmp_path):
    pytest.importorskip("xarray")
    history = fake(tmp_path, "mf.db", "--multi-fidelity")
    stats = history.to_inference_data()["sample_stats"]
    rows = [list(history.waves[-1].index).index(i) for i in stats["particle_index"].values[0]]
    assert np.array_equal(stats["multiplier"].values[0], history.waves[-1].multiplier[rows])
    assert np.array_equal(stats["confirmed"].values[0],
                          history.waves[-1].confirmed[rows].astype(np.uint8))
    # Draws come from the positive part of the signed weights: never a negative particle.
    assert np.all(stats["weight"].values[0] > 0)
    single = fake(tmp_path, "single.db").to_inference_data()["sample_stats"]
    assert "multiplier" not in single and "confirmed" not in single
