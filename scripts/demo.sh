#!/usr/bin/env bash
# The main job: builds the combabc CLI and calibrates the 45 cm example with the paper's
# least-squares metric (Eq. 5), 5 waves x 500 accepted, then writes the report (figures + HTML).
# Run scripts/setup.sh first (the README's first command does both).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build-demo -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCOMBABC_BUILD_TESTS=OFF -DCOMBABC_BUILD_BENCH=OFF -DCOMBABC_BUILD_EXAMPLES=OFF > /dev/null
cmake --build build-demo --target combabc_cli -j "$(nproc)"
build-demo/apps/combabc run examples/sensor-45cm/least_squares.toml --overwrite "$@"
