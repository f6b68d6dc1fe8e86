#!/usr/bin/python3
"""The report script (scripts/report/combabc_report.py) on small hand-made exports: what it draws
from summary.json, particles.csv and curves.csv alone.

    report_script_test.py SCRIPTS_REPORT_DIR WORKDIR

Exit 77 (CTest SKIP_RETURN_CODE) when this python lacks numpy or matplotlib.
"""

import csv
import json
import os
import shutil
import subprocess
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPTS = sys.argv.pop(1) if len(sys.argv) > 1 else os.path.join(HERE, "..", "..", "scripts",
                                                                    "report")
WORKDIR = sys.argv.pop(1) if len(sys.argv) > 1 else "/tmp/combabc-report-script-test"
SCRIPT = os.path.join(SCRIPTS, "combabc_report.py")

try:
    import numpy as np
    import matplotlib  # noqa: F401
except ImportError:
    sys.exit(77)

NAMES = ["inlet valve", "pump B", "sensor <3>"]
X = np.linspace(0.0, 90.0, 31)            # positions, cm
WINDOW = (X >= 40.0) & (X <= 60.0)         # what was measured
PYTHON_SCALE = 7.5                          # a Problem's data and outputs, as the simulator gives


def curve(bits, peak):
    """A bump at 20 cm of height `peak` plus a small one in the window shaped by the bits."""
    return peak * np.exp(-((X - 20.0) / 6.0) ** 2) + (1.0 + 0.3 * bits[0] - 0.2 * bits[1]) * \
        np.exp(-((X - 50.0) / 8.0) ** 2)


def write_export(folder, *, peak, bit_columns="names", checks=None, simulator="command",
                 python=False):
    """A 3-bit run of two complete waves of 12 particles each, with curves. python: as a
    Problem's run (a simulator written in Python) stores it: no config, outputs at their index
    (position unit "index"), the data as observed (7.5 times the true curve: not normalised)."""
    if os.path.exists(folder):
        shutil.rmtree(folder)
    os.makedirs(folder)
    rng = np.random.default_rng(3)
    waves, particles, curves = [], [], []
    for wave in (1, 2):
        bits = (rng.random((12, 3)) < [0.9, 0.5, 0.0]).astype(int)
        bits[:, 2] = 0  # P = 0 for the third bit: its bar must still show
        for i, b in enumerate(bits):
            particles.append([wave, i, "".join(map(str, b)), *b, -0.1 * i, 1 / 12, 0.01 * i])
            curves.append([wave, i, *curve(b, peak)])
        waves.append({"wave": wave, "thresholds": [0.1 / wave], "phi": None, "candidates": 40,
                      "accepted": 12, "failures": 0, "acceptance_rate": 0.3, "complete": True,
                      "ess": 11.0, "distinct": 4, "wall_seconds": 0.1,
                      "marginals_paper": bits.mean(axis=0).tolist(),
                      "marginals_importance": bits.mean(axis=0).tolist(),
                      "reals_mean": [], "reals_sd": []})
    columns = NAMES if bit_columns == "names" else [f"bit_{k}" for k in range(3)]
    with open(os.path.join(folder, "particles.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["wave", "index", "bits", *columns, "log_weight", "weight", "d_least_squares"])
        w.writerows(particles)
    truth = curve(np.array([1, 0, 0]), peak)
    if python:  # the data are the true curve as the simulator gives it: particle 0's of wave 2
        curves[12][2:] = truth
        for row in curves:
            row[2:] = PYTHON_SCALE * np.asarray(row[2:])
    with open(os.path.join(folder, "curves.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["wave", "index", *[f"y_{i}" for i in range(X.size)]])
        w.writerows(curves)
    xs, unit = (np.arange(X.size, dtype=float), "index") if python else (X, "cm")
    with open(os.path.join(folder, "positions.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["column", f"position_{unit}"])
        w.writerows([f"y_{i}", x] for i, x in enumerate(xs))
    scale = PYTHON_SCALE if python else 1.0 / truth[WINDOW].max()
    with open(os.path.join(folder, "measured.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow([f"position_{unit}", "value"])
        w.writerows([x, y * scale] for x, y in zip(xs[WINDOW], truth[WINDOW]))
    summary = {
        "format": "combabc-export", "schema_version": 6,
        "run": {"status": "finished", "termination": "max_waves", "message": "", "config_path": "",
                "combabc_version": "test", "git_hash": "", "seed": 1, "threads": 1,
                "start_time": "", "end_time": "", "resume_count": 0, "estimator": "paper",
                "dimension": 3, "position_unit": unit, "waves_completed": 2, "simulations": 80,
                "simulations_discarded": 0, "failures": 0, "wall_seconds": 0.2},
        "config_text": "" if python else
        f'[simulator]\nkind = "{simulator}"\n[output]\nfigures = ["svg"]\n',
        "bit_names": NAMES, "bit_prior_one": [0.5, 0.5, 0.5],
        "distance_components": [{"name": "least squares", "kind": "threshold", "required": 1}],
        "reals": [], "stop_limits": {},
        "experiments": [{"name": "", "description": "", "outputs": int(X.size),
                         "measured": int(WINDOW.sum()), "components": 1, "first_output": 0,
                         "first_measured": 0, "first_component": 0}],
        "waves": waves}
    if checks is not None:
        summary["checks"] = checks
    if python:  # the answer of its last wave, as the export writes it
        summary["answer"] = {
            "wave": 2, "complete": True, "estimator": "paper", "verdict_level": 0.95,
            "bits": [{"number": k + 1, "name": name, "position": None, "edge": None,
                      "start_m": None, "end_m": None, "p_one": p, "mc_se": 0.05,
                      "verdict": verdict}
                     for k, (name, p, verdict) in enumerate(zip(
                         NAMES, waves[1]["marginals_paper"], ("fixed", "not determined",
                                                              "free")))],
            "top_configurations": [], "exact": False, "particles": 12, "distinct": 4,
            "per_wave": []}
    with open(os.path.join(folder, "summary.json"), "w") as f:
        json.dump(summary, f)


def report(export, out, formats=()):
    result = subprocess.run([sys.executable, SCRIPT, "--out", out, export,
                             *(["--formats", ",".join(formats)] if formats else [])],
                            capture_output=True, text=True, env=dict(os.environ, MPLBACKEND="Agg"))
    return result


def axes_in(svg_path):
    with open(svg_path, encoding="utf-8") as f:
        return f.read().count('<g id="axes_')


def read(path):
    with open(path, encoding="utf-8") as f:
        return f.read()


CHECKS = {"before": [], "after": [], "fit": [{"experiment": "", "best_rms": 0.02,
                                             "noise_sigma": 0.01, "ratio": 2.0,
                                             "verdict": "poor"}],
          "predictive": [{"experiment": "", "positions_m": [40, 50, 60],
                          "measured": [0.2, 1.0, 0.2], "band_low": [0.1, 0.8, 0.1],
                          "band_high": [0.3, 1.2, 0.3], "median": [0.2, 1.0, 0.2],
                          "best": [0.2, 1.0, 0.2], "residuals": [0.0, 0.0, 0.0]}]}


def draw(name, formats=(), **export_options):
    export, out = os.path.join(WORKDIR, name, "export"), os.path.join(WORKDIR, name, "out")
    write_export(export, **export_options)
    result = report(export, out, formats)
    if result.returncode != 0:
        raise AssertionError(f"{name}: exit {result.returncode}: {result.stderr}")
    return out


class ReportScript(unittest.TestCase):
    # Two reports: a peak far outside the measured window with the bit columns named by the bits
    # (the export's convention), and a peak inside it with the old bit_k columns and the checks.
    @classmethod
    def setUpClass(cls):
        cls.peaked = draw("peaked", peak=100.0)
        cls.plain = draw("plain", peak=0.0, bit_columns="bit_k", checks=CHECKS)

    def test_bars_are_labelled_with_the_bit_names_and_zero_bars_show(self):
        for out in (self.peaked, self.plain):
            svg = read(os.path.join(out, "wave_2_marginals.svg"))
            for name in ("inlet valve", "pump B", "sensor &lt;3&gt;"):
                self.assertIn(name, svg)
            self.assertNotIn("Edge 1", svg)
            self.assertNotIn("Parameter number", svg)
            self.assertEqual(axes_in(os.path.join(out, "wave_2_marginals.svg")), 1)
            # The P = 0 bar: a thick line on the axis in the bars' colour.
            self.assertIn("stroke: #3a7d44; stroke-width: 2.5", svg)

    def test_a_joint_run_says_which_experiment_decided_which_clamp_and_one_run_does_not(self):
        # campaign.csv, which `combabc export` writes for a joint run of the sensor only, makes
        # the section; without it (one experiment) the page has none.
        sys.path.insert(0, SCRIPTS)
        try:
            import combabc_report as script
            import combabc_report_page as page
        finally:
            sys.path.pop(0)
        single = os.path.join(WORKDIR, "peaked", "export")
        joint = os.path.join(WORKDIR, "joint", "export")
        shutil.rmtree(joint, ignore_errors=True)
        shutil.copytree(single, joint)
        with open(os.path.join(joint, "campaign.csv"), "w", newline="") as f:
            f.write('clamp,name,edge,from_cm,to_cm,p_fixed_run,p_fixed_together,'
                    '"p_fixed_alone:left","p_fixed_alone:right",decided_by\n'
                    '1,"inlet valve",1,0,30,0.98,0.99,0.97,0.52,"left"\n'
                    '2,"pump B",1,30,60,0.5,0.55,0.5,0.5,""\n'
                    '3,"sensor <3>",1,60,90,0.02,0.01,0.6,0.03,"right"\n')
        pages = {}
        for name, export in (("single", single), ("joint", joint)):
            run, waves = script.load_export(export)
            run["sensor"] = True
            pages[name] = page.page_html(waves, run, "paper", [], ("svg",), "history.sqlite")
        self.assertNotIn("Which experiment decided which clamp", pages["single"])
        html = pages["joint"]
        self.assertIn("Which experiment decided which clamp", html)
        self.assertIn("<li>left alone: clamps 1</li>", html)
        self.assertIn("<li>right alone: clamps 3</li>", html)
        self.assertIn("<li>undecided in the run: clamps 2</li>", html)
        self.assertIn("<th>left alone</th><th>right alone</th>", html)
        self.assertIn("edge 1, 60-90 cm", html)
        # The page is the single run's with the section added, nothing else changed.
        start = html.index('<h2 id="campaign">')
        end = html.index("</table>", start) + len("</table>\n")
        self.assertEqual(html[:start] + html[end:], pages["single"])

    def test_a_peak_outside_the_window_gets_a_zoom_panel(self):
        svg = read(os.path.join(self.peaked, "wave_2_curves.svg"))
        self.assertEqual(axes_in(os.path.join(self.peaked, "wave_2_curves.svg")), 2)
        self.assertIn("Zoom on the measured window", svg)
        self.assertEqual(axes_in(os.path.join(self.plain, "wave_2_curves.svg")), 1)
        # The overview: per wave the curves, their zoom, the marginals; without the zoom column
        # when the peak is inside the window.
        self.assertEqual(axes_in(os.path.join(self.peaked, "overview.svg")), 2 * 3)
        self.assertEqual(axes_in(os.path.join(self.plain, "overview.svg")), 2 * 2)

    def test_predictive_band_from_the_curves(self):
        svg = read(os.path.join(self.peaked, "predictive.svg"))
        self.assertEqual(axes_in(os.path.join(self.peaked, "predictive.svg")), 2)  # band, residuals
        self.assertIn("Posterior predictive check (wave 2)", svg)
        self.assertIn('href="predictive.svg"', read(os.path.join(self.peaked, "index.html")))

    def test_predictive_band_from_summary_checks(self):
        svg = read(os.path.join(self.plain, "predictive.svg"))
        self.assertIn("fit poor: best RMS / noise = 2", svg)
        self.assertNotIn("(wave ", svg)  # not the script's own computation
        self.assertIn("<h2>Checks</h2>", read(os.path.join(self.plain, "index.html")))

    def test_a_noise_estimate_of_zero_draws(self):
        # summary.json writes the fit's non-finite ratio (noise 0: noise-free data) as null.
        checks = {**CHECKS, "fit": [{**CHECKS["fit"][0], "noise_sigma": 0.0, "ratio": None}]}
        out = draw("noise_free", peak=0.0, checks=checks)
        self.assertIn("best RMS / noise = nan", read(os.path.join(out, "predictive.svg")))

    def test_refuses_a_folder_with_files_and_needs_an_export(self):
        result = report(os.path.join(WORKDIR, "plain", "export"), self.plain)
        self.assertEqual(result.returncode, 73, result.stderr)
        self.assertEqual(len(result.stderr.strip().splitlines()), 1, result.stderr)
        result = report(os.path.join(WORKDIR, "no-such-export"), os.path.join(WORKDIR, "x"))
        self.assertEqual(result.returncode, 66, result.stderr)


class ProblemRun(unittest.TestCase):
    """A Problem's run (a simulator written in Python; no config): bits, outputs and data in the
    problem's terms, not the sensor's."""

    @classmethod
    def setUpClass(cls):
        cls.out = draw("python", formats=("svg",), peak=0.0, python=True)

    def has(self, name, *words, absent=()):
        """Whether the drawn file holds every one of `words` and none of `absent` (said short:
        an SVG is long)."""
        text = read(os.path.join(self.out, name))
        self.assertEqual([w for w in words if w not in text], [], f"{name} lacks them")
        self.assertEqual([w for w in absent if w in text], [], f"{name} has them")

    def test_bits_are_bits_with_their_names(self):
        sensor_words = ("clamp", "Clamp", "Edge 1", "P(fixed)")
        for name in ("wave_2_marginals.svg", "overview.svg", "answer.svg"):
            self.has(name, "pump B", "P(bit = 1)", absent=sensor_words)
        self.has("wave_2_marginals.svg", "P(bit = 1) per bit")
        self.has("index.html", "P(bit = 1) ± SE", "bit = 1: inlet valve",
                 absent=sensor_words + ('class="strip"',))

    def test_outputs_against_their_index_unscaled(self):
        self.has("wave_2_curves.svg", "Output index",
                 absent=("Position along sensor", "Normalised", "(cm)"))

    def test_the_data_and_the_curves_share_one_scale(self):
        # A perfect fit (wave 2's particle 0 is the data) is drawn on the data: the curves are not
        # rescaled to peak 1 while the data keep the simulator's scale.
        sys.path.insert(0, SCRIPTS)
        try:
            import combabc_report as script
        finally:
            sys.path.pop(0)
        run, waves = script.load_export(os.path.join(WORKDIR, "python", "export"))
        script.scale_like_the_metric(run, waves)
        at_data = np.interp(run["measured_x_cm"], run["x_cm"], waves[1].curves[0])
        np.testing.assert_allclose(at_data, run["measured_y"], rtol=1e-12)
        self.assertGreater(run["measured_y"].max(), 2.0)  # not a normalised profile

if __name__ == "__main__":
    shutil.rmtree(WORKDIR, ignore_errors=True)
    os.makedirs(WORKDIR)
    unittest.main()
