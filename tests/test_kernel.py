"""The assembly kernels: exact agreement with a brute-force build, the vectorized exponential,
int64 indices, determinism under any schedule, the matrix-free product, memory."""

import math
import time
import tracemalloc
import warnings

import numba
import numpy as np
import pytest

import meshlap
from meshlap import assembly, shapes
from meshlap.assembly import grid as kernel


def kernel_laplacian(*args, **kwargs):
    # the heat-kernel operator these tests are about (the default of meshes is the FEM pencil)
    return meshlap.laplacian(*args, **{"operator": "kernel", **kwargs})


def brute_force_L(V, mass, h, tol):
    """L row by row from all pairs: coef * m_p * exp(-d²/4h) for p ≠ w with mass within r."""
    n = len(V)
    r2 = kernel.cutoff_radius(h, tol) ** 2
    coef = 1.0 / (4 * math.pi * h * h)
    L = np.zeros((n, n))
    pattern = np.zeros((n, n), dtype=bool)
    for w in range(n):
        d2 = np.sum((V - V[w]) ** 2, axis=1)
        keep = (d2 <= r2) & (mass > 0)
        keep[w] = False
        L[w, keep] = coef * mass[keep] * np.exp(-d2[keep] / (4 * h))
        pattern[w, keep] = True
        L[w, w] = -L[w].sum()
    return L, pattern


def messy_mesh(n=700):
    """A random sphere plus 3 unreferenced vertices (no mass): one at a vertex's position,
    one inside the sphere, one far outside the grid of the sources."""
    V, F = shapes.sphere(n, kind="random", seed=11)
    extra = np.array([V[5], [0.1, 0.2, -0.1], [40.0, -3.0, 7.0]])
    return np.vstack([V, extra]), F


def test_exp_matches_libm_to_an_ulp():
    @numba.njit
    def run(x, out):
        for i in range(len(x)):
            out[i] = kernel._exp_neg(x[i])

    rng = np.random.default_rng(0)
    x = np.concatenate([-rng.uniform(0, 20, 200_000), -rng.uniform(0, 708, 20_000),
                        [0.0, -0.0, -1e-300, -0.5 * math.log(2), -708.0, -708.5, -745.2, -1e6]])
    out = np.empty_like(x)
    run(x, out)
    ref = np.exp(x)
    normal = x >= -708
    # about one rounding in the range reduction and a few in the polynomial
    assert np.max(np.abs(out[normal] / ref[normal] - 1)) < 5e-16
    # below -708 the true value is below the smallest normal double; the kernel gives 0
    assert np.all(out[~normal] == 0) and ref[~normal].max() < 2.3e-308


# 1,500 vertices at h = 0.05: rows of about 1,450 entries, more than the fill's and the
# product's first buffers hold (1,024), read with unsigned source indices (branch i20g)
@pytest.mark.parametrize("n, h, tol", [(700, 0.004, 1e-3), (700, 0.004, 1e-8), (1500, 0.05, 1e-8)])
def test_csr_equals_brute_force(n, h, tol):
    V, F = messy_mesh(n)
    with warnings.catch_warnings():  # the mesh is messy on purpose
        warnings.simplefilter("ignore")
        op = kernel_laplacian(V, F, h=h, tol=tol, correction="none")
    ref, pattern = brute_force_L(op.V, op.mass, h, tol)
    L = op.L
    # every row stores its diagonal first, then exactly the pairs within the cut-off
    rows = np.arange(len(V))
    assert np.array_equal(L.indices[L.indptr[:-1]], rows)
    assert np.array_equal(np.diff(L.indptr), pattern.sum(axis=1) + 1)
    stored = np.zeros_like(pattern)
    stored[np.repeat(rows, np.diff(L.indptr)), L.indices] = True
    assert np.array_equal(stored, pattern | np.eye(len(V), dtype=bool))
    dense = L.toarray()
    assert np.max(np.abs(dense - ref)) <= 1e-13 * np.abs(ref).max()
    off = pattern
    assert np.max(np.abs(dense[off] / ref[off] - 1)) < 1e-14
    assert np.all(dense[-1] == 0)  # the far vertex
    assert n < 1500 or np.diff(L.indptr).max() > 1024


def test_int64_indices_give_the_same_matrix(monkeypatch):
    V, F = shapes.sphere(1500, kind="random", seed=3)
    small = kernel_laplacian(V, F, h=0.01, correction="none")
    assert small.L.indptr.dtype == np.int32 and small.L.indices.dtype == np.int32
    # pretend int32 overflows: the int64 path must be taken and give identical arrays
    monkeypatch.setattr(assembly, "_INT32_MAX", small.nnz - 1)
    big = kernel_laplacian(V, F, h=0.01, correction="none")
    assert big.L.indptr.dtype == np.int64 and big.L.indices.dtype == np.int64
    assert np.array_equal(big.L.indptr, small.L.indptr)
    assert np.array_equal(big.L.indices, small.L.indices)
    assert np.array_equal(big.L.data, small.L.data)
    f = np.cos(3 * V[:, 0])
    assert np.array_equal(big @ f, small @ f)
    # the memory estimate counts 8-byte indices for it
    assert big.nbytes == small.nnz * 16 + (len(V) + 1) * 8


def test_identical_under_any_schedule(monkeypatch):
    # an uneven mesh (dense and sparse regions) so that threads finish chunks out of order
    V, F = shapes.sphere(3000, kind="random", seed=4)
    ref = kernel_laplacian(V, F, h=0.003, correction="none").L
    before = numba.get_num_threads()
    variants = []
    try:
        numba.set_num_threads(1)
        variants.append(kernel_laplacian(V, F, h=0.003, correction="none").L)
    finally:
        numba.set_num_threads(before)
    monkeypatch.setattr(kernel, "_CHUNK_ROWS", 1)
    variants.append(kernel_laplacian(V, F, h=0.003, correction="none").L)
    # progress splits the build into several compiled calls
    monkeypatch.setattr(kernel, "_PROGRESS_ENTRIES", ref.nnz // 7)
    seen = []
    variants.append(kernel_laplacian(V, F, h=0.003, progress=lambda f, s: seen.append(s),
            correction="none").L)
    assert seen.count("fill") >= 5 and seen.count("count") >= 5
    for L in variants:
        assert np.array_equal(L.indptr, ref.indptr)
        assert np.array_equal(L.indices, ref.indices)
        assert np.array_equal(L.data, ref.data)


@pytest.mark.parametrize("dtype, n, h", [(np.float64, 700, 0.01), (np.float32, 700, 0.01),
                                         (np.float64, 1500, 0.05)])
def test_matrix_free_matches_the_matrix(dtype, n, h):
    V, F = messy_mesh(n)  # 1,500 at h = 0.05: rows longer than the first buffers
    with warnings.catch_warnings():  # the mesh is messy on purpose
        warnings.simplefilter("ignore")
        op = kernel_laplacian(V, F, h=h, dtype=dtype, correction="none")
        free = kernel_laplacian(V, F, h=h, matrix_free=True, correction="none")
    rng = np.random.default_rng(1)
    for f in (rng.normal(size=len(V)), rng.normal(size=(len(V), 1)), rng.normal(size=(len(V), 3))):
        ref = np.asarray(op.L.astype(np.float64) @ f)
        got = free @ f
        assert got.shape == f.shape
        scale = np.abs(ref).max()
        assert np.abs(got - ref).max() < (1e-12 if dtype == np.float64 else 1e-6) * scale
    lin = free.as_linear_operator()
    x = rng.normal(size=len(V))
    assert np.allclose(lin.matvec(x), free @ x, rtol=0, atol=0)
    assert np.allclose(lin.matmat(np.column_stack([x, x])), np.column_stack([free @ x] * 2), rtol=0, atol=0)


def test_estimate_is_close_and_cheap_when_dense():
    V, F = shapes.sphere(4000, seed=0)
    op = kernel_laplacian(V, F, h=0.01, correction="none")
    assert abs(op.estimate_nnz() - op.nnz) < 0.03 * op.nnz
    # a 200 x 200 grid of quads with h so large that L would be dense: 1.6e9 entries, 19 GB
    n = 200
    xs, ys = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    V = np.column_stack([xs.ravel(), ys.ravel(), np.zeros(n * n)])
    idx = np.arange(n * n).reshape(n, n)
    Q = np.stack([idx[:-1, :-1], idx[:-1, 1:], idx[1:, 1:], idx[1:, :-1]], -1).reshape(-1, 4)
    free = kernel_laplacian(V, Q, h=100.0, matrix_free=True, correction="none")
    t = time.perf_counter()
    assert free.estimate_nnz() == n**4  # every sampled row is full
    assert time.perf_counter() - t < 5.0
    calls = []
    original = kernel.count_entries
    monkey = pytest.MonkeyPatch()
    monkey.setattr(kernel, "count_entries", lambda *a, **k: calls.append(k.get("rows")) or original(*a, **k))
    try:
        with pytest.raises(meshlap.OperatorTooLargeError, match=r"at least about .* entries.*matrix_free"):
            kernel_laplacian(V, Q, h=100.0, max_memory=1 << 30, correction="none")
    finally:
        monkey.undo()
    # it stopped after the sample, before counting every row
    assert len(calls) == 1 and calls[0] is not None


def test_peak_memory_of_a_build():
    V, F = shapes.sphere(4000, seed=1)
    # compile and warm up outside the measurement
    kernel_laplacian(V, F, h=0.01, correction="none").assemble()
    tracemalloc.start()
    try:
        op = kernel_laplacian(V, F, h=0.01, correction="none").assemble()  # the pencil: on first use
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    mesh = V.nbytes + F.nbytes
    assert op.nbytes > 20 * mesh  # the matrix dominates: the bound below is meaningful
    assert peak < 1.3 * op.nbytes + 4 * mesh


def test_unsorted_kernel_rows_and_sorted_shared_patterns():
    # the corrected kernel's rows stay in the fill's order, the diagonal first (issue 19: the
    # sort cost as much as the fill); rows that share the kernel's index arrays (the moment
    # rows, pointwise=True) get them canonical, so an in-place sort of one cannot reorder the other
    V, F = meshlap.shapes.sphere(1500, kind="random", seed=1)
    op = kernel_laplacian(V, F)
    L = op.L_sym
    n = L.shape[0]
    assert (L.indices[L.indptr[:-1]] == np.arange(n)).all()
    f = np.cos(2 * V[:, 0]) + V[:, 1] * V[:, 2]
    canon = L.copy()
    canon.sort_indices()
    assert np.abs(canon @ f - L @ f).max() <= 1e-12 * np.abs(L @ f).max()
    moments = kernel_laplacian(V, F, pointwise=True, quadrature="vertex")
    R = moments.L
    rows = np.repeat(np.arange(n), np.diff(R.indptr))
    step = np.diff(R.indices.astype(np.int64))
    assert R.has_sorted_indices and (step[rows[1:] == rows[:-1]] > 0).all()


def brute_force_variable(V, mass, hv, tol, N, dog, dim):
    """Row by row from all pairs: m_p (c e² − e)/(h_wp (4π h_wp)^{k/2}), e = exp(−d²/4h_wp),
    h_wp = (h_w + h_p)/2, d² times ((α/2)/sin(α/2))² for normals at angle α."""
    n = len(V)
    c = assembly.variable.dog_factor(dim) if dog else 0.0
    L = np.zeros((n, n))
    pattern = np.zeros((n, n), dtype=bool)
    for w in range(n):
        hp = 0.5 * (hv[w] + hv)
        d2 = np.sum((V - V[w]) ** 2, axis=1)
        if N is not None:
            half = 0.5 * np.arccos(np.clip(N @ N[w], -1.0, 1.0))
            d2 = d2 * np.where(half > 0, half / np.where(half > 0, np.sin(half), 1.0), 1.0) ** 2
        keep = (d2 <= 4 * hp * math.log(1 / tol)) & (mass > 0)
        keep[w] = False
        e = np.exp(-d2[keep] / (4 * hp[keep]))
        kern = e * (c * e - 1.0) if dog else e
        L[w, keep] = mass[keep] * kern / (hp[keep] * (4 * math.pi * hp[keep]) ** (0.5 * dim))
        pattern[w, keep] = True
        L[w, w] = -L[w].sum()
    return L, pattern


def _rough_normals(V, rng):
    # unit normals tilted by up to ~50° at random: many pairs beyond the arc factor's series
    # (t > 0.1), whose rows the count and fill passes take through their exact loops
    N = V / np.linalg.norm(V, axis=1)[:, None] + 0.6 * rng.standard_normal(V.shape)
    return N / np.linalg.norm(N, axis=1)[:, None]


@pytest.mark.parametrize("dim, dog, normals", [(2, True, True), (2, False, True), (2, True, False),
                                               (1, True, False), (3, False, False), (2, True, "rough")])
def test_variable_rows_equal_brute_force(dim, dog, normals):
    # the corrected kernel's rows (per-point widths, difference of Gaussians, arc distances):
    # the same pairs and values as the formula, and count_entries equals the filled rows
    # (the count and fill passes are separate loops: they must keep the same pairs)
    V, _ = shapes.sphere(600, kind="random", seed=3)
    rng = np.random.default_rng(4)
    mass = rng.uniform(0.5, 1.5, len(V)) / len(V)
    mass[[7, 100]] = 0.0
    hv = 0.004 * rng.uniform(0.6, 1.6, len(V))
    tol = 1e-6
    N = V / np.linalg.norm(V, axis=1)[:, None] if normals else None
    if normals == "rough":
        N = _rough_normals(V, rng)
    g = kernel.build_grid(V, mass, kernel.cutoff_radius(hv.max(), tol))
    indptr, indices, data = assembly.variable.variable_csr(V, g, hv, tol, N, dog, np.int32, np.float64,
                                                           dim=dim)
    ref, pattern = brute_force_variable(V, mass, hv, tol, N, dog, dim)
    rows = np.arange(len(V))
    assert np.array_equal(indices[indptr[:-1]], rows)  # the diagonal first
    assert np.array_equal(np.diff(indptr), pattern.sum(axis=1) + 1)
    assert np.array_equal(assembly.variable.count_entries(V, g, hv, tol, N, dim), np.diff(indptr))
    some = np.array([5, 5, 300, 599])
    assert np.array_equal(assembly.variable.count_entries(V, g, hv, tol, N, dim, rows=some),
                          np.diff(indptr)[some])
    dense = np.zeros((len(V), len(V)))
    dense[np.repeat(rows, np.diff(indptr)), indices] = data
    assert np.array_equal(dense != 0, pattern | (np.eye(len(V), dtype=bool) & (dense != 0)))
    # against each row's largest weight: the difference of Gaussians cancels near its zero,
    # and the arc factor's series (to t⁶) differs from asin by up to 2e-8 at its edge (t = 0.1),
    # times d²/4h in the weight: measured 5e-11 with radial normals, 7e-8 with rough ones (many
    # pairs near that edge), 4e-15 without
    err = np.abs(dense - ref).max(axis=1) / np.abs(ref).max(axis=1).clip(1e-300)
    assert err.max() < {True: 5e-10, "rough": 5e-7, False: 1e-13}[normals]


def _variable_case(seed, normals):
    # 500 random sphere points, one without mass, per-point widths, and normals (None,
    # "radial" or "rough")
    V, _ = shapes.sphere(500, kind="random", seed=seed)
    rng = np.random.default_rng(seed + 1)
    mass = rng.uniform(0.5, 1.5, len(V)) / len(V)
    mass[seed - 2] = 0.0
    hv = 0.004 * rng.uniform(0.6, 1.6, len(V))
    N = None if normals is None else (V / np.linalg.norm(V, axis=1)[:, None] if normals == "radial"
                                      else _rough_normals(V, rng))
    return V, mass, hv, N


@pytest.mark.parametrize("normals", [None, "radial", "rough"])
@pytest.mark.parametrize("dog", [True, False])
def test_revalue_equals_a_new_build(dog, normals):
    # the fallback of a failed semidefiniteness check gives the rows the other kernel's
    # weights on their pattern: bit for bit the rows a new build of that kernel gives
    V, mass, hv, N = _variable_case(5, normals)
    g = kernel.build_grid(V, mass, kernel.cutoff_radius(hv.max(), 1e-8))
    var = assembly.variable
    indptr, indices, data = var.variable_csr(V, g, hv, 1e-8, N, not dog, np.int32, np.float64)
    want = var.variable_csr(V, g, hv, 1e-8, N, dog, np.int32, np.float64)
    assert not np.array_equal(data, want[2])
    var.revalue(V, mass, hv, N, dog, indptr, indices, data)
    assert np.array_equal(indptr, want[0]) and np.array_equal(indices, want[1])
    assert np.array_equal(data, want[2])
    low = var.variable_csr(V, g, hv, 1e-8, N, not dog, np.int32, np.float32)[2]
    var.revalue(V, mass, hv, N, dog, indptr, indices, low)
    assert low.dtype == np.float32 and np.array_equal(low, want[2].astype(np.float32))


@pytest.mark.parametrize("normals", [None, "radial", "rough"])
def test_product_made_during_the_fill_equals_scipys(normals):
    # the moment scale's block multiplied while the rows are filled (issue 19): the same
    # values, to the bit, as scipy's product with the finished matrix, on every path of the
    # fill (chord, arc series, exact arc); the same rows as a fill without it
    V, mass, hv, N = _variable_case(7, normals)
    g = kernel.build_grid(V, mass, kernel.cutoff_radius(hv.max(), 1e-6))
    X = meshlap.corrections.moments.moment_block(V)
    Y = np.full((len(V), 4), np.nan)
    rows = assembly.variable.variable_csr(V, g, hv, 1e-6, N, True, np.int32, np.float64, times=X, product=Y)
    plain = assembly.variable.variable_csr(V, g, hv, 1e-6, N, True, np.int32, np.float64)
    assert all(np.array_equal(a, b) for a, b in zip(rows, plain, strict=True))
    L = assembly.csr(rows[2], rows[1], rows[0], len(V))
    assert np.array_equal(Y, L @ X)


def test_assemble_gives_the_product_where_it_fills_in_float64():
    V, F = shapes.sphere(400, kind="random", seed=9)
    g = meshlap.geometry.from_mesh(V, F)
    per_point = meshlap.widths.Widths(0.01, np.full(400, 0.01), False)
    L, Y = assembly.assemble(g.points, g.mass, per_point, assembly.Kernel(2, dog=True), times=V)
    assert np.array_equal(Y, L @ V)
    # the one-h kernel's path and float32 rows: the caller multiplies afterwards
    L1, none = assembly.assemble(g.points, g.mass, per_point, assembly.Kernel(2, dog=True), times=V,
                                 dtype=np.float32)
    assert none is None and L1.dtype == np.float32
    L2, none = assembly.assemble(g.points, g.mass, meshlap.widths.Widths(0.01, None, False),
                                 assembly.Kernel(2), times=V)
    assert none is None and L2.shape == (400, 400)
    # a block wider than the fill's registers: the caller multiplies afterwards
    wide = np.column_stack([V, V, V])
    L3, none = assembly.assemble(g.points, g.mass, per_point, assembly.Kernel(2, dog=True), times=wide)
    assert none is None and np.array_equal(L3.data, L.data)
    with pytest.raises(ValueError, match="at most 8 columns"):
        assembly.variable.variable_csr(g.points, kernel.build_grid(g.points, g.mass, 1.0), per_point.h_vertex,
                                       1e-8, None, True, np.int32, np.dtype(np.float64), times=wide,
                                       product=np.empty((400, 9)))


def test_build_moment_scale_equals_the_product_after_the_fill():
    # a plane with a boundary: the band's rows are left out of the mean; the scale from the
    # product made during the fill is the scale of scipy's product with the free rows, to the bit
    V, F = shapes.plane(4000, seed=2)
    op = kernel_laplacian(V, F)
    geo, opts = op.geometry, op.options
    radius = assembly.cutoff_radius(op.widths.largest, opts.tol)
    free = assembly.assemble(geo.points, geo.mass, op.widths,
                             assembly.Kernel(geo.dim, dog=True, normals=geo.normals(), tol=opts.tol))
    band = geo.boundary_frames(radius)[0]
    want = meshlap.corrections.second_moment_scale(lambda X: free @ X, geo.points, geo.mass, band, geo.dim)
    assert op.correction == "richardson" and 0 < len(band) < len(V) and op.moment_scale == want != 1.0


@pytest.mark.parametrize("normals", [None, "radial", "rough"])
def test_variable_rows_longer_than_the_first_buffers(normals):
    # rows of up to ~1,200 candidates, more than the fill's first buffers hold (1,024): each
    # candidate's d² and width written at its place in the grown buffers, then the kept ones
    # moved to the front; the same pairs and values as the formula, and as the count pass
    V, mass, hv, N = _variable_case(9, normals)
    V, mass, hv = np.vstack([V, 1.01 * V, 0.99 * V]), np.tile(mass, 3), 25 * np.tile(hv, 3)
    N = None if N is None else np.tile(N, (3, 1))
    g = kernel.build_grid(V, mass, kernel.cutoff_radius(hv.max(), 1e-6))
    indptr, indices, data = assembly.variable.variable_csr(V, g, hv, 1e-6, N, True, np.int32, np.float64)
    assert np.diff(indptr).max() > 1024
    assert np.array_equal(assembly.variable.count_entries(V, g, hv, 1e-6, N), np.diff(indptr))
    ref, pattern = brute_force_variable(V, mass, hv, 1e-6, N, True, 2)
    rows = np.repeat(np.arange(len(V)), np.diff(indptr))
    dense = np.zeros_like(ref)
    dense[rows, indices] = data
    assert np.array_equal(dense != 0, pattern | (np.eye(len(V), dtype=bool) & (dense != 0)))
    # the arc series' truncation (2e-8 at t = 0.1) times d²/4h: pairs at wider angles here
    err = np.abs(dense - ref).max(axis=1) / np.abs(ref).max(axis=1)
    assert err.max() < (1e-13 if N is None else 5e-7)
