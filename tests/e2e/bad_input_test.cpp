// Bad input through the CLI: each case is one line on stderr naming file:line and field where
// there is one, the sysexits code, and no output left behind.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "cli_runner.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

constexpr int kUsage = 64, kData = 65, kNoInput = 66, kCantCreate = 73, kConfig = 78;

const char* kConfigText = R"(# a small valid calibration
[data]
csv = "data.csv"
position_column = "x_cm"
displacement_column = "w_m"
position_unit = "cm"
displacement_unit = "m"
window = [48, 80]

[metric]
preset = "least_squares"

[sampler]
waves = 2
accepted_per_wave = 20

[output]
directory = "out"
)";

std::string GoodCsv() {
  std::string csv = "x_cm,w_m\n";
  for (int x = 48; x <= 80; ++x) {
    csv += std::to_string(x) + "," + std::to_string(1e-6 / (1.0 + (x - 48) * 0.2)) + "\n";
  }
  return csv;
}

class BadInput : public ::testing::Test {
 protected:
  BadInput()
      : dir_("bad-input-" +
             std::string(::testing::UnitTest::GetInstance()->current_test_info()->name())) {
    Write("config.toml", kConfigText);
    Write("data.csv", GoodCsv());
  }
  void Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
  }
  std::string Replace(std::string text, const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return text.replace(at, from.size(), to);
  }
  // Runs the CLI and checks the common contract: exit code, one stderr line, nothing written.
  std::string Expect(const std::vector<std::string>& args, int code) {
    const auto r = RunCli(args, dir_.path());
    EXPECT_EQ(r.exit_code, code) << r.err;
    EXPECT_EQ(CountLines(r.err), 1) << r.err;
    EXPECT_FALSE(fs::exists(dir_.path() / "out" / "history.sqlite")) << "history left behind";
    EXPECT_FALSE(fs::exists(dir_.path() / "out" / "report")) << "report left behind";
    return r.err;
  }
  std::string config() const { return dir_ / "config.toml"; }
  TempFolder dir_;
};

TEST_F(BadInput, MissingConfigFile) {
  const auto err = Expect({"run", dir_ / "nope.toml"}, kNoInput);
  EXPECT_NE(err.find("nope.toml"), std::string::npos) << err;
}

TEST_F(BadInput, MalformedToml) {
  Write("config.toml", Replace(kConfigText, "waves = 2", "waves = = 2"));
  const auto err = Expect({"run", config()}, kConfig);
  EXPECT_NE(err.find("config.toml:14"), std::string::npos) << err;
}

TEST_F(BadInput, UnknownKey) {
  Write("config.toml", Replace(kConfigText, "waves = 2", "wavez = 2"));
  const auto err = Expect({"run", config()}, kConfig);
  EXPECT_NE(err.find("config.toml:14"), std::string::npos) << err;
  EXPECT_NE(err.find("sampler.wavez"), std::string::npos) << err;
}

TEST_F(BadInput, WrongTypeAndOutOfRange) {
  Write("config.toml", Replace(kConfigText, "waves = 2", "waves = \"two\""));
  auto err = Expect({"run", config()}, kConfig);
  EXPECT_NE(err.find("config.toml:14"), std::string::npos) << err;
  Write("config.toml", Replace(kConfigText, "accepted_per_wave = 20", "accepted_per_wave = 0"));
  err = Expect({"run", config()}, kConfig);
  EXPECT_NE(err.find("config.toml:15"), std::string::npos) << err;
  EXPECT_NE(err.find("accepted_per_wave"), std::string::npos) << err;
}

TEST_F(BadInput, CsvWithNaN) {
  Write("data.csv", Replace(GoodCsv(), "50,", "50,nan\n51,"));
  const auto err = Expect({"run", config()}, kData);
  EXPECT_NE(err.find("data.csv:4"), std::string::npos) << err;
  EXPECT_NE(err.find("w_m"), std::string::npos) << err;
}

TEST_F(BadInput, CsvMissingColumn) {
  Write("data.csv", Replace(GoodCsv(), "x_cm,w_m", "x_cm,displacement"));
  const auto err = Expect({"run", config()}, kData);
  EXPECT_NE(err.find("data.csv:1"), std::string::npos) << err;
  EXPECT_NE(err.find("w_m"), std::string::npos) << err;
}

TEST_F(BadInput, CsvUnsortedOrDuplicatePositions) {
  Write("data.csv", Replace(GoodCsv(), "50,", "49,"));  // duplicate 49
  auto err = Expect({"run", config()}, kData);
  EXPECT_NE(err.find("data.csv:4"), std::string::npos) << err;
  Write("data.csv", Replace(GoodCsv(), "50,", "47,"));  // goes backwards
  err = Expect({"run", config()}, kData);
  EXPECT_NE(err.find("data.csv:4"), std::string::npos) << err;
}

// Regression (issue 20, D8): a comment cell with unquoted commas shifted the row and the run went
// on (exit 0) with wrong data; a repeated header name was used silently.
TEST_F(BadInput, CsvRowWiderThanTheHeaderOrRepeatedColumn) {
  std::string csv = "x_cm,w_m,note\n";
  for (int x = 48; x <= 80; ++x) {
    csv += std::to_string(x) + "," + std::to_string(1e-6 / (1.0 + (x - 48) * 0.2)) +
           (x == 50 ? ",scan 7, 48, 3,\n" : ",ok\n");
  }
  Write("data.csv", csv);
  auto err = Expect({"run", config()}, kData);
  EXPECT_NE(err.find("data.csv:4:4: row has 6 cells; the header has 3"), std::string::npos) << err;
  Write("data.csv", Replace(GoodCsv(), "x_cm,w_m", "x_cm,w_m,w_m"));
  err = Expect({"run", config()}, kData);
  EXPECT_NE(err.find("data.csv:1:3: w_m: duplicate column name (also column 2)"), std::string::npos)
      << err;
}

TEST_F(BadInput, WindowOutsideTheData) {
  Write("config.toml", Replace(kConfigText, "window = [48, 80]", "window = [30, 80]"));
  const auto err = Expect({"run", config()}, kData);
  EXPECT_NE(err.find("window"), std::string::npos) << err;
}

TEST_F(BadInput, ClampStringOfTheWrongLength) {
  auto err = Expect({"simulate", config(), "--clamps", "0101", "-o", dir_ / "p.csv"}, kUsage);
  EXPECT_NE(err.find("--clamps"), std::string::npos) << err;
  err = Expect({"simulate", config(), "--clamps", std::string(35, '0') + "x", "-o", dir_ / "p.csv"},
               kUsage);
  EXPECT_FALSE(fs::exists(dir_.path() / "p.csv"));
}

TEST_F(BadInput, ReadOnlyOutputDirectory) {
  // Root ignores permission bits, so as root use /proc, where nobody may create files.
  std::string target = "/proc/combabc-readonly";
  if (::geteuid() != 0) {
    fs::create_directories(dir_.path() / "ro");
    fs::permissions(dir_.path() / "ro", fs::perms::owner_read | fs::perms::owner_exec);
    target = dir_ / "ro";
  }
  const auto err = Expect({"run", config(), "-o", target}, kCantCreate);
  EXPECT_NE(err.find(target), std::string::npos) << err;
  if (::geteuid() != 0) {
    fs::permissions(dir_.path() / "ro", fs::perms::owner_all);
    EXPECT_TRUE(fs::is_empty(dir_.path() / "ro"));
  }
}

TEST_F(BadInput, UnknownSubcommandOrMissingArgument) {
  Expect({"frobnicate"}, kUsage);
  Expect({"run"}, kUsage);
}

TEST_F(BadInput, ResumeOfAMissingHistory) {
  const auto err = Expect({"resume", dir_ / "none.sqlite"}, kNoInput);
  EXPECT_NE(err.find("none.sqlite"), std::string::npos) << err;
}

// Out-of-range numbers on the command line (issue D16): refused in one short line naming the
// option, never clamped (a 20-digit budget became INT64_MAX) nor waved through (nan).
TEST_F(BadInput, OutOfRangeOptionValues) {
  const std::string history = dir_ / "none.sqlite";
  for (const std::vector<std::string>& option :
       std::vector<std::vector<std::string>>{{"--max-simulations", "-5"},
                                             {"--max-simulations", "99999999999999999999"},
                                             {"--max-simulations", "12abc"},
                                             {"--max-wall-time", "nan"},
                                             {"--max-wall-time", "-1"},
                                             {"--max-wall-time", "inf"},
                                             {"--min-acceptance-rate", "nan"},
                                             {"--max-failure-fraction", "1.5"}}) {
    const auto err = Expect({"resume", history, option[0], option[1]}, kUsage);
    EXPECT_NE(err.find(option[0]), std::string::npos) << err;
    EXPECT_NE(err.find("'" + option[1] + "'"), std::string::npos) << err;
    EXPECT_LT(err.size(), 200u) << err;
  }
  const auto err = Expect({"enumerate", config(), "--threshold", "nan"}, kUsage);
  EXPECT_NE(err.find("--threshold"), std::string::npos) << err;
}

}  // namespace
}  // namespace combabc::testing
