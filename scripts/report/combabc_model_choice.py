#!/usr/bin/python3
"""Figure of a model choice (docs/algorithm.md, "Model choice"): P(model) after each wave.

    /usr/bin/python3 combabc_model_choice.py --out FIGURE.png -- WAVES.csv

WAVES.csv is what `combabc run` writes to model_choice/waves.csv for a config with
[model_choice]: columns wave, model, log_evidence, relative_se, probability, se,
upper_bound_only, upper; one row per wave and model. One line per model with its +-2 se band; a
model with only an upper bound at a wave is drawn as a downward triangle at that bound. Before
the last wave each model's evidence is at its own run's thresholds (the caption says so). Exit
status: 65 unreadable input, 69 numpy/matplotlib missing, 74 write failed.
"""
import csv
import math
import sys

EX_DATAERR, EX_UNAVAILABLE, EX_IOERR = 65, 69, 74

try:
    import numpy as np
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError as missing:
    print(f"combabc_model_choice: needs numpy and matplotlib ({missing}); on Debian: "
          "apt-get install python3-numpy python3-matplotlib", file=sys.stderr)
    sys.exit(EX_UNAVAILABLE)


def read(path):
    """{model: (waves, probability, se, upper_bound_only, upper)} in the file's model order."""
    models = {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            columns = models.setdefault(row["model"], ([], [], [], [], []))
            columns[0].append(int(row["wave"]))
            columns[1].append(float(row["probability"]))
            columns[2].append(float(row["se"]))
            columns[3].append(row["upper_bound_only"] == "1")
            columns[4].append(float(row["upper"]))
    if not models:
        raise ValueError("no rows")
    return {name: tuple(np.array(c) for c in columns) for name, columns in models.items()}


def figure(models):
    fig, ax = plt.subplots(figsize=(6.4, 3.8))
    for name, (wave, p, se, bound, upper) in models.items():
        estimated = ~bound & np.isfinite(p)
        line, = ax.plot(wave[estimated], p[estimated], marker="o", markersize=3.5, label=name)
        ax.fill_between(wave[estimated], np.clip(p - 2 * se, 0, 1)[estimated],
                        np.clip(p + 2 * se, 0, 1)[estimated], color=line.get_color(),
                        alpha=0.2, linewidth=0)
        if bound.any():
            ax.plot(wave[bound], upper[bound], marker="v", linestyle="none",
                    color=line.get_color(), label=f"{name}: P below (no estimate)")
    waves = max(int(c[0].max()) for c in models.values())
    ax.set_xlim(0.5, waves + 0.5)
    ax.set_xticks(range(1, waves + 1, max(1, math.ceil(waves / 15))))
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel("wave")
    ax.set_ylabel("P(model | data)")
    ax.set_title("Model probabilities after each wave (band: ± 2 se)", fontsize=10)
    fig.text(0.01, 0.01, "Before the final wave each model's evidence is at its own run's "
             "thresholds.", fontsize=7, color="#555555")
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    return fig


def main(argv):
    if len(argv) != 5 or argv[1] != "--out" or argv[3] != "--":
        print("combabc_model_choice: usage: combabc_model_choice.py --out FIGURE.png -- "
              "WAVES.csv", file=sys.stderr)
        return EX_DATAERR
    try:
        models = read(argv[4])
    except (OSError, ValueError, KeyError) as e:
        print(f"combabc_model_choice: {argv[4]}: {e}", file=sys.stderr)
        return EX_DATAERR
    fig = figure(models)
    try:
        fig.savefig(argv[2], format="png", dpi=120)
    except OSError as e:
        print(f"combabc_model_choice: {argv[2]}: {e}", file=sys.stderr)
        return EX_IOERR
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
