"""The heat-kernel Laplacian on MPI: a PETSc matrix (or matrix-free shell) over many ranks.

Belkin, Sun and Wang, "Discrete Laplace operator on meshed surfaces", SoCG 2008, eq. (1),
distributed: every rank owns a spatial share of the points, builds its own rows with the
compiled kernel of :mod:`meshlap.assembly` from its points plus a halo of width
r = sqrt(4h ln(1/tol)), and hands them to PETSc (petsc4py) as an MPIAIJ matrix, or keeps only
its points and recomputes the rows in every product (a PETSc shell matrix). Solves go through
PETSc (KSP) and SLEPc; ``docs/distributed.md`` has the design and the measured scaling.

The data flow, in order:

1. Each rank passes its chunk of the points with masses or a share of the faces (the global
   vertex numbering is the chunks in rank order), or every rank passes the whole set
   (``scattered=False``).
2. A recursive coordinate bisection (k-d split) assigns points to ranks, balanced by the
   rows' entry counts: a first split balances points, a second one (when the entries differ
   by more than 10%) the counted entries of the first.
3. Each rank receives the points within r of its own (the halo) and builds its rows.
   The off-diagonal entries are the serial kernel's to the bit; the diagonal, a sum, is then
   recomputed in the order the single-machine build sums it, so the matrix equals the
   single-machine one exactly (see :func:`laplacian`).

Requires mpi4py, petsc4py and (for :func:`eigs`) slepc4py: ``pip install meshlap[mpi]``
installs mpi4py; petsc4py/slepc4py build against a PETSc/SLEPc installation (README section
"Beyond one machine", or ``.ci/install-mpi``). The rest of meshlap never imports this module.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from .. import assembly
from .. import widths as widths_mod
from ..errors import MeshError
from ..geometry import Geometry
from ..geometry.validation import check_faces, check_h, check_tol, check_vertices
from ..operator import as_geometry
from ..pipeline import DEFAULT_TOL, Options
from ..progress import ProgressLike, make_progress
from .comm import (
    _BLOCK_ENTRIES,
    _IMBALANCE,
    _MARGIN,
    _box,
    _canonical_rows,
    _exchange,
    _global_grid,
    _kd_split,
    _mpi,
    _scattered_mass,
    _visit_rank,
)
from .corrected import PointAttributes, attributes, local_rows
from .scattered import scattered_attributes

__all__ = ["DistributedLaplacian", "laplacian"]


class DistributedLaplacian:
    r"""The Belkin–Sun–Wang Laplacian as a PETSc operator over the ranks of a communicator.

    Built by :func:`laplacian`. Each rank owns ``n_local`` rows, a block of PETSc's numbering;
    ``ids`` maps them to the caller's; :meth:`local` and :meth:`gather` convert arrays.

    Attributes
    ----------
    L : petsc4py.PETSc.Mat
        What :meth:`apply` applies: an MPIAIJ matrix (the point-wise rows of the corrected
        default, as ``MeshLaplacian.L``), or a shell that recomputes rows (``matrix_free``).
    L_sym : petsc4py.PETSc.Mat
        The symmetric pencil's L (S = M L_sym), which the solvers use; ``L`` itself for the
        paper's operator.
    correction, moment_scale, fallback_reason : str, float, str or None
        As for :class:`meshlap.MeshLaplacian`.
    mass, ids : (n_local,) ndarray
        Masses and the caller's indices of the own rows.
    n_vertices, n_local, n_halo : int
        Global rows, own rows, and halo points this rank reads from others.
    rebalanced : bool
        Whether the points were split again by their entries (a rank had 10% over the mean).
    h, tol, radius : float
        Kernel width, tolerance and cut-off radius.
    """

    def __init__(self, comm, V: np.ndarray, mass: np.ndarray, uid: np.ndarray, h: float, tol: float,
                 matrix_free: bool, partition: np.ndarray | None, attrs: PointAttributes | None = None,
                 table: np.ndarray | None = None, report: Callable[[float, str], None] | None = None) -> None:
        MPI, PETSc = _mpi()
        tell = report or (lambda fraction, stage: None)
        tell(0.0, "partition")
        self.comm = comm
        self.h, self.tol = h, tol
        self.attrs = attrs
        self.correction = "none" if attrs is None or not attrs.dog else "richardson"
        self.fallback_reason: str | None = None
        self.moment_scale = 1.0
        self.pointwise_choice = None  # the fitted point-wise rows' choice on this rank's own rows
        # the halo reaches as far as the widest pair: the largest width sets the radius
        widest = h if table is None or not len(table) else float(table[:, 0].max())
        widest = comm.allreduce(widest, op=MPI.MAX)
        self.radius = assembly.grid.cutoff_radius(widest, tol)
        self.matrix_free = bool(matrix_free)
        T = np.zeros((len(V), 0)) if table is None else np.asarray(table, dtype=np.float64)
        self._lo, self._cell, self._dims = _global_grid(comm, V, mass, self.radius)
        self.n_vertices = comm.allreduce(len(V), op=MPI.SUM)
        self.rebalanced = False
        if partition is not None:
            owner = np.asarray(partition, dtype=np.int64)
            bad = len(owner) and (owner.min() < 0 or owner.max() >= comm.Get_size())
            if owner.shape != (len(V),) or bad:
                raise MeshError(f"partition must give one rank in [0, {comm.Get_size()}) per local point")
            self._setup(V, mass, uid, T, owner)
        else:
            self._setup(V, mass, uid, T, _kd_split(comm, V, np.ones(len(V))))
            entries = self._counts.sum()
            busiest = comm.allreduce(entries, op=MPI.MAX)
            mean = comm.allreduce(entries, op=MPI.SUM) / comm.Get_size()
            self.rebalanced = bool(busiest > _IMBALANCE * mean)
            if self.rebalanced:
                tell(0.2, "rebalance")
                # re-split the points where they are now, weighted by their counted entries
                Vn, mn, un, wn = self.V, self.mass, self.ids, self._counts.astype(np.float64)
                self._setup(Vn, mn, un, self._Tloc[: self.n_local], _kd_split(comm, Vn, wn))
        tell(0.3, "kernel rows")
        if self.matrix_free:
            self.L = self.L_sym = self._shell()
        elif attrs is None:
            self.L = self.L_sym = self._assemble()
        else:
            self.L_sym, self.L = self._assemble_corrected(tell)
        self._S = None
        self.mesh: tuple[np.ndarray, np.ndarray] | None = None  # the whole mesh, where it was given
        tell(1.0, "done")

    # -- setup: partition, halo, local grid ----------------------------------------------
    def _setup(self, V, mass, uid, T, owner) -> None:
        MPI, PETSc = _mpi()
        comm = self.comm
        V, mass, uid, T = _exchange(comm, owner, V, mass, uid, T)
        # own rows in grid-cell order (locality for the products), independent of chunking
        by_id = np.argsort(uid, kind="stable")
        V, mass, uid, T = V[by_id], mass[by_id], uid[by_id], T[by_id]
        if len(V):
            cells = assembly.grid.build_grid(V, np.ones(len(V)), self.radius if math.isfinite(self.radius)
                                             else math.inf).tgt_order
            V, mass, uid, T = V[cells], mass[cells], uid[cells], T[cells]
        n_own = len(V)
        self.n_local = n_own
        off = comm.exscan(n_own, op=MPI.SUM)  # collective; None on rank 0
        self.offset = int(off) if comm.Get_rank() > 0 else 0
        petsc_id = self.offset + np.arange(n_own, dtype=np.int64)
        # halo: the points of every other rank within r of this rank's box (those without mass
        # too: the fitted rows' neighbours, as on the single machine, a copy's column)
        boxes = np.array(comm.allgather(_box(V)))
        margin = self.radius * (1.0 + _MARGIN)
        dest, rows = [], []
        for q in range(comm.Get_size()):
            if q == comm.Get_rank() or not (boxes[q, :3] <= boxes[q, 3:]).all():
                continue
            sel = np.flatnonzero(np.all((V >= boxes[q, :3] - margin) & (V <= boxes[q, 3:] + margin), axis=1))
            rows.append(sel)
            dest.append(np.full(len(sel), q, dtype=np.int64))
        rows_ = np.concatenate(rows) if rows else np.zeros(0, np.int64)
        dest_ = np.concatenate(dest) if dest else np.zeros(0, np.int64)
        hV, hm, hu, hp, hT = _exchange(comm, dest_, V[rows_], mass[rows_], uid[rows_], petsc_id[rows_],
                                       T[rows_])
        if len(hV) and n_own and math.isfinite(self.radius):
            # keep only points within r of an own point (the box holds more on a curved surface)
            from pykdtree.kdtree import KDTree

            d, _ = KDTree(V).query(hV, k=1, distance_upper_bound=margin)
            keep = np.isfinite(d)
            hV, hm, hu, hp, hT = hV[keep], hm[keep], hu[keep], hp[keep], hT[keep]
        elif not n_own:
            hV, hm, hu, hp, hT = hV[:0], hm[:0], hu[:0], hp[:0], hT[:0]
        self.V, self.mass, self.ids = V, mass, uid
        self.n_halo = len(hV)
        self._Vloc = np.ascontiguousarray(np.vstack([V, hV]))
        self._mloc = np.concatenate([mass, hm])
        self._uloc = np.concatenate([uid, hu])
        self._ploc = np.concatenate([petsc_id, hp])
        self._Tloc = np.concatenate([T, hT])
        self._rows = np.zeros(0, np.int64)
        self._grid = None
        self._counts = np.zeros(0, np.int64)
        if n_own == 0:
            return
        self._grid = assembly.grid.build_grid(self._Vloc, self._mloc, self.radius)
        self._rows = self._grid.tgt_order[self._grid.tgt_order < n_own]
        counts = np.zeros(len(self._Vloc), dtype=np.int64)
        counts[self._rows] = assembly.grid.count_entries(self._Vloc, self._grid, rows=self._rows)
        self._counts = counts[:n_own]

    # -- the stored matrix ---------------------------------------------------------------
    def _row_blocks(self) -> list[np.ndarray]:
        # the own rows in grid order, cut into blocks of about _BLOCK_ENTRIES entries
        ends = np.cumsum(self._counts[self._rows]) if self.n_local else np.zeros(0, np.int64)
        cuts = np.searchsorted(ends, np.arange(_BLOCK_ENTRIES, ends[-1] if len(ends) else 0,
                                               _BLOCK_ENTRIES))
        return [b for b in np.split(self._rows, cuts) if len(b)]

    def _local_csr(self, rows: np.ndarray):
        """Own rows ``rows`` as CSR over all local points (other rows empty) with local column
        indices, each row in the single-machine order with its diagonal summed in that order."""
        n_loc = len(self._Vloc)
        counts = np.zeros(n_loc, dtype=np.int64)
        counts[rows] = self._counts[rows]
        indptr = np.zeros(n_loc + 1, dtype=np.int64)
        np.cumsum(counts, out=indptr[1:])
        # local column indices fit in int32 (n_loc < 2³¹): 12 bytes per entry, as PETSc's
        index_dtype = np.int32 if n_loc < np.iinfo(np.int32).max else np.int64
        indices, data = assembly.grid.fill_csr(self._Vloc, self._grid, self.h, indptr, index_dtype,
                                               np.float64, rows=rows)
        if getattr(self, "_visit", None) is None:
            visit = np.full(n_loc, np.iinfo(np.int64).max, dtype=np.int64)
            src = np.flatnonzero(self._mloc > 0)
            visit[src] = _visit_rank(self._Vloc[src], self._uloc[src], self._lo, self._cell, self._dims)
            self._visit = visit
        _canonical_rows(indptr, indices, data, self._visit, self.n_local)
        return indptr[: self.n_local + 1], indices, data

    def _assemble(self):
        MPI, PETSc = _mpi()
        N, n = self.n_vertices, self.n_local
        # exact preallocation: a row's entries in own columns are its neighbours among the
        # own points (the diagonal included), counted with the same kernel
        d_nnz = np.zeros(n, dtype=np.int64)
        if n:
            own = assembly.grid.build_grid(self.V, self.mass, self.radius)
            d_nnz = assembly.grid.count_entries(self.V, own)
        o_nnz = self._counts - d_nnz
        L = PETSc.Mat().create(comm=self.comm)
        L.setSizes(((n, N), (n, N)))
        L.setType(PETSc.Mat.Type.MPIAIJ)
        L.setPreallocationNNZ((d_nnz.astype(PETSc.IntType), o_nnz.astype(PETSc.IntType)))
        L.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
        ploc = self._ploc.astype(PETSc.IntType)
        self._visit = None
        for rows in self._row_blocks():  # own rows only: nothing for PETSc to send
            indptr, indices, data = self._local_csr(rows)
            L.setValuesCSR(indptr.astype(PETSc.IntType), ploc[indices], data)
        self._visit = None
        L.assemble()
        return L

    def _assemble_corrected(self, tell):
        # stages 4-5 on the own rows (meshlap.distributed.corrected), then into PETSc
        MPI, PETSc = _mpi()
        N, n = self.n_vertices, self.n_local
        L_sym, L_pw, info = local_rows(self.comm, self._Vloc, self._mloc, self._Tloc, n, self._grid,
                                       self._rows, self.attrs, self._uloc,
                                       report=lambda f, s: tell(0.3 + 0.6 * f, s))
        tell(0.9, "PETSc matrices")
        # the facts of the build; pointwise_choice: this rank's rows
        for key in ("pointwise_choice", "correction", "fallback_reason", "moment_scale", "psd_margin"):
            setattr(self, key, info[key])
        mats = []
        for A in (L_sym, L_pw) if L_pw is not L_sym else (L_sym,):
            indptr = A.indptr[: n + 1].astype(PETSc.IntType)
            cols = A.indices[: indptr[-1]]
            row = np.repeat(np.arange(n), np.diff(indptr))
            d_nnz = np.bincount(row[cols < n], minlength=n)  # entries in own columns
            o_nnz = np.diff(indptr) - d_nnz
            M = PETSc.Mat().create(comm=self.comm)
            M.setSizes(((n, N), (n, N)))
            M.setType(PETSc.Mat.Type.MPIAIJ)
            M.setPreallocationNNZ((d_nnz.astype(PETSc.IntType), o_nnz.astype(PETSc.IntType)))
            M.setValuesCSR(indptr, self._ploc[cols].astype(PETSc.IntType), A.data[: indptr[-1]])
            M.assemble()
            mats.append(M)
        return mats[0], mats[-1]

    # -- the matrix-free shell -----------------------------------------------------------
    def _shell(self):
        MPI, PETSc = _mpi()
        N, n = self.n_vertices, self.n_local
        ctx = _ShellContext(self)
        L = PETSc.Mat().createPython(((n, N), (n, N)), context=ctx, comm=self.comm)
        L.setUp()
        return L

    def diagonal(self) -> np.ndarray:
        """Diagonal of L_sym on the own rows (computed in blocks of rows when matrix-free)."""
        if not self.matrix_free:
            return self.L_sym.getDiagonal().getArray().copy()
        if not hasattr(self, "_diag"):
            diag = np.zeros(self.n_local)
            for rows in self._row_blocks():
                indptr, _, data = self._local_csr(rows)
                diag[rows] = data[indptr[rows]]
            self._visit = None
            self._diag = diag
        return self._diag

    # -- vectors -------------------------------------------------------------------------
    def local(self, f: Any) -> np.ndarray:
        """This rank's part of a function given on all vertices (in the caller's numbering)."""
        f = np.asarray(f, dtype=np.float64)
        if f.shape[0] != self.n_vertices:
            raise MeshError(f"f must have {self.n_vertices} rows, one per vertex; got {f.shape}")
        return f[self.ids]

    def gather(self, x: np.ndarray, root: int | None = None) -> np.ndarray | None:
        """A local array collected into the caller's numbering: on every rank (``root=None``)
        or on ``root`` only (None elsewhere)."""
        x = np.asarray(x, dtype=np.float64)
        parts = (self.comm.allgather((self.ids, x)) if root is None
                 else self.comm.gather((self.ids, x), root=root))
        if parts is None:
            return None
        out = np.empty((self.n_vertices, *x.shape[1:]))
        for ids, xs in parts:
            out[ids] = xs
        return out

    def vec(self, x: np.ndarray | None = None):
        """A PETSc vector on the rows (a copy of the local array ``x``, or zeros)."""
        v = self.L.createVecRight()
        if x is not None:
            v.setArray(np.asarray(x, dtype=np.float64))
        else:
            v.zeroEntries()
        return v

    def apply(self, X: Any, symmetric: bool = False) -> np.ndarray:
        """``L @ X`` (``L_sym @ X`` with ``symmetric``) for a local vector (n_local,) or block
        (n_local, k); returns local values."""
        X = np.asarray(X, dtype=np.float64)
        if X.shape[0] != self.n_local or X.ndim not in (1, 2):
            raise MeshError(f"X must have shape ({self.n_local},) or ({self.n_local}, k) on this rank; "
                            f"got {X.shape}")
        X2 = X[:, None] if X.ndim == 1 else X
        if self.matrix_free:
            # one pass over the kernel for the whole block: the weights are the cost
            return self.L.getPythonContext().apply_block(X2).reshape(X.shape)
        out = np.empty_like(X2)
        A = self.L_sym if symmetric else self.L
        x, y = A.createVecs()
        for j in range(X2.shape[1]):
            x.setArray(X2[:, j])
            A.mult(x, y)
            out[:, j] = y.getArray()
        return out.reshape(X.shape)

    __matmul__ = apply

    @property
    def S(self):
        """``M L`` (symmetric, negative semidefinite) as a PETSc matrix; stored operators only."""
        if self.matrix_free:
            raise MeshError("S is not stored for a matrix-free operator")
        if self._S is None:
            self._S = self.L_sym.copy()
            self._S.diagonalScale(L=self.vec(self.mass))
        return self._S

    def to_scipy(self, root: int = 0, symmetric: bool = False):
        """The stored matrix (``L``, or ``L_sym`` with ``symmetric``) gathered on ``root`` as a
        scipy CSR in the caller's numbering (None on the other ranks); for checks and small
        problems."""
        import scipy.sparse as sp

        if self.matrix_free:
            raise MeshError("a matrix-free operator stores no matrix to gather")
        indptr, cols, data = (self.L_sym if symmetric else self.L).getValuesCSR()
        order = self.comm.gather(self.ids, root=root)
        parts = self.comm.gather((self.ids, indptr, cols, data), root=root)
        if parts is None:
            return None
        uid_of_petsc = np.concatenate(order)
        rows, cc, vv = [], [], []
        for ids, ip, c, d in parts:
            rows.append(np.repeat(ids, np.diff(ip)))
            cc.append(uid_of_petsc[c])
            vv.append(d)
        N = self.n_vertices
        return sp.csr_matrix((np.concatenate(vv), (np.concatenate(rows), np.concatenate(cc))), shape=(N, N))

    def halo_bytes(self, k: int = 1) -> int:
        """Bytes this rank receives from others in one product with k functions."""
        return 8 * k * self.n_halo

    def __repr__(self) -> str:
        kind = "matrix-free" if self.matrix_free else "MPIAIJ"
        return (f"DistributedLaplacian(vertices={self.n_vertices:,}, ranks={self.comm.Get_size()}, "
                f"local={self.n_local:,}, halo={self.n_halo:,}, h={self.h:.6g}, tol={self.tol:.3g}, {kind})")


class _ShellContext:
    """PETSc shell (MatPython) context: scatter the halo values, then the compiled kernel on
    the own rows (:func:`meshlap.assembly.grid.apply` with ``rows``)."""

    def __init__(self, op: DistributedLaplacian) -> None:
        MPI, PETSc = _mpi()
        self.op = op
        n_loc = len(op._Vloc)
        self.xloc = PETSc.Vec().createSeq(n_loc, comm=PETSc.COMM_SELF)
        self.isfrom = PETSc.IS().createGeneral(op._ploc.astype(PETSc.IntType), comm=PETSc.COMM_SELF)
        self.scatter = None

    def _gather(self, x) -> np.ndarray:
        # x's values at own + halo points (a PETSc VecScatter: the halo exchange)
        MPI, PETSc = _mpi()
        if self.scatter is None:
            self.scatter = PETSc.Scatter().create(x, self.isfrom, self.xloc, None)
        self.scatter.scatter(x, self.xloc, addv=PETSc.InsertMode.INSERT_VALUES,
                             mode=PETSc.ScatterMode.FORWARD)
        return self.xloc.getArray(readonly=True)

    def mult(self, mat, x, y) -> None:
        op = self.op
        f = self._gather(x)
        if op.n_local:
            y.setArray(assembly.grid.apply(op._Vloc, op._grid, op.h, f, rows=op._rows)[: op.n_local])

    def apply_block(self, X: np.ndarray) -> np.ndarray:
        """L X for a local block: k halo exchanges, one kernel pass."""
        op = self.op
        x = op.L.createVecRight()
        floc = np.empty((len(op._Vloc), X.shape[1]))
        for j in range(X.shape[1]):
            x.setArray(X[:, j])
            floc[:, j] = self._gather(x)
        if not op.n_local:
            return np.zeros_like(X)
        return assembly.grid.apply(op._Vloc, op._grid, op.h, floc, rows=op._rows)[: op.n_local]

    def getDiagonal(self, mat, d) -> None:
        d.setArray(self.op.diagonal())


# -- the public constructors and solvers ---------------------------------------------------
def laplacian(
    V: Any,
    F: Any = None,
    mass: Any = None,
    *,
    h: float | None = None,
    tol: float | None = None,
    comm: Any = None,
    scattered: bool = False,
    matrix_free: bool = False,
    partition: Any = None,
    correction: str | None = None,
    k: int | None = None,
    progress: ProgressLike = None,
    **options: Any,
) -> DistributedLaplacian:
    r"""Build the Belkin–Sun–Wang Laplacian over the ranks of an MPI communicator (collective).

    The heat kernel (``operator="kernel"`` of :func:`meshlap.laplacian`; the single-machine
    default's FEM pencil is not distributed).

    Parameters
    ----------
    V : (n, 3) array_like
        Points: all of them on every rank (default), or this rank's chunk (``scattered``).
    F : faces, optional
        Faces for the masses m_p = Σ Area(t)/#t: those of the whole mesh (every rank the
        same), which also give the default h = (2·mean edge)²; or, with ``scattered``, any
        share of the faces per rank, in global vertex indices (then ``h`` is required).
    mass : (n,) array_like, optional
        Point masses (for point clouds, curves, volumes or precomputed meshes), aligned
        with ``V``; zero-mass points get rows but contribute to none.
    h : float
        Kernel width (required without F).
    tol : float, optional
        Kernel tolerance, halo r = sqrt(4h ln(1/tol)); default 1e-6 corrected, 1e-8 paper's/curves.
    comm : mpi4py communicator, default MPI.COMM_WORLD
    scattered : bool, default False
        Each rank passes its own chunk, numbered in rank order.
    matrix_free : bool, default False
        A PETSc shell that recomputes rows in each product (no MPIAIJ matrix).
    partition : (n,) array_like of int, optional
        Owner rank of each passed point, instead of the k-d split.
    correction : {"richardson", "none"}, optional
        "none" (or ``operator="paper"``): the paper's operator, eq. (1); default the corrected
        kernel, whose other options (``**options``) are :class:`~meshlap.MeshLaplacian`'s.
    progress : bool or callable, optional
        ``True``: a bar on rank 0's stderr; a callable gets ``(fraction, stage)`` on every rank.

    Returns
    -------
    DistributedLaplacian

    Notes
    -----
    Each stored entry equals the single-machine kernel's bit for bit, on any number of ranks
    and any partition: the same compiled code, each diagonal summed in the same order.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> from meshlap import distributed
    >>> V, F = meshlap.shapes.sphere(500, seed=0)
    >>> op = distributed.laplacian(V, F, correction="none", h=0.01)         # on a one-rank COMM_WORLD here
    >>> Lx = op.gather(op.apply(op.local(V[:, 0])))
    >>> serial = meshlap.laplacian(V, F, h=0.01, correction="none")
    >>> bool(np.allclose(Lx, serial @ V[:, 0], rtol=0, atol=1e-12))
    True
    """
    MPI, PETSc = _mpi()
    comm = MPI.COMM_WORLD if comm is None else comm
    report = make_progress(progress if (progress is not True or comm.Get_rank() == 0) else None)
    operator = options.pop("operator", "kernel")
    if operator not in ("kernel", "paper"):
        raise MeshError(f"distributed.laplacian builds operator='kernel' or 'paper'; got {operator!r} "
                        "(the FEM and Galerkin pencils are single-machine: meshlap.laplacian)")
    correction = "none" if operator == "paper" else correction
    if correction != "none":
        if matrix_free or (F is None and not isinstance(V, Geometry)):
            raise MeshError("the corrected default (correction='richardson') needs faces or a Geometry: "
                            "V and F (scattered or whole), or meshlap.geometry.point_cloud_geometry(P), "
                            "without matrix_free=True; or pass correction='none' for the paper's operator")
        if scattered:
            return _scattered_corrected(comm, V, F, h, tol, partition, correction, options, report)
        return _corrected(comm, V, F, k, h, tol, partition, correction, options, report)
    whole = None
    if options:
        raise MeshError(f"correction='none' is the paper's operator: no {', '.join(sorted(options))}")
    tol = check_tol(DEFAULT_TOL if tol is None else tol)
    V = np.asarray(V, dtype=np.float64)
    V = check_vertices(V) if len(V) else np.zeros((0, 3))
    if F is not None and scattered:
        mass, F = (_scattered_mass(comm, V, F) if mass is None else mass), None
    if F is not None:
        from ..geometry.mass import _face_areas, _mean_edge_length, _vertex_mass, paper_width

        faces = check_faces(F, len(V))
        whole = (V, faces.triangles())
        if mass is None:
            mass = _vertex_mass(V, faces, _face_areas(V, faces))
        if h is None:
            h = paper_width(_mean_edge_length(V, faces))
    if mass is None:
        raise MeshError("pass F (faces) or mass (one mass per point)")
    if h is None:
        raise MeshError("h is required without faces and with scattered faces (the default h "
                        "comes from the mean edge length of the whole mesh)")
    h = check_h(h)
    mass = np.asarray(mass, dtype=np.float64)
    if mass.shape != (len(V),) or not np.isfinite(mass).all() or (mass < 0).any():
        raise MeshError(f"mass must hold one finite, non-negative value per point ({len(V)}); "
                        f"got shape {mass.shape}")
    if scattered:
        start = comm.exscan(len(V), op=MPI.SUM)  # collective; None on rank 0
        uid = (int(start) if comm.Get_rank() > 0 else 0) + np.arange(len(V), dtype=np.int64)
        part = partition
    else:
        # every rank holds everything: each keeps a contiguous slice to start from
        size, rank = comm.Get_size(), comm.Get_rank()
        a, b = len(V) * rank // size, len(V) * (rank + 1) // size
        uid = np.arange(a, b, dtype=np.int64)
        part = None if partition is None else np.asarray(partition)[a:b]
        V, mass = V[a:b], mass[a:b]
    op = DistributedLaplacian(comm, np.ascontiguousarray(V), mass, uid, h, tol, matrix_free, part,
                              report=report)
    op.mesh = whole
    return op


def _corrected(comm, V: Any, F: Any, k: int | None, h: Any, tol: float, partition: Any, correction: Any,
               options: dict, report=None) -> DistributedLaplacian:
    # stages 1-2 on every rank (each holds the whole input), then the rows on their owners
    geo = as_geometry(V, F, k)
    if geo.ambient_dim > 3:
        raise MeshError(f"meshlap.distributed needs points in at most 3 dimensions; these have "
                        f"{geo.ambient_dim}")
    opts = Options.resolve(geo, h, correction=correction, tol=tol, **options)
    widths = widths_mod.choose(geo, h, plain=opts.plain, adaptive=opts.adaptive,
                               curvature_limit=opts.curvature_limit)
    attrs = attributes(geo, widths, opts)
    P = assembly.pad3(geo.points)
    size, rank = comm.Get_size(), comm.Get_rank()
    n = geo.n_points
    a, b = n * rank // size, n * (rank + 1) // size
    part = None if partition is None else np.asarray(partition)[a:b]
    op = DistributedLaplacian(comm, np.ascontiguousarray(P[a:b]), geo.mass[a:b],
                              np.arange(a, b, dtype=np.int64), widths.h, opts.tol, False, part,
                              attrs=attrs, table=attrs.table[a:b], report=report)
    if geo.faces is not None and P.shape[1] == 3:  # LOBPCG's cotangent preconditioner and start
        op.mesh = (P, geo.faces.triangles())
    return op


def _scattered_corrected(comm, V: Any, F: Any, h: Any, tol: float, partition: Any, correction: Any,
                         options: dict, report=None) -> DistributedLaplacian:
    # stages 1-2 by global reductions over the faces each rank holds (meshlap.distributed.scattered)
    from mpi4py import MPI

    V = check_vertices(V) if len(V) else np.zeros((0, 3))
    mass, h0, attrs = scattered_attributes(comm, V, F, h, tol, correction, options)
    start = comm.exscan(len(V), op=MPI.SUM)  # collective; None on rank 0
    uid = (int(start) if comm.Get_rank() > 0 else 0) + np.arange(len(V), dtype=np.int64)
    return DistributedLaplacian(comm, np.ascontiguousarray(V, dtype=np.float64), mass, uid, h0, attrs.tol,
                                False, partition, attrs=attrs, table=attrs.table, report=report)
