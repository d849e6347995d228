#!/usr/bin/env bash
# lcm-spy (Debian liblcm-java) with the fact message types, so it decodes our traffic:
#   scripts/spy.sh 'udpm://239.255.76.67:7667?ttl=1'    any LCM URL (LCM's default when none)
# A udpm URL is refused where it could leave this machine (scripts/lib/netns.sh, udpm_may_leave):
# run it inside a private namespace, that of a running swarm (nsenter, see README.md) or one of
# its own beside a log player (scripts/netns-run.sh sh -c "lcm-logplayer ... & scripts/spy.sh ...").
# The jar is built by CMake at $BUILD_DIR/lcmtypes/fact_lcmtypes.jar (BUILD_DIR defaults to build/);
# when it is missing, this builds the target fact_lcmtypes_jar first (configuring if needed).
# FACT_LCM_JAR=/path/to.jar uses that jar instead and builds nothing. Extra arguments after the URL
# go to lcm-spy. Needs a display (DISPLAY); Debian's lcm-spy passes -Xincgc, which Java 17 rejects,
# hence JAVA_TOOL_OPTIONS=-XX:+IgnoreUnrecognizedVMOptions.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
. "$here/scripts/lib/netns.sh"
build="${BUILD_DIR:-$here/build}"
jar="${FACT_LCM_JAR:-$build/lcmtypes/fact_lcmtypes.jar}"

# udpm (a udpm:// URL, or none: LCM's default, unless LCM_DEFAULT_URL names another provider) only
# inside a private network namespace (review, session 33: the spy joined the group on the host's
# interfaces).
url_or_default="${1:-${LCM_DEFAULT_URL:-udpm://}}"
if [[ "$url_or_default" == udpm* ]] && udpm_may_leave; then
  echo "spy.sh: refusing udpm here: this network namespace has interfaces besides lo and may be the machine's own" >&2
  echo "  (multicast must not leave the machine)." >&2
  echo "  Watch a running swarm from inside its namespace: nsenter -t <pid of one of its fact-* apps> -n scripts/spy.sh URL;" >&2
  echo "  a log: scripts/netns-run.sh sh -c \"lcm-logplayer --lcm-url=URL LOG & scripts/spy.sh URL\"." >&2
  exit 2
fi

command -v java >/dev/null 2>&1 || { echo "spy.sh: java not found (scripts/install-deps.sh installs default-jdk-headless)" >&2; exit 1; }
for f in /usr/share/java/lcm.jar /usr/share/java/jchart2d.jar; do
  [ -f "$f" ] || { echo "spy.sh: $f missing (Debian packages liblcm-java, libjchart2d-java)" >&2; exit 1; }
done
if [ ! -f "$jar" ]; then
  if [ -n "${FACT_LCM_JAR:-}" ]; then echo "spy.sh: FACT_LCM_JAR=$jar does not exist" >&2; exit 1; fi
  echo "spy.sh: building $jar (target fact_lcmtypes_jar in $build)" >&2
  if [ ! -f "$build/CMakeCache.txt" ]; then
    cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release >"$build.configure.log" 2>&1 ||
      { cat "$build.configure.log" >&2; exit 1; }
  fi
  cmake --build "$build" --target fact_lcmtypes_jar >&2
  [ -f "$jar" ] || { echo "spy.sh: $jar was not built (no javac? see the CMake configure output)" >&2; exit 1; }
fi
if [ -z "${DISPLAY:-}" ]; then
  echo "spy.sh: no DISPLAY; lcm-spy is a Swing window (for a headless check run it under Xvfb)" >&2
  exit 1
fi

url="${1:-}"
[ "$#" -gt 0 ] && shift
# lcm-spy's class discovery (lcm.util.ClassDiscoverer) scans $CLASSPATH as well as java.class.path,
# and Debian's /usr/bin/lcm-spy sets -cp to lcm.jar:jchart2d.jar only: the jar goes in CLASSPATH.
export CLASSPATH="$jar:/usr/share/java/jchart2d.jar${CLASSPATH:+:$CLASSPATH}"
export JAVA_TOOL_OPTIONS="-XX:+IgnoreUnrecognizedVMOptions${JAVA_TOOL_OPTIONS:+ $JAVA_TOOL_OPTIONS}"
spy="$(command -v lcm-spy || true)"
if [ -n "$spy" ]; then
  exec "$spy" ${url:+--lcm-url="$url"} "$@"
fi
# No /usr/bin/lcm-spy (liblcm-bin missing): the same class, started directly.
exec java -Djava.net.preferIPv4Stack=true -Xmx128m -ea \
  -cp "/usr/share/java/lcm.jar:$CLASSPATH" lcm.spy.Spy ${url:+--lcm-url="$url"} "$@"
