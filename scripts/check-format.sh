#!/usr/bin/env bash
# Fails if any C++ file in the project is not clang-formatted.
set -euo pipefail
cd "$(dirname "$0")/.."
bad=$(git ls-files '*.cpp' '*.hpp' | xargs clang-format --dry-run -Werror 2>&1 | grep -o '^[^:]*:' | sort -u || true)
if [ -n "$bad" ]; then
  echo "not clang-formatted (run clang-format -i):"; echo "$bad"; exit 1
fi
echo "format: clean"

# No identifier the C++ standard reserves to the implementation ([lex.name]: a double underscore,
# or an underscore and a capital letter) in combabc's code. A grep, in place of clang-tidy's
# bugprone-reserved-identifier, whose matcher walked every identifier of the standard headers in
# every translation unit (11 % of clang-tidy's CPU; docs/ci.md). It is stricter (uses count, not only
# declarations); the names allowed are the compiler's and Python's, which the code uses.
allowed='__restrict|__attribute__|__builtin_[a-z_]+|__clang__|__GNUC__|__x86_64__|__FMA__|__AVX2__'
allowed+='|__AVX512F__|__FILE__|__LINE__|__func__|__cplusplus|__has_include|__muldc3'
allowed+='|__(name|repr|init|index|version|len|getitem|builtins)__'
reserved=$(git ls-files '*.cpp' '*.hpp' '*.h' | xargs grep -noE '\b(__[A-Za-z0-9_]+|_[A-Z][A-Za-z0-9_]*)\b' |
  grep -vE ":($allowed)$" || true)
if [ -n "$reserved" ]; then
  echo "reserved identifiers (rename them; or, for a compiler's name, allow it here):"
  echo "$reserved"
  exit 1
fi
echo "reserved identifiers: none"
