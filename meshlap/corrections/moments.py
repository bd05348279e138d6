"""Point-wise rows: each row of the kernel operator made exact for quadratics.

The lumped masses are a one-point quadrature, and on irregular meshes and clouds its error
is larger than the kernel's bias once h is a few squared spacings; within a few √h of a
boundary the one-sided neighbourhood adds ∂f/∂n·e^{−d²/4h}/√(πh). :func:`moment_correction`
changes each row as little as possible (weighted least squares) so that it is exact for every
polynomial of degree ≤ 2 in the point's k-dimensional tangent space: zero first moments,
second moments 2·I. In coordinates of the tangent space, whose metric is the identity to
second order at the point, that is Δf = Σ_a f_{u_a u_a}; it removes both errors.

:func:`second_moment_scale` is the symmetric part of the same idea: one global factor that
brings the mean second moment to 2k, which keeps S = M L symmetric.

The corrected rows are not symmetric, so they are what ``op @ f`` applies (``op.L``), while
spectra and heat flow use the symmetric pencil (``op.S``, ``op.M``).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from .._dense import chol_solve, cholesky, sym_eigh
from .._jit import in_blocks, jit
from ..assembly._intrinsics import zero_row_sum

__all__ = ["moment_block", "moment_correction", "second_moment_scale"]


@jit()
def _moment_rows(start, stop, indptr, indices, data, P, k, out, failed):  # pragma: no cover - compiled
    d = P.shape[1]
    m = k + k * (k + 1) // 2  # linear and quadratic monomials in k tangent coordinates
    C = np.empty((d, d))
    vec = np.empty((d, d))
    ev = np.empty(d)
    for w in range(start, stop):
        a, b = indptr[w], indptr[w + 1]
        for q in range(a, b):
            out[q] = data[q]
        # tangent space from the |weight|-weighted covariance of the neighbourhood
        for i in range(d):
            for j in range(d):
                C[i, j] = 0.0
        tot = 0.0
        for q in range(a, b):
            p = indices[q]
            if p == w:
                continue
            c = abs(data[q])
            tot += c
            for i in range(d):
                di = P[p, i] - P[w, i]
                for j in range(d):
                    C[i, j] += c * di * (P[p, j] - P[w, j])
        if tot == 0.0:
            continue
        sigma2 = 0.0
        for i in range(d):
            sigma2 += C[i, i]
        sigma2 /= tot
        if sigma2 <= 0.0:
            continue
        sym_eigh(C, ev, vec)
        inv = 1.0 / math.sqrt(sigma2)
        # target moments: 0 for u_a and u_a u_b (a ≠ b), 2/σ² for u_a² (units of σ)
        G = np.zeros((m, m))
        r = np.zeros(m)
        floor = np.zeros(m)  # any positive pivot will do
        phi = np.empty(m)
        u = np.empty(k)
        pos = k
        for i in range(k):
            for j in range(i, k):
                if i == j:
                    r[pos] = 2.0 / sigma2
                pos += 1
        for q in range(a, b):
            p = indices[q]
            if p == w:
                continue
            _monomials(P, p, w, vec, k, inv, u, phi)
            c = abs(data[q])
            for i in range(m):
                r[i] -= data[q] * phi[i]
                for j in range(i + 1):
                    G[i, j] += c * phi[i] * phi[j]
        if cholesky(G, m, floor) < m:  # not positive definite: the row stays as it was
            failed[w] = 1
            continue
        chol_solve(G, r, m)
        for q in range(a, b):
            p = indices[q]
            if p == w:
                continue
            _monomials(P, p, w, vec, k, inv, u, phi)
            corr = 0.0
            for i in range(m):
                corr += r[i] * phi[i]
            out[q] = data[q] + abs(data[q]) * corr
        zero_row_sum(w, indptr, indices, out)


@jit(inline="always")
def _monomials(P, p, w, vec, k, inv, u, phi):  # pragma: no cover - compiled
    # tangent coordinates of p − w (the k leading axes of vec), scaled by inv, then their
    # pairwise products u_a u_b, a ≤ b
    d = P.shape[1]
    for a in range(k):
        s = 0.0
        col = d - 1 - a
        for i in range(d):
            s += (P[p, i] - P[w, i]) * vec[i, col]
        u[a] = s * inv
        phi[a] = u[a]
    pos = k
    for a in range(k):
        for b in range(a, k):
            phi[pos] = u[a] * u[b]
            pos += 1


def moment_correction(L: sp.csr_matrix, P: np.ndarray, dim: int = 2) -> tuple[sp.csr_matrix, np.ndarray]:
    """Rows of ``L`` made exact for quadratics in each point's k-dimensional tangent space.

    Each off-diagonal weight a_p of row w becomes a_p + |a_p| φ_pᵀλ_w with φ the tangent
    coordinates u of p − w and their products u_a u_b (tangent space from the |a|-weighted
    covariance of the row's neighbours) and λ_w the smallest change, in the |a|-weighted
    norm, that gives zero first moments and second moments 2·I; the diagonal keeps each row
    summing to zero. Rows whose neighbours do not span a k-space are left unchanged and
    flagged.

    Parameters
    ----------
    L : scipy.sparse.csr_matrix
        A Laplacian with the diagonal stored in every row that has neighbours.
    P : (n, d) ndarray
        Positions.
    dim : int, default 2
        Intrinsic dimension k.

    Returns
    -------
    L_corrected : scipy.sparse.csr_matrix
        Same sparsity pattern (the index arrays are shared).
    unchanged : (n,) bool ndarray
        Rows that could not be corrected.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.plane(800, seed=0)
    >>> op = meshlap.laplacian(V, F, h=0.002, correction="none")
    >>> Lc, bad = moment_correction(op.L, V)
    >>> bool(np.allclose(Lc @ (V[:, 0] ** 2 + V[:, 1]), 2.0)), int(bad.sum())
    (True, 0)
    """
    L = sp.csr_matrix(L)
    out = np.empty_like(L.data)
    failed = np.zeros(L.shape[0], dtype=np.int8)
    in_blocks(_moment_rows, L.shape[0], L.indptr, L.indices, L.data,
              np.ascontiguousarray(P, dtype=np.float64), int(dim), out, failed)
    # same pattern: share the index arrays (neither matrix is changed in place afterwards)
    Lc = sp.csr_matrix(L.shape, dtype=L.dtype)
    Lc.data, Lc.indices, Lc.indptr = out, L.indices, L.indptr
    Lc.has_sorted_indices = L.has_sorted_indices
    return Lc, failed.astype(bool)


def moment_block(V: np.ndarray) -> np.ndarray:
    """The block (|x|², x) whose product with L gives the rows' second moments
    (:func:`second_moment_scale`); the build multiplies it while L's rows are filled
    (:func:`meshlap.assembly.assemble`, ``times``).

    Examples
    --------
    >>> moment_block(np.array([[1.0, 2.0]])).tolist()
    [[5.0, 1.0, 2.0]]
    """
    return np.column_stack([(V**2).sum(axis=1), V])


def second_moment_scale(apply, V: np.ndarray, mass: np.ndarray, exclude: np.ndarray | None,
                        dim: int = 2, product: np.ndarray | None = None) -> float:
    """The factor that brings the mass-weighted mean of the rows' second moments
    μ_w = L(|x − w|²)(w) = L|x|² − 2 w·Lx (L annihilates constants) to 2k, its value for Δ on
    a k-manifold (4 on a surface). ``apply`` applies L to an (n, d + 1) block
    (:func:`moment_block`); ``product``, that block's product when the build already has it
    (None: ``apply`` is called).

    The lumped-mass quadrature underestimates μ systematically when h is a few squared edge
    lengths (by 0.1-4% on the meshes of docs/accuracy.md), which lowers every eigenvalue by
    that fraction; one global factor removes this part and keeps S symmetric and −S
    semidefinite. Rows in ``exclude`` (the boundary band, where μ is one-sided) do not count.

    Examples
    --------
    >>> import meshlap
    >>> op = meshlap.laplacian(*meshlap.shapes.sphere(800, seed=0), correction="none", h=0.02)
    >>> s = second_moment_scale(lambda X: op.L @ X, op.V, op.mass, None)
    >>> s == second_moment_scale(None, op.V, op.mass, None, product=op.L @ moment_block(op.V))
    True
    """
    Y = apply(moment_block(V)) if product is None else product
    mu = Y[:, 0] - 2.0 * (V * Y[:, 1:]).sum(axis=1)
    use = mass > 0
    if exclude is not None:
        use[exclude] = False
    if not use.any():
        return 1.0
    mean = float((mu[use] * mass[use]).sum() / mass[use].sum())
    return 2.0 * dim / mean if mean > 0 else 1.0
