"""Stage 2 of the pipeline: the kernel width h, one value or one per point, from a policy.

The paper's width is h = (2ē)², ē the mean edge length (the geometry's spacing). The
corrected default starts from 4ē² and narrows it where the geometry bends faster than the
kernel can follow: h_w = min(h, β/κ_w²), κ_w² the squared change of the normal per squared
length along the neighbour edges at w (1 on the unit sphere). That needs normals, so it
applies where the codimension is 1 (surfaces in R³, plane curves, clouds of either).
``adaptive`` widths follow the local edge lengths instead, h_w = 4ℓ_w².

Everything here reads a :class:`~meshlap.geometry.Geometry` (points, spacing, edges,
normals) and knows nothing of how it was made.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from ._jit import jit
from .errors import MeshError
from .geometry import Geometry, from_mesh
from .geometry.validation import check_h, check_positive
from .tuned import CLOUD_CAP_FLOOR, H_SCALE

__all__ = ["DEFAULT_H_SCALE", "Widths", "choose", "curvature_h", "default_h", "h_scale", "local_h"]

#: c of h = c·ē² on surfaces (:data:`meshlap.tuned.H_SCALE` of k = 2).
DEFAULT_H_SCALE = H_SCALE[2]


@dataclass(frozen=True)
class Widths:
    """The widths of one build: ``h`` (the base width; the median with ``adaptive``),
    ``h_vertex`` (per point, or None when all are ``h``), whether h was chosen automatically,
    and the policy's parameters."""

    h: float
    h_vertex: np.ndarray | None
    h_auto: bool
    adaptive: bool = False
    curvature_limit: float = 0.0

    @property
    def largest(self) -> float:
        """The largest width: it sets the cut-off radius."""
        return self.h if self.h_vertex is None else float(self.h_vertex.max())

    def per_point(self, n: int) -> np.ndarray:
        """The widths as an (n,) array."""
        return np.full(n, self.h) if self.h_vertex is None else self.h_vertex


def default_h(V: Any, F: Any, k: int | None = None) -> float:
    """The paper's automatic width h = (2 ē)², ē the mean edge length of the cells.

    The Gaussian's standard deviation sqrt(2h) then spans about 2.8 mean edges, so each row
    averages over a few rings of neighbours. Pass ``h`` explicitly for convergence studies:
    the paper's operator's bias grows like O(h).

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    >>> round(default_h(V, [[0, 1, 2]]), 4)
    5.1808
    """
    return from_mesh(V, F, k).default_h


def h_scale(geo: Geometry) -> float:
    """c of the corrected default width h = c · spacing² for this geometry (:data:`~meshlap.tuned.H_SCALE`).

    Examples
    --------
    >>> import meshlap
    >>> h_scale(meshlap.geometry.from_mesh(*meshlap.shapes.sphere(100, seed=0)))
    4.0
    """
    return H_SCALE.get(geo.source, H_SCALE.get(geo.dim, DEFAULT_H_SCALE))


def _adjacency(n: int, edges: np.ndarray) -> sp.csr_matrix:
    e = edges
    return sp.csr_matrix((np.ones(2 * len(e)), (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])),
                         shape=(n, n))


def _ring_average(n: int, edges: np.ndarray, x: np.ndarray, times: int) -> np.ndarray:
    # average over each point and its edge neighbours, ``times`` times
    A = _adjacency(n, edges) + sp.eye(n, format="csr")
    norm = np.asarray(A.sum(axis=1)).ravel()
    for _ in range(times):
        x = (A @ x) / norm
    return x


def local_h(P: np.ndarray, edges: np.ndarray, scale: float, smoothing: int = 3) -> np.ndarray:
    """Per-point width h_w = scale · ℓ_w², ℓ_w² the mean squared length of the edges at w,
    averaged ``smoothing`` times over each point and its neighbours (so that h varies on the
    scale of several edges). Points on no edge get the mean of the others.

    Examples
    --------
    >>> import numpy as np
    >>> P = np.array([[0.0, 0], [1, 0], [2, 0]])
    >>> local_h(P, np.array([[0, 1], [1, 2]]), 4.0).tolist()
    [4.0, 4.0, 4.0]
    """
    n = len(P)
    l2 = ((P[edges[:, 0]] - P[edges[:, 1]]) ** 2).sum(axis=1)
    A = _adjacency(n, edges)
    deg = np.asarray(A.sum(axis=1)).ravel()
    used = deg > 0
    ell2 = np.bincount(edges[:, 0], l2, n) + np.bincount(edges[:, 1], l2, n)
    ell2[used] /= deg[used]
    A = A + sp.diags(used.astype(np.float64))
    norm = np.asarray(A.sum(axis=1)).ravel()
    for _ in range(smoothing):
        ell2 = np.divide(A @ ell2, norm, out=ell2.copy(), where=norm > 0)
    ell2[~used] = ell2[used].mean() if used.any() else 1.0
    return scale * ell2


def curvature_h(P: np.ndarray, edges: np.ndarray, normals: np.ndarray, h: np.ndarray | float,
                beta: float, smoothing: int = 3) -> np.ndarray:
    """Per-point widths h_w = min(h, β/κ_w²), averaged ``smoothing`` times over the neighbours.

    κ_w² = Σ|n_p − n_w|² / Σ|p − w|² over the edges at w (1 on the unit sphere): a ratio of
    sums, so that short edges, whose normals differ by noise, weigh little. Where the
    geometry bends on a scale shorter than √(h/β) (spot's horns, fandisk's creases) the
    kernel narrows; elsewhere h is unchanged.

    Examples
    --------
    >>> import meshlap
    >>> g = meshlap.geometry.from_mesh(*meshlap.shapes.sphere(500, seed=0))
    >>> hv = curvature_h(g.points, g.edges(), g.normals(), 1.0, 0.05)
    >>> bool(0.03 < hv.mean() < 0.07)                  # β/κ² with κ² ≈ 1 on the unit sphere
    True
    """
    n = len(P)
    e = np.ascontiguousarray(edges, dtype=np.int64)
    num, den = np.zeros(n), np.zeros(n)
    _curvature_sums(np.ascontiguousarray(P, dtype=np.float64),
                    np.ascontiguousarray(normals, dtype=np.float64), e, num, den)
    k2 = np.divide(num, den, out=np.zeros(n), where=den > 0)
    hv = np.broadcast_to(np.asarray(h, dtype=np.float64), (n,)).copy()
    capped = beta / np.maximum(k2, 1e-300)
    if not (capped < hv).any():
        return hv
    return _ring_average(n, e, np.minimum(hv, capped), smoothing)


@jit()
def _curvature_sums(P, N, e, num, den):  # pragma: no cover - compiled
    # num, den (zeros) += Σ|n_p − n_w|², Σ|p − w|² over the edges at w: to the bit the numpy
    # expression's np.bincount(e[:, 0], x, n) + np.bincount(e[:, 1], x, n) of
    # x = ((A[e[:, 0]] - A[e[:, 1]]) ** 2).sum(axis=1) (each sum in edge order, the two ends'
    # apart, then added), in one pass (0.31 -> 0.10 s of CPU at 400k vertices, measured)
    n = len(num)
    num1, den1 = np.zeros(n), np.zeros(n)
    for i in range(len(e)):
        a, b = e[i, 0], e[i, 1]
        x = P[a, 0] - P[b, 0]
        s = x * x
        y = N[a, 0] - N[b, 0]
        t = y * y
        for c in range(1, P.shape[1]):
            x = P[a, c] - P[b, c]
            s += x * x
            y = N[a, c] - N[b, c]
            t += y * y
        num[a] += t
        den[a] += s
        num1[b] += t
        den1[b] += s
    for v in range(n):
        num[v] += num1[v]
        den[v] += den1[v]


def _neighbour_edges(geo: Geometry) -> tuple[np.ndarray, Callable[[np.ndarray], np.ndarray]]:
    # a mesh's face sides, each interior edge once per face (so twice), as the widths were
    # measured with; the geometry's neighbour edges (cells, nearest neighbours) otherwise. On a
    # mesh's welded cells, with what gives each copy its point's width: a seam is no edge of the
    # widths, as it is none of the boundary
    e = geo.faces.edges() if geo.faces is not None else geo.edges()
    rep = geo.copies() if geo.tiled else None
    if rep is None:
        return e, lambda x: x
    e = rep[e]
    return e[e[:, 0] != e[:, 1]], lambda x: x[rep]


def choose(geo: Geometry, h: Any, *, plain: bool, adaptive: bool = False,
           curvature_limit: float = 0.0) -> Widths:
    """The widths of a build: an explicit ``h`` (a number or one per point) always wins;
    otherwise the paper's (2ē)² when ``plain``, else 4ē² (or ``adaptive`` local widths),
    capped by the curvature (``curvature_limit`` β > 0, where normals exist; on a surface's
    point cloud not below :data:`~meshlap.tuned.CLOUD_CAP_FLOOR` of the uncapped width).

    Examples
    --------
    >>> import meshlap
    >>> g = meshlap.geometry.from_mesh(*meshlap.shapes.sphere(500, seed=0))
    >>> w = choose(g, None, plain=True)
    >>> w.h == g.default_h, w.h_vertex is None
    (True, True)
    """
    n = geo.n_points
    if adaptive and h is not None:
        raise MeshError("adaptive=True chooses h per point; do not pass h with it")
    h_vertex: np.ndarray | None = None
    if h is not None and np.ndim(h) == 1:
        h_vertex = np.asarray(h, dtype=np.float64)
        if h_vertex.shape != (n,):
            raise MeshError(f"a per-point h needs one value per point ({n}); got {h_vertex.shape}")
        for x in (float(h_vertex.min()), float(h_vertex.max())):
            check_h(x, "the per-point h")
        h0 = float(h_vertex.max())
    elif h is not None:
        h0 = check_h(h)
    elif plain:
        h0 = check_h(geo.default_h, "the automatic h = (2·spacing)²")
    else:
        h0 = check_h(h_scale(geo) * geo.spacing**2, f"the automatic h = {h_scale(geo):g}·(spacing)²")
    if adaptive:
        edges, spread = _neighbour_edges(geo)
        h_vertex = spread(local_h(geo.points, edges, h_scale(geo)))
        check_h(float(h_vertex.min()), "the smallest local h")
        check_h(float(h_vertex.max()), "the largest local h")
        h0 = float(np.median(h_vertex[geo.mass > 0])) if (geo.mass > 0).any() else h0
    beta = 0.0
    normals = geo.normals() if curvature_limit else None
    if normals is not None:
        beta = check_positive(curvature_limit, "curvature_limit")
        base = h0 if h_vertex is None else h_vertex
        edges, spread = _neighbour_edges(geo)
        hv = spread(curvature_h(geo.points, edges, normals, base, beta))
        if not geo.tiled and geo.dim == 2:
            hv = np.maximum(hv, CLOUD_CAP_FLOOR * base)
        if (hv != base).any():
            check_h(float(hv.min()), "the smallest curvature-limited h")
            h_vertex = hv
    return Widths(h=h0, h_vertex=h_vertex,
                  h_auto=h is None, adaptive=adaptive, curvature_limit=beta)
