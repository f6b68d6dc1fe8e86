#include "services/steps/output_folders.hpp"

#include <system_error>

#include "combabc/core/error.hpp"

namespace combabc::services {
namespace fs = std::filesystem;

OutputFolders::~OutputFolders() {
  std::error_code ec;
  for (const fs::path& folder : created_) fs::remove(folder, ec);  // only if empty
}

void OutputFolders::Create(const std::string& directory) {
  std::error_code ec;
  for (fs::path folder = directory; !folder.empty() && !fs::exists(folder, ec);
       folder = folder.parent_path()) {
    created_.push_back(folder);
    if (folder == folder.parent_path()) break;
  }
  fs::create_directories(directory, ec);
  if (ec) {
    throw Error(
        ErrorKind::kCantCreate, "cannot create output directory: " + ec.message(), directory);
  }
}

}  // namespace combabc::services
