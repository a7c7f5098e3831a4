#!/usr/bin/python3
"""View planning on samples nobody tuned it on: a population of random samples in the holder,
each scanned along the planned trajectory (the planner at its defaults), the whole sphere of the
same size and several random trajectories of that size, all reconstructed alike and scored
against the voxelised truth (`ctk plan --compare`).

The samples: 2 to 4 parts drawn per seed, none touching another, all inside the holder's bore:
blocks (6-20 mm; POM, ABS, PVC, aluminium), plates (10-30 mm across, 1-4 mm thick, metal 0.5-1.5
mm; PVC, aluminium, iron), rods (radius 1-4 mm, metal 0.5-1.5 mm, 10-35 mm long; POM, PVC,
aluminium, iron, copper) and beads (radius 0.5-2.5 mm; aluminium, iron, copper), each at a
uniform place and orientation. Attenuations are the materials' at 60 keV (the polychromatic
simulation takes the material's tables).

Per sample the gains over the whole sphere: RMSE (whole - x) / whole, edge gradient
(x - whole) / whole, positive where x is better, for the planned trajectory and for each random
draw. The best random draw is a lower bound on what choosing a trajectory of this size can gain
on the sample (an oracle that knows the truth would do at least as well). The population's mean
gains carry a 95 % bootstrap interval over the samples; the seeds are split in halves (even:
where planner changes would be chosen, odd: where they are reported), both reported.

  PYTHONPATH=build/python /usr/bin/python3 benchmarks/planning_population.py --ctk build/tools/ctk \\
      --work /tmp/plan-population --seeds 1 2 3 4 5 6 7 8
"""

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from diagnosis_population import cpu_name, cpu_slug  # noqa: E402

MU_60KEV = {"pom": 0.027, "abs": 0.020, "pvc": 0.046, "aluminium": 0.075, "iron": 0.95, "copper": 1.43}
METALS = {"aluminium", "iron", "copper"}
# The gains scored: the RMSE over the sample region, the edge gradient, the RMSE outside the
# absorbers and off their neighbours (what the trajectory controls where beam hardening sets the
# metal's own level; the thesis' streaks), and the RMSE with each material at the level the
# reconstruction gives it (what is left of blur, streaks and noise once the spectrum's levels,
# which every material's hardening sets, are taken out; libplan's trajectory_quality.hpp).
# Each: the comparison's key, and whether lower is better.
METRIC_KEYS = {"rmse": ("rmse_per_mm", True), "edge_gradient": ("edge_gradient_per_mm2", False),
               "rmse_outside_absorbers": ("rmse_outside_absorbers_per_mm", True),
               "rmse_level_matched": ("rmse_level_matched_per_mm", True)}
METRICS = tuple(METRIC_KEYS)
BORE_MM, HALF_HEIGHT_MM = 24.0, 40.0  # inside the reference holder's wall (25 mm) and spheres' band


def rotation_vector_deg(rng):
    """A uniform rotation: axis uniform on the sphere, angle with density (1 - cos) / pi."""
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    while True:  # rejection: the angle of a uniform rotation has density (1 - cos t) / pi on [0, pi]
        t = rng.uniform(0, np.pi)
        if rng.uniform(0, 2) < 1 - np.cos(t):
            return list(np.degrees(t) * axis)


def random_part(rng):
    kind = rng.choice(["block", "plate", "rod", "bead"])
    if kind == "block":
        material = rng.choice(["pom", "abs", "pvc", "aluminium"])
        size = rng.uniform(6, 20, 3)
        shape = {"type": "box", "size_mm": list(size)}
        reach = 0.5 * np.linalg.norm(size)
    elif kind == "plate":
        material = rng.choice(["pvc", "aluminium", "iron"])
        thickness = rng.uniform(0.5, 1.5) if material in METALS else rng.uniform(1, 4)
        size = np.array([*rng.uniform(10, 30, 2), thickness])
        shape = {"type": "box", "size_mm": list(size)}
        reach = 0.5 * np.linalg.norm(size)
    elif kind == "rod":
        material = rng.choice(["pom", "pvc", "aluminium", "iron", "copper"])
        radius = rng.uniform(0.5, 1.5) if material in METALS else rng.uniform(1, 4)
        length = rng.uniform(10, 35)
        shape = {"type": "cylinder", "radius_mm": radius, "height_mm": length}
        reach = np.hypot(radius, 0.5 * length)
    else:
        material = rng.choice(["aluminium", "iron", "copper"])
        radius = rng.uniform(0.5, 2.5)
        shape = {"type": "sphere", "radius_mm": radius}
        reach = radius
    return str(kind), str(material), shape, float(reach)


def random_sample(seed):
    """A ctk-phantom/1 sample of 2-4 parts apart from each other inside the bore."""
    rng = np.random.default_rng(seed)
    parts, placed = [], []
    wanted = int(rng.integers(2, 5))
    while len(parts) < wanted:
        kind, material, shape, reach = random_part(rng)
        if reach > 0.9 * BORE_MM:
            continue
        for _ in range(200):
            r = (BORE_MM - reach) * np.sqrt(rng.uniform())
            phi = rng.uniform(0, 2 * np.pi)
            centre = np.array([r * np.cos(phi), r * np.sin(phi), rng.uniform(-1, 1) * (HALF_HEIGHT_MM - reach)])
            if all(np.linalg.norm(centre - c) > reach + q + 0.5 for c, q in placed):
                break
        else:
            continue
        placed.append((centre, reach))
        part = dict(shape, center_mm=list(centre), attenuation_per_mm=MU_60KEV[material], material=material,
                    label=f"{kind} ({material})")
        if shape["type"] != "sphere":
            part["rotation_vector_deg"] = rotation_vector_deg(rng)
        parts.append(part)
    return {"format": "ctk-phantom/1", "name": f"random-sample-{seed}", "primitives": parts}


def gain_over_whole_sphere(comparison, name):
    """The gains of one compared trajectory over the whole sphere, positive where it is better."""
    t = comparison["trajectories"]
    whole, x = t["whole-sphere"], t[name]
    out = {}
    for metric, (key, lower_is_better) in METRIC_KEYS.items():
        if whole.get(key):  # a comparison written before the figure existed lacks it
            out[metric] = (whole[key] - x[key] if lower_is_better else x[key] - whole[key]) / whole[key]
    return out


def gains(comparison):
    """Gains over the whole sphere of the planned trajectory and of each random draw."""
    t = comparison["trajectories"]
    whole = t["whole-sphere"]

    def gain(name):
        return gain_over_whole_sphere(comparison, name)

    draws = [gain(name) for name in sorted(t) if name.startswith("random")]
    return {"planned": gain("planned"), "random": draws,
            "best_random": {k: max(d[k] for d in draws) for k in draws[0]},
            "whole_sphere": {"rmse_per_mm": whole["rmse_per_mm"], "edge_gradient_per_mm2": whole["edge_gradient_per_mm2"]}}


def bootstrap_interval(values, rng, rounds=4000):
    v = np.asarray(values, dtype=float)
    if len(v) < 2:
        return [float(v.mean()), float(v.mean())] if len(v) else [0.0, 0.0]
    means = rng.choice(v, size=(rounds, len(v))).mean(axis=1)
    return [float(np.percentile(means, 2.5)), float(np.percentile(means, 97.5))]


def scored_by_all(cases):
    """The metrics every case has (results compared before a figure existed lack it)."""
    return [m for m in METRICS if all(m in c["gains"]["planned"] for c in cases)]


def summary(cases, rng):
    out = {"samples": len(cases)}
    if not cases:
        return out
    metrics = scored_by_all(cases)
    for what in ("planned", "best_random"):
        for metric in metrics:
            values = [c["gains"][what][metric] for c in cases]
            out[f"{what}_{metric}"] = {"mean": float(np.mean(values)), "interval_95": bootstrap_interval(values, rng)}
    for metric in metrics:
        values = [np.mean([d[metric] for d in c["gains"]["random"]]) for c in cases]
        out[f"random_{metric}"] = {"mean": float(np.mean(values)), "interval_95": bootstrap_interval(values, rng)}
    return out


def paired_against(cases, earlier, rng):
    """The planned gains of this run less those of an earlier run (another planner setting) on the
    samples both scored, per metric: mean, 95 % interval and on how many samples this run did better."""
    before = {c["seed"]: c["gains"]["planned"] for c in earlier["cases"]}
    common = [c for c in cases if c["seed"] in before]
    out = {"samples": len(common), "against": earlier.get("plan_options") or "no plan options",
           "command": earlier.get("command", "")}
    for metric in [m for m in scored_by_all(common) if all(m in before[c["seed"]] for c in common)]:
        d = [c["gains"]["planned"][metric] - before[c["seed"]][metric] for c in common]
        out[metric] = {"mean": float(np.mean(d)), "interval_95": bootstrap_interval(d, rng),
                       "better_on": int(sum(x > 0 for x in d))}
    return out


def picture(cases, file, bars=(("planned", "planned", "tab:blue"),)):
    """Per sample, the gains of each (key, label, colour) in `bars` as bars and the random draws as
    dots: RMSE, edge gradient and (where scored) the level-matched RMSE side by side."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    panels = [(m, t) for m, t in (("rmse", "RMSE gain over the whole sphere"), ("edge_gradient", "edge-gradient gain"),
                                  ("rmse_level_matched", "gain in RMSE, levels matched"))
              if all(m in c["gains"][key] for c in cases for key, _, _ in bars)]
    fig, axes = plt.subplots(1, len(panels), figsize=(5.5 * len(panels), 4))
    x = np.arange(len(cases))
    width = 0.8 / (len(bars) + 1)
    for ax, (metric, title) in zip(axes, panels):
        ax.axhline(0, color="black", lw=0.8)
        for k, (key, label, colour) in enumerate(bars):
            ax.bar(x - 0.4 + width * (k + 0.5), [100 * c["gains"][key][metric] for c in cases], width, label=label,
                   color=colour)
        for i, c in enumerate(cases):
            draws = [100 * d[metric] for d in c["gains"]["random"]]
            ax.plot([i + 0.4 - width / 2] * len(draws), draws, "o", color="tab:orange", ms=4,
                    label="random draws" if i == 0 else None)
        ax.set_xticks(x, [str(c["seed"]) for c in cases])
        ax.set_xlabel("sample seed")
        ax.set_ylabel("%")
        ax.set_title(title)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(file, dpi=110)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--ctk", default="build/tools/ctk")
    p.add_argument("--work", default="/tmp/plan-population")
    p.add_argument("--seeds", nargs="+", type=int, default=list(range(1, 9)))
    p.add_argument("--random-draws", type=int, default=3)
    p.add_argument("--plan-options", default="", help="more `ctk plan` options, e.g. '--views 60 --cols 360 --rows 360 --pitch 1.2'")
    p.add_argument("--json", help="results file (default: benchmarks/results/planning_population-<cpu>.json)")
    p.add_argument("--rescore", action="store_true",
                   help="score the samples already compared in --work again with this build (`ctk plan --compare-only`:"
                        " their trajectories reconstructed and scored anew) without planning or acquiring again")
    p.add_argument("--against", help="an earlier results file on the same seeds: the planned gains compared sample by sample")
    a = p.parse_args()
    work = Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    results = Path(__file__).resolve().parent / "results"
    file = Path(a.json) if a.json else results / f"planning_population-{cpu_slug()}.json"
    # A rescore keeps the command and the planning times the results file already holds.
    earlier = json.loads(file.read_text()) if a.rescore and file.exists() else {"cases": []}
    earlier_seconds = {c["seed"]: c["seconds"] for c in earlier["cases"]}
    cases = []
    for seed in a.seeds:
        sample = work / f"sample-{seed}.json"
        sample.write_text(json.dumps(random_sample(seed), indent=2))
        out = work / f"sample-{seed}"
        start = time.time()
        rescored = a.rescore and (out / "comparison.json").exists()
        command = [a.ctk, "plan", "--out", str(out), "--phantom", str(sample), "--compare-only" if rescored else "--compare",
                   "--random-draws", str(a.random_draws), "--seed", str(seed), *a.plan_options.split()]
        subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        comparison = json.loads((out / "comparison.json").read_text())
        case = {"seed": seed, "half": "choice" if seed % 2 == 0 else "report", "sample": json.loads(sample.read_text()),
                "gains": gains(comparison),
                "seconds": earlier_seconds.get(seed) if rescored else time.time() - start}
        cases.append(case)
        g = case["gains"]
        draws = ", ".join(f"{100 * d['rmse']:+.1f}" for d in g["random"])
        print(f"sample {seed}: planned RMSE {100 * g['planned']['rmse']:+.1f} %, edge {100 * g['planned']['edge_gradient']:+.1f} %;"
              f" random RMSE {draws} %; " + ("rescored" if rescored else f"{case['seconds']:.0f} s"), flush=True)
    rng = np.random.default_rng(0)
    result = {"cpu": cpu_name(), "command": earlier.get("command", " ".join(sys.argv)), "plan_options": a.plan_options,
              "random_draws": a.random_draws, "cases": cases,
              "population": summary(cases, rng),
              "report_half": summary([c for c in cases if c["half"] == "report"], rng),
              "choice_half": summary([c for c in cases if c["half"] == "choice"], rng)}
    if "command" in earlier:
        result["rescored_with"] = " ".join(sys.argv)
    if a.against:
        result["paired"] = paired_against(cases, json.loads(Path(a.against).read_text()), rng)
    file.write_text(json.dumps(result, indent=1) + "\n")
    picture(cases, file.with_suffix(".png"))
    for name in ("population", "report_half"):
        s = result[name]
        parts = [f"{k} {100 * v['mean']:+.1f} % [{100 * v['interval_95'][0]:+.1f}, {100 * v['interval_95'][1]:+.1f}]"
                 for k, v in s.items() if k != "samples"]
        print(name + ": " + "; ".join(parts))
    if a.against:
        d = result["paired"]
        print(f"against the run with {d['against']} ({d['samples']} samples): " + "; ".join(
            f"{m} {100 * d[m]['mean']:+.2f} points [{100 * d[m]['interval_95'][0]:+.2f}, {100 * d[m]['interval_95'][1]:+.2f}],"
            f" better on {d[m]['better_on']}" for m in METRICS if m in d))
    print(f"wrote {file}")


if __name__ == "__main__":
    main()
