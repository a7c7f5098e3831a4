"""The thesis' scan end to end, as a user runs it: a scan made once at the thesis' size (900
views of 720 x 720 16-bit TIFFs, random directions over the sphere from the robot's joint log,
the reference holder with the thesis' sample 1 inside, two of its spheres 0.3 mm off their
declared places without saying so), then `ctk calibrate`, `ctk diagnose` and `ctk reconstruct` with their defaults
(the volume covering the holder at a detector pixel seen at the holder's centre). Each stage's
wall time, CPU time, peak resident memory and bytes read and written come from /usr/bin/time;
the results are scored against the simulation's truth: the calibrated matrices' difference from
the true ones over the holder's spheres, the effect the diagnosis names, and the volume's RMSE
against the phantoms voxelised on its grid (and, for scale, the RMSE of the volume reconstructed
from the true matrices).

    /usr/bin/python3 benchmarks/thesis_pipeline.py --ctk build/tools/ctk --work /tmp/thesis \
        [--views 900] [--pixels 720] [--reconstruct-args "..."] [--references] [--keep-scan] [--out F.json]

--pixels scales the detector (the same field of view: the pitch grows as the pixels shrink), so a
smaller run checks the script; the JSON records what was run. PYTHONPATH must reach the ctk module
(build/python) for the voxelised truth.
"""
import argparse
import json
import math
import os
import pathlib
import re
import shlex
import subprocess
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from diagnosis_population import calibration_figures, cpu_name, cpu_slug  # noqa: E402

EFFECT = ["--displaced-spheres", "2", "--displacement-mm", "0.3"]  # undeclared: only truth.json knows it
SAMPLE = ["--phantom", "helix-holder", "--phantom", "sample-1"]


def timed(command, log):
    """Runs `command` under /usr/bin/time; its figures and its output (to `log`)."""
    figures = log.with_suffix(".time")
    start = time.monotonic()
    with open(log, "w") as out:
        r = subprocess.run(["/usr/bin/time", "-o", str(figures), "-f", "%e %U %S %M %I %O"] + [str(c) for c in command],
                           stdout=out, stderr=subprocess.STDOUT)
    wall = time.monotonic() - start
    if r.returncode:
        raise SystemExit(f"{' '.join(map(str, command))} failed (exit {r.returncode}); see {log}")
    e, user, system, rss_kb, blocks_in, blocks_out = figures.read_text().split()[-6:]
    return {"command": " ".join(shlex.quote(str(c)) for c in command), "wall_s": round(wall, 2),
            "cpu_s": round(float(user) + float(system), 2), "peak_resident_gb": round(int(rss_kb) / 1e6, 3),
            "read_gb": round(int(blocks_in) * 512 / 1e9, 3), "written_gb": round(int(blocks_out) * 512 / 1e9, 3)}


_truths = {}  # voxelised once per grid


def rmse_against_truth(volume_file, phantoms):
    import numpy as np
    import ctk
    volume, layout = ctk.read_volume(volume_file)
    grid = (tuple(phantoms), volume.shape, tuple(layout["voxel_mm"]), tuple(layout["origin_mm"]))
    if grid not in _truths:
        _truths[grid] = ctk.voxelise(phantoms, volume.shape, layout["voxel_mm"], layout["origin_mm"])
    truth = _truths[grid]
    return float(np.sqrt(np.mean((volume.astype(np.float64) - truth) ** 2))), float(np.abs(truth).max())


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--ctk", required=True)
    p.add_argument("--work", required=True, help="folder for the scan and the results (about 1 GB at full size)")
    p.add_argument("--views", type=int, default=900)
    p.add_argument("--pixels", type=int, default=720)
    p.add_argument("--reconstruct-args", default="", help="added to ctk reconstruct (default: none, its defaults)")
    p.add_argument("--keep-scan", action="store_true", help="reuse a scan already simulated in --work")
    p.add_argument("--references", nargs="?", const="all", choices=["all", "os-sqs"],
                   help="also reconstruct (from the calibrated matrices, every view) by 30 WLS-CG iterations (all) and by "
                        "OS-SQS for 1 to 3 epochs past where the default stopped, for the quality the default is held to")
    p.add_argument("--out", help="JSON to write (default: benchmarks/results/thesis_pipeline-<cpu>.json)")
    a = p.parse_args()
    ctk_command = os.path.abspath(a.ctk)
    work = pathlib.Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    scan = work / "scan"
    pitch = 0.6 * 720 / a.pixels
    stages = {}
    if not (a.keep_scan and (scan / "scan.json").exists()):
        stages["simulate"] = timed([ctk_command, "simulate", "--out", scan, "--trajectory", "random", "--views", a.views,
                                    "--cols", a.pixels, "--rows", a.pixels, "--pitch", pitch, "--seed", 7] + SAMPLE + EFFECT,
                                   work / "simulate.log")
    stages["calibrate"] = timed([ctk_command, "calibrate", "--scan", scan / "scan.json", "--out", work / "calibrated.json"],
                                work / "calibrate.log")
    stages["diagnose"] = timed([ctk_command, "diagnose", "--scan", scan / "scan.json", "--geometry", work / "calibrated.json",
                                "--out", work / "diagnosis.json"], work / "diagnose.log")
    extra = shlex.split(a.reconstruct_args)
    stages["reconstruct"] = timed([ctk_command, "reconstruct", "--scan", scan / "scan.json", "--geometry",
                                   work / "calibrated.json", "--out", work / "volume.nrrd"] + extra, work / "reconstruct.log")
    # For scale, not part of the pipeline: the same reconstruction from the true matrices.
    timed([ctk_command, "reconstruct", "--scan", scan / "scan.json", "--geometry", scan / "truth-geometry.json", "--out",
           work / "volume-true-geometry.nrrd"] + extra, work / "reconstruct-true-geometry.log")

    references = {}
    if a.references:
        def reference(name, options):
            out = work / f"reference-{name}.nrrd"
            f = timed([ctk_command, "reconstruct", "--scan", scan / "scan.json", "--geometry", work / "calibrated.json", "--out",
                       out] + options, work / f"reference-{name}.log")
            references[name] = {"wall_s": f["wall_s"], "rmse_per_mm": rmse_against_truth(out, ["helix-holder", "sample-1"])[0]}
        if a.references == "all":
            reference("wls-cg-30", ["--method", "wls-cg", "--iterations", "30"])
        stopped = json.loads((work / "volume.log.json").read_text())["held_out"]["iterations"][-1]
        for epochs in range(1, stopped + 4):
            reference(f"os-sqs-{epochs}", ["--method", "os-sqs", "--iterations", str(epochs)])

    calibration = calibration_figures(scan, "../calibrated.json", a.pixels)
    diagnosis = json.loads((work / "diagnosis.json").read_text())
    accepted = [e["name"] for e in diagnosis.get("effects", []) if e.get("accepted")]
    # The displaced spheres as found, against the truth's offsets (mm).
    truth_effects = json.loads((scan / "truth.json").read_text())["effects"]
    found = {s["index"]: s["offset_mm"] for e in diagnosis.get("effects", []) if e.get("accepted")
             and e["name"] == "sphere_positions" for s in e["parameters"]["spheres"]}
    spheres = [{"index": t["index"], "true_offset_mm": t["offset_mm"], "found_offset_mm": found.get(t["index"]),
                "error_mm": math.dist(t["offset_mm"], found[t["index"]]) if t["index"] in found else None}
               for t in truth_effects.get("sphere_positions", {}).get("spheres", [])]
    log = json.loads((work / "volume.log.json").read_text())
    phantoms = ["helix-holder", "sample-1"]
    rmse, peak = rmse_against_truth(work / "volume.nrrd", phantoms)
    rmse_true, _ = rmse_against_truth(work / "volume-true-geometry.nrrd", phantoms)
    pipeline = ("calibrate", "diagnose", "reconstruct")
    result = {
        "cpu": cpu_name(), "cores": os.cpu_count(),
        "scan": {"views": a.views, "pixels": [a.pixels, a.pixels], "pitch_mm": pitch, "trajectory": "random directions",
                 "phantoms": phantoms, "undeclared_effect": " ".join(EFFECT),
                 "projection_gb": round(sum(f.stat().st_size for f in (scan / "projections").iterdir()) / 1e9, 3)},
        "stages": stages,
        "pipeline_wall_s": round(sum(stages[s]["wall_s"] for s in pipeline), 1),
        "pipeline_peak_resident_gb": max(stages[s]["peak_resident_gb"] for s in pipeline),
        "calibration": calibration,
        "diagnosis": {"accepted": accepted, "true_effects": sorted(truth_effects), "spheres": spheres,
                      "spheres_named": sorted(found)},
        "reconstruction": {"method": log["method"], "volume": log["volume"], "stop_reason": log["solver"]["stop_reason"],
                           "memory_plan": log["memory_plan"], "rmse_per_mm": rmse, "truth_peak_per_mm": peak,
                           "rmse_from_true_matrices_per_mm": rmse_true},
        "references": references,
    }
    if references:
        best = min(r["rmse_per_mm"] for k, r in references.items() if k.startswith("os-sqs"))
        result["reconstruction"]["rmse_over_best_os_sqs_epoch"] = rmse / best
        if "wls-cg-30" in references:
            result["reconstruction"]["rmse_over_30_wls_cg_iterations"] = rmse / references["wls-cg-30"]["rmse_per_mm"]
    out = pathlib.Path(a.out) if a.out else pathlib.Path(__file__).parent / "results" / f"thesis_pipeline-{cpu_slug()}.json"
    out.write_text(json.dumps(result, indent=1) + "\n")
    for s in pipeline:
        f = stages[s]
        print(f"{s}: {f['wall_s']} s wall, {f['cpu_s']} s CPU, peak {f['peak_resident_gb']} GB, read {f['read_gb']} GB, "
              f"wrote {f['written_gb']} GB")
    print(f"calibrate + diagnose + reconstruct: {result['pipeline_wall_s']} s; calibrated {calibration['calibrated']} of "
          f"{calibration['eligible']} views, median {calibration['median_difference_px']} px from the truth; diagnosis "
          f"accepted {accepted} (truth: {sorted(truth_effects)}; spheres named {sorted(found)}, errors "
          f"{[None if x['error_mm'] is None else round(x['error_mm'], 3) for x in spheres]} mm); volume RMSE {rmse:.3g} /mm (from the true matrices {rmse_true:.3g}, truth peak {peak:.3g}); "
          f"{log['solver']['stop_reason']}")
    for name, r in references.items():
        print(f"reference {name}: {r['wall_s']} s, RMSE {r['rmse_per_mm']:.4g} /mm")
    print(f"written {out}")


if __name__ == "__main__":
    main()
