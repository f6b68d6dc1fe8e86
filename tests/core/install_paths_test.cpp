// Run-time files of a build-tree binary: the source tree first, then the install layout's places
// relative to the executable; the description names every place looked at.
#include "combabc/core/install_paths.hpp"

#include <gtest/gtest.h>

#include <filesystem>

namespace combabc {
namespace {
namespace fs = std::filesystem;

TEST(InstallPaths, BuildTreeBinaryFindsTheSourceTreeFileFirst) {
  const auto candidates =
      DataFileCandidates("report/combabc_report.py", "scripts/report/combabc_report.py");
  ASSERT_GE(candidates.size(), 2u);
  const fs::path source = fs::path(COMBABC_SOURCE_DIR) / "scripts/report/combabc_report.py";
  EXPECT_EQ(fs::weakly_canonical(candidates.front()), fs::weakly_canonical(source));
  EXPECT_EQ(fs::weakly_canonical(FindDataFile(candidates)), fs::weakly_canonical(source));
  // The executable's place comes last: <this test's dir>/../share/combabc/report/...
  const fs::path exe = fs::read_symlink("/proc/self/exe");
  EXPECT_EQ(candidates.back(),
            (exe.parent_path() / "../share/combabc/report/combabc_report.py").lexically_normal());
}

TEST(InstallPaths, MissingFileIsNotFoundAndEveryPlaceIsDescribed) {
  const auto candidates = DataFileCandidates("no/such.file", "no/such.file");
  EXPECT_TRUE(FindDataFile(candidates).empty());
  const std::string text = DescribeCandidates(candidates);
  for (const fs::path& candidate : candidates) {
    EXPECT_NE(text.find(candidate.string()), std::string::npos) << text;
  }
  EXPECT_EQ(DescribeCandidates({"a", "b", "c"}), "a, b or c");
  EXPECT_EQ(DescribeCandidates({"a"}), "a");
}

}  // namespace
}  // namespace combabc
