#!/usr/bin/python3
"""Stopping rules for unregularised OS-SQS that were tried against the one `ctk reconstruct` uses
(held_out_fit.hpp: one view in 32 held out, the run ended at the first epoch whose held-out
improvement its noise explains, the last improving iterate returned). The same rule is applied to
other held-out data, and two ways of combining iterates are scored:
  views  one view in `every` held out (the product's rule, for reference);
  rows   in every view one detector row in `every` held out (rows interleaved with fitted rows,
         so the held-out data see the image's finest noise along every direction);
  rays   a random ray in `every` held out of every view;
and, at the rule's result r, the mean of iterates r-1 and r, and the combination of iterates
r-1, r, r+1 fitted on the held-out data.

The standard problem's geometry at --scale (circular or spherical, 1.6 x scale mm pixels, source
1000 mm from the centre and 1500 mm from the detector), Shepp-Logan filling 84 % of the volume
(bench_stopping_rule's phantom), its data projected from a truth on a grid twice as fine as the
solver's (no inverse crime) with Poisson noise at --counts. Each epoch's iterate is a run of that
many epochs from zero (OS-SQS is deterministic), so the script needs only the Python module.

  PYTHONPATH=build/python /usr/bin/python3 benchmarks/stopping_alternatives.py --trajectory circular \\
      --counts 1000 --views 120 --modes views rows rays
"""

import argparse
import json
import sys

import numpy as np

import ctk

SIGNIFICANCE = 2.0  # held_out_fit.hpp's kHeldOutSignificance


def problem(trajectory, views, scale, counts, seed=1):
    n, det = 256 // scale, 256 // scale
    voxel, pitch = float(scale), 1.6 * scale
    origin = (-(n - 1) / 2 * voxel,) * 3
    shrink = 24.0 / (0.42 * 256)  # the built-in Shepp-Logan is 48 mm across and 0.02 /mm at its scale

    def truth_on(m, v, o):
        return (shrink * ctk.voxelise(["shepp-logan"], (m, m, m), (v * shrink,) * 3, tuple(c * shrink for c in o))
                ).astype(np.float32)

    if trajectory == "circular":
        P = ctk.circular_matrices(list(np.arange(views) * 360.0 / views), (det, det), (pitch, pitch), 1000.0, 1500.0)
    else:
        d = np.random.default_rng(2026).normal(size=(views, 3))
        d /= np.linalg.norm(d, axis=1)[:, None]
        P = np.array([ctk.view_matrix(v, detector_shape=(det, det), pitch_mm=pitch, sdd_mm=1500.0, sod_mm=1000.0) for v in d])
    fine_origin = (-(2 * n - 1) / 2 * voxel / 2,) * 3
    line_integrals = ctk.Projector(P, (2 * n,) * 3, voxel / 2, fine_origin, detector_shape=(det, det)).forward(
        truth_on(2 * n, voxel / 2, fine_origin))
    rng = np.random.default_rng(seed)
    detected = np.maximum(rng.poisson(counts * np.exp(-line_integrals.astype(np.float64))), 1)
    b = (-np.log(detected / counts)).astype(np.float32)
    A = ctk.Projector(P, (n,) * 3, voxel, origin, detector_shape=(det, det))
    return A, b, detected.astype(np.float32), truth_on(n, voxel, origin), rng


def held_out_mask(mode, shape, every, rng):
    views, rows, _ = shape
    mask = np.zeros(shape, bool)
    if mode == "views":
        mask[::every] = True
    elif mode == "rows":
        first = rng.integers(every, size=views)
        for v in range(views):
            mask[v, first[v]::every, :] = True
    else:
        mask = rng.random(shape) < 1.0 / every
    return mask


def one_case(a, mode):
    A, b, w, truth, rng = problem(a.trajectory, a.views, a.scale, a.counts)
    held = held_out_mask(mode, b.shape, a.every, rng)
    fitted_weights = (w * ~held).astype(np.float32)
    subsets = min(24, max(1, (a.views + 7) // 15))  # reconstruction_run's default_subset_count

    def rmse(x):
        return float(np.sqrt(np.mean((x - truth) ** 2)))

    def fit(q):
        return float(np.sum((w * (q - b) ** 2)[held])) / 2

    xs, qs = [np.zeros_like(truth)], [np.zeros_like(b)]
    errors, fits = [rmse(xs[0])], [fit(qs[0])]
    best_fit, stops = fits[0], None
    for epoch in range(1, a.epochs + 1):
        x = ctk.os_sqs(A, b, weights=fitted_weights, epochs=epoch, subsets=subsets).x
        q = A.forward(x)
        xs.append(x), qs.append(q), errors.append(rmse(x)), fits.append(fit(q))
        if stops is None and epoch > 1:
            noise_per_ray = 2 * min(best_fit, fits[-1]) / held.sum()
            moved = float(np.sum((w * (q - qs[-2]) ** 2)[held]))
            if fits[-2] - fits[-1] > SIGNIFICANCE * np.sqrt(noise_per_ray * moved):
                best_fit = fits[-1]
            else:
                stops = epoch
        if stops is not None and epoch > stops:
            break
    result = (stops or len(xs)) - 1
    best = int(np.argmin(errors[1:])) + 1
    mean_with_previous = rmse((xs[result] + xs[result - 1]) / 2) if result > 1 else errors[result]
    around = [i for i in (result - 1, result + 1) if 1 <= i < len(xs)]
    D = np.array([(qs[i] - qs[result])[held] for i in around]).T.astype(np.float64)
    sw = np.sqrt(w[held].astype(np.float64))
    coefficients = np.linalg.lstsq(D * sw[:, None], (b - qs[result])[held] * sw, rcond=None)[0]
    combined = rmse(xs[result] + sum(c * (xs[i] - xs[result]) for c, i in zip(coefficients, around)))
    return {"mode": mode, "rmse_per_epoch": errors[1:], "best_epoch": best, "rule_stops_after": stops,
            "rule_result": result, "rule_over_best": errors[result] / errors[best],
            "mean_with_previous_over_best": mean_with_previous / errors[best],
            "combination_over_best": combined / errors[best], "combination_coefficients": list(coefficients)}


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--trajectory", choices=["circular", "spherical"], default="circular")
    p.add_argument("--views", type=int, default=120)
    p.add_argument("--counts", type=float, default=1e3)
    p.add_argument("--scale", type=int, default=2)
    p.add_argument("--every", type=int, default=32)
    p.add_argument("--epochs", type=int, default=10)
    p.add_argument("--modes", nargs="+", choices=["views", "rows", "rays"], default=["views", "rows", "rays"])
    p.add_argument("--out", help="JSON to write (one line per mode is printed either way)")
    a = p.parse_args()
    cases = []
    for mode in a.modes:
        c = one_case(a, mode)
        cases.append(c)
        print(f"{a.trajectory} {a.counts:g} counts {a.views} views, held out {mode}: best epoch {c['best_epoch']}, "
              f"rule result {c['rule_result']} ({c['rule_over_best']:.3f} x best), mean with the one before "
              f"{c['mean_with_previous_over_best']:.3f}, fitted combination {c['combination_over_best']:.3f}", flush=True)
    if a.out:
        with open(a.out, "w") as f:
            json.dump({"command": " ".join(sys.argv), "cases": cases}, f, indent=1)


if __name__ == "__main__":
    main()
