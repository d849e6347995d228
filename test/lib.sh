# Shell helpers shared by the test scripts (POSIX sh). Source it from a script in test/:
#   . "$(dirname "$0")/lib.sh"
# FACT_TEST_TIME_SCALE (a whole number >= 1, default 1; ctest sets it for every test, see
# test/time_scale.cmake; 10 under qemu) multiplies every "give up after SECONDS" deadline here.
# Nothing here measures how fast anything runs.

case "${FACT_TEST_TIME_SCALE:-1}" in
  '' | 0* | *[!0-9]*)
    echo "test/lib.sh: FACT_TEST_TIME_SCALE='$FACT_TEST_TIME_SCALE' is not a whole number >= 1" >&2
    exit 2 ;;
esac

# scaled SECONDS: prints SECONDS (whole) times FACT_TEST_TIME_SCALE, e.g. timeout "$(scaled 20)" CMD.
scaled() { echo $(($1 * ${FACT_TEST_TIME_SCALE:-1})); }

# wait_until SECONDS CMD...: runs CMD every 0.1 s until it succeeds; fails after scaled SECONDS.
wait_until() {
  _wait_limit=$(($(scaled "$1") * 10))
  shift
  _wait_n=0
  while ! "$@"; do
    _wait_n=$((_wait_n + 1))
    [ "$_wait_n" -ge "$_wait_limit" ] && return 1
    sleep 0.1
  done
  return 0
}
