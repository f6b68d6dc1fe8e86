// Subprocess::SpinUntilReadable: true as soon as a line is waiting, false after its budget when
// none comes, and the line is read the same either way. What the Python scripts' runner
// (services' RunProcess) takes from it: stderr kept in memory less the progress lines, stdout
// discarded, argv[0] taken as a path, the spawn's errno, and a held SIGINT forwarded to the child.
#include "combabc/core/subprocess.hpp"

#include <gtest/gtest.h>
#include <signal.h>

#include <cerrno>
#include <chrono>
#include <optional>
#include <string>
#include <vector>

namespace combabc {
namespace {

using std::chrono::milliseconds;

SubprocessOptions Shell(const std::string& script) {
  SubprocessOptions o;
  o.argv = {"/bin/sh", "-c", script};
  o.pipe_stdin = true;
  return o;
}

TEST(SubprocessTest, SpinReturnsAsSoonAsALineIsWaiting) {
  Subprocess p(Shell("read x; echo \"got $x\""));
  ASSERT_TRUE(p.Write("42\n", DeadlineAfter(30)));
  // A generous budget: the spin ends when the answer comes, not when the budget runs out.
  const auto start = std::chrono::steady_clock::now();
  EXPECT_TRUE(p.SpinUntilReadable(std::chrono::seconds(30)));
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(25));
  std::string line;
  ASSERT_EQ(p.ReadLine(&line, 100, DeadlineAfter(30)), ReadStatus::kOk);
  EXPECT_EQ(line, "got 42");
}

TEST(SubprocessTest, SpinGivesUpAfterItsBudgetAndTheLineIsStillRead) {
  Subprocess p(Shell("read x; sleep 0.3; echo \"late $x\""));
  ASSERT_TRUE(p.Write("7\n", DeadlineAfter(30)));
  EXPECT_FALSE(p.SpinUntilReadable(milliseconds(1)));
  std::string line;
  ASSERT_EQ(p.ReadLine(&line, 100, DeadlineAfter(30)), ReadStatus::kOk);
  EXPECT_EQ(line, "late 7");
}

TEST(SubprocessTest, SpinSeesALineAlreadyBufferedAndAnExitedChild) {
  Subprocess p(Shell("echo one; echo two"));
  std::string line;
  ASSERT_EQ(p.ReadLine(&line, 100, DeadlineAfter(30)), ReadStatus::kOk);
  EXPECT_EQ(line, "one");
  EXPECT_TRUE(p.SpinUntilReadable(std::chrono::seconds(30)));  // "two" or end of file
  ASSERT_EQ(p.ReadLine(&line, 100, DeadlineAfter(30)), ReadStatus::kOk);
  EXPECT_EQ(line, "two");
  EXPECT_TRUE(p.SpinUntilReadable(std::chrono::seconds(30)));  // end of file is readable
  EXPECT_EQ(p.ReadLine(&line, 100, DeadlineAfter(30)), ReadStatus::kEof);
}

// Stdout is /dev/null (a megabyte of it never blocks the child), stderr is kept without a file,
// every ended line is heard, and the lines the listener takes are left out of what is kept.
TEST(SubprocessTest, StderrIsKeptLessTheLinesTheListenerTakes) {
  SubprocessOptions o;
  o.argv = {"/bin/sh",
            "-c",
            "head -c 1000000 /dev/zero; echo 'progress 1/2' >&2; echo 'the message' >&2; "
            "printf 'unended' >&2; exit 4"};
  o.pipe_stdout = false;
  o.capture_stderr = true;
  std::vector<std::string> heard;
  o.on_stderr_line = [&heard](const std::string& line) {
    heard.push_back(line);
    return line.rfind("progress ", 0) == 0;
  };
  Subprocess p(o);
  const std::optional<ExitStatus> status = p.Wait(DeadlineAfter(30));
  ASSERT_TRUE(status.has_value()) << "the child blocked on its stdout";
  EXPECT_EQ(status->code, 4);
  EXPECT_EQ(p.Stderr(), "the message\nunended");
  EXPECT_EQ(heard, (std::vector<std::string>{"progress 1/2", "the message"}));
}

// search_path = false: "sh" is ./sh, which does not exist here, not /bin/sh; the failure carries
// posix_spawn's errno. A child killed by a signal says which.
TEST(SubprocessTest, AProgramNotLookedUpInPathAndASignalledChild) {
  SubprocessOptions o;
  o.argv = {"sh", "-c", "exit 0"};
  o.search_path = false;
  try {
    Subprocess p(o);
    ADD_FAILURE() << "./sh was started";
  } catch (const SpawnError& e) {
    EXPECT_EQ(e.error(), ENOENT);
    EXPECT_EQ(std::string(e.what()), "cannot start sh: No such file or directory");
  }
  o.search_path = true;
  o.argv = {"sh", "-c", "kill -9 $$"};
  Subprocess p(o);
  const ExitStatus status = p.Wait(DeadlineAfter(30)).value();
  EXPECT_EQ(status.signal, SIGKILL);
  EXPECT_EQ(Describe(status), "killed by signal 9 (SIGKILL)");
}

// A SIGINT that reaches combabc while it waits is held, not acted on, and forwarded to the child,
// which stops in its own way (here exit 3 from its trap); one that ignores SIGINT is killed after
// the grace period. The signal stays held until the caller releases it.
TEST(SubprocessTest, AHeldSignalInterruptsTheChild) {
  for (const bool stubborn : {false, true}) {
    SubprocessOptions o;
    o.argv = {"/bin/sh",
              "-c",
              std::string(stubborn ? "trap '' INT" : "trap 'echo stopped >&2; exit 3' INT") +
                  "; echo ready; while :; do sleep 0.02; done"};
    o.capture_stderr = true;
    SignalHold hold;
    Subprocess p(o);
    std::string line;
    ASSERT_EQ(p.ReadLine(&line, 100, DeadlineAfter(30)), ReadStatus::kOk);  // its trap is set
    ASSERT_EQ(::raise(SIGINT), 0);
    EXPECT_EQ(hold.signal(), SIGINT);
    const ExitStatus status = p.WaitForwarding(hold, std::chrono::milliseconds(50));
    if (stubborn) {
      EXPECT_EQ(status.signal, SIGKILL);
    } else {
      EXPECT_EQ(status.code, 3);
      EXPECT_EQ(p.Stderr(), "stopped\n");
    }
    EXPECT_FALSE(p.timed_out());
  }
}

}  // namespace
}  // namespace combabc
