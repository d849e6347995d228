#!/usr/bin/env bash
# Setpoint stream of fact-planner under CPU load (issue #6 figure: >= 20 Hz, jitter <= 5 ms).
# Inside a private network namespace (scripts/netns-run.sh): fact-sim (2 drones, real time, LCM
# setpoints) → raw VIO → fact-vio-relay → fact-planner (drone 0: takeoff, spin, wait) →
# FACT_SETPOINT_0, recorded by lcm-logger, while one busy loop per core (`yes > /dev/null`) loads
# the machine. The interval between consecutive setpoints as lcm-logger received them is compared
# with the nominal 1/30 s: jitter = |interval − nominal|.
#   bench/setpoint_jitter.sh [BUILD_DIR] [SECONDS]     (defaults: build, 20)
# Prints the figures and writes bench/results/setpoint_jitter.txt.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=$(cd "${1:-$here/../build}" && pwd)
seconds=${2:-20}
sim=$build/apps/fact_sim/fact-sim
relay=$build/apps/fact-vio-relay
planner=$build/apps/fact_planner/fact-planner
for f in "$sim" "$relay" "$planner"; do
  [ -x "$f" ] || { echo "missing $f (build fact-sim, fact-vio-relay and fact-planner)" >&2; exit 1; }
done
command -v lcm-logger >/dev/null || { echo "missing lcm-logger (Debian liblcm-bin)" >&2; exit 1; }
if [ "${FACT_JITTER_IN_NETNS:-}" != 1 ]; then
  FACT_JITTER_IN_NETNS=1 exec "$here/../scripts/netns-run.sh" bash "$0" "$build" "$seconds"
fi
work=$(mktemp -d)
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; wait 2>/dev/null || true; rm -rf "$work"; }
trap cleanup EXIT
url='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'
"$sim" --drones 2 --seed 3 --rate 1 --camera-rate 5 --lcm-url "$url" 2>"$work/sim.log" & pids+=($!)
"$relay" --drone-id 0 --lcm-url "$url" 2>"$work/relay.log" & pids+=($!)
"$planner" --drone-id 0 --lcm-url "$url" --wait-timeout 60 2>"$work/planner.log" & pids+=($!)
sleep 2
for ((i = 0; i < $(nproc); ++i)); do (exec yes >/dev/null) & pids+=($!); done
lcm-logger --lcm-url "$url" --channel 'FACT_SETPOINT_0' "$work/setpoints.lcmlog" >/dev/null 2>&1 & logger=$!
pids+=($logger)
sleep "$seconds"
kill -INT "$logger"; wait "$logger" 2>/dev/null || true
# The figures go to $work first and replace the results file only when they were computed (a run
# that recorded nothing used to empty it through tee).
/usr/bin/python3 - "$work/setpoints.lcmlog" "$seconds" >"$work/jitter.txt" <<'PY'
import struct, sys, statistics, os, datetime
data = open(sys.argv[1], "rb").read()
times, pos = [], 0
while pos + 28 <= len(data):
    sync, _, utime, clen, dlen = struct.unpack(">IqqII", data[pos:pos + 28])
    if sync != 0xEDA1DA01: raise SystemExit("not an LCM log")
    times.append(utime); pos += 28 + clen + dlen
if len(times) < 10: raise SystemExit("only %d setpoints recorded" % len(times))
iv = [(b - a) / 1000.0 for a, b in zip(times, times[1:])]  # ms
nominal = 1000.0 / 30
jit = sorted(abs(x - nominal) for x in iv)
rate = (len(times) - 1) / ((times[-1] - times[0]) / 1e6)
print("fact-planner setpoint stream under load (%d busy loops on %d cores), %s s, %s" % (os.cpu_count(), os.cpu_count(), sys.argv[2], datetime.datetime.utcnow().strftime("%Y-%m-%dT%H:%M:%SZ")))
print("setpoints %d, rate %.2f Hz (target >= 20)" % (len(times), rate))
print("interval ms: median %.2f, min %.2f, max %.2f" % (statistics.median(iv), min(iv), max(iv)))
print("jitter ms (|interval - %.2f|): median %.3f, p99 %.3f, max %.3f (target <= 5)" % (nominal, statistics.median(jit), jit[min(len(jit) - 1, int(0.99 * len(jit)))], jit[-1]))
PY
cat "$work/jitter.txt"
mkdir -p "$here/results"
cp "$work/jitter.txt" "$here/results/setpoint_jitter.txt.partial" &&
  mv "$here/results/setpoint_jitter.txt.partial" "$here/results/setpoint_jitter.txt"
