"""Runs of a Problem with joint priors (Problem(priors=...): a CustomPrior from Python, a
MultivariateNormalPrior) against the exact ABC posterior, their checks before any simulation, and
the population size per wave and threshold schedules of issue 23 (accepted_by_wave, the
acceptance and ess kinds, weighted quantiles) from Python, with the resume fingerprint over them."""

import math

import numpy as np
import pytest

import combabc
from test_smc import options, problem

SIGMA = 0.5  # y = mu + N(0, SIGMA^2), observed 1.0
OBSERVED = [1.0]


def standard_normal_density(x):
    return -0.5 * float(x[0]) ** 2 - 0.5 * math.log(2 * math.pi)


def noisy(bits, reals, rng):
    return reals[:, :1] + SIGMA * rng.normal(size=1)  # batched: rng is a BatchRandom


class Counted:
    """A per-sample simulator that counts its calls."""

    def __init__(self):
        self.calls = 0

    def __call__(self, bits, reals, rng):
        self.calls += 1
        return np.array([reals[0] + SIGMA * rng.standard_normal()])


def mu_problem(prior, simulator=noisy, batch=True, low=None, high=None):
    reals = [combabc.ContinuousParameter("mu", kind="joint", low=low, high=high)]
    return combabc.Problem(combabc.BinarySpace(dimension=0), simulator, OBSERVED, reals=reals,
                           batch=batch, rng=True, priors={"mu": prior})


def exact_abc_moments(eps):
    """Mean and sd of mu ~ N(0, 1) given |mu + N(0, SIGMA^2) - 1| <= eps, by quadrature."""
    mu = np.linspace(-6.0, 6.0, 24001)
    cdf = np.vectorize(lambda z: 0.5 * (1.0 + math.erf(z / math.sqrt(2.0))))
    accept = cdf((OBSERVED[0] + eps - mu) / SIGMA) - cdf((OBSERVED[0] - eps - mu) / SIGMA)
    p = np.exp(-0.5 * mu ** 2) * accept
    p /= p.sum()
    mean = float(p @ mu)
    return mean, math.sqrt(float(p @ (mu - mean) ** 2))


def weighted_moments(wave, column=0):
    w = wave.weight / wave.weight.sum()
    x = wave.reals[:, column]
    mean = float(w @ x)
    return mean, math.sqrt(float(w @ (x - mean) ** 2)), 1.0 / float(w @ w)


def test_a_custom_prior_from_python_gives_the_exact_abc_posterior():
    prior = combabc.CustomPrior(log_density=standard_normal_density,
                                sample=lambda rng: rng.standard_normal())
    thresholds = [2.0, 0.6, 0.2]
    history = combabc.run(mu_problem(prior), combabc.make_options(
        num_waves=3, accepted_per_wave=800, seed=3, thresholds=thresholds))
    mean, sd, ess = weighted_moments(history.waves[-1])
    exact_mean, exact_sd = exact_abc_moments(thresholds[-1])
    assert abs(mean - exact_mean) < 4.0 * exact_sd / math.sqrt(ess)
    assert abs(sd - exact_sd) < 4.0 * exact_sd / math.sqrt(2.0 * ess)
    assert history.real_priors[0]["kind"] == "joint"


def test_a_custom_prior_run_is_the_same_for_any_thread_count():
    prior = combabc.CustomPrior(log_density=standard_normal_density,
                                sample=lambda rng: rng.standard_normal())

    def run(threads):
        return combabc.run(mu_problem(prior, Counted(), batch=False), combabc.make_options(
            num_waves=2, accepted_per_wave=100, seed=9, threads=threads, thresholds=[1.5, 0.5]))

    one, two = run(1), run(2)
    np.testing.assert_array_equal(one.waves[-1].reals, two.waves[-1].reals)
    np.testing.assert_array_equal(one.waves[-1].weight, two.waves[-1].weight)


def test_a_multivariate_normal_prior_keeps_its_correlation():
    # y observes a alone; b follows through the prior's correlation: E[b | a] = 0.8 a.
    prior = combabc.MultivariateNormalPrior([0.0, 0.0], [[1.0, 0.8], [0.8, 1.0]])
    assert prior.dimension == 2
    assert repr(prior) == ("MultivariateNormalPrior(mean=[0.0, 0.0], "
                           "covariance=[[1.0, 0.8], [0.8, 1.0]])")
    reals = [combabc.ContinuousParameter(n, kind="joint") for n in ("a", "b")]
    p = combabc.Problem(combabc.BinarySpace(dimension=0), noisy, OBSERVED, reals=reals,
                        batch=True, rng=True, priors={("a", "b"): prior})
    history = combabc.run(p, combabc.make_options(num_waves=2, accepted_per_wave=600, seed=4,
                                                  thresholds=[2.0, 0.3]))
    a, _, ess = weighted_moments(history.waves[-1], 0)
    b, _, _ = weighted_moments(history.waves[-1], 1)
    exact_a, _ = exact_abc_moments(0.3)
    assert abs(a - exact_a) < 4.0 / math.sqrt(ess)
    assert abs(b - 0.8 * a) < 4.0 / math.sqrt(ess)
    with pytest.raises(ValueError, match="covariance must be a 2 x 2 matrix"):
        combabc.MultivariateNormalPrior([0.0, 0.0], [1.0, 0.0])


def test_a_prior_whose_sampler_and_density_disagree_fails_before_any_simulation():
    simulator = Counted()
    shifted = combabc.CustomPrior(log_density=standard_normal_density,
                                  sample=lambda rng: rng.normal(0.5, 1.0))
    with pytest.raises(combabc.Error, match="mu.*the sampler and the log density disagree") as e:
        combabc.run(mu_problem(shifted, simulator, batch=False))
    assert "\n" not in str(e.value) and simulator.calls == 0
    # A sampler that leaves the declared bounds, as one line naming the parameter.
    normal = combabc.CustomPrior(log_density=standard_normal_density,
                                 sample=lambda rng: rng.standard_normal())
    with pytest.raises(combabc.Error, match=r"mu.*outside the support") as e:
        combabc.run(mu_problem(normal, simulator, batch=False, low=-1.0, high=1.0))
    assert "\n" not in str(e.value) and simulator.calls == 0


def scaled_normal(scale):
    return combabc.CustomPrior(
        log_density=lambda x: standard_normal_density(x / scale) - math.log(scale),
        sample=lambda rng: scale * rng.standard_normal())


def test_a_custom_prior_run_resumes_with_its_prior_and_refuses_another(tmp_path):
    def options(**fields):
        return combabc.make_options(num_waves=2, accepted_per_wave=200, seed=6,
                                    thresholds=[1.5, 0.5], **fields)

    whole = combabc.run(mu_problem(scaled_normal(1.0)), options())
    stopped = combabc.run(mu_problem(scaled_normal(1.0)), options(max_simulations=300),
                          output_directory=tmp_path)
    assert stopped.termination == "budget_exhausted"
    # The fingerprint holds the joint real's moments from the prior's draws.
    with pytest.raises(combabc.Error, match=r"the problem \(space, reals"):
        combabc.resume(stopped, mu_problem(scaled_normal(1.5)), options(),
                       max_simulations=10 ** 6)
    resumed = combabc.resume(stopped, mu_problem(scaled_normal(1.0)), options(),
                             max_simulations=10 ** 6)
    np.testing.assert_array_equal(resumed.waves[-1].reals, whole.waves[-1].reals)


class TiredSampler:
    """A standard normal sampler that raises LookupError after `calls` draws."""

    def __init__(self, calls):
        self.calls, self.left = calls, calls

    def __call__(self, rng):
        self.left -= 1
        if self.left < 0:
            raise LookupError("the sampler is tired")
        return rng.standard_normal()


def test_the_priors_own_exception_reaches_the_caller_as_itself():
    # 4000 draws for the check, then wave 0's candidates: it raises in a worker thread.
    sampler = TiredSampler(4100)
    prior = combabc.CustomPrior(log_density=standard_normal_density, sample=sampler)
    for _ in range(2):  # a second run of the same prior raises its own error again
        sampler.left = sampler.calls
        with pytest.raises(LookupError, match="the sampler is tired") as e:
            combabc.run(mu_problem(prior), combabc.make_options(
                num_waves=2, accepted_per_wave=500, seed=3, threads=2, thresholds=[1.5, 0.5]))
        assert "CustomPrior: sample raised LookupError" in e.value.__notes__[0]
    # During the check it is the check's one-line error.
    sampler.left = 10
    with pytest.raises(combabc.Error, match="CustomPrior: sample raised LookupError"):
        combabc.run(mu_problem(prior))


def test_bad_priors_are_refused_naming_what_is_wrong():
    with pytest.raises(TypeError, match="CustomPrior: sample must be callable, not str"):
        combabc.CustomPrior(log_density=standard_normal_density, sample="normal")
    with pytest.raises(TypeError, match=r"priors\['mu'\]: expected a CustomPrior or "
                                        r"MultivariateNormalPrior, not int"):
        mu_problem(3)
    with pytest.raises(TypeError, match="priors: expected a mapping"):
        combabc.Problem(combabc.BinarySpace(dimension=0), noisy, OBSERVED,
                        priors=[combabc.MultivariateNormalPrior([0.0], [[1.0]])])
    normal = combabc.MultivariateNormalPrior([0.0], [[1.0]])
    # A real under a joint prior is declared kind="joint"; a joint real needs its prior.
    own = [combabc.ContinuousParameter("mu", kind="normal", mean=0.0, sd=1.0)]
    with pytest.raises(combabc.Error, match="'mu' has a normal prior of its own"):
        combabc.run(combabc.Problem(combabc.BinarySpace(dimension=0), noisy, OBSERVED, reals=own,
                                    batch=True, rng=True, priors={"mu": normal}))
    bare = [combabc.ContinuousParameter("mu", kind="joint")]
    with pytest.raises(combabc.Error, match="mu.*no joint prior covers it"):
        combabc.run(combabc.Problem(combabc.BinarySpace(dimension=0), noisy, OBSERVED,
                                    reals=bare, batch=True, rng=True))
    with pytest.raises(combabc.Error, match="mu.*low"):
        combabc.ContinuousParameter("mu", kind="joint", low=2.0, high=1.0)
    with pytest.raises(combabc.Error, match="not used by kind"):
        combabc.ContinuousParameter("mu", kind="joint", mean=0.0)
    assert repr(bare[0]) == "ContinuousParameter('mu', kind='joint', low=-inf, high=inf)"


def test_the_population_size_per_wave():
    history = combabc.run(problem(), options(accepted_per_wave=np.array([300, 150, 80])))
    assert [len(w.index) for w in history.waves] == [300, 150, 80]
    assert list(options(accepted_per_wave=[300, 150, 80]).accepted_by_wave) == [300, 150, 80]
    with pytest.raises(combabc.Error, match="accepted_by_wave has 2"):
        combabc.run(problem(), options(accepted_per_wave=[300, 150]))


@pytest.mark.parametrize("schedule", [
    combabc.ThresholdSchedule(kind="acceptance", acceptance_rate=0.3, target=2.5),
    combabc.ThresholdSchedule(kind="ess", ess_fraction=0.6, target=2.5),
    combabc.ThresholdSchedule(kind="quantile", quantile=0.5, weighted=True, target=2.5)])
def test_adaptive_threshold_schedules(schedule):
    history = combabc.run(problem(), options(accepted_per_wave=200, num_waves=6,
                                             thresholds=[schedule]))
    eps = [float(w.thresholds[0]) for w in history.waves]
    assert eps[0] == math.inf and all(a >= b for a, b in zip(eps, eps[1:]))
    assert len(eps) >= 2 and math.isfinite(eps[1])


def test_threshold_schedule_keywords_of_other_kinds_are_refused():
    s = combabc.ThresholdSchedule(kind="ess", ess_fraction=0.25)
    assert (s.kind, s.ess_fraction, s.weighted) == ("ess", 0.25, False)
    assert combabc.ThresholdSchedule(kind="acceptance", acceptance_rate=0.2).acceptance_rate == 0.2
    with pytest.raises(ValueError, match='weighted is only used by kind = "quantile", not "ess"'):
        combabc.ThresholdSchedule(kind="ess", weighted=True)
    with pytest.raises(ValueError, match="acceptance_rate is only used by kind = \"acceptance\""):
        combabc.ThresholdSchedule(acceptance_rate=0.2)
    with pytest.raises(ValueError, match="ess_fraction is only used by kind = \"ess\""):
        combabc.ThresholdSchedule(kind="list", values=[1.0], ess_fraction=0.5)


@pytest.mark.parametrize("changed", [
    dict(accepted_per_wave=[200, 200, 100]),
    dict(thresholds=[combabc.ThresholdSchedule(kind="quantile", weighted=True, target=2.5)]),
    dict(thresholds=[combabc.ThresholdSchedule(kind="ess", ess_fraction=0.4, target=2.5)])])
def test_resume_refuses_changed_new_options(tmp_path, changed):
    started = dict(accepted_per_wave=[200, 200, 200],
                   thresholds=[combabc.ThresholdSchedule(kind="ess", ess_fraction=0.5,
                                                         target=2.5)])
    stopped = combabc.run(problem(), options(max_simulations=300, **started),
                          output_directory=tmp_path)
    assert stopped.termination == "budget_exhausted"
    with pytest.raises(combabc.Error, match="the options differ from the run's"):
        combabc.resume(stopped, problem(), options(**{**started, **changed}),
                       max_simulations=10 ** 6)
    resumed = combabc.resume(stopped, problem(), options(**started), max_simulations=10 ** 6)
    assert [len(w.index) for w in resumed.waves] == [200, 200, 200]


def test_a_sampler_returning_a_string_during_the_run_raises_type_error():
    # After the check's draws, wave 0's candidates get "x": the TypeError reaches the caller as
    # itself (issue 35, E8: it was SIGSEGV).
    calls = [0]

    def sample(rng):
        calls[0] += 1
        return rng.standard_normal() if calls[0] <= 4000 else "x"

    prior = combabc.CustomPrior(log_density=standard_normal_density, sample=sample)
    with pytest.raises(TypeError, match="the sampler returned str"):
        combabc.run(mu_problem(prior), combabc.make_options(
            num_waves=2, accepted_per_wave=200, seed=3, threads=2, thresholds=[1.5, 0.5]))
