#!/usr/bin/python3
"""Ctrl-C at the last moment a run can still leave nothing: `ctk.import_nxtomo` interrupted from its
progress callable just after the last frame is copied, when only the publishing step can still see
the signal (Python notices it up to a 20 ms poll later). Each run is counted as leaving files or
not, alone and with every core kept busy by spinning processes; the NXtomo file is the one
`write_vendor_scans` writes through the HDF Group's library.

    PYTHONPATH=build/python /usr/bin/python3 benchmarks/interrupted_publish.py \
        --vendor-scans build/tests/write_vendor_scans --work /tmp/interrupted-publish [--runs 100]

Writes benchmarks/results/interrupted_publish-<cpu>.json."""
import argparse
import json
import os
import pathlib
import signal
import subprocess
import sys
import time

import ctk

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from diagnosis_population import cpu_name, cpu_slug  # noqa: E402


def interrupted_runs(nexus, folder, runs):
    """How many of `runs` imports interrupted after their last frame left files, and the slowest
    delay from the signal to the KeyboardInterrupt."""
    left, slowest = 0, 0.0
    for k in range(runs):
        sent = []

        def ctrl_c(done, total):
            if done == total:
                sent.append(time.perf_counter())
                os.kill(os.getpid(), signal.SIGINT)
        try:
            ctk.import_nxtomo(nexus, folder / f"run-{k}.json", progress=ctrl_c)
        except KeyboardInterrupt:
            slowest = max(slowest, time.perf_counter() - sent[0])
        if any(folder.glob(f"run-{k}.*")) or any(p.name.startswith(f".run-{k}.") for p in folder.iterdir()):
            left += 1
    return left, slowest


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--vendor-scans", required=True)
    p.add_argument("--work", required=True, type=pathlib.Path)
    p.add_argument("--runs", type=int, default=100)
    a = p.parse_args()
    a.work.mkdir(parents=True, exist_ok=True)
    subprocess.run([a.vendor_scans, "write", str(a.work)], check=True, capture_output=True)
    nexus = a.work / "nxtomo" / "scan.nx"
    result = {"cpu": cpu_name(), "command": " ".join(sys.argv), "runs": a.runs}
    for load in ("alone", "cores busy"):
        folder = a.work / load.replace(" ", "-")
        folder.mkdir(exist_ok=True)
        spinners = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(2 * os.cpu_count())] \
            if load == "cores busy" else []
        try:
            left, slowest = interrupted_runs(nexus, folder, a.runs)
        finally:
            for s in spinners:
                s.kill()
        result[load] = {"runs_leaving_files": left, "slowest_interrupt_s": round(slowest, 4)}
        print(f"{load}: {left} of {a.runs} runs left files; KeyboardInterrupt at most {1000 * slowest:.1f} ms after the signal")
    out = pathlib.Path(__file__).resolve().parent / "results" / f"interrupted_publish-{cpu_slug()}.json"
    out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"written {out}")


if __name__ == "__main__":
    main()
