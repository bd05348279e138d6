"""Noise along the normals of a surface mesh, and the heat step that takes it out of the metric.

Normal noise of size σ on a mesh of mean edge ē tilts its triangles by about σ/ē, which inflates
their areas and shortens their cotangent paths: linear FEM on the noisy mesh is off by
O(σ²/ē²) (0.1 ē of noise: 2.5% on eigenvalues 1-9 of spot and fandisk; 0.3 ē: 16%), whatever
its resolution. Averaging the positions with the heat kernel takes it out: one implicit heat
step of time τ = (c σ̂)² (``(M − τS) X' = M X``) damps a displacement of eigenvalue μ by
1/(1 + τμ), the vertex-scale noise (μ of order 1/ē²) by a factor set by (σ/ē)², while it moves
a smooth shape of curvature κ by O(τκ): the shape's own metric changes by O(σ²κ²), smaller
than the error removed by (κē)², which is small wherever the mesh resolves the shape. σ̂ is
measured, not set: the residual of local quadric height fits, whose misfit on a clean surface
is a cubic term far below any noise that matters (a clean 4,000-vertex sphere: below 1e-4).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from .geometry import frames
from .tuned import NOISE_AREA, NOISE_QUANTILE, NOISE_STEP

__all__ = ["NEIGHBOURS", "SAMPLE", "denoised", "kept_shapes", "normal_noise", "smoothed_points"]

#: Neighbours of each cubic height fit: 10 coefficients, 14 degrees of freedom left.
NEIGHBOURS = 24
#: At most this many vertices are fitted (evenly spaced in the input order): the median of
#: their variances is read, and it is stable well before this count.
SAMPLE = 20000


def normal_noise(P: np.ndarray, normals: np.ndarray | None = None) -> float:
    """σ̂: the normal noise seen by cubic height fits, at the lower quartile over the vertices.

    Each fitted vertex takes its :data:`NEIGHBOURS` nearest vertices, their principal frame
    (the smallest principal direction the normal), and fits the heights by a cubic in the
    two tangent coordinates; the residual's variance over its degrees of freedom estimates
    σ² there, and the :data:`~meshlap.tuned.NOISE_QUANTILE` over the vertices passes over
    creases and corners, which a cubic does not fit.

    Parameters
    ----------
    P : (n, 3) ndarray
        Vertex positions of a surface.
    normals : (n, 3) ndarray, optional
        Unused unless given: the frame's normal where the principal one is ambiguous.

    Returns
    -------
    float
        σ̂ in the units of P (0 for fewer than NEIGHBOURS points).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(4000, seed=0)
    >>> noisy = V * (1 + 0.004 * np.random.default_rng(0).standard_normal((4000, 1)))
    >>> bool(0.7 < normal_noise(noisy) / 0.004 < 1.1), normal_noise(V) < 1e-4   # its lower quartile
    (True, True)
    """
    P = np.asarray(P, dtype=np.float64)
    n = len(P)
    if n < NEIGHBOURS or P.shape[1] != 3:
        return 0.0
    rows = np.arange(0, n, max(1, n // SAMPLE))
    T, idx = frames.pca_frames(P, 2, NEIGHBOURS - 1, rows)
    res, dof = frames.height_residuals(P, T, idx, 2, (3,))
    return float(np.sqrt(np.quantile(res[0] / dof[0], NOISE_QUANTILE)))


def smoothed_points(P: np.ndarray, S: sp.spmatrix, m: np.ndarray, tau: float) -> np.ndarray:
    """One implicit heat step of the positions: (M − τS) X' = M X (S ≈ MΔ, negative
    semidefinite), which keeps the centroid of every part.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> S = sp.csr_matrix(np.array([[-1.0, 1], [1, -1]]))
    >>> smoothed_points(np.array([[0.0], [1.0]]), S, np.ones(2), 0.5).ravel().tolist()
    [0.25, 0.75]
    """
    A = sp.csc_matrix(sp.diags(m) - tau * S)
    return np.asarray(sla.splu(A).solve(m[:, None] * np.asarray(P, dtype=np.float64)))


def denoised(P: np.ndarray, S: sp.spmatrix, m: np.ndarray, sigma: float) -> np.ndarray | Any:
    """The positions after the heat step of time (NOISE_STEP·σ)² (module docstring); ``P`` for σ = 0."""
    return P if sigma <= 0 else smoothed_points(P, S, m, (NOISE_STEP * sigma) ** 2)


def kept_shapes(P: np.ndarray, X: np.ndarray, area: np.ndarray, area_after: np.ndarray, label: np.ndarray,
                noise: float) -> np.ndarray:
    """``X`` with every part that the step shrank by more than noise could have inflated it
    back at ``P``: its shape, not its noise, was moved.

    Normal noise σ inflates a surface's area by about 1 + NOISE_AREA·(σ/ē)², which the step
    takes back (0.81-0.87 of the area at 0.3ē on five scans, as the clean meshes have). A part
    that loses more than noise of 2σ̂ would have added, 1/(1 + NOISE_AREA·(2σ̂/ē)²), is one the
    mesh does not resolve (a 10-vertex leg of a coarse model shrinks to a tenth and its masses
    to 1e-8 of the rest): the heat step is a denoiser only where the shape is resolved.

    Parameters
    ----------
    P, X : (n, d) ndarray
        The positions before and after the step.
    area, area_after : (n,) ndarray
        The vertices' masses (areas) before and after.
    label : (n,) int ndarray
        The part of every vertex.
    noise : float
        σ̂ / ē.

    Examples
    --------
    >>> P = np.zeros((4, 3)); X = np.ones((4, 3))
    >>> kept_shapes(P, X, np.ones(4), np.array([0.9, 0.9, 0.1, 0.1]), np.array([0, 0, 1, 1]), 0.2)[:, 0]
    array([1., 1., 0., 0.])
    """
    before = np.bincount(label, area)
    after = np.bincount(label, area_after, minlength=len(before))
    shrunk = after < before / (1.0 + NOISE_AREA * (2.0 * noise) ** 2)
    if not shrunk.any():
        return X
    out = np.array(X, copy=True)
    out[shrunk[label]] = P[shrunk[label]]
    return out
