"""A Galerkin width that follows feature size: narrower next to grooves and on thin parts.

The Galerkin pencil's kernel has one width, h = ½ē². Two features are narrower than it can
follow: a concave crease (a groove, :func:`~meshlap.corrections.galerkin.creases` with
``concave=True``), whose two sides face each other across the air, and a part thinner than a
few kernel widths √(2h) (spot's teats), on which the kernel's disc does not fit. A feature
size per vertex, the smaller of its distance to the nearest concave crease edge over
:data:`~meshlap.tuned.CREASE_WIDTHS` widths and half its distance to the surface's other side
(a vertex of opposite normal along both normals, :func:`thickness`) over
:data:`~meshlap.tuned.FEATURE_THIN_WIDTHS` widths, sets

    h_v = h · clip(size_v², FEATURE_FLOOR, 1),

which :func:`~meshlap.corrections.galerkin.galerkin_pencil` takes as ``h_vertex`` (each pair
at the mean of its two points' widths, triangles cut so that the quadrature resolves the
narrower kernel). Eigenvalues 1-9 against COT 16× refined (benchmarks/RESULTS.md): fandisk
0.142% → 0.087% (COT 0.085%), spot 1.32% → 0.96% (eigenvalue 5, on the teats, −1.33% →
−0.46%). Convex creases are left alone: their unfolded distance is exact across a straight
one, and narrowing there moved the cube surface's 0.043% to 0.051%, its 386-vertex
version's 0.28% to 0.49%.

Noise makes fake creases and fake opposite sides (on a sphere of 16,000 random vertices with
0.5% radial noise 89% of the vertices would narrow): the build narrows nothing on a mesh whose
normals are noise (roughness, :func:`~meshlap.corrections.galerkin.shape_measures`, above
:data:`~meshlap.tuned.NOISE_ROUGHNESS`), nor at an explicit h.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from ..tuned import CREASE_WIDTHS, FEATURE_FLOOR, FEATURE_THIN_WIDTHS

__all__ = ["crease_distance", "feature_widths", "thickness"]


def crease_distance(P: np.ndarray, crease_edges: np.ndarray, limit: float) -> np.ndarray:
    """Each vertex's distance to the nearest crease edge, ``inf`` beyond ``limit``.

    Examples
    --------
    >>> import numpy as np
    >>> P = np.array([[0.0, 0, 0], [1, 0, 0], [0.5, 0.3, 0], [0.5, 2, 0]])
    >>> crease_distance(P, np.array([[0, 1]]), 1.0).round(3).tolist()
    [0.0, 0.0, 0.3, inf]
    """
    out = np.full(len(P), np.inf)
    if not len(crease_edges):
        return out
    a, b = P[crease_edges[:, 0]], P[crease_edges[:, 1]]
    ab = b - a
    reach = limit + 0.5 * float(np.linalg.norm(ab, axis=1).max())
    near = cKDTree(0.5 * (a + b)).query_ball_point(P, reach)
    for v, edges in enumerate(near):
        if edges:
            e = np.asarray(edges)
            t = ((P[v] - a[e]) * ab[e]).sum(axis=1) / np.maximum((ab[e] ** 2).sum(axis=1), 1e-300)
            t = np.clip(t, 0.0, 1.0)
            d = float(np.linalg.norm(a[e] + t[:, None] * ab[e] - P[v], axis=1).min())
            out[v] = d if d <= limit else np.inf
    return out


def thickness(P: np.ndarray, normals: np.ndarray, limit: float) -> np.ndarray:
    """Each vertex's distance to the surface's other side, ``inf`` beyond ``limit``: the nearest
    vertex whose normal points the opposite way (more than 120° apart) and which lies along
    both normals (within 45°), as across a thin limb or wall.

    Examples
    --------
    >>> import numpy as np
    >>> P = np.array([[0.0, 0, 0], [0, 0, 0.1], [1, 0, 0]])      # a slab 0.1 thick
    >>> N = np.array([[0.0, 0, -1], [0, 0, 1], [0, 0, -1]])
    >>> thickness(P, N, 0.5).tolist()
    [0.1, 0.1, inf]
    """
    out = np.full(len(P), np.inf)
    pairs = cKDTree(P).query_pairs(limit, output_type="ndarray")
    if not len(pairs):
        return out
    i, j = pairs[:, 0], pairs[:, 1]
    across = _across(P, normals, i, j)
    dist = np.linalg.norm(P[j] - P[i], axis=1)
    np.minimum.at(out, i[across], dist[across])
    np.minimum.at(out, j[across], dist[across])
    return out


def _across(P: np.ndarray, normals: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    # the pairs on opposite sides: normals more than 120° apart, each along the other's normal
    d = P[j] - P[i]
    reach = np.linalg.norm(d, axis=1) * math.cos(math.pi / 4)
    return (((normals[i] * normals[j]).sum(axis=1) < -0.5) & (np.abs((d * normals[i]).sum(axis=1)) > reach)
            & (np.abs((d * normals[j]).sum(axis=1)) > reach))


def feature_widths(P: np.ndarray, normals: np.ndarray, crease_edges: np.ndarray, h: float,
                   crease: float = CREASE_WIDTHS, thin: float = FEATURE_THIN_WIDTHS,
                   floor: float = FEATURE_FLOOR) -> np.ndarray:
    """Per-vertex widths ``h_v`` at most ``h``: ``h·clip(s², floor, 1)``, s the smaller of the
    distance to the ``crease_edges`` (the concave creases) over ``crease`` kernel widths √(2h)
    and half the thickness over ``thin`` of them.

    Examples
    --------
    >>> import numpy as np
    >>> P = np.array([[0.0, 0, 0], [1, 0, 0], [0.5, 0.7, 0], [0.5, 2, 0]])
    >>> N = np.tile([0.0, 0, 1], (4, 1))
    >>> feature_widths(P, N, np.array([[0, 1]]), 0.02, crease=4.0).round(4).tolist()
    [0.01, 0.01, 0.0153, 0.02]
    """
    sigma = math.sqrt(2.0 * h)
    size = np.minimum(crease_distance(P, crease_edges, crease * sigma) / (crease * sigma),
                      0.5 * thickness(P, normals, 2.0 * thin * sigma) / (thin * sigma))
    return h * np.clip(size**2, floor, 1.0)
