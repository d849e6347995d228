#!/bin/sh
# End-to-end test: the README's main job on a small world. scripts/run-sim.sh runs fact-sim with
# 3 drones and every drone's full app set (detector, VIO relay, gossip, solver, planner, bridge)
# in private network namespaces, --fast (lockstep with the detectors), then fact-run-report judges
# the swarm's certified result against the simulator's ground truth. Passes when run-sim.sh exits
# 0 (certified, every drone's frame within the bounds below) and it wrote the log, the picture and
# a report whose numbers agree with the bounds; then scripts/replay.sh replays the log into fresh
# solvers and planners and must show the same results and decisions. A recording that lost UDP
# messages (replay.sh refuses it, naming them) cannot show that: then the run is made once more,
# and the test fails if that one is incomplete too.
#
#   test/test_e2e_run_sim.sh REPO BUILD_DIR OUT_DIR
#
# Exit 77 (skipped) when no private network namespace can be made here.
set -eu
if [ "$#" -ne 3 ]; then
  echo "usage: $0 REPO BUILD_DIR OUT_DIR" >&2
  exit 2
fi
REPO=$1 BUILD=$2 OUT=$3
YAW_BOUND=0.03      # rad, every drone's frame yaw
POSITION_BOUND=0.15 # m, every drone's frame origin
fail() {
  echo "test_e2e_run_sim: $*" >&2
  for f in "$OUT"/logs/fact-planner-*.log "$OUT"/logs/fact-solver-*.log "$OUT"/logs/fact-sim.log; do
    [ -f "$f" ] && { echo "--- $f" >&2; tail -n 8 "$f" | cut -c1-300 >&2; }
  done
  exit 1
}
# One run and its replay. A recording that lost UDP messages (fact-log-compare names them, from
# the apps' own status counters) cannot be replayed to a match; that, and only that, is run once
# more, and fails the second time.
attempt=1
while :; do
  rm -rf "$OUT"
  rc=0
  BUILD_DIR="$BUILD" "$REPO/scripts/run-sim.sh" --no-build --quiet --fast --drones 3 \
    --world "$REPO/apps/fact_sim/worlds/small.json" --seed 1 --max-sim-time 120 --out "$OUT" \
    --yaw-bound "$YAW_BOUND" --position-bound "$POSITION_BOUND" || rc=$?
  if [ "$rc" -eq 125 ]; then
    echo "test_e2e_run_sim: no private network namespace here: skipped" >&2
    exit 77
  fi
  [ "$rc" -eq 0 ] || fail "run-sim.sh exited $rc (0 = certified and within bounds)"
  for f in run.lcm run.png report.json cpu.csv; do
    [ -s "$OUT/$f" ] || fail "$OUT/$f is missing or empty"
  done
  # The PNG signature, and the report's own verdict.
  [ "$(head -c 8 "$OUT/run.png" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ] || fail "run.png is not a PNG"
  grep -q '"certified": *true' "$OUT/report.json" || fail "report.json does not say certified"
  # Every drone's apps were measured.
  for app in fact-detector fact-vio-relay fact-gossip fact-solver fact-planner fact-fc-bridge; do
    [ "$(grep -c "^$app," "$OUT/cpu.csv")" -eq 3 ] || fail "cpu.csv lacks $app for 3 drones"
  done
  echo "test_e2e_run_sim: certified and within $YAW_BOUND rad / $POSITION_BOUND m"

  # The replay (scripts/replay.sh): fresh solvers and planners fed the recorded run publish the same
  # results byte for byte and take the same decisions.
  rc=0
  BUILD_DIR="$BUILD" "$REPO/scripts/replay.sh" "$OUT/run.lcm" --no-build --speed 1 --out "$OUT/replay" >"$OUT/replay.out" 2>&1 || rc=$?
  cat "$OUT/replay.out"
  if [ "$rc" -eq 2 ] && [ "$attempt" -eq 1 ] && grep -q "recorder lost" "$OUT/replay.out"; then
    echo "test_e2e_run_sim: the recording lost messages (above): running once more" >&2
    attempt=2
    continue
  fi
  [ "$rc" -eq 0 ] || fail "replay.sh exited $rc (0 = the replay matches)"
  grep -q "the replay matches the recorded run" "$OUT/replay.out" || fail "replay.sh did not say the replay matches"
  [ "$(grep -c "  yes  " "$OUT/replay.out")" -eq 3 ] || fail "replay.sh did not show 3 drones with identical results"
  break
done
# Bad input: a log that is not one.
printf 'not an lcm log' >"$OUT/garbage.lcm"
rc=0
BUILD_DIR="$BUILD" "$REPO/scripts/replay.sh" "$OUT/garbage.lcm" --no-build --drones 0 >"$OUT/replay-bad.out" 2>&1 || rc=$?
[ "$rc" -eq 2 ] || { cat "$OUT/replay-bad.out"; fail "replay.sh on a garbage log exited $rc, expected 2"; }
echo "test_e2e_run_sim: the replay matches; a garbage log is refused"
