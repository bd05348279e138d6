"""Pairs the kernel would couple through the air: close in space, far along the surface.

Across a narrow groove, a thin wall or a concave fold, two points can lie within the kernel's
reach while the shortest path between them along the surface is several times longer; the
heat on the surface does not jump the gap, so such a pair must not interact. Here the path
along the mesh (the shortest path over its edges, from the corner nearest each point) decides:
a pair whose path is longer than :data:`~meshlap.tuned.SHORTCUT_RATIO` times its chord, plus the
two cells' longest edges (a point's distance to its corner, and the edge path's own detour), is dropped.
The edge path overestimates the geodesic by about 15% (median on fandisk); the slack keeps
the pairs of a smooth coarse surface (on the 600-vertex torus 1.6% of the area loses a pair,
and its error stays 0.95%). Pairs across a 90° crease can reach the ratio (23% of the cube
surface's area loses one), where the crease's unfolded distance already gave them little
weight: its error stays 0.043%. What dropping cannot mend, parts whose two sides are within a
few kernel widths (spot's teats, ears and horns), the width narrows for
(:mod:`meshlap.corrections.features`).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from .._jit import in_blocks, jit
from .._paths import bounded_paths
from ..assembly._intrinsics import zero_row_sum
from ..tuned import SHORTCUT_RATIO

__all__ = ["drop_shortcuts"]


@jit()
def _drop_rows(start, stop, vptr, vpts, adj_ptr, adj, adj_len, indptr, indices, data, corner, X, slack,
               ratio, limit, n, hit):  # pragma: no cover
    dist = np.full(n, np.inf)
    seen = np.empty(n, dtype=np.int64)
    for a in range(start, stop):
        if vptr[a] == vptr[a + 1]:
            continue
        # the shortest paths from a along the edges, up to limit
        count = bounded_paths(a, limit, adj_ptr, adj, adj_len, dist, seen)
        for i in range(vptr[a], vptr[a + 1]):
            q = vpts[i]
            for e in range(indptr[q], indptr[q + 1]):
                r = indices[e]
                if r == q:
                    continue
                chord = 0.0
                for c in range(X.shape[1]):
                    chord += (X[q, c] - X[r, c]) ** 2
                if data[e] != 0.0 and dist[corner[r]] > ratio * math.sqrt(chord) + slack[q] + slack[r]:
                    data[e] = 0.0
                    hit[q] = True
            zero_row_sum(q, indptr, indices, data)
        for j in range(count):
            dist[seen[j]] = np.inf


def drop_shortcuts(Lq: sp.csr_matrix, P: np.ndarray, tri: np.ndarray, X: np.ndarray, radius: float,
                   ratio: float | None = None, face: np.ndarray | None = None,
                   corner: np.ndarray | None = None, copy: bool = True) -> tuple[sp.csr_matrix, np.ndarray]:
    """The kernel operator on the quadrature points of a triangle mesh without its short cuts.

    Parameters
    ----------
    Lq : scipy.sparse.csr_matrix
        Kernel operator on the points ``X``, three per triangle, point 3t + j nearest corner
        ``tri[t, j]`` (:func:`meshlap.corrections.galerkin.quadrature_points`).
    P : (n, 3) ndarray
        Vertex positions.
    tri : (f, 3) int ndarray
        Triangles.
    X : (3f, 3) ndarray
        Quadrature points.
    radius : float
        The kernel's cut-off: no pair is farther apart.
    ratio : float, optional
        The path over the chord beyond which a pair is dropped;
        :data:`~meshlap.tuned.SHORTCUT_RATIO` by default.
    face, corner : (q,) int ndarray, optional
        Each point's triangle and its vertex of largest weight at the point, for points other than
        three per triangle (:func:`meshlap.corrections.galerkin.split_points`).
    copy : bool, default True
        False: change a float64 ``Lq`` in place (each row reads only its own entries), one
        operator less in memory.

    Returns
    -------
    Lq : scipy.sparse.csr_matrix
        The short cuts' entries zero, rows summing to zero again (a copy unless ``copy=False``).
    hit : (3f,) bool ndarray
        The points that lost a pair.

    Examples
    --------
    >>> import meshlap, scipy.sparse as sp
    >>> from meshlap.corrections.galerkin import quadrature_points
    >>> V, F = meshlap.shapes.plane(400, seed=0, kind="stratified")   # flat: nothing to drop
    >>> X, W, _ = quadrature_points(V, F)
    >>> width = meshlap.widths.Widths(0.005, None, False)
    >>> Lq = meshlap.assembly.assemble(X, W, width, meshlap.assembly.Kernel(2))
    >>> int(drop_shortcuts(Lq, V, F, X, meshlap.assembly.cutoff_radius(0.005, 1e-8))[1].sum())
    0
    """
    ratio = SHORTCUT_RATIO if ratio is None else float(ratio)
    tri = np.asarray(tri, dtype=np.int64)
    n = len(P)
    sides = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    longest = np.linalg.norm(P[sides[:, 0]] - P[sides[:, 1]], axis=1).reshape(3, -1).max(axis=0)
    edges = np.unique(np.sort(sides, axis=1), axis=0)
    length = np.linalg.norm(P[edges[:, 0]] - P[edges[:, 1]], axis=1)
    both = np.r_[edges, edges[:, ::-1]]
    A = sp.csr_matrix((np.r_[length, length], (both[:, 0], both[:, 1])), shape=(n, n))
    if corner is None:
        face, corner = np.repeat(np.arange(len(tri)), 3), tri.ravel()
    corner = np.ascontiguousarray(corner, dtype=np.int64)
    order = np.argsort(corner, kind="stable")
    vptr = np.r_[0, np.cumsum(np.bincount(corner, minlength=n))].astype(np.int64)
    slack = longest[face]
    limit = ratio * radius + 2.0 * float(longest.max())
    out = sp.csr_matrix(Lq, dtype=np.float64, copy=copy)
    hit = np.zeros(len(X), dtype=np.bool_)
    in_blocks(_drop_rows, n, vptr, order.astype(np.int64), A.indptr.astype(np.int64),
              A.indices.astype(np.int64), A.data, out.indptr, out.indices, out.data, corner,
              np.ascontiguousarray(X, dtype=np.float64), slack, float(ratio), float(limit), n, hit)
    return out, hit

