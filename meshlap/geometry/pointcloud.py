"""The heat-kernel Laplacian of a point cloud: masses from the points alone.

Belkin, Sun and Wang, "Constructing Laplace operator from point clouds in R^d" (SODA 2009),
weight each point by the measure of its cell in a local Delaunay/Voronoi structure built in
the estimated tangent space, and normalize the Gaussian by 1/(h (4πh)^{k/2}) for intrinsic
dimension k. One mass per point (as Liu, Prabhakaran and Guo, 2012, do with Voronoi areas)
keeps S = M L symmetric and -S positive semidefinite, exactly as for a mesh.

For each point p, with its K nearest neighbours:

1. the tangent space is the span of the k leading principal axes of the neighbourhood (for
   k = 2 of the first wider one where the first lies along a line, as on a scanner's lines);
2. the neighbours are projected onto it, relative to p;
3. the local Delaunay star of p in that k-plane gives the mass: the measure of the
   simplices around p divided by k + 1 — the lumped mass of a mesh, without a mesh.

For k = 2 the star comes from clipping p's Voronoi cell by the bisectors of its projected
neighbours (convex polygon clipping, O(K²) per point, compiled): two consecutive edges of the
cell, cut by neighbours a and b, meet at the circumcentre of the Delaunay triangle (p, a, b).
For k = 1 the star is the two nearest neighbours along the tangent line, so the mass is half
the gap between them. For k = 3 the star comes from the cell's Voronoi vertices, for k ≥ 4
from scipy's Delaunay of each projected neighbourhood. A star is only trusted when no point
outside the K neighbours can reach it: every Delaunay circumcircle must lie within half the
distance of the farthest neighbour; otherwise K grows. A trusted star is the one in the whole
cloud's Delaunay triangulation, so a volume in R³ takes the stars the first neighbourhood does
not secure from one tetrahedralization of all its points, and searches only the rest. Where
four points are cocircular in space (a grid on a curved surface) every star takes one split.

What the points leave empty is a hole, not a face: a star's triangle (a curve's segment) whose
empty circumdisc i.i.d. sampling at its corners' density would leave with odds below
:data:`HOLE_ODDS` anywhere in the cloud is dropped, so an open surface's opening stays open
however far the search reaches across it, and slivers along a concave rim go too.

On 16,000 i.i.d. random points of the unit sphere these masses are within a few percent of
the barycentric masses of the points' true triangulation (their convex hull), which is what
the Laplacian's accuracy depends on (see the README's point-cloud section for numbers).

Messy input has defined behaviour, each with a :class:`~meshlap.validation.MeshWarning`:

* duplicate and near-coincident points (closer than ``merge_tol`` times the median
  neighbour distance) are merged for the mass estimate and share the merged point's mass;
* outliers (a nearest neighbour ``outlier_ratio`` times farther than usual around it) get mass 0
  and no star: rows of L, never sources of its sums, outside the FEM pencil's cells;
* points whose neighbourhood has no k-dimensional extent (collinear neighbours for k = 2)
  take the median mass of their neighbours;
* fewer than k + 2 distinct points, or d < k, raise :class:`~meshlap.validation.MeshError`.
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np
import scipy.sparse as sp
from pykdtree.kdtree import KDTree
from scipy.sparse.csgraph import connected_components
from scipy.special import gammaln

from .._jit import in_blocks
from .._keys import in_set
from ..errors import MeshError, MeshWarning
from ..tuned import STAR_NEIGHBORS, STAR_THIN
from . import frames
from .core import Geometry, check_points
from .noise import noise_reading, project_to_tangent
from .sheets import bridges
from .stars import (
    _DEGENERATE,
    _INSECURE,
    _OK,
    _STAR_SLOTS,
    _circumradii,
    _consistent,
    _global_stars3,
    _masses1,
    _masses2,
    _masses3,
    _masses_k,
    _off_surface,
    _soup,
    _tie_cut,
    star_pieces,
)
from .validation import _real_scalar, check_int

__all__ = ["point_cloud_geometry", "point_masses"]


# the first neighbourhood (STAR_NEIGHBORS) doubles for the points whose star it does not secure,
# up to this
_MAX_NEIGHBORS = 256
# an empty gap or circumdisc less likely than this under i.i.d. sampling, anywhere in a curve's or a
# surface's cloud, is a hole
HOLE_ODDS = 1e-3

# -- the driver ----------------------------------------------------------------------------------
def _merge_duplicates(P: np.ndarray, merge_tol: float, nearest: tuple[np.ndarray, np.ndarray]
                      ) -> tuple[np.ndarray, np.ndarray, float]:
    """Representative of each point (points within merge_tol·median spacing share one), from
    ``nearest``, the (dist, idx) of every point's nearest points (itself first)."""
    n = len(P)
    kk = min(8, n)
    dist, idx = nearest[0][:, :kk], nearest[1][:, :kk]
    spacing = float(np.median(dist[:, 1])) if kk > 1 else 0.0
    if spacing == 0.0:  # more than half the points coincide with another: use the mean
        spacing = float(dist[:, 1].mean()) if kk > 1 else 0.0
    close = (dist <= merge_tol * spacing) & (idx != np.arange(n)[:, None]) & (idx < n)
    if not close.any():
        return np.arange(n), np.ones(n, dtype=np.int64), spacing
    rows = np.repeat(np.arange(n), kk)[close.ravel()]
    G = sp.coo_matrix((np.ones(len(rows)), (rows, idx[close])), shape=(n, n))
    _, label = connected_components(G, directed=False)
    # representative: the first point of each group
    first = np.full(label.max() + 1, n, dtype=np.int64)
    np.minimum.at(first, label, np.arange(n))
    rep = first[label]
    return rep, np.bincount(rep, minlength=n)[rep], spacing


def _neighbours(tree: KDTree, Q: np.ndarray, K: int) -> tuple[np.ndarray, np.ndarray]:
    dist, idx = tree.query(Q, k=K + 1)
    shape = (len(Q), K + 1)  # one column comes back flat
    return np.asarray(dist, np.float64).reshape(shape), np.asarray(idx, np.int64).reshape(shape)


def point_masses(P: Any, k: int = 2, *, neighbors: int | None = None, merge_tol: float = 1e-6,
                 outlier_ratio: float = 10.0) -> tuple[np.ndarray, dict[str, Any]]:
    """Mass of every point of a cloud sampling a k-manifold: its local Delaunay star / (k + 1).

    Parameters
    ----------
    P : (n, d) array_like
        Points, d ≥ k.
    k : int, default 2
        Intrinsic dimension of the sampled manifold.
    neighbors : int, optional
        First neighbourhood size K (8, 16, 32 for k = 1, 2, 3), also the one that gives the
        tangent space; it grows (up to 256) where the local Delaunay star
        needs more neighbours, and for k = 2 the tangent space with it where the first
        neighbourhood lies along a line (a scan line's: :data:`meshlap.tuned.STAR_THIN`) or
        ends among equidistant points (a pole's ring) too early to stop before them.
    merge_tol : float, default 1e-6
        Points closer than ``merge_tol`` times the median nearest-neighbour distance are one.
    outlier_ratio : float, default 10
        A point whose nearest neighbour is this many times farther than its neighbours'
        typical distance to their 8 nearest neighbours (the median of the means) is an
        outlier and gets mass 0; above 1, ``math.inf`` for none.

    Returns
    -------
    mass : (n,) ndarray
        The masses; they sum to about the measure (length, area, volume) of the manifold.
    info : dict
        ``spacing`` (equivalent lattice spacing), ``duplicates``, ``outliers``,
        ``degenerate``, ``insecure`` (point counts), ``boundary`` ((n,) bool: cells that
        stay open, e.g. on the rim of an open surface, and for k = 2 where the stars end, an
        opening's rim too), ``boundary_share`` (k = 2: each point's share of the boundary's
        length, half its star's edges there; else None), ``triangles`` (k = 2: the local
        Delaunay triangles, each once from its corner of smallest index; a triangle soup,
        not a manifold mesh, used to precondition eigensolvers), ``stars`` (k = 2: every
        point's own star, its centre first: most triangles three times, once from each corner;
        without the triangles that span a hole (:func:`_holes`);
        k = 1: every point's segments to its nearest neighbours on either side along its
        tangent, most segments twice), ``pieces`` (k ≤ 2: the number of connected pieces of the
        stars, each a zero eigenvalue of the FEM pencil, and each point's piece, -1 in no star:
        :func:`~meshlap.geometry.stars.star_pieces`; else None), ``outlier`` ((n,) bool:
        the outliers, mass 0 and in no star).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> P = meshlap.shapes.fibonacci_sphere(2000)
    >>> m, info = point_masses(P)
    >>> bool(abs(m.sum() - 4 * np.pi) < 0.01 * 4 * np.pi)
    True
    """
    P = check_points(P)
    n, d = P.shape
    k = check_int(k, "k (the intrinsic dimension)", 1)
    if neighbors is not None:
        check_int(neighbors, "neighbors")
    if not 0 <= _real_scalar(merge_tol, "merge_tol", "a finite number >= 0") < math.inf:
        raise MeshError(f"merge_tol must be a finite number >= 0; got {merge_tol!r}")
    if not _real_scalar(outlier_ratio, "outlier_ratio", "a number > 1") > 1:  # inf: no outliers
        raise MeshError(f"outlier_ratio must be a number > 1 (math.inf: no outliers); got {outlier_ratio!r}")
    if d < k:
        raise MeshError(f"points in R^{d} cannot sample a {k}-dimensional manifold (k={k} > d={d})")
    # one k-d query of every point's first neighbourhood serves the duplicates, and where there
    # are none the first round and the outlier test too: on a large cloud each query takes seconds
    tree = KDTree(P)
    wanted = neighbors or STAR_NEIGHBORS.get(k, 20 * k)
    first = _neighbours(tree, P, min(max(wanted + 1, 8), n - 1))
    rep, shared, spacing0 = _merge_duplicates(P, merge_tol, first)
    uniq = np.flatnonzero(rep == np.arange(n))
    n_dup = n - len(uniq)
    if len(uniq) < k + 2:
        raise MeshError(f"a point cloud of intrinsic dimension {k} needs at least {k + 2} distinct "
                        f"points; got {len(uniq)}")
    Q = np.ascontiguousarray(P[uniq])
    # the stars see the points moved by a billionth of the spacing, the same for every star: a
    # lattice's cocircular quadruples then split alike in all of them (each point's own tie-break
    # left a regular grid's triangles in one or two of their corners' stars: 21% of its area lost)
    X = Q + 1e-9 * spacing0 * np.random.default_rng(0).uniform(-1.0, 1.0, Q.shape)
    nu = len(Q)
    if nu < n:  # the first neighbourhoods again, among the distinct points
        tree = KDTree(Q)
        first = _neighbours(tree, Q, min(max(wanted + 1, 8), nu - 1))
    K = min(wanted, nu - 1)
    # the tangent space comes from the first neighbourhood, however far the star search grows,
    # unless that lies along a line (STAR_THIN; a scan line's): then from the first wider one
    # that does not, and that round is the point's first (base)
    kt = K
    kts = np.full(nu, K, dtype=np.int64)
    base = np.full(nu, -1, dtype=np.int64)
    axes = np.zeros((nu, 2, d))  # each point's plane, from its base round
    line = np.zeros((nu, d))  # the first axis of each point's first neighbourhood
    lined = np.zeros(nu, dtype=bool)
    if K < k + 1:
        raise MeshError(f"neighbors must be at least k + 1 = {k + 1}; got {K}")
    mass = np.zeros(nu)
    status = np.full(nu, _INSECURE, dtype=np.int64)
    open_cell = np.zeros(nu, dtype=bool)
    first_open = np.zeros(nu, dtype=bool)  # points on the hull of their first neighbours
    nn1 = np.zeros(nu)
    star_parts: list[tuple[int, np.ndarray]] = []
    last = np.zeros(nu, dtype=np.int64)
    ends1 = np.full((nu, 2), -1, dtype=np.int64)  # k = 1: each point's neighbours on either side
    todo = np.arange(nu)
    for it in range(64):
        if not len(todo):
            break
        if it == 0:  # one more than K: is the K-th tied?
            dist, idx = (a[:, :min(K + 1, nu - 1) + 1] for a in first)
            nn1[:] = dist[:, 1]
            reach8 = dist[:, 1:9].mean(axis=1)
        else:
            dist, idx = _neighbours(tree, Q[todo], min(K + 1, nu - 1))
        # drop each point itself from its list (it is the first hit: duplicates are merged)
        not_self = idx != todo[:, None]
        order = np.argsort(~not_self, axis=1, kind="stable")
        nbr = np.ascontiguousarray(np.take_along_axis(idx, order, axis=1)[:, :K])
        if it == 0:
            first_nbr = nbr
        counts = np.full(len(todo), K, dtype=np.int64)
        if k == 1:
            m, st, ends = np.zeros(len(todo)), np.zeros(len(todo), np.int64), np.zeros(len(todo), bool)
            side = np.full((len(todo), 2), -1, dtype=np.int64)
            in_blocks(_masses1, len(todo), X, nbr, counts, kt, todo, m, st, ends, side)
            open_cell[todo] = ends
            if it == 0:
                first_open[:] = open_cell
            ends1[todo] = np.where(side >= 0, np.take_along_axis(nbr, np.maximum(side, 0), axis=1), -1)
        elif k == 2:
            m, vor, st, width = (np.zeros(len(todo)), np.zeros(len(todo)),
                                 np.zeros(len(todo), np.int64), np.zeros(len(todo)))
            T = np.zeros((len(todo), 2, d))
            tri = np.full((len(todo), _STAR_SLOTS, 2), -1, dtype=np.int64)
            ntri = np.zeros(len(todo), dtype=np.int64)
            trim, tied = _tie_cut(dist, kts[todo], base[todo] < 0)
            kts[todo] = trim
            in_blocks(_masses2, len(todo), X, nbr, counts, kts[todo], todo, m, vor, st, width, T, tri, ntri)
            # stars of more triangles than tri holds (a pole's fan, a cone's apex): again, with room
            fan = np.flatnonzero(ntri > _STAR_SLOTS)
            if len(fan):
                wide = np.full((len(fan), int(ntri[fan].max()), 2), -1, dtype=np.int64)
                in_blocks(_masses2, len(fan), X, nbr[fan], counts[fan], kts[todo[fan]], todo[fan], m[fan],
                          vor[fan], st[fan], width[fan], T[fan], wide, ntri[fan])
                tri[fan] = -1
            thin = (width < STAR_THIN) | tied
            fresh = ~thin & (base[todo] < 0)
            base[todo[fresh]] = it
            axes[todo[fresh]] = T[fresh]
            open_cell[todo] = ~np.isfinite(vor)
            if it == 0:
                first_open[:] = open_cell
                line[:] = T[:, 0]
                lined[:] = width < STAR_THIN  # its plane from a wider neighbourhood, or none
            first_open[todo[fresh]] = open_cell[todo[fresh]]
            if K < min(_MAX_NEIGHBORS, nu - 1):
                st[thin] = _INSECURE
                kts[todo[thin]] = min(2 * K, _MAX_NEIGHBORS, nu - 1)
            # every point's local Delaunay star, its centre first
            last[todo] = it
            star = _star_rows(todo, nbr, tri)
            if len(fan):
                star = np.vstack([star, _star_rows(todo[fan], nbr[fan], wide)])
            star_parts.append((it, star))
        elif k == 3 and it == 0:
            m, st, hull = np.zeros(len(todo)), np.zeros(len(todo), np.int64), np.zeros(len(todo), bool)
            in_blocks(_masses3, len(todo), X, nbr, counts, kt, todo, m, st, hull)
            # cospherical neighbours: Qhull (with its joggle) decides the star
            tie = np.flatnonzero(st == _DEGENERATE)
            if len(tie):
                mt, st_t, hull_t = np.zeros(len(tie)), np.zeros(len(tie), np.int64), np.zeros(len(tie), bool)
                in_blocks(_masses_k, len(tie), X, nbr[tie], counts[tie], kt, todo[tie], k, mt, st_t, hull_t)
                m[tie], st[tie], hull[tie] = mt, st_t, hull_t
            open_cell[todo] = hull
        else:
            m, st, hull = np.zeros(len(todo)), np.zeros(len(todo), np.int64), np.zeros(len(todo), bool)
            in_blocks(_masses_k, len(todo), X, nbr, counts, kt, todo, k, m, st, hull)
            open_cell[todo] = hull
        mass[todo], status[todo] = m, st
        if K >= min(_MAX_NEIGHBORS, nu - 1):
            break
        todo = todo[st == _INSECURE]
        K = min(2 * K, _MAX_NEIGHBORS, nu - 1)
        if k == 3 and d == 3 and it == 0 and len(todo):
            # a star secure at any K up to the last is the whole cloud's Delaunay star; the others
            # stay insecure up to the last K, so only that one is searched
            K = min(_MAX_NEIGHBORS, nu - 1)
            far = _neighbours(tree, Q[todo], K)[0][:, -1]
            m, secure = _global_stars3(X, todo, far)
            mass[todo[secure]], status[todo[secure]], open_cell[todo[secure]] = m[secure], _OK, False
            todo = todo[~secure]
    # outliers: isolated far beyond the spacing usual around them
    idx = first[1][:, :min(8, nu - 1) + 1]
    local = np.median(reach8[idx[:, 1:]], axis=1)
    outlier = nn1 > outlier_ratio * np.maximum(local, 1e-300)
    base = np.maximum(base, 0)  # a line's at every K: its first
    stars = _soup(star_parts, np.where(status == _INSECURE, base, last), first_open, base)
    stars = _consistent(stars[~outlier[stars].any(axis=1)], X)
    if k == 2 and d == 3 and lined.any():
        off = _off_surface(stars, lined, axes, line)
        status[off] = _DEGENERATE
        stars = stars[~off[stars].any(axis=1)]
    if k == 2 and d >= 3:  # two sheets closer than the sampling
        stars = stars[~bridges(stars, X)]
    degenerate = (status == _DEGENERATE) & ~outlier
    if degenerate.all():
        raise MeshError(f"no point has a {k}-dimensional neighbourhood (all are "
                        f"{'collinear' if k == 2 else 'degenerate'}); is k={k} the right dimension?")
    if degenerate.any():
        good = np.where(degenerate | outlier, np.nan, mass)
        with warnings.catch_warnings():  # rows without a good neighbour: the global median
            warnings.simplefilter("ignore", RuntimeWarning)
            fill = np.nanmedian(good[idx[degenerate, 1:]], axis=1)
        mass[degenerate] = np.where(np.isfinite(fill), fill, np.nanmedian(good))
    mass[outlier] = 0.0
    # next to an open cell, a star that stays insecure is the local one by design: the global
    # Delaunay triangulation would add long slivers across the boundary
    near_open = open_cell.copy()
    for _ in range(4):  # four rings of neighbours
        near_open |= near_open[first_nbr].any(axis=1)
    insecure = int(((status == _INSECURE) & ~outlier & ~near_open).sum())
    problems = []
    if n_dup:
        problems.append(f"{n_dup} duplicate or near-coincident point(s) (within {merge_tol:g} of the "
                        "median spacing) share the mass of the point they coincide with")
    if outlier.any():
        problems.append(f"{int(outlier.sum())} outlier(s) (nearest neighbour more than {outlier_ratio:g}x "
                        "farther than usual around them) get mass 0")
    if degenerate.any():
        problems.append(f"{int(degenerate.sum())} point(s) have no {k}-dimensional neighbourhood "
                        "(collinear or flat neighbours) and take their neighbours' median mass")
    if insecure:
        problems.append(f"{insecure} point(s) kept an unresolved local Delaunay star after "
                        f"{_MAX_NEIGHBORS} neighbours")
    if problems:
        warnings.warn("messy point cloud: " + "; ".join(problems), MeshWarning, stacklevel=2)
    share = np.zeros(nu)
    if k == 2 and len(stars):
        hole = _holes(stars, Q, reach8, first_open, k)
        lost = np.bincount(stars[:, 0], ~hole, minlength=nu) == 0
        hole &= ~lost[stars[:, 0]]  # a point whose every triangle spans a hole keeps them: its row
        ends = open_cell.copy()
        ends[stars[hole].ravel()] = True
        stars = stars[~hole]
        share = _open_edges(stars, Q, ends)
        open_cell = share > 0  # where the soup ends: an open first cell whose star closed is inside
    stars = uniq[stars]
    if k == 1:  # every point's segments to its neighbours on either side: its 1-D star
        centre, other = np.repeat(np.arange(nu), 2), ends1.ravel()
        seg = np.column_stack([centre, other])[(other >= 0) & (mass[centre] > 0) & ~outlier[other]]
        hole = _holes(seg, Q, reach8, first_open, k)  # such as an open curve's opening
        gap = np.linalg.norm(Q[seg[:, 0]] - Q[seg[:, 1]], axis=1)
        stars = uniq[seg[~hole]]
        ends = seg[hole, 0]  # an end of the curve: half its one segment, as a polyline's
        mass[ends] = 0.5 * np.bincount(seg[~hole, 0], gap[~hole], minlength=nu)[ends]
        open_cell[ends] = True
    triangles = stars[(stars[:, 0] < stars[:, 1]) & (stars[:, 0] < stars[:, 2])] if k == 2 else \
        np.zeros((0, 3), np.int64)  # each once
    at = np.searchsorted(uniq, rep)
    pieces = star_pieces(stars, rep) if k <= 2 else None
    full = mass[at] / shared
    boundary = open_cell[at]
    positive = full[full > 0]
    mean_mass = float(positive.mean()) if len(positive) else 0.0
    info = {
        "spacing": _lattice_spacing(mean_mass, k) if mean_mass > 0 else spacing0,
        "duplicates": n_dup,
        "outliers": int(outlier.sum()),
        "degenerate": int(degenerate.sum()),
        "insecure": insecure,
        "boundary": boundary,
        "triangles": triangles,
        "stars": stars,
        "boundary_share": (share[at] / shared) if k == 2 else None,
        "pieces": pieces,
        "outlier": outlier[at],
    }
    return full, info


def _open_edges(stars: np.ndarray, Q: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Each point's share of the star soup's boundary: half the length of the edges that one
    triangle of its own star has and no other, where the star at the edge's other end has it
    once too, between points ``at`` the sampling ends (an open cell, a hole's corner). Elsewhere
    such an edge is two neighbouring stars' disagreement (a random sphere of 1,000,000 points
    has six), not an end of the surface."""
    n = len(Q)
    rows = stars[at[stars[:, 0]]]
    centre, other = np.repeat(rows[:, 0], 2), rows[:, 1:].ravel()
    key, once = np.unique(centre * n + other, return_counts=True)
    edge = key[once == 1]
    a, b = edge // n, edge % n
    both = at[b] & in_set(b * n + a, edge, of_sorted=True)
    a, b = a[both], b[both]
    return 0.5 * np.bincount(a, np.linalg.norm(Q[a] - Q[b], axis=1), minlength=n)


def _holes(cells: np.ndarray, Q: np.ndarray, reach8: np.ndarray, one_sided: np.ndarray,
           k: int) -> np.ndarray:
    """Which star simplices ``cells`` span a hole: an empty circumball that i.i.d. sampling at its
    sparsest corner's density leaves anywhere in the cloud with probability below HOLE_ODDS.

    Sampling at density ρ in k dimensions (a Poisson process), the j-th nearest point lies
    Γ(j + 1/k) / Γ(j) · (ω_k ρ)^(-1/k) away on average, 2^(1/k) times that where all lie on one
    side (``one_sided``: a point on the hull of its first neighbours); the mean over the 8 nearest
    (``reach8``) gives each point's ρ. A ball of radius R is then empty with probability
    exp(-ρ ω_k R^k), so an empty one among the n points' is a hole when ρ ω_k R^k > log(n / odds):
    an open surface's opening, a curve's gap, the empty side of a concave rim that slivers of
    nearly collinear rim points would span.
    """
    n = len(Q)
    j = np.arange(1, 9)
    c = np.exp(gammaln(j + 1.0 / k) - gammaln(j)).mean() * np.where(one_sided, 2.0 ** (1.0 / k), 1.0)
    density = c / np.maximum(reach8, 1e-300)  # (ω_k ρ)^(1/k)
    expected = (_circumradii(Q[cells]) * density[cells].min(axis=1)) ** k  # a flat simplex: inf
    return ~(expected <= math.log(n / HOLE_ODDS))


def _star_rows(centre: np.ndarray, nbr: np.ndarray, tri: np.ndarray) -> np.ndarray:
    # (centre, a, b) for every neighbour pair of tri (-1: no more)
    r, slot = np.nonzero(tri[:, :, 0] >= 0)
    return np.column_stack([centre[r], nbr[r, tri[r, slot, 0]], nbr[r, tri[r, slot, 1]]])


def _lattice_spacing(mass: float, k: int) -> float:
    # neighbour distance of the densest lattice whose cells have this measure: points a apart
    # on a line; a triangular lattice ((√3/2) a² per point); the FCC lattice (a³/√2)
    if k == 1:
        return mass
    if k == 2:
        return math.sqrt(2.0 * mass / math.sqrt(3.0))
    if k == 3:
        return (math.sqrt(2.0) * mass) ** (1.0 / 3.0)
    return mass ** (1.0 / k)


def point_cloud_geometry(P: Any, k: int = 2, *, denoise: bool | None = None, **kwargs: Any) -> Geometry:
    """The :class:`~meshlap.geometry.Geometry` of a point cloud: points, masses from
    :func:`point_masses`, intrinsic dimension k, open cells as boundary.

    ``denoise=True`` first moves the points onto their local tangent planes
    (:func:`~meshlap.geometry.noise.project_to_tangent`); the kernel then sees distances without
    most of the normal noise, which otherwise scales its weights by about (1 + σ²/h)^{-1/2}, and
    the Richardson kernel's narrow half by (1 + 2σ²/h)^{-1/2}: a bias of about 1.5σ²/h that
    outgrows the O(h) bias it removes. ``denoise=None`` (the default) projects when
    :func:`~meshlap.geometry.noise.noise_reading` finds noise (above about 14% of the spacing,
    :data:`meshlap.tuned.CLOUD_NOISY`, and not explained by cubic fits) and
    notes it in ``notes``; on 16,000 sphere points with 1% radial noise the default's first 9
    eigenvalues are 0.29% off, the kernel's on the points as given 5.6% (the paper's operator:
    2.0%).

    Examples
    --------
    >>> import meshlap
    >>> g = point_cloud_geometry(meshlap.shapes.fibonacci_sphere(1000))
    >>> g.dim, g.source, round(g.spacing, 3), g.notes
    (2, 'point cloud', 0.12, '')
    """
    P = check_points(P)
    notes = ""
    pca = None
    reading = None
    valid_k = isinstance(k, (int, np.integer)) and not isinstance(k, bool) and 1 <= k < P.shape[1]
    if denoise is None and valid_k and len(P) > 8:  # bad k: point_masses names the problem
        pca = frames.pca_frames(P, k)
        reading = noise_reading(P, k, pca)
        denoise = reading.noisy
        if denoise:
            notes = f"denoised: normal noise {reading.ratio:.3g} of the squared spacing"
    raw = P
    if denoise:
        P = project_to_tangent(P, k, kwargs.get("neighbors"))
        pca = None  # the points moved: their frames are computed anew when asked for
    mass, info = point_masses(P, k, **kwargs)
    cells = info["triangles"] if k == 2 else np.unique(np.sort(info["stars"], axis=1), axis=0) if k == 1 \
        else None
    geo = Geometry(P, mass, int(k), info["spacing"], boundary=info["boundary"], cells=cells,
                   boundary_share=info["boundary_share"], source="point cloud", notes=notes)
    if k <= 2:  # the FEM pencil's cells and their weight: each simplex is in its k + 1 corners' stars
        geo._cache["fem_cells"] = (info["stars"], 1 / (k + 1))
        geo._cache["star_pieces"] = info["pieces"]
    if info["outliers"]:  # not on the surface: no distance reaches them (meshlap.geodesics)
        geo._cache["outliers"] = info["outlier"]
    if pca is not None:  # the frames of these very points: the operator's stages reuse them
        geo._cache["pca"] = pca
    if raw is not P:  # where the user's f was sampled: the point-wise rows fit it there
        geo._cache["input_points"] = raw
    if reading is not None:  # of the points as given: op.decision records it
        geo._cache["noise_reading"] = reading
    return geo
