#!/usr/bin/env python3
"""The built-in sensor's plate theories against the layered 3D solid (solid3d.py) on the six
configurations of examples/plate/theory_comparison.cpp, with every loss factor 0 (the 3D model's
static step has no damping). Prints a Markdown table: per configuration and theory the peak ratio
theory / 3D and the largest difference of the two profiles, each divided by its own peak, in % of
the peak.

    /usr/bin/python3 examples/plate/solid3d/compare.py [--combabc combabc]
        [--out results-solid3d] [--mesh 40x24] [--solid 10x8x2] [--face top|mid]
        [--theories kirchhoff:20x12,fsdt,rzt:10x3:2] [--cases 1,3]

Every profile is cached as a CSV in --out (3D: solid-<mesh>-<clamps>.csv; combabc:
<theory>-<mesh>[-order2]-<clamps>.csv), so a second run with more meshes only computes what is
new. Order 2 puts FSDT on MITC9 and RZT on RZT9 elements ([model.mesh] element_order).
"""
import argparse
import csv
import os
import pathlib
import subprocess
import sys
import time

HERE = pathlib.Path(__file__).resolve().parent
SOURCE = HERE.parent.parent / "sensor-45cm" / "least_squares.toml"


def both_edges(pick):
    edge = "".join("1" if pick(s) else "0" for s in range(1, 19))
    return edge + edge


CASES = [
    ("all free", both_edges(lambda s: False)),
    ("all fixed", both_edges(lambda s: True)),
    ("clamps at the load fixed (9, 10)", both_edges(lambda s: s in (9, 10))),
    ("one side fixed at the load", "000000001100000000" + "0" * 18),
    ("alternating", both_edges(lambda s: s % 2 == 0)),
    ("measured window free (10-16)", both_edges(lambda s: s < 10 or s > 16)),
]


def model_table(theory, per_section, across, order=1):
    """least_squares.toml's [model] with every loss factor 0, the theory and the mesh."""
    out, in_model = [], False
    for line in SOURCE.read_text(encoding="utf-8").splitlines():
        if line.startswith("["):
            in_model = line.startswith("[model") or line.startswith("[[model")
            if in_model and line.strip() == "[model.mesh]":
                out += [line, f"elements_per_section = {per_section}",
                        f"elements_across_width = {across}", f"element_order = {order}"]
                in_model = False  # its keys are replaced
                continue
        if not in_model:
            continue
        key = line.split("=")[0].strip()
        if key in ("loss_factor", "foundation_loss_factor"):
            line = f"{key} = 0.0"
        out.append(line)
        if line.strip() == "[model]":
            out.append(f'theory = "{theory}"')
    return "\n".join(out) + "\n"


# `simulate` reads a whole config; the data, metric and sampler are not used.
REST = f"""
[data]
csv = "{HERE.parent.parent / 'sensor-calculix' / 'data.csv'}"
position_column = "position_cm"
displacement_column = "max_displacement_um"
position_unit = "cm"
displacement_unit = "um"

[metric]
preset = "least_squares"
quantile = 0.3

[sampler]
waves = 1
accepted_per_wave = 10
"""


def read_column(path, column):
    with open(path, encoding="utf-8") as f:
        return [float(row[column]) for row in csv.DictReader(r for r in f if not r.startswith("#"))]


def builtin(combabc, theory, mesh, clamps, out):
    """mesh: (per section, across, element order)."""
    name = f"{theory}-{mesh[0]}x{mesh[1]}" + ("-order2" if mesh[2] == 2 else "")
    path = out / f"{name}-{clamps}.csv"
    if not path.exists():
        config = out / f"{name}.toml"
        config.write_text(model_table(theory, *mesh) + REST, encoding="utf-8")
        start = time.perf_counter()
        subprocess.run([combabc, "simulate", str(config), "--clamps", clamps, "-o", str(path)],
                       check=True, stdout=subprocess.DEVNULL)
        print(f"# combabc simulate {name}: "
              f"{time.perf_counter() - start:.1f} s", file=sys.stderr)
    return [1e6 * v for v in read_column(path, "displacement_m")]


def solid(mesh, clamps, out, threads):
    path = out / f"solid-{mesh[0]}x{mesh[1]}x{mesh[2]}-{clamps}.csv"
    if not path.exists():
        text = subprocess.run(
            [sys.executable, str(HERE / "solid3d.py"), "--clamps", clamps,
             "--per-section", str(mesh[0]), "--across", str(mesh[1]), "--per-layer", str(mesh[2]),
             "--threads", str(threads)],
            check=True, stdout=subprocess.PIPE, text=True).stdout
        path.write_text(text, encoding="utf-8")
    return read_column(path, "top_um"), read_column(path, "mid_um")


def compare(a, b):
    """(peak a / peak b, max |a / peak a - b / peak b| in % of the peak)."""
    pa, pb = max(a), max(b)
    return pa / pb, 100.0 * max(abs(x / pa - y / pb) for x, y in zip(a, b))


def mesh_arg(text, n):
    parts = [int(v) for v in text.lower().split("x")]
    if len(parts) != n:
        raise argparse.ArgumentTypeError(f"{text}: want {n} numbers joined by x")
    return tuple(parts)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--combabc", default="combabc", help="the CLI (default: combabc on PATH)")
    p.add_argument("--out", default="results-solid3d", help="cache folder for the profiles")
    p.add_argument("--mesh", type=lambda t: mesh_arg(t, 2), default=(40, 24),
                   help="combabc elements per section x across the width")
    p.add_argument("--solid", type=lambda t: mesh_arg(t, 3), default=(10, 8, 2),
                   help="3D elements per section x across x per layer")
    p.add_argument("--theories", default="kirchhoff,fsdt,rzt",
                   help="comma-separated theory[:PERxACROSS[:ORDER]], e.g. "
                   "kirchhoff:20x12,rzt:10x3:2 (default mesh --mesh, order 1)")
    p.add_argument("--cases", default="", help="indices (0-5) of the cases, comma-separated")
    p.add_argument("--threads", type=int, default=1, help="ccx threads")
    p.add_argument("--face", choices=("top", "mid"), default="top",
                   help="the 3D profile compared: top face (the LDV's) or mid-plane")
    a = p.parse_args()
    out = pathlib.Path(a.out)
    os.makedirs(out, exist_ok=True)
    picked = [CASES[int(i)] for i in a.cases.split(",")] if a.cases else CASES
    theories = []
    for spec in a.theories.split(","):
        name, _, rest = spec.partition(":")
        mesh, _, order = rest.partition(":")
        theories.append((name, (*(mesh_arg(mesh, 2) if mesh else a.mesh), int(order or 1))))
    print(f"3D mesh {a.solid[0] * 18} x {a.solid[1]} x {a.solid[2] * 3}; combabc meshes per "
          f"section as named; loss factors 0; against the 3D "
          f"{'top face' if a.face == 'top' else 'mid-plane'}\n")
    print("| configuration | clamps | 3D peak (um) | top / mid-plane | "
          + " | ".join(f"{t} {m[0]}x{m[1]}{' order 2' if m[2] == 2 else ''} peak ratio | "
                       "profile diff" for t, m in theories)
          + " |")
    print("|---|---|---|---|" + "---|---|" * len(theories))
    for name, clamps in picked:
        top, mid = solid(a.solid, clamps, out, a.threads)
        row = [name, f"`{clamps}`", f"{max(top):.4g}", f"{max(top) / max(mid):.4f}"]
        for theory, mesh in theories:
            reference = top if a.face == "top" else mid
            ratio, diff = compare(builtin(a.combabc, theory, mesh, clamps, out), reference)
            row += [f"{ratio:.3f}", f"{diff:.1f} %"]
        print("| " + " | ".join(row) + " |", flush=True)


if __name__ == "__main__":
    main()
