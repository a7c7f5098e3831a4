#!/usr/bin/env python3
"""Seeded mutation test of every file the tool reads. A small valid scan is simulated once; each
case copies it, damages one file (a flipped or deleted byte, a cut, a number swapped for an extreme
one, a JSON value replaced by one of another type or removed, a TIFF's or HDF5 file's header or
directory bytes overwritten) and runs the command that reads that file; with --vendor, a Nikon
folder's .xtekct and an NXtomo file are damaged and imported too. Every case must end with exit 0 or 2 within its time limit,
never a signal, a hang or exit 1 (an internal error), and an exit 2 must name the damaged file.
Usage: fuzz_readers.py CTK [--cases N] [--seed S] [--jobs J] [--keep] [--vendor WRITE_VENDOR_SCANS]"""
import argparse
import concurrent.futures
import json
import os
import pathlib
import random
import re
import shutil
import subprocess
import sys

EXTREMES = ["1e308", "-1e308", "1e-300", "-1e-300", "0", "-0", "-1", "1e400", "NaN", "nan", "inf", "-inf", "2147483648",
            "-2147483649", "99999999999999999999", "0.5", "3", "1e6", "-1e6", "\"\"", "null", "[]", "{}", "true"]
JSON_VALUES = [None, True, False, 0, -1, 1e308, 1e-300, -1e308, 2 ** 31, 2 ** 63, 0.5, "", "x", "../../etc/passwd", "%s%s%n", [], {},
               [1, 2], [[1e308]], {"a": 1}, "proj_%04d.tif", "%0999999d", 1e6, 100000]
TIMEOUT_S = 60


def text_mutation(data: bytes, rng: random.Random) -> bytes:
    kind = rng.randrange(7)
    n = len(data)
    if n == 0:
        return b"{"
    if kind == 0:  # one byte changed
        i = rng.randrange(n)
        return data[:i] + bytes([rng.randrange(256)]) + data[i + 1:]
    if kind == 1:  # a span deleted
        i = rng.randrange(n)
        return data[:i] + data[i + rng.randrange(1, 64):]
    if kind == 2:  # a span repeated
        i = rng.randrange(n)
        j = min(n, i + rng.randrange(1, 256))
        return data[:j] + data[i:j] + data[j:]
    if kind == 3:  # cut
        return data[:rng.randrange(n)]
    if kind == 4:  # a structural character inserted
        i = rng.randrange(n)
        return data[:i] + rng.choice([b",", b"]", b"[", b"{", b"}", b"\"", b"\n", b"\0", b"\xff", b"-", b"e", b"."]) + data[i:]
    # a number swapped for an extreme one (kinds 5 and 6: the most likely to reach the checks)
    numbers = list(re.finditer(rb"-?\d+(\.\d+)?([eE][-+]?\d+)?", data))
    if not numbers:
        return data + b"1e400"
    m = rng.choice(numbers)
    return data[:m.start()] + rng.choice(EXTREMES).encode() + data[m.end():]


def json_paths(value, path=()):
    yield path
    if isinstance(value, dict):
        for k, v in value.items():
            yield from json_paths(v, path + (k,))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from json_paths(v, path + (i,))


def json_mutation(data: bytes, rng: random.Random) -> bytes:
    doc = json.loads(data)
    paths = [p for p in json_paths(doc) if p]
    path = rng.choice(paths)
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    if rng.random() < 0.25:
        del parent[path[-1]]
    else:
        parent[path[-1]] = rng.choice(JSON_VALUES)
    return json.dumps(doc).encode()


def binary_mutation(data: bytes, rng: random.Random) -> bytes:
    """A TIFF's or an HDF5 file's bytes: their headers at the start, directories also at the end."""
    kind = rng.randrange(4)
    n = len(data)
    b = bytearray(data)
    head = min(n, 512)
    if kind == 0:  # header and directory bytes changed
        for _ in range(rng.randrange(1, 5)):
            b[rng.randrange(head)] = rng.randrange(256)
        # The directory may sit at the end (libtiff writes it after the pixels).
        for _ in range(rng.randrange(0, 4)):
            b[n - 1 - rng.randrange(min(n, 256))] = rng.randrange(256)
        return bytes(b)
    if kind == 1:  # cut
        return data[:rng.randrange(n)]
    if kind == 2:  # a 32-bit field set to its largest value
        i = rng.randrange(0, max(1, n - 4))
        b[i:i + 4] = b"\xff\xff\xff\x7f"
        return bytes(b)
    return bytes(rng.randrange(256) for _ in range(rng.randrange(0, 64)))  # not an image at all


def targets(vendor: bool):
    """(file to damage, mutation, command) — the command reads the file, paths relative to a case;
    files under v/ are the vendor scans (a Nikon folder, an NXtomo file), when they were written."""
    recon = ["reconstruct", "--scan", "s/scan.json", "--geometry", "s/truth-geometry.json", "--out", "out/v.nrrd", "--size", "8",
             "--iterations", "1"]
    geometry = ["geometry", "--scan", "s/scan.json", "--out", "out/g.json"]
    return [
        ("s/scan.json", text_mutation, geometry),
        ("s/scan.json", json_mutation, geometry),
        ("s/scan.json", json_mutation, recon),
        ("s/scan.json", json_mutation, ["calibrate", "--scan", "s/scan.json", "--out", "out/g.json"]),
        ("s/joints.csv", text_mutation, geometry),
        ("s/truth-geometry.json", text_mutation, recon),
        ("s/truth-geometry.json", json_mutation, recon),
        ("s/truth-geometry.json", json_mutation, ["simulate", "--out", "out/sim", "--poses", "s/truth-geometry.json", "--cols", "16",
                                                  "--rows", "16", "--pitch", "27"]),
        ("s/projections/proj_0001.tif", binary_mutation, recon),
        ("s/flat.tif", binary_mutation, recon),
        ("s/dark.tif", binary_mutation, ["calibrate", "--scan", "s/scan.json", "--out", "out/g.json"]),
        ("s/cone_vec.txt", text_mutation, ["import", "cone-vec", "--out", "out/scan.json", "--vectors", "s/cone_vec.txt", "--files",
                                           "s/projections/proj_%04d.tif", "--count", "4", "--kind", "counts", "--flat", "s/flat.tif", "--dark",
                                           "s/dark.tif", "--detector", "48", "48", "--pitch", "9"]),
        ("s/phantom.json", json_mutation, ["simulate", "--out", "out/sim", "--views", "2", "--cols", "16", "--rows", "16", "--pitch",
                                           "27", "--phantom", "s/phantom.json"]),
    ] + ([
        ("v/nikon/ball.xtekct", text_mutation, ["import", "nikon", "--xtekct", "v/nikon/ball.xtekct", "--out", "out/scan.json"]),
        ("v/nxtomo/scan.nx", binary_mutation, ["import", "nxtomo", "--nexus", "v/nxtomo/scan.nx", "--out", "out/nx.json"]),
    ] if vendor else [])


def run_case(ctk: str, base: pathlib.Path, vendor, work: pathlib.Path, index: int, seed: int):
    rng = random.Random(seed * 1_000_003 + index)
    cases = targets(vendor is not None)
    target, mutate, command = cases[index % len(cases)]
    folder = work / f"case-{index:04d}"
    shutil.rmtree(folder, ignore_errors=True)
    shutil.copytree(base, folder / "s")
    if target.startswith("v/"):
        shutil.copytree(vendor, folder / "v")
    (folder / "out").mkdir()
    damaged = folder / target
    original = damaged.read_bytes()
    mutated = original
    while mutated == original:
        mutated = mutate(original, rng)
    damaged.write_bytes(mutated)
    what = f"case {index} ({mutate.__name__} of {target}; ctk {' '.join(command)})"
    try:
        done = subprocess.run([ctk] + command, cwd=folder, capture_output=True, text=True, errors="replace", timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        return folder, what, f"no answer within {TIMEOUT_S} s"
    said = (done.stdout + done.stderr).strip().splitlines()
    last = said[-1] if said else ""
    if done.returncode < 0:
        return folder, what, f"killed by signal {-done.returncode}: {last}"
    if done.returncode not in (0, 2):
        return folder, what, f"exit {done.returncode}: {last}"
    if done.returncode == 2 and pathlib.Path(target).name not in done.stderr:
        return folder, what, f"exit 2 without naming {pathlib.Path(target).name}: {last}"
    return folder, what, None


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("ctk")
    parser.add_argument("--cases", type=int, default=520)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--jobs", type=int, default=os.cpu_count())
    parser.add_argument("--keep", action="store_true", help="keep the case folders (default: only the failing ones)")
    parser.add_argument("--vendor", help="the test tool write_vendor_scans: damage a Nikon folder and an NXtomo file too")
    a = parser.parse_args()
    ctk = str(pathlib.Path(a.ctk).resolve())
    work = pathlib.Path("fuzz-readers").resolve()
    shutil.rmtree(work, ignore_errors=True)
    base = work / "base"
    subprocess.run([ctk, "simulate", "--out", str(base), "--views", "4", "--cols", "48", "--rows", "48", "--pitch", "9", "--phantom",
                    "helix-holder"], check=True, stdout=subprocess.DEVNULL)
    subprocess.run([ctk, "geometry", "--scan", str(base / "scan.json"), "--out", str(work / "nominal.json"), "--astra",
                    str(base / "cone_vec.txt")], check=True, stdout=subprocess.DEVNULL)
    (base / "phantom.json").write_text(json.dumps({"format": "ctk-phantom/1", "primitives": [
        {"type": "sphere", "center_mm": [0, 0, 0], "radius_mm": 20, "attenuation_per_mm": 0.02},
        {"type": "sphere", "center_mm": [5, 0, 10], "radius_mm": 5, "attenuation_per_mm": 0.05}]}))
    vendor = None
    if a.vendor:
        vendor = work / "vendor"
        subprocess.run([a.vendor, "write", str(vendor)], check=True, stdout=subprocess.DEVNULL)
    failures = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=a.jobs) as pool:
        jobs = [pool.submit(run_case, ctk, base, vendor, work, i, a.seed) for i in range(a.cases)]
        for job in jobs:
            folder, what, failure = job.result()
            if failure:
                failures.append(f"{what}: {failure}")
            elif not a.keep:
                shutil.rmtree(folder, ignore_errors=True)
    for f in failures:
        print("FAIL", f)
    print(f"{a.cases} cases (seed {a.seed}), {len(failures)} failed")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
