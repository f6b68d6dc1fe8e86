#!/usr/bin/python3
"""The measuring campaign, closed (issue 34): calibrate, design, measure the chosen experiment,
add it, calibrate again, until `combabc design`'s stop rule ends it or 9 experiments (the 45 cm one
and 8 designed) are made; against k evenly spaced centreline experiments for each k.

The loop is the user's: round 1 runs a config with the 45 cm experiment and the [design] grid;
every later round runs, as it is, the next.toml that `combabc design --posterior` wrote, with the
chosen experiment's data saved where next.toml reads it.

The sensor is run_study.py's: the 45 cm example's ground truth in the finer perturbed model, each
scan 0-90 cm every 1 cm with Gaussian noise of 1 % of its peak, folded (an amplitude). Every
calibration is run_study.py's joint_config: resample-move, folded-normal noise with sigma
estimated from each scan, 500 particles per wave, until every temperature is 1, seed 2024.
Each design is `combabc design --posterior` on the last calibration over run_study.py's 32
candidates; its prediction (the number of clamps decided with the best candidate) is printed next
to what the calibration with that candidate then gives.

Writes campaign.md and campaign.csv here (rewritten after every round, so a stopped campaign
keeps what it measured); work files in work/ (shared with run_study.py; safe to delete).
    COMBABC=build/apps/combabc /usr/bin/python3 examples/sensor-design/run_campaign.py
"""
import csv
import json
import platform
import re
import subprocess
import sys
import time
import tomllib

import numpy as np

import run_study as study

MAX_EXPERIMENTS = 9  # the 45 cm one and at most 8 designed
FIRST = (45.0, 0.5, 0.5)


def with_counts(result):
    """Adds the run's simulations and the clamps it leaves undecided or wrong."""
    export = result["history"].parent / "export"
    with open(export / "summary.json") as f:
        run = json.load(f)["run"]
    result["simulations"] = run["simulations"]
    with open(export / "marginals.csv") as f:
        rows = list(csv.DictReader(f))
    last = max(int(r["wave"]) for r in rows)
    p = np.array([float(r["prob_importance"]) for r in rows if int(r["wave"]) == last])
    truth = np.array([int(c) for c in study.TRUTH])
    decided = np.abs(p - 0.5) > study.CONFIDENT
    result["undecided"] = [k + 1 for k in range(len(p)) if not decided[k]]
    result["wrong_clamps"] = [k + 1 for k in range(len(p))
                              if decided[k] and (p[k] > 0.5) != (truth[k] == 1)]
    return result


def run_config(config, label):
    """`combabc run` on a config as it is (the campaign's first, then each next.toml), exported:
    run_study.calibrate's record of it."""
    with open(config, "rb") as f:
        parsed = tomllib.load(f)
    results = config.parent / parsed["output"]["directory"]
    history = results / "history.sqlite"
    start = time.monotonic()
    subprocess.run([study.cli(), "run", str(config), "-q", "--overwrite", "--no-report"],
                   check=True, stdout=subprocess.DEVNULL)
    seconds = time.monotonic() - start
    subprocess.run([study.cli(), "export", str(history), "--no-netcdf", "--overwrite"], check=True,
                   stdout=subprocess.DEVNULL)
    with open(results / "export" / "summary.json") as f:
        run = json.load(f)["run"]
    result = {"label": label, "history": history, "seconds": seconds,
              "waves": run["waves_completed"],
              "stop": "target" if run["termination"] == "target_reached" else run["termination"]}
    result = with_counts(result)
    result["identified"] = 36 - len(result["undecided"]) - len(result["wrong_clamps"])
    result["wrong"] = len(result["wrong_clamps"])
    return result


def measure(next_toml, truth_model, work):
    """The bench: next.toml's new experiment (its last) measured on the sensor, the file saved
    where next.toml reads it. Returns the experiment as (x cm, load y, scan y)."""
    with open(next_toml, "rb") as f:
        new = tomllib.load(f)["experiment"][-1]
    pick = (round(new["load"]["x"] * 100, 6), new["load"]["y_fraction"],
            new["output"]["y_fraction"])
    study.generate([pick], truth_model, work)
    target = (next_toml.parent / new["data"]["csv"]).resolve()
    target.write_text((work / f"data_{study.name_of(*pick)}.csv").read_text())
    return pick


def design(config, result, label, work):
    """`combabc design --posterior` on the run: the pick (or None when the stop rule fires), the
    printed prediction and what it cost."""
    out = work / f"design-{label}"
    start = time.monotonic()
    printed = subprocess.run([study.cli(), "design", str(config), "--posterior",
                              str(result["history"]), "-o", str(out), "--overwrite",
                              "--no-figure"], check=True, capture_output=True, text=True).stdout
    seconds = time.monotonic() - start
    now = re.search(r"now: (\d+) of (\d+) clamps decided; with the best candidate: ([\d.]+)",
                    printed)
    simulated = re.search(r": (\d+) configurations simulated", printed)
    stop = re.search(r"^stop: (.*)$", printed, re.M)
    step = {"decided_now": int(now.group(1)), "predicted": float(now.group(3)),
            "seconds": seconds, "configurations": int(simulated.group(1)) if simulated else 0,
            "stop": stop.group(1) if stop else "",
            "undecided": re.findall(r"^undecided: (.*)$", printed, re.M),
            "next_toml": (out / "next.toml").exists()}
    step["decided_by"] = re.findall(r"^  (\S+ alone: clamps .*|only together: clamps .*)$",
                                    printed, re.M)
    return (None if stop else out / "next.toml"), step


def evenly_spaced(k):
    """k centreline loads at the centres of k equal parts of the 90 cm (k = 1: 45 cm)."""
    return [(round(90.0 * (i + 0.5) / k * 2) / 2, 0.5, 0.5) for i in range(k)]


def where(e):
    x, y, s = e
    return f"{x:g} cm, load {y * 40:g} mm, scan {s * 40:g} mm"


def write(rounds, steps, even, stop_text, started, view=()):
    lines = ["| experiments | designed: the new one | identified | wrong | predicted by the "
             "design before it | simulations | waves | calibration | design (configurations, "
             "time) | evenly spaced: loads (cm) | identified | wrong | simulations | "
             "calibration |", "|" + "---|" * 14]
    with open(study.HERE / "campaign.csv", "w") as f:
        f.write("experiments,designed_x_cm,designed_load_y_fraction,designed_scan_y_fraction,"
                "designed_identified,designed_wrong,predicted_decided,designed_simulations,"
                "designed_seconds,design_configurations,design_seconds,even_identified,"
                "even_wrong,even_simulations,even_seconds\n")
        for k in range(1, max(len(rounds), len(even)) + 1):
            r = rounds[k - 1] if k <= len(rounds) else None
            s = steps[k - 2] if 2 <= k <= len(steps) + 1 else None
            e = even[k - 1] if k <= len(even) else None
            f.write(",".join(str(v) for v in [
                k, *(r["experiment"] if r else ("", "", "")),
                r["identified"] if r else "", r["wrong"] if r else "",
                f"{s['predicted']:.1f}" if s else "", r["simulations"] if r else "",
                f"{r['seconds']:.0f}" if r else "",
                s["configurations"] if s else "", f"{s['seconds']:.0f}" if s else "",
                e["identified"] if e else "", e["wrong"] if e else "",
                e["simulations"] if e else "", f"{e['seconds']:.0f}" if e else ""]) + "\n")
            lines.append(" | ".join([
                f"| {k}", where(r["experiment"]) if r else "",
                str(r["identified"]) if r else "", str(r["wrong"]) if r else "",
                f"{s['predicted']:.1f} decided" if s else "",
                f"{r['simulations']:,}" if r else "", str(r["waves"]) if r else "",
                f"{r['seconds']:.0f} s" if r else "",
                f"{s['configurations']:,}, {s['seconds']:.0f} s" if s else "",
                ", ".join(f"{x:g}" for x, _, _ in evenly_spaced(k)) if e else "",
                str(e["identified"]) if e else "", str(e["wrong"]) if e else "",
                f"{e['simulations']:,}" if e else "",
                f"{e['seconds']:.0f} s" if e else ""]) + " |")
    last = rounds[-1]
    text = (f"Measured {time.strftime('%Y-%m-%d', time.gmtime())} on {platform.node()} "
            f"({platform.machine()}, {study.os.cpu_count()} cores); the campaign "
            f"{(time.monotonic() - started) / 60:.0f} min of wall time so far.\n\n"
            + "\n".join(lines) + "\n\n"
            + f"After {len(rounds)} experiments: {last['identified']} identified, "
            f"{last['wrong']} wrong (clamps {last['wrong_clamps'] or 'none'}); undecided: "
            f"clamps {', '.join(map(str, last['undecided'])) or 'none'}.\n"
            + (f"\nStop rule: {stop_text}\n" if stop_text else "")
            + ("\nWhich experiment decided which clamp (`combabc design --posterior` on the last "
               "run; its campaign.csv):\n\n" + "".join(f"- {line}\n" for line in view)
               if view else ""))
    (study.HERE / "campaign.md").write_text(text)
    return text


def main():
    work = study.HERE / "work"
    work.mkdir(exist_ok=True)
    model, truth_model = study.model_and_truth_model()
    started = time.monotonic()
    # Round 1: the 45 cm experiment, run_study's joint config with the [design] grid. Each later
    # round runs the next.toml that `combabc design` wrote, as it is, with the chosen
    # experiment's data saved where it says.
    campaign = work / "campaign"
    campaign.mkdir(exist_ok=True)
    study.generate([FIRST], truth_model, work)
    config = campaign / "campaign.toml"
    text = study.joint_config(model, [FIRST], "campaign").replace(
        'csv = "data_', 'csv = "../data_')
    config.write_text(text + study.generate_data.to_toml({"design": dict(study.DESIGN,
                                                                         select=1)}))
    current = [FIRST]
    rounds, steps, even, stop_text, view = [], [], [], "", []
    while True:
        k = len(current)
        r = run_config(config, f"campaign-k{k}")
        r["experiment"] = current[-1]
        rounds.append(r)
        print(f"{k} experiments (designed): {r['identified']} identified, {r['wrong']} wrong, "
              f"{r['simulations']} simulations, {r['seconds']:.0f} s", flush=True)
        write(rounds, steps, even, stop_text, started)
        if k >= MAX_EXPERIMENTS:
            break
        next_toml, step = design(config, r, f"campaign-k{k}", work)
        view = step["decided_by"]
        print(f"  design: {step['decided_now']} decided now, {step['predicted']:.1f} predicted; "
              f"{step['stop'] or next_toml} ({step['seconds']:.0f} s)", flush=True)
        if next_toml is None:
            stop_text = " ".join([step["stop"]] + step["undecided"])
            break
        pick = measure(next_toml, truth_model, work)
        if pick in current:
            stop_text = f"design chose {where(pick)}, already measured; the campaign ends there"
            break
        steps.append(step)
        current.append(pick)
        config = next_toml
    write(rounds, steps, even, stop_text, started, view)
    even.append(rounds[0])
    for k in range(2, len(rounds) + 1):
        experiments = evenly_spaced(k)
        study.generate(experiments, truth_model, work)
        e = with_counts(study.calibrate(model, experiments, f"even-k{k}", work))
        even.append(e)
        print(f"{k} evenly spaced: {e['identified']} identified, {e['wrong']} wrong, "
              f"{e['simulations']} simulations, {e['seconds']:.0f} s", flush=True)
        write(rounds, steps, even, stop_text, started, view)
    print(write(rounds, steps, even, stop_text, started, view))


if __name__ == "__main__":
    sys.exit(main())
