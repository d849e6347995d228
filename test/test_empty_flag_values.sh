#!/bin/bash
# Every app refuses an empty flag value (CLI11 alone read "" as 0: "--drone-id ''" ran as drone 0,
# "--drop ''" as no loss). Each argument is BINARY=FLAG; the app runs with FLAG "" and must exit 2
# before doing anything else, naming the flag and saying the value is empty.
#
#   test/test_empty_flag_values.sh BINARY=FLAG...
set -u
[ "$#" -gt 0 ] || { echo "usage: $0 BINARY=FLAG..." >&2; exit 2; }
failures=0
for pair in "$@"; do
  binary=${pair%=*} flag=${pair##*=}
  name=$(basename "$binary")
  rc=0
  err=$(timeout 30 "$binary" "$flag" "" </dev/null 2>&1 >/dev/null) || rc=$?
  if [ "$rc" -ne 2 ]; then
    echo "FAIL $name $flag \"\": exit $rc, expected 2; stderr: $err" >&2
    failures=$((failures + 1))
  elif ! grep -q -- "$flag: expected a value, got an empty string" <<<"$err"; then
    echo "FAIL $name $flag \"\": stderr does not name the flag and the empty value: $err" >&2
    failures=$((failures + 1))
  else
    echo "ok   $name $flag \"\": $err"
  fi
done
[ "$failures" -eq 0 ] || { echo "test_empty_flag_values: $failures of $# failed" >&2; exit 1; }
