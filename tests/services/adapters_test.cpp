// The adapters (src/services/adapters/): a Python script's exit status and last line as one
// combabc error; running it (core's Subprocess under RunProcess) in the CLI's words.
#include <gtest/gtest.h>
#include <signal.h>

#include "services/adapters/python_script.hpp"

namespace combabc::services {
namespace {

TEST(PythonScript, ExitStatusGivesTheErrorKind) {
  EXPECT_EQ(KindOfScriptStatus(64), ErrorKind::kUsage);
  EXPECT_EQ(KindOfScriptStatus(65), ErrorKind::kData);
  EXPECT_EQ(KindOfScriptStatus(66), ErrorKind::kNoInput);
  EXPECT_EQ(KindOfScriptStatus(69), ErrorKind::kCantCreate);  // a Python package missing
  EXPECT_EQ(KindOfScriptStatus(73), ErrorKind::kCantCreate);
  EXPECT_EQ(KindOfScriptStatus(74), ErrorKind::kIo);
  EXPECT_EQ(KindOfScriptStatus(1), ErrorKind::kSoftware);
}

TEST(PythonScript, MessageIsTheLastLineWithoutItsPrefix) {
  EXPECT_EQ(ScriptMessage("Traceback\nreport: no curves in export\n\n", 65, "report"),
            "no curves in export");
  EXPECT_EQ(ScriptMessage("one line", 1, "report"), "one line");
  EXPECT_EQ(ScriptMessage("", 3, "report"), "report failed with status 3");
}

// The CLI's wording for a program that cannot start (the report's and the export's messages end
// with it); the status of one that ran, the signal of one killed as 128 + N; stderr kept less the
// lines the listener takes.
TEST(PythonScript, RunProcessInTheClisWords) {
  try {
    RunProcess({"/nonexistent/python3", "-c", "pass"}, "install python3");
    ADD_FAILURE() << "a missing program was started";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kCantCreate);
    EXPECT_EQ(e.message(),
              "cannot start /nonexistent/python3 (No such file or directory); install python3");
  }
  const auto progress = [](const std::string& line) { return line == "progress"; };
  const ProcessResult failed = RunProcess(
      {"/bin/sh", "-c", "echo progress >&2; echo 'x: it broke' >&2; exit 65"}, "", {}, progress);
  EXPECT_EQ(failed.status, 65);
  EXPECT_EQ(failed.err, "x: it broke\n");
  EXPECT_EQ(ScriptMessage(failed.err, failed.status, "x"), "it broke");
  EXPECT_EQ(RunProcess({"/bin/sh", "-c", "kill -9 $$"}, "").status, 128 + SIGKILL);
}

}  // namespace
}  // namespace combabc::services
