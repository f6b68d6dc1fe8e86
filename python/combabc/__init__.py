"""combabc: combinatorial ABC-SMC for binary (+ continuous) parameters, from Python.

    import combabc
    history = combabc.run("config.toml", threads=2)        # a config file, as `combabc run`
    history = combabc.load_history("results/history.sqlite")
    space = combabc.BinarySpace(dimension=8, default_prior_one=0.5)
    problem = combabc.Problem(space, simulate, observed=y)  # simulate(bits) -> ndarray[m]
    history = combabc.run(problem, combabc.SmcOptions(...))

See docs/python.md.
"""

import os

import numpy as np

from . import _core
from ._core import (BinarySpace, ContinuousParameter, Error, SimulationFailed, SmcOptions,
                    ThresholdSchedule)
from .history import History, Wave

__version__ = _core.__version__
__all__ = ["BinarySpace", "ContinuousParameter", "Error", "History", "Problem",
           "SimulationFailed", "SmcOptions", "ThresholdSchedule", "Wave", "load_history",
           "make_options", "run"]


class Problem:
    """A problem whose simulator is a Python callable.

    space: a BinarySpace (dimension, prior, ties, names). simulator: f(bits) -> ndarray[m], or
    f(bits, reals) when `reals` (a list of ContinuousParameter) is not empty; bits is uint8[d],
    reals float64[r]. With batch=True f receives uint8[n, d] (and float64[n, r]) and returns
    float64[n, m]. observed: the data y (m values); the distance is Euclidean, one threshold
    component named "euclidean". Raise combabc.SimulationFailed for a candidate that failed (a
    NaN output counts as failed too); any other exception ends the run and reaches the caller.
    """

    def __init__(self, space, simulator, observed, reals=(), batch=False):
        self.space = space
        self.simulator = simulator
        self.observed = np.ascontiguousarray(observed, dtype=np.float64).ravel()
        self.reals = list(reals)
        self.batch = bool(batch)


def make_options(**fields):
    """SmcOptions with the given fields set, e.g. make_options(num_waves=4, seed=7). thresholds
    may be a list of ThresholdSchedule or, for one threshold component, a list of numbers (one
    per wave)."""
    options = SmcOptions()
    thresholds = fields.pop("thresholds", None)
    if thresholds is not None:
        if all(isinstance(t, (int, float)) for t in thresholds):
            thresholds = [ThresholdSchedule(kind="list", values=[float(t) for t in thresholds])]
        options.thresholds = list(thresholds)
    for name, value in fields.items():
        if not hasattr(options, name):
            raise TypeError(f"SmcOptions has no field {name!r}")
        setattr(options, name, value)
    return options


def run(what, options=None, *, threads=None, output_directory=None, overwrite=False,
        report=False):
    """Runs a calibration and returns its History.

    what: a config file (str or path): the same run as `combabc run` (threads, output_directory,
    overwrite as its options; report=True draws the report too); the History is read back from
    the history file it wrote (History.path). Or a Problem, run with `options` (SmcOptions; a
    threads argument overrides options.threads); nothing is written.
    """
    if isinstance(what, Problem):
        if options is None:
            options = SmcOptions()
        if threads is not None:
            options.threads = threads
        data = _core.run_smc(what.space, what.reals, what.simulator, what.batch, what.observed,
                             options)
        # The data's coordinate is the output's index (the NetCDF export's observed_data).
        data.update(measured_position=np.arange(len(what.observed), dtype=np.float64),
                    measured_value=what.observed, position_unit="index",
                    combabc_version=__version__)
        return History(data)
    if options is not None:
        raise TypeError("options apply to a Problem; a config file carries its own")
    data = _core.run_config(os.fspath(what), -1 if threads is None else threads,
                            output_directory or "", overwrite, report)
    return History(data)


def load_history(path):
    """Reads a history file (RUN.sqlite) written by `combabc run`, `resume` or `enumerate`."""
    return History(_core.load_history(os.fspath(path)))
