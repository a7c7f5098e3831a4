#!/bin/sh
# Every refusal names its option or file and exits 2 before any work, with no internal text
# (std::, _M_range_check, "filesystem error"); values pasted by mistake are not echoed in full;
# a legal name of 250 bytes is written. Usage: refusals_are_clear.sh CTK
set -u
ctk=$1
. "$(dirname "$0")/expect.sh"
dir=refusals-are-clear
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir" || exit 1
"$ctk" simulate --out s --views 4 --cols 48 --rows 48 --pitch 9 --phantom helix-holder >/dev/null 2>&1 || { echo "simulate failed"; exit 1; }
import="import circular --out i/scan.json --files s/projections/proj_%04d.tif --count 4 --flat s/flat.tif --dark s/dark.tif"

expect "geometry --out empty" "--out: expected a value, got an empty string" "$ctk" geometry --scan s/scan.json --out ""
expect "simulate --out empty" "--out: expected a value, got an empty string" "$ctk" simulate --views 2 --out ""
long=$(printf 'a%.0s' $(seq 1 251))
expect "an output name of 256 bytes" "a name of 256 bytes; file systems take at most 255" \
  "$ctk" geometry --scan s/scan.json --out "$long.json"
huge=$(printf '9%.0s' $(seq 1 400))
expect "a 400-digit value, clipped" "(400 characters)" "$ctk" simulate --out never --views "$huge"
: > empty.vec
expect "an empty cone_vec file" "empty.vec: no rows of 12 numbers" \
  "$ctk" import cone-vec --vectors empty.vec --out i/scan.json --files 's/projections/*.tif' --flat s/flat.tif --dark s/dark.tif --pitch 9
# shellcheck disable=SC2086
expect "a pitch in the wrong unit" "--pitch, --sod, --sdd, --principal-point, --step: circular orbit: a focal length of" \
  "$ctk" $import --pitch 100 --sod 0.001 --sdd 0.002 --step 90
# shellcheck disable=SC2086
expect "a step whose angles overflow" "view 1's angle is not finite" "$ctk" $import --pitch 9 --sod 1360 --sdd 2150 --step 1e308

# No huge value came back whole.
"$ctk" simulate --out never --views "$huge" 2>&1 | awk 'length > 300 { bad = 1 } END { exit bad }' ||
  { echo "FAIL: a line over 300 characters"; failures=$((failures + 1)); }
[ -e i ] && { echo "FAIL: a refused import wrote i/"; failures=$((failures + 1)); }

# A legal name of 250 bytes is written, and no temporary is left beside it.
name=$(printf 'b%.0s' $(seq 1 245)).json
if "$ctk" geometry --scan s/scan.json --out "$name" >/dev/null 2>&1 && [ -s "$name" ]; then
  echo "ok   a name of 250 bytes written"
else
  echo "FAIL: a name of 250 bytes was not written"; failures=$((failures + 1))
fi
ls -A | grep '^\.' && { echo "FAIL: temporaries left"; failures=$((failures + 1)); }
echo "$failures failed"
[ "$failures" -eq 0 ]
