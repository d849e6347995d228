#!/usr/bin/env bash
# Gossip figures (fact-bench-gossip): completion time, loss/reordering, bytes per round, CPU, for 8
# drones over udpm inside a private network namespace (scripts/netns-run.sh). Writes
# bench/results/gossip.csv. Extra arguments go to fact-bench-gossip (try --help).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$here/build}"
"$here/scripts/install-deps.sh"
cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release >"$build.configure.log" 2>&1 || { cat "$build.configure.log"; exit 1; }
cmake --build "$build" -j "$(nproc)" --target fact-bench-gossip fact-gossip fact-fault-relay fact-vio-relay fact-solver
cd "$here"
exec "$here/scripts/netns-run.sh" "$build/bench/fact-bench-gossip" "$@"
