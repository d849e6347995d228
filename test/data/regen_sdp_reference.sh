#!/bin/sh
# Regenerates test/data/sdp: the reference SDP instances (.dat-s, SDPA-sparse with matrix 0
# = -C) and optima.csv (optima of minimize <C,X> s.t. X >= 0, X_ii = I_d from SDPA, the CSDP
# library and the csdp executable). Needs libsdpa-dev, libsdp-dev and coinor-csdp.
# Usage: test/data/regen_sdp_reference.sh        (BUILD_DIR overrides the build folder)
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${BUILD_DIR:-"$root/build"}
if [ ! -f "$build/CMakeCache.txt" ]; then
  tests=ON
  [ -f "$root/test/CMakeLists.txt" ] || tests=OFF
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DFACT_BUILD_BENCH=ON -DFACT_BUILD_TESTS=$tests
fi
cmake --build "$build" --target fact-sdp-reference -j "$(nproc 2>/dev/null || echo 2)"
"$build/bench/fact-sdp-reference" --out-dir "$root/test/data/sdp"
