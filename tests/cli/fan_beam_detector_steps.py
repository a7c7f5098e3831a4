#!/usr/bin/env python3
"""The markerless loop on three real FleX-ray fan-beam scans (one detector row) whose detector was
moved sideways by a commanded 0.25 mm = 3.342 px between them: each is imported as a user would and
refined for the detector offset; the loop must accept it with a finite uncertainty on every scan,
follow the commanded steps (3.342 +- 0.2 px, one direction) and agree with the conjugate-ray
estimate beside it within 0.3 px. The loop runs with the command's defaults: the `plus` scan lies
0.24 px from the nominal centre, near what a coarser yardstick can tell (--coarsening 4 does not
accept it).  Usage: fan_beam_detector_steps.py CTK DATA_DIR"""
import argparse
import json
import math
import pathlib
import shutil
import subprocess
import sys

from failures import report


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("ctk")
    parser.add_argument("data")
    a = parser.parse_args()
    work = pathlib.Path("fan-beam-detector-steps")
    shutil.rmtree(work, ignore_errors=True)
    failures = []
    u0 = {}
    for which in ("minus", "zero", "plus"):
        src = pathlib.Path(a.data) / which
        scan = work / which / "scan.json"
        subprocess.run([a.ctk, "import", "circular", "--out", str(scan), "--files", str(src / "scan_%06d.tif"), "--count", "3601",
                        "--flat", str(src / "io000000.tif"), str(src / "io000001.tif"), "--dark", str(src / "di000000.tif"),
                        "--detector", "1944", "1", "--pitch", "0.0748", "--sod", "423.562012", "--sdd", "527.99707", "--step", "0.1"],
                       check=True, stdout=subprocess.DEVNULL)
        report_file = work / which / "refine.json"
        subprocess.run([a.ctk, "refine", "--scan", str(scan), "--out", str(report_file), "--effects", "detector_offset"], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        r = json.loads(report_file.read_text())
        effect = next(e for e in r["effects"] if e["name"] == "detector_offset")
        cross = r["cross_check"]
        loop_u0, sigma = effect["parameters"]["u0_px"], effect["uncertainty"]["u0_px"]
        print(f"{which}: accepted {effect['accepted']}, u0 {loop_u0:.3f} +- {sigma:.3f} px; conjugate rays {cross['u0_px']:.3f} "
              f"+- {cross['uncertainty_px']:.3f} (difference {cross['difference_px']:+.3f}); not observable: "
              f"{[n['parameter'] for n in r['not_observable']]}")
        if not effect["accepted"]:
            failures.append(f"{which}: detector_offset not accepted ({effect.get('note', '')})")
        if not (isinstance(sigma, (int, float)) and math.isfinite(sigma) and sigma < 0.2):
            failures.append(f"{which}: uncertainty {sigma}")
        if abs(cross["difference_px"]) > 0.3:
            failures.append(f"{which}: the loop and conjugate rays differ by {cross['difference_px']:.3f} px")
        if "v0_px" not in [n["parameter"] for n in r["not_observable"]] or "v0_px" in effect["parameters"]:
            failures.append(f"{which}: v0 is fitted on a one-row detector")
        u0[which] = loop_u0
    steps = (u0["zero"] - u0["minus"], u0["plus"] - u0["zero"])
    print(f"steps {steps[0]:+.3f} and {steps[1]:+.3f} px (commanded 3.342)")
    for s in steps:
        if abs(abs(s) - 3.342) > 0.2:
            failures.append(f"step {s:+.3f} px is not 3.342 +- 0.2")
    if steps[0] * steps[1] <= 0:
        failures.append("the steps do not go the same way")
    return report(failures)


if __name__ == "__main__":
    sys.exit(main())
