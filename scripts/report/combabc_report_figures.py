"""The report's figures (combabc_report.py reads the export; this module draws it).

Every figure is a function of the waves and the run read by combabc_report.load_export; render_all
draws them all, in parallel, into a folder and returns their names in display order.
"""

import multiprocessing
import os
import re
import textwrap

import numpy as np

import matplotlib

matplotlib.use("Agg")  # files only; never needs a display
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402
from matplotlib.ticker import FuncFormatter, LogLocator, MaxNLocator  # noqa: E402

from combabc_report_page import FIXED_RGB, FREE_RGB  # noqa: E402  the strip's colour scale

DPI = 150
# The position units the report draws in centimetres (combabc_report.CM_PER_UNIT).
CM_UNITS = ("m", "cm", "mm", "um", "nm")
# The simulated peak "lies outside the measured window" when the accepted curves rise above the
# measured window's values by more than this factor: then the curve figures add a panel zoomed on
# the window (the 70 cm example's normalised peak of 80-120 against data at most 1).
ZOOM_FACTOR = 2.0

STYLE = {
    "font.size": 10,
    "axes.titlesize": 11,
    "axes.labelsize": 10,
    "xtick.labelsize": 9,
    "ytick.labelsize": 9,
    "legend.fontsize": 9,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "svg.fonttype": "none",  # keep text as text in SVG: smaller, editable
    # Names come from the user's config: "$x$" in a clamp or metric name is text, not TeX.
    "text.parse_math": False,
}
CURVE_COLOUR = "#1f5fa8"
BAR_COLOUR = "#3a7d44"
BAND_COLOUR = "#9fbfe0"
MEASURED_STYLE = dict(marker="o", markersize=4.5, markerfacecolor="white", markeredgecolor="black",
                      markeredgewidth=0.9, linestyle="none", zorder=5)


# --- labels ---------------------------------------------------------------------------------------

def wave_label(w):
    label = f"Wave {w.number}"
    return label if w.complete else label + " (incomplete)"


def thresholds_text(w, run, prefix=", ", compact=False):
    if not w.thresholds.size:
        return ""
    return prefix + _thresholds(w, run, compact)


def _thresholds(w, run, compact=False):
    names = [name for name, kind in run["components"] if kind == "threshold"]
    if len(names) != len(w.thresholds):
        names = [f"ε{k + 1}" for k in range(len(w.thresholds))]
    if len(w.thresholds) == 1:
        return f"ε = {w.thresholds[0]:.3g}"
    if compact:  # panel titles: the component names are in the per-wave figures and the table
        return "ε = (" + ", ".join(f"{e:.3g}" for e in w.thresholds) + ")"
    return ", ".join(f"ε[{n}] = {e:.3g}" for n, e in zip(names, w.thresholds))


def curve_handles(n, run):
    handles = [Line2D([], [], color=CURVE_COLOUR, linewidth=1.2,
                      label=f"Accepted simulations (n = {n})" if n else "Accepted simulations")]
    if run["measured_x_cm"].size:
        handles.append(Line2D([], [], label="Measured data", **MEASURED_STYLE))
    return handles


def output_labels(run):
    """Axis labels from the simulator's declaration: the sensor's |w| along the sensor, an
    external simulator's declared output name ([simulator.outputs] name) at its coordinates, or
    a Problem's outputs at their positions, or by their index when it gave none."""
    if run["sensor"]:
        return "Position along sensor (cm)", "Normalised |w|"
    name = str(run["config"].get("simulator", {}).get("outputs", {}).get("name", "output"))
    unit = run.get("position_unit", "m")
    xlabel = ("Output index" if unit == "index" else
              "Position (cm)" if unit in CM_UNITS else f"Position ({unit})")
    return xlabel, ("Normalised " if run["normalised"] else "") + name


def experiment_title(experiment, width=60):
    """A panel's title: the experiment's name, its description on a second line (wrapped)."""
    lines = [experiment["name"] or "(unnamed)"]
    if experiment["description"]:
        lines += textwrap.wrap(experiment["description"], width) or []
    return "\n".join(lines)


def experiment_thresholds(w, run, experiment):
    """The wave's thresholds of the experiment's own components ("ε = ..."), or ""."""
    slots = [k for k, (_, kind) in enumerate(run["components"]) if kind != "indicator"]
    if len(slots) != w.thresholds.size:
        return ""
    mine = [w.thresholds[i] for i, k in enumerate(slots)
            if experiment["components"].start <= k < experiment["components"].stop]
    if not mine:
        return ""
    if len(mine) == 1:
        return f"ε = {mine[0]:.3g}"
    return "ε = (" + ", ".join(f"{e:.3g}" for e in mine) + ")"


# --- curves ---------------------------------------------------------------------------------------

def experiment_data(w, run, experiment):
    """(x, curves, measured x, measured y) of one experiment (an entry of run["experiments"]), or
    of the whole run when experiment is None."""
    curves, x = w.curves, run["x_cm"]
    measured_x, measured_y = run["measured_x_cm"], run["measured_y"]
    if experiment is not None:
        curves, x = curves[:, experiment["outputs"]], x[experiment["outputs"]]
        measured_x = measured_x[experiment["measured"]]
        measured_y = measured_y[experiment["measured"]]
    if curves.shape[1] != x.size:
        x = np.arange(curves.shape[1], dtype=float)
    return x, curves, measured_x, measured_y


def window_limits(w, run, experiment):
    """(x range, y range) of the experiment's measured window with the wave's curves there, and
    whether the curves' peak lies outside it (they rise above the window's values by more than
    ZOOM_FACTOR); None without a window to show."""
    x, curves, mx, my = experiment_data(w, run, experiment)
    if mx.size < 2 or not x.size or not len(curves):
        return None
    lo, hi = float(np.min(mx)), float(np.max(mx))
    at_data = np.array([np.interp(mx, x, c) for c in curves])
    window_top = max(float(np.nanmax(np.abs(at_data))), float(np.nanmax(np.abs(my))))
    if not ((x >= lo) & (x <= hi)).any() or window_top <= 0:
        return None
    outside = float(np.nanmax(curves)) > ZOOM_FACTOR * window_top
    pad = 0.04 * (hi - lo)
    # The window's data and the middle 98 % of the curves there (a stray curve does not set it).
    values = np.concatenate([my, np.percentile(at_data, [1, 99], axis=0).ravel()])
    bottom, top = min(0.0, float(np.min(values))), float(np.max(values))
    span = (top - bottom) or 1.0
    return (lo - pad, hi + pad), (bottom - 0.05 * span, top + 0.08 * span), outside


def zoom_window(w, run, experiment):
    """The measured window (x range, y range) to zoom on when the accepted curves' peak lies
    outside it, else None."""
    limits = window_limits(w, run, experiment)
    return limits[:2] if limits is not None and limits[2] else None


def draw_curves(ax, w, run, experiment=None, zoom=None):
    """The wave's accepted curves and the measured circles: all of them, or one experiment's;
    zoom: (x range, y range) of the measured window to show (zoom_window)."""
    x, curves, measured_x, measured_y = experiment_data(w, run, experiment)
    if not x.size:
        ax.text(0.5, 0.5, "no outputs", ha="center", va="center", transform=ax.transAxes)
        return
    n = curves.shape[0]
    # Dense sets need fainter lines to show where curves concentrate (Figures 3/5: 500 curves).
    alpha = float(np.clip(25.0 / max(n, 1), 0.04, 0.5))
    segments = np.stack([np.broadcast_to(x, curves.shape), curves], axis=-1)
    ax.add_collection(LineCollection(segments, colors=CURVE_COLOUR, linewidths=0.6, alpha=alpha,
                                     rasterized=n > 200))
    if measured_x.size:
        ax.plot(measured_x, measured_y, **MEASURED_STYLE)
    xlabel, ylabel = output_labels(run)
    if zoom is not None:
        ax.set_xlim(*zoom[0])
        ax.set_ylim(*zoom[1])
        ax.set_title("Zoom on the measured window", fontsize=9, loc="left")
    else:
        ax.set_xlim(x.min(), x.max())
        top = max(1.0, float(np.nanmax(curves)) if n else 1.0,
                  float(measured_y.max()) if measured_y.size else 1.0)
        ax.set_ylim(0.0, 1.05 * top)
        if measured_x.size and zoom_window(w, run, experiment) is not None:
            ax.axvspan(measured_x.min(), measured_x.max(), color="#f2c14e", alpha=0.25, lw=0)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, linewidth=0.4, alpha=0.4)


def curves_figure(w, run, estimator, out):
    # One panel per experiment (a single one without named experiments): its own scan, its curves
    # and its measured circles, and below it the zoom on its measured window when that is needed.
    experiments = run["experiments"] if run["named"] else [None]
    zooms = [zoom_window(w, run, x) for x in experiments]
    zoomed = any(z is not None for z in zooms)
    cols = min(len(experiments), 3)
    blocks = (len(experiments) + cols - 1) // cols
    rows = blocks * (2 if zoomed else 1)
    width, height = (6.4, 4.3) if not run["named"] else (5.6 * cols, 4.0 * blocks + 0.9)
    if zoomed:
        height = height + 3.6 * blocks
    fig, axes = plt.subplots(rows, cols, figsize=(width, height), squeeze=False)
    for j, experiment in enumerate(experiments):
        row, col = (j // cols) * (2 if zoomed else 1), j % cols
        ax = axes[row][col]
        draw_curves(ax, w, run, experiment)
        if experiment is None:
            ax.set_title(f"{wave_label(w)}: accepted curves{thresholds_text(w, run, compact=True)}")
        else:
            eps = experiment_thresholds(w, run, experiment)
            ax.set_title(experiment_title(experiment, width=64) + (f"\n{eps}" if eps else ""),
                         fontsize=10)
        if zoomed:
            if zooms[j] is not None:
                draw_curves(axes[row + 1][col], w, run, experiment, zoom=zooms[j])
            else:
                axes[row + 1][col].axis("off")
    for j in range(len(experiments), blocks * cols):
        for r in range(2 if zoomed else 1):
            axes[(j // cols) * (2 if zoomed else 1) + r][j % cols].axis("off")
    handles = curve_handles(w.curves.shape[0], run)
    if run["named"]:
        fig.suptitle(f"{wave_label(w)}: accepted curves per experiment", fontsize=11)
    fig.legend(handles=handles, loc="lower center", ncol=2, frameon=False)
    fig.tight_layout(rect=(0, 0.55 / fig.get_figheight(), 1, 1))
    return save(fig, out, f"wave_{w.number}_curves")


# --- marginals ------------------------------------------------------------------------------------

def edges(run):
    """Bit index ranges, one per panel, and whether they are the sensor's two edges of clamps."""
    d = run["dimension"]
    if run["sensor"] and d % 2 == 0 and d >= 2:
        h = d // 2
        return [(f"Edge 1 (clamps 1–{h})", range(0, h)),
                (f"Edge 2 (clamps {h + 1}–{d})", range(h, d))], True
    return [("", range(0, d))], False


def tick_labels(run, bits, clamps):
    """The bars' labels: the clamp's number for the sensor's clamps ("clamp 7" -> "7"), else the
    bit's name."""
    names = run["bit_names"]
    labels = []
    for b in bits:
        name = names[b] if b < len(names) else f"bit {b + 1}"
        number = re.fullmatch(r"clamp\s*(\d+)", name.strip(), re.IGNORECASE)
        labels.append(number.group(1) if clamps and number else name)
    return labels


def uniform_prior(run):
    """The common prior P(bit = 1), or None when bits differ (then drawn per bar)."""
    prior = run["prior"]
    return float(prior[0]) if prior.size and np.all(prior == prior[0]) else None


def marginal_handles(run):
    common = uniform_prior(run)
    label = f"Prior ({common:g})" if common is not None else "Prior"
    return [Patch(color=BAR_COLOUR, label="Posterior estimate"),
            Line2D([], [], color="black", linestyle="--", linewidth=0.9, label=label)]


def draw_marginals(axes, w, run, estimator, tick_step=1, titles=True, title_loc="center"):
    probabilities = w.marginals.get(estimator, np.zeros(0))
    panels, clamps = edges(run)
    for ax, (title, bits) in zip(axes, panels):
        positions = np.arange(len(bits), dtype=float)
        values = (probabilities[list(bits)] if probabilities.size == run["dimension"]
                  else np.full(len(bits), np.nan))
        ax.bar(positions, values, width=0.75, color=BAR_COLOUR, edgecolor="none")
        # A bar at P = 0 has no height: a short thick line on the axis shows it is there.
        low = np.isfinite(values) & (values < 0.01)
        if low.any():
            ax.hlines(np.zeros(int(low.sum())), positions[low] - 0.375, positions[low] + 0.375,
                      colors=BAR_COLOUR, linewidth=2.5, zorder=4)
        if uniform_prior(run) is not None:
            ax.axhline(uniform_prior(run), color="black", linestyle="--", linewidth=0.9, zorder=3)
        else:
            ax.hlines(run["prior"][list(bits)], positions - 0.45, positions + 0.45,
                      colors="black", linestyles="--", linewidth=0.9, zorder=3)
        ax.set_ylim(-0.03, 1.0)
        ax.set_xlim(-0.7, len(bits) - 0.3)
        labels = tick_labels(run, bits, clamps)
        if clamps:
            step = tick_step * (1 if len(bits) <= 20 else max(1, len(bits) // 18))
            ax.set_xticks(positions[::step], labels[::step])
            ax.set_xlabel("Clamp number")
        else:
            ax.set_xticks(positions, labels, rotation=90 if len(bits) > 8 else 30,
                          ha="center" if len(bits) > 8 else "right", fontsize=8)
        ax.set_ylabel("P(fixed)" if clamps else "P(bit = 1)")
        if titles and title:
            ax.set_title(title, fontsize=10, loc=title_loc)
        ax.grid(True, axis="y", linewidth=0.4, alpha=0.4)


def marginals_figure(w, run, estimator, out):
    panels, clamps = edges(run)
    width = 5.0 * len(panels) + 0.6 if clamps else max(7.0, 0.3 * run["dimension"] + 1.5)
    height = 3.4 if clamps else 3.4 + 0.07 * max(len(n) for n in run["bit_names"] or [""])
    fig, axes = plt.subplots(1, len(panels), figsize=(width, height), sharey=True, squeeze=False)
    draw_marginals(axes[0], w, run, estimator)
    what = "probability of each clamp being fixed" if clamps else "P(bit = 1) per bit"
    fig.suptitle(f"{wave_label(w)}: {what} ({estimator} estimator, n = {w.accepted})",
                 fontsize=11)
    fig.legend(handles=marginal_handles(run), loc="lower center", ncol=2, frameon=False)
    fig.tight_layout(rect=(0, 0.25 / height, 1, 1))
    return save(fig, out, f"wave_{w.number}_marginals")


# --- the answer's P(fixed) -------------------------------------------------------------------------

def answer_figure(waves, run, estimator, out):
    """The answer's P(fixed) per clamp (summary.json's "answer": its wave, estimator and standard
    errors) as bars with error bars of one standard error, coloured as the strip on the page
    (black edge: fixed) between the verdict levels: for the sensor one panel per edge, edge 2 above
    edge 1, each bar over its section on a centimetre axis; otherwise one bar per bit, named."""
    answer = run["summary"].get("answer") or {}
    bits = answer.get("bits") or []
    level = float(answer.get("verdict_level") or 0.95)
    placed = all(b.get("edge") in (1, 2) and b.get("start_m") is not None for b in bits)
    sensor = run["sensor"] and placed and len(bits) % 2 == 0
    rows = ([(f"Edge {edge}", [b for b in bits if b["edge"] == edge]) for edge in (2, 1)]
            if sensor else [("", bits)])
    width = 10.0 if sensor else max(7.0, 0.3 * len(bits) + 1.5)
    fig, axes = plt.subplots(len(rows), 1, figsize=(width, 2.3 * len(rows) + 0.9), sharex=True,
                             squeeze=False)
    for ax, (title, mine) in zip(axes[:, 0], rows):
        p = np.array([number(b.get("p_one")) for b in mine])
        se = np.array([number(b.get("mc_se")) or 0.0 for b in mine])
        colours = [strip_colour(v) for v in p]
        edges = ["black" if b.get("verdict") == "fixed" else "#999999" for b in mine]
        if sensor:
            start = np.array([float(b["start_m"]) for b in mine]) * 100.0
            end = np.array([float(b["end_m"]) for b in mine]) * 100.0
            centre, span = (start + end) / 2, (end - start) * 0.85
        else:
            centre, span = np.arange(len(mine), dtype=float), np.full(len(mine), 0.75)
        ax.bar(centre, np.nan_to_num(p), width=span, color=colours, edgecolor=edges, linewidth=0.8)
        # A bar at P = 0 has no height: a short thick line on the axis shows it is there.
        low = np.isfinite(p) & (p < 0.01)
        if low.any():
            ax.hlines(np.zeros(int(low.sum())), centre[low] - span[low] / 2,
                      centre[low] + span[low] / 2, colors="#777777", linewidth=2.5, zorder=4)
        ax.errorbar(centre, np.nan_to_num(p), yerr=np.nan_to_num(se), fmt="none", ecolor="black",
                    elinewidth=0.9, capsize=2.5)
        for y in (level, 1 - level):
            ax.axhline(y, color="#555555", linestyle=":", linewidth=0.8)
        ax.set_ylim(0.0, 1.05)
        ax.set_ylabel("P(fixed)" if sensor else "P(bit = 1)")
        if sensor:
            numbers = [str(b.get("number")) for b in mine]
            for c, text, v in zip(centre, numbers, np.nan_to_num(p)):
                ax.text(c, min(v, 0.98) + 0.03, text, ha="center", va="bottom", fontsize=7,
                        color="#444444")
            ax.set_title(title, fontsize=10, loc="left")
            ax.set_xlim(0.0, float(np.max(end)))
        else:
            ax.set_xticks(centre, [str(b.get("name", "")) for b in mine],
                          rotation=90 if len(mine) > 8 else 30,
                          ha="center" if len(mine) > 8 else "right", fontsize=8)
        ax.grid(True, axis="y", linewidth=0.4, alpha=0.4)
    if sensor:
        axes[-1, 0].set_xlabel("x along the strip (cm)")
    what = "exact" if answer.get("exact") else f"wave {answer.get('wave')}, {answer.get('estimator')}"
    fig.suptitle(f"The answer ({what}): P(fixed) ± one standard error; dotted: the verdict levels "
                 f"{1 - level:g} and {level:g}" if sensor else
                 f"The answer ({what}): P(bit = 1) ± one standard error; dotted: the verdict "
                 f"levels {1 - level:g} and {level:g}", fontsize=10)
    fig.tight_layout()
    return save(fig, out, "answer")


def strip_colour(p):
    """The page's strip colour of P(fixed) (combabc_report_page.p_colour), for matplotlib."""
    if not np.isfinite(p):
        return "#bbbbbb"
    p = min(max(p, 0.0), 1.0)
    free, fixed = np.array(FREE_RGB, dtype=float), np.array(FIXED_RGB, dtype=float)
    return tuple((free + (fixed - free) * p) / 255.0)


# --- continuous parameters ------------------------------------------------------------------------

def prior_range(real, values):
    """Where to draw a parameter: its prior's support when bounded, else mean +- 4 sd (of log x for
    the lognormal), widened to the accepted values."""
    _, kind, low, high, mean, sd = real
    if kind in ("uniform", "truncated_normal"):
        lo, hi = low, high
    elif kind == "lognormal":
        lo, hi = np.exp(mean - 4 * sd), np.exp(mean + 4 * sd)
    else:
        lo, hi = mean - 4 * sd, mean + 4 * sd
    if values.size:
        lo, hi = min(lo, float(np.min(values))), max(hi, float(np.max(values)))
    return (lo, hi) if hi > lo else (lo - 0.5, lo + 0.5)


def reals_figure(waves, run, estimator, out):
    reals = run["reals"]
    cols = min(len(reals), 3)
    rows = (len(reals) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.6 * cols, 3.3 * rows), squeeze=False)
    colours = plt.cm.viridis(np.linspace(0.0, 0.9, max(len(waves), 1)))
    for j, real in enumerate(reals):
        ax = axes[j // cols][j % cols]
        every = np.concatenate([w.reals[:, j] for w in waves if w.reals is not None])
        lo, hi = prior_range(real, every)
        bins = np.linspace(lo, hi, 31)
        for w, colour in zip(waves, colours):
            if w.reals is None or not w.reals.shape[0]:
                continue
            ax.hist(w.reals[:, j], bins=bins, weights=w.weights,
                    histtype="step", color=colour, linewidth=1.3,
                    linestyle="-" if w.complete else "--", label=wave_label(w))
        ax.set_title(f"{real[0]} (prior: {real[1]})", fontsize=10)
        ax.set_xlim(lo, hi)
        ax.xaxis.set_major_locator(MaxNLocator(5))  # wide values (1e4 ... 1e5) must not overlap
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:.3g}"))
        ax.set_xlabel(real[0])
        ax.set_ylabel("Weight per bin")
        ax.grid(True, linewidth=0.4, alpha=0.4)
    for j in range(len(reals), rows * cols):
        axes[j // cols][j % cols].axis("off")
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 6) or 1, frameon=False)
    fig.suptitle(f"Continuous parameters: accepted values per wave ({estimator} estimator)",
                 fontsize=11)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    return save(fig, out, "reals")


# --- overview and summary -------------------------------------------------------------------------

def overview_figure(waves, run, estimator, out):
    """One row per wave, like the (a)-(e) panels of the paper's Figures 3-6 side by side; an
    experiment whose curves peak outside its measured window in some wave gets a second column,
    zoomed on that window."""
    # A continuous-only run has no bits: curve columns alone.
    panels = edges(run)[0] if run["dimension"] else []
    has_curves = any(w.curves is not None and w.curves.size for w in waves)
    # A curve column per experiment when they are named, else one holding every curve; each
    # followed by its zoom column where needed.
    experiments = run["experiments"] if run["named"] else [None]
    columns_of = []  # (experiment, zoomed) per curve column
    if has_curves:
        for x in experiments:
            columns_of.append((x, False))
            if any(w.curves is not None and w.curves.size and zoom_window(w, run, x) is not None
                   for w in waves):
                columns_of.append((x, True))
    curve_columns = len(columns_of)
    columns = len(panels) + curve_columns
    bar_width = 1.0 if len(panels) > 1 else max(1.0, run["dimension"] / 18)
    widths = [1.0 if zoomed else 1.3 for _, zoomed in columns_of] + [bar_width] * len(panels)
    # Shared x per column: one set of tick labels at the bottom keeps the grid legible (and fast).
    fig, axes = plt.subplots(len(waves), columns,
                             figsize=(4.2 * (curve_columns + bar_width * len(panels)),
                                      2.6 * len(waves) + 0.5),
                             squeeze=False, sharex="col", gridspec_kw={"width_ratios": widths})
    tick_step = 2 if max((len(bits) for _, bits in panels), default=0) > 12 else 1
    for row, w in enumerate(waves):
        label = f"({'abcdefghijklmnopqrstuvwxyz'[row % 26]}) {wave_label(w)}"
        for column, (experiment, zoomed) in enumerate(columns_of):
            ax = axes[row][column]
            limits = (window_limits(w, run, experiment)
                      if zoomed and w.curves is not None and w.curves.size else None)
            if w.curves is None or not w.curves.size:
                ax.text(0.5, 0.5, "no curves stored", ha="center", va="center",
                        transform=ax.transAxes)
            elif zoomed and limits is None:
                ax.axis("off")
            else:
                draw_curves(ax, w, run, experiment, zoom=limits[:2] if zoomed else None)
            if zoomed and row != 0:
                ax.set_title("", loc="left")  # said once, at the top
            if column == 0:
                ax.set_title(f"{label}{thresholds_text(w, run, compact=True)}", loc="left")
            if experiment is not None and not zoomed:
                ax.set_title(experiment["name"], loc="right", fontsize=9)
        bar_axes = axes[row][curve_columns:]
        if not panels:
            continue
        # Without a curve column the wave label takes the left of the first title line.
        draw_marginals(bar_axes, w, run, estimator, tick_step=tick_step, titles=row == 0,
                       title_loc="center" if has_curves else "right")
        if not has_curves:
            bar_axes[0].set_title(label, loc="left")
        if row != len(waves) - 1:
            for ax in axes[row]:
                ax.set_xlabel("")
    handles = ((curve_handles(0, run) if has_curves else []) +
               (marginal_handles(run) if panels else []))
    fig.legend(handles=handles, loc="upper center", ncol=len(handles), frameon=False)
    fig.tight_layout(rect=(0, 0, 1, 1.0 - 0.45 / fig.get_figheight()))
    return save(fig, out, "overview")


def summary_figure(waves, run, estimator, out):
    numbers = np.array([w.number for w in waves])
    complete = np.array([w.complete for w in waves])
    fig, axes = plt.subplots(1, 3, figsize=(12.0, 3.4))

    ax = axes[0]
    k = max((w.thresholds.size for w in waves), default=0)
    names = [name for name, kind in run["components"] if kind == "threshold"]
    if len(names) != k:
        names = [f"component {i + 1}" for i in range(k)]
    for i in range(k):
        eps = np.array([w.thresholds[i] if i < w.thresholds.size else np.nan for w in waves])
        ok = np.isfinite(eps) & (eps > 0)
        ax.plot(numbers[ok], eps[ok], marker="o", label=names[i])
    ax.set_yscale("log")
    # Thresholds often span less than two decades: label the 2x and 5x ticks too.
    ax.yaxis.set_minor_locator(LogLocator(base=10.0, subs=(2.0, 5.0)))
    ax.yaxis.set_minor_formatter(FuncFormatter(lambda v, _: f"{v:.3g}"))
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:.3g}"))
    ax.set_ylabel("Threshold ε (log scale)")
    ax.set_title("Thresholds")
    if k > 1:
        ax.legend(frameon=False)

    ax = axes[1]
    rate = np.array([w.acceptance_rate for w in waves], dtype=float) * 100.0
    ax.plot(numbers, rate, color="black", linewidth=1.0)
    ax.plot(numbers[complete], rate[complete], "o", color="black", label="complete")
    if (~complete).any():
        ax.plot(numbers[~complete], rate[~complete], "o", markerfacecolor="white",
                color="black", label="incomplete")
        ax.legend(frameon=False)
    top = np.nanmax(rate) if rate.size and np.isfinite(rate).any() else 0.0
    ax.set_ylim(0.0, max(1.0, top * 1.15))
    ax.set_ylabel("Acceptance rate (%)")
    ax.set_title("Acceptance rate")

    ax = axes[2]
    sims = np.array([w.candidates for w in waves], dtype=float)
    bars = ax.bar(numbers, sims, color="#7a6fa8", width=0.6)
    for bar, done in zip(bars, complete):
        if not done:
            bar.set_hatch("//")
            bar.set_facecolor("white")
            bar.set_edgecolor("#7a6fa8")
    ax.set_ylabel("Simulations")
    ax.set_title(f"Simulations per wave (total {int(sims.sum()):,})")

    for ax in axes:
        ax.set_xlabel("Wave")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.grid(True, linewidth=0.4, alpha=0.4)
    fig.tight_layout()
    return save(fig, out, "summary")


# --- posterior predictive check -------------------------------------------------------------------

def fit_of(run, name):
    """summary.json's checks.fit entry of the experiment, or None."""
    for fit in (run["summary"].get("checks") or {}).get("fit") or []:
        if fit.get("experiment", "") == name:
            return fit
    return None


def predictive_figure(waves, run, estimator, out):
    """A column per experiment: the band of the accepted curves at the measured points with their
    median, the best accepted fit and the data; below, the residuals."""
    checks = run["predictive"]
    cols = len(checks)
    fig, axes = plt.subplots(2, cols, figsize=(max(6.4, 5.2 * cols), 5.8), squeeze=False,
                             sharex="col", gridspec_kw={"height_ratios": [2.2, 1.0]})
    _, ylabel = output_labels(run)
    xlabel = output_labels(run)[0]
    for j, check in enumerate(checks):
        x = np.asarray(check["positions_cm"], dtype=float)
        order = np.argsort(x)
        x = x[order]

        def column(key):
            values = check.get(key)
            return None if values is None else np.asarray(values, dtype=float)[order]

        ax = axes[0][j]
        ax.fill_between(x, column("band_low"), column("band_high"), color=BAND_COLOUR,
                        alpha=0.7, linewidth=0, label="5–95 % of accepted curves")
        ax.plot(x, column("median"), color=CURVE_COLOUR, linewidth=1.4, label="Median")
        if check.get("best") is not None:
            ax.plot(x, column("best"), color="#c0392b", linewidth=1.0, linestyle="--",
                    label="Best accepted fit")
        ax.plot(x, column("measured"), label="Measured data", **MEASURED_STYLE)
        title = check.get("experiment") or ""
        fit = fit_of(run, check.get("experiment", ""))
        if fit is not None:
            # summary.json writes a non-finite ratio (a noise estimate of 0) as null.
            ratio = fit.get("ratio")
            ratio = float("nan") if ratio is None else ratio
            # Judged against the noise-aware components' stated sigma, or the data's estimate.
            stated = " (stated sigma)" if fit.get("sigma_source") == "stated" else ""
            title += (" — " if title else "") + (
                f"fit {fit.get('verdict', '?')}: best RMS / noise = {ratio:.3g}{stated}")
        if title:
            ax.set_title(title, fontsize=10)
        ax.set_ylabel(ylabel)
        ax.grid(True, linewidth=0.4, alpha=0.4)
        ax.legend(frameon=False, fontsize=8)
        residuals = column("residuals")
        ax = axes[1][j]
        ax.axhline(0.0, color="black", linewidth=0.8)
        if residuals is not None:
            ax.plot(x, residuals, marker="o", markersize=3.5, color=CURVE_COLOUR, linewidth=0.8)
        # The script's own check says what it subtracts; summary.json's is the export's.
        ax.set_ylabel("Residual (data − median)" if check.get("source") == "curves.csv"
                      else "Residual")
        ax.set_xlabel(xlabel)
        ax.grid(True, linewidth=0.4, alpha=0.4)
    wave = checks[0].get("wave")
    fig.suptitle("Posterior predictive check" + (f" (wave {wave})" if wave else ""), fontsize=11)
    fig.tight_layout()
    return save(fig, out, "predictive")


# --- rendering in parallel ------------------------------------------------------------------------

_JOB = {}  # what the forked workers render from (inherited, not pickled)


def fidelity_figure(waves, run, estimator, out):
    """A multi-fidelity run's cost split per wave: cheap and expensive simulations, the seconds
    each took, the continuation probabilities the wave used and its ESS per second."""
    mf = run["multi_fidelity"]
    numbers = np.array([int(x["wave"]) for x in mf], dtype=float)
    fig, axes = plt.subplots(1, 4, figsize=(15.0, 3.4))
    width = 0.38

    def bars(ax, cheap, expensive, label):
        ax.bar(numbers - width / 2, cheap, width, color="#8fb3d9", label="cheap")
        ax.bar(numbers + width / 2, expensive, width, color="#c0504d", label="expensive")
        ax.set_ylabel(label)
        ax.legend(frameon=False)

    bars(axes[0], [x["cheap_simulations"] for x in mf], [x["expensive_simulations"] for x in mf],
         "Simulations")
    axes[0].set_title("Simulations per wave")
    bars(axes[1], [number(x.get("cheap_seconds")) for x in mf],
         [number(x.get("expensive_seconds")) for x in mf], "Seconds (summed call time)")
    axes[1].set_title("Simulation time per wave")
    ax = axes[2]
    ax.plot(numbers, [number(x.get("continue_if_accepted")) for x in mf], marker="o",
            label="η₁ (cheap accepted)")
    ax.plot(numbers, [number(x.get("continue_if_rejected")) for x in mf], marker="s",
            label="η₂ (cheap rejected)")
    ax.set_ylim(0.0, 1.05)
    ax.set_ylabel("Continuation probability")
    ax.set_title("Continuation probabilities")
    ax.legend(frameon=False)
    ax = axes[3]
    ax.plot(numbers, [number(x.get("ess_per_second")) for x in mf], marker="o", color="black")
    ax.set_ylabel("ESS / second")
    ax.set_title("ESS per unit cost")
    for ax in axes:
        ax.set_xlabel("Wave")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    fig.tight_layout()
    return save(fig, out, "fidelity")


def number(value):
    return float("nan") if value is None else float(value)


def save(fig, out, name):
    for fmt in _JOB["formats"]:
        # compress_level 3: PNGs a little larger than the default 6, written in a fraction of the
        # time.
        extra = {"pil_kwargs": {"compress_level": 3}} if fmt == "png" else {}
        fig.savefig(os.path.join(out, f"{name}.{fmt}"), dpi=DPI, **extra)
    plt.close(fig)
    return name


_WHOLE_RUN = {"answer": answer_figure, "overview": overview_figure, "summary": summary_figure, "reals": reals_figure,
              "predictive": predictive_figure, "fidelity": fidelity_figure}
_PER_WAVE = {"curves": curves_figure, "marginals": marginals_figure}


def _render(task):
    kind, index = task
    waves, run, estimator, out = _JOB["waves"], _JOB["run"], _JOB["estimator"], _JOB["out"]
    with plt.rc_context(STYLE):
        if kind in _WHOLE_RUN:
            return _WHOLE_RUN[kind](waves, run, estimator, out)
        return _PER_WAVE[kind](waves[index], run, estimator, out)


def render_all(waves, run, estimator, out, formats, progress=None):
    """Renders every figure; returns their names in display order. Figures are independent, so
    they are drawn by a pool of forked processes (matplotlib text layout and PNG encoding are
    single-threaded and dominate the time). progress(done, total), when given, is called before
    the first figure and after each."""
    tasks = [("summary", None)]
    if (run["summary"].get("answer") or {}).get("bits"):
        tasks.insert(0, ("answer", None))
    # The overview draws curves and marginals: a continuous-only run without curves has neither.
    if run["dimension"] or any(w.curves is not None and w.curves.size for w in waves):
        tasks.append(("overview", None))
    if run["multi_fidelity"]:
        tasks.append(("fidelity", None))
    if run["predictive"]:
        tasks.append(("predictive", None))
    if run["reals"] and any(w.reals is not None and w.reals.shape[0] for w in waves):
        tasks.append(("reals", None))
    for i, w in enumerate(waves):
        if w.curves is not None and w.curves.size:
            tasks.append(("curves", i))
        if run["dimension"]:  # a continuous-only run has no marginals to draw
            tasks.append(("marginals", i))
    _JOB.update(waves=waves, run=run, estimator=estimator, out=out, formats=formats)
    workers = min(len(tasks), os.cpu_count() or 1, 8)
    report = progress or (lambda done, total: None)
    report(0, len(tasks))
    names = [""] * len(tasks)
    if workers > 1 and "fork" in multiprocessing.get_all_start_methods():
        # Longest first (the overview) so that the pool finishes together; names in task order.
        order = sorted(range(len(tasks)), key=lambda i: tasks[i][0] != "overview")
        with multiprocessing.get_context("fork").Pool(workers) as pool:
            for done, (i, name) in enumerate(pool.imap_unordered(
                    _render_indexed, [(i, tasks[i]) for i in order], chunksize=1), 1):
                names[i] = name
                report(done, len(tasks))
        return names
    for i, task in enumerate(tasks):
        names[i] = _render(task)
        report(i + 1, len(tasks))
    return names


def _render_indexed(item):
    index, task = item
    return index, _render(task)
