"""Gaussian neighbourhoods: the cut-off radius, a uniform cell grid, and the parallel kernels
that assemble L straight into CSR or apply it without storing it.

The heat kernel exp(-|p-w|^2 / 4h) is dropped where it falls below ``tol``, that is beyond

    r = sqrt(4 h ln(1/tol)).

Points with positive mass (the only ones that contribute to a sum) are binned into cubic
cells of side about r/2; a row visits the cells whose box lies within r of its vertex.
Assembly is two passes over the rows, count then fill, so the CSR arrays are allocated once
at their final size, and every row is written by one thread in a fixed order: the result
does not depend on the number of threads.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numba import njit, prange

__all__ = ["cutoff_radius", "Grid", "build_grid"]

# Cells per cut-off radius: 2 keeps the visited volume close to the ball (box pruning
# removes the corner cells) without many empty cells.
_CELLS_PER_RADIUS = 2
# Cap on the number of cells, so that a tiny h on a large mesh cannot allocate a huge grid.
_MAX_CELLS_PER_POINT = 8


def cutoff_radius(h: float, tol: float) -> float:
    """Distance beyond which exp(-d²/4h) < tol: r = sqrt(4h·ln(1/tol)); inf for tol = 0.

    Examples
    --------
    >>> round(cutoff_radius(0.01, 1e-8), 4)
    0.8584
    """
    if tol == 0:
        return math.inf
    return math.sqrt(4.0 * h * math.log(1.0 / tol))


@dataclass
class Grid:
    """Source points (positive mass) binned by cell, and target rows sorted by cell."""

    src_points: np.ndarray  # (ns, 3) float64, sorted by cell
    src_mass: np.ndarray  # (ns,) float64
    src_index: np.ndarray  # (ns,) int64, original vertex index
    cell_start: np.ndarray  # (n_cells + 1,) int64
    dims: np.ndarray  # (3,) int64
    lo: np.ndarray  # (3,) float64, grid origin
    cell: float  # cell side
    radius: float
    full: bool  # every row sees every source (untruncated operator)
    tgt_order: np.ndarray  # (n,) int64, targets sorted by cell for locality


def build_grid(V: np.ndarray, mass: np.ndarray, radius: float) -> Grid:
    """Bin the vertices with positive mass into a cell grid for a search radius."""
    src = np.flatnonzero(mass > 0)
    P = V[src] if len(src) else V[:1]
    lo = P.min(axis=0)
    extent = P.max(axis=0) - lo
    full = not math.isfinite(radius)
    if full:
        dims = np.ones(3, dtype=np.int64)
        cell = 1.0
    else:
        cell = max(radius / _CELLS_PER_RADIUS, 1e-300)
        max_cells = max(_MAX_CELLS_PER_POINT * len(src), 1024)
        while True:
            dims = np.floor(extent / cell).astype(np.int64) + 1
            if np.prod(dims.astype(np.float64)) <= max_cells:
                break
            cell *= 1.26  # about 2^(1/3): halves the cell count
    src_cell = _cell_ids(V[src], lo, cell, dims) if len(src) else np.zeros(0, np.int64)
    order = np.argsort(src_cell, kind="stable")
    n_cells = int(np.prod(dims))
    counts = np.bincount(src_cell, minlength=n_cells)
    cell_start = np.zeros(n_cells + 1, dtype=np.int64)
    np.cumsum(counts, out=cell_start[1:])
    tgt_order = np.argsort(_cell_ids(V, lo, cell, dims), kind="stable")
    return Grid(
        src_points=np.ascontiguousarray(V[src][order]),
        src_mass=np.ascontiguousarray(mass[src][order]),
        src_index=np.ascontiguousarray(src[order].astype(np.int64)),
        cell_start=cell_start,
        dims=dims,
        lo=lo.astype(np.float64),
        cell=float(cell),
        radius=float(radius),
        full=full,
        tgt_order=tgt_order.astype(np.int64),
    )


def _cell_ids(P: np.ndarray, lo: np.ndarray, cell: float, dims: np.ndarray) -> np.ndarray:
    ijk = np.floor((P - lo) / cell).astype(np.int64)
    np.clip(ijk, 0, dims - 1, out=ijk)
    return (ijk[:, 0] * dims[1] + ijk[:, 1]) * dims[2] + ijk[:, 2]


@njit(cache=True, inline="always")
def _cell_range(x, lo, cell, r, dim, full):
    if full:
        return 0, dim - 1
    a = int(math.floor((x - r - lo) / cell))
    b = int(math.floor((x + r - lo) / cell))
    return max(a, 0), min(b, dim - 1)


@njit(cache=True, inline="always")
def _gap(x, lo, cell, a):
    # distance along one axis from x to the slab [lo + a*cell, lo + (a+1)*cell]
    left = lo + a * cell
    if x < left:
        return left - x
    right = left + cell
    if x > right:
        return x - right
    return 0.0


@njit(cache=True, parallel=True)
def _count_rows(rows, V, P, cell_start, dims, lo, cell, r, full, self_index, counts):
    r2 = r * r
    for k in prange(len(rows)):
        w = rows[k]
        x, y, z = V[w, 0], V[w, 1], V[w, 2]
        a0, a1 = _cell_range(x, lo[0], cell, r, dims[0], full)
        b0, b1 = _cell_range(y, lo[1], cell, r, dims[1], full)
        c0, c1 = _cell_range(z, lo[2], cell, r, dims[2], full)
        cnt = 1  # the diagonal entry
        for a in range(a0, a1 + 1):
            gx = 0.0 if full else _gap(x, lo[0], cell, a)
            for b in range(b0, b1 + 1):
                gy = 0.0 if full else _gap(y, lo[1], cell, b)
                if gx * gx + gy * gy > r2:
                    continue
                for c in range(c0, c1 + 1):
                    gz = 0.0 if full else _gap(z, lo[2], cell, c)
                    if gx * gx + gy * gy + gz * gz > r2:
                        continue
                    cid = (a * dims[1] + b) * dims[2] + c
                    for j in range(cell_start[cid], cell_start[cid + 1]):
                        dx = P[j, 0] - x
                        dy = P[j, 1] - y
                        dz = P[j, 2] - z
                        if dx * dx + dy * dy + dz * dz <= r2 and self_index[j] != w:
                            cnt += 1
        counts[k] = cnt


@njit(cache=True, parallel=True)
def _fill_rows(rows, V, P, m, src_index, cell_start, dims, lo, cell, r, full, inv4h, coef,
               indptr, indices, data):
    r2 = r * r
    for k in prange(len(rows)):
        w = rows[k]
        x, y, z = V[w, 0], V[w, 1], V[w, 2]
        a0, a1 = _cell_range(x, lo[0], cell, r, dims[0], full)
        b0, b1 = _cell_range(y, lo[1], cell, r, dims[1], full)
        c0, c1 = _cell_range(z, lo[2], cell, r, dims[2], full)
        start = indptr[w]
        pos = start + 1  # slot `start` holds the diagonal
        acc = 0.0
        for a in range(a0, a1 + 1):
            gx = 0.0 if full else _gap(x, lo[0], cell, a)
            for b in range(b0, b1 + 1):
                gy = 0.0 if full else _gap(y, lo[1], cell, b)
                if gx * gx + gy * gy > r2:
                    continue
                for c in range(c0, c1 + 1):
                    gz = 0.0 if full else _gap(z, lo[2], cell, c)
                    if gx * gx + gy * gy + gz * gz > r2:
                        continue
                    cid = (a * dims[1] + b) * dims[2] + c
                    for j in range(cell_start[cid], cell_start[cid + 1]):
                        dx = P[j, 0] - x
                        dy = P[j, 1] - y
                        dz = P[j, 2] - z
                        d2 = dx * dx + dy * dy + dz * dz
                        if d2 <= r2 and src_index[j] != w:
                            v = coef * math.exp(-d2 * inv4h) * m[j]
                            indices[pos] = src_index[j]
                            data[pos] = v
                            acc += v
                            pos += 1
        indices[start] = w
        data[start] = -acc


@njit(cache=True, parallel=True)
def _apply_rows(rows, V, P, m, src_index, cell_start, dims, lo, cell, r, full, inv4h, coef,
                f, out):
    # out[w] = coef * sum_p K_wp m_p (f_p - f_w), for a block f of shape (n, k)
    r2 = r * r
    nk = f.shape[1]
    for k in prange(len(rows)):
        w = rows[k]
        x, y, z = V[w, 0], V[w, 1], V[w, 2]
        a0, a1 = _cell_range(x, lo[0], cell, r, dims[0], full)
        b0, b1 = _cell_range(y, lo[1], cell, r, dims[1], full)
        c0, c1 = _cell_range(z, lo[2], cell, r, dims[2], full)
        acc = np.zeros(nk)
        wsum = 0.0
        for a in range(a0, a1 + 1):
            gx = 0.0 if full else _gap(x, lo[0], cell, a)
            for b in range(b0, b1 + 1):
                gy = 0.0 if full else _gap(y, lo[1], cell, b)
                if gx * gx + gy * gy > r2:
                    continue
                for c in range(c0, c1 + 1):
                    gz = 0.0 if full else _gap(z, lo[2], cell, c)
                    if gx * gx + gy * gy + gz * gz > r2:
                        continue
                    cid = (a * dims[1] + b) * dims[2] + c
                    for j in range(cell_start[cid], cell_start[cid + 1]):
                        dx = P[j, 0] - x
                        dy = P[j, 1] - y
                        dz = P[j, 2] - z
                        d2 = dx * dx + dy * dy + dz * dz
                        if d2 <= r2:
                            wt = math.exp(-d2 * inv4h) * m[j]
                            wsum += wt
                            p = src_index[j]
                            for q in range(nk):
                                acc[q] += wt * f[p, q]
        for q in range(nk):
            out[w, q] = coef * (acc[q] - wsum * f[w, q])


def _chunks(order: np.ndarray, n_chunks: int) -> list[np.ndarray]:
    return [c for c in np.array_split(order, n_chunks) if len(c)]


def _n_chunks(n: int, progress: Callable[[float], None] | None) -> int:
    # Chunks only exist to report progress between compiled calls.
    return 1 if progress is None else max(1, min(100, n // 2000))


def count_entries(V: np.ndarray, grid: Grid, rows: np.ndarray | None = None,
                  progress: Callable[[float], None] | None = None) -> np.ndarray:
    """Stored entries (diagonal included) of each row in ``rows`` (default: all, by vertex)."""
    args = (grid.src_points, grid.cell_start, grid.dims, grid.lo, grid.cell, grid.radius,
            grid.full, grid.src_index)
    if rows is not None:
        counts = np.empty(len(rows), dtype=np.int64)
        _count_rows(np.asarray(rows, np.int64), V, *args, counts)
        return counts
    counts = np.empty(len(V), dtype=np.int64)
    done = 0
    for chunk in _chunks(grid.tgt_order, _n_chunks(len(V), progress)):
        tmp = np.empty(len(chunk), dtype=np.int64)
        _count_rows(chunk, V, *args, tmp)
        counts[chunk] = tmp
        done += len(chunk)
        if progress is not None:
            progress(done / len(V))
    return counts


def fill_csr(V: np.ndarray, grid: Grid, h: float, indptr: np.ndarray, index_dtype, value_dtype,
             progress: Callable[[float], None] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Fill the CSR ``indices`` and ``data`` of L for the row pointer from :func:`count_entries`."""
    nnz = int(indptr[-1])
    indices = np.empty(nnz, dtype=index_dtype)
    data = np.empty(nnz, dtype=value_dtype)
    coef = 1.0 / (4.0 * math.pi * h * h)
    done = 0
    for chunk in _chunks(grid.tgt_order, _n_chunks(len(V), progress)):
        _fill_rows(chunk, V, grid.src_points, grid.src_mass, grid.src_index, grid.cell_start,
                   grid.dims, grid.lo, grid.cell, grid.radius, grid.full, 1.0 / (4.0 * h), coef,
                   indptr, indices, data)
        done += len(chunk)
        if progress is not None:
            progress(done / len(V))
    return indices, data


def apply(V: np.ndarray, grid: Grid, h: float, f: np.ndarray) -> np.ndarray:
    """L @ f without storing L; ``f`` of shape (n,) or (n, k)."""
    vec = f.ndim == 1
    f2 = np.ascontiguousarray(f.reshape(len(f), -1), dtype=np.float64)
    out = np.empty_like(f2)
    _apply_rows(grid.tgt_order, V, grid.src_points, grid.src_mass, grid.src_index,
                grid.cell_start, grid.dims, grid.lo, grid.cell, grid.radius, grid.full,
                1.0 / (4.0 * h), 1.0 / (4.0 * math.pi * h * h), f2, out)
    return out[:, 0] if vec else out
