#!/bin/sh
# Multi-host gossip test: 4 fact-gossip processes, each in its own network namespace (as if on its
# own host), joined by veth pairs to one bridge, talking udpm with ttl=1.
#
#   test/test_gossip_multi_host.sh NETNS_RUN SIMGEN GOSSIP INJECT CHECK
#
# NETNS_RUN is scripts/netns-run.sh; the others the fact-simgen, fact-gossip, fact_round_inject and
# fact_swarm_rounds_check binaries. The script re-runs itself inside one outer private network
# namespace (NETNS_RUN), so the bridge and the veths never touch the host's network. There:
#   bridge br0 ── veth ── namespace fact-mh-<pid>-<i> (10.77.0.<i+1>/24, 224.0.0.0/4 on the veth)
# and in each drone namespace: lcm-logger (its drone's FACT_SWARM_ROUNDS_<i>, FACT_STATUS), fact-gossip
# --rounds-from-channel with a swarm key, then fact_round_inject with that drone's rounds of a
# fact-simgen scenario. Passes when every gossip published the K complete rounds of all drones,
# identical across drones and equal to what was injected, and every gossip exits 0 on SIGTERM.
# Exit 77 (skipped) without root, ip or unshare. Namespaces and processes are removed on any exit.
set -eu
. "$(dirname "$0")/lib.sh"  # wait_until, scaled (FACT_TEST_TIME_SCALE)

if [ "$#" -ne 5 ]; then
  echo "usage: $0 NETNS_RUN SIMGEN GOSSIP INJECT CHECK" >&2
  exit 2
fi
NETNS_RUN=$1 SIMGEN=$2 GOSSIP=$3 INJECT=$4 CHECK=$5

if [ -z "${FACT_MULTI_HOST_INNER:-}" ]; then
  if [ "$(id -u)" -ne 0 ] || ! command -v ip >/dev/null 2>&1 || ! command -v unshare >/dev/null 2>&1; then
    echo "test_gossip_multi_host: needs root, ip and unshare: skipped" >&2
    exit 77
  fi
  rc=0
  FACT_MULTI_HOST_INNER=1 "$NETNS_RUN" sh "$0" "$@" || rc=$?
  [ "$rc" -eq 125 ] && { echo "test_gossip_multi_host: no private network namespace here: skipped" >&2; exit 77; }
  exit "$rc"
fi

# ---- inside the outer private namespace ----
DRONES=4
ROUNDS=3
URL='udpm://239.255.76.67:7667?ttl=1'
PREFIX="fact-mh-$$"
WORK=$(mktemp -d /tmp/fact-gossip-multi-host-XXXXXX)
PIDS=""
GOSSIP_PIDS=""

cleanup() {
  # SIGTERM (timeout passes it on to its command), then SIGKILL whatever still runs in our namespaces.
  for pid in $PIDS; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in $PIDS; do wait "$pid" 2>/dev/null || true; done
  i=0
  while [ "$i" -lt "$DRONES" ]; do
    for pid in $(ip netns pids "$PREFIX-$i" 2>/dev/null); do kill -KILL "$pid" 2>/dev/null || true; done
    ip netns del "$PREFIX-$i" 2>/dev/null || true
    i=$((i + 1))
  done
  ip link del br0 2>/dev/null || true
  rm -rf "$WORK"
}
trap cleanup EXIT
trap 'exit 1' INT TERM

fail() {
  echo "test_gossip_multi_host: $*" >&2
  for f in "$WORK"/*.log; do [ -f "$f" ] && { echo "--- $f" >&2; tail -n 40 "$f" >&2; }; done
  exit 1
}

has() { grep -a -q -- "$2" "$1" 2>/dev/null; }
all_have() {  # all_have SUFFIX TEXT: every drone's file $WORK/<kind><i><suffix> contains TEXT
  j=0
  while [ "$j" -lt "$DRONES" ]; do
    has "$WORK/$1$j$2" "$3" || return 1
    j=$((j + 1))
  done
}

"$SIMGEN" --drones "$DRONES" --rounds "$ROUNDS" --seed 11 --output "$WORK/rounds.json" 2>"$WORK/simgen.log" ||
  fail "fact-simgen failed"
echo "8f3c6a1d2e4b5f60718293a4b5c6d7e89011223344556677889900aabbccddee" >"$WORK/swarm.key"

# The bridge (in the outer namespace) and one namespace per drone on a veth pair.
ip link add br0 type bridge mcast_snooping 0 || fail "cannot create the bridge"
ip link set br0 up
i=0
while [ "$i" -lt "$DRONES" ]; do
  ns="$PREFIX-$i"
  ip netns add "$ns" || fail "cannot create namespace $ns"
  ip link add "vh$i" type veth peer name "vd$i" || fail "cannot create veth pair $i"
  ip link set "vd$i" netns "$ns"
  ip link set "vh$i" master br0
  ip link set "vh$i" up
  ip netns exec "$ns" sh -c "
    ip link set lo up &&
    ip addr add 10.77.0.$((i + 1))/24 dev vd$i &&
    ip link set vd$i up &&
    ip route add 224.0.0.0/4 dev vd$i" || fail "cannot set up namespace $ns"
  i=$((i + 1))
done

# In each drone namespace: the logger, then the gossip.
i=0
while [ "$i" -lt "$DRONES" ]; do
  ns="$PREFIX-$i"
  ip netns exec "$ns" timeout "$(scaled 45)" lcm-logger -q -f --lcm-url="$URL" -c "FACT_SWARM_ROUNDS_$i|FACT_STATUS" \
    "$WORK/rec$i.lcm" 2>"$WORK/logger$i.log" &
  PIDS="$PIDS $!"
  ip netns exec "$ns" timeout "$(scaled 45)" "$GOSSIP" --drone-id "$i" --lcm-url "$URL" --key-file "$WORK/swarm.key" \
    --rounds-from-channel --roster 0,1,2,3 --min-members "$DRONES" --summary-period 0.5 --settle 0.6 \
    --status-period 0.25 2>"$WORK/gossip$i.log" &
  PIDS="$PIDS $!"
  GOSSIP_PIDS="$GOSSIP_PIDS $!"
  i=$((i + 1))
done
wait_until 10 all_have gossip .log "started:" || fail "not every fact-gossip started"
# Each logger is live once it has recorded a gossip's heartbeat.
wait_until 10 all_have rec .lcm FACT_STATUS || fail "not every lcm-logger recorded FACT_STATUS"

i=0
while [ "$i" -lt "$DRONES" ]; do
  ip netns exec "$PREFIX-$i" timeout "$(scaled 20)" "$INJECT" --lcm-url "$URL" --drone-id "$i" --input "$WORK/rounds.json" \
    --rounds "$ROUNDS" 2>"$WORK/inject$i.log" || fail "fact_round_inject failed for drone $i"
  i=$((i + 1))
done

wait_until 20 all_have gossip .log "complete: $ROUNDS round(s) of drones \[0,1,2,3\]" ||
  fail "not every gossip published $ROUNDS complete rounds of drones 0-3"
sleep 0.3  # the loggers' flush interval is 100 ms

# Stop: every gossip must exit 0 on SIGTERM; the loggers flush and close.
for pid in $PIDS; do kill -TERM "$pid" 2>/dev/null || true; done
for pid in $GOSSIP_PIDS; do
  rc=0
  wait "$pid" || rc=$?
  [ "$rc" -eq 0 ] || fail "a fact-gossip exited with $rc on SIGTERM"
done
for pid in $PIDS; do wait "$pid" 2>/dev/null || true; done
PIDS=""

"$CHECK" --input "$WORK/rounds.json" --rounds "$ROUNDS" "$WORK"/rec0.lcm "$WORK"/rec1.lcm "$WORK"/rec2.lcm \
  "$WORK"/rec3.lcm || fail "the swarm rounds differ or are incomplete"
# Each gossip could only reach the others over its veth and the bridge.
grep -a -h "complete: $ROUNDS" "$WORK"/gossip*.log >&2
echo "test_gossip_multi_host: $DRONES drones in $DRONES namespaces agree on $ROUNDS complete rounds" >&2
