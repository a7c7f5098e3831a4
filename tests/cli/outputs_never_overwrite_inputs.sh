#!/bin/sh
# Every command refuses, before any work, an output that is one of its inputs or another of its
# outputs (exit 2, naming both), whether the two paths differ by a relative form, `..`, a
# symbolic link or a hard link; and no input changes. Usage: outputs_never_overwrite_inputs.sh CTK
set -u
ctk=$1
. "$(dirname "$0")/expect.sh"
dir=outputs-never-overwrite-inputs
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir" || exit 1
"$ctk" simulate --out s --views 4 --cols 48 --rows 48 --pitch 9 --phantom helix-holder >/dev/null 2>&1 || { echo "simulate failed"; exit 1; }
ln -s s/joints.csv soft-joints.csv
ln s/joints.csv hard-joints.csv
before=$(cat s/*.json s/*.csv s/*.tif s/projections/* | md5sum)
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
# An output that names a device, a FIFO or a folder is refused before any work, never replaced
# by a regular file (a private null device: `--out /dev/null` run as root replaced the machine's).
mknod null-device c 1 3 2>/dev/null && {
  expect "geometry --out onto a device" "is a device, not a regular file" "$ctk" geometry --scan s/scan.json --out null-device
  [ -c null-device ] || { echo "FAIL: the device was replaced"; failures=$((failures + 1)); }
}
mkfifo fifo
expect "geometry --astra onto a FIFO" "is a FIFO, not a regular file" "$ctk" geometry --scan s/scan.json --out f.json --astra fifo
[ -p fifo ] || { echo "FAIL: the FIFO was replaced"; failures=$((failures + 1)); }
mkdir a-folder.h5
expect "reconstruct --out onto a folder" "is a folder, not a regular file" \
  "$ctk" reconstruct --scan s/scan.json --geometry s/truth-geometry.json --out a-folder.h5 --iterations 1
# An output folder that cannot take files is found before the solve, not after it.
mkdir locked && chmod 555 locked
if ! touch locked/probe 2>/dev/null; then  # root writes anywhere but on a read-only file system
  expect "reconstruct --out in a folder that takes no files" "cannot be written" \
    "$ctk" reconstruct --scan s/scan.json --geometry s/truth-geometry.json --out locked/v.nrrd --iterations 1
fi
expect "reconstruct --out on a read-only file system" "cannot be written" \
  "$ctk" reconstruct --scan s/scan.json --geometry s/truth-geometry.json --out /proc/v.nrrd --iterations 1
after=$(cat s/*.json s/*.csv s/*.tif s/projections/* | md5sum)
[ "$before" = "$after" ] || { echo "FAIL: an input changed"; failures=$((failures + 1)); }
ls ./*.nrrd ./*.raw s/*.nrrd s/*.raw g.json d.json both.json f.json 2>/dev/null | grep . && { echo "FAIL: an output was written"; failures=$((failures + 1)); }
echo "$failures failed"
[ "$failures" -eq 0 ]
