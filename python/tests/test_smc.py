"""Runs with a simulator written in Python: the exact ABC posterior of an enumerated problem,
determinism across thread counts, and errors raised in Python reaching the caller."""

import itertools
import os
import warnings

import numpy as np
import pytest

import combabc

# A deterministic linear model y = W bits on d = 8 bits, observed at a truth: several
# configurations lie within the final threshold, so the exact posterior is spread out.
W = np.array([[3.0, 1.0, 2.0, 0.0, 1.0, 2.0, 1.0, 0.0],
              [0.0, 2.0, 1.0, 3.0, 1.0, 0.0, 2.0, 1.0],
              [1.0, 0.0, 1.0, 1.0, 2.0, 1.0, 0.0, 3.0]])
TRUTH = np.array([1, 0, 1, 1, 0, 0, 1, 0], dtype=np.uint8)
OBSERVED = W @ TRUTH
PRIOR = [0.3, 0.5, 0.6, 0.4, 0.5, 0.7, 0.5, 0.35]
THRESHOLDS = [6.0, 4.0, 2.5]


def per_sample(bits):
    return W @ bits


def batched(bits):
    return bits @ W.T


def problem(simulator=per_sample, batch=False):
    space = combabc.BinarySpace(dimension=8, prior_one=PRIOR)
    return combabc.Problem(space, simulator, OBSERVED, batch=batch)


def options(**fields):
    defaults = dict(num_waves=3, accepted_per_wave=1000, seed=11, threads=1,
                    thresholds=THRESHOLDS, estimator="importance")
    defaults.update(fields)
    return combabc.make_options(**defaults)


def exact_posterior(eps):
    """P(bit k = 1 | ||W theta - y|| <= eps) by enumerating all 2^8 configurations."""
    mass = np.zeros(8)
    total = 0.0
    prior = np.array(PRIOR)
    for config in itertools.product([0, 1], repeat=8):
        theta = np.array(config)
        if np.linalg.norm(W @ theta - OBSERVED) > eps:
            continue
        p = np.prod(np.where(theta == 1, prior, 1.0 - prior))
        total += p
        mass += p * theta
    return mass / total


def test_exact_posterior_recovered_through_python_simulator():
    exact = exact_posterior(THRESHOLDS[-1])
    # The test can fail: the posterior is neither the prior nor a point mass.
    assert np.max(np.abs(exact - PRIOR)) > 0.15
    assert np.sum((exact > 0.05) & (exact < 0.95)) >= 3
    history = combabc.run(problem(), options(accepted_per_wave=4000))
    last = history.waves[-1]
    assert last.accepted == 4000
    assert np.all(last.distance[:, 0] <= THRESHOLDS[-1])
    np.testing.assert_allclose(last.distance[:, 0],
                               np.linalg.norm(last.bits @ W.T - OBSERVED, axis=1))
    # Monte-Carlo bound: 4.5 standard errors at the wave's effective sample size (about 0.035),
    # plus a small allowance for the self-normalised estimator's bias. Tight enough to catch
    # ignored weights (the unweighted marginals are off by up to 0.05 here) or a wrong threshold
    # (the exact posterior at eps = 4 differs by up to 0.12).
    bound = 4.5 * np.sqrt(exact * (1.0 - exact) / last.ess) + 0.005
    assert np.all(np.abs(history.posterior - exact) <= bound), (history.posterior, exact, bound)


def same_history(a, b):
    assert len(a.waves) == len(b.waves)
    for wa, wb in zip(a.waves, b.waves):
        for key in ("index", "bits", "reals", "log_weight", "weight", "distance", "output",
                    "thresholds", "proposal", "marginals_importance", "failure_index"):
            np.testing.assert_array_equal(getattr(wa, key), getattr(wb, key), err_msg=key)
        assert (wa.candidates, wa.accepted, wa.ess) == (wb.candidates, wb.accepted, wb.ess)
    assert a.summary["simulations"] == b.summary["simulations"]


def test_same_history_for_one_and_two_threads():
    one = combabc.run(problem(), options(accepted_per_wave=300))
    two = combabc.run(problem(), options(accepted_per_wave=300), threads=2)
    same_history(one, two)
    other_seed = combabc.run(problem(), options(accepted_per_wave=300, seed=12))
    assert not np.array_equal(one.waves[-1].bits, other_seed.waves[-1].bits)


def test_pair_correlations_are_the_weighted_correlations_of_the_bits():
    history = combabc.run(problem(), options(accepted_per_wave=300))
    for w in history.waves:
        bits = w.bits.astype(np.float64)
        p = w.weight / w.weight.sum()
        centred = bits - p @ bits
        cov = centred.T @ (centred * p[:, None])
        varying = bits.min(axis=0) != bits.max(axis=0)  # a constant bit has no correlation: 0
        expected = np.zeros((8, 8))
        sd = np.sqrt(np.diag(cov)[varying])
        expected[np.ix_(varying, varying)] = cov[np.ix_(varying, varying)] / np.outer(sd, sd)
        np.testing.assert_allclose(w.pair_correlations, expected, rtol=0, atol=1e-12)
    last = history.waves[-1].pair_correlations
    assert np.any((np.abs(last) > 0.05) & (np.abs(last) < 1)), last  # not all trivial
    table = history.pair_correlations()
    assert len(table) == len(history.waves) * 28  # 8 bits: 28 pairs a wave
    assert table.iloc[0].tolist() == [1, 1, history.bit_names[0], 2, history.bit_names[1],
                                      history.waves[0].pair_correlations[0, 1]]


def test_batch_simulator_gives_the_per_sample_history():
    calls = []

    def counted(bits):
        calls.append(bits.shape)
        return batched(bits)

    single = combabc.run(problem(), options(accepted_per_wave=300))
    batch = combabc.run(problem(counted, batch=True), options(accepted_per_wave=300), threads=2)
    same_history(single, batch)
    assert all(len(shape) == 2 and shape[1] == 8 for shape in calls)
    assert len(calls) < single.summary["simulations"] / 5  # really batched


def test_continuous_parameters_reach_the_simulator():
    seen = []

    def simulate(bits, reals):
        seen.append(reals.copy())
        return np.array([bits.sum() + reals[0]])

    space = combabc.BinarySpace(dimension=3)
    reals = [combabc.ContinuousParameter("offset", kind="uniform", low=-1.0, high=1.0)]
    p = combabc.Problem(space, simulate, [1.5], reals=reals)
    history = combabc.run(p, combabc.make_options(num_waves=2, accepted_per_wave=50, seed=3,
                                                  thresholds=[1.0, 0.5]))
    assert history.real_names == ["offset"]
    last = history.waves[-1]
    np.testing.assert_allclose(last.distance[:, 0],
                               np.abs(last.bits.sum(axis=1) + last.reals[:, 0] - 1.5))
    assert all(-1.0 <= r[0] <= 1.0 for r in seen)
    assert "offset" in history.particles().columns


@pytest.mark.parametrize("batch", [False, True])
def test_a_continuous_only_space_matches_its_analytic_posterior(batch):
    # mu ~ N(0, 1), y = mu + N(0, 0.5^2) observed 1.0; a small final eps: the ABC posterior is
    # close to the exact N(0.8, 0.2) (variance 1 / (1 + 4)).
    def simulate(bits, reals, rng):
        assert bits.shape == ((len(reals), 0) if batch else (0,))
        if batch:
            return np.array([[r[0] + 0.5 * g.standard_normal()] for r, g in zip(reals, rng)])
        return np.array([reals[0] + 0.5 * rng.standard_normal()])

    space = combabc.BinarySpace(dimension=0)
    reals = [combabc.ContinuousParameter("mu", kind="normal", mean=0.0, sd=1.0)]
    p = combabc.Problem(space, simulate, [1.0], reals=reals, batch=batch, rng=True)
    history = combabc.run(p, combabc.make_options(num_waves=4, accepted_per_wave=1000, seed=5,
                                                  thresholds=[2.0, 1.0, 0.3, 0.05]))
    last = history.waves[-1]
    assert last.bits.shape == (1000, 0)
    w = last.weight / last.weight.sum()
    mean = float(w @ last.reals[:, 0])
    var = float(w @ (last.reals[:, 0] - mean) ** 2)
    ess = 1.0 / float(w @ w)
    assert abs(mean - 0.8) < 5.0 * np.sqrt(0.2 / ess) + 0.01
    assert abs(var - 0.2) < 5.0 * 0.2 * np.sqrt(2.0 / ess) + 0.01
    assert list(history.particles().columns[:4]) == ["wave", "index", "bits", "mu"]


@pytest.mark.parametrize("threads", [1, 2])
@pytest.mark.parametrize("batch", [False, True])
def test_python_exception_reaches_the_caller(threads, batch):
    count = [0]

    def failing(bits):
        count[0] += 1
        if count[0] > 3:
            raise ZeroDivisionError("boom from the simulator")
        return batched(bits) if batch else per_sample(bits)

    with pytest.raises(ZeroDivisionError, match="boom from the simulator") as raised:
        combabc.run(problem(failing, batch=batch), options(accepted_per_wave=300), threads=threads)
    # The engine's line (wave and candidate) comes along as a note.
    assert any("wave" in note for note in getattr(raised.value, "__notes__", []))


@pytest.mark.parametrize("batch", [False, True])
def test_wrong_output_shape_is_a_value_error(batch):
    def wrong(bits):
        return np.zeros((len(bits), 2)) if batch else np.zeros(2)

    expected = r"shape \(\d+, 2\), expected \(\d+, 3\)" if batch else r"shape \(2,\), expected \(3,\)"
    with pytest.raises(ValueError, match=expected):
        combabc.run(problem(wrong, batch=batch), options(accepted_per_wave=50))


def test_not_numbers_is_a_type_error_and_none_a_shape_error():
    with pytest.raises(TypeError, match="not an array of numbers"):
        combabc.run(problem(lambda bits: ["a", "b", "c"]), options(accepted_per_wave=50))
    with pytest.raises(ValueError, match=r"shape \(\), expected \(3,\)"):
        combabc.run(problem(lambda bits: None), options(accepted_per_wave=50))


def test_simulation_failed_rejects_one_candidate():
    def sometimes(bits):
        if bits[0] == 1 and bits[1] == 1:
            raise combabc.SimulationFailed("no solution for bits 0 and 1")
        return per_sample(bits)

    history = combabc.run(problem(sometimes),
                          options(accepted_per_wave=200, max_failure_fraction=1.0))
    failures = sum(len(w.failure_index) for w in history.waves)
    assert failures > 0 and history.summary["failures"] == failures
    assert all(r == "no solution for bits 0 and 1" for w in history.waves
               for r in w.failure_reason)
    for w in history.waves:
        assert not np.any((w.bits[:, 0] == 1) & (w.bits[:, 1] == 1))


def test_invalid_options_raise_the_engines_message():
    bad = options(num_waves=-1, thresholds=[])
    ok, why = bad.is_valid()
    assert not ok and "num_waves" in why
    with pytest.raises(combabc.Error) as raised:
        combabc.run(problem(), bad)
    assert str(raised.value) == "config error: " + why
    assert raised.value.exit_code == 78


def test_invalid_prior_raises():
    with pytest.raises(combabc.Error, match="config error: .*prior"):
        combabc.BinarySpace(dimension=3, prior_one=[0.5, 1.5, 0.5])
    with pytest.raises(combabc.Error, match="expected one of"):
        combabc.ContinuousParameter("x", kind="uniformm")


@pytest.mark.parametrize("arguments, message", [
    (dict(kind="uniform", mean=0.5), r"ContinuousParameter\('x'\)\.mean: not used by kind = "
                                      r'"uniform" \(it takes low and high\)'),
    (dict(kind="normal", low=0.0), r"ContinuousParameter\('x'\)\.low: not used by kind = "
                                    r'"normal" \(it takes mean and sd\)'),
    (dict(kind="lognormal", high=2.0), r"ContinuousParameter\('x'\)\.high: not used"),
    (dict(low=2.0, high=1.0), r"ContinuousParameter\('x'\): low = 2 >= high = 1"),
    (dict(low=1.0, high=1.0), r"ContinuousParameter\('x'\): low = 1 >= high = 1"),
    (dict(kind="normal", sd=0.0), r"ContinuousParameter\('x'\): sd = 0; must be > 0"),
    (dict(kind="truncated_normal", low=50.0, high=60.0),
     r"ContinuousParameter\('x'\): low = 50, high = 60; N\(mean = 0, sd = 1\) has mass 0"),
])
def test_a_continuous_parameter_refuses_what_its_prior_does_not_take(arguments, message):
    # At construction, with one line naming the parameter (config error, as a TOML file's).
    with pytest.raises(combabc.Error, match="^config error: " + message) as raised:
        combabc.ContinuousParameter("x", **arguments)
    assert "\n" not in str(raised.value)
    assert raised.value.exit_code == 78


def test_a_continuous_parameter_shows_its_prior():
    uniform = combabc.ContinuousParameter("k", low=-1.5, high=2)
    assert repr(uniform) == "ContinuousParameter('k', kind='uniform', low=-1.5, high=2.0)"
    assert (uniform.low, uniform.high) == (-1.5, 2.0)
    assert repr(combabc.ContinuousParameter("s", kind="lognormal", sd=0.5)) == \
        "ContinuousParameter('s', kind='lognormal', mean=0.0, sd=0.5)"
    truncated = combabc.ContinuousParameter("t", kind="truncated_normal", low=0, high=3, mean=1,
                                            sd=2)
    assert repr(truncated) == ("ContinuousParameter('t', kind='truncated_normal', low=0.0, "
                               "high=3.0, mean=1.0, sd=2.0)")
    assert truncated.kind == "truncated_normal" and truncated.name == "t"


def test_numpy_scalars_are_numbers_everywhere():
    # numpy.int64 is no Python int (numpy.float64 is a float): thresholds, counts, seeds and
    # priors given as NumPy scalars or arrays run as the same numbers given as Python's.
    numpy_options = combabc.make_options(
        num_waves=np.int64(3), accepted_per_wave=np.int32(300), seed=np.uint64(11),
        threads=np.int8(1), thresholds=np.array([6, 4, 3]), estimator="importance",
        max_simulations=np.int64(10**6), max_wall_time_s=np.float32(600),
        min_acceptance_rate=np.float32(0.0), batch_size=np.int64(64))
    assert [t.values for t in numpy_options.thresholds] == [[6.0, 4.0, 3.0]]
    for thresholds in ([np.int64(6), np.int64(4), np.int64(3)],
                       [np.float32(6), np.float64(4), 3]):
        assert combabc.make_options(thresholds=thresholds).thresholds[0].values == [6.0, 4.0, 3.0]
    space = combabc.BinarySpace(dimension=np.int64(8), prior_one=np.array(PRIOR),
                                default_prior_one=np.float64(0.5))
    numpy_run = combabc.run(combabc.Problem(space, per_sample, OBSERVED), numpy_options)
    python_run = combabc.run(problem(), options(accepted_per_wave=300, thresholds=[6, 4, 3],
                                                batch_size=64))
    same_history(numpy_run, python_run)
    assert combabc.BinarySpace(dimension=2, prior_one=[np.float32(0.25), np.int64(1)]) \
        .bit_prior_one == [0.25, 1.0]
    tied = combabc.BinarySpace(dimension=4, tied=[[np.int64(1), np.uint8(4)]])
    assert tied.num_free == combabc.BinarySpace(dimension=4, tied=[[1, 4]]).num_free == 3
    for not_a_bit in (True, np.bool_(True), np.float64(1.0)):  # numbers from 1, not bools or reals
        with pytest.raises(TypeError, match="tied holds bit names or numbers"):
            combabc.BinarySpace(dimension=4, tied=[[not_a_bit, 2]])
    real = combabc.ContinuousParameter("k", kind="normal", mean=np.int64(1), sd=np.float32(0.5))
    assert (real.mean, real.sd) == (1.0, 0.5)
    schedule = combabc.ThresholdSchedule(kind="quantile", quantile=np.float32(0.5),
                                         initial=np.int64(10), target=np.float64(1))
    assert (schedule.quantile, schedule.initial, schedule.target) == (0.5, 10.0, 1.0)
    assert combabc.ProposalOptions(scale=np.int64(2)).scale == 2.0
    assert combabc.TemperingSchedule(phi0=np.float32(0.5)).phi(np.int64(1), np.int64(3)) >= 0.0


def noisy(bits, rng):
    return W @ bits + rng.normal(0.0, 0.5, size=3)


def noisy_batch(bits, rng):
    return np.stack([W @ b + g.normal(0.0, 0.5, size=3) for b, g in zip(bits, rng)])


def test_stochastic_simulator_with_rng_is_reproducible_for_any_thread_count():
    def run(simulator=noisy, batch=False, threads=1, seed=11):
        space = combabc.BinarySpace(dimension=8, prior_one=PRIOR)
        noisy_problem = combabc.Problem(space, simulator, OBSERVED, batch=batch, rng=True)
        return combabc.run(noisy_problem, options(accepted_per_wave=300, seed=seed),
                           threads=threads)

    one = run()
    same_history(one, run(threads=2))
    same_history(one, run(noisy_batch, batch=True, threads=2))
    # The noise is there: distances are not those of the noise-free model.
    last = one.waves[-1]
    assert not np.allclose(last.distance[:, 0],
                           np.linalg.norm(last.bits @ W.T - OBSERVED, axis=1))
    assert not np.array_equal(last.distance, run(seed=12).waves[-1].distance)


@pytest.mark.parametrize("threads", [1, 2])
def test_ctrl_c_stops_a_python_run_with_keyboard_interrupt(threads):
    import os
    import signal
    calls = []

    def interrupted_once(bits):
        calls.append(1)
        if len(calls) == 200:
            os.kill(os.getpid(), signal.SIGINT)  # as Ctrl-C in the terminal
        return W @ bits

    with pytest.raises(KeyboardInterrupt):
        combabc.run(problem(interrupted_once), options(accepted_per_wave=3000), threads=threads)
    # Stopped soon after, not at the end of the run (which takes several thousand calls).
    assert len(calls) < 2000


def test_a_keyboard_interrupt_raised_in_the_simulator_says_how_to_resume(tmp_path):
    """Issue 35: Ctrl-C that Python delivers inside the simulator (KeyboardInterrupt raised
    there) is an interrupt like one seen between batches: KeyboardInterrupt with the note naming
    combabc.resume, not "simulator failed"; and the run resumes."""
    calls = []

    def interrupted_once(bits):
        calls.append(1)
        if len(calls) == 50:
            raise KeyboardInterrupt
        return W @ bits

    with pytest.raises(KeyboardInterrupt) as raised:
        combabc.run(problem(interrupted_once), options(accepted_per_wave=100),
                    output_directory=tmp_path)
    path = os.path.join(os.fspath(tmp_path), "history.sqlite")
    assert getattr(raised.value, "__notes__", []) == [
        f'combabc: interrupted; continue with combabc.resume("{path}", problem, options)']
    resumed = combabc.resume(path, problem(interrupted_once), options(accepted_per_wave=100))
    assert resumed.status == "finished"
    assert [w.complete for w in resumed.waves] == [True, True, True]


def test_a_budget_stopped_runs_posterior_is_its_last_complete_wave():
    whole = combabc.run(problem(), options(accepted_per_wave=300, batch_size=50))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a finished run's posterior warns nothing
        np.testing.assert_array_equal(whole.posterior, whole.waves[-1].marginals)
    assert whole.posterior_note == "" and whole.posterior_wave is whole.waves[-1]
    # Stopped halfway through wave 3: waves 1 and 2 complete, wave 3 kept, incomplete.
    first_two = sum(w.candidates for w in whole.waves[:2])
    budget = first_two + whole.waves[2].candidates // 2
    stopped = combabc.run(problem(), options(accepted_per_wave=300, batch_size=50,
                                             max_simulations=budget))
    assert stopped.termination == "budget_exhausted"
    assert [w.complete for w in stopped.waves] == [True, True, False]
    assert 0 < stopped.waves[2].accepted < 300
    assert stopped.posterior_wave is stopped.waves[1]
    assert stopped.wave() is stopped.waves[1]
    assert stopped.posterior_note == \
        "the numbers are wave 2's: wave 3 is incomplete (budget_exhausted)"
    with pytest.warns(UserWarning, match=r"wave 2's: wave 3 is incomplete \(budget_exhausted\)"):
        posterior = stopped.posterior
    np.testing.assert_array_equal(posterior, whole.waves[1].marginals)
    np.testing.assert_array_equal(stopped.curves(), stopped.waves[1].output)
    assert set(stopped.particles(wave=None)["wave"]) == {1, 2, 3}  # every wave, as recorded
    # No wave complete: the incomplete first wave answers, and says so.
    early = combabc.run(problem(), options(accepted_per_wave=300, batch_size=50,
                                           max_simulations=whole.waves[0].candidates // 2))
    assert [w.complete for w in early.waves] == [False]
    assert early.posterior_wave is early.waves[0]
    with pytest.warns(UserWarning, match="no complete wave"):
        np.testing.assert_array_equal(early.posterior, early.waves[0].marginals)
