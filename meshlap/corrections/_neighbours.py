"""Neighbourhoods of the point-wise rows: the K nearest points of each centre (:class:`Nearest`),
and the wide stencils held by a random subset of the points (:class:`_Spread`)."""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from .._jit import in_blocks, jit

# Points per occupied cell of the grid, per neighbour asked for: the K nearest then lie within
# two rings of cells (on a surface), about 3K candidates
_PER_CELL = 1 / 8
# Most cells per point the grid may have (its index array), else scipy's k-d tree
_MAX_CELLS = 16


def _distinct(a: np.ndarray) -> int:
    # how many distinct values: a sort, where np.unique's hash path (numpy 2.4) is ~50x slower
    s = np.sort(a)
    return int(len(s) > 0) + int(np.count_nonzero(s[1:] != s[:-1]))


class Nearest:
    """The K nearest of ``D``'s points to query points, as ``scipy.spatial.cKDTree.query`` gives
    them (the same distances, ascending; ties ordered by index, where the tree's order of ties
    may differ).

    Where the points fill a grid of cubes evenly enough (at most :data:`_MAX_CELLS` cubes per
    point with about K/8 points in each occupied one), compiled code searches the cubes ring by
    ring around each query until no unseen point can be nearer than the K-th: 16,000 points of
    a sphere, K = 64, in 55-75% of the k-d tree's CPU (0.071-0.09 s against 0.11-0.16 s at a
    load of 7-8); else the k-d tree.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> P = meshlap.shapes.fibonacci_sphere(2000)
    >>> d, i = Nearest(P).query(P[:5], 64)
    >>> d0, i0 = cKDTree(P).query(P[:5], 64)
    >>> bool(np.array_equal(d, d0) and np.array_equal(i, i0))
    True
    """

    def __init__(self, D: np.ndarray, tree: cKDTree | None = None) -> None:
        self.D = np.ascontiguousarray(D, dtype=np.float64)
        self._tree, self._grids = tree, {}

    @property
    def tree(self) -> cKDTree:
        if self._tree is None:
            self._tree = cKDTree(self.D)
        return self._tree

    def _grid(self, K: int) -> tuple | None:
        # (lo, cell width, cells per axis, each cell's first member, members by cell, their
        # positions in that order: a cell's points contiguous in memory) with about K/8 points
        # per occupied cell, or None where the points do not fill one evenly
        target = max(2.0, K * _PER_CELL)
        key = int(round(math.log2(target)))
        if key in self._grids:
            return self._grids[key]
        D = self.D
        n, d = D.shape
        lo, hi = D.min(axis=0), D.max(axis=0)
        ext = hi - lo
        width = float(ext.max()) / max(n, 1) ** (1 / d) if n else 0.0
        grid = None
        for _ in range(4):  # the occupancy grows as width^k on a k-dimensional set: k = 2 assumed
            if not width > 0:
                break
            dims = np.floor(ext / width).astype(np.int64) + 1
            if float(np.prod(dims.astype(np.float64))) > _MAX_CELLS * n:
                break
            cells = _keys(D, lo, 1.0 / width, dims)
            occupied = _distinct(cells)
            per = n / occupied
            grid = (lo, width, dims, cells)
            if target / 2 <= per <= target * 2:
                break
            width *= math.sqrt(target / per)
            grid = None
        if grid is not None:
            lo, width, dims, cells = grid
            members = np.argsort(cells, kind="stable")
            # 32-bit offsets where they fit: up to 16 cells a point (1,000,000 sphere points: 8 M)
            first = np.zeros(int(np.prod(dims)) + 1, dtype=np.int32 if n < 2**31 - 1 else np.int64)
            np.cumsum(np.bincount(cells, minlength=len(first) - 1), out=first[1:])
            grid = (lo, width, dims, first, members, np.ascontiguousarray(D[members]))
        self._grids[key] = grid
        return grid

    def query(self, Q: np.ndarray, K: int, place: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(dist, idx), each (len(Q), K): the K nearest points of each query point, searched
        cell by cell, or by the k-d tree in the order of ``place`` (a spatial order of the
        queries: consecutive ones then walk the same nodes, 6% less CPU at 16,000 points and
        19% at 100,000)."""
        Q = np.ascontiguousarray(Q, dtype=np.float64)
        grid = self._grid(K) if 1 <= K <= len(self.D) and self.D.shape[1] <= 3 else None
        dist, idx = np.empty((len(Q), K)), np.empty((len(Q), K), dtype=np.int64)
        if grid is None:
            order = np.arange(len(Q)) if place is None else np.argsort(place, kind="stable")
            d, i = self.tree.query(Q[order], k=K, workers=-1)
            dist[order], idx[order] = np.reshape(d, (len(Q), K)), np.reshape(i, (len(Q), K))
            return dist, idx
        lo, width, dims, first, members, by_cell = grid
        order = np.argsort(_keys(Q, lo, 1.0 / width, dims), kind="stable")  # cell by cell
        in_blocks(_grid_nearest, len(Q), order, by_cell, Q, K, lo, width, dims, first, members, dist, idx)
        return dist, idx


def _keys(X: np.ndarray, lo: np.ndarray, inv: float, dims: np.ndarray) -> np.ndarray:
    # each point's cell, row-major
    c = np.clip(np.floor((X - lo) * inv).astype(np.int64), 0, dims - 1)
    return np.ravel_multi_index(tuple(c.T), tuple(dims.tolist()))


@jit(error_model="numpy")
def _grid_nearest(start, stop, order, D, Q, K, lo, width, dims, first, members, dist,
                  idx):  # pragma: no cover - compiled
    # Nearest.query on its grid (D: the points by cell, D[m] = the point members[m]): the K best
    # (squared distance, index) so far kept sorted, the rings of cells at Chebyshev distance
    # s = 0, 1, ... until the K-th best is no farther than the block of cells seen; squared
    # distances summed as scipy's k-d tree sums them
    d = D.shape[1]
    hd = np.empty(K)
    hi = np.empty(K, dtype=np.int64)
    cell = np.empty(d, dtype=np.int64)
    off = np.empty(d, dtype=np.int64)
    inv = 1.0 / width
    slack = 1e-9 * width  # a point's cell from rounded arithmetic: its slab, widened by this
    for o in range(start, stop):
        r = order[o]
        for a in range(d):
            c = int(math.floor((Q[r, a] - lo[a]) * inv))
            cell[a] = min(max(c, 0), dims[a] - 1)
        count = 0
        s = 0
        while True:
            # the cells of ring s: an odometer over the block, the inner cells skipped
            for a in range(d):
                off[a] = -s
            while True:
                ring = False
                inside = True
                lin = 0
                for a in range(d):
                    if off[a] == s or off[a] == -s:
                        ring = True
                    ca = cell[a] + off[a]
                    if ca < 0 or ca >= dims[a]:
                        inside = False
                    lin = lin * dims[a] + ca
                if ring and inside and count == K:  # a cell farther than the K-th best is skipped
                    gap = 0.0
                    for a in range(d):
                        edge = lo[a] + (cell[a] + off[a]) * width
                        t = max(edge - slack - Q[r, a], Q[r, a] - edge - width - slack, 0.0)
                        gap += t * t
                    inside = gap <= hd[K - 1]
                if ring and inside:
                    for m in range(first[lin], first[lin + 1]):
                        p = members[m]
                        s2 = 0.0
                        for a in range(d):
                            t = Q[r, a] - D[m, a]
                            s2 += t * t
                        if count == K and not (s2 < hd[K - 1] or (s2 == hd[K - 1] and p < hi[K - 1])):
                            continue
                        # insertion into the sorted list (the last one drops out when full): past
                        # the farther ones, then past the as far ones of larger index (one test a
                        # step, not two: 3-4% less CPU)
                        j = count if count < K else K - 1
                        while j > 0 and hd[j - 1] > s2:
                            hd[j] = hd[j - 1]
                            hi[j] = hi[j - 1]
                            j -= 1
                        while j > 0 and hd[j - 1] == s2 and hi[j - 1] > p:
                            hd[j] = hd[j - 1]
                            hi[j] = hi[j - 1]
                            j -= 1
                        hd[j] = s2
                        hi[j] = p
                        if count < K:
                            count += 1
                a = d - 1
                while a >= 0 and off[a] == s:
                    off[a] = -s
                    a -= 1
                if a < 0:
                    break
                off[a] += 1
            # no unseen point is nearer than the block's faces (those inside the grid)
            bound = np.inf
            for a in range(d):
                if cell[a] - s > 0:
                    bound = min(bound, Q[r, a] - (lo[a] + (cell[a] - s) * width))
                if cell[a] + s < dims[a] - 1:
                    bound = min(bound, lo[a] + (cell[a] + s + 1) * width - Q[r, a])
            if bound == np.inf or (count == K and hd[K - 1] <= (bound - slack) ** 2):
                break
            s += 1
        for m in range(K):
            dist[r, m] = math.sqrt(hd[m])
            idx[r, m] = hi[m]


def _nearest(near: Nearest, P: np.ndarray, K: int, centers: np.ndarray, place: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
    # the K nearest points of P[centers], in the centres' order (place: each point's place in a
    # spatial order, Nearest.query)
    dist, idx = near.query(P[centers], K, place[centers])
    return idx, dist


class _Spread:
    """Neighbourhoods as wide as the K nearest points, held by at most ``sample`` of them.

    A wide row averages noise; its bias is set by its width, its noise factor by the number
    of points it holds, which falls only as the square root. So beyond ``sample`` neighbours
    a stencil takes its points from a random subset of the cloud, n·sample/K of its points
    (nested subsets, one fixed permutation), whose ``sample`` nearest reach as far as the K
    nearest of the whole cloud; the centre is always among them. The cost of a row then
    stays that of ``sample`` neighbours however wide it is.
    """

    def __init__(self, P: np.ndarray, tree: cKDTree, sample: int, ids: np.ndarray | None = None,
                 n: int | None = None) -> None:
        # ids, n: the points' global ids among n in all (one rank's share of them), so that
        # every rank draws the same subsets
        self.P, self.near, self.sample = P, Nearest(P, tree), sample
        self.n = len(P) if n is None else int(n)
        order = np.random.default_rng(0).permutation(self.n)
        rank = np.empty(self.n, dtype=np.int64)
        rank[order] = np.arange(self.n)
        self.rank = rank if ids is None else rank[ids]  # each point's place in the permutation
        self.trees: dict[int, tuple[np.ndarray, Nearest]] = {}
        self.place = np.empty(len(P), dtype=np.int64)  # each point's place in the tree's order
        self.place[tree.indices] = np.arange(len(P))

    def __call__(self, K: int, centers: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
        n, S = self.n, self.sample
        if K <= 1.25 * S or n <= 2 * S:
            K = min(K, len(self.P))
            idx, dist = _nearest(self.near, self.P, K, centers, self.place)
            return idx, dist, K
        m = max(S + 1, int(math.ceil(n * S / K)))
        if m not in self.trees:
            sub = np.flatnonzero(self.rank < m)
            self.trees[m] = (sub, Nearest(self.P[sub]))
        sub, tree = self.trees[m]
        S = min(S, len(sub))
        loc, dist = _nearest(tree, self.P, S, centers, self.place)
        idx = sub[loc]
        inside = idx[:, 0] == centers  # the centre is in the subset: its own nearest
        out_i = np.where(inside[:, None], idx, np.column_stack([centers, idx[:, :-1]]))
        out_d = np.where(inside[:, None], dist, np.column_stack([np.zeros(len(centers)), dist[:, :-1]]))
        return out_i, out_d, S
