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
from numba import prange

from ._jit import jit
from .geometry import Polygons

__all__ = ["boundary_frames", "curvature_h", "local_h", "moment_correction", "neumann_images",
           "second_moment_scale", "smallest_eigenvalue", "vertex_normals"]


@jit(inline="always")
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


@jit(inline="always")
def _tangent_uv(V, p, w, t1, t2, inv):  # pragma: no cover - compiled
    # coordinates of p - w in the tangent frame (t1, t2) of w, scaled by inv
    dx = V[p, 0] - V[w, 0]
    dy = V[p, 1] - V[w, 1]
    dz = V[p, 2] - V[w, 2]
    return (dx * t1[0] + dy * t1[1] + dz * t1[2]) * inv, (dx * t2[0] + dy * t2[1] + dz * t2[2]) * inv


@jit(parallel=True)
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
            u, v = _tangent_uv(V, p, w, t1, t2, inv)
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
            u, v = _tangent_uv(V, p, w, t1, t2, inv)
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
    out = np.empty_like(L.data)
    failed = np.zeros(L.shape[0], dtype=np.int8)
    _moment_rows(L.indptr, L.indices, L.data, np.ascontiguousarray(V, dtype=np.float64), out, failed)
    # same pattern: share the index arrays (neither matrix is changed in place afterwards)
    Lc = sp.csr_matrix(L.shape, dtype=L.dtype)
    Lc.data, Lc.indices, Lc.indptr = out, L.indices, L.indptr
    Lc.has_sorted_indices = L.has_sorted_indices
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


def _ring_average(V: np.ndarray, faces: Polygons, x: np.ndarray, times: int) -> np.ndarray:
    # average over each vertex and its edge neighbours, ``times`` times
    e = faces.edges()
    n = len(V)
    A = sp.csr_matrix((np.ones(2 * len(e)), (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])),
                      shape=(n, n))
    A = A + sp.eye(n, format="csr")
    norm = np.asarray(A.sum(axis=1)).ravel()
    for _ in range(times):
        x = (A @ x) / norm
    return x


def curvature_h(V: np.ndarray, faces: Polygons, normals: np.ndarray, h: np.ndarray | float,
                beta: float, smoothing: int = 3) -> np.ndarray:
    """Per-vertex widths h_w = min(h, β/κ_w²), averaged ``smoothing`` times over the 1-rings.

    κ_w² = Σ|n_p − n_w|² / Σ|p − w|² over the edges at w (1 on the unit sphere):
    where the surface bends on a scale shorter than √(h/β) (spot's horns and ears, fandisk's
    creases) the kernel narrows so that it no longer averages across the bend; elsewhere h is
    unchanged. Returns an array; it equals h everywhere on meshes that do not bend that fast.
    """
    e = faces.edges()
    n = len(V)
    d2 = ((V[e[:, 0]] - V[e[:, 1]]) ** 2).sum(axis=1)
    dn2 = ((normals[e[:, 0]] - normals[e[:, 1]]) ** 2).sum(axis=1)
    # a ratio of sums: the short edges of skinny triangles, whose normals differ by noise,
    # weigh little
    num = np.bincount(e[:, 0], dn2, n) + np.bincount(e[:, 1], dn2, n)
    den = np.bincount(e[:, 0], d2, n) + np.bincount(e[:, 1], d2, n)
    k2 = np.divide(num, den, out=np.zeros(n), where=den > 0)
    hv = np.broadcast_to(np.asarray(h, dtype=np.float64), (n,)).copy()
    capped = beta / np.maximum(k2, 1e-300)
    if not (capped < hv).any():
        return hv
    return _ring_average(V, faces, np.minimum(hv, capped), smoothing)


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


def smallest_eigenvalue(L: sp.csr_matrix, mass: np.ndarray, V: np.ndarray, faces: Polygons | None,
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
        lam, _ = eigs(op, 2, tol=tol, maxiter=60, mesh=None if faces is None else (V, faces),
                      method="lobpcg"
                      if (mass > 0).sum() > 1200 else "dense")
    scale = float(np.max(-L.diagonal()))
    return float(lam.min()), scale


def _boundary_frames(V: np.ndarray, faces: Polygons, radius: float):
    """For every vertex within ``radius`` of the boundary: its nearest boundary point b and
    the outward unit normal ν of the boundary there (in the plane of the adjacent face)."""
    from pykdtree.kdtree import KDTree

    n = len(V)
    sides = faces.edges()
    face_of = np.repeat(np.arange(faces.n_faces), faces.sizes)
    key = np.sort(sides, axis=1)
    k = key[:, 0] * np.int64(n) + key[:, 1]
    uniq, inv, cnt = np.unique(k, return_inverse=True, return_counts=True)
    on = cnt[inv] == 1
    if not on.any():
        return None
    e, fid = sides[on], face_of[on]
    a, b = V[e[:, 0]], V[e[:, 1]]
    # the outward normal of each boundary edge: in the plane of its face, away from the face
    cen = np.zeros((faces.n_faces, 3))
    np.add.at(cen, face_of, V[sides[:, 0]])
    cen /= faces.sizes[:, None]
    t = b - a
    fn = np.cross(t, cen[fid] - a)  # normal of the plane through the edge and the centroid
    nu = np.cross(t, fn)
    nu /= np.maximum(np.linalg.norm(nu, axis=1, keepdims=True), 1e-300)
    flip = ((cen[fid] - a) * nu).sum(axis=1) > 0
    nu[flip] *= -1
    length = np.linalg.norm(t, axis=1)
    step = max(radius / 16, length.sum() / (4 * n))
    pieces = np.maximum(np.ceil(length / step).astype(np.int64), 1)
    edge = np.repeat(np.arange(len(e)), pieces + 1)
    start = np.repeat(np.cumsum(pieces + 1) - (pieces + 1), pieces + 1)
    frac = (np.arange(len(edge)) - start) / pieces[edge]
    samples = a[edge] + frac[:, None] * t[edge]
    dist, idx = KDTree(samples).query(V, k=1, distance_upper_bound=radius * (1 + 1e-9))
    band = np.flatnonzero(np.isfinite(dist) & (idx < len(samples)))
    return band, samples[idx[band]], nu[edge[idx[band]]]


def boundary_frames(V: np.ndarray, faces: Polygons, radius: float):
    """``(band, b, ν)``: the vertices within ``radius`` of the boundary, their nearest boundary
    point and its outward unit normal; None on a closed mesh."""
    return _boundary_frames(V, faces, radius)


def second_moment_scale(apply, V: np.ndarray, mass: np.ndarray, exclude: np.ndarray | None) -> float:
    """The factor that brings the mass-weighted mean of the rows' second moments
    μ_w = L(|x − w|²)(w) = L|x|² − 2 w·Lx (L annihilates constants) to 4, its value for Δ on
    a surface. ``apply`` applies L to an (n, 4) block.

    The lumped-mass quadrature underestimates μ systematically when h is a few squared edge
    lengths (by 0.1-4% on the meshes of docs/accuracy.md), which lowers every eigenvalue by
    that fraction; one global factor removes this part and keeps S symmetric and −S
    semidefinite. Rows in ``exclude`` (the boundary band, where μ is one-sided) do not count.
    """
    Y = apply(np.column_stack([(V**2).sum(axis=1), V]))
    mu = Y[:, 0] - 2.0 * (V * Y[:, 1:]).sum(axis=1)
    use = mass > 0
    if exclude is not None:
        use[exclude] = False
    if not use.any():
        return 1.0
    mean = float((mu[use] * mass[use]).sum() / mass[use].sum())
    return 4.0 / mean if mean > 0 else 1.0


def neumann_images(L: sp.csr_matrix, V: np.ndarray, frames, mass: np.ndarray,
                   hv: np.ndarray, dog: bool) -> sp.csr_matrix:
    """Add to L the kernel between each vertex and the mirror images of its neighbours across
    the nearest boundary line (the method of images: on a half-plane, K(x, y) + K(x, Ry) is
    the heat kernel with Neumann conditions, so the spectral problem gets natural boundary
    conditions). Pair (w, p) gets ½(K(|w − R_w p|) + K(|p − R_p w|)) with R_w the reflection
    across the boundary line nearest w, which keeps S = M L symmetric. ``frames`` comes from
    :func:`boundary_frames`."""
    if frames is None:
        return L
    band, bpt, nu = frames
    pos = np.full(len(V), -1)
    pos[band] = np.arange(len(band))
    L = sp.csr_matrix(L, copy=True)
    rows = np.repeat(np.arange(L.shape[0]), np.diff(L.indptr))
    cols = L.indices
    sel = np.flatnonzero((pos[rows] >= 0) & (pos[cols] >= 0) & (rows != cols))
    w, p = rows[sel], cols[sel]
    iw, ip = pos[w], pos[p]

    def image_d2(x, y, bx, nx):
        # |x − R y|², R the reflection across the line through bx with normal nx
        ry = y - 2.0 * ((y - bx) * nx).sum(axis=1)[:, None] * nx
        return ((x - ry) ** 2).sum(axis=1)

    # a mirror image only where the half-plane picture holds: each point lies on the inner
    # side of the other's boundary line (across a small hole or a thin strip it does not,
    # and the image would fall on the surface itself)
    inner = (((V[p] - bpt[iw]) * nu[iw]).sum(axis=1) <= 0) & (((V[w] - bpt[ip]) * nu[ip]).sum(axis=1) <= 0)
    sel, w, p, iw, ip = sel[inner], w[inner], p[inner], iw[inner], ip[inner]
    d2w = image_d2(V[w], V[p], bpt[iw], nu[iw])
    d2p = image_d2(V[p], V[w], bpt[ip], nu[ip])
    hp = 0.5 * (hv[w] + hv[p])

    def kern(d2):
        e = np.exp(-d2 / (4 * hp))
        return e * (8 * e - 1) if dog else e

    add = mass[p] * 0.5 * (kern(d2w) + kern(d2p)) / (4 * math.pi * hp * hp)
    L.data[sel] += add.astype(L.dtype)
    # rows keep summing to zero
    diag = np.flatnonzero(rows == cols)
    off = np.asarray(L.sum(axis=1)).ravel() - L.data[diag]
    L.data[diag] = -off[rows[diag]]
    return L
