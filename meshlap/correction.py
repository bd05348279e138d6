"""Accuracy corrections of the heat-kernel Laplacian: bias, discretization and boundary.

Three errors separate the operator of Belkin, Sun and Wang (SoCG 2008, eq. 1) from the
Laplace–Beltrami operator at the resolutions meshes have (docs/accuracy.md has the numbers):

* **the O(h) bias of the continuous operator.** In flat space
  L_h = (e^{hΔ} − 1)/h = Δ + hΔ²/2 + O(h²), so the Richardson combination
  2 L_{h/2} − L_h = Δ − h²Δ³/12 + O(h³) is second order. Its weight per pair is a
  difference of Gaussians, (8 e^{−d²/2h} − e^{−d²/4h}) m_p / (4πh²), assembled by the same
  numba pass as the plain operator (:mod:`meshlap.kernel`). S = M L stays symmetric and its
  rows sum to zero, but some weights are negative, so ``−S`` positive semidefinite is no
  longer automatic: :func:`smallest_eigenvalue` checks it at build time.
* **the quadrature error of the lumped masses**, which on irregular meshes is larger than
  the bias once h is a few squared edge lengths. For point-wise application,
  :func:`moment_correction` changes each row as little as possible (in a weighted least
  squares sense) so that it is exact for every polynomial of degree ≤ 2 in the vertex's
  tangent plane: zero first moment, second moment 2·I. On a surface this is
  Δ_S f(w) = f_uu + f_vv in coordinates of the tangent plane, whose metric is the identity
  to second order at w.
* **the boundary term**: within a few √h of a boundary the Gaussian neighbourhood is
  one-sided, and L f gains ∂f/∂n·e^{−d²/4h}/√(πh) (Shi and Sun's point integral method
  keeps it as a boundary integral). The moment correction removes it, since it forces the
  first moment to zero with whatever neighbours a row has.

The point-wise correction makes L non-symmetric, so it is a second matrix
(``MeshLaplacian.L_pointwise``, what ``op @ f`` applies); spectra and heat flow keep the
symmetric pencil (S, M).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import scipy.sparse as sp
from numba import njit, prange

from .validation import Polygons

__all__ = ["local_h", "moment_correction", "smallest_eigenvalue", "vertex_normals"]


@njit(cache=True, inline="always")
def _solve_spd(G, r, k):  # pragma: no cover - compiled
    # Cholesky solve of the k×k block of G (modified in place); returns False if not SPD
    for j in range(k):
        s = G[j, j]
        for q in range(j):
            s -= G[j, q] * G[j, q]
        if s <= 0.0:
            return False
        G[j, j] = math.sqrt(s)
        for i in range(j + 1, k):
            s = G[i, j]
            for q in range(j):
                s -= G[i, q] * G[j, q]
            G[i, j] = s / G[j, j]
    for i in range(k):
        s = r[i]
        for q in range(i):
            s -= G[i, q] * r[q]
        r[i] = s / G[i, i]
    for i in range(k - 1, -1, -1):
        s = r[i]
        for q in range(i + 1, k):
            s -= G[q, i] * r[q]
        r[i] = s / G[i, i]
    return True


@njit(cache=True, parallel=True)
def _moment_rows(indptr, indices, data, V, out, failed):  # pragma: no cover - compiled
    n = len(indptr) - 1
    for w in prange(n):
        a, b = indptr[w], indptr[w + 1]
        for q in range(a, b):
            out[q] = data[q]
        # tangent plane from the weighted covariance of the neighbourhood (|weights|)
        C = np.zeros((3, 3))
        tot = 0.0
        for q in range(a, b):
            p = indices[q]
            if p == w:
                continue
            c = abs(data[q])
            tot += c
            for i in range(3):
                di = V[p, i] - V[w, i]
                for j in range(3):
                    C[i, j] += c * di * (V[p, j] - V[w, j])
        if tot == 0.0:
            continue
        _, vec = np.linalg.eigh(C)
        t1 = vec[:, 2]
        t2 = vec[:, 1]
        sigma2 = (C[0, 0] + C[1, 1] + C[2, 2]) / tot
        if sigma2 <= 0.0:
            continue
        inv = 1.0 / math.sqrt(sigma2)
        # phi = (u, v, u², uv, v²) in units of sigma; target moments (0, 0, 2, 0, 2)/sigma²
        G = np.zeros((5, 5))
        r = np.zeros(5)
        r[2] = 2.0 / sigma2
        r[4] = 2.0 / sigma2
        phi = np.empty(5)
        for q in range(a, b):
            p = indices[q]
            if p == w:
                continue
            dx = V[p, 0] - V[w, 0]
            dy = V[p, 1] - V[w, 1]
            dz = V[p, 2] - V[w, 2]
            u = (dx * t1[0] + dy * t1[1] + dz * t1[2]) * inv
            v = (dx * t2[0] + dy * t2[1] + dz * t2[2]) * inv
            phi[0] = u
            phi[1] = v
            phi[2] = u * u
            phi[3] = u * v
            phi[4] = v * v
            c = abs(data[q])
            for i in range(5):
                r[i] -= data[q] * phi[i]
                for j in range(i + 1):
                    G[i, j] += c * phi[i] * phi[j]
        if not _solve_spd(G, r, 5):
            failed[w] = 1
            continue
        diag = -1
        s = 0.0
        for q in range(a, b):
            p = indices[q]
            if p == w:
                diag = q
                continue
            dx = V[p, 0] - V[w, 0]
            dy = V[p, 1] - V[w, 1]
            dz = V[p, 2] - V[w, 2]
            u = (dx * t1[0] + dy * t1[1] + dz * t1[2]) * inv
            v = (dx * t2[0] + dy * t2[1] + dz * t2[2]) * inv
            corr = r[0] * u + r[1] * v + r[2] * u * u + r[3] * u * v + r[4] * v * v
            out[q] = data[q] + abs(data[q]) * corr
            s += out[q]
        if diag >= 0:
            out[diag] = -s


def moment_correction(L: sp.csr_matrix, V: np.ndarray) -> tuple[sp.csr_matrix, np.ndarray]:
    """Rows of ``L`` made exact for quadratics in each vertex's tangent plane.

    Each off-diagonal weight a_p of row w becomes a_p + |a_p| φ_pᵀλ_w with
    φ = (u, v, u², uv, v²) the tangent-plane coordinates of p − w (tangent plane from the
    |a|-weighted covariance of the row's neighbours) and λ_w the smallest change, in the
    |a|-weighted norm, that gives zero first moments and second moments 2·I; the diagonal
    keeps each row summing to zero. Rows whose neighbours do not span a plane (fewer than
    five, or collinear) are left unchanged and flagged.

    Parameters
    ----------
    L : scipy.sparse.csr_matrix
        A Laplacian with the diagonal stored in every row that has neighbours.
    V : (n, 3) ndarray
        Vertex positions.

    Returns
    -------
    L_corrected : scipy.sparse.csr_matrix
        Same sparsity pattern.
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
    data = np.ascontiguousarray(L.data, dtype=np.float64)
    out = np.empty_like(data)
    failed = np.zeros(L.shape[0], dtype=np.int8)
    _moment_rows(L.indptr, L.indices, data, np.ascontiguousarray(V, dtype=np.float64), out, failed)
    Lc = sp.csr_matrix((out.astype(L.dtype), L.indices.copy(), L.indptr.copy()), shape=L.shape)
    return Lc, failed.astype(bool)


def local_h(V: np.ndarray, faces: Polygons, scale: float, smoothing: int = 3) -> np.ndarray:
    """Per-vertex kernel width h_w = scale · ℓ_w², ℓ_w² the mean squared length of the face
    sides at w, averaged ``smoothing`` times over each vertex and its edge neighbours (so
    that h varies on the scale of several edges, not from one edge to the next).
    Vertices on no face get the mean of the others."""
    e = faces.edges()
    n = len(V)
    l2 = ((V[e[:, 0]] - V[e[:, 1]]) ** 2).sum(axis=1)
    rows = np.concatenate([e[:, 0], e[:, 1]])
    cols = np.concatenate([e[:, 1], e[:, 0]])
    A = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    deg = np.asarray(A.sum(axis=1)).ravel()
    used = deg > 0
    ell2 = np.bincount(rows, weights=np.concatenate([l2, l2]), minlength=n)
    ell2[used] /= deg[used]
    A = A + sp.diags(used.astype(np.float64))
    norm = np.asarray(A.sum(axis=1)).ravel()
    for _ in range(smoothing):
        ell2 = np.divide(A @ ell2, norm, out=ell2.copy(), where=norm > 0)
    ell2[~used] = ell2[used].mean() if used.any() else 1.0
    return scale * ell2


def vertex_normals(V: np.ndarray, faces: Polygons) -> np.ndarray:
    """Area-weighted unit vertex normals of a (fan-triangulated) mesh; 0 where undefined."""
    T = faces.triangles()
    N = np.zeros_like(V, dtype=np.float64)
    if len(T):
        fn = np.cross(V[T[:, 1]] - V[T[:, 0]], V[T[:, 2]] - V[T[:, 0]])
        for c in range(3):
            np.add.at(N, T[:, c], fn)
    norm = np.linalg.norm(N, axis=1, keepdims=True)
    return np.divide(N, norm, out=np.zeros_like(N), where=norm > 0)


def smallest_eigenvalue(L: sp.csr_matrix, mass: np.ndarray, V: np.ndarray, faces: Polygons,
                        tol: float = 1e-4) -> tuple[float, float]:
    """The two ends that decide whether −S = −M L is positive semidefinite.

    Returns (λ_min, λ_scale): the smallest eigenvalue of the pencil (−S, M) on the vertices
    with mass, from :func:`meshlap.spectral.eigs` (LOBPCG, cotangent preconditioner, a few
    vectors), and the scale ``max_w −L_ww`` it is to be compared with. A negative mode of
    the difference of Gaussians lives at high frequency; LOBPCG minimizes the Rayleigh
    quotient over the whole space, so it finds such a mode if there is one.
    """
    from .baselines import SparseLaplacian
    from .spectral import eigs

    op = SparseLaplacian(L, mass)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        lam, _ = eigs(op, 2, tol=tol, maxiter=60, mesh=(V, faces), method="lobpcg"
                      if (mass > 0).sum() > 1200 else "dense")
    scale = float(np.max(-L.diagonal()))
    return float(lam.min()), scale
