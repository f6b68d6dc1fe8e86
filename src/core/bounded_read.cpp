#include "combabc/core/bounded_read.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

namespace combabc {

std::string FormatBytes(std::size_t bytes) {
  constexpr std::size_t kKiB = 1024, kMiB = kKiB * 1024, kGiB = kMiB * 1024;
  if (bytes >= kGiB && bytes % kGiB == 0) return std::to_string(bytes / kGiB) + " GiB";
  if (bytes >= kMiB && bytes % kMiB == 0) return std::to_string(bytes / kMiB) + " MiB";
  if (bytes >= kKiB && bytes % kKiB == 0) return std::to_string(bytes / kKiB) + " KiB";
  return std::to_string(bytes) + " B";
}

std::string ReadBoundedFile(const std::string& path,
                            std::size_t max_bytes,
                            const char* what,
                            ErrorKind too_large) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw Error(ErrorKind::kNoInput, std::string("is a directory, not a ") + what, path);
  }
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    throw Error(ErrorKind::kNoInput,
                std::string("cannot open ") + what + ": " + std::strerror(errno),
                path);
  }
  std::string text;
  char buffer[1 << 16];
  while (true) {
    // Never ask for more than one byte past the limit: that byte is enough to refuse.
    const std::size_t room = max_bytes + 1 - text.size();
    const ssize_t got = ::read(fd, buffer, std::min(sizeof buffer, room));
    if (got < 0) {
      if (errno == EINTR) continue;
      const int error = errno;
      ::close(fd);
      throw Error(ErrorKind::kNoInput,
                  std::string("cannot read ") + what + ": " + std::strerror(error),
                  path);
    }
    if (got == 0) break;
    text.append(buffer, static_cast<std::size_t>(got));
    if (text.size() > max_bytes) {
      ::close(fd);
      throw Error(too_large,
                  std::string(what) + " is larger than the " + FormatBytes(max_bytes) +
                      " limit (docs/config.md, \"Limits\")",
                  path);
    }
  }
  ::close(fd);
  return text;
}

}  // namespace combabc
