#!/usr/bin/env bash
# The .deb as a user gets it: builds it with CPack in BUILD_DIR (default build-ci), installs it
# with apt-get (offline: scripts/setup.sh has installed its dependencies), runs the demo config
# with the installed /usr/bin/combabc and checks the report was drawn, reads the man page, the
# bash completion and `import combabc` of the installed module; then removes the package.
# Root only (scripts/test.sh runs it in CI); says so and skips otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build-ci}
if [ "$(id -u)" -ne 0 ]; then
  echo "skipped: installing the .deb needs root"
  exit 0
fi
rm -f "$build"/combabc_*.deb
(cd "$build" && cpack -G DEB > /dev/null 2>&1) || { echo "FAIL: cpack -G DEB in $build"; exit 1; }
deb=$(echo "$build"/combabc_*_*.deb)
[ -f "$deb" ] || { echo "FAIL: cpack wrote no combabc_<version>_<arch>.deb"; exit 1; }
echo "built $deb ($(dpkg-deb -f "$deb" Depends))"
dpkg-query -W -f='${Status}' combabc 2>/dev/null | grep -q "install ok installed" &&
  { echo "FAIL: a combabc package is installed already; remove it first"; exit 1; }
DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "./$deb" > /dev/null
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"; DEBIAN_FRONTEND=noninteractive apt-get remove -y -qq combabc > /dev/null' EXIT

# The demo (the 45 cm example, 5 waves x 500), by the installed CLI, into a directory of its own.
[ "$(command -v combabc)" = /usr/bin/combabc ] || { echo "FAIL: combabc is not /usr/bin/combabc"; exit 1; }
/usr/bin/combabc run examples/sensor-45cm/least_squares.toml -q -o "$tmp/demo"
for f in index.html overview.png summary.png predictive.png wave_5_marginals.png; do
  [ -s "$tmp/demo/report/$f" ] || { echo "FAIL: the installed combabc drew no report/$f"; exit 1; }
done

# The man page: `man combabc` when dpkg installed it; Debian's slim images exclude /usr/share/man
# (dpkg path-exclude), and then the packaged page is read with man -l instead.
if [ -f /usr/share/man/man1/combabc.1 ]; then
  MANWIDTH=200 man combabc 2>/dev/null | grep -qE "combabc +- combinatorial ABC-SMC" || { echo "FAIL: man combabc"; exit 1; }
  echo "man combabc: ok"
else
  dpkg-deb --fsys-tarfile "$deb" | tar -xO ./usr/share/man/man1/combabc.1 > "$tmp/combabc.1"
  MANWIDTH=200 man -l "$tmp/combabc.1" 2>/dev/null | grep -qE "combabc +- combinatorial ABC-SMC" ||
    { echo "FAIL: man -l of the packaged page"; exit 1; }
  echo "man combabc: this system excludes /usr/share/man (dpkg path-exclude); man -l of the packaged page: ok"
fi
bash -c 'source /usr/share/bash-completion/completions/combabc && complete -p combabc' > /dev/null
dpkg-deb -c "$deb" > "$tmp/contents"
if grep -q "dist-packages/combabc/__init__.py" "$tmp/contents"; then
  (cd "$tmp" && env -u PYTHONPATH /usr/bin/python3 -c 'import combabc
assert combabc.__file__.startswith("/usr/lib/python3/dist-packages/combabc/"), combabc.__file__
print("import combabc:", combabc.__version__, "from", combabc.__file__)')
else
  echo "no Python module in the .deb (built without COMBABC_PYTHON)"
fi
echo "the .deb installs, runs the demo and draws its report"
