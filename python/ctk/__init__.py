"""ctk: calibration and reconstruction of cone-beam CT along arbitrary trajectories.

Arrays follow numpy order: volumes are float32 (z, y, x), projection stacks float32
(views, rows, cols), matrices float64 (views, 3, 4) mapping holder-frame millimetres to detector
pixels (u = column, v = row). Points and sizes in millimetres are (x, y, z).

Float32 C-contiguous arrays are read and written in place (no copy); other arrays are converted
once on the way in. The solvers copy their data term (b, weights) into their own storage; their
result is returned without a copy.
"""
from __future__ import annotations

import dataclasses
import json
import logging
import os
import warnings
from typing import Callable, Optional, Sequence

import numpy as np

from ._ctk import (  # noqa: F401  (re-exported)
    BinnedProjection,
    InputError,
    Operator,
    Projector,
    WeightedProjection,
    __build__,
    __version__,
    cone_vec_from_matrices,
    circular_matrices,
    fdk,
    import_nikon,
    import_nxtomo,
    import_scan,
    matrices_from_cone_vec,
    read_image,
    read_cone_vec,
    read_geometry,
    read_nxtomo,
    read_rtk_geometry,
    read_xtekct,
    read_scan,
    read_volume,
    voxelise,
    voxelise_per_material,
    write_geometry,
    write_rtk_geometry,
    write_scan,
    write_volume,
)
from . import _ctk
from ._planning import (PlannedTrajectory, PlanResult, plan, plan_lab, plan_on_picture, planning_directions, read_directions, read_plan,
                        read_plan_comparison, view_matrix, write_directions)
from ._reports import read_report

_log = logging.getLogger("ctk")

__all__ = [
    "BinnedProjection", "CalibrationResult", "DiagnosisResult", "InputError", "ReconstructionResult", "RefineResult", "SimulationResult", "calibrate", "diagnose", "measure_holder", "reconstruct", "simulate", "circular_matrices", "import_nikon", "import_nxtomo", "import_scan", "refine", "Operator", "Projector", "SolveResult", "WeightedProjection", "read_volume", "voxelise", "voxelise_per_material", "write_volume",
    "Measurements", "__build__", "__version__", "as_linear_operator", "load_measurements", "read_image", "cone_vec_from_matrices", "fdk", "geometry_matrices",
    "matrices_from_cone_vec", "read_cone_vec", "read_diagnosis", "read_geometry", "read_nxtomo", "read_rtk_geometry", "read_scan", "read_xtekct",
    "os_sqs", "sirt", "wls_cg", "write_geometry", "write_rtk_geometry", "write_scan",
    "PlanResult", "PlannedTrajectory", "plan", "plan_lab", "read_plan", "read_plan_comparison", "bench",
    "planning_directions", "plan_on_picture", "view_matrix", "read_directions", "write_directions",
]


@dataclasses.dataclass
class SolveResult:
    """What a solver returns: the volume (z, y, x), the per-iteration log (iteration 0 is the
    start: cost, data_term, regulariser_term, relative_gradient, seconds) and why it stopped."""

    x: np.ndarray
    iterations: list
    stop_reason: str

    @property
    def cost(self) -> float:
        """The objective after the last iteration."""
        return self.iterations[-1]["cost"]


def _optional_path(path: Optional[str | os.PathLike]) -> Optional[str]:
    return None if path is None else os.fspath(path)


def _iteration_hook(method: str, callback: Optional[Callable[[dict], Optional[bool]]]):
    def hook(log: dict) -> bool:
        _log.info("%s iteration %d: cost %.6g (%.2f s)", method, log["iteration"], log["cost"], log["seconds"])
        return True if callback is None else callback(log) is not False
    return hook


def _penalty_weight(lambda_: float, lam: Optional[float]) -> float:
    """One name for the penalty's weight everywhere, as the command line's --lambda: lambda_
    (`lam`, its earlier name, still taken with a DeprecationWarning)."""
    if lam is None:
        return lambda_
    warnings.warn("lam is now lambda_ (as reconstruct() and the command line's --lambda)", DeprecationWarning, stacklevel=3)
    if lambda_ != 0.0 and lambda_ != lam:
        raise ValueError(f"lambda_ ({lambda_}) and its old name lam ({lam}) disagree: give lambda_ alone")
    return lam


def wls_cg(operator: Operator, b: np.ndarray, *, weights: Optional[np.ndarray] = None,
           x0: Optional[np.ndarray] = None, iterations: int = 30, tolerance: float = 1e-4,
           lambda_: float = 0.0, regulariser: str = "identity", preconditioner: str = "none",
           callback: Optional[Callable[[dict], Optional[bool]]] = None, lam: Optional[float] = None) -> SolveResult:
    """Weighted least squares by conjugate gradients on the normal equations,
    minimise 1/2 ||W^(1/2) (A x - b)||^2 + 1/2 lambda_ ||G x||^2 with G the identity or the
    discrete gradient ('gradient'). One forward and one back projection per iteration.
    preconditioner 'diagonal': CG preconditioned by the separable curvature A'WA1 + lambda_ c (one
    more projection pair at the start, one more volume).

    callback(log) is called after every iteration with its log entry; returning False stops the
    solve. Ctrl-C (KeyboardInterrupt) stops it within the iteration under way. Progress goes to
    the 'ctk' logger at INFO level."""
    x, report = _ctk._wls_cg(operator, b, weights, x0, iterations, tolerance, _penalty_weight(lambda_, lam), regulariser,
                             preconditioner,
                             _iteration_hook("wls-cg", callback))
    return SolveResult(x, report["iterations"], report["stop_reason"])


def os_sqs(operator: Operator, b: np.ndarray, *, weights: Optional[np.ndarray] = None, x0: Optional[np.ndarray] = None,
           epochs: int = 8, subsets: int = 12, lambda_: float = 0.0, regulariser: str = "identity", huber_delta: float = 0.0,
           non_negative: bool = True, callback: Optional[Callable[[dict], Optional[bool]]] = None,
           lam: Optional[float] = None) -> SolveResult:
    """OS-SQS with Nesterov momentum on wls_cg's objective (optionally the edge-preserving Huber
    penalty, huber_delta > 0, weighted by lambda_): one step per ordered subset, the subsets spread
    over the views' source directions for a Projector (interleaved by index for other
    operators). One log entry per epoch; callback as for wls_cg (called after each epoch)."""
    x, report = _ctk._os_sqs(operator, b, weights, x0, epochs, subsets, _penalty_weight(lambda_, lam), regulariser, huber_delta,
                             non_negative,
                             _iteration_hook("os-sqs", callback))
    return SolveResult(x, report["iterations"], report["stop_reason"])


def sirt(operator: Operator, b: np.ndarray, *, x0: Optional[np.ndarray] = None, iterations: int = 100,
         relaxation: float = 1.0, non_negative: bool = True,
         callback: Optional[Callable[[dict], Optional[bool]]] = None) -> SolveResult:
    """SIRT, x <- x + C A' R (b - A x) with R and C the inverse row and column sums of A,
    relaxation in (0, 2), optionally kept non-negative. callback as for wls_cg."""
    x, report = _ctk._sirt(operator, b, x0, iterations, relaxation, non_negative,
                           _iteration_hook("sirt", callback))
    return SolveResult(x, report["iterations"], report["stop_reason"])


def as_linear_operator(operator: Operator):
    """A scipy.sparse.linalg.LinearOperator on flattened arrays (volume raveled in (z, y, x)
    order, projections in (views, rows, cols) order), so scipy's solvers (lsqr, cg, ...) run on
    the projector. Vectors are converted to float32."""
    from scipy.sparse.linalg import LinearOperator

    n = int(np.prod(operator.volume_shape))
    m = int(np.prod(operator.projection_shape))

    def matvec(v):
        x = np.ascontiguousarray(np.asarray(v).reshape(operator.volume_shape), dtype=np.float32)
        return operator.forward(x).ravel()

    def rmatvec(v):
        y = np.ascontiguousarray(np.asarray(v).reshape(operator.projection_shape), dtype=np.float32)
        return operator.adjoint(y).ravel()

    return LinearOperator((m, n), matvec=matvec, rmatvec=rmatvec, dtype=np.float32)


def geometry_matrices(geometry: dict) -> tuple[list[int], np.ndarray]:
    """The ok views of a ctk-geometry/1 document (read_geometry) and their matrices
    (views, 3, 4)."""
    ok = [v for v in geometry["views"] if v["status"] == "ok"]
    return [v["index"] for v in ok], np.array([np.reshape(v["P"], (3, 4)) for v in ok], dtype=np.float64).reshape(-1, 3, 4)


@dataclasses.dataclass
class Measurements:
    """A scan's ok views as the solvers take them (see load_measurements)."""

    view_indices: list
    matrices: np.ndarray
    line_integrals: np.ndarray
    weights: Optional[np.ndarray]
    detector_shape: tuple
    pixel_mm: tuple
    clamped_pixels: int
    masked_pixels: int
    left_out: list
    notes: list

    def projector(self, volume_shape, voxel_mm=1.0, origin_mm=None, threads: int = 0) -> Projector:
        """The Joseph projector on these views' matrices and detector."""
        return Projector(self.matrices, volume_shape, voxel_mm, origin_mm, detector_shape=self.detector_shape,
                         threads=threads)


def load_measurements(scan: str | os.PathLike, geometry: Optional[str | os.PathLike] = None, *,
                      statistical_weights: bool = True, undistort: bool = True) -> Measurements:
    """The ok views of a scan (ctk-scan/1) as line integrals (views, rows, cols), their matrices
    and Poisson weights (None for a scan of line integrals), read as `ctk reconstruct` reads
    them: the geometry file's matrices, or the scan's nominal ones; counts become
    -log((I - dark) / (flat - dark)); a declared detector distortion is resampled away."""
    d = _ctk._load_measurements(os.fspath(scan), _optional_path(geometry),
                                statistical_weights, undistort)
    return Measurements(**d)


@dataclasses.dataclass
class RefineResult:
    """What the markerless loop found: the ctk-diagnosis/1 report (dict), the refined geometry
    (ctk-geometry/1 dict) and its ok views' matrices, the central axial slice of FDK with the
    nominal and the refined geometry (y, x), and a one-line summary."""

    report: dict
    geometry: dict
    matrices: np.ndarray
    slice_before: np.ndarray
    slice_after: np.ndarray
    brief: str
    pictures: list = dataclasses.field(default_factory=list)
    page: Optional[str] = None

    @property
    def accepted(self) -> list:
        """The effects accepted, in the order they entered the model."""
        return [e for e in self.report["effects"] if e.get("accepted")]


def refine(scan: str | os.PathLike, geometry: Optional[str | os.PathLike] = None, *,
           effects: Optional[Sequence[str]] = None, coarsening: float = 2.0, blur_arc_deg: float = 0.0,
           z: float = 3.0, pictures: Optional[str | os.PathLike] = None) -> RefineResult:
    """The markerless loop of `ctk refine` on a circular scan: reconstruct from half of the views,
    predict the others, and accept the effects (detector_offset, detector_roll, axis_tilt,
    magnification, angular_blur, beam_hardening, pixel_gain, column_gain; default all) that
    predict held-out views better by more than z standard errors. Each step is logged to the
    'ctk' logger (INFO); Ctrl-C stops the loop between steps. Save the geometry with
    write_geometry. With `pictures` (a path without extension) the pictures and the HTML page
    `ctk refine` writes are written as <pictures>.before.png ... and <pictures>.html; their paths
    are in the result's `pictures` and `page`."""
    d = _ctk._refine(os.fspath(scan), _optional_path(geometry), list(effects or []), coarsening,
                     blur_arc_deg, z, lambda line: _log.info("refine: %s", line), _optional_path(pictures))
    return RefineResult(**d)


@dataclasses.dataclass
class CalibrationResult:
    """What the calibration found: the geometry (ctk-geometry/1 dict: one matrix per ok view, a
    reason per rejected one), the report (ctk-calibration-report/1 dict: per-view table, holder
    wall, the spheres' contrast loss, robot prior) and a summary."""

    geometry: dict
    report: dict
    brief: str
    pictures: list = dataclasses.field(default_factory=list)
    page: Optional[str] = None

    def matrices(self) -> tuple[list[int], np.ndarray]:
        """The ok views and their matrices (views, 3, 4)."""
        return geometry_matrices(self.geometry)


def calibrate(scan: str | os.PathLike, *, min_spheres: int = 6, max_rms_px: float = 0.5, search_px: float = 40.0,
              image_only: bool = False, progress: Optional[Callable[[int, int], None]] = None,
              pictures: Optional[str | os.PathLike] = None) -> CalibrationResult:
    """`ctk calibrate` on a robot scan with a helix holder: every view's matrix from the spheres in
    its image (the robot's forward kinematics as the first guess), an undeclared holder wall (or
    its undeclared ends) measured from the images, the poses combined with the robot's prior
    unless image_only.
    progress(done, total) after each view; Ctrl-C stops the batch (KeyboardInterrupt). Save the
    geometry with write_geometry. With `pictures` (a path without extension) the pictures and the
    HTML page `ctk calibrate --out <pictures>.json` writes are written (<pictures>.residuals.png, ...,
    <pictures>.report.html); their paths are in the result's `pictures` and `page`."""
    d = _ctk._calibrate(os.fspath(scan), min_spheres, max_rms_px, search_px, image_only, progress,
                        _optional_path(pictures))
    _log.info("%s", d["brief"])
    return CalibrationResult(**d)


@dataclasses.dataclass
class SimulationResult:
    """A simulated scan folder: its scan file, the scan (ctk-scan/1 dict, the nominal setup only)
    and the truth (ctk-truth/1 dict: true matrices, poses and every effect applied)."""

    scan_file: str
    scan: dict
    truth: dict
    brief: str
    saturated_pixels: int


def simulate(out: str | os.PathLike, *, phantoms: Sequence[str] = ("helix-holder",),
             holder: str | os.PathLike = "reference", trajectory: str = "circular",
             views: int = 360, nside: int = 3, cap_deg: tuple[float, float] = (5.0, 90.0),
             poses: Optional[str | os.PathLike] = None, detector_shape: tuple[int, int] = (720, 720),
             pitch_mm: float = 0.6, sdd_mm: float = 2150.0, sod_mm: float = 1360.0, supersampling: int = 2,
             output: str = "counts", flat_counts: float = 1e4, dark_counts: float = 100.0, kvp: Optional[float] = None,
             filter_al_mm: float = 2.0, robot_noise_mm: float = 0.1, robot_noise_deg: float = 0.02, seed: int = 1,
             effects: Optional[dict] = None,
             progress: Optional[Callable[[int, int], None]] = None) -> SimulationResult:
    """`ctk simulate`: a scan folder `out` from analytic phantoms (built-in names or ctk-phantom/1
    files) on the reference robot setup, with its truth beside it; `holder` is the one the scan
    declares and "helix-holder" draws (reference, thesis-first or a ctk-holder/1 file). trajectory: circular (joint-7
    orbit of `views`), spherical (HEALPix, 12 nside^2 directions), cap (`views` directions from
    cap_deg[0] to cap_deg[1] off the holder axis while it spins) or random; or `poses`, a
    ctk-geometry/1 file of matrices. detector_shape (rows, cols). `effects` are undeclared errors
    by the names `ctk simulate --help` lists, '-' as '_': {"base_translation_mm": (0, 0, 1.3),
    "source_drift_mm": (0.5, 0), ...}; an unknown name is a ValueError. A folder holding a scan no
    simulation wrote is refused (InputError)."""
    named = None if effects is None else {k: (list(v) if isinstance(v, (tuple, list, np.ndarray)) else v)
                                          for k, v in effects.items()}
    d = _ctk._simulate(os.fspath(out), list(phantoms), os.fspath(holder), trajectory, views, nside, tuple(cap_deg),
                       _optional_path(poses), tuple(detector_shape), pitch_mm, sdd_mm, sod_mm,
                       supersampling, output, flat_counts, dark_counts, kvp, filter_al_mm, robot_noise_mm, robot_noise_deg,
                       seed, named, progress, lambda line: _log.info("simulate: %s", line))
    _log.info("%s", d["brief"])
    scan_file = os.fspath(d["scan_file"])
    with open(os.path.join(os.path.dirname(scan_file), "truth.json"), encoding="utf-8") as f:
        truth = json.load(f)
    return SimulationResult(scan_file=scan_file, scan=read_scan(scan_file), truth=truth, brief=d["brief"],
                            saturated_pixels=d["saturated_pixels"])


@dataclasses.dataclass
class ReconstructionResult:
    """What `reconstruct` made: the volume (z, y, x) in the holder frame, its voxel size and the
    centre of voxel 0 (x, y, z, mm), the ctk-reconstruction-log/1 report (dict: memory plan,
    views used, per-iteration log, why it stopped) and a summary."""

    volume: np.ndarray
    voxel_mm: float
    origin_mm: tuple
    report: dict
    brief: str


def reconstruct(scan: str | os.PathLike, geometry: Optional[str | os.PathLike] = None, *, method: str = "os-sqs",
                iterations: int = 0, held_out_every: Optional[int] = None, subsets: int = 0, lambda_: float = 0.0,
                regulariser: str = "identity", huber_delta: float = 0.0, tolerance: float = 1e-4, preconditioner: str = "none",
                weighted: bool = True, undistort: bool = True, size: Optional[tuple[int, int, int]] = None,
                voxel_mm: float = 0.0, progress: Optional[Callable[[int, int], None]] = None) -> ReconstructionResult:
    """`ctk reconstruct` without files out: the scan's ok views (of `geometry`, or the scan's
    nominal geometry) read, the memory plan checked, and OS-SQS or WLS-CG (Poisson weights for
    counts unless weighted=False), SIRT or FDK (circular scans) run. iterations 0: at most 30 for
    WLS-CG, 8 epochs of OS-SQS (subsets 0: about 15 views each, at most 24), 100 for SIRT, ended
    once the fit of one view in held_out_every (None: 32, as the command line), held out of the
    solve, stops improving, with the best iterate (report["held_out"]); held_out_every=0 runs the
    count on every view; iterations n > 0 runs exactly n on every view. huber_delta > 0
    (OS-SQS only): an edge-preserving Huber penalty weighted by lambda_ instead of the quadratic one.
    preconditioner 'diagonal' (WLS-CG only): CG preconditioned by the separable curvature.
    size (z, y, x) voxels and voxel_mm default to the holder (or the field of view) at a detector
    pixel seen at the holder origin. progress(done, total) while reading and while iterating;
    Ctrl-C stops it within the current iteration (KeyboardInterrupt)."""
    if held_out_every is not None and held_out_every < 0:
        raise ValueError(f"held_out_every: expected 0 (no views held out) or more, got {held_out_every}")
    d = _ctk._reconstruct(os.fspath(scan), _optional_path(geometry), method, iterations,
                          -1 if held_out_every is None else held_out_every, subsets,
                          lambda_, regulariser, huber_delta, tolerance, preconditioner, weighted, undistort, None if size is None else tuple(size), voxel_mm,
                          progress)
    _log.info("%s", d["brief"])
    d["origin_mm"] = tuple(d["origin_mm"])
    return ReconstructionResult(**d)


@dataclasses.dataclass
class DiagnosisResult:
    """What the diagnosis found: the ctk-diagnosis/1 report (dict), the scan with the accepted
    effects declared (ctk-scan/1 dict, its names relative to the original scan's folder) and a
    summary."""

    report: dict
    corrected_scan: dict
    brief: str
    pictures: list = dataclasses.field(default_factory=list)
    page: Optional[str] = None

    @property
    def accepted(self) -> list:
        """The effects accepted."""
        return [e for e in self.report["effects"] if e.get("accepted")]


def diagnose(scan: str | os.PathLike, geometry: str | os.PathLike, *, repeatability_mm: Optional[float] = None,
             repeatability_deg: Optional[float] = None, pictures: Optional[str | os.PathLike] = None) -> DiagnosisResult:
    """`ctk diagnose`: which named effect explains the residual the calibration `geometry` leaves
    (bundle adjustment, held-out acceptance; the robot's repeatability measured on the scan unless
    given). Each step is logged to the 'ctk' logger. With `pictures` (a path without extension)
    the pictures and the HTML page `ctk diagnose --out <pictures>.json` writes are written
    (<pictures>.field-before.png, ..., <pictures>.html); their paths are in the result's
    `pictures` and `page`."""
    d = _ctk._diagnose(os.fspath(scan), os.fspath(geometry), repeatability_mm, repeatability_deg,
                       lambda line: _log.info("diagnose: %s", line), _optional_path(pictures))
    return DiagnosisResult(**d)


def measure_holder(scan: str | os.PathLike, geometry: str | os.PathLike, *, min_views: int = 60,
                   pictures: Optional[str | os.PathLike] = None) -> dict:
    """`ctk holder measure`: every sphere's centre of the holder `scan` declares, measured from the
    scan's calibrated `geometry` (60 or more well-spread views) with its uncertainty. Returns the
    ctk-holder/1 file as a dict (`measurement` says how; write it with json and name it in a
    scan's `holder`). Each step is logged to the 'ctk' logger. With `pictures` (a path without
    extension) the command's picture and page are written too: <pictures>.spheres.png and
    <pictures>.html."""
    d = _ctk._measure_holder(os.fspath(scan), os.fspath(geometry), min_views, lambda line: _log.info("holder: %s", line),
                             _optional_path(pictures))
    _log.info("%s", d["brief"])
    return d["holder"]


def read_diagnosis(file: str | os.PathLike) -> dict:
    """A ctk-diagnosis/1 report (ctk diagnose, ctk refine) as a dict; InputError unless it is one."""
    return read_report(file, "ctk-diagnosis/1")


def bench(*, views: int = 360, reference_views: int = 12, scale: int = 1, threads: int = 0, repeat: int = 1,
          simd: str = "") -> dict:
    """`ctk bench --json`: the fast Joseph projector (all threads, or `threads`) against the naive
    reference (one thread) in the same run on the standard problem, circular and spherical,
    forward and back; the reference timed on `reference_views` views and scaled to `views`. With
    repeat the two take turns and the medians count; simd: a narrower target than the widest.
    Returns the report (cpu, threads, simd, problem, each direction's seconds, speedup, voxel-views
    per second, relative difference to the reference); the table goes to the 'ctk' logger."""
    d = _ctk._bench(views, reference_views, scale, threads, repeat, simd, lambda line: _log.info("bench: %s", line))
    _log.info("%s", d["brief"])
    return d["report"]
