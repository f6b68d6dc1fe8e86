"""A multi-fidelity run's history in Python (docs/python.md): each wave's continuation
probabilities and costs, each particle's multiplier, confirmed and cheap distances, in the
DataFrames under export's column names and in the NetCDF sample_stats; none of them for a
single-fidelity run. The histories are tests/history's synthetic runs (combabc_fake_history)."""

import json
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
    w = history.posterior_wave
    assert np.any(w.weight < 0)  # the fake's false positives, multiplier 1 - 1/0.8
    with pytest.warns(UserWarning, match="weights are signed"):
        groups = history.to_inference_data()
    stats = groups["sample_stats"]
    # Signed weights: every particle once, in order, not resampled.
    assert np.array_equal(stats["particle_index"].values[0], w.index)
    assert np.array_equal(stats["multiplier"].values[0], w.multiplier)
    assert np.array_equal(stats["confirmed"].values[0], w.confirmed.astype(np.uint8))
    single = fake(tmp_path, "single.db").to_inference_data()["sample_stats"]
    assert "multiplier" not in single and "confirmed" not in single


def test_signed_weights_give_no_posterior_group_but_the_particles_and_their_weights(tmp_path):
    """Issue 35, E3: a posterior resampled from the positive part of signed weights is another
    distribution (P = 0.56 where the answer said 1.00): the NetCDF layout has no posterior then,
    and its sample_stats' weighted particles give the answer's marginals."""
    pytest.importorskip("xarray")
    history = fake(tmp_path, "mf.db", "--multi-fidelity")
    w = history.posterior_wave
    with pytest.warns(UserWarning, match="no posterior group"):
        groups = history.to_inference_data(all_waves=True)
    assert "posterior" not in groups and "posterior_predictive" not in groups
    assert not any(name.startswith("posterior_wave_") for name in groups)
    stats = groups["sample_stats"]
    assert stats.attrs["signed_weights"] == 1
    assert stats.attrs["resampling"] == "none"
    assert f"wave {w.number}'s weights are signed" in stats.attrs["signed_weights_note"]
    assert groups["prior"].attrs["signed_weights"] == 1
    weight = stats["weight"].values[0]
    assert np.array_equal(weight, w.weight)
    bits = stats["particle_bits"].values[0]
    assert list(stats["bit"].values) == history.bit_names
    np.testing.assert_allclose(np.clip(weight @ bits, 0, 1), w.marginals, atol=1e-12)
    # A single-fidelity run keeps its resampled posterior, flagged unsigned.
    single = fake(tmp_path, "single.db").to_inference_data()
    assert "posterior" in single and single["posterior"].attrs["signed_weights"] == 0
    assert "particle_bits" not in single["sample_stats"]


def test_export_of_signed_weights_says_the_netcdf_has_no_posterior(tmp_path):
    pytest.importorskip("xarray")
    netcdf = pytest.importorskip("netCDF4")
    history = fake(tmp_path, "mf.db", "--multi-fidelity")
    with pytest.warns(UserWarning, match=r"inference_data.nc: wave \d+'s weights are signed"):
        out = combabc.export(history, tmp_path / "export")
    with netcdf.Dataset(os.path.join(out, "inference_data.nc")) as f:
        assert "posterior" not in f.groups and "sample_stats" in f.groups
        assert "particle_bits" in f.groups["sample_stats"].variables


def test_standard_errors_and_the_kernel_are_the_summarys(tmp_path):
    """History shows what summary.json shows: per wave the Monte-Carlo errors under its names,
    the answer's mc_se (History.posterior_se), and the kernel `auto` resolved to."""
    history = fake(tmp_path, "mf.db", "--multi-fidelity")
    out = combabc.export(history, tmp_path / "export", netcdf=False)
    with open(os.path.join(out, "summary.json"), encoding="utf-8") as f:
        summary = json.load(f)
    for w, entry in zip(history.waves, summary["waves"]):
        for key in ("marginals_se", "marginals_ess", "reals_mean_se", "reals_sd_se", "reals_ess"):
            np.testing.assert_allclose(getattr(w, key), np.asarray(entry[key], dtype=float),
                                       rtol=1e-12, err_msg=key)
    np.testing.assert_allclose(history.posterior_se,
                               [b["mc_se"] for b in summary["answer"]["bits"]], rtol=1e-12)
    assert np.all(history.posterior_se > 0)
    assert history.binary_kernel == summary["proposal"]["binary_kernel"] != ""
    assert history.continuous_kernel == summary["proposal"]["continuous_kernel"]
