"""The symmetric pencil from the kernel integrated over the cells (a Galerkin form).

The vertex operator integrates the kernel with one point per vertex (the lumped masses);
once the width is near the squared edge length that rule, not the kernel, sets the error.
Here the kernel is integrated over the cells with the piecewise-linear hat functions φ_i,
a degree-2 rule of q points per cell (3 per triangle, 4 per tetrahedron, 2 per segment):

    −S_ij = ½ ∫∫ k_h(x, y) (φ_i(x) − φ_i(y)) (φ_j(x) − φ_j(y)) dx dy

(the energy ½∫∫ k (f(x) − f(y))² of f = Σ f_i φ_i), which is −Φᵀ W L_q Φ with L_q the
kernel operator on the quadrature points x_q of weights W and Φ_qi = φ_i(x_q). The self pairs
cancel, the rows sum to zero, S is symmetric, and −S is semidefinite wherever L_q is (the
Richardson kernel's check decides). Mirror images at the boundary work on L_q as on the
vertices. On a curve the pairs take the distance along it (its chains and loops; the chord
where branches meet), so that strands which pass close by do not couple (a trefoil knot of
60 vertices: 0.53% against 228% with the chord). On a triangle mesh, pairs whose path along
the mesh is much longer than their chord (across a groove or a thin wall) are dropped
(:mod:`meshlap.corrections.shortcuts`).

The form pairs with the consistent mass C = Φᵀ W Φ. The operator's mass is lumped (the
diagonal m = C·1 that :mod:`meshlap.spectral` expects), so the pencil is moved onto it by the
congruence S' = Bᵀ S B, B = I + ½ m⁻¹ (diag(m) − C): to first order in m⁻¹(diag(m) − C),
which is O(ē² λ) on a mode of eigenvalue λ, (S', diag m) has the eigenvalues of (S, C), and a
congruence keeps −S' semidefinite.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import scipy.sparse as sp
from pykdtree.kdtree import KDTree

from .._jit import in_blocks, jit
from ..assembly import Kernel, assemble, cutoff_radius
from ..assembly._intrinsics import zero_row_sum
from ..assembly.variable import dog_factor
from ..errors import MeshError
from ..geometry import frames as frames_mod
from ..geometry import simplex_volumes
from ..tuned import CREASE_ANGLE, SEGMENT_STEP, SPLIT_BELOW
from ..widths import Widths
from .images import neumann_images
from .shortcuts import drop_shortcuts

__all__ = ["RULES", "creases", "galerkin_pencil", "quadrature_points", "shape_measures", "simplices",
           "split_points"]


#: Degree-2 rules on the simplex of k + 1 corners: (a, b) barycentric coordinates, each point
#: a at one corner and b at the others, one point per corner, equal weights.
RULES = {1: (0.5 + 0.5 / np.sqrt(3.0), 0.5 - 0.5 / np.sqrt(3.0)),
         2: (2.0 / 3.0, 1.0 / 6.0),
         3: (0.5854101966249685, 0.1381966011250105)}


@jit()
def _unfold_rows(start, stop, indptr, indices, data, X, N, W, near, hq, dogc, half_k,
                 cos_crease):  # pragma: no cover
    # pairs near a crease whose cells' normals differ by more than the crease angle: the
    # kernel of the distance along the two planes unfolded about their line of intersection,
    # at the pair's width (hq[q] + hq[r]) / 2 as in the assembly
    z0 = np.empty(3)  # a point of the line, and its direction: scratch of this block
    u = np.empty(3)
    for q in range(start, stop):
        if not near[q]:
            continue
        for e in range(indptr[q], indptr[q + 1]):
            r = indices[e]
            if r == q:
                continue
            c = 2.0 if not near[r] else N[q, 0] * N[r, 0] + N[q, 1] * N[r, 1] + N[q, 2] * N[r, 2]
            if c < cos_crease:
                ux = N[q, 1] * N[r, 2] - N[q, 2] * N[r, 1]
                uy = N[q, 2] * N[r, 0] - N[q, 0] * N[r, 2]
                uz = N[q, 0] * N[r, 1] - N[q, 1] * N[r, 0]
                uu = ux * ux + uy * uy + uz * uz
                if uu > 1e-12:  # not opposite faces
                    d1 = N[q, 0] * X[q, 0] + N[q, 1] * X[q, 1] + N[q, 2] * X[q, 2]
                    d2 = N[r, 0] * X[r, 0] + N[r, 1] * X[r, 1] + N[r, 2] * X[r, 2]
                    # z0 on the line: d1 (n_r × u) + d2 (u × n_q), over |u|²
                    z0[0] = (d1 * (N[r, 1] * uz - N[r, 2] * uy) + d2 * (uy * N[q, 2] - uz * N[q, 1])) / uu
                    z0[1] = (d1 * (N[r, 2] * ux - N[r, 0] * uz) + d2 * (uz * N[q, 0] - ux * N[q, 2])) / uu
                    z0[2] = (d1 * (N[r, 0] * uy - N[r, 1] * ux) + d2 * (ux * N[q, 1] - uy * N[q, 0])) / uu
                    inv = 1.0 / math.sqrt(uu)
                    u[0], u[1], u[2] = ux * inv, uy * inv, uz * inv
                    sq = 0.0
                    sr = 0.0
                    for a in range(3):
                        sq += (X[q, a] - z0[a]) * u[a]
                        sr += (X[r, a] - z0[a]) * u[a]
                    aq = 0.0
                    ar = 0.0
                    chord = 0.0
                    for a in range(3):
                        aq += (X[q, a] - z0[a] - sq * u[a]) ** 2
                        ar += (X[r, a] - z0[a] - sr * u[a]) ** 2
                        chord += (X[q, a] - X[r, a]) ** 2
                    d2u = (math.sqrt(aq) + math.sqrt(ar)) ** 2 + (sq - sr) ** 2
                    h = 0.5 * (hq[q] + hq[r])
                    ex = math.exp(-max(d2u, chord) / (4.0 * h))
                    norm = 1.0 / (h * (4.0 * math.pi * h) ** half_k)
                    data[e] = W[r] * norm * (ex * (dogc * ex - 1.0) if dogc != 0.0 else ex)
        zero_row_sum(q, indptr, indices, data)


def _unfold(Lq: sp.csr_matrix, P: np.ndarray, tri: np.ndarray, X: np.ndarray, W: np.ndarray,
            crease_edges: np.ndarray, hq: np.ndarray, dim: int, dog: bool, radius: float,
            face: np.ndarray) -> sp.csr_matrix:
    n = np.cross(P[tri[:, 1]] - P[tri[:, 0]], P[tri[:, 2]] - P[tri[:, 0]])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    N = np.ascontiguousarray(n[face])
    # the quadrature points within the cut-off of a crease (its edges sampled 8 times each)
    s = np.linspace(0.0, 1.0, 9)[:, None, None]
    a, b = P[crease_edges[:, 0]], P[crease_edges[:, 1]]
    samples = ((1.0 - s) * a + s * b).reshape(-1, 3)
    dist, _ = KDTree(samples).query(np.ascontiguousarray(X), k=1, distance_upper_bound=radius)
    near = np.isfinite(dist)
    # in place: the caller's Lq is its own (a copy would double the peak memory)
    Lq = sp.csr_matrix(Lq, dtype=np.float64, copy=False)
    in_blocks(_unfold_rows, len(Lq.indptr) - 1, Lq.indptr, Lq.indices, Lq.data,
              np.ascontiguousarray(X, dtype=np.float64), N, W, near,
              np.ascontiguousarray(hq, dtype=np.float64), dog_factor(dim) if dog else 0.0, 0.5 * dim,
              math.cos(math.radians(CREASE_ANGLE)))
    return Lq


def _arc_coordinates(P: np.ndarray, seg: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    # each segment's curve, the arc length at its two ends along that curve, and each curve's
    # length if it is a loop (0 for a chain); None where a vertex joins more than two segments
    n = len(P)
    deg = np.bincount(seg.ravel(), minlength=n)
    if (deg > 2).any():
        return None
    length = np.linalg.norm(P[seg[:, 1]] - P[seg[:, 0]], axis=1)
    at = [[] for _ in range(n)]
    for e, (a, b) in enumerate(seg.tolist()):
        at[a].append(e)
        at[b].append(e)
    curve = np.full(len(seg), -1, dtype=np.int64)
    ends = np.zeros((len(seg), 2))
    loops = []
    # chains from an end first, then the loops from any vertex
    for v0 in np.r_[np.flatnonzero(deg == 1), np.flatnonzero(deg == 2)].tolist():
        if not at[v0] or curve[at[v0][0]] >= 0:
            continue
        c, v, s, e = len(loops), v0, 0.0, at[v0][0]
        while e >= 0 and curve[e] < 0:
            curve[e] = c
            w = seg[e, 1] if seg[e, 0] == v else seg[e, 0]
            ends[e] = (s, s + length[e]) if seg[e, 0] == v else (s + length[e], s)
            s += length[e]
            nxt = [f for f in at[w] if f != e]
            v, e = w, (nxt[0] if nxt else -1)
        loops.append(s if (e >= 0 and v == v0) else 0.0)
    return curve, ends, np.array(loops)


@jit()
def _arc_rows(start, stop, indptr, indices, data, curve, s, loop, W, h, dogc, norm):  # pragma: no cover
    # the kernel of the distance along the curve; points of different curves do not interact
    for q in range(start, stop):
        for e in range(indptr[q], indptr[q + 1]):
            r = indices[e]
            if r == q:
                continue
            if curve[q] != curve[r]:
                data[e] = 0.0
            else:
                d = abs(s[q] - s[r])
                c = loop[curve[q]]
                if c > 0.0 and c - d < d:
                    d = c - d
                ex = math.exp(-d * d / (4.0 * h))
                data[e] = W[r] * norm * (ex * (dogc * ex - 1.0) if dogc != 0.0 else ex)
        zero_row_sum(q, indptr, indices, data)


def _along_curves(Lq: sp.csr_matrix, P: np.ndarray, seg: np.ndarray, owner: np.ndarray, t: np.ndarray,
                  W: np.ndarray, h: float, dim: int, dog: bool) -> sp.csr_matrix:
    arc = _arc_coordinates(P, seg)
    if arc is None:  # branches: the chord
        return Lq
    curve, ends, loop = arc
    s = (1.0 - t) * ends[owner, 0] + t * ends[owner, 1]
    Lq = sp.csr_matrix(Lq, dtype=np.float64, copy=True)
    in_blocks(_arc_rows, len(Lq.indptr) - 1, Lq.indptr, Lq.indices, Lq.data, curve[owner], s, loop, W,
              float(h), dog_factor(dim) if dog else 0.0, 1.0 / (h * (4.0 * math.pi * h) ** (0.5 * dim)))
    return Lq


def _segment_points(P: np.ndarray, seg: np.ndarray, h: float) -> tuple:
    # each segment cut into pieces of at most SEGMENT_STEP·√h, two Gauss points on each
    length = np.linalg.norm(P[seg[:, 1]] - P[seg[:, 0]], axis=1)
    pieces = np.maximum(np.ceil(length / (SEGMENT_STEP * math.sqrt(h))), 1).astype(np.int64)
    first = np.repeat(np.cumsum(pieces) - pieces, pieces)
    which = np.repeat(np.arange(len(seg)), pieces)
    g = np.array(RULES[1][::-1])  # the two Gauss points of [0, 1]
    t = ((np.arange(pieces.sum()) - first)[:, None] + g[None, :]) / pieces[which][:, None]
    t = t.ravel()
    owner = np.repeat(which, 2)
    X = (1.0 - t)[:, None] * P[seg[owner, 0]] + t[:, None] * P[seg[owner, 1]]
    W = np.repeat(length[which] / pieces[which] / 2.0, 2)
    Phi = sp.csr_matrix((np.column_stack([1.0 - t, t]).ravel(), (np.repeat(np.arange(len(X)), 2),
                         seg[owner].ravel())), shape=(len(X), len(P)))
    return X, W, Phi, owner, t


def quadrature_points(P: np.ndarray, cells: np.ndarray, h: float | None = None
                      ) -> tuple[np.ndarray, np.ndarray, sp.csr_matrix]:
    """Points, weights and hat-function values of the degree-2 rule on every simplex.

    Parameters
    ----------
    P : (n, d) ndarray
        Vertex positions.
    cells : (c, k + 1) int ndarray
        Simplices: segments, triangles or tetrahedra.
    h : float, optional
        Kernel width. Segments are then cut into pieces of at most :data:`~meshlap.tuned.SEGMENT_STEP`·√h
        with two Gauss points on each (degree 3): a curve's points are cheap, and a random
        sampling's long segments would not resolve a narrow kernel with two points.

    Returns
    -------
    X : (q, d) ndarray
        Quadrature points, k + 1 per cell (per piece of a segment).
    W : (q,) ndarray
        Weights (the cell's k-volume shared equally).
    Phi : (q, n) scipy.sparse.csr_matrix
        φ_i(x_q): the barycentric coordinates of each point.

    Examples
    --------
    >>> import numpy as np
    >>> P = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> X, W, Phi = quadrature_points(P, np.array([[0, 1, 2]]))
    >>> X.shape, float(W.sum()), bool(np.allclose(Phi.sum(axis=1), 1))
    ((3, 3), 0.5, True)
    """
    cells = np.asarray(cells, dtype=np.int64)
    k = cells.shape[1] - 1
    if k not in RULES:
        raise MeshError(f"the Galerkin pencil needs segments, triangles or tetrahedra; got cells of {k + 1}")
    if k == 1 and h is not None:
        return _segment_points(np.asarray(P, dtype=np.float64), cells, float(h))[:3]
    a, b = RULES[k]
    B = np.full((k + 1, k + 1), b) + (a - b) * np.eye(k + 1)  # row q: the point near corner q
    X = np.einsum("qa,cad->cqd", B, P[cells]).reshape(-1, P.shape[1])
    W = np.repeat(simplex_volumes(P, cells) / (k + 1), k + 1)
    rows = np.repeat(np.arange(len(X)), k + 1)
    cols = np.repeat(cells, k + 1, axis=0).ravel()
    Phi = sp.csr_matrix((np.tile(B, (len(cells), 1)).ravel(), (rows, cols)), shape=(len(X), len(P)))
    return X, W, Phi


def _split_rule(s: int) -> np.ndarray:
    # the degree-2 rule on each of the s² triangles of the barycentric grid of step 1/s:
    # (3s², 3) barycentric coordinates in the parent, points grouped by small triangle
    a, b = RULES[2]
    B = np.full((3, 3), b) + (a - b) * np.eye(3)
    small = []
    for i in range(s):
        for j in range(s - i):
            small.append([[i, j], [i + 1, j], [i, j + 1]])
            if i + j < s - 1:
                small.append([[i + 1, j], [i + 1, j + 1], [i, j + 1]])
    ij = np.array(small, dtype=np.float64) / s  # (s², 3 corners, 2): weights of corners 1 and 2
    corners = np.concatenate([1.0 - ij.sum(axis=2, keepdims=True), ij], axis=2)
    return np.einsum("qa,tab->tqb", B, corners).reshape(-1, 3)


def split_points(P: np.ndarray, tri: np.ndarray, split: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, sp.csr_matrix, np.ndarray, np.ndarray]:
    """The degree-2 rule on every triangle t cut into split[t]² equal triangles.

    A narrow kernel needs more points than the 3 of :func:`quadrature_points` (3 points at
    h = ē²/4 lose 1% on the 4,000-vertex square); with ``split`` all 1 the points, weights
    and order are those of :func:`quadrature_points`.

    Parameters
    ----------
    P : (n, 3) ndarray
        Vertex positions.
    tri : (f, 3) int ndarray
        Triangles.
    split : (f,) int ndarray
        Cuts per edge of each triangle, at least 1.

    Returns
    -------
    X, W, Phi
        Points, weights and hat-function values, as :func:`quadrature_points`, the points of
        each triangle together and in triangle order.
    face : (q,) int ndarray
        The triangle of each point.
    corner : (q,) int ndarray
        The vertex of that triangle of largest weight at each point.

    Examples
    --------
    >>> import numpy as np
    >>> P = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> X, W, Phi, face, corner = split_points(P, np.array([[0, 1, 2]]), np.array([2]))
    >>> len(X), float(W.sum()), bool(np.allclose(Phi @ P, X))
    (12, 0.5, True)
    """
    tri = np.asarray(tri, dtype=np.int64)
    split = np.maximum(np.asarray(split, dtype=np.int64), 1)
    count = 3 * split**2
    first = np.cumsum(count) - count
    n = int(count.sum())
    X = np.empty((n, P.shape[1]))
    bary = np.empty((n, 3))
    face = np.repeat(np.arange(len(tri)), count)
    for s in np.unique(split).tolist():
        faces = np.flatnonzero(split == s)
        B = _split_rule(s)
        at = (first[faces][:, None] + np.arange(len(B))[None, :]).ravel()
        X[at] = np.einsum("qa,cad->cqd", B, P[tri[faces]]).reshape(-1, P.shape[1])
        bary[at] = np.tile(B, (len(faces), 1))
    W = (simplex_volumes(P, tri) / count)[face]
    corner = tri[face, np.argmax(bary, axis=1)]
    Phi = sp.csr_matrix((bary.ravel(), (np.repeat(np.arange(n), 3), tri[face].ravel())), shape=(n, len(P)))
    return X, W, Phi, face, corner


def _mass_congruence(S: sp.csr_matrix, Phi: sp.csr_matrix, W: np.ndarray) -> tuple[sp.csr_matrix, np.ndarray]:
    C = (Phi.T @ sp.diags(W) @ Phi).tocsr()
    m = np.asarray(C.sum(axis=1)).ravel()
    inv = np.divide(1.0, m, out=np.zeros_like(m), where=m > 0)
    B = sp.eye(len(m), format="csr") + 0.5 * (sp.eye(len(m)) - sp.diags(inv) @ C)
    out = (B.T @ S @ B).tocsr()
    return 0.5 * (out + out.T), m


def galerkin_pencil(P: np.ndarray, cells: np.ndarray, h: float, dim: int, *, dog: bool = True,
                    crease_edges: np.ndarray | None = None, boundary: tuple | None = None, tol: float = 1e-8,
                    guard: Any = None, info: dict | None = None, h_vertex: np.ndarray | None = None
                    ) -> tuple[sp.csr_matrix, np.ndarray]:
    """The Galerkin pencil ``(S, m)`` of the kernel of width ``h`` on the simplices ``cells``.

    Parameters
    ----------
    P : (n, d) ndarray
        Vertex positions.
    cells : (c, k + 1) int ndarray
        Segments, triangles or tetrahedra.
    h : float
        Kernel width.
    dim : int
        Intrinsic dimension k (the kernel's normalization).
    dog : bool, default True
        The Richardson kernel 2K_{h/2} − K_h; False: one Gaussian.
    crease_edges : (e, 2) int ndarray, optional
        Crease edges of a triangle mesh in R³ (:func:`creases`): a pair of quadrature points
        within the cut-off of one, whose faces' normals differ by more than
        :data:`~meshlap.tuned.CREASE_ANGLE`, gets the kernel of its distance along the two face planes
        unfolded about their line of intersection (the geodesic across a straight crease)
        instead of the chord.
    boundary : (samples, ν), optional
        Boundary samples and outward conormals (:mod:`meshlap.geometry.frames`): mirror images
        for Neumann spectra.
    tol : float, default 1e-8
        Kernel tolerance (its cut-off).
    guard : MemoryGuard, optional
        Called with the quadrature operator's entry count before it is allocated.
    h_vertex : (n,) ndarray, optional
        Per-vertex widths of a triangle mesh, at most ``h`` (:mod:`meshlap.corrections.features`):
        each quadrature point takes the hat-function interpolant of them and a pair the mean
        of its two points' widths, normalized per pair as in the assembly (so S stays
        symmetric with rows summing to zero); a triangle whose narrowest corner has width
        h/r is cut into ⌈√(:data:`~meshlap.tuned.SPLIT_BELOW`·r)⌉² triangles of 3 points each
        (:func:`split_points`).
    info : dict, optional
        Filled with ``"points"`` on a triangle mesh: the number of quadrature points.

    Returns
    -------
    S : scipy.sparse.csr_matrix
        Symmetric, rows summing to zero, negative semidefinite for a positive kernel.
    m : (n,) ndarray
        The lumped masses C·1 the pencil goes with (a third of the adjacent triangles' area).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(300, seed=0)
    >>> S, m = galerkin_pencil(V, F, 0.5 * 0.2**2, 2)
    >>> bool(abs(S - S.T).max() < 1e-12), bool(np.abs(S @ np.ones(300)).max() < 1e-9)
    (True, True)
    """
    cells = np.asarray(cells, dtype=np.int64)
    curve = cells.shape[1] == 2
    narrow = h_vertex is not None and cells.shape[1] == 3 and bool((np.asarray(h_vertex) < h).any())
    face = corner = None
    if curve:
        X, W, Phi, owner, t = _segment_points(np.asarray(P, dtype=np.float64), cells, float(h))
    elif narrow:
        hv = np.minimum(np.asarray(h_vertex, dtype=np.float64), h)
        split = np.ceil(np.sqrt(SPLIT_BELOW * h / hv[cells].min(axis=1)) - 1e-9).astype(np.int64)
        X, W, Phi, face, corner = split_points(P, cells, split)
    else:
        X, W, Phi = quadrature_points(P, cells)
    if cells.shape[1] == 3 and face is None:
        face, corner = np.repeat(np.arange(len(cells)), 3), cells.ravel()
    hq = Phi @ hv if narrow else np.full(len(X), float(h))
    widths = Widths(float(h), hq if narrow else None, False)
    Lq = assemble(X, W, widths, Kernel(dim, dog=dog, tol=tol), guard=guard)
    if curve:
        Lq = _along_curves(Lq, P, cells, owner, t, W, h, dim, dog)
    if crease_edges is not None and len(crease_edges):
        Lq = _unfold(Lq, P, cells, X, W, crease_edges, hq, dim, dog, cutoff_radius(h, tol), face)
    if cells.shape[1] == 3:
        Lq, _ = drop_shortcuts(Lq, P, cells, X, cutoff_radius(h, tol), face=face, corner=corner, copy=False)
        if info is not None:
            info["points"] = len(X)
    if boundary is not None:
        samples, nu = boundary
        fr = frames_mod.frames_from_samples(X, samples, nu, cutoff_radius(h, tol))
        Lq = neumann_images(Lq, X, fr, W, hq, dog, dim)
    WP = sp.diags(W) @ Phi
    S = (WP.T @ Lq @ Phi).tocsr()
    return _mass_congruence(0.5 * (S + S.T), Phi, W)


def simplices(geo: Any) -> np.ndarray | None:
    """The geometry's cells as simplices of k + 1 corners (a triangle mesh's faces, a curve's
    segments, tetrahedra), or None when it has none (clouds, polygons other than triangles)."""
    faces = getattr(geo, "faces", None)
    if faces is not None:
        return faces.indices.reshape(-1, 3) if (faces.n_faces and (faces.sizes == 3).all()) else None
    cells = getattr(geo, "cells", None)
    if cells is not None and getattr(geo, "source", None) in ("polyline", "tetrahedra") \
            and cells.shape[1] == geo.dim + 1:
        return np.asarray(cells, dtype=np.int64)
    return None


def _face_pairs(P: np.ndarray, tri: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    # unit face normals, and for every interior edge its two faces and its two vertices
    n = np.cross(P[tri[:, 1]] - P[tri[:, 0]], P[tri[:, 2]] - P[tri[:, 0]])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    sides = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    face = np.tile(np.arange(len(tri)), 3)
    key = sides[:, 0] * np.int64(len(P)) + sides[:, 1]
    order = np.argsort(key, kind="stable")
    pair = np.flatnonzero(key[order][1:] == key[order][:-1])
    return n, face[order][pair], face[order][pair + 1], sides[order][pair]


def creases(P: np.ndarray, tri: np.ndarray, angle: float = CREASE_ANGLE, concave: bool = False) -> np.ndarray:
    """The edges (vertex pairs) of a triangle mesh in R³ whose faces meet at more than
    ``angle`` degrees between their normals; ``concave``: only those where the surface folds
    towards the outside (grooves: a face's far corner lies on the side its neighbour's normal
    points to, outward by the sign of the enclosed volume).

    Examples
    --------
    >>> import meshlap
    >>> V, F = meshlap.shapes.sphere(500, seed=0)
    >>> creases(V, F).shape
    (0, 2)
    """
    n, f1, f2, edges = _face_pairs(P, tri)
    sharp = (n[f1] * n[f2]).sum(axis=1) < math.cos(math.radians(angle))
    if concave:
        outward = np.sign(np.einsum("ij,ij->", P[tri[:, 0]], np.cross(P[tri[:, 1]], P[tri[:, 2]]))) or 1.0
        far = tri[f2].sum(axis=1) - edges.sum(axis=1)  # the corner of f2 off the edge
        sharp &= outward * (n[f1] * (P[far] - P[edges[:, 0]])).sum(axis=1) > 0
    return edges[sharp]


def shape_measures(P: np.ndarray, tri: np.ndarray) -> tuple[float, float]:
    """``(largest dihedral angle in degrees, roughness)`` of a triangle mesh in R³.

    The roughness is the median squared change of the face normal across an edge over the
    same after the normals are averaged twice over each face and its edge neighbours: about
    1 where the normals vary smoothly (1.1-1.6 on the spheres and the torus of
    benchmarks/bench_spectra.py), ten and more where they are noise (11 on the sphere with
    0.5% radial noise), 0 on a flat mesh.

    Examples
    --------
    >>> import meshlap
    >>> V, F = meshlap.shapes.sphere(500, seed=0)
    >>> angle, rough = shape_measures(V, F)
    >>> bool(angle < 15), bool(rough < 2)
    (True, True)
    """
    n, f1, f2, _ = _face_pairs(P, tri)
    if not len(f1):
        return 0.0, 0.0
    angle = float(np.degrees(np.arccos(np.clip((n[f1] * n[f2]).sum(axis=1), -1.0, 1.0))).max())
    A = sp.csr_matrix((np.ones(2 * len(f1)), (np.r_[f1, f2], np.r_[f2, f1])), shape=(len(tri),) * 2)
    A = A + sp.eye(len(tri), format="csr")
    avg = n
    for _ in range(2):
        avg = A @ avg
        avg /= np.maximum(np.linalg.norm(avg, axis=1, keepdims=True), 1e-300)
    raw = float(np.median(((n[f1] - n[f2]) ** 2).sum(axis=1)))
    smooth = float(np.median(((avg[f1] - avg[f2]) ** 2).sum(axis=1)))
    if smooth <= 1e-24:
        return angle, 0.0 if raw <= 1e-24 else math.inf
    return angle, raw / smooth

