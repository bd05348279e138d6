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
    a sphere, K = 64, in a third of the k-d tree's CPU (0.029 s against 0.092 s at a load of
    2); else the k-d tree.

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

    def query(self, Q: np.ndarray, K: int, place: np.ndarray | None = None,
              columns: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(dist, idx), each (len(Q), K), idx 32-bit where the points number fewer than 2³¹:
        the K nearest points of each query point, searched
        cell by cell, or by the k-d tree in the order of ``place`` (a spatial order of the
        queries: consecutive ones then walk the same nodes, 6% less CPU at 16,000 points and
        19% at 100,000). With ``columns`` (ranks from 0), dist is (len(Q), len(columns)) and
        holds those neighbours' distances only (a caller that reads a few of them need not hold
        them all: 180 MB at 400,000 points and K = 64)."""
        Q = np.ascontiguousarray(Q, dtype=np.float64)
        grid = self._grid(K) if 1 <= K <= len(self.D) and self.D.shape[1] <= 3 else None
        cols = np.arange(K) if columns is None else np.asarray(columns, dtype=np.int64)
        # 32-bit indices where they fit (the fits read them as they are: 100 MB less at 400,000
        # points and K = 64)
        index = np.int32 if len(self.D) < 2**31 - 1 else np.int64
        dist, idx = np.empty((len(Q), len(cols))), np.empty((len(Q), K), dtype=index)
        if grid is None:
            order = np.arange(len(Q)) if place is None else np.argsort(place, kind="stable")
            d, i = self.tree.query(Q[order], k=K, workers=-1)
            dist[order], idx[order] = np.reshape(d, (len(Q), K))[:, cols], np.reshape(i, (len(Q), K))
            return dist, idx
        lo, width, dims, first, members, by_cell = grid
        order = np.argsort(_keys(Q, lo, 1.0 / width, dims), kind="stable")  # cell by cell
        in_blocks(_grid_nearest, len(Q), order, by_cell, Q, K, lo, width, dims, first, members, cols, dist,
                  idx)
        return dist, idx


def _keys(X: np.ndarray, lo: np.ndarray, inv: float, dims: np.ndarray) -> np.ndarray:
    # each point's cell, row-major
    c = np.clip(np.floor((X - lo) * inv).astype(np.int64), 0, dims - 1)
    return np.ravel_multi_index(tuple(c.T), tuple(dims.tolist()))


@jit(error_model="numpy")
def _grid_nearest(start, stop, order, D, Q, K, lo, width, dims, first, members, cols, dist,
                  idx):  # pragma: no cover - compiled
    # Nearest.query on its grid (D: the points by cell, D[m] = the point members[m]): the rings
    # of cells at Chebyshev distance s = 0, 1, ... until the K-th best is no farther than the
    # block of cells seen. The points of the rings before K are seen are gathered as they come
    # (cd, ci) and sorted at once (_sort_best: inserting each into a sorted list, the old way,
    # cost twice the CPU); after that, a point nearer than the K-th best is inserted into the
    # sorted K (hd, hi), a few a query. Squared distances summed as scipy's k-d tree sums them
    d = D.shape[1]
    # a fixed buffer (growing it in the loop made the kernel 3x slower): once full, its K best
    # are sorted and the rest inserted
    cap = 4 * K + 64
    cd, hd = np.empty(cap), np.empty(cap)
    ci, hi = np.empty(cap, dtype=np.int64), np.empty(cap, dtype=np.int64)
    nb = np.empty(3 * cap + 1, dtype=np.int64)  # _sort_best's bucket counts, then each entry's bucket
    # the grid as three axes (a missing one a single cell): the block's cells by three loops
    c3, n3, q3 = np.zeros(3, dtype=np.int64), np.ones(3, dtype=np.int64), np.zeros(3)
    l3 = np.zeros(3)
    for a in range(d):
        n3[a], l3[a] = dims[a], lo[a]
    inv = 1.0 / width
    slack = 1e-9 * width  # a point's cell from rounded arithmetic: its slab, widened by this
    for o in range(start, stop):
        r = order[o]
        for a in range(d):
            q3[a] = Q[r, a]
            c = int(math.floor((Q[r, a] - lo[a]) * inv))
            c3[a] = min(max(c, 0), dims[a] - 1)
        nc = 0  # points gathered, while fewer than K are known
        count = 0  # the K best, sorted, once known
        s = 0
        while True:
            for x in range(max(-s, -c3[0]), min(s, n3[0] - 1 - c3[0]) + 1):
                gx = _gap(l3[0] + (c3[0] + x) * width, width, slack, q3[0])
                for y in range(max(-s, -c3[1]), min(s, n3[1] - 1 - c3[1]) + 1):
                    gy = gx + _gap(l3[1] + (c3[1] + y) * width, width, slack, q3[1])
                    z0, z1 = max(-s, -c3[2]), min(s, n3[2] - 1 - c3[2])
                    edge = abs(x) == s or abs(y) == s
                    row = ((c3[0] + x) * n3[1] + c3[1] + y) * n3[2] + c3[2]
                    # a row of the ring: one run of cells in z, their points contiguous (one
                    # range for up to 2s + 1 cells, most of them empty on a surface); a row
                    # inside the block: its two ends
                    for k in range(1 if edge else 2):
                        za, zb = z0, z1
                        if not edge:
                            za = zb = s if k else -s
                            if za < z0 or za > z1:
                                continue
                        f0, f1 = first[row + za], first[row + zb + 1]
                        if f0 == f1:
                            continue
                        # a run farther than the K-th best is skipped
                        gz = _gap(l3[2] + (c3[2] + za) * width, (zb - za + 1) * width, slack, q3[2])
                        if count == K and gy + gz > hd[K - 1]:
                            continue
                        for m in range(f0, f1):
                            p = members[m]
                            if d == 3:  # unrolled: the same sum, 5% less CPU
                                t0, t1, t2 = q3[0] - D[m, 0], q3[1] - D[m, 1], q3[2] - D[m, 2]
                                s2 = t0 * t0 + t1 * t1 + t2 * t2
                            else:
                                s2 = 0.0
                                for a in range(d):
                                    t = q3[a] - D[m, a]
                                    s2 += t * t
                            if count < K:
                                cd[nc] = s2
                                ci[nc] = p
                                nc += 1
                                if nc == len(cd):  # a full buffer: its K best, the rest inserted
                                    _sort_best(cd, ci, nc, K, hd, hi, nb)
                                    count = K
                            elif s2 < hd[K - 1] or (s2 == hd[K - 1] and p < hi[K - 1]):
                                _place(hd, hi, K - 1, s2, p)
            if count < K and nc >= K:
                _sort_best(cd, ci, nc, K, hd, hi, nb)
                count = K
            # no unseen point is nearer than the block's faces (those inside the grid)
            bound = np.inf
            for a in range(d):
                if c3[a] - s > 0:
                    bound = min(bound, q3[a] - (lo[a] + (c3[a] - s) * width))
                if c3[a] + s < dims[a] - 1:
                    bound = min(bound, lo[a] + (c3[a] + s + 1) * width - q3[a])
            if bound == np.inf or (count == K and hd[K - 1] <= (bound - slack) ** 2):
                break
            s += 1
        for m in range(K):
            idx[r, m] = hi[m]
        for c in range(len(cols)):
            dist[r, c] = math.sqrt(hd[cols[c]])


@jit()
def _gap(edge, width, slack, q):  # pragma: no cover - compiled
    # squared distance from q to the slab [edge, edge + width] of a cell, widened by slack
    t = max(edge - slack - q, q - edge - width - slack, 0.0)
    return t * t


@jit()
def _place(hd, hi, j, s2, p):  # pragma: no cover - compiled
    # (s2, p) into the sorted hd[:j], hi[:j] (the entry at j dropped): past the farther ones,
    # then past the as far ones of larger index (one test a step, not two: 3-4% less CPU)
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


@jit()
def _sort_best(cd, ci, nc, K, hd, hi, nb):  # pragma: no cover - compiled
    # the K least (cd, ci) of the nc gathered into hd, hi, sorted by (distance², index): first
    # a counting sort into 2 nc buckets of distance² (equal widths: on a surface, about as many
    # points in each; nc buckets cost 6% more CPU, a plain insertion sort 60%), then an
    # insertion sort that moves each entry past few others. Only the buckets up to the K-th
    # are kept: their entries are not farther than any others. Each entry's bucket kept (cb):
    # 7% less CPU than computing it twice
    top = 0.0
    for i in range(nc):
        top = max(top, cd[i])
    scale = 2 * nc / top if top > 0 else 0.0
    cb = nb[2 * nc + 1:]
    nb[:2 * nc + 1] = 0
    for i in range(nc):
        x = cd[i] * scale
        b = int(x) if x < 2 * nc - 1 else 2 * nc - 1  # a NaN in the last bucket, not out of bounds
        cb[i] = b
        nb[b + 1] += 1
    # the buckets up to the one holding the K-th
    last, total = 0, nb[1]
    while total < K:
        last += 1
        total += nb[last + 1]
    for b in range(last + 1):
        nb[b + 1] += nb[b]
    for i in range(nc):
        b = cb[i]
        if b <= last:
            hd[nb[b]] = cd[i]
            hi[nb[b]] = ci[i]
            nb[b] += 1
    for i in range(1, total):
        _place(hd, hi, i, hd[i], hi[i])


def _nearest(near: Nearest, P: np.ndarray, K: int, centers: np.ndarray, place: np.ndarray,
             columns: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    # the K nearest points of P[centers], in the centres' order (place: each point's place in a
    # spatial order; columns: the distances kept, Nearest.query)
    dist, idx = near.query(P[centers], K, place[centers], columns)
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
