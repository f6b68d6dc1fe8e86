#!/usr/bin/env bash
# Runs clang-tidy (Debian's clang-tidy 14, the checks in .clang-tidy) over every project .cpp in
# src/, apps/, tests/, bench/, examples/ and python/ that the given build compiles, in parallel.
# Fails on any warning (.clang-tidy sets WarningsAsErrors '*'). Needs a configured build for its
# compile_commands.json: scripts/check-tidy.sh [BUILD_DIR] (default build).
#
# A build configured with COMBABC_UNITY=ON (CI's) lists the library components' unity batches
# instead of their sources: each batch is checked as one translation unit, so Eigen, toml++ and the
# standard headers are parsed once per batch, not once per file (docs/ci.md: about 3.5x less CPU).
# The tests, the CLI, benchmarks, examples and the Python module are batched the same way for
# clang-tidy alone (scripts/tidy_batches.py: the files of one command line, eight at a time, no two
# that declare the same file-scope name, with their folder's .clang-tidy: tests/ has no analyzer),
# so gtest, CLI11, pybind11 and Eigen are parsed and matched once per batch. The batches' own
# #include of .cpp files is what unity builds do, so bugprone-suspicious-include is off for them.
# The price: the static analyzer's path-sensitive checks look only at functions of the main file,
# so they skip the batched sources (the AST checks still see every line); the plate stays one file
# at a time with every check, and so does every file of a developer's tree (unity off).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
build=${1:-build}
db="$build/compile_commands.json"
if [ ! -f "$db" ]; then
  echo "check-tidy: no $db; configure first (cmake -S . -B $build -G Ninja)" >&2
  exit 2
fi
tidy=$(command -v run-clang-tidy-14 || command -v run-clang-tidy || true)
if [ -z "$tidy" ]; then
  echo "check-tidy: run-clang-tidy not found (apt-get install clang-tidy)" >&2
  exit 2
fi
build_abs=$(cd "$build" && pwd)
# Generated sources (none today but the unity batches) live in the build tree.
files="^$root/(src|apps|tests|bench|examples|python)/.*\.cpp$"
count=$(grep -cE "\"file\": \"$root/(src|apps|tests|bench|examples|python)/.*\.cpp\"" "$db" || true)
unity=$(grep -cE "\"file\": \"$build_abs/src/CMakeFiles/[^/]+/Unity/" "$db" || true)
echo "check-tidy: $count files and $unity unity batches from $db, $(nproc) jobs"
log=$(mktemp)
trap 'rm -f "$log"' EXIT
start=$SECONDS
status=0
# The database holds GCC's command lines: clang does not know some of its -Wno-* options.
args=(-quiet -extra-arg=-Wno-unknown-warning-option)
if [ "$unity" -gt 0 ]; then
  # A batch's sources are "headers" to clang-tidy: the filter names them; the configuration is
  # its files' (the batches sit in the build tree, which need not be inside the repository).
  binary=$(command -v clang-tidy-14 || command -v clang-tidy)
  python3 scripts/tidy_batches.py "$build" "$root" "$binary" "$(nproc)" \
    -- "${args[@]}" -checks=-bugprone-suspicious-include \
    -header-filter='/(include/combabc|src|apps|tests|bench|examples|python)/.*\.(hpp|cpp)$' \
    -- "${args[@]}" 2>&1 | sed -r 's/\x1b\[[0-9;]*m//g' >>"$log" || status=$?
else
  "$tidy" -p "$build" -j "$(nproc)" "${args[@]}" "$files" 2>&1 | sed -r 's/\x1b\[[0-9;]*m//g' \
    >>"$log" || status=$?
fi
# clang-tidy prints one "N warnings generated" line per file, mostly for suppressed headers.
grep -vE '^[0-9]+ warnings? (and [0-9]+ errors? )?generated\.$|^Suppressed [0-9]+ warnings|^Use -header-filter|^clang-tidy(-[0-9]+)? |^Running clang-tidy' "$log" || true
found=$(grep -E '^/.*: (warning|error): ' "$log" | sort -u || true)
if [ -n "$found" ]; then
  echo "check-tidy: $(wc -l <<<"$found") distinct diagnostics, by check:"
  grep -oE '\[[a-z0-9.,-]+\]$' <<<"$found" | sort | uniq -c | sort -rn
  status=1
fi
echo "check-tidy: $((SECONDS - start)) s"
if [ "$status" -ne 0 ]; then
  echo "check-tidy: FAILED (fix the code, or see .clang-tidy for how checks are curated)" >&2
  exit 1
fi
echo "check-tidy: clean"
