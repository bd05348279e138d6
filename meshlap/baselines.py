"""Other Laplacians in the same shape as :class:`~meshlap.MeshLaplacian`, so that one line
swaps the operator in a comparison: the cotangent scheme ("COT" in Belkin–Sun–Wang's
tables), the uniform graph Laplacian, the intrinsic Delaunay Laplacian of
robust-laplacian (optional extra ``meshlap[robust]``), and a straightforward scipy
implementation of the same heat-kernel operator that serves as the reference point of the
benchmarks.

Every operator here follows meshlap's sign convention: ``L`` approximates +Δ and is
negative semidefinite, ``S = M L`` is symmetric.
"""

from __future__ import annotations

import math
from typing import Any

import igl
import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from .geometry import polyline, simplex_volumes
from .geometry.mass import _vertex_mass
from .geometry.validation import MeshError, check_faces, check_h, check_tol, check_vertices
from .lumped import SparseLaplacian
from .operator import DEFAULT_TOL
from .widths import default_h

__all__ = ["SparseLaplacian", "bsw_scipy", "cotangent", "intrinsic_delaunay", "uniform_graph"]


def cotangent(V: Any, F: Any) -> SparseLaplacian:
    """The cotangent Laplacian with the Voronoi (mixed) mass: L = M⁻¹ C.

    This is the "COT" scheme the paper compares against; ``C`` is libigl's ``cotmatrix``
    (negative semidefinite, like ours) and ``M`` libigl's Voronoi mass matrix. Rows of
    vertices without mass are left at zero. For a polyline (``F`` of two columns, its edges)
    it is the same scheme in 1-D: linear finite elements, C_ij = 1/|e_ij|, with the lumped
    mass (half the adjacent lengths), O(ē²) in the eigenvalues with Neumann ends.

    Examples
    --------
    >>> import meshlap
    >>> V, F = meshlap.shapes.sphere(500, seed=0)
    >>> cot = cotangent(V, F)
    >>> bool(abs((cot @ V[:, 0]) / V[:, 0] + 2).mean() < 0.2)
    True
    >>> P, E, _ = meshlap.samples.circle(400)           # the unit circle: -Δ cos t = cos t
    >>> bool(abs(cotangent(P, E) @ P[:, 0] + P[:, 0]).max() < 1e-4)
    True
    """
    if np.ndim(F) == 2 and np.shape(F)[1] == 2:
        return _segments(V, F)
    V, T = _triangles(V, F, "cotangent Laplacian")
    C = igl.cotmatrix(V, T)
    # libigl sizes both matrices by the largest face index: pad for trailing unreferenced vertices
    C = sp.csr_matrix(C)
    C.resize((len(V), len(V)))
    mass = np.zeros(len(V))
    vor = igl.massmatrix(V, T, igl.MASSMATRIX_TYPE_VORONOI).diagonal()
    mass[: len(vor)] = vor
    inv = np.divide(1.0, mass, out=np.zeros_like(mass), where=mass > 0)
    return SparseLaplacian(sp.diags(inv) @ C, mass, name="COT", S=C)


def _segments(V: Any, E: Any) -> SparseLaplacian:
    # 1-D linear finite elements on a polyline: the stiffness of the hat functions, lumped mass
    g = polyline(V, E)
    i, j = g.cells[:, 0], g.cells[:, 1]
    w = 1.0 / np.maximum(simplex_volumes(g.points, g.cells), 1e-300)
    n = g.n_points
    off = sp.csr_matrix((np.r_[w, w], (np.r_[i, j], np.r_[j, i])), shape=(n, n))
    C = (off - sp.diags(np.asarray(off.sum(axis=1)).ravel())).tocsr()
    inv = np.divide(1.0, g.mass, out=np.zeros_like(g.mass), where=g.mass > 0)
    return SparseLaplacian((sp.diags(inv) @ C).tocsr(), g.mass, name="COT (linear FEM on segments)", S=C)


def _triangles(V: Any, F: Any, what: str) -> tuple[np.ndarray, np.ndarray]:
    V = check_vertices(V)
    faces = check_faces(F, len(V))
    if faces.uniform_size != 3:
        raise MeshError(f"the {what} needs triangles; got polygons with other sizes")
    return V, faces.as_array()


def uniform_graph(V: Any, F: Any, weight: float = 1.0 / math.sqrt(3.0)) -> SparseLaplacian:
    """The uniform graph Laplacian: every mesh edge gets the same weight.

    ``S = weight · (A − D)`` with A the edge adjacency matrix and D its degree matrix (rows
    of S sum to zero), the barycentric mass m_p = Σ_{t∋p} Area(t)/3, and L = M⁻¹ S. The
    default weight 1/√3 is the cotangent weight (cot 60° + cot 60°)/2 of an equilateral
    mesh, so on a regular mesh L matches the cotangent Laplacian; on any other mesh it
    ignores the geometry and does not converge to Δ. It is the floor of the comparisons.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(500, seed=0)
    >>> op = uniform_graph(V, F)
    >>> bool(abs(op.S.sum(axis=1)).max() < 1e-12)
    True
    """
    V, T = _triangles(V, F, "uniform graph Laplacian")
    n = len(V)
    e = np.vstack([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]])
    e = np.unique(np.sort(e, axis=1), axis=0)
    A = sp.csr_matrix((np.ones(2 * len(e)), (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])),
                      shape=(n, n))
    S = float(weight) * (A - sp.diags(np.asarray(A.sum(axis=1)).ravel()))
    mass = _vertex_mass(V, check_faces(T, n))
    inv = np.divide(1.0, mass, out=np.zeros_like(mass), where=mass > 0)
    return SparseLaplacian(sp.diags(inv) @ S, mass, name="uniform graph", S=S)


def intrinsic_delaunay(V: Any, F: Any, mollify_factor: float = 1e-5) -> SparseLaplacian:
    """The intrinsic Delaunay (tufted cover) Laplacian of robust-laplacian, in meshlap's sign.

    robust-laplacian (Sharp and Crane, "A Laplacian for Nonmanifold Triangle Meshes", 2020)
    returns a positive semidefinite weak form ``L_r`` and a lumped mass ``M_r``; here
    ``S = −L_r`` and ``L = −M_r⁻¹ L_r``, so that ``L`` approximates +Δ like every other
    operator of meshlap. Needs the optional extra: ``pip install meshlap[robust]``.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(500, seed=0)
    >>> op = intrinsic_delaunay(V, F)
    >>> bool((op @ V[:, 0] * V[:, 0]).sum() < 0)
    True
    """
    try:
        import robust_laplacian
    except ImportError as exc:
        raise ImportError(
            "intrinsic_delaunay needs the robust-laplacian package: pip install meshlap[robust]"
        ) from exc
    V, T = _triangles(V, F, "intrinsic Delaunay Laplacian")
    Lr, Mr = robust_laplacian.mesh_laplacian(V, T, mollify_factor=mollify_factor)
    mass = np.asarray(Mr.diagonal(), dtype=np.float64)
    inv = np.divide(1.0, mass, out=np.zeros_like(mass), where=mass > 0)
    S = -sp.csr_matrix(Lr)
    return SparseLaplacian(sp.diags(inv) @ S, mass, name="intrinsic Delaunay", S=S)


def bsw_scipy(V: Any, F: Any, h: float | None = None, tol: float = DEFAULT_TOL) -> SparseLaplacian:
    """The Belkin–Sun–Wang operator built the straightforward way with scipy.

    Pairs within the cut-off radius come from ``cKDTree.sparse_distance_matrix`` as COO,
    which is turned into the kernel and converted to CSR. Same matrix as
    :func:`meshlap.laplacian` with ``correction="none"`` (to rounding); kept as the
    benchmarks' baseline.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(300, seed=0)
    >>> ref = bsw_scipy(V, F, h=0.02)
    >>> op = meshlap.laplacian(V, F, h=0.02, correction="none")
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
