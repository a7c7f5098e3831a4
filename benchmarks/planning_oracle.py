#!/usr/bin/python3
"""What a trajectory of a given size can gain on a sample, found by a search that knows the truth
(an oracle), beside what the planner gains, on the random samples of planning_population.py.

Per sample:
1. A pool: the planner's 768 candidate directions (HEALPix nside 8, less those within 8 deg of the
   holder axis, which no view calibrates), each simulated once with the comparison's physics
   (90 kV through 2 mm Al, the holder and the sample, Poisson noise of 10^4 open-beam counts per
   0.6 mm pixel) on a 360^2 detector of 1.2 mm (the comparison's 2 x 2 binning), then binned
   again to 180^2 for the search.
2. The oracle's search on that pool, scored by the true error: every trajectory of n views is
   reconstructed alike (WLS-CG, 20 iterations, gradient penalty, 1 mm voxels over the holder) and
   its RMSE over the sample region taken against the voxelised truth with each material at the
   level the reconstruction gives it (`--score level-matched`, the default: a search on the plain
   RMSE, `--score rmse`, gains by views whose long paths through a dense part harden the beam and
   lower that part's level towards the 60 keV truth, not by a better image). It first takes the whole
   sphere's order less the directions whose most attenuating ray through the true absorbers is
   longest (none, or the worst 5, 10, 20, 30 or 40 %: the planner's damage, known instead of
   estimated), keeps the best of those six, then exchanges a random member for a random
   candidate, keeping the exchange only if the true RMSE falls, until `--budget`
   reconstructions are spent. (Exchanges
   proposed by the error the present image shows a candidate, or by the candidates' data
   inconsistency against the truth, found less: the views that see most error are those along the
   metal's streaks, and the data inconsistency varies by 10 % between directions.)
3. The oracle's trajectory, written as ctk-directions/1 (its n directions, then the rest of the
   pool as spares in whole-sphere order), is acquired and scored by `ctk plan --compare
   --compare-directions` beside the planned trajectory, the whole sphere and the random draws,
   each through the simulated lab (robot, calibration) and the comparison's own reconstruction.
   The search's proxy is checked against the comparison: its RMSE for the whole sphere and for
   the oracle's set against theirs.

Gains over the whole sphere, positive where better: RMSE (whole - x) / whole, edge gradient
(x - whole) / whole; means over the samples with a 95 % bootstrap interval, and over the halves
of the seeds (even: where planner changes are chosen, odd: where they are reported).

  PYTHONPATH=build/python /usr/bin/python3 benchmarks/planning_oracle.py --ctk build/tools/ctk \\
      --work /tmp/plan-oracle --seeds 1 2 3 4 5 6 7 8
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
from planning_population import bootstrap_interval, gain_over_whole_sphere, picture, random_sample  # noqa: E402

import ctk  # noqa: E402

POOL_SHAPE, POOL_PITCH_MM = (360, 360), 1.2  # the comparison's detector after its 2 x 2 binning
POOL_FLAT_COUNTS = 4e4  # 10^4 per 0.6 mm pixel, four of them per 1.2 mm pixel
SEARCH_BINNING = 2  # the search reconstructs from 180^2
AXIS_EXCLUSION_COS = np.cos(np.radians(8.0))
VOXEL_MM, VOLUME_SHAPE = 1.0, (120, 60, 60)  # (z, y, x): the holder's tube and its spheres
REGION_RADIUS_MM, REGION_HALF_HEIGHT_MM = 23.5, 45.0  # the comparison's sample region
PENALTY, ITERATIONS = 3.0, 20  # the comparison's reconstruction
ABSORBER_ABOVE_PER_MM = 2 * 0.027  # the comparison's absorbers: twice the holder's POM wall
# Per --score: the gain the summary judges the planner on, and how the picture names the search.
SCORES = {"level-matched": ("rmse_level_matched", "RMSE, levels matched"), "rmse": ("rmse", "RMSE")}
STREAK_SHELL_MM = 5.0  # the shell around the absorbers where their streaks are scored
RULE_DRAWS = 4  # seeds of the planner's rule drawn per picture in the rule check
TRUTH_READING = {"picture_median": False}  # how plan_on_picture reads the truth (truth_picture)
RULE_SETTINGS = ("damage_exponent", "spread_exponent", "widest_gap_fraction", "edge_tangency_weight", "tangent_width_deg",
                 "picture_median")


def run(command, log):
    with open(log, "w") as f:
        subprocess.run(command, check=True, stdout=f, stderr=subprocess.STDOUT)


def pool_directions():
    """The planner's candidates, in the whole sphere's order, less those along the holder axis."""
    order = ctk.planning_directions(8, "whole-sphere")
    return order[np.abs(order[:, 2]) < AXIS_EXCLUSION_COS]


def simulate_pool(ctk_bin, work, sample_file, directions, seed):
    """The pool's projections through `ctk simulate --poses` (matrices with the detector centred)."""
    if (work / "pool" / "scan.json").exists():
        return work / "pool" / "scan.json"
    views = []
    for i, d in enumerate(directions):
        P = ctk.view_matrix(d, detector_shape=POOL_SHAPE, pitch_mm=POOL_PITCH_MM)
        P = P / np.linalg.norm(P[2, :3])
        views.append({"index": i, "status": "ok", "reason": "", "P": list(P.ravel())})
    geometry = {"format": "ctk-geometry/1",
                "detector": {"cols": POOL_SHAPE[1], "rows": POOL_SHAPE[0], "pixel_pitch_mm": [POOL_PITCH_MM] * 2},
                "views": views}
    (work / "pool-geometry.json").write_text(json.dumps(geometry))
    run([ctk_bin, "simulate", "--out", str(work / "pool"), "--poses", str(work / "pool-geometry.json"), "--phantom",
         "helix-holder", str(sample_file), "--cols", str(POOL_SHAPE[1]), "--rows", str(POOL_SHAPE[0]), "--pitch",
         str(POOL_PITCH_MM), "--kvp", "90", "--filter-al-mm", "2", "--flat-counts", str(POOL_FLAT_COUNTS), "--seed",
         str(seed)], work / "pool.log")
    return work / "pool" / "scan.json"


def binned(m, factor):
    """Line integrals averaged and Poisson weights combined (inverse of the mean's variance) over
    factor x factor pixels; the matrices address the binned pixels (pixel centres at integers)."""
    views, rows, cols = m.line_integrals.shape
    shape = (views, rows // factor, factor, cols // factor, factor)
    b = m.line_integrals[:, :rows // factor * factor, :cols // factor * factor].reshape(shape).mean(axis=(2, 4))
    w = m.weights[:, :rows // factor * factor, :cols // factor * factor].reshape(shape).astype(np.float64)
    with np.errstate(divide="ignore"):
        variance = np.where(w > 0, 1.0 / w, np.inf).sum(axis=(2, 4)) / factor**4
    weights = np.where(np.isfinite(variance), 1.0 / variance, 0.0)
    S = np.array([[1.0 / factor, 0, (1.0 / factor - 1) / 2], [0, 1.0 / factor, (1.0 / factor - 1) / 2], [0, 0, 1]])
    return b.astype(np.float32), weights.astype(np.float32), np.einsum("ij,vjk->vik", S, m.matrices)


class Proxy:
    """The search's model of the comparison: a trajectory's reconstruction from the pool's views
    and its RMSE over the sample region against the truth."""

    def __init__(self, scan_file, sample_file, score="level-matched"):
        m = ctk.load_measurements(scan_file)
        self.b, self.w, self.P = binned(m, SEARCH_BINNING)
        self.detector_shape = self.b.shape[1:]
        nz, ny, nx = VOLUME_SHAPE
        self.origin = (-(nx - 1) / 2 * VOXEL_MM, -(ny - 1) / 2 * VOXEL_MM, -(nz - 1) / 2 * VOXEL_MM)
        self.truth = ctk.voxelise([str(sample_file)], VOLUME_SHAPE, (VOXEL_MM,) * 3, self.origin)
        z, y, x = np.meshgrid(*[self.origin[2 - a] + VOXEL_MM * np.arange(VOLUME_SHAPE[a]) for a in range(3)],
                              indexing="ij")
        self.region = (np.hypot(x, y) <= REGION_RADIUS_MM) & (np.abs(z) <= REGION_HALF_HEIGHT_MM)
        self.evaluations = 0
        # The truth per material over the region (columns) and its pseudo-inverse, once: the levels
        # of a reconstruction are then one product per evaluation.
        parts = ctk.voxelise_per_material([str(sample_file)], VOLUME_SHAPE, (VOXEL_MM,) * 3, self.origin)
        self.materials = np.stack([t[self.region] for t in parts.values()], axis=1).astype(np.float64)
        self.levels_of = np.linalg.pinv(self.materials)
        self.score = {"level-matched": self.level_matched_rmse, "rmse": self.rmse}[score]

    def projector(self, views):
        return ctk.Projector(self.P[views], VOLUME_SHAPE, VOXEL_MM, self.origin, detector_shape=self.detector_shape)

    def reconstruct(self, views):
        views = np.sort(np.asarray(views))
        self.evaluations += 1
        r = ctk.wls_cg(self.projector(views), self.b[views], weights=self.w[views], iterations=ITERATIONS,
                       tolerance=0.0, lambda_=PENALTY, regulariser="gradient")
        return r.x

    def rmse(self, x):
        return float(np.sqrt(np.mean((x - self.truth)[self.region] ** 2)))

    def level_matched_rmse(self, x):
        """The RMSE against the truth with each material at its least-squares level (libplan's
        trajectory_quality.hpp)."""
        inside = x[self.region].astype(np.float64)
        return float(np.sqrt(np.mean((inside - self.materials @ (self.levels_of @ inside)) ** 2)))


def error_share_in_absorbers(proxy, x, absorber_above_per_mm):
    """The share of the squared error of `x` (over the sample region) in the absorbers and the
    voxels touching them: what the beam hardening of their level and their partial volume leave,
    which no choice of directions changes much."""
    from scipy import ndimage
    error2 = (x - proxy.truth) ** 2
    near = ndimage.binary_dilation(proxy.truth > absorber_above_per_mm) & proxy.region
    return float(error2[near].sum() / error2[proxy.region].sum())


def optical_depth_through_absorbers(proxy, absorber_above_per_mm):
    """Per pool view, the most attenuating ray's line integral through the truth's absorbers
    (the planner's damage, known instead of estimated from a scout)."""
    absorbers = np.where(proxy.truth > absorber_above_per_mm, proxy.truth, 0).astype(np.float32)
    return proxy.projector(np.arange(len(proxy.b))).forward(absorbers).max(axis=(1, 2))


def oracle_search(proxy, depth, n, budget, rng, log):
    """The search that knows the truth (see the module): the whole sphere's order with the
    directions of the longest absorber paths left out (none, or the worst 5 to 40 %), the best of
    those, then random exchanges kept only where the true RMSE falls. Returns the members, the
    whole sphere's and the best RMSE, the share left out, the history and the whole sphere's
    reconstruction."""
    def first_n(kept):
        return [int(v) for v in np.flatnonzero(kept)[:n]]

    trials, whole_sphere = [], None
    for share in (0.0, 0.05, 0.1, 0.2, 0.3, 0.4):
        kept = depth <= np.quantile(depth, 1 - share) if share > 0 else np.ones(len(depth), bool)
        members = first_n(kept)
        x = proxy.reconstruct(members)
        whole_sphere = x if whole_sphere is None else whole_sphere
        trials.append((proxy.score(x), share, members))
    start = trials[0][0]
    best, share, members = min(trials)
    history = [{"evaluations": proxy.evaluations, "score_per_mm": r, "left_out_share": s} for r, s, _ in trials]
    log(f"  whole sphere {start:.6f}; longest absorber paths left out: best share {share} {best:.6f} "
        f"({(start - best) / start:+.2%})")
    while proxy.evaluations < budget:
        outside = np.setdiff1d(np.arange(len(depth)), members)
        trial = list(members)
        trial[int(rng.integers(n))] = int(rng.choice(outside))
        r = proxy.score(proxy.reconstruct(trial))
        if r < best:
            members, best = trial, r
            history.append({"evaluations": proxy.evaluations, "score_per_mm": best})
            log(f"  exchange kept after {proxy.evaluations} reconstructions: {best:.6f} ({(start - best) / start:+.2%})")
    return members, start, best, share, history, whole_sphere


def random_sample_on_pool(ctk_bin, work, seed, views):
    """Random sample `seed` (written to `work`/sample.json), its pool (simulated once), the proxy
    scoring trajectories on it with the levels matched, and the score of the whole sphere's first
    `views` views: what the rule-alone comparisons draw against."""
    work.mkdir(parents=True, exist_ok=True)
    sample_file = work / "sample.json"
    sample_file.write_text(json.dumps(random_sample(seed), indent=1))
    pool = pool_directions()
    proxy = Proxy(simulate_pool(ctk_bin, work, sample_file, pool, seed), sample_file, "level-matched")
    return sample_file, pool, proxy, proxy.score(proxy.reconstruct(list(range(views))))


def nearest_pool_views(directions, pool):
    """The pool's views nearest each direction (the scout's nside-2 centres lie up to 4 deg from
    a pool cell; the draws are pool cells), each once."""
    return list(dict.fromkeys(int(np.argmax(pool @ d)) for d in directions))


def planner_settings():
    """The library's defaults of the rule's settings (what `ctk.plan_on_picture` draws with unless
    told otherwise), recorded beside every rule result."""
    return {k: v for k, v in ctk._ctk._plan_defaults().items() if k in RULE_SETTINGS}


def coarse_grid():
    """The planner's coarse grid at the library's defaults: voxels per axis, voxel size (mm), and
    the origin (centre of voxel 0, mm) that centres it on the holder."""
    defaults = ctk._ctk._plan_defaults()
    n, voxel = defaults["coarse_size"], defaults["coarse_voxel_mm"]
    return n, voxel, (-(n - 1) / 2 * voxel,) * 3


def truth_picture(sample_file):
    """The truth on the planner's coarse grid (its default size and voxel, centred), the holder
    with it (its wall is the planner's yardstick for absorbers): what `ctk.plan_on_picture` reads
    when the rule is checked apart from its estimate. The truth has no noise to take out: it is read
    as it is (TRUTH_READING), not through the median meant for the planner's reconstructions, which
    would take out plates thinner than two voxels."""
    n, voxel, origin = coarse_grid()
    return ctk.voxelise(["helix-holder", str(sample_file)], (n,) * 3, (voxel,) * 3, origin)


def rule_gains(proxy, picture_of_sample, pool, views, whole, draws=RULE_DRAWS, **settings):
    """The planner's rule (`ctk.plan_on_picture` at `settings`, seeds 1 to `draws`) drawing from a
    picture of the sample, each trajectory mapped to the pool's nearest views and scored by the
    proxy: gains over the whole sphere's score `whole`, one per draw."""
    reachable = lambda d: abs(d[2]) < AXIS_EXCLUSION_COS  # noqa: E731  the pool's own rule
    gains = []
    for seed in range(1, draws + 1):
        members = nearest_pool_views(ctk.plan_on_picture(picture_of_sample, reachable=reachable, views=views,
                                                         seed=seed, **settings), pool)
        gains.append((whole - proxy.score(proxy.reconstruct(members))) / whole)
    return gains


def rule_check(proxy, work, sample_file, pool, views, whole):
    """Where the planner's gap to the oracle lies, on the search's own score: the planner's rule at
    its defaults drawing from the truth as its picture and from its own last coarse reconstruction
    (the run's `coarse.nrrd`), and the planned trajectory itself, each mapped to the pool's nearest
    views and scored like the oracle. Gains over the whole sphere's score `whole` (the search's
    first trial), positive where better."""
    own, _ = ctk.read_volume(work / "plan" / "planned" / "coarse.nrrd")
    out = {"proxy_score_whole_sphere_per_mm": whole, "planner": planner_settings()}
    for name, picture_of_sample, reading in (("rule_on_truth", truth_picture(sample_file), TRUTH_READING),
                                             ("rule_on_own_picture", own, {})):
        gains = rule_gains(proxy, picture_of_sample, pool, views, whole, **reading)
        out[name] = {"mean": float(np.mean(gains)), "draws": gains}
    planned = json.loads((work / "plan" / "planned" / "trajectory.json").read_text())
    members = nearest_pool_views([v["direction_holder"] for v in planned["views"] if v.get("calibrated")], pool)
    out["planned_on_pool"] = (whole - proxy.score(proxy.reconstruct(members))) / whole
    return out


def streaks_near_absorbers(plan_folder, names):
    """The thesis' metal-streak figure, per trajectory: the RMSE against the truth in a shell of
    STREAK_SHELL_MM around the absorbers, off the voxels touching them (where streaks from dense
    parts are strongest), from the comparison's own volumes. None without absorbers."""
    from scipy import ndimage
    truth, meta = ctk.read_volume(plan_folder / "truth.nrrd")
    absorbers = truth > ABSORBER_ABOVE_PER_MM
    if not absorbers.any():
        return {name: None for name in names}
    z, y, x = (meta["origin_mm"][2 - a] + meta["voxel_mm"][2 - a] * np.arange(truth.shape[a]) for a in range(3))
    region = ((np.hypot(*np.meshgrid(y, x, indexing="ij")) <= REGION_RADIUS_MM)[None, :, :]
              & (np.abs(z) <= REGION_HALF_HEIGHT_MM)[:, None, None])
    distance_mm = ndimage.distance_transform_edt(~absorbers, sampling=meta["voxel_mm"][::-1])
    shell = region & ~ndimage.binary_dilation(absorbers) & (distance_mm <= STREAK_SHELL_MM)
    out = {}
    for name in names:
        volume, _ = ctk.read_volume(plan_folder / name / "volume.nrrd")
        out[name] = float(np.sqrt(np.mean((volume[shell] - truth[shell]) ** 2)))
    return out


def scored(plan_folder):
    """The gains over the whole sphere of the planned, the oracle's and the random trajectories
    (RMSE, edge gradient, streaks near the absorbers), and the whole sphere's figures."""
    comparison = json.loads((plan_folder / "comparison.json").read_text())
    names = ["planned", "oracle"] + sorted(k for k in comparison["trajectories"] if k.startswith("random"))
    g = {name: gain_over_whole_sphere(comparison, name) for name in names}
    streaks = streaks_near_absorbers(plan_folder, names + ["whole-sphere"])
    whole = streaks["whole-sphere"]
    for name in names:
        g[name]["streaks_near_absorbers"] = None if whole is None else (whole - streaks[name]) / whole
    return ({"planned": g["planned"], "oracle": g["oracle"], "random": [g[k] for k in names[2:]]},
            {**comparison["trajectories"]["whole-sphere"], "streak_rmse_near_absorbers_per_mm": whole})


def one_sample(ctk_bin, work, seed, views, random_draws, budget, score, log):
    work.mkdir(parents=True, exist_ok=True)
    sample = random_sample(seed)
    sample_file = work / "sample.json"
    sample_file.write_text(json.dumps(sample, indent=1))
    start = time.time()
    directions = pool_directions()
    proxy = Proxy(simulate_pool(ctk_bin, work, sample_file, directions, seed), sample_file, score)
    log(f"seed {seed}: pool of {len(directions)} views simulated and read ({time.time() - start:.0f} s)")
    depth = optical_depth_through_absorbers(proxy, ABSORBER_ABOVE_PER_MM)
    members, whole_proxy, oracle_proxy, share, history, whole_sphere = oracle_search(
        proxy, depth, views, budget, np.random.default_rng(seed), log)
    share_in_absorbers = error_share_in_absorbers(proxy, whole_sphere, ABSORBER_ABOVE_PER_MM)
    spares = [i for i in range(len(directions)) if i not in members]
    ctk.write_directions(work / "oracle.json", "oracle", directions[members + spares])
    search_seconds = time.time() - start
    out = work / "plan"
    run([ctk_bin, "plan", "--out", str(out), "--phantom", str(sample_file), "--seed", str(seed), "--views", str(views),
         "--compare", "--random-draws", str(random_draws), "--compare-directions", str(work / "oracle.json")],
        work / "plan.log")
    gains, whole_sphere_figures = scored(out)
    rule = rule_check(proxy, work, sample_file, directions, views, whole_proxy)
    return {"seed": seed, "half": "choice" if seed % 2 == 0 else "report", "sample": sample,
            "gains": gains, "whole_sphere": whole_sphere_figures,
            "search": {"evaluations": proxy.evaluations, "pool_views": len(directions), "score": score,
                       "proxy_score_whole_sphere_per_mm": whole_proxy, "proxy_score_oracle_per_mm": oracle_proxy,
                       "proxy_gain": (whole_proxy - oracle_proxy) / whole_proxy, "left_out_share": share,
                       "whole_sphere_error_share_in_absorbers": share_in_absorbers,
                       "optical_depth_quantiles": [float(q) for q in np.quantile(depth, [0, 0.5, 0.9, 1])],
                       "history": history,
                       "seconds": search_seconds},
            "rule_check": rule,
            "seconds": time.time() - start}


def summary(cases, key):
    rng = np.random.default_rng(0)

    def mean_interval(values):
        if not values:
            return None
        lo, hi = bootstrap_interval(values, rng)
        return {"mean": float(np.mean(values)), "interval_95": [lo, hi], "samples": len(values)}
    out = {}
    figures = ("rmse", "rmse_level_matched", "edge_gradient", "streaks_near_absorbers")
    for who in ("planned", "oracle"):
        out[who] = {f: mean_interval([c["gains"][who][f] for c in cases if c["gains"][who].get(f) is not None])
                    for f in figures}
    out["random"] = {f: mean_interval([np.mean([r[f] for r in c["gains"]["random"]]) for c in cases
                                       if c["gains"]["random"][0].get(f) is not None]) for f in figures}
    if cases and all("rule_check" in c for c in cases):
        out["search_score"] = {
            "oracle": mean_interval([c["search"]["proxy_gain"] for c in cases]),
            "rule_on_truth": mean_interval([c["rule_check"]["rule_on_truth"]["mean"] for c in cases]),
            "rule_on_own_picture": mean_interval([c["rule_check"]["rule_on_own_picture"]["mean"] for c in cases]),
            "planned_on_pool": mean_interval([c["rule_check"]["planned_on_pool"] for c in cases])}
    strong = [c for c in cases if c["gains"]["oracle"].get(key, 0) >= 0.10]
    out[f"planned_share_of_oracle_where_oracle_gains_10_percent_{key}"] = [
        {"seed": c["seed"], "share": c["gains"]["planned"][key] / c["gains"]["oracle"][key]} for c in strong]
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--ctk", required=True)
    p.add_argument("--work", type=Path, default=Path("/tmp/plan-oracle"))
    p.add_argument("--seeds", type=int, nargs="+", default=list(range(1, 9)))
    p.add_argument("--views", type=int, default=100)
    p.add_argument("--random-draws", type=int, default=3)
    p.add_argument("--budget", type=int, default=60, help="reconstructions the oracle's search may spend per sample")
    p.add_argument("--score", choices=tuple(SCORES), default="level-matched",
                   help="what the search lowers: the RMSE with each material at its reconstructed level, or the plain RMSE")
    p.add_argument("--out", type=Path)
    p.add_argument("--rescore", action="store_true",
                   help="score the runs already in --work again (the figures of this script), rewriting --out")
    p.add_argument("--rule-check", action="store_true",
                   help="with --rescore: the planner's rule on the truth and on its own picture, scored on the pool "
                        "(rule_check per case; about 20 s per sample)")
    a = p.parse_args()
    out = a.out or Path(__file__).resolve().parent / "results" / f"planning_oracle-{cpu_slug()}.json"
    if a.rescore:
        result = json.loads(out.read_text())
        result["rescored"] = {"command": " ".join(sys.argv), "work": str(a.work)}  # the folders scored now
        for c in result["cases"]:
            work = a.work / f"seed-{c['seed']}"
            c["gains"], c["whole_sphere"] = scored(work / "plan")
            if a.rule_check:
                proxy = Proxy(work / "pool" / "scan.json", work / "sample.json", result.get("score", "rmse"))
                c["rule_check"] = rule_check(proxy, work, work / "sample.json", pool_directions(), result["views"],
                                             c["search"]["proxy_score_whole_sphere_per_mm"])
                print(f"seed {c['seed']}: {json.dumps(c['rule_check'])}", flush=True)
        write_result(result, result["cases"], out)
        return
    cases = []
    for seed in a.seeds:
        cases.append(one_sample(a.ctk, a.work / f"seed-{seed}", seed, a.views, a.random_draws, a.budget, a.score,
                                lambda line: print(line, flush=True)))
        g = cases[-1]["gains"]
        print(f"seed {seed}: RMSE gain planned {g['planned']['rmse']:+.2%} oracle {g['oracle']['rmse']:+.2%} "
              f"random {np.mean([r['rmse'] for r in g['random']]):+.2%}; levels matched planned "
              f"{g['planned']['rmse_level_matched']:+.2%} oracle {g['oracle']['rmse_level_matched']:+.2%}; edge planned "
              f"{g['planned']['edge_gradient']:+.2%} oracle {g['oracle']['edge_gradient']:+.2%} "
              f"({cases[-1]['seconds']:.0f} s)", flush=True)
        result = {"cpu": cpu_name(), "command": " ".join(sys.argv), "views": a.views, "budget": a.budget,
                  "score": a.score}
        write_result(result, cases, out)


def write_result(result, cases, out):
    """The cases with the population's and each half's summary, and the picture beside them."""
    key, searched_on = SCORES[result.get("score", "rmse")]
    result.update({"cases": cases, "population": summary(cases, key),
                   "report_half": summary([c for c in cases if c["half"] == "report"], key),
                   "choice_half": summary([c for c in cases if c["half"] == "choice"], key)})
    out.write_text(json.dumps(result, indent=1) + "\n")
    picture(cases, out.with_suffix(".png"),
            bars=(("oracle", f"oracle (searched on {searched_on})", "tab:green"), ("planned", "planned", "tab:blue")))
    print(json.dumps(result["population"], indent=1))


if __name__ == "__main__":
    main()
