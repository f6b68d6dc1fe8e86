"""Problem(parameters=...): a simulator that takes its parameters by name (a dict, a pandas
Series or DataFrame) gives the history of the same simulator taking positional arrays."""

import numpy as np
import pandas as pd
import pytest

import combabc
from test_smc import OBSERVED, PRIOR, W, batched, options, per_sample, problem, same_history

NAMES = [f"b{k}" for k in range(1, 9)]
COEFFICIENTS = {name: W[:, k] for k, name in enumerate(NAMES)}


def named_problem(simulator, parameters, batch=False, **keywords):
    space = combabc.BinarySpace(dimension=8, prior_one=PRIOR, names=NAMES)
    return combabc.Problem(space, simulator, OBSERVED, batch=batch, parameters=parameters,
                           **keywords)


def test_a_per_sample_simulator_gets_a_dict_or_a_series_by_name():
    seen = []

    def from_dict(params):
        seen.append(params)
        return sum(COEFFICIENTS[name] * params[name] for name in NAMES)

    def from_series(params):
        assert isinstance(params, pd.Series) and list(params.index) == NAMES
        return sum(COEFFICIENTS[name] * params[name] for name in NAMES)

    positional = combabc.run(problem(per_sample), options(accepted_per_wave=200))
    same_history(positional, combabc.run(named_problem(from_dict, "dict"),
                                         options(accepted_per_wave=200)))
    assert list(seen[0]) == NAMES and all(type(v) is int and v in (0, 1)
                                         for v in seen[0].values())
    same_history(positional, combabc.run(named_problem(from_series, "pandas"),
                                         options(accepted_per_wave=200)))


def test_a_batched_simulator_gets_a_dict_of_arrays_or_a_data_frame():
    shapes = []

    def from_dict(params):
        shapes.append({name: (v.dtype, v.shape) for name, v in params.items()})
        return sum(np.outer(params[name], COEFFICIENTS[name]) for name in NAMES)

    def from_frame(params):
        assert isinstance(params, pd.DataFrame) and list(params.columns) == NAMES
        return params.to_numpy(dtype=np.float64) @ W.T

    positional = combabc.run(problem(batched, batch=True), options(accepted_per_wave=200))
    same_history(positional, combabc.run(named_problem(from_dict, "dict", batch=True),
                                         options(accepted_per_wave=200), threads=2))
    assert {dtype for call in shapes for dtype, _ in call.values()} == {np.dtype(np.uint8)}
    assert max(call["b3"][1][0] for call in shapes) > 1 and len(shapes[0]["b3"][1]) == 1
    same_history(positional, combabc.run(named_problem(from_frame, "pandas", batch=True),
                                         options(accepted_per_wave=200)))


@pytest.mark.parametrize("batch", [False, True])
def test_reals_and_rng_reach_a_simulator_by_name(batch):
    def noise(rng):  # batched: one generator per candidate
        if batch:
            return np.array([[g.normal(0.0, 0.1)] for g in rng])
        return rng.normal(0.0, 0.1)

    def positional(bits, reals, rng):
        if batch:
            return bits.sum(axis=1, keepdims=True) + reals[:, :1] + noise(rng)
        return np.array([bits.sum() + reals[0] + noise(rng)])

    def named(params, rng):
        total = sum(params[name] for name in ("x", "y")) + params["offset"]
        if batch:
            return np.asarray(total, dtype=np.float64)[:, None] + noise(rng)
        return np.array([total + noise(rng)])

    space = combabc.BinarySpace(dimension=2, names=["x", "y"])
    reals = [combabc.ContinuousParameter("offset", kind="uniform", low=-1.0, high=1.0)]
    run_options = combabc.make_options(num_waves=2, accepted_per_wave=100, seed=3,
                                       thresholds=[1.0, 0.5])
    expected = combabc.run(combabc.Problem(space, positional, [1.5], reals=reals, batch=batch,
                                           rng=True), run_options)
    for parameters in ("dict", "pandas"):
        got = combabc.run(combabc.Problem(space, named, [1.5], reals=reals, batch=batch,
                                          rng=True, parameters=parameters), run_options)
        same_history(expected, got)


def test_a_bad_parameters_value_or_a_shared_name_is_one_line():
    with pytest.raises(ValueError) as bad:
        named_problem(per_sample, "frame")
    assert str(bad.value) == ("Problem: parameters = 'frame'; expected one of 'arrays', 'dict', "
                              "'pandas'")
    space = combabc.BinarySpace(dimension=1, names=["k"])
    reals = [combabc.ContinuousParameter("k", kind="uniform", low=0.0, high=1.0)]
    with pytest.raises(ValueError, match="'k' names a bit and a continuous parameter"):
        combabc.Problem(space, per_sample, [1.0], reals=reals, parameters="dict")
    # Positional arrays need no distinct names.
    assert combabc.Problem(space, per_sample, [1.0], reals=reals).parameters == "arrays"
