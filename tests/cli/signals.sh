# Sourced by the command-line tests that interrupt a run.
# signal_when LOG PATTERN SIGNAL COMMAND...: runs COMMAND in the background (output to LOG), sends
# it SIGNAL once LOG matches PATTERN (or when 60 s have passed), waits for it and sets $code.
signal_when() {
  log=$1 pattern=$2 signal=$3
  shift 3
  "$@" > "$log" 2>&1 &
  pid=$!
  i=0
  while ! grep -q -- "$pattern" "$log" 2>/dev/null && kill -0 $pid 2>/dev/null && [ $i -lt 3000 ]; do
    i=$((i + 1))
    sleep 0.02
  done
  kill "-$signal" $pid 2>/dev/null
  wait $pid
  code=$?
}
