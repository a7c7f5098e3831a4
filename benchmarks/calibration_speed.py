"""Calibration speed by trajectory family, a build against a reference build run alternately on
the same simulated scans (so the ratio holds on any machine), with what each calibrated: views
with >= 10 spheres on the detector kept, and the median difference from the true matrices.

Scans (720 x 720, counts as deflate TIFFs, robot noise 0.2 mm / 0.1 deg, base 2.6 mm off): a
spinning cap 5-90 deg from the holder axis (120 views), a HEALPix sphere (108), random
directions with a sample inside the holder (120), a joint-7 orbit (120); each with the holder's
wall declared and not declared (then it is measured).

    python3 benchmarks/calibration_speed.py --ctk build/tools/ctk --reference old/ctk --repeat 3
"""
import argparse
import json
import pathlib
import re
import statistics
import subprocess
import tempfile

from diagnosis_population import calibration_figures, cpu_name, cpu_slug

SCANS = {
    "cap": ["--trajectory", "cap", "--views", "120", "--cap-deg", "5", "90"],
    "sphere": ["--trajectory", "spherical", "--nside", "3"],
    "random_with_sample": ["--trajectory", "random", "--views", "120", "--phantom", "helix-holder", "--phantom", "sample-1"],
    "orbit": ["--trajectory", "circular", "--views", "120"],
}
COMMON = ["--robot-noise-mm", "0.2", "--robot-noise-deg", "0.1", "--base-translation-mm", "2", "1.5", "0.5", "--seed", "5"]


def calibrate(ctk, scan, out):
    text = subprocess.run([ctk, "calibrate", "--scan", str(scan), "--out", str(out)], check=True, capture_output=True, text=True).stdout
    return float(re.search(r"\(([0-9.]+) views/s\)", text).group(1))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--ctk", required=True)
    p.add_argument("--reference", help="another build, run alternately with --ctk")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--out", help="JSON to write (default: benchmarks/results/calibration_speed-<cpu>.json)")
    a = p.parse_args()
    builds = {"ctk": a.ctk} | ({"reference": a.reference} if a.reference else {})
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for name, options in SCANS.items():
            folder = pathlib.Path(work) / name
            subprocess.run([a.ctk, "simulate", "--out", str(folder)] + options + COMMON, check=True, capture_output=True)
            scan = json.loads((folder / "scan.json").read_text())
            scan["holder"].pop("wall", None)
            (folder / "scan-no-wall.json").write_text(json.dumps(scan))
            for wall, scan_file in (("declared", "scan.json"), ("measured", "scan-no-wall.json")):
                speeds = {b: [] for b in builds}
                for _ in range(a.repeat):
                    for b, exe in builds.items():
                        speeds[b].append(calibrate(exe, folder / scan_file, folder / f"{b}-{wall}.json"))
                row = {"scan": name, "wall": wall, "cols": 720}
                for b in builds:
                    figures = calibration_figures(folder, f"{b}-{wall}.json", 720)
                    row[b] = {"views_per_s": statistics.median(speeds[b]), "runs": speeds[b], "eligible": figures["eligible"],
                              "calibrated": figures["calibrated"], "median_difference_px": figures["median_difference_px"]}
                if a.reference:
                    row["ratio"] = row["ctk"]["views_per_s"] / row["reference"]["views_per_s"]
                rows.append(row)
                print(f"{name:20s} wall {wall:8s} " + "; ".join(
                    f"{b} {row[b]['views_per_s']:.0f} views/s, {row[b]['calibrated']}/{row[b]['eligible']} views, "
                    f"{row[b]['median_difference_px']:.4f} px" for b in builds) + (f"; ratio {row['ratio']:.2f}" if a.reference else ""),
                      flush=True)
    cpu = cpu_name()
    out = pathlib.Path(a.out) if a.out else pathlib.Path(__file__).parent / "results" / (
        "calibration_speed-" + cpu_slug() + ".json")
    out.write_text(json.dumps({"benchmark": "ctk calibrate, views/s as it reports them, 2 builds alternately", "cpu": cpu,
                               "repeat": a.repeat, "rows": rows}, indent=1) + "\n")
    print(f"written {out}")


if __name__ == "__main__":
    main()
