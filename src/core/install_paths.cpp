#include "combabc/core/install_paths.hpp"

#include <dlfcn.h>
#include <link.h>

#include <algorithm>

#include <system_error>

// Set by src/CMakeLists.txt: the install layout's relative paths, and the trees of this build.
#ifndef COMBABC_DATA_FROM_BINDIR
#define COMBABC_DATA_FROM_BINDIR "../share/combabc"
#endif
#ifndef COMBABC_DATA_FROM_LIBDIR
#define COMBABC_DATA_FROM_LIBDIR "../share/combabc"
#endif
#ifndef COMBABC_DATA_FROM_PYTHONDIR  // from the package directory combabc/; "" when not relative
#define COMBABC_DATA_FROM_PYTHONDIR ""
#endif
#ifndef COMBABC_SOURCE_TREE
#define COMBABC_SOURCE_TREE ""
#endif
#ifndef COMBABC_BUILD_TREE
#define COMBABC_BUILD_TREE ""
#endif

namespace combabc {
namespace fs = std::filesystem;
namespace {

fs::path Executable() {
  std::error_code ec;
  fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : exe;
}

// The shared object this function was loaded from, or an empty path when it is linked into the
// executable itself (a static libcombabc): the main program's link map has an empty name.
fs::path SharedObject() {
  Dl_info info{};
  link_map* map = nullptr;
  void* self = reinterpret_cast<void*>(&SharedObject);  // NOLINT(*-reinterpret-cast): dladdr's API
  if (dladdr1(self, &info, reinterpret_cast<void**>(&map), RTLD_DL_LINKMAP) == 0 ||
      map == nullptr || map->l_name == nullptr || map->l_name[0] == '\0') {
    return {};
  }
  std::error_code ec;
  fs::path path = fs::canonical(map->l_name, ec);
  return ec ? fs::path() : path;
}

bool InTree(const fs::path& file, const char* tree) {
  if (*tree == '\0' || file.empty()) return false;
  std::error_code ec;
  const fs::path root = fs::weakly_canonical(tree, ec);
  if (ec) return false;
  // `file` lies under `root` when every component of root begins it.
  return std::mismatch(root.begin(), root.end(), file.begin(), file.end()).first == root.end();
}

void Add(std::vector<fs::path>& out,
         const fs::path& dir,
         const char* step,
         const std::string& relative) {
  if (dir.empty() || *step == '\0') return;
  const fs::path candidate = (dir / step / relative).lexically_normal();
  for (const fs::path& seen : out) {
    if (seen == candidate) return;
  }
  out.push_back(candidate);
}

}  // namespace

std::vector<fs::path> DataFileCandidates(const std::string& relative,
                                         const std::string& source_relative) {
  std::vector<fs::path> out;
  const fs::path exe = Executable();
  const fs::path object = SharedObject();
  // The binary holding this code: a build-tree one reads the source tree first, even when an
  // installed combabc is beside the executable (python3 from the build tree, /usr installed).
  if (InTree(object.empty() ? exe : object, COMBABC_BUILD_TREE)) {
    Add(out, COMBABC_SOURCE_TREE, ".", source_relative);
  }
  // Its own install first: a shared libcombabc_*.so in lib/, the Python module in its package.
  const std::string name = object.filename().string();
  if (name.rfind("libcombabc", 0) == 0) {
    Add(out, object.parent_path(), COMBABC_DATA_FROM_LIBDIR, relative);
  } else if (name.rfind("_core", 0) == 0) {
    Add(out, object.parent_path(), COMBABC_DATA_FROM_PYTHONDIR, relative);
  }
  Add(out, exe.parent_path(), COMBABC_DATA_FROM_BINDIR, relative);
  return out;
}

fs::path FindDataFile(const std::vector<fs::path>& candidates) {
  for (const fs::path& candidate : candidates) {
    std::error_code ec;
    if (fs::is_regular_file(candidate, ec)) return candidate;
  }
  return {};
}

std::string DescribeCandidates(const std::vector<fs::path>& candidates) {
  std::string text;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (i > 0) text += i + 1 == candidates.size() ? " or " : ", ";
    text += candidates[i].string();
  }
  return text.empty() ? "nowhere (no executable path)" : text;
}

}  // namespace combabc
