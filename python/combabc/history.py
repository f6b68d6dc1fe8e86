"""A run history as NumPy arrays and pandas DataFrames (docs/python.md).

The column names follow `combabc export` (docs/history.md, "Export"). Numbering (docs/python.md,
"Numbering"): waves are numbered from 1 (`Wave.number`, every `wave=` argument, the DataFrames'
`wave` column), bits are named (`History.bit_names`; the DataFrames' bit columns) or counted from
1; NumPy arrays stay positional (column j of `bits` is bit j + 1).
"""

import os
import warnings

import numpy as np

from . import _core, _netcdf


class ModeLossWarning(UserWarning):
    """A wave's proposal gave a heavy pattern of the previous wave a negligible probability: the
    posterior may have lost a mode (docs/algorithm.md, "Mode loss"). combabc.run and
    combabc.resume raise one per such wave, with the line the CLI prints; Wave.mode_loss_warning
    holds it."""


class Wave:
    """One wave: its statistics and its accepted particles as NumPy arrays.

    Attributes: number (from 1), thresholds, phi, proposal, candidates, accepted, acceptance_rate,
    complete, marginals_paper, marginals_importance, ess, reals_mean, reals_sd, distinct,
    discarded, wall_seconds; the Monte-Carlo errors of the run's estimator, as summary.json's
    "waves" entries name them (docs/history.md, "The answer"): marginals_se and marginals_ess
    (float64[d]: per bit its standard error, floored by the rule of three, and its ESS), ess_bits
    (the smallest ESS of a bit that varies; NaN when none does), reals_mean_se, reals_sd_se and
    reals_ess (float64[r]), each NaN for an enumeration (exact); pair_correlations (float64[d, d]: the Pearson correlation of bits i
    and j under the particles' weights, 0 for a bit constant among them; 0 x 0 without
    particles); per particle: index int64[n], bits uint8[n, d], reals float64[n, r],
    log_weight and weight float64[n], distance float64[n, k], output float64[n, m] (m = 0 when the
    run kept no outputs); failure_index int64[f] and failure_reason (list of str);
    pattern_classes, the mode-loss diagnostic's heavy patterns of the previous wave (a list of
    dicts: bits uint8[d] (2 for a bit the class leaves free), mass, proposal (the share of the
    wave's particles), flagged; docs/algorithm.md, "Mode loss") and
    mode_loss_warning (the CLI's line for the flagged ones, "" for none). A
    multi-fidelity run's wave also has multi_fidelity (a dict: continue_if_accepted,
    continue_if_rejected, expensive_simulations, cheap_seconds, expensive_seconds,
    next_continue_if_accepted, next_continue_if_rejected, cost_ratio) and per particle multiplier
    float64[n], confirmed bool[n] and low_distance float64[n, k]; each is None in a
    single-fidelity run. Every wave has ancestor int64[n] (a resample-move wave's particle: the
    index of the previous wave's particle it was resampled from and moved; -1 for one drawn
    afresh) and moves: a resample-move wave's move statistics as summary.json's "moves" (a dict:
    rounds, proposed, accepted, acceptance_rate, independent_proposed, independent_accepted,
    independent_share, survivor_ess, step; docs/history.md), None for a wave drawn by rejection.
    """

    def __init__(self, record, estimator):
        self.__dict__.update(record)
        self._estimator = estimator

    @property
    def marginals(self):
        """Per-bit P(bit = 1) under the run's estimator."""
        if self._estimator == "paper":
            return self.marginals_paper
        return self.marginals_importance

    def __repr__(self):
        return (f"Wave({self.number}: {self.accepted} accepted of {self.candidates}, "
                f"thresholds {list(self.thresholds)})")


class Experiment:
    """One experiment of the run (a config's [[experiment]] table; docs/config.md): its slices of
    the run's concatenated outputs, measured points and distance components.

    Attributes: index (from 0), name ("" for the single experiment of a config without
    [[experiment]]), description (its load and scan in words; may be empty); outputs, measured and
    components: slices of Wave.output's columns, of History.measured_position / measured_value and
    of Wave.distance's columns; output_position (its outputs' x, float64[m_e]), measured_position
    and measured_value (float64[p_e]), component_names (list of str).
    """

    def __init__(self, index, record, history):
        self.index = index
        self.name = record.get("name", "")
        self.description = record.get("description", "")
        self.outputs = _slice(record, "first_output", "outputs")
        self.measured = _slice(record, "first_measured", "measured")
        self.components = _slice(record, "first_component", "components")
        self.output_position = history.output_position[self.outputs]
        self.measured_position = history.measured_position[self.measured]
        self.measured_value = history.measured_value[self.measured]
        self.component_names = history.components[self.components]

    def __repr__(self):
        text = f"Experiment({self.name!r}" if self.name else "Experiment(unnamed"
        return (text + f": {len(self.output_position)} outputs, {len(self.measured_position)} "
                f"measured points, components {self.component_names})")


def _slice(record, first, count):
    """A slice from a record's start and size; everything when the record does not say."""
    if first not in record or count not in record:
        return slice(0, None)
    return slice(int(record[first]), int(record[first]) + int(record[count]))


_WAVE_FIDELITY_COLUMNS = ("continue_if_accepted", "continue_if_rejected", "expensive_simulations",
                          "cheap_seconds", "expensive_seconds", "next_continue_if_accepted",
                          "next_continue_if_rejected", "cost_ratio")


_WAVE_MOVE_COLUMNS = ("rounds", "proposed", "accepted", "acceptance_rate", "independent_proposed",
                      "independent_accepted", "independent_share", "survivor_ess", "step")


def _fidelity_columns(w, distance_columns):
    """A wave's multi-fidelity particle columns, as export's particles.csv names them."""
    n = len(w.index)
    if w.multiplier is None:
        columns = {"multiplier": np.ones(n), "confirmed": np.zeros(n, dtype=np.int64)}
        low = np.full((n, len(distance_columns)), np.nan)
    else:
        columns = {"multiplier": w.multiplier, "confirmed": w.confirmed.astype(np.int64)}
        low = w.low_distance
    for k, name in enumerate(distance_columns):
        columns["low_distance_" + name[2:]] = low[:, k]
    return columns


# History.answer()'s columns, in order.
_ANSWER_COLUMNS = ("name", "kind", "P", "se", "verdict", "mean", "sd", "sd_se", "ess", "q05",
                   "median", "q95")


class History:
    """A run's waves and summary. `waves` is a list of Wave; the methods return DataFrames."""

    def __init__(self, data):
        names = data["names"]
        self.bit_names = list(names["bits"])
        self.real_names = list(names["reals"])
        self.components = list(names["components"])
        self._threshold_columns = list(names["threshold_columns"])
        self._distance_columns = list(names["distance_columns"])
        self.estimator = data["estimator"]
        # The kernels the run used (summary.json's "proposal"): binary_kernel, continuous_kernel.
        self.proposal = dict(data.get("proposal") or {})
        self.summary = dict(data["summary"])
        self.termination = self.summary["termination"]
        self.waves = [Wave(w, self.estimator) for w in data["waves"]]
        self.path = data.get("path")
        # The answer as _core.answer gives it, when the run handed it over (a run without a
        # history file); else answer() reads it from the file.
        self._answer = data.get("answer")
        self.status = data.get("status")
        self.report_directory = data.get("report_directory") or None
        self.seed = data.get("seed")
        # The stated prior: P(bit = 1) per bit (empty: 0.5 each) and each continuous parameter's
        # prior as a dict (kind, low, high, mean, sd), for the NetCDF prior group.
        self.bit_prior_one = list(data.get("bit_prior_one") or ())
        self.real_priors = list(data.get("real_priors") or ())
        # `enumerate` only: directory, configurations, accepted, evidence, wall_seconds.
        self.enumeration = data.get("enumeration")
        # The measured data (positions in position_unit); for a Problem, the observed data by
        # index.
        self.measured_position = np.asarray(data.get("measured_position", ()), dtype=np.float64)
        self.measured_value = np.asarray(data.get("measured_value", ()), dtype=np.float64)
        self.position_unit = data.get("position_unit") or "m"
        # The x of each output value (a config run's history; empty for a Problem's run).
        self.output_position = np.asarray(data.get("output_position", ()), dtype=np.float64)
        # The run's experiments, in order; a Problem's run and a history older than schema v6
        # have one, unnamed, holding everything.
        self.experiments = [Experiment(e, record, self) for e, record in
                            enumerate(data.get("experiments") or [{}])]
        self._provenance = {key: data.get(key) or "" for key in
                            ("combabc_version", "config_path", "config_text", "end_time")}

    @property
    def model_probabilities(self):
        """For one model's run in a model choice (its history in <directory>/models/<name>/, or
        a joint model choice's in <directory>/joint/): the whole choice's table,
        combabc.load_model_choice(<directory>); None for any other run, or before the model
        choice has written its model_choice/models.csv."""
        if not self.path:
            return None
        run = os.path.dirname(os.path.abspath(self.path))
        models = os.path.dirname(run)
        if os.path.basename(run) == "joint":
            folder = os.path.join(models, "model_choice")
        elif os.path.basename(models) == "models":
            folder = os.path.join(os.path.dirname(models), "model_choice")
        else:
            return None
        if not os.path.isfile(os.path.join(folder, "models.csv")):
            return None
        from ._model_choice import load_model_choice
        return load_model_choice(folder)

    @property
    def binary_kernel(self):
        """The binary proposal kernel the run used, `auto` resolved ("independent", "logistic",
        ...), as summary.json's proposal.binary_kernel."""
        return self.proposal.get("binary_kernel", "")

    @property
    def continuous_kernel(self):
        """The continuous proposal kernel the run used, `auto` resolved."""
        return self.proposal.get("continuous_kernel", "")

    @property
    def multi_fidelity(self):
        """Whether the run had a low-fidelity simulator (its waves carry multi_fidelity)."""
        return any(w.multi_fidelity is not None for w in self.waves)

    @property
    def resample_move(self):
        """Whether the run moved particles (a resample-move run: some of its waves carry
        moves)."""
        return any(w.moves is not None for w in self.waves)

    @property
    def dimension(self):
        return len(self.bit_names)

    @property
    def posterior_wave(self):
        """The Wave the run's answer is taken from, as the CLI's answer (docs/history.md,
        "Answer"): the last complete wave with particles; when none is complete, the last wave
        with particles. A run stopped during a wave (budget, wall time, Ctrl-C) answers from the
        wave before: posterior_note says so."""
        return self.waves[_netcdf.answer(self.waves, self.termination)[0]]

    @property
    def posterior_note(self):
        """Why the posterior is not the last wave's, in the CLI's words ("the numbers are wave
        4's: wave 5 is incomplete (budget_exhausted)"), or "" when it is the last complete wave."""
        # One rule with the NetCDF export's (its posterior_note attribute).
        return _netcdf.answer(self.waves, self.termination)[1]

    @property
    def posterior(self):
        """posterior_wave's per-bit marginals under the run's estimator; a UserWarning carries
        posterior_note when that is not the last wave or not complete."""
        note = self.posterior_note
        if note:
            warnings.warn(note, stacklevel=2)
        return self.posterior_wave.marginals

    @property
    def posterior_se(self):
        """posterior's Monte-Carlo standard errors, per bit (posterior_wave.marginals_se: the
        answer's mc_se in summary.json and on the terminal); NaN for an enumeration (exact)."""
        return self.posterior_wave.marginals_se

    def answer(self):
        """The run's answer as a DataFrame, one row per parameter, with the numbers the terminal
        prints at the end of a run and summary.json's "answer" holds (docs/history.md, "The
        answer"): computed by combabc's one function for them, not again here. Columns: name,
        kind ("bit" or "real"); for a bit P (P(bit = 1) under the run's estimator; the sensor's
        P(fixed)), se (its Monte-Carlo standard error, the delta method's; 0 when exact) and
        verdict ("fixed" (bit = 1), "free" (bit = 0) or "not determined", at attrs["verdict_level"]
        0.95); for a continuous parameter mean, se (the mean's standard error), sd, sd_se, ess (the
        mean's effective sample size) and its posterior quantiles q05, median and q95 (weighted,
        no interpolation); NaN (verdict None) where a column does not apply. attrs: wave (the
        answer's, from 1; posterior_wave), waves, complete, exact, estimator, termination,
        verdict_level, particles, distinct, tempered, temperatures, top_configurations (dicts:
        bits, mass, mass_se, fixed) and text (the terminal's answer). Read from the history file
        (History.path), unless the run handed its answer over (a Problem run without
        output_directory: the same numbers a history file of it would give)."""
        import pandas as pd
        if self._answer is not None:
            data = self._answer
        elif not self.path:
            raise ValueError("History.answer(): this History has no history file; run the "
                             "problem with output_directory=... (or load one with "
                             "combabc.load_history)")
        else:
            data = _core.answer(os.fspath(self.path))
        if data["waves"] != len(self.waves):
            raise ValueError(f"History.answer(): {self.path} now holds {data['waves']} waves, "
                             f"this History {len(self.waves)}; load it again "
                             "(combabc.load_history)")
        nan = float("nan")
        rows = [{"name": b["name"], "kind": "bit", "P": b["p_one"], "se": b["mc_se"],
                 "verdict": b["verdict"]} for b in data["bits"]]
        rows += [{"name": r["name"], "kind": "real", "P": nan, "se": r["mc_se"], "verdict": None,
                  "mean": r["mean"], "sd": r["sd"], "sd_se": r["sd_se"], "ess": r["ess"],
                  "q05": r["q05"], "median": r["median"], "q95": r["q95"]}
                 for r in data["reals"]]
        frame = pd.DataFrame(rows, columns=list(_ANSWER_COLUMNS))
        for column in _ANSWER_COLUMNS[5:]:
            frame[column] = frame[column].astype(np.float64)
        frame.attrs.update({key: value for key, value in data.items()
                            if key not in ("bits", "reals")})
        return frame

    def experiment(self, which):
        """An experiment by name or index."""
        if isinstance(which, Experiment):
            return which
        if isinstance(which, str):
            for x in self.experiments:
                if x.name == which:
                    return x
            names = ", ".join(repr(x.name) for x in self.experiments)
            raise KeyError(f"no experiment named {which!r} (the run has {names})")
        return self.experiments[which]

    def wave(self, number=None):
        """A Wave by its number (from 1), or posterior_wave for None (the last complete wave)."""
        if number is None:
            return self.posterior_wave
        if isinstance(number, bool) or not isinstance(number, (int, np.integer)) or \
                not 1 <= number <= len(self.waves):
            raise IndexError(f"wave={number!r}: waves are numbered 1 to {len(self.waves)}")
        return self.waves[int(number) - 1]

    def bit(self, which):
        """A bit's position (from 0, its column in the NumPy arrays) from its name or its number
        (from 1)."""
        if isinstance(which, str):
            if which not in self.bit_names:
                raise KeyError(f"no bit named {which!r} (bits: {', '.join(self.bit_names)})")
            return self.bit_names.index(which)
        if isinstance(which, bool) or not isinstance(which, (int, np.integer)) or \
                not 1 <= which <= self.dimension:
            raise IndexError(f"bit {which!r}: bits are numbered 1 to {self.dimension}, or named")
        return int(which) - 1

    def curves(self, wave=None, experiment=None):
        """A wave's accepted simulated outputs, float64[n, m]: every output, or one experiment's
        (its name, index or Experiment; columns at that experiment's output_position). wave: its
        number (from 1; default posterior_wave, the last complete one). Empty (n x 0) when the run
        kept no outputs."""
        output = self.wave(wave).output
        if experiment is None or not output.shape[1]:
            return output
        return output[:, self.experiment(experiment).outputs]

    def particles(self, wave=None):
        """Accepted particles as export's particles.csv: wave (from 1), index, bits (0/1 text),
        one column per bit named by its name (bit_names), one column per continuous parameter,
        log_weight, weight and d_<component> (component names made column-safe, as in the
        export), for a multi-fidelity run multiplier, confirmed (0/1) and
        low_distance_<component>, and for a resample-move run ancestor (-1 drawn afresh). wave: a
        wave's number (from 1), or None for every wave."""
        import pandas as pd
        frames = []
        for w in self._selected(wave):
            columns = {"wave": np.full(len(w.index), w.number, dtype=np.int64),
                       "index": w.index,
                       "bits": ["".join("1" if b else "0" for b in row) for row in w.bits]}
            for k, name in enumerate(self.bit_names):
                columns[name] = w.bits[:, k].astype(np.int64)
            for k, name in enumerate(self.real_names):
                columns[name] = w.reals[:, k]
            columns["log_weight"] = w.log_weight
            columns["weight"] = w.weight
            for k, name in enumerate(self._distance_columns):
                columns[name] = w.distance[:, k]
            if self.multi_fidelity:
                columns.update(_fidelity_columns(w, self._distance_columns))
            if self.resample_move:
                columns["ancestor"] = w.ancestor
            frames.append(pd.DataFrame(columns))
        return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()

    def marginals(self):
        """Per-bit marginals, long, as export's marginals.csv: wave (from 1), bit (from 1), name,
        prob_paper, prob_importance."""
        import pandas as pd
        rows = []
        for w in self.waves:
            for k in range(min(self.dimension, len(w.marginals_paper))):
                rows.append({"wave": w.number, "bit": k + 1, "name": self.bit_names[k],
                             "prob_paper": w.marginals_paper[k],
                             "prob_importance": w.marginals_importance[k]})
        return pd.DataFrame(rows, columns=["wave", "bit", "name", "prob_paper",
                                           "prob_importance"])

    def pair_correlations(self):
        """Per-wave pair correlations, long, as export's pair_correlations.csv: wave (from 1),
        bit_i, name_i, bit_j, name_j (bits from 1; one row per pair i < j), correlation."""
        import pandas as pd
        rows = []
        for w in self.waves:
            r = w.pair_correlations
            for i, j in zip(*np.triu_indices(len(r), k=1)):
                rows.append({"wave": w.number, "bit_i": int(i) + 1, "name_i": self.bit_names[i],
                             "bit_j": int(j) + 1, "name_j": self.bit_names[j],
                             "correlation": r[i, j]})
        return pd.DataFrame(rows, columns=["wave", "bit_i", "name_i", "bit_j", "name_j",
                                           "correlation"])

    def wave_table(self):
        """One row per wave: wave (from 1), eps_<component> (T_<component> for a likelihood
        component) per threshold, phi, candidates,
        accepted, acceptance_rate, ess, distinct, wall_seconds, complete, failures, ess_bits (as
        waves.csv: the smallest per-bit ESS; NaN when no bit varies or exact), and for a
        multi-fidelity run continue_if_accepted, continue_if_rejected, expensive_simulations,
        cheap_seconds, expensive_seconds, next_continue_if_accepted, next_continue_if_rejected
        and cost_ratio, and for a resample-move run move_rounds, move_proposed, move_accepted,
        move_acceptance_rate, move_independent_proposed, move_independent_accepted,
        move_independent_share, move_survivor_ess and move_step (NaN in a wave drawn by
        rejection), as waves.csv."""
        import pandas as pd
        rows = []
        for w in self.waves:
            row = {"wave": w.number}
            for name, eps in zip(self._threshold_columns, w.thresholds):
                row[name] = eps
            row.update(phi=w.phi, candidates=w.candidates, accepted=w.accepted,
                       acceptance_rate=w.acceptance_rate, ess=w.ess, distinct=w.distinct,
                       wall_seconds=w.wall_seconds, complete=int(w.complete),
                       failures=len(w.failure_index), ess_bits=w.ess_bits)
            if self.multi_fidelity:
                row.update({key: (w.multi_fidelity or {}).get(key, np.nan)
                            for key in _WAVE_FIDELITY_COLUMNS})
            if self.resample_move:
                row.update({"move_" + key: (w.moves or {}).get(key, np.nan)
                            for key in _WAVE_MOVE_COLUMNS})
            rows.append(row)
        return pd.DataFrame(rows)

    def to_inference_data(self, all_waves=False):
        """The run in ArviZ's InferenceData layout: a dict of xarray Datasets, groups posterior
        (posterior_wave's particles, the last complete wave's, resampled to equally weighted draws
        (attributes wave, posterior_note and incomplete_wave_left_out say which): bits and the
        continuous parameters; dims chain = 1, draw; none when that wave's weights are signed, a
        multi-fidelity wave with negative weights: then sample_stats holds every particle with its
        signed weight, particle_bits and particle_<name>, and a UserWarning says so), sample_stats (per draw its particle's weight,
        log_weight, distance per component, particle_index), prior, posterior_predictive (the
        resampled accepted curves, when the run kept outputs) and observed_data, as
        `combabc export` writes in inference_data.nc (docs/history.md, "NetCDF"); all_waves=True
        adds posterior_wave_<k> and sample_stats_wave_<k> for every wave k. Needs xarray
        (python3-xarray)."""
        w = self.posterior_wave
        attrs = {"inference_library_version": self._provenance["combabc_version"],
                 "seed": self.seed if self.seed is not None else "",
                 "termination": self.termination, "status": self.status or "",
                 "estimator": self.estimator, "created_at": self._provenance["end_time"],
                 "config_path": self._provenance["config_path"],
                 "config_text": self._provenance["config_text"]}
        waves = self.waves if all_waves else \
            list({id(x): x for x in (self.waves[0], w, self.waves[-1])}.values())
        groups = _netcdf.inference_data(
            waves=[{"number": x.number, "complete": x.complete, "thresholds": x.thresholds,
                    "bits": x.bits,
                    "reals": x.reals, "log_weight": x.log_weight, "weight": x.weight,
                    "distance": x.distance, "index": x.index, "output": x.output,
                    "multiplier": x.multiplier,
                    "confirmed": None if x.confirmed is None else x.confirmed.astype(np.uint8),
                    "ancestor": x.ancestor if self.resample_move else None, "moves": x.moves}
                   for x in waves],
            bit_names=self.bit_names, real_names=self.real_names, components=self.components,
            measured_position=self.measured_position, measured_value=self.measured_value,
            position_unit=self.position_unit, attrs=attrs, estimator=self.estimator,
            seed=self.seed, bit_prior_one=self.bit_prior_one, real_priors=self.real_priors,
            output_position=self.output_position, all_waves=all_waves,
            experiments=[{"name": x.name, "description": x.description,
                          "first_measured": x.measured.start,
                          "measured": len(x.measured_position),
                          "first_component": x.components.start,
                          "components": len(x.component_names),
                          "first_output": x.outputs.start,
                          "outputs": len(x.output_position)} for x in self.experiments])
        # Signed (multi-fidelity) weights: no posterior group, as `combabc export` notes.
        note = groups["sample_stats"].attrs.get("signed_weights_note", "")
        if note:
            warnings.warn(note, stacklevel=2)
        return groups

    def to_netcdf(self, path, all_waves=False):
        """to_inference_data(all_waves) written to `path` (NetCDF-4, one group each;
        arviz.from_netcdf reads it). Needs xarray and netCDF4 (python3-xarray python3-netcdf4)."""
        _netcdf.write_netcdf(self.to_inference_data(all_waves), os.fspath(path))

    def _selected(self, wave):
        if wave is None:
            return self.waves
        return [self.wave(wave)]

    def __repr__(self):
        return (f"History({len(self.waves)} waves, termination {self.termination}, "
                f"{self.summary['simulations']} simulations)")
