#!/usr/bin/env bash
# Main job until the LCM swarm (scripts/run-sim.sh) lands: a simulated swarm observed over a few
# rounds (fact-simgen), then the estimator on those rounds alone (fact-solve). Truth is written
# beside the rounds for inspection; fact-solve never reads it.
#   scripts/demo-estimate.sh                       8 drones, 2 rounds, depth-camera noise, range 6 m
#   scripts/demo-estimate.sh --drones 16 --seed 3  any fact-simgen flags
# Files go to ${OUT_DIR:-build/demo}: rounds.json, truth.json, result.json.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$here/build}"
out="${OUT_DIR:-$build/demo}"
"$here/scripts/install-deps.sh"
cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release >"$build.configure.log" 2>&1 || { cat "$build.configure.log"; exit 1; }
cmake --build "$build" -j "$(nproc)" --target fact-simgen fact-solve
mkdir -p "$out"
"$build/apps/fact-simgen" --drones 8 --rounds 2 --noise depth --range-limit 6 --room 7 --seed 1 "$@" \
  --output "$out/rounds.json" --truth "$out/truth.json"
status=0
"$build/apps/fact-solve" --input "$out/rounds.json" --output "$out/result.json" || status=$?
echo "== result: $out/result.json (exit $status: 0 certified, 3 not certified, 2 invalid input)"
sed -n '1,12p' "$out/result.json"
exit "$status"
