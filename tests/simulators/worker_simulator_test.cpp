// WorkerSimulator with fault injection: the handshake is checked; a worker that crashes, hangs or
// breaks the protocol is killed (with its group) and replaced, the candidate failing with the
// reason; a worker that answers is kept.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "combabc/core/error.hpp"
#include "combabc/simulators/worker_simulator.hpp"
#include "simulators/simulator_test_support.hpp"

namespace combabc::testing {
namespace {

// The mode is the request's bits; $1 is where a hanging request writes its grandchild's pid.
// Every started worker appends its pid to $1.workers.
constexpr const char* kFaulty = R"(echo $$ >> "$1.workers"
echo "combabc-worker 1 3 sh-faulty 1.0"
while read bits a b; do
  case $bits in
    000) echo "ok 1 2 3" ;;
    001) echo boom >&2; exit 3 ;;
    010) sleep 30 & echo $! > "$1"; wait ;;
    011) echo "hello" ;;
    100) echo "ok 1 2" ;;
    101) echo "ok 1 nan 3" ;;
    110) echo "error mesh did not converge" ;;
    111) echo "ok $a $b 0" ;;
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
  EXPECT_EQ(RefusedBecause("echo combabc-worker 2 3"),
            "the worker 'sh' did not start: it speaks protocol version '2'; this combabc speaks 1");
  EXPECT_EQ(RefusedBecause("echo combabc-worker 1 4"),
            "the worker 'sh' did not start: it declares '4' outputs; the config declares 3 "
            "([simulator.outputs])");
  EXPECT_EQ(RefusedBecause("echo hello"),
            "the worker 'sh' did not start: its first line is 'hello', not a handshake "
            "\"combabc-worker 1 3 ...\"");
  EXPECT_EQ(RefusedBecause("echo nope >&2; exit 5"),
            "the worker 'sh' did not start: the worker exited with status 5; stderr: nope");
  WorkerSimulator s(ShOptions(run_, "echo 'combabc-worker 1 3 my model v2'; cat > /dev/null"));
  EXPECT_EQ(s.handshake(), "combabc-worker 1 3 my model v2");
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
           Case{"011", "expected a response \"ok ...\" or \"error ...\", got 'hello'", true},
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
                "echo 'combabc-worker 1 3 x'; read line; sleep 30 & echo $! > \"$1\"; exit 4",
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

}  // namespace
}  // namespace combabc::testing
