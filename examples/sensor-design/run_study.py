#!/usr/bin/python3
"""Designed experiments against evenly spaced centreline ones (docs/algorithm.md, "Designing the
next experiment"): how many of the 36 clamps are identified, and how many confidently wrong,
after 1, 2, 3 and 4 experiments.

One physical sensor: the 45 cm example's ground truth in a model that differs from the
calibrating one (finer mesh, perturbed materials: examples/generate_data.py's recipe and seed), so
the data never come from the calibrating model itself. Every experiment scans the whole length
(0-90 cm, every 1 cm) and adds Gaussian noise of 1 % of its peak.

  1. Experiment 1: the shaker at 45 cm on the centreline, scan along the centreline.
  2. Its joint calibration (noise-aware acceptance, until every temperature is 1): the 45 cm
     posterior.
  3. Designed, greedy: `combabc design --posterior` on it over the [design] grid below chooses 3
     more experiments at once (greedy selection); joint calibrations with the first 1, 2, 3.
  4. Designed, sequential: after each joint calibration, `combabc design --posterior` on its
     posterior chooses the next experiment (what a lab would do: measure, calibrate, design).
  5. For comparison, centreline loads at 15, 75 and 30 cm, scanned along the centreline.

A clamp is identified when |P(fixed) - 0.5| > 0.4 on the truth's side, confidently wrong when on
the other side. Writes results.md and results.csv here; work files in work/ (safe to delete).
Needs the combabc CLI ($COMBABC, default build-demo/apps/combabc) and numpy.
    /usr/bin/python3 examples/sensor-design/run_study.py
"""
import csv
import os
import pathlib
import subprocess
import sys
import time
import tomllib

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
import generate_data  # noqa: E402  (the perturbation recipe and the TOML writer)

TRUTH = "101101010001101001" "011011010001101100"  # the 45 cm example's
NOISE = 0.01   # of each profile's peak
CONFIDENT = 0.4
DESIGN = {
    "load_x": [10, 20, 30, 40, 50, 60, 70, 80],     # cm
    "load_y_fraction": [0.5, 0.2],
    "scan_y_fraction": [0.5, 0.2],
    "noise": NOISE,
    "truths": 200,
    "select": 3,
}
CENTRELINE = [(15.0, 0.5, 0.5), (75.0, 0.5, 0.5), (30.0, 0.5, 0.5)]  # after 45 cm


def model_and_truth_model():
    with open(HERE.parent / "sensor-45cm" / "least_squares.toml", "rb") as f:
        config = tomllib.load(f)
    # The same draw as the 45 cm example's data (generate_data.py, seed 45): one sensor.
    truth_model = generate_data.perturbed(config["model"], np.random.default_rng(45))
    return config["model"], truth_model


def name_of(x_cm, load_y, scan_y):
    return f"x{x_cm:g}cm_y{load_y:g}_scan{scan_y:g}"


def experiment_table(x_cm, load_y, scan_y, csv_name=None):
    table = {
        "name": name_of(x_cm, load_y, scan_y),
        "load": {"x": x_cm / 100.0, "y_fraction": load_y, "amplitude": 0.042, "frequency": 5.0},
        "output": {"spacing": 0.01, "y_fraction": scan_y},
        "data": {"csv": csv_name or "none.csv", "position_column": "position_cm",
                 "displacement_column": "max_displacement_um", "position_unit": "cm",
                 "displacement_unit": "um", "window": [0, 90]},
        "metric": {"component": [{"type": "least_squares", "window": [0, 90],
                                  "noise": "folded_normal", "quantile": 0.5, "target": 1}]},
    }
    return table


def cli():
    path = os.environ.get("COMBABC", str(HERE.parent.parent / "build-demo" / "apps" / "combabc"))
    if not pathlib.Path(path).exists():
        sys.exit(f"combabc CLI not found at {path}; build it (bash scripts/demo.sh) or set COMBABC")
    return path


def generate(experiments, truth_model, work):
    """Writes data_<name>.csv for each (x_cm, load_y, scan_y) not yet written."""
    todo = [e for e in experiments if not (work / f"data_{name_of(*e)}.csv").exists()]
    if not todo:
        return
    config = {"model": truth_model, "experiment": [experiment_table(*e) for e in todo],
              "sampler": {"seed": 1}}
    (work / "none.csv").write_text("position_cm,max_displacement_um\n0,0\n")
    (work / "truth.toml").write_text(generate_data.to_toml(config))
    subprocess.run([cli(), "simulate", str(work / "truth.toml"), "--clamps", TRUTH,
                    "-o", str(work / "truth_profiles.csv"), "--overwrite"], check=True,
                   stdout=subprocess.DEVNULL)
    with open(work / "truth_profiles.csv") as f:
        rows = list(csv.DictReader(f))
    for e in todo:
        name = name_of(*e)
        mine = [r for r in rows if r["experiment"] == name]
        x_cm = np.array([float(r["position_m"]) * 100 for r in mine])
        w_um = np.array([float(r["displacement_m"]) * 1e6 for r in mine])
        seed = sum(ord(c) for c in name) * 7919
        rng = np.random.default_rng(seed)
        sigma = NOISE * w_um.max()
        noisy = np.abs(w_um + rng.normal(0.0, sigma, size=w_um.shape))
        lines = [f"# Synthetic: truth {TRUTH}, finer perturbed model, noise {sigma:.4f} um",
                 "position_cm,max_displacement_um"]
        lines += [f"{x:.0f},{w:.6f}" for x, w in zip(x_cm, noisy)]
        (work / f"data_{name}.csv").write_text("\n".join(lines) + "\n")


def joint_config(model, experiments, label, design=False):
    config = {"description": f"sensor-design study: {label}", "model": model,
              "experiment": [experiment_table(*e, csv_name=f"data_{name_of(*e)}.csv")
                             for e in experiments],
              "sampler": {"waves": 30, "accepted_per_wave": 500, "estimator": "importance",
                          "seed": 2024, "threads": 0, "method": "resample_move"},
              "output": {"directory": f"results-{label}", "figures": ["png"]}}
    if design:
        config["design"] = DESIGN
    return generate_data.to_toml(config)


def calibrate(model, experiments, label, work):
    path = work / f"{label}.toml"
    text = joint_config(model, experiments, label)
    history = work / f"results-{label}" / "history.sqlite"
    seconds_file = work / f"results-{label}" / "seconds.txt"
    # A finished run of the same config is reused (the study can be rerun to extend it).
    if not (path.exists() and path.read_text() == text and seconds_file.exists()):
        path.write_text(text)
        start = time.monotonic()
        subprocess.run([cli(), "run", str(path), "-q", "--overwrite", "--no-report"], check=True,
                       stdout=subprocess.DEVNULL)
        seconds_file.write_text(f"{time.monotonic() - start}\n")
        subprocess.run([cli(), "export", str(history), "--no-netcdf", "--overwrite"], check=True,
                       stdout=subprocess.DEVNULL)
    seconds = float(seconds_file.read_text())
    with open(work / f"results-{label}" / "export" / "marginals.csv") as f:
        rows = list(csv.DictReader(f))
    last = max(int(r["wave"]) for r in rows)
    p = np.array([float(r["prob_importance"]) for r in rows if int(r["wave"]) == last])
    truth = np.array([int(c) for c in TRUTH])
    decided = np.abs(p - 0.5) > CONFIDENT
    right = decided & ((p > 0.5) == (truth == 1))
    with open(work / f"results-{label}" / "export" / "summary.json") as f:
        summary = f.read()
    stopped = "target" if '"termination": "target_reached"' in summary else "waves"
    return {"label": label, "identified": int(right.sum()), "wrong": int((decided & ~right).sum()),
            "history": history, "seconds": seconds, "stop": stopped, "waves": last}


def main():
    work = HERE / "work"
    work.mkdir(exist_ok=True)
    model, truth_model = model_and_truth_model()
    first = (45.0, 0.5, 0.5)
    generate([first] + CENTRELINE, truth_model, work)
    results = [calibrate(model, [first], "k1", work)]
    print(f"1 experiment: {results[0]['identified']} identified, {results[0]['wrong']} wrong")

    # The design, from the 45 cm posterior.
    (work / "design.toml").write_text(joint_config(model, [first], "k1", design=True))
    start = time.monotonic()
    subprocess.run([cli(), "design", str(work / "design.toml"), "--posterior",
                    str(results[0]["history"]), "-o", str(work / "design"), "--overwrite"],
                   check=True)
    design_seconds = time.monotonic() - start
    with open(work / "design" / "selection.csv") as f:
        chosen = [(float(r["load_x_m"]) * 100, float(r["load_y_fraction"]),
                   float(r["scan_y_fraction"])) for r in csv.DictReader(f)]
    generate(chosen, truth_model, work)

    designed, sequential, centreline = [results[0]], [results[0]], [results[0]]
    for k in range(2, 5):
        designed.append(calibrate(model, [first] + chosen[:k - 1], f"designed-k{k}", work))
        centreline.append(calibrate(model, [first] + CENTRELINE[:k - 1], f"centreline-k{k}", work))
        print(f"{k} experiments: designed {designed[-1]['identified']} identified "
              f"({designed[-1]['wrong']} wrong), centreline {centreline[-1]['identified']} "
              f"({centreline[-1]['wrong']} wrong)")

    # Sequential: design again from each joint posterior.
    current = [first]
    sequence = []
    for k in range(2, 5):
        label = f"sequential-k{k - 1}" if k > 2 else "k1"
        (work / f"design-{k}.toml").write_text(joint_config(model, current, label, design=True))
        previous = sequential[-1]["history"]
        subprocess.run([cli(), "design", str(work / f"design-{k}.toml"), "--posterior",
                        str(previous), "-o", str(work / f"design-{k}"), "--overwrite",
                        "--no-figure"], check=True, stdout=subprocess.DEVNULL)
        with open(work / f"design-{k}" / "selection.csv") as f:
            r = next(csv.DictReader(f))
        pick = (float(r["load_x_m"]) * 100, float(r["load_y_fraction"]),
                float(r["scan_y_fraction"]))
        sequence.append(pick)
        generate([pick], truth_model, work)
        current = current + [pick] if pick not in current else current
        sequential.append(calibrate(model, current, f"sequential-k{k}", work))
        print(f"{k} experiments, sequential: {sequential[-1]['identified']} identified "
              f"({sequential[-1]['wrong']} wrong)")

    with open(HERE / "results.csv", "w") as f:
        f.write("experiments,greedy_identified,greedy_wrong,sequential_identified,"
                "sequential_wrong,centreline_identified,centreline_wrong\n")
        for k in range(4):
            f.write(f"{k + 1},{designed[k]['identified']},{designed[k]['wrong']},"
                    f"{sequential[k]['identified']},{sequential[k]['wrong']},"
                    f"{centreline[k]['identified']},{centreline[k]['wrong']}\n")
    lines = ["| experiments | designed, greedy: identified | wrong | designed, sequential: "
             "identified | wrong | centreline: identified | wrong |",
             "|---|---|---|---|---|---|---|"]
    for k in range(4):
        lines.append(f"| {k + 1} | {designed[k]['identified']} | {designed[k]['wrong']} | "
                     f"{sequential[k]['identified']} | {sequential[k]['wrong']} | "
                     f"{centreline[k]['identified']} | {centreline[k]['wrong']} |")
    def listing(picks):
        return ", ".join(f"{x:g} cm (load y {y:g}, scan y {s:g})" for x, y, s in picks)
    text = ("Greedy picks from the 45 cm posterior (in order): " + listing(chosen) +
            ".\nSequential picks: " + listing(sequence) + ".\n\n" + "\n".join(lines) +
            f"\n\n`combabc design` (32 candidates, from the 45 cm posterior) took "
            f"{design_seconds:.1f} s; the joint runs "
            + ", ".join(f"{r['label']} {r['seconds']:.0f} s ({r['waves']} waves, {r['stop']})"
                        for r in designed + sequential[1:] + centreline[1:]) + ".\n")
    (HERE / "results.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
