#!/usr/bin/env bash
# The arm64 and the x86-64 fact-solve on the same rounds files: the same exit code and the same
# fact-result-v1 to 1e-9 (test/arm64/compare_results.py; timing_us ignored).
#   test/arm64/compare-solve.sh SIMGEN X86_SOLVE ARM64_SOLVE WORK_DIR [ARM64_SIMGEN]
# SIMGEN (x86-64 fact-simgen) writes the scenarios below into WORK_DIR; ARM64_SOLVE is the arm64
# binary's runner (build-arm64/aarch64/apps/fact-solve.qemu: qemu-aarch64 -L <sysroot>). With
# ARM64_SIMGEN, the arm64 fact-simgen's rounds files are also compared with the x86-64 ones, to
# 1e-9, and the count of those that differ is reported (not part of the verdict: the solves all
# use the x86-64 files). Every run of every mode is listed; the last line is the verdict.
set -euo pipefail
if [ "$#" -lt 4 ] || [ "$#" -gt 5 ]; then
  echo "usage: $0 SIMGEN X86_SOLVE ARM64_SOLVE WORK_DIR [ARM64_SIMGEN]" >&2
  exit 2
fi
simgen=$1 x86=$2 arm=$3 work=$4 arm_simgen=${5:-}
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
rm -rf "$work" && mkdir -p "$work"

# name | fact-simgen flags: the demo's scenario over several seeds, larger and noisier swarms,
# false positives, misses, drift, a symmetric formation (2-3 rounds: the summed modes paper and
# complex have no unique answer there, and only their status and optimal value are compared), and
# moving swarms with N + 1 rounds, where the summed modes have one.
scenarios=(
  "demo-s1|--drones 8 --rounds 2 --noise depth --range-limit 6 --seed 1"
  "demo-s2|--drones 8 --rounds 2 --noise depth --range-limit 6 --seed 2"
  "demo-s3|--drones 8 --rounds 3 --noise depth --range-limit 6 --seed 3"
  "paper-noise|--drones 6 --rounds 2 --noise paper --seed 4"
  "exact|--drones 5 --rounds 1 --noise none --seed 5"
  "n16-fp|--drones 16 --rounds 3 --noise depth --range-limit 6 --false-positives 0.3 --miss-rate 0.1 --seed 6"
  "drift-move|--drones 10 --rounds 3 --noise depth --drift-yaw 0.01 --drift-position 0.02 --move 0.5 --seed 7"
  "grid|--drones 9 --rounds 2 --formation grid --noise depth --seed 8"
  "moving-n4|--drones 4 --rounds 5 --noise none --move 1.5 --seed 12"
  "moving-n5|--drones 5 --rounds 6 --noise paper --move 1.5 --seed 9"
  "moving-n8|--drones 8 --rounds 9 --noise depth --move 1.5 --seed 11"
)
modes=(auto paper complex associated)

runs=0 failed=0 largest=0 not_unique=0 simgen_runs=0 simgen_differ=0
for s in "${scenarios[@]}"; do
  name=${s%%|*} flags=${s#*|}
  # shellcheck disable=SC2086  # flags are words
  "$simgen" $flags --output "$work/$name.rounds.json" 2>/dev/null
  if [ -n "$arm_simgen" ]; then
    # shellcheck disable=SC2086
    "$arm_simgen" $flags --output "$work/$name.rounds.arm64.json" 2>/dev/null
    verdict="$(python3 "$here/compare_results.py" "$work/$name.rounds.json" "$work/$name.rounds.arm64.json" || true)"
    echo "fact-simgen $name: arm64 vs x86-64 rounds file: $verdict"
    simgen_runs=$((simgen_runs + 1))
    case "$verdict" in equal:*) ;; *) simgen_differ=$((simgen_differ + 1)) ;; esac
  fi
  for mode in "${modes[@]}"; do
    rc_x86=0 rc_arm=0
    "$x86" --input "$work/$name.rounds.json" --mode "$mode" --output "$work/$name.$mode.x86_64.json" \
      2>"$work/$name.$mode.x86_64.log" || rc_x86=$?
    "$arm" --input "$work/$name.rounds.json" --mode "$mode" --output "$work/$name.$mode.arm64.json" \
      2>"$work/$name.$mode.arm64.log" || rc_arm=$?
    runs=$((runs + 1))
    if [ "$rc_x86" -ne "$rc_arm" ]; then
      verdict="DIFFER exit codes: x86-64 $rc_x86, arm64 $rc_arm"
    else
      verdict="$(python3 "$here/compare_results.py" "$work/$name.$mode.x86_64.json" "$work/$name.$mode.arm64.json" ||
        true)"
    fi
    printf '%-12s %-10s exit %d  %s\n' "$name" "$mode" "$rc_x86" "$verdict"
    case "$verdict" in
      equal:*)
        if [[ "$verdict" == *"not unique"* ]]; then
          not_unique=$((not_unique + 1))
        else
          d=$(sed -nE 's/^equal: largest \|difference\| ([^ ]+).*/\1/p' <<<"$verdict")
          largest=$(awk -v a="$largest" -v b="$d" 'BEGIN { print (b + 0 > a + 0) ? b : a }')
        fi ;;
      *) failed=$((failed + 1)) ;;
    esac
  done
done
if [ "$simgen_runs" -gt 0 ]; then
  echo "fact-simgen arm64 vs x86-64: $simgen_differ of $simgen_runs rounds files differ beyond 1e-9 (not part of the verdict)"
fi
if [ "$failed" -eq 0 ]; then
  echo "PASS: $runs runs ($((runs / ${#modes[@]})) rounds files x ${#modes[@]} modes), arm64 = x86-64 to 1e-9:" \
    "$((runs - not_unique)) whole results (largest difference $largest), $not_unique with a non-unique optimum" \
    "(status and optimal value)"
else
  echo "FAIL: $failed of $runs comparisons differ (see above; files in $work)"
  exit 1
fi
