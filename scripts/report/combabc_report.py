#!/usr/bin/python3
"""Report figures and index.html for a combabc run, after Shamas et al. (Sensors 2024), section 5.

    /usr/bin/python3 combabc_report.py --out DIR [--history LABEL] [--estimator paper|importance]
                                       [--formats png,svg,pdf] [--progress] [--] EXPORT_DIR

`combabc report` runs it: it stages the run's export (the files `combabc export` writes:
summary.json, particles.csv, curves.csv, positions.csv, measured.csv; docs/history.md, "Export") in
a private folder, runs this script on it with DIR another private folder, and then publishes DIR's
files into the report folder under combabc's output-file rules (docs/history.md, "Output files").
The script reads nothing but the export, and writes nothing but new files into DIR (created if
missing; refused unless empty), in each format of the run's [output] figures (default png):

  wave_<k>_curves.<fmt>         accepted simulated curves of wave k, measured data as circles
                                (paper Figures 3, 5, 8, 10); one panel per experiment when the
                                run has named experiments ([[experiment]] tables), and below each
                                a panel zoomed on the measured window when the simulated peak
                                lies outside it; a Problem's run (a simulator written in Python,
                                no config): against the output index, curves and data as the
                                simulator gives them
  wave_<k>_marginals.<fmt>      P(bit = 1) per bit: for the sensor, each clamp being fixed, one
                                panel per edge (paper Figures 4, 6, 9, 11); otherwise one bar per
                                bit, labelled with its name
  overview.<fmt>                one row per wave: curves (a column per named experiment, and its
                                zoom on the measured window when needed) and marginals side by side
  summary.<fmt>                 thresholds, acceptance rate and simulations per wave
  predictive.<fmt>              posterior predictive check, a column per experiment: the 5-95 %
                                band of the final complete wave's accepted curves at the measured
                                points, their median and the data, and the residuals below
  reals.<fmt>                   runs with continuous parameters only: each parameter's accepted
                                values per wave (weighted histograms under the estimator) over
                                its prior's range
  fidelity.<fmt>                multi-fidelity runs only: cheap and expensive simulations and
                                seconds per wave, the continuation probabilities each wave used,
                                and its ESS per second (summary.json's "multi_fidelity")
  answer.<fmt>                  runs with bits: the answer's P(fixed) (P(bit = 1)) per bit with one
                                standard error, coloured as the strip; for the sensor on a
                                centimetre axis, one panel per edge
  index.html                    the sensor's strip to scale (summary.json's "strip": each clamp
                                section coloured by P(fixed), the loads and scan lines), the
                                verdict line, the answer, which experiment decided which clamp
                                (a joint run's campaign.csv), the checks of summary.json, all of
                                the above with the run's provenance, and the per-wave table

Modules: this file (arguments, reading the export), combabc_report_figures.py (the figures),
combabc_report_page.py (index.html). Every failure is one line on stderr and a sysexits status:
64 usage, 65 unreadable export or no committed wave, 66 no export, 69 numpy/matplotlib missing, 73 DIR refused,
74 I/O, 70 bug. Waves are numbered from 1, as in the export and the paper. Needs numpy and
matplotlib only.
"""

import argparse
import csv
import json
import os
import sys
import tomllib

# The modules beside this script are imported from where it is installed (share/combabc/report/,
# owned by the package): no __pycache__ is written there.
sys.dont_write_bytecode = True

# sysexits.h, as combabc uses them (combabc maps the script's status to its own error kinds).
EX_USAGE, EX_DATAERR, EX_NOINPUT, EX_UNAVAILABLE, EX_SOFTWARE, EX_CANTCREAT, EX_IOERR = (
    64, 65, 66, 69, 70, 73, 74)

try:
    import numpy as np

    import combabc_report_figures as figures
except ImportError as missing:
    print(f"combabc_report: the report needs numpy and matplotlib for {sys.executable} "
          f"({missing}); on Debian: apt-get install python3-numpy python3-matplotlib, "
          "or set COMBABC_PYTHON to a python that has them", file=sys.stderr)
    sys.exit(EX_UNAVAILABLE)

import combabc_report_page as page

CM_PER_UNIT = {"m": 100.0, "cm": 1.0, "mm": 0.1, "um": 1e-4, "nm": 1e-7}
FORMATS = ("png", "svg", "pdf")  # what [output] figures may list
BAND = (5.0, 95.0)  # the predictive band's percentiles


class ReportError(Exception):
    """A failure to report as one line, with the sysexits status to exit with."""

    def __init__(self, message, status=EX_DATAERR):
        super().__init__(message)
        self.status = status


# --- reading the export ---------------------------------------------------------------------------

class Wave:
    """One wave of the export: summary.json's entry and its particles (from particles.csv)."""

    def __init__(self, entry):
        self.number = int(entry["wave"])  # from 1, as in every exported file
        self.thresholds = numbers(entry.get("thresholds"))
        self.candidates = int(entry.get("candidates") or 0)
        self.failures = int(entry.get("failures") or 0)
        self.accepted = int(entry.get("accepted") or 0)
        self.acceptance_rate = number(entry.get("acceptance_rate"))
        self.complete = bool(entry.get("complete"))
        self.ess = number(entry.get("ess"))
        self.distinct = int(entry.get("distinct") or 0)
        self.wall_seconds = number(entry.get("wall_seconds"))
        # A resample-move wave's move statistics (summary.json's "moves"); None otherwise.
        self.moves = entry.get("moves")
        self.marginals = {"paper": numbers(entry.get("marginals_paper")),
                          "importance": numbers(entry.get("marginals_importance"))}
        self.index = np.zeros(0, dtype=np.int64)
        self.bits = None      # (n, d) uint8
        self.curves = None    # (n, points) float, or None without stored outputs
        self.reals = None     # (n, r) float: each particle's continuous parameters
        self.log_w = np.zeros(0)
        self.multiplier = None      # (n,) float: multi-fidelity runs' weight multipliers
        self.weights = np.zeros(0)  # the particles' weights under the estimator shown


def number(value):
    return float("nan") if value is None else float(value)


def numbers(values):
    return np.array([number(v) for v in values or ()], dtype=float)


def read_csv(path):
    """(header, rows) of a CSV the export wrote; rows as lists of strings."""
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    if not rows:
        raise ReportError(f"{path}: empty file")
    return rows[0], rows[1:]


def bit_columns(header, bit_names, path):
    """Where particles.csv holds each bit: its column named by the bit's name (the export's
    convention), else bit_0, bit_1, ... (exports written before it)."""
    for names in (bit_names, [f"bit_{k}" for k in range(len(bit_names))]):
        if names and all(n in header for n in names) and len(set(names)) == len(names):
            return [header.index(n) for n in names]
    if not bit_names:
        return []
    raise ReportError(f"{path}: no column per bit (named as summary.json's bit_names, or bit_0...)")


def load_particles(path, waves, bit_names, real_names):
    header, rows = read_csv(path)
    try:
        at_wave, at_index = header.index("wave"), header.index("index")
        at_log_w = header.index("log_weight")
        at_reals = [header.index(n) for n in real_names]
    except ValueError as error:
        raise ReportError(f"{path}: {error}") from None
    at_bits = bit_columns(header, bit_names, path)
    # A multi-fidelity run's multipliers (docs/history.md): the weights are proportional to them.
    at_multiplier = header.index("multiplier") if "multiplier" in header else None
    by_wave = {w.number: [] for w in waves}
    for row in rows:
        if row:
            by_wave.setdefault(int(row[at_wave]), []).append(row)
    for w in waves:
        mine = by_wave[w.number]
        n = len(mine)
        w.index = np.array([int(r[at_index]) for r in mine], dtype=np.int64)
        w.log_w = np.array([float(r[at_log_w]) for r in mine], dtype=float)
        if at_multiplier is not None:
            w.multiplier = np.array([float(r[at_multiplier]) for r in mine], dtype=float)
        w.bits = np.array([[int(r[k]) for k in at_bits] for r in mine],
                          dtype=np.uint8).reshape(n, len(at_bits))
        if real_names:
            w.reals = np.array([[float(r[k]) for k in at_reals] for r in mine],
                               dtype=float).reshape(n, len(real_names))


def load_curves(path, waves, points):
    """Each wave's accepted curves, in the order of its particles, when every one was kept."""
    if not os.path.isfile(path):
        return  # the run did not keep simulated outputs
    table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2, dtype=float)
    if not table.size or table.shape[1] != 2 + points:
        return
    wave_of = table[:, 0].astype(np.int64)
    for w in waves:
        mine = table[wave_of == w.number]
        if len(mine) and len(mine) == len(w.index) and np.array_equal(
                mine[:, 1].astype(np.int64), w.index):
            w.curves = mine[:, 2:]


def load_export(folder, history=None):
    """The run (a dict) and its waves (list of Wave) from an export folder; history names the
    run in messages."""
    summary_path = os.path.join(folder, "summary.json")
    if not os.path.isfile(summary_path):
        raise ReportError(f"{folder}: no summary.json (not a combabc export)", EX_NOINPUT)
    with open(summary_path, encoding="utf-8") as f:
        summary = json.load(f)
    if summary.get("format") != "combabc-export":
        raise ReportError(f"{summary_path}: not a combabc export")
    run = dict(summary["run"])
    run["summary"] = summary
    run["config_text"] = summary.get("config_text", "")
    run["bit_names"] = list(summary.get("bit_names", []))
    run["prior"] = numbers(summary.get("bit_prior_one"))
    run["dimension"] = int(run.get("dimension", len(run["bit_names"])))
    run["components"] = [(c["name"], c["kind"]) for c in summary.get("distance_components", [])]
    run["stop_limits"] = list((summary.get("stop_limits") or {}).items())
    run["reals"] = [(r["name"], r["prior"]["kind"], number(r["prior"].get("low")),
                     number(r["prior"].get("high")), number(r["prior"].get("mean")),
                     number(r["prior"].get("sd"))) for r in summary.get("reals", [])]
    scale = CM_PER_UNIT.get(run.get("position_unit") or "m", 1.0)
    run["cm_per_unit"] = scale
    # The outputs' positions: a Problem's run without positions stores their index ("index").
    run["position_unit"] = run.get("position_unit") or "m"
    _, rows = read_csv(os.path.join(folder, "positions.csv"))
    run["x_cm"] = np.array([float(r[1]) for r in rows if r], dtype=float) * scale
    _, rows = read_csv(os.path.join(folder, "measured.csv"))
    run["measured_x_cm"] = np.array([float(r[0]) for r in rows if r], dtype=float) * scale
    run["measured_y"] = np.array([float(r[1]) for r in rows if r], dtype=float)
    run["experiments"] = experiments_of(summary, run)
    run["named"] = any(x["name"] for x in run["experiments"])
    run["config"] = run_config(run)
    run["campaign"] = load_campaign(os.path.join(folder, "campaign.csv"))
    # A multi-fidelity run's costs and continuation probabilities per wave, and their total.
    fidelity = summary.get("multi_fidelity") or {}
    run["multi_fidelity"] = list(fidelity.get("waves") or ())
    run["multi_fidelity_total"] = fidelity.get("total")
    waves = [Wave(entry) for entry in summary.get("waves", [])]
    if not waves:
        raise ReportError(f"{history or folder}: the run has no committed wave yet")
    load_particles(os.path.join(folder, "particles.csv"), waves, run["bit_names"],
                   [r[0] for r in run["reals"]])
    load_curves(os.path.join(folder, "curves.csv"), waves, run["x_cm"].size)
    return run, waves


def load_campaign(path):
    """campaign.csv (a joint run of the sensor: which experiment decided which clamp;
    docs/history.md, "Export") as {"experiments": names, "rows": one dict per clamp}, or None
    without the file."""
    if not os.path.isfile(path):
        return None
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        alone = [c[len("p_fixed_alone:"):] for c in reader.fieldnames or ()
                 if c.startswith("p_fixed_alone:")]
        rows = []
        for r in reader:
            rows.append({"clamp": int(r["clamp"]), "name": r["name"], "edge": int(r["edge"]),
                         "from_cm": float(r["from_cm"]), "to_cm": float(r["to_cm"]),
                         "run": float(r["p_fixed_run"]), "together": float(r["p_fixed_together"]),
                         "alone": [float(r["p_fixed_alone:" + x]) for x in alone],
                         "decided_by": r["decided_by"]})
    return {"experiments": alone, "rows": rows}


def one_experiment(run):
    """The experiments of a run of one unnamed experiment: it holds everything."""
    return [{"name": "", "description": "", "outputs": slice(0, run["x_cm"].size),
             "measured": slice(0, run["measured_x_cm"].size),
             "components": slice(0, len(run["components"]))}]


def experiments_of(summary, run):
    """summary.json's experiments, each a dict: name, description and the slices `outputs` (of
    x_cm and the curves' columns), `measured` (of the measured points) and `components` (of
    run["components"])."""
    listed = summary.get("experiments") or []
    experiments = [{"name": x.get("name") or "", "description": x.get("description") or "",
                    "outputs": slice(x["first_output"], x["first_output"] + x["outputs"]),
                    "measured": slice(x["first_measured"], x["first_measured"] + x["measured"]),
                    "components": slice(x["first_component"],
                                        x["first_component"] + x["components"])}
                   for x in listed]
    return experiments or one_experiment(run)


def run_config(run):
    """The run's TOML config as stored in the history (a config combabc already validated)."""
    try:
        return tomllib.loads(run["config_text"] or "")
    except tomllib.TOMLDecodeError:
        return {}


def python_run(run):
    """Whether the run is a Problem's, whose simulator is written in Python: its history has no
    config (docs/python.md)."""
    return not (run["config_text"] or "").strip()


def normalised(run):
    """Whether the run's data (and so its curves) are normalised: [data] normalise, or with
    [[experiment]] tables their data.normalise (the same in every experiment). A Problem's run
    has no config: its distance compares the simulator's outputs with the data as they are."""
    if python_run(run):
        return False
    config = run["config"]
    experiments = config.get("experiment")
    if isinstance(experiments, list) and experiments and isinstance(experiments[0], dict):
        return experiments[0].get("data", {}).get("normalise", True)
    return config.get("data", {}).get("normalise", True)


def is_sensor(run):
    """Whether the run's simulator is the built-in sensor (bits are clamps on two edges); a
    Problem's run (no config) never is."""
    if python_run(run):
        return False
    return run["config"].get("simulator", {}).get("kind", "sensor") == "sensor"


def figure_formats(run):
    """[output] figures of the run's config: the formats `combabc run` was asked for."""
    formats = run["config"].get("output", {}).get("figures", ["png"])
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


def estimator_weights(w, estimator):
    """The accepted particles' weights under the estimator, as the engine's statistics use them:
    equal (paper), or p/q self-normalised (importance); in a multi-fidelity run times each
    particle's multiplier, normalised by their signed sum (by the sum of |w| when that is not
    positive), so that some may be negative."""
    n = w.log_w.size
    if estimator == "paper" or n == 0 or not np.isfinite(np.max(w.log_w)):
        weights = np.ones(n)
    else:
        weights = np.exp(w.log_w - np.max(w.log_w))
    if w.multiplier is not None and w.multiplier.size == n:
        weights = weights * w.multiplier
    total = weights.sum()
    if not total > 0:
        total = np.abs(weights).sum()
    return weights / total if total > 0 else np.full(n, 1.0 / max(n, 1))


def weighted_quantiles(values, weights, qs):
    """Per column of values (n, m): the weighted quantiles qs (in [0, 1]), shape (len(qs), m)."""
    # A band is drawn from the positive part of signed (multi-fidelity) weights.
    weights = np.clip(weights, 0.0, None)
    order = np.argsort(values, axis=0)
    sorted_values = np.take_along_axis(values, order, axis=0)
    cumulative = np.cumsum(weights[order], axis=0)
    cumulative = (cumulative - 0.5 * weights[order]) / cumulative[-1]
    return np.array([[np.interp(q, cumulative[:, j], sorted_values[:, j])
                      for j in range(values.shape[1])] for q in qs])


def predictive_checks(run, waves):
    """The posterior predictive check per experiment, as summary.json's checks.predictive holds
    it (docs/history.md): from there when the export has it, else computed here from the final
    complete wave's accepted curves, scaled like the metric and read at the measured positions
    (band: the 5-95 % weighted quantiles under the estimator; residuals: measured - median).
    Positions in cm here. Empty without stored curves or measured points."""
    given = (run["summary"].get("checks") or {}).get("predictive")
    if given:
        return [dict(p, positions_cm=(np.asarray(p["positions_m"], dtype=float)
                                      * run["cm_per_unit"]).tolist(), source="summary.json")
                for p in given]
    final = next((w for w in reversed(waves) if w.complete), None)
    if final is None or final.curves is None or not len(final.curves):
        return []
    weights = final.weights
    checks = []
    for x in run["experiments"]:
        mx, my = run["measured_x_cm"][x["measured"]], run["measured_y"][x["measured"]]
        xs = run["x_cm"][x["outputs"]]
        if not mx.size or not xs.size:
            continue
        at_data = np.array([np.interp(mx, xs, c) for c in final.curves[:, x["outputs"]]])
        low, median, high = weighted_quantiles(at_data, weights,
                                               (BAND[0] / 100, 0.5, BAND[1] / 100))
        best = at_data[np.argmin(np.mean((at_data - my) ** 2, axis=1))]
        checks.append({"experiment": x["name"], "positions_cm": mx.tolist(),
                       "measured": my.tolist(), "band_low": low.tolist(),
                       "band_high": high.tolist(), "median": median.tolist(),
                       "best": best.tolist(), "residuals": (my - median).tolist(),
                       "wave": final.number, "source": "curves.csv"})
    return checks


# --- main -----------------------------------------------------------------------------------------

def print_progress(done, total):
    """One stderr line per figure drawn: `combabc report` shows them as "writing report ...", and
    keeps them out of the script's error message."""
    print(f"combabc_report: progress {done}/{total}", file=sys.stderr, flush=True)


def make_report(export, out, estimator=None, formats=None, history=None, progress=None):
    run, waves = load_export(export, history)
    if any(w.curves is not None and w.curves.shape[1] != run["x_cm"].size for w in waves):
        # Curves that are not one value per output position cannot be cut by experiment.
        run["experiments"], run["named"] = one_experiment(run), False
    scale_like_the_metric(run, waves)
    estimator = estimator or run.get("estimator") or "paper"
    formats = formats or figure_formats(run)
    run["sensor"], run["normalised"] = is_sensor(run), normalised(run)
    for w in waves:
        w.weights = estimator_weights(w, estimator)
    run["predictive"] = predictive_checks(run, waves)
    if os.path.lexists(out) and (not os.path.isdir(out) or os.listdir(out)):
        raise ReportError(f"{out}: exists and is not an empty directory (the script writes only "
                          "into a new one; `combabc report` publishes it)", EX_CANTCREAT)
    os.makedirs(out, exist_ok=True)
    written = figures.render_all(waves, run, estimator, out, formats, progress)
    page.write_index(waves, run, estimator, out, written, formats,
                     history or os.path.abspath(export))
    return out


class OneLineParser(argparse.ArgumentParser):
    """Usage errors as one line, like every other error of the script and of combabc."""

    def error(self, message):
        print(f"combabc_report: usage error: {message} (see --help)", file=sys.stderr)
        sys.exit(EX_USAGE)


def one_line(error):
    return " ".join(str(error).split())


def main(argv=None):
    parser = OneLineParser(description="Figures and an HTML page for a combabc export.")
    parser.add_argument("export", help="a combabc export folder (after --, if it starts with -)")
    parser.add_argument("--out", required=True,
                        help="the folder to write (created; refused unless missing or empty)")
    parser.add_argument("--history", help="the run history's path, shown on the page")
    parser.add_argument("--estimator", choices=["paper", "importance"],
                        help="marginals to plot (default: the run's estimator)")
    parser.add_argument("--progress", action="store_true",
                        help="a line 'combabc_report: progress DONE/TOTAL' on stderr per figure")
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
    try:
        out = make_report(args.export, args.out, args.estimator, formats, args.history,
                          print_progress if args.progress else None)
    except ReportError as error:
        print(f"combabc_report: {one_line(error)}", file=sys.stderr)
        return error.status
    except (KeyError, ValueError, IndexError) as error:
        print(f"combabc_report: {args.export}: unreadable export: {type(error).__name__}: "
              f"{one_line(error)}", file=sys.stderr)
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
