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
shift-invert solves one vector at a time, where SuperLU is faster too (tetrahedral cubes: 9,261
vertices, factor 0.68 s against 0.78 s, 10 eigenpairs 2.5 s against 2.6 s; 29,791 vertices, factor
5.8 s against 16.8 s, one solve 30 ms against 45 ms, 10 eigenpairs 16.8 s against 37.0 s).
``supernodal=True`` (:func:`supernodal`: true for an operator on a volume) takes
SuperLU there; :func:`meshlap.spectral.eigs`, implicit heat steps and Poisson solves ask for it
(the larger cube's heat step 5.2 s against 14.0 s, a Poisson solve 5.5 s against 14.4 s). LDLᵀ's
blocked solves are faster (64 columns of the smaller cube in 57 ms against SuperLU's 303 ms,
``benchmarks/bench_factor.py``), but the factorization's cost comes first unless hundreds of
columns are solved.
"""

from __future__ import annotations

import functools
from typing import Protocol

import numpy as np
import qdldl
import scipy.sparse as sp
import scipy.sparse.linalg  # noqa: F401 - sp.linalg

from ._jit import jit

__all__ = ["NARROW", "Factor", "factor", "supernodal", "triangular_solves"]

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
    def __init__(self, A: sp.csc_matrix) -> None:
        self._lu = sp.linalg.splu(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                                  options={"SymmetricMode": True})
        d = self._lu.U.diagonal()
        symmetric = np.array_equal(self._lu.perm_r, self._lu.perm_c)  # SuperLU did not pivot
        self.negative = (int((d < 0).sum()) if symmetric and not np.iscomplexobj(d)
                         and np.isfinite(d).all() and d.all() else None)

    def solve(self, B: np.ndarray) -> np.ndarray:
        return self._lu.solve(np.asfortranarray(B))

    def triangles(self):
        U = sp.csr_matrix(self._lu.U)
        return (self._lu.perm_r, sp.csr_matrix(sp.tril(self._lu.L, k=-1)), sp.csr_matrix(sp.triu(U, k=1)),
                U.diagonal(), self._lu.perm_c)


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
    return _LU(A)
