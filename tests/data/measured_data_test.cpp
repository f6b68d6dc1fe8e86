#include "combabc/data/measured_data.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "combabc/core/error.hpp"
#include "support/test_support.hpp"

namespace combabc {
namespace {

constexpr double kTol = 1e-12;

DataConfig CentimetreConfig() {
  DataConfig c;
  c.position_column = "x_cm";
  c.displacement_column = "u";
  c.position_unit = LengthUnit::kCentimetre;
  c.displacement_unit = LengthUnit::kMicrometre;
  return c;
}

// Runs ParseMeasuredData and returns the error it throws (fails the test if none).
Error ParseError(const std::string& text, const DataConfig& config = CentimetreConfig()) {
  try {
    ParseMeasuredData(text, "profile.csv", config);
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return Error(ErrorKind::kSoftware, "none");
}

TEST(MeasuredData, ReadsAnyColumnOrderConvertsUnitsAndNormalises) {
  const std::string text =
      "extra,u,x_cm\n"
      "a,1.0,48\n"
      "\n"
      "b,4.0,49\n"
      "c,2.0,50\n";
  const MeasuredData d = ParseMeasuredData(text, "profile.csv", CentimetreConfig());
  ASSERT_EQ(d.size(), 3u);
  EXPECT_NEAR(d.positions[0], 0.48, kTol);
  EXPECT_NEAR(d.positions[2], 0.50, kTol);
  EXPECT_TRUE(d.normalised);
  EXPECT_NEAR(d.scale, 4.0e-6, 1e-18);  // the maximum, in metres
  EXPECT_NEAR(d.displacements[0], 0.25, kTol);
  EXPECT_NEAR(d.displacements[1], 1.0, kTol);
  EXPECT_EQ(d.synthetic, (std::vector<std::uint8_t>{0, 0, 0}));
}

TEST(MeasuredData, WithoutNormalisationKeepsMetres) {
  DataConfig c = CentimetreConfig();
  c.normalise = false;
  const MeasuredData d = ParseMeasuredData("x_cm,u\n1,2\n2,3\n", "p.csv", c);
  EXPECT_FALSE(d.normalised);
  EXPECT_NEAR(d.displacements[1], 3e-6, 1e-18);
}

TEST(MeasuredData, WindowKeepsRowsInside) {
  DataConfig c = CentimetreConfig();
  c.window_min = 0.49;
  c.window_max = 0.50;
  const MeasuredData d = ParseMeasuredData("x_cm,u\n48,1\n49,2\n50,3\n51,4\n", "p.csv", c);
  ASSERT_EQ(d.size(), 2u);
  EXPECT_NEAR(d.positions[0], 0.49, kTol);
  EXPECT_NEAR(d.displacements[0], 2.0 / 3.0, kTol);  // normalised over the window
}

TEST(MeasuredData, MissingColumnNamesFileLineAndColumn) {
  const Error e = ParseError("x_cm,v\n1,2\n");
  EXPECT_EQ(e.kind(), ErrorKind::kData);
  EXPECT_EQ(e.field(), "u");
  EXPECT_NE(std::string(e.what()).find("profile.csv:1: u: missing column"), std::string::npos)
      << e.what();
}

TEST(MeasuredData, NonNumericNanAndInfiniteCells) {
  Error e = ParseError("x_cm,u\n1,2\n2,abc\n");
  EXPECT_EQ(e.kind(), ErrorKind::kData);
  EXPECT_NE(std::string(e.what()).find("profile.csv:3:2: u: not a number"), std::string::npos)
      << e.what();
  e = ParseError("x_cm,u\n1,2\n2,3\nnan,4\n");
  EXPECT_NE(std::string(e.what()).find("profile.csv:4:1: x_cm: value is NaN"), std::string::npos)
      << e.what();
  e = ParseError("x_cm,u\n1,inf\n");
  EXPECT_NE(std::string(e.what()).find("profile.csv:2:2: u: value is infinite"), std::string::npos)
      << e.what();
  e = ParseError("x_cm,u\n1,\n");
  EXPECT_NE(std::string(e.what()).find("profile.csv:2:2: u: empty cell"), std::string::npos)
      << e.what();
  e = ParseError("x_cm,u\n1\n");
  EXPECT_NE(std::string(e.what()).find("profile.csv:2:2: u: row has 1 cell"), std::string::npos)
      << e.what();
}

// Regression: a number followed by text, text in a numeric column, hex and inner blanks are each
// refused naming file:line:column, never read as a prefix or as 0.
TEST(MeasuredData, OnlyWholeNumbersAreNumbers) {
  for (const char* cell : {"abc", "1.5abc", "0x10", "1 2", "--1", "+", "1e", "1.2.3"}) {
    const Error e = ParseError(std::string("x_cm,extra,u\n1,a,2\n2,b,") + cell + "\n");
    EXPECT_EQ(e.kind(), ErrorKind::kData) << cell;
    EXPECT_EQ(e.column(), 3) << cell;
    EXPECT_NE(std::string(e.what()).find("profile.csv:3:3: u: not a number"), std::string::npos)
        << cell << ": " << e.what();
  }
  const Error e = ParseError("x_cm,u\n1,2\n2,1e999\n");
  EXPECT_NE(std::string(e.what()).find("profile.csv:3:2: u: number out of range"),
            std::string::npos)
      << e.what();
  // Leading '+' and surrounding blanks are fine.
  const auto data = ParseMeasuredData("x_cm,u\n1, +2 \n2,\t-1e-1\n", "p.csv", CentimetreConfig());
  ASSERT_EQ(data.size(), 2u);
  EXPECT_NEAR(data.displacements[0], 1.0, kTol);
}

// Regression: a CSV with CR-only line ends (classic Mac exports) was one long header line and
// reported as having no data; CRLF and LF must read the same.
TEST(MeasuredData, CrLfAndCrOnlyLineEndsReadLikeLf) {
  const std::string lf = "# note\nx_cm,u\n1,1\n\n2,2\n3,4\n";
  const auto reference = ParseMeasuredData(lf, "p.csv", CentimetreConfig());
  for (const char* end : {"\r\n", "\r"}) {
    std::string text;
    for (char c : lf) {
      if (c == '\n') {
        text += end;
      } else {
        text += c;
      }
    }
    const auto data = ParseMeasuredData(text, "p.csv", CentimetreConfig());
    EXPECT_EQ(data.positions, reference.positions) << ::testing::PrintToString(end);
    EXPECT_EQ(data.displacements, reference.displacements);
    // Line numbers count the same way: row "3,x" is line 6 whatever the line end.
    const Error e = ParseError(text + "3.5,x" + end);
    EXPECT_NE(std::string(e.what()).find("profile.csv:7:2: u:"), std::string::npos) << e.what();
  }
  // The last line needs no line end.
  EXPECT_EQ(ParseMeasuredData("x_cm,u\r1,1\r2,2", "p.csv", CentimetreConfig()).size(), 2u);
}

// Regression: a missing column echoed the whole header line, which for a mistaken path may be a
// line of another file; only a few short excerpts are quoted now.
TEST(MeasuredData, MissingColumnQuotesOnlyShortExcerptsOfTheHeader) {
  std::string header = std::string(200, 's') + ",\x1b[31mred";
  for (int k = 0; k < 20; ++k) header += ",c" + std::to_string(k);
  const Error e = ParseError(header + "\n1,2\n");
  const std::string what = e.what();
  EXPECT_LT(what.size(), 400u) << what;
  EXPECT_EQ(what.find('\x1b'), std::string::npos) << what;
  EXPECT_NE(what.find("\\x1b[31mred"), std::string::npos) << what;
  EXPECT_NE(what.find(", ..."), std::string::npos) << what;
}

// Regression (issue 20, D8): commas inside a quoted comment cell split it, so every row's "48"
// and "3" were read as position and displacement: the profile came out as all 1.0 (normalised)
// and the run went on. RFC 4180 quoting keeps the comment one cell.
TEST(MeasuredData, QuotedCellsMayHoldCommasQuotesAndLineBreaks) {
  const MeasuredData d = ParseMeasuredData(
      "comment,x_cm,u\n"
      "\"scan 7, 48, 3,\",48,72.89\n"
      "\"scan 8, 49, 3,\",49,145.78\n"
      "\"scan 9, 50, 3,\",50,36.445\n",
      "profile.csv",
      CentimetreConfig());
  ASSERT_EQ(d.size(), 3u);
  EXPECT_NEAR(d.positions[0], 0.48, kTol);
  EXPECT_NEAR(d.positions[2], 0.50, kTol);
  EXPECT_NEAR(d.scale, 145.78e-6, 1e-18);
  EXPECT_NEAR(d.displacements[0], 0.5, kTol);
  EXPECT_NEAR(d.displacements[1], 1.0, kTol);
  EXPECT_NEAR(d.displacements[2], 0.25, kTol);
  // Doubled quotes, a line break inside quotes, CRLF: the rows after it keep their line numbers.
  const MeasuredData n = ParseMeasuredData(
      "comment,x_cm,u\r\n"
      "\"a \"\"quoted\"\" note\r\nover two lines\",48,1\r\n"
      "\"\",49,2\r\n",
      "profile.csv",
      CentimetreConfig());
  ASSERT_EQ(n.size(), 2u);
  EXPECT_NEAR(n.displacements[0], 0.5, kTol);
  EXPECT_NE(std::string(ParseError("comment,x_cm,u\r\n\"a\r\nb\",48,1\r\n\"\",48,2\r\n").what())
                .find("profile.csv:4:2: x_cm: duplicate position '48' after line 2"),
            std::string::npos);
  // A quoted number is a number; blanks inside the quotes are trimmed like those outside.
  const MeasuredData q =
      ParseMeasuredData("\"x_cm\",\"u\"\n\"1\",\" 2 \"\n", "p.csv", CentimetreConfig());
  ASSERT_EQ(q.size(), 1u);
  EXPECT_NEAR(q.positions[0], 0.01, kTol);
}

// Regression (issue 20, D8): rows wider than the header were read (the reproducer above without
// quotes still ran), and a comma in an unquoted cell blamed the next column.
TEST(MeasuredData, EveryRowHasTheHeadersCellsAndHeaderNamesAreDistinct) {
  Error e = ParseError("comment,x_cm,u\nscan 7, 48, 3,,48,72.89\n");
  EXPECT_EQ(e.kind(), ErrorKind::kData);
  EXPECT_NE(std::string(e.what()).find("profile.csv:2:4: row has 6 cells; the header has 3"),
            std::string::npos)
      << e.what();
  e = ParseError("x_cm,u\n1,2,3\n");
  EXPECT_NE(std::string(e.what()).find("profile.csv:2:3: row has 3 cells; the header has 2"),
            std::string::npos)
      << e.what();
  e = ParseError("x_cm,u,u\n1,2,3\n");
  EXPECT_STREQ(e.what(), "profile.csv:1:3: u: duplicate column name (also column 2)");
  e = ParseError("x_cm,u\n1,2\n2,\"3\n");
  EXPECT_STREQ(e.what(), "profile.csv:3:2: u: quoted cell not closed: the file ends inside it");
  e = ParseError("x_cm,u\n1,2\n2,3\"\n");
  EXPECT_NE(std::string(e.what()).find("profile.csv:3:2: u: a quote inside an unquoted cell"),
            std::string::npos)
      << e.what();
}

TEST(MeasuredData, UnsortedAndDuplicatePositions) {
  Error e = ParseError("x_cm,u\n1,2\n3,3\n2,4\n");
  EXPECT_EQ(e.kind(), ErrorKind::kData);
  EXPECT_EQ(e.line(), 4);
  EXPECT_NE(std::string(e.what()).find("profile.csv:4:1: x_cm: positions must increase"),
            std::string::npos)
      << e.what();
  e = ParseError("x_cm,u\n1,2\n1,3\n");
  EXPECT_NE(std::string(e.what()).find("profile.csv:3:1: x_cm: duplicate position"),
            std::string::npos)
      << e.what();
}

TEST(MeasuredData, EmptyFileAndNoRows) {
  Error e = ParseError("");
  EXPECT_EQ(e.kind(), ErrorKind::kData);
  EXPECT_NE(std::string(e.what()).find("profile.csv:1: empty file"), std::string::npos) << e.what();
  e = ParseError("x_cm,u\n\n");
  EXPECT_NE(std::string(e.what()).find("no data rows"), std::string::npos) << e.what();
}

TEST(MeasuredData, WindowOutsideDataIsAnError) {
  DataConfig c = CentimetreConfig();
  c.window_min = 0.47;
  c.window_max = 0.50;
  const Error e = ParseError("x_cm,u\n48,1\n49,2\n50,3\n", c);
  EXPECT_EQ(e.kind(), ErrorKind::kData);
  EXPECT_EQ(e.field(), "data.window");
  EXPECT_NE(std::string(e.what()).find("profile.csv: data.window: window"), std::string::npos)
      << e.what();
}

TEST(MeasuredData, AllZeroCannotBeNormalised) {
  const Error e = ParseError("x_cm,u\n48,0\n49,0\n");
  EXPECT_EQ(e.kind(), ErrorKind::kData);
}

TEST(MeasuredData, LoadsRelativeToConfigDirAndReportsMissingFile) {
  const testing::TempFolder dir("measured-data-test");
  {
    std::ofstream f(dir / "p.csv");
    f << "x_cm,u\n1,1\n2,2\n";
  }
  DataConfig c = CentimetreConfig();
  c.csv = "p.csv";
  const MeasuredData d = LoadMeasuredData(c, dir.path().string());
  EXPECT_EQ(d.size(), 2u);
  EXPECT_EQ(d.source, dir / "p.csv");

  c.csv = "does_not_exist.csv";
  try {
    LoadMeasuredData(c, dir.path().string());
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kNoInput);
    EXPECT_NE(std::string(e.what()).find("does_not_exist.csv"), std::string::npos) << e.what();
  }
}

TEST(MeasuredData, GaussianExtensionFillsTheGapToTheImpact) {
  // Exact Gaussian samples at 74..80 cm, impact at 70 cm (the paper's Figure 7 situation).
  const double a = 3.0, s = 0.03, x0 = 0.70;
  std::string text = "x_cm,u\n";
  for (int cm = 74; cm <= 80; ++cm) {
    const double x = cm * 0.01;
    text += std::to_string(cm) + "," +
            std::to_string(a * std::exp(-(x - x0) * (x - x0) / (2 * s * s))) + "\n";
  }
  DataConfig c = CentimetreConfig();
  c.gaussian_extension.enabled = true;
  c.gaussian_extension.impact_position = x0;
  c.gaussian_extension.fit_points = 3;
  c.gaussian_extension.spacing = 0.01;
  const MeasuredData d = ParseMeasuredData(text, "p.csv", c);
  ASSERT_EQ(d.size(), 11u);  // 70, 71, 72, 73 synthetic + 74..80 measured
  EXPECT_NEAR(d.positions[0], 0.70, kTol);
  EXPECT_NEAR(d.positions[3], 0.73, kTol);
  EXPECT_EQ(d.synthetic[3], 1);
  EXPECT_EQ(d.synthetic[4], 0);
  EXPECT_NEAR(d.displacements[0], 1.0, 1e-6);  // the peak is at the impact
  ASSERT_TRUE(d.gaussian_fit.has_value());
  EXPECT_NEAR(d.gaussian_fit->width, s, 1e-4);  // the CSV text carries 6 significant digits
}

}  // namespace
}  // namespace combabc
