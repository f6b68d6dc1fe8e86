#include "python_history.hpp"

#include <charconv>
#include <cstdint>
#include <cstdio>

#include "combabc/core/enum_names.hpp"

namespace combabc::python {
namespace {

// Text that a fingerprint hashes: every number in its shortest round-trip form.
class Description {
 public:
  Description& operator<<(double value) {
    char text[32];
    const auto end = std::to_chars(text, text + sizeof text, value).ptr;
    text_.append(text, end).push_back(';');
    return *this;
  }
  Description& operator<<(std::int64_t value) { return *this << std::to_string(value); }
  Description& operator<<(const std::string& value) {
    text_ += std::to_string(value.size()) + ':' + value + ';';
    return *this;
  }
  // FNV-1a, 64 bits, as 16 hex digits: a digest to compare, not a secret.
  std::string Digest() const {
    std::uint64_t hash = 14695981039346656037ULL;
    for (const char c : text_) {
      hash = (hash ^ static_cast<unsigned char>(c)) * 1099511628211ULL;
    }
    char digits[17];
    std::snprintf(digits, sizeof digits, "%016llx", static_cast<unsigned long long>(hash));
    return digits;
  }

 private:
  std::string text_;
};

}  // namespace

RunMetadata PythonRunMetadata(const PythonProblem& problem, const SmcOptions& options) {
  RunMetadata m;
  m.seed = options.seed;
  m.threads = options.threads;
  m.estimator = ToString(options.estimator);
  m.dimension = problem.space->dimension();
  for (int k = 0; k < m.dimension; ++k) m.bit_names.push_back(problem.space->name(k));
  m.bit_prior_one = problem.space->bit_prior_one();
  m.distance_components = problem.components;
  m.reals = *problem.reals;
  m.proposal = options.proposal;
  m.tempering_form = ToString(options.tempering.form);
  m.position_unit = "index";
  for (std::size_t i = 0; i < problem.observed->size(); ++i) {
    m.output_positions.push_back(static_cast<double>(i));
  }
  m.measured.positions = m.output_positions;
  m.measured.values = *problem.observed;
  m.fingerprint = PythonRunFingerprint(problem, options);
  return m;
}

std::vector<std::pair<std::string, std::string>> PythonRunFingerprint(const PythonProblem& problem,
                                                                      const SmcOptions& options) {
  Description p;
  const BinarySpace& space = *problem.space;
  p << std::int64_t{space.dimension()} << std::int64_t{space.num_free()};
  for (int k = 0; k < space.dimension(); ++k) {
    p << space.name(k) << std::int64_t{space.free_of_bit(k)};
  }
  for (const double q : space.free_prior_one()) p << q;
  for (const ContinuousParameter& r : *problem.reals) {
    p << r.name << std::string(ToString(r.prior.kind)) << r.prior.low << r.prior.high
      << r.prior.mean << r.prior.sd;
  }
  for (const double y : *problem.observed) p << y;
  for (const DistanceComponent& c : problem.components) {
    p << c.name << std::string(ToString(c.kind)) << c.required;
  }
  p << std::int64_t{problem.batch} << std::int64_t{problem.rng}
    << std::int64_t{problem.python_distance} << std::int64_t{problem.distance_batch};

  Description o;
  o << std::int64_t{options.num_waves} << std::int64_t{options.accepted_per_wave};
  for (const ThresholdSchedule& s : options.thresholds) {
    o << std::string(ToString(s.kind)) << s.quantile << s.initial << s.target;
    for (const double v : s.values) o << v;
    // What came with issue 23, only where it applies, so that older fingerprints are what they
    // were and a history from before still resumes.
    if (s.weighted) o << std::string("weighted");
    if (s.kind == ThresholdKind::kAcceptance) o << s.acceptance_rate;
    if (s.kind == ThresholdKind::kEss) o << s.ess_fraction;
  }
  if (!options.accepted_by_wave.empty()) {
    o << std::string("accepted_by_wave");
    for (const int n : options.accepted_by_wave) o << std::int64_t{n};
  }
  const TemperingSchedule& t = options.tempering;
  o << std::string(ToString(t.kind)) << std::string(ToString(t.form)) << t.phi0;
  for (const double v : t.values) o << v;
  const ProposalOptions& q = options.proposal;
  o << std::string(ToString(q.binary)) << q.logistic.min_correlation
    << std::int64_t{q.logistic.max_predecessors} << q.logistic.ridge << q.logistic.min_marginal
    << q.logistic.clip << std::string(ToString(q.continuous)) << q.scale;
  o << std::string(ToString(options.estimator)) << std::to_string(options.seed)
    << std::int64_t{options.batch_size} << std::int64_t{options.keep_outputs};
  // Resample-move runs only, so that rejection runs' fingerprints are what they were.
  if (options.method != SamplerMethod::kRejection) {
    const MoveOptions& m = options.moves;
    o << std::string(ToString(options.method)) << m.ess_fraction << m.stay_probability
      << std::int64_t{m.max_rounds} << m.independent_share << m.min_survivor_fraction;
  }
  // Multi-fidelity runs only, so that single-fidelity fingerprints are what they were.
  if (problem.low_fidelity) {
    const MultiFidelityOptions& mf = options.multi_fidelity;
    p << std::string("low_fidelity");
    o << mf.continue_if_accepted << mf.continue_if_rejected << std::int64_t{mf.adapt} << mf.floor
      << mf.cost_ratio;
  }
  return {{kPythonFingerprintPart, p.Digest()}, {"python_options", o.Digest()}};
}

}  // namespace combabc::python
