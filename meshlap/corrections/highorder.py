"""Point-wise Laplacian rows of high order: weighted least squares in local coordinates.

For each centre w and a neighbourhood N(w) (a CSR pattern), the row is the linear functional
that maps the samples f(p), p ∈ N(w), to Δ_M f(w) of the polynomial of degree ≤ p that fits
them best in the Gaussian-weighted least-squares sense, weights θ_p = exp(−|p − w|²/4h)
(the heat kernel of Belkin, Sun and Wang). This is generalized moving least squares (GMLS)
with the heat kernel as its weight:

1. a frame at w: k tangent directions and d − k normal ones, from the given unit normals
   (hypersurfaces) or from the θ-weighted principal axes of N(w);
2. local coordinates u (tangent) and z (normal) of every p − w;
3. the manifold as a graph z = g(u) of degree ≤ p, fitted by the same weighted least squares
   (one Gram matrix for the surface and the function);
4. the Laplace–Beltrami operator of the graph metric G = I + Σ_c ∇g_c ∇g_cᵀ at u = 0,

       Δ_M f = G^{ij} (f_ij − Γ^l_ij f_l),   Γ^l_ij = G^{lm} Σ_c ∂_m g_c ∂_ij g_c,

   exact also when the frame is tilted (∇g(0) ≠ 0); with ∇g(0) = 0 it is f_uu + f_vv;
5. the row: with Φ the weighted Vandermonde matrix and λ the coefficients of step 4 on the
   monomials of degree ≤ 2, row_p = θ_p Φ_p (ΦᵀΘΦ)⁻¹ λ. It annihilates constants and is exact
   for every polynomial of degree ≤ p in u, on the fitted manifold.

Monomials are scaled by the stencil radius and the Gram matrix is factored by Cholesky; where
a pivot falls below 1e-11 of its diagonal (too few or degenerate neighbours) the row drops to
the highest degree whose leading block is well conditioned, and the fit reports it. The
degree-2 case on a flat frame is the moment correction of :mod:`meshlap.correction`.
Curves (k = 1), surfaces (k = 2) and volumes (k = d, no height function) share the code.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from itertools import combinations_with_replacement
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from .._jit import in_blocks
from ..errors import MeshError
from ..geometry import check_points
from ..geometry.validation import check_int
from ._fit_kernel import _rows, gather_columns

__all__ = ["RowFit", "fewest_points", "fit_rows", "knn_pattern", "mean_curvature", "mean_curvature_normal",
           "monomials", "pointwise_rows"]

#: Highest polynomial degree of a row (the probes of the error model look two degrees higher).
MAX_DEGREE = 6


def fewest_points(k: int) -> int:
    """The fewest points :func:`meshlap.corrections.rowchoice.choose_rows` fits rows on in
    dimension k: a quadratic's (k + 1)(k + 2)/2 coefficients, and two more to measure the fit's
    residual.

    Examples
    --------
    >>> fewest_points(2)
    8
    """
    return (k + 1) * (k + 2) // 2 + 2


def monomials(k: int, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Exponents of the monomials in k variables of degree ≤ ``degree``, by total degree.

    Returns ``(exps, count)``: exps (m, k) and count[q] = number of monomials of degree ≤ q,
    so the first count[q] rows are the basis of degree q.

    Examples
    --------
    >>> e, c = monomials(2, 2)
    >>> e.tolist(), c.tolist()
    ([[0, 0], [1, 0], [0, 1], [2, 0], [1, 1], [0, 2]], [1, 3, 6])
    """
    rows, count = [], []
    for q in range(degree + 1):
        for combo in combinations_with_replacement(range(k), q):
            e = [0] * k
            for i in combo:
                e[i] += 1
            rows.append(e)
        count.append(len(rows))
    return np.array(rows, dtype=np.int64).reshape(-1, k), np.array(count, dtype=np.int64)


def _derivative_slots(exps: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    # slot of u_i and of u_i u_j in the monomial table
    where = {tuple(e): a for a, e in enumerate(exps.tolist())}
    eye = np.eye(k, dtype=np.int64)
    idx1 = np.array([where[tuple(eye[i])] for i in range(k)], dtype=np.int64)
    idx2 = np.array([[where[tuple(eye[i] + eye[j])] for j in range(k)] for i in range(k)], dtype=np.int64)
    return idx1, idx2


def _recursion(exps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    # monomial a = monomial parent[a] times u_var[a], so the Vandermonde fills by products
    where = {tuple(e): a for a, e in enumerate(exps.tolist())}
    parent = np.zeros(len(exps), dtype=np.int64)
    var = np.zeros(len(exps), dtype=np.int64)
    for a, e in enumerate(exps.tolist()[1:], start=1):
        i = next(i for i, x in enumerate(e) if x > 0)
        e[i] -= 1
        parent[a], var[a] = where[tuple(e)], i
    return parent, var


@functools.cache
def _tables(k: int) -> tuple[np.ndarray, ...]:
    # what the compiled fit reads of the monomials in k variables, once per k: their counts by
    # degree up to twice the highest (the Gram matrix's moments; they hold the probes' two more
    # degrees), the Vandermonde's recursion, the slots of the first and second derivatives, and
    # pair[a, b], the monomial Φ_a Φ_b, for a, b of degree ≤ MAX_DEGREE
    exps, count = monomials(k, 2 * MAX_DEGREE)
    where = {tuple(e): a for a, e in enumerate(exps.tolist())}
    m = int(count[MAX_DEGREE])
    pair = np.array([[where[tuple(exps[a] + exps[b])] for b in range(m)] for a in range(m)], dtype=np.int64)
    return (count, *_recursion(exps), *_derivative_slots(exps, k), pair)


@dataclass
class RowFit:
    """Point-wise rows and what their fits found, one entry per centre.

    Attributes
    ----------
    matrix : scipy.sparse.csr_matrix or None
        (n, n); row w holds the weights of Δf(w) (empty for points not among the centres);
        None where the rows were measured but not kept (``fit_rows(keep_rows=False)``).
    centers : (r,) int ndarray
        The rows that were fitted.
    degree : (r,) int ndarray
        Polynomial degree used (lower than asked where the neighbours did not support it;
        −1 where not even degree 2 was possible, the row is then zero).
    residual : (r,) ndarray
        Noise level of the normal residual of the height fit: √(Σθr² / dof), dof = Σθ minus
        the θ-weighted leverage of the fit (0 when k = d, inf with no degrees left).
    amplification : (r,) ndarray
        ‖row‖₂: the factor by which independent noise in f reaches Δf.
    probes : (r, 2) ndarray
        ‖row applied to the monomials of degree q + 1 and q + 2‖, q the degree used.
    curvature : (r,) ndarray
        √(Σ_c ‖∇²g_c‖²_F / k) at the centre (1 on the unit sphere).
    h : (r,) ndarray
        Widths of the Gaussian weights.
    """

    matrix: sp.csr_matrix | None
    centers: np.ndarray
    degree: np.ndarray
    residual: np.ndarray
    amplification: np.ndarray
    probes: np.ndarray
    curvature: np.ndarray
    h: np.ndarray


def knn_pattern(P: Any, K: int, centers: Any = None, tree: cKDTree | None = None
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The K nearest points of every centre (itself first) as a CSR pattern.

    Returns ``(indptr, indices, dist)`` with dist the distances, ascending within a row.

    Examples
    --------
    >>> import numpy as np
    >>> indptr, indices, dist = knn_pattern(np.eye(3), 2)
    >>> indptr.tolist(), indices[:2].tolist()
    ([0, 2, 4, 6], [0, 1])
    """
    P = check_points(P, "P")
    n = len(P)
    if not 1 <= K <= n:
        raise MeshError(f"knn_pattern: K must be between 1 and the number of points ({n}); got {K}")
    centers = np.arange(n) if centers is None else np.asarray(centers, dtype=np.int64)
    tree = cKDTree(P) if tree is None else tree
    # scipy's tree, in parallel: its queries stay fast for the hundreds of neighbours of
    # the wide rows
    dist, idx = tree.query(P[centers], k=K, workers=-1)
    dist = np.asarray(dist, dtype=np.float64).reshape(len(centers), K)
    idx = np.asarray(idx, dtype=np.int64).reshape(len(centers), K)
    indptr = np.arange(len(centers) + 1, dtype=np.int64) * K
    return indptr, idx.ravel(), dist.ravel()


def _check_inputs(P: Any, k: int, degree: int, normals: Any) -> tuple[np.ndarray, np.ndarray, bool]:
    P = np.ascontiguousarray(check_points(P, "P"), dtype=np.float64)
    d = P.shape[1]
    check_int(k, "k", 1, d)
    check_int(degree, "degree", 2, MAX_DEGREE)
    if normals is None:
        return P, np.zeros((1, d)), False
    if k != d - 1:
        raise MeshError(f"normals define a frame only for hypersurfaces (k = d - 1 = {d - 1}); got k = {k}")
    N = np.asarray(normals, dtype=np.float64)
    if N.shape != P.shape or not np.isfinite(N).all():
        raise MeshError(f"normals must be a finite array of shape {P.shape}; got {N.shape}")
    norm = np.linalg.norm(N, axis=1)
    if not (norm > 0).all():
        raise MeshError(f"normals: {int((norm == 0).sum())} are zero; pass normals=None to use PCA frames")
    return P, np.ascontiguousarray(N / norm[:, None]), True


def pointwise_rows(P: Any, indptr: Any, indices: Any, h: Any, degree: int = 4, *, k: int = 2,
                   normals: Any = None, centers: Any = None, return_fit: bool = False,
                   noise_dof: bool = True) -> sp.csr_matrix | RowFit:
    """Rows that give Δ_M f exactly for polynomials of degree ≤ ``degree`` on the fitted manifold.

    Parameters
    ----------
    P : (n, d) array_like
        Positions.
    indptr, indices : array_like
        CSR pattern: row r's neighbours are ``indices[indptr[r]:indptr[r + 1]]`` (the centre
        itself among them). Row r belongs to point ``centers[r]``.
    h : float or (r,) array_like
        Width of the Gaussian weights exp(−d²/4h), per row or one for all.
    degree : int
        Polynomial degree p, 2 to 6 (each row needs at least as many well spread
        neighbours as there are monomials: 6, 10, 15 for p = 2, 3, 4 on a surface).
    k : int
        Intrinsic dimension (1 curve, 2 surface, d volume).
    normals : (n, d) array_like, optional
        Unit normals of a hypersurface (k = d − 1) for the frames; default: principal axes
        of each θ-weighted neighbourhood.
    centers : (r,) array_like of int, optional
        The points the rows belong to; default all, in order.
    return_fit : bool
        Return a :class:`RowFit` (with per-row diagnostics) instead of the matrix.
    noise_dof : bool
        Correct the residual for the fit's degrees of freedom (an unbiased noise level; costs
        a little more); otherwise ``residual`` is the plain θ-weighted RMS.

    Returns
    -------
    scipy.sparse.csr_matrix or RowFit

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> P = np.column_stack([rng.uniform(-1, 1, (400, 2)), np.zeros(400)])
    >>> indptr, indices, dist = knn_pattern(P, 30)
    >>> L = pointwise_rows(P, indptr, indices, h=0.02, degree=4)
    >>> f = P[:, 0] ** 4 + P[:, 0] * P[:, 1] ** 2        # Δf = 12x² + 2x
    >>> bool(np.allclose(L @ f, 12 * P[:, 0] ** 2 + 2 * P[:, 0]))
    True
    """
    fit = fit_rows(P, indptr, indices, h, (degree,), k=k, normals=normals, centers=centers,
                   noise_dof=noise_dof)[0]
    return fit if return_fit else fit.matrix


def fit_rows(P: Any, indptr: Any, indices: Any, h: Any, degrees: tuple[int, ...], *, k: int = 2,
             normals: Any = None, centers: Any = None, noise_dof: bool = True, order: Any = None,
             starts: Any = None, keep_rows: bool = True) -> list[RowFit]:
    """:func:`pointwise_rows` of several degrees on the same stencils, one :class:`RowFit` each,
    for little more than the highest alone: the frames, weights and Gram matrices are shared.

    ``order`` lists the rows to compute, in the order they are computed (default: all, in
    order; the rows do not depend on it). Rows whose neighbours lie near each other in memory,
    one after another, are faster on large inputs (16% on 100,000 points at degree 6, a k-d
    tree's order). Rows left out are left empty (zero weights and figures), for a caller that
    has them from another fit.

    ``starts``, where each row's neighbours begin in ``indices`` (default ``indptr[:-1]``: a CSR
    pattern), reads the rows from a wider table of neighbours, ``indices`` its rows flattened,
    without a copy of it; ``indptr`` then places the rows' entries, and the matrices hold the
    columns gathered (32-bit where they fit).

    ``keep_rows=False`` measures the rows without keeping them (``matrix`` is then None): a
    candidate that is seldom chosen writes none of its weights (at 400,000 points and 64
    neighbours 205 MB), and the rows that are chosen are fitted again, the same numbers.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> P = meshlap.shapes.fibonacci_sphere(1000)
    >>> indptr, indices, _ = knn_pattern(P, 30)
    >>> four, two = fit_rows(P, indptr, indices, 0.002, (4, 2))
    >>> alone = pointwise_rows(P, indptr, indices, 0.002, 2)
    >>> bool(np.array_equal(two.matrix.data, alone.data)), int(four.degree.min())
    (True, 4)
    """
    if isinstance(degrees, (int, np.integer)) or not len(degrees):
        raise MeshError(f"degrees must be a sequence of degrees; got {degrees!r}")
    for degree in degrees:
        P, N, use_normals = _check_inputs(P, k, degree, normals)
    n, d = P.shape
    indptr = np.ascontiguousarray(indptr, dtype=np.int64)
    # 32-bit neighbours where they fit: one compiled fit for the tables of Nearest and the
    # patterns of callers
    indices = np.ascontiguousarray(indices, dtype=np.int32 if n < 2**31 - 1 else np.int64)
    rows = len(indptr) - 1
    centers = np.arange(n) if centers is None else np.ascontiguousarray(centers, dtype=np.int64)
    if len(centers) != rows or rows < 0 or indptr[0] != 0 or (np.diff(indptr) < 0).any() \
            or (starts is None and indptr[-1] != len(indices)):
        raise MeshError("pointwise_rows: indptr must be a CSR row pointer with one row per centre")
    if starts is not None:
        starts = np.ascontiguousarray(starts, dtype=np.int64)
        ends = starts + np.diff(indptr)
        if starts.shape != (rows,) or rows and (starts.min() < 0 or ends.max() > len(indices)):
            raise MeshError(f"fit_rows: starts must place {rows} rows inside indices")
    if len(indices) and (indices.min() < 0 or indices.max() >= n) or len(centers) and (
            centers.min() < 0 or centers.max() >= n):
        raise MeshError(f"pointwise_rows: indices and centers must lie in [0, {n})")
    hv = np.broadcast_to(np.asarray(h, dtype=np.float64), (rows,)).copy()
    if not (np.isfinite(hv).all() and (hv > 0).all()):
        raise MeshError("pointwise_rows: h must be finite and positive")
    count, parent, var, idx1, idx2, pair = _tables(k)
    T = len(degrees)
    out = np.zeros((T, int(indptr[-1]) if keep_rows else 0))
    used = np.zeros((T, rows), dtype=np.int64)
    resid, amp, kap = np.zeros((T, rows)), np.zeros((T, rows)), np.zeros((T, rows))
    probes = np.full((rows, 2 * T), np.nan)
    if rows:
        targets = np.asarray(degrees, dtype=np.int64)
        order = np.arange(rows) if order is None else np.asarray(order, dtype=np.int64)
        if order.ndim != 1 or len(order) and (order.min() < 0 or order.max() >= rows
                                              or np.bincount(order, minlength=rows).max() > 1):
            raise MeshError(f"fit_rows: order must list each of the {rows} rows at most once")
        first = indptr[:-1] if starts is None else starts
        in_blocks(_rows, len(order), order, P, centers, indptr, first, indices, hv, N, use_normals, k, parent,
                  var, count, pair, targets, idx1, idx2, bool(noise_dof), bool(keep_rows), out, used, resid,
                  amp, probes, kap)
    # the matrices' columns: 32-bit where their row pointers fit too (scipy wants both alike)
    total = int(indptr[-1])
    index = np.int32 if max(n, total) < 2**31 - 1 else np.int64
    cols = indices.astype(index, copy=False)
    if starts is not None and keep_rows:
        cols = np.empty(total, dtype=index)
        gather_columns(indices, starts, indptr, cols)
    return [RowFit(_rows_matrix(n, centers, indptr, cols, out[t]) if keep_rows else None, centers, used[t],
                   resid[t], amp[t], probes[:, 2 * t:2 * t + 2], kap[t], hv) for t in range(T)]


def _rows_matrix(n: int, centers: np.ndarray, indptr: np.ndarray, indices: np.ndarray,
                 data: np.ndarray) -> sp.csr_matrix:
    # the n × n matrix with the given rows at the centres, without a sort through COO
    order = np.argsort(centers, kind="stable")
    counts = np.zeros(n, dtype=np.int64)
    np.add.at(counts, centers, np.diff(indptr))
    full = np.zeros(n + 1, dtype=indices.dtype)  # (scipy's kernels want both of one type)
    np.cumsum(counts, out=full[1:])
    if (np.diff(centers) > 0).all():
        idx, dat = indices, data
    else:
        take = np.concatenate([np.arange(indptr[r], indptr[r + 1]) for r in order]) if len(order) else \
            np.zeros(0, dtype=np.int64)
        idx, dat = indices[take], data[take]
    # no sort: rows keep their neighbours' order (a repeated neighbour still sums in L @ f);
    # the arrays are consistent by construction, so scipy need not check or copy them
    L = sp.csr_matrix((n, n))
    L.data, L.indices, L.indptr = dat, idx, full
    return L


def mean_curvature_normal(L: Any, P: Any) -> np.ndarray:
    """The mean curvature normal H·n = −½ L X from point-wise rows, (n, d).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> P = meshlap.shapes.fibonacci_sphere(2000)
    >>> L = pointwise_rows(P, *knn_pattern(P, 36)[:2], h=0.002)
    >>> bool(np.abs(mean_curvature_normal(L, P) - P).max() < 1e-3)
    True
    """
    P = check_points(P, "P")
    if L.shape != (len(P), len(P)):
        raise MeshError(f"L is {L.shape} but there are {len(P)} points")
    return -0.5 * np.asarray(L @ P)


def mean_curvature(L: Any, P: Any, normals: Any = None) -> np.ndarray:
    """Mean curvature H from ΔX = −2H n; signed by ``normals`` (H > 0 on a sphere with outward
    normals), else |H|.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> P = 2 * meshlap.shapes.fibonacci_sphere(2000)
    >>> L = pointwise_rows(P, *knn_pattern(P, 36)[:2], h=0.008)
    >>> bool(np.abs(mean_curvature(L, P, normals=P) - 0.5).max() < 1e-3)
    True
    """
    Hn = mean_curvature_normal(L, P)
    H = np.linalg.norm(Hn, axis=1)
    if normals is None:
        return H
    N = np.asarray(normals, dtype=np.float64)
    if N.shape != Hn.shape:
        raise MeshError(f"normals must have shape {Hn.shape}; got {N.shape}")
    sign = np.sign((Hn * N).sum(axis=1))
    sign[sign == 0] = 1.0
    return sign * H
