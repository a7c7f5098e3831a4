#!/usr/bin/env python3
"""An independent yardstick for `ctk bench`, outside the project's code: Python's standard
library only, its own arithmetic in double precision, and its own clock.

It repeats the benchmark's checks:
  1. line integrals: Joseph's method written here from its definition (a ray from the source
     through each pixel centre, marched slice by slice along its dominant axis, bilinear in the
     other two, zero outside the volume, weighted by the path length per slice) on random pixels
     of every dumped view, against the fast projector's forward projection;
  2. the back projection at random voxels: the same sums taken the other way (every ray whose
     sample touches the voxel), against the fast projector's back projection;
  3. adjointness: <A x, y> against <x, A' y> from the dumped arrays;
  1-3 on two sets of views per trajectory: the reference's (spread evenly) and 16 neighbouring
     views of the 360-view trajectory, which the fast back projection takes through its bands
     (the reference's take them only in part: circular ones 180 degrees apart, spherical ones not);
  4. timing: two runs of `ctk bench` with N/2 and N views (the reference on the same single view
     in both); the growth of the wall clock, measured here, is compared with the growth of the
     fast projector's own reported seconds. The reference's time cancels out, but only as far
     as it repeats: on a shared 2-core machine its 12 views took 12.6 to 19.7 s in four
     identical runs, enough to move the ratio by 0.4, so these runs give it one view.
  5. repeated runs (`--repeat 3`, the checking run): every reported time is the median of its
     three runs, and all the runs together fit in the wall clock measured here.

Usage: benchmarks/yardstick.py --ctk build/tools/ctk [--scale 1] [--views 360] [--no-timing]
Exits non-zero when a check fails.
"""
import argparse
import array
import json
import math
import os
import random
import subprocess
import sys
import tempfile
import time


def inverse3(m):
    a, b, c = m[0]
    d, e, f = m[1]
    g, h, i = m[2]
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    return [[(e * i - f * h) / det, (c * h - b * i) / det, (b * f - c * e) / det],
            [(f * g - d * i) / det, (a * i - c * g) / det, (c * d - a * f) / det],
            [(d * h - e * g) / det, (b * g - a * h) / det, (a * e - b * d) / det]]


def times(m, v):
    return [sum(m[r][k] * v[k] for k in range(3)) for r in range(3)]


class View:
    """One 3x4 matrix: the source and each pixel's ray, in voxel-index coordinates."""

    def __init__(self, P, volume):
        self.M = [row[:3] for row in P]
        self.Minv = inverse3(self.M)
        source_mm = [-x for x in times(self.Minv, [row[3] for row in P])]
        self.voxel = volume["voxel_mm"]
        self.origin = volume["origin_mm"]
        self.size = volume["size"]
        self.source = [(source_mm[i] - self.origin[i]) / self.voxel[i] for i in range(3)]

    def ray(self, u, v):
        d_mm = times(self.Minv, [u, v, 1.0])
        d = [d_mm[i] / self.voxel[i] for i in range(3)]
        a = max(range(3), key=lambda i: abs(d[i]))
        step_mm = math.sqrt(sum(x * x for x in d_mm)) / abs(d[a])  # path length per slice
        return d, a, step_mm

    def sample(self, d, a, k):
        """(b, c, position along b, position along c) of the ray's sample at slice k, or None
        behind the source."""
        t = (k - self.source[a]) / d[a]
        if t <= 0:
            return None
        b, c = [i for i in range(3) if i != a]
        return b, c, self.source[b] + t * d[b], self.source[c] + t * d[c]


def index(size, ijk):
    return ijk[0] + size[0] * (ijk[1] + size[1] * ijk[2])


def line_integral(view, x, u, v):
    d, a, step_mm = view.ray(u, v)
    size = view.size
    total = 0.0
    for k in range(size[a]):
        s = view.sample(d, a, k)
        if s is None:
            continue
        b, c, pb, pc = s
        ib, ic = math.floor(pb), math.floor(pc)
        fb, fc = pb - ib, pc - ic
        for db, wb in ((0, 1 - fb), (1, fb)):
            for dc, wc in ((0, 1 - fc), (1, fc)):
                jb, jc = ib + db, ic + dc
                if 0 <= jb < size[b] and 0 <= jc < size[c]:
                    ijk = [0, 0, 0]
                    ijk[a], ijk[b], ijk[c] = k, jb, jc
                    total += step_mm * wb * wc * x[index(size, ijk)]
    return total


def back_at_voxel(view, y_view, cols, rows, ijk):
    """Sum over the rays whose sample touches voxel ijk of weight x y: the pixels around the
    voxel's projection (a corner is within one voxel of a sample, about a pixel here)."""
    # The voxel centre's pixel: M (X - source) ~ (u, v, 1), X - source in mm.
    w = times(view.M, [(ijk[i] - view.source[i]) * view.voxel[i] for i in range(3)])
    if w[2] <= 0:
        return 0.0
    u0, v0 = w[0] / w[2], w[1] / w[2]
    total = 0.0
    reach = 4
    for v in range(max(0, math.floor(v0) - reach), min(rows, math.floor(v0) + reach + 2)):
        for u in range(max(0, math.floor(u0) - reach), min(cols, math.floor(u0) + reach + 2)):
            d, a, step_mm = view.ray(u, v)
            s = view.sample(d, a, ijk[a])
            if s is None:
                continue
            b, c, pb, pc = s
            wb = 1 - abs(pb - ijk[b])
            wc = 1 - abs(pc - ijk[c])
            if wb > 0 and wc > 0:
                total += step_mm * wb * wc * y_view[v * cols + u]
    return total


def relative(values, truths):
    num = math.fsum((f - r) ** 2 for f, r in zip(values, truths))
    den = math.fsum(r * r for r in truths)
    return math.sqrt(num / den) if den > 0 else math.sqrt(num)


def load(folder, name, count):
    a = array.array("f")
    with open(os.path.join(folder, name), "rb") as f:
        a.frombytes(f.read())
    if sys.byteorder != "little":
        a.byteswap()
    if len(a) != count:
        raise SystemExit(f"{folder}/{name}: {len(a)} floats, expected {count}")
    return a


def check_dump(folder, rays_per_view, voxels, rng):
    m = json.load(open(os.path.join(folder, "manifest.json")))
    if m.get("format") != "ctk-bench-dump/1":
        raise SystemExit(f"{folder}/manifest.json: format {m.get('format')!r}, expected ctk-bench-dump/1")
    vol, det = m["volume"], m["detector"]
    n = vol["size"][0] * vol["size"][1] * vol["size"][2]
    cols, rows, views = det["cols"], det["rows"], len(m["matrices"])
    x = load(folder, m["files"]["x"], n)
    y = load(folder, m["files"]["y"], views * rows * cols)
    Ax = load(folder, m["files"]["forward"], views * rows * cols)
    Aty = load(folder, m["files"]["back"], n)
    view_list = [View(P, vol) for P in m["matrices"]]

    fast, mine = [], []
    for vi, view in enumerate(view_list):
        for _ in range(rays_per_view):
            u, v = rng.randrange(cols), rng.randrange(rows)
            fast.append(Ax[(vi * rows + v) * cols + u])
            mine.append(line_integral(view, x, u, v))
    forward_diff = relative(fast, mine)

    fast, mine = [], []
    y_views = [y[vi * rows * cols:(vi + 1) * rows * cols] for vi in range(views)]
    for _ in range(voxels):
        ijk = [rng.randrange(s) for s in vol["size"]]
        fast.append(Aty[index(vol["size"], ijk)])
        mine.append(math.fsum(back_at_voxel(view, y_view, cols, rows, ijk) for view, y_view in zip(view_list, y_views)))
    back_diff = relative(fast, mine)

    lhs = math.fsum(a * b for a, b in zip(Ax, y))
    rhs = math.fsum(a * b for a, b in zip(x, Aty))
    norm = math.sqrt(math.fsum(a * a for a in Ax)) * math.sqrt(math.fsum(b * b for b in y))
    adjoint = abs(lhs - rhs) / norm
    return {"trajectory": m["trajectory"], "views": views, "forward_rel_diff": forward_diff,
            "back_rel_diff": back_diff, "adjointness": adjoint, "rays_checked": views * rays_per_view,
            "voxels_checked": voxels}


def this_cpu():
    """The first processor's model name, family and model, read here (figures name their machine)."""
    cpu = {}
    with open("/proc/cpuinfo") as info:
        for line in info:
            if not line.strip():
                break
            key, _, value = line.partition(":")
            key, value = key.strip(), value.strip()
            if key == "model name":
                cpu["model_name"] = value
            elif key == "cpu family":
                cpu["family"] = int(value)
            elif key == "model":
                cpu["model"] = int(value)
    return cpu


def run_bench(ctk, args, reference_views, extra):
    cmd = [ctk, "bench", "--json", "--scale", str(args.scale), "--reference-views", str(reference_views)] + extra
    start = time.monotonic()
    out = subprocess.run(cmd, check=True, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True).stdout
    return time.monotonic() - start, json.loads(out)


def measurements(result):
    """(trajectory, direction, figures) for each of the four measurements in a report: circular
    at the top level, spherical beside it."""
    for name, section in (("circular", result), ("spherical", result["spherical"])):
        for d in ("forward", "back"):
            yield name, d, section[d]


TIMING_REFERENCE_VIEWS = 1  # the timing runs' reference: as little of its variation as possible (check 4)
REPEAT = 3  # runs of each projector in the checking run (odd: the median is one of them)


def check_repeats(result):
    """Whether each reported time is the median of its REPEAT reported runs; and all runs'
    seconds (the reference's as measured, not scaled to every view)."""
    ok, total = True, 0.0
    for _, _, s in measurements(result):
        fast, ref = s["fast_seconds_runs"], s["reference_seconds_runs"]
        ok &= len(fast) == REPEAT and len(ref) == REPEAT
        middle = REPEAT // 2
        ok &= sorted(fast)[middle] == s["fast_seconds"] and sorted(ref)[middle] == s["reference_seconds"]
        scale = s["reference_seconds_measured"] / s["reference_seconds"]
        total += sum(fast) + scale * sum(ref)
    return ok, total


def fast_seconds(result):
    return sum(s["fast_seconds"] for _, _, s in measurements(result))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--ctk", required=True, help="the ctk binary")
    p.add_argument("--scale", type=int, default=1, help="as ctk bench --scale (1: the standard problem)")
    p.add_argument("--views", type=int, default=360, help="views of the larger timing run")
    p.add_argument("--reference-views", type=int, default=12, help="views the reference runs on, and the dump holds")
    p.add_argument("--rays", type=int, default=40, help="random pixels checked per dumped view")
    p.add_argument("--voxels", type=int, default=40, help="random voxels checked in each back projection")
    p.add_argument("--no-timing", action="store_true", help="only the numerical checks (one short run)")
    p.add_argument("--tolerance", type=float, default=1e-5, help="bound on the relative differences and adjointness")
    p.add_argument("--seed", type=int, default=1)
    args = p.parse_args()
    rng = random.Random(args.seed)
    failed = False

    with tempfile.TemporaryDirectory(prefix="ctk-yardstick-") as dump:
        wall, reported = run_bench(args.ctk, args, args.reference_views, ["--views", str(args.reference_views), "--dump", dump, "--repeat", str(REPEAT)])
        ok, timed = check_repeats(reported)
        ok = ok and timed <= wall
        failed |= not ok
        print(f"repeats: medians of {REPEAT} runs each, {timed:.2f} s of runs in {wall:.2f} s of wall clock  {'ok' if ok else 'FAILED'}")
        here = this_cpu()
        ok = reported.get("cpu") == here
        failed |= not ok
        print(f"machine: the report names {reported.get('cpu')}, /proc/cpuinfo says {here}  {'ok' if ok else 'FAILED'}")
        # Each trajectory's reference views, and its neighbouring views (a back projection
        # through bands, which views spread as evenly as the reference's take only in part).
        for folder in ("circular", "spherical", "circular-neighbours", "spherical-neighbours"):
            r = check_dump(os.path.join(dump, folder), args.rays, args.voxels, rng)
            ok = max(r["forward_rel_diff"], r["back_rel_diff"], r["adjointness"]) <= args.tolerance
            failed |= not ok
            print(f"{folder:20s} {r['views']:2d} views: forward vs own Joseph {r['forward_rel_diff']:.2e} "
                  f"({r['rays_checked']} rays), back vs own sums {r['back_rel_diff']:.2e} ({r['voxels_checked']} voxels), "
                  f"adjointness {r['adjointness']:.2e}  {'ok' if ok else 'FAILED'} (bound {args.tolerance:g})")

    if not args.no_timing:
        half = args.views // 2
        wall_half, res_half = run_bench(args.ctk, args, TIMING_REFERENCE_VIEWS, ["--views", str(half)])
        wall_full, res_full = run_bench(args.ctk, args, TIMING_REFERENCE_VIEWS, ["--views", str(args.views)])
        grown_wall = wall_full - wall_half
        grown_fast = fast_seconds(res_full) - fast_seconds(res_half)
        n = res_full["problem"]["volume"]
        voxel_views = n[0] * n[1] * n[2] * (args.views - half) * 4  # 2 trajectories x 2 directions
        ratio = grown_wall / grown_fast
        # The extra views add only fast projection (and filling their projections with numbers);
        # the wall clock may run a little ahead of the projector's own stopwatch, never behind it.
        ok = 0.9 <= ratio <= 1.3
        failed |= not ok
        print(f"timing: {half} -> {args.views} views added {grown_wall:.2f} s of wall clock (measured here) and "
              f"{grown_fast:.2f} s of reported fast projection: ratio {ratio:.2f} {'ok' if ok else 'FAILED'} (0.9 to 1.3)")
        print(f"  fast projector, all four runs together, by this clock: {voxel_views / grown_wall:.3g} voxel-views/s; "
              f"by its own: {voxel_views / grown_fast:.3g}")
        for name, d, s in measurements(res_full):
            print(f"  {name:9s} {d:7s} reported {s['voxel_views_per_s']:.3g} voxel-views/s, {s['speedup']:.1f}x the reference "
                  f"(timed on {s['reference_views_measured']} view)")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
