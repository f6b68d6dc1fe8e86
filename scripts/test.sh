#!/usr/bin/env bash
# Builds combabc and runs every test: the Release build with warnings as errors (all labels:
# unit, statistical, slow, packaging, browser), its .deb installed and run (scripts/check-deb.sh,
# as root), and clang-tidy on it, the unit tests again under
# ASan+UBSan, the tests labelled threads under ThreadSanitizer, the layering and formatting checks,
# and a bounded fuzzing run of the input readers (COMBABC_FUZZ_SECONDS per target, default 30; 0
# skips it; docs/fuzzing.md). Run scripts/setup.sh first (the README's test command does both).
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)
# Each stage's wall time, so that CI's time can be read stage by stage (keep CI under 30 min).
stage_start=$SECONDS
stage() {
  echo "   ($((SECONDS - stage_start)) s)"
  stage_start=$SECONDS
  echo "$1"
}

echo "== layering and formatting"
bash scripts/check-layers.sh
bash scripts/check-format.sh
stage "== configure with the CLI off (the library and its tests stand without it)"
cmake -S . -B build-noapps -G Ninja -DCOMBABC_BUILD_APPS=OFF -DCOMBABC_BUILD_BENCH=OFF > /dev/null

stage "== Release build, warnings as errors"
cmake -S . -B build-ci -G Ninja -DCMAKE_BUILD_TYPE=Release -DCOMBABC_WERROR=ON
cmake --build build-ci -j "$jobs"
ctest --test-dir build-ci -j "$jobs" --output-on-failure --timeout 900

stage "== the .deb (cpack): installed, runs the demo with /usr/bin/combabc, man page, Python (root only)"
bash scripts/check-deb.sh build-ci

stage "== clang-tidy on the Release build's sources (.clang-tidy; any warning fails)"
bash scripts/check-tidy.sh build-ci

stage "== Debug build with AddressSanitizer + UndefinedBehaviorSanitizer (unit tests)"
# -O1, as AddressSanitizer's documentation advises for reasonable speed (Eigen's templates are
# slow at -O0); assertions stay on (no NDEBUG) and every sanitizer check is the same. GCC's
# -Wmaybe-uninitialized misfires on libstdc++'s <regex> at -O1 with the sanitizers; the Release
# build above keeps that warning as an error. No Python module: its tests are not labelled unit.
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug \
  -DCMAKE_CXX_FLAGS_DEBUG="-g -O1 -Wno-maybe-uninitialized" \
  -DCOMBABC_WERROR=ON -DCOMBABC_SANITIZE=ON -DCOMBABC_BUILD_BENCH=OFF -DCOMBABC_PYTHON=OFF
cmake --build build-asan -j "$jobs"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir build-asan -j "$jobs" -L unit --output-on-failure --timeout 900

stage "== ThreadSanitizer build (tests labelled threads)"
cmake -S . -B build-tsan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCOMBABC_WERROR=ON \
  -DCOMBABC_TSAN=ON -DCOMBABC_BUILD_BENCH=OFF -DCOMBABC_BUILD_EXAMPLES=OFF
cmake --build build-tsan -j "$jobs" --target combabc_threads_tests
TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1 \
  ctest --test-dir build-tsan -j "$jobs" -L threads --no-tests=error --output-on-failure --timeout 900

fuzz_seconds=${COMBABC_FUZZ_SECONDS:-30}
if [ "$fuzz_seconds" -gt 0 ]; then
  stage "== Fuzzing the config, CSV and history readers (${fuzz_seconds} s per target)"
  bash scripts/fuzz.sh "$fuzz_seconds"
fi
stage "== done"
