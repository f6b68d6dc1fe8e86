// WorkerSimulator with fault injection: the handshake is checked; a worker that crashes, hangs or
// breaks the protocol is killed (with its group) and replaced, the candidate failing with the
// reason; a worker that answers is kept.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <atomic>
#include <thread>

#include "combabc/core/error.hpp"
#include "combabc/core/subprocess.hpp"
#include "combabc/simulators/worker_simulator.hpp"
#include "simulators/simulator_test_support.hpp"

namespace combabc::testing {
namespace {

// The mode is the request's bits; $1 is where a hanging request writes its grandchild's pid.
// Every started worker appends its pid to $1.workers.
constexpr const char* kFaulty = R"(echo $$ >> "$1.workers"
echo "combabc-worker 2 3 sh-faulty 1.0"
while read id bits a b; do
  case $bits in
    000) echo "$id ok 1 2 3" ;;
    001) echo boom >&2; exit 3 ;;
    010) sleep 30 & echo $! > "$1"; wait ;;
    011) echo "hello" ;;
    100) echo "$id ok 1 2" ;;
    101) echo "$id ok 1 nan 3" ;;
    110) echo "$id error mesh did not converge" ;;
    111) echo "$id ok $a $b 0" ;;
  esac
done)";

// Answers each request with its own bits as outputs ("101" -> 1 0 1), so that an answer given to
// the wrong candidate shows. Request "011" is answered twice, the second time a moment later
// (after combabc has taken the first); "110" twice at once; "111" with the id 7.
constexpr const char* kRepeating = R"(echo "combabc-worker 2 3 sh-repeating"
while read id bits; do
  rest=${bits#?}
  answer="$id ok ${bits%??} ${rest%?} ${bits#??}"
  case $bits in
    011) echo "$answer"; sleep 0.2; echo "$answer" ;;
    110) echo "$answer
$answer" ;;
    111) echo "7 ok 1 1 1" ;;
    *) echo "$answer" ;;
  esac
done)";

class WorkerSimulatorTest : public ::testing::Test {
 protected:
  WorkerSimulatorTest() : run_("worker") {}
  ExternalSimulatorOptions Faulty() const {
    return ShOptions(run_, kFaulty, {run_ / "grandchild.pid"});
  }
  int WorkersStarted() const {
    std::istringstream in(ReadText(run_ / "grandchild.pid.workers"));
    int n = 0;
    for (std::string line; std::getline(in, line);) ++n;
    return n;
  }
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
  std::string RefusedBecause(const std::string& script) const {
    try {
      WorkerSimulator s(ShOptions(run_, script));
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::kConfig);
      return e.message();
    }
    return "accepted";
  }
  RunFolder run_;
};

TEST_F(WorkerSimulatorTest, TheHandshakeIsChecked) {
  // Version 1 had no request ids.
  EXPECT_EQ(RefusedBecause("echo combabc-worker 1 3"),
            "the worker 'sh' did not start: it speaks protocol version '1'; this combabc speaks 2");
  EXPECT_EQ(RefusedBecause("echo combabc-worker 2 4"),
            "the worker 'sh' did not start: it declares '4' outputs; the config declares 3 "
            "([simulator.outputs])");
  EXPECT_EQ(RefusedBecause("echo hello"),
            "the worker 'sh' did not start: its first line is 'hello', not a handshake "
            "\"combabc-worker 2 3 ...\"");
  EXPECT_EQ(RefusedBecause("echo nope >&2; exit 5"),
            "the worker 'sh' did not start: the worker exited with status 5; stderr: nope");
  WorkerSimulator s(ShOptions(run_, "echo 'combabc-worker 2 3 my model v2'; cat > /dev/null"));
  EXPECT_EQ(s.handshake(), "combabc-worker 2 3 my model v2");
}

TEST_F(WorkerSimulatorTest, EachFaultIsASimulationFailedAndABrokenWorkerIsReplaced) {
  WorkerSimulator s(Faulty());
  std::vector<double> out;
  struct Case {
    const char* bits;
    const char* reason;
    bool replaced;
  };
  int started = 1;
  for (const Case& c : {
           Case{"001", "the worker exited with status 3; stderr: boom", true},
           Case{"011", "expected an answer \"2 ok ...\" or \"2 error ...\", got 'hello'", true},
           Case{"100", "returned 2 values; expected 3", false},
           Case{"101", "output value 2 is NaN", false},
           Case{"110", "the worker reported an error: mesh did not converge", false},
       }) {
    SCOPED_TRACE(c.bits);
    EXPECT_EQ(Reason(s, Bits(c.bits), &out), c.reason);
    EXPECT_EQ(Reason(s, Bits("000"), &out), "");
    EXPECT_EQ(out, (std::vector<double>{1, 2, 3}));
    if (c.replaced) ++started;
    EXPECT_EQ(WorkersStarted(), started);
  }
  // Reals travel with 17 significant digits: exactly the candidate's values.
  EXPECT_EQ(Reason(s, Bits("111", {0.1, -2.5e-300}), &out), "");
  EXPECT_EQ(out, (std::vector<double>{0.1, -2.5e-300, 0}));
}

TEST_F(WorkerSimulatorTest, AHangingWorkerIsKilledWithItsGroupAndReplaced) {
  ExternalSimulatorOptions o = Faulty();
  o.timeout_s = 0.3;
  WorkerSimulator s(o);
  std::vector<double> out;
  EXPECT_EQ(Reason(s, Bits("010"), &out), "timed out after 0.3 s (worker killed)");
  EXPECT_TRUE(Gone(std::stoi(ReadText(run_ / "grandchild.pid"))));
  std::istringstream workers(ReadText(run_ / "grandchild.pid.workers"));
  std::string first;
  std::getline(workers, first);
  EXPECT_TRUE(Gone(std::stoi(first)));
  EXPECT_EQ(Reason(s, Bits("000"), &out), "");
  EXPECT_EQ(WorkersStarted(), 2);
}

TEST_F(WorkerSimulatorTest, AWorkerThatDiesLeavingAGrandchildOnItsStdoutFailsAtOnce) {
  ExternalSimulatorOptions o =
      ShOptions(run_,
                "echo 'combabc-worker 2 3 x'; read line; sleep 30 & echo $! > \"$1\"; exit 4",
                {run_ / "grandchild.pid"});
  WorkerSimulator s(o);
  std::vector<double> out;
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(Reason(s, Bits("000"), &out), "the worker exited with status 4");
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(3));
  EXPECT_TRUE(Gone(std::stoi(ReadText(run_ / "grandchild.pid"))));
}

TEST_F(WorkerSimulatorTest, RetriesUseANewWorker) {
  ExternalSimulatorOptions o = Faulty();
  o.retries = 2;
  WorkerSimulator s(o);
  std::vector<double> out;
  EXPECT_EQ(Reason(s, Bits("001"), &out),
            "the worker exited with status 3; stderr: boom (3 attempts)");
  EXPECT_EQ(WorkersStarted(), 3);
}

TEST_F(WorkerSimulatorTest, WorkersAndTheirFoldersEndWithTheSimulator) {
  {
    WorkerSimulator s(Faulty());
    std::vector<double> out;
    EXPECT_EQ(Reason(s, Bits("000"), &out), "");
  }
  std::istringstream workers(ReadText(run_ / "grandchild.pid.workers"));
  for (std::string pid; std::getline(workers, pid);) EXPECT_TRUE(Gone(std::stoi(pid)));
  EXPECT_FALSE(fs::exists(run_ / "history.work"));
}

TEST_F(WorkerSimulatorTest, ThreadsEachUseTheirOwnWorker) {
  WorkerSimulator s(Faulty());
  std::atomic<int> ok{0};
  std::vector<std::thread> threads;
  threads.reserve(4);
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&] {
      std::vector<double> out;
      for (int i = 0; i < 25; ++i) {
        if (Reason(s, Bits("000"), &out).empty() && out == std::vector<double>{1, 2, 3}) ++ok;
      }
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(ok.load(), 100);
  EXPECT_LE(WorkersStarted(), 4);  // never more workers than callers at once
}

// Regression (issue 20, D7): a worker that answered one request twice shifted every later answer
// onto the wrong candidate. Each answer carries its request's id: no candidate gets outputs
// computed from other bits, and the worker out of step is replaced.
TEST_F(WorkerSimulatorTest, ARepeatedOrMisnumberedAnswerFailsTheCandidateAndReplacesTheWorker) {
  WorkerSimulator s(ShOptions(run_, kRepeating));
  std::vector<double> out;
  struct Case {
    const char* bits;
    const char* reason;
  };
  for (const Case& c : {
           Case{"000", ""},
           Case{"011", ""},  // its repeated answer is still on its way
           Case{"100",
                "the worker answered request 2 when request 3 was asked (an answer repeated, "
                "skipped or out of order)"},
           Case{"101", ""},  // a new worker
           Case{"110", "the worker wrote more than one line in answer to request 2"},
           Case{"001", ""},
           Case{"111",
                "the worker answered request 7 when request 2 was asked (an answer repeated, "
                "skipped or out of order)"},
           Case{"010", ""},
       }) {
    SCOPED_TRACE(c.bits);
    EXPECT_EQ(Reason(s, Bits(c.bits), &out), c.reason);
    if (*c.reason == '\0') {
      const Candidate expected = Bits(c.bits);
      EXPECT_EQ(out, std::vector<double>(expected.bits.begin(), expected.bits.end()));
    }
  }
}

// Regression (issue 20, D21): a worker that closed its stdout was reported as "killed by signal
// 9 (SIGKILL)", combabc's own kill.
TEST_F(WorkerSimulatorTest, AWorkerThatClosesItsStdoutIsReportedAsSuch) {
  WorkerSimulator s(ShOptions(run_,
                              "echo 'combabc-worker 2 3 x'; read id bits; echo \"$id ok 1 2 3\"; "
                              "read id bits; echo closing >&2; exec >&-; sleep 30 & echo $! > "
                              "\"$1\"; wait",
                              {run_ / "grandchild.pid"}));
  std::vector<double> out;
  EXPECT_EQ(Reason(s, Bits("000"), &out), "");
  EXPECT_EQ(Reason(s, Bits("000"), &out),
            "the worker closed its stdout after answering 1 request (then killed); stderr: "
            "closing");
  EXPECT_TRUE(Gone(std::stoi(ReadText(run_ / "grandchild.pid"))));
}

// Regression (issue 20, D4 and D5): a worker's stderr file grew without bound (1 MiB per request
// filled a small disk), and the failure reason was read with getline over the whole file (400 MiB
// without a newline: 828 MB of memory). The file keeps the last kMaxStderrBytes; the reason is the
// last line of that tail.
TEST_F(WorkerSimulatorTest, StderrIsCappedToItsLast64KiBAndTheReasonIsItsLastLine) {
  // 2 MiB of stderr per request, then its number; request "001" ends with 32 MiB on one line
  // (no newline) before its last words and exit 3.
  const char* script = R"(echo "combabc-worker 2 3 chatty"
while read id bits; do
  head -c 2097152 /dev/zero | tr '\0' x >&2
  echo " request $id" >&2
  if [ "$bits" = 001 ]; then
    head -c 33554432 /dev/zero | tr '\0' y >&2
    echo >&2; echo "last words" >&2; exit 3
  fi
  echo "$id ok 1 2 3"
done)";
  WorkerSimulator s(ShOptions(run_, script));
  std::vector<double> out;
  for (int i = 0; i < 3; ++i) EXPECT_EQ(Reason(s, Bits("000"), &out), "");
  const std::vector<std::string> workers = Entries(run_ / "history.work");
  ASSERT_EQ(workers.size(), 1u);
  const std::string file = run_ / ("history.work/" + workers[0] + "/stderr.txt");
  ASSERT_TRUE(fs::exists(file));
  EXPECT_LE(fs::file_size(file), kMaxStderrBytes);
  const std::string text = ReadText(file);
  EXPECT_EQ(text.substr(text.size() - 11), " request 3\n");
  rusage before{};
  ::getrusage(RUSAGE_SELF, &before);
  EXPECT_EQ(Reason(s, Bits("001"), &out), "the worker exited with status 3; stderr: last words");
  rusage after{};
  ::getrusage(RUSAGE_SELF, &after);
  // ru_maxrss is in KiB: the 32 MiB line was never held in memory.
  EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 8 * 1024);
}

}  // namespace
}  // namespace combabc::testing

namespace combabc::testing {
namespace {

// A worker serves one experiment: it gets it on its command line when it starts.
TEST(WorkerSimulatorExperiment, TheWorkerIsToldItsExperimentOnItsCommandLine) {
  RunFolder run("worker-experiment");
  ExternalSimulatorOptions o = ShOptions(run,
                                         R"sh(echo "combabc-worker 2 3 sh-experiment"
while read id bits; do echo "$id ok $1 $2 $3"; done)sh",
                                         {"{load_x}", "{load_y_fraction}", "{frequency}"});
  o.experiment = SimulatorExperiment{"offcentre", 0.7, 0.25, 0.042, 5.0};
  WorkerSimulator s(o);
  std::vector<double> out(3);
  RandomStream rng(1, 0, 0);
  s.Simulate(Bits("101").view(), rng, out);
  EXPECT_EQ(out, (std::vector<double>{0.7, 0.25, 5.0}));
}

}  // namespace
}  // namespace combabc::testing
