"""MPI plumbing of the distributed operator: imports, exchanges, the global grid, the k-d split."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .. import assembly
from .._jit import in_blocks, jit
from ..errors import MeshError
from ..geometry.validation import check_faces

# private plumbing of meshlap.distributed: nothing here is public
__all__: list[str] = []

_INSTALL = ("meshlap.distributed needs mpi4py, petsc4py and slepc4py: `pip install 'meshlap[mpi]'` "
            "gives mpi4py; petsc4py/slepc4py build against PETSc/SLEPc (Debian: apt-get install "
            "libpetsc-real-dev libslepc-real-dev, then PETSC_DIR=$(pkg-config --variable=prefix PETSc) "
            "pip install --no-build-isolation petsc4py==3.18.5 and likewise slepc4py==3.18.2 with "
            "SLEPC_DIR; or run .ci/install-mpi). See the README section 'Beyond one machine'.")
# mpi4py 4 imports without an MPI library and raises RuntimeError on first use of MPI
_NO_LIBMPI = "mpi4py is installed but finds no MPI library to load (Debian: apt-get install libopenmpi-dev)"
# the halo and partition margins: wider than r by far more than the rounding of d² <= r², so
# that no pair the kernel keeps is ever missing from a rank
_MARGIN = 1e-6
# re-split when the busiest rank holds this much more than the mean of the entries
_IMBALANCE = 1.10
# rows are filled and handed to PETSc in blocks of about this many entries, so that the
# build's peak stays near the matrix PETSc holds (12 bytes per entry) plus one block
_BLOCK_ENTRIES = 1 << 22


def _mpi():
    try:
        from mpi4py import MPI
        from petsc4py import PETSc
    except ImportError as exc:
        raise ImportError(_INSTALL) from exc
    except RuntimeError as exc:
        raise ImportError(f"{_NO_LIBMPI}: {str(exc).splitlines()[0]}. {_INSTALL}") from exc
    return MPI, PETSc


def _slepc():
    try:
        from slepc4py import SLEPc
    except ImportError as exc:
        raise ImportError(_INSTALL) from exc
    return SLEPc


def _has_mumps() -> bool:
    """Whether this PETSc has MUMPS (Debian's has; a minimal build may not)."""
    return bool(_mpi()[1].Sys.hasExternalPackage("mumps"))


# -- communication helpers ------------------------------------------------------------------
def _exchange(comm, dest: np.ndarray, *arrays: np.ndarray) -> list[np.ndarray]:
    """Send row i of every array to rank dest[i]; returns the rows received, by source rank."""
    size = comm.Get_size()
    order = np.argsort(dest, kind="stable")
    counts = np.bincount(dest, minlength=size).astype(np.int64)
    rcounts = np.empty(size, dtype=np.int64)
    comm.Alltoall(counts, rcounts)
    out = []
    for a in arrays:
        a = np.ascontiguousarray(a[order])
        width = int(np.prod(a.shape[1:], dtype=np.int64))
        recv = np.empty((int(rcounts.sum()), *a.shape[1:]), dtype=a.dtype)
        if width == 0:  # nothing to send (rows without columns)
            out.append(recv)
            continue
        sc, rc = counts * width, rcounts * width
        sd = np.concatenate([[0], np.cumsum(sc)[:-1]])
        rd = np.concatenate([[0], np.cumsum(rc)[:-1]])
        comm.Alltoallv([a, (sc, sd)], [recv, (rc, rd)])
        out.append(recv)
    return out


def _reduce(comm, a, op) -> np.ndarray:
    """Element-wise Allreduce of a numpy array (MIN, MAX, SUM)."""
    a = np.ascontiguousarray(a)
    out = np.empty_like(a)
    comm.Allreduce(a, out, op=op)
    return out


def _box(P: np.ndarray) -> np.ndarray:
    # (lo, hi) of the points; an empty box (lo > hi) for none
    if len(P) == 0:
        return np.concatenate([np.full(3, np.inf), np.full(3, -np.inf)])
    return np.concatenate([P.min(axis=0), P.max(axis=0)])


# -- the global grid: the single-machine build's cell order --------------------------------
def _global_grid(comm, V: np.ndarray, mass: np.ndarray,
                 radius: float) -> tuple[np.ndarray, float, np.ndarray]:
    """Origin, cell side and dims of the grid :func:`meshlap.assembly.grid.build_grid` would build
    from all ranks' points together (the same floating-point operations, on the same values)."""
    MPI, _ = _mpi()
    src = mass > 0
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    if src.any():
        lo = V[src].min(axis=0)
        hi = V[src].max(axis=0)
    n_src = comm.allreduce(int(src.sum()), op=MPI.SUM)
    lo = _reduce(comm, lo, MPI.MIN)
    hi = _reduce(comm, hi, MPI.MAX)
    if n_src == 0:
        raise MeshError("every vertex has zero mass: the point set has no surface to integrate over")
    extent = hi - lo
    if not math.isfinite(radius):
        return lo, 1.0, np.ones(3, dtype=np.int64)
    # assembly.grid.build_grid's rule (tests/test_distributed.py checks that the two agree)
    cell = max(radius / assembly.grid._CELLS_PER_RADIUS, 1e-300)
    max_cells = max(assembly.grid._MAX_CELLS_PER_POINT * n_src, 1024)
    while True:
        dims = np.floor(extent / cell).astype(np.int64) + 1
        if np.prod(dims.astype(np.float64)) <= max_cells:
            break
        cell *= 1.26
    return lo, float(cell), dims


def _visit_rank(P: np.ndarray, uid: np.ndarray, lo: np.ndarray, cell: float, dims: np.ndarray) -> np.ndarray:
    """Position of each source in the order the single-machine kernel visits a row's sources.

    The serial grid sorts sources by cell and then z, ties by vertex index, and a row walks
    its (x, y) columns in index order, inside each column from low to high z. A cell's z
    index grows with z, so that order is (column, z, vertex index) for every row alike.
    """
    ijk = np.floor((P - lo) / cell).astype(np.int64)
    np.clip(ijk, 0, dims - 1, out=ijk)
    column = ijk[:, 0] * dims[1] + ijk[:, 1]
    rank = np.empty(len(P), dtype=np.int64)
    rank[np.lexsort((uid, P[:, 2], column))] = np.arange(len(P))
    return rank


def _canonical_rows(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, visit: np.ndarray,
                    n_rows: int) -> None:
    # Reorder each row's off-diagonal entries to the serial visiting order and sum the
    # diagonal in that order, with the serial kernel's own summation; on meshlap's threads
    # (numba's parallel loop left its OpenMP workers spinning after each call)
    in_blocks(_canonical_block, n_rows, indptr, indices, data, visit)


@jit()
def _canonical_block(start, stop, indptr, indices, data, visit):  # pragma: no cover - compiled
    # _canonical_rows for rows start..stop
    for w in range(start, stop):
        first = indptr[w]
        if indptr[w + 1] == first:  # a row not filled this time
            continue
        first += 1
        cnt = indptr[w + 1] - first
        order = np.argsort(visit[indices[first:first + cnt]])
        idx = indices[first:first + cnt][order]
        val = data[first:first + cnt][order]
        indices[first:first + cnt] = idx
        data[first:first + cnt] = val
        data[first - 1] = -assembly.grid._sum(data, first, cnt)


# -- masses from faces spread over the ranks ------------------------------------------------
def _scattered_mass(comm, V: np.ndarray, F: Any) -> np.ndarray:
    """m_p = Σ_{t∋p} Area(t)/#t for this rank's chunk of points, from the faces each rank holds
    (global vertex indices; any chunking, any face sizes).

    Each rank fetches the corners of its faces from their owners, computes the areas, and
    sends every corner's share to the corner's owner, which adds them up. When the faces are
    chunked in rank order, each vertex adds its shares in face order, the single-machine
    order, so the masses are the single-machine ones to the bit.
    """
    from ..geometry import Polygons
    from ..geometry.mass import _face_areas

    rank = comm.Get_rank()
    ends = np.cumsum(comm.allgather(len(V)))
    start = int(ends[rank] - len(V))
    F = np.asarray(F) if not isinstance(F, (list, Polygons)) else F
    empty = isinstance(F, np.ndarray) and F.size == 0
    faces = Polygons(np.zeros(0, np.int64), np.zeros(1, np.int64)) if empty else check_faces(F, int(ends[-1]))
    ids = faces.indices
    need = np.unique(ids)
    owner = np.searchsorted(ends, need, side="right")
    asked, src = _exchange(comm, owner, need, np.full(len(need), rank, dtype=np.int64))
    coords, got = _exchange(comm, src, V[asked - start], asked)
    Vn = np.empty((len(need), 3))
    Vn[np.searchsorted(need, got)] = coords
    local = Polygons(np.searchsorted(need, ids).astype(np.int64), faces.offsets)
    areas = _face_areas(Vn, local) if faces.n_faces else np.zeros(0)
    share = np.repeat(areas / faces.sizes, faces.sizes)
    r_ids, r_share = _exchange(comm, np.searchsorted(ends, ids, side="right"), ids, share)
    return np.bincount(r_ids - start, weights=r_share, minlength=len(V)).astype(np.float64)


# -- partition -----------------------------------------------------------------------------
def _kd_split(comm, X: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """Owner rank of each local point: recursive coordinate bisection over the ranks.

    A node of ranks [r0, r1) splits its points at the weighted quantile (r_mid - r0)/(r1 - r0)
    of the coordinate of largest extent; the split value comes from bisection on that
    coordinate with one allreduce per step, vectorized over all nodes of a level.
    """
    MPI, _ = _mpi()
    size = comm.Get_size()
    n = len(X)
    r0 = np.zeros(n, dtype=np.int64)
    r1 = np.full(n, size, dtype=np.int64)
    nodes = [(0, size)] if size > 1 else []
    while nodes:
        # the points still in a node of two or more ranks are exactly this level's nodes,
        # which their first rank tells apart
        nn = len(nodes)
        lookup = np.full(size, -1, dtype=np.int64)
        lookup[[a_ for a_, _ in nodes]] = np.arange(nn)
        node = np.where(r1 - r0 > 1, lookup[r0], -1)
        mine = node >= 0
        lo = np.full((nn, 3), np.inf)
        hi = np.full((nn, 3), -np.inf)
        if mine.any():
            np.minimum.at(lo, node[mine], X[mine])
            np.maximum.at(hi, node[mine], X[mine])
        lo = _reduce(comm, lo, MPI.MIN)
        hi = _reduce(comm, hi, MPI.MAX)
        ext = np.where(np.isfinite(hi - lo), hi - lo, -1.0)
        axis = np.argmax(ext, axis=1)
        mid = np.array([(a + b) // 2 for a, b in nodes])
        frac = np.array([(m - a) / (b - a) for (a, b), m in zip(nodes, mid, strict=True)])
        coord = X[np.arange(n), axis[np.maximum(node, 0)]] if n else np.zeros(0)
        w = np.where(mine, weight, 0.0)
        total = _reduce(comm, np.bincount(node[mine], weights=w[mine], minlength=nn), MPI.SUM)
        target = frac * total
        a = lo[np.arange(nn), axis].copy()
        b = hi[np.arange(nn), axis].copy()
        b = np.where(np.isfinite(b), np.nextafter(b, np.inf), 0.0)  # split at b: all go left
        a = np.where(np.isfinite(a), a, 0.0)
        for _ in range(60):
            s = 0.5 * (a + b)
            below = coord < s[np.maximum(node, 0)]
            got = _reduce(comm, np.bincount(node[mine], weights=(w * below)[mine], minlength=nn),
                          MPI.SUM)
            left = got < target
            a = np.where(left, s, a)
            b = np.where(left, b, s)
        split = b
        go_left = coord < split[np.maximum(node, 0)]
        r1 = np.where(mine & go_left, mid[np.maximum(node, 0)], r1)
        r0 = np.where(mine & ~go_left, mid[np.maximum(node, 0)], r0)
        children = [c for a_, b_ in nodes for c in ((a_, (a_ + b_) // 2), ((a_ + b_) // 2, b_))]
        nodes = [c for c in children if c[1] - c[0] > 1]
    return r0


# -- the operator --------------------------------------------------------------------------
