#!/usr/bin/env bash
# lcm-spy (Debian liblcm-java) with the fact message types, so it decodes our traffic:
#   scripts/spy.sh                                      default LCM URL (udpm://239.255.76.67:7667)
#   scripts/spy.sh 'udpm://239.255.76.67:7667?ttl=0'    any LCM URL
#   scripts/netns-run.sh scripts/spy.sh '...?ttl=0'      beside a swarm run in the same namespace
# The jar is built by CMake at $BUILD_DIR/lcmtypes/fact_lcmtypes.jar (BUILD_DIR defaults to build/);
# when it is missing, this builds the target fact_lcmtypes_jar first (configuring if needed).
# FACT_LCM_JAR=/path/to.jar uses that jar instead and builds nothing. Extra arguments after the URL
# go to lcm-spy. Needs a display (DISPLAY); Debian's lcm-spy passes -Xincgc, which Java 17 rejects,
# hence JAVA_TOOL_OPTIONS=-XX:+IgnoreUnrecognizedVMOptions.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$here/build}"
jar="${FACT_LCM_JAR:-$build/lcmtypes/fact_lcmtypes.jar}"

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
