#!/usr/bin/env bash
# Installs what is missing, builds fact-bench-detector, runs it (the depth detector and tracker
# on frames rendered by fact_sim, against its ground truth; writes bench/results/detector.csv and
# detector_summary.txt), then draws bench/results/detector.png with gnuplot (bench/plots/detector.gp).
# Extra arguments go to fact-bench-detector (try --help, --quick, --episodes N, --seed S).
# BUILD_DIR=... builds elsewhere (default: build/).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/bench.sh"
bench_build fact-bench-detector
cd "$here"
bench_args "$build/bench/fact-bench-detector" "$@"
start=$(date +%s)
# One core: the figures are per core (OpenCV's own threads off).
OPENCV_FOR_THREADS_NUM=1 OMP_NUM_THREADS=1 taskset -c 0 "$build/bench/fact-bench-detector" "$@"
echo "== plot"
gnuplot -e "dir='$out_dir'" "$here/bench/plots/detector.gp"
echo "  $out_dir/detector.png"
echo "== done in $(($(date +%s) - start)) s"
