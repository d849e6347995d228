#!/usr/bin/env bash
# The main job: a simulated swarm initializing end to end. fact-sim plays N drones in a room with
# obstacles; every drone runs its own full set of apps (fact-detector, fact-vio-relay, fact-gossip,
# fact-solver, fact-planner, fact-fc-bridge) in its own private network namespace, talking udpm://
# with ttl=1 across a bridge this script makes (never on the machine's real interfaces). The loop
# runs takeoff → spin → detect → gossip → solve → move … until the swarm's result is certified.
#
#   scripts/run-sim.sh                      4 drones, default world, real time, files in build/run-sim
#   scripts/run-sim.sh --drones 3 --world apps/fact_sim/worlds/small.json --fast --out /tmp/r
#
# Flags (see --help): --drones N, --world FILE, --seed S, --realtime | --fast, --out DIR,
# --max-sim-time S, --resolution WxH, --camera-rate HZ, --noise-quadratic Q, --shared-namespace,
# --no-build, --quiet.
# Buses, as on real drones: each drone's apps talk on the drone's own bus (a multicast group and
# port per drone); only the gossip crosses between drones, on the swarm bus, which also carries the
# simulator's truth. Writes to --out: run.lcm (LCM log of every bus, merged: odometry, detections,
# gossip, rounds, results, setpoints, FC state, truth, clock, status; frames stay on the per-drone
# camera groups),
# run.png (top-down picture), report.json (fact-run-report-v1), cpu.csv (CPU per app per drone),
# logs/<app>-<id>.log. Exit codes: 0 certified and within the error bounds; 3 not certified
# (no certified result, or no result at all, within --max-sim-time, or a planner gave up); 4
# certified but outside the bounds (certified-wrong); 1 a process failed (an app or the simulator
# exited early, or the log could not be judged); 2 bad flags or world; 125 no private network
# namespace.
set -euo pipefail
[ -n "${FACT_RUN_SIM_TRACE:-}" ] && set -x  # FACT_RUN_SIM_TRACE=1: trace the script
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
. "$here/scripts/lib/args.sh"
. "$here/scripts/lib/netns.sh"

usage() {
  sed -n '2,23p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
  cat <<EOF
Flags:
  --drones N          drones (default: the world's count, 4 in the default world)
  --world FILE        fact-world-v1 world (default: apps/fact_sim/worlds/default.json)
  --seed S            seed of the simulator and the planners (default 1)
  --realtime          simulated time runs at wall-clock speed (default)
  --fast              as fast as the machine allows (at most --fast-rate x real time); each
                      frame waits until every detector has answered the previous one (fact-sim
                      --lockstep, a silent detector is timed out), so a loaded machine slows the
                      run down instead of changing what the detectors see. --realtime does not
                      wait: a detector that falls behind misses frames, as on a real drone
  --fast-rate X       cap of --fast (default 4: faster multiplies the bus traffic per wall
                      second, and a loaded machine then drops UDP)
  --out DIR           output folder (default build/run-sim)
  --max-sim-time S    give up after S simulated seconds (default 150)
  --resolution WxH    camera: 640x480 (default) or 424x240
  --camera-rate HZ    frames per second per drone (default 10)
  --yaw-bound RAD     error bounds of a correct result (default 0.05 rad, 0.20 m)
  --position-bound M
  --spin-rate RAD/S   the planners' spin rate (default 1.4)
  --max-rounds K      a planner holds, not certified, after K spins (default 8)
  --noise-quadratic Q the solvers' range sigma per m² of range (1/m; default: from the simulated
                      camera, 1.2 x its per-pixel depth sigma z²·0.08 px/(fx·0.05 m): 0.005 at
                      640x480 (fx 387), 0.009 at 424x240 (fx 213))
  --shared-namespace  all drones in one private namespace (what runs without root)
  --no-build          use the binaries in \$BUILD_DIR (default build/) as they are
  --quiet             no live event lines (the table and the verdict are still printed)
Environment: BUILD_DIR (default <repo>/build).
EOF
}

# ---------------------------------------------------------------- flags
drones="" world="$here/apps/fact_sim/worlds/default.json" seed=1 mode=realtime fast_rate=4
out="" max_sim=150 resolution=640x480 camera_rate=10 yaw_bound=0.05 position_bound=0.20
shared=0 build=1 quiet=0 spin_rate=1.4 max_rounds=8 noise_quadratic=""
die_usage() { echo "run-sim: $*" >&2; echo "run-sim: see --help" >&2; exit 2; }
need_value() { [ "$#" -ge 2 ] && [ -n "$2" ] || die_usage "$1 needs a value"; }
while [ "$#" -gt 0 ]; do
  case "$1" in
    -h|--help) usage; exit 0 ;;
    --drones) need_value "$@"; drones=$2; shift 2 ;;
    --world) need_value "$@"; world=$2; shift 2 ;;
    --seed) need_value "$@"; seed=$2; shift 2 ;;
    --realtime) mode=realtime; shift ;;
    --fast) mode=fast; shift ;;
    --fast-rate) need_value "$@"; fast_rate=$2; shift 2 ;;
    --out) need_value "$@"; out=$2; shift 2 ;;
    --max-sim-time) need_value "$@"; max_sim=$2; shift 2 ;;
    --resolution) need_value "$@"; resolution=$2; shift 2 ;;
    --camera-rate) need_value "$@"; camera_rate=$2; shift 2 ;;
    --yaw-bound) need_value "$@"; yaw_bound=$2; shift 2 ;;
    --position-bound) need_value "$@"; position_bound=$2; shift 2 ;;
    --spin-rate) need_value "$@"; spin_rate=$2; shift 2 ;;
    --max-rounds) need_value "$@"; max_rounds=$2; shift 2 ;;
    --noise-quadratic) need_value "$@"; noise_quadratic=$2; shift 2 ;;
    --shared-namespace) shared=1; shift ;;
    --no-build) build=0; shift ;;
    --quiet) quiet=1; shift ;;
    *) die_usage "unknown flag '$1'" ;;
  esac
done
is_uint() { [[ "$1" =~ ^[0-9]+$ ]]; }
[ -z "$drones" ] || { is_uint "$drones" && [ "${#drones}" -le 9 ] && [ "$((10#$drones))" -ge 2 ] && [ "$((10#$drones))" -le 32 ]; } ||
  die_usage "--drones: expected an integer 2..32, got '$drones'"
[ -z "$drones" ] || drones=$((10#$drones))  # decimal for fact-sim too ("010" is 10, not octal 8)
is_uint "$seed" && [ "${#seed}" -le 9 ] || die_usage "--seed: expected an integer 0..999999999, got '$seed'"
seed=$((10#$seed))  # decimal even with leading zeros ("08" is not octal here)
case "$resolution" in 640x480|424x240) ;; *) die_usage "--resolution: expected 640x480 or 424x240, got '$resolution'" ;; esac
# The solvers' range noise model matches the simulated stereo camera (fact/camera.h: depth sigma
# z²·disparity_rms/(fx·baseline) per pixel). The detector's range, the mean of the nearest 20 % of
# the box's depths, is off by 0.8 of that sigma (rms, mostly a bias toward the camera), so 1.2 of it
# bounds the error with a margin; the solvers' own default (0.008, for an uncalibrated camera)
# would throw away half the evidence and cost a round on half the runs (BENCHMARKS.md, session 9).
if [ -z "$noise_quadratic" ]; then
  case "$resolution" in 640x480) noise_quadratic=0.005 ;; 424x240) noise_quadratic=0.009 ;; esac
fi
for pair in "fast-rate:$fast_rate" "max-sim-time:$max_sim" "camera-rate:$camera_rate" \
            "yaw-bound:$yaw_bound" "position-bound:$position_bound" "spin-rate:$spin_rate" "max-rounds:$max_rounds" \
            "noise-quadratic:$noise_quadratic"; do
  is_positive "${pair#*:}" ||
    die_usage "--${pair%%:*}: expected a number > 0, got '${pair#*:}'"
done
# What the apps would refuse only after everything started (exit 1, "an app exited early"):
is_uint "$max_rounds" && [ "${#max_rounds}" -le 6 ] && [ "$((10#$max_rounds))" -ge 1 ] ||
  die_usage "--max-rounds: expected an integer 1..999999, got '$max_rounds'"
max_rounds=$((10#$max_rounds))  # decimal for the apps too (they would read 010 as octal)
awk -v v="$fast_rate" 'BEGIN { exit !(v <= 10000) }' || die_usage "--fast-rate: at most 10000 (fact-sim's --rate), got '$fast_rate'"
awk -v v="$max_sim" 'BEGIN { exit !(v <= 10000000) }' ||
  die_usage "--max-sim-time: at most 1e7 s (fact-sim's --duration), got '$max_sim'"
awk -v v="$spin_rate" 'BEGIN { exit !(v <= 1.5) }' ||
  die_usage "--spin-rate: at most the yaw-rate limit 1.5 rad/s, got '$spin_rate'"
awk -v v="$camera_rate" 'BEGIN { exit !(v <= 100) }' ||
  die_usage "--camera-rate: at most 100 Hz (fact-sim serves one frame per 10 ms batch), got '$camera_rate'"
[ -r "$world" ] || die_usage "--world: cannot read '$world'"
world="$(cd "$(dirname "$world")" && pwd)/$(basename "$world")"

build_dir="${BUILD_DIR:-$here/build}"
out="${out:-$build_dir/run-sim}"
mkdir -p "$out"
out="$(cd "$out" && pwd)"

# ---------------------------------------------------------------- install and build (outside the namespace)
if [ -z "${FACT_RUN_SIM_INNER:-}" ]; then
  targets=(fact-sim fact-detector fact-vio-relay fact-gossip fact-solver fact-planner fact-fc-bridge fact-run-report fact-log-merge
           fact-log-compare)
  if [ "$build" = 1 ]; then
    "$here/scripts/install-deps.sh"
    mkdir -p "$build_dir"
    cmake -S "$here" -B "$build_dir" -DCMAKE_BUILD_TYPE=Release >"$build_dir.configure.log" 2>&1 ||
      { cat "$build_dir.configure.log"; exit 1; }
    echo "== building ${targets[*]}"
    cmake --build "$build_dir" -j "$(nproc)" --target "${targets[@]}" >"$build_dir.build.log" 2>&1 ||
      { tail -n 60 "$build_dir.build.log"; echo "run-sim: build failed (full log: $build_dir.build.log)" >&2; exit 1; }
  fi
  # Choose the network: per-drone namespaces (root), else one unprivileged namespace, else refuse.
  export FACT_RUN_SIM_BUILD="$build_dir"
  for tool in unshare ip; do
    command -v "$tool" >/dev/null 2>&1 || { echo "run-sim: '$tool' not found (install util-linux / iproute2)" >&2; exit 125; }
  done
  args=(--world "$world" --seed "$seed" --fast-rate "$fast_rate" --out "$out" --max-sim-time "$max_sim"
        --resolution "$resolution" --camera-rate "$camera_rate" --yaw-bound "$yaw_bound"
        --position-bound "$position_bound" --spin-rate "$spin_rate" --max-rounds "$max_rounds"
        --noise-quadratic "$noise_quadratic" --no-build)
  [ -n "$drones" ] && args+=(--drones "$drones")
  [ "$mode" = fast ] && args+=(--fast)
  [ "$quiet" = 1 ] && args+=(--quiet)
  if [ "$shared" = 0 ] && [ "$(id -u)" -eq 0 ] && unshare --net -- ip netns list >/dev/null 2>&1; then
    FACT_RUN_SIM_INNER=netns exec "$here/scripts/netns-run.sh" bash "${BASH_SOURCE[0]}" "${args[@]}"
  fi
  if unshare -rn true 2>/dev/null; then
    [ "$shared" = 0 ] && echo "run-sim: not root (or no 'ip netns'): all drones share one private namespace (unshare -rn)"
    FACT_RUN_SIM_INNER=shared exec unshare -rn -- sh -c '
      ip link set lo up && ip route add 224.0.0.0/4 dev lo || { echo "run-sim: cannot set up lo in the namespace" >&2; exit 125; }
      exec "$@"' run-sim bash "${BASH_SOURCE[0]}" "${args[@]}" --shared-namespace
  fi
  echo "run-sim: needs a private network namespace so that multicast never leaves this machine:" >&2
  echo "  run as root (per-drone namespaces with 'ip netns'), or allow unprivileged user namespaces" >&2
  echo "  (sysctl kernel.unprivileged_userns_clone=1) for 'unshare -rn'. Not falling back to real interfaces." >&2
  exit 125
fi

# ---------------------------------------------------------------- inside the private namespace
# FACT_RUN_SIM_INNER is this script's own marker for its second pass; were it set by hand, the apps
# would talk udpm on the machine's real interfaces. So check that this namespace is private: it
# must have no interface but lo yet (/proc/net/dev lists this namespace's interfaces; /sys/class/net
# may still show the host's).
case "$FACT_RUN_SIM_INNER" in netns|shared) ;; *) echo "run-sim: FACT_RUN_SIM_INNER='$FACT_RUN_SIM_INNER' is internal (netns or shared)" >&2; exit 125 ;; esac
foreign=$(foreign_interfaces)
if [ -n "$foreign" ]; then
  echo "run-sim: FACT_RUN_SIM_INNER is set but this is not a private network namespace (interfaces: $foreign);" >&2
  echo "  refusing to send multicast here. Unset it: run-sim.sh makes its own namespace." >&2
  exit 125
fi
B="$FACT_RUN_SIM_BUILD"
bin_sim="$B/apps/fact_sim/fact-sim" bin_det="$B/apps/fact_detector/fact-detector" bin_vio="$B/apps/fact-vio-relay"
bin_gos="$B/apps/fact-gossip" bin_sol="$B/apps/fact-solver" bin_pla="$B/apps/fact_planner/fact-planner"
bin_fcb="$B/firmware_bridge/fact-fc-bridge" bin_rep="$B/apps/fact_run_report/fact-run-report"
bin_mrg="$B/apps/fact-log-merge" bin_cmp="$B/apps/fact-log-compare"
for b in "$bin_sim" "$bin_det" "$bin_vio" "$bin_gos" "$bin_sol" "$bin_pla" "$bin_fcb" "$bin_rep" "$bin_mrg" "$bin_cmp"; do
  [ -x "$b" ] || { echo "run-sim: $b is missing (build first, or drop --no-build)" >&2; exit 1; }
done
command -v lcm-logger >/dev/null || { echo "run-sim: lcm-logger not found (liblcm-bin)" >&2; exit 1; }

# The drones' ids, from the world (and --drones) as fact-sim sees them.
ids=$("$bin_sim" --world "$world" ${drones:+--drones "$drones"} --print-ids) ||
  { echo "run-sim: fact-sim could not read the world $world" >&2; exit 2; }
n=$(echo "$ids" | wc -w)
for id in $ids; do  # each drone's camera group is 239.255.77.<id>
  # (Ports 7700+id and 7800+id must not meet: at id 100 drone 100's frames would reach drone 0's
  # bus sockets, which listen on every group of their port in a shared namespace.)
  [ "$id" -le 99 ] || { echo "run-sim: drone id $id in $world: run-sim.sh supports ids 0..99" >&2; exit 2; }
done

# fill_url TEMPLATE ID: the template with "{id}" replaced by ID and "{B+id}" by B + ID, as fact-sim
# fills its --frames-url and --drone-url templates.
fill_url() {
  local u=${1//\{id\}/$2}
  while [[ $u =~ \{([0-9]+)\+id\} ]]; do u=${u//"${BASH_REMATCH[0]}"/$((BASH_REMATCH[1] + $2))}; done
  echo "$u"
}
# The swarm bus: the gossip between drones, and the simulator's truth and status.
BUS='udpm://239.255.76.67:7667?ttl=1&recv_buf_size=2097152'
# Each drone's own bus ({id} and {7800+id} as for FRAMES below): its odometry, detections, rounds,
# result, setpoints, FC state, status and the simulation clock. A drone's apps never receive
# another drone's traffic, so the CPU a drone uses does not grow with the swarm.
DRONE_BUS='udpm://239.255.78.{id}:{7800+id}?ttl=1&recv_buf_size=2097152'
# Frames: a multicast group and port per drone ({id} and {7700+id} are filled in per drone), so a
# drone's apps never receive another drone's frames, even when the drones share a namespace.
FRAMES='udpm://239.255.77.{id}:{7700+id}?ttl=1&recv_buf_size=8388608'
MAV_BASE=14600     # the simulated flight controllers listen on MAV_BASE + id (ids 0..99)
BRIDGE_BASE=14300  # each fact-fc-bridge binds BRIDGE_BASE + id: never one of the simulator's ports
prefix="fact-run-$$"
sim_addr=127.0.0.1
# Bus logs kept by an earlier run whose merge failed (or warned) are not thrown away.
if compgen -G "$out/logs/bus-*.lcm" >/dev/null; then
  echo "run-sim: $out/logs holds bus logs an earlier run kept (its merge failed or warned); move them away or use another --out" >&2
  exit 2
fi
rm -rf "$out/logs"
mkdir -p "$out/logs"
rm -f "$out/run.lcm" "$out/run.png" "$out/report.json" "$out/cpu.csv" "$out/run-params.txt"

pids=() names=() logger_pids=() bus_logs=()
# merge_logs: stops the recorders and merges their bus logs into run.lcm (the bus logs go once it
# is written, unless the merge warned of damage: a torn last event or a clock set back, shown here;
# an empty bus log is no loss). False, keeping the bus logs and no run.lcm, when the merge fails.
merge_logs() {
  for pid in "${logger_pids[@]}"; do kill -INT "$pid" 2>/dev/null || true; done
  for pid in "${logger_pids[@]}"; do wait "$pid" 2>/dev/null || true; done
  logger_pids=()
  if "$bin_mrg" --output "$out/run.lcm" "${bus_logs[@]}" >"$out/logs/fact-log-merge.log" 2>&1; then
    if grep "^fact-log-merge: warning:" "$out/logs/fact-log-merge.log" | grep -qv " is empty$"; then
      cat "$out/logs/fact-log-merge.log" >&2
      echo "run-sim: the merge warned; the bus logs are kept in $out/logs" >&2
    else
      rm -f "${bus_logs[@]}"
    fi
    return 0
  fi
  rm -f "$out/run.lcm"
  cat "$out/logs/fact-log-merge.log" >&2
  echo "run-sim: merging the bus logs failed; they are kept in $out/logs" >&2
  return 1
}
cleanup() {
  for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  # Interrupted before the end: what was recorded still becomes run.lcm.
  [ "${#logger_pids[@]}" -gt 0 ] && { merge_logs || true; }
  sleep 0.3
  for pid in "${pids[@]}" "${logger_pids[@]}"; do kill -KILL "$pid" 2>/dev/null || true; done
  if [ "$FACT_RUN_SIM_INNER" = netns ]; then
    for id in $ids; do ip netns del "$prefix-$id" 2>/dev/null || true; done
    ip link del fact-br0 2>/dev/null || true
  fi
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# ns_prefix ID: the command prefix that enters drone ID's namespace (none in shared mode). nsenter
# execs the command itself (ip netns exec forks), so $! is the app and signals reach it.
ns_prefix() {
  if [ "$FACT_RUN_SIM_INNER" = netns ] && [ "$1" -ge 0 ]; then echo "nsenter --net=/var/run/netns/$prefix-$1 --"; fi
}

if [ "$FACT_RUN_SIM_INNER" = netns ]; then
  # bridge fact-br0 (10.79.0.254) in this outer private namespace; a veth into each drone's namespace.
  sim_addr=10.79.0.254
  ip link add fact-br0 type bridge
  ip addr add "$sim_addr/24" dev fact-br0
  ip link set fact-br0 up
  ip route replace 224.0.0.0/4 dev fact-br0
  k=1
  for id in $ids; do
    ns="$prefix-$id"
    ip netns add "$ns"
    ip link add "fv$id" type veth peer name eth0 netns "$ns"
    ip link set "fv$id" master fact-br0 up
    ip -n "$ns" link set lo up
    ip -n "$ns" addr add "10.79.0.$k/24" dev eth0
    ip -n "$ns" link set eth0 up
    ip -n "$ns" route add 224.0.0.0/4 dev eth0
    k=$((k + 1))
  done
  echo "== network: bridge fact-br0 in a private namespace, drones ${ids// /,} each in its own namespace (veth, udpm ttl=1)"
else
  echo "== network: one private namespace (lo), drones ${ids// /,} share it"
fi

# start NAME ID CMD...: starts CMD in the background (in drone ID's namespace when ID >= 0), stderr
# and stdout to logs/NAME.log; $! is CMD's own pid.
start() {
  local name=$1 id=$2 pre
  shift 2
  read -r -a pre <<<"$(ns_prefix "$id")"
  "${pre[@]}" "$@" >"$out/logs/$name.log" 2>&1 &
  pids+=("$!")
  names+=("$name")
}

# What a replay needs to start the same planners (scripts/replay.sh reads it): key=value lines.
printf 'ids=%s\nseed=%s\nspin_rate=%s\nmax_rounds=%s\nnoise_quadratic=%s\n' "${ids// /,}" "$seed" "$spin_rate" "$max_rounds" \
  "$noise_quadratic" >"$out/run-params.txt"

# One recorder per bus (an LCM URL is one group), merged into run.lcm at the end. A drone's bus is
# recorded inside that drone's namespace, on the path its own apps receive it by (a recorder
# outside took it over the veth and bridge, and once missed two messages that drone 0's planner
# had acted on); the swarm bus is recorded here, beside the bridge. They run at a higher priority
# (where allowed), so that a loaded machine does not make them drop messages from their socket
# buffers.
record() {  # record URL NAME ID (ID: the drone whose namespace to record in, -1 here)
  local pre
  read -r -a pre <<<"$(ns_prefix "$3")"
  nice -n -5 "${pre[@]}" lcm-logger --lcm-url="${1%%&*}&recv_buf_size=16777216" --quiet "$out/logs/$2.lcm" \
    >"$out/logs/lcm-logger-$2.log" 2>&1 &
  logger_pids+=("$!")
  bus_logs+=("$out/logs/$2.lcm")
}
record "$BUS" bus-swarm -1
for id in $ids; do record "$(fill_url "$DRONE_BUS" "$id")" "bus-$id" "$id"; done

for id in $ids; do
  c=(--drone-id "$id" --lcm-url "$(fill_url "$DRONE_BUS" "$id")" --sim-clock)
  start "fact-vio-relay-$id" "$id" "$bin_vio" "${c[@]}"
  start "fact-detector-$id" "$id" "$bin_det" "${c[@]}" --frames-url "$(fill_url "$FRAMES" "$id")"
  start "fact-gossip-$id" "$id" "$bin_gos" "${c[@]}" --swarm-url "$BUS" --insecure --min-members "$n" --roster "${ids// /,}"
  start "fact-solver-$id" "$id" "$bin_sol" "${c[@]}" --noise-quadratic "$noise_quadratic"
  start "fact-planner-$id" "$id" "$bin_pla" "${c[@]}" --frames-url "$(fill_url "$FRAMES" "$id")" --seed "$((seed * 100 + id))" \
    --spin-rate "$spin_rate" --max-rounds "$max_rounds"
  start "fact-fc-bridge-$id" "$id" "$bin_fcb" "${c[@]}" --udp "$((BRIDGE_BASE + id)):$sim_addr:$((MAV_BASE + id))" --arm --offboard
done

rate=1
[ "$mode" = fast ] && rate=$fast_rate
sim_flags=(--world "$world" ${drones:+--drones "$drones"} --seed "$seed" --rate "$rate" --duration "$max_sim"
           --resolution "$resolution" --camera-rate "$camera_rate" --lcm-url "$BUS" --frames-url "$FRAMES"
           --drone-url "$DRONE_BUS"
           --mavlink-port "$MAV_BASE" --mavlink-bind "$sim_addr")
[ "$mode" = fast ] && sim_flags+=(--lockstep)
sleep 0.5  # let every app subscribe before the clock starts
start fact-sim -1 "$bin_sim" "${sim_flags[@]}"
sim_pid=$!
wall0=$(date +%s.%N)
echo "== $n drones (${ids// /,}), world $(basename "$world"), seed $seed, $mode (sim rate ${rate}x at most), $resolution at $camera_rate Hz; logs in $out/logs"

# Live: one line per event from every app's log. $! is tail itself, so stopping it ends the
# filter behind it too.
if [ "$quiet" = 0 ]; then
  tail --pid=$$ -q -n +1 -F "$out"/logs/fact-*.log 2>/dev/null > >(
    grep --line-buffered -E "state: |own round [0-9]+ closed|estimate: |error|failsafe|lockstep:|exit:|sim t = [0-9]+0\.0 s|took off|armed|OFFBOARD" |
    sed -u -E 's/^[0-9T:.-]+Z //') &
  pids+=("$!")
  names+=("live")
fi

# running PID: the process has not exited. (Bash reaps its children as they exit, so an exited
# app's /proc entry is gone; the stat check also covers a zombie that was not reaped yet.)
running() {
  local st
  st=$(cut -d' ' -f3 "/proc/$1/stat" 2>/dev/null) || return 1
  [ -n "$st" ] && [ "$st" != Z ] && [ "$st" != X ]
}

# Wait until every planner is done (holding a certified result, or giving up at --max-rounds), the
# simulator runs out of time, or a process dies. The apps keep running until their CPU is read.
verdict="" failed=0
while :; do
  if ! running "$sim_pid"; then
    sim_rc=0
    wait "$sim_pid" || sim_rc=$?
    if [ "$sim_rc" -eq 0 ]; then
      verdict="the simulator reached --max-sim-time ($max_sim s)"
    else
      verdict="fact-sim failed (exit $sim_rc; see $out/logs/fact-sim.log)"
      failed=1
    fi
    break
  fi
  done_count=0
  for i in "${!pids[@]}"; do
    # The simulator is judged above, by its exit code: it may end at --max-sim-time in between.
    [ "${names[$i]}" = live ] || [ "${pids[$i]}" = "$sim_pid" ] && continue
    running "${pids[$i]}" || { verdict="${names[$i]} exited early (see $out/logs/${names[$i]}.log)"; failed=1; break 2; }
  done
  for id in $ids; do grep -a -q "state: done" "$out/logs/fact-planner-$id.log" && done_count=$((done_count + 1)); done
  [ "$done_count" -eq "$n" ] && { verdict="every planner is done"; break; }
  sleep 0.2
done
# About 8 s more of simulated time, so the log also holds what follows the last decision: a
# replay's planners, behind the originals by their solvers' latency on a loaded machine, need it.
[ "$verdict" = "every planner is done" ] && sleep "$(awk -v r="$rate" 'BEGIN { printf "%.2f", 8 / r }')"
wall1=$(date +%s.%N)

# CPU per app per drone, read from /proc before anything is stopped. An app that exited early has
# no /proc entry left: its row says so (empty figures) rather than going missing.
hz=$(getconf CLK_TCK)
wall_s=$(awk -v a="$wall0" -v b="$wall1" 'BEGIN { printf "%.3f", b - a }')
echo "app,drone,cpu_s,wall_s,cpu_percent" >"$out/cpu.csv"
for i in "${!pids[@]}"; do
  name=${names[$i]} pid=${pids[$i]}
  [ "$name" = live ] && continue
  app=${name%-*} id=${name##*-}
  [ "$name" = fact-sim ] && { app=fact-sim; id=-1; }
  if ! running "$pid" || ! read -r -a st <"/proc/$pid/stat"; then
    echo "$app,$id,,$wall_s," >>"$out/cpu.csv"
    continue
  fi
  ticks=$((st[13] + st[14]))
  awk -v a="$app" -v i="$id" -v t="$ticks" -v hz="$hz" -v w="$wall_s" \
    'BEGIN { printf "%s,%s,%.3f,%.3f,%.2f\n", a, i, t / hz, w, 100 * t / hz / w }' >>"$out/cpu.csv"
done

for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
pids=()
# Let the recorders drain their sockets before they stop: wait until the logs stop growing.
size=-1
for _ in $(seq 50); do
  now=$(stat -c %s "${bus_logs[@]}" 2>/dev/null | awk '{ s += $1 } END { print s + 0 }' || true)
  [ "$now" = "$size" ] && break
  size=$now
  sleep 0.2
done
# Datagrams the kernel dropped because a socket's receive buffer was full (Udp RcvbufErrors of
# /proc/net/snmp), in this namespace (the swarm bus's recorder, the simulator) and in each
# drone's: a recorder or an app that fell behind. Frames a detector drops this way are expected
# under load; results and rounds a recorder drops make run.lcm incomplete (checked below).
rcvbuf_errors() {  # rcvbuf_errors ID (-1: this namespace); "?" when the counters cannot be read
  local pre
  read -r -a pre <<<"$(ns_prefix "$1")"
  { "${pre[@]}" cat /proc/net/snmp 2>/dev/null || echo "Udp: ?"; } |
    awk '$1 == "Udp:" { if (!n) { for (i = 2; i <= NF; ++i) if ($i == "RcvbufErrors") c = i; n = 1 } else { v = c ? $c + 0 : "?" } }
         END { print v == "" ? "?" : v }'
}
if [ "$FACT_RUN_SIM_INNER" = netns ]; then
  drops="bridge namespace: $(rcvbuf_errors -1)"
  for id in $ids; do drops+=", drone $id: $(rcvbuf_errors "$id")"; done
else
  drops="$(rcvbuf_errors -1) (one namespace)"
fi
echo "== UDP datagrams dropped by full receive buffers: $drops"
# One log of the whole run.
if ! merge_logs; then
  failed=1
  verdict="$verdict; merging the bus logs into run.lcm failed (see $out/logs/fact-log-merge.log)"
fi

echo "== run ended: $verdict, after $(printf '%.1f' "$wall_s") s of wall time"
# Whether run.lcm holds every result and complete round the apps published (their status counters):
# a recorder can miss UDP messages on a loaded machine, and a replay of such a log cannot match.
# (A log without any result is fact-log-compare's error too, and not this warning.)
lost=""
[ -f "$out/run.lcm" ] && lost=$("$bin_cmp" "$out/run.lcm" "$out/run.lcm" --no-planner 2>&1 >/dev/null | grep "recorder lost" || true)
if [ -n "$lost" ]; then
  echo "== warning: run.lcm is incomplete, so scripts/replay.sh will refuse it:" >&2
  echo "$lost" | sed 's/^fact-log-compare: error: /   /' >&2
fi
planner_codes=""
for id in $ids; do
  line=$(grep -a -E "state: done" "$out/logs/fact-planner-$id.log" | tail -n 1 | sed -E 's/^[0-9T:.-]+Z //' || true)
  [ -n "$line" ] && planner_codes+="  $line"$'\n'
done
[ -n "$planner_codes" ] && printf '%s' "$planner_codes" | cut -c1-200

# The verdict: fact-run-report's 0 (certified and correct), 3 (not certified, or no result) or 4
# (certified-wrong); a log it cannot judge (its 2) is a failed run here (1), as is an app or the
# simulator that exited early, whatever the log holds.
rc=0
[ -f "$out/run.lcm" ] && { "$bin_rep" --log "$out/run.lcm" --world "$world" --png "$out/run.png" --json "$out/report.json" \
  --yaw-bound "$yaw_bound" --position-bound "$position_bound" || rc=$?; }
echo "== files: $out/run.lcm (LCM log; replay it with scripts/replay.sh $out/run.lcm), $out/run.png (picture),"
echo "   $out/report.json, $out/cpu.csv, $out/run-params.txt, $out/logs/"
if [ "$failed" = 1 ]; then
  echo "== FAILED: $verdict" >&2
  exit 1
fi
case "$rc" in
  0) echo "== certified and correct" ;;
  3|4) ;;
  *) echo "== FAILED: fact-run-report could not judge the run (exit $rc)" >&2; exit 1 ;;
esac
exit "$rc"
