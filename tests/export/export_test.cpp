// ExportRun: the files, their headers and row counts, and the all-or-nothing directory.
#include "combabc/export/export.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "combabc/core/error.hpp"
#include "combabc/export/answer.hpp"
#include "combabc/samplers/monte_carlo_error.hpp"
#include "export/json_text.hpp"
#include "history/fake_run.hpp"
#include "support/test_support.hpp"

namespace combabc {
namespace {

namespace fs = std::filesystem;
using testing::TempFolder;

std::vector<std::string> Lines(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::size_t Fields(const std::string& line) {
  return static_cast<std::size_t>(std::count(line.begin(), line.end(), ',')) + 1;
}

// Field n (from 0) of a CSV line without quoted commas.
std::string Field(const std::string& line, int n) {
  std::stringstream in(line);
  std::string value;
  for (int i = 0; i <= n; ++i) std::getline(in, value, ',');
  return value;
}

class ExportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    options_.waves = 2;
    options_.per_wave = 5;
    options_.dimension = 6;
    options_.points = 7;
  }

  std::string WriteRun(bool outputs, const std::string& name = "RUN.db") {
    options_.outputs = outputs;
    std::string path = (dir_ / name).string();
    HistoryStore store = HistoryStore::Create(path, testing::MakeFakeMetadata(options_));
    const RunHistory history = testing::MakeFakeHistory(options_);
    for (const WaveRecord& wave : history.waves) testing::RecordWave(store, wave, 4);
    store.Finish(history.summary);
    return path;
  }

  const TempFolder folder_{"export-test"};
  const fs::path dir_ = folder_.path();
  testing::FakeRunOptions options_;
};

TEST_F(ExportTest, WritesEveryTableWithHeaders) {
  const std::string db = WriteRun(/*outputs=*/true);
  const fs::path out = dir_ / "export";
  ExportRun(db, out.string());

  const auto waves = Lines(out / "waves.csv");
  ASSERT_EQ(waves.size(), 3u);
  EXPECT_EQ(waves[0],
            "wave,eps_least_squares,phi,candidates,accepted,acceptance_rate,ess,distinct,"
            "wall_seconds,complete,ess_bits");
  EXPECT_EQ(Fields(waves[1]), Fields(waves[0]));

  const auto marginals = Lines(out / "marginals.csv");
  EXPECT_EQ(marginals[0], "wave,bit,name,prob_paper,prob_importance");
  EXPECT_EQ(marginals.size(), 1u + 2u * 6u);
  EXPECT_EQ(marginals[1].rfind("1,1,clamp 1,", 0), 0u) << "waves and bits from 1: " << marginals[1];

  const auto pairs = Lines(out / "pair_correlations.csv");
  EXPECT_EQ(pairs[0], "wave,bit_i,name_i,bit_j,name_j,correlation");
  EXPECT_EQ(pairs.size(), 1u + 2u * 15u);  // 6 bits: 15 pairs a wave

  const auto particles = Lines(out / "particles.csv");
  EXPECT_EQ(particles[0],
            "wave,index,bits,clamp 1,clamp 2,clamp 3,clamp 4,clamp 5,clamp 6,log_weight,weight,"
            "d_least_squares,d_secondary_peak");
  EXPECT_EQ(particles.size(), 1u + 2u * 5u);
  EXPECT_EQ(Fields(particles[1]), Fields(particles[0]));
  EXPECT_EQ(particles[1].rfind("1,", 0), 0u) << particles[1];
  EXPECT_EQ(particles.back().rfind("2,", 0), 0u) << particles.back();

  const auto curves = Lines(out / "curves.csv");
  EXPECT_EQ(curves[0], "wave,index,y_0,y_1,y_2,y_3,y_4,y_5,y_6");
  EXPECT_EQ(curves.size(), 1u + 2u * 5u);
  EXPECT_EQ(curves[1].rfind("1,", 0), 0u) << curves[1];
  const auto positions = Lines(out / "positions.csv");
  EXPECT_EQ(positions[0], "column,position_m");
  EXPECT_EQ(positions[1], "y_0,0");
  EXPECT_EQ(positions.size(), 8u);
  const auto measured = Lines(out / "measured.csv");
  EXPECT_EQ(measured[0], "position_m,value");
  // One unnamed experiment holding everything: listed, but no experiment column anywhere.
  const auto experiments = Lines(out / "experiments.csv");
  ASSERT_EQ(experiments.size(), 2u);
  EXPECT_EQ(experiments[0],
            "index,name,description,outputs,measured,components,first_output,first_measured");
  EXPECT_EQ(experiments[1], "0,,,7," + std::to_string(measured.size() - 1) + ",2,0,0");

  std::ifstream json(out / "summary.json");
  std::stringstream text;
  text << json.rdbuf();
  EXPECT_NE(text.str().find("\"termination\": \"max_waves\""), std::string::npos);
  EXPECT_NE(text.str().find("\"marginals_importance\""), std::string::npos);
  EXPECT_NE(text.str().find("{\"wave\": 1,"), std::string::npos) << "waves from 1";
  EXPECT_EQ(text.str().find("{\"wave\": 0,"), std::string::npos);
  EXPECT_EQ(text.str().find("multi_fidelity"), std::string::npos) << "a single-fidelity run";
  EXPECT_EQ(text.str().find("expensive"), std::string::npos);
  // The answer (issue 22): the numbers the terminal shows, from the same function of the history.
  const HistoryStore store = HistoryStore::Open(db, true);
  const std::string answer = AnswerJson(SummariseAnswer(store.LoadMetadata(), store.LoadHistory()));
  // No strip: the synthetic run's config is not the sensor's (issue 34).
  EXPECT_NE(text.str().find("\"answer\": " + answer + ",\n  \"strip\": null,\n  \"checks\": "),
            std::string::npos)
      << text.str();
  EXPECT_NE(answer.find("\"wave\": 2,\n    \"complete\": true"), std::string::npos) << answer;
  EXPECT_NE(answer.find("\"verdict_level\": 0.95"), std::string::npos) << answer;
  EXPECT_NE(answer.find("{\"number\": 1, \"name\": \"clamp 1\", \"position\": null"),
            std::string::npos)
      << answer;
  EXPECT_NE(answer.find("\"per_wave\": [\n      {\"wave\": 1, \"ess\": "), std::string::npos)
      << answer;
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos)
        << "temporary directory left behind";
  }
}

// A multi-fidelity run: particles.csv gains multiplier, confirmed and low_distance_<component>,
// waves.csv the continuation probabilities and costs, summary.json its "multi_fidelity" block, and
// the answer the expensive simulations.
TEST_F(ExportTest, AMultiFidelityRunGetsItsColumnsAndBlock) {
  options_.multi_fidelity = true;
  options_.per_wave = 9;
  const std::string db = WriteRun(/*outputs=*/false);
  const fs::path out = dir_ / "export";
  ExportRun(db, out.string());
  const HistoryStore store = HistoryStore::Open(db, true);
  const RunHistory history = store.LoadHistory();

  const auto particles = Lines(out / "particles.csv");
  EXPECT_EQ(particles[0],
            "wave,index,bits,clamp 1,clamp 2,clamp 3,clamp 4,clamp 5,clamp 6,log_weight,weight,"
            "d_least_squares,d_secondary_peak,multiplier,confirmed,low_distance_least_squares,"
            "low_distance_secondary_peak");
  ASSERT_EQ(particles.size(), 1u + 2u * 9u);
  EXPECT_EQ(Fields(particles[1]), Fields(particles[0]));
  // Particle 1 of wave 1 is confirmed with multiplier 1, particle 4 with 1 / eta_2 = 4.
  EXPECT_NE(particles[1].find(",1,1,"), std::string::npos) << particles[1];
  EXPECT_NE(particles[4].find(",4,1,"), std::string::npos) << particles[4];
  EXPECT_NE(particles[2].find(",1,0,"), std::string::npos) << particles[2];

  const auto waves = Lines(out / "waves.csv");
  ASSERT_EQ(waves.size(), 3u);
  EXPECT_EQ(waves[0],
            "wave,eps_least_squares,phi,candidates,accepted,acceptance_rate,ess,distinct,"
            "wall_seconds,complete,ess_bits,continue_if_accepted,continue_if_rejected,"
            "expensive_simulations,cheap_seconds,expensive_seconds,next_continue_if_accepted,"
            "next_continue_if_rejected,cost_ratio");
  const WaveFidelity& f = *history.waves[0].multi_fidelity;
  EXPECT_NE(waves[1].find(",0.8,0.25," + std::to_string(f.expensive_simulations) + ","),
            std::string::npos)
      << waves[1];
  EXPECT_EQ(waves[1].substr(waves[1].size() - 11), ",0.9,0.2,50") << waves[1];

  std::ifstream json(out / "summary.json");
  std::stringstream read;
  read << json.rdbuf();
  const std::string text = read.str();
  const std::int64_t expensive = history.waves[0].multi_fidelity->expensive_simulations +
                                 history.waves[1].multi_fidelity->expensive_simulations;
  EXPECT_NE(text.find("\"multi_fidelity\": {\"waves\": [\n    {\"wave\": 1, "
                      "\"continue_if_accepted\": 0.8, \"continue_if_rejected\": 0.25, "
                      "\"cheap_simulations\": " +
                      std::to_string(history.waves[0].candidates) +
                      ", \"expensive_simulations\": " + std::to_string(f.expensive_simulations)),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("\"total\": {\"cheap_simulations\": " +
                      std::to_string(history.summary.simulations) +
                      ", \"expensive_simulations\": " + std::to_string(expensive)),
            std::string::npos)
      << text;
  const double seconds = f.cheap_seconds + f.expensive_seconds;
  EXPECT_NE(text.find("\"ess_per_second\": " + export_text::Number(history.waves[0].ess / seconds)),
            std::string::npos);
  EXPECT_NE(text.find("\"expensive_simulations\": " + std::to_string(expensive) + ",\n"),
            std::string::npos)
      << "the answer's count";

  const Answer answer = SummariseAnswer(store.LoadMetadata(), history);
  ASSERT_TRUE(answer.expensive_simulations.has_value());
  EXPECT_EQ(*answer.expensive_simulations, expensive);
  const std::string terminal = AnswerText(answer);
  EXPECT_NE(terminal.find(" multi-fidelity: " + std::to_string(expensive) +
                          " expensive simulations for " +
                          std::to_string(history.summary.simulations) + " candidates ("),
            std::string::npos)
      << terminal;
  options_.multi_fidelity = false;
  const std::string single = WriteRun(/*outputs=*/false, "single.db");
  const HistoryStore single_store = HistoryStore::Open(single, true);
  const std::string plain =
      AnswerText(SummariseAnswer(single_store.LoadMetadata(), single_store.LoadHistory()));
  EXPECT_EQ(plain.find("multi-fidelity"), std::string::npos) << plain;
}

// A resample-move run: particles.csv gains each particle's ancestor, waves.csv the moves'
// statistics (NaN in a wave drawn by rejection), summary.json's waves their "moves"; a rejection
// run's files keep their columns (WritesEveryTableWithHeaders).
TEST_F(ExportTest, AResampleMoveRunGetsItsAncestorsAndMoveStatistics) {
  options_.moves = true;
  const std::string db = WriteRun(/*outputs=*/false);
  const fs::path out = dir_ / "export";
  ExportRun(db, out.string());
  const RunHistory history = HistoryStore::Open(db, true).LoadHistory();
  ASSERT_EQ(history.waves.size(), 2u);
  ASSERT_TRUE(history.waves[1].moves.has_value());
  const WaveMoves& m = *history.waves[1].moves;

  const auto particles = Lines(out / "particles.csv");
  EXPECT_EQ(particles[0],
            "wave,index,bits,clamp 1,clamp 2,clamp 3,clamp 4,clamp 5,clamp 6,log_weight,weight,"
            "d_least_squares,d_secondary_peak,ancestor");
  ASSERT_EQ(particles.size(), 1u + 2u * 5u);
  EXPECT_EQ(particles[1].substr(particles[1].rfind(',')), ",-1") << "wave 1 drew afresh";
  const Particle& moved = history.waves[1].particles[2];
  EXPECT_EQ(particles[8].substr(particles[8].rfind(',')), "," + std::to_string(moved.ancestor));
  EXPECT_GE(moved.ancestor, 0);

  const auto waves = Lines(out / "waves.csv");
  ASSERT_EQ(waves.size(), 3u);
  const std::string columns =
      "move_rounds,move_proposed,move_accepted,move_acceptance_rate,move_independent_proposed,"
      "move_independent_accepted,move_independent_share,move_survivor_ess,move_step";
  EXPECT_EQ(waves[0].substr(waves[0].size() - columns.size()), columns);
  EXPECT_EQ(waves[1].substr(waves[1].size() - 36), ",NaN,NaN,NaN,NaN,NaN,NaN,NaN,NaN,NaN");
  const auto share = static_cast<double>(m.independent_proposed) / static_cast<double>(m.proposed);
  const std::string row =
      "," + std::to_string(m.rounds) + "," + std::to_string(m.proposed) + "," +
      std::to_string(m.accepted) + "," +
      export_text::Number(static_cast<double>(m.accepted) / static_cast<double>(m.proposed)) + "," +
      std::to_string(m.independent_proposed) + "," + std::to_string(m.independent_accepted) + "," +
      export_text::Number(share) + "," + export_text::Number(m.survivor_ess) + "," +
      export_text::Number(m.step);
  EXPECT_EQ(waves[2].substr(waves[2].size() - row.size()), row) << waves[2];

  std::ifstream json(out / "summary.json");
  std::stringstream read;
  read << json.rdbuf();
  const std::string text = read.str();
  EXPECT_NE(text.find("\"moves\": null}"), std::string::npos) << "wave 1";
  EXPECT_NE(text.find("\"moves\": {\"rounds\": " + std::to_string(m.rounds) + ", \"proposed\": " +
                      std::to_string(m.proposed) + ", \"accepted\": " + std::to_string(m.accepted)),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("\"independent_share\": " + export_text::JsonNumber(share) +
                      ", \"survivor_ess\": " + export_text::JsonNumber(m.survivor_ess) +
                      ", \"step\": " + export_text::JsonNumber(m.step) + "}"),
            std::string::npos)
      << text;

  options_.moves = false;
  const fs::path plain = dir_ / "plain";
  ExportRun(WriteRun(/*outputs=*/false, "plain.db"), plain.string());
  EXPECT_EQ(Lines(plain / "particles.csv")[0].find("ancestor"), std::string::npos);
  EXPECT_EQ(Lines(plain / "waves.csv")[0].find("move_"), std::string::npos);
  std::ifstream plain_json(plain / "summary.json");
  std::stringstream plain_text;
  plain_text << plain_json.rdbuf();
  EXPECT_EQ(plain_text.str().find("\"moves\""), std::string::npos);
}

// A run with continuous parameters: a column per real in particles.csv (after the bits), its mean
// and sd per wave in waves.csv, and their priors, the proposal options and the fingerprint in
// summary.json.
TEST_F(ExportTest, PairCorrelationsAreEachWavesOneRowAPair) {
  const std::string db = WriteRun(/*outputs=*/false);
  const fs::path out = dir_ / "export";
  ExportRun(db, out.string());
  const RunHistory history = HistoryStore::Open(db, /*read_only=*/true).LoadHistory();
  const auto rows = Lines(out / "pair_correlations.csv");
  ASSERT_EQ(rows.size(), 1u + 2u * 15u);
  std::size_t row = 1;
  int between = 0;
  for (const WaveRecord& w : history.waves) {
    ASSERT_EQ(w.pair_correlations.size(), 36u);
    for (std::size_t i = 0; i < 6; ++i) {
      for (std::size_t j = i + 1; j < 6; ++j, ++row) {
        // Waves and bits from 1, the bits with their names, as in marginals.csv.
        const std::string key = std::to_string(w.wave + 1) + "," + std::to_string(i + 1) +
                                ",clamp " + std::to_string(i + 1) + "," + std::to_string(j + 1) +
                                ",clamp " + std::to_string(j + 1) + ",";
        ASSERT_EQ(rows[row].rfind(key, 0), 0u) << rows[row];
        // Shortest round-trip text: the history's value exactly.
        const double r = std::strtod(rows[row].c_str() + key.size(), nullptr);
        EXPECT_EQ(r, w.pair_correlations[i * 6 + j]) << rows[row];
        between += r != 0.0 && std::abs(r) < 1.0;
      }
    }
  }
  EXPECT_GT(between, 0) << "only trivial correlations: the comparison proves little";
}

TEST_F(ExportTest, RealsGetColumnsAndTheirMetadataIsInTheSummary) {
  options_.reals = 2;
  RunMetadata metadata = testing::MakeFakeMetadata(options_);
  metadata.proposal.binary = BinaryKernelKind::kLogistic;
  metadata.proposal.continuous = ContinuousKernelKind::kOlcm;
  metadata.fingerprint = {{"data", "0123456789abcdef"}};
  const std::string db = (dir_ / "RUN.db").string();
  const RunHistory history = testing::MakeFakeHistory(options_);
  {
    HistoryStore store = HistoryStore::Create(db, metadata);
    for (const WaveRecord& wave : history.waves) testing::RecordWave(store, wave, 4);
    store.Finish(history.summary);
  }
  const fs::path out = dir_ / "export";
  ExportRun(db, out.string());

  const auto pairs = Lines(out / "pair_correlations.csv");
  EXPECT_EQ(pairs[0], "wave,bit_i,name_i,bit_j,name_j,correlation");
  EXPECT_EQ(pairs.size(), 1u + 2u * 15u);  // 6 bits: 15 pairs a wave

  const auto particles = Lines(out / "particles.csv");
  EXPECT_EQ(
      particles[0],
      "wave,index,bits,clamp 1,clamp 2,clamp 3,clamp 4,clamp 5,clamp 6,stiffness_1,stiffness_2,"
      "log_weight,weight,d_least_squares,d_secondary_peak");
  ASSERT_EQ(particles.size(), 1u + 2u * 5u);
  const Particle& last = history.waves[1].particles.back();
  EXPECT_EQ(std::stod(Field(particles.back(), 9)), last.theta.reals[0]) << "exact round trip";
  EXPECT_EQ(std::stod(Field(particles.back(), 10)), last.theta.reals[1]);

  const auto waves = Lines(out / "waves.csv");
  EXPECT_EQ(waves[0],
            "wave,eps_least_squares,phi,candidates,accepted,acceptance_rate,ess,distinct,"
            "wall_seconds,complete,stiffness_1_mean,stiffness_1_sd,stiffness_2_mean,stiffness_2_sd,"
            "ess_bits,stiffness_1_mean_se,stiffness_1_sd_se,stiffness_1_ess,stiffness_2_mean_se,"
            "stiffness_2_sd_se,stiffness_2_ess");
  ASSERT_EQ(waves.size(), 3u);
  EXPECT_EQ(std::stod(Field(waves[2], 10)), history.waves[1].reals_mean[0]);
  EXPECT_EQ(std::stod(Field(waves[2], 13)), history.waves[1].reals_sd[1]);
  // The Monte-Carlo errors: the bits' ESS, then per real its mean's and sd's SE and its ESS.
  const WaveErrors errors = WaveMonteCarloErrors(history.waves[1]);
  ASSERT_TRUE(errors.bits_ess);
  EXPECT_NEAR(std::stod(Field(waves[2], 14)), *errors.bits_ess, 1e-9 * *errors.bits_ess);
  EXPECT_NEAR(std::stod(Field(waves[2], 18)), errors.real_means[1].se, 1e-12);
  EXPECT_NEAR(std::stod(Field(waves[2], 19)), errors.real_sds[1].se, 1e-12);
  EXPECT_NEAR(
      std::stod(Field(waves[2], 20)), errors.real_means[1].ess, 1e-9 * errors.real_means[1].ess);

  std::ifstream json(out / "summary.json");
  std::stringstream text;
  text << json.rdbuf();
  const std::string prior_json =
      std::string("{\"name\": \"stiffness_2\", \"prior\": {\"kind\": \"uniform\", ") +
      "\"low\": 10000, \"high\": 1e+05";
  for (const char* expected : {prior_json.c_str(),
                               "\"binary_kernel\": \"logistic\"",
                               "\"continuous_kernel\": \"olcm\"",
                               "\"tempering_form\": \"geometric\"",
                               "\"fingerprint\": {\"data\": \"0123456789abcdef\"}",
                               "\"reals_mean\": [",
                               "\"marginals_se\": [",
                               "\"marginals_ess\": [",
                               "\"ess_bits\": ",
                               "\"reals_mean_se\": [",
                               "\"reals_sd_se\": [",
                               "\"reals_ess\": ["}) {
    EXPECT_NE(text.str().find(expected), std::string::npos) << expected << " in\n" << text.str();
  }
}

// Two named experiments ([[experiment]] tables): experiments.csv gives each one's slices, and
// positions.csv and measured.csv name each row's experiment in a last column; summary.json lists
// them.
TEST_F(ExportTest, NamedExperimentsGetTheirTableAndAColumn) {
  RunMetadata metadata = testing::MakeFakeMetadata(options_);
  ASSERT_EQ(metadata.output_positions.size(), 7u);
  ASSERT_EQ(metadata.measured.positions.size(), 2u);
  metadata.distance_components[0].name = "45cm/least squares";
  metadata.distance_components[1].name = "70cm/secondary peak";
  metadata.experiments = {{"45cm", "load at 0.45 m, 5 Hz", 4, 1, 1},
                          {"70cm", "load at 0.7 m, 5 Hz", 3, 1, 1}};
  const std::string db = (dir_ / "RUN.db").string();
  {
    HistoryStore store = HistoryStore::Create(db, metadata);
    const RunHistory history = testing::MakeFakeHistory(options_);
    for (const WaveRecord& wave : history.waves) testing::RecordWave(store, wave, 4);
    store.Finish(history.summary);
  }
  const fs::path out = dir_ / "export";
  ExportRun(db, out.string());

  const auto experiments = Lines(out / "experiments.csv");
  ASSERT_EQ(experiments.size(), 3u);
  EXPECT_EQ(experiments[1], "0,45cm,\"load at 0.45 m, 5 Hz\",4,1,1,0,0");
  EXPECT_EQ(experiments[2], "1,70cm,\"load at 0.7 m, 5 Hz\",3,1,1,4,1");
  const auto positions = Lines(out / "positions.csv");
  ASSERT_EQ(positions.size(), 8u);
  EXPECT_EQ(positions[0], "column,position_m,experiment");
  EXPECT_EQ(positions[1], "y_0,0,45cm");
  EXPECT_EQ(positions[4], "y_3,0.45,45cm");
  EXPECT_EQ(positions[5], "y_4,0.6,70cm");
  const auto measured = Lines(out / "measured.csv");
  ASSERT_EQ(measured.size(), 3u);
  EXPECT_EQ(measured[0], "position_m,value,experiment");
  EXPECT_EQ(measured[1].substr(measured[1].rfind(',')), ",45cm");
  EXPECT_EQ(measured[2].substr(measured[2].rfind(',')), ",70cm");
  const auto particles = Lines(out / "particles.csv");
  EXPECT_NE(particles[0].find(",d_45cm_least_squares,d_70cm_secondary_peak"), std::string::npos)
      << particles[0];
  const auto curves = Lines(out / "curves.csv");
  EXPECT_EQ(curves[0], "wave,index,y_0,y_1,y_2,y_3,y_4,y_5,y_6") << "curves are not cut";

  std::ifstream json(out / "summary.json");
  std::stringstream text;
  text << json.rdbuf();
  for (const char* expected :
       {"\"experiments\": [\n    {\"name\": \"45cm\", \"description\": \"load at 0.45 m, 5 Hz\", "
        "\"outputs\": 4, \"measured\": 1, \"components\": 1, \"first_output\": 0, "
        "\"first_measured\": 0, \"first_component\": 0},",
        "{\"name\": \"70cm\", \"description\": \"load at 0.7 m, 5 Hz\", \"outputs\": 3, "
        "\"measured\": 1, \"components\": 1, \"first_output\": 4, \"first_measured\": 1, "
        "\"first_component\": 1}\n  ],"}) {
    EXPECT_NE(text.str().find(expected), std::string::npos) << expected << " in\n" << text.str();
  }
}

TEST_F(ExportTest, KilledRunExportsItsPartialWave) {
  const std::string path = (dir_ / "RUN.db").string();
  const RunHistory history = testing::MakeFakeHistory(options_);
  {
    HistoryStore store = HistoryStore::Create(path, testing::MakeFakeMetadata(options_));
    testing::RecordWave(store, history.waves[0], 4);
    testing::RecordWave(store, history.waves[1], 2, /*stop_after_batches=*/2);
  }
  const fs::path out = dir_ / "export";
  ExportRun(path, out.string());
  const auto waves = Lines(out / "waves.csv");
  ASSERT_EQ(waves.size(), 3u);
  // `complete`, the tenth column.
  EXPECT_EQ(Field(waves[1], 9), "1");
  EXPECT_EQ(Field(waves[2], 9), "0") << "the cut wave is exported as incomplete: " << waves[2];
  EXPECT_EQ(waves[1].rfind("1,", 0), 0u) << "waves are numbered from 1, as users see them";
  EXPECT_EQ(waves[2].rfind("2,", 0), 0u);
  // The answer is the last complete wave's.
  std::ifstream json(out / "summary.json");
  std::stringstream text;
  text << json.rdbuf();
  EXPECT_NE(text.str().find("\"answer\": {\n    \"wave\": 1,\n    \"complete\": true"),
            std::string::npos)
      << text.str();
}

TEST_F(ExportTest, RunWithoutOutputsHasNoCurves) {
  const std::string db = WriteRun(/*outputs=*/false);
  const fs::path out = dir_ / "export";
  ExportRun(db, out.string());
  EXPECT_FALSE(fs::exists(out / "curves.csv"));
  EXPECT_TRUE(fs::exists(out / "particles.csv"));
}

TEST_F(ExportTest, RefusesAForeignDirectoryAndOverwriteKeepsTheUsersFiles) {
  const std::string db = WriteRun(/*outputs=*/true);
  const fs::path out = dir_ / "export";
  fs::create_directories(out);
  std::ofstream(out / "keep.txt") << "x";
  std::ofstream(out / "waves.csv") << "the user's own waves.csv";
  try {
    ExportRun(db, out.string());
    ADD_FAILURE() << "no error";
  } catch (const Error& error) {
    EXPECT_EQ(error.kind(), ErrorKind::kCantCreate);
  }
  EXPECT_TRUE(fs::exists(out / "keep.txt"));
  EXPECT_EQ(Lines(out / "waves.csv").front(), "the user's own waves.csv");
  // --overwrite writes combabc's files into it: same-named files replaced, nothing removed.
  ExportOptions options;
  options.overwrite = true;
  ExportRun(db, out.string(), options);
  EXPECT_TRUE(fs::exists(out / "keep.txt")) << "overwrite removed a file combabc did not write";
  EXPECT_EQ(Lines(out / "waves.csv").front().rfind("wave,", 0), 0u);
}

TEST_F(ExportTest, OverwriteNeverRemovesAFileAtTheTarget) {
  const std::string db = WriteRun(/*outputs=*/true);
  const fs::path out = dir_ / "export";
  std::ofstream(out) << "a file, not a directory";
  ExportOptions options;
  options.overwrite = true;
  try {
    ExportRun(db, out.string(), options);
    ADD_FAILURE() << "no error";
  } catch (const Error& error) {
    EXPECT_EQ(error.kind(), ErrorKind::kCantCreate);
  }
  EXPECT_EQ(Lines(out), std::vector<std::string>{"a file, not a directory"});
}

TEST_F(ExportTest, ReExportReplacesItsOwnFilesOnly) {
  const std::string db = WriteRun(/*outputs=*/true);
  const fs::path out = dir_ / "export";
  ExportRun(db, out.string());
  std::ofstream(out / "analysis.m") << "% the user's script";
  const std::string plain = WriteRun(/*outputs=*/false, "PLAIN.db");  // no curves
  ExportRun(plain, out.string());  // its own previous export: no --overwrite needed
  EXPECT_FALSE(fs::exists(out / "curves.csv")) << "a stale file of the previous export remains";
  EXPECT_TRUE(fs::exists(out / "waves.csv"));
  EXPECT_TRUE(fs::exists(out / "analysis.m"));
}

TEST_F(ExportTest, MissingHistoryIsNoInput) {
  try {
    ExportRun((dir_ / "none.db").string(), (dir_ / "export").string());
    ADD_FAILURE() << "no error";
  } catch (const Error& error) {
    EXPECT_EQ(error.kind(), ErrorKind::kNoInput);
  }
  EXPECT_FALSE(fs::exists(dir_ / "export"));
}

}  // namespace
}  // namespace combabc
