#pragma once
// What the tests of every layer share: a temporary folder of their own, and closeness checks for
// vectors. Header-only: every test executable includes what it uses (tests/ is on its include
// path, so "support/test_support.hpp").
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstddef>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

namespace combabc::testing {

// Under a sanitizer (ASan + UBSan, TSan: COMBABC_TEST_SANITIZED) a test's repeated random draws
// check memory, undefined behaviour and races on code paths that the first few draws already
// take; their number is for the optimised build, where it is the test's statistical power.
// Under a sanitizer: a quarter of `n`, never fewer than min(n, at_least) (docs/ci.md).
#ifdef COMBABC_TEST_SANITIZED
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
constexpr int Repetitions(int n, int at_least = 3) {
  if (!kSanitized) return n;
  const int floor = n < at_least ? n : at_least;
  return n / 4 > floor ? n / 4 : floor;
}
// A loop's step over checkpoints, bytes, ...: four times wider under a sanitizer.
constexpr int Stride(int step) { return kSanitized ? 4 * step : step; }

// A fresh, empty folder under the system's temporary directory, "combabc-<name>-<pid>" (the pid:
// ctest runs the tests of one executable as parallel processes), removed with everything in it
// when it goes out of scope, folders the test made read-only included.
class TempFolder {
 public:
  explicit TempFolder(const std::string& name)
      : path_(std::filesystem::temp_directory_path() /
              ("combabc-" + name + "-" + std::to_string(::getpid()))) {
    Remove(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempFolder() { Remove(path_); }
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::string operator/(const std::string& name) const { return (path_ / name).string(); }

 private:
  // Gives the owner back every folder's permissions first: a test may have taken them away to
  // check a refusal. Never throws (a destructor calls it).
  static void Remove(const std::filesystem::path& path) {
    namespace fs = std::filesystem;
    std::error_code ignored;
    if (!fs::is_directory(fs::symlink_status(path, ignored))) {
      fs::remove(path, ignored);
      return;
    }
    fs::permissions(path, fs::perms::owner_all, fs::perm_options::add, ignored);
    for (fs::directory_iterator it(path, ignored), end; it != end; it.increment(ignored)) {
      if (fs::is_directory(it->symlink_status(ignored))) Remove(it->path());
    }
    fs::remove_all(path, ignored);
  }

  std::filesystem::path path_;
};

// EXPECT_NEAR for every value of `actual` against `expected` (sizes first), each failure naming
// `what` and the index.
inline void ExpectNear(const std::vector<double>& actual,
                       const std::vector<double>& expected,
                       double tolerance,
                       const std::string& what) {
  ASSERT_EQ(actual.size(), expected.size()) << what << ": sizes differ";
  for (std::size_t i = 0; i < actual.size(); ++i) {
    EXPECT_NEAR(actual[i], expected[i], tolerance) << what << ", index " << i;
  }
}

}  // namespace combabc::testing
