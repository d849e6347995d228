# Sourced by the scripts/bench-*.sh scripts: the preamble they share. Sets `here` (the repository)
# and `build` (BUILD_DIR, default <repo>/build), and defines:
#   bench_build TARGET...      installs what is missing (scripts/install-deps.sh), configures
#                              $build in Release and builds the targets
#   bench_args BINARY ARGS...  with --help/-h among ARGS, shows BINARY's help and exits; sets
#                              out_dir to the --out-dir among ARGS (default bench/results)
here="$(cd "$(dirname "${BASH_SOURCE[1]}")/.." && pwd)"
# (absolute: the scripts cd to the repository before they run the binary, so a relative BUILD_DIR
# was built under the caller's folder and then looked for under the repository)
build="$(realpath -m "${BUILD_DIR:-$here/build}")"

bench_build() {
  "$here/scripts/install-deps.sh"
  cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release >"$build.configure.log" 2>&1 ||
    { cat "$build.configure.log"; exit 1; }
  cmake --build "$build" -j "$(nproc)" --target "$@"
}

bench_args() {
  local bin=$1 i
  shift
  local args=("$@")
  out_dir="bench/results"
  for ((i = 0; i < ${#args[@]}; ++i)); do
    case "${args[i]}" in
      --help|-h) exec "$bin" --help ;;
      --out-dir) out_dir="${args[i + 1]:-$out_dir}" ;;
      --out-dir=*) out_dir="${args[i]#--out-dir=}" ;;
    esac
  done
}
