#!/usr/bin/env bash
# fact-fc-bridge's bytes decoded by node-mavlink 2.3.0 (an independent implementation):
#   test_fc_bridge_node_mavlink.sh SOURCE_DIR FC_BRIDGE PEER WORK_DIR
# 1. Installs node-mavlink@2.3.0 with npm into WORK_DIR/npm (once; skipped when present). Exits 77
#    (skip) only when node/npm are missing or the registry cannot be reached.
# 2. Inside a private network namespace (scripts/netns-run.sh; LCM udpm never leaves it) runs
#    fact-fc-bridge --arm --offboard --dump, with fact_fc_bridge_peer publishing setpoints and
#    odometry and acting as the flight controller on UDP 127.0.0.1 (it captures what it receives).
# 3. test/mavlink_decode.js checks every field of every message in the dump and in the capture,
#    and that a flipped byte is a CRC error.
set -uo pipefail
src=$1 bridge=$2 peer=$3 work=$4
mkdir -p "$work"
npm_dir=$work/npm

if [ "${FACT_FC_BRIDGE_IN_NETNS:-}" != 1 ]; then
  if [ ! -f "$npm_dir/node_modules/node-mavlink/package.json" ]; then
    if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
      echo "SKIP: node or npm not installed (Debian packages nodejs npm)"; exit 77
    fi
    if ! npm install --prefix "$npm_dir" --no-audit --no-fund node-mavlink@2.3.0 >"$work/npm.log" 2>&1; then
      if grep -qiE "ENOTFOUND|EAI_AGAIN|ETIMEDOUT|ECONNREFUSED|ECONNRESET|network|registry" "$work/npm.log"; then
        echo "SKIP: the npm registry is unreachable:"; tail -5 "$work/npm.log"; exit 77
      fi
      echo "FAIL: npm install node-mavlink@2.3.0 failed:"; tail -20 "$work/npm.log"; exit 1
    fi
  fi
  version=$(node -p "require('$npm_dir/node_modules/node-mavlink/package.json').version")
  [ "$version" = 2.3.0 ] || { echo "FAIL: node-mavlink $version installed, want 2.3.0"; exit 1; }
  FACT_FC_BRIDGE_IN_NETNS=1 exec "$src/scripts/netns-run.sh" bash "$0" "$@"
fi

# Inside the namespace: nothing but lo.
if grep -vE '^ *(lo|Inter-| face)' /proc/net/dev | grep -q .; then
  echo "FAIL: an interface other than lo is visible; refusing udpm"; exit 1
fi
url='udpm://239.255.76.67:7667?ttl=0'
rm -f "$work/dump.bin" "$work/capture.bin"
"$bridge" --drone-id 2 --lcm-url "$url" --udp 14600:127.0.0.1:14601 --dump "$work/dump.bin" --arm --offboard \
  --command-tries 3 2>"$work/bridge.log" &
bridge_pid=$!
sleep 0.3
"$peer" --lcm-url "$url" --drone-id 2 --fc-port 14601 --bridge-port 14600 --capture "$work/capture.bin" \
  --duration 3.2 --setpoint-rate 20 --odometry-rate 100 2>"$work/peer.log"
peer_rc=$?
kill -INT "$bridge_pid"
wait "$bridge_pid"
bridge_rc=$?
cat "$work/bridge.log"
cat "$work/peer.log"
[ "$peer_rc" = 0 ] || { echo "FAIL: peer exited $peer_rc"; exit 1; }
[ "$bridge_rc" = 0 ] || { echo "FAIL: fact-fc-bridge exited $bridge_rc"; exit 1; }
for what in "setpoint position\[1\] = nan is not finite" "setpoint position\[2\] = 80 m outside the geofence z" "setpoint drone_id = 3"; do
  grep -q "rejected: $what" "$work/bridge.log" || { echo "FAIL: no log line 'rejected: $what'"; exit 1; }
done
rc=0
for f in dump.bin capture.bin; do
  echo "== $f ($(stat -c %s "$work/$f") bytes)"
  NODE_PATH="$npm_dir/node_modules" node "$src/test/mavlink_decode.js" "$work/$f" --expect-commands || rc=1
done
[ "$rc" = 0 ] && echo "1 passed, 0 failed" || echo "0 passed, 1 failed"
exit $rc
