#!/usr/bin/env bash
# One real drone's apps: the same set run-sim.sh gives each simulated drone, on the drone's own
# computer, with its camera, its VIO and its flight controller.
#
#   scripts/run-drone.sh --id 2 --camera lcm --vio udp:5600 --fc serial:/dev/ttyTHS1:921600 --key swarm.key
#   scripts/run-drone.sh --id 2 --camera lcm --vio lcm --fc udp:14540:127.0.0.1:14580 --key swarm.key --check-only
#
# Sources:
#   --camera lcm[:URL]       gray + depth frames already published as fact::frame_t on FACT_FRAMES_<id>
#                            by the camera driver (on --lcm-url, or on URL)
#            png:DIR         a directory of PNG pairs (fact-detector --png-dir; bench-top tests)
#   --vio    lcm             raw VIO as fact::odometry_t on FACT_VIO_RAW_<id>
#            tum:FILE        a TUM trajectory file;  udp:PORT  one pose line per datagram
#   --fc     udp:LOCAL:HOST:PORT   MAVLink over UDP (PX4 SITL: udp:14540:127.0.0.1:14580)
#            serial:DEV[:BAUD]     MAVLink over a serial port (default 921600 bit/s)
#   --vio-restamp            (tum/udp VIO) fact-vio-relay --restamp: put the VIO's times on the wall
#                            clock, when the VIO stamps with its own (boot) clock and the camera not
#   --key FILE               the swarm key for fact-gossip (32 raw bytes or 64 hex digits, mode 600);
#                            --insecure runs without one (bench tests only)
#   --session NAME           this flight's name for fact-gossip (the same on every drone, new for
#                            each flight): a recording of another flight's gossip then fails
#                            authentication (needs --key)
# Other flags: --roster IDS (the swarm's ids, comma separated), --lcm-url URL (the drone's own
# bus; default: LCM's default), --swarm-url URL (the swarm's bus, for the gossip only; default:
# --lcm-url). Best: --lcm-url with ttl=0 (stays on the drone's computer) and --swarm-url with
# ttl=1 on the swarm's network, so only the gossip crosses between drones; --out DIR (logs; default build/run-drone-<id>),
# --arm (let fact-fc-bridge arm and switch to OFFBOARD; default: the pilot does), --sim-clock
# (apps follow fact-sim's clock: simulated hardware), --preflight-timeout S (0.1 … 3600, default 10),
# --check-only (run the checklist and stop), --no-build, --noise-quadratic Q (the solver's range
# σ per m² of range, 1/m: measure it for this camera; default: fact-solver's 0.008).
#
# Pre-flight: the relay, the detector and the bridge start first; then fact-preflight checks the
# swarm key, the flight controller's heartbeat (through the bridge), camera frames and VIO odometry.
# Only when every item passes do gossip, solver and planner (the app that moves the drone) start.
# Ctrl-C stops every app. Exit codes: 0 stopped by Ctrl-C once every app runs (or --check-only
# passed); 1 the checklist failed or an app died (the reason is printed); 2 bad flags; 130 / 143
# stopped by SIGINT / SIGTERM before the checklist passed (nothing was started after it).
# Environment: BUILD_DIR (default <repo>/build); FACT_RUN_SUFFIX, appended to every app's path
# (".qemu" runs the arm64 apps of a cross build under the emulator; test/arm64/cross_tests.cmake).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
. "$here/scripts/lib/args.sh"

die() { echo "run-drone: $*" >&2; echo "run-drone: see --help" >&2; exit 2; }
id="" camera="" vio="" vio_restamp=0 fc="" key="" session="" insecure=0 roster="" lcm_url="" out="" arm=0 sim_clock=0
check_only=0 build=1 preflight_timeout=10 swarm_url="" noise_quadratic=""
while [ "$#" -gt 0 ]; do
  case "$1" in
    -h|--help) sed -n '2,/^[^#]/{/^#/p}' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
    --id) [ "$#" -ge 2 ] || die "--id needs a value"; id=$2; shift 2 ;;
    --camera) [ "$#" -ge 2 ] || die "--camera needs a value"; camera=$2; shift 2 ;;
    --vio) [ "$#" -ge 2 ] || die "--vio needs a value"; vio=$2; shift 2 ;;
    --fc) [ "$#" -ge 2 ] || die "--fc needs a value"; fc=$2; shift 2 ;;
    --key) [ "$#" -ge 2 ] || die "--key needs a value"; key=$2; shift 2 ;;
    --insecure) insecure=1; shift ;;
    --vio-restamp) vio_restamp=1; shift ;;
    --session) [ "$#" -ge 2 ] || die "--session needs a value"; session=$2; shift 2 ;;
    --roster) [ "$#" -ge 2 ] || die "--roster needs a value"; roster=$2; shift 2 ;;
    --lcm-url) [ "$#" -ge 2 ] || die "--lcm-url needs a value"; lcm_url=$2; shift 2 ;;
    --swarm-url) [ "$#" -ge 2 ] || die "--swarm-url needs a value"; swarm_url=$2; shift 2 ;;
    --out) [ "$#" -ge 2 ] || die "--out needs a value"; out=$2; shift 2 ;;
    --arm) arm=1; shift ;;
    --sim-clock) sim_clock=1; shift ;;
    --preflight-timeout) [ "$#" -ge 2 ] || die "--preflight-timeout needs a value"; preflight_timeout=$2; shift 2 ;;
    --check-only) check_only=1; shift ;;
    --no-build) build=0; shift ;;
    --noise-quadratic) [ "$#" -ge 2 ] || die "--noise-quadratic needs a value"; noise_quadratic=$2; shift 2 ;;
    *) die "unknown flag '$1'" ;;
  esac
done
# (No leading zero: the apps would read 010 as octal 8.)
[[ "$id" =~ ^(0|[1-9][0-9]{0,8})$ ]] || die "--id: expected the drone's id (an integer 0 … 999999999, no leading zero), got '$id'"
[ -n "$camera" ] || die "--camera is required (lcm[:URL] or png:DIR)"
[ -n "$vio" ] || die "--vio is required (lcm, tum:FILE or udp:PORT)"
[ -n "$fc" ] || die "--fc is required (udp:LOCAL:HOST:PORT or serial:DEV[:BAUD])"
[ "$insecure" = 1 ] || [ -n "$key" ] || die "--key FILE is required (or --insecure for bench tests)"
[ "$insecure" = 0 ] || [ -z "$key" ] || die "--key and --insecure exclude each other"
[ -z "$session" ] || [ -n "$key" ] || die "--session needs --key (a session names a flight of an authenticated swarm)"
# As fact-gossip checks them, before anything starts (it would exit only once the planner ran).
[ -z "$session" ] || [[ "$session" =~ ^[A-Za-z0-9._:-]{1,64}$ ]] ||
  die "--session: expected 1-64 characters of A-Z a-z 0-9 . _ : -, got '$session'"
if [ -n "$roster" ]; then
  [[ "$roster" =~ ^(0|[1-9][0-9]*)(,(0|[1-9][0-9]*))*$ ]] || die "--roster: expected ids like 0,1,2, got '$roster'"
  [[ ",$roster," == *",$id,"* ]] || die "--roster $roster does not list this drone's --id $id"
  [[ "$roster" == *,* ]] || die "--roster $roster: a swarm needs at least 2 drones"
  dup=$(tr , '\n' <<<"$roster" | sort | uniq -d | head -n 1)
  [ -z "$dup" ] || die "--roster $roster lists id $dup twice"
  [ "$(tr , '\n' <<<"$roster" | wc -l)" -le 32 ] || die "--roster $roster: more than 32 ids (fact-gossip's --max-origins)"
else
  [ "$id" -le 9999 ] || die "--id $id: above 9999 (fact-gossip's --max-drone-id) needs a --roster that lists it"
fi
[[ "$preflight_timeout" =~ ^[0-9]+([.][0-9]+)?$ ]] &&
  awk -v v="$preflight_timeout" 'BEGIN { exit !(v >= 0.1 && v <= 3600) }' ||
  die "--preflight-timeout: expected seconds in [0.1, 3600] (fact-preflight's --timeout), got '$preflight_timeout'"
[ -z "$noise_quadratic" ] || is_positive "$noise_quadratic" ||
  die "--noise-quadratic: expected a number > 0, got '$noise_quadratic'"

# Sources → app flags.
det_src=() pre_cam=() pla_src=() vio_src=() fc_link=()
case "$camera" in
  lcm) ;;
  lcm:*) det_src=(--frames-url "${camera#lcm:}"); pre_cam=(--frames-url "${camera#lcm:}"); pla_src=(--frames-url "${camera#lcm:}") ;;
  png:*) [ -d "${camera#png:}" ] || die "--camera png:DIR: '${camera#png:}' is not a directory"
         det_src=(--png-dir "${camera#png:}"); pre_cam=(--png-dir "${camera#png:}") ;;
  *) die "--camera: expected lcm, lcm:URL or png:DIR, got '$camera'" ;;
esac
case "$vio" in
  lcm) vio_src=(--source lcm) ;;
  tum:*) [ -r "${vio#tum:}" ] || die "--vio tum:FILE: cannot read '${vio#tum:}'"; vio_src=(--source tum --file "${vio#tum:}") ;;
  udp:*) is_port "${vio#udp:}" || die "--vio udp:PORT: expected a port 1-65535, got '${vio#udp:}'"
         vio_src=(--source udp --port "${vio#udp:}") ;;
  *) die "--vio: expected lcm, tum:FILE or udp:PORT, got '$vio'" ;;
esac
[ "$vio_restamp" = 0 ] || [[ "$vio" == tum:* || "$vio" == udp:* ]] || die "--vio-restamp is only for --vio tum:FILE or udp:PORT"
[ "$vio_restamp" = 0 ] || vio_src+=(--restamp)
case "$fc" in
  udp:*:*:*) IFS=: read -r _ local_port fc_host fc_port <<<"$fc"
             is_port "$local_port" && is_port "$fc_port" && [ -n "$fc_host" ] ||
               die "--fc udp:LOCAL:HOST:PORT: expected ports 1-65535 and a host, got '$fc'"
             fc_link=(--udp "${fc#udp:}") ;;
  # A baud is the digits after the last colon; a device path may hold colons (/dev/serial/by-path/…).
  serial:*) d=${fc#serial:}
            if [[ "$d" =~ ^(.+):([0-9]+)$ ]]; then fc_link=(--serial "${BASH_REMATCH[1]}" --baud "${BASH_REMATCH[2]}")
            else fc_link=(--serial "$d"); fi ;;
  *) die "--fc: expected udp:LOCAL:HOST:PORT or serial:DEV[:BAUD], got '$fc'" ;;
esac

build_dir="${BUILD_DIR:-$here/build}"
out="${out:-$build_dir/run-drone-$id}"
if [ "$build" = 1 ]; then
  "$here/scripts/install-deps.sh"
  cmake -S "$here" -B "$build_dir" -DCMAKE_BUILD_TYPE=Release >"$build_dir.configure.log" 2>&1 || { cat "$build_dir.configure.log"; exit 1; }
  cmake --build "$build_dir" -j "$(nproc)" --target fact-detector fact-vio-relay fact-gossip fact-solver fact-planner \
    fact-fc-bridge fact-preflight >"$build_dir.build.log" 2>&1 || { tail -n 40 "$build_dir.build.log"; exit 1; }
fi
B="$build_dir"
x="${FACT_RUN_SUFFIX:-}"
mkdir -p "$out/logs"

common=(--drone-id "$id")
[ -n "$lcm_url" ] && common+=(--lcm-url "$lcm_url")
[ "$sim_clock" = 1 ] && common+=(--sim-clock)
keyflag=(--insecure)
[ -n "$key" ] && keyflag=(--key-file "$key")
armflags=()
[ "$arm" = 1 ] && armflags=(--arm --offboard)

pids=() names=()
stop_all() {
  for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do wait "$p" 2>/dev/null || true; done
  pids=()
}
trap stop_all EXIT
# Before the checklist has passed a signal is a stop, not a success: 130 / 143.
flying=0
trap 'echo "run-drone: stopping"; [ "$flying" = 1 ] && exit 0; exit 130' INT
trap 'echo "run-drone: stopping"; [ "$flying" = 1 ] && exit 0; exit 143' TERM
start() {
  local name=$1
  shift
  "$@" >"$out/logs/$name.log" 2>&1 &
  pids+=("$!")
  names+=("$name")
  echo "== started $name (pid $!)"
}
# An app that died: its name and the last lines of its log; exit 1.
check_alive() {
  for i in "${!pids[@]}"; do
    if ! kill -0 "${pids[$i]}" 2>/dev/null || [ "$(cut -d' ' -f3 "/proc/${pids[$i]}/stat" 2>/dev/null)" = Z ]; then
      echo "run-drone: ${names[$i]} exited; its log ($out/logs/${names[$i]}.log) ends:" >&2
      tail -n 5 "$out/logs/${names[$i]}.log" >&2
      exit 1
    fi
  done
}

start fact-vio-relay "$B/apps/fact-vio-relay$x" "${common[@]}" "${vio_src[@]}"
start fact-fc-bridge "$B/firmware_bridge/fact-fc-bridge$x" "${common[@]}" "${fc_link[@]}" "${armflags[@]}"
[ "$check_only" = 1 ] || start fact-detector "$B/apps/fact_detector/fact-detector$x" "${common[@]}" "${det_src[@]}"
sleep 0.5
check_alive
rc=0
# In the background and waited for, so that a signal's trap runs at once (and stop_all stops it).
"$B/apps/fact-preflight$x" "${common[@]}" "${keyflag[@]}" "${pre_cam[@]}" --timeout "$preflight_timeout" &
pids+=("$!")
names+=(fact-preflight)
wait "$!" || rc=$?
unset 'pids[-1]' 'names[-1]'
if [ "$rc" -eq 2 ]; then
  echo "run-drone: fact-preflight refused its flags (above): a bad flag value" >&2
  exit 2
fi
if [ "$rc" -ne 0 ]; then
  echo "run-drone: the pre-flight checklist failed: not starting gossip, solver or planner" >&2
  exit 1
fi
[ "$check_only" = 1 ] && { echo "run-drone: --check-only: the checklist passed"; flying=1; exit 0; }
flying=1
gossip_flags=("${keyflag[@]}")
[ -n "$roster" ] && gossip_flags+=(--roster "$roster")
[ -n "$session" ] && gossip_flags+=(--session "$session")
[ -n "$swarm_url" ] && gossip_flags+=(--swarm-url "$swarm_url")
start fact-gossip "$B/apps/fact-gossip$x" "${common[@]}" "${gossip_flags[@]}"
start fact-solver "$B/apps/fact-solver$x" "${common[@]}" ${noise_quadratic:+--noise-quadratic "$noise_quadratic"}
start fact-planner "$B/apps/fact_planner/fact-planner$x" "${common[@]}" "${pla_src[@]}"
echo "== drone $id flying its initialization; Ctrl-C stops every app. Events:"
(cd "$out/logs" && exec tail --pid=$$ -q -n 0 -F fact-*.log 2>/dev/null |
  grep --line-buffered -E "state: |own round [0-9]+ closed|estimate: |error|failsafe|streaming|flight controller" |
  sed -u -E 's/^[0-9T:.-]+Z //') &
while :; do
  check_alive
  sleep 0.5
done
