#!/usr/bin/env bash
# Installs what is missing, builds, and runs the SDP benchmark against SDPA and CSDP.
# Extra arguments go to fact-bench-sdp (try --help, --quick, --max-n N).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/bench.sh"
bench_build fact-bench-sdp
cd "$here"
# glibc.malloc.hugetlb=1: malloc asks for transparent huge pages (madvise) for its heap, for
# every solver in the process alike; with 4 KiB pages a tight_noisy N = 100 solve measured
# 19–27 ms against 12–21 ms (BENCHMARKS.md, session 16). Older glibc ignores the tunable.
export GLIBC_TUNABLES="${GLIBC_TUNABLES:+$GLIBC_TUNABLES:}glibc.malloc.hugetlb=1"
OPENBLAS_NUM_THREADS=1 exec "$build/bench/fact-bench-sdp" "$@"
