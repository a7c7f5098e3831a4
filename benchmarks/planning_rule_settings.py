#!/usr/bin/python3
"""The planner's settings compared by its rule alone, on many samples at little cost.

The real planner draws from its own coarse reconstruction; `ctk.plan_on_picture` draws by the same
rule from a picture given once. Fed the truth, its trajectories gain over the whole sphere what
the planned ones gain on the mean (planning_oracle.py --rule-check), so settings can be compared
without acquiring anything: per sample, the pool of planning_oracle.py is simulated once (760
views, 20 s), and each setting's rule draws `--draws` trajectories (seeds 1, 2, ...) from the
truth, each mapped to the pool's nearest views, reconstructed and scored as the oracle scores
(the RMSE with each material at its own level, over the sample region). About 2 s per
trajectory.

Gains over the whole sphere's score, positive where better: per setting the mean over samples of
each sample's mean over draws, with a 95 % percentile bootstrap interval, and its paired
difference to the default sample by sample. The choice rule, fixed before the runs: the setting
with the highest mean gain whose paired difference to the default has its interval above zero;
none: the default stays. A setting chosen here is then measured with the real planner through
the simulated lab (`planning_population.py --plan-options`) on seeds it was not chosen on.

  PYTHONPATH=build/python /usr/bin/python3 benchmarks/planning_rule_settings.py --ctk build/tools/ctk \\
      --work /tmp/plan-oracle --seeds 2 4 6 8 10 12 14 16 18 20 22 24
"""

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from diagnosis_population import cpu_name, cpu_slug  # noqa: E402
from planning_oracle import TRUTH_READING, planner_settings, random_sample_on_pool, rule_gains, truth_picture  # noqa: E402
from planning_population import bootstrap_interval  # noqa: E402

# Each setting: its plan_on_picture keywords and the same as `ctk plan` options, one moved at a
# time from the library's defaults (kept in the results as `defaults`; when the even seeds were
# compared they were damage exponent 0.25, edge share 0.5, widest-gap fraction 0.5, tangent width
# 10 deg, and the edge share 1 chosen there is the default now).
SETTINGS = {
    "default": ({}, ""),
    "damage-exponent-0": ({"damage_exponent": 0.0}, "--damage-exponent 0"),
    "damage-exponent-1": ({"damage_exponent": 1.0}, "--damage-exponent 1"),
    "edge-share-0": ({"edge_tangency_weight": 0.0}, "--edge-tangency-weight 0"),
    "edge-share-0.5": ({"edge_tangency_weight": 0.5}, "--edge-tangency-weight 0.5"),
    "widest-gap-0": ({"widest_gap_fraction": 0.0}, "--widest-gap-fraction 0"),
    "widest-gap-0.9": ({"widest_gap_fraction": 0.9}, "--widest-gap-fraction 0.9"),
    "tangent-width-20": ({"tangent_width_deg": 20.0}, "--tangent-width 20"),
}


def one_sample(ctk_bin, work, seed, views, draws, names, log):
    start = time.time()
    sample_file, pool, proxy, whole = random_sample_on_pool(ctk_bin, work, seed, views)
    truth = truth_picture(sample_file)
    gains = {}
    for name in names:
        keywords = SETTINGS[name][0]
        gains[name] = rule_gains(proxy, truth, pool, views, whole, draws, **{**TRUTH_READING, **keywords})
        log(f"seed {seed} {name}: {100 * np.mean(gains[name]):+.2f} % ({', '.join(f'{100 * g:+.1f}' for g in gains[name])})")
    return {"seed": seed, "proxy_score_whole_sphere_per_mm": whole, "gains": gains, "seconds": time.time() - start}


def summary(cases):
    """Per setting the mean gain and its paired difference to the default, and the rule's choice."""
    rng = np.random.default_rng(0)
    names = list(cases[0]["gains"])
    per_sample = {name: [float(np.mean(c["gains"][name])) for c in cases] for name in names}
    out = {}
    for name, values in per_sample.items():
        difference = np.subtract(values, per_sample["default"])
        out[name] = {"options": SETTINGS[name][1], "mean_gain": float(np.mean(values)),
                     "interval_95": bootstrap_interval(values, rng),
                     "difference_to_default": float(np.mean(difference)),
                     "difference_interval_95": bootstrap_interval(difference, rng),
                     "better_than_default_on": int(np.sum(difference > 0))}
    beyond = [n for n in names if n != "default" and out[n]["difference_interval_95"][0] > 0]
    chosen = max(beyond, key=lambda n: out[n]["mean_gain"]) if beyond else "default"
    return {"settings": out, "chosen": chosen, "samples": len(cases)}


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--ctk", required=True)
    p.add_argument("--work", type=Path, default=Path("/tmp/plan-oracle"))
    p.add_argument("--seeds", type=int, nargs="+", default=list(range(2, 25, 2)))
    p.add_argument("--views", type=int, default=100)
    p.add_argument("--draws", type=int, default=4, help="trajectories drawn per setting and sample (seeds 1, 2, ...)")
    p.add_argument("--settings", nargs="+", choices=tuple(SETTINGS), default=list(SETTINGS),
                   help="the settings to draw (default: all; 'default' is always drawn, the others are compared to it)")
    p.add_argument("--out", type=Path)
    a = p.parse_args()
    names = ["default"] + [n for n in a.settings if n != "default"]
    out = a.out or Path(__file__).resolve().parent / "results" / f"planning_rule_settings-{cpu_slug()}.json"
    cases = []
    for seed in a.seeds:
        cases.append(one_sample(a.ctk, a.work / f"seed-{seed}", seed, a.views, a.draws, names,
                                lambda line: print(line, flush=True)))
        result = {"cpu": cpu_name(), "command": " ".join(sys.argv), "views": a.views, "draws": a.draws,
                  "defaults": planner_settings(),
                  "cases": cases, "summary": summary(cases)}
        out.write_text(json.dumps(result, indent=1) + "\n")
    for name, s in result["summary"]["settings"].items():
        print(f"{name:18s} gain {100 * s['mean_gain']:+.2f} % [{100 * s['interval_95'][0]:+.2f}, "
              f"{100 * s['interval_95'][1]:+.2f}]; less the default {100 * s['difference_to_default']:+.2f} points "
              f"[{100 * s['difference_interval_95'][0]:+.2f}, {100 * s['difference_interval_95'][1]:+.2f}], "
              f"better on {s['better_than_default_on']} of {len(cases)}")
    print(f"chosen: {result['summary']['chosen']}")


if __name__ == "__main__":
    main()
