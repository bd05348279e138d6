"""Gradient and divergence of functions on the vertices of any geometry meshlap builds.

The heat method (:mod:`meshlap.geodesics`) needs a gradient of a vertex function and a
divergence of a vector field that is its adjoint. Each is a sparse matrix ``G`` from the
n vertex values to one vector of R^d per *element*, with the elements' measures ``w``:

* meshes (curves k = 1, surfaces k = 2 fan-triangulated, tetrahedra k = 3, any ambient
  dimension d ≥ k): the elements are the simplices, and ``G`` is the gradient of the linear
  (P1) interpolant, ∇u = Σ_j u_j ∇λ_j with ∇λ_j (j ≥ 1) the rows of (EEᵀ)⁻¹E, E the
  simplex's k edge vectors from its first corner, and ∇λ_0 = -Σ_{j≥1} ∇λ_j. On triangles this
  is the usual (N × e_i) / 2A; ``Gᵀ W G`` is then the P1 stiffness (the cotangent matrix on
  triangles) in any dimension;
* point clouds of intrinsic dimension 2 keep the local Delaunay triangles of their masses
  (:func:`~meshlap.geometry.point_cloud_geometry`): those are the elements by default
  (``method="auto"``), as for a mesh, but measured in the mean tangent plane of their corners
  (the top k eigenvectors of the sum of the corners' projectors onto their principal axes): a
  cloud samples a surface, and the triangles' tilt by the noise across it would lengthen every
  path (by 2% on a sphere of 10,000 points with 0.5% radial noise), while the mean plane is the
  triangle's own to O(h²) on a smooth surface. So are a mesh's triangles when its operator was
  built on denoised positions (``denoise=True``; the gradient of such an operator reads
  ``op.pencil_points``): the denoising step leaves them tilted by what noise remains;
  a cloud along a curve (k = 1) is joined to each point's
  nearest neighbour on either side along its tangent, the neighbours that set its mass;
* other point clouds (and ``method="least squares"``): the elements are the points, with
  their masses; the gradient at a point is
  the weighted least-squares fit of a linear function to its 16 nearest neighbours'
  differences in its k-dimensional tangent frame (principal axes), Gaussian weights of the
  neighbourhood's mean squared distance, mapped back to R^d.

The divergence is the (W-weighted) adjoint of the gradient, integrated over each vertex's
share: ``div X = -Gᵀ W X``, so that Σ_i φ_i (div X)_i = -Σ_e w_e ∇φ_e · X_e for every φ, the
weak form of ∫ φ div X = -∫ ∇φ · X (no boundary term: natural boundary conditions).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from .errors import MeshError
from .geometry import Geometry, frames, simplex_volumes

__all__ = ["Gradient", "gradient_operator"]

# neighbours of a point cloud's least-squares gradient (the frames' own neighbourhood size)
_CLOUD_NEIGHBORS = 16


@dataclass(frozen=True)
class Gradient:
    """A gradient ``G`` ((E·d) × n sparse) with the elements' measures ``w`` ((E,)).

    Attributes
    ----------
    G : scipy.sparse.csr_matrix
        Rows ``e·d + a``: component a of the gradient on element e.
    w : (E,) ndarray
        Measure of each element (simplex volume, or point mass for clouds).
    d : int
        Ambient dimension.
    kind : str
        "simplices" or "least squares".
    cells : (E, k+1) int ndarray or None
        The simplices (None for least squares, whose elements are the points).
    tangent : bool
        Whether the simplices are measured in their corners' mean tangent plane (a point
        cloud's, a denoised mesh's) rather than in their own.
    """

    G: sp.csr_matrix
    w: np.ndarray
    d: int
    kind: str
    cells: np.ndarray | None = None
    tangent: bool = False

    @property
    def n_elements(self) -> int:
        return len(self.w)

    def __call__(self, u: np.ndarray) -> np.ndarray:
        """Gradient of u ((n,) or (n, s)): (E, d) or (E, d, s)."""
        u = np.asarray(u, dtype=np.float64)
        g = self.G @ u
        return g.reshape(self.n_elements, self.d, *u.shape[1:])

    def divergence(self, X: np.ndarray) -> np.ndarray:
        """Integrated divergence ``-Gᵀ W X`` of X ((E, d) or (E, d, s)) at the vertices."""
        X = np.asarray(X, dtype=np.float64)
        wx = self.w.reshape(-1, *([1] * (X.ndim - 1))) * X
        return -(self.G.T @ wx.reshape(self.n_elements * self.d, *X.shape[2:]))

    def stiffness(self) -> sp.csr_matrix:
        """``Gᵀ W G``: positive semidefinite, the P1 stiffness on simplices."""
        Wd = sp.diags(np.repeat(self.w, self.d))
        return sp.csr_matrix(self.G.T @ Wd @ self.G)


def _simplices(geo: Geometry) -> np.ndarray | None:
    if geo.faces is not None:
        return np.asarray(geo.faces.triangles(), dtype=np.int64)
    if geo.cells is not None and len(geo.cells):  # curves, tetrahedra, a cloud's local triangles
        return np.asarray(geo.cells, dtype=np.int64)
    if geo.dim == 1:  # a cloud along a curve: each point's nearest neighbours ahead and behind
        return _curve_edges(geo)
    return None


def _curve_edges(geo: Geometry) -> np.ndarray:
    """Edges from each point to its nearest neighbour on either side along its tangent line (the
    neighbours that set its mass), each edge once."""
    T, idx = geo._pca()
    P = geo.points
    along = np.einsum("nkd,nd->nk", P[idx[:, 1:]] - P[:, None, :], T[:, :, 0])
    dist = np.abs(along)
    edges = [np.column_stack([np.arange(len(P)), idx[:, 1:][np.arange(len(P)), pick]])[ok]
             for side in (along > 0, along < 0)
             for pick, ok in [(np.argmin(np.where(side, dist, np.inf), axis=1), side.any(axis=1))]]
    e = np.sort(np.vstack(edges), axis=1)
    return np.unique(e[e[:, 0] != e[:, 1]], axis=0)


def _simplex_gradient(P: np.ndarray, cells: np.ndarray, tangent: np.ndarray | None = None) -> Gradient:
    m, c = cells.shape
    k, d = c - 1, P.shape[1]
    E = P[cells[:, 1:]] - P[cells[:, :1]]  # (m, k, d)
    if tangent is not None:  # the edges' components in the plane of the corners' mean projector
        T = tangent[cells]  # (m, c, d, k)
        frame = np.linalg.eigh(np.einsum("mcdk,mcek->mde", T, T))[1][:, :, -k:]
        E = np.einsum("mid,mda,mea->mie", E, frame, frame)
        vol = np.sqrt(np.maximum(np.linalg.det(np.einsum("mid,mjd->mij", E, E)), 0.0)) / math.factorial(k)
    else:
        vol = simplex_volumes(P, cells)
    gram = np.einsum("mid,mjd->mij", E, E)
    good = vol > 1e-12 * max(float(vol.max()), 1e-300)
    B = np.zeros((m, k, d))  # ∇λ_j, j = 1..k; degenerate cells keep 0 and measure 0
    B[good] = np.linalg.solve(gram[good], E[good])
    grads = np.concatenate([-B.sum(axis=1, keepdims=True), B], axis=1)  # (m, k+1, d)
    rows = (np.arange(m)[:, None, None] * d + np.arange(d)[None, None, :]).repeat(c, axis=1)
    cols = np.broadcast_to(cells[:, :, None], (m, c, d))
    G = sp.csr_matrix((grads.ravel(), (rows.ravel(), cols.ravel())), shape=(m * d, len(P)))
    return Gradient(G, np.where(good, vol, 0.0), d, "simplices", cells=cells, tangent=tangent is not None)


def _cloud_gradient(geo: Geometry) -> Gradient:
    P, k = geo.points, geo.dim
    n, d = P.shape
    T, idx = geo._pca()
    idx = idx[:, : _CLOUD_NEIGHBORS + 1]
    K = idx.shape[1] - 1
    if K < k:
        raise MeshError(f"a point cloud gradient needs more than {k} points; got {n}")
    vals = np.empty((n, d, K + 1))
    for a in range(0, n, 65536):  # blocks bound the temporaries
        sl = slice(a, min(a + 65536, n))
        D = P[idx[sl, 1:]] - P[sl, None, :]  # (b, K, d)
        Tk = T[sl, :, :k]  # (b, d, k)
        Y = np.einsum("bkd,bda->bka", D, Tk)
        r2 = np.maximum((D * D).sum(axis=2).mean(axis=1, keepdims=True), 1e-300)
        wgt = np.exp(-(D * D).sum(axis=2) / r2)  # (b, K)
        A = np.einsum("bka,bk,bkc->bac", Y, wgt, Y)
        A += 1e-10 * np.trace(A, axis1=1, axis2=2)[:, None, None] * np.eye(k)
        C = np.linalg.solve(A, np.swapaxes(Y * wgt[:, :, None], 1, 2))  # (b, k, K)
        Gi = Tk @ C  # (b, d, K): the gradient's weights on u_j - u_i
        vals[sl, :, 1:] = Gi
        vals[sl, :, 0] = -Gi.sum(axis=2)
    rows = np.broadcast_to((np.arange(n)[:, None] * d + np.arange(d))[:, :, None], (n, d, K + 1))
    cols = np.broadcast_to(idx[:, None, :], (n, d, K + 1))
    G = sp.csr_matrix((vals.ravel(), (rows.ravel(), cols.ravel())), shape=(n * d, n))
    return Gradient(G, np.asarray(geo.mass, dtype=np.float64), d, "least squares")


def gradient_operator(geometry: Any, method: str = "auto") -> Gradient:
    """The :class:`Gradient` of a geometry or of an operator (``op.geometry``).

    Parameters
    ----------
    geometry : Geometry or MeshLaplacian
        A mesh (curve, surface, tetrahedra) or a point cloud. An operator's simplices are
        measured at the positions its pencil was built on (``op.pencil_points``: after the
        denoising step of ``denoise=True``), so that ``Gᵀ W G`` is its FEM stiffness.
    method : {"auto", "simplices", "least squares"}
        ``"auto"``: the simplices of a mesh or of a cloud's local triangles, else least squares.

    Returns
    -------
    Gradient

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.plane(400, seed=0)
    >>> grad = gradient_operator(meshlap.geometry.surface(V, F))
    >>> g = grad(2 * V[:, 0] - V[:, 1])                 # exact for linear functions
    >>> bool(np.allclose(g[grad.w > 0, :2], [2, -1]))
    True
    """
    geo = getattr(geometry, "geometry", geometry)
    if not isinstance(geo, Geometry):
        raise MeshError(f"gradient_operator needs a Geometry or an operator with .geometry; got "
                        f"{type(geometry).__name__}")
    if method not in ("auto", "simplices", "least squares"):
        raise MeshError(f"method must be 'auto', 'simplices' or 'least squares'; got {method!r}")
    cells = _simplices(geo)
    if method != "least squares" and cells is not None:
        P = getattr(geometry, "pencil_points", geo.points)
        tangent = None  # a cloud's local triangles and a denoised mesh's are measured in their
        if not geo.tiled:  # corners' mean tangent plane
            tangent = geo._pca()[0][:, :, :geo.dim]
        elif P is not geo.points:
            tangent = frames.pca_frames(P, geo.dim)[0][:, :, :geo.dim]
        return _simplex_gradient(P, cells, tangent)
    if method == "simplices":
        raise MeshError("this geometry has no simplices (a point cloud of intrinsic dimension other than 2)")
    return _cloud_gradient(geo)
