"""The peers' idioms with meshlap's objects swapped in give the right spectrum and the right Δf.

On the unit sphere (``meshlap.shapes.sphere(2000, seed=0)``, near-regular triangles) the
eigenvalues of −Δ are l(l+1): 0, then 2 three times, 6 five times, 12 ... and Δx = −2x. Each
test writes a peer's idiom as its README or tutorial does (robust-laplacian, libigl, LaPy,
scipy's eigsh and lobpcg) with meshlap's pair or operator in place of the peer's, and asserts:
the first 9 nonzero eigenvalues within 1% of l(l+1) and Δx within 1% of −2x (relative 2-norm).
At 2,000 vertices the default's eigenvalues are 0.23% off and libigl's cotangent ones 0.47%, so
1% leaves room for a default at linear FEM's accuracy; its point-wise Δx is 3e-6 off.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as sla

import meshlap

EXACT = np.array([2.0] * 3 + [6.0] * 5 + [12.0])  # the first 9 nonzero l(l+1)
TOL = 0.01


@pytest.fixture(scope="module")
def sphere():
    return meshlap.shapes.sphere(2000, seed=0)


@pytest.fixture(scope="module")
def pair(sphere):
    return meshlap.mesh_laplacian(*sphere)


def spectrum_error(lam):
    lam = np.sort(np.asarray(lam))
    assert abs(lam[0]) < 1e-6, f"the first eigenvalue is the constant's, 0: got {lam[0]}"
    return np.abs(lam[1:10] / EXACT - 1).max()


def delta_error(Lx, x):
    return np.linalg.norm(Lx + 2 * x) / np.linalg.norm(2 * x)


def test_pair_is_robust_laplacians_convention(pair):
    """L symmetric positive semidefinite with L @ 1 = 0, M diagonal and positive (the sphere's area)."""
    L, M = pair
    assert isinstance(L, sp.csr_matrix) and isinstance(M, sp.csr_matrix)
    assert abs(L - L.T).max() <= 1e-12 * abs(L).max()
    assert np.abs(L @ np.ones(L.shape[0])).max() <= 1e-10 * abs(L).max()
    assert sla.eigsh(L, 1, which="SA", tol=1e-6)[0][0] > -1e-8 * abs(L).max()   # no negative mode
    assert (M - sp.diags(M.diagonal())).nnz == 0 and M.diagonal().min() > 0
    assert M.diagonal().sum() == pytest.approx(4 * np.pi, rel=0.01)


def test_robust_laplacian_idiom(sphere, pair):
    """robust-laplacian's README: ``L, M = mesh_laplacian(V, F); eigsh(L, k, M, sigma=1e-8)``."""
    V, F = sphere
    L, M = pair                                    # robust_laplacian.mesh_laplacian(V, F)
    evals, _ = sla.eigsh(L, 10, M, sigma=1e-8)
    assert spectrum_error(evals) < TOL
    # Δf: meshlap's point-wise matrix, where a robust-laplacian user reads -M⁻¹ L f
    assert delta_error(meshlap.pointwise_laplacian(V, F) @ V[:, 0], V[:, 0]) < TOL


def test_libigl_idiom(sphere):
    """libigl's tutorial: ``L = cotmatrix``, ``M = massmatrix``, ``eigsh(-L, k, M, sigma=...)``;
    meshlap: ``op.S`` has cotmatrix's sign (≈ M Δ, negative semidefinite) and ``op @ f`` is Δf."""
    V, F = sphere
    op = meshlap.laplacian(V, F)
    L, M = op.S, op.M                              # igl.cotmatrix(V, F), igl.massmatrix(V, F)
    assert L.diagonal().max() < 0                  # cotmatrix's sign
    evals, _ = sla.eigsh(-L, 10, M, sigma=-1e-6)
    assert spectrum_error(evals) < TOL
    assert delta_error(op @ V[:, 0], V[:, 0]) < TOL    # where libigl writes M⁻¹ (L @ x)


def test_lapy_idiom(sphere, pair):
    """LaPy's ``Solver(TriaMesh(V, F)).eigs(k)`` run by LaPy itself on meshlap's pair: its
    ``stiffness`` is the positive semidefinite weak form and ``mass`` the mass, as meshlap's."""
    lapy = pytest.importorskip("lapy", reason="LaPy absent (pip install lapy)")
    V, F = sphere
    fem = lapy.Solver(lapy.TriaMesh(V, F))
    L, M = pair
    x = V[:, 0]                                    # the same sign as LaPy's: x·Ax = ∫|∇x|² = 8π/3
    assert x @ (fem.stiffness @ x) == pytest.approx(8 * np.pi / 3, rel=0.01)
    assert x @ (L @ x) == pytest.approx(8 * np.pi / 3, rel=0.01)
    fem.stiffness, fem.mass = L.tocsc(), M.tocsc()
    evals, _ = fem.eigs(k=10)
    assert spectrum_error(evals) < TOL
    assert delta_error(meshlap.pointwise_laplacian(V, F) @ V[:, 0], V[:, 0]) < TOL


def test_scipy_eigsh_and_lobpcg_on_the_pair(pair):
    """scipy as its users write it: eigsh in shift-invert mode, and lobpcg on the pair and on
    LinearOperators of it, preconditioned by a factorization of L + σM, its block ending at a
    gap of the spectrum (16 = 1 + 3 + 5 + 7 on the sphere)."""
    L, M = pair
    n = L.shape[0]
    assert spectrum_error(sla.eigsh(L.tocsc(), 10, M.tocsc(), sigma=-0.01)[0]) < TOL
    lu = sla.splu((L + 0.01 * M).tocsc())
    precond = sla.LinearOperator((n, n), matvec=lu.solve, matmat=lu.solve, dtype=np.float64)
    X = np.random.default_rng(0).normal(size=(n, 16))   # l ≤ 3: a block that does not cut a cluster
    for A, B in ((L, M), (sla.aslinearoperator(L), sla.aslinearoperator(M))):
        with warnings.catch_warnings():
            warnings.simplefilter("error")     # not converged would warn
            evals, _ = sla.lobpcg(A, X, B=B, M=precond, largest=False, tol=1e-6, maxiter=100)
        assert spectrum_error(evals) < TOL


def test_spectral_eigs_agrees(sphere):
    """meshlap's own eigensolver on the pair (``elements="linear"``): the same spectrum as eigsh."""
    op = meshlap.laplacian(*sphere)
    lam, _ = meshlap.spectral.eigs(op, 10, elements="linear")
    assert spectrum_error(lam) < TOL
    ref = sla.eigsh(-op.S, 10, op.M, sigma=-1e-6)[0]
    assert np.abs(np.sort(ref)[1:] / lam[1:] - 1).max() < 1e-6
    # by default eigs solves quadratic elements on the same triangles: l(l+1) as closely
    assert spectrum_error(meshlap.spectral.eigs(op, 10)[0]) < TOL


def test_point_cloud_pair_idiom():
    """robust-laplacian's ``L, M = point_cloud_laplacian(P)`` is ``meshlap.point_cloud_matrices(P)``."""
    P = meshlap.samples.sphere_points(3000, "uniform")
    L, M = meshlap.point_cloud_matrices(P)
    assert abs(L - L.T).max() <= 1e-12 * abs(L).max()
    assert spectrum_error(sla.eigsh(L, 10, M, sigma=1e-8)[0]) < TOL
    assert delta_error(meshlap.pointwise_laplacian(P) @ P[:, 0], P[:, 0]) < TOL


def test_weak_form_read_pointwise(sphere, pair):
    """libigl's Δf, ``M⁻¹ (L @ f)``, read from meshlap's weak pair: the Voronoi areas of the FEM
    pencil's lumped mass make it as accurate as libigl's cotangent (0.37%; with the barycentric
    lumping it was 8.2% off)."""
    V, _ = sphere
    L, M = pair
    assert delta_error(-(L @ V[:, 0]) / M.diagonal(), V[:, 0]) < TOL


def test_old_meaning_warns(sphere):
    """0.1.0's pair, ``(op.L, op.M)``, is one keyword away for one release, with a DeprecationWarning."""
    V, F = sphere
    with pytest.warns(DeprecationWarning, match="pointwise_laplacian"):
        Lp, M = meshlap.mesh_laplacian(V, F, form="pointwise")
    assert delta_error(Lp @ V[:, 0], V[:, 0]) < TOL
    with pytest.raises(meshlap.MeshError, match="form must be"):
        meshlap.mesh_laplacian(V, F, form="strong")
    P = meshlap.samples.sphere_points(1000, "uniform")
    with pytest.warns(DeprecationWarning, match="point_cloud_matrices"):
        Lp, M = meshlap.point_cloud_matrices(P, form="pointwise")
    op = meshlap.point_cloud_laplacian(P)
    assert abs(Lp - op.L).max() == 0 and abs(M - op.M).max() == 0
