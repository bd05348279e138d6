"""Sparse factorizations of the symmetric matrices the solvers shift and invert.

A real symmetric matrix is factored by QDLDL (``qdldl``): ``A[p][:, p] = (I + L) D (I + L)ᵀ``
in an approximate-minimum-degree ordering p, without pivoting. It stores one triangle where an
LU stores two, for about the same fill. On the quadratic elements' pencils it factors 13× faster
than SuperLU (camelhead's 68,167 rows: 0.28 s against 3.6 s), on linear ones about as fast, and
its blocked solves (:func:`triangular_solves`) take a 64-column block 3-14× faster. Its D gives
Sylvester's inertia: the number of negative pivots is the number of negative eigenvalues. A
complex matrix (heat flow's contour points zM − tS) and a real one whose D meets an exact zero
in that ordering are factored by SuperLU instead, in a symmetric ordering without pivoting,
where U's diagonal carries the pivots.

A volume's eigenpairs are another matter: its separators are surfaces, so its fronts are dense,
SuperLU's supernodes (BLAS-3 on those fronts) factor it faster for the same fill, and
shift-invert solves one vector at a time, where SuperLU is faster too (``benchmarks/bench_factor.py``:
tetrahedral cube of 29,791 vertices, factor 2.7 s against LDLᵀ's 7.1 s, one solve 25 ms against
36 ms). ``supernodal=True`` (:func:`supernodal`: true for an operator on a volume) takes
SuperLU there, in the ordering of :func:`nested_dissection`: minimum degree, which looks one
vertex ahead, does not find a volume's surface separators, and its fill grows faster (the same
table: 68,921 vertices, 11.6 s and 71 M stored entries against 68.7 s and 107 M; 46,656: 4.4 s
against 19.2 s). :func:`meshlap.spectral.eigs`, implicit heat steps, Poisson solves and the heat
method's step ask for it. LDLᵀ's blocked solves are faster (64 columns of the 9,261-vertex cube
in 51 ms against SuperLU's 173-215 ms), but the factorization's cost comes first unless
hundreds of columns are solved.
"""

from __future__ import annotations

import functools
from typing import Protocol

import numpy as np
import qdldl
import scipy.sparse as sp
import scipy.sparse.linalg  # noqa: F401 - sp.linalg

from ._jit import jit

__all__ = ["NARROW", "Factor", "factor", "nested_dissection", "supernodal", "triangular_solves"]

#: blocks up to this many columns are solved one column after the other; wider ones by
#: :func:`triangular_solves`, one pass over each factor for all columns (64 columns of a
#: 16,000-vertex sphere's linear pencil: 13 ms, SuperLU 111 ms; column by column about 140 ms)
NARROW = 8


@jit()
def _forward(indptr, indices, data, X):  # pragma: no cover - compiled
    # X ← L⁻¹ X for a strictly lower CSR part with unit diagonal; the column loop is innermost
    n, c = X.shape
    for i in range(n):
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            a = data[p]
            for q in range(c):
                X[i, q] -= a * X[j, q]


@jit()
def _backward(indptr, indices, data, diag, X):  # pragma: no cover - compiled
    # X ← U⁻¹ X for a strictly upper CSR part and its diagonal
    n, c = X.shape
    for i in range(n - 1, -1, -1):
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            a = data[p]
            for q in range(c):
                X[i, q] -= a * X[j, q]
        d = 1.0 / diag[i]
        for q in range(c):
            X[i, q] *= d


def triangular_solves(lower: sp.csr_matrix, upper: sp.csr_matrix, diag: np.ndarray, X: np.ndarray) -> None:
    """X ← (diag(diag) + upper)⁻¹ (I + lower)⁻¹ X in place (lower and upper strict CSR
    triangles, X of shape (n, c), C-ordered, of their dtype).

    Examples
    --------
    >>> lower = sp.csr_matrix(np.array([[0.0, 0.0], [2.0, 0.0]]))
    >>> upper = sp.csr_matrix(np.array([[0.0, 1.0], [0.0, 0.0]]))
    >>> X = np.array([[3.0], [8.0]])
    >>> triangular_solves(lower, upper, np.array([1.0, 2.0]), X)
    >>> X.ravel().tolist()       # [[1, 1], [2, 4]] x = [3, 8]
    [2.0, 1.0]
    """
    _forward(lower.indptr, lower.indices, lower.data, X)
    _backward(upper.indptr, upper.indices, upper.data, diag, X)


class Factor(Protocol):
    """What :func:`factor` returns for a square sparse matrix A: :meth:`solve`, the inertia, the
    factors.

    Examples
    --------
    >>> A = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(100, 100))
    >>> f = factor(A)
    >>> bool(np.allclose(A @ f.solve(np.ones((100, 2))), 1.0))
    True
    >>> bool(np.allclose(A @ f.solve(np.ones((100, 12))), 1.0))       # blocked: triangular_solves
    True
    >>> exact = 2 - 2 * np.cos(np.pi * np.arange(1, 101) / 101)
    >>> factor(A - 0.5 * sp.identity(100)).negative, int((exact < 0.5).sum())
    (23, 23)
    """

    #: negative pivots (the negative eigenvalues of a symmetric A); None where the factors do not say
    negative: int | None

    def solve(self, B: np.ndarray) -> np.ndarray:
        """A⁻¹ B for B of shape (n,) or (n, c)."""
        ...

    def triangles(self) -> tuple[np.ndarray, sp.csr_matrix, sp.csr_matrix, np.ndarray, np.ndarray]:
        """``(into, lower, upper, diag, out)``: A⁻¹ B is ``X[out]`` after ``X[into] = B``, then a
        forward solve with the unit lower triangle ``I + lower`` and a backward one with
        ``diag(diag) + upper`` (lower and upper strict, CSR)."""
        ...


class _LDL:
    def __init__(self, A: sp.csc_matrix) -> None:
        self._solver = qdldl.Solver(A)

    @functools.cached_property
    def _factors(self) -> tuple[sp.csc_matrix, np.ndarray, np.ndarray]:
        return self._solver.factors()  # a copy of L: made only when asked for

    @property
    def negative(self) -> int:
        return int((self._factors[1] < 0).sum())

    def solve(self, B: np.ndarray) -> np.ndarray:
        B = np.asarray(B, dtype=np.float64)
        if B.ndim == 1:
            return self._solver.solve(np.ascontiguousarray(B))
        if B.shape[1] <= NARROW:
            return np.column_stack([self._solver.solve(np.ascontiguousarray(b)) for b in B.T])
        into, lower, upper, diag, out = self.triangles()
        X = np.empty(B.shape)
        X[into] = B
        triangular_solves(lower, upper, diag, X)
        return X[out]

    def triangles(self):
        return self._triangles

    @functools.cached_property
    def _triangles(self):  # made on the first wide block, kept with the factorization
        L, D, p = self._factors
        back = np.argsort(p)
        lower = sp.csr_matrix(L)
        return back, lower, sp.csr_matrix(sp.diags(D) @ lower.T), D, back


class _LU:
    def __init__(self, A: sp.csc_matrix, order: np.ndarray | None = None) -> None:
        # ``order``: a symmetric ordering of our own (nested dissection), kept as it is
        self._p = order
        if order is not None:
            A = sp.csc_matrix(A[order][:, order])
        self._lu = sp.linalg.splu(A, permc_spec="MMD_AT_PLUS_A" if order is None else "NATURAL",
                                  diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        d = self._lu.U.diagonal()
        symmetric = np.array_equal(self._lu.perm_r, self._lu.perm_c)  # SuperLU did not pivot
        self.negative = (int((d < 0).sum()) if symmetric and not np.iscomplexobj(d)
                         and np.isfinite(d).all() and d.all() else None)

    def solve(self, B: np.ndarray) -> np.ndarray:
        if self._p is None:
            return self._lu.solve(np.asfortranarray(B))
        X = np.empty(B.shape, dtype=np.result_type(B, self._lu.U.dtype))
        X[self._p] = self._lu.solve(np.asfortranarray(B[self._p]))
        return X

    def triangles(self):
        U = sp.csr_matrix(self._lu.U)
        into, out = self._lu.perm_r, self._lu.perm_c
        if self._p is not None:  # B[p] goes in, the result comes back to p
            back = np.argsort(self._p)
            into, out = into[back], out[back]
        lower, upper = sp.csr_matrix(sp.tril(self._lu.L, k=-1)), sp.csr_matrix(sp.triu(U, k=1))
        return into, lower, upper, U.diagonal(), out


def nested_dissection(A: sp.spmatrix, leaf: int = 64) -> np.ndarray:
    """A fill-reducing symmetric ordering of ``A``'s graph by recursive bisection (George's
    nested dissection with level structures): the vertices at the median distance from a
    pseudo-peripheral vertex separate the rest into two halves, each ordered the same way, the
    separator last. A volume's separators are surfaces, so minimum degree, which looks one
    vertex ahead, fills far more (module notes).

    Examples
    --------
    >>> A = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(200, 200))
    >>> p = nested_dissection(A, leaf=8)
    >>> sorted(p.tolist()) == list(range(200)), int(p[-1])      # a path: its middle goes last
    (True, 100)
    """
    from scipy.sparse.csgraph import connected_components, dijkstra

    G = sp.csr_matrix(A, dtype=np.float64, copy=True)
    G.data[:] = 1.0
    G.setdiag(0.0)
    G.eliminate_zeros()

    def hops(H: sp.csr_matrix, root: int) -> np.ndarray:
        return dijkstra(H, directed=False, indices=root, unweighted=True)

    def order(idx: np.ndarray) -> list[np.ndarray]:
        if len(idx) <= leaf:
            return [idx]
        H = G[idx][:, idx]
        parts, label = connected_components(H, directed=False)
        if parts > 1:
            return [o for c in range(parts) for o in order(idx[label == c])]
        root = int(np.argmax(hops(H, 0)))  # two sweeps: a pseudo-peripheral vertex
        level = hops(H, root).astype(np.int64)
        counts = np.bincount(level)
        middle = int(np.searchsorted(np.cumsum(counts), len(idx) / 2))
        if middle == 0 or middle >= len(counts) - 1:
            return [idx]
        return order(idx[level < middle]) + order(idx[level > middle]) + [idx[level == middle]]

    return np.concatenate(order(np.arange(A.shape[0])))


def supernodal(op: object) -> bool:
    """Whether ``op``'s factorizations come faster from supernodes: a volume's (module notes).

    Examples
    --------
    >>> import meshlap
    >>> supernodal(meshlap.laplacian(*meshlap.shapes.sphere(200, seed=0)))
    False
    """
    return int(getattr(getattr(op, "geometry", None), "dim", 2)) >= 3


def factor(A: sp.spmatrix, supernodal: bool = False) -> Factor:
    """The factorization of a symmetric (or complex symmetric) sparse matrix (module notes):
    QDLDL's LDLᵀ, or SuperLU's LU where A is complex, where LDLᵀ meets a zero pivot, or where
    ``supernodal`` asks for it (a volume's).

    Raises ``RuntimeError`` where A is exactly singular in the symmetric ordering.

    Examples
    --------
    >>> A = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(50, 50))
    >>> b = np.arange(50.0)
    >>> bool(np.allclose(A @ factor(A).solve(b), b)), type(factor(A * (1 + 1j))).__name__
    (True, '_LU')
    """
    A = sp.csc_matrix(A)
    if not (supernodal or np.iscomplexobj(A.data)):
        try:
            return _LDL(A)
        except RuntimeError:  # a zero pivot (or a diagonal entry not stored): SuperLU's ordering
            pass
    return _LU(A, nested_dissection(A) if supernodal else None)
