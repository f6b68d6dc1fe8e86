#pragma once
// Reads a whole input file, refusing it once it exceeds a size limit. The limit is
// enforced while reading (at most limit + 1 bytes are ever read), so a FIFO, a device such as
// /dev/zero or a file that grows while read cannot exhaust memory.
#include <cstddef>
#include <string>

#include "combabc/core/error.hpp"

namespace combabc {

// `what` names the file in messages ("config file", "data file"). A missing, unreadable or
// directory path is kNoInput; a file over `max_bytes` is `too_large` with the limit in the message.
std::string ReadBoundedFile(const std::string& path,
                            std::size_t max_bytes,
                            const char* what,
                            ErrorKind too_large);

// "1 MiB", "64 MiB", "512 KiB", "100 B": a byte count for messages and docs.
std::string FormatBytes(std::size_t bytes);

}  // namespace combabc
