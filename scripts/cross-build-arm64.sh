#!/usr/bin/env bash
# Cross-builds fact for aarch64 (64-bit ARM Linux: Jetson Orin class boards running Debian 12 arm64)
# on an x86-64 Debian 12 host, and tests the result under qemu user mode. As root (or with sudo):
#   scripts/cross-build-arm64.sh                       everything below, in ./build-arm64
#   BUILD_DIR=/tmp/b JOBS=2 scripts/cross-build-arm64.sh
#   CTEST_ARGS="-R Gossip" scripts/cross-build-arm64.sh  extra ctest arguments
#   FACT_TEST_TIME_SCALE=20 scripts/cross-build-arm64.sh   test deadlines and timeouts x20 (default 10)
#   HOST_BUILD_DIR=build scripts/cross-build-arm64.sh    x86-64 reference tools from ./build
#   scripts/cross-build-arm64.sh --no-tests            sysroot + cross build + stripped binaries only
# Phases (each timed; the summary at the end prints the results):
#   1. host packages: scripts/install-deps.sh, g++-aarch64-linux-gnu, qemu-user, mmdebstrap
#   2. sysroot: Debian bookworm arm64 with the project's -dev packages (mmdebstrap
#      --variant=extract), in BUILD_DIR/sysroot, kept for the next run while its package list is
#      the same. Maintainer scripts do not run there, so absolute symlinks are made relative and the
#      BLAS/LAPACK alternatives are linked here.
#   3. x86-64 reference tools (BUILD_DIR/x86_64, or an existing native build tree named by
#      HOST_BUILD_DIR, e.g. HOST_BUILD_DIR=build after scripts/test.sh): fact-solve, fact-simgen,
#      fact-gossip and the gossip test helpers, built natively for the comparisons below
#   4. cross build (BUILD_DIR/aarch64): every app, test and benchmark, with
#      cmake/toolchains/aarch64-linux-gnu.cmake and the host's lcm-gen
#   5. ctest: every test under qemu-aarch64 -L BUILD_DIR/sysroot (CMAKE_CROSSCOMPILING_EMULATOR;
#      no binfmt handler needed), udpm tests in private network namespaces as natively. qemu runs
#      the code far slower than the host, so the tests' waiting deadlines and ctest timeouts are
#      multiplied by FACT_TEST_TIME_SCALE (default 10 here; test/time_scale.cmake)
#   6. fact-solve arm64 vs x86-64 on the same rounds files: equal to 1e-9 (test/arm64/compare-solve.sh)
#   7. an arm64 and an x86-64 fact-gossip exchange a round over udpm:// in a private network
#      namespace (test/arm64/gossip-exchange.sh)
#   8. stripped copies of the arm64 apps in BUILD_DIR/deploy/bin (what to copy to a board), sizes
# Exit 0 when every phase run passed.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$here/build-arm64}"
jobs="${JOBS:-$(nproc)}"
mirror="${FACT_DEBIAN_MIRROR:-http://deb.debian.org/debian}"
security_mirror="${FACT_DEBIAN_SECURITY_MIRROR:-http://deb.debian.org/debian-security}"
run_tests=1
time_scale="${FACT_TEST_TIME_SCALE:-10}"
case "${1:-}" in
  "") ;;
  --no-tests) run_tests=0 ;;
  -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
  *) echo "cross-build-arm64: unknown argument '$1' (use --no-tests or --help)" >&2; exit 2 ;;
esac

sysroot="$build/sysroot"
host_build="${HOST_BUILD_DIR:-$build/x86_64}"
cross_build="$build/aarch64"
deploy="$build/deploy"
check="$build/check"
# The arm64 -dev packages of scripts/install-deps.sh that the build links or includes (the SDP peers
# of the benchmark, SDPA and CSDP, are left out: bench/ builds without them).
sysroot_packages=(
  libc6-dev libstdc++-12-dev
  libeigen3-dev libgtest-dev nlohmann-json3-dev libcli11-dev
  liblcm-dev libglib2.0-dev libsodium-dev libccd-dev
  libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev libopencv-dnn-dev
)
mkdir -p "$build"
sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"

declare -a phase_names=() phase_seconds=()
phase_start=0
begin() { echo "== $1"; phase_names+=("$1"); phase_start=$SECONDS; }
end() { phase_seconds+=($((SECONDS - phase_start))); }
# log FILE CMD...: runs CMD with its output in FILE; on failure shows the end of FILE.
log() {
  local file=$1; shift
  "$@" >"$file" 2>&1 || { local rc=$?; tail -n 60 "$file" >&2; echo "cross-build-arm64: failed ($rc): $* (log: $file)" >&2; return "$rc"; }
}

# ---- 1. host packages
begin "host packages"
"$here/scripts/install-deps.sh"
missing=()
for p in g++-aarch64-linux-gnu qemu-user mmdebstrap; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "== installing: ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
end

# ---- 2. sysroot
begin "sysroot"
sources=("deb $mirror bookworm main" "deb $mirror bookworm-updates main" "deb $security_mirror bookworm-security main")
want_stamp="$(printf '%s\n' "${sysroot_packages[@]}" "${sources[@]}")"
if [ -f "$sysroot/.fact-sysroot" ] && [ "$(cat "$sysroot/.fact-sysroot")" = "$want_stamp" ]; then
  echo "== sysroot cached: $sysroot"
else
  $sudo rm -rf "$sysroot" "$sysroot.tmp"
  echo "== mmdebstrap: bookworm arm64 -> $sysroot (log: $build/mmdebstrap.log)"
  log "$build/mmdebstrap.log" $sudo mmdebstrap --variant=extract --architectures=arm64 \
    --include="$(IFS=,; echo "${sysroot_packages[*]}")" bookworm "$sysroot.tmp" "${sources[@]}"
  # qemu -L takes any path that exists in the sysroot from there: the sysroot's own /dev (ptmx,
  # null, ...) would shadow the host's (openpty fails), so it goes, with the other empty mount points.
  $sudo rm -rf "$sysroot.tmp/dev" "$sysroot.tmp/proc" "$sysroot.tmp/sys" "$sysroot.tmp/run" "$sysroot.tmp/tmp"
  # Absolute symlinks (libz.so -> /lib/aarch64-linux-gnu/libz.so.1.2.13, ...) would resolve into
  # the host's x86-64 files: point them inside the sysroot.
  while IFS= read -r -d '' link; do
    $sudo ln -sfn --relative "$sysroot.tmp$(readlink "$link")" "$link"
  done < <(find "$sysroot.tmp" -type l -lname '/*' -print0)
  # update-alternatives did not run: libblas.so.3 / liblapack.so.3 (needed by OpenCV) are missing.
  libdir="$sysroot.tmp/usr/lib/aarch64-linux-gnu"
  for lib in libblas.so.3 liblapack.so.3; do
    [ -e "$libdir/$lib" ] && continue
    for impl in openblas-pthread blas lapack atlas; do
      if [ -e "$libdir/$impl/$lib" ]; then $sudo ln -sfn "$impl/$lib" "$libdir/$lib"; break; fi
    done
    [ -e "$libdir/$lib" ] || { echo "cross-build-arm64: no $lib implementation in the sysroot" >&2; exit 1; }
  done
  printf '%s\n' "$want_stamp" | $sudo tee "$sysroot.tmp/.fact-sysroot" >/dev/null
  $sudo mv "$sysroot.tmp" "$sysroot"
fi
echo "== sysroot: $(du -sh "$sysroot" | cut -f1)"
end

# ---- 3. x86-64 reference tools
host_targets=(fact-solve fact-simgen fact-gossip fact_round_inject fact_swarm_rounds_check)
if ((run_tests)); then
  begin "x86-64 reference build"
  if [ ! -f "$host_build/CMakeCache.txt" ]; then
    log "$build/x86_64.configure.log" cmake -S "$here" -B "$host_build" -DCMAKE_BUILD_TYPE=Release -DFACT_BUILD_BENCH=OFF
  fi
  log "$build/x86_64.build.log" cmake --build "$host_build" -j "$jobs" --target "${host_targets[@]}"
  end
fi

# ---- 4. cross build
begin "arm64 cross build"
jar_args=()
# The lcm-spy jar is Java bytecode: lcm-gen -j and javac of the host, against the host's lcm.jar.
[ -f /usr/share/java/lcm.jar ] && jar_args=(-DLCM_JAR=/usr/share/java/lcm.jar)
log "$build/aarch64.configure.log" cmake -S "$here" -B "$cross_build" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_TOOLCHAIN_FILE="$here/cmake/toolchains/aarch64-linux-gnu.cmake" -DFACT_ARM64_SYSROOT="$sysroot" \
  -DFACT_TEST_TIME_SCALE="$time_scale" "${jar_args[@]}"
echo "== build ($cross_build, log: $build/aarch64.build.log)"
log "$build/aarch64.build.log" cmake --build "$cross_build" -j "$jobs"
end

# ---- 5. tests under qemu
ctest_line="not run"
solve_line="not run"
simgen_line="not run"
gossip_line="not run"
status=0
if ((run_tests)); then
  begin "ctest under qemu-aarch64"
  rc=0
  echo "== FACT_TEST_TIME_SCALE=$time_scale (waiting deadlines and timeouts; no test checks a speed)"
  # shellcheck disable=SC2086  # CTEST_ARGS are words, e.g. CTEST_ARGS="-R Gossip"
  ctest --test-dir "$cross_build" --output-on-failure -j "$jobs" ${CTEST_ARGS:-} 2>&1 | tee "$build/ctest.log" || rc=$?
  ctest_line="$(grep -E '^[0-9]+% tests passed' "$build/ctest.log" | tail -n1 || true)"
  skipped="$(grep -c '\*\*\*Skipped\|Not Run' "$build/ctest.log" || true)"
  [ "${rc}" -eq 0 ] && [ -n "$ctest_line" ] || status=1
  ctest_line="${ctest_line:-ctest failed to run} (skipped: $skipped; FACT_TEST_TIME_SCALE=$time_scale; log: $build/ctest.log)"
  end

  # ---- 6. fact-solve arm64 vs x86-64
  begin "fact-solve arm64 vs x86-64"
  rc=0
  bash "$here/test/arm64/compare-solve.sh" "$host_build/apps/fact-simgen" "$host_build/apps/fact-solve" \
    "$cross_build/apps/fact-solve.qemu" "$check/solve" "$cross_build/apps/fact-simgen.qemu" 2>&1 | tee "$build/compare-solve.log" || rc=$?
  solve_line="$(tail -n1 "$build/compare-solve.log")"
  simgen_line="$(sed -n 's/^fact-simgen arm64 vs x86-64: //p' "$build/compare-solve.log")"
  [ "$rc" -eq 0 ] || status=1
  end

  # ---- 7. gossip arm64 <-> x86-64
  begin "fact-gossip arm64 <-> x86-64"
  rc=0
  FACT_TEST_TIME_SCALE="$time_scale" sh "$here/test/arm64/gossip-exchange.sh" "$host_build/apps/fact-simgen" \
    "$host_build/apps/fact-gossip" "$cross_build/apps/fact-gossip.qemu" "$host_build/test/fact_round_inject" \
    "$host_build/test/fact_swarm_rounds_check" "$check/gossip" 2>&1 | tee "$build/gossip-exchange.log" || rc=$?
  gossip_line="$(tail -n1 "$build/gossip-exchange.log")"
  [ "$rc" -eq 0 ] || status=1
  end
fi

# ---- 8. stripped binaries
begin "stripped binaries"
rm -rf "$deploy" && mkdir -p "$deploy/bin"
while IFS= read -r -d '' f; do
  case "$(od -An -tx1 -j18 -N2 "$f" | tr -d ' \n')" in b700) ;; *) continue ;; esac
  aarch64-linux-gnu-strip -o "$deploy/bin/$(basename "$f")" "$f"
done < <(find "$cross_build/apps" "$cross_build/firmware_bridge" -maxdepth 2 -type f -name 'fact-*' -perm -u+x -print0)
mkdir -p "$deploy/share/fact" && cp -r "$here/apps/fact_sim/worlds" "$deploy/share/fact/"
end

# ---- summary
echo
echo "== arm64 cross build: summary ($build)"
echo "stripped arm64 binaries ($deploy/bin):"
(cd "$deploy/bin" && for f in *; do
  awk -v f="$f" -v b="$(stat -c %s "$f")" 'BEGIN { printf "  %-22s %9d bytes %7.2f MiB\n", f, b, b / 1048576 }'
done)
echo "  total                  $(cat "$deploy"/bin/* | wc -c) bytes"
echo "shared libraries they load (besides libc, libm, libstdc++, libgcc_s):"
for f in "$deploy"/bin/*; do aarch64-linux-gnu-readelf -d "$f" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'; done |
  grep -Ev '^(libc|libm|libstdc\+\+|libgcc_s|ld-linux-aarch64)\.so' | sort -u | tr '\n' ' ' | fold -s -w 96 | sed 's/^/  /'
echo
echo "unit tests under qemu-aarch64: $ctest_line"
echo "fact-solve arm64 vs x86-64:    $solve_line"
echo "fact-simgen arm64 vs x86-64:   $simgen_line"
echo "fact-gossip arm64 <-> x86-64:  $gossip_line"
echo "phase timings:"
for i in "${!phase_names[@]}"; do printf '  %-30s %5d s\n' "${phase_names[$i]}" "${phase_seconds[$i]}"; done
echo "  total                          $SECONDS s"
exit "$status"
