"""The block eigensolver behind :func:`meshlap.spectral.eigs` and the distributed one.

LOBPCG (Knyazev 2001) for ``A x = λ M x`` with ``M = diag(m) > 0``, in the basis selection of
Hetmaniuk and Lehoucq (2006): the search directions W and P are kept M-orthonormal and M-orthogonal
to the Ritz vectors X, so the mass Gram matrix of the basis [X, W, P] is the identity and is never
formed; of the operator's Gram matrix only the rows of W are products over the long dimension (X's
own block is diag(θ); P is the basis times coefficients E orthogonal to the Ritz vectors' C, so
P.T A X = 0 and P.T A P = E.T G E come from the last small problem), and P's update is found and
orthonormalized in the small coefficient space; X and P are kept side by side in one array, so that
each of these products is one BLAS call. What stays proportional to n per iteration is one product
with A, one preconditioner application, the orthogonalization of W and the combinations that form
the new X and P.

The convergence test is on the eigenvalues, not the residuals: a Ritz value θ_i whose residual is
r_i = A x_i - θ_i M x_i lies within ``‖r_i‖`` of an eigenvalue (Bauer–Fike in the M⁻¹ norm) and,
when the Ritz values within ``_WINDOW`` of it are the whole cluster that holds it, within
``‖R_c‖₂² / δ`` (Kato–Temple for the cluster: R_c the block of their residuals, ‖·‖₂ its spectral
norm in the M⁻¹ inner product, δ the distance to the nearest Ritz value outside; Mathias 1998, Li
and Li 2013). The spectral norm is the largest eigenvalue of the cluster's share of the residuals'
Gram matrix: for a cluster of c near-orthogonal residuals of like size it is about 1/c of the sum of
their squares, which ends the iteration on a sphere's (2l+1)-fold eigenvalues one iteration sooner.
A relative eigenvalue accuracy ε so needs a residual of only about √(ε·θ·δ), not ε·θ: half the
iterations for ε = 1e-8.

The product with a stored operator (:func:`csr_times`) adds 16 entries of a row per pass over the
row's accumulator, in the entries' order: the accumulator's load and store per entry, not the
reading of the matrix, bounded the plain loop. Its rows are shared, in shares of equal entries,
among meshlap's own threads (:func:`meshlap._jit.each_thread`'s pool), each running the compiled
loop with one numba thread. numba's OpenMP workers, which a parallel loop on numba's threads would
use, keep spinning for about 8 ms of CPU after each loop (GNU OpenMP's default wait policy): on two
cores they took the second core from the dense steps that follow each product, and their CPU time
counted against the solve. meshlap's threads sleep when idle, and the process's threading settings
(``OMP_WAIT_POLICY``, numba's threading layer) stay the user's.

The products over the long dimension (``A @ B`` with a small B, ``A.T @ B``) share their rows among
the same threads (:func:`matmul`, :func:`inner`), BLAS staying on one thread each: a threaded BLAS
here competed with the spinning OpenMP workers of the products (3-10× slower, measured when the
products ran on numba's threads), where a share of the rows per thread does not. ``A.T @ B`` adds
the products of fixed blocks of rows in a fixed order, so that the results do not depend on the
number of threads.

The preconditioner factor is a sparse LDLᵀ (:mod:`meshlap._ldl`), applied to wide blocks with
blocked triangular solves compiled here: one pass over each factor serves every column of the block,
where the factorization's own solve treats the columns one after the other; in single precision, as
a preconditioner needs no more (:class:`BlockFactor`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, NamedTuple

import numba
import numpy as np
import scipy.sparse as sp
from numba import prange
from scipy.linalg import blas

from . import _ldl
from ._jit import _threads, jit

__all__ = ["BlockFactor", "CotPreconditioner", "Ritz", "combine", "cotangent_start", "csr_times", "eig_error",
           "inner", "lobpcg", "lobpcg_progress", "matmul", "svqb"]

# the relative width of the k-th eigenvalue's cluster that LOBPCG's block must hold
_CLUSTER = 0.1
# the relative half-width of the window of Ritz values counted as one cluster by the bound
_WINDOW = 0.05
# rows per block of the products over the long dimension (module notes)
_ROWS = 4096
# every this many iterations the basis' M-orthonormality is audited; beyond _DRIFT, a restart
_AUDIT = 10
_DRIFT = 1e-8

# entries summed per pass over a row's accumulator (module notes): 37% less time for 40 columns
# of the 16k default than one a pass, the same sums to the bit
_UNROLL = 16


# compiled as a parallel loop for the code numba's parfor lowering makes of it (the column loop
# vectorized; the same loop compiled serially ran 6× slower, measured), but always called with
# one numba thread, on row shares run by meshlap's own threads (module notes)
@jit(parallel=True)
def _spmm(indptr, indices, data, X, Y, scale):  # pragma: no cover - compiled
    n = len(indptr) - 1
    k = X.shape[1]
    for i in prange(n):
        acc = np.zeros(k)
        p, end = indptr[i], indptr[i + 1]
        while p < end:
            step = min(_UNROLL, end - p)
            if step == _UNROLL:
                for c in range(k):
                    s = acc[c]
                    for q in range(_UNROLL):
                        s += data[p + q] * X[indices[p + q], c]
                    acc[c] = s
            else:
                for q in range(step):
                    j = indices[p + q]
                    a = data[p + q]
                    for c in range(k):
                        acc[c] += a * X[j, c]
            p += step
        Y[i] = acc * scale[i]


# products with fewer multiply-adds than this run on the calling thread alone
_SERIAL_WORK = 1 << 17


def csr_times(A: sp.csr_matrix, X: np.ndarray, scale: np.ndarray | None = None) -> np.ndarray:
    """``A @ X`` for a CSR matrix (rows in any column order) and a block, on meshlap's threads;
    with ``scale``, row i of the product times ``scale[i]`` (``diag(scale) @ A @ X``, in the
    same pass). Each row is summed by the same code whatever the number of threads.

    Examples
    --------
    >>> A = sp.csr_matrix(np.array([[2.0, 1.0], [0.0, 3.0]]))
    >>> csr_times(A, np.ones((2, 2))).tolist()
    [[3.0, 3.0], [3.0, 3.0]]
    >>> csr_times(A, np.ones((2, 1)), np.array([-1.0, 0.5])).tolist()
    [[-3.0], [1.5]]
    """
    Y = np.empty((A.shape[0], X.shape[1]))
    scale = np.ones(A.shape[0]) if scale is None else np.asarray(scale, dtype=np.float64)
    X = np.ascontiguousarray(X, dtype=np.float64)
    indptr = A.indptr
    threads, _ = _threads()
    shares = 1 if A.nnz * X.shape[1] < _SERIAL_WORK else threads
    # row shares of equal entries
    edges = np.searchsorted(indptr, np.linspace(0, A.nnz, shares + 1), side="left").tolist()
    edges[0], edges[-1] = 0, A.shape[0]

    def share(a: int, b: int) -> None:
        was = numba.get_num_threads()
        numba.set_num_threads(1)  # this thread runs the kernel's loop itself
        try:
            for t in range(a, b):
                lo, hi = edges[t], edges[t + 1]
                _spmm(indptr[lo:hi + 1], A.indices, A.data, X, Y[lo:hi], scale[lo:hi])
        finally:
            numba.set_num_threads(was)

    _in_threads(share, shares, 2)
    return Y


def _in_threads(fn: Callable[[int, int], None], n: int, least: int) -> None:
    """``fn(start, stop)`` over contiguous shares of ``range(n)``, one per numba thread (the
    calling thread takes the first); serially for ``n < least``."""
    threads, pool = _threads()
    if pool is None or n < least:
        fn(0, n)
        return
    edges = np.linspace(0, n, min(threads, n) + 1).astype(np.int64).tolist()
    shares = [pool.submit(fn, a, b) for a, b in zip(edges[1:-1], edges[2:], strict=True)]
    fn(edges[0], edges[1])
    for share in shares:
        share.result()


def matmul(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``A @ B`` for a tall A (n × p) and a small B, A's rows shared among the threads.

    Examples
    --------
    >>> A, B = np.ones((10000, 3)), np.ones((3, 2))
    >>> matmul(A, B)[-1].tolist()
    [3.0, 3.0]
    """
    out = np.empty((A.shape[0], B.shape[1]))

    def share(a: int, b: int) -> None:
        np.matmul(A[a:b], B, out=out[a:b])

    _in_threads(share, A.shape[0], 2 * _ROWS)
    return out


def inner(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``A.T @ B`` for tall A and B: the sum of the products of blocks of ``_ROWS`` rows, in
    block order, so that the result does not depend on the number of threads.

    Examples
    --------
    >>> A = np.arange(20000.0).reshape(10000, 2) / 1e4
    >>> bool(np.allclose(inner(A, A), A.T @ A, rtol=1e-14))
    True
    """
    n = A.shape[0]
    if n <= _ROWS:
        return A.T @ B
    starts = list(range(0, n, _ROWS))
    parts = np.empty((len(starts), A.shape[1], B.shape[1]))

    def share(a: int, b: int) -> None:
        for i in range(a, b):
            lo = starts[i]
            np.matmul(A[lo:lo + _ROWS].T, B[lo:lo + _ROWS], out=parts[i])

    _in_threads(share, len(starts), 2)
    return parts.sum(axis=0)


def combine(pairs: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]) -> list[np.ndarray]:
    """``A @ CA + B @ CB`` for each (A, CA, B, CB), tall A and B, rows shared among the threads
    in one pass: the second product is added in place by BLAS, no temporary.

    Examples
    --------
    >>> A, B = np.ones((10000, 3)), np.ones((10000, 2))
    >>> combine([(A, np.ones((3, 2)), B, np.ones((2, 2)))])[0][-1].tolist()
    [5.0, 5.0]
    """
    outs = [np.empty((A.shape[0], CA.shape[1])) for A, CA, _, _ in pairs]

    def share(a: int, b: int) -> None:
        for (A, CA, B, CB), out in zip(pairs, outs, strict=True):
            np.matmul(A[a:b], CA, out=out[a:b])
            _gemm_add(out[a:b], B[a:b], CB)

    _in_threads(share, pairs[0][0].shape[0], 2 * _ROWS)
    return outs


def _gemm_add(out: np.ndarray, A: np.ndarray, C: np.ndarray) -> None:
    # out += A @ C in place (C-ordered out and A): as the transposes' Fortran-ordered product
    if out.size:
        blas.dgemm(1.0, np.asfortranarray(C.T), A.T, beta=1.0, c=out.T, overwrite_c=1)


class BlockFactor:
    """The factorization of a symmetric positive definite matrix (:func:`meshlap._ldl.factor`),
    solved for a block of right-hand sides at once.

    Blocks wider than 8 columns are solved in single precision (factors and block): that is
    for a preconditioner, to which ~6 digits are plenty, and the solve, bound by the reading
    of the factors and the block's scattered rows, takes 30-40% less time (26 columns of a
    random 100k/400k-vertex sphere's cotangent factor: relative difference 7e-7/3e-6).

    Examples
    --------
    >>> import scipy.sparse as sp, numpy as np
    >>> A = sp.diags([-1.0, 2.5, -1.0], [-1, 0, 1], shape=(50, 50))
    >>> B = np.random.default_rng(0).standard_normal((50, 3))
    >>> bool(np.allclose(A @ BlockFactor(A).solve(B), B))
    True
    >>> B = np.random.default_rng(0).standard_normal((50, 12))      # the single-precision path
    >>> bool(np.allclose(A @ BlockFactor(A).solve(B), B, atol=1e-5))
    True
    """

    def __init__(self, A: sp.spmatrix) -> None:
        self.factor = _ldl.factor(A)
        self._tri = None

    def solve(self, B: np.ndarray) -> np.ndarray:
        """A⁻¹ B for B of shape (n,) or (n, c)."""
        B = np.asarray(B, dtype=np.float64)
        if B.ndim == 1 or B.shape[1] <= _ldl.NARROW:
            return self.factor.solve(B)
        if self._tri is None:  # the factors as CSR in single precision, made on the first wide block
            into, lower, upper, diag, out = self.factor.triangles()
            self._tri = (into, sp.csr_matrix(lower, dtype=np.float32), sp.csr_matrix(upper, dtype=np.float32),
                         diag.astype(np.float32), out)
        into, lower, upper, diag, out = self._tri
        X = np.empty(B.shape, dtype=np.float32)
        X[into] = B
        _ldl.triangular_solves(lower, upper, diag, X)
        return X[out].astype(np.float64)


class CotPreconditioner:
    """T R = (K + σM)⁻¹ R + ½ D⁻¹ R (see :mod:`meshlap.spectral`); K a sparse stiffness
    (the cotangent Laplacian's) or None for the diagonal term alone; ``factor`` what inverts it."""

    def __init__(self, K: sp.spmatrix | None, m: np.ndarray, diag: np.ndarray, sigma: float,
                 factor: Callable[[sp.spmatrix], Any] | None = None) -> None:
        self.K = K
        self.m = m
        self.sigma = sigma
        self.lu = None if K is None else (factor or BlockFactor)(K + sp.diags(sigma * m))
        typical = float(np.median(diag / m)) if len(m) else 1.0  # no rows: an MPI rank without any
        d = np.where(diag > 0, diag, m * max(typical, 1e-300))
        self.half_inv_diag = 0.5 / d

    def __call__(self, R: np.ndarray) -> np.ndarray:
        out = self.half_inv_diag[:, None] * R
        if self.lu is not None:
            out += self.lu.solve(R)
        return out


def _local(a: np.ndarray) -> np.ndarray:
    return a


def svqb(U: np.ndarray, m: np.ndarray, drop: float = 1e-10, allsum=_local) -> tuple[np.ndarray, np.ndarray]:
    """M-orthonormalize the columns of U (dropping near-dependent directions): U @ T."""
    G = allsum(inner(U, m[:, None] * U))
    d = np.sqrt(np.abs(np.diag(G)))
    d[d == 0] = 1.0
    w, Q = np.linalg.eigh(G / d[:, None] / d[None, :])
    keep = w > drop * max(float(w.max()), 1e-300)
    T = (Q[:, keep] / np.sqrt(w[keep])) / d[:, None]
    return matmul(U, T), T


def _orthogonalize(W: np.ndarray, XP: np.ndarray, mc: np.ndarray, allsum, again: bool) -> np.ndarray:
    """W ← W - XP XPᵀ M W in place (XP M-orthonormal) by classical Gram–Schmidt; with
    ``again``, a second pass for the columns that the first shrank below 1/√2 of their norm.
    Returns the columns to keep: those left with more than 1e-10 of their norm (1e-6 after
    one pass), the others being rounding error.

    Kahan and Parlett's criterion: a column that keeps most of its norm loses little to
    cancellation, and one pass leaves it orthogonal to about the rounding error; "twice is
    enough" for the others. LOBPCG's preconditioned residuals keep 0.66-1 of their norm (36
    eigenpairs of a 16,000-vertex sphere), so the second pass is rare. A column that lies in
    XP's span to within the rounding error is not: what is left of it is noise, far from
    orthogonal relative to its own size, and normalized it would enter the basis as a
    direction that is not M-orthogonal to the rest (issue 38: with the exact preconditioner of
    a cotangent pencil, whose converged columns' corrections lie in the span, such columns
    made the block collapse onto the constant function, ten Ritz values of 0).

    Examples
    --------
    >>> XP = np.eye(3)[:, :1]
    >>> W = np.array([[1.0, 1.0], [0.0, 1e-9], [0.0, 0.0]])
    >>> _orthogonalize(W, XP, np.ones((3, 1)), _local, True).tolist()   # the first: XP's own
    [False, True]
    >>> W.tolist()
    [[0.0, 0.0], [0.0, 1e-09], [0.0, 0.0]]
    """
    MW = mc * W
    C = allsum(inner(XP, MW))
    before = allsum(np.einsum("ij,ij->j", W, MW))
    W -= matmul(XP, C)
    # the squared norms after the pass, by Pythagoras (inexact exactly where it cancelled)
    redo = np.flatnonzero(before - np.sum(C * C, axis=0) < 0.5 * before)
    keep = np.ones(W.shape[1], dtype=bool)
    if not len(redo):
        return keep
    Wr = W[:, redo]
    if again:
        Wr -= matmul(XP, allsum(inner(XP, mc * Wr)))
        W[:, redo] = Wr
    after = allsum(np.einsum("ij,ij->j", Wr, mc * Wr))
    keep[redo] = after > (1e-20 if again else 1e-12) * before[redo]
    return keep


def _drifted(X: np.ndarray, mc: np.ndarray, allsum) -> bool:
    """Whether X has drifted from M-orthonormality by more than ``_DRIFT`` (any entry)."""
    G = allsum(inner(X, mc * X))
    return bool(np.abs(G - np.eye(len(G))).max() > _DRIFT)


def _restart(X: np.ndarray, m: np.ndarray, apply_A, allsum, nb: int):
    """M-orthonormal Ritz vectors from the span of X (nb of them: random directions, the same
    on every share's rows of a seed, fill what the span lost) and their products."""
    Y, _ = svqb(X, m, allsum=allsum)
    if Y.shape[1] < nb:
        extra = np.random.default_rng(Y.shape[1]).standard_normal((len(m), nb - Y.shape[1]))
        _orthogonalize(extra, Y, m[:, None], allsum, True)
        Y = np.hstack([Y, svqb(extra, m, allsum=allsum)[0]])[:, :nb]
    AY = apply_A(Y)
    lam, Q = np.linalg.eigh(allsum(inner(Y, AY)))
    return matmul(Y, Q), matmul(AY, Q), lam


def eig_error(theta: np.ndarray, res: np.ndarray, gram: np.ndarray | None = None,
              ceiling: float | None = None) -> np.ndarray:
    """Bound on the distance from each Ritz value to the spectrum (module notes).

    ``res`` holds the residual norms; ``gram``, the residuals' Gram matrix ``R.T M⁻¹ R``
    (its diagonal ``res²``), gives each cluster's spectral norm. Without it the sum of the
    cluster's squared residuals stands in for the squared spectral norm (an upper bound on it).
    The gap above a cluster is to the next Ritz value outside it, or, for the top one, to
    ``ceiling`` (a bound below the eigenvalues past θ); else the top cluster keeps Bauer–Fike's
    ‖r‖ (a block ending among 13 values within 1e-5 had certified 4e-7 errors as 2e-9).

    Examples
    --------
    >>> theta, res = np.array([1.0, 1.001, 2.0]), np.array([1e-4, 1e-4, 1e-3])
    >>> (eig_error(theta, res) * 1e8).round(1)     # the pair's residuals squared over its gap
    array([2.e+00, 2.e+00, 1.e+05])
    >>> (eig_error(theta, res, np.diag(res ** 2), ceiling=3.0) * 1e8).round(1)  # orthogonal: half
    array([  1. ,   1. , 100.1])
    """
    err = res.astype(np.float64)
    squares: dict[bytes, float] = {}  # a cluster's squared norm, once for all its members
    for i, t in enumerate(theta):
        near = np.abs(theta - t) <= _WINDOW * max(abs(t), 1e-300)
        above, below = theta[~near & (theta > t)], theta[~near & (theta < t)]
        up = float(above.min()) if len(above) else ceiling  # None: the top cluster, nothing known above
        gap = 0.0 if up is None else min(up - t, t - float(below.max()) if len(below) else np.inf)
        if gap <= 0:
            continue
        key = near.tobytes()
        if key not in squares:
            if gram is None:
                squares[key] = float(np.sum(res[near] ** 2))
            else:
                squares[key] = float(np.linalg.eigvalsh(gram[np.ix_(near, near)])[-1])
        err[i] = min(err[i], squares[key] / gap)
    return err


def lobpcg_progress(report: Callable[[float, str], None] | None, stage: str, lo: float,
                    hi: float) -> Callable[[int, float], None] | None:
    """``report(fraction, stage)`` from LOBPCG's (iteration, worst error ratio): the fraction of the way,
    on a log scale, from the first ratio down to 1 (converged); a ratio that rises holds it where it was.

    Examples
    --------
    >>> seen = []
    >>> cb = lobpcg_progress(lambda f, s: seen.append(round(f, 2)), "LOBPCG", 0.0, 1.0)
    >>> for it, ratio in enumerate([100.0, 10.0, 50.0, 1.0]):
    ...     cb(it, ratio)
    >>> seen
    [0.0, 0.5, 0.5, 1.0]
    """
    if report is None:
        return None
    first, best = [], [0.0]

    def cb(it: int, ratio: float) -> None:
        if not first:
            first.append(max(ratio, 1.0 + 1e-12))
        done = 1.0 if ratio <= 1 else math.log(first[0] / ratio) / math.log(first[0])
        best[0] = max(best[0], min(done, 1.0))
        report(lo + (hi - lo) * best[0], f"{stage} (iteration {it})")

    return cb


class Ritz(NamedTuple):
    """What :func:`lobpcg` returns: Ritz values (ascending) and M-orthonormal vectors, the
    iterations run, the residual norms, and each column's error measure over its tolerance
    (converged where ≤ 1)."""

    lam: np.ndarray
    X: np.ndarray
    iterations: int
    residuals: np.ndarray
    ratio: np.ndarray


def lobpcg(apply_A: Callable[[np.ndarray], np.ndarray], m: np.ndarray, precond, X0: np.ndarray, k: int,
           tol: float, maxiter: int, allsum=_local, *, on_values: bool = True,
           report: Callable[[int, float], None] | None = None, floor: float | None = None,
           cheap: bool = False, least: float = 0.0, ceiling: Callable | None = None,
           give_up: Callable[[int, float], bool] | None = None) -> Ritz:
    """Locally optimal block preconditioned CG for A x = λ M x, M = diag(m) > 0.

    Columns whose error measure is below ``tol · max(|θ|, θ_k / 100, least)`` stop receiving new directions
    (``least``: the scale of a block whose first k values are all zero, as on a mesh of k parts or more); the
    iteration ends when the first k have. The measure is the eigenvalue bound of :func:`eig_error`
    (``on_values``) or the residual ``‖A x - θ M x‖_{M⁻¹}``. The rows may be a share of the problem's (an MPI
    rank's): ``allsum`` then adds the small Gram matrices and norms over the shares, so every share solves the
    same small problems. ``report(iteration, worst ratio)`` is called once per iteration. With ``floor``, the
    iteration also ends as soon as the smallest Ritz value is below it: a Ritz value bounds an eigenvalue from
    above (Courant–Fischer), so that proves an eigenvalue below ``floor``. ``cheap`` is for a rough answer
    with a sparse A (a start): one Gram–Schmidt pass instead of two, and A X, A P recomputed by products
    rather than combined from the basis. ``ceiling(θ)``: a count's (σ, j)
    (:func:`meshlap._eigcheck.count_ceiling`); the first j then converge against the gap up to σ, as the check
    will read it. ``give_up(iteration, worst ratio)``: True ends the iteration unconverged
    (:class:`meshlap._multigrid.Stall`).

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> A = sp.diags(np.arange(1.0, 201.0))
    >>> out = lobpcg(lambda Y: A @ Y, np.ones(200), lambda R: R / np.arange(1.0, 201.0)[:, None],
    ...              np.random.default_rng(0).standard_normal((200, 6)), 4, 1e-10, 100)
    >>> np.round(out.lam[:4], 8)
    array([1., 2., 3., 4.])
    """
    mc = m[:, None]
    X, _ = svqb(X0, m, allsum=allsum)
    AX = apply_A(X)
    G = allsum(inner(X, AX))
    lam, Q = np.linalg.eigh(0.5 * (G + G.T))
    # XP = [X P] and AXP = [AX AP] side by side in one array each: every product over the long
    # dimension below is then one BLAS call that reads each array once
    XP, AXP = matmul(X, Q), matmul(AX, Q)
    nb = XP.shape[1]
    PAP = np.zeros((0, 0))  # P.T A P; no P yet
    for it in range(maxiter + 1):
        X, AX = XP[:, :nb], AXP[:, :nb]
        if it and it % _AUDIT == 0 and _drifted(X, mc, allsum):
            # the basis is no longer what the small problems assume (a poor preconditioner can
            # collapse the block onto the constant): restart from the Ritz vectors (_restart)
            XP, AXP, lam = _restart(X, m, apply_A, allsum, nb)
            PAP, X, AX = np.zeros((0, 0)), XP, AXP
        R, last = AX - (mc * X) * lam, k
        if on_values:
            gram = allsum(inner(R, R / mc))
            res = np.sqrt(np.maximum(np.diag(gram), 0.0))
            err = eig_error(lam, res, gram)
            proven = None if ceiling is None else ceiling(lam)
            if proven is not None:  # else a circle's 16s passed at 0.65 tol here, failed the check at 1.3
                last = proven[1]
                err[:last] = eig_error(lam[:last], res[:last], gram[:last, :last], proven[0])
        else:
            err = res = np.sqrt(allsum(np.sum(R * R / mc, axis=0)))
        scale = np.maximum(np.abs(lam), max(0.01 * abs(float(lam[k - 1])), least, 1e-300))
        ratio = err / np.maximum(tol * scale, 1e-300)
        if report is not None:
            report(it, float(ratio[:k].max()))
        active = ratio > 1.0
        if not active[:max(k, last)].any() or it == maxiter or (floor is not None and lam[0] < floor) or \
                (give_up is not None and give_up(it, float(ratio[:k].max()))):
            break
        W = precond(R[:, active])
        W = W[:, _orthogonalize(W, XP, mc, allsum, not cheap)]
        if not W.shape[1]:  # no direction left outside the basis: the iteration has stagnated
            break
        W, _ = svqb(W, m, allsum=allsum)
        AW = apply_A(W)
        # the operator's Gram matrix of the basis [X, P, W], lower triangle (all eigh reads);
        # its mass Gram matrix is I by construction, and its block of X is diag(θ)
        q, s = XP.shape[1], XP.shape[1] + W.shape[1]
        G = np.zeros((s, s))
        G[q:, :q] = inner(W, AXP)
        G[q:, q:] = inner(W, AW)
        G = allsum(G)
        G[np.arange(nb), np.arange(nb)] = lam
        G[nb:q, nb:q] = PAP  # P's rows from the last small problem (below); P.T A X = 0
        lam_all, C = np.linalg.eigh(G)
        C, lam = C[:, :nb], lam_all[:nb]
        # the new directions: the update's part outside the old X, orthogonal to the new X,
        # orthonormalized in the coefficient space (where the basis is orthonormal)
        E = np.zeros((s, int(active.sum())))
        E[nb:] = C[nb:, active]
        for _ in range(2):
            E -= C @ (C.T @ E)
        E, _ = svqb(E, np.ones(s))
        # the new P = basis @ E: E ⟂ C, so its rows of the next Gram matrix are E.T G E
        PAP = E.T @ (np.tril(G) + np.tril(G, -1).T) @ E
        CE = np.hstack([C, E])
        if cheap:
            XP, = combine([(XP, CE[:q], W, CE[q:])])
            AXP = apply_A(XP)
        else:
            XP, AXP = combine([(XP, CE[:q], W, CE[q:]), (AXP, CE[:q], AW, CE[q:])])
    return Ritz(lam, np.ascontiguousarray(X), it, res, ratio)


def _cluster_end(theta: np.ndarray, k: int) -> int:
    """Ritz values up to the end of λ_k's cluster (every θ below (1 + _CLUSTER)·θ_{k-1})."""
    return int(np.searchsorted(theta, (1.0 + _CLUSTER) * theta[k - 1], side="right"))


def cotangent_start(apply_K: Callable[[np.ndarray], np.ndarray], m: np.ndarray, solve, random, k: int,
                    least: int, n: int, tol: float, maxiter: int, allsum=_local, *, adapt: bool = True,
                    cheap: bool = False, report: Callable[[int, float], None] | None = None
                    ) -> tuple[np.ndarray, int]:
    """LOBPCG's start block from the cotangent pencil ``K x = λ M x``, ``solve`` its exact
    inverse ``(K + σM)⁻¹``, and the iterations that took: the Ritz vectors of the whole cluster
    of λ_k plus two, at least ``least`` of them. A block ending inside a cluster converges at
    the tiny gap within it (k = 50 on a 20,000-vertex sphere: 148 iterations, 12 without).

    ``random(c)`` gives c random columns (this share's rows). The start is k/4 columns wider
    than ``least``; where λ_k's cluster reaches past its last column (copies of one part, a
    sphere's 2l+1 equal values) it runs again twice as wide (at most n/3), from its own vectors
    and new random ones, until the cluster's end is seen (two 20,000-point spheres, k = 10: 57
    iterations with the block ending among ten values within 0.1%, 9 with the cluster whole).
    One step of inverse iteration first damps each random column's high frequencies by their
    eigenvalue before the first Rayleigh–Ritz step. Without ``adapt`` it is ``least`` wide and
    returned whole.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> K = sp.diags(np.r_[0.0, 1.0, 1.0, 1.0, 1.0, 1.0, np.arange(3.0, 203.0)]).tocsr()
    >>> rng = np.random.default_rng(0)
    >>> X0, it = cotangent_start(lambda Y: K @ Y, np.ones(206), lambda R: R / (K.diagonal() + 1)[:, None],
    ...                          lambda c: rng.standard_normal((206, c)), 3, 4, 206, 1e-3, 20)
    >>> X0.shape[1]   # the five 1's whole, the 0 and one more
    8
    """
    width = max(least, min(n // 3, least + k // 4)) if adapt else least
    X0 = solve(m[:, None] * random(width))
    iterations, goal = 0, k
    while True:
        start = lobpcg(apply_K, m, solve, X0, goal, tol, maxiter, allsum, on_values=False, report=report,
                       cheap=cheap)
        iterations += start.iterations
        if not adapt:
            return start.X, iterations
        if _cluster_end(start.lam, k) + 2 <= len(start.lam) or width >= n // 3:
            return start.X[:, :min(len(start.lam), max(least, _cluster_end(start.lam, k) + 2))], iterations
        # all but the last two columns converge this time: the cluster's end is then read off
        # converged Ritz values, not off the new random columns' first guesses
        width = min(n // 3, 2 * width)
        goal = max(k, width - 2)
        X0 = np.hstack([start.X, solve(m[:, None] * random(width - start.X.shape[1]))])
