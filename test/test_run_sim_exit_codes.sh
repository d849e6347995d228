#!/bin/bash
# scripts/run-sim.sh's exit codes on runs that do not end certified, each checked on a real run of
# 2 drones on the small world (--fast, private namespaces as always):
#   - a run too short for any result: 3 (not certified), report.json says no result;
#   - an app killed during the run: 1, naming the app;
#   - its internal FACT_RUN_SIM_INNER marker set by hand outside a private namespace: 125, and no
#     app is started (multicast would otherwise reach the machine's interfaces); the same for
#     replay.sh's FACT_REPLAY_INNER;
#   - a seed with a leading zero is decimal ("08"), not a bad octal number;
#   - the solvers run with the range noise model of the simulated camera (0.005/m at 640x480),
#     recorded in run-params.txt for replay.sh; a bad --noise-quadratic is refused (2), naming it.
#
#   test/test_run_sim_exit_codes.sh REPO BUILD_DIR OUT_DIR
#
# Exit 77 (skipped) when no private network namespace can be made here.
set -u
if [ "$#" -ne 3 ]; then
  echo "usage: $0 REPO BUILD_DIR OUT_DIR" >&2
  exit 2
fi
REPO=$1 BUILD=$2 OUT=$3
. "$(dirname "$0")/lib.sh"
rm -rf "$OUT"
mkdir -p "$OUT"
fail() {
  echo "test_run_sim_exit_codes: $*" >&2
  exit 1
}
run_sim() {  # run_sim NAME FLAGS...: run-sim.sh into $OUT/NAME, output in $OUT/NAME.out
  local name=$1
  shift
  BUILD_DIR="$BUILD" "$REPO/scripts/run-sim.sh" --no-build --quiet --fast --drones 2 \
    --world "$REPO/apps/fact_sim/worlds/small.json" --out "$OUT/$name" "$@" >"$OUT/$name.out" 2>&1
}

# 1. Too short for a result: not certified (3), and the report says why.
rc=0
run_sim short --seed 08 --max-sim-time 3 || rc=$?
[ "$rc" -eq 125 ] && { echo "test_run_sim_exit_codes: no private network namespace here: skipped" >&2; exit 77; }
[ "$rc" -eq 3 ] || { cat "$OUT/short.out"; fail "a 3 s run exited $rc, expected 3 (not certified)"; }
grep -q '"status": "no_result"' "$OUT/short/report.json" || fail "report.json does not say no_result"
grep -q '"certified": false' "$OUT/short/report.json" || fail "report.json does not say certified false"
grep -q "^seed=8$" "$OUT/short/run-params.txt" || fail "--seed 08 was not read as 8: $(cat "$OUT/short/run-params.txt")"
grep -q "reached --max-sim-time" "$OUT/short.out" || fail "the 3 s run does not say it reached --max-sim-time"
grep -q "^noise_quadratic=0.005$" "$OUT/short/run-params.txt" ||
  fail "run-params.txt does not record the camera's noise model 0.005: $(cat "$OUT/short/run-params.txt")"
for id in 0 1; do
  grep -q "0.005\*d^2" "$OUT/short/logs/fact-solver-$id.log" ||
    fail "fact-solver-$id does not run with the camera's range model: $(head -n 5 "$OUT/short/logs/fact-solver-$id.log")"
done
rc=0
run_sim badnoise --noise-quadratic 0 || rc=$?
[ "$rc" -eq 2 ] || { cat "$OUT/badnoise.out"; fail "--noise-quadratic 0 exited $rc, expected 2"; }
grep -q "noise-quadratic: expected a number > 0, got '0'" "$OUT/badnoise.out" || fail "the refusal does not name --noise-quadratic"
# Values the apps would refuse only after the start (exit 1, "exited early") are refused first: 2.
for bad in "--max-rounds 2.5" "--spin-rate 50" "--camera-rate 500"; do
  rc=0
  # shellcheck disable=SC2086
  run_sim badflag $bad || rc=$?
  [ "$rc" -eq 2 ] || { cat "$OUT/badflag.out"; fail "$bad exited $rc, expected 2"; }
  grep -q -- "${bad%% *}" "$OUT/badflag.out" || fail "the refusal of $bad does not name the flag"
done

# 2. An app killed during the run: 1, naming it. The solver of drone 1 is found by its log file,
# which only that process holds open.
run_sim killed --max-sim-time 60 &
sim=$!
log="$OUT/killed/logs/fact-solver-1.log"
victim=""
writer_of_log() {  # sets victim to the pid whose stdout is $log
  [ -s "$log" ] || return 1
  victim=$(for fd in /proc/[0-9]*/fd/1; do
    [ "$(readlink "$fd" 2>/dev/null)" = "$log" ] && { p=${fd#/proc/}; echo "${p%%/*}"; }
  done | head -n 1)
  [ -n "$victim" ]
}
wait_until 20 writer_of_log || { kill "$sim"; fail "no process writes $log"; }
[ "$(cat "/proc/$victim/comm")" = fact-solver ] || fail "pid $victim writing $log is $(cat "/proc/$victim/comm")"
kill -KILL "$victim"
rc=0
wait "$sim" || rc=$?
[ "$rc" -eq 1 ] || { cat "$OUT/killed.out"; fail "a run whose solver was killed exited $rc, expected 1"; }
grep -q "FAILED: fact-solver-1 exited early" "$OUT/killed.out" || { cat "$OUT/killed.out"; fail "the failure does not name fact-solver-1"; }

# 3. The internal marker outside a private namespace (only checkable where this machine has an
# interface besides lo, as every real machine has).
if awk -F: 'NR > 2 { gsub(/ /, "", $1); if ($1 != "lo") found = 1 } END { exit !found }' /proc/net/dev; then
  rc=0
  FACT_RUN_SIM_INNER=shared FACT_RUN_SIM_BUILD="$BUILD" run_sim marker --max-sim-time 3 || rc=$?
  [ "$rc" -eq 125 ] || { cat "$OUT/marker.out"; fail "FACT_RUN_SIM_INNER outside a namespace exited $rc, expected 125"; }
  grep -q "not a private network namespace" "$OUT/marker.out" || fail "the refusal does not say why"
  [ ! -e "$OUT/marker/logs" ] || fail "apps were started outside a private namespace"
fi
# replay.sh's own marker (FACT_REPLAY_INNER) in a namespace that has an interface besides lo (a
# veth made in a private namespace, so that nothing reaches the host even if the guard failed):
# 125, naming the interface, and no app started.
printf 'not read\n' >"$OUT/fake.lcm"
rc=0
"$REPO/scripts/netns-run.sh" bash -c "ip link add fact-rv0 type veth peer name fact-rv1 &&
  FACT_REPLAY_INNER=1 BUILD_DIR='$BUILD' '$REPO/scripts/replay.sh' '$OUT/fake.lcm' --out '$OUT/replay-marker' --no-build" \
  >"$OUT/replay-marker.out" 2>&1 || rc=$?
[ "$rc" -eq 125 ] || { cat "$OUT/replay-marker.out"; fail "FACT_REPLAY_INNER outside a private namespace exited $rc, expected 125"; }
grep -q "not a private network namespace (interfaces: fact-rv" "$OUT/replay-marker.out" ||
  { cat "$OUT/replay-marker.out"; fail "replay.sh's refusal does not name the interface"; }
[ ! -e "$OUT/replay-marker/logs" ] || fail "replay.sh started apps outside a private namespace"
# 4. A run killed by SIGKILL (a ctest timeout) leaves no network namespace on the host: the ones
# 'ip netns add' makes inside netns-run.sh live in its private mount namespace.
if command -v ip >/dev/null 2>&1; then
  leak="fact-leak-test-$$"
  "$REPO/scripts/netns-run.sh" sh -c "ip netns add $leak && kill -KILL \$\$" 2>/dev/null || true
  ! ip netns list 2>/dev/null | grep -q "$leak" || { ip netns del "$leak"; fail "a SIGKILLed run left namespace $leak"; }
  [ ! -e "/run/netns/$leak" ] || { rm -f "/run/netns/$leak"; fail "a SIGKILLed run left /run/netns/$leak"; }
fi
# 5. Bus logs an earlier run kept (its merge failed or warned) are not thrown away: a run into the
# same --out refuses to start (2) and leaves them (review, session 33: they were removed).
mkdir -p "$OUT/kept/logs"
printf 'kept\n' >"$OUT/kept/logs/bus-1.lcm"
rc=0
run_sim kept --max-sim-time 1 || rc=$?
[ "$rc" -eq 2 ] || { cat "$OUT/kept.out"; fail "a run into an --out with kept bus logs exited $rc, expected 2"; }
grep -q "holds bus logs an earlier run kept" "$OUT/kept.out" || { cat "$OUT/kept.out"; fail "the refusal does not say why"; }
[ "$(cat "$OUT/kept/logs/bus-1.lcm")" = kept ] || fail "the kept bus log was removed"
# 6. --drones with a leading zero is decimal for the apps too ("08" is 8; the apps refuse 08, and
# read 010 as octal 8).
rc=0
run_sim drones08 --drones 08 --max-sim-time 1 || rc=$?
grep -q "== 8 drones" "$OUT/drones08.out" || { cat "$OUT/drones08.out"; fail "--drones 08 did not run 8 drones (exit $rc)"; }
echo "test_run_sim_exit_codes: no result 3, killed app 1, marker outside a namespace 125 (run-sim and replay), kept bus logs refused, --drones 08 is 8, seed 08 read as 8, camera noise model used"
