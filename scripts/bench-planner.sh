#!/usr/bin/env bash
# Installs what is missing, builds fact-bench-planner, runs it: 1000 randomized simulated planning
# episodes (4–8 drones, obstacles; every drone maps its own rendered depth frames and plans; all
# trajectories flown at once and checked against the simulator's truth: separation, obstacles,
# room), plus the planner step and map update times. Writes bench/results/planner.csv and
# planner_summary.txt and prints the summary; exits 3 if any safety violation was found.
# Extra arguments go to fact-bench-planner (try --help, --quick, --episodes N, --seed S, --frames F).
# BUILD_DIR=... builds elsewhere (default: build/).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/bench.sh"
bench_build fact-bench-planner
cd "$here"
bench_args "$build/bench/fact-bench-planner" "$@"
start=$(date +%s)
# One core: the timing figures are per core.
taskset -c 0 "$build/bench/fact-bench-planner" "$@"
echo "== done in $(($(date +%s) - start)) s"
