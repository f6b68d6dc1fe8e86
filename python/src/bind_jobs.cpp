// combabc._core's jobs on config files and history files, as the CLI's subcommands run them
// (run, resume, enumerate, export, simulate), and the history read back as NumPy arrays.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "combabc/config/config.hpp"
#include "combabc/export/export.hpp"
#include "combabc/services/enumerate.hpp"
#include "combabc/services/history_tools.hpp"
#include "combabc/services/run.hpp"
#include "combabc/services/simulate.hpp"

namespace py = pybind11;

namespace combabc::python {

bool PythonSignals::ShouldStop() {
  if (raised_) return true;
  const py::gil_scoped_acquire gil;
  if (PyErr_CheckSignals() != 0) raised_.emplace();  // takes the pending exception
  return raised_.has_value();
}

void PythonSignals::RaiseIfInterrupted(const std::string& note) {
  if (!raised_) return;
  if (!note.empty() && py::hasattr(raised_->value(), "add_note")) {
    raised_->value().attr("add_note")(note);
  }
  throw *raised_;
}

std::string ContinueNote(const std::string& path, const std::string& arguments) {
  return "combabc: interrupted; continue with combabc.resume(\"" + path + "\"" + arguments + ")";
}

HistoryNames NamesOf(const RunMetadata& metadata, const RunHistory& history) {
  HistoryNames names;
  for (int k = 0; k < metadata.dimension; ++k) {
    names.bits.push_back(BitName(metadata, static_cast<std::size_t>(k)));
  }
  for (const ContinuousParameter& p : metadata.reals) names.reals.push_back(p.name);
  for (const DistanceComponent& c : metadata.distance_components) {
    names.components.push_back(c.name);
  }
  names.estimator = metadata.estimator;
  names.binary_kernel = ToString(metadata.proposal.binary);
  names.continuous_kernel = ToString(metadata.proposal.continuous);
  names.exact = metadata.termination == ToString(Termination::kEnumerated);
  names.bit_prior_one = metadata.bit_prior_one;
  std::size_t thresholds = 0;
  for (const DistanceComponent& c : metadata.distance_components) {
    if (c.kind != ComponentKind::kIndicator) ++thresholds;
  }
  if (!history.waves.empty()) thresholds = history.waves.front().thresholds.size();
  names.threshold_columns = ThresholdColumns(metadata, thresholds);
  names.distance_columns = DistanceColumns(metadata, metadata.distance_components.size());
  return names;
}

// Each continuous parameter's prior as summary.json's "reals" give it (History.real_priors).
py::list RealPriors(const std::vector<ContinuousParameter>& reals) {
  py::list priors;
  for (const ContinuousParameter& r : reals) {
    py::dict prior;
    prior["kind"] = std::string(ToString(r.prior.kind));
    prior["low"] = r.prior.low;
    prior["high"] = r.prior.high;
    prior["mean"] = r.prior.mean;
    prior["sd"] = r.prior.sd;
    priors.append(prior);
  }
  return priors;
}

py::dict LoadHistory(const std::string& path, const std::string& report_directory) {
  RunMetadata metadata;
  RunHistory history;
  {
    const py::gil_scoped_release release;
    const HistoryStore store = HistoryStore::Open(path, /*read_only=*/true);
    metadata = store.LoadMetadata();
    history = store.LoadHistory();
  }
  py::dict result = HistoryToDict(history, NamesOf(metadata, history));
  result["status"] = std::string(ToString(metadata.status));
  // The file's termination, empty until the run ended by a criterion (a failed or killed run):
  // the loaded summary's enum cannot say "none" and would read max_waves.
  result["summary"].cast<py::dict>()["termination"] = metadata.termination;
  result["bit_prior_one"] = metadata.bit_prior_one;
  result["real_priors"] = RealPriors(metadata.reals);
  result["seed"] = metadata.seed;
  result["path"] = path;
  // What the NetCDF export records beside the particles (History.to_inference_data).
  result["measured_position"] = metadata.measured.positions;
  result["measured_value"] = metadata.measured.values;
  result["position_unit"] = metadata.position_unit;
  result["output_position"] = metadata.output_positions;
  result["experiments"] = ExperimentsToList(metadata);
  result["combabc_version"] = metadata.combabc_version;
  result["config_path"] = metadata.config_path;
  result["config_text"] = metadata.config_text;
  result["end_time"] = metadata.end_time;
  if (!report_directory.empty()) result["report_directory"] = report_directory;
  return result;
}

namespace {

// A config run or resume (services::RunOutcome), read back from the history file it wrote, so
// that the arrays are exactly what `combabc export` writes.
py::dict RunAndReadBack(const std::function<services::RunOutcome(SmcObserver*)>& job) {
  const auto outcome = RunReleased<services::RunOutcome>(
      job, [](const services::RunOutcome& o) { return ContinueNote(o.history_path); });
  return LoadHistory(outcome.history_path, outcome.report_directory);
}

py::dict Enumerate(const services::EnumerateRequest& request) {
  const auto outcome = RunReleased<services::EnumerateOutcome>(
      [&](SmcObserver* signals) { return services::RunEnumeration(request, signals); },
      [](const services::EnumerateOutcome&) {
        return std::string("combabc: enumeration interrupted; nothing written");
      });
  py::dict result = LoadHistory(outcome.history_path, outcome.report_directory);
  py::dict enumeration;
  enumeration["directory"] = outcome.enumeration_directory;
  enumeration["configurations"] = outcome.configurations;
  enumeration["accepted"] = outcome.accepted;
  enumeration["evidence"] = outcome.evidence;
  enumeration["wall_seconds"] = outcome.wall_seconds;
  result["enumeration"] = enumeration;
  return result;
}

py::dict Export(const std::string& history_path,
                const std::string& directory,
                bool overwrite,
                bool netcdf,
                bool all_waves) {
  services::ExportOutcome outcome;
  {
    const py::gil_scoped_release release;
    outcome = services::ExportHistory(history_path, directory, overwrite, netcdf, all_waves);
  }
  py::dict result;
  result["directory"] = outcome.directory;
  result["netcdf_path"] = outcome.netcdf_path;
  result["note"] = outcome.note;
  return result;
}

// The config's simulator at its nominal values (services::NominalSimulator): SensorModel.
std::unique_ptr<services::NominalSimulator> MakeNominal(const std::string& config_path,
                                                        const std::string& work_directory) {
  const py::gil_scoped_release release;
  return std::make_unique<services::NominalSimulator>(LoadConfig(config_path), work_directory);
}

using Bits = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>;

// bits: uint8[d] or uint8[n, d]; returns float64[m] or float64[n, m].
py::array_t<double> SimulateNominal(const services::NominalSimulator& model, const Bits& bits) {
  const auto d = static_cast<py::ssize_t>(model.dimension());
  const auto m = static_cast<py::ssize_t>(model.output_size());
  const bool single = bits.ndim() == 1;
  if (!(bits.ndim() == 1 || bits.ndim() == 2) || bits.shape(bits.ndim() - 1) != d) {
    throw py::value_error("clamps: expected " + std::to_string(d) + " values of 0/1 per " +
                          "configuration, as an array of shape (" + std::to_string(d) +
                          ",) or (n, " + std::to_string(d) + ")");
  }
  const py::ssize_t n = single ? 1 : bits.shape(0);
  const std::uint8_t* in = bits.data();
  for (py::ssize_t i = 0; i < n * d; ++i) {
    if (in[i] > 1) throw py::value_error("clamps: every value must be 0 or 1");
  }
  py::array_t<double> out = single ? py::array_t<double>(m) : py::array_t<double>({n, m});
  double* values = out.mutable_data();
  {
    const py::gil_scoped_release release;
    for (py::ssize_t i = 0; i < n; ++i) {
      const std::vector<double> w =
          model.Simulate(std::span<const std::uint8_t>(in + i * d, static_cast<std::size_t>(d)));
      std::copy(w.begin(), w.end(), values + i * m);
    }
  }
  return out;
}

}  // namespace

void BindJobs(py::module_& m) {
  m.def(
      "load_history", [](const std::string& path) { return LoadHistory(path); }, py::arg("path"));
  m.def(
      "run_config",
      [](const std::string& config_path,
         int threads,
         const std::string& output_directory,
         bool overwrite,
         bool report,
         const std::string& start_from) {
        services::RunRequest request;
        request.config_path = config_path;
        request.start_from = start_from;
        request.output_directory = output_directory;
        request.threads = threads;
        request.overwrite = overwrite;
        request.report = report;
        return RunAndReadBack(
            [&](SmcObserver* signals) { return services::RunCalibration(request, signals); });
      },
      py::arg("config_path"),
      py::arg("threads") = -1,
      py::arg("output_directory") = std::string(),
      py::arg("overwrite") = false,
      py::arg("report") = false,
      py::arg("start_from") = std::string());
  m.def("export",
        &Export,
        py::arg("history_path"),
        py::arg("directory") = std::string(),
        py::arg("overwrite") = false,
        py::arg("netcdf") = true,
        py::arg("all_waves") = false);
  m.def(
      "resume",
      [](const std::string& history_path,
         int threads,
         bool report,
         std::optional<std::int64_t> max_simulations,
         std::optional<double> max_wall_time,
         std::optional<double> min_acceptance_rate,
         std::optional<double> max_failure_fraction,
         std::optional<int> waves) {
        services::ResumeRequest request;
        request.history_path = history_path;
        request.threads = threads;
        request.report = report;
        request.limits = {
            max_simulations, max_wall_time, min_acceptance_rate, max_failure_fraction, waves};
        request.names = services::OptionNames::kPython;
        return RunAndReadBack(
            [&](SmcObserver* signals) { return services::ResumeCalibration(request, signals); });
      },
      py::arg("history_path"),
      py::arg("threads") = -1,
      py::arg("report") = false,
      py::arg("max_simulations") = py::none(),
      py::arg("max_wall_time") = py::none(),
      py::arg("min_acceptance_rate") = py::none(),
      py::arg("max_failure_fraction") = py::none(),
      py::arg("waves") = py::none());
  m.def(
      "enumerate",
      [](const std::string& config_path,
         const std::vector<double>& thresholds,
         int threads,
         const std::string& output_directory,
         bool overwrite,
         bool report,
         int top,
         int max_particles) {
        services::EnumerateRequest request;
        request.config_path = config_path;
        request.thresholds = thresholds;
        request.threads = threads;
        request.output_directory = output_directory;
        request.overwrite = overwrite;
        request.report = report;
        request.top = top;
        request.max_particles = max_particles;
        return Enumerate(request);
      },
      py::arg("config_path"),
      py::arg("thresholds") = std::vector<double>{},
      py::arg("threads") = -1,
      py::arg("output_directory") = std::string(),
      py::arg("overwrite") = false,
      py::arg("report") = false,
      py::arg("top") = 20,
      py::arg("max_particles") = 100000);
  py::class_<services::NominalSimulator>(m, "NominalSimulator")
      .def(py::init(&MakeNominal), py::arg("config_path"), py::arg("work_directory"))
      .def_property_readonly("dimension", &services::NominalSimulator::dimension)
      .def_property_readonly("positions", &services::NominalSimulator::positions)
      .def_property_readonly("output_name", &services::NominalSimulator::output_name)
      .def_property_readonly("is_sensor", &services::NominalSimulator::is_sensor)
      .def("simulate", &SimulateNominal, py::arg("bits"))
      .def("parse", [](const services::NominalSimulator& model, const std::string& clamps) {
        // The CLI's --clamps check and messages, for a "0110..." string.
        const std::vector<std::uint8_t> bits = model.ParseBits(clamps);
        return py::array_t<std::uint8_t>(static_cast<py::ssize_t>(bits.size()), bits.data());
      });
}

}  // namespace combabc::python
