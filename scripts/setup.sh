#!/usr/bin/env bash
# Installs every Debian package combabc needs to build, test and plot. Idempotent; run as root on
# Debian 12. Nothing else is fetched: all dependencies come from Debian's archive.
set -euo pipefail
packages=(
  g++ cmake ninja-build pkg-config git
  libeigen3-dev          # dense/sparse linear algebra, LM fit (unsupported/NonLinearOptimization)
  libtomlplusplus-dev    # TOML config parsing with line numbers
  libcli11-dev           # command-line parsing
  libsqlite3-dev sqlite3 # run history
  libcsv-dev             # RFC 4180 CSV parsing of the data files (runtime: libcsv3)
  libxxhash-dev          # XXH3 for the sensor's precompute cache (header-only: no runtime)
  libopenmpi-dev openmpi-bin  # the MPI executor (mpirun -np N combabc run; COMBABC_MPI)
  libgtest-dev libgmock-dev libbenchmark-dev
  clang-format clang-tidy
  clang-14 libclang-rt-14-dev  # libFuzzer + sanitizer runtimes for scripts/fuzz.sh (docs/fuzzing.md)
  lld-14                 # the sanitizer build's linker: a quarter of GNU ld's CPU there (docs/ci.md)
  python3 python3-numpy python3-matplotlib  # report figures (Debian's python3, not a pyenv one)
  calculix-ccx           # the CalculiX example (examples/sensor-calculix) and its test
  python3-dev pybind11-dev python3-pybind11  # the Python module (COMBABC_PYTHON, docs/python.md)
  python3-pytest python3-pandas             # its tests and DataFrames
  python3-xarray python3-netcdf4            # export's inference_data.nc (ArviZ layout)
  chromium               # the report page's browser test (ctest -L browser), headless
  dpkg-dev file man-db   # the .deb: cpack's dpkg-shlibdeps and ELF detection; man for its check
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
echo "setup: all ${#packages[@]} packages present"
