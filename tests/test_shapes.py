"""Test surfaces: counts, orientation, reproducibility, and the exact Laplacians checked
symbolically (sympy, from the parametrization's metric) and by finite differences."""

import math

import igl
import numpy as np
import pytest
import sympy as sy

from meshlap import MeshError, shapes


def closed_manifold(F):
    e = np.sort(np.vstack([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    return bool(np.all(counts == 2)), len(counts)


def test_plane_counts_orientation_seed():
    V, F = shapes.plane(300, seed=3)
    assert V.shape == (300, 3) and np.all(V[:, 2] == 0) and np.abs(V[:, :2]).max() <= 1
    assert {(-1.0, -1.0), (1.0, 1.0)} <= set(map(tuple, V[:, :2].tolist()))
    N = igl.per_face_normals(V, F, np.array([0.0, 0, 1]))
    assert np.all(N[:, 2] > 0.999)
    assert igl.doublearea(V, F).sum() / 2 == pytest.approx(4.0, rel=1e-12)
    V2, F2 = shapes.plane(300, seed=3)
    assert np.array_equal(V, V2) and np.array_equal(F, F2)
    assert not np.array_equal(V, shapes.plane(300, seed=4)[0])


def test_stratified_plane_one_sample_per_cell():
    V, F = shapes.plane(500, seed=2, kind="stratified")
    m = 22  # round(√500)
    assert V.shape == (m * m, 3) and np.all(V[:, 2] == 0)
    N = igl.per_face_normals(V, F, np.array([0.0, 0, 1]))
    assert np.all(N[:, 2] > 0.999)
    assert igl.doublearea(V, F).sum() / 2 == pytest.approx(4.0, rel=1e-12)  # covers the square
    # each vertex lies in the grid cell around its node; the edge nodes stay on the edges
    grid = np.linspace(-1, 1, m)
    nodes = np.column_stack([np.repeat(grid, m), np.tile(grid, m)])
    step = 2 / (m - 1)
    assert np.abs(V[:, :2] - nodes).max() <= step / 2
    edge = np.abs(nodes).max(axis=1) == 1
    assert np.array_equal(V[edge, :2], nodes[edge]) and np.abs(V[~edge, :2] - nodes[~edge]).max() > 0.4 * step
    assert np.array_equal(V, shapes.plane(500, seed=2, kind="stratified")[0])


def test_noisy_sphere_amplitude():
    clean, F0 = shapes.sphere(2000, kind="uniform", seed=5)
    a = shapes.mean_edge_estimate(4 * math.pi, 2000)
    for noise in (0.05, 0.2):
        V, F = shapes.sphere(2000, kind="noisy", seed=5, noise=noise)
        assert np.array_equal(F, F0)  # the clean mesh's connectivity, its vertices moved
        assert np.std(V - clean) == pytest.approx(noise * a, rel=0.03)
    assert np.array_equal(shapes.sphere(2000, kind="noisy", seed=5, noise=0.0)[0], clean)


@pytest.mark.parametrize("kind", shapes.SPHERE_KINDS)
def test_sphere_counts_orientation_seed(kind):
    n = 1000
    V, F = shapes.sphere(n, kind=kind, seed=1)
    assert V.shape == (n, 3) and F.shape == (2 * n - 4, 3) and F.dtype == np.int64
    closed, n_edges = closed_manifold(F)
    assert closed and n - n_edges + len(F) == 2  # a sphere: Euler characteristic 2
    normal = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    assert np.all(np.einsum("ij,ij->i", normal, V[F].mean(axis=1)) > 0)  # outward
    radius = np.linalg.norm(V, axis=1)
    if kind == "noisy":
        sigma = shapes.NOISE_FRACTION * shapes.mean_edge_estimate(4 * math.pi, n)
        # the radial part of an isotropic N(0, σ²) shift has standard deviation σ
        assert np.std(radius - 1) == pytest.approx(sigma, rel=0.1)
    else:
        assert np.allclose(radius, 1, atol=1e-12)
    V2, F2 = shapes.sphere(n, kind=kind, seed=1)
    assert np.array_equal(V, V2) and np.array_equal(F, F2)
    assert not np.array_equal(V, shapes.sphere(n, kind=kind, seed=2)[0])


def test_sphere_triangle_quality_by_kind():
    min_angle = {k: np.degrees(shapes.triangle_angles(*shapes.sphere(2000, kind=k, seed=0))).min()
                 for k in shapes.SPHERE_KINDS}
    assert min_angle["uniform"] > 30          # near-regular
    assert min_angle["nonuniform"] < 5 and min_angle["random"] < 5   # skinny triangles


def test_nonuniform_density_ratio():
    V, _ = shapes.sphere(20000, kind="nonuniform", seed=0)
    beta = 0.5 * math.log(shapes.NONUNIFORM_RATIO)
    # fraction of samples with z > 0.8 (and z < -0.8) under density ∝ exp(βz)
    expect_top = (math.exp(beta) - math.exp(0.8 * beta)) / (math.exp(beta) - math.exp(-beta))
    expect_bottom = (math.exp(-0.8 * beta) - math.exp(-beta)) / (math.exp(beta) - math.exp(-beta))
    assert np.mean(V[:, 2] > 0.8) == pytest.approx(expect_top, rel=0.05)
    assert np.mean(V[:, 2] < -0.8) == pytest.approx(expect_bottom, rel=0.15)
    # per unit area, the two polar caps differ by about the stated ratio
    assert 30 < np.mean(V[:, 2] > 0.8) / np.mean(V[:, 2] < -0.8) < 70


def test_torus_mesh():
    R, r = 1.0, 0.4
    V, F = shapes.torus(3000, R=R, r=r, seed=2)
    closed, n_edges = closed_manifold(F)
    assert closed and len(V) - n_edges + len(F) == 0  # a torus: Euler characteristic 0
    rho = np.hypot(V[:, 0], V[:, 1])
    assert np.allclose((rho - R) ** 2 + V[:, 2] ** 2, r * r, atol=1e-12)
    th, ph = shapes.torus_angles(V[F].mean(axis=1), R)
    outward = np.column_stack([np.cos(th) * np.cos(ph), np.cos(th) * np.sin(ph), np.sin(th)])
    N = igl.per_face_normals(V, F, np.array([0.0, 0, 1]))
    assert np.all(np.einsum("ij,ij->i", N, outward) > 0.5)
    assert igl.doublearea(V, F).sum() / 2 == pytest.approx(4 * math.pi**2 * R * r, rel=5e-3)
    assert np.array_equal(V, shapes.torus(3000, R=R, r=r, seed=2)[0])
    assert abs(len(V) - 3000) < 0.05 * 3000


@pytest.mark.parametrize("call", [lambda: shapes.sphere(3), lambda: shapes.sphere(100, kind="cube"),
                                  lambda: shapes.plane(2), lambda: shapes.torus(100, R=1, r=2),
                                  lambda: shapes.sphere(10.5), lambda: shapes.plane(100, kind="hex"),
                                  lambda: shapes.sphere(100, kind="noisy", noise=-0.1)])
def test_bad_arguments(call):
    with pytest.raises(MeshError):
        call()


# -- exact Laplacians ------------------------------------------------------------------------
def laplace_beltrami(X, u, v, f):
    """Δ_S f = (1/√g) ∂_i(√g g^{ij} ∂_j f) for f(x, y, z) on the surface X(u, v)."""
    J = sy.Matrix.hstack(X.diff(u), X.diff(v))
    g = sy.simplify(J.T * J)
    sqrt_g = sy.sqrt(sy.simplify(g.det()))
    ginv = sy.simplify(g.inv())
    F = f(*X)
    grad = [F.diff(u), F.diff(v)]
    coords = [u, v]
    return sum((sqrt_g * sum(ginv[i, j] * grad[j] for j in range(2))).diff(coords[i])
               for i in range(2)) / sqrt_g


SYMPY_FUNCS = {
    "x": lambda x, y, z: x, "z": lambda x, y, z: z, "x^2": lambda x, y, z: x**2,
    "exp(x)": lambda x, y, z: sy.exp(x), "exp(x+y)": lambda x, y, z: sy.exp(x + y),
}


def test_sphere_laplacians_match_sympy():
    th, ph = sy.symbols("theta phi", real=True)
    X = sy.Matrix([sy.sin(th) * sy.cos(ph), sy.sin(th) * sy.sin(ph), sy.cos(th)])
    rng = np.random.default_rng(0)
    T, P = rng.uniform(0.2, 3.0, 20), rng.uniform(0, 2 * np.pi, 20)
    V = np.column_stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)])
    for name, (_, lap) in shapes.sphere_functions().items():
        expr = sy.lambdify((th, ph), laplace_beltrami(X, th, ph, SYMPY_FUNCS[name]), "numpy")
        assert np.allclose(lap(V), expr(T, P), rtol=1e-10, atol=1e-12), name


@pytest.mark.parametrize("R, r", [(1.0, 0.4), (2.0, 0.5)])
def test_torus_laplacians_match_sympy(R, r):
    th, ph = sy.symbols("theta phi", real=True)
    X = sy.Matrix([(R + r * sy.cos(th)) * sy.cos(ph), (R + r * sy.cos(th)) * sy.sin(ph), r * sy.sin(th)])
    rng = np.random.default_rng(1)
    T, P = rng.uniform(-np.pi, np.pi, 20), rng.uniform(-np.pi, np.pi, 20)
    V = np.column_stack([(R + r * np.cos(T)) * np.cos(P), (R + r * np.cos(T)) * np.sin(P), r * np.sin(T)])
    for name, (_, lap) in shapes.torus_functions(R, r).items():
        expr = sy.lambdify((th, ph), laplace_beltrami(X, th, ph, SYMPY_FUNCS[name]), "numpy")
        assert np.allclose(lap(V), expr(T, P), rtol=1e-9, atol=1e-12), name


def test_plane_laplacians_match_sympy():
    x, y = sy.symbols("x y", real=True)
    V = np.random.default_rng(2).uniform(-1, 1, size=(10, 3))
    for name, (_, lap) in shapes.plane_functions().items():
        f = SYMPY_FUNCS[name](x, y, 0)
        expr = sy.lambdify((x, y), f.diff(x, 2) + f.diff(y, 2), "numpy")
        assert np.allclose(lap(V), np.broadcast_to(expr(V[:, 0], V[:, 1]), len(V)), rtol=1e-12)


def fd_laplacian_3d(F, P, step=1e-3):
    """Second-order central differences of the ambient Laplacian of F at points P."""
    out = np.zeros(len(P))
    for k in range(3):
        e = np.zeros(3)
        e[k] = step
        out += (F(P + e) - 2 * F(P) + F(P - e)) / step**2
    return out


def test_sphere_laplacians_match_finite_differences():
    # f(x/|x|) is constant along rays, so its ambient Laplacian on |x| = 1 is Δ_S f.
    V, _ = shapes.sphere(50, kind="random", seed=4)
    for name, (f, lap) in shapes.sphere_functions().items():
        ext = lambda P, f=f: f(P / np.linalg.norm(P, axis=1, keepdims=True))  # noqa: E731
        assert np.allclose(fd_laplacian_3d(ext, V), lap(V), atol=2e-5), name


def test_torus_laplacians_match_finite_differences():
    # f ∘ (closest point on the torus) has ambient Laplacian Δ_S f on the torus.
    R, r = 1.0, 0.4
    V, _ = shapes.torus(60, R=R, r=r, seed=5)

    def closest(P):
        th, ph = shapes.torus_angles(P, R)
        return shapes._torus_point(th, ph, R, r)

    for name, (f, lap) in shapes.torus_functions(R, r).items():
        fd = fd_laplacian_3d(lambda P, f=f: f(closest(P)), V, step=3e-4)
        assert np.allclose(fd, lap(V), rtol=5e-5, atol=1e-5), name
