#!/usr/bin/python3
"""Generates the examples' "measured" data from documented ground-truth clamp configurations.

The data must never come from the exact model that calibrates them, so each data set is simulated
with a model that differs from the example config's [model] in three ways:
  * a finer mesh: twice the elements per clamp section and across the width;
  * perturbed materials: each layer's Young's modulus, thickness and density, and the foundation
    stiffness, multiplied by exp(N(0, s^2)) with s = 5 %, 2 %, 2 % and 10 %;
  * measurement noise: Gaussian, sigma = 1 % of the largest displacement in the window,
and only the positions the paper's LDV measured are kept (every 1 cm over the window).
Everything is seeded, so the files are reproducible:  /usr/bin/python3 examples/generate_data.py
It needs the combabc CLI (default build-demo/apps/combabc; override with $COMBABC).
"""
import os
import pathlib
import subprocess
import sys
import tempfile
import tomllib

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent

# Ground truths (1 = clamp fixed), clamps 1-18 on one edge from x = 0, 19-36 facing them.
EXAMPLES = [
    {
        # Paper Figures 1, 3-6: free at the 45 cm load (clamps 9-11, 27-29), fixed 10-20 cm away
        # (clamps 8, 12, 13 and 26, 30, 31), the rest arbitrary.
        "dir": "sensor-45cm",
        "config": "least_squares.toml",
        "truth": "101101010001101001" "011011010001101100",
        "window_cm": (48, 80),
        "seed": 45,
    },
    {
        # Paper Figures 7-11: load at 70 cm, fixed clamps 14, 15, 32, 33 (65-75 cm) as the paper
        # infers, free clamps 16 and 34 beyond them, the rest arbitrary.
        "dir": "sensor-70cm",
        "config": "split_least_squares.toml",
        "truth": "010110100101011001" "101001011010011010",
        "window_cm": (74, 89),
        "seed": 70,
    },
]


def emit(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return '"' + value.replace('"', '\\"') + '"'
    if isinstance(value, list):
        return "[" + ", ".join(emit(v) for v in value) + "]"
    raise TypeError(value)


def to_toml(table, prefix=""):
    """A small TOML writer for configs: scalars, arrays, tables and arrays of tables."""
    lines, subtables = [], []
    for key, value in table.items():
        name = f"{prefix}.{key}" if prefix else key
        if isinstance(value, dict):
            subtables.append((name, value, False))
        elif isinstance(value, list) and value and isinstance(value[0], dict):
            subtables.extend((name, item, True) for item in value)
        else:
            lines.append(f"{key} = {emit(value)}")
    out = "\n".join(lines) + ("\n" if lines else "")
    for name, sub, is_array in subtables:
        out += f"\n[[{name}]]\n" if is_array else f"\n[{name}]\n"
        out += to_toml(sub, name)
    return out


def perturbed(model, rng):
    model = dict(model)
    layers = []
    for layer in model["layer"]:
        layer = dict(layer)
        layer["young_modulus"] *= float(np.exp(rng.normal(0, 0.05)))
        layer["thickness"] *= float(np.exp(rng.normal(0, 0.02)))
        layer["density"] *= float(np.exp(rng.normal(0, 0.02)))
        layers.append(layer)
    model["layer"] = layers
    model["foundation_stiffness"] *= float(np.exp(rng.normal(0, 0.10)))
    mesh = dict(model["mesh"])
    mesh["elements_per_section"] *= 2
    mesh["elements_across_width"] *= 2
    model["mesh"] = mesh
    return model


def generate(example, cli):
    folder = ROOT / example["dir"]
    with open(folder / example["config"], "rb") as f:
        config = tomllib.load(f)
    rng = np.random.default_rng(example["seed"])
    truth_config = dict(config)
    truth_config["model"] = perturbed(config["model"], rng)
    truth_config["data"] = dict(config["data"])
    truth_config["data"].pop("gaussian_extension", None)
    with tempfile.TemporaryDirectory() as tmp:
        cfg = pathlib.Path(tmp) / "truth.toml"
        cfg.write_text(to_toml(truth_config))
        (pathlib.Path(tmp) / config["data"]["csv"]).write_text("x,y\n0,0\n")
        out = pathlib.Path(tmp) / "profile.csv"
        subprocess.run([cli, "simulate", str(cfg), "--clamps", example["truth"], "-o", str(out)],
                       check=True)
        profile = np.loadtxt(out, delimiter=",", skiprows=1)
    x_cm = np.round(profile[:, 0] * 100.0, 6)
    lo, hi = example["window_cm"]
    keep = (x_cm >= lo - 1e-9) & (x_cm <= hi + 1e-9)
    w_um = profile[keep, 1] * 1e6
    sigma = 0.01 * np.max(w_um)
    noisy = np.abs(w_um + rng.normal(0.0, sigma, size=w_um.shape))  # an LDV reports amplitudes
    lines = [
        f"# Synthetic measurement for combabc's {example['dir']} example (examples/generate_data.py):",
        # tests/examples/posterior_test.cpp reads the truth from this line: keep "# truth <bits>".
        f"# truth {example['truth']} (1 = fixed), finer mesh, perturbed materials, "
        f"noise sigma {sigma:.4f} um.",
        "position_cm,max_displacement_um",
    ]
    lines += [f"{x:.0f},{w:.5f}" for x, w in zip(x_cm[keep], noisy)]
    (folder / config["data"]["csv"]).write_text("\n".join(lines) + "\n")
    print(f"wrote {folder / config['data']['csv']} ({keep.sum()} points)")


def main():
    cli = os.environ.get("COMBABC", str(ROOT.parent / "build-demo" / "apps" / "combabc"))
    if not pathlib.Path(cli).exists():
        sys.exit(f"combabc CLI not found at {cli}; build it (bash scripts/demo.sh) or set COMBABC")
    for example in EXAMPLES:
        generate(example, cli)


if __name__ == "__main__":
    main()
