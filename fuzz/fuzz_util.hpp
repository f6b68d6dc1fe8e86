#pragma once
// Shared by the fuzz targets (docs/fuzzing.md): a private scratch directory per process for the
// readers that take a path, and the rule for what counts as a finding.
//
// What is a finding: the readers promise that every problem in their input is a combabc::Error
// (the CLI prints its one line and exits 65/66/78). So a target catches combabc::Error and nothing
// else: a crash, a sanitizer report, a timeout, running out of memory, and ANY other exception
// (std::length_error, std::bad_alloc, std::out_of_range, toml++'s own, ...) escaping the reader
// is a finding. Another exception type would reach the CLI's catch-all and be reported to the
// user as an "internal error" (exit 70) instead of a message naming the file, line and key.
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

namespace combabc::fuzz {

// A directory of this process's own (mkdtemp under $TMPDIR, else /tmp), removed at normal exit:
// parallel fuzzers (-jobs, -fork) each get theirs, and nothing is written into the repository.
inline const std::string& ScratchDir() {
  static const std::string dir = [] {
    const char* base = std::getenv("TMPDIR");
    std::string pattern =
        std::string(base != nullptr && *base != '\0' ? base : "/tmp") + "/combabc-fuzz-XXXXXX";
    if (::mkdtemp(pattern.data()) == nullptr) {
      std::perror("combabc fuzz: mkdtemp");
      std::abort();
    }
    static std::string remove_at_exit;
    remove_at_exit = pattern;
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove_all(remove_at_exit, ignored);
    });
    return pattern;
  }();
  return dir;
}

// Writes `size` bytes to `path`, replacing it; aborts if it cannot (that is the harness failing,
// not the code under test, but it must not pass silently).
inline void WriteFile(const std::string& path, const std::uint8_t* data, std::size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (size > 0) out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  out.close();
  if (!out) {
    std::perror(("combabc fuzz: cannot write " + path).c_str());
    std::abort();
  }
}

// Removes a SQLite database and the files SQLite may have left beside it.
inline void RemoveDatabase(const std::string& path) {
  std::error_code ignored;
  for (const char* suffix : {"", "-wal", "-shm", "-journal"}) {
    std::filesystem::remove(path + suffix, ignored);
  }
}

}  // namespace combabc::fuzz
