"""Mean curvature per vertex from the Laplacian of the coordinates.

On a surface the Laplace–Beltrami operator of the position is ΔX = -2H n, with H the mean
of the principal curvatures and n the unit normal (H = 1/R on a sphere of radius R with the
outward normal). The point-wise convergence of the Belkin–Sun–Wang operator (SoCG 2008,
Theorem 3.1) therefore gives point-wise mean curvature on any mesh, including irregular and
noisy ones where the cotangent estimate does not converge.
"""

from __future__ import annotations

from typing import Any

import igl
import numpy as np

from .errors import MeshError
from .fem import welded_cells
from .geometry.topology import duplicate_vertices
from .geometry.validation import check_faces, check_vertices

__all__ = ["mean_curvature_normal", "mean_curvature"]


def _vertices(op: Any, V: Any) -> np.ndarray:
    if V is None:
        if not hasattr(op, "V"):
            raise MeshError("this operator does not carry its vertices; pass V (and F)")
        V = op.V
    V = check_vertices(V)
    if len(V) != op.n_vertices:
        raise MeshError(f"V has {len(V)} vertices but the operator has {op.n_vertices}")
    return V


def _geometry(op: Any, V: Any, F: Any) -> tuple[np.ndarray, np.ndarray]:
    V = _vertices(op, V)
    if F is None:
        if getattr(op, "faces", None) is None:
            raise MeshError("this operator does not carry faces (a curve, volume or point cloud has none) "
                            "to orient normals; pass F, or use mean_curvature_normal, whose norm is |H|")
        faces = op.faces
    else:
        faces = check_faces(F, len(V))
    return V, faces.triangles()


def mean_curvature_normal(op: Any, V: Any = None) -> np.ndarray:
    """The mean curvature normal H·n = -½ L X at every vertex, (n, 3).

    Parameters
    ----------
    op : MeshLaplacian or SparseLaplacian
        The Laplacian of the mesh.
    V : (n, 3) array_like, optional
        Vertex positions; default ``op.V``.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(2000, seed=0)
    >>> Hn = mean_curvature_normal(meshlap.laplacian(V, F), V)
    >>> bool(np.allclose(Hn, V, atol=0.05))        # H = 1, n = x on the unit sphere
    True
    """
    return -0.5 * np.asarray(op @ _vertices(op, V))


def mean_curvature(op: Any, V: Any = None, F: Any = None) -> np.ndarray:
    r"""Signed mean curvature H at every vertex, from ΔX = -2H n.

    ``|H| = ‖L X‖ / 2`` and the sign is that of ``-(L X)·n`` with n libigl's area-weighted
    vertex normal (``per_vertex_normals`` on the fan-triangulated faces), so H > 0 where the
    surface bends away from its normal (a sphere with outward-facing triangles has H = 1/R).

    Parameters
    ----------
    op : MeshLaplacian or SparseLaplacian
        The Laplacian of the mesh (any operator with ``op @ f``).
    V : (n, 3) array_like, optional
        Vertex positions; default ``op.V``.
    F : faces, optional
        Faces (any size) for the normals; default ``op.faces``.

    Returns
    -------
    (n,) ndarray
        Mean curvature; NaN at vertices that no face uses. Coincident copies share the normal
        of the faces around their point; where the faces' normals cancel (a triangle given
        twice, once each way) there is no sign and H is +|LX|/2.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(4000, seed=0)
    >>> H = mean_curvature(meshlap.laplacian(2 * V, F))      # radius 2
    >>> bool(np.abs(H - 0.5).max() < 0.01)
    True
    """
    V, T = _geometry(op, V, F)
    LX = np.asarray(op @ V)
    # copies of a point (an unwelded seam, a pole repeated per segment, whose own faces collapse)
    # take the normal of the faces around the point
    rep = duplicate_vertices(V)
    T = welded_cells(T, rep)
    N = igl.per_vertex_normals(V, T)[rep]
    used = np.zeros(len(V), dtype=bool)
    used[T.ravel()] = True
    used = used[rep]
    # faces that cancel (a triangle given twice, once each way) leave no normal: the sign is +
    sign = np.sign(-np.einsum("ij,ij->i", LX, np.nan_to_num(N, nan=0.0)))
    sign[sign == 0] = 1.0
    H = 0.5 * sign * np.linalg.norm(LX, axis=1)
    H[~used] = np.nan
    return H
