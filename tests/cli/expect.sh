# Sourced by the command-line tests that check refusals. Counts failures in $failures.
# expect NAME PATTERN COMMAND...: the command must exit 2 and print PATTERN, and none of C++'s own
# text (an exception's internal message) may reach the user.
failures=0
expect() {
  name=$1 pattern=$2
  shift 2
  out=$("$@" 2>&1)
  code=$?
  if [ "$code" -ne 2 ] || ! printf '%s' "$out" | grep -q -- "$pattern" ||
    printf '%s' "$out" | grep -q -e 'std::' -e '_M_' -e 'filesystem error' -e 'bad_alloc'; then
    echo "FAIL $name: exit $code, expected 2 and '$pattern'; said: $out"
    failures=$((failures + 1))
  else
    echo "ok   $name: $(printf '%s' "$out" | tail -n 1)"
  fi
}
