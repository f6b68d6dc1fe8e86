#!/usr/bin/env python3
"""combabc from Python, step by step (docs/python.md).

1. A toy model: ten on/off switches seen through a noisy linear sensor. Its exact ABC posterior
   comes from enumerating all 2^10 configurations; ABC-SMC with a Python simulator recovers it,
   writes its history and draws its figures (combabc.plot).
2. The sensor: the built-in plate model of the 45 cm fibre-optic sensor, its profile for a clamp
   configuration, a short calibration from its config file, and the result as pandas tables and
   as an ArviZ-style NetCDF file.

Run from the build tree:

    PYTHONPATH=build/python /usr/bin/python3 examples/python/tutorial.py [--small] [--out DIR]

--small runs it in a few seconds (CI runs it so); the default sizes take about a minute.
"""

import argparse
import itertools
import pathlib
import re
import tempfile

import numpy as np

import combabc

EXAMPLES = pathlib.Path(__file__).resolve().parents[1]

# --- 1. a toy model ------------------------------------------------------------------------------

D = 10
WEIGHTS = np.random.default_rng(1).integers(0, 4, size=(4, D)).astype(float)
TRUTH = np.array([1, 0, 1, 1, 0, 0, 1, 0, 0, 1], dtype=np.uint8)
OBSERVED = WEIGHTS @ TRUTH
PRIOR = 0.5
THRESHOLDS = [8.0, 5.0, 3.0]


def simulate(bits):
    """One configuration (uint8[10]) to the four readings."""
    return WEIGHTS @ bits


def simulate_batch(bits):
    """Vectorised: n configurations (uint8[n, 10]) at once, one interpreter call per batch."""
    return bits @ WEIGHTS.T


def exact_marginals(eps):
    """P(switch k on | distance <= eps) by enumerating every configuration (uniform prior)."""
    configurations = np.array(list(itertools.product([0, 1], repeat=D)), dtype=float)
    distance = np.linalg.norm(configurations @ WEIGHTS.T - OBSERVED, axis=1)
    accepted = configurations[distance <= eps]
    return accepted.mean(axis=0), len(accepted)


def toy_model(accepted_per_wave, out):
    print("1. A toy model: 10 switches, 4 readings")
    space = combabc.BinarySpace(dimension=D, default_prior_one=PRIOR,
                                names=[f"switch {k + 1}" for k in range(D)])
    problem = combabc.Problem(space, simulate_batch, observed=OBSERVED, batch=True)
    options = combabc.make_options(num_waves=len(THRESHOLDS), accepted_per_wave=accepted_per_wave,
                                   thresholds=THRESHOLDS, estimator="importance", seed=7,
                                   threads=2)
    # output_directory: the run writes its history (out/toy/history.sqlite), which
    # combabc.resume(path, problem, options) continues after a crash and combabc.export reads.
    history = combabc.run(problem, options, output_directory=out / "toy", overwrite=True)
    print(history)
    print(history.wave_table()[["wave", "eps_euclidean", "candidates", "accepted", "ess"]]
          .to_string(index=False))
    exact, count = exact_marginals(THRESHOLDS[-1])
    last = history.waves[-1]
    # 4.5 Monte-Carlo standard errors at the wave's effective sample size.
    bound = 4.5 * np.sqrt(exact * (1 - exact) / last.ess) + 0.005
    print(f"exact posterior: {count} of {2 ** D} configurations within eps = {THRESHOLDS[-1]}")
    print("switch   exact    ABC-SMC  truth")
    for k in range(D):
        print(f"{k + 1:6d}  {exact[k]:6.3f}  {history.posterior[k]:7.3f}  {TRUTH[k]:5d}")
    worst = np.max(np.abs(history.posterior - exact) - bound)
    assert worst <= 0, f"ABC-SMC is off the exact posterior by {worst:.3f} beyond its bound"
    # The same run, one configuration per call: the same history, whatever the batching.
    single = combabc.run(combabc.Problem(space, simulate, observed=OBSERVED), options)
    assert np.array_equal(single.waves[-1].bits, last.bits)
    print("the per-sample simulator gives the same history")
    figures(history, out / "toy")
    print()


def figures(history, out):
    """combabc.plot's figures of a run, as PNG files (needs python3-matplotlib)."""
    try:
        import matplotlib
    except ImportError as missing:
        print(f"no figures ({missing})")
        return
    matplotlib.use("Agg")
    import combabc.plot
    for name in ("marginals", "curves", "thresholds", "predictive_band"):
        getattr(combabc.plot, name)(history).savefig(out / f"{name}.png", dpi=80)
    print(f"figures: {out}/{{marginals,curves,thresholds,predictive_band}}.png")


# --- 2. the sensor -------------------------------------------------------------------------------

def sensor_config(out, small):
    """The 45 cm example's least-squares config, writing into `out` (smaller with --small)."""
    example = EXAMPLES / "sensor-45cm"
    text = (example / "least_squares.toml").read_text()
    changes = [(r'(?m)^csv = "data.csv"', f'csv = "{example / "data.csv"}"'),
               (r'(?m)^directory = "[^"]*"', f'directory = "{out / "sensor-run"}"'),
               (r"(?m)^threads = \d+", "threads = 2")]
    if small:
        changes += [(r"(?m)^waves = \d+", "waves = 2"),
                    (r"(?m)^accepted_per_wave = \d+", "accepted_per_wave = 50"),
                    (r"(?m)^elements_per_section = \d+", "elements_per_section = 4"),
                    (r"(?m)^elements_across_width = \d+", "elements_across_width = 2")]
    for pattern, replacement in changes:
        text, count = re.subn(pattern, replacement, text)
        assert count == 1, pattern
    path = out / "sensor.toml"
    path.write_text(text)
    return path


def sensor(out, small):
    print("2. The sensor (examples/sensor-45cm)")
    config = sensor_config(out, small)
    model = combabc.SensorModel(config)
    clamps = "0" * 10 + "1" * 16 + "0" * 10  # 1 = clamp fixed, as `combabc simulate --clamps`
    profile = model.profile(clamps, normalised=True)
    print(f"{model}: the profile of {clamps} peaks at x = "
          f"{model.positions[np.argmax(profile)]:.2f} m")

    history = combabc.run(config)  # as `combabc run sensor.toml --no-report`
    print(history)
    marginals = history.marginals()
    last = marginals[marginals["wave"] == marginals["wave"].max()]
    print("P(clamp fixed), final wave:",
          " ".join(f"{p:.2f}" for p in last["prob_importance"].to_numpy()))
    path = out / "sensor.nc"
    try:
        history.to_netcdf(path)  # needs python3-xarray python3-netcdf4
    except ImportError as missing:
        print(f"no NetCDF file ({missing})")
        return
    import xarray as xr
    posterior = xr.open_dataset(path, group="posterior")
    print(f"wrote {path}: posterior bits {dict(posterior['bits'].sizes)}")
    posterior.close()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--small", action="store_true", help="small sizes (seconds; CI)")
    parser.add_argument("--out", help="directory to write into (default: a new temporary one)")
    args = parser.parse_args()
    out = pathlib.Path(args.out) if args.out else pathlib.Path(tempfile.mkdtemp(prefix="combabc-"))
    out.mkdir(parents=True, exist_ok=True)
    toy_model(1000 if args.small else 5000, out)
    sensor(out, args.small)
    print(f"files in {out}")


if __name__ == "__main__":
    main()
