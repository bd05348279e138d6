"""The compiled small dense routines against numpy's LAPACK."""

import numpy as np
import pytest

from meshlap._dense import chol_solve, cholesky, sym_eigh


def _covariances(d, count, rng):
    # θ-weighted covariances as the frames see them: random spreads over twelve decades, a few
    # repeated eigenvalues (flat or isotropic neighbourhoods) and rank-deficient ones
    for t in range(count):
        if t % 7 == 0:
            yield np.diag(rng.uniform(size=d))
        elif t % 11 == 0:
            yield np.eye(d) * 2.0
        else:
            X = rng.normal(size=(1 + t % 5, d)) * rng.uniform(0, 3, d) * 10.0 ** rng.integers(-6, 6)
            yield X.T @ X


@pytest.mark.parametrize("d", [1, 2, 3])
def test_sym_eigh_matches_lapack(d):
    rng = np.random.default_rng(d)
    for C in _covariances(d, 400, rng):
        want = np.linalg.eigh(C)[0]
        w, V = np.empty(d), np.empty((d, d))
        sym_eigh(C.copy(), w, V)
        scale = max(np.abs(C).max(), 1e-300)
        assert np.all(np.diff(w) >= 0)  # ascending, as eigh
        assert np.abs(w - want).max() <= 1e-14 * scale
        assert np.abs(C @ V - V * w).max() <= 1e-14 * scale
        assert np.abs(V.T @ V - np.eye(d)).max() <= 1e-14


def test_cholesky_solves_and_reports_the_failing_pivot():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(8, 4))
    A = a.T @ a
    G, x = A.copy(), rng.normal(size=4)
    assert cholesky(G, 4, np.zeros(4)) == 4
    want = np.linalg.solve(A, x)
    chol_solve(G, x, 4)
    assert np.abs(x - want).max() <= 1e-12 * np.abs(want).max()
    A[3] = A[2]  # the fourth monomial repeats the third
    A[:, 3] = A[:, 2]
    assert cholesky(A, 4, 1e-11 * np.diag(A).copy()) == 3
