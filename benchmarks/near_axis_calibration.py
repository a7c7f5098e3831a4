"""Calibration looking along the holder's axis: spinning caps from 0 to 12 deg of the axis, each
calibrated five ways, with the holder's wall declared with its true ends, with ends 9 mm too
short or too long at each side, declared as an infinitely long tube (the ends removed), and not
declared (none of the views sees the holder from the side, so the wall cannot be measured and no
shadow is modelled). For each: views with >= 10 spheres on
the detector kept, the median difference from the true matrices, and the views lost with the
angle between the true beam and the holder axis and the reason.

Scans: 720 x 720 px at 0.6 mm (ctk simulate's reference setup), 60 views, robot noise 0.2 mm /
0.1 deg, the base 2.6 mm and 1.2 deg off, seeds 1..N.

    python3 benchmarks/near_axis_calibration.py --ctk build/tools/ctk [--seeds 3]
"""
import argparse
import json
import math
import pathlib
import subprocess
import tempfile

from diagnosis_population import calibration_figures, cpu_name

SCAN = ["--phantom", "helix-holder", "--cols", "720", "--rows", "720", "--pitch", "0.6", "--trajectory", "cap", "--views", "60",
        "--cap-deg", "0", "12", "--robot-noise-mm", "0.2", "--robot-noise-deg", "0.1", "--base-translation-mm", "1.5", "-2.0", "0.8",
        "--base-rotation-deg", "0.5", "-0.3", "1.0"]
def ends_moved(mm):
    return lambda w: dict(w, ends_mm=[w["ends_mm"][0] - mm, w["ends_mm"][1] + mm])


# The wall as declared, its ends 9 mm too close together or too far apart, no ends, no wall.
WALLS = {"ends": lambda w: w, "ends_9mm_short": ends_moved(-9), "ends_9mm_long": ends_moved(9),
         "infinite": lambda w: {k: v for k, v in w.items() if k != "ends_mm"}, "none": lambda w: None}


def axis_angle_deg(P):
    """Angle between the principal ray (the matrix's depth row) and the holder axis."""
    row = P[8:11]
    return math.degrees(math.acos(min(1.0, abs(row[2]) / math.sqrt(sum(x * x for x in row)))))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--ctk", required=True)
    p.add_argument("--seeds", type=int, default=3)
    p.add_argument("--out", help="JSON to write (default: benchmarks/results/near_axis_calibration-<cpu>.json)")
    a = p.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for seed in range(1, a.seeds + 1):
            folder = pathlib.Path(work) / f"seed-{seed}"
            subprocess.run([a.ctk, "simulate", "--out", str(folder), "--seed", str(seed)] + SCAN, check=True, capture_output=True)
            scan = json.loads((folder / "scan.json").read_text())
            truth = {v["index"]: v["P"] for v in json.loads((folder / "truth-geometry.json").read_text())["views"] if v.get("P")}
            for name, wall_of in WALLS.items():
                variant = json.loads(json.dumps(scan))
                wall = wall_of(scan["holder"]["wall"])
                if wall is None:
                    variant["holder"].pop("wall")
                else:
                    variant["holder"]["wall"] = wall
                (folder / f"scan-{name}.json").write_text(json.dumps(variant))
                subprocess.run([a.ctk, "calibrate", "--scan", str(folder / f"scan-{name}.json"), "--out", str(folder / f"g-{name}.json")],
                               check=True, capture_output=True)
                f = calibration_figures(folder, f"g-{name}.json", 720)
                lost = [{"view": x["view"], "axis_deg": round(axis_angle_deg(truth[x["view"]]), 2), "reason": x["reason"]} for x in f["lost"]]
                rows.append({"seed": seed, "wall": name, "eligible": f["eligible"], "calibrated": f["calibrated"],
                             "median_difference_px": f["median_difference_px"], "lost": lost})
                print(f"seed {seed} wall {name:14s}: {f['calibrated']} of {f['eligible']} calibrated, median "
                      f"{f['median_difference_px']:.4f} px from the truth; lost at "
                      + ", ".join(f"{x['axis_deg']:.1f}" for x in lost) + " deg", flush=True)
    summary = {}
    for name in WALLS:
        mine = [r for r in rows if r["wall"] == name]
        summary[name] = {"eligible": sum(r["eligible"] for r in mine), "calibrated": sum(r["calibrated"] for r in mine),
                         "median_difference_px": sorted(r["median_difference_px"] for r in mine),
                         "lost_above_5_deg": sum(1 for r in mine for x in r["lost"] if x["axis_deg"] >= 5)}
        print(name, summary[name])
    cpu = cpu_name()
    out = pathlib.Path(a.out) if a.out else pathlib.Path(__file__).parent / "results" / (
        "near_axis_calibration-" + "".join(ch if ch.isalnum() else "-" for ch in cpu.lower()).strip("-") + ".json")
    out.write_text(json.dumps({"benchmark": "calibration 0-12 deg from the holder axis, the wall with its ends, infinite, or none",
                               "cpu": cpu, "scan": SCAN, "summary": summary, "rows": rows}, indent=1))
    print("wrote", out)


if __name__ == "__main__":
    main()
