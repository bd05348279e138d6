"""Quadratic elements with a lumped mass on a triangle mesh: the spectra of the default.

The linear pencil ``(S, M)`` of :mod:`meshlap.fem` has one degree of freedom per vertex; its
eigenvalues carry linear FEM's O(h²) error, which on coarse CAD parts (long flat triangles) and
decimated models is 10-30%. :func:`meshlap.spectral.eigs` solves instead, on the same intrinsic
Delaunay triangles, the seven-node element of Cohen, Joly and Tordjman (2001): quadratic
polynomials enriched by the cubic bubble λ₀λ₁λ₂, with nodes at the corners, the edge midpoints
and the centroid, and the mass lumped by the quadrature rule on those nodes with weights
area·(1/20, 2/15, 9/20), exact for cubics. The weights are positive, so the mass stays diagonal
(every solver here expects that), and the scheme keeps the quadratic element's order; the
stiffness is integrated exactly. Its eigenvectors are read at the vertices (each basis function
but a corner's vanishes there).

The polyhedral surface is the one linear FEM discretizes (the element is flat in the triangle's
intrinsic metric), so the linear pencil's own limit is what it approximates better: on the 50 real
surfaces of ``benchmarks/bench_real.py``, against linear FEM on the 4× and 16× refinement, its
largest error of eigenvalues 1-9 is a median 0.028× (worst 0.89×) that of the best of libigl's
cotangent Laplacian, LaPy and robust-laplacian (benchmarks/RESULTS.md). It costs the degrees of
freedom of the vertices, the edges and the triangles, about six per vertex.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from . import fem
from .errors import MeshError
from .lumped import SparseLaplacian

__all__ = ["at_vertices", "element_matrices", "fine_pencil", "quadratic_pencil", "unknowns"]

# Dunavant's 6-point rule, exact to degree 4 (the stiffness of cubics' gradients), barycentric
_A, _B, _WA = 0.445948490915965, 0.108103018168070, 0.223381589678011
_C, _D, _WC = 0.091576213509771, 0.816847572980459, 0.109951743655322
_POINTS = np.array([[_A, _A, _B], [_A, _B, _A], [_B, _A, _A], [_C, _C, _D], [_C, _D, _C], [_D, _C, _C]])
_WEIGHTS = np.array([_WA] * 3 + [_WC] * 3)
#: the lumped mass of the corners, the edge midpoints and the centroid, per unit area
NODE_WEIGHTS = np.array([1 / 20] * 3 + [2 / 15] * 3 + [9 / 20])
_SIDES = ((0, 1), (1, 2), (2, 0))


def element_matrices(lengths: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and lumped mass of the seven-node element on triangles given by edge lengths.

    Parameters
    ----------
    lengths : (m, 3) ndarray
        ``lengths[f, c]`` the length of the side from corner c to corner c + 1; a degenerate
        triangle (as :func:`meshlap.fem.triangle_areas` judges it) gets zero matrices.

    Returns
    -------
    K : (m, 7, 7) ndarray
        ∫ ∇φ_i · ∇φ_j, nodes ordered corners 0-2, midpoints of sides 01, 12, 20, centroid;
        positive semidefinite, rows summing to zero.
    w : (m, 7) ndarray
        The lumped masses, area · (1/20, 1/20, 1/20, 2/15, 2/15, 2/15, 9/20).

    Examples
    --------
    >>> import numpy as np
    >>> K, w = element_matrices(np.array([[1.0, np.sqrt(2), 1.0]]))   # the right triangle, area ½
    >>> bool(abs(K[0].sum(axis=1)).max() < 1e-12), round(float(w.sum()), 12)
    (True, 0.5)
    >>> x = np.array([0, 1, 0, 0.5, 0.5, 0, 1 / 3])   # u = x at the nodes: ∫|∇u|² = area
    >>> round(float(x @ K[0] @ x), 12)
    0.5
    """
    L = np.asarray(lengths, dtype=np.float64)
    area = fem.triangle_areas(L)
    ok = area > 0
    L = np.where(ok[:, None], L, 1.0)  # a unit equilateral stand-in, zeroed by its area below
    l01, l12, l20 = L[:, 0], L[:, 1], L[:, 2]
    x = (l01**2 + l20**2 - l12**2) / (2 * l01)  # the triangle laid out: (0, 0), (l01, 0), (x, y)
    y = np.where(ok, 2 * area / l01, np.sqrt(0.75))
    g1 = np.stack([1 / l01, -x / (l01 * y)], axis=1)
    g2 = np.stack([np.zeros_like(x), 1 / y], axis=1)
    g = np.stack([-g1 - g2, g1, g2], axis=1)  # (m, 3, 2) gradients of the barycentrics
    # the gradients at every quadrature point, side by side and scaled by √w (the weights are
    # positive): K = Σ_q w_q G_q G_qᵀ is then one batched product
    G = np.empty((len(L), 7, 2 * len(_WEIGHTS)))
    for q, (lam, wq) in enumerate(zip(_POINTS, _WEIGHTS, strict=True)):
        Gq = G[:, :, 2 * q:2 * q + 2]
        grad_b = lam[1] * lam[2] * g[:, 0] + lam[0] * lam[2] * g[:, 1] + lam[0] * lam[1] * g[:, 2]
        for i in range(3):  # λ_i(2λ_i - 1) + 3 λ₀λ₁λ₂
            Gq[:, i] = (4 * lam[i] - 1) * g[:, i] + 3 * grad_b
        for s, (i, j) in enumerate(_SIDES):  # 4 λ_i λ_j - 12 λ₀λ₁λ₂
            Gq[:, 3 + s] = 4 * (lam[j] * g[:, i] + lam[i] * g[:, j]) - 12 * grad_b
        Gq[:, 6] = 27 * grad_b
        Gq *= np.sqrt(wq)
    K = G @ G.transpose(0, 2, 1)
    return K * area[:, None, None], area[:, None] * NODE_WEIGHTS[None, :]


def unknowns(geo: Any) -> int:
    """About how many unknowns :func:`quadratic_pencil` has for a polygon mesh: its vertices,
    edges (1.5 per fan triangle) and triangles, without building anything.

    Examples
    --------
    >>> import meshlap
    >>> unknowns(meshlap.geometry.from_mesh(*meshlap.shapes.sphere(1000, seed=0)))   # 1,000 + 4,990
    5990
    """
    return int(geo.n_points + 2.5 * int((geo.faces.sizes - 2).sum()))


def quadratic_pencil(geo: Any, points: np.ndarray | None = None,
                     area_scale: np.ndarray | None = None) -> tuple[sp.csr_matrix, np.ndarray]:
    """The seven-node elements' pencil ``(S, m)`` on a triangle mesh's intrinsic Delaunay
    triangulation: the vertices' degrees of freedom first (in order), then one per edge and one
    per triangle. Copies of a vertex (``Geometry.copies``) are welded onto their
    representative; the copies' own rows are empty and massless.

    Parameters
    ----------
    geo : Geometry
        A surface mesh (faces of any size, fan-triangulated).
    points : (n, d) ndarray, optional
        Positions to use instead of the geometry's (the denoised ones of ``op.pencil_points``).
    area_scale : (n,) ndarray, optional
        A factor on each vertex's mass, taken by the elements of its triangles
        (``op.area_scale``: the denoised positions' metric).

    Returns
    -------
    S : (N, N) scipy.sparse.csr_matrix
        Negative semidefinite, rows summing to zero.
    m : (N,) ndarray
        The lumped masses (zero on copies and on vertices in no triangle).

    Examples
    --------
    >>> import meshlap, numpy as np, scipy.sparse as sp, scipy.sparse.linalg as sla
    >>> g = meshlap.geometry.from_mesh(*meshlap.shapes.sphere(500, seed=0))
    >>> S, m = quadratic_pencil(g)
    >>> lam = np.sort(sla.eigsh(-S, 4, sp.diags(m), sigma=-1e-3, return_eigenvectors=False))
    >>> (np.round(lam, 2) + 0.0).tolist()       # 0, then l(l + 1) = 2 (the inscribed polyhedron: 0.5% above)
    [0.0, 2.01, 2.01, 2.01]
    """
    cells = fem.simplicial_cells(geo)
    if geo.faces is None or cells is None or cells.shape[1] != 3:
        raise MeshError(f"quadratic elements need a triangle or polygon mesh; this {geo.source} has none")
    n = geo.n_points
    weld = geo.copies()
    if weld is not None:
        cells = fem.welded_cells(cells, weld)
    tri, lengths = fem.intrinsic_delaunay(geo.points if points is None else points, cells)
    K, w = element_matrices(lengths)
    if area_scale is not None:
        w = w * np.asarray(area_scale)[tri[:, :1]]
    sides = np.sort(np.concatenate([tri[:, list(p)] for p in _SIDES]), axis=1)
    edges, which = np.unique(sides, axis=0, return_inverse=True)
    dof = np.hstack([tri, n + which.reshape(3, len(tri)).T, (n + len(edges) + np.arange(len(tri)))[:, None]])
    N = n + len(edges) + len(tri)
    rows, cols = np.repeat(dof, 7, axis=1).ravel(), np.tile(dof, (1, 7)).ravel()
    S = -sp.csr_matrix((K.ravel(), (rows, cols)), shape=(N, N))
    return sp.csr_matrix(0.5 * (S + S.T)), np.bincount(dof.ravel(), w.ravel(), minlength=N)


def fine_pencil(op: Any) -> SparseLaplacian:
    """The operator whose eigenpairs :func:`meshlap.spectral.eigs` computes for ``op`` with
    ``elements="quadratic"``: the seven-node pencil on ``op``'s triangles and pencil points,
    once per operator.

    Examples
    --------
    >>> import meshlap
    >>> op = meshlap.laplacian(*meshlap.shapes.sphere(300, seed=0))
    >>> fine = fine_pencil(op)
    >>> fine.n_vertices > 5 * op.n_vertices, fine.name
    (True, 'quadratic elements')
    """
    geo = getattr(op, "geometry", None)
    if geo is None or geo.faces is None:
        raise MeshError("elements='quadratic' needs an operator built on a triangle or polygon mesh "
                        "(meshlap.laplacian(V, F))")
    cached = getattr(op, "_quadratic", None)
    if cached is None:
        S, m = quadratic_pencil(geo, op.pencil_points, getattr(op, "area_scale", None))
        inv = np.divide(1.0, m, out=np.zeros_like(m), where=m > 0)
        cached = op._quadratic = SparseLaplacian(sp.diags(inv) @ S, m, name="quadratic elements", S=S)
    return cached


def at_vertices(op: Any, X: np.ndarray) -> np.ndarray:
    """Eigenvectors of :func:`fine_pencil` read at ``op``'s vertices (a copy takes its
    representative's value), then made orthonormal in ``op.M`` (Löwdin: the nearest such block).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> op = meshlap.laplacian(*meshlap.shapes.sphere(300, seed=0))
    >>> phi = at_vertices(op, np.random.default_rng(0).normal(size=(fine_pencil(op).n_vertices, 3)))
    >>> bool(np.allclose(phi.T @ op.M @ phi, np.eye(3)))
    True
    """
    n = op.n_vertices
    weld = op.geometry.copies()
    phi = X[:n] if weld is None else X[weld]
    gram = phi.T @ (op.mass[:, None] * phi)
    vals, vecs = np.linalg.eigh(0.5 * (gram + gram.T))
    return phi @ (vecs / np.sqrt(np.maximum(vals, 1e-300))) @ vecs.T
