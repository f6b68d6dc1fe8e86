// Subprocess::SpinUntilReadable: true as soon as a line is waiting, false after its budget when
// none comes, and the line is read the same either way.
#include "combabc/core/subprocess.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <string>

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

}  // namespace
}  // namespace combabc
