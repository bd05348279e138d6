"""The operator against a literal evaluation of eq. (1) and against analytic Laplacians."""

import math
from pathlib import Path

import igl
import numpy as np
import pytest
import scipy.sparse as sp

import meshlap
from meshlap import shapes

DATA = Path(__file__).parent / "data"


def formula_1(V, faces, h, f):
    """Eq. (1) of Belkin–Sun–Wang evaluated face by face, with no mass lumping or cut-off."""
    out = np.zeros(len(V))
    coef = 1.0 / (4 * math.pi * h * h)
    for face in faces:
        face = list(face)
        P = V[face]
        # polygon area by fan triangulation from corner 0 (planar, convex test faces)
        area = 0.5 * np.linalg.norm(
            sum(np.cross(P[i] - P[0], P[i + 1] - P[0]) for i in range(1, len(face) - 1))
        )
        share = area / len(face)
        for p in face:
            K = np.exp(-np.sum((V[p] - V) ** 2, axis=1) / (4 * h))
            out += coef * share * K * (f[p] - f)
    return out


def small_polygon_mesh():
    """A bumpy 6x5 grid of quads with some quads split into triangles and one pentagon."""
    xs, ys = np.meshgrid(np.linspace(0, 1, 7), np.linspace(0, 0.8, 6))
    V = np.column_stack([xs.ravel(), ys.ravel(), 0.1 * np.sin(3 * xs.ravel()) * ys.ravel()])
    idx = np.arange(42).reshape(6, 7)
    faces = []
    for i in range(5):
        for j in range(6):
            a, b, c, d = idx[i, j], idx[i, j + 1], idx[i + 1, j + 1], idx[i + 1, j]
            if (i + j) % 3 == 0:
                faces += [[a, b, c], [a, c, d]]
            else:
                faces.append([a, b, c, d])
    return V, faces


def test_matches_formula_1_untruncated():
    V, F = shapes.sphere(120, kind="random", seed=3)
    rng = np.random.default_rng(0)
    f = rng.normal(size=len(V))
    h = 0.05
    ref = formula_1(V, F, h, f)
    op = meshlap.laplacian(V, F, h=h, tol=0, correction="none")
    assert op.exact and math.isinf(op.radius)
    assert np.linalg.norm(op @ f - ref) / np.linalg.norm(ref) < 1e-12


def test_matches_formula_1_mixed_polygons():
    V, faces = small_polygon_mesh()
    f = np.cos(2 * V[:, 0]) + V[:, 1] ** 2
    h = 0.02
    ref = formula_1(V, faces, h, f)
    op = meshlap.laplacian(V, faces, h=h, exact=True, correction="none")
    assert np.linalg.norm(op @ f - ref) / np.linalg.norm(ref) < 1e-12
    # the block form applies the operator column by column
    block = op @ np.column_stack([f, 2 * f])
    assert np.allclose(block[:, 1], 2 * ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())


@pytest.mark.parametrize("tol", [1e-3, 1e-6])
def test_truncation_within_stated_bound(tol):
    V, F = shapes.sphere(400, kind="random", seed=1)
    f = np.exp(V[:, 0]) + V[:, 2]
    h = 0.02
    exact = meshlap.laplacian(V, F, h=h, tol=0, correction="none") @ f
    op = meshlap.laplacian(V, F, h=h, tol=tol, correction="none")
    assert op.radius == pytest.approx(math.sqrt(4 * h * math.log(1 / tol)))
    err = np.abs(op @ f - exact)
    bound = meshlap.truncation_bound(op, f)
    assert np.all(err <= bound)
    assert err.max() > 0  # the cut-off really dropped something


def _interior(V, h, width=5.0):
    # At 3√h from the edge the Gaussian still weighs e^(-9/4) ≈ 0.1 of its peak and the
    # missing half-plane dominates the error (≈ 11% for x² at 4h = 0.04); at 5√h it is
    # e^(-25/4) ≈ 0.002.
    return np.all(np.abs(V[:, :2]) < 1 - width * math.sqrt(h), axis=1)


def test_plane_analytic_and_convergence():
    h = 0.01  # 4h = 0.04, as in the paper's Table 1
    errors = {}
    for n in (2000, 16000):
        V, F = shapes.plane(n, seed=7)
        op = meshlap.laplacian(V, F, h=h, matrix_free=n > 4000, correction="none")
        inner = _interior(V, h)
        for name, (f, lap) in shapes.plane_functions().items():
            approx, exact = (op @ f(V))[inner], lap(V)[inner]
            errors[name, n] = np.linalg.norm(approx - exact) / np.linalg.norm(exact)
    # measured (seed 7): x² 0.0124 -> 0.0019; exp(x+y) 0.034 -> 0.0093
    assert errors["x^2", 2000] < 0.02 and errors["x^2", 16000] < 0.004
    assert errors["x^2", 16000] < errors["x^2", 2000] / 3
    # exp(x+y) keeps the continuous operator's bias (e^(2h) - 1)/(2h) - 1 = 1.01%
    assert errors["exp(x+y)", 16000] < 0.012
    assert errors["exp(x+y)", 16000] < errors["exp(x+y)", 2000] / 2


@pytest.mark.parametrize("kind", ["uniform", "random"])
def test_sphere_analytic_and_convergence(kind):
    h = 0.01
    errors = {}
    for n in (500, 2000, 8000):
        V, F = shapes.sphere(n, kind=kind, seed=2)
        op = meshlap.laplacian(V, F, h=h, correction="none")
        for name, (f, lap) in shapes.sphere_functions().items():
            errors[name, n] = np.linalg.norm(op @ f(V) - lap(V)) / np.linalg.norm(lap(V))
    for name in shapes.sphere_functions():
        seq = [errors[name, n] for n in (500, 2000, 8000)]
        assert seq[0] > seq[1] > seq[2], (name, seq)
        # the continuous operator's own bias at h = 0.01 is about 2h = 0.02
        assert seq[2] < 0.045, (name, seq)


@pytest.fixture(scope="module")
def sphere_op():
    V, F = shapes.sphere(600, kind="random", seed=5)
    return meshlap.laplacian(V, F, h=0.02, correction="none")


def test_rows_sum_to_zero_and_constants(sphere_op):
    L = sphere_op.L
    rowsum = np.asarray(L.sum(axis=1)).ravel()
    assert np.abs(rowsum).max() < 1e-12 * np.abs(L.diagonal()).max()
    assert np.abs(sphere_op @ np.full(sphere_op.n_vertices, 3.7)).max() < 1e-10


def test_S_symmetric_negative_semidefinite(sphere_op):
    S = sphere_op.S
    asym = abs(S - S.T).max()
    assert asym <= 1e-15 * abs(S).max()
    eig = np.linalg.eigvalsh(S.toarray())
    assert eig.max() < 1e-12 * abs(eig).max()
    assert eig.min() < -1  # not a zero matrix
    # S is M L with M the lumped mass
    assert np.allclose(sphere_op.M.diagonal(), sphere_op.mass)
    assert abs(sphere_op.M @ sphere_op.L - S).max() == 0


def test_scaling_law():
    V, F = shapes.sphere(300, seed=4)
    f = V[:, 0] ** 2
    a = meshlap.laplacian(V, F, h=0.02, correction="none") @ f
    s = 3.5
    b = meshlap.laplacian(s * V, F, h=0.02 * s * s, correction="none") @ f
    assert np.allclose(b, a / s**2, rtol=1e-10, atol=1e-12)


def test_L_x2_is_two_on_the_plane_quads():
    # a regular quad grid: every interior vertex sees L x² = 2 up to the discretization
    n = 41
    xs, ys = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
    V = np.column_stack([xs.ravel(), ys.ravel()])
    idx = np.arange(n * n).reshape(n, n)
    Q = np.stack([idx[:-1, :-1], idx[:-1, 1:], idx[1:, 1:], idx[1:, :-1]], -1).reshape(-1, 4)
    h = 0.005
    op = meshlap.laplacian(V, Q, h=h, correction="none")
    inner = _interior(op.V, h)
    assert np.abs((op @ (op.V[:, 0] ** 2))[inner] - 2).max() < 0.02


def test_spot_triangles_and_quads():
    V, F = igl.read_triangle_mesh(str(DATA / "spot.obj"))
    op = meshlap.laplacian(V, F, correction="none")
    assert not op.h_auto or op.h == pytest.approx(meshlap.default_h(V, F))
    area = 0.5 * igl.doublearea(V, F).sum()
    assert op.mass.sum() == pytest.approx(area, rel=1e-12)
    Vq, _, _, Fq, _, _ = igl.readOBJ(str(DATA / "spot-quads.obj"))
    assert Fq.shape[1] == 4
    opq = meshlap.laplacian(Vq, Fq, h=op.h, correction="none")
    # quads hand a quarter of their area to each corner: total = the quads' area
    assert opq.mass.sum() == pytest.approx(meshlap.face_areas(Vq, Fq).sum(), rel=1e-12)
    # both discretize the same surface: coordinates' Laplacians agree to a few percent
    LV, LVq = op @ V, opq @ Vq
    assert np.linalg.norm(LV - LVq) / np.linalg.norm(LV) < 0.1


def test_operator_surface():
    V, F = shapes.sphere(200, seed=0)
    op = meshlap.laplacian(V, F, h=0.05, correction="none")
    assert isinstance(op.L, sp.csr_matrix) and op.L.shape == (200, 200)
    assert op.nnz == op.L.nnz and op.nbytes > 0
    assert "MeshLaplacian(" in repr(op) and "h=0.05" in repr(op)
    assert "<table>" in op._repr_html_()
    L, M = meshlap.mesh_laplacian(V, F, h=0.05, correction="none")
    assert abs(L + op.S).max() == 0 and np.allclose(M.diagonal(), op.mass)
    assert abs(meshlap.pointwise_laplacian(V, F, h=0.05, correction="none") - op.L).max() == 0
    lin = op.as_linear_operator()
    x = np.random.default_rng(0).normal(size=200)
    assert np.allclose(lin @ x, op @ x)


def test_matrix_free_and_float32_agree():
    V, F = shapes.sphere(1000, kind="random", seed=8)
    f = np.column_stack([np.exp(V[:, 0]), V[:, 1] ** 2])
    op = meshlap.laplacian(V, F, h=0.01, correction="none")
    free = meshlap.laplacian(V, F, h=0.01, matrix_free=True, correction="none")
    ref = op @ f
    assert np.abs(free @ f - ref).max() < 1e-10 * np.abs(ref).max()
    assert np.allclose(free.as_linear_operator().matmat(f), ref, rtol=1e-10, atol=1e-10)
    with pytest.raises(meshlap.MeshError, match="matrix-free"):
        free.L  # noqa: B018
    with pytest.raises(meshlap.MeshError, match="poisson, distances"):  # what needs a factor says so
        meshlap.poisson(free, f[:, 0] - f[:, 0].mean())
    op32 = meshlap.laplacian(V, F, h=0.01, dtype=np.float32, correction="none")
    assert op32.L.dtype == np.float32
    assert np.abs(op32 @ f - ref).max() < 1e-5 * np.abs(ref).max()


def test_matrix_free_applies_the_fitted_rows():
    # the rows read the points alone: without the kernel stored, op @ f is the default's
    V, F = shapes.sphere(1500, seed=0)
    x = V[:, 0]
    err = lambda y: np.linalg.norm(y + 2 * x) / np.linalg.norm(2 * x)  # noqa: E731  Δx = -2x
    free = meshlap.laplacian(V, F, matrix_free=True)
    assert np.array_equal(free @ V, meshlap.laplacian(V, F) @ V) and free.decision.rows == "fitted"
    assert err(free @ x) < 2e-5 and free._built.pencil_pending  # 7.6e-6; the kernel's rows: 0.037
    assert np.array_equal(free.as_linear_operator() @ x, free @ x)
    assert 40 * len(V) < free.L.nnz < 60 * len(V) and free.nbytes >= free.L.data.nbytes  # the rows, stored
    # spectra and heat flow read the kernel, recomputed: the stored kernel with the same options
    kernel = meshlap.laplacian(V, F, operator="kernel", h=free.h, arc_distance=False, neumann=False,
                               curvature_limit=0)
    assert np.abs(free.sym_product(V) - kernel.L_sym @ V).max() < 1e-10
    assert err(free.sym_product(x)) > 0.01
    assert np.allclose(meshlap.spectral.eigs(free, 5)[0], meshlap.spectral.eigs(kernel, 5)[0], atol=1e-9)
    plain = meshlap.laplacian(V, F, matrix_free=True, pointwise=False)  # the kernel's own rows, asked for
    assert plain.decision.rows == "pencil" and np.array_equal(plain @ x, plain.sym_product(x))
    with pytest.raises(meshlap.MeshError, match="pointwise='fit' or False"):
        meshlap.laplacian(V, F, matrix_free=True, pointwise=True)


def test_deterministic_whatever_thread_count():
    import numba

    V, F = shapes.sphere(3000, kind="random", seed=9)
    a = meshlap.laplacian(V, F, h=0.005, correction="none").L
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        b = meshlap.laplacian(V, F, h=0.005, correction="none").L
    finally:
        numba.set_num_threads(before)
    assert np.array_equal(a.indptr, b.indptr)
    assert np.array_equal(a.indices, b.indices)
    assert np.array_equal(a.data, b.data)


def test_progress_callback():
    V, F = shapes.sphere(6000, seed=0)
    seen = []
    op = meshlap.laplacian(V, F, h=0.002, progress=lambda frac, stage: seen.append((frac, stage)),
                           correction="none")
    assert seen == [(1.0, "done")]  # construction builds nothing: the pencil comes on first use
    seen.clear()
    op @ V  # the paper's L is its pencil's
    fracs = [f for f, _ in seen]
    assert fracs == sorted(fracs) and fracs[-1] == 1.0
    assert {"count", "fill", "done"} <= {s for _, s in seen}
    V, F = shapes.plane(1500, seed=0, kind="stratified")
    seen.clear()
    meshlap.laplacian(V, F, progress=lambda frac, stage: seen.append((frac, stage))).assemble()
    assert [s for _, s in seen] == ["done", "FEM pencil", "done"]  # the default: no kernel
    # the kernel reports each stage of the pipeline by name, in order (the Galerkin pencil's
    # after the vertex pencil's)
    seen.clear()
    op = meshlap.laplacian(V, F, operator="galerkin", progress=lambda frac, stage: seen.append((frac, stage)))
    assert seen == [(1.0, "done")]
    seen.clear()
    op.assemble()  # the pencil: on first use
    assert list(dict.fromkeys(s for _, s in seen)) == [
        "kernel rows", "boundary images", "semidefinite check", "moment scale", "Galerkin pencil", "done"]
    assert [f for f, _ in seen] == sorted(f for f, _ in seen)
    seen.clear()
    op @ V  # the fitted rows: on first use
    stages = list(dict.fromkeys(s for _, s in seen))
    fits = [s for s in stages if s.startswith("point-wise rows: ")]  # the row choice's own stages
    assert [s for s in stages if s not in fits] == ["point-wise rows", "done"]
    first = stages.index("point-wise rows") + 1
    assert stages[first:first + len(fits)] == fits and len(fits) >= 4
    assert fits[0] == "point-wise rows: queries" and fits[-1] == "point-wise rows: assemble"
    assert [f for f, _ in seen] == sorted(f for f, _ in seen)


def test_memory_guard():
    V, F = shapes.sphere(2000, seed=0)
    with pytest.raises(meshlap.OperatorTooLargeError, match="matrix_free=True"):
        meshlap.laplacian(V, F, h=1.0, max_memory=1_000_000, correction="none")
    free = meshlap.laplacian(V, F, h=1.0, max_memory=1_000_000, matrix_free=True, correction="none")
    assert free.nnz == 0


@pytest.mark.parametrize(
    ("V", "F", "kw", "match"),
    [
        (np.zeros(3), [[0, 1, 2]], {}, r"shape \(n, 3\)"),
        (np.zeros((3, 4)), [[0, 1, 2]], {}, "zero area"),
        (np.zeros((0, 3)), [[0, 1, 2]], {}, "empty"),
        (np.array([[0, 0, 0], [1, 0, np.nan], [0, 1, 0]]), [[0, 1, 2]], {}, "NaN"),
        (np.array([[0, 0, 0], [1, 0, np.inf], [0, 1, 0]]), [[0, 1, 2]], {}, "infinite"),
        (np.eye(3), [[0, 1, 3]], {}, "vertex 3 in face 0"),
        (np.eye(3), [[0, -1, 2]], {}, "vertex -1"),
        (np.eye(3), np.array([[0]]), {}, "at least 3"),
        (np.eye(3), np.array([[0, 1]]), {"k": 2}, "pass k=1"),
        (np.eye(3), np.array([[0.0, 1.5, 2.0]]), {}, "integer"),
        (np.eye(3), [[0, 1, 2]], {"h": 0}, "h must be"),
        (np.eye(3), [[0, 1, 2]], {"h": -1.0}, "h must be"),
        (np.eye(3), [[0, 1, 2]], {"h": float("nan")}, "h must be"),
        (np.eye(3), [[0, 1, 2]], {"tol": 1.0}, "tol must"),
        (np.eye(3), [[0, 1, 2]], {"tol": -1e-3}, "tol must"),
        (np.array([["a", "b", "c"]] * 3), [[0, 1, 2]], {}, "numeric"),
    ],
)
def test_bad_input_names_the_problem(V, F, kw, match):
    with pytest.raises(meshlap.MeshError, match=match):
        meshlap.laplacian(V, F, **kw)


def test_bad_function_shape():
    V, F = shapes.sphere(50, seed=0)
    op = meshlap.laplacian(V, F, h=0.1, correction="none")
    with pytest.raises(meshlap.MeshError, match=r"shape \(50,\)"):
        op @ np.ones(49)
    with pytest.raises(meshlap.MeshError, match="NaN"):
        op @ np.full(50, np.nan)
