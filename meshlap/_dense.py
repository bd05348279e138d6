"""Small dense linear algebra for the compiled kernels: Cholesky and a symmetric eigensolver.

The matrices are tiny (a frame's d × d covariance, d ≤ 3; a metric's k × k; a fit's Gram
matrix of a few dozen monomials) and live inside per-row loops. numba's ``np.linalg``
bindings go through LAPACK with finiteness checks and error handling that are compiled into
every kernel that uses them (``eigh`` and its helpers 1.5 s, ``inv`` 0.4 s of CPU in the
first build of :mod:`meshlap.corrections.highorder` on a busy machine) and allocate on every
call; these loops write into the caller's arrays.
"""

from __future__ import annotations

import math

from ._jit import jit

__all__ = ["chol_solve", "cholesky", "sym_eigh"]

# Jacobi sweeps end when the off-diagonal part is below this fraction of the matrix (squared
# Frobenius norms): then each eigenvalue is within rounding of the LAPACK one.
_OFF_TOL = 1e-32
_MAX_SWEEPS = 60
# Every divisor below is nonzero by construction (a pivot above its floor, a rotation of a
# nonzero entry): error_model="numpy" leaves out numba's ZeroDivisionError test before each
# division (the same numbers, less CPU: meshlap.corrections._fit_kernel)


@jit(error_model="numpy")
def cholesky(G, m, floor):  # pragma: no cover - compiled
    # in-place lower Cholesky of G[:m, :m]; returns the first column whose pivot is not
    # above floor[j] (m when all are). Each entry's sum runs over q in order, as in the plain
    # left-looking loops; four rows of a column are summed side by side (independent chains
    # of additions, where one at a time waits on each: 15% less CPU at m = 28), and scaled by
    # the pivot's reciprocal (a division each costs as much: 6% of a degree-6 fit)
    for j in range(m):
        s = G[j, j]
        for q in range(j):
            s -= G[j, q] * G[j, q]
        if not s > floor[j]:
            return j
        piv = math.sqrt(s)
        G[j, j] = piv
        inv = 1.0 / piv
        i = j + 1
        while i + 3 < m:
            s0, s1, s2, s3 = G[i, j], G[i + 1, j], G[i + 2, j], G[i + 3, j]
            for q in range(j):
                g = G[j, q]
                s0 -= G[i, q] * g
                s1 -= G[i + 1, q] * g
                s2 -= G[i + 2, q] * g
                s3 -= G[i + 3, q] * g
            G[i, j], G[i + 1, j], G[i + 2, j], G[i + 3, j] = s0 * inv, s1 * inv, s2 * inv, s3 * inv
            i += 4
        for r in range(i, m):
            s = G[r, j]
            for q in range(j):
                s -= G[r, q] * G[j, q]
            G[r, j] = s * inv
    return m


@jit(error_model="numpy")
def chol_solve(Lc, x, m):  # pragma: no cover - compiled
    # x <- (Lc Lcᵀ)⁻¹ x with the factor of cholesky. The forward sweep takes two rows at a time,
    # each summed in the order of one at a time (the second's last term waits on the first)
    i = 0
    while i + 1 < m:
        s0, s1 = x[i], x[i + 1]
        for q in range(i):
            s0 -= Lc[i, q] * x[q]
            s1 -= Lc[i + 1, q] * x[q]
        x[i] = s0 / Lc[i, i]
        s1 -= Lc[i + 1, i] * x[i]
        x[i + 1] = s1 / Lc[i + 1, i + 1]
        i += 2
    if i < m:
        s = x[i]
        for q in range(i):
            s -= Lc[i, q] * x[q]
        x[i] = s / Lc[i, i]
    for i in range(m - 1, -1, -1):
        s = x[i]
        for q in range(i + 1, m):
            s -= Lc[q, i] * x[q]
        x[i] = s / Lc[i, i]


@jit(error_model="numpy")
def sym_eigh(C, w, V):  # pragma: no cover - compiled
    # eigenvalues of the symmetric C into w, ascending, and the orthonormal eigenvectors into
    # the columns of V, as np.linalg.eigh orders them; cyclic Jacobi rotations, C is overwritten
    d = C.shape[0]
    for i in range(d):
        for j in range(d):
            V[i, j] = 1.0 if i == j else 0.0
    for _ in range(_MAX_SWEEPS):
        off = 0.0
        total = 0.0
        for i in range(d):
            total += C[i, i] * C[i, i]
            for j in range(i + 1, d):
                off += C[i, j] * C[i, j]
        if not off > _OFF_TOL * (total + 2.0 * off):
            break
        for p in range(d - 1):
            for q in range(p + 1, d):
                apq = C[p, q]
                if apq == 0.0:
                    continue
                # the rotation (c, s) that zeroes C[p, q], the smaller of the two angles
                theta = (C[q, q] - C[p, p]) / (2.0 * apq)
                t = 1.0 / (abs(theta) + math.sqrt(theta * theta + 1.0))
                if theta < 0.0:
                    t = -t
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                for k in range(d):
                    akp, akq = C[k, p], C[k, q]
                    C[k, p] = c * akp - s * akq
                    C[k, q] = s * akp + c * akq
                for k in range(d):
                    apk, aqk = C[p, k], C[q, k]
                    C[p, k] = c * apk - s * aqk
                    C[q, k] = s * apk + c * aqk
                for k in range(d):
                    vkp, vkq = V[k, p], V[k, q]
                    V[k, p] = c * vkp - s * vkq
                    V[k, q] = s * vkp + c * vkq
    for i in range(d):
        w[i] = C[i, i]
    for i in range(1, d):  # insertion sort, the columns of V alongside
        j = i
        while j > 0 and w[j - 1] > w[j]:
            w[j - 1], w[j] = w[j], w[j - 1]
            for k in range(d):
                V[k, j - 1], V[k, j] = V[k, j], V[k, j - 1]
            j -= 1
