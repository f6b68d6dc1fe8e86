"""ABC model choice from Python (docs/python.md, "Model choice"): combabc.model_choice runs (or
enumerates) every model of a config's [model_choice], or runs several Problems and compares them;
combabc.load_model_choice reads a finished one back. Both return the table `combabc run` writes to model_choice/models.csv, as a DataFrame
indexed by model name, with each model's history file added."""

import json
import os
import warnings
from collections.abc import Mapping

import numpy as np

from . import _core

# models.csv's columns, in order (docs/config.md, "Model choice"), and their types.
_BOOLEAN = ("upper_bound_only", "reached")
_INTEGER = ("wave", "simulations")


def _folder(path):
    """The model_choice/ folder from it, from the output directory above it, or from models.csv."""
    path = os.fspath(path)
    if os.path.basename(path) == "models.csv":
        return os.path.dirname(path)
    if os.path.isfile(os.path.join(path, "models.csv")):
        return path
    return os.path.join(path, "model_choice")


def load_model_choice(path):
    """A finished model choice's probabilities: path is the run's output directory (or the
    enumeration/ folder inside it, for `combabc enumerate`), its model_choice/ folder, or
    models.csv. Returns a DataFrame indexed by model: prior, probability, se, upper_bound_only,
    upper (a model that died out: P is below it), log_evidence, relative_se, log10_bayes_factor
    (against attrs["reference"]), reached, wave, simulations, termination, history (the model's
    history file, for combabc.load_history; the joint run's for every model with method "joint").
    attrs: reference, exact (by enumeration), method ("evidence", "joint" or "enumeration"),
    directory (model_choice/); bits, each model's P(bit = 1 | model, data) (bits.csv, method
    "joint"), or None; and
    waves, the probabilities after each wave (waves.csv; docs/algorithm.md, "Model choice"), or
    None where the run wrote none."""
    import pandas as pd

    folder = _folder(path)
    csv = os.path.join(folder, "models.csv")
    if not os.path.isfile(csv):
        raise FileNotFoundError(f"{csv}: no model choice here (combabc run writes it for a "
                                "config with [model_choice])")
    table = pd.read_csv(csv, index_col="model", keep_default_na=False,
                        na_values=["nan", "-nan", "NaN"])
    table.index = table.index.astype(str)
    for column in _BOOLEAN:
        table[column] = table[column].astype(bool)
    for column in _INTEGER:
        table[column] = table[column].astype("int64")
    table["termination"] = table["termination"].astype(str)
    with open(os.path.join(folder, "summary.json")) as f:
        summary = json.load(f)
    top = os.path.dirname(os.path.abspath(folder))
    method = summary.get("method", "enumeration" if summary["exact"] else "evidence")
    if method == "joint":  # one run for all models
        table["history"] = [os.path.join(top, "joint", "history.sqlite")] * len(table.index)
    else:
        table["history"] = [os.path.join(top, "models", name, "history.sqlite")
                            for name in table.index]
    table.attrs["reference"] = summary["reference"]
    table.attrs["exact"] = bool(summary["exact"])
    table.attrs["method"] = method
    table.attrs["directory"] = folder
    waves = os.path.join(folder, "waves.csv")
    table.attrs["waves"] = pd.read_csv(waves) if os.path.isfile(waves) else None
    bits = os.path.join(folder, "bits.csv")
    table.attrs["bits"] = pd.read_csv(bits) if os.path.isfile(bits) else None
    return table


def model_choice(models, options=None, *, priors=None, exact=False, threads=None,
                 output_directory=None, overwrite=False, report=False):
    """ABC model choice. models: a config file with [model_choice] (str or path), as
    `combabc run CONFIG` (exact=True: as `combabc enumerate CONFIG`, the exact probabilities);
    or the candidate models as Problems: a dict {name: Problem}, or a list of (name, Problem) or
    (name, Problem, prior) (docs/python.md, "Model choice").

    A config: each model is calibrated (enumerated) on its own into <directory>/models/<name>/
    (<directory>/enumeration/models/<name>/); running it again reads the finished models and
    resumes unfinished ones, overwrite=True starts afresh. threads, output_directory and report as
    combabc.run's (report=True also draws model_choice/model_probabilities.png; a UserWarning says
    why when it cannot).

    Problems: each model k runs as combabc.run(problem, options with seed + k,
    output_directory=<output_directory>/models/<name>) (output_directory is required; overwrite
    replaces the models' histories and tables), and the probabilities come from the models'
    evidences at the final thresholds of options.thresholds (a list schedule's last value or an
    adaptive schedule's target, one schedule per distance component), as a config's method
    "evidence". priors: None (equal), a dict {name: prior} or a list in the models' order; each
    above 0, summing to 1. The Problems must have the same observed data and the same distance
    components (by name); refused (ValueError, combabc.Error) before any run otherwise.

    Returns load_model_choice's DataFrame: table.loc["clamped", "probability"], table["se"],
    combabc.load_history(table["history"][k])."""
    if not isinstance(models, (str, os.PathLike)):
        if exact:
            raise ValueError("exact=True enumerates a config's models; a model choice over "
                             "Problems is estimated from their runs")
        return _problem_model_choice(models, options, priors, threads, output_directory,
                                     overwrite, report)
    if options is not None or priors is not None:
        raise TypeError("options and priors apply to a model choice over Problems; a config "
                        "carries its own ([sampler], [model_choice])")
    data = _core.model_choice(os.fspath(models), -1 if threads is None else threads,
                              os.fspath(output_directory or ""), overwrite, report, exact)
    return _table(data)


def _table(data):
    if data.get("note"):
        warnings.warn(data["note"], stacklevel=3)
    table = load_model_choice(data["directory"])
    # The histories as the service names them (the same files; this keeps its spelling).
    table["history"] = [m["history"] or path
                        for m, path in zip(data["models"], table["history"])]
    return table


def _candidates(models, priors):
    """The models as (name, Problem, prior) triples, priors equal when none is given."""
    if isinstance(models, Mapping):
        entries = [(name, problem, None) for name, problem in models.items()]
    else:
        entries = []
        for entry in models:
            if not isinstance(entry, tuple) or len(entry) not in (2, 3):
                raise TypeError("models: expected a dict {name: Problem} or a list of "
                                f"(name, Problem) or (name, Problem, prior), not {entry!r}")
            entries.append(entry if len(entry) == 3 else (*entry, None))
    given = [prior for _, _, prior in entries if prior is not None]
    if given and priors is not None:
        raise TypeError("priors: given twice, in the models' tuples and as priors=")
    if given and len(given) != len(entries):
        raise ValueError("priors: give every model a prior, or none")
    if priors is None:
        values = given or [1.0 / max(len(entries), 1)] * len(entries)
    elif isinstance(priors, Mapping):
        unknown = set(priors) - {name for name, _, _ in entries}
        if unknown or len(priors) != len(entries):
            raise ValueError("priors: expected one prior for each model, by name; got "
                             + ", ".join(map(repr, priors)))
        values = [priors[name] for name, _, _ in entries]
    else:
        values = list(priors)
        if len(values) != len(entries):
            raise ValueError(f"priors: {len(values)} values for {len(entries)} models")
    return [(str(name), problem, float(prior))
            for (name, problem, _), prior in zip(entries, values)]


def _components(problem):
    """The names of a Problem's distance components, as its run names them."""
    if problem.components:
        return list(problem.components)
    return ["euclidean"] if problem.distance is None else ["distance"]


def _problem_model_choice(models, options, priors, threads, output_directory, overwrite, report):
    from . import Problem, SmcOptions, run

    candidates = _candidates(models, priors)
    names = [name for name, _, _ in candidates]
    for name, problem, _ in candidates:
        if not isinstance(problem, Problem):
            raise TypeError(f"model {name!r}: expected a combabc.Problem, not "
                            f"{type(problem).__name__}")
    _core.check_model_runs(names, [prior for _, _, prior in candidates])
    if output_directory is None:
        raise ValueError("a model choice over Problems needs output_directory: each model's "
                         "history goes to <directory>/models/<name>/, the tables to "
                         "<directory>/model_choice/")
    if options is None:
        options = SmcOptions()
    if not options.thresholds:
        raise ValueError("options.thresholds: model choice compares the models' evidences at "
                         "common final thresholds, and the default (quantile) schedules have "
                         "none; give thresholds ending at a final value (a list, or an adaptive "
                         "schedule's target)")
    final = _core.common_final_thresholds(options)
    first_name, first, _ = candidates[0]
    for name, problem, _ in candidates[1:]:
        if _components(problem) != _components(first):
            raise ValueError(f"model {name!r}: its distance's components "
                             f"{_components(problem)} differ from model {first_name!r}'s "
                             f"{_components(first)}; the evidences are compared at common final "
                             "thresholds of the same components")
        if not np.array_equal(problem.observed, first.observed):
            raise ValueError(f"model {name!r}: its observed data differ from model "
                             f"{first_name!r}'s; the models must explain the same data")
    if len(final) != len(_components(first)):
        raise ValueError(f"options.thresholds: {len(final)} schedules for the distance's "
                         f"{len(_components(first))} components ({', '.join(_components(first))})")
    directory = os.fspath(output_directory)
    seed = options.seed
    histories = []
    try:
        for k, (name, problem, _) in enumerate(candidates):
            # Model k on seed + k, as a config's: independent runs, as the errors assume.
            options.seed = (seed + k) % 2**64
            folder = os.path.join(directory, "models", name)
            history = run(problem, options, threads=threads, output_directory=folder,
                          overwrite=overwrite)
            histories.append(history.path or os.path.join(folder, "history.sqlite"))
    finally:
        options.seed = seed
    return _table(_core.combine_model_runs(names, [prior for _, _, prior in candidates],
                                           histories, final, directory, overwrite, report))
