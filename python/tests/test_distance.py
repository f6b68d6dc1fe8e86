"""Distances written in Python (Problem(..., distance=...)): the exact ABC posterior under an L1
distance, several named components, per-sample and batch callables, determinism across thread
counts, and the errors and failures of a distance."""

import itertools

import numpy as np
import pytest

import combabc
from test_smc import (OBSERVED, PRIOR, W, batched, exact_posterior, options, per_sample,
                      same_history)

L1_THRESHOLDS = [8.0, 5.0, 3.0]


def l1(output, observed):
    return np.abs(output - observed).sum()


def l1_batch(outputs, observed):
    return np.abs(outputs - observed).sum(axis=1)


def l1_and_max(output, observed):
    diff = np.abs(output - observed)
    return np.array([diff.sum(), diff.max()])


def problem(distance=l1, simulator=per_sample, batch=False, **keywords):
    space = combabc.BinarySpace(dimension=8, prior_one=PRIOR)
    return combabc.Problem(space, simulator, OBSERVED, batch=batch, distance=distance, **keywords)


def l1_options(**fields):
    return options(thresholds=L1_THRESHOLDS, **fields)


def exact_l1_posterior(eps):
    """P(bit k = 1 | ||W theta - y||_1 <= eps) by enumerating all 2^8 configurations."""
    mass, total, prior = np.zeros(8), 0.0, np.array(PRIOR)
    for config in itertools.product([0, 1], repeat=8):
        theta = np.array(config)
        if np.abs(W @ theta - OBSERVED).sum() > eps:
            continue
        p = np.prod(np.where(theta == 1, prior, 1.0 - prior))
        total += p
        mass += p * theta
    return mass / total


def test_exact_posterior_under_a_python_l1_distance():
    exact = exact_l1_posterior(L1_THRESHOLDS[-1])
    # The test can fail: the posterior is neither the prior nor the Euclidean one at the same
    # threshold (what the built-in distance would give), each off by twice the bound below.
    assert np.max(np.abs(exact - PRIOR)) > 0.15
    assert np.max(np.abs(exact - exact_posterior(L1_THRESHOLDS[-1]))) > 0.08
    history = combabc.run(problem(), l1_options(accepted_per_wave=4000))
    assert history.components == ["distance"]
    last = history.waves[-1]
    assert last.accepted == 4000
    np.testing.assert_array_equal(last.distance[:, 0], np.abs(last.bits @ W.T - OBSERVED).sum(1))
    assert np.all(last.distance[:, 0] <= L1_THRESHOLDS[-1])
    # The outputs are the simulator's alone (the distance is not appended to them).
    np.testing.assert_array_equal(last.output, last.bits @ W.T)
    # test_smc.py's bound: 4.5 standard errors at the effective sample size, plus 0.005.
    bound = 4.5 * np.sqrt(exact * (1.0 - exact) / last.ess) + 0.005
    assert np.all(np.abs(history.posterior - exact) <= bound), (history.posterior, exact, bound)


def test_same_history_for_threads_and_for_per_sample_or_batch_distances():
    one = combabc.run(problem(), l1_options(accepted_per_wave=300))
    same_history(one, combabc.run(problem(), l1_options(accepted_per_wave=300), threads=2))
    calls = []

    def counted(outputs, observed):
        calls.append(outputs.shape)
        return l1_batch(outputs, observed)

    batch = combabc.run(problem(counted, batched, batch=True), l1_options(accepted_per_wave=300),
                        threads=2)
    same_history(one, batch)
    assert all(len(shape) == 2 and shape[1] == 3 for shape in calls)
    assert len(calls) < one.summary["simulations"] / 5  # really batched
    # A batch simulator with a per-sample distance, and the other way round.
    same_history(one, combabc.run(problem(l1, batched, batch=True, distance_batch=False),
                                  l1_options(accepted_per_wave=300)))
    same_history(one, combabc.run(problem(l1_batch, distance_batch=True),
                                  l1_options(accepted_per_wave=300), threads=2))


@pytest.mark.parametrize("batch", [False, True])
def test_named_components_each_with_a_threshold_schedule(batch):
    def both_batch(outputs, observed):
        diff = np.abs(outputs - observed)
        return np.stack([diff.sum(axis=1), diff.max(axis=1)], axis=1)

    schedules = [combabc.ThresholdSchedule(kind="list", values=[8.0, 5.0, 3.0]),
                 combabc.ThresholdSchedule(kind="list", values=[3.0, 2.0, 1.0])]
    p = problem(both_batch if batch else l1_and_max, batched if batch else per_sample,
                batch=batch, components=["l1", "max"])
    history = combabc.run(p, options(accepted_per_wave=200, thresholds=schedules), threads=2)
    assert history.components == ["l1", "max"]
    last = history.waves[-1]
    diff = np.abs(last.bits @ W.T - OBSERVED)
    np.testing.assert_array_equal(last.distance, np.stack([diff.sum(1), diff.max(1)], axis=1))
    assert np.all(last.distance <= [3.0, 1.0])
    # The second component binds: some L1-accepted configurations fail it.
    assert np.any(np.max(np.abs(W @ np.array(c) - OBSERVED)) > 1.0
                  for c in itertools.product([0, 1], repeat=8)
                  if np.abs(W @ np.array(c) - OBSERVED).sum() <= 3.0)
    assert {"d_l1", "d_max"} <= set(history.particles().columns)
    # One schedule for two components is the engine's error.
    with pytest.raises(combabc.Error, match="schedules"):
        combabc.run(p, options(accepted_per_wave=50, thresholds=[3.0, 2.0, 1.0]))


def test_nan_distance_and_simulation_failed_fail_the_candidate():
    def partial(output, observed):
        if output[0] > 5.0:
            return float("nan")
        if output[1] > 5.0:
            raise combabc.SimulationFailed("output 1 too large")
        return l1(output, observed)

    history = combabc.run(problem(partial),
                          l1_options(accepted_per_wave=200, max_failure_fraction=1.0))
    reasons = {r for w in history.waves for r in w.failure_reason}
    assert reasons == {"distance component 0 is NaN", "output 1 too large"}
    for w in history.waves:
        assert np.all(w.output[:, 0] <= 5.0) and np.all(w.output[:, 1] <= 5.0)


def test_distance_sees_only_simulated_outputs():
    def sometimes_nan(bits):
        if bits[0] == 1 and bits[1] == 1:
            return np.full(3, np.nan)
        if bits[2] == 0 and bits[3] == 0:
            raise combabc.SimulationFailed("no solution")
        return per_sample(bits)

    def strict(outputs, observed):
        assert not np.isnan(outputs).any()
        assert not observed.flags.writeable
        return l1_batch(outputs, observed)

    history = combabc.run(problem(strict, sometimes_nan, distance_batch=True),
                          l1_options(accepted_per_wave=200, max_failure_fraction=1.0))
    reasons = {r for w in history.waves for r in w.failure_reason}
    assert "no solution" in reasons and any(r.startswith("output holds NaN") for r in reasons)


@pytest.mark.parametrize("threads", [1, 2])
@pytest.mark.parametrize("batch", [False, True])
def test_python_exception_in_the_distance_reaches_the_caller(threads, batch):
    count = [0]

    def failing(output, observed):
        count[0] += 1
        if count[0] > 3:
            raise ZeroDivisionError("boom from the distance")
        return l1_batch(output, observed) if batch else l1(output, observed)

    with pytest.raises(ZeroDivisionError, match="boom from the distance") as raised:
        combabc.run(problem(failing, batched if batch else per_sample, batch=batch),
                    l1_options(accepted_per_wave=300), threads=threads)
    assert any("wave" in note and "distance" in note
               for note in getattr(raised.value, "__notes__", []))


@pytest.mark.parametrize("batch", [False, True])
def test_wrong_distance_shape_is_a_value_error(batch):
    def wrong(output, observed):
        return np.zeros((len(output), 2)) if batch else np.zeros(2)

    expected = r"distance returned an array of shape \(\d+, 2\), expected \(\d+,\)" if batch \
        else r"distance returned an array of shape \(2,\), expected \(\)"
    with pytest.raises(ValueError, match=expected):
        combabc.run(problem(wrong, batched if batch else per_sample, batch=batch),
                    l1_options(accepted_per_wave=50))
    with pytest.raises(ValueError, match=r"shape \(\), expected \(2,\)"):
        combabc.run(problem(l1, components=["a", "b"]),
                    options(accepted_per_wave=50, thresholds=[
                        combabc.ThresholdSchedule(kind="list", values=L1_THRESHOLDS)] * 2))
    with pytest.raises(TypeError, match="distance returned str, not an array of numbers"):
        combabc.run(problem(lambda output, observed: "far"), l1_options(accepted_per_wave=50))


def test_bad_distance_arguments():
    with pytest.raises(TypeError, match="distance must be callable"):
        problem(distance="l1")
    with pytest.raises(ValueError, match="components"):
        problem(components=[])
    with pytest.raises(combabc.Error, match="components name the values of a distance"):
        combabc.run(problem(None, components=["a"]), l1_options(accepted_per_wave=50))
