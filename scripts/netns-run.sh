#!/usr/bin/env bash
# Runs a command inside a fresh private network namespace, so that LCM's udpm:// multicast never
# leaves this machine (and never meets other runs' traffic):
#   scripts/netns-run.sh CMD [ARGS...]
# The namespace has only the loopback interface, brought up, with the multicast route
# 224.0.0.0/4 on lo. The command's exit code is passed through; the namespace disappears with it.
# Needs root (or CAP_SYS_ADMIN) and util-linux unshare + iproute2 ip. Fails (exit 125) with the
# reason when they are missing.
set -euo pipefail
if [ "$#" -eq 0 ]; then
  echo "usage: $0 CMD [ARGS...]   (runs CMD in a private network namespace with lo up and 224.0.0.0/4 on lo)" >&2
  exit 125
fi
for tool in unshare ip; do
  command -v "$tool" >/dev/null 2>&1 || { echo "netns-run: '$tool' not found (install util-linux / iproute2)" >&2; exit 125; }
done
if [ "$(id -u)" -ne 0 ]; then
  echo "netns-run: needs root to create a network namespace (run with sudo)" >&2
  exit 125
fi
unshare --net -- true 2>/dev/null || {
  echo "netns-run: 'unshare --net' is not permitted here (a container without CAP_SYS_ADMIN?)" >&2
  exit 125
}
# Inside: set up lo and the route; any failure there is reported as 125, then exec the command
# (so its exit code and signals are its own). Where mounts are allowed, the command also gets a
# private mount namespace with its own /run/netns: the namespaces 'ip netns add' makes inside
# (run-sim.sh's per-drone ones) then vanish with it, even when it is killed by SIGKILL before its
# cleanup runs (a ctest timeout left them mounted on the host). Where they are not (a container
# that allows network namespaces only), everything runs as before, without that guard.
mounts=(--mount --propagation private)
private_run_netns=1
if ! unshare --net --mount --propagation private -- sh -c 'mount -t tmpfs -o size=1m fact-netns /tmp' 2>/dev/null; then
  mounts=()
  private_run_netns=0
fi
exec unshare --net "${mounts[@]}" -- env FACT_NETNS_PRIVATE_RUN="$private_run_netns" sh -c '
  ip link set lo up || { echo "netns-run: cannot bring lo up in the new namespace" >&2; exit 125; }
  ip route add 224.0.0.0/4 dev lo || { echo "netns-run: cannot add the multicast route on lo" >&2; exit 125; }
  if [ "$FACT_NETNS_PRIVATE_RUN" = 1 ]; then
    mkdir -p /run/netns && mount -t tmpfs -o size=1m fact-netns /run/netns ||
      { echo "netns-run: cannot mount a private /run/netns" >&2; exit 125; }
  fi
  unset FACT_NETNS_PRIVATE_RUN
  exec "$@"
' netns-run "$@"
