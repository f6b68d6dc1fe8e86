"""combabc.CustomPrior: a prior from a log density and a sampler (issue 23): its checks, as one
line naming the parameter, and its density."""

import math

import numpy as np
import pytest

import combabc
from combabc import _core


def normal(mean, sd):
    return lambda x: -0.5 * ((x[0] - mean) / sd) ** 2 - math.log(sd) - 0.5 * math.log(2 * math.pi)


def test_a_consistent_prior_passes_its_check_and_gives_its_density():
    prior = combabc.CustomPrior(log_density=normal(1.0, 2.0), sample=lambda rng: rng.normal(1.0, 2.0))
    prior.check(["k"])
    assert prior.dimension == 1
    assert prior.log_density([1.0]) == pytest.approx(-math.log(2.0) - 0.5 * math.log(2 * math.pi))
    assert repr(prior) == "CustomPrior(dimension=1)"


def test_a_joint_prior_of_two_reals():
    cov = np.array([[1.0, 0.6], [0.6, 1.0]])
    inv, logdet = np.linalg.inv(cov), math.log(np.linalg.det(cov))

    def log_density(x):
        return -0.5 * x @ inv @ x - 0.5 * logdet - math.log(2 * math.pi)

    prior = combabc.CustomPrior(log_density=log_density,
                              sample=lambda rng: rng.multivariate_normal([0.0, 0.0], cov),
                              dimension=2)
    prior.check(["a", "b"])
    # Ignoring the correlation is caught on the pair.
    wrong = combabc.CustomPrior(log_density=log_density, sample=lambda rng: rng.normal(size=2),
                              dimension=2)
    with pytest.raises(_core.Error, match=r"b: prior: the sampler and the log density disagree: "
                                          r"the draws' covariance with a"):
        wrong.check(["a", "b"])


def test_invalid_custom_priors_are_refused_in_one_line():
    with pytest.raises(TypeError, match="CustomPrior: log_density must be callable, not int"):
        combabc.CustomPrior(log_density=3, sample=lambda rng: 0.0)
    with pytest.raises(ValueError, match="dimension = 0; must be >= 1"):
        combabc.CustomPrior(log_density=normal(0, 1), sample=lambda rng: 0.0, dimension=0)
    # The wrong shape, a density that is not finite, a sampler outside the bounds, a sampler that
    # disagrees with the density: each names the parameter, before any simulation.
    shape = combabc.CustomPrior(log_density=normal(0, 1), sample=lambda rng: rng.normal(size=3))
    with pytest.raises(_core.Error, match=r"sampler returned an array of shape \(3,\)"):
        shape.check(["k"])
    nan = combabc.CustomPrior(log_density=lambda x: float("nan"), sample=lambda rng: rng.normal())
    with pytest.raises(_core.Error, match="k: prior: the log density is nan"):
        nan.check(["k"])
    bounded = combabc.CustomPrior(log_density=normal(0, 1), sample=lambda rng: rng.normal())
    with pytest.raises(_core.Error, match=r"k: prior: the sampler drew .*outside the support"):
        bounded.check(["k"], low=[-1.0], high=[1.0])
    shifted = combabc.CustomPrior(log_density=normal(0, 1), sample=lambda rng: rng.normal(0.5, 1))
    with pytest.raises(_core.Error, match="k: prior: the sampler and the log density disagree"):
        shifted.check(["k"])
    for error in (shape, nan, bounded, shifted):
        try:
            error.check(["k"], low=[-1.0], high=[1.0])
        except _core.Error as e:
            assert "\n" not in str(e)


@pytest.mark.parametrize("bad", ["x", "0.5", {}, 1j, np.complex128(0.5), object()],
                         ids=["str", "digits", "dict", "complex", "numpy-complex", "object"])
def test_callables_returning_no_real_number_are_a_type_error_not_a_crash(bad):
    # These killed Python with SIGSEGV (issue 35, E8), or (complex, a string of digits) were
    # silently cast to a number; now the one-line error of the check names the prior and TypeError.
    sampler = combabc.CustomPrior(log_density=normal(0, 1), sample=lambda rng: bad)
    with pytest.raises(_core.Error, match="CustomPrior: TypeError: the sampler returned"):
        sampler.check(["k"])
    pair = combabc.CustomPrior(log_density=lambda x: 0.0, sample=lambda rng: [bad, bad],
                               dimension=2)
    with pytest.raises(_core.Error, match="CustomPrior: TypeError: the sampler returned"):
        pair.check(["a", "b"])
    density = combabc.CustomPrior(log_density=lambda x: bad, sample=lambda rng: rng.normal())
    with pytest.raises(_core.Error, match="CustomPrior: TypeError: the log density returned"):
        density.check(["k"])
