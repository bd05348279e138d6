"""Issue 12: the default operator (Richardson kernel, arc-corrected distances, point-wise moment
correction) against ground truth, and the guarantees that come with it (symmetric S, −S
positive semidefinite or a stated fallback, the paper's operator unchanged on request)."""

import math
import warnings
from dataclasses import replace
from pathlib import Path

import igl
import numpy as np
import pytest

import meshlap
from meshlap import baselines, samples, shapes, spectral
from meshlap.assembly import grid as kernel
from meshlap.corrections import moment_correction

DATA = Path(__file__).parent / "data"
DEGREES = np.repeat(np.arange(6), 2 * np.arange(6) + 1)  # l = 0..5: 36 eigenvalues
EXACT = DEGREES * (DEGREES + 1.0)


def e2(a, t):
    return float(np.linalg.norm(a - t) / np.linalg.norm(t))


def sphere_errors(kind, n):
    V, F = shapes.sphere(n, kind=kind, seed=0)
    U = V / np.linalg.norm(V, axis=1, keepdims=True)
    op = meshlap.laplacian(V, F)
    funcs = shapes.sphere_functions()
    errs = {name: e2(op @ f(U), lap(U)) for name, (f, lap) in funcs.items()}
    lam, _ = spectral.eigs(op, 36)
    return op, errs, float(np.max(np.abs(lam[1:] - EXACT[1:]) / EXACT[1:]))


def real_mesh(name):
    V, F = igl.read_triangle_mesh(str(DATA / f"{name}.obj"))
    used = np.unique(F)
    remap = np.full(len(V), -1)
    remap[used] = np.arange(len(used))
    V, F = V[used], remap[F]
    return V / math.sqrt(igl.doublearea(V, F).sum() / 2), F


def eig_error_vs_cotangent(name, k=12, **options):
    V, F = real_mesh(name)
    ref, _ = spectral.eigs(baselines.cotangent(V, F), k)
    lam, _ = spectral.eigs(meshlap.laplacian(V, F, **options), k)
    return float(np.max(np.abs(lam[1:] - ref[1:]) / ref[1:]))


# -- the options and guarantees ----------------------------------------------------------------
def test_plain_option_is_the_papers_operator():
    V, F = shapes.sphere(1500, seed=1)
    op = meshlap.laplacian(V, F, h=0.01, correction="none")
    ref = baselines.bsw_scipy(V, F, h=0.01)
    assert op.correction == "none" and not op.pointwise
    assert abs(op.L - ref.L).max() < 1e-10 * abs(ref.L).max()
    f = V[:, 0] ** 2
    assert np.array_equal(op @ f, op.L @ f)
    # the automatic h of the plain operator is still (2 ē)²
    assert meshlap.laplacian(V, F, correction="none").h == meshlap.default_h(V, F)


def test_richardson_operator_is_the_difference_of_two_widths():
    V, F = shapes.sphere(1500, seed=2)
    h = 0.004
    op = meshlap.laplacian(V, F, h=h, arc_distance=False, pointwise=False)
    assert op.correction == "richardson" and op.fallback_reason is None
    # 2 L_{h/2} − L_h with both widths cut at r(h): what the matrix-free pencil applies
    free = meshlap.laplacian(V, F, h=h, matrix_free=True)
    grid = kernel.build_grid(V, op.mass, kernel.cutoff_radius(h, op.tol))
    X = np.column_stack([V[:, 0], V[:, 1] * V[:, 2]])
    ref = 2 * kernel.apply(V, grid, h / 2, X) - kernel.apply(V, grid, h, X)
    # one global factor brings the mean second moment to its continuous value (docs/accuracy.md)
    assert abs(op.moment_scale - free.moment_scale) < 1e-12 and abs(op.moment_scale - 1) < 0.02
    ref *= op.moment_scale
    np.testing.assert_allclose(op @ X, ref, rtol=0, atol=1e-9 * np.abs(ref).max())
    np.testing.assert_allclose(free.sym_product(X), ref, rtol=0, atol=1e-12 * np.abs(ref).max())


def test_an_explicit_width_builds_the_kernel_asked_for_and_the_check_decides():
    # no prediction chooses the kernel: 2,000 random vertices at h = 0.3 ē², where the Richardson
    # operator's -S is not semidefinite (bench_psd): its rows are made, the check fails and the
    # build falls back to the plain kernel at the same widths, with the warning; at 2 ē² the
    # check passes and the Richardson operator is kept
    V, F = shapes.sphere(2000, kind="random", seed=1)
    e2 = meshlap.geometry.from_mesh(V, F).spacing ** 2
    with pytest.warns(meshlap.MeshWarning, match="not negative semidefinite"):
        op = meshlap.laplacian(V, F, h=0.3 * e2).assemble()
    assert op.correction == "none" and op.psd_margin < 0
    stages = []
    op = meshlap.laplacian(V, F, h=2 * e2, progress=lambda f, stage: stages.append(stage))
    assert stages == ["done"]  # the pencil on first use
    stages.clear()
    assert op.correction == "richardson" and op.psd_margin > -1e-9
    assert stages[:2] == ["kernel rows", "kernel rows"]


def test_default_is_symmetric_with_zero_row_sums_and_semidefinite():
    V, F = shapes.sphere(2500, kind="random", seed=3)
    op = meshlap.laplacian(V, F, operator="kernel")
    S = op.S
    assert abs(S - S.T).max() <= 1e-12 * abs(S).max()
    assert np.abs(np.asarray(op.L_sym.sum(axis=1))).max() <= 1e-9 * abs(op.L_sym).max()
    assert (op.L_sym.data < 0).sum() > op.n_vertices  # the difference of Gaussians has negative weights
    assert op.psd_margin > -1e-9
    lam, _ = spectral.eigs(op, 4)
    assert lam[0] > -1e-8 and abs(lam[0]) < 1e-8 * lam[1]


def test_loss_of_semidefiniteness_falls_back_with_the_reason(monkeypatch):
    # at h = ē²/8 the narrow width h/2 is not resolved by spot's vertices: −S of the
    # Richardson operator has eigenvalues near −2 (measured densely), so the build falls back
    V, F = igl.read_triangle_mesh(str(DATA / "spot.obj"))
    h = meshlap.default_h(V, F) / 32
    built = []
    assemble = meshlap.assembly.assemble
    monkeypatch.setattr(meshlap.assembly, "assemble", lambda *a, **k: built.append(a[3]) or assemble(*a, **k))
    with pytest.warns(meshlap.MeshWarning, match="not negative semidefinite"):
        op = meshlap.laplacian(V, F, h=h).assemble()
    assert op.correction == "none" and "narrow kernel" in op.fallback_reason
    # the plain kernel's weights were given to the Richardson rows in place (the same pairs):
    # one neighbour search, and to the bit the rows a build of the plain kernel gives
    assert len(built) == 1 and built[0].dog
    plain = assemble(op.geometry.points, op.mass, op.widths, replace(built[0], dog=False))
    assert np.array_equal(op.L_sym.indptr, plain.indptr) and np.array_equal(op.L_sym.indices, plain.indices)
    assert np.array_equal(op.L_sym.data, plain.data)
    lam, _ = spectral.eigs(op, 3)
    assert lam[0] > -1e-8


def test_moment_correction_is_exact_for_quadratics_at_the_boundary():
    V, F = shapes.plane(1500, seed=4)
    op = meshlap.laplacian(V, F, h=0.004, correction="none")
    Lc, bad = moment_correction(op.L, V)
    assert not bad.any()
    q = 3 * V[:, 0] ** 2 - V[:, 0] * V[:, 1] + 2 * V[:, 1] ** 2 + V[:, 0] - 5  # Δq = 10
    np.testing.assert_allclose(Lc @ q, 10.0, atol=1e-8)
    np.testing.assert_allclose(Lc @ np.ones(len(V)), 0.0, atol=1e-9)
    assert abs(op.L @ q - 10).max() > 1.0  # the plain rows at the boundary are far off


def test_unknown_correction_and_conflicting_options_are_errors():
    V, F = shapes.sphere(300, seed=0)
    with pytest.raises(meshlap.MeshError, match="correction"):
        meshlap.laplacian(V, F, correction="cubic")
    with pytest.raises(meshlap.MeshError, match="matrix_free"):
        meshlap.laplacian(V, F, h=0.01, matrix_free=True, pointwise=True)
    with pytest.raises(meshlap.MeshError, match="adaptive"):
        meshlap.laplacian(V, F, h=0.01, adaptive=True)


def test_adaptive_width_on_a_mesh_whose_density_varies_50_fold():
    V, F = shapes.sphere(2000, kind="nonuniform", seed=5)
    op = meshlap.laplacian(V, F, adaptive=True)
    assert op.correction == "richardson" and op.h_vertex.max() / op.h_vertex.min() > 5
    assert abs(op.S - op.S.T).max() <= 1e-12 * abs(op.S).max()
    U = V / np.linalg.norm(V, axis=1, keepdims=True)
    plain = meshlap.laplacian(V, F, correction="none")
    for f, lap in shapes.sphere_functions().values():
        assert e2(op @ f(U), lap(U)) < min(0.04, e2(plain @ f(U), lap(U)) / 2)


# -- accuracy with the defaults ------------------------------------------------------------------
def test_sphere_4000_defaults_beat_the_plain_operator():
    for kind, bound_e2 in (("uniform", 0.003), ("random", 0.012)):
        V, F = shapes.sphere(4000, kind=kind, seed=0)
        U = V / np.linalg.norm(V, axis=1, keepdims=True)
        f, lap = shapes.sphere_functions()["x^2"]
        new = e2(meshlap.laplacian(V, F) @ f(U), lap(U))
        old = e2(meshlap.laplacian(V, F, correction="none") @ f(U), lap(U))
        assert new < bound_e2 and new < old / 3, (kind, new, old)
    lam, _ = spectral.eigs(meshlap.laplacian(*shapes.sphere(4000, seed=0)), 36)
    assert np.max(np.abs(lam[1:] - EXACT[1:]) / EXACT[1:]) < 0.025  # measured 0.020; 16k: 0.002


def test_noisy_sphere_keeps_the_papers_advantage():
    # Table 4's noisy sphere, 8,000 vertices: E2 at most 1.2× today's default (measured
    # 0.0014-0.0021 against 0.012-0.015)
    V, F = shapes.sphere(8000, kind="noisy", seed=0)
    U = V / np.linalg.norm(V, axis=1, keepdims=True)
    new, old = meshlap.laplacian(V, F), meshlap.laplacian(V, F, correction="none")
    for f, lap in shapes.sphere_functions().values():
        assert e2(new @ f(U), lap(U)) <= 1.2 * e2(old @ f(U), lap(U))


def test_plane_all_vertices_with_the_boundary():
    V, F = shapes.plane(4000, seed=0)
    op = meshlap.laplacian(V, F)
    errs = {name: e2(op @ f(V), lap(V)) for name, (f, lap) in shapes.plane_functions().items()}
    assert errs["x^2"] < 1e-8 and errs["exp(x+y)"] < 0.05, errs  # measured 0.041; 16k: 0.013


def test_fandisk_first_12_eigenvalues_within_5_percent_of_cotangent():
    assert eig_error_vs_cotangent("fandisk") < 0.005  # measured 0.0020 (the vertex pencil 0.032, 0.50 before)


def test_spot_first_12_eigenvalues_within_5_percent_of_cotangent():
    assert eig_error_vs_cotangent("spot") < 0.05  # measured 0.011 (0.49 before)


def test_width_narrows_only_where_the_surface_bends():
    V, F = shapes.sphere(3000, seed=0)
    assert meshlap.laplacian(V, F).h_vertex is None  # the unit sphere bends slowly: one h
    V, F = real_mesh("spot")
    # the vertex pencil's widths (the Galerkin pencil has its own h)
    op = meshlap.laplacian(V, F, operator="kernel")
    wide = meshlap.laplacian(V, F, curvature_limit=0, operator="kernel")
    assert op.h == wide.h and op.h_vertex.max() <= op.h and op.h_vertex.min() < 0.1 * op.h
    assert op.correction == "richardson" and abs(op.S - op.S.T).max() <= 1e-12 * abs(op.S).max()
    ref, _ = spectral.eigs(baselines.cotangent(V, F), 12)
    lam, _ = spectral.eigs(wide, 12)
    assert np.max(np.abs(lam[1:] - ref[1:]) / ref[1:]) > 0.05  # one width for all: 7.7%


def test_neumann_eigenvalues_of_the_square():
    # mirror images across the boundary give natural boundary conditions: (π/2)²(a² + b²)
    # the kernel's mirror images (a random plane's boundary slivers cost FEM, the default, 5.7%)
    V, F = shapes.plane(6000, seed=0)
    lam, _ = spectral.eigs(meshlap.laplacian(V, F, operator="kernel"), 10)
    exact = (math.pi / 2) ** 2 * np.array([0, 1, 1, 2, 4, 4, 5, 5, 8, 9], float)
    assert abs(lam[0]) < 1e-8
    assert np.max(np.abs(lam[1:] - exact[1:]) / exact[1:]) < 0.015  # 16,000 vertices: 0.006
    plain, _ = spectral.eigs(meshlap.laplacian(V, F, neumann=False), 10)
    assert np.max(np.abs(plain[1:] - exact[1:]) / exact[1:]) > 0.015


@pytest.mark.slow
def test_neumann_eigenvalues_of_the_square_16000():
    V, F = shapes.plane(16000, seed=0)
    lam, _ = spectral.eigs(meshlap.laplacian(V, F, operator="kernel"), 10)
    exact = (math.pi / 2) ** 2 * np.array([0, 1, 1, 2, 4, 4, 5, 5, 8, 9], float)
    assert np.max(np.abs(lam[1:] - exact[1:]) / exact[1:]) < 0.01  # measured 0.0060


@pytest.mark.slow
def test_plane_16000_all_vertices():
    V, F = shapes.plane(16000, seed=0)
    op = meshlap.laplacian(V, F)
    for f, lap in shapes.plane_functions().values():
        assert e2(op @ f(V), lap(V)) <= 0.02  # measured 0 and 0.013


@pytest.mark.slow
def test_sphere_16000_uniform_meets_the_targets():
    _, errs, eig = sphere_errors("uniform", 16000)
    assert eig < 0.005  # measured 0.0021
    assert errs["x^2"] <= 0.003 and errs["exp(x)"] <= 0.003  # measured 0.0003, 0.0003


@pytest.mark.slow
def test_sphere_16000_random_meets_the_targets():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        _, errs, eig = sphere_errors("random", 16000)
    assert errs["x^2"] <= 0.003 and errs["exp(x)"] <= 0.003, errs  # measured 0.0025, 0.0020
    assert eig < 0.005, eig  # measured 0.0047


def test_error_estimate_follows_the_exact_error():
    # the norm of op.error_estimate(f) against the norm of the exact error: the default's fitted
    # rows against the same rows twice as wide, measured 0.6-2.1 here (0.4-2.1 for the moment
    # rows from h and h/2 on spheres of 4,000 and 16,000, the torus and the plane)
    cases = [(shapes.sphere(3000, kind="random", seed=0), shapes.sphere_functions()),
             (shapes.torus(4000, seed=0), shapes.torus_functions()),
             (shapes.plane(3000, seed=0), shapes.plane_functions())]
    for (V, F), funcs in cases:
        op = meshlap.laplacian(V, F)
        for name, (f, lap) in funcs.items():
            err = np.linalg.norm(op @ f(V) - lap(V))
            if err < 1e-8 * np.linalg.norm(lap(V)):
                continue  # x² on the plane is exact: what is left is rounding (measured 1.3e-9)
            ratio = np.linalg.norm(op.error_estimate(f(V))) / err
            assert 0.3 < ratio < 3, (name, ratio)
    # the paper's operator: its O(h) bias, estimated from h and h/2
    V, F = shapes.sphere(3000, seed=0)
    op = meshlap.laplacian(V, F, correction="none")
    f, lap = shapes.sphere_functions()["x^2"]
    ratio = np.linalg.norm(op.error_estimate(f(V))) / np.linalg.norm(op @ f(V) - lap(V))
    assert 0.5 < ratio < 2


def _largest_error(op, exact, k=10):
    lam = spectral.eigs(op, k, tol=1e-6)[0]
    return float(np.abs(lam[1:k] / exact[1:k] - 1).max())


def test_the_kernel_on_a_cube_of_tetrahedra_and_on_a_sphere_cloud():
    # measured (kept from the former resolution tests): the kernel on a 13³ cube of tetrahedra,
    # Neumann, 2.6% against LaPy's 2.8%; on 8,000 random sphere points its first 16 eigenvalues
    # 0.50% off (robust-laplacian on 16,000 points: 7.8%)
    V, T = samples.cube_tetrahedra(12)
    op = meshlap.laplacian(V, T, k=3, operator="kernel")
    cube = math.pi**2 * np.array([0, 1, 1, 1, 2, 2, 2, 3, 4, 4], float)
    assert op.correction == "richardson" and _largest_error(op, cube) < 0.03
    P = samples.sphere_points(8000, "random", seed=0)
    sphere = np.array([deg * (deg + 1) for deg in range(4) for _ in range(2 * deg + 1)], float)
    assert _largest_error(meshlap.point_cloud_laplacian(P, operator="kernel"), sphere, 16) < 0.01
