"""Other Laplacians in the same shape as :class:`~meshlap.MeshLaplacian`, so that one line
swaps the operator in a comparison: the cotangent scheme ("COT" in Belkin–Sun–Wang's
tables) and a straightforward scipy implementation of the same heat-kernel operator that
serves as the reference point of the benchmarks.
"""

from __future__ import annotations

import math
from typing import Any

import igl
import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import LinearOperator
from scipy.spatial import cKDTree

from .mass import _vertex_mass
from .operator import DEFAULT_TOL, default_h
from .validation import MeshError, check_faces, check_function, check_h, check_tol, check_vertices

__all__ = ["SparseLaplacian", "cotangent", "bsw_scipy"]


class SparseLaplacian:
    """A Laplacian ``L`` with a diagonal mass ``M``: the common surface of every operator.

    ``L`` approximates +Δ (negative semidefinite), ``S = M L`` is symmetric, and
    ``op @ f`` applies ``L``, exactly as for :class:`~meshlap.MeshLaplacian`.

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

    @property
    def M(self) -> sp.csr_matrix:
        return sp.diags(self.mass, format="csr")

    @property
    def S(self) -> sp.csr_matrix:
        if self._S is None:
            self._S = sp.csr_matrix(self.M @ self.L)
        return self._S

    @property
    def n_vertices(self) -> int:
        return self.L.shape[0]

    @property
    def shape(self) -> tuple[int, int]:
        return self.L.shape

    @property
    def nnz(self) -> int:
        return int(self.L.nnz)

    def __matmul__(self, f: Any) -> np.ndarray:
        return np.asarray(self.L @ check_function(f, self.n_vertices))

    def as_linear_operator(self) -> LinearOperator:
        """``L`` as a :class:`scipy.sparse.linalg.LinearOperator`."""
        return sp.linalg.aslinearoperator(self.L)

    def __repr__(self) -> str:
        return f"SparseLaplacian({self.name}, vertices={self.n_vertices:,}, nnz={self.nnz:,})"


def cotangent(V: Any, F: Any) -> SparseLaplacian:
    """The cotangent Laplacian with the Voronoi (mixed) mass: L = M⁻¹ C.

    This is the "COT" scheme the paper compares against; ``C`` is libigl's ``cotmatrix``
    (negative semidefinite, like ours) and ``M`` libigl's Voronoi mass matrix. Rows of
    vertices without mass are left at zero.

    Examples
    --------
    >>> import meshlap
    >>> V, F = meshlap.shapes.sphere(500, seed=0)
    >>> cot = cotangent(V, F)
    >>> bool(abs((cot @ V[:, 0]) / V[:, 0] + 2).mean() < 0.2)
    True
    """
    V = check_vertices(V)
    faces = check_faces(F, len(V))
    if faces.uniform_size != 3:
        raise MeshError("the cotangent Laplacian needs triangles; got polygons with other sizes")
    T = faces.as_array()
    C = igl.cotmatrix(V, T)
    mass = igl.massmatrix(V, T, igl.MASSMATRIX_TYPE_VORONOI).diagonal()
    inv = np.divide(1.0, mass, out=np.zeros_like(mass), where=mass > 0)
    return SparseLaplacian(sp.diags(inv) @ C, mass, name="COT", S=C)


def bsw_scipy(V: Any, F: Any, h: float | None = None, tol: float = DEFAULT_TOL) -> SparseLaplacian:
    """The Belkin–Sun–Wang operator built the straightforward way with scipy.

    Pairs within the cut-off radius come from ``cKDTree.sparse_distance_matrix`` as COO,
    which is turned into the kernel and converted to CSR. Same matrix as
    :func:`meshlap.laplacian` (to rounding); kept as the benchmarks' baseline.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(300, seed=0)
    >>> ref = bsw_scipy(V, F, h=0.02)
    >>> op = meshlap.laplacian(V, F, h=0.02)
    >>> bool(abs(ref.L - op.L).max() < 1e-10)
    True
    """
    V = check_vertices(V)
    faces = check_faces(F, len(V))
    tol = check_tol(tol)
    if tol == 0:
        raise MeshError("bsw_scipy needs tol in (0, 1): it is the truncated baseline")
    h = default_h(V, faces) if h is None else check_h(h)
    mass = _vertex_mass(V, faces)
    r = math.sqrt(4.0 * h * math.log(1.0 / tol))
    tree = cKDTree(V)
    D = tree.sparse_distance_matrix(tree, r, output_type="coo_matrix")
    keep = D.row != D.col
    rows, cols, d = D.row[keep], D.col[keep], D.data[keep]
    w = np.exp(-(d * d) / (4.0 * h)) * mass[cols] / (4.0 * math.pi * h * h)
    n = len(V)
    off = sp.csr_matrix((w, (rows, cols)), shape=(n, n))
    L = off - sp.diags(np.asarray(off.sum(axis=1)).ravel())
    return SparseLaplacian(L.tocsr(), mass, name="BSW (scipy)")
