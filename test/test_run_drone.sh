#!/bin/sh
# scripts/run-drone.sh's pre-flight checklist against simulated hardware: fact-sim (one drone of the
# small world, its simulated PX4 on MAVLink/UDP 127.0.0.1:14600) stands in for the drone's camera
# driver, VIO and flight controller. run-drone.sh --check-only starts the relay and the bridge and
# runs fact-preflight: it passes with everything present, and fails, naming the item, with a
# missing key, a key other users may read or write or own, a flight controller on the wrong port and no
# camera frames; bad flag values exit 2 before anything starts, and SIGTERM during the checklist
# exits 143 with nothing left running.
#
#   test/test_run_drone.sh REPO BUILD_DIR [RUN_SUFFIX]
#
# RUN_SUFFIX (".qemu" in cross builds) is appended to every app's path (FACT_RUN_SUFFIX of
# run-drone.sh). The pre-flight timeouts are scaled by FACT_TEST_TIME_SCALE (test/lib.sh).
# Re-runs itself in a private network namespace (scripts/netns-run.sh); exit 77 if none can be made.
set -eu
. "$(dirname "$0")/lib.sh"  # scaled (FACT_TEST_TIME_SCALE)
REPO=$1 BUILD=$2 SUFFIX=${3:-}
if [ -z "${FACT_RUN_DRONE_INNER:-}" ]; then
  rc=0
  FACT_RUN_DRONE_INNER=1 "$REPO/scripts/netns-run.sh" sh "$0" "$@" || rc=$?
  [ "$rc" -eq 125 ] && { echo "test_run_drone: no private network namespace here: skipped" >&2; exit 77; }
  exit "$rc"
fi
WORK=$(mktemp -d /tmp/fact-run-drone-XXXXXX)
URL='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'
"$BUILD/apps/fact_sim/fact-sim$SUFFIX" --world "$REPO/apps/fact_sim/worlds/small.json" --drones 1 --rate 1 --duration "$(scaled 120)" \
  --camera-rate 5 --mavlink-port 14600 --lcm-url "$URL" 2>"$WORK/sim.log" &
SIM=$!
trap 'kill $SIM 2>/dev/null; wait $SIM 2>/dev/null; rm -rf "$WORK"' EXIT
head -c 32 /dev/urandom >"$WORK/swarm.key"
chmod 600 "$WORK/swarm.key"
fail() { echo "test_run_drone: $*" >&2; cat "$WORK/out" >&2; exit 1; }
# check EXPECTED_RC EXTRA_FLAGS...: run-drone.sh --check-only, output in $WORK/out
check() {
  expected=$1
  shift
  rc=0
  BUILD_DIR="$BUILD" FACT_RUN_SUFFIX="$SUFFIX" "$REPO/scripts/run-drone.sh" --id 0 --camera lcm --vio lcm --lcm-url "$URL" --sim-clock \
    --no-build --check-only --out "$WORK/drone" "$@" >"$WORK/out" 2>&1 || rc=$?
  [ "$rc" -eq "$expected" ] || fail "run-drone.sh $* exited $rc, expected $expected"
}
check 0 --fc udp:14540:127.0.0.1:14600 --key "$WORK/swarm.key" --preflight-timeout "$(scaled 10)"
for item in "swarm key" "flight controller" "camera" "VIO"; do
  grep -q "\[PASS\] $item" "$WORK/out" || fail "the checklist did not pass '$item'"
done
grep -q "HEARTBEAT" "$WORK/out" || fail "the flight-controller line does not report the heartbeat"
check 1 --fc udp:14541:127.0.0.1:14600 --key "$WORK/missing.key" --preflight-timeout "$(scaled 3)"
grep -q "\[FAIL\] swarm key" "$WORK/out" || fail "a missing key file did not fail the key item"
for mode in 644 640 602; do  # readable or writable by another user
  chmod "$mode" "$WORK/swarm.key"
  check 1 --fc udp:14542:127.0.0.1:14600 --key "$WORK/swarm.key" --preflight-timeout "$(scaled 3)"
  grep -q "\[FAIL\] swarm key.*open to other users (mode $mode)" "$WORK/out" || fail "a key of mode $mode did not fail"
done
chmod 600 "$WORK/swarm.key"
if [ "$(id -u)" = 0 ]; then  # another user's key (that user may rewrite it); only root can chown
  cp "$WORK/swarm.key" "$WORK/other.key"
  chown 65534 "$WORK/other.key"
  check 1 --fc udp:14542:127.0.0.1:14600 --key "$WORK/other.key" --preflight-timeout "$(scaled 3)"
  grep -q "\[FAIL\] swarm key.*owned by uid 65534" "$WORK/out" || fail "a key owned by another user did not fail"
fi
check 1 --fc udp:14543:127.0.0.1:14699 --key "$WORK/swarm.key" --preflight-timeout "$(scaled 3)"
grep -q "\[FAIL\] flight controller" "$WORK/out" || fail "a flight controller on the wrong port did not fail"
check 1 --fc udp:14544:127.0.0.1:14600 --key "$WORK/swarm.key" --preflight-timeout "$(scaled 3)" \
  --camera 'lcm:udpm://239.255.77.9:7799?ttl=0'
grep -q "\[FAIL\] camera" "$WORK/out" || fail "no camera frames did not fail the camera item"
grep -q "must not fly" "$WORK/out" || fail "a failed checklist did not say the drone must not fly"
check 2 --fc bogus --key "$WORK/swarm.key"
grep -q "\-\-fc: expected" "$WORK/out" || fail "a bad --fc was not named"
check 2 --fc udp:14545:127.0.0.1:14600 --key "$WORK/swarm.key" --noise-quadratic -0.5
grep -q "\-\-noise-quadratic: expected a number > 0, got '-0.5'" "$WORK/out" || fail "a bad --noise-quadratic was not named"
# Flag values the apps would refuse only after the planner started (or read otherwise) exit 2 first.
check 2 --fc udp:14546:127.0.0.1:14600 --key "$WORK/swarm.key" --id 010
grep -q "no leading zero" "$WORK/out" || fail "--id 010 (octal 8 to the apps) was not refused"
check 2 --fc udp:14546:127.0.0.1:14600 --key "$WORK/swarm.key" --session 'flight 1'
grep -q "\-\-session: expected 1-64 characters" "$WORK/out" || fail "a bad --session was not refused"
check 2 --fc udp:14546:127.0.0.1:14600 --key "$WORK/swarm.key" --roster 1,2
grep -q "does not list this drone's --id 0" "$WORK/out" || fail "a roster without the drone was not refused"
check 2 --fc udp:14546:127.0.0.1:14600 --key "$WORK/swarm.key" --roster 0
grep -q "at least 2 drones" "$WORK/out" || fail "a one-drone roster was not refused"
check 2 --fc udp:14546:127.0.0.1:14600 --key "$WORK/swarm.key" --roster 0,1,1
grep -q "lists id 1 twice" "$WORK/out" || fail "a roster listing an id twice was not refused"
check 2 --fc udp:14546:127.0.0.1:14600 --key "$WORK/swarm.key" --preflight-timeout 0
grep -q "\-\-preflight-timeout: expected seconds in \[0.1, 3600\]" "$WORK/out" || fail "--preflight-timeout 0 was not refused"
# (beyond fact-preflight's own range: refused here, before any app is started)
check 2 --fc udp:14546:127.0.0.1:14600 --key "$WORK/swarm.key" --preflight-timeout 5000
grep -q "\-\-preflight-timeout: expected seconds in \[0.1, 3600\] .*got '5000'" "$WORK/out" ||
  fail "--preflight-timeout 5000 was not refused"
check 2 --fc udp:abc:127.0.0.1:14600 --key "$WORK/swarm.key"
grep -q "\-\-fc udp:LOCAL:HOST:PORT: expected ports" "$WORK/out" || fail "a bad --fc port was not refused"
# SIGTERM while the checklist waits: 143 (not 0, which says it passed), and nothing left running.
rc=0
BUILD_DIR="$BUILD" FACT_RUN_SUFFIX="$SUFFIX" "$REPO/scripts/run-drone.sh" --id 0 --camera lcm --vio lcm --lcm-url "$URL" \
  --sim-clock --no-build --check-only --out "$WORK/drone" --fc udp:14547:127.0.0.1:14699 --key "$WORK/swarm.key" \
  --preflight-timeout "$(scaled 30)" >"$WORK/out" 2>&1 &
RUN=$!
sleep "$(scaled 2)"
kill -TERM $RUN
wait $RUN || rc=$?
[ "$rc" -eq 143 ] || fail "SIGTERM during the checklist: exit $rc, expected 143"
sleep 0.5
! pgrep -f "fact-preflight.* --timeout $(scaled 30)" >/dev/null || fail "fact-preflight still runs after SIGTERM"
echo "test_run_drone: the checklist passes on simulated hardware and names each missing item"
