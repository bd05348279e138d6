"""The curvature cap's sums: compiled, and equal to the bit to the numpy expression they
replaced; an explicit h too narrow for the corrected kernel's narrow half (meshlap.widths)."""

import warnings

import numpy as np
import pytest
import scipy.linalg as sla

import meshlap
from meshlap import widths


def _edges_with_repeats(n, rng):
    # face sides of a random sphere, again reversed, a point joined to 40 others, an edge from a
    # point to itself
    V, F = meshlap.shapes.sphere(n, kind="random", seed=4)
    e = meshlap.geometry.validation.check_faces(F, n).edges()
    hub = np.column_stack([np.zeros(40, dtype=np.int64), rng.choice(np.arange(1, n), 40, replace=False)])
    return V, np.vstack([e, e[::-1, ::-1], hub, [[7, 7]]])


def test_curvature_sums_equal_the_bincounts():
    rng = np.random.default_rng(5)
    V, e = _edges_with_repeats(1500, rng)
    n = len(V)
    for P, N in ((V, V + 0.01 * rng.normal(size=V.shape)), (V[:, :2], rng.normal(size=(n, 2)))):
        d2 = ((P[e[:, 0]] - P[e[:, 1]]) ** 2).sum(axis=1)
        dn2 = ((N[e[:, 0]] - N[e[:, 1]]) ** 2).sum(axis=1)
        num, den = np.zeros(n), np.zeros(n)
        widths._curvature_sums(np.ascontiguousarray(P), np.ascontiguousarray(N), e, num, den)
        assert np.array_equal(num, np.bincount(e[:, 0], dn2, n) + np.bincount(e[:, 1], dn2, n))
        assert np.array_equal(den, np.bincount(e[:, 0], d2, n) + np.bincount(e[:, 1], d2, n))


def test_an_h_too_narrow_for_the_corrected_kernel_is_warned_of_where_it_costs():
    """At h = spacing² on a random 1,000-vertex sphere the corrected kernel's eigenvalues are
    further off than the paper's plain kernel's (its narrow half falls between the samples), and
    the build says so; at its own width, at a wide explicit h, with correction='none' or
    integrated over the cells (Galerkin) it does not."""
    V, F = meshlap.shapes.sphere(1000, kind="random", seed=0)
    a2 = meshlap.geometry.from_mesh(V, F).spacing ** 2
    exact = meshlap.samples.sphere_eigenvalues(16)[1:]

    def error(op):
        S = op.S.toarray()
        lam = sla.eigh(-0.5 * (S + S.T), np.diag(op.mass), eigvals_only=True, subset_by_index=[0, 15])
        return np.abs(lam[1:] / exact - 1).max()
    with pytest.warns(meshlap.MeshWarning, match="narrow half"):
        narrow = meshlap.laplacian(V, F, a2, pointwise=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error", meshlap.MeshWarning)
        plain = meshlap.laplacian(V, F, a2, correction="none")
        meshlap.laplacian(V, F, 2 * a2)
        meshlap.laplacian(V, F, operator="kernel")
        meshlap.laplacian(V, F, a2, quadrature="galerkin")
    assert error(narrow) > 1.5 * error(plain)  # measured 24.6% against 13.2%
