#include "combabc/simulators/work_directory.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "combabc/core/error.hpp"

namespace combabc {
namespace fs = std::filesystem;

WorkDirectory::WorkDirectory(std::string path) : path_(std::move(path)) {
  if (::mkdir(path_.c_str(), 0755) == 0) {
    created_ = true;
  } else if (errno != EEXIST || !fs::is_directory(path_)) {
    throw Error(ErrorKind::kCantCreate,
                std::string("cannot create the simulator's work folder: ") + std::strerror(errno),
                path_);
  }
}

WorkDirectory::~WorkDirectory() {
  // rmdir, not remove_all: a folder combabc created but that is not empty holds something left
  // there by someone else (or a subfolder that could not be removed): keep it.
  if (created_) ::rmdir(path_.c_str());
}

std::string WorkDirectory::MakeSubfolder(const std::string& prefix) const {
  for (int attempt = 0; attempt < 1000; ++attempt) {
    std::string sub = path_ + "/" + prefix + "-" + std::to_string(next_.fetch_add(1));
    // mkdir fails on anything that exists: a subfolder left by an earlier, killed run is never
    // reused (nor deleted).
    if (::mkdir(sub.c_str(), 0755) == 0) return sub;
    if (errno != EEXIST) {
      throw std::runtime_error("cannot create a work folder in " + path_ + ": " +
                               std::strerror(errno));
    }
  }
  throw std::runtime_error("cannot create a work folder in " + path_ + ": all names taken");
}

void WorkDirectory::Remove(const std::string& subfolder) {
  std::error_code ec;
  fs::remove_all(subfolder, ec);  // best effort: a leftover folder is harmless
}

}  // namespace combabc
