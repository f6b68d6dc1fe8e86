#pragma once
// The one-line error a config text gets from ParseConfig, as "dir/run.toml" (checked to be a
// config error), or "no error" when it parses.
#include <gtest/gtest.h>

#include <string>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"

namespace combabc::testing {

inline std::string ConfigErrorOf(const std::string& text) {
  try {
    ParseConfig(text, "dir/run.toml");
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kConfig);
    return e.what();
  }
  return "no error";
}

}  // namespace combabc::testing
