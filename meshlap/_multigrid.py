"""Smoothed-aggregation multigrid as LOBPCG's preconditioner, for a volume's pencil.

A tetrahedral volume's separators are surfaces, so a sparse factorization of its stiffness
fills as n^(4/3) and costs about n² operations: shift-invert on VTK's 68³ voxel grid split into
314,432-vertex tetrahedra held 9.7 GB and had not returned after 6 minutes. One V-cycle of
smoothed aggregation (Vaněk, Mandel and Brezina 1996; pyamg) costs O(n) and preconditions a
Laplacian's LOBPCG almost as well as the exact inverse does, in memory proportional to the
matrix (``benchmarks/bench_volume_eigs.py``).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["Multigrid"]

# the coarsest level is solved directly: up to this many unknowns (pyamg's default is 10)
_COARSE = 500


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
