"""Gaussian neighbourhoods: the cut-off radius, a uniform cell grid, and the parallel kernels
that assemble L straight into CSR or apply it without storing it.

The heat kernel exp(-|p-w|^2 / 4h) is dropped where it falls below ``tol``, that is beyond

    r = sqrt(4 h ln(1/tol)).

Points with positive mass (the only ones that contribute to a sum) are binned into cubic
cells of side about r/3 and stored sorted by cell and, inside a cell, by z, coordinates in
separate arrays. Cells that share (x, y) indices are consecutive in that order, so each
(x, y) column is sorted by z and a row visits a short list of contiguous ranges: for each
column near its vertex, the points inside the z window that r leaves at the column's
distance in x and y, found by bisection.

Assembly is two passes over the rows, count then fill, so the CSR arrays are allocated once
at their final size. A row of the fill pass first gathers (source, d²) of the accepted
points into a small per-thread buffer, then evaluates the kernel in a branch-free loop that
the compiler vectorizes (the exponential is a polynomial with range reduction, accurate to
about an ulp, since libm's exp does not vectorize). Threads take chunks of rows from a shared
atomic counter, which balances uneven meshes and busy machines; every row is still written by
one thread in a fixed order, so the result does not depend on the number of threads or on
the schedule.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._jit import each_thread, jit
from ..geometry.validation import check_function
from ._intrinsics import _exp_neg, _fetch_add

__all__ = ["cutoff_radius", "normalization", "Grid", "build_grid", "count_entries", "fill_csr", "apply"]

# Cells per cut-off radius. Finer columns hug the disc of radius r better (candidates per
# accepted neighbour on a surface: 1.86 with 2, 1.56 with 3, 1.40 with 4) but cost more
# ranges per row; 3 is best or near it from ~300 to ~3,000 entries per row.
_CELLS_PER_RADIUS = 3
# Cap on the number of cells, so that a tiny h on a large mesh cannot allocate a huge grid.
_MAX_CELLS_PER_POINT = 8
# Rows per task handed out by the atomic counter: small enough to balance, large enough
# that the counter is not contended.
_CHUNK_ROWS = 32
# Progress callbacks come between compiled calls; each call covers at least this many
# entries, so that reporting does not cost measurable time.
_PROGRESS_ENTRIES = 20_000_000


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


def normalization(h: float, dim: int = 2) -> float:
    """The kernel's factor 1/(h (4πh)^{k/2}) for intrinsic dimension k (1/(4πh²) on surfaces).

    Belkin, Sun and Wang, "Constructing Laplace operator from point clouds in R^d" (SODA 2009):
    with it, Σ_p m_p exp(-|p-w|²/4h) (f(p) - f(w)) tends to Δf(w) on a k-manifold.

    Examples
    --------
    >>> import math
    >>> normalization(0.01, 1) == 1 / (0.01 * math.sqrt(4 * math.pi * 0.01))
    True
    """
    if dim == 2:  # the surface case, rounded exactly as before
        return 1.0 / (4.0 * math.pi * h * h)
    return 1.0 / (h * (4.0 * math.pi * h) ** (0.5 * dim))


def truncation_bound(op: Any, f: np.ndarray) -> np.ndarray:
    """Per-vertex bound on |L_exact f - L_tol f| = tol·A·max_p|f(p)-f(w)| / (h (4πh)^{k/2}).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(300, seed=0)
    >>> op = meshlap.laplacian(V, F, h=0.02, correction="none")
    >>> bool(truncation_bound(op, V[:, 0]).max() < 1e-4)   # tol · area · spread / (4πh²) = 5e-5
    True
    """
    f = check_function(f, op.n_vertices)
    spread = np.maximum(np.abs(f.max(axis=0) - f), np.abs(f - f.min(axis=0)))
    return op.tol * op.mass.sum() * spread * normalization(op.h, op.dim)


@dataclass
class Grid:
    """Source points (positive mass) binned by cell, and target rows sorted by cell."""

    xs: np.ndarray  # (ns,) float64 source coordinates, sorted by cell
    ys: np.ndarray
    zs: np.ndarray
    src_mass: np.ndarray  # (ns,) float64
    src_index: np.ndarray  # (ns,) int64, original vertex index
    self_slot: np.ndarray  # (n,) int64, position of each vertex among the sources or -1
    cell_start: np.ndarray  # (n_cells + 1,) int64
    dims: np.ndarray  # (3,) int64
    lo: np.ndarray  # (3,) float64, grid origin
    cell: float  # cell side
    radius: float
    full: bool  # every row sees every source (untruncated operator)
    tgt_order: np.ndarray  # (n,) int64, targets sorted by cell for locality
    max_columns: int  # bound on the (x, y) columns one row visits

    @property
    def n_sources(self) -> int:
        return len(self.xs)


def build_grid(V: np.ndarray, mass: np.ndarray, radius: float) -> Grid:
    """Bin the vertices with positive mass into a cell grid for a search radius.

    Examples
    --------
    >>> import numpy as np
    >>> g = build_grid(np.eye(3), np.array([1.0, 0.0, 1.0]), 0.5)
    >>> g.n_sources, g.self_slot.tolist()
    (2, [1, -1, 0])
    """
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
    # by cell, then by z inside a cell: each (x, y) column is then sorted by z, and a row
    # finds its exact z window by bisection
    order = np.lexsort((V[src, 2], src_cell)) if len(src) else np.zeros(0, np.int64)
    n_cells = int(np.prod(dims))
    counts = np.bincount(src_cell, minlength=n_cells)
    cell_start = np.zeros(n_cells + 1, dtype=np.int64)
    np.cumsum(counts, out=cell_start[1:])
    tgt_order = np.argsort(_cell_ids(V, lo, cell, dims), kind="stable")
    sorted_src = src[order].astype(np.int64)
    self_slot = np.full(len(V), -1, dtype=np.int64)
    self_slot[sorted_src] = np.arange(len(sorted_src))
    if full:
        max_columns = 1
    else:
        span = int(min(2 * radius * (1.0 + 1e-7) / cell + 2, 1 << 40))  # the search radius of _columns
        max_columns = int(min(dims[0], span) * min(dims[1], span))
    P = V[sorted_src]
    return Grid(
        xs=np.ascontiguousarray(P[:, 0]),
        ys=np.ascontiguousarray(P[:, 1]),
        zs=np.ascontiguousarray(P[:, 2]),
        src_mass=np.ascontiguousarray(mass[sorted_src], dtype=np.float64),
        src_index=sorted_src,
        self_slot=self_slot,
        cell_start=cell_start,
        dims=dims,
        lo=lo.astype(np.float64),
        cell=float(cell),
        radius=float(radius),
        full=full,
        tgt_order=tgt_order.astype(np.int64),
        max_columns=max_columns,
    )


def _cell_ids(P: np.ndarray, lo: np.ndarray, cell: float, dims: np.ndarray) -> np.ndarray:
    ijk = np.floor((P - lo) / cell).astype(np.int64)
    np.clip(ijk, 0, dims - 1, out=ijk)
    return (ijk[:, 0] * dims[1] + ijk[:, 1]) * dims[2] + ijk[:, 2]


@jit(inline="always")
def _axis_range(x, lo, cell, r, dim):
    # cells [a, b] along one axis that intersect [x - r, x + r]; clamped in floating point
    # first so that a huge r cannot overflow the integer conversion
    a = max(math.floor((x - r - lo) / cell), 0.0)
    b = min(math.floor((x + r - lo) / cell), dim - 1.0)
    return int(a), int(b)


@jit(inline="always")
def _gap(x, lo, cell, a):
    # distance along one axis from x to the slab [lo + a*cell, lo + (a+1)*cell]
    left = lo + a * cell
    if x < left:
        return left - x
    right = left + cell
    if x > right:
        return x - right
    return 0.0


@jit(inline="always")
def _lower_bound(zs, lo, hi, v):
    # first j in [lo, hi) with zs[j] >= v (zs sorted there), hi if none
    while lo < hi:
        mid = (lo + hi) >> 1
        if zs[mid] < v:
            lo = mid + 1
        else:
            hi = mid
    return lo


@jit(inline="always")
def _columns(x, y, z, zs, cell_start, dims, lo, cell, r, full, cols):
    # Source ranges [cols[i, 0], cols[i, 1]) that hold every point within r of (x, y, z):
    # per (x, y) column, the points whose z lies within the window that r leaves there.
    if full:
        cols[0, 0] = 0
        cols[0, 1] = cell_start[len(cell_start) - 1]
        return 1
    # A slightly larger radius for the search, so that rounding in the cell and window
    # bounds can never drop a pair that the exact test d² <= r² keeps (then both (w, p) and
    # (p, w) are stored or neither is, and S stays exactly symmetric).
    rs = r * (1.0 + 1e-7)
    r2 = rs * rs
    a0, a1 = _axis_range(x, lo[0], cell, rs, dims[0])
    b0, b1 = _axis_range(y, lo[1], cell, rs, dims[1])
    n = 0
    for a in range(a0, a1 + 1):
        gx = _gap(x, lo[0], cell, a)
        for b in range(b0, b1 + 1):
            gy = _gap(y, lo[1], cell, b)
            rest = r2 - gx * gx - gy * gy
            if rest < 0.0:
                continue
            rz = math.sqrt(rest)
            c0, c1 = _axis_range(z, lo[2], cell, rz, dims[2])
            if c0 > c1:
                continue
            base = (a * dims[1] + b) * dims[2]
            # each end of the window lies in its own end cell: a point of a cell above c0 has
            # z > z - rz, one of a cell below c1 has z <= z + rz (the cell of a z is floor((z -
            # lo)/cell), here and in build_grid, monotone in z), so each bisection searches one
            # cell, not the column: the same window, the paper's count and fill 7-17% faster
            # (16k sphere)
            j0 = _lower_bound(zs, cell_start[base + c0], cell_start[base + c0 + 1], z - rz)
            j1 = _lower_bound(zs, max(j0, cell_start[base + c1]), cell_start[base + c1 + 1],
                              math.nextafter(z + rz, math.inf))
            if j1 > j0:
                cols[n, 0] = j0
                cols[n, 1] = j1
                n += 1
    return n


@jit(inline="always")
def _gather(x, y, z, sw, xs, ys, zs, r2, cols, ncols, sj, sd):
    # Compact the sources within r (other than slot sw) into sj (slot) and sd (d²), in
    # column order; branch-free: every candidate is written, the position only advances
    # for accepted ones. Returns their number. The source index is unsigned: numba guards a
    # signed index against negative values (Python's wraparound) at every load, and with that
    # select the compiler loaded the candidates' coordinates by gathers (vgatherqpd);
    # unsigned, by contiguous vector loads (as in variable._count_var, branch i20k)
    pos = 0
    for i in range(ncols):
        for j in range(np.uint64(cols[i, 0]), np.uint64(cols[i, 1])):
            dx = xs[j] - x
            dy = ys[j] - y
            dz = zs[j] - z
            d2 = dx * dx + dy * dy + dz * dz
            sj[pos] = j
            sd[pos] = d2
            pos += np.int64((d2 <= r2) & (np.int64(j) != sw))
    return pos


@jit(inline="always")
def _candidates(cols, ncols):
    total = 0
    for i in range(ncols):
        total += cols[i, 1] - cols[i, 0]
    return total


@jit(inline="always")
def _weights(sj, sd, sm, m, cnt, inv4h, scale):
    # sd[i] <- scale * m_j * exp(-d²/4h). The masses are gathered first: with the indirect
    # load in it the kernel loop would not vectorize.
    for i in range(cnt):
        sm[i] = m[sj[i]]
    for i in range(cnt):
        sd[i] = scale * sm[i] * _exp_neg(-sd[i] * inv4h)


@jit(inline="always")
def _sum(v, first, cnt):
    # v[first:first + cnt] in four interleaved partial sums: a fixed order, but not one long
    # chain of dependent additions
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    i = first
    end = first + cnt
    while i + 4 <= end:
        s0 += v[i]
        s1 += v[i + 1]
        s2 += v[i + 2]
        s3 += v[i + 3]
        i += 4
    while i < end:
        s0 += v[i]
        i += 1
    return (s0 + s1) + (s2 + s3)


@jit(inline="always")
def _dot_diff(wt, sj, fq, fw, cnt):
    # sum_i wt[i] * (fq[sj[i]] - fw), in four interleaved partial sums like _sum
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    i = 0
    while i + 4 <= cnt:
        s0 += wt[i] * (fq[sj[i]] - fw)
        s1 += wt[i + 1] * (fq[sj[i + 1]] - fw)
        s2 += wt[i + 2] * (fq[sj[i + 2]] - fw)
        s3 += wt[i + 3] * (fq[sj[i + 3]] - fw)
        i += 4
    while i < cnt:
        s0 += wt[i] * (fq[sj[i]] - fw)
        i += 1
    return (s0 + s1) + (s2 + s3)


# -- the parallel passes -------------------------------------------------------------------
@jit()
def _count_rows(next_chunk, rows, V, xs, ys, zs, self_slot, cell_start, dims, lo, cell, r, full,
                max_columns, chunk, counts, by_vertex):
    # one thread's share (each_thread), like the other passes: chunks of rows from the counter
    n_rows = len(rows)
    n_chunks = (n_rows + chunk - 1) // chunk
    r2 = r * r
    cols = np.empty((max_columns, 2), dtype=np.int64)
    while True:
        c = _fetch_add(next_chunk, 0, 1)
        if c >= n_chunks:
            break
        for k in range(c * chunk, min((c + 1) * chunk, n_rows)):
            w = rows[k]
            x, y, z = V[w, 0], V[w, 1], V[w, 2]
            ncols = _columns(x, y, z, zs, cell_start, dims, lo, cell, r, full, cols)
            cnt = 0
            for i in range(ncols):
                for j in range(np.uint64(cols[i, 0]), np.uint64(cols[i, 1])):  # unsigned: see _gather
                    dx = xs[j] - x
                    dy = ys[j] - y
                    dz = zs[j] - z
                    cnt += np.int64(dx * dx + dy * dy + dz * dz <= r2)
            # the diagonal takes the place of the vertex itself when it is a source
            cnt += np.int64(self_slot[w] < 0)
            counts[w if by_vertex else k] = cnt


@jit()
def _fill_rows(next_chunk, rows, V, xs, ys, zs, m, src_index, self_slot, cell_start, dims, lo, cell, r,
               full, max_columns, chunk, inv4h, coef, indptr, indices, data, status):
    n_rows = len(rows)
    n_chunks = (n_rows + chunk - 1) // chunk
    r2 = r * r
    cols = np.empty((max_columns, 2), dtype=np.int64)
    sj = np.empty(1024, dtype=np.int64)
    sd = np.empty(1024, dtype=np.float64)
    sm = np.empty(1024, dtype=np.float64)
    while True:
        c = _fetch_add(next_chunk, 0, 1)
        if c >= n_chunks:
            break
        for k in range(c * chunk, min((c + 1) * chunk, n_rows)):
            w = rows[k]
            x, y, z = V[w, 0], V[w, 1], V[w, 2]
            ncols = _columns(x, y, z, zs, cell_start, dims, lo, cell, r, full, cols)
            need = _candidates(cols, ncols)
            if need > len(sj):
                sj = np.empty(2 * need, dtype=np.int64)
                sd = np.empty(2 * need, dtype=np.float64)
                sm = np.empty(2 * need, dtype=np.float64)
            cnt = _gather(x, y, z, self_slot[w], xs, ys, zs, r2, cols, ncols, sj, sd)
            start = indptr[w]
            if cnt != indptr[w + 1] - start - 1:
                status[0] = 1  # the count pass disagrees: never write past the row
                cnt = min(cnt, indptr[w + 1] - start - 1)
            first = start + 1
            for i in range(cnt):
                j = sj[i]
                sm[i] = m[j]
                indices[first + i] = src_index[j]
            for i in range(cnt):  # vectorized: no indirect access
                data[first + i] = coef * sm[i] * _exp_neg(-sd[i] * inv4h)
            indices[start] = w
            data[start] = -_sum(data, first, cnt)


@jit()
def _apply_rows(next_chunk, rows, V, xs, ys, zs, m, self_slot, cell_start, dims, lo, cell, r, full,
                max_columns, chunk, inv4h, coef, fs, f, out):
    # out[w] = coef * sum_p K_wp m_p (f_p - f_w); fs holds f in source order, one row per
    # column of f, so that each column's gather runs over contiguous memory
    n_rows = len(rows)
    n_chunks = (n_rows + chunk - 1) // chunk
    r2 = r * r
    nk = f.shape[1]
    cols = np.empty((max_columns, 2), dtype=np.int64)
    sj = np.empty(1024, dtype=np.int64)
    sd = np.empty(1024, dtype=np.float64)
    sm = np.empty(1024, dtype=np.float64)
    while True:
        c = _fetch_add(next_chunk, 0, 1)
        if c >= n_chunks:
            break
        for k in range(c * chunk, min((c + 1) * chunk, n_rows)):
            w = rows[k]
            x, y, z = V[w, 0], V[w, 1], V[w, 2]
            ncols = _columns(x, y, z, zs, cell_start, dims, lo, cell, r, full, cols)
            need = _candidates(cols, ncols)
            if need > len(sj):
                sj = np.empty(2 * need, dtype=np.int64)
                sd = np.empty(2 * need, dtype=np.float64)
                sm = np.empty(2 * need, dtype=np.float64)
            cnt = _gather(x, y, z, self_slot[w], xs, ys, zs, r2, cols, ncols, sj, sd)
            _weights(sj, sd, sm, m, cnt, inv4h, 1.0)
            for q in range(nk):
                out[w, q] = coef * _dot_diff(sd, sj, fs[q], f[w, q], cnt)


# -- drivers -------------------------------------------------------------------------------
def _row_blocks(grid: Grid, entries_per_row: float, progress) -> list[tuple[int, int]]:
    # One block without progress; otherwise blocks of about _PROGRESS_ENTRIES entries.
    n = len(grid.tgt_order)
    if progress is None:
        return [(0, n)]
    n_blocks = int(min(100, max(1, entries_per_row * n // _PROGRESS_ENTRIES)))
    edges = np.linspace(0, n, n_blocks + 1).astype(np.int64)
    return [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:], strict=True) if b > a]


def _geometry(grid: Grid) -> tuple:
    return (grid.cell_start, grid.dims, grid.lo, grid.cell, grid.radius, grid.full, grid.max_columns,
            _CHUNK_ROWS)


def _counter() -> np.ndarray:
    # the next chunk of rows, shared by the threads of one pass (each_thread)
    return np.zeros(1, dtype=np.int64)


def count_entries(V: np.ndarray, grid: Grid, rows: np.ndarray | None = None,
                  progress: Callable[[float], None] | None = None,
                  expected_nnz: float = 0.0) -> np.ndarray:
    """Stored entries (diagonal included) of each row in ``rows`` (default: all, by vertex).

    ``expected_nnz`` (an estimate of the total) sizes the blocks between progress calls.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [0.1, 0, 0], [5, 0, 0]], float)
    >>> count_entries(V, build_grid(V, np.ones(3), 1.0)).tolist()
    [2, 2, 1]
    """
    head = (V, grid.xs, grid.ys, grid.zs, grid.self_slot)
    if rows is not None:
        rows = np.ascontiguousarray(rows, dtype=np.int64)
        counts = np.empty(len(rows), dtype=np.int64)
        each_thread(_count_rows, _counter(), rows, *head, *_geometry(grid), counts, False)
        return counts
    counts = np.empty(len(V), dtype=np.int64)
    blocks = _row_blocks(grid, expected_nnz / max(len(V), 1), progress)
    for a, b in blocks:
        each_thread(_count_rows, _counter(), grid.tgt_order[a:b], *head, *_geometry(grid), counts, True)
        if progress is not None:
            progress(b / len(V))
    return counts


def fill_csr(V: np.ndarray, grid: Grid, h: float, indptr: np.ndarray, index_dtype, value_dtype,
             progress: Callable[[float], None] | None = None,
             rows: np.ndarray | None = None, dim: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Fill the CSR ``indices`` and ``data`` of L for the row pointer from :func:`count_entries`;
    ``dim`` is the intrinsic dimension k of :func:`normalization`.

    ``rows`` (default: all) fills only those vertices' rows; ``indptr`` is still indexed by
    vertex, and the other rows must be empty in it (a rank's own rows among its halo).
    """
    nnz = int(indptr[-1])
    indices = np.empty(nnz, dtype=index_dtype)
    data = np.empty(nnz, dtype=value_dtype)
    coef = normalization(h, dim)
    status = np.zeros(1, dtype=np.int64)
    order = grid.tgt_order if rows is None else np.ascontiguousarray(rows, dtype=np.int64)
    for a, b in _row_blocks(grid, nnz / max(len(V), 1), progress):
        each_thread(_fill_rows, _counter(), order[a:b], V, grid.xs, grid.ys, grid.zs, grid.src_mass,
                    grid.src_index, grid.self_slot, *_geometry(grid), 1.0 / (4.0 * h), coef, indptr,
                    indices, data, status)
        if progress is not None:
            progress(b / len(V))
    if status[0]:
        raise RuntimeError("meshlap internal error: the count and fill passes found different "
                           "neighbourhoods; please report this with the mesh")
    return indices, data


def apply(V: np.ndarray, grid: Grid, h: float, f: np.ndarray, dim: int = 2,
          rows: np.ndarray | None = None) -> np.ndarray:
    """L @ f without storing L; ``f`` of shape (n,) or (n, q); ``dim`` as in :func:`fill_csr`.

    ``rows`` (default: all) computes only those rows; the other rows of the result are
    undefined.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]], float)
    >>> g = build_grid(V, np.ones(3), 1.0)
    >>> float(np.abs(apply(V, g, 0.01, np.ones(3))).max())   # L annihilates constants
    0.0
    """
    vec = f.ndim == 1
    f2 = np.ascontiguousarray(f.reshape(len(f), -1), dtype=np.float64)
    fs = np.ascontiguousarray(f2[grid.src_index].T)
    out = np.empty_like(f2)
    order = grid.tgt_order if rows is None else np.ascontiguousarray(rows, dtype=np.int64)
    each_thread(_apply_rows, _counter(), order, V, grid.xs, grid.ys, grid.zs, grid.src_mass,
                grid.self_slot, *_geometry(grid), 1.0 / (4.0 * h), normalization(h, dim), fs, f2, out)
    return out[:, 0] if vec else out
