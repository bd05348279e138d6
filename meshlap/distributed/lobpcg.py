"""Eigenpairs of the distributed heat-kernel Laplacian without a factorization (issue 19).

A distributed LOBPCG: every MPI rank holds its own rows of the blocks of functions (numpy
arrays of shape (n_local, k)); the operator's product is the only step that talks to other
ranks' rows (its halo exchange), and the small Rayleigh–Ritz problems are the sums over the
ranks of the local Gram matrices (one ``Allreduce`` each), so every rank solves the same
small problem and keeps its share of the Ritz vectors. The iteration is
:func:`meshlap.spectral.eigs`'s LOBPCG, run on the shares.

The preconditioner is the single machine's,

    T = (K + σM)⁻¹ + ½ D⁻¹,

with D = diag(-S) (what saturates the heat-kernel symbol at high frequency) and K a sparse
Laplacian of the same geometry. With a mesh and ``preconditioner="global"`` (the default), K
is the cotangent stiffness assembled as a distributed PETSc matrix and K + σM is factored
once by MUMPS over all ranks (a sparse matrix of about 7 entries per row, not the operator):
exactly the single machine's preconditioner, hence its iteration count on any number of
ranks. Otherwise (``preconditioner="local"``, a point cloud, or a PETSc without MUMPS) it is
block Jacobi over the ranks: each rank factors by a sparse LU its own block K_r + σM_r,
which loses the coupling across the cuts and costs iterations (26 against 12 for 50
eigenpairs of a 100k-vertex sphere on 2 ranks); for a mesh K_r is the block of the cotangent
stiffness on the own rows (the faces touching them); for a point cloud, a graph Laplacian of
the own points' nearest neighbours with heat weights, scaled to the operator's quadratic form
on the coordinate functions, with the weights of each row on other ranks' points on its
diagonal. With a mesh, the start is one step of inverse iteration on a random block,
(K + σM)⁻¹ M X₀, then LOBPCG on the cotangent problem (K as a distributed PETSc matrix,
(K + σM)⁻¹ as preconditioner), whose Ritz values also size the block to hold the k-th
eigenvalue's cluster, as in :func:`meshlap.spectral.eigs`. Memory per rank: the
operator's own rows, the factors of a sparse matrix with a handful of entries per row (its
share of MUMPS's), and about a dozen blocks of n_local × (block width) numbers. See
docs/distributed.md for the measured figures.

Examples
--------
>>> import meshlap, numpy as np
>>> from meshlap import distributed
>>> from meshlap.distributed.lobpcg import eigs
>>> V, F = meshlap.shapes.sphere(2000, seed=0)
>>> lam, phi = eigs(distributed.laplacian(V, F, correction="none", h=0.005), 9, mesh=(V, F))
>>> np.round(lam, 1) + 0.0
array([0. , 2. , 2. , 2. , 5.9, 5.9, 5.9, 5.9, 5.9])
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np
import scipy.sparse as sp

from .. import _eigcheck, _lobpcg, baselines, spectral
from .._jit import one_blas_thread
from ..errors import EigenError, MeshError
from ..geometry.topology import duplicate_vertices
from ..geometry.validation import check_faces, check_k, check_solver, check_vertices
from ..progress import ProgressLike, make_progress, onward
from .comm import _has_mumps

__all__ = ["eigs", "finish"]

# nearest neighbours of the point-cloud preconditioner's graph
_NEIGHBOURS = 10
# iterations of the start on the cotangent problem, as on the single machine; block Jacobi's
# start is slower, and 10 was chosen for it: 2 ranks, random spheres, the operator's own
# iterations after a start of 5, 7, 10 or 20: 8, 7, 6, 6 (8k, k = 20); 6 after 10 or 20 (16k)
_START_ITERATIONS = 10
# problems up to this many points with mass go to rank 0 when the ranks' own solves fail the check
_GATHER = 50_000


def _allsum(comm):
    from mpi4py import MPI

    def allsum(a: np.ndarray) -> np.ndarray:
        a = np.ascontiguousarray(a, dtype=np.float64)
        out = np.empty_like(a)
        comm.Allreduce(a, out, op=MPI.SUM)
        return out

    return allsum


def _mesh_blocks(op: Any, P: np.ndarray, mesh: Any, shift: np.ndarray):
    """The cotangent stiffness K on the points with mass: its rows on this rank as a
    distributed PETSc matrix (columns numbered over the points with mass, rank by rank), the
    same with ``shift`` (σ m) added on the diagonal, and K's own × own block for the local
    factorization; all from the faces touching own rows."""
    from petsc4py import PETSc

    try:
        V, F = mesh
    except (TypeError, ValueError) as exc:
        raise MeshError("mesh must be (V, F): the whole mesh, in the caller's numbering") from exc
    V = check_vertices(V, "mesh[0]")
    if len(V) != op.n_vertices:
        raise MeshError(f"mesh has {len(V)} vertices but the operator has {op.n_vertices}")
    T = check_faces(F, len(V), "mesh[1]").triangles()
    comm = op.comm
    own = op.ids[P]
    # the points with mass, numbered rank by rank (the order of the solver's rows)
    gid = np.full(len(V), -1, dtype=np.int64)
    start = 0
    for part in comm.allgather(own):
        gid[part] = start + np.arange(len(part))
        start += len(part)
    first = int(gid[own[0]]) if len(own) else 0
    # on the welded triangles, each copy tied to its point, as on one machine (spectral._mesh_of):
    # the triangles of the own rows' points, and every copy of their corners
    rep = duplicate_vertices(V)
    mine = np.zeros(len(V), dtype=bool)
    mine[rep[own]] = True
    T = rep[T]
    T = T[mine[T].any(axis=1)]
    used = np.flatnonzero(np.isin(rep, np.union1d(np.unique(T), rep[own])))
    K = spectral._cot_stiffness(V[used], np.searchsorted(used, T), np.arange(len(used)),
                                np.searchsorted(used, rep[used])) if len(T) else None
    # no usable face here (an empty rank, degenerate faces): empty rows, K_r the diagonal term alone
    K = sp.coo_matrix(sp.csr_matrix((len(own), len(used))) if K is None else sp.csr_matrix(K)[
        np.searchsorted(used, own)])
    cols = gid[used][K.col]
    keep = cols >= 0  # no column for points without mass
    K = sp.csr_matrix((K.data[keep], (K.row[keep], cols[keep])), shape=(len(own), start))
    K.eliminate_zeros()
    sizes = ((len(own), start), (len(own), start))

    def petsc(A: sp.csr_matrix):
        A.sort_indices()
        csr = (A.indptr.astype(PETSc.IntType), A.indices.astype(PETSc.IntType), A.data)
        return PETSc.Mat().createAIJ(sizes, csr=csr, comm=comm)

    D = sp.csr_matrix((shift, (np.arange(len(own)), first + np.arange(len(own)))), shape=K.shape)
    block = sp.csc_matrix(K[:, first:first + len(own)])
    return (block if block.nnz else None), petsc(K), petsc(sp.csr_matrix(K + D))


class _GlobalSolve:
    """(K + σM)⁻¹ R for this rank's rows of a block R: the distributed cotangent K + σM
    factored once by MUMPS (KSP "preonly", PC "lu"), applied to the block's columns in one
    ``MatMatSolve`` of the factor."""

    def __init__(self, A) -> None:
        from petsc4py import PETSc

        self.A = A
        self.ksp = PETSc.KSP().create(comm=A.getComm())
        self.ksp.setOperators(A)
        self.ksp.setType("preonly")
        pc = self.ksp.getPC()
        pc.setType("lu")
        pc.setFactorSolverType("mumps")
        self.ksp.setUp()
        self.factor = pc.getFactorMatrix()

    def solve(self, R: np.ndarray) -> np.ndarray:
        from petsc4py import PETSc

        (n_local, n), _ = self.A.getSizes()
        comm = self.A.getComm()
        B = PETSc.Mat().createDense(((n_local, n), (PETSc.DECIDE, R.shape[1])), comm=comm)
        B.setUp()
        B.getDenseArray()[:] = R
        B.assemble()
        X = B.duplicate()
        self.factor.matSolve(B, X)
        out = X.getDenseArray().copy()
        B.destroy()
        X.destroy()
        return out


def _global_solve(A, choice: str) -> _GlobalSolve | None:
    """MUMPS on ``A`` for ``preconditioner="global"`` on more than one rank; None (the local
    LU) on one rank, where PETSc has no MUMPS, or where its factorization fails on any rank
    (the ranks agree, no rank left waiting)."""
    from mpi4py import MPI
    from petsc4py import PETSc

    if choice != "global" or A.getComm().getSize() == 1 or not _has_mumps():
        return None  # one rank: the local LU is the same matrix's, and solves 4x faster than MUMPS
    try:
        solver = _GlobalSolve(A)
        ok = True
    except PETSc.Error:
        solver, ok = None, False
    if not A.getComm().tompi4py().allreduce(ok, op=MPI.LAND):
        warnings.warn("eigs: the MUMPS factorization of the cotangent K + σM failed; block Jacobi instead",
                      RuntimeWarning, stacklevel=3)
        return None
    return solver


def _rank_colors(op: Any) -> tuple[np.ndarray, int]:
    """A colour per rank such that ranks whose points come within the kernel radius differ
    (greedy, in rank order, on the bounding boxes of the own points)."""
    V = op.V
    box = (np.concatenate([V.min(axis=0), V.max(axis=0)]) if len(V)
           else np.concatenate([np.full(3, np.inf), np.full(3, -np.inf)]))
    boxes = np.array(op.comm.allgather(box))
    r = op.radius if math.isfinite(op.radius) else np.inf
    near = np.all((boxes[:, None, :3] <= boxes[None, :, 3:] + r)
                  & (boxes[None, :, :3] <= boxes[:, None, 3:] + r), axis=2)
    colors = np.full(len(boxes), -1)
    for q in range(len(boxes)):
        taken = set(colors[near[q]].tolist())
        colors[q] = next(c for c in range(len(boxes)) if c not in taken)
    return colors, int(colors.max()) + 1


def _leak(op: Any) -> np.ndarray:
    """-Σ_{j not own} L_ij for the own rows: the coupling that the own block of -S keeps on its
    diagonal and a graph of the own points lacks (one product of a block of rank colours)."""
    colors, n_colors = _rank_colors(op)
    X = np.zeros((op.n_local, n_colors))
    X[:, colors[op.comm.Get_rank()]] = 1.0
    return np.maximum(-_product(op, X)[:, colors[op.comm.Get_rank()]], 0.0)


def _cloud_block(op: Any, P: np.ndarray, m: np.ndarray, allsum) -> sp.csc_matrix | None:
    """A k-nearest-neighbour graph Laplacian of the own points, on the operator's scale.

    Weights m_i m_j exp(-d²/ε), ε the mean squared neighbour distance; the scale c makes
    x·(cG)x equal x·(-S)x summed over the three coordinate functions (smooth, so both forms
    approximate ∫|∇x|² there). The own block of -S also holds on its diagonal the weights to
    other ranks' points, m_i Σ_{j not own} (-L_ij); they are added, as in a Dirichlet block.
    """
    from pykdtree.kdtree import KDTree

    X = np.ascontiguousarray(op.V[P])
    nb = min(_NEIGHBOURS + 1, len(X))
    if nb < 2:
        G = None
    else:
        d, j = KDTree(X).query(X, k=nb)
        d, j = d[:, 1:], j[:, 1:].astype(np.int64)
        eps = max(float(np.mean(d * d)), 1e-300)
        i = np.repeat(np.arange(len(X)), nb - 1)
        w = (m[i] * m[j.ravel()]) * np.exp(-(d.ravel() ** 2) / eps)
        W = sp.csr_matrix((w, (i, j.ravel())), shape=(len(X),) * 2)
        W = W.maximum(W.T)
        G = sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W
    Y = np.zeros((op.n_local, 3))
    Y[P] = op.V[P]
    SX = -(m[:, None] * _product(op, Y)[P])
    local = [float(np.sum(Y[P] * SX)), 0.0 if G is None else float(np.sum(X * (G @ X)))]
    quad_S, quad_G = allsum(np.array(local))
    leak = m * _leak(op)[P]
    if G is None or not (quad_G > 0 and quad_S > 0):
        return sp.diags(leak, format="csc") if leak.any() else None
    return sp.csc_matrix((quad_S / quad_G) * G + sp.diags(leak))


def _product(op: Any, X: np.ndarray) -> np.ndarray:
    """L X for a local block: one PETSc MatMatMult with a dense block for a stored operator
    (the matrix is read once, not once per column), the shell's block product otherwise."""
    return op.apply(X) if op.matrix_free else _matmat(op.L_sym, X)


def _matmat(A, X: np.ndarray) -> np.ndarray:
    """A X for a distributed PETSc matrix and this rank's rows of a dense block."""
    from petsc4py import PETSc

    (n_local, n), _ = A.getSizes()
    D = PETSc.Mat().createDense(((n_local, n), (PETSc.DECIDE, X.shape[1])), comm=A.getComm())
    D.setUp()
    D.getDenseArray()[:] = X
    D.assemble()
    C = A.matMult(D)
    out = C.getDenseArray().copy()
    C.destroy()
    D.destroy()
    return out


def eigs(
    op: Any,
    k: int = 20,
    *,
    tol: float = 1e-8,
    maxiter: int = 300,
    extra: int | None = None,
    mesh: tuple[Any, Any] | None = None,
    preconditioner: str = "global",
    seed: int = 0,
    info: dict | None = None,
    progress: ProgressLike = None,
    count: bool | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    r"""The k smallest eigenpairs of ``-S φ = λ M φ`` by distributed LOBPCG (collective), verified.

    No factorization of the operator: it is only multiplied (stored or matrix-free); the
    preconditioner factors a sparse Laplacian of the same geometry (module notes).

    Parameters
    ----------
    op : DistributedLaplacian
        Stored or matrix-free.
    k : int, default 20
        Number of eigenpairs.
    tol : float, default 1e-8
        Relative accuracy of the eigenvalues, as in :func:`meshlap.spectral.eigs` (a bound
        from the residuals; eigenvectors then accurate to about √tol); 0 asks for machine precision.
    maxiter : int, default 300
        Iterations before giving up with a warning.
    extra : int, optional
        Guard vectors; by default as in :func:`meshlap.spectral.eigs` (enough to hold the
        cluster of the k-th eigenvalue, seen in the cotangent start).
    mesh : (V, F), optional
        The whole mesh in the caller's numbering (the same on every rank): the preconditioner
        is then its cotangent Laplacian; without it, a nearest-neighbour graph of the points.
        Default: the mesh the operator was built from (``op.mesh``: ``laplacian(V, F)`` with
        the whole faces), else none.
    preconditioner : {"global", "local"}, default "global"
        With a mesh, ``"global"`` factors the distributed cotangent K + σM with MUMPS (the
        single machine's preconditioner exactly, so about its iteration count); ``"local"``
        (block Jacobi) factors each rank's own block alone, which loses the coupling across
        the ranks' cuts. Without a mesh, or with a PETSc built without MUMPS, block Jacobi.
    seed : int, default 0
        Seed of the random start vectors (with the rank).
    info : dict, optional
        Filled with the last LOBPCG run's ``iterations``, relative ``residuals``
        ``‖r‖ / max(λ, λ_k)``, eigenvalue ``error_bounds`` relative to tol's scale, ``block``
        width and cotangent start's ``start_iterations`` (0 without a mesh); and with the
        check's ``method``, ``tried``, ``bounds``, ``orthogonality``, ``count``, ``shift``,
        ``complete`` and ``uncertified``, as in :func:`meshlap.spectral.eigs`.
    count : bool, optional
        Count the eigenvalues below a shift above λ_k (on the pencil gathered on rank 0) to show
        that none is missing. Default: for a sparse pencil (at most 40 entries per row) of at
        most 50,000 points; ``True`` always (a result that cannot be counted then raises).

    Raises
    ------
    meshlap.EigenError
        On every rank, when no solver's pairs pass the check (:func:`meshlap.spectral.eigs`):
        LOBPCG, LOBPCG with a wider block and twice the iterations, and, up to 50,000 points
        with mass, :func:`meshlap.spectral.eigs` on the pencil gathered on rank 0.
    progress : bool or callable, optional
        As in :func:`meshlap.spectral.eigs`: ``True`` draws a bar on rank 0's stderr; a
        callable gets ``(fraction, stage)`` on every rank, the same calls everywhere.

    Returns
    -------
    lam : (k,) ndarray
        Eigenvalues, ascending, on every rank.
    phi : (n_local, k) ndarray
        This rank's rows of the M-orthonormal eigenvectors (signs as in
        :func:`meshlap.spectral.eigs`); zero-mass points take the kernel-weighted mean of
        their row.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> from meshlap import distributed
    >>> V = meshlap.shapes.sphere(1500, seed=0)[0]
    >>> op = distributed.laplacian(V, mass=np.full(1500, 4 * np.pi / 1500), correction="none", h=0.01)
    >>> lam, _ = eigs(op, 4)
    >>> np.round(lam, 2) + 0.0
    array([0., 2., 2., 2.])
    """
    from mpi4py import MPI

    comm = op.comm
    tol = check_solver(tol, maxiter, extra, seed)
    if preconditioner not in ("global", "local"):
        raise MeshError(f"preconditioner must be 'global' or 'local'; got {preconditioner!r}")
    m_all = np.asarray(op.mass, dtype=np.float64)
    P = np.flatnonzero(m_all > 0)
    m = m_all[P]
    n_p = comm.allreduce(len(P), op=MPI.SUM)
    if n_p == 0:
        raise MeshError("every point has zero mass: the operator has no surface")
    k = check_k(k, n_p)
    nb = min(k + (max(4, k // 10) if extra is None else int(extra)), n_p)
    mesh = getattr(op, "mesh", None) if mesh is None else mesh
    allsum = _allsum(comm)
    full = len(P) == op.n_local
    # a retry (LOBPCG wider, the gathered solve) starts its stages over
    report = onward(make_progress(progress if (progress is not True or comm.Get_rank() == 0) else None))
    if report is not None:
        report(0.0, "preconditioner")

    def apply_A(Xp: np.ndarray) -> np.ndarray:
        if full:
            return -m[:, None] * _product(op, Xp)
        X = np.zeros((op.n_local, Xp.shape[1]))
        X[P] = Xp
        return -m[:, None] * _product(op, X)[P]

    L_ii = op.diagonal()[P]  # collective: every rank calls it, an empty one too
    diag = -m * L_ii
    sigma = 4.0 * math.pi / float(allsum(np.array([m.sum()]))[0])
    # the check's yardstick near λ = 0: what roundoff leaves of A x on the stiffest row of any rank
    stiff = comm.allreduce(float(np.abs(L_ii).max()) if len(P) else 0.0, op=MPI.MAX)
    glob = None
    if mesh is None:
        K, Kg = _cloud_block(op, P, m, allsum), None
    else:
        K, Kg, Ag = _mesh_blocks(op, P, mesh, sigma * m)
        glob = _global_solve(Ag, preconditioner)
    T = _lobpcg.CotPreconditioner(K if len(P) and glob is None else None, m, diag, sigma)
    if glob is not None:  # T R = ½ D⁻¹ R + (K + σM)⁻¹ R, the second term now over all ranks
        half = T

        def T(R: np.ndarray) -> np.ndarray:
            return half(R) + glob.solve(R)

    def local(R: np.ndarray) -> np.ndarray:  # (K + σM)⁻¹ alone, for the cotangent start
        if glob is not None:
            return glob.solve(R)
        return R / (sigma * m[:, None]) if T.lu is None else T.lu.solve(R)
    adapt = extra is None and Kg is not None
    rank = comm.Get_rank()
    facts: dict = {}

    def run_lobpcg(wide: bool):
        def run(want: int):
            # past k, all that the count asked for converge (λ_k's ties, or values skipped)
            goal = max(k, min(want, n_p // 3 - (nb - k)))
            more = (nb - k) + (max(4, k // 2) if wide else 0)
            rng = np.random.default_rng([seed + wide, rank])

            def random(c: int) -> np.ndarray:
                return rng.standard_normal((len(P), min(c, n_p)))
            start = 0
            with one_blas_thread():
                if Kg is None:
                    X0 = random(goal + more)
                else:
                    # start from the cotangent eigenvectors, (K + σM)⁻¹ (global or per rank) as
                    # preconditioner, as on the single machine
                    X0, start = _lobpcg.cotangent_start(
                        lambda Y: _matmat(Kg, Y), m, local, random, goal, goal + more, n_p,
                        spectral._START_TOL, _START_ITERATIONS, allsum, adapt=adapt and not wide,
                        report=_lobpcg.lobpcg_progress(report, "cotangent start", 0.05, 0.2))
                ceiling = (lambda lam: _eigcheck.count_ceiling(lam, k, tol, floor)) if counted else None
                out = _lobpcg.lobpcg(apply_A, m, T, X0, goal, tol, 2 * maxiter if wide else maxiter, allsum,
                                     least=0.01 * sigma, ceiling=ceiling,
                                     report=_lobpcg.lobpcg_progress(report, "LOBPCG", 0.2, 1.0))
            lam = out.lam
            scale = np.maximum(np.abs(lam[:k]), abs(float(lam[k - 1])))
            facts.update(iterations=out.iterations, residuals=out.residuals[:k] / scale,
                         error_bounds=out.ratio[:k], block=X0.shape[1],
                         start_iterations=start)
            return out.lam, out.X, out.iterations
        return run

    attempts = [_eigcheck.Attempt("lobpcg", run_lobpcg(False)),
                _eigcheck.Attempt("lobpcg (wider)", run_lobpcg(True))]
    gathered = _Gathered(op, P, tol) if not op.matrix_free else None
    small = gathered is not None and n_p <= _GATHER
    if small:
        attempts.append(_eigcheck.Attempt("gathered", gathered.solve))
    sparse = gathered is not None and gathered.nnz() <= spectral._SPARSE_ROW_MAX * op.n_vertices
    counted = gathered is not None and ((sparse and small) if count is None else bool(count))
    checked: dict = {}
    with one_blas_thread():
        floor = _eigcheck.roundoff_floor(stiff, tol, sigma)
        lam, X = _eigcheck.first_verified(attempts, k, apply_A, m, tol, floor,
                                          gathered.count if counted else None, bool(count), allsum,
                                          info=checked)
    _eigcheck.warn_roundoff(lam, tol, floor, sigma, stiff, checked)  # lam and stiff: the same on every rank
    if info is not None:
        info.update(facts, **checked)
    if report is not None:
        report(1.0, "done")
    return finish(op, P, lam, X)


class _Gathered:
    """The pencil gathered on rank 0 (collective calls): the count of its eigenvalues below a
    shift (:func:`meshlap._eigcheck.count_below`), and :func:`meshlap.spectral.eigs` on it, a
    fallback for problems small enough for one machine; the vectors' own rows go back to each
    rank."""

    def __init__(self, op: Any, P: np.ndarray, tol: float) -> None:
        self.op, self.P, self.tol = op, P, tol
        self._pencil = None

    def nnz(self) -> int:
        from petsc4py import PETSc

        return int(self.op.L_sym.getInfo(PETSc.Mat.InfoType.GLOBAL_SUM)["nz_used"])

    def pencil(self):
        if self._pencil is None:
            L = self.op.to_scipy(root=0, symmetric=True)
            mass = self.op.gather(self.op.mass, root=0)
            self._pencil = (None if L is None else baselines.SparseLaplacian(L, mass),)
        return self._pencil[0]

    def count(self, sigma: float) -> int | None:
        pencil = self.pencil()
        n = None
        if pencil is not None:
            P = np.flatnonzero(pencil.mass > 0)
            n = _eigcheck.count_below(-spectral._restricted_S(pencil, P), pencil.mass[P], sigma)
        return self.op.comm.bcast(n, root=0)

    def solve(self, want: int):
        pencil = self.pencil()
        out = None
        if pencil is not None:
            try:
                n_p = int((pencil.mass > 0).sum())
                lam, phi = spectral.eigs(pencil, min(want + 1, n_p - 1), tol=self.tol)
                out = (lam, phi)
            except EigenError:
                out = None
        lam = self.op.comm.bcast(None if out is None else out[0], root=0)
        phi = self.op.comm.bcast(None if out is None else out[1], root=0)
        if lam is None:  # rank 0's solver failed too: pairs that fail the check
            return np.zeros(want), np.zeros((len(self.P), want)), 0
        return lam, phi[self.op.ids[self.P]], 0


def finish(op: Any, P: np.ndarray, lam: np.ndarray, vecs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvectors on the own rows with mass ``P`` → all own rows, M-normalized, signed.

    Zero-mass rows take the kernel-weighted mean of their row of L (the single machine's
    extension); the entry of largest magnitude is made positive, ties to the lowest vertex
    index (collective).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> from meshlap import distributed
    >>> V, F = meshlap.shapes.sphere(300, seed=0)
    >>> op = distributed.laplacian(V, F, h=0.02)
    >>> lam, phi = finish(op, np.arange(op.n_local), np.zeros(1), -np.ones((op.n_local, 1)))
    >>> bool(np.allclose(phi, 1 / np.sqrt(op.mass.sum())))
    True
    """
    from mpi4py import MPI

    comm, m, k = op.comm, op.mass, len(lam)
    allsum = _allsum(comm)
    vecs = vecs / np.sqrt(allsum((m[P, None] * vecs * vecs).sum(axis=0)))
    phi = np.zeros((op.n_local, k))
    phi[P] = vecs
    Z = np.setdiff1d(np.arange(op.n_local), P)
    if comm.allreduce(len(Z), op=MPI.SUM):
        ind = np.zeros((op.n_local, 1))
        ind[P] = 1.0
        LY = op.apply(np.hstack([phi, ind]), symmetric=True)[Z]
        den = LY[:, -1]
        big = comm.allreduce(float(np.abs(den).max()) if len(Z) else 0.0, op=MPI.MAX)
        ok = den > 1e-12 * max(big, 1e-300)
        phi[Z[ok]] = LY[ok, :-1] / den[ok, None]
    none = np.iinfo(np.int64).max
    amax = np.abs(phi).max(axis=0) if op.n_local else np.zeros(k)
    gmax = np.empty_like(amax)
    comm.Allreduce(amax, gmax, op=MPI.MAX)
    cand = (np.where(np.abs(phi) == gmax, op.ids[:, None], none).min(axis=0) if op.n_local
            else np.full(k, none))
    first = np.empty_like(cand)
    comm.Allreduce(cand, first, op=MPI.MIN)
    sign = np.zeros(k)
    for j in range(k):
        hit = np.flatnonzero(op.ids == first[j])
        if len(hit):
            sign[j] = 1.0 if phi[hit[0], j] >= 0 else -1.0
    sign = allsum(sign)
    return lam, phi * np.where(sign == 0, 1.0, sign)
