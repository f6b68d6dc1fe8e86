"""Resample-move runs in Python (docs/python.md, "Resample-move"): SmcOptions.method and
MoveOptions, their errors, their place in the run's fingerprint; a move run's history with each
wave's move statistics and each particle's ancestor, in the DataFrames and the export under
`combabc export`'s names, and none of them for a rejection run. The histories are tests/history's
synthetic runs (combabc_fake_history --moves)."""

import json
import os
import subprocess

import numpy as np
import pytest

import combabc

FAKE = os.environ.get("COMBABC_FAKE_HISTORY")
needs_fake = pytest.mark.skipif(not FAKE, reason="COMBABC_FAKE_HISTORY not set (run through ctest)")

MOVE_KEYS = ["rounds", "proposed", "accepted", "acceptance_rate", "independent_proposed",
             "independent_accepted", "independent_share", "survivor_ess", "step"]

W = np.array([[3.0, 1.0, 2.0, 0.0], [0.0, 2.0, 1.0, 3.0]])
OBSERVED = W @ np.array([1, 0, 1, 1])


def simulator(bits):
    return W @ bits


def fake(tmp_path, name, *flags):
    path = tmp_path / name
    subprocess.run([FAKE, str(path), "--waves", "3", "--per-wave", "12", "--no-curves", *flags],
                   check=True)
    return combabc.load_history(path)


def test_method_and_move_options_are_settable_as_the_config_names_them():
    options = combabc.make_options(method="resample_move",
                                   moves=combabc.MoveOptions(max_rounds=10, ess_fraction=0.7))
    assert options.method == "resample_move"
    assert (options.moves.max_rounds, options.moves.ess_fraction) == (10, 0.7)
    # The keywords' defaults are the engine's (SmcOptions' own MoveOptions).
    defaults, engine = combabc.MoveOptions(), combabc.SmcOptions().moves
    for name in ("ess_fraction", "stay_probability", "max_rounds", "independent_share",
                 "min_survivor_fraction", "final_wave"):
        assert getattr(defaults, name) == getattr(engine, name), name
    assert defaults.final_wave == "auto"
    assert combabc.MoveOptions(final_wave="never").final_wave == "never"
    with pytest.raises(combabc.Error, match="always"):
        combabc.MoveOptions(final_wave="sometimes")
    assert combabc.SmcOptions().method == "rejection"
    options.moves.independent_share = 0.25  # nested fields are written in place
    assert options.moves.independent_share == 0.25
    for bad in (dict(ess_fraction=1.0), dict(stay_probability=0.0), dict(max_rounds=0),
                dict(independent_share=1.5), dict(min_survivor_fraction=0.0)):
        with pytest.raises(ValueError, match=next(iter(bad))):
            combabc.MoveOptions(**bad)
    with pytest.raises(combabc.Error, match="rejection"):
        options.method = "mcmc"


def test_moves_are_refused_for_a_multi_fidelity_problem():
    space = combabc.BinarySpace(dimension=4)
    problem = combabc.Problem(space, simulator, OBSERVED, low_fidelity=simulator)
    options = combabc.make_options(num_waves=2, accepted_per_wave=5, method="resample_move")
    with pytest.raises(ValueError, match="moves do not apply to multi-fidelity runs"):
        combabc.run(problem, options)


def test_a_rejection_run_resumed_as_a_move_run_is_refused(tmp_path):
    space = combabc.BinarySpace(dimension=4)
    problem = combabc.Problem(space, simulator, OBSERVED)
    options = combabc.make_options(num_waves=2, accepted_per_wave=5, seed=3, threads=1,
                                   thresholds=[4.0, 2.0], max_simulations=3)
    history = combabc.run(problem, options, output_directory=tmp_path)
    assert history.termination == "budget_exhausted"
    moved = combabc.make_options(num_waves=2, accepted_per_wave=5, seed=3, threads=1,
                                 thresholds=[4.0, 2.0], max_simulations=3,
                                 method="resample_move")
    with pytest.raises(combabc.Error, match="the options differ"):
        combabc.resume(history.path, problem, moved, max_simulations=0)


def test_a_resample_move_run_records_its_moves_and_resumes_to_the_same_history(tmp_path):
    space = combabc.BinarySpace(dimension=4)
    problem = combabc.Problem(space, simulator, OBSERVED)

    def options(**fields):
        return combabc.make_options(num_waves=3, accepted_per_wave=8, seed=5, threads=1,
                                    thresholds=[6.0, 3.0, 1.5], method="resample_move",
                                    moves=combabc.MoveOptions(max_rounds=3), **fields)

    whole = combabc.run(problem, options(), output_directory=tmp_path / "whole")
    assert whole.resample_move and whole.waves[0].moves is None
    for w in whole.waves[1:]:
        assert w.moves["proposed"] >= w.moves["accepted"] > 0
        assert np.all(w.ancestor >= 0)
    cut = combabc.run(problem, options(max_simulations=20), output_directory=tmp_path / "cut")
    assert cut.termination == "budget_exhausted"
    resumed = combabc.resume(cut.path, problem, options(), max_simulations=0)
    for a, b in zip(whole.waves, resumed.waves):
        assert a.moves == b.moves
        assert np.array_equal(a.ancestor, b.ancestor) and np.array_equal(a.bits, b.bits)


@needs_fake
def test_a_move_run_has_its_statistics_and_ancestors(tmp_path):
    history = fake(tmp_path, "moves.db", "--moves")
    assert history.resample_move
    first, second = history.waves[0], history.waves[1]
    assert first.moves is None and np.all(first.ancestor == -1)
    m = second.moves
    assert sorted(m) == sorted(MOVE_KEYS)
    assert m["rounds"] == 3 and m["proposed"] == 3 * second.accepted
    assert m["acceptance_rate"] == m["accepted"] / m["proposed"]
    assert second.ancestor.dtype == np.int64 and second.ancestor.shape == (second.accepted,)
    assert set(second.ancestor) <= set(first.index)

    particles = history.particles()
    assert particles.columns[-1] == "ancestor"
    assert np.array_equal(particles[particles["wave"] == 2]["ancestor"].to_numpy(),
                          second.ancestor)
    table = history.wave_table()
    columns = ["move_" + key for key in MOVE_KEYS]
    assert list(table.columns[-len(columns):]) == columns
    assert np.isnan(table["move_rounds"].iloc[0])
    assert table["move_proposed"].iloc[1] == m["proposed"]

    out = combabc.export(history, tmp_path / "export", netcdf=False)
    with open(os.path.join(out, "summary.json"), encoding="utf-8") as f:
        summary = json.load(f)
    assert summary["waves"][0]["moves"] is None
    assert summary["waves"][1]["moves"] == pytest.approx(m)
    with open(os.path.join(out, "waves.csv"), encoding="utf-8") as f:
        assert f.readline().rstrip("\n").split(",")[-len(columns):] == columns


@needs_fake
def test_a_rejection_run_has_none_of_them(tmp_path):
    history = fake(tmp_path, "plain.db")
    assert not history.resample_move
    assert all(w.moves is None and np.all(w.ancestor == -1) for w in history.waves)
    assert "ancestor" not in history.particles().columns
    assert "move_rounds" not in history.wave_table().columns
    out = combabc.export(history, tmp_path / "export", netcdf=False)
    with open(os.path.join(out, "summary.json"), encoding="utf-8") as f:
        assert all("moves" not in w for w in json.load(f)["waves"])


@needs_fake
def test_the_netcdf_sample_stats_carry_the_ancestors(tmp_path):
    pytest.importorskip("xarray")
    history = fake(tmp_path, "moves.db", "--moves")
    w = history.posterior_wave
    stats = history.to_inference_data()["sample_stats"]
    drawn = stats["particle_index"].values[0]
    ancestor = dict(zip(w.index, w.ancestor))
    assert np.array_equal(stats["ancestor"].values[0], [ancestor[i] for i in drawn])
    assert stats.attrs["move_rounds"] == w.moves["rounds"]
    plain = fake(tmp_path, "plain.db").to_inference_data()["sample_stats"]
    assert "ancestor" not in plain and "move_rounds" not in plain.attrs
