#!/bin/sh
# An interrupted calibration continued with --resume takes the views the first run finished as
# they are and calibrates the rest: the geometry equals an uninterrupted run's (every matrix entry
# to 1e-9 relative), after Ctrl-C (exit 130) and after a kill. A journal is refused by a run with
# other options, naming the option, and removed once the run completes.
# Usage: calibrate_resumes.sh CTK PYTHON
set -u
. "$(dirname "$0")/signals.sh"
ctk=$1
python=$2
dir=calibrate-resumes
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir" || exit 1
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
"$ctk" simulate --out s --views 200 --cols 360 --rows 360 --pitch 1.2 >/dev/null 2>&1 || { echo "simulate failed"; exit 1; }


same_geometry() {
  "$python" - "$1" "$2" <<'EOF'
import json, sys
a, b = (json.load(open(name))["views"] for name in sys.argv[1:3])
worst = 0.0
for u, v in zip(a, b):
    if u["status"] != v["status"]:
        sys.exit(f"view {u['index']}: {u['status']} against {v['status']}")
    if "P" in u:
        scale = max(abs(x) for x in u["P"])
        worst = max(worst, max(abs(x - y) for x, y in zip(u["P"], v["P"])) / scale)
print(f"{sys.argv[2]}: {len(b)} views, largest matrix difference {worst:.1e}")
sys.exit(0 if len(a) == len(b) and worst <= 1e-9 else 1)
EOF
}

"$ctk" calibrate --scan s/scan.json --out whole.json >/dev/null 2>&1 || fail "the uninterrupted calibration failed"

signal_when int.log "calibrate: [1-9][0-9][0-9]* / " INT "$ctk" calibrate --scan s/scan.json --out int.json
[ "$code" -eq 130 ] || fail "Ctrl-C gave exit $code, expected 130: $(tail -n 1 int.log)"
grep -q "run the same command with --resume" int.log || fail "Ctrl-C did not say how to continue"
[ -e int.json ] && fail "an interrupted calibration published a geometry"
finished=$(($(wc -l < int.journal) - 1))
"$ctk" calibrate --scan s/scan.json --out int.json --min-spheres 7 --resume > refused.log 2>&1
code=$?
{ [ "$code" -eq 2 ] && grep -q "int.journal: key 'run.min_spheres'" refused.log; } ||
  fail "a journal continued by a run with another --min-spheres: exit $code, $(tail -n 1 refused.log)"
"$ctk" calibrate --scan s/scan.json --out int.json --resume > int.resumed.log 2>&1 || fail "--resume failed: $(tail -n 1 int.resumed.log)"
grep -q "continuing: $finished views were calibrated by the interrupted run" int.resumed.log ||
  fail "the continued run did not take the $finished journaled views: $(grep continuing int.resumed.log)"
same_geometry whole.json int.json || fail "continued after Ctrl-C, not the uninterrupted geometry"
[ -e int.journal ] && fail "the journal outlived the completed run"

signal_when kill.log "calibrate: [1-9][0-9][0-9]* / " KILL "$ctk" calibrate --scan s/scan.json --out kill.json
[ -s kill.journal ] || fail "no journal after a kill"
"$ctk" calibrate --scan s/scan.json --out kill.json --resume > kill.resumed.log 2>&1 || fail "--resume after a kill failed: $(tail -n 1 kill.resumed.log)"
same_geometry whole.json kill.json || fail "continued after a kill, not the uninterrupted geometry"
echo "$failures failed"
[ "$failures" -eq 0 ]
