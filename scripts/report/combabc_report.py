#!/usr/bin/python3
"""Report figures for a combabc run history (RUN.sqlite), after Shamas et al. (Sensors 2024), section 5.

    /usr/bin/python3 combabc_report.py [--out DIR] [--overwrite] [--estimator paper|importance]
                                       [--formats png,svg,pdf] [--] RUN.sqlite

Reads the SQLite history directly (schema: docs/history.md; no export needed) and writes into
DIR (default: report/ beside RUN.sqlite), in each format of the run's [output] figures (default png):

  wave_<k>_curves.<fmt>         accepted simulated curves of wave k, measured data as circles
                                (paper Figures 3, 5, 8, 10); one panel per experiment when the
                                run has named experiments ([[experiment]] tables)
  wave_<k>_marginals.<fmt>      probability of each clamp being fixed, one panel per edge
                                (paper Figures 4, 6, 9, 11)
  overview.<fmt>                one row per wave: curves (a column per named experiment) and
                                marginals side by side
  summary.<fmt>                 thresholds, acceptance rate and simulations per wave
  reals.<fmt>                   runs with continuous parameters only: each parameter's accepted
                                values per wave (weighted histograms under the estimator) over
                                its prior's range
  index.html                    all of the above with the run's provenance and per-wave table

DIR follows combabc's rule for output directories (docs/history.md, "Output files"): created if
missing; a previous report there (listed in its .combabc-manifest) is replaced file by file; a
non-empty directory combabc did not write is refused unless --overwrite, which then replaces only
same-named files. Nothing else is ever deleted. Every failure is one line on stderr and a sysexits
status: 65 not a history, 66 missing, 69 numpy/matplotlib missing, 73 DIR refused, 74 I/O, 70 bug.

Waves are numbered from 1 in the figures, as in the paper (wave t = 0 of the engine is "Wave 1").
Works on a run still in progress or killed (its last wave is shown as incomplete) and on runs
that did not keep simulated outputs (no curve figures). Needs numpy and matplotlib only.
"""

import argparse
import html
import multiprocessing
import os
import shutil
import sqlite3
import sys
import tempfile
import textwrap
import tomllib

# sysexits.h, as combabc uses them (combabc maps the script's status to its own error kinds).
EX_DATAERR, EX_NOINPUT, EX_UNAVAILABLE, EX_SOFTWARE, EX_CANTCREAT, EX_IOERR = 65, 66, 69, 70, 73, 74

try:
    import numpy as np

    import matplotlib

    matplotlib.use("Agg")  # files only; never needs a display
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch
    from matplotlib.ticker import FuncFormatter, LogLocator, MaxNLocator
except ImportError as missing:
    print(f"combabc_report: the report needs numpy and matplotlib for {sys.executable} "
          f"({missing}); on Debian: apt-get install python3-numpy python3-matplotlib, "
          "or set COMBABC_PYTHON to a python that has them", file=sys.stderr)
    sys.exit(EX_UNAVAILABLE)

# v2 added wave.discarded, wave.content_hash and checksum rows in meta; v3 the continuous
# parameters (table real, particle.reals, wave.reals_mean / reals_sd), the proposal options and
# the fingerprint; v4 the failed simulations (table failure, wave.failures); v5 the meta row
# wave_count (nothing the report reads); v6 the table experiment (the run's experiments, as slices
# of output_position, measured and component). Older files read as runs without reals, without
# failures and of one unnamed experiment holding everything.
SCHEMA_VERSION = 6
APPLICATION_ID = 0x43424142  # 'CBAB', written by HistoryStore::Create
CM_PER_UNIT = {"m": 100.0, "cm": 1.0, "mm": 0.1, "um": 1e-4, "nm": 1e-7}
DPI = 150
FORMATS = ("png", "svg", "pdf")  # what [output] figures may list
MANIFEST = ".combabc-manifest"   # the files combabc wrote in a directory (core/output_files.hpp)
TEMPORARY_PREFIX = ".combabc-tmp-"  # every combabc temporary; alone, they leave a directory empty

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
MEASURED_STYLE = dict(marker="o", markersize=4.5, markerfacecolor="white", markeredgecolor="black",
                      markeredgewidth=0.9, linestyle="none", zorder=5)


class ReportError(Exception):
    """A failure to report as one line, with the sysexits status to exit with."""

    def __init__(self, message, status=EX_DATAERR):
        super().__init__(message)
        self.status = status


# --- reading the history ------------------------------------------------------------------------

def doubles(blob):
    return np.frombuffer(blob, dtype="<f8") if blob else np.zeros(0)


def connect(path):
    if not os.path.isfile(path):
        raise ReportError(f"{path}: no such run history", EX_NOINPUT)
    # SQLite refuses a `..` that climbs above `/` ("/../RUN.sqlite"), which the kernel reads as `/`
    # (history_sqlite.cpp does the same).
    if ".." in path.split(os.sep):
        path = os.path.realpath(path)
    # mode=ro: a report never writes. A WAL-mode history (run in progress or killed) needs its
    # -shm file, which a read-only connection cannot create; then fall back to a normal one.
    try:
        con = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
        con.execute("PRAGMA user_version").fetchone()
    except sqlite3.Error:
        con = sqlite3.connect(path)
    try:
        app = con.execute("PRAGMA application_id").fetchone()[0]
        version = con.execute("PRAGMA user_version").fetchone()[0]
    except sqlite3.DatabaseError as error:
        raise ReportError(f"{path}: not a combabc run history ({error})")
    if app != APPLICATION_ID or version < 1:
        raise ReportError(f"{path}: not a combabc run history")
    if version > SCHEMA_VERSION:
        raise ReportError(f"{path}: run history schema version {version} is newer than this "
                          f"script reads ({SCHEMA_VERSION})")
    return con


class Wave:
    def __init__(self):
        self.number = 0  # engine's wave index t (0-based)
        self.thresholds = np.zeros(0)
        self.candidates = 0
        self.failures = 0
        self.accepted = 0
        self.acceptance_rate = float("nan")
        self.complete = False
        self.ended = False
        self.ess = float("nan")
        self.distinct = 0
        self.wall_seconds = float("nan")
        self.marginals = {}
        self.bits = None      # (n, d) uint8
        self.curves = None    # (n, points) float or None
        self.reals = None     # (n, r) float: each particle's continuous parameters
        self.log_w = None     # (n,) log p/q of each particle


def load_run(con):
    cols = ["status", "config_text", "config_path", "combabc_version", "git_hash", "seed", "threads",
            "start_time", "end_time", "termination", "message", "resume_count", "estimator",
            "dimension", "position_unit", "waves_completed", "simulations",
            "simulations_discarded", "wall_seconds"]
    row = con.execute(f"SELECT {', '.join(cols)} FROM run WHERE id = 1").fetchone()
    if row is None:
        raise ReportError("corrupt run history: no run row")
    run = dict(zip(cols, row))
    bits = con.execute("SELECT name, prior FROM bit ORDER BY bit").fetchall()
    run["bit_names"] = [name for name, _ in bits]
    run["prior"] = np.array([prior for _, prior in bits], dtype=float)
    run["components"] = con.execute(
        "SELECT name, kind FROM component ORDER BY component").fetchall()
    scale = CM_PER_UNIT.get(run["position_unit"], 1.0)
    run["x_cm"] = np.array([r[0] for r in con.execute(
        "SELECT position FROM output_position ORDER BY i")], dtype=float) * scale
    measured = np.array(con.execute("SELECT position, value FROM measured ORDER BY i").fetchall(),
                        dtype=float).reshape(-1, 2)
    run["measured_x_cm"] = measured[:, 0] * scale
    run["measured_y"] = measured[:, 1]
    run["schema_version"] = con.execute("PRAGMA user_version").fetchone()[0]
    # Stop limits a resume set over the config's (meta rows stop_limit_<key>; docs/history.md).
    run["stop_limits"] = [(key[len("stop_limit_"):], value) for key, value in con.execute(
        "SELECT key, value FROM meta WHERE substr(key, 1, 11) = 'stop_limit_' ORDER BY key")]
    run["reals"] = []
    if run["schema_version"] >= 3:
        run["reals"] = con.execute(
            "SELECT name, kind, low, high, mean, sd FROM real ORDER BY i").fetchall()
    run["experiments"] = load_experiments(con, run)
    run["named"] = any(x["name"] for x in run["experiments"])
    return run


def one_experiment(run):
    """The experiments of a run of one unnamed experiment: it holds everything."""
    return [{"name": "", "description": "", "outputs": slice(0, run["x_cm"].size),
             "measured": slice(0, run["measured_x_cm"].size),
             "components": slice(0, len(run["components"]))}]


def load_experiments(con, run):
    """The run's experiments (schema v6, table experiment), each a dict: name, description and
    the slices `outputs` (of x_cm and the curves' columns), `measured` (of the measured points)
    and `components` (of run["components"]). A file without the table (v5 and older), or whose
    counts do not add up (a checked history's always do), is one unnamed experiment holding
    everything."""
    totals = (run["x_cm"].size, run["measured_x_cm"].size, len(run["components"]))
    everything = one_experiment(run)
    if not con.execute("SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = "
                       "'experiment'").fetchone()[0]:
        return everything
    experiments, starts = [], [0, 0, 0]
    for name, description, *counts in con.execute(
            "SELECT name, description, outputs, measured, components FROM experiment ORDER BY e"):
        if any(not isinstance(c, int) or c < 0 for c in counts):
            return everything
        slices = [slice(a, a + c) for a, c in zip(starts, counts)]
        starts = [a + c for a, c in zip(starts, counts)]
        experiments.append({"name": name or "", "description": description or "",
                            "outputs": slices[0], "measured": slices[1], "components": slices[2]})
    if not experiments or tuple(starts) != totals:
        return everything
    return experiments


def load_waves(con, dimension, num_reals=0):
    rows = con.execute("""
        SELECT wave, thresholds, next_index, accepted_so_far, ended, complete, candidates,
               accepted, acceptance_rate, marginals_paper, marginals_importance, ess,
               distinct_count, wall_seconds
        FROM wave ORDER BY wave""").fetchall()
    has_failures = con.execute("SELECT count(*) FROM sqlite_master WHERE type = 'table' "
                               "AND name = 'failure'").fetchone()[0] > 0
    waves = []
    for (t, thresholds, next_index, accepted_so_far, ended, complete, candidates, accepted, rate,
         m_paper, m_importance, ess, distinct, wall) in rows:
        if not ended and next_index == 0:
            break  # started, nothing committed: not part of the history
        w = Wave()
        w.number, w.thresholds, w.ended, w.complete = t, doubles(thresholds), bool(ended), bool(complete)
        if ended:
            w.candidates, w.accepted = candidates, accepted
            w.acceptance_rate = rate if rate is not None else float("nan")
            w.ess = ess if ess is not None else float("nan")
            w.distinct, w.wall_seconds = distinct, wall if wall is not None else float("nan")
            w.marginals = {"paper": doubles(m_paper), "importance": doubles(m_importance)}
        else:
            w.candidates, w.accepted = next_index, accepted_so_far
            w.acceptance_rate = accepted_so_far / next_index if next_index else float("nan")
        load_particles(con, w, dimension, num_reals)
        if has_failures:
            w.failures = con.execute("SELECT count(*) FROM failure WHERE wave = ?",
                                     (t,)).fetchone()[0]
        waves.append(w)
        if not (ended and complete):
            break  # at most one incomplete wave, and it is the last
    return waves


def load_particles(con, wave, dimension, num_reals=0):
    # particle.reals exists from schema v3 on; a run without reals has none to read.
    reals = "reals" if num_reals else "NULL"
    rows = con.execute(f"SELECT bits, log_weight, output, {reals} FROM particle WHERE wave = ? "
                       "ORDER BY candidate", (wave.number,)).fetchall()
    n = len(rows)
    wave.log_w = np.array([r[1] if r[1] is not None else -np.inf for r in rows], dtype=float)
    if num_reals:
        values = [doubles(r[3]) for r in rows]
        if any(v.size != num_reals for v in values):
            raise ReportError(f"corrupt run history: wave {wave.number + 1}: a particle does not "
                              f"have {num_reals} reals")
        wave.reals = np.array(values, dtype=float).reshape(n, num_reals)
    nbytes = (dimension + 7) // 8
    packed = np.frombuffer(b"".join(r[0] for r in rows), dtype=np.uint8).reshape(n, nbytes)
    wave.bits = np.unpackbits(packed, axis=1, bitorder="little")[:, :dimension]
    outputs = [r[2] for r in rows if r[2]]
    if n and len(outputs) == n:
        wave.curves = np.frombuffer(b"".join(outputs), dtype="<f8").reshape(n, -1)
    if not wave.marginals.get("paper", np.zeros(0)).size and n:
        # A wave cut short before its end: marginals from the particles, as the engine computes
        # them (paper Eq. 2 unweighted; importance weights p/q self-normalised).
        log_w = np.array([r[1] if r[1] is not None else -np.inf for r in rows])
        weights = np.exp(log_w - np.max(log_w))
        weights /= weights.sum()
        wave.marginals = {"paper": wave.bits.mean(axis=0), "importance": weights @ wave.bits}
        wave.accepted = n
        wave.ess = 1.0 / np.sum(weights ** 2)
        wave.distinct = len({row.tobytes() for row in wave.bits})


def run_config(run):
    """The run's TOML config as stored in the history (a config combabc already validated)."""
    try:
        return tomllib.loads(run["config_text"] or "")
    except tomllib.TOMLDecodeError:
        return {}


def normalised(run):
    """Whether the run's data (and so its curves) are normalised: [data] normalise, or with
    [[experiment]] tables their data.normalise (the same in every experiment)."""
    config = run_config(run)
    experiments = config.get("experiment")
    if isinstance(experiments, list) and experiments and isinstance(experiments[0], dict):
        return experiments[0].get("data", {}).get("normalise", True)
    return config.get("data", {}).get("normalise", True)


def figure_formats(run):
    """[output] figures of the run's config: the formats `combabc run` was asked for."""
    formats = run_config(run).get("output", {}).get("figures", ["png"])
    return [f for f in dict.fromkeys(formats) if f in FORMATS] or ["png"]


def scale_like_the_metric(run, waves):
    """Draws Y* as the metric compares it: when the data are normalised, each simulated curve is
    divided by its maximum over the measured positions (CompositeDistance's NormaliseOver::kData),
    so curves and circles share one scale even if the peak lies outside the measured window. Each
    experiment's curve by its own maximum over its own measured positions, as its own metric
    does."""
    if not normalised(run) or not run["measured_x_cm"].size:
        return
    for w in waves:
        if w.curves is None or not len(w.curves):
            continue
        curves = np.array(w.curves, dtype=float)
        for x in run["experiments"]:
            mx, xs = run["measured_x_cm"][x["measured"]], run["x_cm"][x["outputs"]]
            if not mx.size or not xs.size:
                continue
            part = curves[:, x["outputs"]]
            at_data = np.array([np.interp(mx, xs, c) for c in part])
            peak = np.max(np.abs(at_data), axis=1)
            peak[peak <= 0] = 1.0
            curves[:, x["outputs"]] = part / peak[:, None]
        w.curves = curves


# --- figures ------------------------------------------------------------------------------------

def wave_label(w):
    label = f"Wave {w.number + 1}"
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
    """Axis labels from the simulator's declaration: the sensor's |w| along the sensor, or an
    external simulator's declared output name ([simulator.outputs] name) at its coordinates."""
    simulator = run_config(run).get("simulator", {})
    if simulator.get("kind", "sensor") == "sensor":
        return "Position along sensor (cm)", "Normalised |w|"
    name = str(simulator.get("outputs", {}).get("name", "output"))
    return "Position (cm)", ("Normalised " if normalised(run) else "") + name


def draw_curves(ax, w, run, experiment=None):
    """The wave's accepted curves and the measured circles: all of them, or one experiment's
    (an entry of run["experiments"])."""
    curves, x = w.curves, run["x_cm"]
    measured_x, measured_y = run["measured_x_cm"], run["measured_y"]
    if experiment is not None:
        curves, x = curves[:, experiment["outputs"]], x[experiment["outputs"]]
        measured_x = measured_x[experiment["measured"]]
        measured_y = measured_y[experiment["measured"]]
    if curves.shape[1] != x.size:
        x = np.arange(curves.shape[1], dtype=float)
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
    ax.set_xlim(x.min(), x.max())
    top = max(1.0, float(np.nanmax(curves)) if n else 1.0,
              float(measured_y.max()) if measured_y.size else 1.0)
    ax.set_ylim(0.0, 1.05 * top)
    xlabel, ylabel = output_labels(run)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, linewidth=0.4, alpha=0.4)


def edges(run):
    """Bit index ranges, one per panel: two edges of clamps when the names say so."""
    d = run["dimension"]
    names = run["bit_names"]
    clamps = d % 2 == 0 and d >= 2 and names and all("clamp" in n.lower() for n in names)
    if clamps:
        h = d // 2
        return [(f"Edge 1 (clamps 1–{h})", range(0, h)), (f"Edge 2 (clamps {h + 1}–{d})", range(h, d))], True
    return [("All parameters", range(0, d))], False


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
        numbers = np.array(bits) + 1
        values = probabilities[list(bits)] if probabilities.size else np.full(len(bits), np.nan)
        ax.bar(numbers, values, width=0.75, color=BAR_COLOUR, edgecolor="none")
        if uniform_prior(run) is not None:
            ax.axhline(uniform_prior(run), color="black", linestyle="--", linewidth=0.9, zorder=3)
        else:
            ax.hlines(run["prior"][list(bits)], numbers - 0.45, numbers + 0.45, colors="black",
                      linestyles="--", linewidth=0.9, zorder=3)
        ax.set_ylim(0.0, 1.0)
        ax.set_xlim(numbers[0] - 0.7, numbers[-1] + 0.7)
        step = tick_step * (1 if len(numbers) <= 20 else max(1, len(numbers) // 18))
        ax.set_xticks(numbers[::step])
        ax.set_xlabel("Clamp number" if clamps else "Parameter number")
        ax.set_ylabel("P(fixed)" if clamps else "P(bit = 1)")
        if titles:
            ax.set_title(title, fontsize=10, loc=title_loc)
        ax.grid(True, axis="y", linewidth=0.4, alpha=0.4)


def save(fig, out, name):
    for fmt in _JOB["formats"]:
        # compress_level 3: PNGs a little larger than the default 6, written in a fraction of the
        # time.
        extra = {"pil_kwargs": {"compress_level": 3}} if fmt == "png" else {}
        fig.savefig(os.path.join(out, f"{name}.{fmt}"), dpi=DPI, **extra)
    plt.close(fig)
    return name


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


def curves_figure(w, run, estimator, out):
    if not run["named"]:
        fig, ax = plt.subplots(figsize=(6.4, 4.3))
        draw_curves(ax, w, run)
        ax.set_title(f"{wave_label(w)}: accepted curves{thresholds_text(w, run, compact=True)}")
        # Below the axes: inside, it would hide curves or data wherever the peak happens to be.
        ax.legend(handles=curve_handles(w.curves.shape[0], run), loc="upper center",
                  bbox_to_anchor=(0.5, -0.16), ncol=2, frameon=False)
        fig.tight_layout()
        return save(fig, out, f"wave_{w.number + 1}_curves")
    # One panel per experiment: its own scan, its curves and its measured circles.
    experiments = run["experiments"]
    cols = min(len(experiments), 3)
    rows = (len(experiments) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(5.6 * cols, 4.0 * rows + 0.9), squeeze=False)
    for j, experiment in enumerate(experiments):
        ax = axes[j // cols][j % cols]
        draw_curves(ax, w, run, experiment)
        title = experiment_title(experiment, width=64)
        eps = experiment_thresholds(w, run, experiment)
        ax.set_title(title + (f"\n{eps}" if eps else ""), fontsize=10)
    for j in range(len(experiments), rows * cols):
        axes[j // cols][j % cols].axis("off")
    fig.suptitle(f"{wave_label(w)}: accepted curves per experiment", fontsize=11)
    fig.legend(handles=curve_handles(w.curves.shape[0], run), loc="lower center", ncol=2,
               frameon=False)
    fig.tight_layout(rect=(0, 0.6 / fig.get_figheight(), 1, 1))
    return save(fig, out, f"wave_{w.number + 1}_curves")


def marginals_figure(w, run, estimator, out):
    panels, clamps = edges(run)
    width = 5.0 * len(panels) + 0.6 if clamps else max(7.0, 0.2 * run["dimension"] + 1.5)
    fig, axes = plt.subplots(1, len(panels), figsize=(width, 3.4), sharey=True, squeeze=False)
    draw_marginals(axes[0], w, run, estimator)
    what = "probability of each clamp being fixed" if clamps else "P(bit = 1) per parameter"
    fig.suptitle(f"{wave_label(w)}: {what} ({estimator} estimator, n = {w.accepted})",
                 fontsize=11)
    fig.legend(handles=marginal_handles(run), loc="lower center", ncol=2, frameon=False)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    return save(fig, out, f"wave_{w.number + 1}_marginals")


def estimator_weights(w, estimator):
    """The accepted particles' weights under the estimator, as the engine's statistics use them:
    equal (paper), or p/q self-normalised (importance)."""
    n = w.log_w.size
    if estimator == "paper" or n == 0 or not np.isfinite(np.max(w.log_w)):
        return np.full(n, 1.0 / max(n, 1))
    weights = np.exp(w.log_w - np.max(w.log_w))
    return weights / weights.sum()


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
            ax.hist(w.reals[:, j], bins=bins, weights=estimator_weights(w, estimator),
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


def overview_figure(waves, run, estimator, out):
    """One row per wave, like the (a)-(e) panels of the paper's Figures 3-6 side by side."""
    panels, _ = edges(run)
    has_curves = any(w.curves is not None and w.curves.size for w in waves)
    # A curve column per experiment when they are named, else one holding every curve.
    experiments = run["experiments"] if run["named"] else [None]
    curve_columns = len(experiments) if has_curves else 0
    columns = len(panels) + curve_columns
    widths = [1.3] * curve_columns + [1.0] * len(panels)
    # Shared x per column: one set of tick labels at the bottom keeps the grid legible (and fast).
    fig, axes = plt.subplots(len(waves), columns, figsize=(4.2 * columns, 2.6 * len(waves) + 0.5),
                             squeeze=False, sharex="col", gridspec_kw={"width_ratios": widths})
    tick_step = 2 if max(len(bits) for _, bits in panels) > 12 else 1
    for row, w in enumerate(waves):
        label = f"({'abcdefghijklmnopqrstuvwxyz'[row % 26]}) {wave_label(w)}"
        for column, experiment in enumerate(experiments[:curve_columns]):
            ax = axes[row][column]
            if w.curves is not None and w.curves.size:
                draw_curves(ax, w, run, experiment)
            else:
                ax.text(0.5, 0.5, "no curves stored", ha="center", va="center",
                        transform=ax.transAxes)
            if column == 0:
                ax.set_title(f"{label}{thresholds_text(w, run, compact=True)}", loc="left")
            if experiment is not None:
                ax.set_title(experiment["name"], loc="right", fontsize=9)
        bar_axes = axes[row][curve_columns:]
        # Without a curve column the wave label takes the left of the first title line.
        draw_marginals(bar_axes, w, run, estimator, tick_step=tick_step, titles=row == 0,
                       title_loc="center" if has_curves else "right")
        if not has_curves:
            bar_axes[0].set_title(label, loc="left")
        if row != len(waves) - 1:
            for ax in axes[row]:
                ax.set_xlabel("")
    handles = (curve_handles(0, run) if has_curves else []) + marginal_handles(run)
    fig.legend(handles=handles, loc="upper center", ncol=len(handles), frameon=False)
    fig.tight_layout(rect=(0, 0, 1, 1.0 - 0.45 / fig.get_figheight()))
    return save(fig, out, "overview")


def summary_figure(waves, run, estimator, out):
    numbers = np.array([w.number + 1 for w in waves])
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
    ax.set_ylim(0.0, max(1.0, np.nanmax(rate) * 1.15) if rate.size else 1.0)
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


# --- index.html ---------------------------------------------------------------------------------

def fmt(value, spec=".4g"):
    if value is None:
        return ""
    if isinstance(value, float):
        return "" if np.isnan(value) else format(value, spec)
    return str(value)


def figure_html(name, formats):
    """A figure shown as PNG (or SVG, which browsers also draw inline), linked in every format."""
    e = html.escape
    links = ", ".join(f'<a href="{e(name)}.{f}">{f.upper()}</a>' for f in formats)
    shown = next((f for f in ("png", "svg") if f in formats), None)
    image = (f'<a href="{e(name)}.{shown}"><img src="{e(name)}.{shown}" alt="{e(name)}"></a>'
             if shown else "")
    return f"<figure>{image}<figcaption>{e(name)} ({links})</figcaption></figure>"


def write_index(waves, run, estimator, out, written, db_path, formats):
    e = html.escape
    provenance = [
        ("Run history", os.path.abspath(db_path)), ("Status", run["status"]),
        ("Termination", run["termination"] or "—"), ("Message", run["message"] or "—"),
        ("Config", run["config_path"] or "—"), ("Seed", run["seed"]), ("Threads", run["threads"]),
        ("Estimator", run["estimator"]), ("Estimator shown", estimator),
        ("Dimension", run["dimension"]),
        ("Simulations", run["simulations"] if run["simulations"] is not None
         else sum(w.candidates for w in waves)),
        ("Failed simulations", sum(w.failures for w in waves)),
        ("Wall time (s)", fmt(run["wall_seconds"], ".1f")),
        ("Started", run["start_time"]), ("Ended", run["end_time"] or "—"),
        ("Resumed", f"{run['resume_count']} times"),
        ("Stop limits set on resume", ", ".join(f"{k} = {v}" for k, v in run["stop_limits"])
         or "—"),
        ("combabc", f"{run['combabc_version']} {run['git_hash']}".strip()),
    ]
    rows = "\n".join(f"<tr><th>{e(str(k))}</th><td>{e(str(v))}</td></tr>" for k, v in provenance)
    head = ("<tr><th>Wave</th><th>Thresholds</th><th>Candidates</th><th>Failed</th><th>Accepted</th>"
            "<th>Acceptance rate</th><th>ESS</th><th>Distinct</th><th>Wall time (s)</th>"
            "<th>Complete</th></tr>")
    body = "\n".join(
        f"<tr><td>{w.number + 1}</td><td>{e(', '.join(format(x, '.4g') for x in w.thresholds))}</td>"
        f"<td>{w.candidates}</td><td>{w.failures}</td><td>{w.accepted}</td>"
        f"<td>{fmt(w.acceptance_rate)}</td>"
        f"<td>{fmt(float(w.ess), '.1f')}</td><td>{w.distinct}</td>"
        f"<td>{fmt(w.wall_seconds, '.2f')}</td><td>{'yes' if w.complete else 'no'}</td></tr>"
        for w in waves)
    figures = "\n".join(figure_html(n, formats) for n in written)
    experiments = ""
    if run["named"]:  # a single unnamed experiment's page is as it was before experiments
        listed = "\n".join(
            f"<tr><td>{e(x['name'])}</td><td>{e(x['description'])}</td>"
            f"<td>{x['outputs'].stop - x['outputs'].start}</td>"
            f"<td>{x['measured'].stop - x['measured'].start}</td>"
            f"<td>{e(', '.join(name for name, _ in run['components'][x['components']]))}</td></tr>"
            for x in run["experiments"])
        experiments = ("<h2>Experiments</h2><table><tr><th>Experiment</th><th>Description</th>"
                       "<th>Outputs</th><th>Measured points</th><th>Distance components</th></tr>"
                       f"\n{listed}</table>\n")
    note = ("" if any(w.curves is not None for w in waves)
            else "<p>This run did not keep simulated outputs: no curve figures.</p>")
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>combabc report</title>
<style>
body {{ font-family: sans-serif; margin: 2em; max-width: 1400px; }}
table {{ border-collapse: collapse; margin-bottom: 1.5em; }}
th, td {{ border: 1px solid #ccc; padding: 3px 8px; text-align: left; font-size: 0.9em; }}
figure {{ display: inline-block; margin: 0.5em; vertical-align: top; }}
img {{ max-width: 680px; border: 1px solid #eee; }}
pre {{ background: #f6f6f6; padding: 1em; overflow-x: auto; }}
</style></head><body>
<h1>combabc run report</h1>
<h2>Run</h2><table>{rows}</table>
{experiments}<h2>Waves</h2><table>{head}{body}</table>
{note}
<h2>Figures</h2>
{figures}
<h2>Configuration</h2><pre>{e(run["config_text"])}</pre>
</body></html>
"""
    with open(os.path.join(out, "index.html"), "w", encoding="utf-8") as f:
        f.write(page)


# --- rendering in parallel -----------------------------------------------------------------------

_JOB = {}  # what the forked workers render from (inherited, not pickled)


def _render(task):
    kind, index = task
    waves, run, estimator, out = _JOB["waves"], _JOB["run"], _JOB["estimator"], _JOB["out"]
    with plt.rc_context(STYLE):
        if kind == "overview":
            return overview_figure(waves, run, estimator, out)
        if kind == "summary":
            return summary_figure(waves, run, estimator, out)
        if kind == "reals":
            return reals_figure(waves, run, estimator, out)
        figure = curves_figure if kind == "curves" else marginals_figure
        return figure(waves[index], run, estimator, out)


def render_all(waves, run, estimator, out, formats):
    """Renders every figure; returns their names in display order. Figures are independent, so
    they are drawn by a pool of forked processes (matplotlib text layout and PNG encoding are
    single-threaded and dominate the time)."""
    tasks = [("summary", None), ("overview", None)]
    if run["reals"] and any(w.reals is not None and w.reals.shape[0] for w in waves):
        tasks.append(("reals", None))
    for i, w in enumerate(waves):
        if w.curves is not None and w.curves.size:
            tasks.append(("curves", i))
        tasks.append(("marginals", i))
    _JOB.update(waves=waves, run=run, estimator=estimator, out=out, formats=formats)
    workers = min(len(tasks), os.cpu_count() or 1, 8)
    if workers > 1 and "fork" in multiprocessing.get_all_start_methods():
        # Longest first (the overview) so that the pool finishes together; results keep task order.
        with multiprocessing.get_context("fork").Pool(workers) as pool:
            return pool.map(_render, tasks, chunksize=1)
    return [_render(task) for task in tasks]


# --- the output directory ------------------------------------------------------------------------
# The rules of combabc's OutputDirectory (include/combabc/core/output_files.hpp), which export uses:
# never delete, truncate or replace what combabc did not write, unless --overwrite, and then only
# files of the same names. The manifest lists what combabc wrote in a directory.

def plain_name(name):
    return name not in ("", ".", "..", MANIFEST) and not any(c in name for c in "/\n\r")


def read_manifest(out):
    """The names a previous combabc output listed in `out`, or None when it has no manifest."""
    path = os.path.join(out, MANIFEST)
    if os.path.islink(path) or not os.path.isfile(path):
        return None
    with open(path, encoding="utf-8") as f:
        lines = [line.rstrip("\n") for line in f]
    return {n for n in lines if n and not n.startswith("#") and plain_name(n)}


def open_output_directory(out, overwrite):
    """Checks `out` and creates it when missing; returns (created, names of the previous
    report's files). Changes nothing when it refuses."""
    if not os.path.lexists(out):
        parent = os.path.dirname(out)
        if not os.path.isdir(parent):
            raise ReportError(f"{out}: directory {parent} does not exist", EX_CANTCREAT)
        os.mkdir(out)
        return True, set()
    if not os.path.isdir(out):  # a symlink to a directory the user named is that directory
        raise ReportError(f"{out}: exists and is not a directory (refusing to replace it; choose "
                          "another path)", EX_CANTCREAT)
    previous = read_manifest(out)
    others = [n for n in os.listdir(out) if not n.startswith(TEMPORARY_PREFIX)]
    if previous is None and others and not overwrite:
        raise ReportError(f"{out}: directory exists, is not empty and was not written by combabc "
                          f"(it has no {MANIFEST}); choose another directory, or use --overwrite "
                          "to add combabc's files to it", EX_CANTCREAT)
    return False, previous or set()


def umask():
    """The process's umask (os.umask can only be read by setting it: set back at once)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_manifest(out, names):
    fd, temp = tempfile.mkstemp(prefix=TEMPORARY_PREFIX, suffix=MANIFEST, dir=out)
    try:
        # mkstemp makes the file 0600; the manifest gets the mode of any other file written here
        # (0666 less the umask), as the C++ side's (core/output_files.cpp) does.
        os.fchmod(fd, 0o666 & ~umask())
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write("# Files combabc wrote in this directory; combabc replaces only these here.\n")
            f.writelines(n + "\n" for n in sorted(names))
            f.flush()
            os.fsync(f.fileno())
        os.replace(temp, os.path.join(out, MANIFEST))
    except BaseException:
        os.unlink(temp)
        raise


def move_without_replacing(source, target):
    exists = ReportError(f"{target}: file exists and was not written by combabc (refusing to "
                         "replace it; use --overwrite)", EX_CANTCREAT)
    try:
        os.link(source, target)  # fails if anything is at target: nothing is ever replaced
    except FileExistsError:
        raise exists from None
    except OSError:  # a file system without hard links: checked, then renamed
        if os.path.lexists(target):
            raise exists from None
        os.rename(source, target)
        return
    os.unlink(source)


def publish(staging, out, previous, overwrite):
    """Moves the staged files into `out`: files of the previous report (listed in its manifest)
    are replaced and, when not written again, removed; any other file of the same name only with
    `overwrite`; nothing else is touched."""
    names = sorted(os.listdir(staging))
    for name in names:  # every check first, so that a refusal changes nothing
        target = os.path.join(out, name)
        if not os.path.lexists(target):
            continue
        if os.path.isdir(target) and not os.path.islink(target):
            raise ReportError(f"{target}: is a directory (refusing to replace it; move it away "
                              "or write the report elsewhere: combabc report -o DIR)",
                              EX_CANTCREAT)
        ours = name in previous and os.path.isfile(target) and not os.path.islink(target)
        if not (ours or overwrite):
            raise ReportError(f"{target}: file exists and was not written by combabc (refusing to "
                              "replace it; use --overwrite)", EX_CANTCREAT)
    # Old and new names are listed while files are swapped, so an interrupted report leaves every
    # combabc file listed; then only the new ones.
    write_manifest(out, previous | set(names))
    for name in names:
        source, target = os.path.join(staging, name), os.path.join(out, name)
        if os.path.lexists(target):
            os.replace(source, target)
        else:
            move_without_replacing(source, target)
    for name in previous - set(names):  # a previous report's file not written now (more waves)
        stale = os.path.join(out, name)
        if os.path.isfile(stale) and not os.path.islink(stale):
            os.unlink(stale)
    write_manifest(out, set(names))


# --- main ---------------------------------------------------------------------------------------

def make_report(db_path, out, estimator=None, overwrite=False, formats=None):
    con = connect(db_path)
    try:
        run = load_run(con)
        waves = load_waves(con, run["dimension"], len(run["reals"]))
        if any(w.curves is not None and w.curves.shape[1] != run["x_cm"].size for w in waves):
            # Curves that are not one value per output position cannot be cut by experiment.
            run["experiments"], run["named"] = one_experiment(run), False
        scale_like_the_metric(run, waves)
    finally:
        con.close()
    if not waves:
        raise ReportError(f"{db_path}: the run has no committed wave yet")
    estimator = estimator or run["estimator"] or "paper"
    formats = formats or figure_formats(run)
    out = os.path.abspath(out)
    created, previous = open_output_directory(out, overwrite)
    # Rendered into a private directory inside DIR (same file system, so files move by rename);
    # a failure leaves DIR as it was, and removes it only if this call created it.
    staging, published = None, False
    try:
        staging = tempfile.mkdtemp(prefix=TEMPORARY_PREFIX, dir=out)
        written = render_all(waves, run, estimator, staging, formats)
        write_index(waves, run, estimator, staging, written, db_path, formats)
        publish(staging, out, previous, overwrite)
        published = True
    finally:
        if staging:
            shutil.rmtree(staging, ignore_errors=True)  # made by mkdtemp above: only our files
        if created and not published:
            try:
                os.rmdir(out)
            except OSError:
                pass
    return out


class OneLineParser(argparse.ArgumentParser):
    """Usage errors as one line, like every other error of the script and of combabc."""

    def error(self, message):
        print(f"combabc_report: usage error: {message} (see --help)", file=sys.stderr)
        sys.exit(64)


def one_line(error):
    return " ".join(str(error).split())


def main(argv=None):
    parser = OneLineParser(description="Figures and an HTML page for a combabc run.")
    parser.add_argument("history", help="the run history, RUN.sqlite (after --, if it starts with -)")
    parser.add_argument("--out", help="output directory (default: report/ beside RUN.sqlite)")
    parser.add_argument("--overwrite", action="store_true",
                        help="write into --out even if combabc did not create it (replaces only "
                             "same-named files; nothing is deleted)")
    parser.add_argument("--estimator", choices=["paper", "importance"],
                        help="marginals to plot (default: the run's estimator)")
    parser.add_argument("--formats",
                        help="comma-separated figure formats among png, svg, pdf "
                             "(default: the run's [output] figures, else png)")
    args = parser.parse_args(argv)
    formats = None
    if args.formats is not None:
        formats = list(dict.fromkeys(f.strip() for f in args.formats.split(",") if f.strip()))
        unknown = [f for f in formats if f not in FORMATS]
        if unknown or not formats:
            parser.error(f"--formats: expected png, svg or pdf, got {args.formats!r}")
    out = args.out or os.path.join(os.path.dirname(os.path.abspath(args.history)), "report")
    try:
        out = make_report(args.history, out, args.estimator, args.overwrite, formats)
    except ReportError as error:
        print(f"combabc_report: {one_line(error)}", file=sys.stderr)
        return error.status
    except sqlite3.DatabaseError as error:
        print(f"combabc_report: {args.history}: {one_line(error)}", file=sys.stderr)
        return EX_DATAERR
    except OSError as error:
        print(f"combabc_report: {one_line(error)}", file=sys.stderr)
        return EX_IOERR
    except KeyboardInterrupt:
        return 130
    except Exception as error:  # a bug: still one line, never a traceback
        print(f"combabc_report: internal error: {type(error).__name__}: {one_line(error)}",
              file=sys.stderr)
        return EX_SOFTWARE
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
