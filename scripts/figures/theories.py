#!/usr/bin/python3
"""The figure of docs/model.md, "When the theory matters" (docs/figures/theories.png).

    build/examples/plate/plate_theory_sweep 2 > theories.csv
    /usr/bin/python3 scripts/figures/theories.py [--overwrite] [--coarse COARSE.csv] theories.csv OUT.png

Reads the CSV of examples/plate/theory_sweep.cpp (one row per sweep point: the peaks of Kirchhoff,
FSDT and RZT and the normalised-profile differences from RZT) and draws one column per sweep:
the core's modulus relative to the faces', the total thickness, the free span between fixed
clamps. Top row: each theory's peak |w| over RZT's (RZT is the closest to the exact 3D solution,
docs/model.md, "Plate theories"). Bottom row: the largest difference of the normalised profiles
from RZT's, in per cent of the peak. --coarse adds the same from a second CSV (another mesh) as
thin lines, to show what the mesh moves.

OUT.png is written only if it does not exist, unless --overwrite. Failures are one line on
stderr: status 66 input missing, 65 bad CSV, 69 numpy/matplotlib missing, 73 OUT refused or
not writable (no partial figure is left).
Needs numpy and matplotlib only (Debian: python3-numpy python3-matplotlib).
"""

import argparse
import csv
import os
import sys
import tempfile

EX_DATAERR, EX_NOINPUT, EX_UNAVAILABLE, EX_CANTCREAT = 65, 66, 69, 73

try:
    import numpy as np

    import matplotlib

    matplotlib.use("Agg")  # files only; never needs a display
    import matplotlib.pyplot as plt
except ImportError as missing:
    print(f"theories.py: needs numpy and matplotlib for {sys.executable} ({missing}); on Debian: "
          "apt-get install python3-numpy python3-matplotlib", file=sys.stderr)
    sys.exit(EX_UNAVAILABLE)

COLUMNS = ["sweep", "value", "kirchhoff_peak_um", "fsdt_peak_um", "rzt_peak_um",
           "fsdt_over_kirchhoff", "rzt_over_kirchhoff", "rzt_over_fsdt",
           "profile_diff_kirchhoff_rzt", "profile_diff_fsdt_rzt"]

# Per sweep: x label, the default sensor's value, log x, and what the x axis runs towards.
SWEEPS = {
    "core_modulus": ("core modulus / face modulus,  $E_{core}/E_{face}$", 1.0 / 6.0, True),
    "thickness": ("total thickness (mm), all layers scaled", 4.0, False),
    "free_span": ("free span between fixed clamps along the strip (cm)", None, False),
}
TITLES = {
    "core_modulus": "(a) core softness\n(clamps at the load fixed, h = 4 mm)",
    "thickness": "(b) thickness\n(clamps at the load fixed, $E_{core}/E_{face}$ = 1/6)",
    "free_span": "(c) clamp spacing\n(window of free clamps centred on the load)",
}
KIRCHHOFF, FSDT = "#1f4e9c", "#d2691e"


def fail(status, message):
    print(f"theories.py: {message}", file=sys.stderr)
    sys.exit(status)


def read(path):
    """{sweep: {column: numpy array}} from the example's CSV, each sweep sorted by value."""
    try:
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
    except FileNotFoundError:
        fail(EX_NOINPUT, f"{path}: no such file")
    except OSError as e:
        fail(EX_NOINPUT, f"{path}: {e.strerror}")
    if not rows or rows[0] != COLUMNS:
        fail(EX_DATAERR, f"{path}:1: header is not that of plate_theory_sweep ({','.join(COLUMNS)})")
    data = {}
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != len(COLUMNS) or row[0] not in SWEEPS:
            fail(EX_DATAERR, f"{path}:{line}: expected {len(COLUMNS)} fields, sweep one of "
                 f"{', '.join(SWEEPS)}")
        try:
            values = [float(v) for v in row[1:]]
        except ValueError:
            fail(EX_DATAERR, f"{path}:{line}: a field is not a number")
        data.setdefault(row[0], []).append(values)
    missing = [s for s in SWEEPS if s not in data]
    if missing:
        fail(EX_DATAERR, f"{path}: no rows for sweep {', '.join(missing)}")
    out = {}
    for sweep, values in data.items():
        a = np.array(sorted(values))
        out[sweep] = {name: a[:, k] for k, name in enumerate(COLUMNS[1:])}
    return out


def draw(axes, data, thin):
    width, alpha = (0.9, 0.55) if thin else (2.0, 1.0)
    style = dict(linewidth=width, alpha=alpha, marker=None if thin else "o", markersize=3.5)
    for column, sweep in enumerate(SWEEPS):
        d = data[sweep]
        r = d["rzt_peak_um"]
        top, bottom = axes[0][column], axes[1][column]
        top.plot(d["value"], d["kirchhoff_peak_um"] / r, color=KIRCHHOFF,
                 label=None if thin else "Kirchhoff", **style)
        top.plot(d["value"], d["fsdt_peak_um"] / r, color=FSDT, label=None if thin else "FSDT",
                 **style)
        bottom.plot(d["value"], 100 * d["profile_diff_kirchhoff_rzt"], color=KIRCHHOFF, **style)
        bottom.plot(d["value"], 100 * d["profile_diff_fsdt_rzt"], color=FSDT, **style)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("csv")
    parser.add_argument("out")
    parser.add_argument("--coarse", help="a second sweep (another mesh), drawn as thin lines")
    parser.add_argument("--coarse-label", default="10 x 6 per section",
                        help="legend text of --coarse")
    parser.add_argument("--label", default="20 x 12 per section", help="legend text of CSV")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing OUT")
    args = parser.parse_args()
    data = read(args.csv)
    coarse = read(args.coarse) if args.coarse else None
    if os.path.exists(args.out) and not args.overwrite:
        fail(EX_CANTCREAT, f"{args.out}: exists; pass --overwrite to replace it")

    fig, axes = plt.subplots(2, 3, figsize=(13, 6.6), sharex="col",
                             gridspec_kw=dict(height_ratios=[1.25, 1]))
    draw(axes, data, thin=False)
    if coarse is not None:
        draw(axes, coarse, thin=True)
    for column, (sweep, (xlabel, default, logx)) in enumerate(SWEEPS.items()):
        top, bottom = axes[0][column], axes[1][column]
        top.set_title(TITLES[sweep], fontsize=10)
        top.set_yscale("log")
        top.set_ylim(0.2, 2.5)
        top.set_yticks([0.25, 0.5, 0.75, 1, 1.5, 2])
        top.set_yticklabels(["0.25", "0.5", "0.75", "1", "1.5", "2"])
        top.minorticks_off()
        top.axhline(1.0, color="0.4", linewidth=0.8)
        bottom.set_ylim(0, 14)
        bottom.axhline(2.0, color="0.5", linewidth=0.8, linestyle="--")
        bottom.set_xlabel(xlabel)
        if logx:
            bottom.set_xscale("log")
            bottom.invert_xaxis()  # softer core to the right, as thicker and shorter spans
            bottom.set_xticks([1, 0.5, 0.2, 0.1, 0.05, 0.02, 0.01])
            bottom.set_xticklabels(["1", "1/2", "1/5", "1/10", "1/20", "1/50", "1/100"])
            bottom.minorticks_off()
        if sweep == "free_span":
            bottom.invert_xaxis()  # shorter spans to the right, where shear matters
            top.annotate("all fixed:\nspan = 4 cm width", xy=(0, 0.7), xytext=(28, 0.3),
                         fontsize=8, arrowprops=dict(arrowstyle="->", color="0.3"))
            top.text(88, 1.1, "all free", fontsize=8)
        if default is not None:
            for ax in (top, bottom):
                ax.axvline(default, color="0.6", linewidth=0.8, linestyle=":")
            top.text(default, 2.3, " default", fontsize=8, color="0.35", va="top")
        for ax in (top, bottom):
            ax.grid(True, which="major", color="0.9", linewidth=0.6)
    axes[0][0].set_ylabel("peak |w| over RZT's")
    axes[1][0].set_ylabel("profile shape difference\nfrom RZT (% of peak)")
    axes[1][0].text(0.98, 2.3, "2 %: the mesh criterion", fontsize=8, color="0.35",
                    transform=axes[1][0].get_yaxis_transform(), ha="right")
    handles, labels = axes[0][0].get_legend_handles_labels()
    if coarse is not None:
        handles += [plt.Line2D([], [], color="0.3", linewidth=2.0, marker="o", markersize=3.5),
                    plt.Line2D([], [], color="0.3", linewidth=0.9, alpha=0.55)]
        labels += [args.label, args.coarse_label]
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), frameon=False,
               fontsize=9)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    out_dir = os.path.dirname(os.path.abspath(args.out))
    if not os.path.isdir(out_dir):
        fail(EX_CANTCREAT, f"{args.out}: no directory {out_dir}")
    # Written beside OUT and renamed, so that a failure leaves no partial figure.
    partial = None
    try:
        fd, partial = tempfile.mkstemp(prefix=".theories-", suffix=".png", dir=out_dir)
        umask = os.umask(0)
        os.umask(umask)
        os.fchmod(fd, 0o666 & ~umask)  # mkstemp makes it private; a figure is not
        with os.fdopen(fd, "wb") as f:
            fig.savefig(f, format="png", dpi=90)
        os.replace(partial, args.out)
    except OSError as e:
        if partial is not None and os.path.exists(partial):
            os.unlink(partial)
        fail(EX_CANTCREAT, f"{args.out}: {e.strerror}")


if __name__ == "__main__":
    main()
