"""combabc: combinatorial ABC-SMC for binary (+ continuous) parameters, from Python.

    import combabc
    history = combabc.run("config.toml", threads=2)        # a config file, as `combabc run`
    history = combabc.load_history("results/history.sqlite")
    space = combabc.BinarySpace(dimension=8, default_prior_one=0.5)
    problem = combabc.Problem(space, simulate, observed=y)  # simulate(bits) -> ndarray[m]
    history = combabc.run(problem, combabc.SmcOptions(...))
    history = combabc.resume("results/history.sqlite")   # as `combabc resume`
    history = combabc.run(problem, options, output_directory="out")  # writes out/history.sqlite
    history = combabc.resume(history.path, problem, options)  # a Problem's run, continued
    history = combabc.enumerate("config.toml")            # as `combabc enumerate`
    models = combabc.model_choice("choice.toml")          # [model_choice]: P(model) per model
    models = combabc.model_choice({"a": problem, "b": other}, options, output_directory="mc")
    figure = combabc.plot.marginals(history)              # matplotlib figures (combabc.plot)
    model = combabc.SensorModel("config.toml")            # as `combabc simulate`
    y = model.profile("0110...")

See docs/python.md.
"""

import os
import warnings

import numpy as np

from . import _core
from ._core import (MAX_BITS, BatchRandom, BinarySpace, ContinuousParameter, CustomPrior, Error,
                    LogisticKernelOptions, MoveOptions, MultiFidelityOptions,
                    MultivariateNormalPrior, ProposalOptions, SimulationFailed, SmcOptions, TemperingSchedule,
                    ThresholdSchedule)
from . import plot
from .history import Experiment, History, ModeLossWarning, Wave
from ._model_choice import load_model_choice, model_choice

__version__ = _core.__version__
__all__ = ["MAX_BITS", "BatchRandom", "BinarySpace", "ContinuousParameter", "CustomPrior", "Error",
           "Experiment", "History", "LogisticKernelOptions", "MoveOptions", "MultiFidelityOptions",
           "ModeLossWarning", "MultivariateNormalPrior", "Problem", "ProposalOptions",
           "SensorModel", "SimulationFailed", "SmcOptions", "TemperingSchedule",
           "ThresholdSchedule", "Wave", "enumerate", "export", "load_history", "load_model_choice",
           "make_options", "model_choice", "plot", "resume", "run"]


class Problem:
    """A problem whose simulator is a Python callable.

    space: a BinarySpace (dimension, prior, ties, names). simulator: f(bits) -> ndarray[m], or
    f(bits, reals) when `reals` (a list of ContinuousParameter) is not empty; bits is uint8[d],
    reals float64[r]. With batch=True f receives uint8[n, d] (and float64[n, r]) and returns
    float64[n, m]. observed: the data y (m values). Raise combabc.SimulationFailed for a
    candidate that failed (a NaN output counts as failed too); any other exception ends the run
    and reaches the caller. rng=True: f also gets the keyword argument rng, a numpy Generator
    seeded from the candidate's own random stream (batched: a combabc.BatchRandom, whose draws
    are vectorised across the rows, row i from candidate i's stream, and whose items are the
    rows' numpy Generators), so that a stochastic simulator gives the same history for any thread
    count and batch size.

    distance: None for the Euclidean distance to `observed` (one threshold component named
    "euclidean"), or d(output, observed) -> a number (one component named "distance"); with
    components=["a", "b"] it returns those k values as a 1-D array, one threshold schedule per
    component. distance_batch (default: batch): d(outputs float64[n, m], observed) -> float64[n]
    (or [n, k]). A NaN distance or combabc.SimulationFailed fails the candidate, as for the
    simulator.

    low_fidelity: None, or a cheap simulator for a multi-fidelity run (docs/python.md): called
    as `simulator` is (the same batch and rng), its m outputs standing for the simulator's. Every
    candidate runs it; the simulator runs only with the continuation probabilities of
    options.multi_fidelity (a MultiFidelityOptions), and the posterior is the simulator's.

    parameters: how the simulator (and low_fidelity) receives the parameters. "arrays" (default):
    f(bits) or f(bits, reals) as above, by position. "dict": f(params), params a dict by name
    (the bits' names, space.names, then the reals'): {name: int 0/1 or float} per sample,
    {name: uint8[n] or float64[n]} batched. "pandas": f(params), params a pandas Series of
    float64 (per sample, bits as 0.0/1.0) or a DataFrame with one row per candidate (batched),
    columns by name.

    priors: joint priors of reals, a mapping from a real's name, or a tuple of names, to a
    combabc.CustomPrior (a log density and a sampler) or combabc.MultivariateNormalPrior over
    them, in that order; each of those reals is declared ContinuousParameter(name, kind="joint",
    low=..., high=...) (bounds optional). The run checks each against its sampler before any
    simulation (docs/python.md, "Custom and joint priors").

    positions: the outputs' coordinates (m numbers, e.g. metres along a scan), stored in the
    history as a sensor run's output positions are, so that the report and the export draw the
    outputs and the data against them; position_unit names their unit (e.g. "m"). None (the
    default): the outputs are by index (unit "index").
    """

    def __init__(self, space, simulator, observed, reals=(), batch=False, rng=False, *,
                 distance=None, components=None, distance_batch=None, low_fidelity=None,
                 parameters="arrays", priors=None, positions=None, position_unit=""):
        self.space = space
        self.reals = list(reals)
        self.priors = _joint_priors(priors)
        self.batch = bool(batch)
        self.parameters = parameters
        if parameters not in _PARAMETER_STYLES:
            raise ValueError(f"Problem: parameters = {parameters!r}; expected one of "
                             + ", ".join(repr(s) for s in _PARAMETER_STYLES))
        self.simulator = _by_name(simulator, self, "simulator")
        self.observed = np.ascontiguousarray(observed, dtype=np.float64).ravel()
        self.rng = bool(rng)
        if distance is not None and not callable(distance):
            raise TypeError(f"distance must be callable or None, not {type(distance).__name__}")
        self.distance = distance
        self.components = [str(c) for c in components] if components is not None else []
        if components is not None and not self.components:
            raise ValueError("components: name at least one distance component")
        self.distance_batch = self.batch if distance_batch is None else bool(distance_batch)
        if low_fidelity is not None and not callable(low_fidelity):
            raise TypeError("low_fidelity must be callable (a cheap simulator) or None, not "
                            f"{type(low_fidelity).__name__}")
        self.low_fidelity = _by_name(low_fidelity, self, "low_fidelity")
        self.positions = None
        if positions is not None:
            self.positions = np.ascontiguousarray(positions, dtype=np.float64).ravel()
            if len(self.positions) != len(self.observed):
                raise ValueError(f"Problem: positions has {len(self.positions)} values; expected "
                                 f"one per output ({len(self.observed)}, as observed)")
            if not np.all(np.isfinite(self.positions)):
                raise ValueError("Problem: positions must be finite numbers")
        self.position_unit = str(position_unit)


_PARAMETER_STYLES = ("arrays", "dict", "pandas")


def _joint_priors(priors):
    """Problem(priors=...) as the run takes them: a list of (names, prior)."""
    if priors is None:
        return []
    if not hasattr(priors, "items"):
        raise TypeError("priors: expected a mapping from a real's name (or a tuple of names) to "
                        f"a CustomPrior or MultivariateNormalPrior, not {type(priors).__name__}")
    groups = []
    for names, prior in priors.items():
        names = [names] if isinstance(names, str) else [str(n) for n in names]
        if not isinstance(prior, _core.JointPrior):
            raise TypeError(f"priors[{', '.join(map(repr, names))}]: expected a CustomPrior or "
                            f"MultivariateNormalPrior, not {type(prior).__name__}")
        groups.append((names, prior))
    return groups


def _by_name(function, problem, what):
    """The simulator as the engine calls it, f(bits[, reals][, rng=]), for one that takes its
    parameters by name (Problem(parameters="dict" or "pandas")): a wrapper that builds them."""
    if function is None or problem.parameters == "arrays":
        return function
    bit_names = list(problem.space.names)
    real_names = [r.name for r in problem.reals]
    seen = set(bit_names)
    for name in real_names:
        if name in seen:
            raise ValueError(f"Problem: parameters = {problem.parameters!r} needs distinct "
                             f"names; {name!r} names a bit and a continuous parameter")
        seen.add(name)
    empty = np.zeros((0,), dtype=np.float64)
    if problem.parameters == "dict":
        if problem.batch:
            def build(bits, reals):
                values = dict(zip(bit_names, bits.T))  # the columns, bit by bit
                values.update(zip(real_names, reals.T))
                return values
        else:
            def build(bits, reals):
                values = dict(zip(bit_names, bits.tolist()))
                values.update(zip(real_names, reals.tolist()))
                return values
    else:
        import pandas as pd
        columns = bit_names + real_names
        if problem.batch:
            def build(bits, reals):
                values = dict(zip(bit_names, bits.T))
                values.update(zip(real_names, reals.T))
                return pd.DataFrame(values, columns=columns)
        else:
            index = pd.Index(columns)  # made once: a Series costs about 20 us per call

            def build(bits, reals):
                return pd.Series(np.concatenate([bits, reals]), index=index, copy=False)

    def by_name(bits, reals=empty, **rng):
        return function(build(bits, reals), **rng)

    by_name.__qualname__ = by_name.__name__ = getattr(function, "__name__", what)
    return by_name


def make_options(**fields):
    """SmcOptions with the given fields set, e.g. make_options(num_waves=4, seed=7).
    accepted_per_wave may be a list (or array) of one population size per wave, as the config's
    (it sets accepted_by_wave). thresholds
    (as SmcOptions.thresholds) may be a list of ThresholdSchedule, one per threshold component,
    or of lists of numbers (one per wave: a "list" schedule), or for one threshold component a
    list of numbers; numbers are Python's or NumPy's scalars, a list may be a NumPy array. proposal=ProposalOptions(...)
    picks the kernels, tempering=TemperingSchedule(...) tempers the binary proposal toward the
    prior (paper Eq. 3), multi_fidelity=MultiFidelityOptions(...) sets a multi-fidelity run's
    continuation probabilities (with Problem(low_fidelity=...)), method="resample_move" moves the
    particles that fit instead of drawing every wave afresh ("rejection", the default), with
    moves=MoveOptions(...) (a config's [sampler] method and [sampler.moves], same names)."""
    options = SmcOptions()
    for name, value in fields.items():
        if not hasattr(options, name):
            raise TypeError(f"SmcOptions has no field {name!r}")
        if name == "accepted_per_wave" and np.ndim(value) == 1:
            name = "accepted_by_wave"
        setattr(options, name, value)
    return options


def _smc_request(problem, options):
    return _core.SmcRequest(
        space=problem.space, reals=problem.reals, priors=problem.priors,
        simulator=problem.simulator,
        batch=problem.batch, rng=problem.rng, observed=problem.observed, options=options,
        distance=problem.distance, distance_batch=problem.distance_batch,
        components=problem.components, low_fidelity=problem.low_fidelity,
        positions=[] if problem.positions is None else problem.positions,
        position_unit="index" if problem.positions is None else problem.position_unit)


def _problem_history(data, problem):
    # The data's coordinate is the output's index (the NetCDF export's observed_data), for the
    # outputs as for the data; a history file records the same.
    positions = problem.positions
    if positions is None:
        positions = np.arange(len(problem.observed), dtype=np.float64)
    data.setdefault("measured_position", positions)
    data.setdefault("measured_value", problem.observed)
    data.setdefault("output_position", positions)
    data.setdefault("position_unit", "index" if problem.positions is None else
                    problem.position_unit)
    data.setdefault("combabc_version", __version__)
    return History(data)


def _warned(history):
    """The history, after a ModeLossWarning per wave whose proposal may have lost a mode (the
    line the CLI prints under that wave's progress line): a Python run prints nothing else, and
    summary.json's answer.mode_loss is not where a user looks. stacklevel 3: the caller of run or
    resume."""
    for wave in history.waves:
        if wave.mode_loss_warning:
            warnings.warn(wave.mode_loss_warning, ModeLossWarning, stacklevel=3)
    return history


def run(what, options=None, *, threads=None, output_directory=None, overwrite=False,
        report=False, start_from=None):
    """Runs a calibration and returns its History.

    what: a config file (str or path): the same run as `combabc run` (threads, output_directory,
    overwrite as its options; report=True draws the report too); the History is read back from
    the history file it wrote (History.path). Or a Problem, run with `options` (SmcOptions; a
    threads argument overrides options.threads): with output_directory it writes the history
    file history.sqlite there (overwrite: replace one; report=True draws the report too), which
    combabc.export, combabc.load_history and combabc.resume(path, problem, options) read;
    without, nothing is written (History.path is None).

    start_from: a finished run's history file (or a History that has one) whose posterior the run
    starts from instead of the prior: for a config, adding the config's other experiments to it,
    as `combabc run CONFIG --from RUN.sqlite` (docs/algorithm.md, "Adding data to a finished
    run"); for a Problem (which needs output_directory), with the same bits and reals by name,
    its distance's components keeping the finished run's final thresholds by name.
    """
    if isinstance(what, Problem):
        if start_from is not None and output_directory is None:
            raise ValueError("start_from needs output_directory: the run records the run it "
                             "started from in its history file")
        if options is None:
            options = SmcOptions()
        if threads is not None:
            options.threads = threads
        if report and output_directory is None:
            raise ValueError("report=True needs output_directory: the report is drawn from the "
                             "history file written there")
        path = ""
        if output_directory is not None:
            os.makedirs(output_directory, exist_ok=True)
            path = os.path.join(os.fspath(output_directory), "history.sqlite")
        data = _core.run_smc(_smc_request(what, options), path, overwrite, False, report,
                             "" if start_from is None else _history_path(start_from))
        return _warned(_problem_history(data, what))
    if options is not None:
        raise TypeError("options apply to a Problem; a config file carries its own")
    data = _core.run_config(os.fspath(what), -1 if threads is None else threads,
                            os.fspath(output_directory or ""), overwrite, report,
                            "" if start_from is None else _history_path(start_from))
    return _warned(History(data))


def load_history(path):
    """Reads a history file (RUN.sqlite) written by `combabc run`, `resume` or `enumerate`."""
    return History(_core.load_history(os.fspath(path)))


def _history_path(history):
    """A history file's path from a path or a History."""
    if isinstance(history, History):
        if not history.path:
            raise ValueError("this History has no history file: run the problem with "
                             "combabc.run(problem, options, output_directory=...) to write one")
        return history.path
    return os.fspath(history)


def export(path, directory=None, *, overwrite=False, netcdf=True, all_waves=False):
    """`combabc export RUN.sqlite`: the CSV and JSON files, and inference_data.nc (netcdf=False
    skips it; all_waves=True adds every wave's resampled posterior, as --all-waves), into
    `directory` (default export/ beside the history). path: the history file or a History that
    has one (History.path). Returns the directory. When the NetCDF file cannot be made (no
    xarray for the report's python) the rest is written and a UserWarning says why, as the CLI's
    note."""
    outcome = _core.export(_history_path(path), os.fspath(directory or ""), overwrite, netcdf,
                           all_waves)
    if outcome["note"]:
        warnings.warn(outcome["note"], stacklevel=2)
    return outcome["directory"]


def resume(path, problem=None, options=None, *, threads=None, report=False,
           max_simulations=None, max_wall_time=None, min_acceptance_rate=None,
           max_failure_fraction=None, waves=None):
    """Continues an interrupted, killed or failed run from its history file (a path or a
    History), as `combabc resume` (the result equals an uninterrupted run's); returns its
    History. A run that stopped on a limit continues with that limit raised (the keywords are
    `combabc resume`'s --max-simulations, --max-wall-time (seconds), --min-acceptance-rate and
    --max-failure-fraction). A run that did all its waves (termination "max_waves") continues with
    more: waves=N, the number in all, as `combabc resume --waves N`; the result equals one run of
    N waves. The limits and waves given are recorded in the history; later resumes keep them. A
    finished run otherwise, or a stopped one whose limits would stop it again at once, is a
    combabc.Error (usage) that says which keyword to give.

    A run of a Problem (combabc.run(problem, options, output_directory=...)) is resumed with the
    same Problem (the same simulator and distance functions) and the same options passed again:
    the history's fingerprint refuses other ones (threads and the stop limits may differ)."""
    path = _history_path(path)
    if problem is None:
        if options is not None:
            raise TypeError("options apply to a Problem's run; a config run carries its own")
        return _warned(History(_core.resume(path, -1 if threads is None else threads, report,
                                            max_simulations, max_wall_time, min_acceptance_rate,
                                            max_failure_fraction, waves)))
    if options is None:
        options = SmcOptions()
    if threads is not None:
        options.threads = threads
    data = _core.run_smc(_smc_request(problem, options), path, False, True, report, "",
                         max_simulations, max_wall_time, min_acceptance_rate,
                         max_failure_fraction, waves)
    return _warned(_problem_history(data, problem))


def enumerate(config, *, thresholds=None, threads=None, output_directory=None, overwrite=False,
              report=False, top=20, max_particles=100000):
    """The exact ABC posterior of a config's problem by enumerating every configuration, as
    `combabc enumerate` (thresholds: one per threshold component; default the config's final
    ones). Returns the History of its one wave; History.enumeration holds directory (the
    tables), configurations, accepted, evidence and wall_seconds."""
    # Not `thresholds or []`: a NumPy array has no truth value.
    thresholds = [] if thresholds is None else [float(t) for t in thresholds]
    data = _core.enumerate(os.fspath(config), thresholds,
                           -1 if threads is None else threads, os.fspath(output_directory or ""),
                           overwrite, report, top, max_particles)
    return History(data)


class SensorModel:
    """The simulator of a config file at its nominal values, as `combabc simulate CONFIG --clamps`
    runs it: the built-in sensor at its [model] values (or the config's external simulator, which
    works in "<config stem>.simulate.work" beside the config unless work_directory is given).

    profile(clamps): one configuration, "0110..." (one character per clamp, 1 = fixed) or d
    values of 0/1, to float64[m]: the sensor's |w| in metres at `positions` (normalised=True:
    divided by its largest magnitude, the CSV's normalised column). profiles(clamps): n
    configurations (uint8[n, d] or a list of strings) to float64[n, m]. The GIL is released
    while the model works.
    """

    def __init__(self, config, *, work_directory=None):
        config = os.fspath(config)
        if work_directory is None:
            stem = os.path.splitext(os.path.basename(config))[0]
            work_directory = os.path.join(os.path.dirname(config), stem + ".simulate.work")
        self.config = config
        self._model = _core.NominalSimulator(config, os.fspath(work_directory))
        self.dimension = self._model.dimension
        self.positions = np.asarray(self._model.positions, dtype=np.float64)
        self.output_name = self._model.output_name

    def _bits(self, clamps):
        if isinstance(clamps, str):
            return self._model.parse(clamps)
        return np.ascontiguousarray(clamps, dtype=np.uint8)

    def profile(self, clamps, normalised=False):
        values = self._model.simulate(self._bits(clamps))
        return _normalised(values) if normalised else values

    def profiles(self, clamps, normalised=False):
        if not isinstance(clamps, np.ndarray) and all(isinstance(c, str) for c in clamps):
            clamps = np.stack([self._model.parse(c) for c in clamps]) if clamps else \
                np.zeros((0, self.dimension), dtype=np.uint8)
        bits = np.ascontiguousarray(clamps, dtype=np.uint8)
        if bits.ndim != 2:
            raise ValueError(f"clamps: expected an array of shape (n, {self.dimension})")
        values = self._model.simulate(bits)
        return np.stack([_normalised(v) for v in values]) if normalised and len(values) else values

    def __repr__(self):
        return f"SensorModel({self.config!r}: {self.dimension} clamps, {len(self.positions)} outputs)"


def _normalised(values):
    peak = np.max(np.abs(values)) if values.size else 0.0
    return values / peak if peak > 0 else np.zeros_like(values)
