"""ABC model choice from Python (docs/python.md, "Model choice"): combabc.model_choice runs (or
enumerates) every model of a config's [model_choice]; combabc.load_model_choice reads a finished
one back. Both return the table `combabc run` writes to model_choice/models.csv, as a DataFrame
indexed by model name, with each model's history file added."""

import json
import os
import warnings

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


def model_choice(config, *, exact=False, threads=None, output_directory=None, overwrite=False,
                 report=False):
    """ABC model choice on a config with [model_choice], as `combabc run CONFIG` (exact=True: as
    `combabc enumerate CONFIG`, the exact probabilities). Each model is calibrated (enumerated) on
    its own into <directory>/models/<name>/ (<directory>/enumeration/models/<name>/); running it
    again reads the finished models and resumes unfinished ones, overwrite=True starts afresh.
    threads, output_directory and report as combabc.run's (report=True also draws
    model_choice/model_probabilities.png; a UserWarning says why when it cannot). Returns load_model_choice's DataFrame:
    table.loc["clamped", "probability"], table["se"], combabc.load_history(table["history"][k])."""
    data = _core.model_choice(os.fspath(config), -1 if threads is None else threads,
                              os.fspath(output_directory or ""), overwrite, report, exact)
    if data.get("note"):
        warnings.warn(data["note"], stacklevel=2)
    table = load_model_choice(data["directory"])
    # The histories as the service names them (the same files; this keeps its spelling).
    table["history"] = [m["history"] or path
                        for m, path in zip(data["models"], table["history"])]
    return table
