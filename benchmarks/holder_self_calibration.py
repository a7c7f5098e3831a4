#!/usr/bin/python3
"""Holder self-calibration against the truth: printed holders (every sphere off by a Gaussian of
sigma per axis), both built-in holders, several seeds.

Per case: scan A of the holder alone (random directions) is calibrated with the declared holder
and measured (`ctk holder measure`); the centres are compared with the truth in the frame the
declared centres define (the truth's offsets less their similarity part, which no scan can tell
from a move of the frame or a change of depth). Scan B (the same holder, another seed, a sample
inside) is then calibrated with the declared, the measured and the true holder, and scan B0
(B with a perfect holder) with the declared one: each calibration's median residual and its pose
error, as the RMS reprojection error of a grid of points in the holder against the true matrices.

  PYTHONPATH=build/python /usr/bin/python3 benchmarks/holder_self_calibration.py --ctk build/tools/ctk \
      --work /tmp/holder-bench
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from diagnosis_population import cpu_name, cpu_slug  # noqa: E402

# The detectors each holder is seen on: the reference holder's 2 mm spheres at 5 px, the thesis'
# first holder's 0.678 mm spheres at 3.6 px on a 720^2 detector.
SETUPS = {
    "reference": {"cols": 360, "rows": 360, "pitch": 0.6, "sample": "sample-1"},
    "thesis-first": {"cols": 720, "rows": 720, "pitch": 0.3, "sample": "sample-1"},
}


def run(args, log):
    with open(log, "a") as f:
        subprocess.run(args, check=True, stdout=f, stderr=subprocess.STDOUT)


def simulate(ctk, out, holder, setup, views, seed, sigma, holder_seed, sample=None):
    phantoms = ["--phantom", "helix-holder"] + (["--phantom", sample] if sample else [])
    jitter = ["--sphere-jitter-mm", str(sigma), "--holder-seed", str(holder_seed)] if sigma > 0 else []
    run([ctk, "simulate", "--out", str(out), "--holder", holder, *phantoms, "--trajectory", "random", "--views", str(views),
         "--cols", str(setup["cols"]), "--rows", str(setup["rows"]), "--pitch", str(setup["pitch"]), "--seed", str(seed),
         *jitter], out.parent / "log.txt")


def calibrate(ctk, scan, out):
    run([ctk, "calibrate", "--scan", str(scan), "--out", str(out)], out.parent / "log.txt")
    report = json.load(open(str(out).replace(".json", ".report.json")))
    return report["summary"]


def gauge_modes(X):
    """The 7 similarity modes of a centre list (3 translations, 3 turns, 1 scale), as columns."""
    n, Xc = len(X), X - X.mean(0)
    G = []
    for i in range(3):
        g = np.zeros((n, 3))
        g[:, i] = 1
        G.append(g.ravel())
    for i in range(3):
        w = np.zeros(3)
        w[i] = 1
        G.append(np.cross(w, Xc).ravel())
    G.append(Xc.ravel())
    return np.array(G).T


def true_offsets(scan_dir, declared):
    truth = json.load(open(scan_dir / "truth.json"))
    d = np.zeros_like(declared)
    for e in truth["effects"].get("sphere_positions", {}).get("spheres", []):
        d[e["index"]] = e["offset_mm"]
    return d


def matrices(file):
    g = json.load(open(file))
    return {v.get("view", i): np.array(v["P"]).reshape(3, 4) for i, v in enumerate(g["views"]) if v.get("P") is not None}


def grid_error_px(scan_dir, calibrated, declared, in_declared_frame):
    """RMS over views of the RMS reprojection difference of a grid spanning the holder."""
    truth = matrices(scan_dir / "truth-geometry.json")
    cal = matrices(calibrated)
    lo, hi = declared.min(0), declared.max(0)
    axes = [np.linspace(lo[i], hi[i], 3) for i in range(3)]
    grid = np.array([[x, y, z] for x in axes[0] for y in axes[1] for z in axes[2]])
    moved = grid
    if in_declared_frame:
        c = declared.mean(0)
        a = np.linalg.lstsq(gauge_modes(declared), true_offsets(scan_dir, declared).ravel(), rcond=None)[0]
        moved = grid + a[:3] + np.cross(a[3:6], grid - c) + a[6] * (grid - c)
    h = lambda p: np.vstack([p.T, np.ones(len(p))])
    errors = []
    for v, P in cal.items():
        if v in truth:
            A, B = truth[v] @ h(moved), P @ h(grid)
            errors.append(np.sqrt(((A[:2] / A[2] - B[:2] / B[2]) ** 2).sum(0).mean()))
    return float(np.sqrt(np.mean(np.square(errors))))


def holder_file_with(scan_dir, centres, out):
    scan = json.load(open(scan_dir / "scan.json"))
    holder = dict(scan["holder"], format="ctk-holder/1", name="the truth", spheres_mm=centres.tolist())
    json.dump(holder, open(out, "w"), indent=1)


def scan_declaring(scan_dir, holder_file, name):
    scan = json.load(open(scan_dir / "scan.json"))
    scan["holder"] = os.path.relpath(holder_file, scan_dir)
    out = scan_dir / name
    json.dump(scan, open(out, "w"), indent=1)
    return out


def one_case(ctk, work, holder, sigma, seed, views):
    setup = SETUPS[holder]
    case = work / f"{holder}-{sigma}-{seed}"
    case.mkdir(parents=True, exist_ok=True)
    (case / "log.txt").write_text("")
    started = time.monotonic()
    a, b, b0 = case / "a", case / "b", case / "b0"
    simulate(ctk, a, holder, setup, views, 100 + seed, sigma, seed)
    calibrate(ctk, a / "scan.json", case / "a-cal.json")
    t = time.monotonic()
    run([ctk, "holder", "measure", "--scan", str(a / "scan.json"), "--geometry", str(case / "a-cal.json"), "--out",
         str(case / "holder.json")], case / "log.txt")
    measure_seconds = time.monotonic() - t
    measured = json.load(open(case / "holder.json"))
    declared = np.array(json.load(open(a / "scan.json"))["holder"]["spheres_mm"])
    G = gauge_modes(declared)
    d_true = true_offsets(a, declared)
    d_gauge_free = (d_true.ravel() - G @ np.linalg.lstsq(G, d_true.ravel(), rcond=None)[0]).reshape(-1, 3)
    d_measured = np.array(measured["measurement"]["offsets_mm"])
    sigma_stated = np.array(measured["measurement"]["spheres_sigma_mm"])
    error = d_measured - d_gauge_free
    z = error / sigma_stated
    rms3 = lambda x: float(np.sqrt((x ** 2).sum(1).mean()))

    simulate(ctk, b, holder, setup, views, 200 + seed, sigma, seed, setup["sample"])
    simulate(ctk, b0, holder, setup, views, 200 + seed, 0, seed, setup["sample"])
    holder_file_with(b, declared + d_true, case / "true-holder.json")
    shutil.copy(case / "holder.json", b / "measured-holder.json")
    shutil.copy(case / "true-holder.json", b / "true-holder.json")
    calibrations = {}
    for name, scan, frame in (("declared", b / "scan.json", True),
                              ("measured", scan_declaring(b, b / "measured-holder.json", "scan-measured.json"), True),
                              ("true", scan_declaring(b, b / "true-holder.json", "scan-true.json"), False),
                              ("perfect_holder", b0 / "scan.json", False)):
        out = case / f"b-{name}.json"
        summary = calibrate(ctk, scan, out)
        calibrations[name] = {"views_ok": summary["ok"], "views": summary["views"],
                              "median_rms_px": summary["median_rms_px"],
                              "grid_error_rms_px": grid_error_px(scan.parent, out, declared, frame)}
    return {
        "holder": holder, "sigma_mm": sigma, "seed": seed, "views": views, **setup,
        "true_offset_rms_mm": rms3(d_true), "true_offset_rms_gauge_free_mm": rms3(d_gauge_free),
        "error_rms_mm": rms3(error), "error_fraction_of_offset": rms3(error) / rms3(d_gauge_free),
        "stated_sigma_rms_mm": rms3(sigma_stated), "normalised_error_rms": float(np.sqrt((z ** 2).mean())),
        "coverage_1.96": float((np.abs(z) < 1.96).mean()), "max_abs_z": float(np.abs(z).max()),
        "variance_factor": measured["measurement"]["variance_factor"],
        "halves_factor": measured["measurement"]["halves_factor"],
        "helix_rms_deviation_mm": measured["measurement"]["helix_fit"]["rms_deviation_mm"],
        "measure_seconds": measure_seconds, "case_seconds": time.monotonic() - started,
        "second_scan": calibrations,
    }


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--ctk", default="build/tools/ctk")
    p.add_argument("--work", default="/tmp/holder-bench")
    p.add_argument("--holders", nargs="+", default=list(SETUPS))
    p.add_argument("--sigmas", nargs="+", type=float, default=[0.05, 0.1])
    p.add_argument("--seeds", nargs="+", type=int, default=[1, 2, 3])
    p.add_argument("--views", type=int, default=90)
    p.add_argument("--json", help="results file (default: benchmarks/results/holder_self_calibration-<cpu>.json)")
    a = p.parse_args()
    ctk = str(Path(a.ctk).resolve())
    work = Path(a.work)
    cases = []
    for holder in a.holders:
        for sigma in a.sigmas:
            for seed in a.seeds:
                c = one_case(ctk, work, holder, sigma, seed, a.views)
                s = c["second_scan"]
                print(f"{holder:12s} sigma {sigma:.2f} seed {seed}: error {c['error_rms_mm']:.4f} mm "
                      f"({100 * c['error_fraction_of_offset']:.1f} % of {c['true_offset_rms_gauge_free_mm']:.3f}), "
                      f"z RMS {c['normalised_error_rms']:.2f}, within 1.96: {c['coverage_1.96']:.2f}; second scan grid "
                      f"error declared {s['declared']['grid_error_rms_px']:.4f}, measured {s['measured']['grid_error_rms_px']:.4f}, "
                      f"true {s['true']['grid_error_rms_px']:.4f}, perfect {s['perfect_holder']['grid_error_rms_px']:.4f} px; "
                      f"residual {s['declared']['median_rms_px']:.3f} / {s['measured']['median_rms_px']:.3f} / "
                      f"{s['true']['median_rms_px']:.3f} / {s['perfect_holder']['median_rms_px']:.3f} px "
                      f"({c['case_seconds']:.0f} s)", flush=True)
                cases.append(c)
    a.json = a.json or str(Path(__file__).resolve().parent / "results" / f"holder_self_calibration-{cpu_slug()}.json")
    if cases:
        result = {"benchmark": "holder_self_calibration", "cpu": cpu_name(), "command": " ".join(sys.argv), "cases": cases}
        tmp = a.json + ".tmp"
        with open(tmp, "w") as f:
            json.dump(result, f, indent=1)
        os.replace(tmp, a.json)


if __name__ == "__main__":
    main()
