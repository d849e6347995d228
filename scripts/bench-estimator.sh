#!/usr/bin/env bash
# Installs what is missing, builds fact-bench-estimator, runs it (the paper's evaluation and the
# estimator's modes; writes bench/results/estimator_*.csv and estimator_summary.txt), then draws
# the PNG plots with gnuplot (bench/plots/estimator.gp) next to the CSV files.
# Extra arguments go to fact-bench-estimator (try --help, --quick, --scenarios S, --max-n N).
# BUILD_DIR=... builds elsewhere (default: build/).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$here/build}"
"$here/scripts/install-deps.sh"
cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j "$(nproc)" --target fact-bench-estimator
cd "$here"
# --out-dir given on the command line decides where the CSV files (and so the plots) go.
out_dir="bench/results"
args=("$@")
for ((i = 0; i < ${#args[@]}; ++i)); do
  case "${args[i]}" in
    --help|-h) exec "$build/bench/fact-bench-estimator" --help ;;
    --out-dir) out_dir="${args[i + 1]:-$out_dir}" ;;
    --out-dir=*) out_dir="${args[i]#--out-dir=}" ;;
  esac
done
start=$(date +%s)
OPENBLAS_NUM_THREADS=1 "$build/bench/fact-bench-estimator" "$@"
echo "== plots"
# (a --quick run leaves some series empty; gnuplot's "no valid points" warnings are dropped)
gnuplot -e "dir='$out_dir'" "$here/bench/plots/estimator.gp" 2> >(grep -v "Skipping data file with no valid points" >&2)
for f in table1_time mae_vs_n mae_vs_noise rounds_vs_n success_vs_n; do
  echo "  $out_dir/estimator_$f.png"
done
echo "== done in $(($(date +%s) - start)) s"
