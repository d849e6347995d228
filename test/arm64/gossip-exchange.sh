#!/bin/sh
# An x86-64 and an arm64 fact-gossip exchange rounds over udpm:// (authenticated envelopes, libsodium
# on both sides) inside a private network namespace (scripts/netns-run.sh; the script re-runs
# itself there, so multicast never leaves it).
#   test/arm64/gossip-exchange.sh SIMGEN X86_GOSSIP ARM64_GOSSIP INJECT CHECK WORK_DIR
# SIMGEN, INJECT and CHECK are the x86-64 fact-simgen, fact_round_inject and
# fact_swarm_rounds_check; ARM64_GOSSIP the arm64 binary's runner
# (build-arm64/aarch64/apps/fact-gossip.qemu). Drone 0 is the x86-64 gossip, drone 1 the arm64 one;
# each is given only its own drone's round packets (FACT_ROUND_PACKET_<id>), so each can publish the
# complete rounds only with the other's packets, received over FACT_GOSSIP. Passes when both publish
# the same K complete rounds of drones 0 and 1, equal to what was injected (CHECK on their
# lcm-logger logs), and both exit 0 on SIGTERM. The last line is the verdict.
set -eu
if [ "$#" -ne 6 ]; then
  echo "usage: $0 SIMGEN X86_GOSSIP ARM64_GOSSIP INJECT CHECK WORK_DIR" >&2
  exit 2
fi
. "$(dirname "$0")/../lib.sh"  # wait_until, scaled (FACT_TEST_TIME_SCALE)
SIMGEN=$1 X86=$2 ARM=$3 INJECT=$4 CHECK=$5 WORK=$6
if [ -z "${FACT_GOSSIP_EXCHANGE_INNER:-}" ]; then
  netns_run="$(cd "$(dirname "$0")/../.." && pwd)/scripts/netns-run.sh"
  FACT_GOSSIP_EXCHANGE_INNER=1 exec "$netns_run" sh "$0" "$@"
fi

# ---- inside the private namespace (only lo, 224.0.0.0/4 on lo)
ROUNDS=2
URL='udpm://239.255.76.67:7667?ttl=0'
rm -rf "$WORK" && mkdir -p "$WORK"
PIDS=""
cleanup() {
  for pid in $PIDS; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in $PIDS; do wait "$pid" 2>/dev/null || true; done
}
trap cleanup EXIT
trap 'exit 1' INT TERM
fail() {
  echo "gossip-exchange: $*" >&2
  for f in "$WORK"/*.log; do [ -f "$f" ] && { echo "--- $f" >&2; tail -n 30 "$f" >&2; }; done
  echo "FAIL: $*"
  exit 1
}
has() { grep -a -q -- "$2" "$1" 2>/dev/null; }
both_have() { has "$WORK/$1""0$2" "$3" && has "$WORK/$1""1$2" "$3"; }

start=$(date +%s.%N)
"$SIMGEN" --drones 2 --rounds "$ROUNDS" --noise depth --seed 21 --output "$WORK/rounds.json" 2>"$WORK/simgen.log" ||
  fail "fact-simgen failed"
echo "5b1e0c9a7d3f2e4a6b8c0d1e2f3a4b5c6d7e8f90123456789abcdef012345678" >"$WORK/swarm.key"

for i in 0 1; do
  timeout "$(scaled 60)" lcm-logger -q -f --lcm-url="$URL" -c "FACT_SWARM_ROUNDS_$i|FACT_STATUS" "$WORK/rec$i.lcm" \
    2>"$WORK/logger$i.log" &
  PIDS="$PIDS $!"
done
gossip_pids=""
i=0
for gossip in "$X86" "$ARM"; do
  timeout "$(scaled 60)" "$gossip" --drone-id "$i" --lcm-url "$URL" --key-file "$WORK/swarm.key" --rounds-from-channel \
    --roster 0,1 --min-members 2 --summary-period 0.5 --settle 0.6 --status-period 0.25 2>"$WORK/gossip$i.log" &
  PIDS="$PIDS $!"
  gossip_pids="$gossip_pids $!"
  i=$((i + 1))
done
wait_until 30 both_have gossip .log "started:" || fail "a fact-gossip did not start"
wait_until 30 both_have rec .lcm FACT_STATUS || fail "an lcm-logger recorded no FACT_STATUS"

for i in 0 1; do
  timeout "$(scaled 30)" "$INJECT" --lcm-url "$URL" --drone-id "$i" --input "$WORK/rounds.json" --rounds "$ROUNDS" \
    2>"$WORK/inject$i.log" || fail "fact_round_inject failed for drone $i"
done
wait_until 30 both_have gossip .log "complete: $ROUNDS round(s) of drones \[0,1\]" ||
  fail "a gossip did not publish $ROUNDS complete rounds of drones 0 and 1"
sleep 0.3  # the loggers' flush interval is 100 ms

for pid in $PIDS; do kill -TERM "$pid" 2>/dev/null || true; done
for pid in $gossip_pids; do
  rc=0
  wait "$pid" || rc=$?
  [ "$rc" -eq 0 ] || fail "a fact-gossip exited with $rc on SIGTERM"
done
for pid in $PIDS; do wait "$pid" 2>/dev/null || true; done
PIDS=""

"$CHECK" --input "$WORK/rounds.json" --rounds "$ROUNDS" "$WORK/rec0.lcm" "$WORK/rec1.lcm" >"$WORK/check.log" 2>&1 ||
  fail "the published swarm rounds differ or are incomplete: $(cat "$WORK/check.log")"
echo "x86-64 (drone 0): $(grep -a -m1 "complete: $ROUNDS" "$WORK/gossip0.log")"
echo "arm64  (drone 1): $(grep -a -m1 "complete: $ROUNDS" "$WORK/gossip1.log")"
echo "PASS: x86-64 and arm64 fact-gossip exchanged $ROUNDS rounds over udpm:// in a private network namespace;" \
  "both published the same complete rounds of drones 0,1, equal to those injected" \
  "($(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }') s)"
