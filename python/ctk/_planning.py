"""View planning from Python: `ctk plan` against the simulated lab (with the comparison of the
planned, whole-sphere and random trajectories) and with a lab through request/answer files, and
the files it writes (ctk-plan/1 trajectory.json, ctk-plan-comparison/1 comparison.json) read back."""
from __future__ import annotations

import dataclasses
import logging
import os
from typing import Callable, Optional, Sequence

import numpy as np

from . import _ctk
from ._reports import read_report

_log = logging.getLogger("ctk")

ViewCallback = Callable[[str, dict], Optional[bool]]


@dataclasses.dataclass
class PlannedTrajectory:
    """One trajectory as written: its folder (scan.json, geometry.json, trajectory.json and the
    projections), the ctk-plan/1 report (every request in order: scout or planned, acquired or
    refused with the reason, calibrated, the damage predicted when it was chosen), the calibrated
    views' matrices (views, 3, 4) in request order, and the pictures drawn for it."""

    name: str
    folder: str
    report: dict
    matrices: np.ndarray
    pictures: list
    brief: str
    seconds: float

    @property
    def scan_file(self) -> str:
        return os.path.join(self.folder, "scan.json")

    @property
    def geometry_file(self) -> str:
        return os.path.join(self.folder, "geometry.json")

    @property
    def views(self) -> list:
        """The requests, as trajectory.json lists them."""
        return self.report["views"]


@dataclasses.dataclass
class PlanResult:
    """What `plan` made: the trajectories by name ('planned', and with compare 'whole-sphere',
    'random', 'random-2', ...), the ctk-plan-comparison/1 report when they were compared, a
    summary and the wall time. `stopped`: the callback or Ctrl-C ended the run (the folders
    finished before are complete, nothing else is returned)."""

    trajectories: dict
    comparison: Optional[dict]
    brief: str
    seconds: float
    stopped: bool = False

    @property
    def planned(self) -> Optional[PlannedTrajectory]:
        return self.trajectories.get("planned")


def _trajectory(d: dict) -> PlannedTrajectory:
    return PlannedTrajectory(name=d["name"], folder=os.fspath(d["folder"]), report=d["report"], matrices=d["matrices"],
                             pictures=[os.fspath(p) for p in d["pictures"]], brief=d["brief"], seconds=d["seconds"])


def _hook(callback: Optional[ViewCallback]):
    def on_view(trajectory: str, record: dict) -> bool:
        _log.info("plan %s: request %d %s", trajectory, record["request"],
                  "calibrated" if record.get("calibrated") else record.get("reason", record["status"]))
        return True if callback is None else callback(trajectory, record) is not False
    return on_view


def plan(out: str | os.PathLike, *, phantoms: Sequence[str], holder: str | os.PathLike = "reference", views: int = 100, scout_nside: int = 2,
         candidate_nside: int = 8, damage_exponent: float = 0.25, spread_exponent: float = 4.0,
         widest_gap_fraction: float = 0.5, edge_tangency_weight: float = 1.0, tangent_width_deg: float = 10.0,
         picture_median: bool = True, seed: int = 1, coarse_size: int = 128, coarse_voxel_mm: float = 0.75,
         binning: int = 3, detector_shape: tuple[int, int] = (720, 720), pitch_mm: float = 0.6, sdd_mm: float = 2150.0,
         sod_mm: float = 1360.0, kvp: float = 90.0, filter_al_mm: float = 2.0, flat_counts: float = 1e4,
         compare: bool = False, compare_only: bool = False, random_draws: int = 1,
         compare_directions: Sequence[str | os.PathLike] = (), eval_size: int = 0,
         eval_voxel_mm: float = 0.5, eval_iterations: int = 20, eval_lambda: float = 3.0, eval_binning: int = 2,
         callback: Optional[ViewCallback] = None) -> PlanResult:
    """`ctk plan --phantom`: an absorption-aware spherical trajectory planned against the
    simulated lab (phantoms: built-in names or ctk-phantom/1 files, in `holder`: reference,
    thesis-first or a ctk-holder/1 file),
    each view calibrated from its spheres, written to `out`/planned. compare: the whole-sphere and
    `random_draws` random trajectories of as many views are acquired too, each reconstructed alike
    (WLS-CG, eval_*; eval_size 0: a volume holding the holder and the sample) and scored against
    the voxelised truth (comparison.json), as are the trajectories of `compare_directions`
    (ctk-directions/1 files, see write_directions). compare_only: score the trajectories already in `out`.
    The keywords are the command's options (detector_shape is (rows, cols)).

    callback(trajectory, record) sees every request as it is settled (its trajectory.json entry);
    returning False stops the run, as does Ctrl-C (KeyboardInterrupt). Progress goes to the 'ctk'
    logger. A bad keyword is a ValueError naming it; a phantom file that cannot be read, or an `out`
    holding an input, an InputError."""
    keywords = {k: v for k, v in locals().items() if k not in ("callback",)}
    keywords["out"] = os.fspath(out)
    keywords["phantoms"] = [os.fspath(p) for p in phantoms]
    keywords["holder"] = os.fspath(holder)
    keywords["compare_directions"] = [os.fspath(p) for p in compare_directions]
    keywords["detector_shape"] = list(detector_shape)
    d = _ctk._plan(keywords, _hook(callback), lambda line: _log.info("plan: %s", line))
    if d["stopped"]:
        return PlanResult(trajectories={}, comparison=None, brief="stopped", seconds=0.0, stopped=True)
    trajectories = {t["name"]: _trajectory(t) for t in d["trajectories"]}
    _log.info("%s", d["brief"])
    return PlanResult(trajectories=trajectories, comparison=d["comparison"], brief=d["brief"], seconds=d["seconds"])


def plan_lab(lab: str | os.PathLike, setup: str | os.PathLike, out: str | os.PathLike, *, views: int = 100,
             scout_nside: int = 2, candidate_nside: int = 8, damage_exponent: float = 0.25, spread_exponent: float = 4.0,
             widest_gap_fraction: float = 0.5, edge_tangency_weight: float = 1.0, tangent_width_deg: float = 10.0,
             picture_median: bool = True, seed: int = 1, coarse_size: int = 128, coarse_voxel_mm: float = 0.75,
             binning: int = 3, sod_mm: float = 1360.0, timeout_s: int = 600,
             callback: Optional[ViewCallback] = None) -> Optional[PlannedTrajectory]:
    """`ctk plan --lab`: plans with a lab's acquisition process through request/answer files in
    `lab` (formats in libplan/README.md), from the lab's ctk-scan/1 `setup` (detector, robot
    frames, holder, flat, dark), and writes the planned scan to `out` (nothing in `lab` is
    touched). Run again with the same settings it replays the answers already given. timeout_s:
    the wait for each answer. callback as for `plan`; None when it stopped the run."""
    keywords = {k: v for k, v in locals().items() if k not in ("callback",)}
    for k in ("lab", "setup", "out"):
        keywords[k] = os.fspath(keywords[k])
    d = _ctk._plan_lab(keywords, _hook(callback))
    return None if d["stopped"] else _trajectory(d["trajectory"])


def read_plan(file: str | os.PathLike) -> dict:
    """A planned trajectory's trajectory.json (ctk-plan/1) as a dict: every request under 'views',
    the planner's settings under 'planner'; InputError unless it is one (naming the key)."""
    return read_report(file, "ctk-plan/1", {"views": list, "planner": dict})


def read_plan_comparison(file: str | os.PathLike) -> dict:
    """comparison.json (ctk-plan-comparison/1) as a dict: per trajectory the RMSE, the RMSE outside
    the absorbers, the RMSE with each material at its reconstructed level (and those levels), the
    edge and profile gradients, and the random draws' spread."""
    return read_report(file, "ctk-plan-comparison/1", {"trajectories": dict, "random_draws": dict})


def planning_directions(nside: int = 8, order: str = "healpix") -> np.ndarray:
    """The planner's directions (n, 3), unit beam directions in the holder frame: its candidates,
    the HEALPix cell centres of `nside` (order 'healpix'), or the same cells in the order the
    whole-sphere trajectory takes them ('whole-sphere': each next one farthest from those before)."""
    return _ctk._planning_directions(nside, order)


def view_matrix(direction, *, detector_shape: tuple[int, int] = (720, 720), pitch_mm: float = 0.6,
                sdd_mm: float = 2150.0, sod_mm: float = 1360.0) -> np.ndarray:
    """The 3 x 4 matrix of a view along `direction` (holder frame) with the detector centred on
    the beam at the setup's distances, as the planner pictures a view (a robot's view along the
    same direction differs by its roll and its errors). detector_shape is (rows, cols)."""
    return _ctk._view_matrix(tuple(float(x) for x in direction), tuple(detector_shape), pitch_mm, sdd_mm,
                             sod_mm)[0]


def plan_on_picture(picture: np.ndarray, *, reachable: Optional[Callable[[tuple[float, float, float]], bool]] = None,
                    views: int = 100, scout_nside: int = 2, candidate_nside: int = 8, damage_exponent: float = 0.25,
                    spread_exponent: float = 4.0, widest_gap_fraction: float = 0.5, edge_tangency_weight: float = 1.0,
                    tangent_width_deg: float = 10.0, picture_median: bool = True, seed: int = 1, coarse_size: int = 128,
                    coarse_voxel_mm: float = 0.75, sdd_mm: float = 2150.0, sod_mm: float = 1360.0) -> np.ndarray:
    """The directions (views, 3) the planner's rule draws when its picture of the sample is
    `picture` from the start (an array (z, y, x) on its coarse grid: coarse_size^3 voxels of
    coarse_voxel_mm centred on the holder origin, e.g. the truth from voxelise) and every
    direction `reachable(direction)` allows is taken exactly as requested. The scout comes first,
    then the draws, with damage and edge demand read off `picture` once: the rule checked apart from
    how well the scout's reconstruction shows the sample. The keywords are plan()'s."""
    keywords = {k: v for k, v in locals().items() if k not in ("picture", "reachable")}
    return _ctk._plan_on_picture(keywords, np.asarray(picture, dtype=np.float32), reachable)


def read_directions(file: str | os.PathLike) -> tuple[str, np.ndarray]:
    """A ctk-directions/1 file: the trajectory's name and its directions (n, 3) in the order they
    are tried."""
    d = _ctk._read_directions(os.fspath(file))
    return d["name"], d["directions"]


def write_directions(file: str | os.PathLike, name: str, directions) -> None:
    """Writes a trajectory as ctk-directions/1 (beam directions in the holder frame, tried in order
    until the trajectory has its views, so spares may follow), for plan(compare_directions=...) and
    `ctk plan --compare-directions`. `name` becomes its folder: lower-case letters, digits and '-',
    none of the comparison's own names."""
    _ctk._write_directions(os.fspath(file), name, np.asarray(directions, dtype=np.float64))
