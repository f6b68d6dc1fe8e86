// The adapters (src/services/adapters/): a Python script's exit status and last line as one
// combabc error.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace combabc::services
