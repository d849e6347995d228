#!/usr/bin/env bash
# Replays a recorded run into fresh fact-solver and fact-planner processes and shows that the
# result matches:
#
#   scripts/replay.sh build/run-sim/run.lcm            (a log written by scripts/run-sim.sh)
#   scripts/replay.sh LOG --speed 4 --out /tmp/replay
#
# Inside a private network namespace it makes itself (udpm never leaves it), lcm-logplayer plays
# the log's simulation clock, odometry, detections and complete rounds (FACT_SIM_CLOCK,
# FACT_ODOMETRY_<id>, FACT_DETECTIONS_<id>, FACT_SWARM_ROUNDS_<id>) — not its results, setpoints or
# status — into one fresh fact-solver and one fresh fact-planner per drone, on the log's
# simulation clock, while lcm-logger records what they publish (OUT/replay.lcm). Then
# fact-log-compare checks, per drone, that the fresh solver published the same results byte for
# byte (fact-solver's results carry their input's utime and no timing, so they are reproducible)
# and that the fresh planner took the same decisions (its phase-and-round sequence, e.g.
# takeoff round 0 → spin round 0 → move round 1 → … → done round 2; waits are not decisions).
# The frames are not in the log (they stay on the per-drone camera groups), so the fresh planner's
# obstacle map is empty: its move targets may differ by the obstacle push-out, its decisions do not.
# The planners are started with the run's seed, spin rate and round limit, and the solvers with its
# range noise model, from run-params.txt beside the log (written by run-sim.sh), or from the flags;
# a log without noise_quadratic there ran with the solver's default, and so does its replay.
#
# Flags: --out DIR (default: LOG's folder /replay), --speed X (lcm-logplayer speed, default 1),
# --drones IDS (comma separated; default: from run-params.txt, else every drone with a result in
# the log), --seed S, --spin-rate R, --max-rounds K, --noise-quadratic Q (override run-params.txt),
# --no-build.
# Exit codes: 0 the replay matches; 1 it differs (the table says what); 2 bad input (unreadable
# log, no result in it, a drone id without a result, a log that lost messages — fewer results or
# complete rounds of a drone than its apps' FACT_STATUS counters grew by in it — bad flags);
# 125 no private namespace.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
. "$here/scripts/lib/args.sh"
. "$here/scripts/lib/netns.sh"

die() { echo "replay: $*" >&2; exit 2; }
[ "$#" -ge 1 ] || die "usage: scripts/replay.sh LOG [--out DIR] [--speed X] [--drones IDS] [--seed S] [--spin-rate R] [--max-rounds K] [--noise-quadratic Q] [--no-build]"
case "$1" in -h|--help) sed -n '2,30p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;; esac
log=$1
shift
out="" speed=1 drones="" seed="" spin_rate="" max_rounds="" noise_quadratic="" build=1
while [ "$#" -gt 0 ]; do
  case "$1" in
    --out) [ "$#" -ge 2 ] || die "--out needs a value"; out=$2; shift 2 ;;
    --speed) [ "$#" -ge 2 ] || die "--speed needs a value"; speed=$2; shift 2 ;;
    --drones) [ "$#" -ge 2 ] || die "--drones needs a value"; drones=$2; shift 2 ;;
    --seed) [ "$#" -ge 2 ] || die "--seed needs a value"; seed=$2; shift 2 ;;
    --spin-rate) [ "$#" -ge 2 ] || die "--spin-rate needs a value"; spin_rate=$2; shift 2 ;;
    --max-rounds) [ "$#" -ge 2 ] || die "--max-rounds needs a value"; max_rounds=$2; shift 2 ;;
    --noise-quadratic) [ "$#" -ge 2 ] || die "--noise-quadratic needs a value"; noise_quadratic=$2; shift 2 ;;
    --no-build) build=0; shift ;;
    *) die "unknown flag '$1'" ;;
  esac
done
[ -r "$log" ] && [ -s "$log" ] || die "LOG: cannot read '$log'"
log="$(cd "$(dirname "$log")" && pwd)/$(basename "$log")"
is_positive "$speed" || die "--speed: expected a number > 0, got '$speed'"

# The run's parameters (key=value lines; only these keys are read, nothing is executed).
params="$(dirname "$log")/run-params.txt"
param() { [ -r "$params" ] || return 0; sed -n "s/^$1=\([-0-9.,]*\)$/\1/p" "$params" | head -n 1; }
drones=${drones:-$(param ids)}
seed=${seed:-$(param seed)}
seed=${seed:-1}
spin_rate=${spin_rate:-$(param spin_rate)}
spin_rate=${spin_rate:-1.2}
max_rounds=${max_rounds:-$(param max_rounds)}
max_rounds=${max_rounds:-8}
noise_quadratic=${noise_quadratic:-$(param noise_quadratic)}
[[ "$seed" =~ ^[0-9]{1,9}$ ]] || die "--seed: expected a non-negative integer (at most 9 digits), got '$seed'"
[[ "$max_rounds" =~ ^[0-9]{1,6}$ ]] && [ "$((10#$max_rounds))" -ge 1 ] ||
  die "--max-rounds: expected a positive integer, got '$max_rounds'"
# Decimal, as run-sim.sh reads them ("08" is not octal; "010" is 10, not 8).
seed=$((10#$seed))
max_rounds=$((10#$max_rounds))
[[ "$spin_rate" =~ ^[0-9]+([.][0-9]+)?$ ]] || die "--spin-rate: expected a number, got '$spin_rate'"
[ -z "$noise_quadratic" ] || is_positive "$noise_quadratic" ||
  die "--noise-quadratic: expected a number > 0, got '$noise_quadratic'"
[ -z "$drones" ] || [[ "$drones" =~ ^[0-9]+(,[0-9]+)*$ ]] || die "--drones: expected ids like 0,1,2, got '$drones'"

build_dir="${BUILD_DIR:-$here/build}"
out="${out:-$(dirname "$log")/replay}"
mkdir -p "$out"
out="$(cd "$out" && pwd)"

if [ -z "${FACT_REPLAY_INNER:-}" ]; then
  if [ "$build" = 1 ]; then
    "$here/scripts/install-deps.sh"
    cmake -S "$here" -B "$build_dir" -DCMAKE_BUILD_TYPE=Release >"$build_dir.configure.log" 2>&1 ||
      { cat "$build_dir.configure.log"; exit 1; }
    cmake --build "$build_dir" -j "$(nproc)" --target fact-solver fact-planner fact-log-compare >"$build_dir.build.log" 2>&1 ||
      { tail -n 40 "$build_dir.build.log"; exit 1; }
  fi
  # The log must hold results of the drones to replay (fact-log-compare of the log with itself
  # names what is wrong); which drones: the flag, run-params.txt, else every drone with a result.
  check=$("$build_dir/apps/fact-log-compare" "$log" "$log" --no-planner ${drones:+--drones "$drones"} 2>&1) ||
    die "$log cannot be replayed: $(echo "$check" | grep -m1 error || echo "$check" | tail -n 1)"
  [ -n "$drones" ] || drones=$(echo "$check" | awk '$1 ~ /^[0-9]+$/ { printf "%s%s", sep, $1; sep = "," }')
  rc=0
  FACT_REPLAY_INNER=1 BUILD_DIR="$build_dir" "$here/scripts/netns-run.sh" bash "${BASH_SOURCE[0]}" "$log" --out "$out" \
    --speed "$speed" --drones "$drones" --seed "$seed" --spin-rate "$spin_rate" --max-rounds "$max_rounds" \
    ${noise_quadratic:+--noise-quadratic "$noise_quadratic"} --no-build || rc=$?
  exit "$rc"
fi

# ---------------------------------------------------------------- inside the private namespace
# FACT_REPLAY_INNER is this script's own marker for its second pass; set by hand outside a private
# namespace, the apps would talk udpm on the machine's interfaces (review, session 33).
foreign=$(foreign_interfaces)
if [ -n "$foreign" ]; then
  echo "replay: FACT_REPLAY_INNER is set but this is not a private network namespace (interfaces: $foreign);" >&2
  echo "  refusing to send multicast here. Unset it: replay.sh makes its own namespace." >&2
  exit 125
fi
URL='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=2097152'
B="$build_dir"
for b in "$B/apps/fact-solver" "$B/apps/fact_planner/fact-planner" "$B/apps/fact-log-compare"; do
  [ -x "$b" ] || { echo "replay: $b is missing (build first, or drop --no-build)" >&2; exit 1; }
done
rm -rf "$out/logs" "$out/replay.lcm"
mkdir -p "$out/logs"
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do wait "$p" 2>/dev/null || true; done
}
trap cleanup EXIT
lcm-logger --lcm-url="$URL" --quiet -c '^(FACT_RESULT_[0-9]+|FACT_SETPOINT_[0-9]+|FACT_STATUS)$' "$out/replay.lcm" \
  >"$out/logs/lcm-logger.log" 2>&1 &
logger=$!
for id in ${drones//,/ }; do
  c=(--drone-id "$id" --lcm-url "$URL" --sim-clock)
  "$B/apps/fact-solver" "${c[@]}" ${noise_quadratic:+--noise-quadratic "$noise_quadratic"} \
    >"$out/logs/fact-solver-$id.log" 2>&1 &
  pids+=("$!")
  "$B/apps/fact_planner/fact-planner" "${c[@]}" --seed "$((seed * 100 + id))" --spin-rate "$spin_rate" \
    --max-rounds "$max_rounds" >"$out/logs/fact-planner-$id.log" 2>&1 &
  pids+=("$!")
done
sleep 0.5
echo "== replaying $log at ${speed}x into fresh fact-solver and fact-planner for drones $drones (seed $seed)"
start=$(date +%s)
lcm-logplayer --lcm-url="$URL" --speed="$speed" \
  --regexp='^(FACT_SIM_CLOCK|FACT_ODOMETRY_[0-9]+|FACT_DETECTIONS_[0-9]+|FACT_SWARM_ROUNDS_[0-9]+)$' "$log" \
  >"$out/logs/lcm-logplayer.log" 2>&1 || { echo "replay: lcm-logplayer failed (see $out/logs/lcm-logplayer.log)" >&2; exit 2; }
sleep 1  # the last results and states
cleanup
pids=()
kill -INT "$logger" 2>/dev/null || true
wait "$logger" 2>/dev/null || true
echo "== played in $(($(date +%s) - start)) s; fresh processes' messages in $out/replay.lcm, their logs in $out/logs/"
"$B/apps/fact-log-compare" "$log" "$out/replay.lcm" --drones "$drones"
