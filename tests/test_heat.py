"""Heat flow against the exact decay of spherical harmonics, implicit steps, smoothing."""

import math

import numpy as np
import pytest

import meshlap
from meshlap import heat, shapes, smoothing, spectral
from meshlap.baselines import cotangent

H = 0.01


@pytest.fixture(scope="module")
def sphere_op():
    V, F = shapes.sphere(3000, seed=0)
    return V, F, meshlap.laplacian(V, F, h=H, correction="none")


def harmonic(V, degree):
    x, y, z = V.T
    return {1: z, 2: x * y, 3: x * y * z}[degree]


@pytest.mark.parametrize("degree", [1, 2, 3])
def test_harmonic_decays_as_exp_minus_lambda_t(sphere_op, degree):
    V, F, op = sphere_op
    f = harmonic(V, degree)
    t = np.array([0.05, 0.2, 0.4])
    lam = spectral.sphere_eigenvalue(degree, H)
    norm = lambda u: math.sqrt(np.sum(op.mass * u * u))  # noqa: E731
    for method in ("chebyshev", "krylov", "spectral"):
        u = heat.heat_flow(op, f, t, method=method, k=16)
        rates = np.array([-math.log(norm(ui) / norm(f)) / ti for ui, ti in zip(u, t, strict=True)])
        # the discrete operator's shell sits within 0.5% of the continuous value at this n
        assert np.abs(rates / lam - 1).max() < 0.005, (method, rates, lam)
        # and the shape is kept: u(t) stays proportional to f
        for ui in u:
            c = np.dot(ui, f) / np.dot(f, f)
            assert np.linalg.norm(ui - c * f) < 0.02 * np.linalg.norm(ui)


def test_chebyshev_matches_expm_multiply():
    # the default series against scipy's expm_multiply, on BSW and on the cotangent operator
    V, F = meshlap.shapes.sphere(1500, kind="random", seed=4)
    f = np.exp(V[:, 0]) + V[:, 1] ** 2
    times = [0.0, 0.02, 0.3, 1.5]
    for op in (meshlap.laplacian(V, F, h=0.01, correction="none"), cotangent(V, F)):
        cheb = heat.heat_flow(op, f, times)
        ref = heat.heat_flow(op, f, times, method="krylov")
        assert np.abs(cheb - ref).max() < 1e-12 * np.abs(f).max()
    free = meshlap.laplacian(V, F, h=0.01, matrix_free=True, correction="none")
    with pytest.raises(meshlap.MeshError, match="stored pencil"):
        heat.heat_flow(free, f, 0.1)


def test_rational_matches_chebyshev_and_the_dense_exponential(monkeypatch):
    # Talbot's contour, 12 complex solves per time, against the Chebyshev series
    V, F = meshlap.shapes.sphere(1500, kind="random", seed=4)
    f = np.exp(V[:, 0]) + V[:, 1] ** 2
    times = [0.0, 0.02, 0.3, 1.5]
    op = meshlap.laplacian(V, F)
    rational = heat.heat_flow(op, f, times, method="rational")
    assert np.abs(rational - heat.heat_flow(op, f, times, method="chebyshev")).max() < 1e-12 * np.abs(f).max()
    # a vertex a thousandth of an edge off its neighbour: its sliver sets the Gershgorin bound
    # (the series takes 2,507 products), so "auto" takes the contour
    W = np.vstack([V, V[F[0, 0]] + 1e-3 * (V[F[0, 1]] - V[F[0, 0]])])
    G = np.vstack([F, [[F[0, 0], 1500, F[0, 2]]]])
    G[0, 0] = 1500
    op = meshlap.laplacian(W, G)
    g = np.r_[f, f[F[0, 0]]]
    series = heat.heat_flow(op, g, 0.3, method="chebyshev")
    monkeypatch.setattr(heat, "_chebyshev_heat", None)  # "auto" must not call it
    assert np.abs(heat.heat_flow(op, g, 0.3) - series).max() < 1e-12 * np.abs(g).max()  # measured 1.1e-13


def test_many_times_match_single_calls(sphere_op):
    V, F, op = sphere_op
    f = np.exp(V[:, 0]) + V[:, 1] ** 2
    times = [0.3, 0.0, 0.1]
    many = heat.heat_flow(op, np.column_stack([f, 2 * f]), times)
    assert many.shape == (3, len(V), 2)
    for ti, ui in zip(times, many, strict=True):
        one = heat.heat_flow(op, f, ti)
        assert np.allclose(ui[:, 0], one, rtol=0, atol=1e-10) and np.allclose(ui[:, 1], 2 * one, atol=2e-10)
    assert np.array_equal(many[1][:, 0], f)
    with pytest.raises(meshlap.MeshError, match="t must"):
        heat.heat_flow(op, f, -1.0)
    with pytest.raises(meshlap.MeshError, match="method"):
        heat.heat_flow(op, f, 1.0, method="euler")


def test_implicit_steps_cg_matches_direct_and_converge_to_exp(sphere_op):
    V, F, op = sphere_op
    f = np.exp(V[:, 0]) + np.sin(3 * V[:, 2])
    tau = 0.02
    cg = heat.ImplicitHeat(op, tau, solver="cg", rtol=1e-12)
    u_cg = cg(f)
    # the direct solver agrees (on a smaller mesh, where its LU is cheap)
    Vs, Fs = shapes.sphere(800, seed=3)
    small = meshlap.laplacian(Vs, Fs, h=0.02, correction="none")
    fs = np.exp(Vs[:, 0])
    u_dir = heat.ImplicitHeat(small, tau, solver="direct")(fs)
    u_small = heat.ImplicitHeat(small, tau, solver="cg", rtol=1e-12)(fs)
    assert np.linalg.norm(u_small - u_dir) < 1e-9 * np.linalg.norm(u_dir)
    # residual of (M - τS) u = M f
    r = op.M @ f - (op.M @ u_cg - tau * (op.S @ u_cg))
    assert np.linalg.norm(r) < 1e-10 * np.linalg.norm(op.M @ f)
    # the cotangent preconditioner keeps CG short even for a large step
    big = heat.ImplicitHeat(op, 1.0, solver="cg", rtol=1e-10)
    big(f)
    # measured: 10 and 11 iterations
    assert cg.iterations[-1] <= 14 and big.iterations[-1] <= 16, (cg.iterations, big.iterations)
    # backward Euler is first order: doubling the steps halves the error to exp(tL) f
    exact = heat.heat_flow(op, f, 0.2)
    err = [np.linalg.norm(heat.implicit_heat(op, f, 0.2 / s, s) - exact) for s in (4, 8, 16)]
    assert 1.8 < err[0] / err[1] < 2.2 and 1.8 < err[1] / err[2] < 2.2


def test_implicit_heat_with_zero_mass_vertices():
    V, F = shapes.sphere(1200, seed=1)
    extra = 1.01 * shapes.fibonacci_sphere(10)
    V2, F2 = np.vstack([extra, V]), F + 10
    with pytest.warns(UserWarning):
        op = meshlap.laplacian(V2, F2, h=0.02, correction="none")
    f = V2[:, 0].copy()
    u = heat.implicit_heat(op, f, 0.05)
    # the vertices with mass solve their own system; the others their row of (I - τL) u = f
    L = op.L.toarray()
    row = u[:10] - 0.05 * (L[:10] @ u)
    assert np.allclose(row, f[:10], atol=1e-10)
    assert np.abs(u[:10] / f[:10] - 1 / (1 + 0.05 * 2)).max() < 0.03
    u_cot = heat.implicit_heat(cotangent(V2, F2), f, 0.05)
    assert np.array_equal(u_cot[:10], f[:10])
    # the corrected kernel: op @ f applies the fitted rows, the step the pencil's rows L_sym
    with pytest.warns(UserWarning):
        op = meshlap.laplacian(V2, F2, operator="kernel")
    u = heat.implicit_heat(op, f, 0.01)
    assert np.allclose(u[:10] - 0.01 * (op.L_sym[:10] @ u), f[:10], atol=1e-10)
    assert np.abs(u[:10] / f[:10] - math.exp(-0.02)).max() < 0.01  # 0.40 / 0.98 before


def test_smoothing_a_noisy_function(sphere_op):
    V, F, op = sphere_op
    clean = V[:, 2] + V[:, 0] * V[:, 1]
    noise = 0.2 * np.random.default_rng(0).standard_normal(len(V))
    # the operator's spectrum saturates near 1/h = 100, so noise is damped by about
    # (1 + t/(h·steps))^-steps = 0.2 while the clean part (λ ≤ 6) loses less than 8%
    out = smoothing.smooth_function(op, clean + noise, t=0.02, steps=4)
    before, after = np.linalg.norm(noise), np.linalg.norm(out - clean)
    assert after < before / 3, (before, after)
    kept = smoothing.smooth_function(op, clean, t=0.02, steps=4)
    assert np.linalg.norm(kept - clean) < 0.08 * np.linalg.norm(clean)
    with pytest.raises(meshlap.MeshError, match="steps"):
        smoothing.smooth_function(op, clean, 0.01, steps=0)


def test_a_large_volume_steps_and_solves_without_a_factorization(monkeypatch):
    # where factoring would cost more than _multigrid.MAX_FACTOR_WORK a volume's implicit steps and
    # Poisson solves run CG
    # preconditioned by a multigrid V-cycle of their own matrix (a 68,921-vertex cube: a step
    # 0.6 s instead of 50 s, a solve 0.8 s instead of 103 s), to the direct solution's accuracy;
    # the heat method's step stays factored, its far field being below any residual
    from meshlap import _multigrid, geodesics, samples, solve

    V, T = samples.cube_tetrahedra(21)  # 10,648 vertices
    op = meshlap.laplacian(V, T, k=3)
    assert _multigrid.replaces_factor(op)
    f = np.cos(np.pi * V[:, 0]) * np.cos(np.pi * V[:, 1])
    bottom = np.flatnonzero(V[:, 2] < 1e-9)
    u_ref = heat.implicit_heat(op, f, 0.01, solver="direct")
    phi_ref = solve.PoissonSolver(op, bottom, solver="direct").solve(-op.mass * f)
    d_ref = geodesics.geodesic_distance(op, 0, solver="direct")

    def no_factor(*args, **kwargs):
        raise AssertionError("a factorization was made")

    monkeypatch.setattr(heat, "_factor", no_factor)
    monkeypatch.setattr(solve, "_factor", no_factor)
    # factoring made slow: the V-cycle's measured seconds cannot tip it to a factorization (Stall)
    monkeypatch.setattr(_multigrid, "FACTOR_RATE", 1.0)
    step = heat.ImplicitHeat(op, 0.01)
    poisson = solve.PoissonSolver(op, bottom)
    assert step.solver == poisson.solver == "cg"
    assert np.abs(step(f) - u_ref).max() < 1e-8 * np.abs(u_ref).max()
    assert np.abs(poisson.solve(-op.mass * f) - phi_ref).max() < 1e-8 * np.abs(phi_ref).max()
    assert max(step.iterations + poisson.iterations) < 40
    # heat flow long enough to leave the series for the contour elsewhere keeps the series here:
    # the contour's 12 complex factorizations would cost more
    g = 1.0 + np.cos(np.pi * V[:, 0])
    mean = g @ op.mass / op.mass.sum()
    assert np.abs(heat.heat_flow(op, g, 20.0) - mean).max() < 1e-10
    with pytest.raises(AssertionError, match="a factorization was made"):
        geodesics.geodesic_distance(op, 0)  # the heat method's step is factored
    monkeypatch.undo()
    d = geodesics.geodesic_distance(op, 0)
    assert np.abs(d - d_ref).max() < 1e-6 * d_ref.max()
    exact = np.linalg.norm(V - V[0], axis=1)
    assert np.abs(d - exact).mean() < 0.015 * exact.max()  # the heat method's own: 1.04%


def test_a_volume_kernels_poisson_preconditioner_is_not_factored_above_the_threshold(monkeypatch):
    # the kernel's dense rows take CG, preconditioned by the P1 stiffness; on a volume above
    # _multigrid.MAX_FACTOR_WORK that stiffness is inverted by a V-cycle, not factored (it fills as
    # a volume's does). The bound is lowered here so that a small cloud crosses it.
    from meshlap import _lobpcg, _multigrid, solve

    P = np.random.default_rng(0).random((700, 3))
    op = meshlap.point_cloud_laplacian(P, k=3)
    fixed = np.flatnonzero(P[:, 2] < 0.1)
    b = -op.mass * np.cos(np.pi * P[:, 0])
    reference = solve.PoissonSolver(op, fixed, solver="direct").solve(b)

    def no_factor(*args, **kwargs):
        raise AssertionError("a factorization was made")

    monkeypatch.setattr(_multigrid, "MAX_FACTOR_WORK", 0.0)
    monkeypatch.setattr(_lobpcg, "BlockFactor", no_factor)
    poisson = solve.PoissonSolver(op, fixed)
    assert poisson.solver == "cg"
    assert np.abs(poisson.solve(b) - reference).max() < 1e-7 * np.abs(reference).max()


def test_a_dense_row_poisson_solve_neither_copies_nor_slices_s(monkeypatch):
    # a volume kernel's S holds about as many entries a row as there are points nearby; CG reads
    # it through products alone, so its set-up must not symmetrize, slice or negate a copy of it
    # (bench_pointcloud.py --volume: 7.8 s of set-up against 2.8 s of solve). Neumann and Dirichlet
    # problems, each against the factored solve.
    import scipy.sparse as sp

    from meshlap import solve

    P = np.random.default_rng(1).random((600, 3))
    op = meshlap.point_cloud_laplacian(P, k=3)
    b = -op.mass * np.cos(np.pi * P[:, 0])
    fixed = np.flatnonzero(P[:, 2] < 0.1)
    references = [solve.PoissonSolver(op, f, solver="direct").solve(b) for f in (None, fixed)]
    S = op.S
    copies = []
    for name in ("__getitem__", "__add__", "__neg__"):  # (its parts still take one transpose)
        original = getattr(sp.csr_matrix, name)

        def watched(self, *args, _original=original, _name=name):
            if self.shape == S.shape and self.nnz == S.nnz:  # S or a copy of it
                copies.append(_name)
            return _original(self, *args)
        monkeypatch.setattr(sp.csr_matrix, name, watched)
    for fixed_vertices, reference in zip((None, fixed), references, strict=True):
        poisson = solve.PoissonSolver(op, fixed_vertices)
        assert poisson.solver == "cg"
        x = poisson.solve(b)
        assert np.abs(x - reference).max() < 1e-7 * np.abs(reference).max()
    assert copies == []
