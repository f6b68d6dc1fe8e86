"""One numbering in Python (docs/python.md, "Numbering"): waves from 1, bits by name or from 1;
NumPy arrays positional."""

import numpy as np
import pytest

import combabc
from test_smc import options, problem


@pytest.fixture(scope="module")
def history():
    space = combabc.BinarySpace(dimension=8, names=[f"s{k + 1}" for k in range(8)],
                                prior_one=[0.3, 0.5, 0.6, 0.4, 0.5, 0.7, 0.5, 0.35])
    p = problem()
    p.space = space
    return combabc.run(p, options(accepted_per_wave=100))


def test_waves_count_from_one(history):
    assert [w.number for w in history.waves] == [1, 2, 3]
    first = history.particles(wave=1)
    assert set(first["wave"]) == {1} and len(first) == history.waves[0].accepted
    np.testing.assert_array_equal(first["index"], history.waves[0].index)
    assert set(history.particles(wave=3)["wave"]) == {3}
    np.testing.assert_array_equal(history.curves(wave=1), history.waves[0].output)
    np.testing.assert_array_equal(history.curves(), history.waves[-1].output)
    assert history.wave(2) is history.waves[1]
    for wrong in (0, 4, -1):
        with pytest.raises(IndexError, match="numbered 1 to 3"):
            history.particles(wave=wrong)
    assert list(history.wave_table()["wave"]) == [1, 2, 3]


def test_bits_are_named_or_count_from_one(history):
    frame = history.particles()
    assert [c for c in frame.columns if c.startswith("s")] == history.bit_names
    np.testing.assert_array_equal(frame.loc[frame["wave"] == 3, "s1"], history.waves[2].bits[:, 0])
    marginals = history.marginals()
    assert list(marginals.loc[marginals["wave"] == 1, "bit"]) == list(range(1, 9))
    pairs = history.pair_correlations()
    assert pairs["bit_i"].min() == 1 and pairs["bit_j"].max() == 8
    assert history.bit("s3") == history.bit(3) == 2


def test_tied_bits_by_number_from_one_or_by_name():
    by_number = combabc.BinarySpace(dimension=4, tied=[[1, 4]])
    by_name = combabc.BinarySpace(dimension=4, names=["a", "b", "c", "d"], tied=[["a", "d"]])
    assert by_number.num_free == by_name.num_free == 3
    with pytest.raises(ValueError, match="numbered 1 to 4"):
        combabc.BinarySpace(dimension=4, tied=[[0, 1]])
    with pytest.raises(ValueError, match="not one of names"):
        combabc.BinarySpace(dimension=4, names=["a", "b", "c", "d"], tied=[["a", "e"]])
    # Tied bits 1 and 4 are equal in every accepted particle.
    p = problem()
    p.space = combabc.BinarySpace(dimension=8, tied=[[1, 4]])
    bits = combabc.run(p, options(accepted_per_wave=50)).waves[-1].bits
    np.testing.assert_array_equal(bits[:, 0], bits[:, 3])
