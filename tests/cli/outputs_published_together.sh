#!/bin/sh
# A run's outputs are published together or not at all: a simulation killed half way (or stopped
# by Ctrl-C, exit 130) into the folder of an earlier one leaves that scan exactly as it was (no new
# projections under the old truth), and a reconstruction killed while iterating leaves the earlier volume, its previews and
# its log as they were. A finished simulation replaces the earlier scan as a whole (no stale
# projections of a longer run), keeps the files it does not own and removes what the killed one
# left; a projection of another run
# copied into a scan's folder is refused by the readers. A diagnosis stopped by Ctrl-C writes
# nothing and exits 130. Usage: outputs_published_together.sh CTK
set -u
. "$(dirname "$0")/signals.sh"
ctk=$1
dir=outputs-published-together
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir" || exit 1
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
fingerprint() { find "$1" -type f | sort | xargs cat | md5sum; }


"$ctk" simulate --out s --views 6 --cols 48 --rows 48 --pitch 9 >/dev/null 2>&1 || { echo "simulate failed"; exit 1; }
echo "the user's note" > s/notes.txt
before=$(fingerprint s)
signal_when sim.log "simulate: [1-9][0-9]* / " KILL "$ctk" simulate --out s --views 200 --cols 512 --rows 512 --pitch 0.85
grep -q "simulate: [1-9][0-9]* / " sim.log || fail "the simulation was not caught half way: $(tail -n 1 sim.log)"
[ "$(fingerprint s)" = "$before" ] || fail "a simulation killed half way changed the earlier scan"
# Ctrl-C: exit 130 soon after, the earlier scan as it was and no hidden folder left behind.
signal_when sim-int.log "simulate: [1-9][0-9]* / " INT "$ctk" simulate --out s --views 200 --cols 512 --rows 512 --pitch 0.85
[ "$code" -eq 130 ] || fail "Ctrl-C during a simulation gave exit $code, expected 130: $(tail -n 1 sim-int.log)"
[ "$(fingerprint s)" = "$before" ] || fail "a simulation stopped by Ctrl-C changed the earlier scan"
ls -a | grep -q '^\.s\.' && fail "a simulation stopped by Ctrl-C left its hidden folder: $(ls -a | grep '^\.s\.')"

# Ctrl-C during a diagnosis (in its detection, or in a fit that checks no flag): exit 130, nothing written.
"$ctk" simulate --out d --views 40 --cols 360 --rows 360 --pitch 1.2 >/dev/null 2>&1 || fail "the diagnosis' scan failed"
signal_when diag.log "detect: [1-9][0-9]* / " INT "$ctk" diagnose --scan d/scan.json --geometry d/truth-geometry.json --out d/diag.json
# (A process ended by the signal also shows 130 to the shell: the message tells that it stopped itself.)
{ [ "$code" -eq 130 ] && grep -q "diagnose stopped by Ctrl-C: nothing written" diag.log; } ||
  fail "Ctrl-C during a diagnosis gave exit $code, expected 130 and the diagnosis' own stop: $(tail -n 1 diag.log)"
ls d/diag* 2>/dev/null | grep . && fail "a diagnosis stopped by Ctrl-C wrote its outputs"

"$ctk" reconstruct --scan s/scan.json --geometry s/truth-geometry.json --out s/v.nrrd --size 16 --iterations 1 >/dev/null 2>&1 ||
  fail "the first reconstruction failed"
before=$(cat s/v.nrrd s/v.log.json s/v_axial.png | md5sum)
signal_when recon.log "wls-cg: [1-9][0-9]* / " KILL "$ctk" reconstruct --scan s/scan.json --geometry s/truth-geometry.json --out s/v.nrrd --size 96 --method wls-cg --iterations 400
grep -q "wls-cg: [1-9][0-9]* / " recon.log || fail "the reconstruction was not caught iterating: $(tail -n 1 recon.log)"
[ "$(cat s/v.nrrd s/v.log.json s/v_axial.png | md5sum)" = "$before" ] || fail "a reconstruction killed while iterating changed the earlier outputs"

"$ctk" simulate --out s --views 3 --cols 48 --rows 48 --pitch 9 >/dev/null 2>&1 || fail "the second simulation failed"
ls -a | grep -q '^\.s\.' && fail "the hidden folder of the killed simulation is still there: $(ls -a | grep '^\.s\.')"
[ "$(ls s/projections | wc -l)" -eq 3 ] || fail "stale projections of the earlier scan: $(ls s/projections | tr '\n' ' ')"
[ "$(cat s/notes.txt 2>/dev/null)" = "the user's note" ] || fail "the user's note was not kept"
[ -s s/v.nrrd ] || fail "the earlier reconstruction beside the scan was not kept"
# A folder whose parts two runs wrote is refused by its readers, naming the stranger.
"$ctk" simulate --out other --views 6 --cols 48 --rows 48 --pitch 9 >/dev/null 2>&1 || fail "the other simulation failed"
cp other/projections/proj_0001.tif s/projections/proj_0001.tif
out=$("$ctk" reconstruct --scan s/scan.json --geometry s/truth-geometry.json --out s/mixed.nrrd --size 16 --iterations 1 2>&1)
code=$?
{ [ "$code" -eq 2 ] && printf '%s' "$out" | grep -q "proj_0001.tif: was written by ctk run .*the folder mixes two runs' files"; } ||
  fail "a projection of another run was accepted: exit $code, $(printf '%s' "$out" | tail -n 1)"
echo "$failures failed"
[ "$failures" -eq 0 ]
