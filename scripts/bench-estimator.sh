#!/usr/bin/env bash
# Installs what is missing, builds fact-bench-estimator, runs it (the paper's evaluation and the
# estimator's modes; writes bench/results/estimator_*.csv and estimator_summary.txt), then draws
# the PNG plots with gnuplot (bench/plots/estimator.gp) next to the CSV files.
# Extra arguments go to fact-bench-estimator (try --help, --quick, --scenarios S, --max-n N).
# BUILD_DIR=... builds elsewhere (default: build/).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/bench.sh"
bench_build fact-bench-estimator
cd "$here"
bench_args "$build/bench/fact-bench-estimator" "$@"
start=$(date +%s)
OPENBLAS_NUM_THREADS=1 "$build/bench/fact-bench-estimator" "$@"
echo "== plots"
# (a --quick run leaves some series empty; gnuplot's "no valid points" warnings are dropped)
gnuplot -e "dir='$out_dir'" "$here/bench/plots/estimator.gp" 2> >(grep -v "Skipping data file with no valid points" >&2)
for f in table1_time mae_vs_n mae_vs_noise rounds_vs_n success_vs_n; do
  echo "  $out_dir/estimator_$f.png"
done
echo "== done in $(($(date +%s) - start)) s"
