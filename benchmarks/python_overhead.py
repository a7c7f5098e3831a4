"""The Python binding against C++ in the same process: a forward projection of the standard
problem (256^3, 360 views of 256^2, circular and spherical) called from Python
(`Projector.forward(x, out=y)`) and timed inside C++ on the same arrays, taking turns; and the
peak memory a 1 GiB volume's forward projection adds in Python (nothing but the output should).

    PYTHONPATH=build/python /usr/bin/python3 benchmarks/python_overhead.py [--repeat 5] [--scale 1]

Writes benchmarks/results/python_overhead-<cpu>.json."""
import argparse
import json
import pathlib
import platform
import resource
import statistics
import time

import numpy as np

import ctk
from diagnosis_population import cpu_name, cpu_slug


def overhead(trajectory, scale, repeat):
    p = ctk._ctk._standard_problem(trajectory, 360, scale)
    A = ctk.Projector(p["matrices"], p["volume_shape"], p["voxel_mm"], p["origin_mm"], detector_shape=p["detector_shape"])
    x = np.random.default_rng(1).random(A.volume_shape, dtype=np.float32)
    y = np.empty(A.projection_shape, np.float32)
    A.forward(x, out=y)  # warm: pages, tables, threads
    python, cpp = [], []
    for _ in range(repeat):
        start = time.perf_counter()
        A.forward(x, out=y)
        python.append(time.perf_counter() - start)
        cpp.append(ctk._ctk._time_forward_in_cpp(A, x, y))
    return {"trajectory": trajectory, "python_s": python, "cpp_s": cpp,
            "python_median_s": statistics.median(python), "cpp_median_s": statistics.median(cpp),
            # Each round's two runs are neighbours in time; the median of their ratios discounts drift.
            "ratio": statistics.median(a / b for a, b in zip(python, cpp))}


def peak_rss_bytes():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def memory_of_a_large_forward():
    p = ctk._ctk._standard_problem("spherical", 16, 1)
    shape = (1024, 512, 512)  # 2^28 floats: 1 GiB
    A = ctk.Projector(p["matrices"], shape, 1.0, detector_shape=p["detector_shape"])
    x = np.full(shape, 0.01, np.float32)  # every page touched before measuring
    before = peak_rss_bytes()
    start = time.perf_counter()
    y = A.forward(x)
    seconds = time.perf_counter() - start
    added = peak_rss_bytes() - before
    return {"volume_bytes": x.nbytes, "output_bytes": y.nbytes, "peak_rss_added_bytes": added, "seconds": seconds,
            "added_over_output_plus_5_percent_of_volume": added / (y.nbytes + 0.05 * x.nbytes)}


def main():
    a = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    a.add_argument("--repeat", type=int, default=5)
    a.add_argument("--scale", type=int, default=1)
    a.add_argument("--out", type=pathlib.Path)
    o = a.parse_args()
    memory = memory_of_a_large_forward()
    runs = [overhead(t, o.scale, o.repeat) for t in ("circular", "spherical")]
    for r in runs:
        print(f"{r['trajectory']}: Python {r['python_median_s']:.4f} s, C++ {r['cpp_median_s']:.4f} s, median ratio of the rounds {r['ratio']:.4f}")
    print(f"1 GiB volume forward: peak memory +{memory['peak_rss_added_bytes'] / 2**20:.1f} MiB "
          f"(output {memory['output_bytes'] / 2**20:.1f} MiB), {memory['seconds']:.2f} s")
    result = {"benchmark": "python_overhead", "cpu": cpu_name(), "machine": platform.machine(), "scale": o.scale,
              "repeat": o.repeat, "forward": runs, "memory": memory, "ctk_version": ctk.__version__}
    out = o.out or pathlib.Path(__file__).parent / "results" / (
        "python_overhead-" + cpu_slug() + ".json")
    out.write_text(json.dumps(result, indent=2) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
