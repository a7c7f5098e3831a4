#!/usr/bin/env python3
"""Draws the time-to-quality curves that bench_time_to_quality wrote: RMSE against the truth as a
function of wall time, one panel per JSON file (circular, spherical), WLS-CG's 30-iteration RMSE as
a dashed line.

  /usr/bin/python3 benchmarks/plot_time_to_quality.py results/time_to_quality-circular-*.json \
      results/time_to_quality-spherical-*.json --out docs/time-to-quality.png"""
import argparse
import json

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


CG_NAMES = {"wls-cg": "WLS-CG", "wls-cg-diagonal": "WLS-CG, diagonal preconditioner", "wls-cg-fdk-start": "WLS-CG from FDK"}
CG_STYLES = {"wls-cg": "k-o", "wls-cg-diagonal": "k--", "wls-cg-fdk-start": "k:"}


def label(method):
    if method["method"] in CG_NAMES:
        return CG_NAMES[method["method"]]
    name = "OS-SQS" if method["method"] == "os-sqs" else "OS-SQS without x >= 0"
    return f"{name}, {method['subsets']} subsets"


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("results", nargs="+")
    parser.add_argument("--out", required=True)
    a = parser.parse_args()
    figure, axes = plt.subplots(1, len(a.results), figsize=(6 * len(a.results), 4.5), squeeze=False)
    for ax, file in zip(axes[0], a.results):
        with open(file, encoding="utf-8") as f:
            r = json.load(f)
        p = r["problem"]
        for m in r["methods"]:
            style = CG_STYLES.get(m["method"], "-o" if m["method"] == "os-sqs" else "--")
            ax.plot(m["seconds"], [1e3 * v for v in m["rmse"]], style, markersize=3, label=label(m))
        ax.axhline(1e3 * r["target_rmse"], color="grey", linestyle=":", label="30 WLS-CG iterations")
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel("RMSE against the truth (1e-3 / mm)")
        vol = "x".join(str(n) for n in p["volume"])
        ax.set_title(f"{p['trajectory']}: {vol} voxels, {p['views']} views of {p['detector'][0]}^2\n{r['cpu'].get('model_name', '?')} family {r['cpu'].get('family', '?')} model {r['cpu'].get('model', '?')}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(a.out, dpi=110)


if __name__ == "__main__":
    main()
