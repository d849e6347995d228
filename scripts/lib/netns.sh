# Shared by the scripts that talk udpm inside a private network namespace (sourced, not run).

# foreign_interfaces: the network interfaces of this namespace other than lo, space separated
# (empty in a private namespace made by netns-run.sh). /proc/net/dev lists this namespace's own;
# /sys/class/net may still show the host's.
foreign_interfaces() { awk -F: 'NR > 2 { gsub(/ /, "", $1); if ($1 != "lo") printf "%s ", $1 }' /proc/net/dev; }

# udpm_may_leave: true when udpm here could reach the machine's interfaces: this namespace has an
# interface besides lo and is not known to be another than the machine's own (that of PID 1; not
# known when /proc/1/ns/net cannot be read). A namespace made by netns-run.sh (lo only) is safe, and
# so is one of run-sim.sh's drone namespaces (veths to a bridge in its private namespace), which
# root can tell from the machine's.
udpm_may_leave() {
  [ -n "$(foreign_interfaces)" ] || return 1
  local self host
  self=$(readlink /proc/self/ns/net 2>/dev/null) || return 0
  host=$(readlink /proc/1/ns/net 2>/dev/null) || return 0
  [ "$self" = "$host" ]
}
