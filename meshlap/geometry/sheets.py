"""Star triangles that join two sheets of a point cloud's surface across the air.

Where a surface comes closer to itself than its sampling (a limb against a body, the two walls
of a thin shell), a point's local Delaunay star can take a neighbour from the other sheet, and the
FEM pencil on the stars then glues the sheets: every eigenvalue goes up. Such an edge is seldom in
both of its ends' stars, and the edges that both ends' stars do hold join its ends only by a long
way round (over the fold, or not at all). :func:`bridges` finds those edges and drops their
triangles from the stiffness, but never so as to cut the cloud into more pieces than its stars
had (a part the sampling joins by such edges alone stays joined).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from .._jit import in_blocks, jit
from .._keys import in_set, key_set
from .._paths import bounded_paths
from ..tuned import SHEET_DETOUR

__all__ = ["bridges"]


@jit()
def _far(start, stop, src, ptr, other, length, adj_ptr, adj, adj_len, ratio, n, far):  # pragma: no cover
    # far[e] <- whether the paths over (adj_ptr, adj, adj_len) from src[i] reach other[e] only
    # beyond ratio * length[e], for the edges ptr[i]:ptr[i + 1]; Dijkstra bounded by the longest
    dist = np.full(n, np.inf)
    seen = np.empty(n, dtype=np.int64)
    for i in range(start, stop):
        a = src[i]
        limit = 0.0
        for e in range(ptr[i], ptr[i + 1]):
            limit = max(limit, ratio * length[e])
        count = bounded_paths(a, limit, adj_ptr, adj, adj_len, dist, seen)
        for e in range(ptr[i], ptr[i + 1]):
            far[e] = dist[other[e]] > ratio * length[e]
        for j in range(count):
            dist[seen[j]] = np.inf


def _edge_keys(a: np.ndarray, b: np.ndarray, n: int) -> np.ndarray:
    return a.astype(np.int64) * n + b


def _components(triangles: np.ndarray, n: int) -> np.ndarray:
    i = np.r_[triangles[:, 0], triangles[:, 1]]
    j = np.r_[triangles[:, 1], triangles[:, 2]]
    return connected_components(sp.coo_matrix((np.ones(len(i)), (i, j)), shape=(n, n)), directed=False)[1]


def bridges(stars: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Which rows of ``stars`` (every point's own star triangles, its centre first) join two sheets.

    An edge held by the stars of both its ends is agreed; any other edge whose ends the agreed
    edges join by no path shorter than :data:`meshlap.tuned.SHEET_DETOUR` times its length
    bridges two sheets, and so does every star triangle that has such an edge, unless dropping
    them would cut the stars into more pieces: those that span two pieces stay.

    Parameters
    ----------
    stars : (m, 3) int array
        Star triangles, a point's centre first (most triangles come once from each corner).
    X : (n, d) array
        The points.

    Returns
    -------
    (m,) bool ndarray
        The triangles to leave out of the stiffness (their corners keep their masses).

    Examples
    --------
    A strip folded over at its end, its two sheets 0.5 apart, and a star that takes a point of the
    other sheet: its triangle goes.

    >>> import numpy as np
    >>> x = np.arange(6.0)
    >>> X = np.vstack([np.c_[x, 0 * x, 0 * x], np.c_[x, 0 * x + 1, 0 * x],
    ...                np.c_[x, 0 * x, 0 * x + 0.5], np.c_[x, 0 * x + 1, 0 * x + 0.5]])
    >>> quads = [(a, a + 1, a + 7) for a in range(5)] + [(a, a + 7, a + 6) for a in range(5)]
    >>> fold = [(5, 17, 23), (5, 23, 11)]
    >>> T = np.array(quads + [(a + 12, b + 12, c + 12) for a, b, c in quads] + fold)
    >>> stars = np.vstack([np.roll(T, -s, axis=1) for s in range(3)])  # each from every corner
    >>> glue = np.array([[3, 4, 15]])  # point 3's star reaches across to the other sheet
    >>> bridges(np.vstack([stars, glue]), X).nonzero()[0].tolist()
    [66]
    """
    n = len(X)
    if not len(stars):
        return np.zeros(0, dtype=bool)
    own = key_set(_edge_keys(np.r_[stars[:, 0], stars[:, 0]], np.r_[stars[:, 1], stars[:, 2]], n))
    s = np.sort(stars, axis=1)
    sides = [(s[:, 0], s[:, 1]), (s[:, 1], s[:, 2]), (s[:, 0], s[:, 2])]
    keys = [_edge_keys(a, b, n) for a, b in sides]
    edges = key_set(np.concatenate(keys))
    a, b = edges // n, edges % n
    agreed = in_set(edges, own, of_sorted=True) & in_set(_edge_keys(b, a, n), own, of_sorted=True)
    length = np.linalg.norm(X[a] - X[b], axis=1)
    graph = sp.coo_matrix((length[agreed], (a[agreed], b[agreed])), shape=(n, n))
    graph = (graph + graph.T).tocsr()
    ask = np.flatnonzero(~agreed)  # sorted by a, as edges are
    if not len(ask):
        return np.zeros(len(stars), dtype=bool)
    first = np.flatnonzero(np.r_[True, a[ask][1:] != a[ask][:-1]])
    src, ptr = a[ask][first], np.append(first, len(ask)).astype(np.int64)
    hit = np.zeros(len(ask), dtype=bool)
    in_blocks(_far, len(src), src, ptr, b[ask], length[ask], graph.indptr.astype(np.int64),
              graph.indices.astype(np.int64), graph.data, SHEET_DETOUR, n, hit)
    far = np.zeros(len(edges), dtype=bool)
    far[ask] = hit
    if not far.any():
        return np.zeros(len(stars), dtype=bool)
    drop = np.zeros(len(stars), dtype=bool)
    for k in keys:
        drop |= far[np.searchsorted(edges, k)]
    for _ in range(len(stars)):  # each pass keeps the triangles that join two pieces of the rest
        label = _components(stars[~drop], n)
        corner = label[stars]
        span = drop & ((corner[:, 0] != corner[:, 1]) | (corner[:, 1] != corner[:, 2]))
        if not span.any():
            break
        drop &= ~span
    return drop
