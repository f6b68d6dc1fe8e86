"""NumPy's scalar types are numbers wherever the public Python API takes one (thresholds, options,
Problem and space arguments, History and plot arguments, BatchRandom), and what is not a threshold
is refused on one line. (test_smc.py checks that such a run equals the run with Python's
numbers.)"""

import numpy as np
import pytest

import combabc
from test_smc import OBSERVED, PRIOR, W, options, per_sample, problem, same_history


@pytest.mark.parametrize("thresholds", [
    [6, 4, 3], np.array([6, 4, 3]), [np.int64(6), np.float32(4), np.uint8(3)],
    [[6, 4, 3]], np.array([[6.0, 4.0, 3.0]]), [np.array([6, 4, 3])],
    [combabc.ThresholdSchedule(kind="list", values=np.array([6, 4, 3]))]])
def test_the_thresholds_field_takes_numbers_lists_or_schedules(thresholds):
    o = combabc.SmcOptions()
    o.thresholds = thresholds  # the field itself, as make_options sets it
    assert [(t.kind, t.values) for t in o.thresholds] == [("list", [6.0, 4.0, 3.0])]
    assert [t.values for t in combabc.make_options(thresholds=thresholds).thresholds] == \
        [[6.0, 4.0, 3.0]]


def test_two_components_by_lists_of_numpy_numbers():
    o = combabc.make_options(thresholds=[np.array([8, 5, 3]), [np.int64(3), 2.0, np.float32(1)]])
    assert [t.values for t in o.thresholds] == [[8.0, 5.0, 3.0], [3.0, 2.0, 1.0]]
    o = combabc.make_options(thresholds=[combabc.ThresholdSchedule(quantile=np.float32(0.5)),
                                         np.array([3, 2, 1])])
    assert [t.kind for t in o.thresholds] == ["quantile", "list"]


@pytest.mark.parametrize("thresholds, message", [
    (np.float64(5), "got float64"), (5, "got int"), ("6, 4", "got str"),
    ([True, 4], r"\[0\] is bool"), ([np.bool_(True), 4], r"\[0\] is bool_"),
    ([[6, "4"]], r"\[0\] holds str, not a number"), ([combabc.SmcOptions()], r"\[0\] is SmcOptions")])
def test_what_is_no_threshold_is_a_one_line_type_error(thresholds, message):
    with pytest.raises(TypeError, match="SmcOptions.thresholds: " + message) as error:
        combabc.make_options(thresholds=thresholds)
    assert "\n" not in str(error.value) and "expected a list of ThresholdSchedule" in str(error.value)


def test_numpy_numbers_in_every_argument():
    space = combabc.BinarySpace(dimension=np.int64(8), prior_one=np.array(PRIOR),
                                default_prior_one=np.float64(0.5), names=np.array(
                                    [f"b{k}" for k in range(1, 9)]))
    assert space.names[0] == "b1"
    fidelity = combabc.MultiFidelityOptions(continue_if_accepted=np.float32(1),
                                            continue_if_rejected=np.float64(0.5),
                                            adapt=np.bool_(False), floor=np.float32(0.25),
                                            cost_ratio=np.int64(2))
    assert (fidelity.continue_if_rejected, fidelity.adapt, fidelity.cost_ratio) == (0.5, False, 2)
    logistic = combabc.LogisticKernelOptions(max_predecessors=np.int64(3), clip=np.float32(0.25))
    logistic.max_predecessors = np.uint8(2)
    assert (logistic.max_predecessors, logistic.clip) == (2, 0.25)
    tempering = combabc.TemperingSchedule(kind="list", values=np.array([0.5, 1]),
                                          phi0=np.float32(0.5))
    assert tempering.values == [0.5, 1.0]
    defaults = combabc.SmcOptions()
    o = combabc.make_options(num_waves=np.int64(3), accepted_per_wave=np.int32(200),
                             seed=np.uint64(11), threads=np.int8(1), thresholds=np.array([6, 4, 2.5]),
                             estimator="importance", keep_outputs=np.bool_(True),
                             acceptance_floor_after=np.int64(defaults.acceptance_floor_after),
                             failure_fraction_after=np.int64(1),
                             max_failure_fraction=np.float32(1), batch_size=np.uint16(0))
    history = combabc.run(combabc.Problem(space, per_sample, list(OBSERVED.astype(np.float32)),
                                          batch=np.bool_(False), rng=np.bool_(False)), o,
                          threads=np.int64(2))
    same_history(history, combabc.run(problem(), options(accepted_per_wave=200)))
    # History's arguments.
    assert history.wave(np.int64(2)) is history.waves[1] and history.bit(np.uint8(3)) == 2
    assert history.bit(np.str_("b4")) == 3 and history.experiment(np.int64(0)).index == 0
    assert set(history.particles(wave=np.int32(1))["wave"]) == {1}
    np.testing.assert_array_equal(history.curves(wave=np.int64(3), experiment=np.int64(0)),
                                  history.waves[2].output)
    with pytest.raises(IndexError):
        history.wave(np.float64(1))  # a wave is numbered by an integer


def test_batch_random_takes_numpy_numbers():
    seen = []

    def simulate(bits, rng):
        if not seen:
            n = len(rng)
            seen.append(rng.uniform(np.float32(1), np.int64(2), size=np.int64(3)).shape == (n, 3))
            seen.append(rng.integers(np.int64(2), np.uint8(5), size=(np.int64(2),)).max() < 5)
            seen.append(rng.normal(np.int64(0), np.float32(1), size=np.array([2, 2])).shape ==
                        (n, 2, 2))
            seen.append(type(rng[np.int64(0)]).__name__ == "Generator")
            with pytest.raises(TypeError, match="size: None, an int or a tuple of ints, not float"):
                rng.random(size=2.0)
        return bits @ W.T

    p = combabc.Problem(combabc.BinarySpace(dimension=8, prior_one=PRIOR), simulate, OBSERVED,
                        batch=True, rng=True)
    combabc.run(p, options(num_waves=1, thresholds=[6.0], accepted_per_wave=50))
    assert seen == [True] * 4  # and the TypeError was raised
