#!/usr/bin/env bash
# Builds combabc and runs every test: the Release build with warnings as errors (all labels:
# unit, statistical, slow, packaging, browser, docs), its .deb installed and run (scripts/check-deb.sh,
# as root), clang-tidy on it, the unit tests again under ASan+UBSan, the fuzzing of the input
# readers (COMBABC_FUZZ_SECONDS per target, default 30; 0 skips it; docs/fuzzing.md) from the same
# sanitizer build, the tests labelled threads under ThreadSanitizer, and the layering and
# formatting checks. Run scripts/setup.sh first (the README's test command does both).
#
# CI's time (docs/ci.md): each stage prints its wall time. clang-tidy needs only a compile
# database, so it runs beside the other stages at the lowest priority, on the CPU they leave idle,
# and the script waits for it at the end; one clang build serves both the ASan+UBSan unit tests and
# the fuzz targets; sanitizer builds compile only what their label runs; the library's components
# are unity builds.
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

# clang-tidy needs only a compile database: a configure-only tree, with the library's unity
# batches, which it checks one batch at a time (scripts/check-tidy.sh, docs/ci.md). It starts now
# and runs beside every stage below at the lowest priority, on the CPU they leave idle; the script
# waits for it at the end. In a session of its own, so that the trap can stop the whole
# run-clang-tidy tree on a failure.
stage "== clang-tidy on every source: started, beside the stages below"
cmake -S . -B build-tidy -G Ninja -DCMAKE_BUILD_TYPE=Release -DCOMBABC_UNITY=ON > /dev/null
tidy_log=$(mktemp)
# A new session is a new scheduling group where the kernel groups by session (autogroup), and a
# group's own nice level is what ranks it against the others: 19 there too, set from inside the
# new session (from here it could still be this script's group, before setsid has run).
setsid bash -c 'echo 19 > /proc/self/autogroup 2> /dev/null || true
  exec nice -n 19 bash scripts/check-tidy.sh build-tidy' > "$tidy_log" 2>&1 &
tidy_pid=$!
trap 'kill -- "-$tidy_pid" 2> /dev/null || true; rm -f "$tidy_log"' EXIT

# COMBABC_UNITY: the library's components as unity builds (docs/ci.md), here and below.
stage "== Release build, warnings as errors"
# The tests' own code at -O1 and with one precompiled header (docs/ci.md): the library, the CLI and
# the Python module keep -O3, and the tests spend their time in them.
cmake -S . -B build-ci -G Ninja -DCMAKE_BUILD_TYPE=Release -DCOMBABC_WERROR=ON -DCOMBABC_UNITY=ON \
  -DCOMBABC_TEST_PCH=ON -DCOMBABC_TEST_OPTIMIZE=-O1
cmake --build build-ci -j "$jobs"
# Each build's tests share one precompute cache of their own (docs/model.md), not the user's.
COMBABC_CACHE_DIR="$PWD/build-ci/precompute-cache" \
  ctest --test-dir build-ci -j "$jobs" --output-on-failure --timeout 900

stage "== the .deb (cpack): installed, runs the demo with /usr/bin/combabc, man page, Python (root only)"
bash scripts/check-deb.sh build-ci

stage "== clang build with AddressSanitizer + UndefinedBehaviorSanitizer: the unit tests and the fuzz targets"
# One build for both (libFuzzer's coverage instrumentation is inert outside a fuzz target): the
# library is compiled with sanitizers once, not twice. -O1, as AddressSanitizer's documentation
# advises for reasonable speed (Eigen's templates are slow at -O0); line tables are all that a
# sanitizer's report needs; assertions stay on (no NDEBUG). Warnings are the Release build's job
# (GCC, -Werror above). Only the executables with tests labelled unit, and the fuzz targets.
# lld links an instrumented test in a quarter of GNU ld's CPU (docs/ci.md); the tests share one
# precompiled header.
CC=clang-14 CXX=clang++-14 cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug \
  -DCMAKE_CXX_FLAGS_DEBUG="-O1 -gline-tables-only" -DCMAKE_EXE_LINKER_FLAGS=-fuse-ld=lld \
  -DCOMBABC_SANITIZE=ON -DCOMBABC_FUZZ=ON -DCOMBABC_BUILD_BENCH=OFF -DCOMBABC_PYTHON=OFF \
  -DCOMBABC_UNITY=ON -DCOMBABC_TEST_PCH=ON > /dev/null
cmake --build build-asan -j "$jobs" --target combabc_unit_tests combabc_fuzzers
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
  COMBABC_CACHE_DIR="$PWD/build-asan/precompute-cache" \
  ctest --test-dir build-asan -j "$jobs" -L unit --output-on-failure --timeout 900

fuzz_seconds=${COMBABC_FUZZ_SECONDS:-30}
if [ "$fuzz_seconds" -gt 0 ]; then
  stage "== Fuzzing the config, CSV, history and worker-answer readers (${fuzz_seconds} s per target)"
  COMBABC_FUZZ_BUILD=build-asan bash scripts/fuzz.sh "$fuzz_seconds"
fi

stage "== ThreadSanitizer build (tests labelled threads)"
cmake -S . -B build-tsan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCOMBABC_WERROR=ON \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" \
  -DCOMBABC_TSAN=ON -DCOMBABC_BUILD_BENCH=OFF -DCOMBABC_BUILD_EXAMPLES=OFF -DCOMBABC_PYTHON=OFF \
  -DCOMBABC_UNITY=ON -DCOMBABC_TEST_PCH=ON -DCOMBABC_TEST_OPTIMIZE=-O1
cmake --build build-tsan -j "$jobs" --target combabc_threads_tests
TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1 \
  COMBABC_CACHE_DIR="$PWD/build-tsan/precompute-cache" \
  ctest --test-dir build-tsan -j "$jobs" -L threads --no-tests=error --output-on-failure --timeout 900

stage "== clang-tidy (waiting for it to finish)"
tidy_status=0
wait "$tidy_pid" || tidy_status=$?
cat "$tidy_log"
[ "$tidy_status" -eq 0 ] || exit "$tidy_status"
stage "== done"
