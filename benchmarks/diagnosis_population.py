#!/usr/bin/env python3
"""The diagnosis qualified on a population, not on examples: scans simulated over trajectory
families (joint-7 orbit, HEALPix sphere), robot noise, every effect of the vocabulary at three
sizes, null scans, pairs of effects and effects outside the vocabulary, several seeds; each is
calibrated and diagnosed by `ctk` as a user runs it. Prints and stores (JSON under
benchmarks/results/) the confusion matrix (true effects x accepted set), the false acceptance on
null scans, how often the diagnosis is exactly right, and for the parameters whose truth is known
the distribution of (estimate - truth) / reported sigma.

  diagnosis_population.py --ctk build/tools/ctk [--slice small|full] [--seeds N] [--jobs N]

"small" (eleven scans: every effect at its middle size on a joint-7 orbit, null scans on both
trajectories at both noise levels, a sagging holder on a sphere of directions) is what the test
suite runs; "full" is the population."""
import argparse
import concurrent.futures
import itertools
import json
import math
import os
import pathlib
import platform
import shutil
import subprocess
import sys
import tempfile
import time

# effect -> (ctk simulate options at a size, truth of the reported parameters at that size)
# Sizes run from about the detection limit to a few times it.
EFFECTS = {
    "detector_intrinsics": [(["--principal-point-error-px", str(s), str(-s / 2)], None) for s in (2.0, 5.0, 12.0)],
    "detector_distortion": [(["--distortion-k1", str(k)], {"k1_per_px2": k}) for k in (1.5e-8, 3e-8, 6e-8)],
    "sphere_positions": [(["--displaced-spheres", "1", "--displacement-mm", str(d)], None) for d in (0.12, 0.25, 0.5)],
    "robot_base_frame": [(["--base-translation-mm", str(t / 2), str(-t / 3), str(t)], {"translation_mm": [t / 2, -t / 3, t]})
                         for t in (0.3, 0.8, 2.0)],
    "holder_mount": [(["--mount-translation-mm", str(t), str(t / 2), "0"], {"translation_mm": [t, t / 2, 0.0]}) for t in (0.3, 0.8, 2.0)],
    "source_drift": [(["--source-drift-mm", str(d), str(-d / 2)], None) for d in (0.1, 0.3, 1.0)],
}
OUTSIDE = {"holder_sag": [(["--holder-sag-deg", str(a)], None) for a in (0.05, 0.15)]}
TRAJECTORIES = {"orbit": ["--trajectory", "circular", "--views", "60"], "sphere": ["--trajectory", "spherical", "--nside", "2"]}


def population(kind, seeds):
    cases = []
    noise = [("0.05", "0.01"), ("0.2", "0.05")]
    for traj, (mm, deg), seed in itertools.product(list(TRAJECTORIES), noise, range(1, seeds + 1)):
        small_null_only = kind == "small" and (traj != "orbit" or mm != "0.05")
        base = {"trajectory": traj, "noise_mm": float(mm), "noise_deg": float(deg), "seed": seed,
                "options": TRAJECTORIES[traj] + ["--robot-noise-mm", mm, "--robot-noise-deg", deg, "--seed", str(seed)]}
        cases.append(dict(base, truth=[], outside=False, size=0, truth_parameters={}))
        for effect, sizes in EFFECTS.items():
            if small_null_only:
                break  # the small slice: every effect on the orbit at the lower noise, null scans everywhere
            chosen = sizes if kind == "full" else sizes[1:2]
            for i, (opts, truth) in enumerate(chosen):
                cases.append(dict(base, truth=[effect], outside=False, size=i, truth_parameters={effect: truth} if truth else {},
                                  options=base["options"] + opts))
        for effect, sizes in OUTSIDE.items():
            if traj == "orbit" or (kind == "small" and mm != "0.05"):
                continue  # on a joint-7 orbit the holder's axis keeps its angle to gravity: a sag is a constant turn of the base
            for i, (opts, _) in enumerate(sizes if kind == "full" else sizes[1:]):
                cases.append(dict(base, truth=[], outside=True, size=i, truth_parameters={}, options=base["options"] + opts))
        if kind == "full":
            for a, b in (("robot_base_frame", "detector_distortion"), ("source_drift", "sphere_positions")):
                cases.append(dict(base, truth=[a, b], outside=False, size=1, truth_parameters={},
                                  options=base["options"] + EFFECTS[a][1][0] + EFFECTS[b][1][0]))
    return cases


def run_case(ctk, case, work, size):
    folder = pathlib.Path(work) / f"case-{case['index']:04d}"
    shutil.rmtree(folder, ignore_errors=True)
    cols, pitch = size
    start = time.monotonic()
    run = lambda args: subprocess.run([ctk] + args, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    run(["simulate", "--out", str(folder), "--phantom", "helix-holder", "--cols", str(cols), "--rows", str(cols), "--pitch", str(pitch)]
        + case["options"])
    run(["calibrate", "--scan", str(folder / "scan.json"), "--out", str(folder / "geometry.json")])
    run(["diagnose", "--scan", str(folder / "scan.json"), "--geometry", str(folder / "geometry.json"), "--out", str(folder / "d.json")])
    report = json.loads((folder / "d.json").read_text())
    shutil.rmtree(folder, ignore_errors=True)
    return report, time.monotonic() - start


def judge(case, report):
    accepted = [e for e in report["effects"] if e["accepted"]]
    names = [e["name"] for e in accepted]
    explained = set(names)
    for e in accepted:
        explained.update(e.get("confounded_with", []))
    truth = set(case["truth"])
    structured = report["unexplained"]["structured"]
    if case["outside"]:
        right = not names and structured
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


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--ctk", required=True)
    p.add_argument("--slice", choices=["small", "full"], default="small")
    p.add_argument("--seeds", type=int, default=1)
    p.add_argument("--jobs", type=int, default=1, help="cases at once (each uses every core)")
    p.add_argument("--out", help="JSON to write (default: benchmarks/results/diagnosis_population-<slice>-<cpu>.json)")
    p.add_argument("--min-right", type=float, default=None, help="exit 1 when fewer are exactly right (a share, 0..1)")
    p.add_argument("--no-false-acceptance", action="store_true", help="exit 1 when anything is accepted on a null scan")
    a = p.parse_args()
    size = (720, 0.6)  # the setup the effects' sizes are stated for
    cases = population(a.slice, a.seeds)
    for i, c in enumerate(cases):
        c["index"] = i
    work = tempfile.mkdtemp(prefix="ctk-diagnosis-population-")
    results = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=a.jobs) as pool:
        futures = {pool.submit(run_case, a.ctk, c, work, size): c for c in cases}
        for f in concurrent.futures.as_completed(futures):
            c = futures[f]
            try:
                report, seconds = f.result()
            except subprocess.CalledProcessError as e:
                results.append(dict(c, accepted=None, right=False, error=str(e)))
                print(f"case {c['index']}: {c['truth'] or ('outside' if c['outside'] else 'none')}: FAILED TO RUN ({e})", flush=True)
                continue
            names, right = judge(c, report)
            results.append(dict(c, accepted=names, right=right, structured=report["unexplained"]["structured"], seconds=seconds,
                                pulls=pulls(c, report),
                                confounded={e["name"]: e.get("confounded_with", []) for e in report["effects"] if e["accepted"]}))
            label = "+".join(c["truth"]) or ("outside" if c["outside"] else "none")
            print(f"case {c['index']:3d} {c['trajectory']:6s} seed {c['seed']} {label:40s} size {c['size']}: accepted {names or '-'}"
                  f"{' structured' if report['unexplained']['structured'] else ''} -> {'right' if right else 'WRONG'} ({seconds:.0f} s)",
                  flush=True)
    shutil.rmtree(work, ignore_errors=True)
    results.sort(key=lambda r: r["index"])
    confusion = {}
    for r in results:
        label = "+".join(r["truth"]) or ("outside (holder sag)" if r["outside"] else "none")
        key = ",".join(r["accepted"]) if r["accepted"] else ("(error)" if r["accepted"] is None else "-")
        confusion.setdefault(label, {}).setdefault(key, 0)
        confusion[label][key] += 1
    null = [r for r in results if not r["truth"] and not r["outside"]]
    all_pulls = [p for r in results for p in r.get("pulls", [])]
    within2 = sum(abs(p["pull"]) <= 2 for p in all_pulls)
    summary = {
        "slice": a.slice, "cases": len(results), "exactly_right": sum(r["right"] for r in results),
        "share_right": sum(r["right"] for r in results) / max(len(results), 1),
        "false_acceptance_on_null": sum(bool(r["accepted"]) for r in null) / max(len(null), 1),
        "pulls_within_2_sigma": within2 / len(all_pulls) if all_pulls else None, "pulls": len(all_pulls),
        "confusion": confusion, "cpu": cpu_name(), "machine": platform.machine(),
        "command": " ".join(["benchmarks/diagnosis_population.py"] + sys.argv[1:]),
    }
    print(json.dumps({k: v for k, v in summary.items() if k != "confusion"}, indent=2))
    for truth, row in confusion.items():
        print(f"  {truth:40s} " + "; ".join(f"{k}: {n}" for k, n in sorted(row.items())))
    out = pathlib.Path(a.out) if a.out else pathlib.Path(__file__).resolve().parent / "results" / (
        f"diagnosis_population-{a.slice}-" + "".join(ch if ch.isalnum() else "-" for ch in cpu_name().lower()).strip("-") + ".json")
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
