#!/usr/bin/python3
"""Clamped or simply supported? ABC model choice on data from a finer, perturbed sensor
(docs/algorithm.md, "Model choice"; README.md here has the measured outcome).

One physical sensor: the 45 cm example's ground truth clamps in a model that differs from the
calibrating ones (finer mesh, perturbed materials: examples/generate_data.py's recipe and seed),
once with its fixed clamps simply supported (pinned) and once with them clamped. One experiment:
the shaker at 45 cm on the centreline, the whole length (0-90 cm) scanned every 1 cm, Gaussian
noise of 1 % of the peak. Each data set is calibrated with both candidate models (model_choice.toml:
`fixed_support = "clamped"` against `"simply_supported"`, prior 1/2 each, noise-aware
folded-normal acceptance, resample-move waves of 500 until the temperature is 1).

A clamp is identified when |P(fixed) - 0.5| > 0.4 on the truth's side, confidently wrong when on
the other side. Writes results.md and results.csv here; work files in work/ (safe to delete).
Needs the combabc CLI ($COMBABC, default build-demo/apps/combabc) and numpy.
    /usr/bin/python3 examples/sensor-model-choice/run_example.py
"""
import csv
import json
import os
import pathlib
import platform
import subprocess
import sys
import time
import tomllib

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
import generate_data  # noqa: E402  (the perturbation recipe and the TOML writer)

TRUTH = "101101010001101001" "011011010001101100"  # the 45 cm example's
NOISE = 0.01   # of the profile's peak
CONFIDENT = 0.4
SUPPORTS = ["simply_supported", "clamped"]  # the truth's fixed clamps, one data set each


def cli():
    path = os.environ.get("COMBABC", str(HERE.parent.parent / "build-demo" / "apps" / "combabc"))
    if not pathlib.Path(path).exists():
        sys.exit(f"combabc CLI not found at {path}; build it (bash scripts/demo.sh) or set COMBABC")
    return path


def truth_model(support):
    with open(HERE / "model_choice.toml", "rb") as f:
        config = tomllib.load(f)
    # The same draw as the 45 cm example's data (generate_data.py, seed 45): one sensor, whose
    # clamps either pin or clamp the edge.
    model = generate_data.perturbed(config["model"], np.random.default_rng(45))
    model["clamps"] = dict(model["clamps"], fixed_support=support)
    return config, model


def generate(support, work):
    """Writes data_<support>.csv: the finer perturbed sensor's profile plus noise."""
    out = HERE / f"data_{support}.csv"
    if out.exists():
        return
    config, model = truth_model(support)
    experiment = dict(config["experiment"][0])
    experiment["data"] = dict(experiment["data"], csv="none.csv")
    truth = {"model": model, "experiment": [experiment], "sampler": {"seed": 1}}
    (work / "none.csv").write_text("position_cm,max_displacement_um\n0,0\n")
    (work / "truth.toml").write_text(generate_data.to_toml(truth))
    subprocess.run([cli(), "simulate", str(work / "truth.toml"), "--clamps", TRUTH,
                    "-o", str(work / "truth_profile.csv"), "--overwrite"], check=True,
                   stdout=subprocess.DEVNULL)
    with open(work / "truth_profile.csv") as f:
        rows = list(csv.DictReader(f))
    x_cm = np.array([float(r["position_m"]) * 100 for r in rows])
    w_um = np.array([float(r["displacement_m"]) * 1e6 for r in rows])
    rng = np.random.default_rng(sum(ord(c) for c in support) * 7919)
    sigma = NOISE * w_um.max()
    noisy = np.abs(w_um + rng.normal(0.0, sigma, size=w_um.shape))
    # "# truth BITS support NAME": tests/examples/posterior_test.cpp reads both.
    lines = [f"# truth {TRUTH} support {support} (fixed clamps); synthetic: finer perturbed "
             f"model (seed 45), noise {sigma:.4f} um", "position_cm,max_displacement_um"]
    lines += [f"{x:.0f},{w:.6f}" for x, w in zip(x_cm, noisy)]
    out.write_text("\n".join(lines) + "\n")


def choose(support, work):
    """Runs the model choice on data_<support>.csv; returns one row per candidate model."""
    text = (HERE / "model_choice.toml").read_text()
    text = text.replace('csv = "data_simply_supported.csv"', f'csv = "../data_{support}.csv"')
    text = text.replace('directory = "results-model-choice"', f'directory = "results-{support}"')
    path = work / f"{support}.toml"
    out = work / f"results-{support}"
    seconds_file = out / "seconds.txt"
    # A finished model choice of the same config is reused.
    if not (path.exists() and path.read_text() == text and seconds_file.exists()):
        path.write_text(text)
        start = time.monotonic()
        subprocess.run([cli(), "run", str(path), "-q", "--overwrite", "--no-report"], check=True,
                       stdout=subprocess.DEVNULL)
        seconds_file.write_text(f"{time.monotonic() - start}\n")
    seconds = float(seconds_file.read_text())
    with open(out / "model_choice" / "summary.json") as f:
        summary = json.load(f)
    truth = np.array([int(c) for c in TRUTH])
    rows = []
    for m in summary["models"]:
        history = out / "models" / m["name"] / "history.sqlite"
        export = history.parent / "export" / "marginals.csv"
        if not export.exists():
            subprocess.run([cli(), "export", str(history), "--no-netcdf", "--overwrite"],
                           check=True, stdout=subprocess.DEVNULL)
        with open(export) as f:
            marginals = list(csv.DictReader(f))
        last = max(int(r["wave"]) for r in marginals)
        p = np.array([float(r["prob_importance"]) for r in marginals if int(r["wave"]) == last])
        decided = np.abs(p - 0.5) > CONFIDENT
        right = decided & ((p > 0.5) == (truth == 1))
        rows.append({"data": support, "model": m["name"], "probability": m["probability"],
                     "se": m["se"], "upper_bound_only": m["upper_bound_only"],
                     "log10_bayes_factor": m["log10_bayes_factor"], "waves": last,
                     "simulations": m["simulations"], "termination": m["termination"],
                     "identified": int(right.sum()), "wrong": int((decided & ~right).sum()),
                     "seconds": seconds})
    return rows


def main():
    work = HERE / "work"
    work.mkdir(exist_ok=True)
    rows = []
    for support in SUPPORTS:
        generate(support, work)
        rows.extend(choose(support, work))
    with open(HERE / "results.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    lines = [f"Measured {time.strftime('%Y-%m-%d', time.gmtime())} on {platform.machine()} "
             f"({os.cpu_count()} cores), `run_example.py`.", "",
             "| data (truth's clamps) | model | P(model) ± se | log10 B | waves | simulations "
             "| stopped | clamps identified | wrong |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        p = (f"< {r['probability']:.3g}" if r["upper_bound_only"]
             else f"{r['probability']:.4g} ± {r['se']:.2g}")
        lines.append(f"| {r['data']} | {r['model']} | {p} | {r['log10_bayes_factor']:.1f} "
                     f"| {r['waves']} | {r['simulations']} | {r['termination']} | {r['identified']} "
                     f"| {r['wrong']} |")
    lines.append("")
    for support in SUPPORTS:
        mine = [r for r in rows if r["data"] == support]
        lines.append(f"Data {support}: the model choice (both models) took {mine[0]['seconds']:.0f} "
                     f"s and {sum(r['simulations'] for r in mine)} simulations.")
    (HERE / "results.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
