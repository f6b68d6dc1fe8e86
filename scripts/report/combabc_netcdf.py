#!/usr/bin/env python3
"""A combabc run as a NetCDF file in ArviZ's InferenceData layout (docs/history.md, "NetCDF").

    combabc_netcdf.py --particles particles.csv --measured measured.csv --summary summary.json
                      --out inference_data.nc

`combabc export` runs it on the files it has just staged, so that the NetCDF values are the CSVs'
(it is not meant to be run by hand, though it can be on any export directory). The Python module
imports the same builder (`inference_data`) for History.to_inference_data(), so both write one
layout:

- posterior: the final wave's accepted particles as draws of one chain: `bits` (chain, draw, bit;
  uint8, the bit coordinate holds the bit / clamp names) and one variable per continuous parameter
  (chain, draw);
- sample_stats: `weight` and `log_weight` (chain, draw), `distance` (chain, draw, component) and
  `particle_index`, the particle's candidate index in its wave;
- observed_data: `measured` (position), its coordinate the measured positions; a run of named
  experiments instead has one variable per experiment, `measured_<name>` (position_<name>), each
  with its own positions, and sample_stats the coordinate `component_experiment` (component);
- attributes of every group: inference_library = combabc, its version, the seed, the wave (from 1),
  the termination, the config file's path and text.

Exit status (sysexits): 0, 64 usage, 65 unreadable input, 69 xarray or netCDF4 missing, 74 I/O.
"""

import argparse
import json
import sys

EX_USAGE, EX_DATAERR, EX_UNAVAILABLE, EX_SOFTWARE, EX_IOERR = 64, 65, 69, 70, 74
NEEDS = ("the NetCDF file needs xarray and netCDF4 for {python}; on Debian: apt-get install "
         "python3-xarray python3-netcdf4, or set COMBABC_PYTHON to a python that has them")


def variable_name(name):
    """NetCDF names may hold any character but '/'."""
    return name.replace("/", "_")


def named_experiments(experiments):
    """The experiments when they have names (a config with [[experiment]] tables), else None: a
    single unnamed experiment is drawn as before experiments existed."""
    experiments = list(experiments or ())
    return experiments if any(x["name"] for x in experiments) else None


def inference_data(*, bits, reals, log_weight, weight, distance, index, bit_names, real_names,
                   components, measured_position, measured_value, position_unit, attrs,
                   experiments=None):
    """The groups posterior, sample_stats and observed_data as xarray Datasets (a dict by group
    name), from one wave's particles as NumPy arrays (n draws): bits uint8[n, d], reals
    float64[n, r], log_weight, weight float64[n], distance float64[n, k], index int64[n].
    experiments: the run's experiments as dicts (name, description, first_measured, measured,
    first_component, components: summary.json's "experiments"), or None for one holding
    everything."""
    import numpy as np
    import xarray as xr

    n = len(weight)
    attrs = {key: ("" if value is None else value) for key, value in attrs.items()}
    attrs.setdefault("inference_library", "combabc")
    draws = {"chain": np.array([0]), "draw": np.arange(n)}
    posterior = {"bits": (("chain", "draw", "bit"),
                          np.asarray(bits, dtype=np.uint8).reshape(1, n, len(bit_names)))}
    reals = np.asarray(reals, dtype=np.float64).reshape(n, len(real_names))
    for k, name in enumerate(real_names):
        posterior[variable_name(name)] = (("chain", "draw"), reals[None, :, k])
    sample_stats = {
        "weight": (("chain", "draw"), np.asarray(weight, dtype=np.float64)[None]),
        "log_weight": (("chain", "draw"), np.asarray(log_weight, dtype=np.float64)[None]),
        "distance": (("chain", "draw", "component"),
                     np.asarray(distance, dtype=np.float64).reshape(1, n, len(components))),
        "particle_index": (("chain", "draw"), np.asarray(index, dtype=np.int64)[None]),
    }
    measured_position = np.asarray(measured_position, dtype=np.float64)
    measured_value = np.asarray(measured_value, dtype=np.float64)
    units = {"units": position_unit or "m"}
    stats_coords = {**draws, "component": list(components)}
    named = named_experiments(experiments)
    if named is None:
        position = xr.Variable("position", measured_position, attrs=units)
        observed = {"measured": ("position", measured_value)}
        observed_coords = {"position": position}
    else:
        # One observed variable per experiment, on its own positions (experiments may scan the
        # same stretch, or lines of different lengths): what ArviZ gets from a model with one
        # likelihood per data set.
        observed, observed_coords = {}, {}
        owner = [""] * len(components)
        for x in named:
            name = variable_name(x["name"])
            rows = slice(x["first_measured"], x["first_measured"] + x["measured"])
            dim = f"position_{name}"
            observed_coords[dim] = xr.Variable(dim, measured_position[rows], attrs=units)
            observed[f"measured_{name}"] = xr.Variable(
                dim, measured_value[rows],
                attrs={"experiment": x["name"], "description": x.get("description", "")})
            first = x.get("first_component", 0)
            for k in range(first, min(first + x.get("components", 0), len(owner))):
                owner[k] = x["name"]
        stats_coords["component_experiment"] = ("component", owner)
    return {
        "posterior": xr.Dataset(posterior, coords={**draws, "bit": list(bit_names)}, attrs=attrs),
        "sample_stats": xr.Dataset(sample_stats, coords=stats_coords, attrs=attrs),
        "observed_data": xr.Dataset(observed, coords=observed_coords, attrs=attrs),
    }


def write_netcdf(groups, path):
    """The groups into one NetCDF-4 file, one HDF5 group each (what arviz.from_netcdf reads)."""
    mode = "w"
    for name, dataset in groups.items():
        dataset.to_netcdf(path, mode=mode, group=name, engine="netcdf4")
        mode = "a"


def from_export(particles_csv, measured_csv, summary_json):
    """The builder's arguments from an export's files: the final wave's particles."""
    import numpy as np
    import pandas as pd

    with open(summary_json, encoding="utf-8") as f:
        summary = json.load(f)
    run = summary["run"]
    bit_names = summary["bit_names"]
    real_names = [r["name"] for r in summary["reals"]]
    components = [c["name"] for c in summary["distance_components"]]
    wave = summary["waves"][-1]["wave"] if summary["waves"] else 0
    table = pd.read_csv(particles_csv, dtype={"bits": str}, float_precision="round_trip")
    table = table[table["wave"] == wave]
    weight_at = list(table.columns).index("weight")
    distance_columns = list(table.columns[weight_at + 1:])
    if len(distance_columns) != len(components):
        components = [c[2:] for c in distance_columns]  # an older file: the export's names
    measured = pd.read_csv(measured_csv, float_precision="round_trip")
    unit = measured.columns[0][len("position_"):]
    attrs = {"inference_library_version": run["combabc_version"], "seed": run["seed"],
             "wave": wave, "termination": run["termination"], "status": run["status"],
             "estimator": run["estimator"], "created_at": run["end_time"],
             "config_path": run["config_path"], "config_text": summary["config_text"]}
    return dict(
        bits=table[[f"bit_{k}" for k in range(len(bit_names))]].to_numpy(dtype=np.uint8),
        reals=table[real_names].to_numpy(dtype=np.float64),
        log_weight=table["log_weight"].to_numpy(), weight=table["weight"].to_numpy(),
        distance=table[distance_columns].to_numpy(dtype=np.float64),
        index=table["index"].to_numpy(dtype=np.int64), bit_names=bit_names,
        real_names=real_names, components=components,
        measured_position=measured.iloc[:, 0].to_numpy(),
        measured_value=measured.iloc[:, 1].to_numpy(), position_unit=unit, attrs=attrs,
        experiments=summary.get("experiments"))


class OneLineParser(argparse.ArgumentParser):
    def error(self, message):
        print(f"combabc_netcdf: usage error: {message} (see --help)", file=sys.stderr)
        sys.exit(EX_USAGE)


def main(argv=None):
    parser = OneLineParser(description="A combabc export as NetCDF (ArviZ InferenceData).")
    for name in ("particles", "measured", "summary", "out"):
        parser.add_argument(f"--{name}", required=True)
    args = parser.parse_args(argv)
    try:
        import netCDF4  # noqa: F401  (xarray's engine; imported here to name it when missing)
        import xarray  # noqa: F401
    except ImportError as missing:
        print(f"combabc_netcdf: {NEEDS.format(python=sys.executable)} ({missing})",
              file=sys.stderr)
        return EX_UNAVAILABLE
    try:
        write_netcdf(inference_data(**from_export(args.particles, args.measured, args.summary)),
                     args.out)
    except (KeyError, ValueError, json.JSONDecodeError) as error:
        print(f"combabc_netcdf: unreadable export: {type(error).__name__}: {error}",
              file=sys.stderr)
        return EX_DATAERR
    except OSError as error:
        print(f"combabc_netcdf: {args.out}: {' '.join(str(error).split())}", file=sys.stderr)
        return EX_IOERR
    return 0


if __name__ == "__main__":
    sys.exit(main())
