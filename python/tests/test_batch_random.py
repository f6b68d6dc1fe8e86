"""rng=True with a batched simulator: one combabc.BatchRandom per call, whose draws are vectorised
across the batch's candidates while each candidate's come from its own random stream, so that they
do not depend on the batch size or the threads."""

import numpy as np
import pytest

import combabc
from test_smc import OBSERVED, PRIOR, W, same_history

DRAWS = 3 + 2 + 2 + 1  # normal(size=3), uniform(size=2), integers(size=2), random()


def noisy_batch(bits, rng, calls):
    calls.append(len(rng))
    noise = rng.normal(0.0, 0.5, size=3)
    extra = np.column_stack([rng.uniform(-1.0, 2.0, size=2), rng.integers(3, 9, size=2),
                             rng.random()])
    return np.column_stack([bits @ W.T + noise, noise, extra])


def first_three(output, observed):
    return float(np.linalg.norm(output[:3] - observed[:3]))


def noisy_problem(calls):
    space = combabc.BinarySpace(dimension=8, prior_one=PRIOR)
    observed = np.concatenate([OBSERVED, np.zeros(DRAWS)])  # the draws, after the model's
    return combabc.Problem(space, lambda bits, rng: noisy_batch(bits, rng, calls), observed,
                           batch=True, rng=True, distance=first_three, distance_batch=False)


def noisy_options(batch_size, threads=1, **fields):
    return combabc.make_options(num_waves=2, accepted_per_wave=200, seed=11, threads=threads,
                                thresholds=[6.0, 4.0], batch_size=batch_size, **fields)


def run(batch_size, threads=1):
    calls = []
    return combabc.run(noisy_problem(calls), noisy_options(batch_size, threads)), calls


def test_a_batch_of_one_and_of_64_give_each_candidate_the_same_draws():
    one, calls_one = run(batch_size=1)
    many, calls_many = run(batch_size=64, threads=2)
    assert set(calls_one) == {1} and max(calls_many) > 1
    same_history(one, many)  # outputs (the draws) and distances, candidate by candidate
    draws = one.waves[-1].output[:, 3:]
    normal, uniform, integers, unit = draws[:, :3], draws[:, 3:5], draws[:, 5:7], draws[:, 7]
    assert len(np.unique(normal[:, 0])) == len(normal)  # every candidate its own numbers
    assert np.all((-1.0 <= uniform) & (uniform < 2.0)) and np.all((0.0 <= unit) & (unit < 1.0))
    assert set(np.unique(integers)) <= set(range(3, 9)) and len(np.unique(integers)) == 6


def test_the_draws_have_their_distributions_and_shapes():
    seen = {}

    def simulate(bits, rng):
        if not seen:  # the first call
            n = len(rng)
            seen["n"] = n
            seen["shapes"] = [rng.random().shape, rng.normal(size=np.int64(4)).shape,
                              rng.uniform(size=(2, 3)).shape, rng.integers(5, size=0).shape]
            seen["normal"] = rng.normal(np.float32(1.0), np.int64(2), size=2000)
            seen["standard"] = rng.standard_normal(size=2000)
            seen["integers"] = rng.integers(np.int64(4), size=2000)
            loc = np.arange(n, dtype=np.float64)[:, None]  # one mean per candidate
            seen["by_row"] = rng.normal(loc, 0.0, size=2) - loc
            seen["repr"] = repr(rng)
            seen["generators"] = [type(g).__name__ for g in rng]
            with pytest.raises(ValueError, match="scale < 0"):
                rng.normal(0.0, -1.0)
            with pytest.raises(ValueError, match="low >= high"):
                rng.integers(3, 3)
            with pytest.raises(IndexError):
                rng[n]
        return np.zeros((len(bits), 1))

    space = combabc.BinarySpace(dimension=2)
    problem = combabc.Problem(space, simulate, [0.0], batch=True, rng=True)
    combabc.run(problem, combabc.make_options(num_waves=1, accepted_per_wave=64, seed=2,
                                              thresholds=[1.0], batch_size=64))
    n = seen["n"]
    assert n > 1  # a range of the batch of 64 (the engine splits a batch among its workers)
    assert seen["shapes"] == [(n,), (n, 4), (n, 2, 3), (n, 0)]
    normal = seen["normal"]
    assert normal.shape == (n, 2000)
    assert abs(normal.mean() - 1.0) < 0.03 and abs(normal.std() - 2.0) < 0.03
    assert abs(seen["standard"].mean()) < 0.02 and abs(seen["standard"].std() - 1.0) < 0.02
    counts = np.bincount(seen["integers"].ravel(), minlength=4)
    assert len(counts) == 4 and np.all(np.abs(counts / counts.sum() - 0.25) < 0.01)
    np.testing.assert_array_equal(seen["by_row"], np.zeros((n, 2)))
    assert seen["repr"] == f"<combabc.BatchRandom: {n} candidates>"
    assert seen["generators"] == ["Generator"] * n


def test_a_resumed_run_draws_what_the_uninterrupted_run_drew(tmp_path):
    whole, _ = run(batch_size=32)
    budget = whole.waves[0].candidates + whole.waves[1].candidates // 2
    stopped = combabc.run(noisy_problem([]), noisy_options(32, max_simulations=budget),
                          output_directory=tmp_path)
    assert [w.complete for w in stopped.waves] == [True, False]
    resumed = combabc.resume(stopped, noisy_problem([]), noisy_options(32),
                             max_simulations=10 * budget, threads=2)
    same_history(whole, resumed)
