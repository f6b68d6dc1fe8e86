#!/usr/bin/env bash
# Runs clang-tidy (Debian's clang-tidy 14, the checks in .clang-tidy) over every project .cpp in
# src/, apps/, tests/, bench/, examples/ and python/ that the given build compiles, in parallel.
# Fails on any warning (.clang-tidy sets WarningsAsErrors '*'). Needs a configured build for its
# compile_commands.json: scripts/check-tidy.sh [BUILD_DIR] (default build).
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
# Generated sources (none today) live in the build tree, outside these directories.
files="^$root/(src|apps|tests|bench|examples|python)/.*\.cpp$"
count=$(grep -cE "\"file\": \"$root/(src|apps|tests|bench|examples|python)/.*\.cpp\"" "$db" || true)
echo "check-tidy: $count files from $db, $(nproc) jobs"
log=$(mktemp)
trap 'rm -f "$log"' EXIT
start=$SECONDS
status=0
# The database holds GCC's command lines: clang does not know some of its -Wno-* options.
"$tidy" -p "$build" -j "$(nproc)" -quiet -extra-arg=-Wno-unknown-warning-option "$files" 2>&1 |
  sed -r 's/\x1b\[[0-9;]*m//g' >"$log" || status=$?
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
