"""combabc.plot: matplotlib Figures of a History, with the artists and data expected (Agg)."""

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")

import combabc  # noqa: E402
import combabc.plot  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from test_smc import OBSERVED, options, problem  # noqa: E402


@pytest.fixture(scope="module")
def history():
    return combabc.run(problem(), options(accepted_per_wave=100))


def test_marginals_per_wave(history):
    fig = combabc.plot.marginals(history)
    assert isinstance(fig, Figure)
    (ax,) = fig.axes
    heights = [bar.get_height() for bar in ax.containers[0]]
    np.testing.assert_allclose(heights, history.posterior)
    assert len(ax.lines) == len(history.waves)
    np.testing.assert_allclose(ax.lines[0].get_ydata(), history.waves[0].marginals)
    assert [t.get_text() for t in ax.get_xticklabels()] == history.bit_names
    one = combabc.plot.marginals(history, wave=1).axes[0]
    np.testing.assert_allclose([b.get_height() for b in one.containers[0]],
                               history.waves[0].marginals)
    fig.canvas.draw()  # renders


def test_curves_with_the_data(history):
    ax = combabc.plot.curves(history, wave=2).axes[0]
    data = [line for line in ax.lines if line.get_label() == "measured"]
    np.testing.assert_array_equal(data[0].get_ydata(), OBSERVED)
    assert len(ax.lines) == history.waves[1].accepted + 1
    assert "wave 2" in ax.get_title()


def test_thresholds_and_acceptance(history):
    top, bottom = combabc.plot.thresholds(history).axes
    np.testing.assert_array_equal(top.lines[0].get_ydata(), [6.0, 4.0, 2.5])
    np.testing.assert_allclose(bottom.lines[0].get_ydata(),
                               [w.acceptance_rate for w in history.waves])
    np.testing.assert_array_equal(bottom.lines[0].get_xdata(), [1, 2, 3])


def test_predictive_band(history):
    ax = combabc.plot.predictive_band(history).axes[0]
    assert len(ax.collections) == 1  # the band
    band = ax.collections[0].get_paths()[0].vertices[:, 1]
    curves = history.waves[-1].output
    assert band.min() >= curves.min() and band.max() <= curves.max()
    median = [line for line in ax.lines if line.get_label() == "median"][0].get_ydata()
    assert np.all(median >= curves.min(axis=0)) and np.all(median <= curves.max(axis=0))


@pytest.fixture(scope="module")
def mixed():
    from test_python_runs import mixed_options, mixed_problem
    return combabc.run(mixed_problem(), mixed_options())


def test_densities_per_wave(mixed):
    fig = combabc.plot.densities(mixed)
    assert [ax.get_xlabel() for ax in fig.axes] == ["gain", "offset"]
    assert all(ax.get_ylabel() == "density" for ax in fig.axes)
    for j, ax in enumerate(fig.axes):
        assert [line.get_label() for line in ax.lines] == ["wave 1", "wave 2", "wave 3"]
        assert ax.get_legend() is not None
        # Each is a density: it integrates to 1 over the drawn range (the values lie well
        # inside it), and the last wave's peaks among the wave's particles.
        for line in ax.lines:
            x, y = line.get_xdata(), line.get_ydata()
            assert np.sum((y[1:] + y[:-1]) / 2 * np.diff(x)) == pytest.approx(1.0, abs=0.02)
        x, y = ax.lines[-1].get_xdata(), ax.lines[-1].get_ydata()
        values = mixed.waves[-1].reals[:, j]
        assert values.min() <= x[np.argmax(y)] <= values.max()
    one = combabc.plot.densities(mixed, wave=1, parameters="offset")
    (ax,) = one.axes
    assert ax.get_xlabel() == "offset" and len(ax.lines) == 1
    with pytest.raises(KeyError, match="no continuous parameter named 'speed'"):
        combabc.plot.densities(mixed, parameters=["speed"])
    fig.canvas.draw()  # renders


def test_pairs(mixed):
    fig = combabc.plot.pairs(mixed)
    axes = np.array(fig.axes).reshape(2, 2)
    assert [ax.get_xlabel() for ax in axes[1]] == ["gain", "offset"]
    assert axes[1][0].get_ylabel() == "offset"
    assert not axes[0][1].axison  # above the diagonal: nothing
    w = mixed.posterior_wave
    (points,) = axes[1][0].collections
    np.testing.assert_array_equal(points.get_offsets(), w.reals[:, [0, 1]])
    assert len(axes[0][0].lines) == 1 and len(axes[1][1].lines) == 1  # the diagonal densities
    assert f"wave {w.number}" in fig._suptitle.get_text()
    fig.canvas.draw()


def test_continuous_plots_need_continuous_parameters(history):
    with pytest.raises(ValueError, match="no continuous parameters"):
        combabc.plot.densities(history)
    with pytest.raises(ValueError, match="no continuous parameters"):
        combabc.plot.pairs(history)
