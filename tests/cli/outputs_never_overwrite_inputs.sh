#!/bin/sh
# Every command refuses, before any work, an output that is one of its inputs or another of its
# outputs (exit 2, naming both), whether the two paths differ by a relative form, `..`, a
# symbolic link or a hard link; and no input changes. Usage: outputs_never_overwrite_inputs.sh CTK
set -u
ctk=$1
dir=outputs-never-overwrite-inputs
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir" || exit 1
"$ctk" simulate --out s --views 4 --cols 48 --rows 48 --pitch 9 --phantom helix-holder >/dev/null 2>&1 || { echo "simulate failed"; exit 1; }
ln -s s/joints.csv soft-joints.csv
ln s/joints.csv hard-joints.csv
before=$(cat s/*.json s/*.csv s/*.tif s/projections/* | md5sum)
failures=0
# expect NAME PATTERN COMMAND...: the command must exit 2 and print PATTERN.
expect() {
  name=$1 pattern=$2
  shift 2
  out=$("$@" 2>&1)
  code=$?
  if [ "$code" -ne 2 ] || ! printf '%s' "$out" | grep -q -- "$pattern"; then
    echo "FAIL $name: exit $code, expected 2 and '$pattern'; said: $out"
    failures=$((failures + 1))
  else
    echo "ok   $name: $(printf '%s' "$out" | tail -n 1)"
  fi
}
expect "calibrate --report onto the joint log" "would overwrite the input --scan: pose_source.joints_csv" \
  "$ctk" calibrate --scan s/scan.json --out g.json --report s/joints.csv
expect "geometry --out onto the scan" "would overwrite the input --scan (s/scan.json)" \
  "$ctk" geometry --scan s/scan.json --out s/scan.json
expect "geometry --out through .. onto the scan" "would overwrite the input --scan" \
  "$ctk" geometry --scan s/scan.json --out s/../s/scan.json
expect "geometry --out through a symbolic link" "would overwrite the input --scan: pose_source.joints_csv" \
  "$ctk" geometry --scan s/scan.json --out soft-joints.csv
expect "geometry --out through a hard link" "the same file under another name" \
  "$ctk" geometry --scan s/scan.json --out hard-joints.csv
expect "geometry --astra onto its own --out" "would overwrite the output --out" \
  "$ctk" geometry --scan s/scan.json --out both.json --astra both.json
# A geometry file under a volume's extension (readers go by content): --out passes the extension
# check and must still be refused.
cp s/truth-geometry.json s/geometry.mha
expect "reconstruct --out onto --geometry" "would overwrite the input --geometry" \
  "$ctk" reconstruct --scan s/scan.json --geometry s/geometry.mha --out s/geometry.mha
expect "diagnose --corrected-scan onto the scan" "would overwrite the input --scan" \
  "$ctk" diagnose --scan s/scan.json --geometry s/truth-geometry.json --out d.json --corrected-scan s/scan.json
expect "refine --out onto --geometry" "would overwrite the input --geometry" \
  "$ctk" refine --scan s/scan.json --geometry s/truth-geometry.json --out s/truth-geometry.json
expect "import --out onto --flat" "would overwrite the input --flat" \
  "$ctk" import circular --out s/flat.tif --files 's/projections/proj_%04d.tif' --count 4 --flat s/flat.tif --dark s/dark.tif \
  --detector 48 48 --pitch 9 --sod 1360 --sdd 2150 --step 90
expect "simulate into the folder of its --poses" "would overwrite the input poses" \
  "$ctk" simulate --out s --poses s/truth-geometry.json --cols 48 --rows 48 --pitch 9
after=$(cat s/*.json s/*.csv s/*.tif s/projections/* | md5sum)
[ "$before" = "$after" ] || { echo "FAIL: an input changed"; failures=$((failures + 1)); }
ls ./*.nrrd ./*.raw s/*.nrrd s/*.raw g.json d.json both.json 2>/dev/null | grep . && { echo "FAIL: an output was written"; failures=$((failures + 1)); }
echo "$failures failed"
[ "$failures" -eq 0 ]
