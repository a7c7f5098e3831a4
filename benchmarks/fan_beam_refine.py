#!/usr/bin/env python3
"""Time of one 3600-view fan-beam `ctk refine` (the real FleX-ray scan `zero` of
../shared/data/real/flexray-fanbeam-detector-shifts, detector offset), on all cores against one
core of the same build, the two runs taking turns. Writes benchmarks/results/fan_beam_refine-<cpu>.json.
Usage: fan_beam_refine.py --ctk build/tools/ctk [--data DIR] [--rounds 1]"""
import argparse
import json
import os
import pathlib
import platform
import subprocess
import tempfile
import time


def cpu_name():
    info = pathlib.Path("/proc/cpuinfo").read_text()
    fields = {k.strip(): v for k, v in (line.split(":", 1) for line in info.splitlines() if ":" in line)}
    get = lambda k: fields.get(k, "?").strip()
    avx512 = "avx512f" in get("flags")
    return f"{get('model name')} family {get('cpu family')} model {get('model')}{' avx512' if avx512 else ''}", os.cpu_count()


def main():
    here = pathlib.Path(__file__).resolve().parent
    p = argparse.ArgumentParser()
    p.add_argument("--ctk", required=True)
    p.add_argument("--data", default=str(here.parent.parent / "shared/data/real/flexray-fanbeam-detector-shifts/zero"))
    p.add_argument("--rounds", type=int, default=1)
    a = p.parse_args()
    work = pathlib.Path(tempfile.mkdtemp(prefix="ctk-fan-bench-"))
    d = pathlib.Path(a.data)
    subprocess.run([a.ctk, "import", "circular", "--out", str(work / "scan.json"), "--files", str(d / "scan_%06d.tif"), "--count", "3601",
                    "--flat", str(d / "io000000.tif"), str(d / "io000001.tif"), "--dark", str(d / "di000000.tif"), "--detector", "1944", "1",
                    "--pitch", "0.0748", "--sod", "423.562012", "--sdd", "527.99707", "--step", "0.1"], check=True, stdout=subprocess.DEVNULL)
    runs = []
    for r in range(a.rounds):
        for threads in (None, 1):
            env = dict(os.environ)
            if threads:
                env["OMP_NUM_THREADS"] = str(threads)
            out = work / f"refine-{threads or 'all'}.json"
            start = time.monotonic()
            subprocess.run([a.ctk, "refine", "--scan", str(work / "scan.json"), "--out", str(out), "--effects", "detector_offset"], check=True,
                           env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            seconds = time.monotonic() - start
            report = json.loads(out.read_text())
            effect = next(e for e in report["effects"] if e["name"] == "detector_offset")
            runs.append({"threads": threads or os.cpu_count(), "seconds": seconds, "accepted": effect["accepted"],
                         "u0_px": effect["parameters"]["u0_px"], "conjugate_u0_px": report["cross_check"].get("u0_px")})
            print(runs[-1], flush=True)
    best = lambda t: min(x["seconds"] for x in runs if x["threads"] == t)
    cpu, cores = cpu_name()
    result = {"benchmark": "ctk refine --effects detector_offset on a 3601-view, 1944-column fan-beam scan",
              "command": "benchmarks/fan_beam_refine.py --ctk build/tools/ctk", "cpu": cpu, "cores": cores,
              "machine": platform.machine(), "runs": runs,
              "seconds_all_cores": best(os.cpu_count()), "seconds_one_core": best(1),
              "speedup_all_cores_over_one": best(1) / best(os.cpu_count())}
    print(json.dumps(result, indent=2))
    results = here / "results"
    results.mkdir(exist_ok=True)
    tag = "".join(c if c.isalnum() else "-" for c in cpu.lower()).strip("-")
    (results / f"fan_beam_refine-{tag}.json").write_text(json.dumps(result, indent=2) + "\n")


if __name__ == "__main__":
    main()
