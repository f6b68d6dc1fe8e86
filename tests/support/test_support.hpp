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
