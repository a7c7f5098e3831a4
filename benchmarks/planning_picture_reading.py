#!/usr/bin/python3
"""How the planner reads its picture of the sample, compared by its rule alone on pictures it
really reads.

The planner draws from a coarse reconstruction of the views so far: few CG iterations on binned
views, noisy and streaked. `ctk.plan_on_picture` draws by the same rule from a picture given once,
so readings of a picture can be compared without acquiring anything (as planning_rule_settings.py
compares settings). Per sample, from its planned run through the simulated lab (`--lab`, a
planning_population.py work folder holding sample-N/planned): three pictures the planner read or
would have read, each on its coarse grid,
  own     the run's last coarse reconstruction (coarse.nrrd),
  scout   the pool's views nearest the planned trajectory's first 24 (the scout), reconstructed,
  half    the same from its first 50 views,
and each read three ways: as it is (picture_median False), through a Gaussian of one voxel
(scipy, then as it is) and through the library's 3^3 median (picture_median True, the default).
The rule draws `--draws` trajectories from each (seeds 1, 2, ...) and from the truth (the bound);
each is mapped to the pool's nearest views, reconstructed and scored as the oracle scores (the
RMSE with each material at its own level over the sample region), as a gain over the whole sphere.

The choice rule, fixed before the runs: the reading with the highest mean gain (over samples, of
each sample's mean over its three pictures) whose paired difference to reading the picture as it
is has its 95 % bootstrap interval above zero; none: as it is. A reading chosen here is then
measured with the real planner through the simulated lab on seeds it was not chosen on
(`planning_population.py --against`).

  PYTHONPATH=build/python /usr/bin/python3 benchmarks/planning_picture_reading.py --ctk build/tools/ctk \\
      --lab /tmp/plan-even --work /tmp/plan-oracle --seeds 2 4 6 8 10 12
"""

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy import ndimage

sys.path.insert(0, str(Path(__file__).resolve().parent))
from diagnosis_population import cpu_name, cpu_slug  # noqa: E402
from planning_oracle import (ITERATIONS, PENALTY, TRUTH_READING, coarse_grid, nearest_pool_views,  # noqa: E402
                             planner_settings, random_sample_on_pool, rule_gains, truth_picture)
from planning_population import bootstrap_interval  # noqa: E402

import ctk  # noqa: E402

PICTURES = {"scout": 24, "half": 50}  # views of the planned trajectory a pool picture is made from
READINGS = ("as-it-is", "gaussian-1-voxel", "median-3")


def pool_picture(proxy, pool, directions):
    """The pool's views nearest `directions` reconstructed on the planner's coarse grid, as the
    proxy reconstructs (WLS-CG, gradient penalty)."""
    n, voxel, origin = coarse_grid()
    members = nearest_pool_views(directions, pool)
    projector = ctk.Projector(proxy.P[members], (n, n, n), voxel, origin, detector_shape=proxy.detector_shape)
    return ctk.wls_cg(projector, proxy.b[members], weights=proxy.w[members], iterations=ITERATIONS, tolerance=0.0,
                      lambda_=PENALTY, regulariser="gradient").x


def readings_of(picture):
    """Each reading: the picture handed over and whether the library reads it through its median."""
    return {"as-it-is": (picture, False), "gaussian-1-voxel": (ndimage.gaussian_filter(picture, 1.0), False),
            "median-3": (picture, True)}


def one_sample(ctk_bin, work, lab, seed, views, draws, log):
    start = time.time()
    sample_file, pool, proxy, whole = random_sample_on_pool(ctk_bin, work, seed, views)
    planned = lab / f"sample-{seed}" / "planned"
    own, _ = ctk.read_volume(planned / "coarse.nrrd")
    trajectory = json.loads((planned / "trajectory.json").read_text())
    directions = [v["direction_holder"] for v in trajectory["views"] if v.get("calibrated")]
    pictures = {"own": own, **{name: pool_picture(proxy, pool, directions[:k]) for name, k in PICTURES.items()}}
    gains = {"truth": rule_gains(proxy, truth_picture(sample_file), pool, views, whole, draws, **TRUTH_READING)}
    for name, picture in pictures.items():
        for reading, (given, median) in readings_of(np.ascontiguousarray(picture, dtype=np.float32)).items():
            gains[f"{name}/{reading}"] = rule_gains(proxy, given, pool, views, whole, draws, picture_median=median)
    for key, g in gains.items():
        log(f"seed {seed} {key:24s} {100 * np.mean(g):+.2f} % ({', '.join(f'{100 * x:+.1f}' for x in g)})")
    return {"seed": seed, "proxy_score_whole_sphere_per_mm": whole, "gains": gains, "seconds": time.time() - start}


def summary(cases):
    """Per reading the mean gain over samples (each sample's mean over its pictures) and its paired
    difference to reading as it is; the rule's choice."""
    rng = np.random.default_rng(0)

    def per_sample(reading):
        return [float(np.mean([np.mean(c["gains"][f"{p}/{reading}"]) for p in ("own", *PICTURES)])) for c in cases]

    plain = per_sample("as-it-is")
    out = {"truth": {"mean_gain": float(np.mean([np.mean(c["gains"]["truth"]) for c in cases]))}}
    for reading in READINGS:
        values = per_sample(reading)
        difference = np.subtract(values, plain)
        out[reading] = {"mean_gain": float(np.mean(values)), "interval_95": bootstrap_interval(values, rng),
                        "per_sample": values, "difference_to_as_it_is": float(np.mean(difference)),
                        "difference_interval_95": bootstrap_interval(difference, rng),
                        "better_than_as_it_is_on": int(np.sum(difference > 0))}
    beyond = [r for r in READINGS[1:] if out[r]["difference_interval_95"][0] > 0]
    chosen = max(beyond, key=lambda r: out[r]["mean_gain"]) if beyond else "as-it-is"
    return {"readings": out, "chosen": chosen, "samples": len(cases)}


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--ctk", required=True)
    p.add_argument("--lab", type=Path, required=True, help="planning_population.py's work folder (sample-N/planned)")
    p.add_argument("--work", type=Path, default=Path("/tmp/plan-oracle"), help="the pools (seed-N), made when missing")
    p.add_argument("--seeds", type=int, nargs="+", default=list(range(2, 13, 2)))
    p.add_argument("--views", type=int, default=100)
    p.add_argument("--draws", type=int, default=4, help="trajectories drawn per picture and reading (seeds 1, 2, ...)")
    p.add_argument("--out", type=Path)
    a = p.parse_args()
    out = a.out or Path(__file__).resolve().parent / "results" / f"planning_picture_reading-{cpu_slug()}.json"
    cases = []
    for seed in a.seeds:
        cases.append(one_sample(a.ctk, a.work / f"seed-{seed}", a.lab, seed, a.views, a.draws,
                                lambda line: print(line, flush=True)))
        result = {"cpu": cpu_name(), "command": " ".join(sys.argv), "views": a.views, "draws": a.draws,
                  "planner": planner_settings(), "cases": cases, "summary": summary(cases)}
        out.write_text(json.dumps(result, indent=1) + "\n")
    s = result["summary"]["readings"]
    print(f"truth            gain {100 * s['truth']['mean_gain']:+.2f} %")
    for reading in READINGS:
        r = s[reading]
        print(f"{reading:16s} gain {100 * r['mean_gain']:+.2f} % [{100 * r['interval_95'][0]:+.2f}, "
              f"{100 * r['interval_95'][1]:+.2f}]; less as it is {100 * r['difference_to_as_it_is']:+.2f} points "
              f"[{100 * r['difference_interval_95'][0]:+.2f}, {100 * r['difference_interval_95'][1]:+.2f}], "
              f"better on {r['better_than_as_it_is_on']} of {len(cases)}")
    print(f"chosen: {result['summary']['chosen']}")


if __name__ == "__main__":
    main()
