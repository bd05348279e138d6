"""Smoothed-aggregation multigrid in place of a volume's sparse factorization.

A tetrahedral volume's separators are surfaces, so a sparse factorization of its stiffness
fills as n^(4/3) and costs about n² operations: shift-invert on VTK's 68³ voxel grid split into
314,432-vertex tetrahedra held 9.7 GB and had not returned after 6 minutes. One V-cycle of
smoothed aggregation (Vaněk, Mandel and Brezina 1996; pyamg) costs O(n) and preconditions a
Laplacian's LOBPCG almost as well as the exact inverse does, in memory proportional to the
matrix (``benchmarks/bench_volume_eigs.py``). Conjugate gradient preconditioned by it solves
a volume's Poisson problems and implicit heat steps (:mod:`meshlap.solve`, :mod:`meshlap.heat`)
without factoring either. On a quasi-uniform volume, that is; on a graded or anisotropic one the
V-cycle stalls, and :class:`Stall` hands the problem back to the factorization whose cost was
counted before (:func:`replaces_factor`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp

from ._ldl import factors_within, supernodal

__all__ = ["FACTOR_RATE", "MAX_FACTOR_WORK", "Multigrid", "Stall", "replaces_factor"]

# the coarsest level is solved directly: up to this many unknowns (pyamg's default is 10)
_COARSE = 500
#: multiply-adds of a volume's factorization (:func:`meshlap._ldl.factor_work`, in the cheaper
#: of its two orderings) up to which it is factored rather than preconditioned by multigrid. A
#: factorization's cost is counted before it is made; LOBPCG's iterations with a V-cycle are not
#: known until it runs: 20-33 on tetrahedral cubes and a 102,578-vertex FEA jaw, 149-252 on the
#: graded bunny-tet, notch_stress and can volumes (10 pairs, CPU by hand: 2.3 s, 14.7 s, 5.6 s
#: against shift-invert's 0.27 s, 0.43 s, 0.14 s). 10⁹ multiply-adds factor in under a second, about
#: what multigrid takes where it converges well at that size (the 9,261-vertex cube: 0.85 G,
#: shift-invert 0.81 s against multigrid's 0.61 s; the 12,167-vertex one, 1.6 G: 1.25 s against
#: 0.75 s), so a volume is factored where that bounded cost is small and multigrid runs beyond.
MAX_FACTOR_WORK = 1e9
#: multiply-adds per second of the factorization's way to 10 eigenpairs (factor, then
#: shift-invert's solves), counted work over seconds here: a 102,578-vertex FEA jaw 14.4 G in 18 s,
#: the notch_stress volume refined to 96,029 vertices 3.0 G in 5.7 s, the 68,921-vertex cube 46 G
#: in 25-31 s; the same equivalence MAX_FACTOR_WORK states
FACTOR_RATE = 1e9
# LOBPCG's error measure first rises before it falls (the jaw's: 1.2e8 at iteration 0, 1.3e10 at
# 3, 3e8 at 9): its rate is read from the 5th iteration on, and first judged at the 10th
_SETTLED = 5


def replaces_factor(op: object, A: sp.spmatrix | None = None) -> bool:
    """Whether ``op``'s systems of matrix ``A`` (default ``op.S``'s pattern) are solved by
    multigrid rather than factored: a volume's whose factorization
    :func:`meshlap._ldl.factors_within` counts above :data:`MAX_FACTOR_WORK` multiply-adds. A
    bulky volume's factor fills as n^(4/3) and costs about n² operations, a V-cycle O(n); a thin
    or graded volume's factor stays cheap where a V-cycle converges slowly.

    Examples
    --------
    >>> import meshlap
    >>> replaces_factor(meshlap.laplacian(*meshlap.shapes.sphere(200, seed=0)))
    False
    """
    return supernodal(op) and not factors_within(op.S if A is None else A, MAX_FACTOR_WORK)


class Multigrid:
    """One V-cycle of smoothed-aggregation multigrid on a symmetric positive definite ``A``:
    ``solve(R)`` approximates ``A⁻¹ R`` column by column, as :class:`meshlap._lobpcg.BlockFactor`
    solves exactly.

    Examples
    --------
    >>> import scipy.sparse as sp, numpy as np
    >>> A = sp.diags([-1.0, 2.01, -1.0], [-1, 0, 1], shape=(2000, 2000), format="csr")
    >>> b = np.ones((2000, 2))
    >>> x = Multigrid(A).solve(b)
    >>> bool(np.linalg.norm(A @ x - b) < 0.5 * np.linalg.norm(b))
    True
    """

    def __init__(self, A: sp.spmatrix) -> None:
        import pyamg

        self._ml = pyamg.smoothed_aggregation_solver(sp.csr_matrix(A), symmetry="symmetric",
                                                     max_coarse=_COARSE)

    def solve(self, R: np.ndarray) -> np.ndarray:
        R = np.asarray(R)
        if R.ndim == 1:
            return self._cycle(R)
        out = np.empty_like(R)
        for j in range(R.shape[1]):
            out[:, j] = self._cycle(np.ascontiguousarray(R[:, j]))
        return out

    def _cycle(self, r: np.ndarray) -> np.ndarray:
        return self._ml.solve(r, maxiter=1, cycle="V", tol=1e-300)


class Stall:
    """Whether an iteration preconditioned by a V-cycle (LOBPCG, conjugate gradient) should stop
    and give way to the factorization whose work ``work()`` counts (multiply-adds,
    :func:`meshlap._ldl.least_work`): ``stall(iteration, worst error ratio)`` is True once the
    iterations still to go, at the rate the ratio fell since the 5th iteration and at the run's
    measured seconds per iteration, would take longer than the factorization's way (``work()`` /
    :data:`FACTOR_RATE`). The count is asked for only where they would take longer than
    :data:`MAX_FACTOR_WORK` / :data:`FACTOR_RATE`, what multigrid was chosen for exceeding: a
    converging run (a cube's Poisson solve, 0.4 s) does not pay for it (0.24 s more). A V-cycle
    converges at a rate independent of the size on a quasi-uniform volume (20-33 LOBPCG
    iterations for 10 pairs) and stalls on a graded or anisotropic one, whose counted
    factorization is cheap for its size (notch_stress refined once: 211 s for 10 pairs against
    shift-invert's 5.7 s, ``benchmarks/bench_volume_eigs.py``). ``fired`` stays True once it has
    said so.

    Examples
    --------
    >>> stall = Stall(lambda: 1e9)   # about a second of factoring
    >>> [stall(it, 1e10) for it in range(12)][-1]   # no progress in 11 iterations
    True
    >>> stall.fired
    True
    """

    def __init__(self, work: Callable[[], float]) -> None:
        self._work = work
        self._floor = MAX_FACTOR_WORK / FACTOR_RATE  # seconds the factorization takes at least
        self._budget: float | None = None
        self.fired = False
        self._log: list[float] = []
        self._start = 0.0

    def __call__(self, it: int, ratio: float) -> bool:
        if it == 0:  # a new run
            self._log, self._start = [], time.perf_counter()
        self._log.append(math.log(max(ratio, 1.0)))
        if self.fired or it < 2 * _SETTLED:
            return self.fired
        rate = (self._log[_SETTLED] - self._log[it]) / (it - _SETTLED)  # log ratio fallen per iteration
        to_go = math.inf if rate <= 0 else self._log[it] / rate
        seconds = to_go * (time.perf_counter() - self._start) / it
        if seconds <= self._floor:
            return False
        if self._budget is None:
            self._budget = self._work() / FACTOR_RATE
        self.fired = seconds > self._budget
        return self.fired
