// The CSV dialect of the input files (data/csv_reader.hpp): RFC 4180 quoting, one width for every
// record, distinct header names, and every error naming file:line:column and the column's name.
#include "combabc/data/csv_reader.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "combabc/core/error.hpp"

namespace combabc {
namespace {

using Rows = std::vector<std::vector<std::string>>;

// Every record after the header, and the line each starts on.
Rows ReadAll(const std::string& text, std::vector<int>* lines = nullptr) {
  CsvReader csv(text, "t.csv");
  csv.ReadHeader();
  Rows rows;
  while (csv.Next()) {
    rows.push_back(csv.cells());
    if (lines != nullptr) lines->push_back(csv.line());
  }
  return rows;
}

// The error reading `text` throws; fails the test if none.
Error ReadError(const std::string& text) {
  try {
    ReadAll(text);
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return Error(ErrorKind::kSoftware, "none");
}

TEST(CsvReader, QuotedCellsHoldCommasDoubledQuotesAndLineBreaks) {
  std::vector<int> lines;
  const Rows rows = ReadAll(
      "a,\"b, c\",d\r\n"
      "\"1,5\",\"say \"\"hi\"\"\",\"\"\r\n"
      "  \"x\" , y ,\"two\r\nlines\"\r\n"
      "\n"
      "# a note between records\n"
      "3,\"\"\"\",5",
      &lines);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"1,5", "say \"hi\"", ""}));
  EXPECT_EQ(rows[1], (std::vector<std::string>{"x", "y", "two\r\nlines"}));
  EXPECT_EQ(rows[2], (std::vector<std::string>{"3", "\"", "5"}));
  // A record is numbered by its first line; the line break inside quotes is counted.
  EXPECT_EQ(lines, (std::vector<int>{2, 3, 7}));
}

TEST(CsvReader, HeaderNamesAreUnquotedAndABomIsDropped) {
  CsvReader csv("\xEF\xBB\xBF# provenance\n\"x, cm\",u,,\n1,2,,\n", "t.csv");
  EXPECT_EQ(csv.ReadHeader(), (std::vector<std::string>{"x, cm", "u", "", ""}));
  EXPECT_EQ(csv.line(), 2);
  ASSERT_TRUE(csv.Next());
  EXPECT_EQ(csv.cells(), (std::vector<std::string>{"1", "2", "", ""}));
  EXPECT_FALSE(csv.Next());
}

// Regression (issue 20, D8): a header name used twice was taken silently, the first one winning.
TEST(CsvReader, ADuplicateHeaderNameIsRefused) {
  const Error e = ReadError("x,u,u\n1,2,3\n");
  EXPECT_EQ(e.kind(), ErrorKind::kData);
  EXPECT_STREQ(e.what(), "t.csv:1:3: u: duplicate column name (also column 2)");
}

// Regression (issue 20, D8): rows with more cells than the header were read.
TEST(CsvReader, EveryRowHasTheHeadersWidth) {
  Error e = ReadError("x,u,note\n1,2,a\n2,3,b, c\n");
  EXPECT_STREQ(e.what(),
               "t.csv:3:4: row has 4 cells; the header has 3 (a comma in an unquoted cell? "
               "enclose such cells in double quotes)");
  e = ReadError("x,u,note\n1,2,a\n2\n");
  EXPECT_STREQ(e.what(), "t.csv:3:2: u: row has 1 cell; the header has 3; the column is missing");
}

TEST(CsvReader, MalformedQuotingNamesLineAndColumn) {
  Error e = ReadError("x,u\n1,2\n3,4\"5\n");
  EXPECT_EQ(e.kind(), ErrorKind::kData);
  EXPECT_EQ(std::string(e.what()).rfind("t.csv:3:2: u: a quote inside an unquoted cell", 0), 0u)
      << e.what();
  e = ReadError("x,u\n\"1\"2,3\n");
  EXPECT_EQ(std::string(e.what()).rfind("t.csv:2:1: x: text after the closing quote", 0), 0u)
      << e.what();
  e = ReadError("x,u\n1,2\n3,\"4\n5,6\n");
  EXPECT_STREQ(e.what(), "t.csv:3:2: u: quoted cell not closed: the file ends inside it");
  e = ReadError("");
  EXPECT_STREQ(e.what(), "t.csv:1: empty file (no header row)");
}

TEST(CsvReader, WithoutAHeaderTheFirstRecordSetsTheWidth) {
  CsvReader csv("1,a\n2,b\n3\n", "t.csv");
  ASSERT_TRUE(csv.Next());
  ASSERT_TRUE(csv.Next());
  EXPECT_EQ(csv.cells(), (std::vector<std::string>{"2", "b"}));
  try {
    csv.Next();
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "t.csv:3:2: row has 1 cell; the first row has 2; the column is missing");
  }
}

TEST(CsvReader, AHeaderOfTooManyColumnsIsRefused) {
  const Error e = ReadError(std::string(kMaxCsvColumns, ',') + "\n");
  EXPECT_EQ(e.line(), 1);
  EXPECT_NE(std::string(e.what()).find("more than 100000 columns"), std::string::npos) << e.what();
  // At the limit it is read.
  const std::string widest = std::string(kMaxCsvColumns - 1, ',') + "\n";
  CsvReader csv(widest, "t.csv");
  EXPECT_EQ(csv.ReadHeader().size(), kMaxCsvColumns);
}

}  // namespace
}  // namespace combabc
