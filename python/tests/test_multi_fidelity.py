"""Problem(low_fidelity=...): a multi-fidelity run of a toy whose cheap model is shifted; the
options (combabc.MultiFidelityOptions) and the errors that name their argument."""

import numpy as np
import pytest

import combabc

W = np.array([[3.0, 1.0, 2.0, 0.0, 1.0, 2.0],
              [0.0, 2.0, 1.0, 3.0, 1.0, 0.0]])
TRUTH = np.array([1, 0, 1, 1, 0, 0], dtype=np.uint8)
OBSERVED = W @ TRUTH


def expensive(bits):
    return W @ bits


def cheap(bits):
    return W @ bits + 0.3  # biased: the run still targets the expensive model's posterior


def problem(**fields):
    space = combabc.BinarySpace(dimension=6)
    return combabc.Problem(space, expensive, OBSERVED, **fields)


def options():
    return combabc.make_options(
        num_waves=3, accepted_per_wave=40, seed=4, threads=1, thresholds=[5.0, 3.0, 2.0],
        multi_fidelity=combabc.MultiFidelityOptions(continue_if_rejected=0.5, cost_ratio=10))


def test_a_multi_fidelity_run_goes_through_the_cheap_model(tmp_path):
    calls = {"cheap": 0, "expensive": 0}

    def counted_cheap(bits):
        calls["cheap"] += 1
        return cheap(bits)

    def counted_expensive(bits):
        calls["expensive"] += 1
        return expensive(bits)

    space = combabc.BinarySpace(dimension=6)
    p = combabc.Problem(space, counted_expensive, OBSERVED, low_fidelity=counted_cheap)
    history = combabc.run(p, options(), output_directory=tmp_path)
    assert len(history.waves) == 3
    assert all(w.accepted == 40 for w in history.waves)
    # Every candidate ran the cheap model; the expensive one only the continued ones.
    assert calls["cheap"] > 0
    assert 0 < calls["expensive"] < calls["cheap"]


def test_a_resume_without_the_cheap_model_is_another_problem(tmp_path):
    stopped = options()
    stopped.max_simulations = 60
    history = combabc.run(problem(low_fidelity=cheap), stopped, output_directory=tmp_path)
    with pytest.raises(combabc.Error, match="the problem"):
        combabc.resume(history.path, problem(), options())
    resumed = combabc.resume(history.path, problem(low_fidelity=cheap), options())
    assert [w.accepted for w in resumed.waves] == [40, 40, 40]


def test_options_and_errors_name_their_argument():
    o = combabc.MultiFidelityOptions(continue_if_accepted=0.8, floor=0.05, adapt=False)
    assert (o.continue_if_accepted, o.continue_if_rejected, o.floor, o.adapt, o.cost_ratio) == \
        (0.8, 0.1, 0.05, False, 0.0)
    for bad in (dict(continue_if_accepted=0.0), dict(continue_if_rejected=1.5), dict(floor=0.0)):
        name = next(iter(bad))
        with pytest.raises(ValueError, match=name):
            combabc.MultiFidelityOptions(**bad)
    with pytest.raises(ValueError, match="cost_ratio"):
        combabc.MultiFidelityOptions(cost_ratio=-1.0)
    with pytest.raises(TypeError, match="low_fidelity"):
        problem(low_fidelity=[1, 2])
    # A field set later is checked when the run starts.
    late = options()
    late.multi_fidelity.floor = 2.0
    with pytest.raises(ValueError, match="floor"):
        combabc.run(problem(low_fidelity=cheap), late)
