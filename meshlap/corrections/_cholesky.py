"""The small dense Cholesky factorization and solve that the point-wise rows share."""

from __future__ import annotations

import math

from .._jit import jit

__all__ = ["chol_solve", "cholesky"]


@jit()
def cholesky(G, m, floor):  # pragma: no cover - compiled
    # in-place lower Cholesky of G[:m, :m]; returns the first column whose pivot is not
    # above floor[j] (m when all are)
    for j in range(m):
        s = G[j, j]
        for q in range(j):
            s -= G[j, q] * G[j, q]
        if not s > floor[j]:
            return j
        G[j, j] = math.sqrt(s)
        for i in range(j + 1, m):
            s = G[i, j]
            for q in range(j):
                s -= G[i, q] * G[j, q]
            G[i, j] = s / G[j, j]
    return m


@jit()
def chol_solve(Lc, x, m):  # pragma: no cover - compiled
    # x <- (Lc Lcᵀ)⁻¹ x with the factor of cholesky
    for i in range(m):
        s = x[i]
        for q in range(i):
            s -= Lc[i, q] * x[q]
        x[i] = s / Lc[i, i]
    for i in range(m - 1, -1, -1):
        s = x[i]
        for q in range(i + 1, m):
            s -= Lc[q, i] * x[q]
        x[i] = s / Lc[i, i]
