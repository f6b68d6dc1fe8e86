#!/usr/bin/env python3
"""A combabc run as a NetCDF file in ArviZ's InferenceData layout (docs/history.md, "NetCDF").

    combabc_netcdf.py --particles particles.csv --measured measured.csv --summary summary.json
                      [--curves curves.csv --positions positions.csv] [--all-waves]
                      --out inference_data.nc

`combabc export` runs it on the files it has just staged, so that the NetCDF values are the CSVs'
(it is not meant to be run by hand, though it can be on any export directory). The Python module
imports the same builder (`inference_data`) for History.to_inference_data(), so both write one
layout. Waves are numbered from 1 and bits named, as everywhere a user sees them:

- posterior: equally weighted draws of the answer's wave (one chain, as many draws as particles):
  as the CLI's answer and History.posterior_wave, the last complete wave (`answer`), so a run
  stopped during a wave (budget, wall time, Ctrl-C) leaves that incomplete wave out and says so
  in the attributes `posterior_note` and `incomplete_wave_left_out` (below),
  resampled from its weighted particles by systematic resampling under the run's estimator's
  weights (importance: the particles' weights; paper: equal), its uniform draw seeded by
  (run seed, wave): so ArviZ's and xarray's means equal combabc's marginals within resampling
  error, and the file is reproducible. `bits` (chain, draw, bit; uint8, the bit coordinate holds
  the bit / clamp names) and one variable per continuous parameter (chain, draw);
- sample_stats, per draw, of the particle it was drawn from: `weight` and `log_weight`,
  `distance` (chain, draw, component) and `particle_index` (its candidate index in the wave); in a
  multi-fidelity run also `multiplier` and `confirmed` (0/1). Such a run's draws are resampled
  from its particles' weights (which hold the multipliers) under either estimator. In a
  resample-move run also `ancestor` (the previous wave's particle_index it was resampled from and
  moved; -1 drawn afresh), and a move wave's sample_stats the attributes `move_rounds`,
  `move_proposed`, `move_accepted`, `move_independent_proposed`, `move_independent_accepted`,
  `move_survivor_ess` and `move_step` (summary.json's "moves");
- signed weights (a multi-fidelity wave with some negative weights): no equally weighted sample
  can be drawn from them (resampling their positive part gives another distribution), so that
  wave has no `posterior` (nor `posterior_predictive`) group; its sample_stats holds every
  particle once, in order, unresampled: `weight` (signed, summing to 1), the other statistics,
  and the particle's `particle_bits` (chain, draw, bit) and `particle_<name>` per continuous
  parameter, so that sum(weight * particle_bits) is combabc's marginals. The attributes
  `signed_weights` (1) and `signed_weights_note` say so (`combabc export` prints the note, and
  History.to_inference_data warns it);
- prior: wave 1's particles when its thresholds are all infinite (prior draws), else as many
  draws from the stated prior (independent bits at bit_prior_one, the continuous priors);
  attribute `source` says which;
- posterior_predictive (when the run kept its outputs): the accepted curves of the answer's wave,
  resampled as the posterior (the same draws). Per experiment, named as its observed variable on
  the same positions when the outputs lie at the measured positions, else `simulated`
  (`simulated_<name>`) on `output_position` (`output_position_<name>`);
- observed_data: `measured` (position), its coordinate the measured positions; a run of named
  experiments instead has one variable per experiment, `measured_<name>` (position_<name>), each
  with its own positions, and sample_stats the coordinate `component_experiment` (component);
- with --all-waves (History.to_inference_data(all_waves=True)) also `posterior_wave_<k>` and
  `sample_stats_wave_<k>` for every wave k from 1, resampled likewise;
- attributes of every group: inference_library = combabc, its version, the seed, the wave (from 1)
  of the posterior, `signed_weights` (0 or 1) and `signed_weights_note` ("" or why that wave has
  no posterior group, above), the termination, the config file's path and text, `posterior_note` (why the
  posterior is not the last wave's, in the CLI's words: "the numbers are wave 2's: wave 3 is
  incomplete (budget_exhausted)"; "" when it is the last wave, complete) and
  `incomplete_wave_left_out` (the number of the incomplete last wave left out; 0 for none).

Exit status (sysexits): 0, 64 usage, 65 unreadable input, 69 xarray or netCDF4 missing, 74 I/O.
"""

import argparse
import json
import os
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


def resample(weight, seed, wave):
    """Systematic resampling: n indices into the n weighted particles, the one uniform draw seeded
    by (seed, wave) so that the same run always gives the same draws."""
    import numpy as np
    weight = np.asarray(weight, dtype=np.float64)
    n = len(weight)
    if n == 0 or not np.sum(weight) > 0:
        return np.zeros(0, dtype=np.int64)
    cumulative = np.cumsum(weight / np.sum(weight))
    u = np.random.default_rng([int(seed or 0), int(wave)]).random()
    indices = np.searchsorted(cumulative, (u + np.arange(n)) / n, side="right")
    return np.minimum(indices, n - 1).astype(np.int64)


def signed(wave):
    """Whether a wave's weights are signed (a multi-fidelity wave with some negative ones)."""
    import numpy as np
    return bool(np.any(np.asarray(wave["weight"], dtype=np.float64) < 0))


def signed_note(number):
    """Why a wave of signed weights has no posterior group, in one sentence."""
    return (f"wave {number}'s weights are signed (multi-fidelity: some are negative) and no "
            f"equally weighted sample can be drawn from them: no posterior group; its particles "
            f"and their signed weights are in sample_stats (particle_bits, weight: weigh each "
            f"particle by its weight)")


def prior_draws(n, bit_prior_one, dimension, real_priors, seed):
    """n draws from the stated prior: independent bits at their prior P(1) (ties are not
    kept: the export does not carry them), the continuous parameters' priors."""
    import numpy as np
    rng = np.random.default_rng([int(seed or 0), 0])
    p = np.asarray(bit_prior_one if len(bit_prior_one) else [0.5] * dimension, dtype=np.float64)
    bits = (rng.random((n, dimension)) < p).astype(np.uint8)
    reals = np.empty((n, len(real_priors)))
    for k, prior in enumerate(real_priors):
        kind = prior["kind"]
        if kind == "uniform":
            reals[:, k] = rng.uniform(prior["low"], prior["high"], n)
        elif kind == "normal":
            reals[:, k] = rng.normal(prior["mean"], prior["sd"], n)
        elif kind == "lognormal":
            reals[:, k] = np.exp(rng.normal(prior["mean"], prior["sd"], n))
        elif kind == "joint":  # a joint or custom prior's sampler is code: not drawn here
            reals[:, k] = np.nan
        else:  # truncated_normal, by rejection
            values = np.empty(0)
            while len(values) < n:
                x = rng.normal(prior["mean"], prior["sd"], 4 * n)
                values = np.concatenate([values, x[(x >= prior["low"]) & (x <= prior["high"])]])
            reals[:, k] = values[:n]
    return bits, reals


def answer(waves, termination):
    """Which wave answers, as the CLI's answer (docs/history.md, "Answer"): the position in
    `waves` (dicts or objects with `complete`, `number` and their particles' `index`) of the last
    complete wave with particles; when none is complete, of the last wave with particles. And the
    note saying why that is not the last wave, complete, in the CLI's words ("" when it is);
    termination: the run's ("" for a failed or killed run: "stopped")."""
    def field(wave, key):
        return wave[key] if isinstance(wave, dict) else getattr(wave, key)

    with_particles = [k for k, w in enumerate(waves) if len(field(w, "index"))]
    complete = [k for k in with_particles if field(waves[k], "complete")]
    k = complete[-1] if complete else with_particles[-1] if with_particles else len(waves) - 1
    if not field(waves[k], "complete"):
        return k, "no complete wave: the numbers are those of the incomplete last wave"
    if k != len(waves) - 1:
        return k, (f"the numbers are wave {field(waves[k], 'number')}'s: wave "
                   f"{field(waves[-1], 'number')} is incomplete ({termination or 'stopped'})")
    return k, ""


def inference_data(*, waves, bit_names, real_names, components, measured_position,
                   measured_value, position_unit, attrs, estimator, seed, bit_prior_one=(),
                   real_priors=(), output_position=(), experiments=None, all_waves=False):
    """The InferenceData groups (above) as xarray Datasets, a dict by group name. waves: every wave
    (at least the first, the answer's and the last), each a dict: number (from 1), complete (a
    wave without it counts as complete), thresholds, and its particles as
    NumPy arrays (n particles): bits uint8[n, d], reals float64[n, r], log_weight, weight
    float64[n], distance float64[n, k], index int64[n], output float64[n, m] (m = 0 without
    outputs), in a multi-fidelity run multiplier float64[n] and confirmed uint8[n], and in a
    resample-move run ancestor int64[n] and, for a move wave, moves (summary.json's dict).
    experiments: the run's experiments as dicts (name, description, first_measured,
    measured, first_component, components, first_output, outputs: summary.json's
    "experiments"), or None for one holding everything. real_priors: per continuous parameter its
    prior as a dict (kind, low, high, mean, sd)."""
    import numpy as np
    import xarray as xr

    attrs = {key: ("" if value is None else value) for key, value in attrs.items()}
    attrs.setdefault("inference_library", "combabc")
    waves = [{"complete": True, **w} for w in waves]
    answer_at, note = answer(waves, attrs.get("termination", ""))
    final = waves[answer_at]
    attrs["wave"] = final["number"]
    attrs["posterior_note"] = note
    attrs["incomplete_wave_left_out"] = waves[-1]["number"] if answer_at != len(waves) - 1 else 0
    attrs["signed_weights"] = int(signed(final))
    attrs["signed_weights_note"] = signed_note(final["number"]) if signed(final) else ""
    d, r = len(bit_names), len(real_names)
    measured_position = np.asarray(measured_position, dtype=np.float64)
    measured_value = np.asarray(measured_value, dtype=np.float64)
    output_position = np.asarray(output_position, dtype=np.float64)
    units = {"units": position_unit or "m"}
    named = named_experiments(experiments)
    layout = named or [{"name": "", "first_measured": 0, "measured": len(measured_position),
                        "first_component": 0, "components": len(components),
                        "first_output": 0, "outputs": None}]

    def draws(n):
        return {"chain": np.array([0]), "draw": np.arange(n)}

    def parameters(bits, reals):
        n = len(bits)
        group = {"bits": (("chain", "draw", "bit"),
                          np.asarray(bits, dtype=np.uint8).reshape(1, n, d))}
        reals = np.asarray(reals, dtype=np.float64).reshape(n, r)
        for k, name in enumerate(real_names):
            group[variable_name(name)] = (("chain", "draw"), reals[None, :, k])
        return xr.Dataset(group, coords={**draws(n), "bit": list(bit_names)}, attrs=attrs)

    def resampled(wave):
        weight = np.asarray(wave["weight"], dtype=np.float64)
        distance = np.asarray(wave["distance"], dtype=np.float64).reshape(len(weight),
                                                                          len(components))
        uniform = estimator == "paper" and wave.get("multiplier") is None
        # Signed (multi-fidelity) weights: no resample (its draws would follow their positive
        # part, not the posterior); every particle once, with its weight, and no posterior.
        is_signed = signed(wave)
        if is_signed:
            rows = np.arange(len(weight), dtype=np.int64)
        else:
            rows = resample(np.ones_like(weight) if uniform else weight, seed, wave["number"])
        n = len(rows)
        stats = {
            "weight": (("chain", "draw"), weight[rows][None]),
            "log_weight": (("chain", "draw"), np.asarray(wave["log_weight"])[rows][None]),
            "distance": (("chain", "draw", "component"), distance[rows][None]),
            "particle_index": (("chain", "draw"), np.asarray(wave["index"],
                                                             dtype=np.int64)[rows][None]),
        }
        # A multi-fidelity run: each draw's particle's multiplier and whether the expensive
        # simulator confirmed it.
        if wave.get("multiplier") is not None:
            stats["multiplier"] = (("chain", "draw"),
                                   np.asarray(wave["multiplier"], dtype=np.float64)[rows][None])
            stats["confirmed"] = (("chain", "draw"),
                                  np.asarray(wave["confirmed"], dtype=np.uint8)[rows][None])
        # A resample-move run: the previous wave's particle each draw's particle moved from.
        if wave.get("ancestor") is not None:
            stats["ancestor"] = (("chain", "draw"),
                                 np.asarray(wave["ancestor"], dtype=np.int64)[rows][None])
        coords = {**draws(n), "component": list(components)}
        if named is not None:
            owner = [""] * len(components)
            for x in named:
                first = x.get("first_component", 0)
                for k in range(first, min(first + x.get("components", 0), len(owner))):
                    owner[k] = x["name"]
            coords["component_experiment"] = ("component", owner)
        bits = np.asarray(wave["bits"], dtype=np.uint8).reshape(len(weight), d)[rows]
        reals = np.asarray(wave["reals"], dtype=np.float64).reshape(len(weight), r)[rows]
        stats_attrs = {**attrs, "wave": wave["number"],
                       "resampling": "none" if is_signed else "systematic",
                       "resampling_weights": "none (signed weights)" if is_signed else
                       "equal" if uniform else "weight",
                       "signed_weights": int(is_signed),
                       "signed_weights_note": signed_note(wave["number"]) if is_signed else ""}
        for key, value in (wave.get("moves") or {}).items():
            if value is not None and key in ("rounds", "proposed", "accepted",
                                             "independent_proposed", "independent_accepted",
                                             "survivor_ess", "step"):
                stats_attrs[f"move_{key}"] = value
        if is_signed:
            # The particles themselves beside their weights: the posterior is their signed
            # weighted sum, which no unweighted statistic of a posterior group would give.
            stats["particle_bits"] = (("chain", "draw", "bit"), bits[None])
            for k, name in enumerate(real_names):
                stats[f"particle_{variable_name(name)}"] = (("chain", "draw"), reals[None, :, k])
            coords["bit"] = list(bit_names)
            return rows, None, xr.Dataset(stats, coords=coords, attrs=stats_attrs)
        posterior = parameters(bits, reals)
        posterior.attrs = stats_attrs
        return rows, posterior, xr.Dataset(stats, coords=coords, attrs=stats_attrs)

    observed, observed_coords = {}, {}
    for x in layout:
        suffix = f"_{variable_name(x['name'])}" if named else ""
        rows = slice(x["first_measured"], x["first_measured"] + x["measured"])
        dim = f"position{suffix}"
        observed_coords[dim] = xr.Variable(dim, measured_position[rows], attrs=units)
        observed[f"measured{suffix}"] = xr.Variable(
            dim, measured_value[rows],
            attrs={"experiment": x["name"], "description": x.get("description", "")}
            if named else {})

    rows, posterior, sample_stats = resampled(final)
    groups = {"sample_stats": sample_stats} if posterior is None else \
        {"posterior": posterior, "sample_stats": sample_stats}

    first = waves[0]
    if first["number"] == 1 and len(first["thresholds"]) and \
            np.all(np.isinf(np.asarray(first["thresholds"], dtype=np.float64))):
        prior = parameters(first["bits"], first["reals"])
        prior.attrs = {**attrs, "source": "wave 1 (infinite thresholds: prior draws)"}
    else:
        prior = parameters(*prior_draws(len(rows), bit_prior_one, d, real_priors, seed))
        prior.attrs = {**attrs, "source": "stated prior"}
    groups["prior"] = prior

    output = np.asarray(final.get("output", np.zeros((0, 0))), dtype=np.float64)
    if posterior is not None and output.ndim == 2 and output.shape[1] and len(rows):
        curves = output[rows]
        predictive, predictive_coords = {}, {}
        for x in layout:
            suffix = f"_{variable_name(x['name'])}" if named else ""
            count = x["outputs"] if x["outputs"] is not None else output.shape[1]
            columns = slice(x["first_output"], x["first_output"] + count)
            at = output_position[columns] if len(output_position) else \
                measured_position[x["first_measured"]:x["first_measured"] + x["measured"]]
            measured_at = observed_coords[f"position{suffix}"].values
            if len(at) == len(measured_at) and np.array_equal(at, measured_at):
                name, dim = f"measured{suffix}", f"position{suffix}"
                predictive_coords[dim] = observed_coords[dim]
            else:
                name, dim = f"simulated{suffix}", f"output_position{suffix}"
                predictive_coords[dim] = xr.Variable(dim, at, attrs=units)
            predictive[name] = (("chain", "draw", dim), curves[None, :, columns])
        groups["posterior_predictive"] = xr.Dataset(
            predictive, coords={**draws(len(rows)), **predictive_coords},
            attrs={**attrs, "resampling": "systematic"})
    groups["observed_data"] = xr.Dataset(observed, coords=observed_coords, attrs=attrs)
    if all_waves:
        for wave in waves:
            _, posterior, stats = resampled(wave)
            if posterior is not None:
                groups[f"posterior_wave_{wave['number']}"] = posterior
            groups[f"sample_stats_wave_{wave['number']}"] = stats
    return groups


def write_netcdf(groups, path):
    """The groups into one NetCDF-4 file, one HDF5 group each (what arviz.from_netcdf reads)."""
    mode = "w"
    for name, dataset in groups.items():
        dataset.to_netcdf(path, mode=mode, group=name, engine="netcdf4")
        mode = "a"


def from_export(particles_csv, measured_csv, summary_json, curves_csv=None, positions_csv=None,
                all_waves=False):
    """The builder's arguments from an export's files (curves.csv and positions.csv when the run
    kept its outputs): the first, the answer's and the last wave, or every wave."""
    import numpy as np
    import pandas as pd

    with open(summary_json, encoding="utf-8") as f:
        summary = json.load(f)
    run = summary["run"]
    bit_names = summary["bit_names"]
    real_names = [r["name"] for r in summary["reals"]]
    components = [c["name"] for c in summary["distance_components"]]
    table = pd.read_csv(particles_csv, dtype={"bits": str}, float_precision="round_trip")
    columns = list(table.columns)
    weight_at = columns.index("weight")
    # A multi-fidelity run's columns follow the distances (multiplier, confirmed, low_distance_*),
    # then a resample-move run's ancestor.
    fidelity = "multiplier" in columns
    moved = "ancestor" in columns
    after = [columns.index(c) for c in ("multiplier", "ancestor") if c in columns]
    distance_columns = columns[weight_at + 1:min(after) if after else None]
    if len(distance_columns) != len(components):
        components = [c[2:] for c in distance_columns]  # an older file: the export's names
    curves = None
    if curves_csv and os.path.isfile(curves_csv):
        curves = pd.read_csv(curves_csv, float_precision="round_trip")
    output_position = np.zeros(0)
    if positions_csv and os.path.isfile(positions_csv):
        output_position = pd.read_csv(positions_csv, float_precision="round_trip").iloc[:, 1]
    stats = summary["waves"] if summary["waves"] else [{"wave": 0, "thresholds": []}]
    if not all_waves:
        counts = [{"index": table.index[table["wave"] == w["wave"]],
                   "complete": w.get("complete", True), "number": w["wave"]} for w in stats]
        at, _ = answer(counts, run["termination"])
        stats = [stats[k] for k in sorted({0, at, len(stats) - 1})]
    waves = []
    for w in stats:
        rows = table[table["wave"] == w["wave"]]
        wave = {"number": w["wave"], "complete": w.get("complete", True),
                # null: a non-finite threshold (summary.json), the first wave's infinite ones
                "thresholds": [np.inf if t is None else t for t in w.get("thresholds", [])],
                "bits": rows[bit_names].to_numpy(dtype=np.uint8),
                "reals": rows[real_names].to_numpy(dtype=np.float64),
                "log_weight": rows["log_weight"].to_numpy(), "weight": rows["weight"].to_numpy(),
                "distance": rows[distance_columns].to_numpy(dtype=np.float64),
                "index": rows["index"].to_numpy(dtype=np.int64), "output": np.zeros((0, 0))}
        if fidelity:
            wave["multiplier"] = rows["multiplier"].to_numpy(dtype=np.float64)
            wave["confirmed"] = rows["confirmed"].to_numpy(dtype=np.uint8)
        if moved:
            wave["ancestor"] = rows["ancestor"].to_numpy(dtype=np.int64)
            wave["moves"] = w.get("moves")
        if curves is not None:
            by_index = curves[curves["wave"] == w["wave"]].drop(columns="wave").set_index("index")
            if set(wave["index"]) <= set(by_index.index):
                wave["output"] = by_index.loc[wave["index"]].to_numpy(dtype=np.float64)
        waves.append(wave)
    measured = pd.read_csv(measured_csv, float_precision="round_trip")
    unit = measured.columns[0][len("position_"):]
    attrs = {"inference_library_version": run["combabc_version"], "seed": run["seed"],
             "termination": run["termination"],
             "status": run["status"], "estimator": run["estimator"],
             "created_at": run["end_time"], "config_path": run["config_path"],
             "config_text": summary["config_text"]}
    return dict(
        waves=waves, bit_names=bit_names, real_names=real_names, components=components,
        measured_position=measured.iloc[:, 0].to_numpy(),
        measured_value=measured.iloc[:, 1].to_numpy(), position_unit=unit, attrs=attrs,
        estimator=run["estimator"], seed=run["seed"], bit_prior_one=summary["bit_prior_one"],
        real_priors=[r["prior"] for r in summary["reals"]],
        output_position=np.asarray(output_position, dtype=np.float64),
        experiments=summary.get("experiments"), all_waves=all_waves)


class OneLineParser(argparse.ArgumentParser):
    def error(self, message):
        print(f"combabc_netcdf: usage error: {message} (see --help)", file=sys.stderr)
        sys.exit(EX_USAGE)


def main(argv=None):
    parser = OneLineParser(description="A combabc export as NetCDF (ArviZ InferenceData).")
    for name in ("particles", "measured", "summary", "out"):
        parser.add_argument(f"--{name}", required=True)
    parser.add_argument("--curves", help="curves.csv, when the run kept its outputs")
    parser.add_argument("--positions", help="positions.csv (the outputs' x)")
    parser.add_argument("--all-waves", action="store_true",
                        help="also every wave's resampled posterior and sample_stats")
    args = parser.parse_args(argv)
    try:
        import netCDF4  # noqa: F401  (xarray's engine; imported here to name it when missing)
        import xarray  # noqa: F401
    except ImportError as missing:
        print(f"combabc_netcdf: {NEEDS.format(python=sys.executable)} ({missing})",
              file=sys.stderr)
        return EX_UNAVAILABLE
    try:
        groups = inference_data(**from_export(args.particles, args.measured, args.summary,
                                              args.curves, args.positions, args.all_waves))
        write_netcdf(groups, args.out)
    except (KeyError, ValueError, json.JSONDecodeError) as error:
        print(f"combabc_netcdf: unreadable export: {type(error).__name__}: {error}",
              file=sys.stderr)
        return EX_DATAERR
    except OSError as error:
        print(f"combabc_netcdf: {args.out}: {' '.join(str(error).split())}", file=sys.stderr)
        return EX_IOERR
    # `combabc export` prints this line as its note: the file has no posterior to read.
    note = groups["sample_stats"].attrs.get("signed_weights_note", "")
    if note:
        print(f"combabc_netcdf: note: {note}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
