#!/usr/bin/env bash
# Gossip figures (fact-bench-gossip): completion time, loss/reordering, bytes per round, CPU, for 8
# drones over udpm inside a private network namespace (scripts/netns-run.sh). Writes
# bench/results/gossip.csv. Extra arguments go to fact-bench-gossip (try --help).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/bench.sh"
bench_build fact-bench-gossip fact-gossip fact-fault-relay fact-vio-relay fact-solver
cd "$here"
exec "$here/scripts/netns-run.sh" "$build/bench/fact-bench-gossip" "$@"
