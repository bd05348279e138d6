"""Eigenpairs against the sphere's exact spectrum, against scipy, and on awkward meshes."""

import math
import warnings
from pathlib import Path

import igl
import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.linalg import eigsh

import meshlap
from meshlap import _multigrid, shapes, spectral
from meshlap.baselines import bsw_scipy, cotangent

DATA = Path(__file__).parent / "data"
SHELLS = [(0, 1), (1, 3), (2, 5), (3, 7)]  # (degree l, multiplicity 2l+1): 16 eigenpairs


def check_eigenpairs(op, lam, phi, rtol):
    """M-orthonormal, ascending, and -S φ = λ M φ to rtol·λ_max on the vertices with mass."""
    P = op.mass > 0
    M = sp.diags(op.mass)
    assert np.all(np.diff(lam) >= -1e-12 * lam[-1])
    assert np.abs(phi.T @ M @ phi - np.eye(len(lam))).max() < 1e-9
    R = (-(op.S @ phi) - (M @ phi) * lam)[P]
    res = np.sqrt(np.sum(R**2 / op.mass[P, None], axis=0))
    assert res.max() < rtol * lam[-1]
    assert np.isfinite(phi).all()


def test_sphere_eigenvalue_closed_form_and_limit():
    for h in (0.3, 0.05, 0.01):
        exact = 2 * (1 - math.exp(-1 / h) * (1 + 1 / h))
        assert abs(spectral.sphere_eigenvalue(1, h) - exact) < 1e-12
    assert spectral.sphere_eigenvalue(0, 0.1) == 0.0
    # c_l(h) -> l(l+1) linearly in h, with the slope (l-1)l(l+1)(l+2)/2 of the u² term of P_l
    for d in (2, 3, 5):
        gaps = [d * (d + 1) - spectral.sphere_eigenvalue(d, h) for h in (4e-3, 2e-3, 1e-3)]
        assert all(g > 0 for g in gaps)
        assert 1.9 < gaps[0] / gaps[1] < 2.1 and 1.9 < gaps[1] / gaps[2] < 2.1
        slope = (d - 1) * d * (d + 1) * (d + 2) / 2
        assert abs(gaps[2] / 1e-3 / slope - 1) < 0.05
    with pytest.raises(meshlap.MeshError, match="l must"):
        spectral.sphere_eigenvalue(-1, 0.1)
    with pytest.raises(meshlap.MeshError, match="h must"):
        spectral.sphere_eigenvalue(2, 0.0)


def test_unit_sphere_multiplicities_and_convergence_in_n():
    """Shells of 1, 3, 5, 7 eigenvalues; distance to c_l(h) falls as the mesh is refined."""
    h = 0.01
    errors = []
    for n in (1000, 4000):
        V, F = shapes.sphere(n, seed=0)
        op = meshlap.laplacian(V, F, h=h, correction="none")
        lam, phi = spectral.eigs(op, 16, method="lobpcg")
        check_eigenpairs(op, lam, phi, 1e-4)  # about √tol: tol is on the eigenvalues
        start, err = 0, 0.0
        for d, mult in SHELLS:
            shell = lam[start:start + mult]
            c = spectral.sphere_eigenvalue(d, h)
            # a shell's spread is much smaller than the gap to the next shell
            assert np.ptp(shell) < 0.05 * max(c, 1) and (start == 0 or shell[0] - lam[start - 1] > 1.5)
            err = max(err, np.abs(shell - c).max() / max(c, 1))
            start += mult
        errors.append(err)
    assert errors[0] < 0.01 and errors[1] < 0.5 * errors[0]  # measured 0.0071, 0.0029


def test_unit_sphere_approaches_l_l_plus_1_as_h_shrinks():
    """h halves and n doubles (h/ē² fixed): the shell means approach l(l+1) at rate ~h."""
    gaps = []
    for h, n in ((0.02, 1000), (0.01, 2000), (0.005, 4000)):
        V, F = shapes.sphere(n, seed=1)
        lam, _ = spectral.eigs(meshlap.laplacian(V, F, h=h, correction="none"), 16)
        means = np.split(lam, np.cumsum([m for _, m in SHELLS])[:-1])
        gaps.append(max(abs(s.mean() - d * (d + 1)) / (d * (d + 1))
                        for (d, _), s in zip(SHELLS[1:], means[1:], strict=True)))
    assert gaps[0] > gaps[1] > gaps[2]
    assert gaps[2] < 0.035 and gaps[0] / gaps[2] > 3


@pytest.mark.parametrize("kind", ["uniform", "random"])
def test_lobpcg_matches_scipy_eigsh(kind):
    V, F = shapes.sphere(1300, kind=kind, seed=2)
    op = meshlap.laplacian(V, F, h=0.008, correction="none")
    ref, ref_phi = eigsh(-op.S, k=20, M=op.M.tocsc(), sigma=-1e-3, tol=1e-12)
    # the default tol = 1e-8 is the eigenvalues' relative accuracy; eigenvectors to about √tol
    lam, phi = spectral.eigs(op, 20, method="lobpcg")
    assert (np.abs(lam[1:] - ref[1:]) / ref[1:]).max() < 1e-8 and abs(lam[0]) < 1e-8 * ref[1]
    check_eigenpairs(op, lam, phi, 1e-3)
    lam, phi = spectral.eigs(op, 20, method="lobpcg", tol=1e-14)
    assert np.abs(lam[1:] - ref[1:]).max() / ref[-1] < 1e-10
    check_eigenpairs(op, lam, phi, 1e-7)
    # same invariant subspace, to the residual tolerance (largest principal angle)
    Q = np.linalg.qr(np.sqrt(op.mass)[:, None] * ref_phi)[0]
    Y = np.sqrt(op.mass)[:, None] * phi
    assert np.linalg.norm(Y - Q @ (Q.T @ Y), axis=0).max() < 1e-6
    # the other two methods agree
    for method in ("shift-invert", "dense"):
        other, _ = spectral.eigs(op, 20, method=method)
        assert np.abs(other[1:] - ref[1:]).max() / ref[-1] < 1e-9


def test_cotangent_operator_and_mesh_argument():
    V, F = shapes.sphere(1500, kind="random", seed=3)
    cot = cotangent(V, F)
    lam, phi = spectral.eigs(cot, 10)  # auto: sparse rows -> shift-invert
    C = igl.cotmatrix(V, F)
    Mv = igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI)
    ref = eigsh(-C, k=10, M=Mv, sigma=-1e-3, return_eigenvectors=False)
    assert np.abs(np.sort(ref) - lam)[1:].max() / lam[-1] < 1e-9
    check_eigenpairs(cot, lam, phi, 1e-7)
    # an operator without its mesh gets the cotangent preconditioner from `mesh=`
    plain = bsw_scipy(V, F, h=0.02)
    with_mesh, _ = spectral.eigs(plain, 10, method="lobpcg", mesh=(V, F), tol=1e-12)
    direct, _ = spectral.eigs(meshlap.laplacian(V, F, h=0.02, correction="none"), 10, method="dense")
    assert np.abs(with_mesh - direct)[1:].max() / direct[-1] < 1e-9


def test_zero_mass_vertices_are_extended_not_nan():
    V, F = shapes.sphere(1600, seed=4)
    rng = np.random.default_rng(0)
    extra = rng.normal(size=(40, 3))
    extra *= (1 + 0.02 * rng.uniform(-1, 1, (40, 1))) / np.linalg.norm(extra, axis=1, keepdims=True)
    # 40 unreferenced vertices near the surface (zero mass), numbered first
    V2, F2 = np.vstack([extra, V]), F + 40
    h = 0.01
    op = meshlap.laplacian(V, F, h=h, correction="none")
    with pytest.warns(UserWarning, match="unreferenced"):
        op2 = meshlap.laplacian(V2, F2, h=h, correction="none")
    lam, phi = spectral.eigs(op, 9, method="lobpcg", tol=1e-14)
    lam2, phi2 = spectral.eigs(op2, 9, method="lobpcg", tol=1e-14)
    assert np.abs(lam2 - lam).max() < 1e-9 * lam[-1]
    check_eigenpairs(op2, lam2, phi2, 1e-7)
    # degree-1 eigenfunctions extend smoothly: the mean of neighbours, close to the sphere's value
    Z = np.arange(40)
    L = op2.L.toarray()
    off = L[Z].copy()
    off[np.arange(len(Z)), Z] = 0
    assert np.allclose(phi2[Z], off @ phi2 / off.sum(axis=1, keepdims=True), atol=1e-12)
    span = phi2[:, 1:4]
    coef = np.linalg.lstsq(span[40:], V, rcond=None)[0]  # x, y, z in the degree-1 shell
    assert np.abs(span[Z] @ coef - extra).max() < 0.05
    # cotangent rows vanish there: zeros, still finite
    lam_c, phi_c = spectral.eigs(cotangent(V2, F2), 9)
    assert np.all(phi_c[Z] == 0) and np.isfinite(lam_c).all()


def read_quads(path):
    V, F = [], []
    for line in path.read_text().splitlines():
        parts = line.split()
        if parts and parts[0] == "v":
            V.append([float(x) for x in parts[1:4]])
        elif parts and parts[0] == "f":
            F.append([int(p.split("/")[0]) - 1 for p in parts[1:]])
    return np.array(V), np.array(F)


def test_polygon_mesh_uses_fan_triangles():
    V, F = read_quads(DATA / "spot-quads.obj")
    assert F.shape[1] == 4
    op = meshlap.laplacian(V, F, correction="none")
    lam, phi = spectral.eigs(op, 12, method="lobpcg", tol=1e-14)
    ref, _ = spectral.eigs(op, 12, method="shift-invert", tol=1e-12)
    assert np.abs(lam - ref)[1:].max() / ref[-1] < 1e-10
    check_eigenpairs(op, lam, phi, 1e-7)


def test_heat_kernel_signature_on_the_sphere():
    V, F = shapes.sphere(2000, seed=5)
    op = meshlap.laplacian(V, F, h=0.01, correction="none")
    lam, phi = spectral.eigs(op, 25)
    t = np.array([0.5, 2.0])
    hks = spectral.heat_kernel_signature(t=t, eig=(lam, phi))
    assert hks.shape == (2000, 2)
    # by symmetry Σ_l (2l+1) exp(-λ_l t) / area at every vertex (l ≤ 4 fills 25 pairs)
    area = op.mass.sum()
    expect = [sum((2 * d + 1) * math.exp(-spectral.sphere_eigenvalue(d, 0.01) * s) for d in range(5)) / area
              for s in t]
    assert np.abs(hks / expect - 1).max() < 0.01
    assert np.allclose(spectral.heat_kernel_signature(op, 0.5, k=25), hks[:, 0], atol=1e-10)
    with pytest.raises(meshlap.MeshError, match="t must"):
        spectral.heat_kernel_signature(t=-1.0, eig=(lam, phi))


def test_bad_arguments():
    V, F = shapes.sphere(300, seed=0)
    op = meshlap.laplacian(V, F, h=0.05, correction="none")
    for k in (0, 300, 2.5, True):
        with pytest.raises(meshlap.MeshError, match="k must"):
            spectral.eigs(op, k)
    with pytest.raises(meshlap.MeshError, match="method must"):
        spectral.eigs(op, 4, method="arnoldi")
    with pytest.raises(meshlap.MeshError, match="tol must"):
        spectral.eigs(op, 4, tol=2.0)
    # these crashed inside LOBPCG (UnboundLocalError, IndexError, TypeError) or numpy's seeding
    for bad in ({"maxiter": -3}, {"maxiter": 2.5}, {"maxiter": True}, {"extra": -2}, {"seed": -1},
                {"seed": "a"}):
        name = next(iter(bad))
        with pytest.raises(meshlap.MeshError, match=f"{name} must be a (positive|non-negative) integer"):
            spectral.eigs(op, 4, method="lobpcg", **bad)
    with pytest.raises(meshlap.MeshError, match="mesh has"):
        spectral.eigs(op, 4, method="lobpcg", mesh=(V[:10], F[:2]))


@pytest.mark.slow
def test_bunny_50_eigenpairs():
    V, F = igl.read_triangle_mesh(str(DATA / "stanford-bunny.obj"))
    # a third of the automatic h (480 instead of 1,400 entries per row) keeps the test short
    op = meshlap.laplacian(V, F, h=3e-6, correction="none")
    assert (op.mass == 0).sum() == 1113
    lam, phi = spectral.eigs(op, 50, tol=1e-10)
    check_eigenpairs(op, lam, phi, 1e-5)
    assert abs(lam[0]) < 1e-8 * lam[-1] and lam[1] > 0


def test_matrix_free_operator_gives_the_same_spectrum():
    V, F = shapes.sphere(1500, seed=6)
    stored = meshlap.laplacian(V, F, h=0.01, correction="none")
    free = meshlap.laplacian(V, F, h=0.01, matrix_free=True, correction="none")
    lam, _ = spectral.eigs(stored, 9, method="lobpcg", tol=1e-12)
    lam_free, phi_free = spectral.eigs(free, 9, tol=1e-12)  # auto: LOBPCG through op @ X
    assert np.abs(lam_free - lam).max() < 1e-10 * lam[-1]
    assert np.abs(phi_free.T @ (stored.mass[:, None] * phi_free) - np.eye(9)).max() < 1e-9
    # a problem small enough to solve densely: S from the products, as the stored operator's
    V, F = shapes.sphere(300, seed=6)
    stored = meshlap.laplacian(V, F, h=0.01, correction="none")
    free = meshlap.laplacian(V, F, h=0.01, matrix_free=True, correction="none")
    lam, lam_free = spectral.eigs(stored, 6)[0], spectral.eigs(free, 6)[0]
    assert np.abs(lam_free - lam).max() < 1e-10 * lam[-1]


def test_matrix_free_pencil_that_lobpcg_cannot_verify_is_solved_densely():
    """Where LOBPCG fails the check (here: two iterations allowed), a matrix-free pencil of at most
    4,000 vertices goes to dense eigh on its columns before the wider LOBPCG, and its answer is the
    stored pencil's; two parts give two zeros."""
    V, F = shapes.sphere(1500, seed=6)
    V2, F2 = np.vstack([V, V + [3.0, 0, 0]]), np.vstack([F, F + len(V)])
    stored = meshlap.laplacian(V2, F2, h=0.01, correction="none")
    free = meshlap.laplacian(V2, F2, h=0.01, matrix_free=True, correction="none")
    info: dict = {}
    lam_free, phi = spectral.eigs(free, 8, maxiter=2, info=info)
    assert info["tried"] == ["lobpcg", "dense"] and info["complete"]
    lam = spectral.eigs(stored, 8, method="dense")[0]
    assert np.abs(lam_free - lam).max() < 1e-10 * lam[-1]
    assert np.abs(lam_free[:2]).max() < 1e-10 and lam_free[2] > 1.0
    check_eigenpairs(stored, lam_free, phi, 1e-6)


def test_default_operator_eigenvalues_to_the_tolerance_asked():
    """The corrected default (its own pencil) by LOBPCG against dense eigh: each eigenvalue
    within tol of the reference, relative to itself, for tol = 1e-8 and 1e-5."""
    V, F = shapes.sphere(1500, kind="random", seed=7)
    op = meshlap.laplacian(V, F)
    ref, _ = spectral.eigs(op, 16, method="dense", elements="linear")
    for tol in (1e-8, 1e-5):
        lam, phi = spectral.eigs(op, 16, method="lobpcg", tol=tol, elements="linear")
        assert (np.abs(lam[1:] - ref[1:]) / ref[1:]).max() < tol
        assert abs(lam[0]) < tol * ref[1]
        check_eigenpairs(op, lam, phi, 10 * math.sqrt(tol))


def test_lobpcg_error_bound_on_clustered_spectrum():
    """A diagonal pencil with tight clusters (spacing 1e-6 within, 1 between) and a poor
    preconditioner: the eigenvalue bound stops the iteration while every Ritz value is
    within tol of the exact one, well before the residuals reach tol."""
    from meshlap import _lobpcg

    exact = np.sort(np.concatenate([c + 1e-6 * np.arange(c) for c in range(1, 7)] + [np.arange(7.0, 400)]))
    n = len(exact)
    rng = np.random.default_rng(1)
    m = rng.uniform(0.5, 2.0, n)
    A = sp.diags(exact * m)  # the pencil (A, diag(m)) has the eigenvalues `exact`
    pre = 1.0 / ((exact * rng.uniform(0.5, 2.0, n) + 1.0) * m)
    X0 = rng.standard_normal((n, 26))
    out = _lobpcg.lobpcg(lambda Y: A @ Y, m, lambda R: pre[:, None] * R, X0, 21, 1e-10, 200)
    assert (out.ratio[:21] <= 1).all()
    lam_ref = exact[:21]
    assert (np.abs(out.lam[:21] - lam_ref) / lam_ref).max() < 1e-10
    assert out.residuals[:21].max() > 1e-9 * lam_ref[-1]  # stopped on the values, not the residuals
    bound = _lobpcg.eig_error(out.lam, out.residuals)
    assert (np.abs(out.lam[:21] - lam_ref) <= bound[:21] + 1e-15).all()
    # the clusters' spectral norms (what the iteration stops on): still a bound, and tighter
    R = A @ out.X - m[:, None] * out.X * out.lam
    sharp = _lobpcg.eig_error(out.lam, out.residuals, R.T @ (R / m[:, None]))
    assert (np.abs(out.lam[:21] - lam_ref) <= sharp[:21] + 1e-15).all()
    assert (sharp <= bound * (1 + 1e-6)).all() and (sharp[:21] < 0.7 * bound[:21]).any()


def test_block_factor_solves_like_splu():
    from meshlap import _lobpcg

    V, F = shapes.sphere(800, kind="random", seed=8)
    K = sp.csc_matrix(-igl.cotmatrix(V, F)) + sp.diags(np.full(800, 0.01))
    B = np.random.default_rng(3).standard_normal((800, 12))
    factor = _lobpcg.BlockFactor(K)
    X = factor.solve(B)  # wide: the compiled triangular solves, in single precision
    exact = np.linalg.solve(K.toarray(), B)
    assert X.dtype == np.float64
    assert 1e-12 < np.abs(X - exact).max() < 1e-5 * np.abs(exact).max()
    # narrow: the factorization's own solve, in double precision
    assert np.abs(factor.solve(B[:, :3]) - exact[:, :3]).max() < 1e-10 * np.abs(exact).max()
    assert np.abs(factor.solve(B[:, 0]) - exact[:, 0]).max() < 1e-10 * np.abs(exact).max()


def test_a_large_volume_is_solved_by_multigrid_without_a_factorization(monkeypatch):
    # where factoring costs more than _multigrid.MAX_FACTOR_WORK, a volume's LOBPCG is preconditioned
    # by a multigrid V-cycle:
    # nothing is factored (shift-invert held 3.1 GiB for 26 s on the 68,921-vertex cube, multigrid
    # 0.56 GiB and 5.3 s); the pairs are those shift-invert finds, verified
    from meshlap import _ldl, samples

    V, T = samples.cube_tetrahedra(21)  # 10,648 vertices
    op = meshlap.laplacian(V, T, k=3)
    assert _multigrid.replaces_factor(op)
    reference = spectral.eigs(op, 10, method="shift-invert")[0]

    def no_factor(*args, **kwargs):
        raise AssertionError("a factorization was made")

    monkeypatch.setattr(_ldl, "factor", no_factor)
    # the V-cycle gives way to factoring where its measured seconds would exceed the factorization's
    # (Stall): on this small cube the two are close, so a loaded machine tipped it to shift-invert
    # in 1 run of 4; here factoring is made slow, so the choice is multigrid's alone
    monkeypatch.setattr(_multigrid, "FACTOR_RATE", 1.0)
    info = {}
    lam, phi = spectral.eigs(op, 10, info=info)
    assert info["method"] == "lobpcg (multigrid)" and info["count"] is None
    assert np.abs(lam - reference).max() < 1e-7 * reference[-1]
    assert np.allclose(phi.T @ (op.mass[:, None] * phi), np.eye(10), atol=1e-8)
    exact = samples.cube_eigenvalues(10)
    assert np.abs(lam[1:] / exact[1:] - 1).max() < 0.01  # linear FEM's own error at 20 cells a side


def _box_tetrahedra(nx: int, ny: int, nz: int) -> tuple[np.ndarray, np.ndarray]:
    # an nx × ny × nz grid of unit cubes, each cut as samples.cube_tetrahedra cuts its cube
    from meshlap import samples

    corners, tets = samples.cube_tetrahedra(1)
    idx = np.arange((nx + 1) * (ny + 1) * (nz + 1)).reshape(nx + 1, ny + 1, nz + 1)
    grid = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    cells = np.stack(grid, -1).reshape(-1, 3)
    at = cells[:, None, :] + corners.astype(np.int64)[None, :, :]
    local = idx[at[..., 0], at[..., 1], at[..., 2]]
    V = np.stack(np.meshgrid(*(np.arange(m + 1.0) for m in (nx, ny, nz)), indexing="ij"), -1).reshape(-1, 3)
    return V, local[:, tets].reshape(-1, 4)


def test_a_volume_is_factored_where_its_counted_work_is_small_whatever_its_size():
    """Multigrid replaced a volume's factorization above 8,000 vertices; a thin or graded volume
    factors cheaply where the V-cycle converges slowly (pyvista's 12,472-vertex notch_stress FEA
    mesh: 252 LOBPCG iterations, 14.7 s, against shift-invert's 0.43 s). The choice now reads the
    factorization's counted work: a 12,675-vertex plate, two cells thick, is factored; the
    10,648-vertex cube is not."""
    from meshlap import _ldl, _multigrid, samples

    V, T = _box_tetrahedra(64, 64, 2)
    plate = meshlap.laplacian(V, T)
    assert plate.n_vertices == 12675 and plate.dim == 3
    assert _ldl.factor_work(-plate.S, _ldl.volume_order(-plate.S)) < 0.2 * _multigrid.MAX_FACTOR_WORK
    assert not _multigrid.replaces_factor(plate)
    info = {}
    lam = spectral.eigs(plate, 6, info=info)[0]
    assert info["method"] == "shift-invert"
    # the 64 × 64 × 2 box's Neumann values (π m / 64)², to linear FEM's accuracy
    assert np.allclose(lam[1:], np.pi**2 / 64**2 * np.array([1, 1, 2, 4, 4]), rtol=0.01)
    cube = meshlap.laplacian(*samples.cube_tetrahedra(21))
    assert _multigrid.replaces_factor(cube)
    assert not _ldl.factors_within(-cube.S, _multigrid.MAX_FACTOR_WORK)


def test_a_stalled_v_cycle_gives_way_to_the_counted_factorization(monkeypatch):
    """LOBPCG with a V-cycle stalls on a graded or anisotropic volume (pyvista's notch_stress
    refined once, 96,029 vertices: 211 s, 200 iterations and a wider run's, against shift-invert's
    5.7 s). Where the iterations still to go, at the rate they go, would take longer than the
    counted factorization, eigs factors after all; where they converge, it keeps them. Both volumes
    have one pattern, so one factorization cost, set to 0.05 s: the cube's V-cycle converges in
    13 iterations of 3 ms, the slab's would need seconds. Where the iterations left take less than
    the bound multigrid was chosen above, the factorization is not even counted."""
    from meshlap import _ldl, _multigrid, samples

    V, T = samples.cube_tetrahedra(12)
    slab, cube = meshlap.laplacian(V * [1.0, 1.0, 0.01], T), meshlap.laplacian(V, T)
    monkeypatch.setattr(_multigrid, "MAX_FACTOR_WORK", -1.0)  # both by multigrid first
    monkeypatch.setattr(_multigrid, "FACTOR_RATE", _ldl.least_work(slab.S) / 0.05)
    info = {}
    lam = spectral.eigs(slab, 4, info=info)[0]
    assert info["tried"] == ["lobpcg (multigrid)", "shift-invert"]
    # the unit square's Neumann values π²(a² + b²), far below the slab's first vertical one
    assert np.allclose(lam[1:], np.pi**2 * np.array([1, 1, 2]), rtol=0.015)
    info, counted = {}, []
    spectral.eigs(cube, 4, info=info)
    assert info["tried"] == ["lobpcg (multigrid)"] and info["iterations"] < 40
    # the bound just below the cube's work: multigrid, and a run too short to ask for the count
    monkeypatch.setattr(_multigrid, "MAX_FACTOR_WORK", 0.999 * _ldl.least_work(cube.S))
    monkeypatch.setattr(_ldl, "least_work", lambda A: counted.append(A) or 0.0)
    info = {}
    spectral.eigs(cube, 4, info=info)
    assert info["tried"] == ["lobpcg (multigrid)"] and not counted


def test_a_stalled_v_cycle_in_a_solve_or_a_heat_step_factors_after_all(monkeypatch):
    """Conjugate gradient with the V-cycle stalls where LOBPCG's does (the refined notch_stress
    volume: 254 iterations, 6.7 s for one Poisson solve against 1.3 s factored). The solver and
    the heat step factor after all, for that solve and the next ones, with the same answer."""
    from meshlap import _ldl, samples
    from meshlap.heat import ImplicitHeat
    from meshlap.solve import PoissonSolver

    V, T = samples.cube_tetrahedra(12)
    slab = meshlap.laplacian(V * [1.0, 1.0, 0.01], T)
    b = slab.M @ np.cos(np.pi * V[:, 0])
    exact = PoissonSolver(slab, solver="direct").solve(b)
    heat = ImplicitHeat(slab, 0.01, solver="direct").step(V[:, 0])
    monkeypatch.setattr(_multigrid, "MAX_FACTOR_WORK", -1.0)
    monkeypatch.setattr(_multigrid, "FACTOR_RATE", _ldl.least_work(slab.S) / 0.05)
    solver = PoissonSolver(slab)
    assert solver.solver == "cg"
    assert np.allclose(solver.solve(b), exact, atol=1e-8 * np.abs(exact).max())
    assert solver.solver == "direct" and solver.iterations[0] < 40
    step = ImplicitHeat(slab, 0.01)
    assert step.solver == "cg"
    assert np.allclose(step.step(V[:, 0]), heat, atol=1e-8)
    assert step.solver == "direct"
    # asked for by name, CG stays CG
    assert PoissonSolver(slab, solver="cg")._stall is None


def test_eigs_progress_reports_stages_in_order():
    V, F = shapes.sphere(800, seed=9)
    op = meshlap.laplacian(V, F, h=0.02, correction="none")
    calls = []
    lam, _ = spectral.eigs(op, 6, method="lobpcg", progress=lambda f, s: calls.append((f, s)))
    stages = [s.split(" (")[0] for _, s in calls]
    assert stages[0] == "preconditioner" and stages[-1] == "done" and calls[-1][0] == 1.0
    assert "cotangent start" in stages and "LOBPCG" in stages
    fractions = [f for f, _ in calls]
    assert all(0 <= f <= 1 for f in fractions) and fractions == sorted(fractions)
    assert any(s.startswith("LOBPCG (iteration 2)") for _, s in calls)
    dense = []
    spectral.eigs(op, 4, method="dense", progress=lambda f, s: dense.append(s))
    assert dense == ["dense", "done"]
    sparse = []  # a sparse pencil: the factorization, each Lanczos run, the inertia count
    V, F = shapes.sphere(3000, seed=9)
    spectral.eigs(meshlap.laplacian(V, F), 6, elements="linear", progress=lambda f, s: sparse.append((f, s)))
    stages = [s for _, s in sparse]
    assert stages[:3] == ["shift-invert", "shift-invert: factoring", "Lanczos"], stages
    assert stages[-2:] == ["inertia count", "done"] and [f for f, _ in sparse] == sorted(f for f, _ in sparse)
    retried, info = [], {}  # LOBPCG given 3 iterations fails its check; shift-invert goes on
    spectral.eigs(meshlap.laplacian(V, F), 6, method="lobpcg", maxiter=3, elements="linear", info=info,
                  progress=lambda f, s: retried.append((f, s)))
    assert info["tried"][:2] == ["lobpcg", "shift-invert"], info["tried"]
    stages = [s for _, s in retried]
    assert "LOBPCG (iteration 1)" in stages and "shift-invert: factoring" in stages and stages[-1] == "done"
    assert [f for f, _ in retried] == sorted(f for f, _ in retried)  # it went back to 0.6 after 0.85


def test_spatial_order_is_the_same_problem_permuted(monkeypatch):
    # LOBPCG runs on L_sym restricted to the vertices with mass, in spatial order (issue 19):
    # exactly the submatrix, permuted, and the same eigenpairs as in the input's order
    V, F = shapes.sphere(1600, kind="random", seed=4)
    V2, F2 = np.vstack([1.01 * V[:25], V]), F + 25  # 25 unreferenced vertices: zero mass
    with pytest.warns(UserWarning, match="unreferenced"):
        op = meshlap.laplacian(V2, F2, h=0.01, correction="none")
    P = np.flatnonzero(op.mass > 0)
    B, order = spectral._ordered_L(op, P)
    assert sorted(order.tolist()) == list(range(len(P)))
    rows = P[order]
    ref = op.L_sym[rows][:, rows]
    assert abs(B - ref).max() == 0 and B.nnz == ref.nnz
    # neighbours in the order are neighbours in space: consecutive points far closer than random ones
    step = np.linalg.norm(np.diff(op.V[rows], axis=0), axis=1).mean()
    assert step < 0.3 * np.linalg.norm(np.diff(op.V[P], axis=0), axis=1).mean()
    lam, phi = spectral.eigs(op, 12, method="lobpcg", tol=1e-12)
    monkeypatch.setattr(spectral, "_ordered_L", lambda op, P: None)
    lam0, phi0 = spectral.eigs(op, 12, method="lobpcg", tol=1e-12)
    assert np.abs(lam - lam0).max() < 1e-10 * lam[-1]
    check_eigenpairs(op, lam, phi, 1e-6)
    # the same subspaces: each eigenvector of the one lies in the span of the other's
    W = np.sqrt(op.mass)[:, None]
    Q = np.linalg.qr(W * phi0)[0]
    assert np.linalg.norm(W * phi - Q @ (Q.T @ (W * phi)), axis=0).max() < 1e-5


def test_ordered_lobpcg_keeps_the_eigenvalues_it_had():
    # the kernel operator on a 3,000-vertex random sphere, 12 eigenpairs to tol 1e-12: the values
    # that meshlap at dd61feb (two Gram–Schmidt passes, products then scaled) returned; the
    # single pass with Kahan–Parlett's second pass and the scaled product keep them to 1e-10
    before = np.array([9.131266341131774e-15, 1.998091627573647, 1.999417427693732, 1.999779511952462,
                       5.967478880754770, 5.981138422948256, 5.985404973788827, 5.995998156131942,
                       6.003589812293266, 11.86580103102071, 11.88758669739634, 11.90867573704229])
    V, F = shapes.sphere(3000, kind="random", seed=5)
    op = meshlap.laplacian(V, F, operator="kernel")
    lam, phi = spectral.eigs(op, 12, method="lobpcg", tol=1e-12)
    assert np.abs(lam - before).max() < 1e-10 * before[-1]
    check_eigenpairs(op, lam, phi, 1e-6)


def test_orthogonalize_passes_twice_only_where_it_cancelled():
    from meshlap import _lobpcg

    rng = np.random.default_rng(2)
    n = 3000
    m = rng.uniform(0.5, 2.0, n)
    XP, _ = _lobpcg.svqb(rng.standard_normal((n, 8)), m)
    # column 0 keeps its norm; column 1 is XP's span plus 1e-8 of the rest: one pass cancels
    W = np.column_stack([rng.standard_normal(n), XP @ rng.standard_normal(8) + 1e-8 * rng.standard_normal(n)])
    exact = W - XP @ (XP.T @ (m[:, None] * W))
    exact -= XP @ (XP.T @ (m[:, None] * exact))

    def leak(Y):  # |XPᵀ M y| / |y|_M per column
        return np.abs(XP.T @ (m[:, None] * Y)).max(axis=0) / np.sqrt((m[:, None] * Y * Y).sum(axis=0))

    once = W.copy()
    _lobpcg._orthogonalize(once, XP, m[:, None], _lobpcg._local, False)
    twice = W.copy()
    _lobpcg._orthogonalize(twice, XP, m[:, None], _lobpcg._local, True)
    assert leak(once)[1] > 1e-11  # one pass leaves the cancelled column far from orthogonal
    assert leak(twice).max() < 1e-14
    assert np.array_equal(twice[:, 0], once[:, 0])  # the column that kept its norm: one pass only
    assert np.allclose(twice, exact, rtol=0, atol=1e-12 * np.abs(exact).max(axis=0))
    # a scaled product: diag(s) A X in one pass
    A = sp.random(50, 50, density=0.2, random_state=1, format="csr")
    X, s = rng.standard_normal((50, 3)), rng.standard_normal(50)
    assert np.allclose(_lobpcg.csr_times(A, X, s), s[:, None] * (A @ X), rtol=1e-14, atol=1e-14)


def test_block_product_is_the_same_on_any_number_of_threads():
    # csr_times shares its rows (of unequal lengths) among meshlap's threads, each running the
    # compiled loop with one numba thread: the same bits as on one thread, numba's count restored
    import numba

    from meshlap import _lobpcg

    rng = np.random.default_rng(3)
    A = sp.random(4000, 4000, density=0.01, random_state=3, format="csr")
    long_rows = sp.random(4000, 4000, density=0.02, random_state=4).multiply(np.arange(4000)[:, None] < 500)
    A = sp.csr_matrix(A + sp.diags(rng.uniform(1, 2, 4000)) + long_rows)  # the first 500 three times longer
    X, s = rng.standard_normal((4000, 40)), rng.standard_normal(4000)
    assert A.nnz * X.shape[1] >= _lobpcg._SERIAL_WORK
    threads = numba.get_num_threads()
    shared = _lobpcg.csr_times(A, X, s)
    assert numba.get_num_threads() == threads
    numba.set_num_threads(1)
    try:
        alone = _lobpcg.csr_times(A, X, s)
    finally:
        numba.set_num_threads(threads)
    assert np.array_equal(shared, alone)
    assert np.allclose(shared, s[:, None] * (A @ X), rtol=1e-13, atol=1e-13)


def test_combined_update_is_the_two_products_summed():
    # LOBPCG's update A @ CA + B @ CB in one pass over row shares, the second product added in
    # place by BLAS: the sum of the two products, for every pair, past the threaded row count
    from meshlap import _lobpcg

    rng = np.random.default_rng(4)
    n = 3 * _lobpcg._ROWS + 7
    pairs = [(rng.standard_normal((n, 9)), rng.standard_normal((9, 6)), rng.standard_normal((n, 4)),
              rng.standard_normal((4, 6))) for _ in range(2)]
    inputs = [tuple(a.copy() for a in pair) for pair in pairs]
    for (A, CA, B, CB), out in zip(inputs, _lobpcg.combine(pairs), strict=True):
        assert out.flags.c_contiguous
        assert np.allclose(out, A @ CA + B @ CB, rtol=0, atol=1e-13)
    assert all(np.array_equal(a, b) for pair, kept in zip(pairs, inputs, strict=True)
               for a, b in zip(pair, kept, strict=True))  # the inputs are read, not written


def test_lobpcg_block_holds_a_cluster_that_outgrows_the_start():
    """Two copies of a sphere double each multiplicity: for k = 10 the 6's cluster (2l + 1 = 5
    per copy) ends at index 18, past a start k/4 wider than the block (16 columns). The start
    widens until it sees the cluster end, and LOBPCG, carrying it whole, converges in a few
    iterations (7 here; 9 when the block ended inside the cluster)."""
    from meshlap import _lobpcg

    V, F = shapes.sphere(1500, seed=3)
    V2, F2 = np.vstack([V, V + [3.0, 0.0, 0.0]]), np.vstack([F, F + len(V)])
    K = sp.csc_matrix(-igl.cotmatrix(V2, F2))
    m = igl.massmatrix(V2, F2, igl.MASSMATRIX_TYPE_VORONOI).diagonal()
    lu = sp.linalg.splu(K + sp.diags(m))
    rng = np.random.default_rng(0)
    X0, _ = _lobpcg.cotangent_start(lambda Y: K @ Y, m, lu.solve, lambda c: rng.standard_normal((len(m), c)),
                                    10, 14, len(m), 0.1, 10)
    theta = np.linalg.eigvalsh(X0.T @ (K @ X0))
    assert X0.shape[1] >= 20 and theta[17] < 6.5 < theta[18]  # two zeros, six 2's, ten 6's, and more
    op = meshlap.laplacian(V2, F2, operator="kernel")
    info = {}
    lam, _ = spectral.eigs(op, 10, method="lobpcg", info=info)
    ref, _ = spectral.eigs(op, 10, method="dense", elements="linear")
    assert np.abs(lam - ref).max() < 1e-8 * ref[-1]
    assert info["iterations"] <= 8


@pytest.mark.parametrize("n, method", [(250, "dense"), (600, "shift-invert")])
def test_auto_solves_a_sparse_pencil_densely_only_up_to_the_crossover(n, method):
    """A sparse pencil of up to 300 rows is solved densely, a larger one by shift-invert, whose
    cost is lower there (benchmarks/bench_eigs.py --dense-crossover: 1,100 rows 68-82 ms against
    12-35 ms); both give the sphere's l = 1 triple near 2, to 1e-8 of the dense spectrum."""
    op = cotangent(*shapes.sphere(n, seed=1))
    info = {}
    lam, phi = spectral.eigs(op, 6, info=info)
    assert info["method"] == method
    w = np.linalg.eigvalsh(np.diag(op.mass ** -0.5) @ -op.S.toarray() @ np.diag(op.mass ** -0.5))
    assert np.abs(lam - w[:6]).max() < 1e-8 * w[5]
    assert np.abs(lam[1:4] - 2).max() < 0.1 and lam[0] == pytest.approx(0, abs=1e-9)


@pytest.mark.parametrize(("n", "k", "method"), [(1000, 6, "lobpcg"), (1500, 40, "dense")])
def test_auto_solves_a_dense_row_pencil_densely_up_to_80_rows_per_vector(n, k, method):
    """A dense-row pencil (a volume cloud's heat kernel) is solved densely up to 80 rows per
    vector of LOBPCG's block (k + extra), where LOBPCG's n² products per vector cost as much as
    eigh's n³ (benchmarks/bench_eigs.py --dense-crossover: 1,000 rows, 10 vectors: 70 ms dense
    against 51 ms; 1,500 rows, 44 vectors: 267 ms against 873 ms); both agree with the dense
    spectrum."""
    P = np.random.default_rng(1).uniform(size=(n, 3))
    with warnings.catch_warnings(action="ignore"):
        op = meshlap.point_cloud_laplacian(P, k=3)
    assert op.L_sym.nnz > spectral._SPARSE_ROW_MAX * n
    info = {}
    lam, _ = spectral.eigs(op, k, info=info)
    assert info["method"] == method
    ref, _ = spectral.eigs(op, k, method="dense")
    assert np.abs(lam - ref).max() < 1e-6 * ref[-1]


@pytest.mark.parametrize("operator", ["cotangent", "kernel"])
def test_tol_zero_asks_for_machine_precision_as_eigsh_does(operator):
    """tol=0, eigsh's machine precision, was accepted and then failed every solver: an EigenError
    ("error bound up to inf × tol") after three solves; so did 1e-300. Both now check to ε:
    shift-invert on the cotangent pencil, LOBPCG on the heat kernel's dense rows; both match the
    dense spectrum."""
    V, F = shapes.sphere(1000, seed=0)
    op = cotangent(V, F) if operator == "cotangent" else meshlap.laplacian(V, F, operator="kernel")
    info = {}
    lam, _ = spectral.eigs(op, 6, tol=0, info=info)
    assert info["method"] == ("shift-invert" if operator == "cotangent" else "lobpcg")
    S = op.S.toarray()
    w = np.linalg.eigvalsh(np.diag(op.mass ** -0.5) @ -(S + S.T) / 2 @ np.diag(op.mass ** -0.5))
    assert np.abs(lam - w[:6]).max() < 1e-10 * w[5]
    below, _ = spectral.eigs(op, 6, tol=1e-300)  # below machine precision: the same
    assert np.abs(below - lam).max() < 1e-10 * w[5]


def test_a_volume_is_factored_in_the_ordering_whose_work_is_counted_smaller():
    """A volume's factorization (_ldl.factor, supernodal) takes minimum degree or nested
    dissection, whichever factor_work counts fewer operations for; the count is exact (a dense
    Cholesky's pattern). A thin irregular bar keeps minimum degree; the 20³ tetrahedral cube takes
    nested dissection (0.7× the work), with fewer stored entries. Its solves, its blocked
    triangular solves (the ordering composed with SuperLU's) and its pivots' inertia are those of
    minimum degree."""
    from scipy.spatial import Delaunay

    from meshlap import _ldl, samples

    axes = np.meshgrid(np.arange(60.0), np.arange(4.0), np.arange(4.0), indexing="ij")
    g = np.stack(axes, -1).reshape(-1, 3)
    P = g + 0.1 * np.random.default_rng(0).uniform(-1, 1, g.shape)
    bar = meshlap.laplacian(P, Delaunay(P).simplices)
    A = sp.csc_matrix(-sp.csr_matrix(bar.S) + sp.diags(1e-3 * bar.mass))
    order = _ldl.minimum_degree(A)
    L = np.linalg.cholesky(A.toarray()[np.ix_(order, order)])
    assert _ldl.factor_work(A, order) == float(np.sum((np.abs(np.tril(L, -1)) > 0).sum(axis=0) ** 2.0))
    np.testing.assert_array_equal(_ldl.volume_order(A), order)

    V, T = samples.cube_tetrahedra(20)
    op = meshlap.laplacian(V, T)
    S = sp.csr_matrix(op.S)
    A = sp.csc_matrix(-0.5 * (S + S.T) + sp.diags(1e-3 * op.mass))
    dissected = _ldl.nested_dissection(A)
    assert _ldl.factor_work(A, dissected) < 0.8 * _ldl.factor_work(A, _ldl.minimum_degree(A))
    np.testing.assert_array_equal(_ldl.volume_order(A), dissected)
    work = _ldl.factor_work(A, dissected)  # the bounded count stops early, on the right side
    assert _ldl.factors_within(A, work) and not _ldl.factors_within(A, 0.999 * work)
    _ldl._STRUCTURES.clear()
    assert _ldl.factors_within(A, work) and not _ldl.factors_within(A, 0.01 * work)
    f, plain = _ldl.factor(A, supernodal=True), _ldl._LU(A)
    assert f._lu.L.nnz + f._lu.U.nnz < plain._lu.L.nnz + plain._lu.U.nnz
    B = np.random.default_rng(0).standard_normal((A.shape[0], 12))
    X = f.solve(B)
    assert np.abs(A @ X - B).max() < 1e-9 * np.abs(B).max()
    into, lower, upper, diag, out = f.triangles()
    Y = np.empty(B.shape)
    Y[into] = B
    _ldl.triangular_solves(lower, upper, diag, Y)
    assert np.abs(Y[out] - X).max() < 1e-12 * np.abs(X).max()
    shifted = sp.csc_matrix(-0.5 * (S + S.T) - 30.0 * sp.diags(op.mass))  # eigenvalues below 30
    assert _ldl.factor(shifted, supernodal=True).negative == _ldl._LU(shifted).negative > 1


def test_one_blas_thread_limits_and_restores_without_scanning_the_libraries_again():
    """BLAS runs on one thread inside the context, as many as before after it, nested too; the
    loaded libraries are found once (each scan read /proc/self/maps: 2 ms per call, half a
    15-part mesh's eigs)."""
    threadpoolctl = pytest.importorskip("threadpoolctl")
    from meshlap import _jit

    def blas():
        return [p["num_threads"] for p in threadpoolctl.threadpool_info() if p["user_api"] == "blas"]

    before = blas()
    with _jit.one_blas_thread():
        assert set(blas()) <= {1}
        with _jit.one_blas_thread():
            assert set(blas()) <= {1}
        assert set(blas()) <= {1}
    assert blas() == before
    scans = _jit._blas_pools.cache_info().misses
    with _jit.one_blas_thread():
        pass
    assert _jit._blas_pools.cache_info().misses == scans <= 1
