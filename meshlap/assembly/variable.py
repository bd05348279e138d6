"""Assembly with per-point widths, the difference-of-Gaussians kernel and arc distances.

The corrected operator's kernel: pair (w, p) has width h_wp = (h_w + h_p)/2 and is kept when
its distance d² (times the squared arc/chord ratio of the pair's normals, when given) is at
most 4 h_wp ln(1/tol). Every quantity is symmetric in (w, p), so the kept pairs and K are
symmetric. The same two passes (count, then fill) as :mod:`meshlap.assembly.grid`, whose
neighbour search they reuse.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from .._jit import each_thread, in_blocks, jit
from ._intrinsics import _exp_neg, _fetch_add
from .grid import _CHUNK_ROWS, Grid, _candidates, _columns, _sum

__all__ = ["count_entries", "dog_factor", "revalue", "sort_rows", "variable_csr"]

#: Most columns of the block that the fill multiplies its rows with (``times=``), one
#: register each: the moment scale's |x|², x, y, z, the check's constant and its start's
#: three random vectors (:func:`meshlap.corrections.psd.fill_columns`).
BLOCK = 8


@jit(inline="always")
def _arc_factor(nw0, nw1, nw2, np0, np1, np2):
    # (α/2)/sin(α/2) squared, α the angle between the unit normals: the squared ratio of arc
    # to chord for a circle through both points with those normals (1 for parallel normals)
    t = _sin2_half(_cosine(nw0, nw1, nw2, np0, np1, np2))
    if t <= 0.1:
        return _arc_series(t)
    sn = math.sqrt(t)
    q = math.asin(sn) / sn
    return q * q


@jit(inline="always")
def _cosine(nw0, nw1, nw2, np0, np1, np2):
    # cos α of the angle α between two unit normals
    return nw0 * np0 + nw1 * np1 + nw2 * np2


@jit(inline="always")
def _sin2_half(c):
    # t = sin²(α/2) from c = cos α
    return min(max(0.5 * (1.0 - c), 0.0), 1.0)


@jit(inline="always")
def _arc_series(t):
    # _arc_factor for t <= 0.1: asin(s)/s as a series in t = s² (truncation below 2e-8), squared;
    # no libm call and no branch, for the nearly parallel normals of most pairs
    q = 1.0 + t * (1.0 / 6.0 + t * (3.0 / 40.0 + t * (5.0 / 112.0 + t * (35.0 / 1152.0
                                                                     + t * 63.0 / 2816.0))))
    return q * q


@jit(inline="always")
def _count_var(x, y, z, sw, hw, nw, xs, ys, zs, hs, ns, lnt4, use_normals, cols, ncols):
    # what _gather_var returns, without its stores. The loop repeats _gather_var's on purpose:
    # with the pair's d² in a shared inline helper numba compiled both passes 2.5x slower
    # (measured). With normals, the arc factor's series is taken for every candidate, without
    # a branch, so that the loop vectorizes (the count pass 2x faster); a row with a pair
    # beyond the series' range (t > 0.1, rare) is counted again by _count_exact. The source
    # index is unsigned: numba guards a signed index against negative values (Python's
    # wraparound) at every load, and with that select the compiler loaded the candidates'
    # coordinates and normals by gathers; unsigned, by contiguous vector loads (the count
    # pass 0.101 -> 0.044 s of CPU on a 16k sphere, single thread, measured)
    if not use_normals:
        return _count_exact(x, y, z, sw, hw, nw, xs, ys, zs, hs, ns, lnt4, False, cols, ncols)
    cnt = 0
    nw0, nw1, nw2 = nw[0], nw[1], nw[2]
    n0, n1, n2 = ns[0], ns[1], ns[2]
    far = 0
    for i in range(ncols):
        for j in range(np.uint64(cols[i, 0]), np.uint64(cols[i, 1])):
            dx = xs[j] - x
            dy = ys[j] - y
            dz = zs[j] - z
            d2 = dx * dx + dy * dy + dz * dz
            lim = lnt4 * 0.5 * (hw + hs[j])
            t = _sin2_half(_cosine(nw0, nw1, nw2, n0[j], n1[j], n2[j]))
            far += np.int64((t > 0.1) & (d2 <= lim))
            cnt += np.int64((d2 * _arc_series(t) <= lim) & (np.int64(j) != sw))
    if far:
        return _count_exact(x, y, z, sw, hw, nw, xs, ys, zs, hs, ns, lnt4, True, cols, ncols)
    return cnt


@jit()
def _count_exact(x, y, z, sw, hw, nw, xs, ys, zs, hs, ns, lnt4, use_normals, cols, ncols):
    # _count_var's count without normals, or with the exact arc factor at every pair within
    # the cut-off
    cnt = 0
    for i in range(ncols):
        for j in range(np.uint64(cols[i, 0]), np.uint64(cols[i, 1])):
            dx = xs[j] - x
            dy = ys[j] - y
            dz = zs[j] - z
            d2 = dx * dx + dy * dy + dz * dz
            lim = lnt4 * 0.5 * (hw + hs[j])  # = lnt4 * h_wp to the bit (halving is exact)
            if use_normals and d2 <= lim:
                d2 = d2 * _arc_factor(nw[0], nw[1], nw[2], ns[0, j], ns[1, j], ns[2, j])
            cnt += np.int64((d2 <= lim) & (np.int64(j) != sw))
    return cnt


@jit(inline="always")
def _gather_var(x, y, z, sw, hw, nw, xs, ys, zs, hs, ns, lnt4, use_normals, cols, ncols, sj, sd, sh):
    # like _gather, with the per-pair cut-off; sh receives h_wp. First every candidate's d²
    # (times its arc factor's series, with normals) and h_wp at its place in the buffers, in a
    # loop over contiguous sources that vectorizes; then the pairs kept moved to the front, in
    # a loop that does nothing else. A row with a pair within the chord's cut-off beyond the
    # series' range (t > 0.1) takes _gather_arc. The same operations per pair as the exact
    # loop, so the same values. Unsigned source indices, as in _count_var (contiguous loads)
    nw0, nw1, nw2 = nw[0], nw[1], nw[2]
    n0, n1, n2 = ns[0], ns[1], ns[2]
    far = 0
    k0 = np.uint64(0)
    for i in range(ncols):
        j0 = np.uint64(cols[i, 0])
        for u in range(np.uint64(cols[i, 1]) - j0):
            j = j0 + u
            dx = xs[j] - x
            dy = ys[j] - y
            dz = zs[j] - z
            d2 = dx * dx + dy * dy + dz * dz
            hp = 0.5 * (hw + hs[j])
            if use_normals:  # the same for every pair: the compiler takes it out of the loop
                t = _sin2_half(_cosine(nw0, nw1, nw2, n0[j], n1[j], n2[j]))
                far += np.int64((t > 0.1) & (d2 <= lnt4 * hp))
                d2 = d2 * _arc_series(t)
            sd[k0 + u] = d2
            sh[k0 + u] = hp
        k0 += np.uint64(cols[i, 1]) - j0
    if far:
        return _gather_arc(x, y, z, sw, hw, nw, xs, ys, zs, hs, ns, lnt4, cols, ncols, sj, sd, sh)
    kept = 0
    k = 0
    for i in range(ncols):
        for j in range(cols[i, 0], cols[i, 1]):
            d2 = sd[k]
            hp = sh[k]
            sj[kept] = j
            sd[kept] = d2
            sh[kept] = hp
            kept += np.int64((d2 <= lnt4 * hp) & (j != sw))
            k += 1
    return kept


@jit()
def _gather_arc(x, y, z, sw, hw, nw, xs, ys, zs, hs, ns, lnt4, cols, ncols, sj, sd, sh):
    # _gather_var's gather with the exact arc factor at every pair within the cut-off
    pos = 0
    for i in range(ncols):
        for j in range(np.uint64(cols[i, 0]), np.uint64(cols[i, 1])):
            dx = xs[j] - x
            dy = ys[j] - y
            dz = zs[j] - z
            d2 = dx * dx + dy * dy + dz * dz
            hp = 0.5 * (hw + hs[j])
            # the factor is at least 1: a pair already beyond the cut-off needs none
            if d2 <= lnt4 * hp:
                d2 = d2 * _arc_factor(nw[0], nw[1], nw[2], ns[0, j], ns[1, j], ns[2, j])
            sj[pos] = j
            sd[pos] = d2
            sh[pos] = hp
            pos += np.int64((d2 <= lnt4 * hp) & (np.int64(j) != sw))
    return pos


@jit(inline="always")
def _var_weights(sd, sh, sm, cnt, dogc, half_k, data, first):
    # data[first + i] <- m_j K(d², h_wp) over contiguous arrays, one loop per kernel: without
    # an indirect load or a branch in it the loop vectorizes (the weights cost 3x as much
    # written inline with the gathers); the same operations per entry, so the same values.
    # Its callers are compiled with error_model="numpy": numba's default checks every
    # division for a zero divisor, and that branch kept this loop scalar (5.6x slower
    # alone, measured; h_wp > 0, so the check never fired and the values are the same)
    if half_k == 1.0:  # surfaces, rounded as the plain operator is
        if dogc != 0.0:
            for i in range(cnt):
                hp = sh[i]
                e = _exp_neg(-sd[i] / (4.0 * hp))
                data[first + i] = sm[i] * (e * (dogc * e - 1.0)) / (4.0 * math.pi * hp * hp)
        else:
            for i in range(cnt):
                hp = sh[i]
                data[first + i] = sm[i] * _exp_neg(-sd[i] / (4.0 * hp)) / (4.0 * math.pi * hp * hp)
        return
    for i in range(cnt):
        hp = sh[i]
        e = _exp_neg(-sd[i] / (4.0 * hp))
        kern = e * (dogc * e - 1.0) if dogc != 0.0 else e
        data[first + i] = sm[i] * kern / (hp * (4.0 * math.pi * hp) ** half_k)


@jit(error_model="numpy")
def _var_rows(next_chunk, rows, V, xs, ys, zs, m, src_index, self_slot, cell_start, dims, lo, cell,
              full, max_columns, chunk, hv, hs, nv, ns, use_normals, lnt4, hmax, dogc, half_k, fill,
              indptr, indices, data, counts, status, tv, ts, product):
    # one thread's share (each_thread): chunks of rows from the shared counter. fill=False:
    # counts[w] = entries of row w; fill=True: write the row into CSR, and where product has
    # columns, product[w] = the row times the block (tv by vertex, ts by source)
    n_rows = len(rows)
    n_chunks = (n_rows + chunk - 1) // chunk
    cols = np.empty((max_columns, 2), dtype=np.int64)
    sj = np.empty(1024, dtype=np.int64)
    sd = np.empty(1024, dtype=np.float64)
    sh = np.empty(1024, dtype=np.float64)
    sm = np.empty(1024, dtype=np.float64)
    while True:
        c = _fetch_add(next_chunk, 0, 1)
        if c >= n_chunks:
            break
        for k in range(c * chunk, min((c + 1) * chunk, n_rows)):
            w = rows[k]
            x, y, z = V[w, 0], V[w, 1], V[w, 2]
            hw = hv[w]
            r = math.sqrt(lnt4 * 0.5 * (hw + hmax)) if not full else math.inf
            ncols = _columns(x, y, z, zs, cell_start, dims, lo, cell, r, full, cols)
            need = _candidates(cols, ncols)
            if need > len(sj):
                sj = np.empty(2 * need, dtype=np.int64)
                sd = np.empty(2 * need, dtype=np.float64)
                sh = np.empty(2 * need, dtype=np.float64)
                sm = np.empty(2 * need, dtype=np.float64)
            if not fill:
                counts[w] = _count_var(x, y, z, self_slot[w], hw, nv[w], xs, ys, zs, hs, ns, lnt4,
                                       use_normals, cols, ncols) + 1
                continue
            cnt = _gather_var(x, y, z, self_slot[w], hw, nv[w], xs, ys, zs, hs, ns, lnt4,
                              use_normals, cols, ncols, sj, sd, sh)
            start = indptr[w]
            if cnt != indptr[w + 1] - start - 1:
                status[0] = 1
                cnt = min(cnt, indptr[w + 1] - start - 1)
            first = start + 1
            for i in range(cnt):  # the indirect loads first, as in grid._fill_rows
                j = sj[i]
                sm[i] = m[j]
                indices[first + i] = src_index[j]
            _var_weights(sd, sh, sm, cnt, dogc, half_k, data, first)
            indices[start] = w
            data[start] = -_sum(data, first, cnt)
            if product.shape[1]:
                _row_times(w, first, cnt, sj, data, tv, ts, product)


@jit(inline="always")
def _row_times(w, first, cnt, sj, data, tv, ts, product):
    # product[w] = row w times the block, added in the row's stored order one entry after the
    # other, as scipy's CSR product adds them (the same values to the bit), while the row is
    # still in cache. The block has BLOCK columns (zero-padded), one register each: with the
    # column count unknown to the compiler each sum went through memory (3.7x the cost on a
    # 16k sphere, measured with 5 columns). ts is the block in source order,
    # read in the order of the row's sources (near each other in memory)
    a = data[first - 1]  # the diagonal, first in the row
    s0 = 0.0 + a * tv[w, 0]
    s1 = 0.0 + a * tv[w, 1]
    s2 = 0.0 + a * tv[w, 2]
    s3 = 0.0 + a * tv[w, 3]
    s4 = 0.0 + a * tv[w, 4]
    s5 = 0.0 + a * tv[w, 5]
    s6 = 0.0 + a * tv[w, 6]
    s7 = 0.0 + a * tv[w, 7]
    for i in range(cnt):
        a = data[first + i]
        j = sj[i]
        s0 += a * ts[j, 0]
        s1 += a * ts[j, 1]
        s2 += a * ts[j, 2]
        s3 += a * ts[j, 3]
        s4 += a * ts[j, 4]
        s5 += a * ts[j, 5]
        s6 += a * ts[j, 6]
        s7 += a * ts[j, 7]
    product[w, 0] = s0
    product[w, 1] = s1
    product[w, 2] = s2
    product[w, 3] = s3
    product[w, 4] = s4
    product[w, 5] = s5
    product[w, 6] = s6
    product[w, 7] = s7


def dog_factor(dim: int) -> float:
    """c_k of the Richardson kernel 2K_{h/2} − K_h = (c_k e^{−d²/2h} − e^{−d²/4h}) / (h (4πh)^{k/2}):
    c_k = 2^{2+k/2} (8 on surfaces).

    Examples
    --------
    >>> dog_factor(2), round(dog_factor(1), 4)
    (8.0, 5.6569)
    """
    return 8.0 if dim == 2 else 2.0 ** (2.0 + 0.5 * dim)


def _pass_args(V: np.ndarray, grid: Grid, hv: np.ndarray, tol: float, normals: np.ndarray | None,
               dog: bool, dim: int, rows: np.ndarray | None) -> tuple:
    # the arguments of _var_rows up to its fill flag: rows, sources, grid, widths, kernel
    lnt4 = math.inf if tol == 0 else 4.0 * math.log(1.0 / tol)
    hv = np.ascontiguousarray(hv, dtype=np.float64)
    use_normals = normals is not None
    nv = np.ascontiguousarray(normals if use_normals else np.zeros((len(V), 3)), dtype=np.float64)
    # the sources' normals by coordinate; unread without normals (the copy cost a sampled count
    # 0.04 s of CPU at 400k vertices)
    ns = np.ascontiguousarray(nv[grid.src_index].T) if use_normals else np.zeros((3, 1))
    order = grid.tgt_order if rows is None else np.ascontiguousarray(rows, dtype=np.int64)
    return (order, V, grid.xs, grid.ys, grid.zs, grid.src_mass, grid.src_index, grid.self_slot,
            grid.cell_start, grid.dims, grid.lo, grid.cell, grid.full, grid.max_columns, _CHUNK_ROWS,
            hv, np.ascontiguousarray(hv[grid.src_index]), nv, ns,
            use_normals, lnt4, float(hv.max()), dog_factor(dim) if dog else 0.0, 0.5 * dim)


def _count_pass(args: tuple, n: int, index_dtype) -> np.ndarray:
    # entries per vertex of the rows in args (0 for the others); the index arrays have the fill
    # pass's type, so that one compiled specialization serves both passes
    counts = np.zeros(n, dtype=np.int64)
    dummy_i = np.zeros(1, dtype=index_dtype)
    none = np.zeros((1, 0))
    each_thread(_var_rows, np.zeros(1, dtype=np.int64), *args, False, dummy_i, dummy_i, np.zeros(1), counts,
                np.zeros(1, dtype=np.int64), none, none, none)
    return counts


def count_entries(V: np.ndarray, grid: Grid, hv: np.ndarray, tol: float, normals: np.ndarray | None,
                  dim: int = 2, rows: np.ndarray | None = None) -> np.ndarray:
    """Stored entries (diagonal included) of each row in ``rows`` (default: all, by vertex), as
    :func:`variable_csr` with the same arguments would store them; ``rows`` may repeat.

    Examples
    --------
    >>> import numpy as np
    >>> from meshlap.assembly.grid import build_grid
    >>> V = np.array([[0, 0, 0], [0.1, 0, 0], [5, 0, 0]], float)
    >>> count_entries(V, build_grid(V, np.ones(3), 1.0), np.full(3, 0.01), 1e-8, None).tolist()
    [2, 2, 1]
    """
    counts = _count_pass(_pass_args(V, grid, hv, tol, normals, False, dim, rows), len(V), np.int32)
    return counts if rows is None else counts[np.asarray(rows, dtype=np.int64)]


def variable_csr(V: np.ndarray, grid: Grid, hv: np.ndarray, tol: float, normals: np.ndarray | None,
                 dog: bool, index_dtype, value_dtype,
                 max_nnz: Callable[[int], None] | None = None, dim: int = 2,
                 rows: np.ndarray | None = None, times: np.ndarray | None = None,
                 product: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """CSR arrays (indptr, indices, data) of L with per-vertex widths ``hv``.

    Pair width h_wp = (h_w + h_p)/2 with the matching factor 1/(h_wp (4π h_wp)^{k/2}), so the
    second moment of every pair's kernel is that of the Gaussian of width h_wp; ``dog`` gives
    the Richardson kernel 2K_{h/2} − K_h, (2^{2+k/2} e^{−d²/2h} − e^{−d²/4h}) per pair;
    ``normals`` multiplies d² by the squared arc/chord ratio of the pair. ``grid`` must be
    built for the largest radius. ``max_nnz`` is called with the exact count before the
    arrays are allocated (a memory guard). ``rows`` (default all) fills only those rows; the
    others stay empty (one MPI rank's own rows). With ``times`` (n, c ≤ :data:`BLOCK`) float64, ``product``
    (n, c) receives L @ times, computed while each row is filled (in float64, summed in the
    row's stored order: what scipy's product with the float64 matrix gives, to the bit).

    Examples
    --------
    >>> from meshlap.assembly.grid import build_grid
    >>> V = np.random.default_rng(0).random((200, 3))
    >>> X, Y = np.column_stack([(V**2).sum(axis=1), V]), np.empty((200, 4))
    >>> ip, ind, dat = variable_csr(V, build_grid(V, np.ones(200), 1.0), np.full(200, 0.01), 1e-8, None,
    ...                             True, np.int32, np.dtype(np.float64), times=X, product=Y)
    >>> import scipy.sparse as sp
    >>> bool(np.array_equal(Y, sp.csr_matrix((dat, ind, ip), shape=(200, 200)) @ X))
    True
    """
    n = len(V)
    args = _pass_args(V, grid, hv, tol, normals, dog, dim, rows)
    counts = _count_pass(args, n, index_dtype)
    nnz = int(counts.sum())
    if max_nnz is not None:
        max_nnz(nnz)
    indptr = np.zeros(n + 1, dtype=index_dtype)
    np.cumsum(counts, out=indptr[1:])
    indices = np.empty(nnz, dtype=index_dtype)
    data = np.empty(nnz, dtype=np.float64)
    status = np.zeros(1, dtype=np.int64)
    tv = ts = padded = np.zeros((1, 0))
    if times is not None:
        if times.shape[1] > BLOCK:
            raise ValueError(f"times: at most {BLOCK} columns; got {times.shape[1]}")
        tv = np.zeros((n, BLOCK))
        tv[:, :times.shape[1]] = times
        ts, padded = tv[grid.src_index], np.zeros((n, BLOCK))  # rows not filled: 0
    each_thread(_var_rows, np.zeros(1, dtype=np.int64), *args, True, indptr, indices, data, counts, status,
                tv, ts, padded)
    if times is not None:
        product[:] = padded[:, :times.shape[1]]
    if status[0]:
        raise RuntimeError("meshlap internal error: the count and fill passes found different "
                           "neighbourhoods; please report this with the mesh")
    return indptr, indices, data.astype(value_dtype, copy=False)


@jit(error_model="numpy")
def _revalue_rows(start, stop, V, m, hv, nv, use_normals, dogc, half_k, indptr, indices, data):
    # the weights of rows start..stop recomputed on their stored pattern: d² and h_wp by the
    # same operations as _gather_var's and _gather_arc's (so the same values, and the same
    # order of the row's sum); every stored pair is within the cut-off, where the arc factor
    # applies
    longest = 1
    for w in range(start, stop):
        longest = max(longest, indptr[w + 1] - indptr[w])
    sd = np.empty(longest)
    sh = np.empty(longest)
    sm = np.empty(longest)
    for w in range(start, stop):
        a = indptr[w]
        cnt = indptr[w + 1] - a - 1
        if cnt < 0:
            continue
        x, y, z = V[w, 0], V[w, 1], V[w, 2]
        hw = hv[w]
        for i in range(cnt):
            p = indices[a + 1 + i]
            dx = V[p, 0] - x
            dy = V[p, 1] - y
            dz = V[p, 2] - z
            d2 = dx * dx + dy * dy + dz * dz
            if use_normals:
                d2 = d2 * _arc_factor(nv[w, 0], nv[w, 1], nv[w, 2], nv[p, 0], nv[p, 1], nv[p, 2])
            sd[i] = d2
            sh[i] = 0.5 * (hw + hv[p])
            sm[i] = m[p]
        _var_weights(sd, sh, sm, cnt, dogc, half_k, data, a + 1)
        data[a] = -_sum(data, a + 1, cnt)


def revalue(V: np.ndarray, mass: np.ndarray, hv: np.ndarray, normals: np.ndarray | None, dog: bool,
            indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, dim: int = 2) -> None:
    """The weights of :func:`variable_csr`'s rows for another kernel (``dog``), in place on
    their pattern: the kept pairs depend on the widths, normals and tolerance, not on the
    kernel, so the plain kernel's rows that a failed semidefiniteness check falls back to
    need no neighbour search, no count and no new arrays. The values are those a new build
    would give, to the bit (``data`` of another type gets them rounded, as the build's cast).

    Examples
    --------
    >>> import numpy as np
    >>> from meshlap.assembly.grid import build_grid
    >>> V = np.array([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]], float)
    >>> args = (V, build_grid(V, np.ones(3), 1.0), np.full(3, 0.01), 1e-8, None)
    >>> ip, ind, dat = variable_csr(*args, True, np.int32, np.dtype(np.float64))
    >>> revalue(V, np.ones(3), np.full(3, 0.01), None, False, ip, ind, dat)
    >>> bool(np.array_equal(dat, variable_csr(*args, False, np.int32, np.dtype(np.float64))[2]))
    True
    """
    use_normals = normals is not None
    nv = np.ascontiguousarray(normals if use_normals else np.zeros((1, 3)), dtype=np.float64)
    out = data if data.dtype == np.float64 else np.empty(len(data))
    in_blocks(_revalue_rows, len(indptr) - 1, np.ascontiguousarray(V, dtype=np.float64),
              np.ascontiguousarray(mass, dtype=np.float64), np.ascontiguousarray(hv, dtype=np.float64), nv,
              use_normals, dog_factor(dim) if dog else 0.0, 0.5 * dim, indptr, indices, out)
    if out is not data:
        data[:] = out


@jit()
def _sort_rows(start, stop, indptr, indices, data):  # pragma: no cover - compiled
    for w in range(start, stop):
        _sort_pairs(indices, data, indptr[w], indptr[w + 1])


@jit()
def _sort_pairs(key, val, lo, hi):  # pragma: no cover - compiled
    # key[lo:hi] ascending (distinct keys), val moved alongside, in place: quicksort with the
    # median of three as pivot and insertion sort below 16 entries. Written out because
    # np.argsort costs seconds to compile and needs two gathers and their copies.
    stack = np.empty((64, 2), dtype=np.int64)  # the larger part waits: depth <= log2(n)
    top = 0
    while True:
        while hi - lo > 16:
            mid = (lo + hi) >> 1
            # the median of key[lo], key[mid], key[hi - 1] goes to lo, the pivot of Hoare's scheme
            a, b, c = key[lo], key[mid], key[hi - 1]
            m = mid if (a < b) == (b < c) else (lo if (b < a) == (a < c) else hi - 1)
            _swap(key, val, lo, m)
            p = key[lo]
            i = lo - 1
            j = hi
            while True:
                i += 1
                while key[i] < p:
                    i += 1
                j -= 1
                while key[j] > p:
                    j -= 1
                if i >= j:
                    break
                _swap(key, val, i, j)
            # parts [lo, j] and [j + 1, hi), both non-empty
            if j + 1 - lo < hi - j - 1:
                stack[top, 0], stack[top, 1] = j + 1, hi
                hi = j + 1
            else:
                stack[top, 0], stack[top, 1] = lo, j + 1
                lo = j + 1
            top += 1
        for i in range(lo + 1, hi):
            k, v = key[i], val[i]
            j = i - 1
            while j >= lo and key[j] > k:
                key[j + 1] = key[j]
                val[j + 1] = val[j]
                j -= 1
            key[j + 1] = k
            val[j + 1] = v
        if top == 0:
            return
        top -= 1
        lo, hi = stack[top, 0], stack[top, 1]


@jit(inline="always")
def _swap(key, val, i, j):  # pragma: no cover - compiled
    key[i], key[j] = key[j], key[i]
    val[i], val[j] = val[j], val[i]


def sort_rows(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray) -> None:
    """Sort every CSR row by column, in place (the fill writes the diagonal first).

    Matrices that share one index array (the symmetric L and the point-wise rows) must be
    canonical: scipy sorts unsorted rows in place, which would reorder the shared indices
    under the other matrix's values.

    Examples
    --------
    >>> import numpy as np
    >>> ip, ind, dat = np.array([0, 3]), np.array([0, 2, 1]), np.array([1.0, 3.0, 2.0])
    >>> sort_rows(ip, ind, dat); ind.tolist(), dat.tolist()
    ([0, 1, 2], [1.0, 2.0, 3.0])
    """
    in_blocks(_sort_rows, len(indptr) - 1, indptr, indices, data)
