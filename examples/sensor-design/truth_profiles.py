#!/usr/bin/python3
"""Writes truth_profiles.csv: the noise-free full-length scans (0-90 cm, every 1 cm) of this
study's sensor -- the 45 cm example's ground truth in the finer, perturbed model that makes the
study's data (run_study.py's generate(), before its noise) -- for the designed, centreline and
evenly spaced experiments. tests/examples/noise_estimate_test.cpp adds noise to them as
generate() does, |w + e| with sigma 1 % of the peak, and measures the noise estimates on them
(docs/algorithm.md, "Noise estimate"). Needs the combabc CLI ($COMBABC, default
build-demo/apps/combabc) and numpy.
    /usr/bin/python3 examples/sensor-design/truth_profiles.py
"""
import csv
import subprocess
import tempfile
import pathlib

import run_study
import generate_data

EXPERIMENTS = [(45.0, 0.5, 0.5), (20.0, 0.5, 0.2), (80.0, 0.5, 0.2), (10.0, 0.5, 0.2)]  # designed
EXPERIMENTS += run_study.CENTRELINE
EXPERIMENTS += [(x, 0.5, s) for x in (10.0, 30.0, 50.0, 70.0) for s in (0.5, 0.2)]
EXPERIMENTS = list(dict.fromkeys(EXPERIMENTS))


def main():
    _, truth_model = run_study.model_and_truth_model()
    config = {"model": truth_model,
              "experiment": [run_study.experiment_table(*e) for e in EXPERIMENTS],
              "sampler": {"seed": 1}}
    with tempfile.TemporaryDirectory() as tmp:
        work = pathlib.Path(tmp)
        (work / "none.csv").write_text("position_cm,max_displacement_um\n0,0\n")
        (work / "truth.toml").write_text(generate_data.to_toml(config))
        subprocess.run([run_study.cli(), "simulate", str(work / "truth.toml"), "--clamps",
                        run_study.TRUTH, "-o", str(work / "profiles.csv")], check=True,
                       stdout=subprocess.DEVNULL)
        with open(work / "profiles.csv") as f:
            rows = list(csv.DictReader(f))
    lines = [f"# Noise-free scans of truth {run_study.TRUTH} in the finer perturbed model "
             "(truth_profiles.py)", "experiment,position_cm,displacement_um"]
    for e in EXPERIMENTS:
        name = run_study.name_of(*e)
        for r in rows:
            if r["experiment"] == name:
                lines.append(f"{name},{float(r['position_m']) * 100:.0f},"
                             f"{float(r['displacement_m']) * 1e6:.6e}")
    out = run_study.HERE / "truth_profiles.csv"
    out.write_text("\n".join(lines) + "\n")
    print(f"wrote {out} ({len(EXPERIMENTS)} experiments)")


if __name__ == "__main__":
    main()
