"""Calibration looking along the holder's axis, with the holder's wall declared in several ways.

Two trajectories, each a spinning cap of directions (720 x 720 px at 0.6 mm, ctk simulate's
reference setup, robot noise 0.2 mm / 0.1 deg, the base 2.6 mm and 1.2 deg off, seeds 1..N):
- `cap_0_12`: 60 views 0-12 deg from the axis. No view sees the holder from the side, so nothing
  of the wall can be measured: the wall with its true ends, its ends 9 mm too short or too long at
  each side, declared as an infinitely long tube (no ends), and not declared (no shadow modelled).
- `cap_0_90`: 240 views 0-90 deg from the axis, the wall with its ends, declared without its ends
  (they are measured in the side views) and not declared (radii and ends measured).
For each: views with >= 10 spheres on the detector kept, the median difference from the true
matrices over all of them and over those within 10 deg of the axis, the views lost with the angle
between the true beam and the holder axis and the reason, and the wall's ends when measured.

    python3 benchmarks/near_axis_calibration.py --ctk build/tools/ctk [--seeds 3]
"""
import argparse
import json
import math
import pathlib
import subprocess
import tempfile

from diagnosis_population import calibration_figures, cpu_name, cpu_slug, project

COMMON = ["--phantom", "helix-holder", "--cols", "720", "--rows", "720", "--pitch", "0.6", "--trajectory", "cap",
          "--robot-noise-mm", "0.2", "--robot-noise-deg", "0.1", "--base-translation-mm", "1.5", "-2.0", "0.8",
          "--base-rotation-deg", "0.5", "-0.3", "1.0"]
SCANS = {"cap_0_12": ["--views", "60", "--cap-deg", "0", "12"], "cap_0_90": ["--views", "240", "--cap-deg", "0", "90"]}


def ends_moved(mm):
    return lambda w: dict(w, ends_mm=[w["ends_mm"][0] - mm, w["ends_mm"][1] + mm])


# The wall as declared, its ends 9 mm too close together or too far apart, no ends, no wall.
WALLS = {"ends": lambda w: w, "ends_9mm_short": ends_moved(-9), "ends_9mm_long": ends_moved(9),
         "infinite": lambda w: {k: v for k, v in w.items() if k != "ends_mm"}, "none": lambda w: None}
WALLS_OF = {"cap_0_12": list(WALLS), "cap_0_90": ["ends", "infinite", "none"]}
NEAR_DEG = 10


def axis_angle_deg(P):
    """Angle between the principal ray (the matrix's depth row) and the holder axis."""
    row = P[8:11]
    return math.degrees(math.acos(min(1.0, abs(row[2]) / math.sqrt(sum(x * x for x in row)))))


def near_axis_figures(folder, geometry_name, cols):
    """Views within NEAR_DEG of the axis with >= 10 spheres on the detector: how many, how many
    calibrated, and the median RMS difference of those from the true matrices."""
    spheres = json.loads((folder / "truth.json").read_text())["holder_spheres_mm"]
    truth = {v["index"]: v["P"] for v in json.loads((folder / "truth-geometry.json").read_text())["views"] if v.get("P")}
    fitted = {v["index"]: v for v in json.loads((folder / geometry_name).read_text())["views"]}
    eligible, differences = 0, []
    for index, P in truth.items():
        on_detector = [X for X in spheres if all(0 <= c <= cols - 1 for c in project(P, X))]
        if axis_angle_deg(P) >= NEAR_DEG or len(on_detector) < 10:
            continue
        eligible += 1
        fv = fitted.get(index)
        if fv and fv["status"] == "ok":
            sq = [sum((a - b) ** 2 for a, b in zip(project(fv["P"], X), project(P, X))) for X in on_detector]
            differences.append(math.sqrt(sum(sq) / len(sq)))
    differences.sort()
    return {"eligible": eligible, "calibrated": len(differences),
            "median_difference_px": differences[len(differences) // 2] if differences else None}


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--ctk", required=True)
    p.add_argument("--seeds", type=int, default=3)
    p.add_argument("--out", help="JSON to write (default: benchmarks/results/near_axis_calibration-<cpu>.json)")
    a = p.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for scan_name, scan_args in SCANS.items():
            for seed in range(1, a.seeds + 1):
                folder = pathlib.Path(work) / f"{scan_name}-seed-{seed}"
                subprocess.run([a.ctk, "simulate", "--out", str(folder), "--seed", str(seed)] + COMMON + scan_args, check=True,
                               capture_output=True)
                scan = json.loads((folder / "scan.json").read_text())
                truth = {v["index"]: v["P"] for v in json.loads((folder / "truth-geometry.json").read_text())["views"] if v.get("P")}
                for name in WALLS_OF[scan_name]:
                    variant = json.loads(json.dumps(scan))
                    wall = WALLS[name](scan["holder"]["wall"])
                    if wall is None:
                        variant["holder"].pop("wall")
                    else:
                        variant["holder"]["wall"] = wall
                    (folder / f"scan-{name}.json").write_text(json.dumps(variant))
                    subprocess.run([a.ctk, "calibrate", "--scan", str(folder / f"scan-{name}.json"), "--out",
                                    str(folder / f"g-{name}.json")], check=True, capture_output=True)
                    f = calibration_figures(folder, f"g-{name}.json", 720)
                    near = near_axis_figures(folder, f"g-{name}.json", 720)
                    report = json.loads((folder / f"g-{name}.report.json").read_text())
                    measured = (report.get("holder_wall") or {}).get("measured") or {}
                    lost = [{"view": x["view"], "axis_deg": round(axis_angle_deg(truth[x["view"]]), 2), "reason": x["reason"]}
                            for x in f["lost"]]
                    rows.append({"scan": scan_name, "seed": seed, "wall": name, "eligible": f["eligible"],
                                 "calibrated": f["calibrated"], "median_difference_px": f["median_difference_px"],
                                 "near_axis": near, "measured_ends": measured.get("ends"),
                                 "views_per_second": report["summary"]["views_per_second"], "lost": lost})
                    print(f"{scan_name} seed {seed} wall {name:14s}: {f['calibrated']} of {f['eligible']} calibrated, median "
                          f"{f['median_difference_px']:.4f} px from the truth; within {NEAR_DEG} deg of the axis "
                          f"{near['calibrated']} of {near['eligible']}, median {near['median_difference_px'] or 0:.4f} px; "
                          f"ends measured {(measured.get('ends') or {}).get('ends_mm')}; lost at "
                          + ", ".join(f"{x['axis_deg']:.1f}" for x in lost) + " deg", flush=True)
    summary = {}
    for scan_name in SCANS:
        summary[scan_name] = {}
        for name in WALLS_OF[scan_name]:
            mine = [r for r in rows if r["wall"] == name and r["scan"] == scan_name]
            summary[scan_name][name] = {
                "eligible": sum(r["eligible"] for r in mine), "calibrated": sum(r["calibrated"] for r in mine),
                "median_difference_px": sorted(r["median_difference_px"] for r in mine),
                "near_axis_eligible": sum(r["near_axis"]["eligible"] for r in mine),
                "near_axis_calibrated": sum(r["near_axis"]["calibrated"] for r in mine),
                "near_axis_median_difference_px": sorted(r["near_axis"]["median_difference_px"] for r in mine
                                                         if r["near_axis"]["median_difference_px"] is not None),
                "views_per_second": sorted(r["views_per_second"] for r in mine)}
            print(scan_name, name, summary[scan_name][name])
    cpu = cpu_name()
    out = pathlib.Path(a.out) if a.out else pathlib.Path(__file__).parent / "results" / (
        "near_axis_calibration-" + cpu_slug() + ".json")
    out.write_text(json.dumps({"benchmark": "calibration near the holder axis, the wall with its ends, without them, or none",
                               "cpu": cpu, "scans": {k: COMMON + v for k, v in SCANS.items()}, "summary": summary,
                               "rows": rows}, indent=1))
    print("wrote", out)


if __name__ == "__main__":
    main()
