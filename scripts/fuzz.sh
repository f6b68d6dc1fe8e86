#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/, docs/fuzzing.md) with clang-14 and fuzzes each for SECONDS
# (default 30), starting from a scratch copy of its committed corpus in fuzz/corpus/ (the
# repository is never written to, except crashing inputs, which go to fuzz-findings/TARGET/,
# ignored by git). Fails if any target finds a crash, a sanitizer report, an uncaught non-combabc
# exception, a leak, a timeout (> 10 s) or an out-of-memory (> 2 GB).
#   scripts/fuzz.sh [SECONDS] [TARGET...]      e.g. scripts/fuzz.sh 600 history_patch
# Targets: config measured_data history history_patch worker_answer. Needs clang-14 and
# libclang-rt-14-dev (scripts/setup.sh installs them).
# The targets are built in build-fuzz, or in COMBABC_FUZZ_BUILD: a build directory configured with
# clang-14 and -DCOMBABC_FUZZ=ON already (scripts/test.sh's sanitizer build, which also runs the
# unit tests). Each libFuzzer process runs on one core: the targets run nproc at a time.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
shift || true
targets=("$@")
((${#targets[@]})) || targets=(config measured_data history history_patch worker_answer)
findings=${COMBABC_FUZZ_FINDINGS:-$PWD/fuzz-findings}
build=${COMBABC_FUZZ_BUILD:-}

if [ -z "$build" ]; then
  build=build-fuzz
  echo "== fuzz: building the targets ($build, clang-14, ASan + UBSan + libFuzzer)"
  CC=clang-14 CXX=clang++-14 cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCOMBABC_FUZZ=ON -DCOMBABC_BUILD_TESTS=OFF -DCOMBABC_BUILD_BENCH=OFF \
    -DCOMBABC_BUILD_APPS=OFF -DCOMBABC_BUILD_EXAMPLES=OFF > /dev/null
else
  echo "== fuzz: building the targets in $build"
fi
cmake --build "$build" --target combabc_fuzzers -j "$(nproc)"

scratch=$(mktemp -d "${TMPDIR:-/tmp}/combabc-fuzz.XXXXXX")
trap 'rm -rf "$scratch"' EXIT
for target in "${targets[@]}"; do
  [ -x "$PWD/$build/fuzz/${target}_fuzzer" ] || { echo "fuzz: no target '$target'"; exit 64; }
done

# Fuzzes one target; its verdict goes to $scratch/TARGET/verdict, printed in order below.
fuzz_one() {
  local target=$1
  local binary=$PWD/$build/fuzz/${target}_fuzzer
  local work=$scratch/$target
  mkdir -p "$work/corpus" "$work/tmp" "$findings/$target"
  if [ -d "fuzz/corpus/$target" ]; then cp -r "fuzz/corpus/$target/." "$work/corpus/"; fi
  local options=(-max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 -print_final_stats=1
    -artifact_prefix="$findings/$target/")
  if [ -f "fuzz/$target.dict" ]; then options+=(-dict="$PWD/fuzz/$target.dict"); fi
  # TMPDIR: the targets' scratch files (fuzz_util.hpp) stay inside $scratch, removed on exit.
  if (cd "$work" && TMPDIR=$work/tmp ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1} \
    UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1} \
    "$binary" "${options[@]}" corpus > log 2>&1); then
    echo "   $(awk '/^stat::number_of_executed_units/ {print $2}' "$work/log") executions," \
      "corpus $(ls "$work/corpus" | wc -l) inputs: no finding" > "$work/verdict"
  else
    {
      echo "   FINDING in $target (last lines of its log; the input is in $findings/$target/):"
      summary=$(grep -E 'ERROR|runtime error|SUMMARY|terminate called|what\(\)|Test unit written|broken promise|#[0-3] 0x' \
        "$work/log" | head -40 || true)
      [ -n "$summary" ] || summary=$(tail -15 "$work/log")
      sed 's/^/   | /' <<< "$summary"
    } > "$work/verdict"
    return 1
  fi
}

status=0
jobs=$(nproc)
running=()
for target in "${targets[@]}"; do
  fuzz_one "$target" &
  running+=($!)
  if ((${#running[@]} >= jobs)); then
    wait "${running[0]}" || status=1
    running=("${running[@]:1}")
  fi
done
for pid in "${running[@]}"; do wait "$pid" || status=1; done
for target in "${targets[@]}"; do
  echo "== fuzz: $target for ${seconds} s"
  cat "$scratch/$target/verdict"
done
if [ $status -ne 0 ]; then
  echo "fuzz: findings (docs/fuzzing.md says how to reproduce and minimise them)"
fi
exit $status
