#!/usr/bin/env bash
# Installs what is missing, builds, and runs the SDP benchmark against SDPA and CSDP.
# Extra arguments go to fact-bench-sdp (try --help, --quick, --max-n N).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/bench.sh"
bench_build fact-bench-sdp
cd "$here"
OPENBLAS_NUM_THREADS=1 exec "$build/bench/fact-bench-sdp" "$@"
