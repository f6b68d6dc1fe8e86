// `combabc report` through the CLI: its directory rules (never replace what the user wrote),
// names drawn literally, the configured figure formats, and every failure as one line.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "cli_runner.hpp"
#include "combabc/core/error.hpp"
#include "combabc/services/report.hpp"
#include "output_test_support.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

constexpr int kData = 65, kSoftware = 70, kCantCreate = 73;

bool HavePlotting() {
  static const bool have =
      std::system("/usr/bin/python3 -c 'import numpy, matplotlib' > /dev/null 2>&1") == 0;
  return have;
}

class Report : public ::testing::Test {
 protected:
  Report()
      : dir_("report-" +
             std::string(::testing::UnitTest::GetInstance()->current_test_info()->name())) {}
  void SetUp() override {
    if (!HavePlotting()) {
      GTEST_SKIP() << "/usr/bin/python3 lacks numpy or matplotlib (scripts/setup.sh installs them)";
    }
  }
  void Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
  }
  // Runs the CLI expecting one failure line and exit `code`; returns the line.
  std::string ExpectFailure(const std::vector<std::string>& args, int code) {
    const auto r = RunCli(args, dir_.path());
    EXPECT_EQ(r.exit_code, code) << r.err;
    EXPECT_EQ(CountLines(r.err), 1) << r.err;
    EXPECT_EQ(r.err.find("Traceback"), std::string::npos) << r.err;
    EXPECT_EQ(r.out, "") << "partial output on stdout";
    return r.err;
  }
  TempFolder dir_;
};

TEST_F(Report, IntoTheWorkingDirectoryIsRefusedAndDeletesNothing) {
  const std::string db = MakeHistory(dir_.path() / "RUN.db");
  fs::create_directories(dir_.path() / "work");
  Write("work/thesis.tex", "years of work");
  const auto before = Listing(dir_.path() / "work");
  {
    ScopedWorkingDirectory cwd(dir_.path() / "work");
    const auto err = ExpectFailure({"report", db, "-o", "."}, kCantCreate);
    EXPECT_NE(err.find("--overwrite"), std::string::npos) << err;
  }
  EXPECT_EQ(Listing(dir_.path() / "work"), before);
  EXPECT_EQ(ReadFile(dir_.path() / "work" / "thesis.tex"), "years of work");
}

TEST_F(Report, RewritesItsOwnReportAndOverwriteKeepsTheUsersFiles) {
  const std::string db = MakeHistory(dir_.path() / "RUN.db");
  const fs::path out = dir_.path() / "report";
  auto r = RunCli({"report", db}, dir_.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(out / ".combabc-manifest"));
  // Not a terminal: nothing on stderr (the progress line is for a terminal).
  EXPECT_EQ(r.err, "");
  Write("report/notes.txt", "the user's notes");
  r = RunCli({"report", db}, dir_.path());  // its own report: replaced without --overwrite
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(ReadFile(out / "notes.txt"), "the user's notes");
  EXPECT_TRUE(fs::exists(out / "wave_2_marginals.png"));

  // Someone else's directory: refused; with --overwrite, only same-named files are replaced.
  fs::create_directories(dir_.path() / "figures");
  Write("figures/summary.png", "the user's own summary");
  Write("figures/keep.txt", "keep");
  ExpectFailure({"report", db, "-o", dir_ / "figures"}, kCantCreate);
  EXPECT_EQ(ReadFile(dir_.path() / "figures" / "summary.png"), "the user's own summary");
  r = RunCli({"report", db, "-o", dir_ / "figures", "--overwrite"}, dir_.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(ReadFile(dir_.path() / "figures" / "keep.txt"), "keep");
  EXPECT_EQ(ReadFile(dir_.path() / "figures" / "summary.png").rfind("\x89PNG", 0), 0u);
  for (const auto& name : Listing(dir_.path() / "figures")) {
    EXPECT_EQ(name.find(".combabc-tmp"), std::string::npos) << "staging left behind: " << name;
  }
}

// The manifest, like every other file of the report, gets 0666 less the umask (mkstemp made it
// 0600 whatever the umask).
TEST_F(Report, FilesGetTheUmasksMode) {
  const std::string db = MakeHistory(dir_.path() / "RUN.db");
  const mode_t saved = ::umask(022);
  const auto r = RunCli({"report", db}, dir_.path());
  ::umask(saved);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* name : {".combabc-manifest", "index.html"}) {
    struct stat st {};
    ASSERT_EQ(::stat((dir_.path() / "report" / name).c_str(), &st), 0) << name;
    EXPECT_EQ(st.st_mode & 07777, 0644u) << name;
  }
}

TEST_F(Report, MathtextInNamesIsDrawnLiterally) {
  const std::string db = MakeHistory(dir_.path() / "RUN.db", [](RunMetadata& m, RunHistory& h) {
    // Two threshold components, so that their names reach the figures (summary legend).
    m.distance_components = {{"$\\frac{$", ComponentKind::kThreshold, 1.0},
                             {"$x_{$ and $", ComponentKind::kThreshold, 1.0}};
    m.bit_names[0] = "$\\frac{$";
    for (WaveRecord& w : h.waves) {
      w.thresholds.push_back(w.thresholds.front() / 2);
      for (Particle& p : w.particles) p.distance.resize(2, 0.0);
    }
  });
  const auto r = RunCli({"report", db}, dir_.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir_.path() / "report" / "summary.png")) << r.err;
}

TEST_F(Report, HistoryNamedLikeAnOptionIsStillTheHistory) {
  MakeHistory(dir_.path() / "-h");
  ScopedWorkingDirectory cwd(dir_.path());
  const auto r = RunCli({"report", "--", "-h"}, dir_.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.find("usage"), std::string::npos) << r.out;
  EXPECT_TRUE(fs::exists(dir_.path() / "report" / "index.html")) << r.out << r.err;
}

TEST_F(Report, FiguresFollowTheConfiguredFormats) {
  const auto with_figures = [](const std::string& list) {
    return [list](RunMetadata& m, RunHistory&) {
      m.config_text += "\n[output]\nfigures = " + list + "\n";
    };
  };
  const std::string pdf = MakeHistory(dir_.path() / "PDF.db", with_figures("[\"pdf\"]"));
  auto r = RunCli({"report", pdf, "-o", dir_ / "pdf"}, dir_.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir_.path() / "pdf" / "wave_2_curves.pdf"));
  EXPECT_FALSE(fs::exists(dir_.path() / "pdf" / "wave_2_curves.png"));
  EXPECT_FALSE(fs::exists(dir_.path() / "pdf" / "wave_2_curves.svg"));
  EXPECT_NE(ReadFile(dir_.path() / "pdf" / "index.html").find("href=\"summary.pdf\""),
            std::string::npos);

  const std::string both = MakeHistory(dir_.path() / "BOTH.db", with_figures("[\"svg\", \"png\"]"));
  r = RunCli({"report", both, "-o", dir_ / "both"}, dir_.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir_.path() / "both" / "overview.svg"));
  EXPECT_TRUE(fs::exists(dir_.path() / "both" / "overview.png"));
  EXPECT_FALSE(fs::exists(dir_.path() / "both" / "overview.pdf"));
  // The page shows the raster format.
  EXPECT_NE(ReadFile(dir_.path() / "both" / "index.html").find("<img src=\"overview.png\""),
            std::string::npos);
}

// The number of axes (panels) in a matplotlib SVG: one <g id="axes_N"> each.
int SvgAxes(const std::string& svg) {
  int count = 0;
  for (std::size_t at = svg.find("<g id=\"axes_"); at != std::string::npos;
       at = svg.find("<g id=\"axes_", at + 1)) {
    ++count;
  }
  return count;
}

// A run of two named experiments ([[experiment]] tables) scanning the same line under two loads:
// the curve figures get one panel per experiment, titled with its name and description, and
// index.html lists them; the marginals are the run's, as for one experiment.
TEST_F(Report, EveryExperimentGetsItsCurvePanel) {
  const auto svg = [](RunMetadata& m, RunHistory&) {
    m.config_text += "\n[output]\nfigures = [\"svg\"]\n";
  };
  const std::string one = MakeHistory(dir_.path() / "ONE.db", svg);
  const std::string two = MakeHistory(dir_.path() / "TWO.db", [&](RunMetadata& m, RunHistory& h) {
    svg(m, h);
    const auto points = static_cast<int>(m.output_positions.size());
    const auto measured = static_cast<int>(m.measured.positions.size());
    auto twice = [](std::vector<double>& v) { v.insert(v.end(), v.begin(), v.end()); };
    twice(m.output_positions);
    twice(m.measured.positions);
    twice(m.measured.values);
    m.distance_components = {{"45cm/least squares", ComponentKind::kThreshold, 1.0},
                             {"70cm/least squares", ComponentKind::kThreshold, 1.0}};
    m.experiments = {{"45cm", "load at 0.45 m; scan 0-0.9 m", points, measured, 1},
                     {"70cm", "load at 0.7 m; scan 0-0.9 m", points, measured, 1}};
    for (WaveRecord& w : h.waves) {
      w.thresholds.push_back(w.thresholds.front());
      for (Particle& p : w.particles) twice(p.output);
    }
  });
  auto r = RunCli({"report", one, "-o", dir_ / "one"}, dir_.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = RunCli({"report", two, "-o", dir_ / "two"}, dir_.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;

  // One experiment: one panel, no experiment table, as before experiments existed.
  EXPECT_EQ(SvgAxes(ReadFile(dir_.path() / "one" / "wave_1_curves.svg")), 1);
  EXPECT_EQ(SvgAxes(ReadFile(dir_.path() / "one" / "overview.svg")), 2 * (1 + 2));
  EXPECT_EQ(ReadFile(dir_.path() / "one" / "index.html").find("Experiments"), std::string::npos);

  for (const char* wave : {"wave_1_curves.svg", "wave_2_curves.svg"}) {
    const std::string figure = ReadFile(dir_.path() / "two" / wave);
    EXPECT_EQ(SvgAxes(figure), 2) << wave;
    for (const char* title :
         {"45cm", "load at 0.45 m; scan 0-0.9 m", "70cm", "load at 0.7 m; scan 0-0.9 m"}) {
      EXPECT_NE(figure.find(title), std::string::npos) << title << " in " << wave;
    }
  }
  // The posterior predictive check: band and residuals per experiment.
  EXPECT_EQ(SvgAxes(ReadFile(dir_.path() / "one" / "predictive.svg")), 2);
  EXPECT_EQ(SvgAxes(ReadFile(dir_.path() / "two" / "predictive.svg")), 2 * 2);
  // Per wave: a curve column per experiment, then the two edges' marginals.
  EXPECT_EQ(SvgAxes(ReadFile(dir_.path() / "two" / "overview.svg")), 2 * (2 + 2));
  EXPECT_EQ(SvgAxes(ReadFile(dir_.path() / "two" / "wave_1_marginals.svg")), 2);
  const std::string page = ReadFile(dir_.path() / "two" / "index.html");
  EXPECT_NE(page.find("<h2>Experiments</h2>"), std::string::npos);
  EXPECT_NE(page.find("<td>70cm</td><td>load at 0.7 m; scan 0-0.9 m</td><td>91</td>"),
            std::string::npos)
      << page;
}

TEST_F(Report, FailuresAreOneLineAndLeaveNothingBehind) {
  {  // the script's own error: a history with no committed wave
    const fs::path path = dir_.path() / "EMPTY.db";
    FakeRunOptions options;
    HistoryStore::Create(path.string(), MakeFakeMetadata(options));
    const auto err = ExpectFailure({"report", path.string(), "-o", dir_ / "r1"}, kData);
    EXPECT_NE(err.find("no committed wave"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir_.path() / "r1"));
  }
  const std::string db = MakeHistory(dir_.path() / "RUN.db");
  {  // matplotlib missing: a module that fails to import stands in for it
    fs::create_directories(dir_.path() / "fake" / "matplotlib");
    Write("fake/matplotlib/__init__.py", "raise ImportError('No module named matplotlib')\n");
    ScopedEnv path("PYTHONPATH", dir_ / "fake");
    const auto err = ExpectFailure({"report", db, "-o", dir_ / "r2"}, kCantCreate);
    EXPECT_NE(err.find("matplotlib"), std::string::npos) << err;
    EXPECT_NE(err.find("COMBABC_PYTHON"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir_.path() / "r2"));
  }
  {  // no python at all
    ScopedEnv python("COMBABC_PYTHON", dir_ / "no-such-python3");
    const auto err = ExpectFailure({"report", db, "-o", dir_ / "r3"}, kCantCreate);
    EXPECT_NE(err.find("no-such-python3"), std::string::npos) << err;
    EXPECT_NE(err.find("COMBABC_PYTHON"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir_.path() / "r3"));
  }
  {  // a script that dies with a multi-line traceback still gives one combabc line
    Write("broken.py", "raise RuntimeError('the script broke')\n");
    ScopedEnv script("COMBABC_REPORT_SCRIPT", dir_ / "broken.py");
    const auto err = ExpectFailure({"report", db, "-o", dir_ / "r4"}, kSoftware);
    EXPECT_NE(err.find("the script broke"), std::string::npos) << err;
  }
}

// One reader of the history (issue 22): the script is given the export that combabc staged (a
// folder with summary.json, particles.csv, curves.csv ...), never the history, and what it draws
// is published into the report directory with combabc's manifest; the staging folder under TMPDIR
// is removed. A stand-in script checks its arguments; needs no plotting packages.
TEST(ReportStaging, TheScriptReadsTheStagedExportAndCombabcPublishes) {
  TempFolder dir("report-staging");
  const std::string db = MakeHistory(dir.path() / "RUN.db");
  const std::string script = dir / "check_args.py";
  std::ofstream(script) << R"(import os, sys
out = sys.argv[sys.argv.index("--out") + 1]
export = sys.argv[-1]
assert sys.argv[-2] == "--", sys.argv
for name in ("summary.json", "particles.csv", "curves.csv", "positions.csv", "measured.csv"):
    assert os.path.isfile(os.path.join(export, name)), name
history = sys.argv[sys.argv.index("--history") + 1]
assert history.endswith("RUN.db") and os.path.isabs(history), history
assert all(not a.endswith("RUN.db") for a in sys.argv[1:] if a != history), sys.argv
os.makedirs(out)
with open(os.path.join(out, "index.html"), "w") as f:
    f.write("drawn from " + export)
)";
  ScopedEnv use("COMBABC_REPORT_SCRIPT", script);
  fs::create_directories(dir.path() / "tmp");
  ScopedEnv tmp("TMPDIR", dir / "tmp");
  const auto r = RunCli({"report", db}, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(ReadFile(dir.path() / "report" / "index.html").rfind("drawn from " + (dir / "tmp"), 0),
            0u);
  EXPECT_NE(ReadFile(dir.path() / "report" / ".combabc-manifest").find("index.html"),
            std::string::npos);
  EXPECT_EQ(Listing(dir.path() / "report"),
            (std::set<std::string>{".combabc-manifest", "index.html"}));
  EXPECT_TRUE(Listing(dir.path() / "tmp").empty()) << "the staging folder was left behind";
}

// Issue 34: the report's progress. With a listener, the script is asked for --progress and its
// "combabc_report: progress D/N" lines reach the listener, after (0, 0) for the start; they never
// become the error's message, even when the script dies right after one. A stand-in script.
TEST(ReportProgress, TheScriptsProgressLinesReachTheListenerAndNotTheError) {
  TempFolder dir("report-progress");
  const std::string db = MakeHistory(dir.path() / "RUN.db");
  const std::string script = dir / "progress.py";
  std::ofstream(script) << R"(import os, sys
assert "--progress" in sys.argv, sys.argv
out = sys.argv[sys.argv.index("--out") + 1]
for done in range(3):
    print(f"combabc_report: progress {done}/2", file=sys.stderr, flush=True)
if os.environ.get("FAIL") == "message":
    print("combabc_report: the figures broke", file=sys.stderr)
    sys.exit(70)
if os.environ.get("FAIL") == "silent":
    sys.exit(70)
os.makedirs(out)
with open(os.path.join(out, "index.html"), "w") as f:
    f.write("drawn")
)";
  ScopedEnv use("COMBABC_REPORT_SCRIPT", script);
  std::vector<std::pair<int, int>> heard;
  const auto listen = [&heard](int done, int total) { heard.emplace_back(done, total); };
  services::WriteReport(db, dir / "report", false, listen);
  EXPECT_EQ(heard, (std::vector<std::pair<int, int>>{{0, 0}, {0, 2}, {1, 2}, {2, 2}}));
  EXPECT_EQ(ReadFile(dir.path() / "report" / "index.html"), "drawn");
  for (const char* fail : {"message", "silent"}) {
    ScopedEnv failing("FAIL", fail);
    try {
      services::WriteReport(db, dir / fail, false, listen);
      ADD_FAILURE() << "the script's failure was not an error";
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()),
                std::string(fail) == "message" ? "the figures broke"
                                               : "combabc_report failed with status 70");
    }
    EXPECT_FALSE(fs::exists(dir.path() / fail));
  }
}

// Regression (issue 20, D20): SIGINT to combabc during the report ended combabc alone; the report
// script went on and published later. Now the script (a stand-in that would draw after 30 s, and
// cleans up on KeyboardInterrupt) is interrupted and waited for, nothing is published, the staging
// folder (export and drawing, under TMPDIR) is removed, and combabc ends by the signal (exit
// status 130). Needs no plotting packages.
TEST(ReportInterrupt, SigintStopsTheScriptAndNothingIsPublished) {
  TempFolder dir("report-interrupt");
  const std::string db = MakeHistory(dir.path() / "RUN.db");
  const std::string mark = dir / "script";
  const std::string script = dir / "slow_report.py";
  std::ofstream(script) << R"(import os, sys, time
mark = ")" << mark << R"("
out = sys.argv[sys.argv.index("--out") + 1]
with open(mark + ".pid", "w") as f:
    f.write(str(os.getpid()))
try:
    time.sleep(30)
except KeyboardInterrupt:
    with open(mark + ".interrupted", "w") as f:
        f.write("cleaned up")
    sys.exit(130)
os.makedirs(out)
with open(os.path.join(out, "index.html"), "w") as f:
    f.write("published")
)";
  ScopedEnv use("COMBABC_REPORT_SCRIPT", script);
  fs::create_directories(dir.path() / "tmp");
  ScopedEnv tmp("TMPDIR", dir / "tmp");
  const std::string out = dir / "report";
  const pid_t cli = SpawnCli({"report", db, "-o", out}, dir.path());
  ASSERT_GT(cli, 0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  std::string pid_text;
  while (pid_text.empty() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    pid_text = ReadFile(mark + ".pid");  // empty until the script has written it
  }
  ASSERT_FALSE(pid_text.empty()) << "the report script did not start";
  const pid_t script_pid = std::stoi(pid_text);
  ::kill(cli, SIGINT);
  const auto r = WaitCli(cli, dir.path());
  EXPECT_EQ(r.exit_code, 128 + SIGINT) << r.err;
  // The script was interrupted (it cleaned up) and reaped before combabc ended.
  EXPECT_TRUE(fs::exists(mark + ".interrupted"));
  EXPECT_NE(::kill(script_pid, 0), 0) << "the report script outlived combabc";
  EXPECT_FALSE(fs::exists(out));
  EXPECT_TRUE(Listing(dir.path() / "tmp").empty()) << "the staging folder was left behind";
}

}  // namespace
}  // namespace combabc::testing
