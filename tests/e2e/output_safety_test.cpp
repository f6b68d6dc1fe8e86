// What commands write, through the CLI: no command deletes, truncates or replaces a file or
// directory it did not create, unless the user named that path with --overwrite, and then only
// that path. (The report's own cases, which need Python, are in report_test.cpp.)
#include <gtest/gtest.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "cli_runner.hpp"
#include "output_test_support.hpp"
#include "tiny_sensor.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

constexpr int kCantCreate = 73;

std::string PaperConfig() {
  return std::string(COMBABC_SOURCE_DIR) + "/tests/config/testdata/paper_45cm_least_squares.toml";
}

class OutputSafety : public ::testing::Test {
 protected:
  OutputSafety()
      : dir_("output-safety-" +
             std::string(::testing::UnitTest::GetInstance()->current_test_info()->name())) {}
  void Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
  }
  // The tiny sensor (3 + 3 clamps), tiny.toml and its data.csv in the test's folder: what simulate
  // writes does not depend on the mesh, and the paper's mesh costs 20 s under ASan.
  std::string TinyConfig() {
    WriteTinySensorData(dir_.path());
    Write("tiny.toml", TinySensorConfig("waves = 1\naccepted_per_wave = 5\n"));
    return dir_ / "tiny.toml";
  }
  TempFolder dir_;
};

const std::string kAllFree = "000000";

TEST_F(OutputSafety, SimulateRefusesAnExistingFileUnlessOverwrite) {
  const std::string config = TinyConfig();
  Write("profile.csv", "the user's measurements\n");
  auto r =
      RunCli({"simulate", config, "--clamps", kAllFree, "-o", dir_ / "profile.csv"}, dir_.path());
  EXPECT_EQ(r.exit_code, kCantCreate) << r.err;
  EXPECT_EQ(CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("profile.csv"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--overwrite"), std::string::npos) << r.err;
  EXPECT_EQ(ReadFile(dir_ / "profile.csv"), "the user's measurements\n");

  r = RunCli({"simulate", config, "--clamps", kAllFree, "-o", dir_ / "profile.csv", "--overwrite"},
             dir_.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(ReadFile(dir_ / "profile.csv").rfind("position_m,", 0), 0u);
}

TEST_F(OutputSafety, SimulateNeverFollowsASymlinkPlantedAtTheTemporaryName) {
  const std::string config = TinyConfig();
  Write("victim.txt", "precious\n");
  fs::create_symlink(dir_.path() / "victim.txt", dir_.path() / "profile.csv.tmp");
  const auto r =
      RunCli({"simulate", config, "--clamps", kAllFree, "-o", dir_ / "profile.csv"}, dir_.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(ReadFile(dir_ / "victim.txt"), "precious\n") << "the symlink's target was clobbered";
  EXPECT_TRUE(fs::is_symlink(dir_.path() / "profile.csv.tmp"));
  EXPECT_EQ(ReadFile(dir_ / "profile.csv").rfind("position_m,", 0), 0u);
  EXPECT_EQ(Listing(dir_.path()),
            (std::set<std::string>{"victim.txt",
                                   "profile.csv.tmp",
                                   "profile.csv",
                                   "cli.stdout",
                                   "cli.stderr",
                                   "tiny.toml",
                                   "data.csv"}));
}

TEST_F(OutputSafety, ExportOverwriteKeepsEverythingElseInTheDirectory) {
  const std::string db = MakeHistory(dir_.path() / "RUN.db");
  fs::create_directories(dir_.path() / "analysis");
  Write("analysis/fit.m", "% the user's script");
  auto r = RunCli({"export", db, "-o", dir_ / "analysis"}, dir_.path());
  EXPECT_EQ(r.exit_code, kCantCreate) << r.err;
  EXPECT_EQ(CountLines(r.err), 1) << r.err;
  EXPECT_EQ(Listing(dir_.path() / "analysis"), std::set<std::string>{"fit.m"});

  r = RunCli({"export", db, "-o", dir_ / "analysis", "--overwrite"}, dir_.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(ReadFile(dir_ / "analysis/fit.m"), "% the user's script");
  EXPECT_TRUE(fs::exists(dir_.path() / "analysis" / "waves.csv"));

  // A file at the target is never deleted, not even with --overwrite.
  Write("export", "a file named export");
  r = RunCli({"export", db, "-o", dir_ / "export", "--overwrite"}, dir_.path());
  EXPECT_EQ(r.exit_code, kCantCreate) << r.err;
  EXPECT_EQ(ReadFile(dir_ / "export"), "a file named export");
}

// Issue 35 (E15): Ctrl-C during an export (here while its NetCDF script runs, when every file is
// staged) ends combabc by the signal and leaves none of its temporaries, nor the export directory
// it created.
TEST_F(OutputSafety, AnExportInterruptedBySigintLeavesNothing) {
  const std::string db = MakeHistory(dir_.path() / "RUN.db");
  Write("interrupt.py",
        "import os, signal, time\nos.kill(os.getppid(), signal.SIGINT)\ntime.sleep(30)\n");
  ASSERT_EQ(::setenv("COMBABC_NETCDF_SCRIPT", (dir_ / "interrupt.py").c_str(), 1), 0);
  const auto r = RunCli({"export", db, "-o", dir_ / "export"}, dir_.path());
  ::unsetenv("COMBABC_NETCDF_SCRIPT");
  EXPECT_EQ(r.exit_code, 128 + SIGINT) << r.err;
  EXPECT_FALSE(fs::exists(dir_.path() / "export"))
      << "left: "
      << ::testing::PrintToString(fs::exists(dir_.path() / "export")
                                      ? Listing(dir_.path() / "export")
                                      : std::set<std::string>{});
}

TEST_F(OutputSafety, RunRefusesAForeignReportDirectoryBeforeSampling) {
  fs::create_directories(dir_.path() / "out" / "report");
  Write("out/report/draft.md", "the user's draft");
  const auto r = RunCli({"run", PaperConfig(), "-o", dir_ / "out", "-q"}, dir_.path());
  EXPECT_EQ(r.exit_code, kCantCreate) << r.err;
  EXPECT_EQ(CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("--no-report"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_.path() / "out" / "history.sqlite")) << "it sampled first";
  EXPECT_EQ(Listing(dir_.path() / "out" / "report"), std::set<std::string>{"draft.md"});
}

}  // namespace
}  // namespace combabc::testing
