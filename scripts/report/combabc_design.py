#!/usr/bin/python3
"""Figure of `combabc design`: each clamp's expected identifiability per candidate experiment.

    /usr/bin/python3 combabc_design.py IDENTIFIABILITY.csv OUT png|svg|pdf

IDENTIFIABILITY.csv is what combabc design writes: columns candidate, label, then one per bit
(clamp) holding E|2 P(fixed) - 1| over the plausible truths (0: the prior's coin, 1: decided).
One row of the figure per candidate, one column per clamp, edge 1 then edge 2. Exit status:
65 unreadable input, 69 numpy/matplotlib missing, 74 write failed.
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
        print("combabc_design: usage: combabc_design.py IDENTIFIABILITY.csv OUT png|svg|pdf",
              file=sys.stderr)
        return EX_DATAERR
    try:
        with open(argv[1], newline="") as f:
            rows = list(csv.reader(f))
        names = rows[0][2:]
        labels = [r[1] for r in rows[1:]]
        values = np.array([[float(v) for v in r[2:]] for r in rows[1:]], dtype=float)
    except (OSError, ValueError, IndexError) as e:
        print(f"combabc_design: {argv[1]}: {e}", file=sys.stderr)
        return EX_DATAERR
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
    fig.tight_layout()
    try:
        fig.savefig(argv[2], dpi=120, format=argv[3])
    except OSError as e:
        print(f"combabc_design: {argv[2]}: {e}", file=sys.stderr)
        return EX_IOERR
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
