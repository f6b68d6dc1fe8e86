// combabc::Error is the one place user input reaches the terminal: it must stay one short,
// printable line whatever the input holds.
#include "combabc/core/error.hpp"
#include "combabc/core/validation_error.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace combabc {
namespace {

bool HasRawControlCharacter(const std::string& text) {
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte == 0x7f) return true;
  }
  return false;
}

TEST(Printable, EscapesControlCharactersAndInvalidUtf8) {
  EXPECT_EQ(Printable("plain text 1.5 m"), "plain text 1.5 m");
  EXPECT_EQ(Printable("\x1b[2J"), "\\x1b[2J");  // ANSI "clear screen"
  EXPECT_EQ(Printable(std::string("a\0b", 3)), "a\\0b");
  EXPECT_EQ(Printable("a\nb\rc\td\x7f"), "a\\nb\\rc\\td\\x7f");
  EXPECT_EQ(Printable("\xc2\x9b"), "\\xc2\\x9b");  // C1 CSI, a terminal escape too
  EXPECT_EQ(Printable("\xff\xfe"), "\\xff\\xfe");  // not UTF-8
  EXPECT_EQ(Printable("\xc0\xaf"), "\\xc0\\xaf");  // overlong '/'
  EXPECT_EQ(Printable("\xe2\x82"), "\\xe2\\x82");  // truncated sequence
  EXPECT_EQ(Printable("5 \xc2\xb5m \xe2\x82\xac"), "5 \xc2\xb5m \xe2\x82\xac");  // µm €
}

TEST(Printable, CutsOnACharacterBoundary) {
  EXPECT_EQ(Printable("abcdef", 3), "abc...");
  EXPECT_EQ(Printable("ab\xc2\xb5", 3), "ab...");  // never half of µ
  EXPECT_EQ(Printable("a\x1b", 3), "a...");        // never half of \x1b
}

TEST(Excerpt, QuotesAShortPrintablePiece) {
  EXPECT_EQ(Excerpt("abc"), "'abc'");
  const std::string long_line(10000, 'x');
  EXPECT_LT(Excerpt(long_line).size(), 50u);
}

// Regression: messages echoed raw input (ANSI escapes, NUL bytes, whole lines of a file).
TEST(Error, WhatIsOneShortPrintableLine) {
  const std::string hostile = "\x1b]0;owned\x07" + std::string(100000, 'y') + "\n\x1b[31m";
  const Error e(ErrorKind::kConfig, "bad " + hostile, "dir/\x1b[1mcfg.toml", 3, "key\nnext");
  const std::string what = e.what();
  EXPECT_FALSE(HasRawControlCharacter(what)) << what;
  EXPECT_LT(what.size(), 1200u);
  EXPECT_EQ(what.rfind("dir/\\x1b[1mcfg.toml:3: key\\nnext: bad \\x1b]0;owned\\x07yyy", 0), 0u)
      << what;
  // The raw parts stay available to code that re-throws with more context.
  EXPECT_EQ(e.message(), "bad " + hostile);
}

TEST(Error, ColumnFollowsTheLine) {
  EXPECT_STREQ(Error(ErrorKind::kData, "not a number", "d.csv", 4, "w", 2).what(),
               "d.csv:4:2: w: not a number");
  EXPECT_STREQ(Error(ErrorKind::kData, "empty", "d.csv", 4, "w").what(), "d.csv:4: w: empty");
}

// The sentence of a failed check is made of its parts, with or without a value or an owner.
TEST(ValidationError, MessageFromItsParts) {
  const ValidationError load{"SensorOptions", "load_x", "1.2", "must be in [0, 0.9] m"};
  EXPECT_EQ(load.Message(), "SensorOptions::load_x = 1.2; must be in [0, 0.9] m");
  EXPECT_EQ(load.Detail(), "load_x = 1.2; must be in [0, 0.9] m");
  EXPECT_EQ(load.Member(), "load_x");
  const ValidationError tie{"BinarySpaceOptions", "tied[2]", "", "has fewer than 2 bits"};
  EXPECT_EQ(tie.Message(), "BinarySpaceOptions::tied[2] has fewer than 2 bits");
  EXPECT_EQ(tie.Member(), "tied");
  const ValidationError schedule{"", "values[1]", "0.5 > values[0]", "must not increase"};
  EXPECT_EQ(schedule.Message(), "values[1] = 0.5 > values[0]; must not increase");
  EXPECT_EQ((ValidationError{"SensorOptions", "layers[1]::density", "0", "x"}).Member(), "layers");
  EXPECT_EQ((ValidationError{"SmcOptions", "tempering.values", "", "x"}).Member(), "tempering");
}

TEST(ValidationError, ExplainWritesTheSentenceOnlyOnFailure) {
  const ValidationError e{"X", "y", "1", "must be 0"};
  std::string why = "untouched";
  EXPECT_TRUE(ExplainValidation(true, e, &why));
  EXPECT_EQ(why, "untouched");
  EXPECT_FALSE(ExplainValidation(false, e, &why));
  EXPECT_EQ(why, "X::y = 1; must be 0");
  EXPECT_FALSE(ExplainValidation(false, e, nullptr));
}

}  // namespace
}  // namespace combabc
