#!/bin/bash
# Every app refuses an empty flag value, and an integer flag refuses a value that is not a plain
# decimal integer (CLI11 alone read "" as 0 and "010", " 010" or "0x10" in C's bases:
# "--drone-id ''" ran as drone 0, "--drone-id 010" as drone 8). Each argument is BINARY=FLAG:int
# (an integer flag: "", "010", " 010" and "0x10" are each refused) or BINARY=FLAG:text (any other:
# "" is refused). The app must exit 2 before doing anything else, naming the flag and what is
# wrong with the value.
#
#   test/test_unclear_flag_values.sh BINARY=FLAG:int|text...
set -u
# Apps that got past their flags would open LCM's default URL: memq://, in process, so that even a
# failing case sends no udpm outside a private namespace.
export LCM_DEFAULT_URL=memq://
[ "$#" -gt 0 ] || { echo "usage: $0 BINARY=FLAG:int|text..." >&2; exit 2; }
failures=0 runs=0
check() {  # check BINARY FLAG VALUE EXPECTED_TEXT
  local name rc=0 err
  name=$(basename "$1")
  runs=$((runs + 1))
  err=$(timeout 30 "$1" "$2" "$3" </dev/null 2>&1 >/dev/null) || rc=$?
  if [ "$rc" -ne 2 ]; then
    echo "FAIL $name $2 '$3': exit $rc, expected 2; stderr: $err" >&2
    failures=$((failures + 1))
  elif ! grep -qF -- "$2: $4" <<<"$err"; then
    echo "FAIL $name $2 '$3': stderr does not say '$2: $4': $err" >&2
    failures=$((failures + 1))
  else
    echo "ok   $name $2 '$3': $err"
  fi
}
for case_ in "$@"; do
  binary=${case_%=*} rest=${case_##*=}
  flag=${rest%:*} kind=${rest##*:}
  check "$binary" "$flag" "" "expected a value, got an empty string"
  if [ "$kind" = int ]; then
    check "$binary" "$flag" "010" "'010' has a leading zero, which would read as octal"
    check "$binary" "$flag" " 010" "expected a decimal integer, got ' 010'"
    check "$binary" "$flag" "0x10" "expected a decimal integer, got '0x10'"
  fi
done
[ "$failures" -eq 0 ] || { echo "test_unclear_flag_values: $failures of $runs failed" >&2; exit 1; }
