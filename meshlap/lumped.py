"""What every Laplacian with a lumped (diagonal) mass shares, below the operators that build one.

Two matrices, one meaning each: ``L`` is what ``op @ f`` applies (the accurate point-wise
rows), and ``L_sym`` is the L of the symmetric pencil, ``S = M L_sym``, that spectra, heat
flow and smoothing use. For most operators they are the same matrix.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import LinearOperator

from .geometry.validation import check_function

__all__ = ["LumpedLaplacian", "SparseLaplacian"]


class LumpedLaplacian:
    """``M``, ``S = M L_sym`` and ``L_sym`` (``L`` unless a subclass keeps a second matrix)."""

    mass: np.ndarray
    L: sp.csr_matrix
    _S: sp.csr_matrix | None = None

    @property
    def L_sym(self) -> sp.csr_matrix:
        """The symmetric pencil's L: ``S = M @ L_sym`` is symmetric and negative semidefinite."""
        return self.L

    @property
    def M(self) -> sp.csr_matrix:
        """Diagonal lumped mass matrix, in the value type of L."""
        return sp.diags(self.mass.astype(self.L_sym.dtype), format="csr")

    @property
    def S(self) -> sp.csr_matrix:
        """``M @ L_sym``: symmetric and negative semidefinite."""
        if self._S is None:
            self._S = sp.csr_matrix(self.M @ self.L_sym)
        return self._S

    @property
    def n_vertices(self) -> int:
        return len(self.mass)

    @property
    def shape(self) -> tuple[int, int]:
        return (self.n_vertices, self.n_vertices)

    @property
    def nnz(self) -> int:
        """Stored entries of ``L_sym``."""
        return int(self.L_sym.nnz)

    def dot(self, f: Any) -> np.ndarray:
        """``self @ f``, as scipy's sparse matrices and LinearOperator spell it."""
        return self @ f


class SparseLaplacian(LumpedLaplacian):
    """A Laplacian ``L`` with a diagonal mass ``M``: the common surface of every operator.

    ``L`` approximates +Δ (negative semidefinite), ``S = M L`` is symmetric, and
    ``op @ f`` applies ``L``, exactly as for :class:`~meshlap.MeshLaplacian`; ``L_sym`` is
    ``L`` itself (the matrix is symmetric in the M inner product).

    Parameters
    ----------
    L : sparse matrix
        The operator, (n, n).
    mass : (n,) array_like
        Diagonal of the mass matrix.
    name : str
        Short label used in tables and plots.
    S : sparse matrix, optional
        ``M @ L`` when it is known exactly (e.g. the cotangent matrix itself).

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> op = SparseLaplacian(sp.csr_matrix(np.array([[-1.0, 1.0], [1.0, -1.0]])), [1.0, 1.0])
    >>> op @ np.array([0.0, 1.0])
    array([ 1., -1.])
    """

    def __init__(self, L: Any, mass: Any, name: str = "custom", S: Any = None) -> None:
        self.L = sp.csr_matrix(L)
        self.mass = np.asarray(mass, dtype=np.float64)
        self.name = name
        self._S = None if S is None else sp.csr_matrix(S)

    def __matmul__(self, f: Any) -> np.ndarray:
        return np.asarray(self.L @ check_function(f, self.n_vertices))

    def as_linear_operator(self) -> LinearOperator:
        """``L`` as a :class:`scipy.sparse.linalg.LinearOperator`."""
        return sp.linalg.aslinearoperator(self.L)

    def __repr__(self) -> str:
        return f"SparseLaplacian({self.name}, vertices={self.n_vertices:,}, nnz={self.nnz:,})"
