#!/usr/bin/env bash
# Fails if any C++ file in the project is not clang-formatted.
set -euo pipefail
cd "$(dirname "$0")/.."
bad=$(git ls-files '*.cpp' '*.hpp' | xargs clang-format --dry-run -Werror 2>&1 | grep -o '^[^:]*:' | sort -u || true)
if [ -n "$bad" ]; then
  echo "not clang-formatted (run clang-format -i):"; echo "$bad"; exit 1
fi
echo "format: clean"
