#!/usr/bin/python3
"""The report page's answer and checks tables (scripts/report/combabc_report_page.py), rendered
from a hand-made summary.json holding summary.json's "answer" and "checks" (docs/history.md,
"Export"). Standard library only: the page module needs no plotting packages.

    report_page_test.py SCRIPTS_REPORT_DIR
"""

import json
import os
import re
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, sys.argv.pop(1) if len(sys.argv) > 1 else
                os.path.join(HERE, "..", "..", "scripts", "report"))
import combabc_report_page as page  # noqa: E402


def fixture():
    with open(os.path.join(HERE, "data", "summary_answer_checks.json"), encoding="utf-8") as f:
        return json.load(f)


def compact(text):
    return " ".join(text.split())


class Wave:
    number, thresholds, candidates, failures, accepted = 2, [0.01], 700, 0, 500
    acceptance_rate, ess, distinct, wall_seconds, complete, curves = 0.7, 433.5, 90, 0.5, True, None
    moves = None


class AnswerTables(unittest.TestCase):
    def test_every_bit_with_its_position_probability_and_verdict(self):
        html = compact(page.answer_html(fixture()))
        self.assertIn("<h2>Answer</h2>", html)
        self.assertIn("From wave 2, importance estimator", html)
        self.assertIn("Verdict at level 0.95", html)
        self.assertIn('<tr class="fixed"><td class="number">1</td><td>clamp 1</td>'
                      '<td>edge 1, 0-5 cm</td><td class="number">0.983 &plusmn; 0.006</td>'
                      '<td>fixed</td></tr>', html)
        self.assertIn('<tr class="free"><td class="number">2</td><td>clamp 2</td>', html)
        # A name is text, escaped; a bit without a position gets a dash.
        self.assertIn("<td>clamp &lt;3&gt;</td><td>—</td><td class=\"number\">0.610 &plusmn; "
                      "0.030</td><td>not determined</td>", html)

    def test_top_configurations_and_per_wave_numbers(self):
        html = compact(page.answer_html(fixture()))
        self.assertIn("<h3>Most probable configurations</h3>", html)
        self.assertIn('<td class="number">1</td><td class="number">0.5875 &plusmn; 0.0210</td>'
                      "<td>clamp 1, clamp &lt;3&gt;</td><td><code>101</code></td>", html)
        self.assertIn('<td class="number">0.3751</td><td>clamp 1</td>', html)  # no SE: none shown
        # Per wave: the weights' ESS, the bits' (the smallest per-bit one; a dash for none).
        self.assertIn("<th>ESS bits (smallest)</th>", html)
        self.assertIn('<td class="number">1</td><td class="number">812.2</td>'
                      '<td class="number">640.5</td><td class="number">1000</td>', html)
        self.assertIn('<td class="number">433.5</td><td class="number">—</td>', html)

    def test_reals_with_their_errors_and_ess(self):
        # A continuous parameter: mean and sd each +- its delta-method SE, its ESS, and an ESS
        # column per wave.
        summary = fixture()
        summary["answer"]["reals"] = [{"name": "k<1>", "mean": 1.25, "mc_se": 0.012, "sd": 0.5,
                                       "sd_se": 0.0091, "ess": 377.4}]
        for w, ess in zip(summary["answer"]["per_wave"], (801.0, 377.4)):
            w["ess_reals"] = [ess]
        html = compact(page.answer_html(summary))
        self.assertIn("<td>k&lt;1&gt;</td><td class=\"number\">1.25 &plusmn; 0.012</td>"
                      "<td class=\"number\">0.5 &plusmn; 0.0091</td><td class=\"number\">377</td>",
                      html)
        self.assertIn("<th>ESS k&lt;1&gt;</th>", html)
        self.assertIn('<td class="number">640.5</td><td class="number">801.0</td>', html)

    def test_mode_loss_is_a_warning_table_only_when_flagged(self):
        html = compact(page.answer_html(fixture()))
        self.assertNotIn("lost a mode", html)
        summary = fixture()
        summary["answer"]["mode_loss"] = [
            {"wave": 2, "bits": "110", "mass": 0.0433, "proposal": 0.00061}]
        html = compact(page.answer_html(summary))
        self.assertIn("<h3>Warning: the posterior may have lost a mode</h3>", html)
        self.assertIn('<td class="number">2</td><td><code>110</code></td>'
                      '<td class="number">0.0433</td><td class="number">0.00061</td>', html)

    def test_exact_answers_and_other_simulators_say_so(self):
        summary = fixture()
        summary["answer"]["exact"] = True
        html = compact(page.answer_html(summary, sensor=False))
        self.assertIn("From the enumeration (exact)", html)
        self.assertIn("P(bit = 1) ± SE", html)

    def test_all_distinct_particles_list_no_configuration(self):
        # As on the terminal: 500 particles, 500 configurations, so each "mass" would be one
        # particle's weight; the page says that none stands out instead.
        summary = fixture()
        summary["answer"].update(particles=500, distinct=500)
        html = compact(page.answer_html(summary))
        self.assertIn("None stands out: the 500 particles are 500 distinct configurations", html)
        self.assertNotIn("<code>101</code>", html)
        summary["answer"].update(distinct=90)
        self.assertIn("<code>101</code>", compact(page.answer_html(summary)))

    def test_whole_probabilities_keep_three_decimals(self):
        # JSON writes 1.0 as 1: read back as an int, it is still shown as 1.000 +- 0.000.
        summary = fixture()
        summary["answer"]["bits"][0].update(p_one=1, mc_se=0)
        self.assertIn("1.000 &plusmn; 0.000", compact(page.answer_html(summary)))

    def test_a_tempered_answer_says_so_with_its_temperatures(self):
        summary = fixture()
        self.assertNotIn("tempered", page.answer_html(summary))
        summary["answer"].update(tempered=True, temperatures=[
            {"component": "a/least_squares[48-80cm]", "temperature": 3.9},
            {"component": "b/least_squares[0-89cm]", "temperature": None}])
        html = compact(page.answer_html(summary))
        self.assertIn("Warning: a tempered answer", html)
        self.assertIn("3.9 (a/least_squares[48-80cm]), inf (b/least_squares[0-89cm])", html)

    def test_no_answer_no_section(self):
        summary = fixture()
        del summary["answer"]
        self.assertEqual(page.answer_html(summary), "")


class CheckLists(unittest.TestCase):
    def test_warnings_before_and_after_and_the_fit_verdict(self):
        html = compact(page.checks_html(fixture()))
        self.assertIn("<h2>Checks</h2>", html)
        self.assertIn('<li class="warning"><b>warning</b> [units_mismatch]: the data&#x27;s peak '
                      "(2.1e4) is 1e4 times the prior predictive&#x27;s &lt;range&gt;</li>", html)
        self.assertIn("[threshold_below_noise]", html)
        self.assertIn("<h3>Goodness of fit</h3>", html)
        # The fixture's fit predates sigma, points and p: judged against the estimate.
        self.assertIn('<td class="number">0.0123</td><td class="number">0.0101</td>'
                      '<td>estimated</td><td class="number"></td><td class="number">1.22</td>'
                      '<td class="number"></td><td>good</td>', html)
        summary = fixture()
        summary["checks"]["fit"][0].update(sigma=0.0007, sigma_source="stated", points=33,
                                           ratio=13.1, p_value=1e-200, verdict="poor")
        html = compact(page.checks_html(summary))
        self.assertIn('<td class="number">0.0007</td><td>stated</td><td class="number">33</td>'
                      '<td class="number">13.1</td><td class="number">1e-200</td><td>poor</td>',
                      html)
        self.assertIn("<td>best-fit residuals</td>", html)

    def test_no_warnings_is_said(self):
        summary = fixture()
        summary["checks"]["after"] = []
        self.assertIn("<p>No warnings.</p>", page.checks_html(summary))

    def test_no_checks_no_section(self):
        summary = fixture()
        del summary["checks"]
        self.assertEqual(page.checks_html(summary), "")


def strip_summary():
    """The fixture on a strip of 2 sections per edge (its bits padded to 4 clamps), one load at
    60 % of the length on the centreline, scanned along edge 2."""
    summary = fixture()
    bits = summary["answer"]["bits"]
    bits.append(dict(bits[1], number=4, name="clamp 4", p_one=0.2, verdict="not determined"))
    summary["strip"] = {"length_m": 0.5, "width_m": 0.04, "clamps_per_edge": 2,
                        "experiments": [{"name": "x60", "load_x_m": 0.3, "load_y_m": 0.02,
                                         "scan_from_m": 0.1, "scan_to_m": 0.4,
                                         "scan_y_m": 0.04}]}
    return summary


def page_of(summary, sensor=True, written=("summary",)):
    run = dict(summary["run"], summary=summary, config_text=summary["config_text"],
               stop_limits=[], named=False, experiments=[], components=[], sensor=sensor)
    return page.page_html([Wave()], run, "importance", list(written), ["png"], "/r/RUN.sqlite")


class Strip(unittest.TestCase):
    def test_sections_are_coloured_by_p_fixed_with_their_verdicts(self):
        html = page.strip_html(strip_summary())
        sections = re.findall(r'<g class="section" data-clamp="(\d+)" data-edge="(\d)" '
                              r'data-p="([^"]*)" data-verdict="([^"]*)">.*?<rect [^>]*'
                              r'fill="(#[0-9a-f]{6})"', html)
        self.assertEqual([(c, edge, v) for c, edge, _, v, _ in sections],
                         [("1", "1", "fixed"), ("2", "1", "free"), ("3", "2", "not determined"),
                          ("4", "2", "not determined")])
        # The documented scale: P = 0 at rgb(242, 242, 242), 1 at rgb(27, 120, 55), linear.
        for _, _, p, _, fill in sections:
            want = [round(a + (b - a) * float(p)) for a, b in ((242, 27), (242, 120), (242, 55))]
            got = [int(fill[k:k + 2], 16) for k in (1, 3, 5)]
            # data-p is P to 2 decimals: within one step of the colour of P itself.
            self.assertTrue(all(abs(g - w) <= 1 for g, w in zip(got, want)), (p, got, want))
        self.assertEqual(page.p_colour(0.0), "#f2f2f2")
        self.assertEqual(page.p_colour(1.0), "#1b7837")

    def test_load_and_scan_line_to_scale(self):
        html = page.strip_html(strip_summary())
        plate = re.search(r'<rect class="plate" x="([\d.]+)" y="([\d.]+)" width="([\d.]+)" '
                          r'height="([\d.]+)"', html)
        x, y, width, height = (float(v) for v in plate.groups())
        self.assertAlmostEqual(height / width, 0.04 / 0.5, places=3)  # to scale
        load = re.search(r'<circle cx="([\d.]+)" cy="([\d.]+)"', html)
        self.assertAlmostEqual((float(load.group(1)) - x) / width, 0.6, places=3)
        self.assertAlmostEqual(float(load.group(2)), y + height / 2, places=1)
        scan = re.search(r'<line class="scan" data-experiment="1" x1="([\d.]+)" y1="([\d.]+)" '
                         r'x2="([\d.]+)"', html)
        self.assertAlmostEqual((float(scan.group(1)) - x) / width, 0.2, places=3)
        self.assertAlmostEqual((float(scan.group(3)) - x) / width, 0.8, places=3)
        self.assertAlmostEqual(float(scan.group(2)), y, places=1)  # along edge 2, the top
        self.assertIn("<li><b>1</b> x60: load at 30 cm, 20 mm from edge 1; scanned from 10 to "
                      "40 cm at 40 mm from edge 1</li>", html)

    def test_the_strip_verdict_and_answer_open_the_page(self):
        html = page_of(strip_summary(), written=("answer", "summary"))
        self.assertIn("<p class=\"verdict\"><b>Verdict</b> &mdash; fixed: 1; free: 2; "
                      "not determined: 3, 4</p>", html)
        order = [html.index(t) for t in ('<svg class="strip"', 'class="verdict"',
                                         "<h2>Answer</h2>", '<img src="answer.png"',
                                         "<h2>Checks</h2>", "<h2>Run</h2>", "<h2>Waves</h2>",
                                         '<img src="summary.png"')]
        self.assertEqual(order, sorted(order))

    def test_no_strip_for_other_simulators(self):
        # A Python (command) simulator's export has "strip": null; and a run that is not the
        # sensor's never draws one. The rest of the page is the same.
        summary = strip_summary()
        for html in (page_of(dict(summary, strip=None)), page_of(summary, sensor=False)):
            self.assertNotIn("<svg", html)
            self.assertIn("<h2>Answer</h2>", html)
            self.assertIn('class="verdict"', html)
        self.assertIn("bit = 1: clamp 1; bit = 0: clamp 2; not determined: clamp &lt;3&gt;, "
                      "clamp 4", page_of(summary, sensor=False))

    def test_verdict_line_counts_long_groups(self):
        summary = fixture()
        summary["answer"]["bits"] = [{"number": k, "verdict": "free"} for k in range(1, 14)]
        self.assertEqual(page.verdict_line(summary),
                         "fixed: none; free: 13 clamps; not determined: none")


class MovesTable(unittest.TestCase):
    def test_a_move_run_shows_each_waves_moves_and_a_rejection_run_none(self):
        first, moved = Wave(), Wave()
        first.number = 1
        moved.moves = {"rounds": 6, "proposed": 3000, "accepted": 930, "acceptance_rate": 0.31,
                       "independent_proposed": 1500, "independent_accepted": 210,
                       "independent_share": 0.5, "survivor_ess": 241.26, "step": 0.625}
        html = compact(page.moves_html([first, moved]))
        self.assertIn("<h2>Moves</h2>", html)
        self.assertIn('<tr><td>1</td><td colspan="8">drawn by rejection</td></tr>', html)
        self.assertIn("<tr><td>2</td><td>6</td><td>3000</td><td>930</td><td>0.31</td>"
                      "<td>0.5</td><td>210</td><td>241.3</td><td>0.625</td></tr>", html)
        self.assertEqual(page.moves_html([first]), "")


class WholePage(unittest.TestCase):
    def test_answer_and_checks_come_before_the_run_and_the_waves(self):
        html = page_of(fixture())
        self.assertLess(html.index("<h2>Answer</h2>"), html.index("<h2>Checks</h2>"))
        self.assertLess(html.index("<h2>Checks</h2>"), html.index("<h2>Run</h2>"))
        self.assertLess(html.index("<h2>Run</h2>"), html.index("<h2>Waves</h2>"))
        self.assertIn('<img src="summary.png"', html)
        self.assertIn("<td>/r/RUN.sqlite</td>", html)


if __name__ == "__main__":
    unittest.main()
