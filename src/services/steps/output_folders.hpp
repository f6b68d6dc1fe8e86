#pragma once
// The output folder of a run or an enumeration, created before anything is written and removed
// again if nothing was. Private to src/services.
#include <filesystem>
#include <string>
#include <vector>

namespace combabc::services {

// The run's output folder and whichever of its parents were missing, created on the primary and
// removed again (those still empty, deepest first) unless Keep() is called once the history
// exists: a run that fails before it has written anything leaves no folder behind.
class OutputFolders {
 public:
  OutputFolders() = default;
  OutputFolders(const OutputFolders&) = delete;
  OutputFolders& operator=(const OutputFolders&) = delete;
  ~OutputFolders();

  void Create(const std::string& directory);
  void Keep() { created_.clear(); }

 private:
  std::vector<std::filesystem::path> created_;  // deepest first
};

}  // namespace combabc::services
