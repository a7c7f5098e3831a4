#!/bin/sh
# `ctk bench --simd SSE4` runs the projector's SSE4 kernels (4 float lanes) and agrees with the
# reference; a target this machine has not (NEON) is refused, naming the ones it has.
# Usage: bench_on_a_chosen_simd_target.sh CTK
set -eu
ctk=$1
"$ctk" bench --simd SSE4 --scale 16 --views 8 --reference-views 2 --json > bench-sse4.json
python3 - <<'PY'
import json
r = json.load(open("bench-sse4.json"))
assert r["simd"]["target"] == "SSE4" and r["simd"]["float_lanes"] == 4, r["simd"]
assert max(r[d]["relative_difference_to_reference"] for d in ("forward", "back")) < 1e-5
print("target", r["simd"]["target"], "of", ",".join(r["simd"]["available"]))
PY
if "$ctk" bench --simd NEON; then
  echo "FAIL: a SIMD target this machine has not was accepted"
  exit 1
fi
