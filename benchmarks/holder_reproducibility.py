#!/usr/bin/python3
"""How reproducible a holder measurement is: the same scan measured from matrices that differ by
rounding alone.

A printed reference holder (0.1 mm per axis) is simulated as tests/python/test_workflows.py does
(40 random views of 360^2), calibrated, and measured (`ctk holder measure`) from the calibrated
matrices and from copies whose every entry is scaled by 1 + e N(0, 1) (e = 1e-13 by default, far
below any physical meaning). Each copy's centres are compared with the unperturbed ones in units of
the centres' stated uncertainty: their RMS and largest difference, and which effects each run
fitted beside the centres. Python's measurement of the unperturbed matrices is compared alike.

  PYTHONPATH=build/python /usr/bin/python3 benchmarks/holder_reproducibility.py --ctk build/tools/ctk \
      --work /tmp/holder-repro
"""

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

import ctk

sys.path.insert(0, str(Path(__file__).resolve().parent))
from diagnosis_population import cpu_name, cpu_slug  # noqa: E402


def measure(ctk_command, scan, geometry, out):
    subprocess.run([ctk_command, "holder", "measure", "--scan", str(scan), "--geometry", str(geometry), "--min-views", "40",
                    "--out", str(out)], check=True, capture_output=True)
    return json.loads(Path(out).read_text())


def compare(reference, other):
    sigma = np.array(reference["measurement"]["spheres_sigma_mm"])
    d = (np.array(reference["spheres_mm"]) - np.array(other["spheres_mm"])) / sigma
    return {"rms_sigma": float(np.sqrt(np.mean(d ** 2))), "max_sigma": float(np.abs(d).max()),
            "fitted_with": other["measurement"]["fitted_with"]}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ctk", required=True)
    parser.add_argument("--work", required=True, type=Path)
    parser.add_argument("--copies", type=int, default=3)
    parser.add_argument("--relative", type=float, default=1e-13)
    parser.add_argument("--out", type=Path, default=None)
    a = parser.parse_args()
    a.work.mkdir(parents=True, exist_ok=True)
    s = ctk.simulate(a.work / "printed", holder="reference", trajectory="random", views=40, detector_shape=(360, 360), seed=5,
                     effects={"sphere_jitter_mm": 0.1, "holder_seed": 4})
    ctk.write_geometry(ctk.calibrate(s.scan_file).geometry, a.work / "g.json")
    reference = measure(a.ctk, s.scan_file, a.work / "g.json", a.work / "h.json")
    rows = {"python": compare(reference, ctk.measure_holder(s.scan_file, a.work / "g.json", min_views=40))}
    for copy in range(1, a.copies + 1):
        g = json.loads((a.work / "g.json").read_text())
        rng = np.random.default_rng(copy)
        for view in g["views"]:
            if view.get("P"):
                view["P"] = [p * (1 + a.relative * rng.standard_normal()) for p in view["P"]]
        (a.work / f"g{copy}.json").write_text(json.dumps(g))
        rows[f"copy {copy}"] = compare(reference, measure(a.ctk, s.scan_file, a.work / f"g{copy}.json", a.work / f"h{copy}.json"))
    result = {"cpu": cpu_name(), "relative_change": a.relative, "fitted_with": reference["measurement"]["fitted_with"],
              "stated_sigma_mm_median": float(np.median(reference["measurement"]["spheres_sigma_mm"])), "runs": rows,
              "command": " ".join(sys.argv)}
    for name, row in rows.items():
        print(f"{name:8s} RMS {row['rms_sigma']:.3f} sigma, largest {row['max_sigma']:.3f} sigma, fitted with "
              f"{', '.join(row['fitted_with'])}")
    out = a.out or Path(__file__).resolve().parent / "results" / f"holder_reproducibility-{cpu_slug()}.json"
    out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"written {out}")


if __name__ == "__main__":
    main()
