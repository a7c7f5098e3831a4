"""The projector from Python: adjointness, subsets, arrays shared rather than copied, shapes
refused, scipy's solvers on the adapter."""
import json
import subprocess

import numpy as np
import pytest
from scipy.sparse.linalg import lsqr

import ctk


def adjoint_mismatch(A, seed):
    rng = np.random.default_rng(seed)
    x = rng.random(A.volume_shape, dtype=np.float32)
    y = rng.random(A.projection_shape, dtype=np.float32)
    Ax, Aty = A.forward(x), A.adjoint(y)
    lhs = np.vdot(Ax.astype(np.float64), y)
    rhs = np.vdot(x.astype(np.float64), Aty)
    return abs(lhs - rhs) / (np.linalg.norm(Ax) * np.linalg.norm(y))


def test_every_operator_is_adjoint_to_float_rounding(small_projector):
    A = small_projector
    binned = ctk.BinnedProjection(A, 3)
    factors = np.random.default_rng(3).random(binned.projection_shape, dtype=np.float32)
    for op in (A, binned, ctk.WeightedProjection(binned, factors), A.subset([5, 0, 17])):
        assert adjoint_mismatch(op, 11) < 1e-5
    assert binned.projection_shape == (24, 13, 18)  # partial last row and column dropped


def test_a_subset_projects_its_views_as_the_whole_does(small_projector):
    x = np.random.default_rng(4).random(small_projector.volume_shape, dtype=np.float32)
    whole = small_projector.forward(x)
    chosen = [7, 2, 23]
    part = small_projector.subset(chosen).forward(x)
    np.testing.assert_allclose(part, whole[chosen], rtol=1e-6, atol=1e-6)
    np.testing.assert_array_equal(small_projector.subset(chosen).matrices, small_projector.matrices[chosen])


def test_outputs_are_written_in_place_and_results_are_not_copied(small_projector):
    A = small_projector
    x = np.random.default_rng(5).random(A.volume_shape, dtype=np.float32)
    out = np.empty(A.projection_shape, dtype=np.float32)
    y = A.forward(x, out=out)
    assert np.shares_memory(y, out)
    back = np.empty(A.volume_shape, dtype=np.float32)
    assert np.shares_memory(A.adjoint(y, out=back), back)
    # A volume of another dtype or order is converted once, with the same result.
    np.testing.assert_array_equal(A.forward(x.astype(np.float64)), y)
    np.testing.assert_array_equal(A.forward(np.asfortranarray(x)), y)
    # A solver's result is the C++ volume itself, handed over: writable, owning no copy of b.
    result = ctk.wls_cg(A, y, iterations=1)
    assert result.x.flags.c_contiguous and result.x.dtype == np.float32 and result.x.shape == A.volume_shape


def test_shapes_that_do_not_fit_are_refused_with_the_shape_expected(small_projector):
    A = small_projector
    with pytest.raises(ValueError, match=r"expected \(18, 20, 22\)"):
        A.forward(np.zeros((18, 20, 21), np.float32))
    with pytest.raises(ValueError, match=r"\(views, rows, cols\)"):
        A.adjoint(np.zeros((24, 40, 55), np.float32))
    with pytest.raises(ValueError, match="out="):
        A.forward(np.zeros(A.volume_shape, np.float32), out=np.zeros(A.projection_shape, np.float64))
    with pytest.raises(IndexError):
        A.subset([24])
    with pytest.raises(ValueError, match=r"\(views, 3, 4\)"):
        ctk.Projector(np.zeros((3, 4, 3)), (4, 4, 4), detector_shape=(8, 8))
    with pytest.raises(ValueError):
        ctk.BinnedProjection(A, 0)
    with pytest.raises(ValueError, match="WlsOptions.iterations"):
        ctk.wls_cg(A, np.zeros(A.projection_shape, np.float32), iterations=-1)
    with pytest.raises(ValueError, match="SirtOptions.relaxation"):
        ctk.sirt(A, np.zeros(A.projection_shape, np.float32), relaxation=2.5)
    with pytest.raises(ValueError, match="regulariser"):
        ctk.wls_cg(A, np.zeros(A.projection_shape, np.float32), regulariser="tv")
    with pytest.raises(ValueError, match="preconditioner"):
        ctk.wls_cg(A, np.zeros(A.projection_shape, np.float32), preconditioner="jacobi")


def test_scipy_lsqr_on_the_adapter_converges(small_projector):
    A = small_projector
    truth = np.zeros(A.volume_shape, np.float32)
    truth[5:13, 6:14, 7:15] = 0.02
    b = A.forward(truth)
    op = ctk.as_linear_operator(A)
    assert op.shape == (b.size, truth.size)
    solution = lsqr(op, b.ravel(), iter_lim=60, atol=0, btol=0)
    x = solution[0]
    assert np.linalg.norm(op.matvec(x) - b.ravel()) < 0.02 * np.linalg.norm(b)
    # And the solver of ctk agrees on the data fit.
    r = ctk.wls_cg(A, b, iterations=60, tolerance=0)
    assert r.iterations[-1]["data_term"] < 1e-3 * r.iterations[0]["data_term"]
    # Preconditioned by the separable curvature, to the same fit.
    p = ctk.wls_cg(A, b, iterations=60, tolerance=0, preconditioner="diagonal")
    assert p.iterations[-1]["data_term"] < 1e-3 * p.iterations[0]["data_term"]


def test_a_callback_sees_every_iteration_and_may_stop_the_solve(small_projector):
    A = small_projector
    b = A.forward(np.ones(A.volume_shape, np.float32))
    seen = []
    r = ctk.wls_cg(A, b, iterations=10, tolerance=0, callback=lambda log: (seen.append(log["iteration"]), log["iteration"] < 3)[1])
    assert seen == [0, 1, 2, 3]
    assert r.stop_reason == "stopped by the callback"
    assert len(r.iterations) == 4
    costs = [it["cost"] for it in r.iterations]
    assert all(b < a for a, b in zip(costs, costs[1:]))
    # An exception in the callback (Ctrl-C arrives as one) stops the solve and reaches the caller.
    def interrupt(log):
        if log["iteration"] == 2:
            raise KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt):
        ctk.sirt(A, b, iterations=50, callback=interrupt)


def test_sirt_and_fdk_from_python(small_projector):
    from conftest import orbit_matrices

    A = ctk.Projector(orbit_matrices(120), (18, 20, 22), voxel_mm=1.5, detector_shape=(40, 56))
    truth = np.zeros(A.volume_shape, np.float32)
    truth[4:14, 5:15, 6:16] = 0.03
    b = A.forward(truth)
    r = ctk.sirt(A, b, iterations=30)
    assert r.cost < 0.05 * r.iterations[0]["cost"]
    assert (r.x >= 0).all()
    x = ctk.fdk(A, b)
    assert abs(float(np.mean(x[7:11, 8:12, 9:13])) - 0.03) < 0.003  # the cube's core
    assert abs(float(np.mean(x[:, :2, :])) ) < 0.003  # outside it
    # Sources at two radii are not a circle: FDK is refused, saying by how much.
    mixed = np.concatenate([orbit_matrices(12, sod=300.0), orbit_matrices(12, sod=360.0)])
    B = ctk.Projector(mixed, (18, 20, 22), voxel_mm=1.5, detector_shape=(40, 56))
    with pytest.raises(ValueError, match="mm"):
        ctk.fdk(B, np.zeros(B.projection_shape, np.float32))


def test_os_sqs_from_python_fits_in_few_epochs_on_any_operator():
    from conftest import orbit_matrices

    A = ctk.Projector(orbit_matrices(120), (18, 20, 22), voxel_mm=1.5, detector_shape=(40, 56))
    truth = np.zeros(A.volume_shape, np.float32)
    truth[4:14, 5:15, 6:16] = 0.03
    b = A.forward(truth)
    seen = []
    r = ctk.os_sqs(A, b, epochs=6, subsets=10, callback=lambda log: seen.append(log["iteration"]))
    assert seen == list(range(7))
    assert "10 subsets" in r.stop_reason
    cg = ctk.wls_cg(A, b, iterations=6, tolerance=0)
    # Six epochs of ten subsets fit the data better than six CG iterations (the same passes).
    data_term = 0.5 * float(np.sum((A.forward(r.x) - b).astype(np.float64) ** 2))
    assert data_term < cg.iterations[-1]["data_term"]
    assert (r.x >= 0).all()
    # A composed operator has no matrices: its subsets are interleaved by index, and it works too.
    binned = ctk.BinnedProjection(A, 2)
    rb = ctk.os_sqs(binned, binned.forward(truth), epochs=4, subsets=6)
    assert rb.iterations[-1]["cost"] < 0.05 * rb.iterations[0]["cost"]
    with pytest.raises(ValueError, match="OsSqsOptions.epochs"):
        ctk.os_sqs(A, b, epochs=-1)


def test_ctrl_c_stops_a_projection_and_a_solve_within_a_second():
    import os
    import signal
    import threading
    import time

    P = ctk.circular_matrices(np.linspace(0, 360, 360, endpoint=False), (256, 256), (1.0, 1.0), sod=500, sdd=1000)
    A = ctk.Projector(P, (256, 256, 256), voxel_mm=0.5, detector_shape=(256, 256))
    x = np.ones(A.volume_shape, dtype=np.float32)
    start = time.perf_counter()
    whole = A.forward(x)
    seconds = time.perf_counter() - start

    def interrupted_after(delay, call):
        timer = threading.Timer(delay, lambda: os.kill(os.getpid(), signal.SIGINT))
        start = time.perf_counter()
        timer.start()
        with pytest.raises(KeyboardInterrupt):
            call()
        timer.join()
        return time.perf_counter() - start - delay

    # Stopped within the projection (which takes seconds here), not after it.
    assert seconds > 1.0, f"the projection took {seconds:.2f} s: too short to interrupt"
    late = interrupted_after(0.3, lambda: A.forward(x))
    assert late < min(1.0, 0.5 * seconds), f"stopped {late:.2f} s after Ctrl-C (a projection takes {seconds:.2f} s)"
    # A solve stops inside an iteration too (one takes two projections here), and the next call
    # runs whole. (Its first fraction of a second, allocating and clearing its vectors, is not
    # looked into: 0.75 s here for 0.4 GB.)
    late = interrupted_after(1.5, lambda: ctk.wls_cg(A, whole, iterations=20))
    assert late < 1.0, f"the solve stopped {late:.2f} s after Ctrl-C"
    np.testing.assert_array_equal(A.forward(x), whole)


def test_bench_measures_the_projector_against_the_reference_as_the_command_line_does(ctk_command):
    report = ctk.bench(scale=16, views=8, reference_views=2)
    for direction in (report["forward"], report["back"], report["spherical"]["forward"], report["spherical"]["back"]):
        assert direction["relative_difference_to_reference"] < 1e-5
        assert direction["reference_views_measured"] == 2
    done = subprocess.run([ctk_command, "bench", "--scale", "16", "--views", "8", "--reference-views", "2", "--json"],
                          capture_output=True, text=True, check=True)
    assert set(json.loads(done.stdout)) == set(report)
    with pytest.raises(ValueError, match="ProjectorBenchmarkOptions.simd"):
        ctk.bench(scale=16, views=8, simd="AVX9")


def test_sizes_and_threads_are_refused_as_the_command_line_refuses_them(tmp_path):
    """A voxel of zero or negative size, or a thread count no machine has, is refused naming the
    keyword (a negative voxel gave a mirrored volume; 100,000 threads ended the interpreter)."""
    P = np.tile(np.array([[1000.0, 0, 20, 0], [0, 1000, 20, 0], [0, 0, 1, 500]]), (3, 1, 1))
    for voxel in (0, -1, (1, 0, 1), float("nan")):
        with pytest.raises(ValueError, match="voxel_mm: expected finite sizes above 0"):
            ctk.Projector(P, (8, 8, 8), voxel_mm=voxel, detector_shape=(40, 40))
        with pytest.raises(ValueError, match="voxel_mm: expected finite sizes above 0"):
            ctk.write_volume(np.zeros((2, 2, 2), np.float32), tmp_path / "v.nrrd",
                             voxel_mm=voxel if isinstance(voxel, tuple) else (voxel, 1, 1))
    assert not (tmp_path / "v.nrrd").exists()
    with pytest.raises(ValueError, match=r"ProjectorOptions.threads: expected 0 .* \(four per processor\), got 100000"):
        ctk.Projector(P, (8, 8, 8), voxel_mm=1, detector_shape=(40, 40), threads=100000)


def test_the_penalty_weight_has_the_command_lines_name(small_projector):
    """lambda_ as reconstruct() and --lambda name it; lam, the earlier name, the same solve with a
    DeprecationWarning; both at once and different refused."""
    A = small_projector
    b = A.forward(np.random.default_rng(3).random(A.volume_shape, dtype=np.float32))
    new = ctk.wls_cg(A, b, iterations=3, lambda_=2.0)
    with pytest.warns(DeprecationWarning, match="lam is now lambda_"):
        old = ctk.wls_cg(A, b, iterations=3, lam=2.0)
    assert np.array_equal(new.x, old.x)
    assert not np.array_equal(new.x, ctk.wls_cg(A, b, iterations=3).x)
    with pytest.raises(ValueError, match="disagree"):
        ctk.os_sqs(A, b, epochs=1, subsets=2, lambda_=1.0, lam=2.0)
