#!/usr/bin/python3
"""Figure of `combabc design`: each clamp's expected identifiability per candidate experiment.

    /usr/bin/python3 combabc_design.py IDENTIFIABILITY.csv OUT png|svg|pdf

IDENTIFIABILITY.csv is what combabc design writes: columns candidate, label, then one per bit
(clamp) holding E|2 P(fixed) - 1| over the plausible truths (0: the prior's coin, 1: decided).
One row of the figure per candidate, one column per clamp, edge 1 then edge 2. Exit status:
65 unreadable input, 69 numpy/matplotlib missing, 74 write failed.

    /usr/bin/python3 combabc_design.py CAMPAIGN.csv OUT png|svg|pdf

CAMPAIGN.csv (design --posterior of a run): which experiment decided which clamp. One row per
clamp with its P(fixed) in the run, with the run's experiments together and with each alone; the
figure has one row each (run, together, then the experiments), one column per clamp, coloured
from free (0) to fixed (1), each decided cell (|P(fixed) - 0.5| > 0.4) marked with its verdict.
"""
import csv
import sys

EX_DATAERR, EX_UNAVAILABLE, EX_IOERR = 65, 69, 74

try:
    import numpy as np
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError as missing:
    print(f"combabc_design: needs numpy and matplotlib ({missing}); on Debian: "
          "apt-get install python3-numpy python3-matplotlib", file=sys.stderr)
    sys.exit(EX_UNAVAILABLE)


def main(argv):
    if len(argv) != 4 or argv[3] not in ("png", "svg", "pdf"):
        print("combabc_design: usage: combabc_design.py IDENTIFIABILITY.csv|CAMPAIGN.csv OUT "
              "png|svg|pdf", file=sys.stderr)
        return EX_DATAERR
    try:
        with open(argv[1], newline="") as f:
            rows = list(csv.reader(f))
        if rows and rows[0][:3] == ["clamp", "name", "edge"]:
            return campaign(rows, argv)
        names = rows[0][2:]
        labels = [r[1] for r in rows[1:]]
        values = np.array([[float(v) for v in r[2:]] for r in rows[1:]], dtype=float)
    except (OSError, ValueError, IndexError) as e:
        print(f"combabc_design: {argv[1]}: {e}", file=sys.stderr)
        return EX_DATAERR
    return save(fig_identifiability(names, labels, values), argv)


def fig_identifiability(names, labels, values):
    height = 1.2 + 0.28 * len(labels)
    fig, ax = plt.subplots(figsize=(max(8.0, 0.26 * len(names) + 4.0), height))
    image = ax.imshow(values, aspect="auto", cmap="viridis", vmin=0.0, vmax=1.0,
                      interpolation="nearest")
    ax.set_yticks(range(len(labels)), labels, fontsize=7)
    ax.set_xticks(range(len(names)), [n.replace("clamp ", "") for n in names], fontsize=6)
    ax.set_xlabel("clamp (edge 1, then edge 2)")
    half = len(names) / 2 - 0.5
    if len(names) % 2 == 0:
        ax.axvline(half, color="white", linewidth=1.0)
    fig.colorbar(image, ax=ax, label="expected |2 P(fixed) - 1|")
    ax.set_title("Expected identifiability of each clamp per candidate experiment")
    return fig


def campaign(rows, argv):
    try:
        header = rows[0]
        columns = [i for i, h in enumerate(header) if h.startswith("p_fixed_")]
        labels = ["the run", "together"] + [header[i].split(":", 1)[1] + " alone"
                                           for i in columns[2:]]
        names = [r[0] for r in rows[1:]]
        values = np.array([[float(r[i]) for r in rows[1:]] for i in columns], dtype=float)
    except (ValueError, IndexError) as e:
        print(f"combabc_design: {argv[1]}: {e}", file=sys.stderr)
        return EX_DATAERR
    fig, ax = plt.subplots(figsize=(max(8.0, 0.26 * len(names) + 4.0),
                                    1.4 + 0.32 * len(labels)))
    image = ax.imshow(values, aspect="auto", cmap="coolwarm", vmin=0.0, vmax=1.0,
                      interpolation="nearest")
    for (i, k), p in np.ndenumerate(values):
        if abs(p - 0.5) > 0.4:
            ax.text(k, i, "F" if p > 0.5 else "f", ha="center", va="center", fontsize=6,
                    color="white")
    ax.set_yticks(range(len(labels)), labels, fontsize=7)
    ax.set_xticks(range(len(names)), names, fontsize=6)
    ax.set_xlabel("clamp (edge 1, then edge 2); F fixed, f free: decided")
    if len(names) % 2 == 0:
        ax.axvline(len(names) / 2 - 0.5, color="black", linewidth=1.0)
    ax.axhline(1.5, color="black", linewidth=0.8)
    fig.colorbar(image, ax=ax, label="P(fixed)")
    ax.set_title("Which experiment decided which clamp (each alone: the other clamps at the "
                 "run's values)", fontsize=9)
    return save(fig, argv)


def save(fig, argv):
    fig.tight_layout()
    try:
        fig.savefig(argv[2], dpi=120, format=argv[3])
    except OSError as e:
        print(f"combabc_design: {argv[2]}: {e}", file=sys.stderr)
        return EX_IOERR
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
