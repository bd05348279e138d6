"""Smoothed-aggregation multigrid in place of a volume's sparse factorization.

A tetrahedral volume's separators are surfaces, so a sparse factorization of its stiffness
fills as n^(4/3) and costs about n² operations: shift-invert on VTK's 68³ voxel grid split into
314,432-vertex tetrahedra held 9.7 GB and had not returned after 6 minutes. One V-cycle of
smoothed aggregation (Vaněk, Mandel and Brezina 1996; pyamg) costs O(n) and preconditions a
Laplacian's LOBPCG almost as well as the exact inverse does, in memory proportional to the
matrix (``benchmarks/bench_volume_eigs.py``). Conjugate gradient preconditioned by it solves
a volume's Poisson problems and implicit heat steps (:mod:`meshlap.solve`, :mod:`meshlap.heat`)
without factoring either.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ._ldl import supernodal

__all__ = ["MIN_VERTICES", "Multigrid", "replaces_factor"]

# the coarsest level is solved directly: up to this many unknowns (pyamg's default is 10)
_COARSE = 500
#: a volume's unknowns above which multigrid replaces its factorization. Tetrahedral cubes:
#: eigs, 4,913 vertices 0.47 s against shift-invert's 0.14 s, 9,261 0.78 s against 1.49 s
#: (bench_volume_eigs.py); a Poisson solve with its set-up, 9,261 vertices 0.09 s
#: against 0.38 s, 68,921 0.41 s against 110 s (bench_volume_eigs.py --solves)
MIN_VERTICES = 8000


def replaces_factor(op: object, unknowns: int) -> bool:
    """Whether ``op``'s systems of ``unknowns`` unknowns are solved by multigrid rather than
    factored: a volume's (whose factor fills as n^(4/3)) above :data:`MIN_VERTICES`.

    Examples
    --------
    >>> import meshlap
    >>> replaces_factor(meshlap.laplacian(*meshlap.shapes.sphere(200, seed=0)), 10**6)
    False
    """
    return supernodal(op) and unknowns > MIN_VERTICES


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
