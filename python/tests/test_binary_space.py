"""BinarySpace's bounds: the config's limit on the number of bits and distinct names (issue 20,
D24: it accepted any size and repeated names)."""

import pytest

import combabc


def test_duplicate_names_are_refused_naming_the_duplicate():
    with pytest.raises(ValueError, match=r"names\[2\] 'b' repeats names\[1\]"):
        combabc.BinarySpace(dimension=3, names=["a", "b", "b"])
    space = combabc.BinarySpace(dimension=3, names=["a", "b", "c"])
    assert space.names == ["a", "b", "c"]


def test_size_is_capped_at_the_configs_limit(tmp_path):
    assert combabc.BinarySpace(dimension=combabc.MAX_BITS).dimension == combabc.MAX_BITS
    with pytest.raises(ValueError, match=f"dimension = {combabc.MAX_BITS + 1}; at most "
                                         f"{combabc.MAX_BITS} bits"):
        combabc.BinarySpace(dimension=combabc.MAX_BITS + 1)
    # The same number as the config's [simulator.bits] limit, not a second one.
    config = tmp_path / "run.toml"
    config.write_text(f"""[simulator]
kind = "worker"
argv = ["python3", "w.py"]
[simulator.bits]
count = {combabc.MAX_BITS + 1}
[simulator.outputs]
coordinates = [0.0, 0.1]
[data]
csv = "p.csv"
[metric]
[[metric.component]]
type = "least_squares"
""")
    with pytest.raises(combabc.Error,
                       match=rf"run.toml:5: simulator.bits.count: must be in \[0, "
                             rf"{combabc.MAX_BITS}\]"):
        combabc.run(config)
