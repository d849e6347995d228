#!/usr/bin/env bash
# CPU use of fact-fc-bridge at 50 Hz setpoint streaming + 100 Hz odometry forwarding (issue #6
# figure: <= 2 % of one core). Runs inside a private network namespace (scripts/netns-run.sh):
# fact_fc_bridge_peer publishes setpoints (50 Hz) and odometry (100 Hz) over LCM udpm and plays
# the flight controller on UDP 127.0.0.1 (HEARTBEAT 5 Hz, receives everything). The bridge
# reports its own getrusage (user + system CPU) and wall time when stopped.
#   bench/bridge_bench.sh [BUILD_DIR] [SECONDS]     (defaults: build, 10)
# Prints the figure and writes bench/results/bridge.txt.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=$(cd "${1:-$here/../build}" && pwd)
seconds=${2:-10}
bridge=$build/firmware_bridge/fact-fc-bridge
peer=$build/test/fact_fc_bridge_peer
for f in "$bridge" "$peer"; do
  [ -x "$f" ] || { echo "missing $f (build the targets fact-fc-bridge and fact_fc_bridge_peer)" >&2; exit 1; }
done
if [ "${FACT_BRIDGE_BENCH_IN_NETNS:-}" != 1 ]; then
  FACT_BRIDGE_BENCH_IN_NETNS=1 exec "$here/../scripts/netns-run.sh" bash "$0" "$build" "$seconds"
fi
work=$(mktemp -d)
pid=
# On any failure: the bridge is stopped and both logs are shown (a failed peer used to end the
# script silently, its log deleted and the bridge left running; review, session 34).
finish() {
  local rc=$?
  set +e  # (a bridge killed here makes wait fail; errexit would end the trap before the logs)
  [ -n "$pid" ] && kill "$pid" 2>/dev/null && wait "$pid" 2>/dev/null
  if [ "$rc" -ne 0 ]; then
    echo "bridge_bench: failed (exit $rc)" >&2
    for f in peer bridge; do [ -s "$work/$f.log" ] && { echo "--- $f log:" >&2; tail -n 20 "$work/$f.log" >&2; }; done
  fi
  rm -rf "$work"
  exit "$rc"
}
trap finish EXIT
url='udpm://239.255.76.67:7667?ttl=0'
"$bridge" --drone-id 0 --lcm-url "$url" --udp 14700:127.0.0.1:14701 --stream-rate 50 2>"$work/bridge.log" &
pid=$!
sleep 0.3
"$peer" --lcm-url "$url" --drone-id 0 --fc-port 14701 --bridge-port 14700 --duration "$seconds" \
  --setpoint-rate 50 --odometry-rate 100 2>"$work/peer.log"
kill -INT "$pid"
wait "$pid"
pid=
line=$(grep -o 'cpu_s=.*' "$work/bridge.log" | tail -1)
[ -n "$line" ] || { echo "bridge_bench: the bridge reported no cpu_s line" >&2; exit 1; }
cpu=$(sed -E 's/.*cpu_s=([0-9.e-]+).*/\1/' <<<"$line")
wall=$(sed -E 's/.*wall_s=([0-9.e-]+).*/\1/' <<<"$line")
result=$(awk -v c="$cpu" -v w="$wall" 'BEGIN { printf "%.2f", 100 * c / w }')
{
  echo "fact-fc-bridge CPU at 50 Hz SET_POSITION_TARGET_LOCAL_NED + 100 Hz ODOMETRY (UDP loopback, LCM udpm)"
  echo "date: $(date -u +%Y-%m-%dT%H:%M:%SZ)  host: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
  echo "bridge: $line"
  echo "peer: $(cat "$work/peer.log")"
  echo "cpu_percent_of_one_core: $result  (target <= 2)"
} >"$work/bridge.txt"
cat "$work/bridge.txt"
mkdir -p "$here/results"
cp "$work/bridge.txt" "$here/results/bridge.txt.partial" && mv "$here/results/bridge.txt.partial" "$here/results/bridge.txt"
