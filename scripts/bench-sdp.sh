#!/usr/bin/env bash
# Installs what is missing, builds, and runs the SDP benchmark against SDPA and CSDP.
# Extra arguments go to fact-bench-sdp (try --help, --quick, --max-n N).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$here/build}"
"$here/scripts/install-deps.sh"
cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j "$(nproc)" --target fact-bench-sdp
cd "$here"
OPENBLAS_NUM_THREADS=1 exec "$build/bench/fact-bench-sdp" "$@"
