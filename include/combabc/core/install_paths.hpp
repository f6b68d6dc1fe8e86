#pragma once
// Where combabc finds the files it needs at run time (the report script under share/combabc/),
// without any install prefix compiled in: an install moved to another prefix after
// `cmake --install`, or unpacked from the .deb, still finds them. docs/architecture.md,
// "Install layout".
#include <filesystem>
#include <string>
#include <vector>

namespace combabc {

// The places a data file may be, in the order they are tried, for `relative` under share/combabc
// (e.g. "report/combabc_report.py"):
//  1. only when the binary holding this code (the shared object, else the executable) lies in the
//     build tree: the source tree's `source_relative` (a build-tree binary uses the scripts as
//     they are edited; an installed one never reads the source tree);
//  2. beside the shared object holding this code, when it is one: libcombabc_*.so in lib/, or
//     the Python module's _core*.so in its package: <its dir>/<step to share/combabc>/relative;
//  3. beside the executable (/proc/self/exe): <exe dir>/<bin -> share/combabc>/relative.
// The relative steps are the install layout's (GNUInstallDirs), fixed at configure time.
std::vector<std::filesystem::path> DataFileCandidates(const std::string& relative,
                                                      const std::string& source_relative);

// The first candidate that is a regular file, or an empty path.
std::filesystem::path FindDataFile(const std::vector<std::filesystem::path>& candidates);

// "a, b or c": the candidates for an error message that says where combabc looked.
std::string DescribeCandidates(const std::vector<std::filesystem::path>& candidates);

}  // namespace combabc
