"""Reconstruction spread over MPI ranks: the scaling model of docs/distributed.md, checked on this
machine and extrapolated to clusters.

Measured here: WLS-CG on a simulated circular scan, once as one process with every core, once
over as many ranks as cores (one thread each), with mpirun. From the one-process run comes the
throughput R (voxel-views per second and core, forward and back projection together); from the
spread run the bytes each rank summed per iteration (counted by ctk) against the plan's model,
and its time per iteration against the model's prediction for this machine (ranks on one machine
share memory, so the sum's time is small here: it is measured, not modelled).

Slabs: the same scan reconstructed into a larger volume (--slab-size) on 1, 2 and 4 ranks split
into slabs: every rank's peak resident memory (the largest should fall about as 1/N above what a
process holds anyway), and the rows the first rank exchanges per iteration, counted, against
the cone's spread on paper (a slab boundary at height z seen from depths -r .. r lands on rows
z SDD / (SOD + r) .. z SDD / (SOD - r), widened by a voxel each side for the interpolation).

Then the model, for views split over nodes (each holding the whole volume) and slabs of the
volume (each node its slab and the detector rows it projects to), on 1 to 64 nodes of stated
cores and memory joined by a stated network:

    time per iteration = 2 n^3 views / (nodes cores R) + sum time
    sum time (views split) = 2 (nodes - 1) / nodes  4 n^3 bytes / bandwidth + 2 (nodes - 1) latency   (ring all-reduce)

    python3 benchmarks/mpi_scaling.py --ctk build/tools/ctk [--mpirun mpirun] [--size 128 --views 180]
"""
import argparse
import json
import math
import os
import pathlib
import statistics
import subprocess
import tempfile

from diagnosis_population import cpu_name, cpu_slug

GIB = 1 << 30
SOD_MM, SDD_MM = 1360.0, 2150.0  # ctk simulate's reference setup


def per_iteration_seconds(log):
    return statistics.median(i["seconds"] for i in log["solver"]["iterations"][1:])


def ring_sum_seconds(nodes, volume_bytes, bandwidth_bytes_per_s, latency_s):
    if nodes == 1:
        return 0.0
    return 2 * (nodes - 1) / nodes * volume_bytes / bandwidth_bytes_per_s + 2 * (nodes - 1) * latency_s


def cg_memory_bytes(n, views, rows, volumes_fraction=1.0, views_fraction=1.0):
    """WLS-CG with weights: 4 volumes and 4 stacks (memory_plan.hpp), scaled to one node's share."""
    return 4 * 4 * n ** 3 * volumes_fraction + 4 * 4 * views * views_fraction * rows * n


def slab_band_rows(n, nodes, magnification_spread):
    """Detector rows the widest slab projects to: its own height plus the cone's spread at the
    volume's top or bottom (rows at height z project between z M_near and z M_far)."""
    return min(n, n / nodes + 0.5 * n * magnification_spread)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--ctk", required=True)
    p.add_argument("--mpirun", default="mpirun")
    p.add_argument("--size", type=int, default=128, help="voxels per side of the measured run")
    p.add_argument("--views", type=int, default=180)
    p.add_argument("--iterations", type=int, default=6)
    p.add_argument("--slab-size", type=int, default=288, help="voxels per side of the slab runs")
    p.add_argument("--node-cores", type=int, default=64, help="cores of a cluster node in the model")
    p.add_argument("--node-memory-gib", type=float, default=512)
    p.add_argument("--network-gbit", type=float, default=25.0)
    p.add_argument("--latency-us", type=float, default=5.0)
    p.add_argument("--out", help="JSON to write (default: benchmarks/results/mpi_scaling-<cpu>.json)")
    a = p.parse_args()
    cores = os.cpu_count() or 1
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    with tempfile.TemporaryDirectory() as work:
        work = pathlib.Path(work)
        detector = a.size + a.size // 2
        subprocess.run([a.ctk, "simulate", "--out", work / "scan", "--phantom", "shepp-logan", "--trajectory", "circular", "--views",
                        str(a.views), "--cols", str(detector), "--rows", str(detector), "--pitch", str(0.6 * 720 / detector),
                        "--sod", str(SOD_MM), "--sdd", str(SDD_MM)],
                       check=True, capture_output=True)
        args = ["reconstruct", "--scan", str(work / "scan" / "scan.json"), "--geometry", str(work / "scan" / "truth-geometry.json"),
                "--size", str(a.size), "--iterations", str(a.iterations), "--tolerance", "0"]
        subprocess.run([a.ctk, *args, "--out", str(work / "one.nrrd")], check=True, capture_output=True,
                       env=dict(env, OMP_NUM_THREADS=str(cores)))
        subprocess.run([a.mpirun, "--oversubscribe", "-np", str(cores), a.ctk, *args, "--out", str(work / "spread.nrrd")],
                       check=True, capture_output=True, env=dict(env, OMP_NUM_THREADS="1"))
        one = json.loads((work / "one.log.json").read_text())
        spread = json.loads((work / "spread.log.json").read_text())
        views_used = len(one["views_used"])
        # The same field of view in finer voxels.
        voxel = one["volume"]["voxel_mm"] * a.size / a.slab_size
        slab_args = args[:args.index("--size")] + ["--size", str(a.slab_size), "--voxel", str(voxel), "--iterations", "2",
                                                   "--tolerance", "0", "--decomposition", "slabs"]
        slab_runs = []
        for n in (1, 2, 4):
            out = work / f"slabs-{n}.nrrd"
            subprocess.run([a.mpirun, "--oversubscribe", "-np", str(n), a.ctk, *slab_args, "--out", str(out)], check=True,
                           capture_output=True, env=dict(env, OMP_NUM_THREADS="1"))
            log = json.loads(out.with_suffix(".log.json").read_text())
            peaks = log["peak_resident_bytes_per_rank"]
            slab_runs.append({"ranks": n, "peak_resident_bytes_per_rank": peaks, "largest_peak_gib": max(peaks) / GIB,
                              "memory_plan": log["memory_plan"],
                              "bytes_per_iteration": log.get("distribution", {}).get("bytes_per_iteration", 0)})
        scan = json.loads((work / "scan" / "scan.json").read_text())
    t_one = per_iteration_seconds(one)
    t_spread = per_iteration_seconds(spread)
    work_per_iteration = 2 * a.size ** 3 * views_used  # voxel-views, forward and back
    throughput_per_core = work_per_iteration / t_one / cores
    counted = spread["distribution"]["bytes_per_iteration"]
    modelled = spread["distribution"]["model_bytes_per_iteration"]
    measured = {
        "scan": {"volume": a.size, "views": views_used, "detector": detector, "iterations": a.iterations},
        "cores": cores,
        "one_process_seconds_per_iteration": t_one,
        "throughput_voxel_views_per_s_per_core": throughput_per_core,
        "ranks": cores,
        "spread_seconds_per_iteration": t_spread,
        "spread_predicted_compute_seconds_per_iteration": work_per_iteration / (cores * throughput_per_core),
        "summed_bytes_per_iteration_counted": counted,
        "summed_bytes_per_iteration_model": modelled,
    }
    # The first slab's boundary on paper (circular scan about z: every view sees it alike).
    pitch = scan["detector"]["pixel_pitch_mm"][1]
    sod, sdd = SOD_MM, SDD_MM
    for run in slab_runs:
        n = run["ranks"]
        if n == 1:
            run["paper_bytes_per_iteration"] = 0
            continue
        planes = -(-a.slab_size // n)  # the first rank's
        boundary = (planes - a.slab_size / 2) * voxel  # mm above the centre
        r = a.slab_size / 2 * voxel * math.sqrt(2)  # the volume's half diagonal across the beam
        top, bottom = abs(boundary) + voxel, abs(boundary) - voxel
        rows = (top * sdd / (sod - r) - bottom * sdd / (sod + r)) / pitch + 3  # the footprints' margins
        run["paper_bytes_per_iteration"] = rows * detector * views_used * 4
    print("slabs (%d^3, %d views of %d^2): " % (a.slab_size, views_used, detector) + "; ".join(
        f"{run['ranks']} ranks: largest peak {run['largest_peak_gib']:.3f} GiB, exchanged {run['bytes_per_iteration']} bytes per "
        f"iteration (paper {run['paper_bytes_per_iteration']:.0f})" for run in slab_runs))
    print(f"this machine ({cpu_name()}, {cores} cores): one process {t_one:.3f} s per iteration, "
          f"{throughput_per_core / 1e9:.3f} G voxel-views/s per core; over {cores} ranks {t_spread:.3f} s "
          f"(compute predicted {measured['spread_predicted_compute_seconds_per_iteration']:.3f} s); "
          f"summed per iteration {counted} bytes counted, {modelled} modelled")

    bandwidth = a.network_gbit * 1e9 / 8
    latency = a.latency_us * 1e-6
    node_rate = a.node_cores * throughput_per_core
    # The reference setup's cone: source 1360 mm from the axis, the volume's diameter about 160 mm.
    magnification_spread = 160 / 1360
    predictions = []
    for n in (1024, 2048, 4096):
        views = round(math.pi / 2 * n)  # angular sampling of a circle at the detector's resolution
        compute_one = 2 * n ** 3 * views / node_rate
        for nodes in (1, 2, 4, 8, 16, 32, 64):
            view_memory = cg_memory_bytes(n, views, n, 1.0, 1.0 / nodes)
            view_time = compute_one / nodes + ring_sum_seconds(nodes, 4 * n ** 3, bandwidth, latency)
            band = slab_band_rows(n, nodes, magnification_spread)
            slab_memory = cg_memory_bytes(n, views, band, 1.0 / nodes, 1.0)
            # Rows shared with neighbours are summed forward and handed back for the adjoint.
            shared_rows = max(0.0, band - n / nodes) if nodes > 1 else 0.0
            slab_bytes = 2 * shared_rows * n * views * 4
            slab_time = compute_one / nodes + slab_bytes / bandwidth
            fits = view_memory <= a.node_memory_gib * GIB
            predictions.append({
                "n": n, "views": views, "nodes": nodes,
                "views_split": {"memory_per_node_gib": view_memory / GIB, "seconds_per_iteration": view_time,
                                "fits": fits, "speedup": compute_one / view_time},
                "slabs": {"memory_per_node_gib": slab_memory / GIB, "seconds_per_iteration": slab_time,
                                     "bytes_per_iteration": slab_bytes, "speedup": compute_one / slab_time},
                "picked": "views" if fits else "slabs",
            })
    print(f"\nmodel: nodes of {a.node_cores} cores at the throughput measured here, {a.node_memory_gib:g} GiB, "
          f"{a.network_gbit:g} Gbit/s, {a.latency_us:g} us; WLS-CG with weights")
    print(f"{'n':>5} {'views':>5} {'nodes':>5} | {'views split: GiB/node':>21} {'s/iter':>8} {'speedup':>7} | "
          f"{'slabs: GiB/node':>23} {'s/iter':>8} {'speedup':>7} | picked")
    for r in predictions:
        v, s = r["views_split"], r["slabs"]
        print(f"{r['n']:>5} {r['views']:>5} {r['nodes']:>5} | {v['memory_per_node_gib']:>21.1f} {v['seconds_per_iteration']:>8.2f} "
              f"{v['speedup']:>7.1f} | {s['memory_per_node_gib']:>23.1f} {s['seconds_per_iteration']:>8.2f} {s['speedup']:>7.1f} | "
              f"{r['picked']}")
    cpu = cpu_name()
    out = pathlib.Path(a.out) if a.out else pathlib.Path(__file__).parent / "results" / (
        "mpi_scaling-" + cpu_slug() + ".json")
    measured["slabs"] = slab_runs
    out.write_text(json.dumps({"benchmark": "mpi_scaling", "cpu": cpu, "measured": measured,
                               "model": {"node_cores": a.node_cores, "node_memory_gib": a.node_memory_gib,
                                         "network_gbit_per_s": a.network_gbit, "latency_us": a.latency_us,
                                         "magnification_spread": magnification_spread},
                               "predictions": predictions}, indent=1) + "\n")
    print(f"\nwritten to {out}")


if __name__ == "__main__":
    main()
