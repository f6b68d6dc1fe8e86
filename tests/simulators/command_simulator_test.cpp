// CommandSimulator with fault injection: each failure is a SimulationFailed naming the reason, the
// next call works, nothing is left running and every call's folder is removed.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <atomic>
#include <thread>

#include "combabc/core/error.hpp"
#include "combabc/core/subprocess.hpp"
#include "combabc/simulators/command_simulator.hpp"
#include "simulators/simulator_test_support.hpp"

namespace combabc::testing {
namespace {

// The mode is the candidate's bits (params.csv rows "b1,0" ...); $2 is where a hanging call
// writes its grandchild's pid.
constexpr const char* kFaulty = R"(mode=$(sed -n 's/^b[123],//p' "$1" | tr -d '\n')
case $mode in
  000) printf '1,2\n3\n' ;;
  001) echo first line >&2; echo boom >&2; exit 3 ;;
  010) sleep 30 & echo $! > "$2"; wait ;;
  011) echo 'Traceback (most recent call last):' ;;
  100) echo 1,2 ;;
  101) printf '1\nnan\n3\n' ;;
  110) kill -SEGV $$ ;;
  111) touch leftover.txt; mkdir sub; touch sub/x; echo 4 5 6 ;;
esac)";

class CommandSimulatorTest : public ::testing::Test {
 protected:
  CommandSimulatorTest() : run_("command") {}
  ExternalSimulatorOptions Faulty() const {
    ExternalSimulatorOptions o = ShOptions(run_, kFaulty, {"{params}", run_ / "grandchild.pid"});
    o.params_format = DataFormat::kCsv;
    return o;
  }
  // The reason Simulate gave, or "" when it succeeded.
  static std::string Reason(const Simulator& s, const Candidate& c, std::vector<double>* out) {
    RandomStream rng(1, 0, 0);
    out->assign(static_cast<std::size_t>(s.output_size()), -1.0);
    try {
      s.Simulate(c.view(), rng, *out);
    } catch (const SimulationFailed& e) {
      return e.what();
    }
    return "";
  }
  RunFolder run_;
};

TEST_F(CommandSimulatorTest, EachFaultIsASimulationFailedWithItsReasonAndTheNextCallWorks) {
  CommandSimulator s(Faulty());
  std::vector<double> out;
  struct Case {
    const char* bits;
    const char* reason;
  };
  for (const Case& c : {
           Case{"001", "exited with status 3; stderr: boom"},
           Case{"011", "stdout: line 1: 'Traceback' is not a number"},
           Case{"100", "stdout: returned 2 values; expected 3"},
           Case{"101", "stdout: output value 2 is NaN (line 2)"},
           Case{"110", "killed by signal 11 (SIGSEGV)"},
       }) {
    SCOPED_TRACE(c.bits);
    EXPECT_EQ(Reason(s, Bits(c.bits), &out), c.reason);
    EXPECT_EQ(Reason(s, Bits("000"), &out), "");
    EXPECT_EQ(out, (std::vector<double>{1, 2, 3}));
  }
  // What the program leaves in its folder goes with the folder; no call folder remains.
  EXPECT_EQ(Reason(s, Bits("111"), &out), "");
  EXPECT_EQ(out, (std::vector<double>{4, 5, 6}));
  EXPECT_TRUE(Entries(run_ / "history.work").empty());
}

TEST_F(CommandSimulatorTest, ATimeoutKillsTheWholeProcessGroupGrandchildrenIncluded) {
  ExternalSimulatorOptions o = Faulty();
  o.timeout_s = 0.3;
  CommandSimulator s(o);
  std::vector<double> out;
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(Reason(s, Bits("010"), &out), "timed out after 0.3 s (process group killed)");
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
  const pid_t grandchild = std::stoi(ReadText(run_ / "grandchild.pid"));
  EXPECT_TRUE(Gone(grandchild)) << "the sleep the script started is still running";
  EXPECT_TRUE(Entries(run_ / "history.work").empty());
  EXPECT_EQ(Reason(s, Bits("000"), &out), "");
}

TEST_F(CommandSimulatorTest, AGrandchildHoldingStdoutDoesNotStallACallThatEnded) {
  // The program exits at once but leaves a background sleep holding stdout open.
  ExternalSimulatorOptions o =
      ShOptions(run_, "sleep 30 & echo $! > \"$1\"; echo 7 8 9", {run_ / "bg.pid"});
  o.params = Transport::kStdin;
  CommandSimulator s(o);
  std::vector<double> out;
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(Reason(s, Bits("000"), &out), "");
  EXPECT_EQ(out, (std::vector<double>{7, 8, 9}));
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(3));
  EXPECT_TRUE(Gone(std::stoi(ReadText(run_ / "bg.pid"))));
}

TEST_F(CommandSimulatorTest, ArgumentsAndPathsWithShellMetacharactersArriveLiterally) {
  const std::vector<std::string> tricky = {
      "$(touch x)", "; rm -rf y", "it's \"quoted\"", "`touch z`", "a b  c", "*", "{config_dir}/f"};
  std::vector<std::string> args = {run_ / "args.txt"};
  args.insert(args.end(), tricky.begin(), tricky.end());
  args.emplace_back("{output}");
  // The shared temporary folder may hold such names already (other programs' files): only a
  // name that appears during the call counts.
  std::vector<bool> in_parent_before;
  for (const char* name : {"x", "y", "z", "pwned"}) {
    in_parent_before.push_back(fs::exists(run_.path().parent_path() / name));
  }
  ExternalSimulatorOptions o =
      ShOptions(run_,
                R"(out=$1; shift; printf '%s\n' "$@" > "$out"; for a; do last=$a; done
echo 1 2 3 > "$last")",
                args);
  o.results = Transport::kFile;
  o.params = Transport::kStdin;
  CommandSimulator s(o);
  std::vector<double> out;
  ASSERT_EQ(Reason(s, Bits("101"), &out), "");
  EXPECT_EQ(out, (std::vector<double>{1, 2, 3}));
  std::vector<std::string> got;
  std::istringstream lines(ReadText(run_ / "args.txt"));
  for (std::string line; std::getline(lines, line);) got.push_back(line);
  ASSERT_EQ(got.size(), tricky.size() + 1);
  for (std::size_t k = 0; k + 1 < tricky.size(); ++k) EXPECT_EQ(got[k], tricky[k]);
  // Placeholders are expanded (once, literally): the run folder's path has "$(touch pwned); ".
  EXPECT_EQ(got[tricky.size() - 1], run_.path().string() + "/f");
  EXPECT_EQ(got.back().rfind(run_ / "history.work/call-", 0), 0u) << got.back();
  std::size_t k = 0;
  for (const char* name : {"x", "y", "z", "pwned"}) {
    EXPECT_FALSE(fs::exists(run_.path() / name)) << name;
    if (!in_parent_before[k++]) {
      EXPECT_FALSE(fs::exists(run_.path().parent_path() / name)) << name;
    }
  }
}

TEST_F(CommandSimulatorTest, ParametersAsJsonOnStdinAndResultsAsJson) {
  ExternalSimulatorOptions o =
      ShOptions(run_, "cat > \"$1\"; echo '[1, 2.5e-3,\n -3]'", {run_ / "params.json"});
  o.params = Transport::kStdin;
  o.results_format = DataFormat::kJson;
  o.real_names = {"k \"f\"", "scale"};
  CommandSimulator s(o);
  std::vector<double> out;
  ASSERT_EQ(Reason(s, Bits("101", {0.1, -2.5e-300}), &out), "");
  EXPECT_EQ(out, (std::vector<double>{1, 2.5e-3, -3}));
  EXPECT_EQ(ReadText(run_ / "params.json"),
            "{\"bits\": [1, 0, 1], \"reals\": {\"k \\\"f\\\"\": 0.10000000000000001, "
            "\"scale\": -2.5e-300}}\n");
  // A broken JSON array names the line.
  ExternalSimulatorOptions bad = o;
  bad.argv = {"sh", "-c", "printf '[1,\\n2 3]'"};
  CommandSimulator b(bad);
  EXPECT_EQ(Reason(b, Bits("000", {1, 2}), &out), "stdout: line 2: expected ',' or ']', got '3]'");
}

TEST_F(CommandSimulatorTest, RetriesRunAFailedCallAgain) {
  const std::string marker = run_ / "tried";
  const std::string script = "if [ -e \"$1\" ]; then echo 1 2 3; else touch \"$1\"; exit 4; fi";
  ExternalSimulatorOptions o = ShOptions(run_, script, {marker});
  o.params = Transport::kStdin;
  std::vector<double> out;
  {
    CommandSimulator once(o);
    EXPECT_EQ(Reason(once, Bits("000"), &out), "exited with status 4");
  }
  fs::remove(marker);
  o.retries = 1;
  CommandSimulator twice(o);
  EXPECT_EQ(Reason(twice, Bits("000"), &out), "");
  o.argv = {"sh", "-c", "exit 9"};
  CommandSimulator never(o);
  EXPECT_EQ(Reason(never, Bits("000"), &out), "exited with status 9 (2 attempts)");
}

// Regression (issue 20, D12): a program that does not exist ran 100 failing simulations and
// stopped the run on its failure fraction (exit 69), where a worker is refused up front (78).
TEST_F(CommandSimulatorTest, AProgramThatCannotRunIsAConfigErrorBeforeAnySimulation) {
  std::ofstream(run_ / "not-executable.sh") << "echo 1 2 3\n";
  struct Case {
    std::string program;
    std::string says;
  };
  for (const Case& c : {
           Case{"/nonexistent/simulator", "/nonexistent/simulator: No such file or directory"},
           Case{"no-such-simulator-program",
                "'no-such-simulator-program' is not an executable file in any directory of PATH"},
           Case{"{config_dir}/not-executable.sh", "not-executable.sh: not executable"},
           Case{"{config_dir}", ": not a regular file"},
           Case{"./model.sh",
                "./model.sh: No such file or directory (relative to the folder the program starts "
                "in; use an absolute path or {config_dir}/...)"},
       }) {
    SCOPED_TRACE(c.program);
    ExternalSimulatorOptions o = ShOptions(run_, "");
    o.params = Transport::kStdin;
    o.argv = {c.program};
    try {
      CommandSimulator s(o);
      ADD_FAILURE() << "accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::kConfig);
      EXPECT_EQ(e.field(), "simulator.argv");
      EXPECT_NE(e.message().find("the command cannot be run: "), std::string::npos) << e.message();
      EXPECT_NE(e.message().find(c.says), std::string::npos) << e.message();
    }
  }
  EXPECT_TRUE(Entries(run_ / "history.work").empty()) << "nothing ran";
  // Found in PATH, or by a path relative to the call's folder: accepted.
  ExternalSimulatorOptions o = ShOptions(run_, "");
  o.params = Transport::kStdin;
  o.argv = {"true"};
  EXPECT_NO_THROW(CommandSimulator{o});
}

// Regression (issue 20, D4 and D5): the stderr file grew without bound and the failure reason was
// read by getline over all of it. The file keeps the last kMaxStderrBytes (the program measures
// its own stderr file after writing 3 MiB to it); the reason is the last line of that tail.
TEST_F(CommandSimulatorTest, StderrIsCappedToItsLast64KiBAndTheReasonIsItsLastLine) {
  ExternalSimulatorOptions o = ShOptions(run_,
                                         R"(head -c 3145728 /dev/zero | tr '\0' x >&2
echo >&2; echo "last words" >&2
wc -c < stderr.txt; echo 0; echo 0
if [ -n "$1" ]; then head -c 33554432 /dev/zero | tr '\0' y >&2; echo >&2; echo "the end" >&2; exit 3; fi)",
                                         {""});
  o.params = Transport::kStdin;
  CommandSimulator s(o);
  std::vector<double> out;
  ASSERT_EQ(Reason(s, Bits("000"), &out), "");
  EXPECT_LE(out[0], static_cast<double>(kMaxStderrBytes));
  EXPECT_GT(out[0], 0.0);
  o.argv.back() = "fail";
  CommandSimulator failing(o);
  rusage before{};
  ::getrusage(RUSAGE_SELF, &before);
  EXPECT_EQ(Reason(failing, Bits("000"), &out), "exited with status 3; stderr: the end");
  rusage after{};
  ::getrusage(RUSAGE_SELF, &after);
  EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 8 * 1024);  // KiB: the 32 MiB line never held
}

TEST_F(CommandSimulatorTest, InvalidOptionsAreAConfigError) {
  ExternalSimulatorOptions o = ShOptions(run_, "echo 1 2 3");  // params = file, no {params}
  try {
    CommandSimulator s(o);
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kConfig);
    EXPECT_NE(std::string(e.what()).find("argv has no {params}"), std::string::npos) << e.what();
  }
}

TEST_F(CommandSimulatorTest, TheWorkFolderGoesWhenCombabcCreatedItAndAnOldOneIsKept) {
  {
    CommandSimulator s(Faulty());
    std::vector<double> out;
    EXPECT_EQ(Reason(s, Bits("000"), &out), "");
  }
  EXPECT_FALSE(fs::exists(run_ / "history.work"));
  // A folder from an earlier, killed run: its call folder is neither reused nor deleted.
  fs::create_directories(run_ / "history.work/call-0");
  {
    CommandSimulator s(Faulty());
    std::vector<double> out;
    EXPECT_EQ(Reason(s, Bits("000"), &out), "");
  }
  EXPECT_EQ(Entries(run_ / "history.work"), std::vector<std::string>{"call-0"});
}

TEST_F(CommandSimulatorTest, ThreadsCallItConcurrently) {
  CommandSimulator s(Faulty());
  std::atomic<int> ok{0};
  std::vector<std::thread> threads;
  threads.reserve(4);
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&] {
      std::vector<double> out;
      for (int i = 0; i < 5; ++i) {
        if (Reason(s, Bits(i % 2 ? "000" : "100"), &out) ==
            (i % 2 ? "" : "stdout: returned 2 values; expected 3")) {
          ++ok;
        }
      }
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(ok.load(), 20);
  EXPECT_TRUE(Entries(run_ / "history.work").empty());
}

}  // namespace
}  // namespace combabc::testing

namespace combabc::testing {
namespace {

// A run with [[experiment]] tables tells the program which experiment it simulates: in argv
// placeholders and in the params file (docs/simulators.md, "Experiments").
TEST(CommandSimulatorExperiment, TheExperimentReachesArgvAndTheParamsFile) {
  RunFolder run("command-experiment");
  // Echoes the load position from argv, the experiment's name from params.json, and a constant.
  ExternalSimulatorOptions o =
      ShOptions(run,
                R"sh(name=$(sed -n 's/.*"experiment": {"name": "\([^"]*\)".*/\1/p' "$1")
[ "$name" = "70cm" ] || { echo "no experiment in params: $(cat "$1")" >&2; exit 2; }
echo "$2,$3,7")sh",
                {"{params}", "{load_x}", "{frequency}"});
  o.experiment = SimulatorExperiment{"70cm", 0.7, 0.25, 0.042, 5.0};
  CommandSimulator s(o);
  std::vector<double> out(3);
  RandomStream rng(1, 0, 0);
  s.Simulate(Bits("010").view(), rng, out);
  EXPECT_EQ(out, (std::vector<double>{0.7, 5.0, 7.0}));
}

TEST(CommandSimulatorExperiment, WithoutAnExperimentThePlaceholdersStayAsWritten) {
  const std::vector<std::string> argv = {"prog", "{load_x}", "{params}"};
  EXPECT_EQ(ExpandArgv(argv, "p.json", "", "", ""),
            (std::vector<std::string>{"prog", "{load_x}", "p.json"}));
  const SimulatorExperiment e{"a", 0.25, 0.5, 0.5, 12.5};
  EXPECT_EQ(
      ExpandArgv(
          {"--x={load_x}", "{experiment}", "{load_amplitude}{frequency}"}, "", "", "", "", &e),
      (std::vector<std::string>{"--x=0.25", "a", "0.512.5"}));
}

}  // namespace
}  // namespace combabc::testing
