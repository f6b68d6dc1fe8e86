"""The proposal kernels and tempering from Python (SmcOptions.proposal, SmcOptions.tempering): each
choice still recovers the exact enumerated posterior, changes the run, and keeps it the same for
any thread count; bad values raise the engine's messages."""

import numpy as np
import pytest

import combabc
from test_smc import THRESHOLDS, exact_posterior, options, problem, same_history

# (kernel, tempering): the untempered paper kernel, the logistic conditionals, each with a
# tempering form, and the joint ancestor kernel, so that every binding reaches the engine.
CHOICES = {
    "independent": (combabc.ProposalOptions(), combabc.TemperingSchedule()),
    "logistic": (combabc.ProposalOptions(kind="logistic"), combabc.TemperingSchedule()),
    "independent-linear": (combabc.ProposalOptions(),
                           combabc.TemperingSchedule(kind="linear", phi0=0.5)),
    "logistic-mixture": (
        combabc.ProposalOptions(kind="logistic",
                                logistic=combabc.LogisticKernelOptions(max_predecessors=3)),
        combabc.TemperingSchedule(kind="list", form="mixture", values=[0.4, 0.2])),
    "ancestor": (combabc.ProposalOptions(kind="ancestor"), combabc.TemperingSchedule()),
}


def run_choice(name, threads=1, **fields):
    proposal, tempering = CHOICES[name]
    return combabc.run(problem(), options(proposal=proposal, tempering=tempering, **fields),
                       threads=threads)


@pytest.mark.parametrize("name", sorted(CHOICES))
def test_every_kernel_and_tempering_recovers_the_exact_posterior(name):
    exact = exact_posterior(THRESHOLDS[-1])
    history = run_choice(name, accepted_per_wave=4000)
    last = history.waves[-1]
    assert last.accepted == 4000 and np.all(last.distance[:, 0] <= THRESHOLDS[-1])
    # The bound of test_smc.py's exact test: 4.5 standard errors at the wave's effective sample
    # size plus 0.005 for the self-normalised estimator's bias (the unweighted marginals, which
    # ignore the kernel's density, are off by 0.05 to 0.07 for three of the four choices).
    bound = 4.5 * np.sqrt(exact * (1.0 - exact) / last.ess) + 0.005
    assert np.all(np.abs(history.posterior - exact) <= bound), (history.posterior, exact, bound)


def test_tempering_phi_is_recorded_as_the_schedule_gives_it():
    linear = run_choice("independent-linear", accepted_per_wave=200)
    schedule = CHOICES["independent-linear"][1]
    assert [w.phi for w in linear.waves[1:]] == [schedule.phi(t, 3) for t in (1, 2)]
    assert linear.waves[1].phi == 0.5 and linear.waves[2].phi == 0.0
    listed = run_choice("logistic-mixture", accepted_per_wave=200)
    assert [w.phi for w in listed.waves[1:]] == [0.4, 0.2]


def test_kernels_and_tempering_change_the_run_and_keep_it_thread_independent():
    histories = {name: run_choice(name, accepted_per_wave=300) for name in CHOICES}
    # Wave 0 proposes from the prior whatever the choice: the same particles.
    first = [h.waves[0].bits for h in histories.values()]
    assert all(np.array_equal(first[0], b) for b in first)
    # Later waves differ pairwise: each choice reached the engine.
    last = {name: h.waves[-1].bits for name, h in histories.items()}
    names = sorted(last)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            assert not np.array_equal(last[a], last[b]), (a, b)
    for name in ("logistic", "logistic-mixture"):
        same_history(histories[name], run_choice(name, threads=2, accepted_per_wave=300))


def test_continuous_kernels_reach_the_engine():
    def simulate(bits, reals):
        return np.array([bits.sum() + reals[0]])

    def run(continuous, threads=1, kind="independent"):
        space = combabc.BinarySpace(dimension=3)
        reals = [combabc.ContinuousParameter("offset", kind="uniform", low=-1.0, high=1.0)]
        p = combabc.Problem(space, simulate, [1.5], reals=reals)
        proposal = combabc.ProposalOptions(kind=kind, continuous=continuous, scale=1.0)
        return combabc.run(p, combabc.make_options(num_waves=3, accepted_per_wave=200, seed=3,
                                                   thresholds=[1.0, 0.5, 0.25],
                                                   proposal=proposal), threads=threads)

    normal, olcm, ancestor = run("normal"), run("olcm"), run("normal", kind="ancestor")
    assert not np.array_equal(normal.waves[-1].reals, olcm.waves[-1].reals)
    assert not np.array_equal(normal.waves[-1].reals, ancestor.waves[-1].reals)
    same_history(olcm, run("olcm", threads=2))
    same_history(ancestor, run("normal", threads=2, kind="ancestor"))
    for h in (normal, olcm, ancestor):
        last = h.waves[-1]
        assert np.all(np.abs(last.bits.sum(axis=1) + last.reals[:, 0] - 1.5) <= 0.25)


def test_fields_read_and_write():
    proposal = combabc.ProposalOptions(kind="logistic", continuous="olcm", scale=1.5,
                                       logistic=combabc.LogisticKernelOptions(ridge=0.01))
    assert (proposal.kind, proposal.continuous, proposal.scale) == ("logistic", "olcm", 1.5)
    assert proposal.logistic.ridge == 0.01
    defaults = combabc.SmcOptions()
    # "auto": the ancestor kernel for a mixed space, independent otherwise (resolved at the run).
    assert (defaults.proposal.kind, defaults.proposal.continuous) == ("auto", "normal")
    assert (defaults.tempering.kind, defaults.tempering.form) == ("none", "geometric")
    # Nested fields are written in place, as in C++.
    defaults.proposal.kind = "logistic"
    defaults.proposal.logistic.max_predecessors = 2
    defaults.tempering.values = [0.5]
    assert defaults.proposal.kind == "logistic"
    assert defaults.proposal.logistic.max_predecessors == 2
    assert defaults.tempering.values == [0.5]
    assert combabc.LogisticKernelOptions().clip == 1e-4  # the engine's defaults


def test_bad_values_raise_the_engines_messages():
    with pytest.raises(combabc.Error,
                       match=r'expected one of "auto", "independent", "logistic", "ancestor"'):
        combabc.ProposalOptions(kind="logistc")
    with pytest.raises(combabc.Error, match=r'expected one of "normal", "olcm"'):
        combabc.ProposalOptions(continuous="gaussian")
    with pytest.raises(combabc.Error, match=r'expected one of "none", "linear", "list"'):
        combabc.TemperingSchedule(kind="geometric")
    with pytest.raises(combabc.Error, match=r'expected one of "geometric", "mixture"'):
        combabc.TemperingSchedule(form="linear")
    with pytest.raises(combabc.Error) as raised:
        combabc.LogisticKernelOptions(clip=0.7)
    assert str(raised.value) == "config error: LogisticKernelOptions::clip = 0.700000; must be " \
                                "in (0, 0.5)"
    with pytest.raises(combabc.Error, match=r"ProposalOptions::scale = -1.000000; must be"):
        combabc.ProposalOptions(scale=-1.0)
    with pytest.raises(combabc.Error, match=r"TemperingSchedule.phi0 = 2.000000; must be in"):
        combabc.TemperingSchedule(kind="linear", phi0=2.0)
    with pytest.raises(combabc.Error, match=r"values\[1\] = -0.100000; must be in \[0, 1\]"):
        combabc.TemperingSchedule(kind="list", values=[0.5, -0.1])


@pytest.mark.parametrize("change", ["clip", "phi0", "short list"])
def test_fields_set_later_are_checked_when_the_run_starts(change):
    opts = options(accepted_per_wave=50)
    if change == "clip":
        opts.proposal.logistic.clip = 0.6
    elif change == "phi0":
        opts.tempering.phi0 = -0.5
    else:
        opts.tempering = combabc.TemperingSchedule(kind="list", values=[0.5])  # needs 2
    ok, why = opts.is_valid()
    assert not ok and why.startswith("SmcOptions::")
    with pytest.raises(combabc.Error) as raised:
        combabc.run(problem(), opts)
    assert str(raised.value) == "config error: " + why


def parity_run(kind):
    """The mode-loss problem of tests/e2e/mode_loss_test.cpp: three bits (prior P(1) = 0.2, 0.2,
    0.5) whose data accept the even-parity patterns; the logistic kernel cannot represent bit 3 =
    bit 1 xor bit 2 and loses 110 (mass 0.04) in wave 2."""
    space = combabc.BinarySpace(dimension=3, prior_one=[0.2, 0.2, 0.5])

    def simulate(bits):
        odd = bits.sum(axis=1) % 2
        return np.stack([1.0 - odd, odd], axis=1).astype(np.float64)

    problem = combabc.Problem(space, simulate, np.array([1.0, 0.0]), batch=True)
    return combabc.run(problem, combabc.make_options(
        num_waves=4, accepted_per_wave=300, seed=1, threads=1, thresholds=[0.5] * 4,
        estimator="importance", proposal=combabc.ProposalOptions(kind=kind)))


def test_a_lost_mode_is_a_python_warning():
    # Issue 35: the loss was in the history only (Wave.pattern_classes, summary.json), so a Python
    # user, who sees no progress line, was never told.
    with pytest.warns(combabc.ModeLossWarning, match=r"^wave 2 proposed pattern 110 \(mass "
                      r".*the posterior may have lost a mode$") as caught:
        history = parity_run("logistic")
    assert caught[0].filename == __file__  # stacklevel: the caller of combabc.run
    assert history.waves[1].mode_loss_warning == str(caught[0].message)
    assert any(c["flagged"] for c in history.waves[1].pattern_classes)


def test_a_run_that_keeps_its_modes_warns_of_nothing():
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error", combabc.ModeLossWarning)
        history = parity_run("independent")
    assert all(w.mode_loss_warning == "" for w in history.waves)
