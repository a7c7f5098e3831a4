"""How soon Ctrl-C stops a computation started from Python: a forward and a back projection of
the standard problem (circular, 256^3, 360 views of 256^2) and a WLS-CG solve on it, each
interrupted at several fractions of its uninterrupted time measured in the same process. The
figure is the delay from the signal to the KeyboardInterrupt, also as a fraction of the whole call.

    PYTHONPATH=build/python /usr/bin/python3 benchmarks/python_interrupt.py [--scale 1]

Writes benchmarks/results/python_interrupt-<cpu>.json."""
import argparse
import json
import os
import pathlib
import platform
import signal
import threading
import time

import numpy as np

import ctk
from diagnosis_population import cpu_name, cpu_slug


def timed(call):
    start = time.perf_counter()
    call()
    return time.perf_counter() - start


def late(delay, call):
    """Seconds from a SIGINT sent `delay` s into `call` to the KeyboardInterrupt it raises."""
    timer = threading.Timer(delay, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.perf_counter()
    timer.start()
    try:
        call()
        raise RuntimeError("the call finished before it was interrupted")
    except KeyboardInterrupt:
        pass
    timer.join()
    return time.perf_counter() - start - delay


def main():
    a = argparse.ArgumentParser()
    a.add_argument("--scale", type=int, default=1)
    o = a.parse_args()
    p = ctk._ctk._standard_problem("circular", 360, o.scale)
    A = ctk.Projector(p["matrices"], p["volume_shape"], p["voxel_mm"], p["origin_mm"], detector_shape=p["detector_shape"])
    x = np.random.default_rng(1).random(A.volume_shape, dtype=np.float32)
    y = A.forward(x)  # warm
    calls = {"forward": lambda: A.forward(x), "back": lambda: A.adjoint(y),
             "wls_cg_20_iterations": lambda: ctk.wls_cg(A, y, iterations=20)}
    result = {"benchmark": "python_interrupt", "cpu": cpu_name(), "machine": platform.machine(), "scale": o.scale,
              "volume_shape": list(A.volume_shape), "projection_shape": list(A.projection_shape), "calls": {}}
    for name, call in calls.items():
        # The solve's own length is far beyond what is needed: interrupt at fractions of one projection pair.
        whole = timed(call) if name != "wls_cg_20_iterations" else 2 * timed(calls["forward"])
        rows = []
        for fraction in (0.1, 0.3, 0.6, 0.9):
            d = late(fraction * whole, call)
            rows.append({"at_seconds": fraction * whole, "stopped_after_seconds": d, "fraction_of_call": d / whole})
            print(f"{name:22s} whole {whole:6.2f} s, Ctrl-C at {fraction * whole:5.2f} s: stopped {d * 1000:7.1f} ms later")
        result["calls"][name] = {"uninterrupted_seconds": whole, "interrupted": rows}
    out = pathlib.Path(__file__).parent / "results" / (
        "python_interrupt-" + cpu_slug() + ".json")
    out.write_text(json.dumps(result, indent=2) + "\n")
    print("written", out)


if __name__ == "__main__":
    main()
