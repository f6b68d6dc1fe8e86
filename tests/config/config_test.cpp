#include "combabc/config/config.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "combabc/config/distance_from_config.hpp"
#include "combabc/core/error.hpp"
#include "combabc/metrics/composite_distance.hpp"

namespace combabc {
namespace {

constexpr double kTol = 1e-12;

std::string Fixture(const std::string& name) {
  return std::string(COMBABC_SOURCE_DIR) + "/tests/config/testdata/" + name;
}

// The error ParseConfig throws for `text` (fails the test if none).
Error ConfigError(const std::string& text) {
  try {
    ParseConfig(text, "inline.toml");
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return Error(ErrorKind::kSoftware, "none");
}

Error LoadError(const std::string& path) {
  try {
    LoadConfig(path);
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "no error for " << path;
  return Error(ErrorKind::kSoftware, "none");
}

// what() must read "file:line: key: ..." with exactly this prefix.
void ExpectLocated(const Error& e, const std::string& file, int line, const std::string& key) {
  EXPECT_EQ(e.kind(), ErrorKind::kConfig) << e.what();
  EXPECT_EQ(e.line(), line) << e.what();
  EXPECT_EQ(e.field(), key) << e.what();
  const std::string prefix = file + ":" + std::to_string(line) + ": " + key + ": ";
  EXPECT_EQ(std::string(e.what()).rfind(prefix, 0), 0u) << e.what() << "\nexpected " << prefix;
}

const std::string kMinimal =
    "[data]\n"
    "csv = \"p.csv\"\n"
    "[metric]\n"
    "preset = \"area\"\n";

// ------------------------------------------------------------------------------ valid files

TEST(Config, PaperLeastSquaresFixtureFillsEveryOption) {
  const CalibrationConfig c = LoadConfig(Fixture("paper_45cm_least_squares.toml"));
  EXPECT_EQ(c.description, "45 cm load, Eq. 5 least squares");
  EXPECT_EQ(c.directory, std::string(COMBABC_SOURCE_DIR) + "/tests/config/testdata");
  EXPECT_NE(c.text.find("[sampler.tempering]"), std::string::npos);
  // data
  EXPECT_EQ(c.experiments[0].data.csv, "profile_45cm.csv");
  EXPECT_EQ(c.experiments[0].data.position_column, "position_cm");
  EXPECT_EQ(c.experiments[0].data.position_unit, LengthUnit::kCentimetre);
  EXPECT_EQ(c.experiments[0].data.displacement_unit, LengthUnit::kMicrometre);
  ASSERT_TRUE(c.experiments[0].data.window_min && c.experiments[0].data.window_max);
  EXPECT_NEAR(*c.experiments[0].data.window_min, 0.48, kTol);
  EXPECT_NEAR(*c.experiments[0].data.window_max, 0.80, kTol);
  EXPECT_TRUE(c.experiments[0].data.normalise);
  EXPECT_FALSE(c.experiments[0].data.gaussian_extension.enabled);
  // metric
  ASSERT_TRUE(c.experiments[0].metric.preset.has_value());
  EXPECT_EQ(*c.experiments[0].metric.preset, MetricPreset::kLeastSquares);
  ASSERT_EQ(c.experiments[0].metric.components.size(), 1u);
  EXPECT_EQ(c.experiments[0].metric.components[0].type, MetricType::kLeastSquares);
  EXPECT_NEAR(c.experiments[0].metric.components[0].to, 0.80, kTol);
  // sampler -> SmcOptions
  EXPECT_EQ(c.smc.num_waves, 5);
  EXPECT_EQ(c.smc.accepted_per_wave, 500);
  EXPECT_EQ(c.smc.estimator, Estimator::kPaper);
  EXPECT_EQ(c.smc.seed, 2024u);
  EXPECT_EQ(c.smc.threads, 0);
  EXPECT_EQ(c.smc.max_simulations, 2000000);
  ASSERT_EQ(c.smc.thresholds.size(), 1u);
  EXPECT_EQ(c.smc.thresholds[0].kind, ThresholdKind::kList);
  EXPECT_EQ(c.smc.thresholds[0].values, (std::vector<double>{2.0, 1.0, 0.5, 0.25, 0.1}));
  EXPECT_EQ(c.smc.tempering.kind, TemperingKind::kLinear);
  EXPECT_EQ(c.smc.tempering.form, TemperingForm::kGeometric);
  EXPECT_EQ(c.smc.tempering.phi0, 0.5);
  EXPECT_TRUE(c.smc.keep_outputs);
  std::string why;
  EXPECT_TRUE(c.smc.IsValid(&why)) << why;
  // sampler -> BinarySpaceOptions
  EXPECT_EQ(c.space.dimension, 36);
  EXPECT_EQ(c.space.default_prior_one, 0.5);
  EXPECT_EQ(c.space.tied, (std::vector<std::vector<int>>{{0, 18}, {1, 19}}));
  ASSERT_EQ(c.space.names.size(), 36u);
  EXPECT_EQ(c.space.names[18], "clamp 19");
  // output
  EXPECT_EQ(c.output.directory, "results-45cm");
  EXPECT_EQ(c.output.database, "history.sqlite");
  EXPECT_EQ(c.output.figure_formats, (std::vector<std::string>{"png", "svg"}));
}

TEST(Config, PaperLeastSquaresEndToEndDistance) {
  const CalibrationConfig c = LoadConfig(Fixture("paper_45cm_least_squares.toml"));
  const MeasuredData data = LoadMeasuredData(c.experiments[0].data, c.directory);
  ASSERT_EQ(data.size(), 33u);  // 48..80 cm
  std::vector<double> out_x;
  for (int cm = 0; cm <= 90; ++cm) out_x.push_back(cm * 0.01);
  CompositeDistance distance(c.experiments[0].metric.components,
                             data.positions,
                             data.displacements,
                             out_x,
                             {.normalise_simulated = c.experiments[0].data.normalise});
  EXPECT_EQ(distance.threshold_schedules().size(), c.smc.thresholds.size());
  // Feeding the data back (zero elsewhere) reproduces them exactly: D = 0.
  std::vector<double> simulated(out_x.size(), 0.0);
  for (std::size_t j = 0; j < data.size(); ++j) {
    simulated[static_cast<std::size_t>(std::lround(data.positions[j] * 100))] =
        data.displacements[j] * 7.0;
  }
  double d = -1;
  distance.Evaluate(simulated, std::span<double>(&d, 1));
  EXPECT_NEAR(d, 0.0, 1e-20);
}

TEST(Config, SplitPresetWithGaussianExtension) {
  const CalibrationConfig c = LoadConfig(Fixture("paper_70cm_split.toml"));
  EXPECT_TRUE(c.experiments[0].data.gaussian_extension.enabled);  // the table's presence enables it
  EXPECT_NEAR(c.experiments[0].data.gaussian_extension.impact_position, 0.70, kTol);
  EXPECT_NEAR(c.experiments[0].data.gaussian_extension.spacing, 0.01, kTol);
  ASSERT_EQ(c.experiments[0].metric.components.size(), 5u);
  ASSERT_EQ(c.smc.thresholds.size(), 3u);  // indicators take no schedule
  for (const auto& s : c.smc.thresholds) {
    EXPECT_EQ(s.kind, ThresholdKind::kQuantile);
    EXPECT_EQ(s.quantile, 0.5);
    EXPECT_EQ(s.target, 0.01);
    EXPECT_TRUE(std::isinf(s.initial));
  }
  const MeasuredData data = LoadMeasuredData(c.experiments[0].data, c.directory);
  EXPECT_EQ(data.size(), 20u);  // 70..73 synthetic + 74..89 measured
  EXPECT_NEAR(data.positions.front(), 0.70, kTol);
  // The measured profile itself satisfies Eq. 7: a secondary peak in 76-80 cm.
  std::vector<double> out_x(data.positions.begin(), data.positions.end());
  CompositeDistance distance(
      c.experiments[0].metric.components, data.positions, data.displacements, out_x);
  std::vector<double> d(5);
  distance.Evaluate(data.displacements, d);
  EXPECT_EQ(d, (std::vector<double>{0, 0, 0, 1, 1}));
}

TEST(Config, MakeDistanceUsesTheSimulatorsDeclaredOutputs) {
  const CalibrationConfig c = LoadConfig(Fixture("paper_70cm_split.toml"));
  // The sensor declares its [model.output] positions as its outputs.
  EXPECT_EQ(c.simulator.kind, SimulatorKind::kSensor);
  EXPECT_EQ(c.simulator.outputs.coordinates, c.model.load_cases[0].output_positions);
  const MeasuredData data = LoadMeasuredData(c.experiments[0].data, c.directory);
  const std::vector<MeasuredProfile> profiles = ProfilesOf({data});
  const auto distance = MakeDistance(c, profiles);
  EXPECT_EQ(distance->output_size(), c.model.load_cases[0].output_positions.size());
  EXPECT_EQ(distance->components().size(), 5u);
  // A simulator whose output stops short of the data is a config error naming the file.
  CalibrationConfig short_model = c;
  short_model.experiments[0].output_coordinates = {0.0, 0.1, 0.2};
  try {
    MakeDistance(short_model, profiles);
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kConfig);
    EXPECT_EQ(e.file(), c.path);
    EXPECT_EQ(e.line(), 19);  // the preset key
    EXPECT_EQ(e.field(), "metric.component[0]");
  }
}

TEST(Config, ComponentsWithOwnAndInheritedSchedules) {
  const CalibrationConfig c = LoadConfig(Fixture("custom_components.toml"));
  ASSERT_EQ(c.experiments[0].metric.components.size(), 5u);
  EXPECT_FALSE(c.experiments[0].metric.preset.has_value());
  EXPECT_EQ(c.experiments[0].metric.components[1].name, "secondary peak");
  EXPECT_EQ(c.experiments[0].metric.components[3].type, MetricType::kRise);
  EXPECT_NEAR(c.experiments[0].metric.components[4].from, 0.78, kTol);
  ASSERT_EQ(c.smc.thresholds.size(), 3u);
  EXPECT_EQ(c.smc.thresholds[0].kind, ThresholdKind::kList);
  EXPECT_EQ(c.smc.thresholds[1].quantile, 0.4);  // inherited from [metric]
  EXPECT_EQ(c.smc.thresholds[2].quantile, 0.7);
  EXPECT_EQ(c.smc.thresholds[2].initial, 5.0);
  ASSERT_EQ(c.space.prior_one.size(), 36u);
  EXPECT_EQ(c.space.prior_one[35], 0.9);
  EXPECT_EQ(c.smc.tempering.kind, TemperingKind::kList);
  EXPECT_EQ(c.smc.tempering.form, TemperingForm::kMixture);
  EXPECT_TRUE(c.experiments[0].data.gaussian_extension.enabled);
}

TEST(Config, DefaultsComeFromTheOptionStructs) {
  const CalibrationConfig c = ParseConfig(kMinimal, "dir/minimal.toml");
  EXPECT_EQ(c.directory, "dir");
  const SmcOptions defaults;
  EXPECT_EQ(c.smc.num_waves, defaults.num_waves);
  EXPECT_EQ(c.smc.accepted_per_wave, defaults.accepted_per_wave);
  EXPECT_EQ(c.smc.estimator, defaults.estimator);
  EXPECT_EQ(c.smc.seed, defaults.seed);
  EXPECT_EQ(c.smc.max_simulations, defaults.max_simulations);
  EXPECT_EQ(c.smc.min_acceptance_rate, defaults.min_acceptance_rate);
  EXPECT_EQ(c.smc.acceptance_floor_after, defaults.acceptance_floor_after);
  EXPECT_EQ(c.smc.max_failure_fraction, defaults.max_failure_fraction);
  EXPECT_EQ(c.smc.failure_fraction_after, defaults.failure_fraction_after);
  EXPECT_EQ(c.experiments[0].data.position_column, "position");
  EXPECT_EQ(c.experiments[0].data.position_unit, LengthUnit::kCentimetre);
  EXPECT_EQ(c.output.figure_formats, (std::vector<std::string>{"png"}));
  EXPECT_EQ(c.space.dimension, 36);
  EXPECT_TRUE(c.space.tied.empty());
}

TEST(Config, ModelSectionFillsSensorOptions) {
  const CalibrationConfig c = LoadConfig(Fixture("paper_45cm_least_squares.toml"));
  const plate::SensorOptions& m = c.model;
  EXPECT_EQ(m.length, 0.90);
  EXPECT_EQ(m.width, 0.04);
  ASSERT_EQ(m.layers.size(), 3u);
  EXPECT_EQ(m.layers[1].youngs_modulus, 5.0e6);
  EXPECT_EQ(m.layers[1].loss_factor, 0.15);
  EXPECT_EQ(m.clamps_per_edge, 18);
  EXPECT_EQ(m.fixed_support, plate::Support::kClamped);
  EXPECT_EQ(m.short_edge_end, plate::Support::kFree);
  EXPECT_EQ(m.load_cases[0].load_x, 0.45);
  EXPECT_EQ(m.load_cases[0].load_force, 0.042);
  EXPECT_EQ(m.frequency_hz, 5.0);
  ASSERT_EQ(m.load_cases[0].output_positions.size(), 91u);
  EXPECT_NEAR(m.load_cases[0].output_positions.back(), 0.90, kTol);
  EXPECT_TRUE(m.normalise);
  std::string why;
  EXPECT_TRUE(m.IsValid(&why)) << why;
}

TEST(Config, ModelKeysAreOptionalAndDefaultsComeFromSensorOptions) {
  const CalibrationConfig c = ParseConfig(kMinimal +
                                              "[model.clamps]\nper_edge = 9\n"
                                              "[model.load]\ntype = \"point\"\nx = 0.3\n"
                                              "[data.gaussian_extension]\n",
                                          "inline.toml");
  const plate::SensorOptions defaults;
  EXPECT_EQ(c.model.length, defaults.length);
  EXPECT_EQ(c.model.layers.size(), defaults.layers.size());
  EXPECT_EQ(c.model.load_cases[0].output_positions, defaults.load_cases[0].output_positions);
  EXPECT_EQ(c.model.clamps_per_edge, 9);
  EXPECT_EQ(c.space.dimension, 18);                         // 2 x 9 clamps
  EXPECT_EQ(c.model.load_cases[0].load_patch_length, 0.0);  // point load
  EXPECT_EQ(c.model.load_cases[0].load_x, 0.3);
  // The Gaussian extension is centred at the model's load unless told otherwise.
  EXPECT_EQ(c.experiments[0].data.gaussian_extension.impact_position, 0.3);
}

TEST(Config, ModelTheorySelectsThePlateTheory) {
  EXPECT_EQ(ParseConfig(kMinimal, "inline.toml").model.theory, plate::PlateTheory::kRzt);
  EXPECT_EQ(ParseConfig(kMinimal + "[model]\ntheory = \"kirchhoff\"\n", "inline.toml").model.theory,
            plate::PlateTheory::kKirchhoff);
  EXPECT_EQ(ParseConfig(kMinimal + "[model]\ntheory = \"fsdt\"\n", "inline.toml").model.theory,
            plate::PlateTheory::kFsdt);
  EXPECT_EQ(ParseConfig(kMinimal + "[model]\ntheory = \"rzt\"\n", "inline.toml").model.theory,
            plate::PlateTheory::kRzt);
  const Error e = ConfigError(kMinimal + "[model]\ntheory = \"mindlin\"\n");
  ExpectLocated(e, "inline.toml", 6, "model.theory");
  EXPECT_NE(std::string(e.what()).find("\"kirchhoff\", \"fsdt\", \"rzt\""), std::string::npos)
      << e.what();
}

TEST(Config, MeshElementOrderIsForTheShearTheories) {
  // Unset, the theory's own: 2 for the default RZT, 1 for Kirchhoff; the width's default follows
  // (6 node intervals across).
  const plate::SensorOptions defaults = ParseConfig(kMinimal, "inline.toml").model;
  EXPECT_FALSE(defaults.element_order.has_value());
  EXPECT_EQ(defaults.ElementOrder(), 2);
  EXPECT_EQ(defaults.ElementsAcrossWidth(), 3);
  const std::string kirchhoff = kMinimal + "[model]\ntheory = \"kirchhoff\"\n[model.mesh]\n";
  const plate::SensorOptions k = ParseConfig(kirchhoff, "inline.toml").model;
  EXPECT_EQ(k.ElementOrder(), 1);
  EXPECT_EQ(k.ElementsAcrossWidth(), 6);
  const std::string rzt = kMinimal + "[model]\ntheory = \"rzt\"\n[model.mesh]\n";
  EXPECT_EQ(ParseConfig(rzt + "element_order = 1\n", "inline.toml").model.ElementOrder(), 1);
  EXPECT_EQ(ParseConfig(rzt + "element_order = 1\n", "inline.toml").model.ElementsAcrossWidth(), 6);
  ExpectLocated(
      ConfigError(rzt + "element_order = 3\n"), "inline.toml", 8, "model.mesh.element_order");
  const Error e = ConfigError(kirchhoff + "element_order = 2\n");
  ExpectLocated(e, "inline.toml", 8, "model.mesh.element_order");
  EXPECT_NE(std::string(e.what()).find("kirchhoff"), std::string::npos) << e.what();
}

TEST(Config, ModelErrorsNameTheKey) {
  ExpectLocated(ConfigError(kMinimal + "[model]\nlength = -1\n"), "inline.toml", 6, "model.length");
  ExpectLocated(ConfigError(kMinimal + "[model.short_edges]\nstart = \"pinned\"\n"),
                "inline.toml",
                6,
                "model.short_edges.start");
  ExpectLocated(ConfigError(kMinimal + "[[model.layer]]\nthickness = 1e-3\ndensity = 1000\n"),
                "inline.toml",
                5,
                "model.layer[0].young_modulus");
  ExpectLocated(ConfigError(kMinimal + "[model.clamps]\nsection_length = 0.07\n"),
                "inline.toml",
                6,
                "model.clamps.section_length");
  // The load beyond the plate is caught by SensorOptions::IsValid and reported at its key.
  ExpectLocated(
      ConfigError(kMinimal + "[model.load]\nx = 1.2\n"), "inline.toml", 6, "model.load.x");
  // The clamp count bounds the tie numbers.
  ExpectLocated(ConfigError(kMinimal + "[model.clamps]\nper_edge = 2\n[sampler]\ntie = [[1, 5]]\n"),
                "inline.toml",
                8,
                "sampler.tie[0][1]");
}

TEST(Config, ProposalAndContinuousParameters) {
  const auto c = ParseConfig(kMinimal +
                                 "[proposal]\nkind = \"logistic\"\nmax_predecessors = 4\n"
                                 "continuous = \"olcm\"\n"
                                 "[parameters.stiffness_scale]\nprior = \"uniform\"\nlow = 0.5\n"
                                 "high = 2\n"
                                 "[parameters.foundation_stiffness]\nprior = \"lognormal\"\n"
                                 "mean = 10.8\nsd = 0.5\n",
                             "inline.toml");
  EXPECT_EQ(c.smc.proposal.binary, BinaryKernelKind::kLogistic);
  EXPECT_EQ(c.smc.proposal.logistic.max_predecessors, 4);
  EXPECT_EQ(c.smc.proposal.continuous, ContinuousKernelKind::kOlcm);
  ASSERT_EQ(c.reals.size(), 2u);
  EXPECT_EQ(c.reals[0].name, "foundation_stiffness");  // by name
  EXPECT_EQ(c.reals[0].prior.kind, PriorKind::kLogNormal);
  EXPECT_EQ(c.reals[1].name, "stiffness_scale");
  EXPECT_EQ(c.reals[1].prior.high, 2.0);
}

// kind = "ancestor" is the joint kernel: it takes scale and refuses another continuous kernel.
TEST(Config, AncestorProposal) {
  const auto c =
      ParseConfig(kMinimal + "[proposal]\nkind = \"ancestor\"\nscale = 1.5\n", "inline.toml");
  EXPECT_EQ(c.smc.proposal.binary, BinaryKernelKind::kAncestor);
  EXPECT_EQ(c.smc.proposal.scale, 1.5);
  ExpectLocated(ConfigError(kMinimal + "[proposal]\nkind = \"ancestor\"\ncontinuous = \"olcm\"\n"),
                "inline.toml",
                7,
                "proposal.continuous");
}

// A mixed run builds the continuous-unknowns precompute too: at a limit between the clamp-only
// estimate and that plus the continuous one, the clamp-only run is accepted and the mixed one
// refused, with the estimate.
TEST(Config, AMixedRunCountsTheContinuousPrecomputeInItsMemory) {
  plate::SensorOptions model;
  model.elements_across_width = 12;
  const double clamp_only = model.EstimatedMemoryBytes();
  const double continuous = model.EstimatedContinuousMemoryBytes(false);
  const std::string limit = std::to_string((clamp_only + 0.5 * continuous) / 1e9);
  const std::string clamps = "memory_limit_gb = " + limit + "\n" + kMinimal +
                             "[model.mesh]\nelements_across_width = 12\n"
                             "[sampler]\nbatch_size = 8\nestimator = \"importance\"\n";
  EXPECT_NO_THROW(ParseConfig(clamps, "inline.toml"));
  const Error e = ConfigError(clamps +
                              "[parameters.foundation_stiffness]\nprior = \"uniform\"\n"
                              "low = 1e4\nhigh = 1e5\n");
  EXPECT_EQ(e.kind(), ErrorKind::kConfig);
  EXPECT_NE(std::string(e.what()).find("the run would need about"), std::string::npos) << e.what();
  EXPECT_NE(std::string(e.what()).find("raise memory_limit_gb"), std::string::npos) << e.what();
}

// [design]'s sizes are refused when the config is read, at their key, against memory_limit_gb
// (the reviewers' scan_spacing = 0.00000025 built 5.6 GB of positions before a refusal naming no
// key, and particles = 3e6 ended in bad_alloc, exit 70).
TEST(Config, DesignSizesAreRefusedAtTheirKey) {
  const std::string design = kMinimal + "[design]\nload_x = [45]\n";
  EXPECT_NO_THROW(ParseConfig(design, "inline.toml"));
  const Error spacing = ConfigError(design + "scan_spacing = 0.00000025\n");
  ExpectLocated(spacing, "inline.toml", 7, "design.scan_spacing");
  EXPECT_NE(std::string(spacing.what()).find("scan points"), std::string::npos) << spacing.what();
  const Error particles = ConfigError(design + "particles = 3000000\n");
  ExpectLocated(particles, "inline.toml", 7, "design.particles");
  EXPECT_NE(std::string(particles.what()).find("the design would need about"), std::string::npos)
      << particles.what();
  ExpectLocated(ConfigError(design + "truths = 1000000\n"), "inline.toml", 7, "design.truths");
  // The estimate holds a larger memory limit.
  EXPECT_NO_THROW(
      ParseConfig("memory_limit_gb = 1000\n" + design + "particles = 3000000\n", "inline.toml"));
}

// A load of amplitude 0 deflects nothing: a design over it would rank every candidate at zero
// gain. Refused at the amplitude's key.
TEST(Config, ADesignRefusesALoadOfAmplitudeZero) {
  const std::string load = "[model.load]\namplitude = 0\n";
  ExpectLocated(ConfigError(load + kMinimal + "[design]\nload_x = [45]\n"),
                "inline.toml",
                2,
                "model.load.amplitude");
}

TEST(Config, ProposalAndParameterErrorsNameTheKey) {
  ExpectLocated(ConfigError(kMinimal + "[proposal]\nkind = \"pairwise\"\n"),
                "inline.toml",
                6,
                "proposal.kind");
  ExpectLocated(ConfigError(kMinimal + "[proposal]\nkind = \"logistic\"\nmin_correlation = 1.5\n"),
                "inline.toml",
                7,
                "proposal.min_correlation");
  ExpectLocated(ConfigError(kMinimal + "[proposal]\nridge = 0.1\n"),  // independent kernel
                "inline.toml",
                6,
                "proposal.ridge");
  ExpectLocated(ConfigError(kMinimal + "[parameters.damping]\nprior = \"uniform\"\nlow = 0\n"
                                       "high = 1\n"),
                "inline.toml",
                5,
                "parameters.damping");
  ExpectLocated(ConfigError(kMinimal + "[parameters.loss_factor]\nprior = \"normal\"\nmean = 0.1\n"
                                       "sd = -1\n"),
                "inline.toml",
                8,
                "parameters.loss_factor.sd");
  ExpectLocated(ConfigError(kMinimal + "[parameters.loss_factor]\nprior = \"uniform\"\nlow = 2\n"
                                       "high = 1\n"),
                "inline.toml",
                8,
                "parameters.loss_factor.high");
  // A prior reaching outside the physical range: a negative foundation stiffness.
  ExpectLocated(ConfigError(kMinimal + "[parameters.foundation_stiffness]\nprior = \"uniform\"\n"
                                       "low = -5\nhigh = 1e5\n"),
                "inline.toml",
                7,
                "parameters.foundation_stiffness.low");
  ExpectLocated(ConfigError(kMinimal + "[parameters.foundation_stiffness]\nprior = \"normal\"\n"
                                       "mean = 5e4\nsd = 1e4\n"),
                "inline.toml",
                6,
                "parameters.foundation_stiffness.prior");
  ExpectLocated(ConfigError(kMinimal + "[parameters.stiffness_scale]\nprior = \"uniform\"\n"
                                       "low = 0.5\nhigh = 2\nmean = 1\n"),
                "inline.toml",
                9,
                "parameters.stiffness_scale.mean");
  // Continuous parameters need importance weights.
  ExpectLocated(ConfigError(kMinimal + "[sampler]\nestimator = \"paper\"\n"
                                       "[parameters.stiffness_scale]\nprior = \"uniform\"\n"
                                       "low = 0.5\nhigh = 2\n"),
                "inline.toml",
                5,
                "sampler.estimator");
}

TEST(Config, DocumentedExampleIsTheTestedFixture) {
  // docs/config.md's complete example must stay identical to the fixture parsed above.
  std::ifstream doc(std::string(COMBABC_SOURCE_DIR) + "/docs/config.md");
  std::ifstream fixture(Fixture("paper_45cm_least_squares.toml"));
  ASSERT_TRUE(doc && fixture);
  std::stringstream doc_text, fixture_text;
  doc_text << doc.rdbuf();
  fixture_text << fixture.rdbuf();
  const std::string text = doc_text.str();
  const std::size_t begin = text.find("```toml\n", text.find("## Complete example"));
  ASSERT_NE(begin, std::string::npos);
  const std::size_t end = text.find("```", begin + 8);
  EXPECT_EQ(text.substr(begin + 8, end - begin - 8), fixture_text.str());
}

// ------------------------------------------------------------------------------ bad fixtures

TEST(Config, MalformedTomlNamesFileAndLine) {
  const std::string path = Fixture("bad_malformed.toml");
  const Error e = LoadError(path);
  EXPECT_EQ(e.kind(), ErrorKind::kConfig);
  EXPECT_EQ(e.line(), 5) << e.what();
  EXPECT_EQ(std::string(e.what()).rfind(path + ":5: malformed TOML", 0), 0u) << e.what();
}

TEST(Config, UnknownNestedKeyNamesFileLineAndDottedKey) {
  const std::string path = Fixture("bad_unknown_key.toml");
  const Error e = LoadError(path);
  ExpectLocated(e, path, 10, "sampler.tempering.phi_0");
  EXPECT_NE(std::string(e.what()).find("unknown key; expected one of: kind, form, phi0, values"),
            std::string::npos)
      << e.what();
}

TEST(Config, WrongTypeNamesFileLineAndKey) {
  const std::string path = Fixture("bad_wrong_type.toml");
  const Error e = LoadError(path);
  ExpectLocated(e, path, 8, "sampler.waves");
  EXPECT_NE(std::string(e.what()).find("expected an integer, got a string"), std::string::npos);
}

TEST(Config, OutOfRangeNamesFileLineAndKey) {
  const std::string path = Fixture("bad_out_of_range.toml");
  const Error e = LoadError(path);
  ExpectLocated(e, path, 9, "sampler.min_acceptance_rate");
  EXPECT_NE(std::string(e.what()).find("must be in [0, 1]"), std::string::npos) << e.what();
}

TEST(Config, MissingFileIsNoInput) {
  const Error e = [] {
    try {
      LoadConfig(Fixture("no_such_config.toml"));
    } catch (const Error& err) {
      return err;
    }
    return Error(ErrorKind::kSoftware, "none");
  }();
  EXPECT_EQ(e.kind(), ErrorKind::kNoInput);
  EXPECT_NE(std::string(e.what()).find("no_such_config.toml"), std::string::npos);
}

// ------------------------------------------------------------------------------ inline cases

TEST(Config, UnknownKeysAnywhere) {
  ExpectLocated(ConfigError("colour = 1\n" + kMinimal), "inline.toml", 1, "colour");
  ExpectLocated(
      ConfigError(kMinimal + "[output]\nformat = \"png\"\n"), "inline.toml", 6, "output.format");
  ExpectLocated(ConfigError("[data]\ncsv = \"p.csv\"\n[data.gaussian_extension]\n"
                            "impact_position = 70\nfit = 3\n[metric]\npreset = \"area\"\n"),
                "inline.toml",
                5,
                "data.gaussian_extension.fit");
  ExpectLocated(ConfigError("[data]\ncsv = \"p.csv\"\n[metric]\n"
                            "[[metric.component]]\ntype = \"area\"\nwindow = [48, 80]\n"
                            "[[metric.component]]\ntype = \"area\"\nwindow = [48, 80]\n"
                            "windw = [1, 2]\n"),
                "inline.toml",
                10,
                "metric.component[1].windw");
}

TEST(Config, WrongTypes) {
  ExpectLocated(ConfigError("[data]\ncsv = \"p.csv\"\nnormalise = \"yes\"\n[metric]\n"
                            "preset = \"area\"\n"),
                "inline.toml",
                3,
                "data.normalise");
  ExpectLocated(
      ConfigError(kMinimal + "[sampler]\nthreads = 1.5\n"), "inline.toml", 6, "sampler.threads");
  ExpectLocated(ConfigError(kMinimal + "[sampler]\ntie = [[1, \"two\"]]\n"),
                "inline.toml",
                6,
                "sampler.tie[0][1]");
  ExpectLocated(
      ConfigError("[data]\ncsv = 3\n[metric]\npreset = \"area\"\n"), "inline.toml", 2, "data.csv");
  ExpectLocated(ConfigError("[data]\ncsv = \"p.csv\"\nwindow = [48, \"80\"]\n[metric]\n"
                            "preset = \"area\"\n"),
                "inline.toml",
                3,
                "data.window[1]");
}

TEST(Config, StoppingKeys) {
  const CalibrationConfig c = ParseConfig(kMinimal +
                                              "[sampler]\nmax_simulations = 0\n"
                                              "min_acceptance_rate = 0.001\n"
                                              "acceptance_floor_after = 5000\n"
                                              "max_failure_fraction = 0.25\n"
                                              "failure_fraction_after = 40\n",
                                          "inline.toml");
  EXPECT_EQ(c.smc.max_simulations, 0);
  EXPECT_EQ(c.smc.min_acceptance_rate, 0.001);
  EXPECT_EQ(c.smc.acceptance_floor_after, 5000);
  EXPECT_EQ(c.smc.max_failure_fraction, 0.25);
  EXPECT_EQ(c.smc.failure_fraction_after, 40);
  ExpectLocated(ConfigError(kMinimal + "[sampler]\nmax_failure_fraction = 1.5\n"),
                "inline.toml",
                6,
                "sampler.max_failure_fraction");
  ExpectLocated(ConfigError(kMinimal + "[sampler]\nacceptance_floor_after = 0\n"),
                "inline.toml",
                6,
                "sampler.acceptance_floor_after");
}

TEST(Config, OutOfRangeAndInconsistentValues) {
  ExpectLocated(
      ConfigError(kMinimal + "[sampler]\nwaves = 0\n"), "inline.toml", 6, "sampler.waves");
  ExpectLocated(ConfigError(kMinimal + "[sampler]\nseed = -1\n"), "inline.toml", 6, "sampler.seed");
  ExpectLocated(
      ConfigError(kMinimal + "[sampler]\nprior = 1.2\n"), "inline.toml", 6, "sampler.prior");
  ExpectLocated(ConfigError(kMinimal + "[sampler]\ntie = [[1, 37]]\n"),
                "inline.toml",
                6,
                "sampler.tie[0][1]");
  ExpectLocated(ConfigError(kMinimal + "[sampler]\ntie = [[1, 2], [3, 1]]\n"),
                "inline.toml",
                6,
                "sampler.tie[1][1]");
  ExpectLocated(ConfigError(kMinimal + "[sampler]\nestimator = \"weighted\"\n"),
                "inline.toml",
                6,
                "sampler.estimator");
  ExpectLocated(ConfigError("[data]\ncsv = \"p.csv\"\nwindow = [80, 48]\n[metric]\n"
                            "preset = \"area\"\n"),
                "inline.toml",
                3,
                "data.window");
  ExpectLocated(ConfigError("[data]\ncsv = \"p.csv\"\nposition_unit = \"inch\"\n[metric]\n"
                            "preset = \"area\"\n"),
                "inline.toml",
                3,
                "data.position_unit");
  // A list threshold must have one value per wave (checked by ThresholdSchedule::IsValid and
  // reported at the key that set it).
  ExpectLocated(ConfigError("[data]\ncsv = \"p.csv\"\n[metric]\npreset = \"area\"\n"
                            "threshold = [0.5, 0.2]\n"),
                "inline.toml",
                5,
                "metric.threshold");
  // Increasing thresholds violate Eq. 1.
  ExpectLocated(ConfigError("[data]\ncsv = \"p.csv\"\n[metric]\n[[metric.component]]\n"
                            "type = \"least_squares\"\nwindow = [48, 80]\n"
                            "threshold = [1, 2, 0.5, 0.2, 0.1]\n"),
                "inline.toml",
                7,
                "metric.component[0].threshold");
  // Tempering list with the wrong length: SmcOptions::IsValid, attributed to the key.
  ExpectLocated(ConfigError(kMinimal + "[sampler.tempering]\nkind = \"list\"\nvalues = [0.5]\n"),
                "inline.toml",
                7,
                "sampler.tempering.values");
}

TEST(Config, MetricShapeErrors) {
  ExpectLocated(ConfigError("[data]\ncsv = \"p.csv\"\n[metric]\npreset = \"eq5\"\n"),
                "inline.toml",
                4,
                "metric.preset");
  ExpectLocated(ConfigError("[data]\ncsv = \"p.csv\"\n[metric]\npreset = \"area\"\n"
                            "[[metric.component]]\ntype = \"area\"\nwindow = [1, 2]\n"),
                "inline.toml",
                4,
                "metric.preset");
  ExpectLocated(ConfigError("[data]\ncsv = \"p.csv\"\n[metric]\n[[metric.component]]\n"
                            "type = \"rise\"\nwindow = [76, 78]\nthreshold = [1, 1, 1, 1, 1]\n"),
                "inline.toml",
                7,
                "metric.component[0].threshold");
  ExpectLocated(ConfigError("[data]\ncsv = \"p.csv\"\n[metric]\n[[metric.component]]\n"
                            "type = \"peak\"\nwindow = [76, 78]\n"),
                "inline.toml",
                5,
                "metric.component[0].type");
  ExpectLocated(ConfigError("[data]\ncsv = \"p.csv\"\n[metric]\n[[metric.component]]\n"
                            "type = \"area\"\n"),
                "inline.toml",
                4,
                "metric.component[0].window");
  const Error e = ConfigError("[data]\ncsv = \"p.csv\"\n");
  EXPECT_EQ(e.field(), "metric");
}

// Two components whose names differ only in case or punctuation would give export columns of one
// name (d_fit_a twice): refused at the second, naming the first, within a metric and across
// experiments ("a_b" / "c" and "a" / "b_c" are both a_b_c).
TEST(Config, ComponentsThatWouldShareExportColumnsAreRefused) {
  const std::string head = "[data]\ncsv = \"p.csv\"\n[metric]\n";
  auto component = [](const std::string& window, const std::string& name) {
    return "[[metric.component]]\ntype = \"area\"\nwindow = " + window + "\n" +
           (name.empty() ? "" : "name = \"" + name + "\"\n");
  };
  Error e = ConfigError(head + component("[1, 2]", "fit-a") + component("[3, 4]", "Fit_A"));
  ExpectLocated(e, "inline.toml", 8, "metric.component[1]");
  EXPECT_NE(std::string(e.what()).find("component 'Fit_A' would share the export columns "
                                       "(d_fit_a) of component 'fit-a' at line 4"),
            std::string::npos)
      << e.what();
  e = ConfigError(head + component("[1, 2]", "") + component("[1, 2]", ""));
  ExpectLocated(e, "inline.toml", 7, "metric.component[1]");
  EXPECT_NE(std::string(e.what()).find("give one a name"), std::string::npos) << e.what();
  EXPECT_NO_THROW(
      ParseConfig(head + component("[1, 2]", "fit-a") + component("[3, 4]", "fit_b"), "in.toml"));
  auto experiment = [&](const std::string& name, const std::string& component_name) {
    std::string text = "[[experiment]]\nname = \"" + name +
                       "\"\n[experiment.data]\ncsv = \"p.csv\"\n[experiment.metric]\n" +
                       component("[1, 2]", component_name);
    return text.replace(text.find("[[metric"), 8, "[[experiment.metric");
  };
  e = ConfigError(experiment("a_b", "c") + experiment("a", "b_c"));
  ExpectLocated(e, "inline.toml", 15, "experiment[1].metric.component[0]");
  EXPECT_NE(std::string(e.what()).find("component 'a/b_c' would share the export columns "
                                       "(d_a_b_c) of component 'a_b/c' at line 6"),
            std::string::npos)
      << e.what();
}

}  // namespace
}  // namespace combabc

namespace combabc {
namespace {

const std::string kGaussianBase =
    "[data]\n"
    "csv = \"p.csv\"\n"
    "[metric]\n"
    "[[metric.component]]\n"
    "type = \"least_squares\"\n"
    "window = [0.5, 0.8]\n"
    "noise = \"gaussian\"\n";  // line 7

TEST(Config, GaussianNoiseModelKeys) {
  const auto c = ParseConfig(kGaussianBase + "sigma_noise = 0.02\nsigma_model = 0.01\n", "x.toml");
  ASSERT_EQ(c.experiments[0].metric.components.size(), 1u);
  const auto& m = c.experiments[0].metric.components[0];
  EXPECT_EQ(m.noise.model, NoiseModel::kGaussian);
  EXPECT_EQ(m.noise.sigma_noise, 0.02);
  EXPECT_EQ(m.noise.sigma_model, 0.01);
  EXPECT_EQ(KindOf(m), ComponentKind::kNegLogLikelihood);
  EXPECT_EQ(c.smc.thresholds.at(0).target, 1.0);  // temperatures end at 1
  const auto estimated = ParseConfig(kGaussianBase + "sigma_noise = \"estimate\"\n", "x.toml");
  EXPECT_FALSE(estimated.experiments[0].metric.components[0].noise.sigma_noise.has_value());
  // [metric]-level noise applies to a preset's least_squares components.
  const auto preset = ParseConfig(
      "[data]\ncsv = \"p.csv\"\n[metric]\npreset = \"split_least_squares\"\nnoise = "
      "\"gaussian\"\nsigma_noise = 0.01\n",
      "x.toml");
  int likelihoods = 0;
  for (const auto& m2 : preset.experiments[0].metric.components) {
    likelihoods += KindOf(m2) == ComponentKind::kNegLogLikelihood;
  }
  EXPECT_EQ(likelihoods, 3);
  EXPECT_EQ(preset.smc.thresholds.size(), 3u);
}

// noise = "folded_normal" (amplitude data, docs/algorithm.md): the same keys as "gaussian", a
// likelihood component whose schedule holds temperatures; a misspelt model is refused at its key.
TEST(Config, FoldedNormalNoiseModelKeys) {
  std::string base = kGaussianBase;
  base.replace(base.find("\"gaussian\""), 10, "\"folded_normal\"");
  const auto c = ParseConfig(base + "sigma_noise = 0.02\nsigma_model = 0.01\n", "x.toml");
  const auto& m = c.experiments[0].metric.components[0];
  EXPECT_EQ(m.noise.model, NoiseModel::kFoldedNormal);
  EXPECT_EQ(m.noise.sigma_noise, 0.02);
  EXPECT_EQ(m.noise.sigma_model, 0.01);
  EXPECT_EQ(KindOf(m), ComponentKind::kNegLogLikelihood);
  EXPECT_EQ(c.smc.thresholds.at(0).target, 1.0);
  EXPECT_FALSE(ParseConfig(base, "x.toml").experiments[0].metric.components[0].noise.sigma_noise);
  ExpectLocated(
      ConfigError(base + "target = 0.5\n"), "inline.toml", 8, "metric.component[0].target");
  ExpectLocated(
      ConfigError(base + "sigma_noise = 0\n"), "inline.toml", 8, "metric.component[0].sigma_noise");
  std::string misspelt = kGaussianBase;
  misspelt.replace(misspelt.find("\"gaussian\""), 10, "\"folded\"");
  const Error e = ConfigError(misspelt);
  ExpectLocated(e, "inline.toml", 7, "metric.component[0].noise");
  EXPECT_NE(std::string(e.what()).find("folded_normal"), std::string::npos) << e.what();
  // In an [[experiment]] table, and at [metric] level for a preset.
  std::string experiment = base;
  experiment.replace(
      experiment.find("[data]"), 6, "[[experiment]]\nname = \"a\"\n[experiment.data]");
  experiment.replace(experiment.find("[metric]"), 8, "[experiment.metric]");
  experiment.replace(
      experiment.find("[[metric.component]]"), 20, "[[experiment.metric.component]]");
  experiment.replace(experiment.find("folded_normal"), 13, "folded_norm");
  ExpectLocated(
      ConfigError(experiment), "inline.toml", 9, "experiment[0].metric.component[0].noise");
  ExpectLocated(ConfigError("[data]\ncsv = \"p.csv\"\n[metric]\npreset = \"area\"\nnoise = "
                            "\"folded_normal\"\n"),
                "inline.toml",
                5,
                "metric.noise");
  ExpectLocated(
      ConfigError("[data]\ncsv = \"p.csv\"\n[metric]\npreset = \"area\"\nsigma_noise = 0.1\n"),
      "inline.toml",
      5,
      "metric.sigma_noise");
}

TEST(Config, GaussianNoiseModelErrorsNameLineAndKey) {
  ExpectLocated(ConfigError(kGaussianBase + "sigma_noise = -1\n"),
                "inline.toml",
                8,
                "metric.component[0].sigma_noise");
  ExpectLocated(ConfigError(kGaussianBase + "sigma_noise = inf\n"),
                "inline.toml",
                8,
                "metric.component[0].sigma_noise");
  ExpectLocated(ConfigError(kGaussianBase + "sigma_noise = \"guess\"\n"),
                "inline.toml",
                8,
                "metric.component[0].sigma_noise");
  ExpectLocated(ConfigError(kGaussianBase + "sigma_model = -0.1\n"),
                "inline.toml",
                8,
                "metric.component[0].sigma_model");
  ExpectLocated(ConfigError(kGaussianBase + "target = 0.5\n"),
                "inline.toml",
                8,
                "metric.component[0].target");
  ExpectLocated(ConfigError(kGaussianBase + "sigma_nois = 0.1\n"),
                "inline.toml",
                8,
                "metric.component[0].sigma_nois");
  ExpectLocated(
      ConfigError("[data]\ncsv = \"p.csv\"\n[metric]\npreset = \"area\"\nnoise = \"gaussian\"\n"),
      "inline.toml",
      5,
      "metric.noise");
}

}  // namespace
}  // namespace combabc
