#!/usr/bin/env bash
# lcm-spy decodes the fact types. In a private network namespace (scripts/netns-run.sh): Xvfb on a
# free display, scripts/spy.sh on udpm://239.255.76.67:7667?ttl=0, fact-lcm-publish-sample sending
# every top-level type there. Checks: lcm-spy found at least as many LCM types as lcmtypes/ has
# files, its "LCM Spy" window exists, it is still running after the traffic with no Java exception;
# and LcmDecodeCheck.java (the same class lookup lcm-spy uses, over the same jar) decodes a log of
# the same messages and re-encodes every one to identical bytes. A screenshot of the spy is kept in
# OUT_DIR/lcm_spy.xwd (and .png when ImageMagick's convert exists) for humans.
#   test_lcm_spy.sh SOURCE_DIR PUBLISHER JAR OUT_DIR
# Exit 0 pass, 1 fail, 77 skip (no Xvfb / java / jar / root).
set -u
. "$(dirname "$0")/lib.sh"  # wait_until, scaled (FACT_TEST_TIME_SCALE)
if [ "$#" -ne 4 ]; then echo "usage: $0 SOURCE_DIR PUBLISHER JAR OUT_DIR" >&2; exit 2; fi
src="$1" pub="$2" jar="$3" out="$4"
url='udpm://239.255.76.67:7667?ttl=0'

skip() { echo "SKIP: $*"; exit 77; }
fail() { echo "FAIL: $*"; for f in "$out"/spy.log "$out"/decode.txt; do [ -f "$f" ] && { echo "--- $f"; cat "$f"; }; done; exit 1; }

if [ -z "${FACT_LCM_SPY_IN_NETNS:-}" ]; then
  command -v Xvfb >/dev/null 2>&1 || skip "Xvfb not installed (Debian xvfb)"
  command -v java >/dev/null 2>&1 || skip "java not installed (Debian default-jdk-headless)"
  [ -n "$jar" ] || skip "the fact_lcmtypes jar is not built here (no javac or lcm.jar at configure time)"
  [ -f /usr/share/java/jchart2d.jar ] || skip "/usr/share/java/jchart2d.jar missing (Debian libjchart2d-java)"
  command -v xwininfo >/dev/null 2>&1 || skip "xwininfo not installed (Debian x11-utils)"
  [ "$(id -u)" -eq 0 ] || skip "needs root for a private network namespace (udpm must not leave the machine)"
  [ -f "$jar" ] || fail "jar $jar missing although the build should have made it"
  [ -x "$pub" ] || fail "publisher $pub missing"
  rm -rf "$out" && mkdir -p "$out" || fail "cannot create $out"
  # Here, in this machine's own network namespace (it has interfaces besides lo), spy.sh refuses
  # udpm before starting anything (review, session 33: it joined the group on the host's
  # interfaces). A jar that does not exist makes a spy.sh without the guard stop at its jar
  # check (exit 1), so even then lcm-spy never starts here.
  if [ -n "$(awk -F: 'NR > 2 { gsub(/ /, "", $1); if ($1 != "lo") print $1 }' /proc/net/dev)" ]; then
    rc=0
    FACT_LCM_JAR=/nonexistent/fact.jar "$src/scripts/spy.sh" "$url" >"$out/host.log" 2>&1 || rc=$?
    [ "$rc" -eq 2 ] || fail "spy.sh with udpm in the machine's namespace exited $rc, expected 2: $(cat "$out/host.log")"
    grep -q "refusing udpm" "$out/host.log" || fail "spy.sh's refusal does not say why: $(cat "$out/host.log")"
  fi
  FACT_LCM_SPY_IN_NETNS=1 exec "$src/scripts/netns-run.sh" bash "$0" "$@"
fi

# --- inside the namespace ---
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done; wait 2>/dev/null; }
trap cleanup EXIT

# Xvfb picks a free display itself and writes its number to fd 3.
timeout "$(scaled 60)" Xvfb -displayfd 3 -screen 0 1024x768x24 -nolisten tcp 3>"$out/display" >"$out/xvfb.log" 2>&1 &
pids+=($!)
wait_until 10 test -s "$out/display" || fail "Xvfb did not start: $(cat "$out/xvfb.log")"
export DISPLAY=":$(head -n1 "$out/display")"
echo "Xvfb on $DISPLAY"

FACT_LCM_JAR="$jar" timeout "$(scaled 60)" "$src/scripts/spy.sh" "$url" >"$out/spy.log" 2>&1 &
spy=$!
pids+=("$spy")
wait_until 20 grep -Eq 'Found [0-9]+ LCM types' "$out/spy.log" || fail "lcm-spy did not report its LCM types"
found=$(sed -nE 's/.*Found ([0-9]+) LCM types.*/\1/p' "$out/spy.log" | head -n1)
want=$(ls "$src"/lcmtypes/fact_*_t.lcm | wc -l)
echo "lcm-spy: Found $found LCM types (lcmtypes/ has $want)"
[ "$found" -ge "$want" ] || fail "lcm-spy found $found LCM types, fewer than the $want in lcmtypes/"
wait_until 20 sh -c 'xwininfo -root -tree | grep -q "\"LCM Spy\""' || fail "no \"LCM Spy\" window on $DISPLAY"

timeout "$(scaled 20)" "$pub" --lcm-url "$url" --drone-id 3 --count 10 --period-ms 50 >"$out/publish.log" 2>&1 ||
  fail "fact-lcm-publish-sample failed: $(cat "$out/publish.log")"
sleep 1  # let the spy's table refresh before the screenshot
kill -0 "$spy" 2>/dev/null || fail "lcm-spy exited while our messages arrived"
if grep -Eq 'Exception|Error' "$out/spy.log"; then fail "lcm-spy logged an exception"; fi
xwd -root -silent -out "$out/lcm_spy.xwd" && echo "screenshot: $out/lcm_spy.xwd"
if command -v convert >/dev/null 2>&1; then convert "xwd:$out/lcm_spy.xwd" "$out/lcm_spy.png" 2>/dev/null && echo "screenshot: $out/lcm_spy.png"; fi

# The same messages into a log file, decoded by the jar's classes as lcm-spy finds them.
timeout "$(scaled 20)" "$pub" --lcm-url "file://$out/sample.lcmlog?mode=w" --drone-id 3 --count 1 >>"$out/publish.log" 2>&1 ||
  fail "fact-lcm-publish-sample could not write $out/sample.lcmlog"
timeout "$(scaled 60)" java -cp "/usr/share/java/lcm.jar:/usr/share/java/jchart2d.jar:$jar" "$src/test/LcmDecodeCheck.java" "$out/sample.lcmlog" >"$out/decode.txt" 2>&1 ||
  fail "the jar did not decode every message"
for type in app_status_t detections_t fc_state_t frame_t gossip_challenge_t gossip_packet_t gossip_request_t gossip_summary_t \
            odometry_t round_packet_t setpoint_t sim_clock_t swarm_result_t swarm_rounds_t truth_t; do
  grep -q " fact\.$type " "$out/decode.txt" || fail "fact.$type not decoded by the jar"
done
grep -q '^FACT_ODOMETRY_3 fact.odometry_t ' "$out/decode.txt" || fail "FACT_ODOMETRY_3 not decoded as fact.odometry_t"
grep -q '^FACT_RESULT_3 fact.swarm_result_t ' "$out/decode.txt" || fail "FACT_RESULT_3 not decoded as fact.swarm_result_t"
tail -n1 "$out/decode.txt"
echo "PASS: lcm-spy found $found types and ran through our traffic; the jar decodes all 15 message types"
exit 0
