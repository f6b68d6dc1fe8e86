#!/usr/bin/env python3
"""Writes data.csv: the CalculiX model (model.py) at the ground truth TRUTH on a mesh REFINE times
finer in both directions (so the data do not come from the very model that calibrates them; the
other examples do the same, examples/README.md), plus Gaussian measurement noise of NOISE x the
peak (seeded), at the model's 91 centreline positions.

    python3 examples/sensor-calculix/generate_data.py      # needs ccx; rewrites data.csv
    python3 examples/sensor-calculix/generate_data.py --clamps BITS36 OUT.csv
                                  # the same at a full 36-clamp truth ('1' = clamp k fixed),
                                  # written to OUT.csv (examples/sensor-multifidelity)
"""
import pathlib
import random
import sys
import tempfile

import model

TRUTH = [1, 0]  # clamps 9 + 27 fixed, clamps 10 + 28 free (model.FREE_BITS)
NOISE = 0.01  # sd, as a fraction of the peak
SEED = 2026
REFINE = 2  # 360 x 16 elements of 2.5 mm


def main():
    if len(sys.argv) == 4 and sys.argv[1] == "--clamps":
        truth = [int(c) for c in sys.argv[2]]
        if len(truth) != 2 * model.CLAMPS_PER_EDGE or set(truth) - {0, 1}:
            sys.exit("--clamps wants 36 characters 0/1")
        fixed = ", ".join(str(k + 1) for k, c in enumerate(truth) if c) or "none"
        meaning = f"one bit per clamp, clamp 1 first: clamps {fixed} fixed"
        path = pathlib.Path(sys.argv[3]).resolve()
    elif len(sys.argv) == 1:
        truth = TRUTH
        meaning = "bit 1 = clamps 9 + 27 fixed, bit 2 = clamps 10 + 28 fixed; every other clamp free"
        path = pathlib.Path(__file__).resolve().parent / "data.csv"
    else:
        sys.exit(__doc__)
    model.NX, model.NY = REFINE * model.NX, REFINE * model.NY
    with tempfile.TemporaryDirectory() as work:
        values = model.simulate(model.clamps_from_bits(truth), work)
    rng = random.Random(SEED)
    peak = max(values)
    with open(path, "w", encoding="utf-8") as f:
        f.write(f"# The CalculiX sensor strip (model.py, mesh {model.NX} x {model.NY}), noise sd "
                f"{NOISE} x peak (seed {SEED}); generate_data.py\n")
        f.write(f"# truth {''.join(map(str, truth))} ({meaning})\n")
        f.write("position_cm,max_displacement_um\n")
        for x, w in zip(model.OUTPUT_X, values):
            f.write(f"{100 * x:.0f},{1e6 * (w + rng.gauss(0.0, NOISE * peak)):.6f}\n")


if __name__ == "__main__":
    main()
