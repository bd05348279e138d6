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

import math
from dataclasses import dataclass
from itertools import combinations_with_replacement
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from .._dense import chol_solve, cholesky, sym_eigh
from .._jit import in_blocks, jit
from ..errors import MeshError
from ..geometry import check_points

__all__ = ["RowFit", "knn_pattern", "mean_curvature", "mean_curvature_normal", "monomials",
           "pointwise_rows"]

#: Highest polynomial degree of a row (the probes of the error model look two degrees higher).
MAX_DEGREE = 6
# A Cholesky pivot below this fraction of its diagonal means the monomial adds nothing new.
_PIVOT_TOL = 1e-11


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


@jit()
def _frame(P, w, nbr, th, normal, use_normal, B, C, ev, vec, v):  # pragma: no cover - compiled
    # B: orthonormal rows, the first k tangent, the rest normal; C, vec (d × d), ev, v (d) scratch
    d = P.shape[1]
    if use_normal:
        # a hypersurface: the given normal, tangents by Gram–Schmidt of the coordinate axes
        for a in range(d):
            B[d - 1, a] = normal[a]
        row = 0
        for e in range(d):
            if row == d - 1:
                break
            for a in range(d):
                v[a] = 1.0 if a == e else 0.0
            for r in range(row):
                dot = 0.0
                for a in range(d):
                    dot += v[a] * B[r, a]
                for a in range(d):
                    v[a] -= dot * B[r, a]
            dot = 0.0
            for a in range(d):
                dot += v[a] * normal[a]
            for a in range(d):
                v[a] -= dot * normal[a]
            nv = 0.0
            for a in range(d):
                nv += v[a] * v[a]
            nv = math.sqrt(nv)
            if nv > 0.3:
                for a in range(d):
                    B[row, a] = v[a] / nv
                row += 1
        return
    tot = 0.0
    for j in range(len(nbr)):
        tot += th[j]
    mean = v
    for a in range(d):
        s = 0.0
        for j in range(len(nbr)):
            s += th[j] * P[nbr[j], a]
        mean[a] = s / tot
    for a in range(d):
        for b in range(d):
            C[a, b] = 0.0
    for j in range(len(nbr)):
        for a in range(d):
            xa = P[nbr[j], a] - mean[a]
            for b in range(a + 1):
                C[a, b] += th[j] * xa * (P[nbr[j], b] - mean[b])
    for a in range(d):
        for b in range(a):
            C[b, a] = C[a, b]
    sym_eigh(C, ev, vec)
    for r in range(d):
        for a in range(d):
            B[r, a] = vec[a, d - 1 - r]


@jit(fastmath=True)
def _gram(W, Phi, m, K, G):  # pragma: no cover - compiled
    # the lower triangle of G = W Phiᵀ over the first m monomials (W = θ-weighted Phi): sums
    # over contiguous rows, which the compiler vectorizes
    for al in range(m):
        for be in range(al + 1):
            s = 0.0
            for j in range(K):
                s += W[al, j] * Phi[be, j]
            G[al, be] = s


@jit()
def _rows(start, stop, P, centers, indptr, indices, hv, normals, use_normals, k, parent, var, count,
          degree, idx1, idx2, want_noise, out, used, resid, amp, bias, kap):  # pragma: no cover - compiled
    d = P.shape[1]
    nc = d - k
    # the frame's and the metric's scratch, once per block
    B = np.empty((d, d))
    C = np.empty((d, d))
    vec = np.empty((d, d))
    ev = np.empty(d)
    v = np.empty(d)
    Gi = np.empty((k, k))
    Lk = np.empty((k, k))
    kfloor = np.zeros(k)
    kcol = np.empty(k)
    for r in range(start, stop):
        w = centers[r]
        a0 = indptr[r]
        K = indptr[r + 1] - a0
        nbr = indices[a0:a0 + K]
        inv4h = 1.0 / (4.0 * hv[r])
        th = np.empty(K)
        th_sum = 0.0
        for j in range(K):
            s = 0.0
            for a in range(d):
                t = P[nbr[j], a] - P[w, a]
                s += t * t
            th[j] = math.exp(-s * inv4h)
            th_sum += th[j]
        _frame(P, w, nbr, th, normals[w if use_normals else 0], use_normals, B, C, ev, vec, v)
        U = np.empty((K, k))
        Z = np.empty((K, nc))
        rho2 = 0.0
        for j in range(K):
            s2 = 0.0
            for b in range(d):
                s = 0.0
                for a in range(d):
                    s += (P[nbr[j], a] - P[w, a]) * B[b, a]
                if b < k:
                    U[j, b] = s
                    s2 += s * s
                else:
                    Z[j, b - k] = s
            rho2 = max(rho2, s2)
        rho = math.sqrt(rho2) if rho2 > 0.0 else 1.0
        for j in range(K):
            for b in range(k):
                U[j, b] /= rho
        # Vandermonde with two more degrees, for the probes of the error model; stored by
        # monomial (rows contiguous over the neighbours, for the sums over them)
        top = min(degree + 2, len(count) - 1)
        mb = count[top]
        # np.empty and np.zeros of one and two dimensions only: each other allocation
        # (np.ones, a third dimension) is one more numba overload to compile
        Phi = np.empty((mb, K))
        for j in range(K):
            Phi[0, j] = 1.0
        for al in range(1, mb):
            pa, va = parent[al], var[al]
            for j in range(K):
                Phi[al, j] = Phi[pa, j] * U[j, va]
        m = count[degree]
        G = np.zeros((m, m))
        W = np.empty((m, K))
        for al in range(m):
            for j in range(K):
                W[al, j] = th[j] * Phi[al, j]
        _gram(W, Phi, m, K, G)
        floor = np.empty(m)  # a pivot must stay above this fraction of its diagonal entry
        for al in range(m):
            floor[al] = _PIVOT_TOL * G[al, al]
        good = cholesky(G, m, floor)
        q = degree
        while q >= 2 and count[q] > good:
            q -= 1
        if q < 2:
            used[r] = -1
            for j in range(K):
                out[a0 + j] = 0.0
            continue
        used[r] = q
        mq = count[q]
        # the graph z = g(u): its gradient a and Hessian gh at u = 0, in unscaled units
        ag = np.zeros((nc, k))
        gh = np.zeros((nc * k, k))  # ∂_ij g_c at row c·k + i
        res = 0.0
        coef = np.empty(mq)
        zr = np.empty(K)
        for c in range(nc):
            for al in range(mq):
                s = 0.0
                for j in range(K):
                    s += W[al, j] * Z[j, c]
                coef[al] = s
            chol_solve(G, coef, mq)
            for i in range(k):
                ag[c, i] = coef[idx1[i]] / rho
                for jj in range(k):
                    gh[c * k + i, jj] = coef[idx2[i, jj]] * (2.0 if i == jj else 1.0) / rho2
            for j in range(K):
                zr[j] = Z[j, c]
            for al in range(mq):
                ca = coef[al]
                for j in range(K):
                    zr[j] -= ca * Phi[al, j]
            for j in range(K):
                res += th[j] * zr[j] * zr[j]
        if not want_noise:
            resid[r] = math.sqrt(res / (max(nc, 1) * th_sum))
        # E[Σθr²] = σ² (Σθ − Σ θ_j² Φ_j G⁻¹ Φ_jᵀ): the degrees of freedom the fit leaves
        dof = 0.0
        if want_noise:
            # the leverages Φ_jᵀ G⁻¹ Φ_j by one forward substitution, the K columns innermost
            # (45% of a degree-6 row's cost one column at a time); per column the same operations
            X = np.empty((mq, K))
            lev = np.zeros(K)
            for i in range(mq):
                for j in range(K):
                    X[i, j] = Phi[i, j]
                for q2 in range(i):
                    for j in range(K):
                        X[i, j] -= G[i, q2] * X[q2, j]
                gi = G[i, i]
                for j in range(K):
                    X[i, j] /= gi
                    lev[j] += X[i, j] * X[i, j]
            for j in range(K):
                dof += th[j] - th[j] * th[j] * lev[j]
        if want_noise:
            resid[r] = math.sqrt(res / (nc * dof)) if nc > 0 and dof > 1e-3 * th_sum else (
                0.0 if nc == 0 else np.inf)
        ks = 0.0
        for c in range(nc):
            for i in range(k):
                for jj in range(k):
                    ks += gh[c * k + i, jj] * gh[c * k + i, jj]
        kap[r] = math.sqrt(ks / k)
        # the metric G = I + Σ_c ∇g_c ∇g_cᵀ, factored in place; Gi = G⁻¹ column by column
        # (G ≥ I is positive definite)
        for i in range(k):
            for jj in range(k):
                Lk[i, jj] = 1.0 if i == jj else 0.0
        for c in range(nc):
            for i in range(k):
                for jj in range(k):
                    Lk[i, jj] += ag[c, i] * ag[c, jj]
        cholesky(Lk, k, kfloor)
        for jj in range(k):
            for i in range(k):
                kcol[i] = 1.0 if i == jj else 0.0
            chol_solve(Lk, kcol, k)
            for i in range(k):
                Gi[i, jj] = kcol[i]
        # Γ contracted with G^{ij}: v_l = G^{lm} Σ_c ∂_m g_c (G^{ij} ∂_ij g_c)
        t = np.zeros(k)
        for c in range(nc):
            tr = 0.0
            for i in range(k):
                for jj in range(k):
                    tr += Gi[i, jj] * gh[c * k + i, jj]
            for i in range(k):
                t[i] += ag[c, i] * tr
        lam = np.zeros(mq)
        for i in range(k):
            for jj in range(k):
                lam[idx2[i, jj]] += Gi[i, jj] * (2.0 if i == jj else 1.0) / rho2
            vl = 0.0
            for mm in range(k):
                vl += Gi[i, mm] * t[mm]
            lam[idx1[i]] -= vl / rho
        chol_solve(G, lam, mq)
        s2 = 0.0
        acc = np.zeros(K)
        for al in range(mq):
            la = lam[al]
            for j in range(K):
                acc[j] += Phi[al, j] * la
        for j in range(K):
            s = acc[j] * th[j]
            out[a0 + j] = s
            s2 += s * s
        # the basis holds the constants, so the row sums to zero up to rounding: make it exact
        # on the centre's own entry (it is among the neighbours)
        tot_row = 0.0
        self_q = -1
        for j in range(K):
            tot_row += out[a0 + j]
            if nbr[j] == w:
                self_q = a0 + j
        if self_q >= 0:
            out[self_q] -= tot_row
        amp[r] = math.sqrt(s2)
        # probes: the row applied to the monomials of degree q + 1 and q + 2 (unscaled)
        for e in range(2):
            qq = q + 1 + e
            if qq > top:
                bias[r, e] = np.nan
                continue
            pacc = 0.0
            for al in range(count[qq - 1], count[qq]):
                s = 0.0
                for j in range(K):
                    s += out[a0 + j] * Phi[al, j]
                pacc += s * s
            bias[r, e] = math.sqrt(pacc) * rho ** qq


@dataclass
class RowFit:
    """Point-wise rows and what their fits found, one entry per centre.

    Attributes
    ----------
    matrix : scipy.sparse.csr_matrix
        (n, n); row w holds the weights of Δf(w) (empty for points not among the centres).
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

    matrix: sp.csr_matrix
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
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not 1 <= k <= d:
        raise MeshError(f"k must be an integer between 1 and the dimension {d}; got {k!r}")
    if isinstance(degree, bool) or not isinstance(degree, (int, np.integer)) or not 2 <= degree <= MAX_DEGREE:
        raise MeshError(f"degree must be an integer from 2 to {MAX_DEGREE}; got {degree!r}")
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
    P, N, use_normals = _check_inputs(P, k, degree, normals)
    n, d = P.shape
    indptr = np.ascontiguousarray(indptr, dtype=np.int64)
    indices = np.ascontiguousarray(indices, dtype=np.int64)
    rows = len(indptr) - 1
    centers = np.arange(n) if centers is None else np.ascontiguousarray(centers, dtype=np.int64)
    if len(centers) != rows or rows < 0 or indptr[0] != 0 or (np.diff(indptr) < 0).any() \
            or indptr[-1] != len(indices):
        raise MeshError("pointwise_rows: indptr must be a CSR row pointer with one row per centre")
    if len(indices) and (indices.min() < 0 or indices.max() >= n) or len(centers) and (
            centers.min() < 0 or centers.max() >= n):
        raise MeshError(f"pointwise_rows: indices and centers must lie in [0, {n})")
    hv = np.broadcast_to(np.asarray(h, dtype=np.float64), (rows,)).copy()
    if not (np.isfinite(hv).all() and (hv > 0).all()):
        raise MeshError("pointwise_rows: h must be finite and positive")
    exps, count = monomials(k, MAX_DEGREE + 2)
    idx1, idx2 = _derivative_slots(exps, k)
    out = np.zeros(len(indices))
    used = np.zeros(rows, dtype=np.int64)
    resid, amp, kap = np.zeros(rows), np.zeros(rows), np.zeros(rows)
    probes = np.full((rows, 2), np.nan)
    if rows:
        parent, var = _recursion(exps)
        in_blocks(_rows, rows, P, centers, indptr, indices, hv, N, use_normals, k, parent, var, count, degree,
                  idx1, idx2, bool(noise_dof), out, used, resid, amp, probes, kap)
    L = _rows_matrix(n, centers, indptr, indices, out)
    if not return_fit:
        return L
    return RowFit(L, centers, used, resid, amp, probes, kap, hv)


def _rows_matrix(n: int, centers: np.ndarray, indptr: np.ndarray, indices: np.ndarray,
                 data: np.ndarray) -> sp.csr_matrix:
    # the n × n matrix with the given rows at the centres, without a sort through COO
    order = np.argsort(centers, kind="stable")
    counts = np.zeros(n, dtype=np.int64)
    np.add.at(counts, centers, np.diff(indptr))
    full = np.zeros(n + 1, dtype=np.int64)
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
