"""The report's index.html (combabc_report.py reads the export; this module writes the page).

Python's standard library only, so that the page's tables can be tested without the plotting
packages. The answer and the checks come from summary.json's "answer" and "checks" (docs/history.md,
"Export") and are shown only when the export has them.
"""

import html
import math
import os

e = html.escape

STYLE = """
body { font-family: sans-serif; margin: 2em; max-width: 1400px; }
table { border-collapse: collapse; margin-bottom: 1.5em; }
th, td { border: 1px solid #ccc; padding: 3px 8px; text-align: left; font-size: 0.9em; }
td.number { text-align: right; font-variant-numeric: tabular-nums; }
tr.fixed td { background: #e7f3e9; }
tr.free td { background: #f4f4f4; }
li.warning { color: #8a3b00; }
figure { display: inline-block; margin: 0.5em; vertical-align: top; }
img { max-width: 680px; border: 1px solid #eee; }
pre { background: #f6f6f6; padding: 1em; overflow-x: auto; }
div.strip svg { max-width: 100%; height: auto; }
p.verdict { font-size: 1.1em; }
"""


def fmt(value, spec=".4g"):
    if value is None:
        return ""
    if isinstance(value, float):
        return "" if math.isnan(value) else format(value, spec)
    return str(value)


def table(head, rows, numeric=()):
    """An HTML table: head, a list of column titles; rows, lists of (already escaped) cells, or
    (cells, class) pairs; numeric, the columns aligned right."""
    out = ["<table><tr>" + "".join(f"<th>{e(h)}</th>" for h in head) + "</tr>"]
    for row in rows:
        cells, css = row if isinstance(row, tuple) else (row, "")
        attribute = f' class="{e(css)}"' if css else ""
        out.append(f"<tr{attribute}>" + "".join(
            f'<td class="number">{c}</td>' if k in numeric else f"<td>{c}</td>"
            for k, c in enumerate(cells)) + "</tr>")
    return "\n".join(out) + "</table>\n"


def answer_html(summary, sensor=True):
    """summary.json's "answer" as tables: per bit its name, position, P(fixed) +- its Monte-Carlo
    SE and verdict; the most probable configurations with their mass; ESS and simulations per
    wave. Empty when the export has no answer."""
    answer = summary.get("answer")
    if not answer:
        return ""
    p = "P(fixed)" if sensor else "P(bit = 1)"
    level = answer.get("verdict_level")
    source = ("From the enumeration (exact)" if answer.get("exact")
              else f"From wave {answer.get('wave')}"
              + ("" if answer.get("complete", True) else " (no complete wave: incomplete)"))
    bits = answer.get("bits") or []
    parts = [f"<h2>Answer</h2>\n<p>{e(source)}, {e(str(answer.get('estimator', '')))} "
             f"estimator."]
    # A continuous-only run has no bits: no verdicts, bit table or configurations.
    if level is not None and bits:
        parts.append(f" Verdict at level {fmt(float(level), 'g')}: fixed if {e(p)} &ge; "
                     f"{fmt(float(level), 'g')}, free if {e(p)} &le; {fmt(1 - float(level), 'g')}, "
                     "else not determined.")
    parts.append("</p>\n")
    if answer.get("tempered"):
        # A noise-aware run whose answer wave is above T = 1 (stopped early by a limit, or a
        # target above 1): not the posterior under the noise model (docs/algorithm.md).
        # summary.json writes an infinite temperature (the prior's wave) as null.
        temperatures = ", ".join(
            f"{fmt(t.get('temperature'), '.3g') or 'inf'} ({t.get('component', '')})"
            for t in answer.get("temperatures") or [])
        parts.append("<h3>Warning: a tempered answer</h3>\n<p>The likelihood's temperatures in "
                     f"this wave are {e(temperatures)}: only T = 1 is the posterior under the "
                     "noise model; these numbers are a flatter, tempered one. A run stopped by a "
                     "limit goes on towards T = 1 when resumed past it.</p>\n")
    rows = []
    for bit in bits:
        verdict = str(bit.get("verdict", ""))
        p_one, se = bit.get("p_one"), bit.get("mc_se")
        shown = fmt(float(p_one), ".3f") if p_one is not None else "—"
        if se is not None:
            shown += f" &plusmn; {fmt(float(se), '.3f')}"
        rows.append(([e(fmt(bit.get("number"))), e(str(bit.get("name", ""))),
                      e(str(bit.get("position") or "—")), shown, e(verdict)],
                     {"fixed": "fixed", "free": "free"}.get(verdict, "")))
    if bits:
        parts.append(table(["#", "Name", "Position", f"{p} ± SE", "Verdict"], rows,
                           numeric=(0, 3)))
    reals = answer.get("reals") or []
    if reals:
        rows = []
        for r in reals:
            mean = fmt(float(r.get("mean", math.nan)), ".4g")
            sd = fmt(float(r.get("sd", math.nan)), ".4g")
            if not answer.get("exact"):
                if r.get("mc_se") is not None:
                    mean += f" &plusmn; {fmt(float(r['mc_se']), '.2g')}"
                if r.get("sd_se") is not None:
                    sd += f" &plusmn; {fmt(float(r['sd_se']), '.2g')}"
            ess = r.get("ess")
            rows.append([e(str(r.get("name", ""))), mean, sd,
                         e(fmt(float(ess), ".0f")) if ess is not None else "—"])
        parts.append("<h3>Continuous parameters</h3>\n<p>Standard errors by the delta method "
                     "(they see how the importance weights go with each quantity); ESS: the "
                     "mean's own effective sample size, Var/SE&sup2;.</p>\n" + table(
                         ["Name", "Posterior mean ± SE", "Posterior sd ± SE", "ESS"], rows,
                         numeric=(1, 2, 3)))
    configurations = answer.get("top_configurations") or []
    particles, distinct = answer.get("particles"), answer.get("distinct")
    if not bits:
        pass
    elif not answer.get("exact") and particles and particles > 1 and distinct == particles:
        # Every particle its own configuration: their masses are single particles' weights, which
        # say nothing of a configuration's probability (the terminal says the same).
        parts.append("<h3>Most probable configurations</h3>\n<p>None stands out: the "
                     f"{particles} particles are {particles} distinct configurations; read the "
                     f"{'clamps' if sensor else 'bits'} above.</p>\n")
    elif configurations:
        rows = []
        for rank, c in enumerate(configurations, 1):
            mass = fmt(float(c.get("mass", math.nan)), ".4f")
            if c.get("mass_se") is not None:
                mass += f" &plusmn; {fmt(float(c['mass_se']), '.4f')}"
            fixed = ", ".join(str(n) for n in c.get("fixed") or []) or "none"
            rows.append([str(rank), mass, e(fixed), f"<code>{e(str(c.get('bits', '')))}</code>"])
        title = "fixed" if sensor else "= 1"
        parts.append("<h3>Most probable configurations</h3>\n" + table(
            ["Rank", "Posterior mass", f"Bits {title}", "Bits"], rows, numeric=(0, 1)))
    per_wave = answer.get("per_wave") or []
    if per_wave:
        # Per-quantity ESS (Var/SE^2): the bits' smallest and each real's mean's, beside the
        # weights' 1/sum w^2; "—" where a wave has none (no particles, an enumeration).
        names = [str(r.get("name", "")) for r in reals]
        with_bits = bool(bits) and not answer.get("exact")

        def ess(value):
            return e(fmt(float(value), ".1f")) if value is not None else "—"
        rows = []
        for w in per_wave:
            row = [e(fmt(w.get("wave"))), ess(w.get("ess"))]
            if with_bits:
                row.append(ess(w.get("ess_bits")))
            by_real = w.get("ess_reals") or []
            row += [ess(by_real[k] if k < len(by_real) else None) for k in range(len(names))]
            rows.append(row + [e(fmt(w.get("simulations")))])
        header = (["Wave", "ESS"] + (["ESS bits (smallest)"] if with_bits else [])
                  + [f"ESS {n}" for n in names] + ["Simulations"])
        parts.append("<h3>ESS and simulations per wave</h3>\n" +
                     table(header, rows, numeric=tuple(range(len(header)))))
    lost = answer.get("mode_loss") or []
    if lost:
        # The mode-loss diagnostic (docs/algorithm.md, "Mode loss"): patterns the previous wave
        # held that a wave's proposal gave negligible probability.
        rows = [[e(fmt(f.get("wave"))), f"<code>{e(str(f.get('bits', '')))}</code>",
                 e(fmt(f.get("mass"), ".3g")), e(fmt(f.get("proposal"), ".2g"))] for f in lost]
        parts.append("<h3>Warning: the posterior may have lost a mode</h3>\n<p>Each wave's "
                     "proposal gave these patterns, which carried the mass shown in the wave "
                     "before, so little probability that the wave expected fewer than one "
                     "particle of them.</p>\n" +
                     table(["Wave", "Pattern", "Mass before", "Proposal probability"], rows,
                           numeric=(0, 2, 3)))
    return "".join(parts)


# The strip's colour scale: P(fixed) = 0 light grey, 1 dark green, linear in RGB between them
# (the terminal's 256-colour strip follows the same ends; docs/history.md, "The strip").
FREE_RGB = (242, 242, 242)
FIXED_RGB = (27, 120, 55)


def p_colour(p):
    """The strip's colour of P(fixed) = p, as "#rrggbb"; grey for an unknown p."""
    if p is None or not math.isfinite(float(p)):
        return "#bbbbbb"
    p = min(max(float(p), 0.0), 1.0)
    return "#" + "".join(f"{round(a + (b - a) * p):02x}" for a, b in zip(FREE_RGB, FIXED_RGB))


def verdict_line(summary, sensor=True):
    """The verdicts in one line, as the terminal prints it (export/strip.hpp, VerdictLine):
    "fixed: 12, 30; free: 10, 11; not determined: 30 clamps". Empty without bits."""
    bits = (summary.get("answer") or {}).get("bits") or []
    if not bits:
        return ""
    what = "clamps" if sensor else "bits"
    groups = {"fixed": [], "free": [], "not determined": []}
    for bit in bits:
        label = str(bit.get("number")) if sensor else str(bit.get("name", ""))
        groups.get(str(bit.get("verdict")), groups["not determined"]).append(label)

    def group(title, members):
        if not members:
            return f"{title}: none"
        if len(members) > VERDICT_LINE_LIST:
            return f"{title}: {len(members)} {what}"
        return f"{title}: " + ", ".join(members)
    titles = ("fixed", "free") if sensor else ("bit = 1", "bit = 0")
    return "; ".join([group(titles[0], groups["fixed"]), group(titles[1], groups["free"]),
                      group("not determined", groups["not determined"])])


VERDICT_LINE_LIST = 12  # as kVerdictLineList: a group lists up to this many, else counts them


def _cm(metres):
    return f"{metres * 100:.1f}".removesuffix(".0")


def strip_html(summary):
    """The sensor strip to scale (summary.json's "strip"), as inline SVG: the plate, its two rows of
    clamp sections coloured by P(fixed) (edge 2 above, edge 1 below) with their numbers, P and
    verdicts, each experiment's load (a numbered dot) and scan line (dashed), a centimetre axis and
    the colour scale; then a line per experiment. Empty when the export has no strip (simulators
    other than the sensor) or its bits are not the strip's clamps."""
    strip = summary.get("strip")
    bits = (summary.get("answer") or {}).get("bits") or []
    if not strip:
        return ""
    n, length, width = int(strip["clamps_per_edge"]), float(strip["length_m"]), float(strip["width_m"])
    if n <= 0 or length <= 0 or len(bits) != 2 * n:
        return ""
    left, plot = 70.0, 900.0
    scale = plot / length  # px per metre, along and across alike: the plate to scale
    plate_h = min(max(width * scale, 12.0), 240.0)
    row_h, gap = 34.0, 14.0
    top = 24.0 + 14.0  # room for edge 2's clamp numbers
    plate_top = top + row_h
    plate_bottom = plate_top + plate_h
    axis_y = plate_bottom + row_h + 16.0
    height = axis_y + 60.0
    out = [f'<svg class="strip" xmlns="http://www.w3.org/2000/svg" width="{left + plot + 110:.0f}" '
           f'height="{height:.0f}" viewBox="0 0 {left + plot + 110:.0f} {height:.0f}" '
           'role="img" aria-label="the sensor strip with each clamp section coloured by '
           'P(fixed)" font-family="sans-serif">']
    out.append(f'<rect class="plate" x="{left}" y="{plate_top:.1f}" width="{plot}" '
               f'height="{plate_h:.1f}" fill="#fbfaf5" stroke="#555" stroke-width="1"/>')
    section = plot / n
    # Narrow sections (many clamps) show their colour alone, and every `label_step`-th number.
    texts = section >= 34
    label_step = max(1, math.ceil(22 / section))
    for k, bit in enumerate(bits):
        edge = 1 if k < n else 2
        s = k % n
        x = left + s * section
        y = plate_bottom if edge == 1 else plate_top - row_h
        p = bit.get("p_one")
        verdict = str(bit.get("verdict", ""))
        p_text = "—" if p is None else f"{float(p):.2f}"
        colour = p_colour(p)
        dark = p is not None and float(p) > 0.6
        title = (f"clamp {bit.get('number')} ({bit.get('position') or ''}): P(fixed) = {p_text}"
                 + (f" ± {float(bit['mc_se']):.3f}" if bit.get("mc_se") else "")
                 + f", {verdict}")
        stroke = ('stroke="#000" stroke-width="2.5"' if verdict == "fixed" else
                  'stroke="#999" stroke-width="0.8"')
        out.append(
            f'<g class="section" data-clamp="{e(str(bit.get("number")))}" data-edge="{edge}" '
            f'data-p="{e(p_text)}" data-verdict="{e(verdict)}"><title>{e(title)}</title>'
            f'<rect x="{x + 1:.1f}" y="{y:.1f}" width="{section - 2:.1f}" height="{row_h - 2:.1f}" '
            f'fill="{colour}" {stroke}/>'
            + (f'<text x="{x + section / 2:.1f}" y="{y + 14:.1f}" font-size="11" '
               f'text-anchor="middle" fill="{"#fff" if dark else "#000"}">{e(p_text)}</text>'
               f'<text x="{x + section / 2:.1f}" y="{y + 27:.1f}" font-size="10" '
               f'text-anchor="middle" fill="{"#fff" if dark else "#000"}">'
               f'{e({"fixed": "fixed", "free": "free"}.get(verdict, "?"))}</text>'
               if texts else "") + '</g>')
        if s % label_step == 0:
            number_y = y - 4 if edge == 2 else y + row_h + 11
            out.append(f'<text x="{x + section / 2:.1f}" y="{number_y:.1f}" font-size="10" '
                       f'text-anchor="middle" fill="#444">{e(str(bit.get("number")))}</text>')
    out.append(f'<text x="{left - 8}" y="{plate_top - row_h / 2 + 4:.1f}" font-size="12" '
               'text-anchor="end">edge 2</text>')
    out.append(f'<text x="{left - 8}" y="{plate_bottom + row_h / 2 + 4:.1f}" font-size="12" '
               'text-anchor="end">edge 1</text>')
    # Loads and scan lines, y measured from edge 1 (the bottom).
    for k, x in enumerate(strip.get("experiments") or [], 1):
        def at(x_m, y_m):
            return (left + x_m * scale,
                    plate_bottom - min(max(y_m / width, 0.0), 1.0) * plate_h if width > 0 else
                    (plate_top + plate_bottom) / 2)
        x0, y0 = at(float(x["scan_from_m"]), float(x["scan_y_m"]))
        x1, _ = at(float(x["scan_to_m"]), float(x["scan_y_m"]))
        out.append(f'<line class="scan" data-experiment="{k}" x1="{x0:.1f}" y1="{y0:.1f}" '
                   f'x2="{x1:.1f}" y2="{y0:.1f}" stroke="#1f5fa8" stroke-width="2" '
                   'stroke-dasharray="5 3"/>')
        lx, ly = at(float(x["load_x_m"]), float(x["load_y_m"]))
        out.append(f'<g class="load" data-experiment="{k}"><circle cx="{lx:.1f}" cy="{ly:.1f}" '
                   'r="6" fill="#c0392b" stroke="#fff" stroke-width="1"/>'
                   f'<text x="{lx:.1f}" y="{ly + 3.5:.1f}" font-size="9" fill="#fff" '
                   f'text-anchor="middle">{k}</text></g>')
    # The centimetre axis.
    length_cm = length * 100
    step = next(m * 10 ** d for d in range(-2, 6) for m in (1, 2, 5)
                if m * 10 ** d / length_cm * plot >= 45)
    out.append(f'<line x1="{left}" y1="{axis_y}" x2="{left + plot}" y2="{axis_y}" '
               'stroke="#333"/>')
    ticks = [k * step for k in range(int(length_cm / step + 1e-9) + 1)]
    if length_cm - ticks[-1] > 1e-9:
        ticks.append(length_cm)
    for t in ticks:
        tx = left + t / length_cm * plot
        out.append(f'<line x1="{tx:.1f}" y1="{axis_y}" x2="{tx:.1f}" y2="{axis_y + 5}" '
                   f'stroke="#333"/><text x="{tx:.1f}" y="{axis_y + 17}" font-size="11" '
                   f'text-anchor="middle">{_cm(t / 100)}</text>')
    out.append(f'<text x="{left + plot / 2}" y="{axis_y + 33}" font-size="11" '
               'text-anchor="middle">x along the strip (cm)</text>')
    # The colour scale.
    sx, sy = left + plot + 20, plate_top - row_h
    out.append('<defs><linearGradient id="p-fixed" x1="0" y1="1" x2="0" y2="0">'
               f'<stop offset="0" stop-color="{p_colour(0)}"/>'
               f'<stop offset="1" stop-color="{p_colour(1)}"/></linearGradient></defs>'
               f'<rect x="{sx}" y="{sy}" width="14" height="{2 * row_h + plate_h:.1f}" '
               'fill="url(#p-fixed)" stroke="#999"/>'
               f'<text x="{sx + 18}" y="{sy + 9}" font-size="10">1</text>'
               f'<text x="{sx + 18}" y="{sy + 2 * row_h + plate_h:.1f}" font-size="10">0</text>'
               f'<text x="{sx + 18}" y="{sy + row_h + plate_h / 2 + 4:.1f}" font-size="10">'
               'P(fixed)</text>')
    out.append("</svg>")
    rows = "".join(
        f"<li><b>{k}</b>{' ' + e(x['name']) if x.get('name') else ''}: load at "
        f"{_cm(float(x['load_x_m']))} cm, {float(x['load_y_m']) * 1000:.0f} mm from edge 1; "
        f"scanned from {_cm(float(x['scan_from_m']))} to {_cm(float(x['scan_to_m']))} cm at "
        f"{float(x['scan_y_m']) * 1000:.0f} mm from edge 1</li>"
        for k, x in enumerate(strip.get("experiments") or [], 1))
    caption = (f"<p class=\"strip-caption\">The strip to scale: {_cm(length)} cm long, "
               f"{width * 1000:.0f} mm wide, {n} clamp sections per edge, each coloured by its "
               "P(fixed) (thick outline: fixed). Red dots: the loads; dashed lines: the scan "
               f"lines.</p>\n<ul class=\"experiments\">{rows}</ul>\n")
    return '<div class="strip">' + "".join(out) + "</div>\n" + caption


def _findings(title, items):
    if not items:
        return f"<h3>{e(title)}</h3>\n<p>No warnings.</p>\n"
    lines = "\n".join(
        f'<li class="{e(str(i.get("severity", "")))}"><b>{e(str(i.get("severity", "")))}</b> '
        f'[{e(str(i.get("code", "")))}]: {e(str(i.get("message", "")))}</li>' for i in items)
    return f"<h3>{e(title)}</h3>\n<ul>\n{lines}\n</ul>\n"


def campaign_html(campaign):
    """A joint run's campaign.csv: which experiment decided which clamp. Per experiment the clamps
    it decides alone (|P(fixed) - 0.5| above the margin on the run's side), those only the
    experiments together decide, and per clamp its P(fixed) in the run, with each experiment's
    likelihood alone and with all of them. Empty without the file (one experiment, or not the
    sensor)."""
    if not campaign or not campaign["rows"]:
        return ""
    names = campaign["experiments"]
    rows = campaign["rows"]

    def listed(clamps):
        return ", ".join(str(c) for c in clamps) if clamps else "none"

    by = [[r["clamp"] for r in rows if x in [w.strip() for w in r["decided_by"].split(",")]]
          for x in names]
    together = [r["clamp"] for r in rows if r["decided_by"] == "together"]
    undecided = [r["clamp"] for r in rows if not r["decided_by"]]
    items = [f"<li>{e(x)} alone: clamps {e(listed(c))}</li>" for x, c in zip(names, by)]
    if together:
        items.append(f"<li>only together: clamps {e(listed(together))}</li>")
    if undecided:
        items.append(f"<li>undecided in the run: clamps {e(listed(undecided))}</li>")
    head = (["Clamp", "Where", "P(fixed) in the run"] + [f"{x} alone" for x in names]
            + ["Together", "Decided by"])
    body = [[e(str(r["clamp"])), e(f"edge {r['edge']}, {r['from_cm']:g}-{r['to_cm']:g} cm"),
             fmt(r["run"], ".2f")] + [fmt(p, ".2f") for p in r["alone"]]
            + [fmt(r["together"], ".2f"), e(r["decided_by"] or "—")] for r in rows]
    numeric = range(2, 3 + len(names) + 1)
    return ('<h2 id="campaign">Which experiment decided which clamp</h2>\n'
            "<p>Each clamp's P(fixed) with each experiment's likelihood alone, the other clamps "
            "held at the run's likely values (docs/algorithm.md, \"Which experiment decided which "
            "clamp\"; campaign.csv of <code>combabc export</code>).</p>\n"
            f"<ul>{''.join(items)}</ul>\n" + table(head, body, numeric))


def checks_html(summary):
    """summary.json's "checks": the warnings before and after sampling, the noise level and the
    fit verdict per experiment. Empty when the export has no checks."""
    checks = summary.get("checks")
    if not checks:
        return ""
    parts = ["<h2>Checks</h2>\n",
             _findings("Before sampling: the model and the data", checks.get("before") or []),
             _findings("After sampling: the fit", checks.get("after") or [])]
    fits = checks.get("fit") or []
    if fits:
        # Older exports have no sigma, points or p_value: their sigma was the estimate.
        rows = [([e(str(f.get("experiment") or "—")), e(fmt(f.get("best_rms"))),
                  e(fmt(f.get("sigma", f.get("noise_sigma")))),
                  e(str(f.get("sigma_source", "estimated"))), e(fmt(f.get("points"))),
                  e(fmt(f.get("ratio"), ".3g")), e(fmt(f.get("p_value"), ".2g")),
                  e(str(f.get("verdict", "")))],
                 "fixed" if f.get("verdict") == "good" else "")
                for f in fits]
        parts.append("<h3>Goodness of fit</h3>\n<p>The best accepted curve against the noise: "
                     "the noise-aware components' stated sigma (chi-square), or the data's "
                     "estimate (an F test: the estimate's own scatter counts); poor when the "
                     "ratio exceeds 3 or p &lt; 0.001.</p>\n" + table(
            ["Experiment", "Best accepted RMS", "Sigma", "Sigma from", "Points", "Ratio", "p",
             "Verdict"], rows, numeric=(1, 2, 4, 5, 6)))
    noise = checks.get("noise_sigma") or []
    if isinstance(noise, dict):
        noise = [noise]
    if noise:
        rows = [[e(str(n.get("experiment") or "—")), e(fmt(n.get("value"))),
                 e(str(n.get("method", "")))] for n in noise]
        parts.append("<h3>Noise level of the data</h3>\n" +
                     table(["Experiment", "Sigma", "Method"], rows, numeric=(1,)))
    return "".join(parts)


def figure_html(name, formats):
    """A figure shown as PNG (or SVG, which browsers also draw inline), linked in every format."""
    links = ", ".join(f'<a href="{e(name)}.{f}">{f.upper()}</a>' for f in formats)
    shown = next((f for f in ("png", "svg") if f in formats), None)
    image = (f'<a href="{e(name)}.{shown}"><img src="{e(name)}.{shown}" alt="{e(name)}"></a>'
             if shown else "")
    return f"<figure>{image}<figcaption>{e(name)} ({links})</figcaption></figure>"


def fidelity_html(run):
    """A multi-fidelity run's cost split per wave and in total (summary.json's "multi_fidelity");
    nothing for a single-fidelity run."""
    if not run.get("multi_fidelity"):
        return ""
    head = ("<tr><th>Wave</th><th>Cheap simulations</th><th>Expensive simulations</th>"
            "<th>Cheap seconds</th><th>Expensive seconds</th><th>η₁ (cheap accepted)</th>"
            "<th>η₂ (cheap rejected)</th><th>ESS per second</th><th>Next η₁, η₂</th>"
            "<th>Cost ratio</th></tr>")

    def row(x, label):
        return (f"<tr><td>{e(str(label))}</td><td>{x['cheap_simulations']}</td>"
                f"<td>{x['expensive_simulations']}</td><td>{fmt(x.get('cheap_seconds'), '.3g')}</td>"
                f"<td>{fmt(x.get('expensive_seconds'), '.3g')}</td>")

    body = "\n".join(
        row(x, x["wave"]) + f"<td>{fmt(x.get('continue_if_accepted'))}</td>"
        f"<td>{fmt(x.get('continue_if_rejected'))}</td><td>{fmt(x.get('ess_per_second'))}</td>"
        f"<td>{fmt(x.get('next_continue_if_accepted'))}, "
        f"{fmt(x.get('next_continue_if_rejected'))}</td><td>{fmt(x.get('cost_ratio'))}</td></tr>"
        for x in run["multi_fidelity"])
    total = run.get("multi_fidelity_total")
    if total:
        body += "\n" + row(total, "total") + (
            f"<td>—</td><td>—</td><td>{fmt(total.get('ess_per_second'))}</td><td>—</td>"
            "<td>—</td></tr>")
    return ("<h2>Multi-fidelity</h2><p>Every candidate ran the cheap simulator; the expensive "
            "one ran with probability η₁ or η₂ after the cheap one accepted or rejected it. "
            "ESS per second: the wave's effective sample size over its simulation seconds (the "
            f"total: the answer's wave's over the run's).</p><table>{head}{body}</table>\n")


def moves_html(waves):
    """A resample-move run's moves per wave (summary.json's "moves"); nothing for a run whose
    waves all drew their candidates by rejection."""
    if not any(getattr(w, "moves", None) for w in waves):
        return ""
    head = ("<tr><th>Wave</th><th>Rounds</th><th>Proposals</th><th>Accepted</th>"
            "<th>Acceptance rate</th><th>Independent share</th>"
            "<th>Independent accepted</th><th>Survivors' ESS</th><th>Step</th></tr>")

    def row(w):
        m = getattr(w, "moves", None)
        if not m:
            return (f"<tr><td>{w.number}</td><td colspan=\"8\">drawn by rejection</td></tr>")
        return (f"<tr><td>{w.number}</td><td>{m['rounds']}</td><td>{m['proposed']}</td>"
                f"<td>{m['accepted']}</td><td>{fmt(m.get('acceptance_rate'), '.3g')}</td>"
                f"<td>{fmt(m.get('independent_share'), '.3g')}</td>"
                f"<td>{m['independent_accepted']}</td>"
                f"<td>{fmt(m.get('survivor_ess'), '.1f')}</td><td>{fmt(m.get('step'), '.3g')}</td>"
                "</tr>")

    body = "\n".join(row(w) for w in waves)
    return ("<h2>Moves</h2><p>Each move wave reweighted the previous wave's particles to its "
            "target (survivors' ESS: their effective sample size then; step: the share of the "
            "schedule's step taken), resampled them and moved each by Metropolis-Hastings "
            "proposals, one per particle and round; independent proposals come from the kernel "
            "fitted to the reweighted particles, the others flip bits or step the reals.</p>"
            f"<table>{head}{body}</table>\n")


def page_html(waves, run, estimator, written, formats, history):
    """The whole page."""
    provenance = [
        ("Run history", history), ("Status", run.get("status")),
        ("Termination", run.get("termination") or "—"), ("Message", run.get("message") or "—"),
        ("Config", run.get("config_path") or "—"), ("Seed", run.get("seed")),
        ("Threads", run.get("threads")), ("Estimator", run.get("estimator")),
        ("Estimator shown", estimator), ("Dimension", run.get("dimension")),
        ("Simulations", run["simulations"] if run.get("simulations") is not None
         else sum(w.candidates for w in waves)),
        ("Failed simulations", sum(w.failures for w in waves)),
        ("Wall time (s)", fmt(run.get("wall_seconds"), ".1f")),
        ("Started", run.get("start_time")), ("Ended", run.get("end_time") or "—"),
        ("Resumed", f"{run.get('resume_count', 0)} times"),
        ("Stop limits set on resume", ", ".join(f"{k} = {v}" for k, v in run["stop_limits"])
         or "—"),
        ("combabc", f"{run.get('combabc_version', '')} {run.get('git_hash', '')}".strip()),
    ]
    rows = "\n".join(f"<tr><th>{e(str(k))}</th><td>{e(str(v))}</td></tr>" for k, v in provenance)
    head = ("<tr><th>Wave</th><th>Thresholds</th><th>Candidates</th><th>Failed</th><th>Accepted</th>"
            "<th>Acceptance rate</th><th>ESS</th><th>Distinct</th><th>Wall time (s)</th>"
            "<th>Complete</th></tr>")
    body = "\n".join(
        f"<tr><td>{w.number}</td><td>{e(', '.join(format(x, '.4g') for x in w.thresholds))}</td>"
        f"<td>{w.candidates}</td><td>{w.failures}</td><td>{w.accepted}</td>"
        f"<td>{fmt(float(w.acceptance_rate))}</td>"
        f"<td>{fmt(float(w.ess), '.1f')}</td><td>{w.distinct}</td>"
        f"<td>{fmt(float(w.wall_seconds), '.2f')}</td><td>{'yes' if w.complete else 'no'}</td></tr>"
        for w in waves)
    # The P(fixed) bars stand under the answer's table; the other figures in the gallery.
    bars = figure_html("answer", formats) if "answer" in written else ""
    figures = "\n".join(figure_html(n, formats) for n in written if n != "answer")
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
    fidelity = fidelity_html(run)
    note = ("" if any(w.curves is not None for w in waves)
            else "<p>This run did not keep simulated outputs: no curve figures.</p>")
    summary = run["summary"]
    sensor = run.get("sensor", True)
    verdicts = verdict_line(summary, sensor)
    verdicts = f'<p class="verdict"><b>Verdict</b> &mdash; {e(verdicts)}</p>\n' if verdicts else ""
    campaign = campaign_html(run.get("campaign")) if sensor else ""
    # What the engineer asked first: the strip, the verdicts and the answer; the run's provenance
    # after them.
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>combabc report</title>
<style>{STYLE}</style></head><body>
<h1>combabc run report</h1>
{strip_html(summary) if sensor else ""}{verdicts}{answer_html(summary, sensor)}{bars}
{campaign}{checks_html(summary)}<h2>Run</h2><table>{rows}</table>
{experiments}<h2>Waves</h2><table>{head}{body}</table>
{moves_html(waves)}{fidelity}{note}
<h2>Figures</h2>
{figures}
<h2>Configuration</h2><pre>{e(run.get("config_text") or "")}</pre>
</body></html>
"""


def write_index(waves, run, estimator, out, written, formats, history):
    with open(os.path.join(out, "index.html"), "w", encoding="utf-8") as f:
        f.write(page_html(waves, run, estimator, written, formats, history))
