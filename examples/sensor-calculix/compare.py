#!/usr/bin/env python3
"""CalculiX (model.py) against the built-in sensor model (`combabc simulate` on a config whose
[model] has only `theory`, every other key at its default: docs/model.md) on the example's four
configurations: peak |w|,
where it is, and the largest difference of the two profiles each normalised by its own peak (over
0-90 cm and over the 48-80 cm window), and the time of each CalculiX run.

    python3 examples/sensor-calculix/compare.py [path/to/combabc [theory]]
    # defaults: combabc (on PATH), kirchhoff (the theory of the README's table; CalculiX's S4
    # shell is an equivalent single layer, closest to the built-in "fsdt")
"""
import csv
import pathlib
import subprocess
import sys
import tempfile
import time

import model

HERE = pathlib.Path(__file__).resolve().parent
# The default sensor (load 0.04 N at 45 cm, 5 Hz; outputs every 1 cm on 0-90 cm) with
# config.toml's data and metric; `simulate` needs a whole config.
BUILTIN = """[model]
theory = "{theory}"

[data]
csv = "{data}"
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


def builtin(combabc, theory, clamps, work):
    out = pathlib.Path(work) / "builtin.csv"
    config = pathlib.Path(work) / "builtin.toml"
    config.write_text(BUILTIN.format(theory=theory, data=HERE / "data.csv"), encoding="utf-8")
    subprocess.run([combabc, "simulate", str(config), "--clamps", clamps,
                    "-o", str(out), "--overwrite"], check=True, stdout=subprocess.DEVNULL)
    with open(out, encoding="utf-8") as f:
        return [float(row["displacement_m"]) for row in csv.DictReader(f)]


def main():
    combabc = sys.argv[1] if len(sys.argv) > 1 else "combabc"
    theory = sys.argv[2] if len(sys.argv) > 2 else "kirchhoff"
    print("bits  clamps fixed      CalculiX peak        built-in peak        ratio  "
          "max |diff| normalised (0-90 / 48-80 cm)  ccx run")
    for bits in ([0, 0], [1, 0], [0, 1], [1, 1]):
        clamps = model.clamps_from_bits(bits)
        text = "".join(map(str, clamps))
        with tempfile.TemporaryDirectory() as work:
            start = time.perf_counter()
            ccx = model.simulate(clamps, work)
            seconds = time.perf_counter() - start
            ref = builtin(combabc, theory, text, work)
        fixed = ",".join(str(k + 1) for k, c in enumerate(clamps) if c) or "none"
        peak_c, peak_b = max(ccx), max(ref)
        diff = [abs(c / peak_c - b / peak_b) for c, b in zip(ccx, ref)]
        window = diff[48:81]
        print(f"{''.join(map(str, bits))}    {fixed:<16}"
              f"{1e6 * peak_c:8.3f} um at {ccx.index(peak_c):2d} cm  "
              f"{1e6 * peak_b:8.3f} um at {ref.index(peak_b):2d} cm  "
              f"{peak_c / peak_b:5.3f}  {max(diff):.4f} / {max(window):.4f}"
              f"{'':24}{seconds:.2f} s")


if __name__ == "__main__":
    main()
