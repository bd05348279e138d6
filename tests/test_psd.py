"""The semidefiniteness check: cheap on a semidefinite operator, and a negative mode is caught
wherever it lives (issue 19)."""

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

import meshlap
from meshlap import geometry, shapes
from meshlap.corrections import psd


def dense_min(L, mass):
    S = mass[:, None] * L.toarray()
    return sla.eigh(-0.5 * (S + S.T), np.diag(mass), eigvals_only=True, subset_by_index=[0, 0])[0]


def spiked(L, mass, a, b, excess):
    """L plus a rank-one term on two vertices: S stays symmetric and the rows still sum to zero;
    −S gets a mode localized at a and b whose Rayleigh quotient is −excess times its own energy."""
    v = np.zeros(len(mass))
    v[a], v[b] = 1.0 / mass[a], -1.0 / mass[b]  # M-orthogonal to the constant
    Mv = mass * v
    energy = float(v @ (-(mass * (L @ v))))
    alpha = (1.0 + excess) * energy / float(v @ Mv) ** 2
    ab = [a, b]
    rank_one = sp.coo_matrix((alpha * np.outer(v[ab], Mv[ab]).ravel(), (np.repeat(ab, 2), np.tile(ab, 2))),
                             shape=L.shape)
    return sp.csr_matrix(L + rank_one)


def test_semidefinite_default_passes_and_agrees_with_dense():
    V, F = shapes.sphere(1300, kind="random", seed=5)
    op = meshlap.laplacian(V, F, check_psd=False)
    faces = geometry.from_mesh(V, F).faces
    lam, scale = psd.smallest_eigenvalue(op.L_sym, op.mass, V, faces)
    assert abs(lam) < 1e-12 * scale  # the constant: 0 up to rounding
    assert dense_min(op.L_sym, op.mass) > -1e-9 * scale  # measured densely: semidefinite
    margin, reason = psd.check(op.L_sym, op.mass, V, faces, "mesh")
    assert reason is None and margin > -1e-12


def test_a_localized_negative_mode_is_caught():
    # a high-frequency mode at two neighbouring vertices, the kind the smooth start misses
    V, F = shapes.sphere(1300, kind="random", seed=5)
    op = meshlap.laplacian(V, F, check_psd=False)
    faces = geometry.from_mesh(V, F).faces
    a, b = int(F[100, 0]), int(F[100, 1])
    L = spiked(op.L_sym, op.mass, a, b, 1e-2)
    assert np.abs(L @ np.ones(len(V))).max() < 1e-9 * abs(L).max()
    exact = dense_min(L, op.mass)
    scale = float(np.max(-L.diagonal()))
    assert exact < -1e-4 * scale  # measured densely: not semidefinite
    lam, _ = psd.smallest_eigenvalue(L, op.mass, V, faces)
    assert lam < -psd.PSD_RTOL * scale and lam >= exact - 1e-9 * scale  # a Ritz value: above λ_min
    margin, reason = psd.check(L, op.mass, V, faces, "mesh")
    assert reason is not None and "not negative semidefinite" in reason and margin < 0


def test_a_positive_diagonal_decides_without_the_eigensolver(monkeypatch):
    # at a quarter of e-bar squared some points' kernel weights sum below zero: the indicator
    # of such a point has Rayleigh quotient -L_ww < 0, a proof of the failure that needs no
    # LOBPCG, and an upper bound of the smallest eigenvalue (checked densely)
    import igl

    V, F = shapes.sphere(2000, kind="random", seed=1)
    h = 0.25 * float(igl.edge_lengths(V, F).mean()) ** 2
    op = meshlap.laplacian(V, F, h=h, check_psd=False, pointwise=False)
    d = op.L_sym.diagonal()
    assert d.max() > 0

    def unused(*args, **kwargs):
        raise AssertionError("the eigensolver ran")

    monkeypatch.setattr(meshlap._lobpcg, "lobpcg", unused)
    faces = geometry.from_mesh(V, F).faces
    lam, scale = psd.smallest_eigenvalue(op.L_sym, op.mass, V, faces)
    assert lam == -d.max() and dense_min(op.L_sym, op.mass) <= lam
    margin, reason = psd.check(op.L_sym, op.mass, V, faces, "mesh")
    assert reason is not None and margin == lam / scale


def test_the_diagonal_and_constant_product_from_the_fill_give_the_same_margin(monkeypatch):
    # on a closed mesh the checked rows are the filled ones: the build hands the check their
    # diagonal and product with the constant, and makes neither again (issue 19); the margin
    # is the one the check computes from the matrix alone, to the bit
    V, F = shapes.sphere(1500, kind="random", seed=6)
    geo = geometry.from_mesh(V, F)
    calls = []
    real = sp.csr_matrix.diagonal
    monkeypatch.setattr(sp.csr_matrix, "diagonal", lambda self, k=0: calls.append(k) or real(self, k))
    op = meshlap.laplacian(V, F, pointwise=False)
    assert op.correction == "richardson" and calls == []
    kern = meshlap.assembly.Kernel(2, dog=True, normals=geo.normals(), tol=op.options.tol)
    free = meshlap.assembly.assemble(geo.points, geo.mass, op.widths, kern)
    margin = psd.check(free, geo.mass, V, geo.faces, "mesh")[0]
    assert op._built.assemble().psd_margin == margin and calls == [0]


def fill_products(L, V, mass):
    # what the build hands the check: L's diagonal and its product with [V, fill_columns]
    return L.diagonal(), L @ np.column_stack([V, psd.fill_columns(V, mass)])


def counted_products(monkeypatch):
    calls = []
    real = meshlap.spectral.apply_block
    monkeypatch.setattr(meshlap.spectral, "apply_block", lambda op, X: calls.append(X.shape) or real(op, X))
    return calls


def test_the_start_products_from_the_fill_save_the_first_product(monkeypatch):
    # the coordinate functions' and random vectors' products come from the fill: LOBPCG's
    # start multiplies nothing, one product of six columns fewer than alone, and the result
    # is the one the check computes alone
    V, F = shapes.sphere(1500, kind="random", seed=6)
    op = meshlap.laplacian(V, F, check_psd=False, pointwise=False)
    faces = geometry.from_mesh(V, F).faces
    calls = counted_products(monkeypatch)
    alone = psd.smallest_eigenvalue(op.L_sym, op.mass, V, faces)
    made = len(calls)
    fused = psd.smallest_eigenvalue(op.L_sym, op.mass, V, faces, known=fill_products(op.L_sym, V, op.mass))
    assert made >= 1 and calls[0][1] == 6 and len(calls) == 2 * made - 1
    assert abs(fused[0] - alone[0]) < 1e-12 * alone[1] and fused[1] == alone[1]


def test_an_indefinite_operator_still_fails_from_the_fills_start(monkeypatch):
    # the localized mode of the test above, the start's products from the fill: the iteration
    # still finds it, and what it returns is a Ritz value, an upper bound of the smallest
    # eigenvalue (measured densely)
    V, F = shapes.sphere(1300, kind="random", seed=5)
    op = meshlap.laplacian(V, F, check_psd=False)
    faces = geometry.from_mesh(V, F).faces
    a, b = int(F[100, 0]), int(F[100, 1])
    L = spiked(op.L_sym, op.mass, a, b, 1e-2)
    exact = dense_min(L, op.mass)
    calls = counted_products(monkeypatch)
    alone, _ = psd.smallest_eigenvalue(L, op.mass, V, faces)
    made = len(calls)
    lam, scale = psd.smallest_eigenvalue(L, op.mass, V, faces, known=fill_products(L, V, op.mass))
    assert made >= 2 and len(calls) == 2 * made - 1  # the start's product saved
    assert exact <= lam < -psd.PSD_RTOL * scale and exact <= alone < -psd.PSD_RTOL * scale
