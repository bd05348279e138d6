"""Shortest paths over a graph's edges from one vertex, up to a length: a compiled Dijkstra that
touches only what it reaches, for the tests that ask whether two close points are far apart
along a surface (:mod:`meshlap.corrections.shortcuts`, :mod:`meshlap.geometry.sheets`)."""

from __future__ import annotations

import heapq

import numpy as np

from ._jit import jit

__all__ = ["bounded_paths"]


@jit()
def bounded_paths(a, limit, adj_ptr, adj, adj_len, dist, seen):  # pragma: no cover
    """Set ``dist[v]`` to the shortest path length from ``a`` over the CSR graph ``(adj_ptr, adj,
    adj_len)`` for every v it reaches within ``limit`` (``dist`` is all inf before; the caller
    resets the reached ones after), list them in ``seen`` and return their count.

    Examples
    --------
    >>> import numpy as np
    >>> ptr, adj, w = np.array([0, 1, 3, 4]), np.array([1, 0, 2, 1]), np.array([1.0, 1.0, 2.0, 2.0])
    >>> dist, seen = np.full(3, np.inf), np.zeros(3, dtype=np.int64)
    >>> bounded_paths(0, 2.5, ptr, adj, w, dist, seen), dist.tolist()
    (2, [0.0, 1.0, inf])
    """
    count = 1
    dist[a] = 0.0
    seen[0] = a
    heap = [(0.0, a)]
    while len(heap) > 0:
        d, v = heapq.heappop(heap)
        if d > dist[v]:
            continue
        for e in range(adj_ptr[v], adj_ptr[v + 1]):
            w = adj[e]
            nd = d + adj_len[e]
            if nd < dist[w] and nd <= limit:
                if dist[w] == np.inf:
                    seen[count] = w
                    count += 1
                dist[w] = nd
                heapq.heappush(heap, (nd, w))
    return count
