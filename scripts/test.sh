#!/usr/bin/env bash
# The whole test suite: installs what it needs (Debian 12, as root or with sudo), configures,
# builds and runs ctest. Safe to run again: installed packages are skipped.
#   scripts/test.sh            build in ./build and run every test
#   BUILD_DIR=/tmp/b scripts/test.sh
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$here/build}"
"$here/scripts/install-deps.sh"
echo "== configure ($build)"
cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release >"$build.configure.log" 2>&1 || { cat "$build.configure.log"; exit 1; }
echo "== build"
cmake --build "$build" -j "$(nproc)"
echo "== test"
ctest --test-dir "$build" --output-on-failure -j "$(nproc)"
