#!/bin/sh
# Replay test: record an initialization with lcm-logger, replay the log with lcm-logplayer into a
# fresh fact-solver, and check that the fresh solver publishes exactly the same results, byte for
# byte (fact-solver stamps a result with its input's utime and leaves solve_us at 0).
#
#   test/test_replay.sh NETNS_RUN SIMGEN SOLVER PUBLISH COMPARE
#
# NETNS_RUN is scripts/netns-run.sh, the others the fact-simgen, fact-solver, fact-rounds-publish
# and fact_lcm_log_compare binaries. Each phase runs in its own fresh private network namespace
# (udpm:// never leaves it):
#   record: lcm-logger records FACT_.*, fact-rounds-publish feeds a solver (drone 1) the rounds of
#           a fact-simgen scenario as they complete one by one (1, 2, 3 rounds, then a repeat);
#   replay: lcm-logplayer plays the log's FACT_SWARM_ROUNDS_1 into a fresh solver, while
#           lcm-logger records its results.
# Then fact_lcm_log_compare compares FACT_RESULT_1 in both logs. Every process is time-limited
# and stopped at the end. Exit 0 when identical.
set -eu
. "$(dirname "$0")/lib.sh"  # wait_until, scaled (FACT_TEST_TIME_SCALE)

URL='udpm://239.255.76.67:7667?ttl=0'


# occurrences FILE TEXT: how many times TEXT appears in FILE (binary files too).
occurrences() { grep -a -o -- "$2" "$1" 2>/dev/null | wc -l; }
has_at_least() { [ "$(occurrences "$1" "$2")" -ge "$3" ]; }

# stop PID...: SIGTERM (SIGINT for lcm-logger is not needed: it flushes on SIGTERM too), then wait.
stop() {
  for pid in "$@"; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "$@"; do wait "$pid" 2>/dev/null || true; done
}

fail() {
  echo "test_replay: $*" >&2
  for f in "$WORK"/*.log; do [ -f "$f" ] && { echo "--- $f" >&2; cat "$f" >&2; }; done
  exit 1
}

phase_record() {
  lcm-logger -q -f --lcm-url="$URL" -c 'FACT_.*' "$WORK/original.lcm" 2>"$WORK/logger1.log" &
  logger=$!
  timeout "$(scaled 30)" "$SOLVER" --drone-id 1 --lcm-url "$URL" --status-period 0.1 2>"$WORK/solver1.log" &
  solver=$!
  trap 'stop $solver $logger' EXIT
  # The logger is live once it has recorded the solver's heartbeat.
  wait_until 10 has_at_least "$WORK/original.lcm" FACT_STATUS 1 || fail "lcm-logger recorded no FACT_STATUS"
  timeout "$(scaled 20)" "$PUBLISH" --lcm-url "$URL" --drone-id 1 --input "$WORK/rounds.json" \
    --incremental --count 4 --interval 0.3 2>"$WORK/publish.log" || fail "fact-rounds-publish failed"
  wait_until 10 has_at_least "$WORK/solver1.log" "estimate:" 3 || fail "the solver did not estimate 3 times"
  wait_until 10 has_at_least "$WORK/original.lcm" FACT_RESULT_1 3 || fail "lcm-logger recorded fewer than 3 results"
  # The repeat is published last and flushed up to a flush interval later: stop only once the
  # file holds it (a fixed sleep lost it once on a loaded machine).
  wait_until 10 has_at_least "$WORK/original.lcm" FACT_SWARM_ROUNDS_1 4 ||
    fail "lcm-logger recorded fewer than 4 FACT_SWARM_ROUNDS_1 messages"
  stop $solver $logger
  trap - EXIT
}

phase_replay() {
  lcm-logger -q -f --lcm-url="$URL" -c 'FACT_RESULT_.*|FACT_STATUS' "$WORK/replay.lcm" 2>"$WORK/logger2.log" &
  logger=$!
  timeout "$(scaled 30)" "$SOLVER" --drone-id 1 --lcm-url "$URL" --status-period 0.1 2>"$WORK/solver2.log" &
  solver=$!
  trap 'stop $solver $logger' EXIT
  wait_until 10 has_at_least "$WORK/replay.lcm" FACT_STATUS 1 || fail "lcm-logger recorded no FACT_STATUS"
  # Only the solver's input is played: the original results stay out of the fresh run.
  timeout "$(scaled 20)" lcm-logplayer --lcm-url="$URL" --regexp='FACT_SWARM_ROUNDS_1' "$WORK/original.lcm" \
    >"$WORK/logplayer.log" 2>&1 || fail "lcm-logplayer failed"
  wait_until 10 has_at_least "$WORK/solver2.log" "estimate:" 3 || fail "the fresh solver did not estimate 3 times"
  wait_until 10 has_at_least "$WORK/replay.lcm" FACT_RESULT_1 3 || fail "lcm-logger recorded fewer than 3 replayed results"
  sleep 0.3
  stop $solver $logger
  trap - EXIT
}

if [ "${1:-}" = "--phase" ]; then
  # Inside a namespace: --phase NAME WORK SOLVER PUBLISH
  WORK=$3 SOLVER=$4 PUBLISH=$5
  "phase_$2"
  exit 0
fi

if [ "$#" -ne 5 ]; then
  echo "usage: $0 NETNS_RUN SIMGEN SOLVER PUBLISH COMPARE" >&2
  exit 2
fi
NETNS_RUN=$1 SIMGEN=$2 SOLVER=$3 PUBLISH=$4 COMPARE=$5
command -v lcm-logger >/dev/null && command -v lcm-logplayer >/dev/null || {
  echo "test_replay: lcm-logger / lcm-logplayer not found (Debian liblcm-bin)" >&2
  exit 1
}
WORK=$(mktemp -d "${TMPDIR:-/tmp}/fact-replay-XXXXXX")
trap 'rm -rf "$WORK"' EXIT

"$SIMGEN" --drones 5 --rounds 3 --noise depth --seed 11 --output "$WORK/rounds.json" || fail "fact-simgen failed"
SELF=$(readlink -f "$0")
timeout "$(scaled 60)" "$NETNS_RUN" sh "$SELF" --phase record "$WORK" "$SOLVER" "$PUBLISH" || fail "the recording phase failed"
timeout "$(scaled 60)" "$NETNS_RUN" sh "$SELF" --phase replay "$WORK" "$SOLVER" "$PUBLISH" || fail "the replay phase failed"
[ "$(occurrences "$WORK/original.lcm" FACT_SWARM_ROUNDS_1)" -eq 4 ] ||
  fail "expected 4 FACT_SWARM_ROUNDS_1 messages in the original log, found $(occurrences "$WORK/original.lcm" FACT_SWARM_ROUNDS_1)"
"$COMPARE" "$WORK/original.lcm" "$WORK/replay.lcm" FACT_RESULT_1 certified || fail "the replay's results differ"
echo "test_replay: the replayed initialization gave identical results"
