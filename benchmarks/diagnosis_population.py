#!/usr/bin/env python3
"""The diagnosis qualified on a population, not on examples: scans simulated over four trajectory
families (joint-7 orbit, HEALPix sphere, a spinning cap of directions reaching 5 deg from the
holder axis, random directions), three robot noise levels (0.02, 0.05, 0.2 mm), every effect of
the vocabulary at three sizes, null scans, pairs of effects and three effects outside the
vocabulary (a sagging holder, a focal spot that wanders without a linear trend, a sphere that
moves during the scan); each is calibrated and diagnosed by `ctk` as a user runs it. Prints and
stores (JSON under benchmarks/results/) the confusion matrix (true effects x accepted set), the
false acceptance on null scans, how often the diagnosis is exactly right, for the parameters
whose truth is known the distribution of (estimate - truth) / reported sigma, and the
calibration's figures: views calibrated among those with >= 10 spheres on the detector, with the
holder wall declared and (spherical families) without it, and the median reprojection difference
from the true matrices.

  diagnosis_population.py --ctk build/tools/ctk [--slice small|full] [--seeds N] [--jobs N]

"small" (every effect at its middle size on a joint-7 orbit, a null scan on each family, the
wandering focal spot and the moving sphere on the orbit, the sagging holder on the cap) is what
the test suite runs; "full" is the population."""
import argparse
import concurrent.futures
import itertools
import json
import math
import os
import pathlib
import platform
import re
import shutil
import random
import subprocess
import sys
import tempfile
import time

SOD_MM, SDD_MM = 1360.0, 2150.0  # ctk simulate's reference setup, for which the sizes are stated


def drift_limit_mm_per_100_views(noise_mm, views):
    """The smallest focal-spot drift a scan can show: the calibration sees a drift s as the holder
    moving sideways by s (1 - SOD / SDD), which the robot's repeatability (noise_mm / sqrt(3) per
    axis) hides unless the trend over the views stands 5 standard deviations above it."""
    sigma_axis = noise_mm / math.sqrt(3)
    slope_sigma = sigma_axis * math.sqrt(12.0 / (views * (views * views - 1)))  # mm per view
    return 5 * slope_sigma * 100 / (1 - SOD_MM / SDD_MM)


# The distortion whose part no per-view pose can absorb explains 0.01 px of held-out RMS at the
# reference setup (the diagnosis' floor for image-only effects): k1 ~ 1.5e-8 per px^2.
DISTORTION_LIMIT = 1.5e-8
SIZES = (1.5, 3.0, 6.0)
JOINT_PATTERN = (1.0, -1.5, 0.5, 2.0, -1.0, 1.5, 1.0)  # joint offsets q1..q7 in units of the size (deg)  # multiples of the detection limit, for the effects whose limit is in reach


def effects(noise_mm, views):
    """effect -> [(ctk simulate options at a size, truth of the reported parameters at that size)].
    The rigid offsets, the principal point and the displaced sphere are at sizes well above their
    limits at every noise level (a held-out z of tens); the drift and the distortion at multiples
    of theirs."""
    drift = drift_limit_mm_per_100_views(noise_mm, views)
    return {
        "detector_intrinsics": [(["--principal-point-error-px", str(s), str(-s / 2)], None) for s in (2.0, 5.0, 12.0)],
        "detector_distortion": [(["--distortion-k1", f"{m * DISTORTION_LIMIT:.4g}"], {"k1_per_px2": float(f"{m * DISTORTION_LIMIT:.4g}")})
                                for m in SIZES],
        "sphere_positions": [(["--displaced-spheres", "1", "--displacement-mm", str(d)], None) for d in (0.12, 0.25, 0.5)],
        "robot_base_frame": [(["--base-translation-mm", str(t / 2), str(-t / 3), str(t)], {"translation_mm": [t / 2, -t / 3, t]})
                             for t in (0.3, 0.8, 2.0)],
        "holder_mount": [(["--mount-translation-mm", str(t), str(t / 2), "0"], {"translation_mm": [t, t / 2, 0.0]}) for t in (0.3, 0.8, 2.0)],
        # Every joint off, by up to 0.04, 0.1 and 0.24 deg (about 0.3 to 2 mm at the holder).
        "joint_offsets": [(["--joint-offsets-deg"] + [f"{s * j:.4g}" for j in JOINT_PATTERN], {"offsets_deg": [s * j for j in JOINT_PATTERN]})
                          for s in (0.02, 0.05, 0.12)],
        # Along camera x and y as (d, -d/2): the limit holds for the larger component.
        "source_drift": [(["--source-drift-mm", f"{m * drift:.4g}", f"{-m * drift / 2:.4g}"], None) for m in SIZES],
    }


def wobble_limit_mm(noise_mm):
    """A focal spot wandering without a trend shows in the poses' order only when the holder's
    apparent motion, amplitude (1 - SOD / SDD) / sqrt(2) RMS, is as large as the robot's noise per axis."""
    return noise_mm / math.sqrt(3) * math.sqrt(2) / (1 - SOD_MM / SDD_MM)


def outside(noise_mm):
    """Outside the vocabulary: effect -> (ctk simulate options, the effects the judge lets stand
    beside the structure it leaves). A loose sphere is misplaced on average (sphere_positions may
    take that part); nothing else."""
    w = 3 * wobble_limit_mm(noise_mm)
    return {
        "holder_sag": (["--holder-sag-deg", "0.15"], set()),
        "source_wobble": (["--source-wobble-mm", f"{w:.3g}", f"{-w / 2:.3g}"], set()),
        "moving_sphere": (["--moving-sphere-mm", "0.4"], {"sphere_positions"}),
    }
TRAJECTORIES = {
    "orbit": (["--trajectory", "circular", "--views", "60"], 60),
    "sphere": (["--trajectory", "spherical", "--nside", "2"], 48),
    "cap": (["--trajectory", "cap", "--views", "60", "--cap-deg", "5", "90"], 60),
    "random": (["--trajectory", "random", "--views", "60"], 60),
}
NOISE = [("0.02", "0.005"), ("0.05", "0.01"), ("0.2", "0.05")]
NULL_SEEDS = 3  # null scans per family, noise level and seed block: the false-acceptance rate's denominator


def lab_nuisances(seed):
    """What a real lab adds that the model does not name, drawn per scan over the ranges labs see:
    a polychromatic spectrum (beam hardening of spheres and wall), scatter of 2-10 % of the flat,
    a detector PSF of 0.5-1 px, a focal spot of 0.1-0.4 mm, lag of up to 5 % of the previous view,
    a thesis sample inside the holder, and robot errors that are not Gaussian: two landing places
    per target (half the scans). An arm that droops with its reach is not among them: over a
    scan's workspace that droop is nearly a turn and shift of the base, which the diagnosis rightly
    reports as the base frame (nuisance_population's droop cases)."""
    r = random.Random(seed)
    options = ["--kvp", f"{r.uniform(60, 120):.0f}", "--filter-al-mm", "1", "--scatter", f"{r.uniform(0.02, 0.10):.3f}",
               "--detector-psf-px", f"{r.uniform(0.5, 1.0):.2f}", "--focal-spot-mm", f"{r.uniform(0.1, 0.4):.2f}",
               "--lag", f"{r.uniform(0.0, 0.05):.3f}", "--phantom", r.choice(["sample-1", "sample-2"])]
    if r.random() < 0.5:
        options += ["--robot-clusters-mm", f"{r.uniform(0.05, 0.15):.3f}"]
    return options


def nuisance_population(seeds):
    """Null scans with lab nuisances on every trajectory family (`seeds` per family: the
    false-acceptance rate's denominator), and every effect at its three sizes, with nuisances, on
    random directions (the detection rate per effect). Robot noise 0.05 mm throughout; the wall
    declared (the measured wall is the full slice's question)."""
    cases = []
    mm, deg = "0.05", "0.01"
    for traj, (options, views) in TRAJECTORIES.items():
        for seed in range(1, seeds + 1):
            s = 5000 + seed
            cases.append({"trajectory": traj, "noise_mm": 0.05, "noise_deg": 0.01, "seed": s, "allowed": [], "truth": [],
                          "outside": None, "size": 0, "truth_parameters": {},
                          "options": options + ["--robot-noise-mm", mm, "--robot-noise-deg", deg, "--seed", str(s)] + lab_nuisances(s)})
    # An arm drooping with its reach: the base frame (or what it is confounded with) may take it.
    for traj in ("random", "cap"):
        options, views = TRAJECTORIES[traj]
        for k, droop in enumerate((0.1, 0.2, 0.3, 0.5)):
            s = 6000 + 10 * k + (traj == "cap")
            cases.append({"trajectory": traj, "noise_mm": 0.05, "noise_deg": 0.01, "seed": s, "truth": [], "outside": "arm_droop",
                          "allowed": ["holder_mount", "joint_offsets", "robot_base_frame"], "structure_optional": True,
                          "size": k, "truth_parameters": {},
                          "options": options + ["--robot-noise-mm", mm, "--robot-noise-deg", deg, "--seed", str(s),
                                                "--robot-droop-mm-per-m", str(droop)] + lab_nuisances(s)})
    options, views = TRAJECTORIES["random"]
    for effect, sizes in effects(0.05, views).items():
        for i, (opts, truth) in enumerate(sizes):
            s = 7000 + 10 * i + list(effects(0.05, views)).index(effect)
            cases.append({"trajectory": "random", "noise_mm": 0.05, "noise_deg": 0.01, "seed": s, "allowed": [], "truth": [effect],
                          "outside": None, "size": i, "truth_parameters": {effect: truth} if truth else {},
                          "options": options + ["--robot-noise-mm", mm, "--robot-noise-deg", deg, "--seed", str(s)] +
                          lab_nuisances(s) + opts})
    for c in cases:
        c["wall_declared_only"] = True
    return cases


def wilson_interval(k, n, z=1.959964):
    """95 % score interval of a rate seen k times in n (Wilson 1927): honest at k = 0."""
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (max(0.0, centre - half), min(1.0, centre + half))


def population(kind, seeds):
    if kind == "nuisances":
        return nuisance_population(seeds)
    cases = []
    for traj, (mm, deg), seed in itertools.product(list(TRAJECTORIES), NOISE, range(1, seeds + 1)):
        options, views = TRAJECTORIES[traj]
        small = kind == "small"
        if small and mm != "0.05":
            continue
        base = {"trajectory": traj, "noise_mm": float(mm), "noise_deg": float(deg), "seed": seed, "allowed": [],
                "options": options + ["--robot-noise-mm", mm, "--robot-noise-deg", deg, "--seed", str(seed)]}
        for null_seed in range(NULL_SEEDS if not small else 1):
            s = 1000 * seed + null_seed
            cases.append(dict(base, seed=s, truth=[], outside=None, size=0, truth_parameters={},
                              options=options + ["--robot-noise-mm", mm, "--robot-noise-deg", deg, "--seed", str(s)]))
        if small and traj != "orbit":
            if traj == "cap":  # where a sag's mean looks most like a base offset
                opts, allowed = outside(float(mm))["holder_sag"]
                cases.append(dict(base, truth=[], outside="holder_sag", allowed=sorted(allowed), size=0, truth_parameters={},
                                  options=base["options"] + opts))
            continue
        table = effects(float(mm), views)
        for effect, sizes in table.items():
            chosen = sizes if not small else sizes[1:2]
            for i, (opts, truth) in enumerate(chosen):
                cases.append(dict(base, truth=[effect], outside=None, size=i if not small else 1,
                                  truth_parameters={effect: truth} if truth else {}, options=base["options"] + opts))
        for effect, (opts, allowed) in outside(float(mm)).items():
            # On a joint-7 orbit the holder's axis keeps its angle to gravity: a sag is a constant turn of the base.
            if effect == "holder_sag" and traj == "orbit":
                continue
            cases.append(dict(base, truth=[], outside=effect, allowed=sorted(allowed), size=0, truth_parameters={},
                              options=base["options"] + opts))
        if not small:
            for a, b in (("robot_base_frame", "detector_distortion"), ("source_drift", "sphere_positions")):
                cases.append(dict(base, truth=[a, b], outside=None, size=1, truth_parameters={},
                                  options=base["options"] + table[a][1][0] + table[b][1][0]))
    return cases


def project(P, X):
    h = [sum(P[4 * r + c] * X[c] for c in range(3)) + P[4 * r + 3] for r in range(3)]
    return h[0] / h[2], h[1] / h[2]


def calibration_figures(folder, geometry_name, cols):
    """Per scan: views with >= 10 true sphere centres on the detector, how many of them the
    calibration kept, and each kept view's RMS difference from the true matrix over the spheres."""
    truth = json.loads((folder / "truth.json").read_text())
    true_views = {v["index"]: v for v in json.loads((folder / "truth-geometry.json").read_text())["views"] if v["status"] == "ok"}
    fitted = {v["index"]: v for v in json.loads((folder / geometry_name).read_text())["views"]}
    spheres = truth["holder_spheres_mm"]
    eligible, kept, differences, lost = 0, 0, [], []
    for index, tv in true_views.items():
        on_detector = [X for X in spheres if all(0 <= c <= cols - 1 for c in project(tv["P"], X))]
        if len(on_detector) < 10:
            continue
        eligible += 1
        fv = fitted.get(index)
        if not fv or fv["status"] != "ok":
            lost.append({"view": index, "reason": fv.get("reason", "") if fv else "absent"})
            continue
        kept += 1
        sq = [sum((a - b) ** 2 for a, b in zip(project(fv["P"], X), project(tv["P"], X))) for X in on_detector]
        differences.append(math.sqrt(sum(sq) / len(sq)))
    return {"eligible": eligible, "calibrated": kept, "median_difference_px": sorted(differences)[len(differences) // 2] if differences else None,
            "lost": lost}


def run_case(ctk, case, work, size):
    folder = pathlib.Path(work) / f"case-{case['index']:04d}"
    shutil.rmtree(folder, ignore_errors=True)
    cols, pitch = size
    start = time.monotonic()
    run = lambda args: subprocess.run([ctk] + args, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    run(["simulate", "--out", str(folder), "--phantom", "helix-holder", "--cols", str(cols), "--rows", str(cols), "--pitch", str(pitch)]
        + case["options"])
    run(["calibrate", "--scan", str(folder / "scan.json"), "--out", str(folder / "geometry.json")])
    calibration = {"wall_declared": calibration_figures(folder, "geometry.json", cols)}
    if case["trajectory"] != "orbit" and not case.get("wall_declared_only"):
        # The same scan as a lab that does not know its holder's wall declares it.
        scan = json.loads((folder / "scan.json").read_text())
        scan["holder"].pop("wall", None)
        (folder / "scan-no-wall.json").write_text(json.dumps(scan))
        run(["calibrate", "--scan", str(folder / "scan-no-wall.json"), "--out", str(folder / "geometry-no-wall.json")])
        calibration["wall_not_declared"] = calibration_figures(folder, "geometry-no-wall.json", cols)
        measured = json.loads((folder / "geometry-no-wall.report.json").read_text()).get("holder_wall", {}).get("measured")
        if measured:  # the wall the images show against the one the scan had declared
            truth = json.loads((folder / "scan.json").read_text())["holder"]["wall"]
            calibration["wall_measured"] = {k: measured[f"{k}_radius_mm"] - truth[f"{k}_radius_mm"] for k in ("inner", "outer")}
            calibration["wall_measured"].update({f"{k}_sigma_mm": measured[f"{k}_sigma_mm"] for k in ("inner", "outer")})
            if measured.get("ends") and truth.get("ends_mm"):
                for i, k in enumerate(("lower_end", "upper_end")):
                    calibration["wall_measured"][k] = measured["ends"]["ends_mm"][i] - truth["ends_mm"][i]
                    calibration["wall_measured"][f"{k}_sigma_mm"] = measured["ends"]["ends_sigma_mm"][i]
    run(["diagnose", "--scan", str(folder / "scan.json"), "--geometry", str(folder / "geometry.json"), "--out", str(folder / "d.json")])
    report = json.loads((folder / "d.json").read_text())
    without_wall = None
    if case["trajectory"] != "orbit" and not case.get("wall_declared_only"):
        # Diagnosed as that lab would: from the calibration whose wall was measured in the images.
        run(["diagnose", "--scan", str(folder / "scan-no-wall.json"), "--geometry", str(folder / "geometry-no-wall.json"),
             "--out", str(folder / "d-no-wall.json")])
        without_wall = json.loads((folder / "d-no-wall.json").read_text())
    shutil.rmtree(folder, ignore_errors=True)
    return report, without_wall, calibration, time.monotonic() - start


def judge(case, report):
    accepted = [e for e in report["effects"] if e["accepted"]]
    names = [e["name"] for e in accepted]
    explained = set(names)
    for e in accepted:
        explained.update(e.get("confounded_with", []))
    truth = set(case["truth"])
    structured = report["unexplained"]["structured"]
    if case["outside"]:
        right = (structured or case.get("structure_optional", False)) and set(names) <= set(case["allowed"])
    elif not truth:
        right = not names and not structured
    else:
        # Every true effect accepted or named as confounded with an accepted one; nothing else
        # accepted unless it is confounded with a true one.
        unexplained_truth = truth - explained
        extra = [e for e in accepted if e["name"] not in truth and not truth & set(e.get("confounded_with", []))]
        right = not unexplained_truth and not extra and not structured
    return names, right


def pulls(case, report):
    out = []
    for e in report["effects"]:
        truth = case["truth_parameters"].get(e["name"]) if e["accepted"] else None
        if not truth:
            continue
        for key, value in truth.items():
            est, sig = e["parameters"].get(key), e["uncertainty"].get(key)
            if est is None or sig is None:
                continue
            values = value if isinstance(value, list) else [value]
            ests = est if isinstance(est, list) else [est]
            sigs = sig if isinstance(sig, list) else [sig]
            for t, x, s in zip(values, ests, sigs):
                if s and s > 0:
                    out.append({"effect": e["name"], "key": key, "truth": t, "estimate": x, "sigma": s, "pull": (x - t) / s,
                                "relative_error": abs(x - t) / abs(t) if t else None})
    return out


def cpu_name():
    fields = {k.strip(): v.strip() for k, v in (l.split(":", 1) for l in pathlib.Path("/proc/cpuinfo").read_text().splitlines() if ":" in l)}
    return f"{fields.get('model name', '?')} family {fields.get('cpu family', '?')} model {fields.get('model', '?')}" + (
        " avx512" if "avx512f" in fields.get("flags", "") else "")


def cpu_slug():
    """cpu_name() as a file name's part: lower case, every other character a hyphen."""
    return "".join(ch if ch.isalnum() else "-" for ch in cpu_name().lower()).strip("-")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--ctk", required=True)
    p.add_argument("--slice", choices=["small", "full", "nuisances"], default="small")
    p.add_argument("--seeds", type=int, default=1, help="seed blocks (nuisances: null scans per trajectory family)")
    p.add_argument("--jobs", type=int, default=1, help="cases at once (each uses every core)")
    p.add_argument("--match", help="only the cases whose '<trajectory> <effect>' contains this regular expression "
                   "(e.g. 'cap holder_sag', '^sphere none'); a look at a part, not the population")
    p.add_argument("--out", help="JSON to write (default: benchmarks/results/diagnosis_population-<slice>-<cpu>.json)")
    p.add_argument("--min-right", type=float, default=None, help="exit 1 when fewer are exactly right (a share, 0..1)")
    p.add_argument("--no-false-acceptance", action="store_true", help="exit 1 when anything is accepted on a null scan")
    a = p.parse_args()
    size = (720, 0.6)  # the setup the effects' sizes are stated for
    cases = population(a.slice, a.seeds)
    for i, c in enumerate(cases):
        c["index"] = i
    if a.match:
        label = lambda c: "+".join(c["truth"]) or (c["outside"] or "none")
        cases = [c for c in cases if re.search(a.match, f"{c['trajectory']} {label(c)}")]
    work = tempfile.mkdtemp(prefix="ctk-diagnosis-population-")
    results = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=a.jobs) as pool:
        futures = {pool.submit(run_case, a.ctk, c, work, size): c for c in cases}
        for f in concurrent.futures.as_completed(futures):
            c = futures[f]
            try:
                report, without_wall, calibration, seconds = f.result()
            except subprocess.CalledProcessError as e:
                results.append(dict(c, accepted=None, right=False, error=str(e)))
                print(f"case {c['index']}: {c['truth'] or ('outside' if c['outside'] else 'none')}: FAILED TO RUN ({e})", flush=True)
                continue
            names, right = judge(c, report)
            results.append(dict(c, accepted=names, right=right, structured=report["unexplained"]["structured"], seconds=seconds,
                                calibration=calibration, note=report["unexplained"]["note"],
                                pulls=pulls(c, report),
                                confounded={e["name"]: e.get("confounded_with", []) for e in report["effects"] if e["accepted"]}))
            label = "+".join(c["truth"]) or (c["outside"] or "none")
            verdict = lambda n, r, rep: f"{n or '-'}{' structured' if rep['unexplained']['structured'] else ''} -> {'right' if r else 'WRONG'}"
            line = f"case {c['index']:3d} {c['trajectory']:6s} seed {c['seed']} {label:40s} size {c['size']}: accepted {verdict(names, right, report)}"
            if without_wall:
                nw_names, nw_right = judge(c, without_wall)
                results[-1]["wall_not_declared"] = dict(
                    accepted=nw_names, right=nw_right, structured=without_wall["unexplained"]["structured"],
                    note=without_wall["unexplained"]["note"], pulls=pulls(c, without_wall),
                    confounded={e["name"]: e.get("confounded_with", []) for e in without_wall["effects"] if e["accepted"]})
                line += f"; wall not declared: {verdict(nw_names, nw_right, without_wall)}"
            print(line + f" ({seconds:.0f} s)", flush=True)
    shutil.rmtree(work, ignore_errors=True)
    results.sort(key=lambda r: r["index"])
    def confusion_of(rows):
        confusion = {}
        for r in rows:
            label = "+".join(r["truth"]) or (f"outside: {r['outside']}" if r["outside"] else "none")
            key = ",".join(r["accepted"]) if r["accepted"] else ("(error)" if r["accepted"] is None else "-")
            confusion.setdefault(label, {}).setdefault(key, 0)
            confusion[label][key] += 1
        return confusion
    confusion = confusion_of(results)
    null = [r for r in results if not r["truth"] and not r["outside"]]
    all_pulls = [p for r in results for p in r.get("pulls", [])]
    within2 = sum(abs(p["pull"]) <= 2 for p in all_pulls)
    def calibration_summary(key, trajectories):
        rows = [r["calibration"][key] for r in results if r.get("calibration") and key in r["calibration"] and r["trajectory"] in trajectories]
        eligible, kept = sum(x["eligible"] for x in rows), sum(x["calibrated"] for x in rows)
        medians = sorted(x["median_difference_px"] for x in rows if x["median_difference_px"] is not None)
        return {"views_eligible": eligible, "views_calibrated": kept, "share": kept / eligible if eligible else None,
                "median_of_scan_medians_px": medians[len(medians) // 2] if medians else None,
                "worst_scan_median_px": medians[-1] if medians else None}

    walls = [r["calibration"]["wall_measured"] for r in results if r.get("calibration", {}).get("wall_measured")]
    wall_summary = {"scans": len(walls)}
    if walls:
        for k in ("inner", "outer", "lower_end", "upper_end"):
            mine = [w for w in walls if k in w]
            if not mine:
                continue
            wall_summary[f"{k}_measured_on"] = len(mine)
            wall_summary[f"{k}_worst_error_mm"] = max(abs(w[k]) for w in mine)
            wall_summary[f"{k}_within_2_sigma"] = sum(abs(w[k]) <= 2 * w[f"{k}_sigma_mm"] for w in mine) / len(mine)

    by_family = {}
    for traj in TRAJECTORIES:
        rows = [r for r in results if r["trajectory"] == traj]
        by_family[traj] = {"cases": len(rows), "exactly_right": sum(r["right"] for r in rows)}
    spherical = [t for t in TRAJECTORIES if t != "orbit"]
    no_wall = [dict(r["wall_not_declared"], truth=r["truth"], outside=r["outside"]) for r in results if r.get("wall_not_declared")]
    no_wall_pulls = [p for r in no_wall for p in r["pulls"]]
    no_wall_null = [r for r in no_wall if not r["truth"] and not r["outside"]]
    summary = {
        "slice": a.slice, "cases": len(results), "exactly_right": sum(r["right"] for r in results),
        "share_right": sum(r["right"] for r in results) / max(len(results), 1),
        "false_acceptance_on_null": sum(bool(r["accepted"]) for r in null) / max(len(null), 1),
        "null_scans": len(null), "null_scans_with_an_acceptance": sum(bool(r["accepted"]) for r in null),
        "false_acceptance_95_interval": wilson_interval(sum(bool(r["accepted"]) for r in null), len(null)),
        "null_scans_reported_structured": sum(bool(r.get("structured")) for r in null),
        "detection_by_effect_and_size": {
            e: {str(size): sum(1 for r in results if r["truth"] == [e] and r["size"] == size and
                               (e in (r["accepted"] or []) or any(e in v for v in r.get("confounded", {}).values())))
                / max(1, sum(1 for r in results if r["truth"] == [e] and r["size"] == size))
                for size in sorted({r["size"] for r in results if r["truth"] == [e]})}
            for e in sorted({t for r in results for t in r["truth"]})},
        "pulls_within_2_sigma": within2 / len(all_pulls) if all_pulls else None, "pulls": len(all_pulls),
        "by_family": by_family,
        "diagnosed_with_the_wall_measured": {
            "cases": len(no_wall), "exactly_right": sum(r["right"] for r in no_wall),
            "share_right": sum(r["right"] for r in no_wall) / max(len(no_wall), 1),
            "false_acceptance_on_null": sum(bool(r["accepted"]) for r in no_wall_null) / max(len(no_wall_null), 1),
            "pulls_within_2_sigma": sum(abs(p["pull"]) <= 2 for p in no_wall_pulls) / len(no_wall_pulls) if no_wall_pulls else None,
            "pulls": len(no_wall_pulls)},
        "calibration": {"wall_declared": calibration_summary("wall_declared", list(TRAJECTORIES)),
                        "wall_declared_spherical_families": calibration_summary("wall_declared", spherical),
                        "wall_not_declared_spherical_families": calibration_summary("wall_not_declared", spherical),
                        "wall_measured_when_not_declared": wall_summary},
        "confusion": confusion, "confusion_with_the_wall_measured": confusion_of(no_wall), "cpu": cpu_name(), "machine": platform.machine(),
        "command": " ".join(["benchmarks/diagnosis_population.py"] + sys.argv[1:]),
    }
    print(json.dumps({k: v for k, v in summary.items() if not k.startswith("confusion")}, indent=2))
    for title, table in (("wall declared", confusion), ("wall measured in the images", summary["confusion_with_the_wall_measured"])):
        print(f"confusion, {title} (true effects: accepted sets):")
        for truth, row in table.items():
            print(f"  {truth:40s} " + "; ".join(f"{k}: {n}" for k, n in sorted(row.items())))
    out = pathlib.Path(a.out) if a.out else pathlib.Path(__file__).resolve().parent / "results" / (
        f"diagnosis_population-{a.slice}-" + cpu_slug() + ".json")
    if a.out or not a.match:  # a part of the population is not stored as the population's result
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(dict(summary, results=results), indent=2) + "\n")
    failed = [r for r in results if r["accepted"] is None]
    if failed:
        print(f"{len(failed)} cases failed to run")
    if a.no_false_acceptance and summary["false_acceptance_on_null"] > 0:
        print("FAIL: an effect was accepted on a null scan")
        return 1
    if a.min_right is not None and summary["share_right"] < a.min_right:
        print(f"FAIL: {summary['share_right']:.2f} exactly right, fewer than {a.min_right}")
        return 1
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
