"""Figures of a History, as matplotlib Figures (docs/python.md, "Figures"), in the manner of
pyABC's visualisation: the caller shows or saves them (fig.savefig("marginals.png")).

    import combabc.plot
    combabc.plot.marginals(history)          # P(bit = 1) per bit, every wave
    combabc.plot.curves(history)             # the posterior wave's accepted curves and the data
    combabc.plot.thresholds(history)         # thresholds and acceptance rate per wave
    combabc.plot.predictive_band(history)    # the posterior predictive band and the data
    combabc.plot.densities(history)          # each continuous parameter's density, every wave
    combabc.plot.pairs(history)              # the continuous parameters two by two

Waves are numbered from 1 (wave=None: every wave in marginals; in curves and predictive_band
History.posterior_wave, the last complete one; in pairs too), bits and continuous parameters are
labelled by their names;
experiments by name or index. Needs matplotlib (python3-matplotlib); nothing here picks a
backend.
"""

import numpy as np


def _figure(panels, width=7.0, height=3.2):
    from matplotlib.figure import Figure
    fig = Figure(figsize=(width, height * panels), layout="constrained")
    return fig, [fig.add_subplot(panels, 1, k + 1) for k in range(panels)]


def _experiments(history, experiment):
    if experiment is None:
        return history.experiments
    return [history.experiment(experiment)]


def _weights(history, wave):
    """The wave's particle weights under the run's estimator (paper: equal), summing to 1."""
    n = len(wave.weight)
    if history.estimator == "paper" or not np.sum(wave.weight) > 0:
        return np.full(n, 1.0 / n) if n else np.zeros(0)
    return wave.weight / np.sum(wave.weight)


def _positions(history, x, width):
    """An experiment's output positions, or the outputs' index when the run has none."""
    if len(x.output_position) == width:
        return x.output_position
    return np.arange(width, dtype=np.float64)


def marginals(history, wave=None):
    """P(bit = 1) per bit (the run's estimator), bits along x by name. wave=None: one line per
    wave and the final wave as bars; a wave's number: that wave's bars. A bar at P = 0 is drawn as
    a thin outline so that it stays visible."""
    fig, (ax,) = _figure(1, width=max(7.0, 0.25 * history.dimension))
    x = np.arange(history.dimension)
    shown = history.waves if wave is None else [history.wave(wave)]
    final = shown[-1]
    ax.bar(x, final.marginals, color="tab:blue", edgecolor="tab:blue", linewidth=0.8,
           label=f"wave {final.number}")
    if wave is None:
        colours = np.linspace(0.85, 0.25, len(shown))
        for w, grey in zip(shown, colours):
            ax.plot(x, w.marginals, marker=".", lw=0.8, color=str(grey), label=f"wave {w.number}")
    ax.set_xticks(x, history.bit_names, rotation=90, fontsize="small")
    ax.set_ylim(0, 1)
    ax.set_ylabel("P(bit = 1)")
    ax.set_title(f"Marginals ({history.estimator})")
    ax.legend(fontsize="small", ncol=2)
    return fig


def curves(history, wave=None, experiment=None, max_curves=200):
    """The accepted simulated curves of a wave (default posterior_wave; at most max_curves, the
    heaviest) with the measured data, one panel per experiment (or the one named)."""
    w = history.wave(wave)
    chosen = _experiments(history, experiment)
    fig, axes = _figure(len(chosen))
    order = np.argsort(-_weights(history, w))[:max_curves]
    for ax, x in zip(axes, chosen):
        ys = history.curves(w.number, experiment=x.index) if w.output.shape[1] else \
            np.zeros((0, 0))
        if ys.shape[1]:
            xs = _positions(history, x, ys.shape[1])
            for row in ys[order]:
                ax.plot(xs, row, color="tab:blue", alpha=0.15, lw=0.8)
        ax.plot(x.measured_position, x.measured_value, "o", color="black", ms=3, label="measured")
        ax.set_xlabel(f"position ({history.position_unit})")
        ax.set_title(f"Accepted curves, wave {w.number}" + (f": {x.name}" if x.name else ""))
        ax.legend(fontsize="small")
    return fig


def thresholds(history):
    """Per wave: each threshold component's threshold (log scale when positive and finite) and
    the acceptance rate."""
    fig, (top, bottom) = _figure(2)
    numbers = [w.number for w in history.waves]
    values = np.array([w.thresholds for w in history.waves], dtype=np.float64)
    for k, name in enumerate(history._threshold_columns):
        top.plot(numbers, values[:, k], marker="o", label=name)
    finite = values[np.isfinite(values)]
    if finite.size and np.all(finite > 0):
        top.set_yscale("log")
    top.set_ylabel("threshold")
    top.legend(fontsize="small")
    bottom.plot(numbers, [w.acceptance_rate for w in history.waves], marker="o",
                color="tab:orange", label="acceptance rate")
    bottom.set_yscale("log")
    bottom.set_ylabel("acceptance rate")
    bottom.set_xlabel("wave")
    for ax in (top, bottom):
        ax.set_xticks(numbers)
    return fig


def _weighted_quantiles(values, weights, qs):
    """Per column of values[n, m], the weighted quantiles qs (inverse of the weighted CDF)."""
    order = np.argsort(values, axis=0)
    out = np.empty((len(qs), values.shape[1]))
    for j in range(values.shape[1]):
        v = values[order[:, j], j]
        cdf = np.cumsum(weights[order[:, j]])
        out[:, j] = [v[min(np.searchsorted(cdf, q * cdf[-1]), len(v) - 1)] for q in qs]
    return out


def predictive_band(history, wave=None, experiment=None, level=0.9):
    """The posterior predictive band of a wave (default posterior_wave): per experiment, the
    weighted central `level` band of the accepted curves (fill), their weighted median (line)
    and the measured data (points). Band and median use the run's estimator's weights."""
    w = history.wave(wave)
    if not w.output.shape[1]:
        raise ValueError("the run kept no outputs (keep_outputs = false): no curves to draw")
    chosen = _experiments(history, experiment)
    fig, axes = _figure(len(chosen))
    weights = _weights(history, w)
    low, high = (1 - level) / 2, 1 - (1 - level) / 2
    for ax, x in zip(axes, chosen):
        ys = history.curves(w.number, experiment=x.index)
        xs = _positions(history, x, ys.shape[1])
        lo, median, hi = _weighted_quantiles(ys, weights, [low, 0.5, high])
        ax.fill_between(xs, lo, hi, color="tab:blue", alpha=0.3,
                        label=f"{level:.0%} band")
        ax.plot(xs, median, color="tab:blue", label="median")
        ax.plot(x.measured_position, x.measured_value, "o", color="black", ms=3, label="measured")
        ax.set_xlabel(f"position ({history.position_unit})")
        ax.set_title(f"Posterior predictive, wave {w.number}" + (f": {x.name}" if x.name else ""))
        ax.legend(fontsize="small")
    return fig


def _reals(history, parameters):
    """The columns (from 0) of the continuous parameters asked for: every one for None, else
    names (or a name)."""
    if not history.real_names:
        raise ValueError("the run has no continuous parameters: nothing to draw")
    if parameters is None:
        return list(range(len(history.real_names)))
    if isinstance(parameters, str):
        parameters = [parameters]
    columns = []
    for name in parameters:
        if name not in history.real_names:
            raise KeyError(f"no continuous parameter named {name!r} (the run has "
                           f"{', '.join(history.real_names)})")
        columns.append(history.real_names.index(name))
    return columns


def _density(values, weights, grid):
    """A weighted Gaussian kernel density estimate on `grid`, its bandwidth by Silverman's rule
    at the weights' effective sample size; negative (multi-fidelity) weights count as 0. A spike
    (a single value) gets a narrow bump a thousandth of its magnitude wide."""
    weights = np.clip(weights, 0.0, None)
    total = weights.sum()
    if not values.size or not total > 0:
        return np.zeros_like(grid)
    weights = weights / total
    mean = np.sum(weights * values)
    sd = np.sqrt(np.sum(weights * (values - mean) ** 2))
    ess = 1.0 / np.sum(weights ** 2)
    width = 1.06 * sd * ess ** -0.2
    if not width > 0:
        width = 1e-3 * max(abs(mean), 1.0)
    z = (grid[:, None] - values[None, :]) / width
    return np.exp(-0.5 * z ** 2) @ weights / (width * np.sqrt(2.0 * np.pi))


def _span(values):
    """The x range of a parameter's panels: its values, padded by a tenth."""
    lo, hi = float(np.min(values)), float(np.max(values))
    pad = 0.1 * (hi - lo) if hi > lo else 0.5 * max(abs(lo), 1.0)
    return lo - pad, hi + pad


def densities(history, wave=None, parameters=None, points=200):
    """Each continuous parameter's posterior density per wave (a weighted Gaussian kernel estimate
    under the run's estimator's weights), one panel per parameter, one line per wave (the later
    the darker) and the last thick; wave: a wave's number (from 1) for that wave alone.
    parameters: names (default every continuous parameter)."""
    columns = _reals(history, parameters)
    shown = history.waves if wave is None else [history.wave(wave)]
    shown = [w for w in shown if len(w.index)]
    fig, axes = _figure(len(columns))
    colours = np.linspace(0.8, 0.0, len(shown)) if len(shown) > 1 else [0.0]
    for ax, j in zip(axes, columns):
        every = np.concatenate([w.reals[:, j] for w in shown]) if shown else np.zeros(1)
        grid = np.linspace(*_span(every), points)
        for w, grey in zip(shown, colours):
            last = w is shown[-1]
            ax.plot(grid, _density(w.reals[:, j], _weights(history, w), grid),
                    color="tab:blue" if last else str(grey), lw=1.8 if last else 0.9,
                    label=f"wave {w.number}")
        ax.set_xlabel(history.real_names[j])
        ax.set_ylabel("density")
        ax.set_title(f"{history.real_names[j]}: posterior density per wave ({history.estimator})")
        ax.legend(fontsize="small", ncol=2)
    return fig


def pairs(history, wave=None, parameters=None, points=200):
    """The continuous parameters two by two in a wave (default posterior_wave): on the diagonal
    each one's density (as densities), below it the particles of each pair (their size and
    shade by weight), above it nothing. parameters: names (default every one)."""
    columns = _reals(history, parameters)
    w = history.wave(wave)
    weights = _weights(history, w)
    k = len(columns)
    from matplotlib.figure import Figure
    fig = Figure(figsize=(2.4 * k + 0.8, 2.4 * k + 0.6), layout="constrained")
    grid = fig.subplots(k, k, squeeze=False)
    shade = np.clip(weights, 0.0, None)
    shade = shade / shade.max() if shade.size and shade.max() > 0 else shade
    spans = [_span(w.reals[:, j]) if len(w.index) else (0.0, 1.0) for j in columns]
    for row, j in enumerate(columns):
        for col, i in enumerate(columns):
            ax = grid[row][col]
            if col > row:
                ax.set_axis_off()
                continue
            if col == row:
                x = np.linspace(*spans[col], points)
                ax.plot(x, _density(w.reals[:, j], weights, x), color="tab:blue")
                ax.set_yticks([])
            else:
                ax.scatter(w.reals[:, i], w.reals[:, j], s=4 + 16 * shade, c=shade,
                           cmap="Blues", vmin=-0.3, vmax=1.0, linewidths=0)
                ax.set_ylim(*spans[row])
            ax.set_xlim(*spans[col])
            if row == k - 1:
                ax.set_xlabel(history.real_names[i])
            if col == 0 and row > 0:
                ax.set_ylabel(history.real_names[j])
    fig.suptitle(f"Continuous parameters, wave {w.number} ({history.estimator})")
    return fig
