#!/usr/bin/env bash
# Installs what is missing, builds every app and fact-bench-e2e, runs whole simulated
# initializations (scripts/run-sim.sh --fast per swarm size and seed, in private network
# namespaces), writes bench/results/e2e_runs.csv, e2e.csv, e2e_summary.txt, then draws
# bench/results/e2e.png (bench/plots/e2e.gp). Extra arguments go to fact-bench-e2e (try --help,
# --drones 2,4 --seeds 5 for a quick look). BUILD_DIR=... builds elsewhere (default: build/).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/bench.sh"
bench_build fact-bench-e2e fact-sim fact-detector fact-vio-relay fact-gossip \
  fact-solver fact-planner fact-fc-bridge fact-run-report fact-log-merge fact-log-compare
cd "$here"
bench_args "$build/bench/fact-bench-e2e" "$@"
start=$(date +%s)
"$build/bench/fact-bench-e2e" --repo "$here" --build "$build" "$@"
echo "== plot"
gnuplot -e "dir='$out_dir'" "$here/bench/plots/e2e.gp"
echo "  $out_dir/e2e.png"
echo "== done in $(($(date +%s) - start)) s"
