#pragma once
// The folder inside a run's output folder where external simulators work: each call or worker
// gets a fresh subfolder that combabc creates (never one that already existed) and removes with
// everything the program put in it. The folder itself is removed at the end only when combabc
// created it and it is empty again; nothing else is ever deleted.
#include <atomic>
#include <string>

namespace combabc {

class WorkDirectory {
 public:
  explicit WorkDirectory(std::string path);  // created when absent (kCantCreate if it cannot be)
  ~WorkDirectory();
  WorkDirectory(const WorkDirectory&) = delete;
  WorkDirectory& operator=(const WorkDirectory&) = delete;
  const std::string& path() const { return path_; }
  // A new, empty subfolder "<prefix>-<n>"; throws std::runtime_error when none can be made.
  std::string MakeSubfolder(const std::string& prefix) const;
  // Removes a subfolder MakeSubfolder returned, with its contents (symbolic links not followed).
  static void Remove(const std::string& subfolder);

 private:
  std::string path_;
  bool created_ = false;
  mutable std::atomic<long long> next_{0};
};

}  // namespace combabc
