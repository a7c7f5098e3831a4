#!/usr/bin/env python3
"""Runs spread over MPI ranks on one machine, as a user starts them with mpirun: on a circular and
a spherical scan, WLS-CG over 2 and 3 ranks gives the single-process volume to 1e-5 of its largest
value and its cost to 1e-6, SIRT and OS-SQS over 3 ranks too (the ranks add their back projections
in another order than one process does: float rounding, which CG carries on); a spread run repeated gives the same bits; the bytes summed over the
ranks per iteration, as counted, are the plan's model to 10 %; calibration over 2 and 3 ranks
writes the single-process geometry; a rank that fails (an unreadable projection only it reads) or
is killed ends the whole job, named, with nothing written; a command that does not spread is
refused.  Usage: mpi_runs.py CTK MPIRUN"""
import argparse
import array
import json
import math
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import time

from failures import report


def read_nrrd(path):
    return read_raw_after(path.read_bytes(), b"\n\n")


def read_raw_after(data, marker):
    values = array.array("f")
    values.frombytes(data[data.index(marker) + len(marker):])
    return values


def relative_difference(a, b):
    """Largest difference relative to the largest value, and the relative L2 difference."""
    top = max(abs(x) for x in a)
    norm = math.sqrt(sum(x * x for x in a))
    return max(abs(x - y) for x, y in zip(a, b)) / top, math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b))) / norm


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("ctk")
    parser.add_argument("mpirun")
    a = parser.parse_args()
    work = pathlib.Path("mpi-runs")
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir()
    # One thread per rank (the ranks share the machine); OpenMPI refuses root unless told (CI is root).
    env = dict(os.environ, OMP_NUM_THREADS="1", OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    ctk = lambda *args: subprocess.run([a.ctk, *map(str, args)], capture_output=True, text=True, env=env)
    spread = lambda n, *args: subprocess.run([a.mpirun, "--oversubscribe", "-np", str(n), a.ctk, *map(str, args)],
                                             capture_output=True, text=True, env=env)
    failures = []

    scans = {}
    for name, trajectory in {"circular": ["--trajectory", "circular", "--views", "40"],
                             "spherical": ["--trajectory", "spherical", "--nside", "2"]}.items():
        folder = work / name
        r = ctk("simulate", "--out", folder, "--phantom", "shepp-logan", "--cols", "96", "--rows", "80", "--pitch", "4.5",
                *trajectory)
        if r.returncode:
            return report([f"simulate {name}: {r.stderr}"])
        scans[name] = folder

    def reconstruct(runner, scan, out, method, iterations, *more):
        return runner("reconstruct", "--scan", scan / "scan.json", "--geometry", scan / "truth-geometry.json", "--out", out,
                      "--size", "40", "--method", method, "--iterations", iterations, *more)

    # Six CG iterations: beyond, CG carries the rounding of the other order of additions further
    # (after 10 on the spherical scan, 6e-6 to 1.1e-5 of the largest value; the cost within 2e-7).
    cases = [("circular", "wls-cg", 6, (2, 3)), ("spherical", "wls-cg", 6, (2, 3)), ("spherical", "sirt", 10, (3,)),
             ("spherical", "os-sqs", 4, (3,))]
    for name, method, iterations, rank_counts in cases:
        one = work / f"{name}-{method}-1.nrrd"
        r = reconstruct(ctk, scans[name], one, method, iterations)
        if r.returncode:
            failures.append(f"{name} {method} on one process: {r.stderr}")
            continue
        for decomposition in ("views", "slabs"):
            for n in rank_counts:
                out = work / f"{name}-{method}-{decomposition}-{n}.nrrd"
                r = reconstruct(lambda *args: spread(n, *args), scans[name], out, method, iterations, "--decomposition",
                                decomposition)
                if r.returncode or f"spread over {n} ranks" not in r.stdout or f"picked: {decomposition}" not in r.stdout:
                    failures.append(f"{name} {method} over {n} ranks by {decomposition}: exit {r.returncode}, "
                                    f"{r.stdout[-400:]} {r.stderr[-800:]}")
                    continue
                largest, l2 = relative_difference(read_nrrd(one), read_nrrd(out))
                cost = lambda f: json.loads(f.with_suffix(".log.json").read_text())["solver"]["iterations"][-1]["cost"]
                cost_difference = abs(cost(out) - cost(one)) / cost(one)
                whole_log = json.loads(out.with_suffix(".log.json").read_text())
                log = whole_log["distribution"]
                counted, model = log["bytes_per_iteration"], log["model_bytes_per_iteration"]
                print(f"{name} {method} over {n} ranks by {decomposition}: largest difference {largest:.2e} of the largest "
                      f"value (L2 {l2:.2e} relative), cost {cost_difference:.1e} relative; to the other ranks per iteration "
                      f"{counted} bytes counted, {model} modelled")
                if not (largest <= 1e-5 and cost_difference <= 1e-6):
                    failures.append(f"{name} {method} over {n} ranks by {decomposition} differs from one process: {largest:.3g} "
                                    f"of the largest value, cost {cost_difference:.3g}")
                if not (log["ranks"] == n and log["decomposition"] == decomposition and model > 0
                        and abs(counted - model) <= 0.1 * model and len(whole_log["peak_resident_bytes_per_rank"]) == n):
                    failures.append(f"{name} {method} over {n} ranks by {decomposition}: {log}")

    # Slabs in the other volume formats, written slab by slab: as large as one process's file (the
    # TIFF library's own tags may differ by a few bytes; a MetaImage's voxels compared).
    for extension in (".mha", ".tif", ".h5"):
        one, split = work / f"formats-1{extension}", work / f"formats-slabs{extension}"
        r1 = reconstruct(ctk, scans["circular"], one, "wls-cg", 4)
        r2 = reconstruct(lambda *args: spread(3, *args), scans["circular"], split, "wls-cg", 4, "--decomposition", "slabs")
        if r1.returncode or r2.returncode or not split.exists() or abs(split.stat().st_size - one.stat().st_size) > (
                64 if extension == ".tif" else 0):
            failures.append(f"slabs written as {extension}: exit {r1.returncode} / {r2.returncode}, {r2.stderr[-400:]}")
        elif extension == ".mha":
            voxels = lambda f: read_raw_after(f.read_bytes(), b"ElementDataFile = LOCAL\n")
            if relative_difference(voxels(one), voxels(split))[0] > 1e-5:
                failures.append("slabs written as .mha differ from one process's volume")
    # A penalty of neighbour differences cannot run on slabs (they hold no neighbouring planes).
    r = reconstruct(lambda *args: spread(2, *args), scans["circular"], work / "refused.nrrd", "wls-cg", 4, "--decomposition",
                    "slabs", "--lambda", "1", "--regulariser", "gradient")
    if r.returncode == 0 or "gradient penalty" not in r.stderr or (work / "refused.nrrd").exists():
        failures.append(f"slabs with the gradient penalty: exit {r.returncode}, {r.stderr[-400:]}")

    # The same spread run twice: the same bits (the sums' order does not depend on timing).
    for decomposition in ("views", "slabs"):
        again = work / f"spherical-wls-cg-{decomposition}-2-again.nrrd"
        r = reconstruct(lambda *args: spread(2, *args), scans["spherical"], again, "wls-cg", 6, "--decomposition", decomposition)
        if r.returncode or read_nrrd(again) != read_nrrd(work / f"spherical-wls-cg-{decomposition}-2.nrrd"):
            failures.append(f"a spread run by {decomposition} repeated gave other bits (exit {r.returncode})")

    # Default iterations hold the same views out on every rank and stop at the same iteration.
    def held_out_run(runner, out, *more):
        return runner("reconstruct", "--scan", scans["circular"] / "scan.json", "--geometry",
                      scans["circular"] / "truth-geometry.json", "--out", out, "--size", "40", *more)
    one = work / "held-out-1.nrrd"
    r = held_out_run(ctk, one)
    stop = lambda log: json.loads(log.with_suffix(".log.json").read_text())["held_out"]
    if r.returncode:
        failures.append(f"default iterations on one process: {r.stderr[-400:]}")
    else:
        for decomposition in ("views", "slabs"):
            out = work / f"held-out-{decomposition}-2.nrrd"
            r = held_out_run(lambda *args: spread(2, *args), out, "--decomposition", decomposition)
            largest = relative_difference(read_nrrd(one), read_nrrd(out))[0] if r.returncode == 0 else float("inf")
            if r.returncode or stop(out)["best_iteration"] != stop(one)["best_iteration"] or \
                    stop(out)["view_indices"] != stop(one)["view_indices"] or largest > 1e-5:
                failures.append(f"default iterations over 2 ranks by {decomposition}: exit {r.returncode}, largest "
                                f"difference {largest:.3g}, {r.stderr[-400:]}")
            else:
                print(f"default iterations over 2 ranks by {decomposition}: the same {len(stop(one)['view_indices'])} "
                      f"views held out, stopped after iteration {stop(one)['best_iteration']}, largest difference "
                      f"{largest:.2e}")

    # Calibration over ranks writes the single-process geometry.
    cal = work / "calibration"
    r = ctk("simulate", "--out", cal, "--trajectory", "random", "--views", "18", "--cols", "240", "--rows", "240", "--pitch",
            "1.8", "--seed", "3")
    if r.returncode:
        return report(failures + [f"simulate for calibration: {r.stderr}"])
    r = ctk("calibrate", "--scan", cal / "scan.json", "--out", work / "g-1.json")
    if r.returncode:
        failures.append(f"calibrate on one process: {r.stderr}")
    else:
        single = json.loads((work / "g-1.json").read_text())["views"]
        for n in (2, 3):
            r = spread(n, "calibrate", "--scan", cal / "scan.json", "--out", work / f"g-{n}.json")
            if r.returncode:
                failures.append(f"calibrate over {n} ranks: exit {r.returncode}, {r.stderr[-800:]}")
                continue
            views = json.loads((work / f"g-{n}.json").read_text())["views"]
            ok = sum(v["status"] == "ok" for v in views)
            same = len(views) == len(single) and all(
                v["status"] == w["status"] and v.get("P") == w.get("P") and v.get("rms_px") == w.get("rms_px")
                for v, w in zip(views, single))
            print(f"calibration over {n} ranks: {ok} of {len(views)} views ok, {'the same' if same else 'NOT the same'} "
                  f"geometry as one process")
            if not same or ok < len(views) // 2:
                failures.append(f"calibration over {n} ranks differs from one process ({ok} ok)")

    # A rank that cannot read its projection ends the job: the file named, exit 2, nothing written.
    bad = work / "damaged"
    shutil.copytree(scans["circular"], bad)
    (bad / "projections" / "proj_0005.tif").write_bytes(b"not a TIFF")
    out = work / "damaged.nrrd"
    r = spread(3, "reconstruct", "--scan", bad / "scan.json", "--out", out, "--size", "24", "--iterations", "3")
    written = sorted(p.name for p in work.glob("damaged.*"))
    if r.returncode != 2 or "rank 2 of 3" not in r.stderr or "proj_0005.tif" not in r.stderr or written:
        failures.append(f"a rank's unreadable image: exit {r.returncode}, wrote {written}, {r.stderr[-600:]}")

    # A rank killed mid-run ends the job, with nothing written.
    out = work / "killed.nrrd"
    job = subprocess.Popen([a.mpirun, "--oversubscribe", "-np", "2", a.ctk, "reconstruct", "--scan",
                            scans["spherical"] / "scan.json", "--out", out, "--size", "64", "--iterations", "100000",
                            "--tolerance", "0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    ranks = []
    for _ in range(200):  # wait until both ranks run
        time.sleep(0.1)
        found = subprocess.run(["pgrep", "-f", f"reconstruct --scan {scans['spherical']}/scan.json --out {out}"],
                               capture_output=True, text=True).stdout.split()
        ranks = [int(p) for p in found if int(p) != job.pid]
        if len(ranks) >= 2:
            break
    if len(ranks) < 2:
        job.kill()
        failures.append(f"the ranks to kill were not found: {ranks}")
    else:
        time.sleep(1.0)
        os.kill(max(ranks), signal.SIGKILL)
        try:
            _, stderr = job.communicate(timeout=60)
            written = sorted(p.name for p in work.glob("killed.*"))
            print(f"a rank killed: mpirun exit {job.returncode}")
            if job.returncode == 0 or written:
                failures.append(f"a killed rank: exit {job.returncode}, wrote {written}, {stderr[-400:]}")
        except subprocess.TimeoutExpired:
            job.kill()
            failures.append("a killed rank left the job running")

    # A command that does not spread over ranks is refused.
    r = spread(2, "simulate", "--out", work / "not-spread")
    if r.returncode != 2 or "does not spread over MPI ranks" not in r.stderr or (work / "not-spread").exists():
        failures.append(f"simulate under mpirun: exit {r.returncode}, {r.stderr[-400:]}")
    return report(failures)


if __name__ == "__main__":
    sys.exit(main())
