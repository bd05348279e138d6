"""Local frames of a geometry: normals, tangent spaces, neighbour edges and the boundary.

Every function takes plain arrays (points, faces, cells, flags), so the same code serves a
mesh, a point cloud and the points of one MPI rank. :class:`~meshlap.geometry.Geometry`
calls them lazily and keeps each result, so a build computes each frame once.

The boundary is described the same way for every intrinsic dimension k: sample points b on
it with the outward unit conormal ν there (tangent to the geometry, normal to its boundary).
A point w near the boundary is then reflected across the hyperplane through its nearest
sample b with normal ν, which is what the mirror images of
:mod:`meshlap.corrections.images` need:

* curves (k = 1): the end points, ν along the curve away from its last edge;
* surfaces (k = 2): the boundary edges, sampled finely, ν in the plane of the adjacent face;
* volumes (k = 3): the hull triangles of the tetrahedra, sampled, ν their outward normal;
* point clouds: the points flagged as boundary by their masses, ν the tangent-plane
  direction away from the centroid of their neighbours.
"""

from __future__ import annotations

import itertools

import numpy as np
import scipy.sparse as sp
from pykdtree.kdtree import KDTree
from scipy.sparse.csgraph import breadth_first_order, connected_components

from .._jit import jit
from .polygons import Polygons

__all__ = ["BoundaryFrames", "boundary_samples_cloud", "boundary_samples_curve",
           "boundary_samples_surface", "boundary_samples_volume", "frames_from_samples",
           "height_residuals", "knn_edges", "orient_normals", "pca_frames", "vertex_normals"]

#: ``(band, b, nu)``: the points within the radius of the boundary, their nearest boundary
#: sample and the outward unit conormal there; None when there is no boundary.
BoundaryFrames = tuple[np.ndarray, np.ndarray, np.ndarray] | None


def vertex_normals(V: np.ndarray, faces: Polygons) -> np.ndarray:
    """Area-weighted unit vertex normals of a (fan-triangulated) mesh in R³; 0 where undefined.

    Examples
    --------
    >>> import numpy as np
    >>> from meshlap.geometry.validation import check_faces
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    >>> vertex_normals(V, check_faces([[0, 1, 2]], 3))[0].tolist()
    [0.0, 0.0, 1.0]
    """
    # float32 positions keep their float32 cross products, as numpy made them
    V = np.ascontiguousarray(V, dtype=V.dtype if V.dtype == np.float32 else np.float64)
    N = np.zeros((len(V), 3))
    _unit_normal_sums(V, np.ascontiguousarray(faces.triangles(), dtype=np.int64), N)
    return N


@jit()
def _unit_normal_sums(V, T, N):  # pragma: no cover - compiled
    # N (zeros) += each face's cross product at its corners, then N / |N| (0 where |N| = 0):
    # the sums of the numpy expression to the bit (np.cross's products, np.add.at(N, T[:, c],
    # fn) for c = 0, 1, 2: the first corners' in face order, then the second's, the third's;
    # np.linalg.norm's ((x² + y²) + z²)), in one pass per corner (0.12 -> 0.02 s of CPU at
    # 400k vertices, measured)
    m = len(T)
    fn = np.empty((m, 3))
    for c in range(3):
        for t in range(m):
            if c == 0:
                i0, i1, i2 = T[t, 0], T[t, 1], T[t, 2]
                a0, a1, a2 = V[i1, 0] - V[i0, 0], V[i1, 1] - V[i0, 1], V[i1, 2] - V[i0, 2]
                b0, b1, b2 = V[i2, 0] - V[i0, 0], V[i2, 1] - V[i0, 1], V[i2, 2] - V[i0, 2]
                fn[t, 0] = a1 * b2 - a2 * b1
                fn[t, 1] = a2 * b0 - a0 * b2
                fn[t, 2] = a0 * b1 - a1 * b0
            v = T[t, c]
            N[v, 0] += fn[t, 0]
            N[v, 1] += fn[t, 1]
            N[v, 2] += fn[t, 2]
    for v in range(len(N)):
        s = N[v, 0] * N[v, 0] + N[v, 1] * N[v, 1] + N[v, 2] * N[v, 2]
        if s > 0.0:
            r = np.sqrt(s)
            N[v, 0] /= r
            N[v, 1] /= r
            N[v, 2] /= r
        else:
            N[v, 0] = N[v, 1] = N[v, 2] = 0.0


def pca_frames(P: np.ndarray, k: int, neighbors: int = 16, rows: np.ndarray | None = None
               ) -> tuple[np.ndarray, np.ndarray]:
    """Tangent bases from the principal axes of each point's ``neighbors`` nearest points.

    Returns ``(T, idx)``: T (n, d, d) with the k tangent axes first (largest variance first)
    and the normal axes after them, and the neighbour indices (n, K+1), the point first; for
    the points ``rows`` only, if given.

    Examples
    --------
    >>> import numpy as np
    >>> P = np.random.default_rng(0).normal(size=(200, 3)) * [1, 1, 0]
    >>> T, _ = pca_frames(P, 2)
    >>> bool(np.allclose(abs(T[:, :, 2]), [0, 0, 1]))      # the normal of the plane
    True
    """
    d = P.shape[1]
    K = min(neighbors, len(P) - 1)
    _, idx = KDTree(P).query(P if rows is None else P[rows], k=K + 1)
    idx = np.asarray(idx, dtype=np.int64)
    n = len(idx)
    T = np.empty((n, d, d))
    for a in range(0, n, 65536):  # blocks bound the (block, K+1, d) temporaries
        nb = P[idx[a:a + 65536]]
        X = nb - nb.mean(axis=1, keepdims=True)
        _, v = np.linalg.eigh(np.einsum("nki,nkj->nij", X, X))
        T[a:a + 65536] = v[:, :, ::-1]  # largest variance first
    return T, idx


def height_residuals(P: np.ndarray, T: np.ndarray, idx: np.ndarray, k: int, degrees: tuple[int, ...]
                     ) -> tuple[np.ndarray, tuple[int, ...]]:
    """Residual sums of least-squares fits of each neighbourhood's heights along its normals by
    polynomials of the given degrees in its k tangent coordinates, and their degrees of freedom.

    ``T, idx`` are :func:`pca_frames`' (the neighbourhoods, their frames). Returns ``res``
    (len(degrees), m) and ``dof``: points per neighbourhood minus monomials; where a degree
    leaves fewer than one, its row is zero (the fit is exact).

    Examples
    --------
    >>> P = np.random.default_rng(0).normal(size=(300, 3)) * [1, 1, 0]
    >>> T, idx = pca_frames(P, 2)
    >>> res, dof = height_residuals(P, T, idx, 2, (2, 3))
    >>> dof, bool(res.max() < 1e-20)             # a plane: nothing is left
    ((11, 7), True)
    """
    # the monomials in the k tangent coordinates, by degree
    powers = [c for deg in range(max(degrees) + 1)
              for c in itertools.combinations_with_replacement(range(k), deg)]
    sizes = [sum(len(c) <= deg for c in powers) for deg in degrees]
    dof = tuple(idx.shape[1] - s for s in sizes)
    res = np.zeros((len(degrees), len(idx)))
    for a in range(0, len(idx), 65536):  # blocks bound the (block, K+1, monomials) temporaries
        nb = P[idx[a:a + 65536]]
        X = nb - nb.mean(axis=1, keepdims=True)
        z = X @ T[a:a + 65536, :, k:]  # heights along the normals
        u = X @ T[a:a + 65536, :, :k]  # tangent coordinates
        u /= np.maximum(np.abs(u).max(axis=(1, 2), keepdims=True), 1e-300)  # conditioning
        A = np.stack([np.prod(u[..., list(c)], axis=2) for c in powers], axis=2)
        At = np.swapaxes(A, 1, 2)
        G, b = At @ A, At @ z  # a lower degree's normal equations are their leading block
        for i, m in enumerate(sizes):
            if dof[i] >= 1:
                Gm = G[:, :m, :m] + 1e-12 * np.einsum("nii->n", G[:, :m, :m])[:, None, None] * np.eye(m)
                r = z - A[..., :m] @ np.linalg.solve(Gm, b[:, :m])
                res[i, a:a + 65536] = (r**2).sum(axis=(1, 2))
    return res, dof


@jit()
def _flip_along(order, pred, N):  # pragma: no cover - compiled
    for i in order:
        p = pred[i]
        if p >= 0:
            s = 0.0
            for c in range(N.shape[1]):
                s += N[i, c] * N[p, c]
            if s < 0.0:
                for c in range(N.shape[1]):
                    N[i, c] = -N[i, c]


def orient_normals(N: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Flip normals so that neighbours agree: along a breadth-first walk of the neighbour
    graph ``idx`` (rows: a point, then its neighbours), each normal takes the side of the one
    it was reached from. Each connected piece keeps the side of its first point.

    Examples
    --------
    >>> import numpy as np
    >>> N = np.array([[0, 0, 1.0], [0, 0, -1.0], [0, 0.1, 1.0]])
    >>> orient_normals(N, np.array([[0, 1], [1, 2], [2, 0]]))[:, 2].tolist()
    [1.0, 1.0, 1.0]
    """
    n = len(N)
    rows = np.repeat(np.arange(n), idx.shape[1])
    G = sp.csr_matrix((np.ones(len(rows)), (rows, idx.reshape(-1))), shape=(n, n))
    G = G + G.T
    N = np.array(N, dtype=np.float64)
    _, label = connected_components(G, directed=False)
    for root in np.unique(label, return_index=True)[1]:
        order, pred = breadth_first_order(G, int(root), directed=False)
        _flip_along(order.astype(np.int64), pred.astype(np.int64), N)
    return N


def knn_edges(idx: np.ndarray) -> np.ndarray:
    """Undirected edges (each once) between every point and its nearest neighbours ``idx``
    (rows as :func:`pca_frames` returns them: the point first)."""
    i = np.repeat(idx[:, 0], idx.shape[1] - 1)
    j = idx[:, 1:].reshape(-1)
    e = np.sort(np.stack([i, j], axis=1), axis=1)
    return np.unique(e[e[:, 0] != e[:, 1]], axis=0)


def frames_from_samples(P: np.ndarray, samples: np.ndarray, nu: np.ndarray,
                        radius: float) -> BoundaryFrames:
    """For every point within ``radius`` of a boundary sample: the nearest one and its ν."""
    if not len(samples):
        return None
    dist, idx = KDTree(samples).query(P, k=1, distance_upper_bound=radius * (1 + 1e-9))
    band = np.flatnonzero(np.isfinite(dist) & (idx < len(samples)))
    return band, samples[idx[band]], nu[idx[band]]


def _unit(x: np.ndarray) -> np.ndarray:
    return x / np.maximum(np.linalg.norm(x, axis=1, keepdims=True), 1e-300)


def _sample_segments(a: np.ndarray, t: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray]:
    # points along segments a + s t, s in [0, 1], at most `step` apart; and their segment
    length = np.linalg.norm(t, axis=1)
    pieces = np.maximum(np.ceil(length / step).astype(np.int64), 1)
    seg = np.repeat(np.arange(len(a)), pieces + 1)
    start = np.repeat(np.cumsum(pieces + 1) - (pieces + 1), pieces + 1)
    frac = (np.arange(len(seg)) - start) / pieces[seg]
    return a[seg] + frac[:, None] * t[seg], seg


def boundary_samples_curve(P: np.ndarray, edges: np.ndarray, rep: np.ndarray | None = None
                           ) -> tuple[np.ndarray, np.ndarray]:
    """End points of a polyline and the direction away from their edge (any dimension); ``rep``:
    each point's representative among coincident copies, which join the edges they end."""
    degree = np.bincount(edges.reshape(-1), minlength=len(P))
    welded = degree if rep is None else np.bincount(rep[edges].reshape(-1), minlength=len(P))[rep]
    ends = np.flatnonzero((degree == 1) & (welded == 1))
    if not len(ends):
        return np.zeros((0, P.shape[1])), np.zeros((0, P.shape[1]))
    other = np.empty(len(P), dtype=np.int64)
    other[edges[:, 0]] = edges[:, 1]
    other[edges[:, 1]] = edges[:, 0]
    return P[ends], _unit(P[ends] - P[other[ends]])


def boundary_samples_surface(P: np.ndarray, faces: Polygons, step: float, rep: np.ndarray | None = None
                             ) -> tuple[np.ndarray, np.ndarray]:
    """Points along the boundary edges, ``step`` apart, with the outward conormal in the plane
    of the adjacent face (any ambient dimension); ``rep``: each point's representative among
    coincident copies (a seam between copies is no boundary)."""
    n = len(P)
    sides = faces.edges()
    face_of = np.repeat(np.arange(faces.n_faces), faces.sizes)
    key = np.sort(sides if rep is None else rep[sides], axis=1)
    _, inv, cnt = np.unique(key[:, 0] * np.int64(n) + key[:, 1], return_inverse=True,
                            return_counts=True)
    on = (cnt[inv] == 1) & (key[:, 0] != key[:, 1])
    if not on.any():
        return np.zeros((0, P.shape[1])), np.zeros((0, P.shape[1]))
    e, fid = sides[on], face_of[on]
    cen = np.zeros((faces.n_faces, P.shape[1]))
    np.add.at(cen, face_of, P[sides[:, 0]])
    cen /= faces.sizes[:, None]
    a, t = P[e[:, 0]], P[e[:, 1]] - P[e[:, 0]]
    inward = cen[fid] - a
    tu = _unit(t)
    nu = _unit(-(inward - (inward * tu).sum(axis=1)[:, None] * tu))
    samples, seg = _sample_segments(a, t, step)
    return samples, nu[seg]


def boundary_samples_volume(P: np.ndarray, tets: np.ndarray, step: float, rep: np.ndarray | None = None
                            ) -> tuple[np.ndarray, np.ndarray]:
    """Points on the hull triangles of a tetrahedral mesh in R³, about ``step`` apart, with
    the outward unit normal of their triangle; ``rep``: each point's representative among
    coincident copies."""
    opp = np.array([[1, 2, 3, 0], [0, 2, 3, 1], [0, 1, 3, 2], [0, 1, 2, 3]])
    tri = tets[:, opp].reshape(-1, 4)  # three corners, then the opposite one
    key = np.sort(tri[:, :3] if rep is None else rep[tri[:, :3]], axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    hull = tri[(cnt[inv.reshape(-1)] == 1) & (key[:, 0] != key[:, 1]) & (key[:, 1] != key[:, 2])]
    if not len(hull):
        return np.zeros((0, 3)), np.zeros((0, 3))
    A, B, C, D = (P[hull[:, c], :3] for c in range(4))
    nrm = _unit(np.cross(B - A, C - A))
    nrm[((D - A) * nrm).sum(axis=1) > 0] *= -1
    longest = max(float(np.linalg.norm(B - A, axis=1).max()), float(np.linalg.norm(C - A, axis=1).max()))
    m = max(int(np.ceil(longest / step)), 1)
    s, t = np.meshgrid(np.arange(m + 1), np.arange(m + 1), indexing="ij")
    keep = s + t <= m
    s, t = s[keep] / m, t[keep] / m  # barycentric grid on every triangle
    samples = (A[:, None] + s[None, :, None] * (B - A)[:, None] + t[None, :, None] * (C - A)[:, None])
    return samples.reshape(-1, 3), np.repeat(nrm, len(s), axis=0)


def boundary_samples_cloud(P: np.ndarray, flags: np.ndarray, T: np.ndarray, idx: np.ndarray,
                           k: int) -> tuple[np.ndarray, np.ndarray]:
    """The boundary points of a cloud, with the tangent direction away from the centroid of
    their neighbours (T, idx from :func:`pca_frames`)."""
    b = np.flatnonzero(flags)
    if not len(b):
        return np.zeros((0, P.shape[1])), np.zeros((0, P.shape[1]))
    out = P[b] - P[idx[b]].mean(axis=1)
    tan = T[b, :, :k]
    out = np.einsum("ndk,nk->nd", tan, np.einsum("ndk,nd->nk", tan, out))
    return P[b], _unit(out)
