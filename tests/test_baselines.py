"""The baseline Laplacians: values against analytic Laplacians, signs and conventions."""

import math
import sys

import igl
import numpy as np
import pytest
import scipy.sparse as sp

from meshlap import MeshError, baselines, samples, shapes


@pytest.fixture(scope="module")
def sphere2000():
    return shapes.sphere(2000, kind="uniform", seed=0)


def rel(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


def test_cotangent_on_sphere(sphere2000):
    V, F = sphere2000
    op = baselines.cotangent(V, F)
    x = V[:, 0]
    assert rel(op @ x, -2 * x) < 0.006          # measured 0.0037
    assert rel(op @ x**2, 2 - 6 * x**2) < 0.012   # measured 0.0073
    assert op.mass.sum() == pytest.approx(4 * np.pi, rel=2e-3)
    S = op.S
    assert abs(S - S.T).max() < 1e-12 and abs(np.asarray(S.sum(axis=1))).max() < 1e-10


def equilateral_patch(k=12):
    """A hexagon-shaped patch of the equilateral triangle lattice (edge 1) and its interior."""
    i, j = np.meshgrid(np.arange(-k, k + 1), np.arange(-k, k + 1), indexing="ij")
    xy = np.column_stack([(i + 0.5 * j).ravel(), (np.sqrt(3) / 2 * j).ravel()])
    from scipy.spatial import Delaunay

    F = Delaunay(xy).simplices
    a, b, c = xy[F[:, 0]], xy[F[:, 1]], xy[F[:, 2]]
    cw = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) < 0
    F[cw] = F[cw][:, ::-1]
    V = np.column_stack([xy, np.zeros(len(xy))])
    inner = (np.abs(i) < k - 1).ravel() & (np.abs(j) < k - 1).ravel() & (np.abs(i + j) < k - 1).ravel()
    return V, F.astype(np.int64), inner


def test_uniform_graph_rows_sum_to_zero_and_structure(sphere2000):
    V, F = sphere2000
    op = baselines.uniform_graph(V, F)
    S = op.S.tocsr()
    assert abs(np.asarray(S.sum(axis=1))).max() < 1e-12
    assert abs(np.asarray(op.L.sum(axis=1))).max() < 1e-9
    assert abs(S - S.T).max() == 0
    off = S - sp.diags(S.diagonal())
    # every edge once in each direction, all with the same weight
    assert off.nnz == 2 * (3 * len(V) - 6)
    assert np.allclose(off.data, 1 / np.sqrt(3))
    assert np.all(S.diagonal() < 0)


def test_uniform_graph_matches_cotangent_on_equilateral_lattice():
    V, F, inner = equilateral_patch()
    g = baselines.uniform_graph(V, F)
    c = baselines.cotangent(V, F)
    f = V[:, 0] ** 2 + 3 * V[:, 1]
    assert np.allclose((g @ f)[inner], 2.0, atol=1e-10)
    assert np.allclose((g @ f)[inner], (c @ f)[inner], atol=1e-10)


def test_uniform_graph_ignores_geometry():
    # on an irregular mesh the uniform graph Laplacian is far from Δ, unlike COT
    V, F = shapes.sphere(2000, kind="nonuniform", seed=1)
    x = V[:, 0]
    assert rel(baselines.uniform_graph(V, F) @ x, -2 * x) > 1.0


def test_intrinsic_delaunay_signs_and_values(sphere2000):
    import robust_laplacian

    V, F = sphere2000
    op = baselines.intrinsic_delaunay(V, F)
    Lr, Mr = robust_laplacian.mesh_laplacian(V, F)
    # robust-laplacian's weak form is positive semidefinite; ours is its negative
    assert np.all(Lr.diagonal() > 0) and np.all(op.S.diagonal() < 0)
    assert abs(op.S + Lr).max() == 0
    assert np.allclose(op.mass, Mr.diagonal())
    f = np.random.default_rng(0).normal(size=len(V))
    assert f @ (op.S @ f) < 0
    # a hull of points on a sphere is already Delaunay: the intrinsic Delaunay cotangent matrix
    # is libigl's cotangent matrix (up to the tiny mollification)
    C = igl.cotmatrix(V, F)
    assert abs(op.S - C).max() < 1e-6 * abs(C).max()
    x = V[:, 0]
    # its lumped barycentric mass leaves a pointwise error that does not vanish: measured 0.082
    assert rel(op @ x, -2 * x) < 0.1


def test_intrinsic_delaunay_missing_extra(monkeypatch, sphere2000):
    monkeypatch.setitem(sys.modules, "robust_laplacian", None)
    with pytest.raises(ImportError, match=r"pip install meshlap\[robust\]"):
        baselines.intrinsic_delaunay(*sphere2000)


@pytest.mark.parametrize("make", [baselines.cotangent, baselines.uniform_graph, baselines.intrinsic_delaunay])
def test_triangles_only_and_block_apply(make):
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    with pytest.raises(MeshError, match="triangles"):
        make(V, [[0, 1, 2, 3]])
    V, F = shapes.sphere(300, seed=0)
    op = make(V, F)
    block = op @ V
    assert block.shape == (300, 3) and np.allclose(block[:, 1], op @ V[:, 1])
    assert op.shape == (300, 300) and op.M.shape == (300, 300)


def test_cotangent_with_trailing_unreferenced_vertices():
    # libigl sizes its matrices by the largest face index; trailing free vertices must still fit
    V, F = shapes.sphere(300, seed=0)
    V2 = np.vstack([V, [[5.0, 5.0, 5.0], [6.0, 6.0, 6.0]]])
    cot, ref = baselines.cotangent(V2, F), baselines.cotangent(V, F)
    assert cot.L.shape == (302, 302) and np.array_equal(cot.mass[-2:], [0.0, 0.0])
    assert np.allclose((cot @ V2[:, 0])[:300], ref @ V[:, 0], rtol=1e-12, atol=1e-12)


def test_cotangent_of_a_polyline_is_linear_fem_on_its_segments():
    # the uniform n-gon: (K, lumped mass) has the eigenvalues 4 sin²(πm/n)/ℓ², ℓ = 2 sin(π/n)
    n = 50
    P, E, _ = samples.circle(n)
    op = baselines.cotangent(P, E)
    ell = 2 * math.sin(math.pi / n)
    lam = np.sort(np.linalg.eigvalsh(-op.S.toarray() / ell))
    exact = np.sort(4 * np.sin(math.pi * np.arange(n) / n) ** 2 / ell**2)
    assert np.allclose(lam, exact, rtol=1e-10, atol=1e-10)
    assert np.allclose(op.mass, ell) and abs(op.S - op.S.T).max() == 0
    # an open chain: Neumann ends, rows sum to zero, and x'' = 0 in the interior rows
    x = np.sort(np.random.default_rng(0).uniform(0, 1, 30))
    chain = np.column_stack([np.arange(29), np.arange(1, 30)])
    op = baselines.cotangent(np.column_stack([x, 0 * x]), chain)
    assert np.abs(op @ np.ones(30)).max() < 1e-9 and np.abs((op @ x)[1:-1]).max() < 1e-9
