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
shift-invert solves one vector at a time, where SuperLU is faster too
(``benchmarks/bench_factor.py``: tetrahedral cube of 29,791 vertices, factor 2.6 s against
LDLᵀ's 6.7 s, one solve 24 ms against 33 ms, both in minimum degree). ``supernodal=True``
(:func:`supernodal`: true for an operator on a volume) takes SuperLU there, in the ordering
:func:`volume_order` chooses: minimum degree, which looks one vertex ahead and misses a bulky
volume's surface separators, or :func:`nested_dissection`, whose level structures fill more on
small irregular volumes, whichever needs fewer multiply-adds as :func:`factor_work` counts them
from the structure alone (the same benchmark: a 68,921-vertex tetrahedral cube in 8.6 s and 66 M
stored entries against minimum degree's 71.7 s and 107 M, VTK's 167,580-vertex carotid volume
32.8 s and 200 M against 239 s and 454 M; the corpus's real tetrahedral meshes and a
102,578-vertex FEA jaw keep minimum degree). :func:`meshlap.spectral.eigs`, implicit heat steps,
Poisson solves and the heat method's step ask for it. LDLᵀ's blocked solves are faster (64
columns of the 9,261-vertex cube in 51 ms against SuperLU's 173-215 ms), but the factorization's
cost comes first unless hundreds of columns are solved.
"""

from __future__ import annotations

import functools
import math
from typing import Protocol

import numpy as np
import qdldl
import scipy.sparse as sp
import scipy.sparse.linalg  # noqa: F401 - sp.linalg

from ._jit import jit

__all__ = ["NARROW", "Factor", "factor", "factor_work", "least_work", "minimum_degree", "nested_dissection",
           "supernodal", "triangular_solves", "volume_order"]

# nested dissection stops at parts this small (natural order inside): on the 29,791-vertex
# tetrahedral cube the work is 1.7% above leaves of 64, the ordering 40% faster
_LEAF = 256

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
        # ``order``: a symmetric ordering chosen beforehand (volume_order), kept as it is
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


def nested_dissection(A: sp.spmatrix, leaf: int = _LEAF) -> np.ndarray:
    """A fill-reducing symmetric ordering of ``A``'s graph by recursive bisection (George's
    nested dissection with level structures): among the levels of distance from a
    pseudo-peripheral vertex that leave at least a third on either side, the smallest separates
    the rest into two parts, each ordered the same way, the separator last.

    Examples
    --------
    >>> A = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(200, 200))
    >>> p = nested_dissection(A, leaf=8)
    >>> sorted(p.tolist()) == list(range(200)), 66 <= int(p[-1]) <= 133   # a path: a middle vertex last
    (True, True)
    """
    return _dissect(*_graph(A), int(leaf))


def _graph(A: sp.spmatrix) -> tuple[np.ndarray, np.ndarray]:
    # the symmetric pattern of A without its diagonal, as CSR index arrays
    G = abs(sp.csr_matrix(A))
    G = (G + G.T).tocsr()
    G.setdiag(0.0)
    G.eliminate_zeros()
    return G.indptr.astype(np.int64), G.indices.astype(np.int64)


@jit()
def _bfs(indptr, indices, root, part, mark, level, queue):  # pragma: no cover - compiled
    # levels of the vertices marked ``part`` reached from root; returns how many and the last
    level[root] = 0
    queue[0] = root
    head, tail = 0, 1
    while head < tail:
        v = queue[head]
        head += 1
        for p in range(indptr[v], indptr[v + 1]):
            u = indices[p]
            if mark[u] == part and level[u] < 0:
                level[u] = level[v] + 1
                queue[tail] = u
                tail += 1
    return tail, queue[tail - 1]


@jit()
def _dissect(indptr, indices, leaf):  # pragma: no cover - compiled
    # nested_dissection on a graph without loops: parts are slices of ``verts`` waiting on a
    # stack with the slice of ``out`` they fill; a part's vertices carry its number in ``mark``
    n = len(indptr) - 1
    verts = np.arange(n)
    out = np.empty(n, dtype=np.int64)
    mark = np.zeros(n, dtype=np.int64)
    level = np.full(n, -1, dtype=np.int64)
    queue = np.empty(n, dtype=np.int64)
    tmp = np.empty(n, dtype=np.int64)
    stack = np.empty((n + 1, 3), dtype=np.int64)
    stack[0, 0], stack[0, 1], stack[0, 2] = 0, n, 0
    top, parts = 1, 1
    while top > 0:
        top -= 1
        s, e, o = stack[top, 0], stack[top, 1], stack[top, 2]
        m = e - s
        if m <= leaf:
            out[o:o + m] = verts[s:e]
            continue
        part = mark[verts[s]]
        reached, last = _bfs(indptr, indices, verts[s], part, mark, level, queue)
        if reached < m:  # several connected pieces: each its own part, side by side
            for q in range(s, e):
                level[verts[q]] = -1
            k = 0
            for q in range(s, e):
                v = verts[q]
                if level[v] < 0:  # a new piece: a new number (the pieces found have levels)
                    got, _ = _bfs(indptr, indices, v, part, mark, level, queue)
                    for r in range(got):
                        tmp[k + r] = queue[r]
                        mark[queue[r]] = parts
                    parts += 1
                    stack[top, 0], stack[top, 1], stack[top, 2] = s + k, s + k + got, o + k
                    top += 1
                    k += got
            for q in range(m):
                verts[s + q] = tmp[q]
            for q in range(s, e):
                level[verts[q]] = -1
            continue
        for q in range(s, e):  # the second sweep starts at a pseudo-peripheral vertex
            level[verts[q]] = -1
        _bfs(indptr, indices, last, part, mark, level, queue)
        depth = 0
        for q in range(s, e):
            depth = max(depth, level[verts[q]])
        counts = np.zeros(depth + 1, dtype=np.int64)
        for q in range(s, e):
            counts[level[verts[q]]] += 1
        middle, below = -1, 0
        for lv in range(depth + 1):
            above = m - below - counts[lv]
            if 3 * below >= m and 3 * above >= m and (middle < 0 or counts[lv] < counts[middle]):
                middle = lv
            below += counts[lv]
        if middle < 0:
            out[o:o + m] = verts[s:e]
        else:
            nl, nr = 0, 0
            for q in range(s, e):
                nl += level[verts[q]] < middle
                nr += level[verts[q]] > middle
            a, b, c = 0, nl, nl + nr
            for q in range(s, e):
                v = verts[q]
                if level[v] < middle:
                    tmp[a] = v
                    a += 1
                    mark[v] = parts
                elif level[v] > middle:
                    tmp[b] = v
                    b += 1
                    mark[v] = parts + 1
                else:
                    tmp[c] = v
                    c += 1
            parts += 2
            for q in range(m):
                verts[s + q] = tmp[q]
            out[o + nl + nr:o + m] = verts[s + nl + nr:e]
            stack[top, 0], stack[top, 1], stack[top, 2] = s, s + nl, o
            stack[top + 1, 0], stack[top + 1, 1], stack[top + 1, 2] = s + nl, s + nl + nr, o + nl
            top += 2
        for q in range(s, e):
            level[verts[q]] = -1
    return out


def minimum_degree(A: sp.spmatrix) -> np.ndarray | None:
    """SuperLU's multiple-minimum-degree ordering of A + Aᵀ as an ordering of ``A``'s rows (the
    one ``splu`` would take), from an incomplete factorization that drops all but the diagonal;
    None where even that meets a zero pivot.

    Examples
    --------
    >>> A = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(50, 50), format="csc")
    >>> sorted(minimum_degree(A).tolist()) == list(range(50))
    True
    """
    try:
        ilu = sp.linalg.spilu(sp.csc_matrix(A), drop_tol=1.0, fill_factor=1.0, permc_spec="MMD_AT_PLUS_A",
                              diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    except RuntimeError:
        return None
    return np.argsort(ilu.perm_c)


@jit()
def _column_counts(indptr, indices, order, where, most):  # pragma: no cover - compiled
    # entries below the diagonal in each column of the Cholesky factor of A[order][:, order]:
    # the elimination tree (Liu, with path compression), then each row's subtree walked up
    # from its entries to the marks the row leaves; None once more than ``most`` entries are met
    n = len(order)
    parent = np.full(n, -1, dtype=np.int64)
    ancestor = np.full(n, -1, dtype=np.int64)
    for k in range(n):
        old = order[k]
        for p in range(indptr[old], indptr[old + 1]):
            i = where[indices[p]]
            while i != -1 and i < k:
                nxt = ancestor[i]
                ancestor[i] = k
                if nxt == -1:
                    parent[i] = k
                i = nxt
    count = np.zeros(n, dtype=np.int64)
    mark = np.full(n, -1, dtype=np.int64)
    entries = 0
    for k in range(n):
        mark[k] = k
        old = order[k]
        for p in range(indptr[old], indptr[old + 1]):
            i = where[indices[p]]
            while i < k and mark[i] != k:
                count[i] += 1
                mark[i] = k
                i = parent[i]
                entries += 1
        if entries > most:
            return None
    return count


def factor_work(A: sp.spmatrix, order: np.ndarray) -> float:
    """The multiply-adds of a Cholesky factorization of ``A[order][:, order]``, counted exactly
    from its structure before any factoring: Σ_j c_j², c_j the entries below the diagonal in
    column j of the factor.

    Examples
    --------
    >>> A = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(5, 5))
    >>> factor_work(A, np.arange(5)), factor_work(A, np.array([0, 2, 4, 1, 3]))  # a path, two orders
    (4.0, 7.0)
    """
    return _work(_graph(A), order)


def _work(graph: tuple[np.ndarray, np.ndarray], order: np.ndarray, most: float = math.inf) -> float:
    # Σ c_j², or inf once it must exceed ``most``: Σ c_j² ≥ (Σ c_j)² / n, so the count stops
    # after √(n·most) entries
    n = len(order)
    where = np.empty(n, dtype=np.int64)
    where[order] = np.arange(n)
    bound = math.sqrt(n * max(most, 0.0)) if math.isfinite(most) else math.inf
    count = _column_counts(*graph, np.asarray(order, dtype=np.int64), where, min(bound, 2.0**62))
    return math.inf if count is None else float(np.sum(count.astype(np.float64) ** 2))


class _Structure:
    """What is known of one sparsity pattern: its graph, its two orderings (each made on first
    use) and their counted work (exact, or only known to exceed a bound), so that deciding
    whether to factor and then factoring order and count it once."""

    def __init__(self, A: sp.csc_matrix) -> None:
        self.A, self.graph = A, _graph(A)
        self.orders: dict[str, np.ndarray | None] = {}
        self.work: dict[str, float] = {}  # exact Σ c_j²
        self.above: dict[str, float] = {}  # a bound Σ c_j² is known to exceed

    def order(self, kind: str) -> np.ndarray | None:
        if kind not in self.orders:
            self.orders[kind] = _dissect(*self.graph, _LEAF) if kind == "nd" else minimum_degree(self.A)
        return self.orders[kind]

    def within(self, kind: str, most: float) -> bool:
        if kind in self.work:
            return self.work[kind] <= most
        if most <= self.above.get(kind, -math.inf) or (order := self.order(kind)) is None:
            return False
        work = _work(self.graph, order, most)
        if math.isfinite(work) or not math.isfinite(most):
            self.work[kind] = work
        else:
            self.above[kind] = max(most, self.above.get(kind, -math.inf))
        return work <= most


def _structure(A: sp.spmatrix) -> _Structure:
    # kept for the last four patterns: shift-invert and its inertia count factor one twice, and
    # eigs, a Poisson solver and heat steps on one volume ask whether to factor it
    A = sp.csc_matrix(A)
    key = (A.shape, A.nnz, hash(A.indptr.tobytes()), hash(A.indices.tobytes()))
    if key not in _STRUCTURES:
        _STRUCTURES[key] = _Structure(A)
        while len(_STRUCTURES) > 4:
            _STRUCTURES.pop(next(iter(_STRUCTURES)))
    return _STRUCTURES[key]


_STRUCTURES: dict[tuple, _Structure] = {}


def volume_order(A: sp.spmatrix) -> np.ndarray:
    """The ordering a volume's factorization takes: minimum degree or nested dissection,
    whichever :func:`factor_work` counts the fewer operations for (minimum degree looks one
    vertex ahead and misses a bulky volume's surface separators; nested dissection's level
    structures fill more on small, irregular ones).

    Examples
    --------
    >>> A = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(300, 300), format="csc")
    >>> sorted(volume_order(A).tolist()) == list(range(300))
    True
    """
    known = _structure(A)
    return known.order(_cheaper(known))


def least_work(A: sp.spmatrix) -> float:
    """The multiply-adds of factoring ``A`` in :func:`volume_order`'s ordering
    (:func:`factor_work`), counted once per sparsity pattern.

    Examples
    --------
    >>> A = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(300, 300), format="csc")
    >>> least_work(A)   # a path's factor: one entry below each diagonal but the last
    299.0
    """
    known = _structure(A)
    return known.work[_cheaper(known)]


def _cheaper(known: _Structure) -> str:
    kinds = [k for k in ("md", "nd") if known.order(k) is not None]
    for k in kinds:
        known.within(k, math.inf)  # exact counts
    return min(kinds, key=lambda k: known.work[k])


def factors_within(A: sp.spmatrix, most: float) -> bool:
    """Whether the cheaper of :func:`volume_order`'s two orderings factors ``A`` in at most
    ``most`` multiply-adds (:func:`factor_work`). Each count stops as soon as it must exceed
    ``most``, and nested dissection (compiled, O(n log n)) is counted before minimum degree is
    ordered, so a volume too large to factor is told so at little cost; before either, the
    factor's pattern holds A's own, so Σ c_j² ≥ (Σ c_j)² / n ≥ (A's entries below the diagonal)²
    / n rules out a matrix of dense rows (a kernel's) at once. The orderings and counts made are
    those :func:`volume_order` then uses.

    Examples
    --------
    >>> A = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(300, 300), format="csc")
    >>> factors_within(A, 1e3), factors_within(A, 1.0)
    (True, False)
    """
    if (0.5 * (A.nnz - A.shape[0])) ** 2 / max(A.shape[0], 1) > most:
        return False
    known = _structure(A)
    return known.within("nd", most) or known.within("md", most)


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
    return _LU(A, volume_order(A) if supernodal else None)
