"""The heat-kernel Laplacian of a point cloud: masses from the points alone.

Belkin, Sun and Wang, "Constructing Laplace operator from point clouds in R^d" (SODA 2009),
weight each point by the measure of its cell in a local Delaunay/Voronoi structure built in
the estimated tangent space, and normalize the Gaussian by 1/(h (4πh)^{k/2}) for intrinsic
dimension k. One mass per point (as Liu, Prabhakaran and Guo, 2012, do with Voronoi areas)
keeps S = M L symmetric and -S positive semidefinite, exactly as for a mesh.

For each point p, with its K nearest neighbours:

1. the tangent space is the span of the k leading principal axes of the neighbourhood;
2. the neighbours are projected onto it, relative to p;
3. the local Delaunay star of p in that k-plane gives the mass: the measure of the
   simplices around p divided by k + 1 — the lumped mass of a mesh, without a mesh.

For k = 2 the star comes from clipping p's Voronoi cell by the bisectors of its projected
neighbours (convex polygon clipping, O(K²) per point, compiled): two consecutive edges of the
cell, cut by neighbours a and b, meet at the circumcentre of the Delaunay triangle (p, a, b).
For k = 1 the star is the two nearest neighbours along the tangent line, so the mass is half
the gap between them. For k ≥ 3 scipy's Delaunay triangulates each projected neighbourhood.
A star is only trusted when no point outside the K neighbours can reach it: every Delaunay
circumcircle must lie within half the distance of the farthest neighbour; otherwise K grows.

On 16,000 i.i.d. random points of the unit sphere these masses are within a few percent of
the barycentric masses of the points' true triangulation (their convex hull), which is what
the Laplacian's accuracy depends on (see the README's point-cloud section for numbers).

Messy input has defined behaviour, each with a :class:`~meshlap.validation.MeshWarning`:

* duplicate and near-coincident points (closer than ``merge_tol`` times the median
  neighbour distance) are merged for the mass estimate and share the merged point's mass;
* outliers (a nearest neighbour more than ``outlier_ratio`` times farther than is usual
  around it) get mass 0: they are rows of L but never sources of its sums;
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
from numba import prange
from pykdtree.kdtree import KDTree
from scipy.sparse.csgraph import connected_components
from scipy.spatial import Delaunay, QhullError

from ._jit import jit
from .geometry import Geometry, check_points
from .operator import DEFAULT_TOL, MeshLaplacian
from .validation import MeshError, MeshWarning

__all__ = ["point_cloud_geometry", "point_cloud_laplacian", "point_cloud_matrices", "point_masses",
           "project_to_tangent"]

# First neighbourhood size per intrinsic dimension; it doubles for the points whose star it
# does not secure, up to _MAX_NEIGHBORS.
_NEIGHBORS = {1: 8, 2: 16, 3: 32}
_MAX_NEIGHBORS = 256
# A neighbourhood whose k-th principal variance is below this fraction of the first has no
# k-dimensional extent.
_FLAT = 1e-10
# Triangles kept per star (a star in a Delaunay triangulation has 6 on average).
_STAR_SLOTS = 24
# status codes of one point's star
_OK, _INSECURE, _DEGENERATE = 0, 1, 2


# -- tangent spaces --------------------------------------------------------------------------
@jit()
def _tangent(P, p, nbr, kdim, T):
    # T[:kdim] <- the k leading principal axes of {p} ∪ neighbours; returns λ_k / λ_1
    d = P.shape[1]
    K = len(nbr)
    mean = P[p].copy()
    for j in range(K):
        mean += P[nbr[j]]
    mean /= K + 1
    C = np.zeros((d, d))
    for j in range(-1, K):
        q = p if j < 0 else nbr[j]
        for a in range(d):
            xa = P[q, a] - mean[a]
            for b in range(d):
                C[a, b] += xa * (P[q, b] - mean[b])
    w, v = np.linalg.eigh(C)
    for a in range(kdim):
        for b in range(d):
            T[a, b] = v[b, d - 1 - a]
    return w[d - kdim] / max(w[d - 1], 1e-300)


@jit()
def _project(P, p, nbr, T, U):
    kdim = T.shape[0]
    for j in range(len(nbr)):
        for a in range(kdim):
            s = 0.0
            for b in range(P.shape[1]):
                s += (P[nbr[j], b] - P[p, b]) * T[a, b]
            U[j, a] = s


# -- k = 2: the Voronoi cell by half-plane clipping ---------------------------------------------
@jit()
def _clip(px, py, gen, nv, ax, ay, b, label, qx, qy, qgen):
    # Clip the convex polygon (px, py)[:nv] by a·x <= b; gen[i] labels the edge from vertex i
    # to vertex i+1. Writes the result to (qx, qy, qgen) and returns its size.
    m = 0
    for i in range(nv):
        i1 = i + 1 if i + 1 < nv else 0
        si = ax * px[i] + ay * py[i] - b
        s1 = ax * px[i1] + ay * py[i1] - b
        if si <= 0.0:
            qx[m] = px[i]
            qy[m] = py[i]
            qgen[m] = gen[i]
            m += 1
            if s1 > 0.0:  # leaving: the cut point starts an edge on the clipping line
                t = si / (si - s1)
                qx[m] = px[i] + t * (px[i1] - px[i])
                qy[m] = py[i] + t * (py[i1] - py[i])
                qgen[m] = label
                m += 1
        elif s1 <= 0.0:  # entering: the cut point starts the rest of edge i
            t = si / (si - s1)
            qx[m] = px[i] + t * (px[i1] - px[i])
            qy[m] = py[i] + t * (py[i1] - py[i])
            qgen[m] = gen[i]
            m += 1
    return m


@jit()
def _star2(U, K, tri):
    # (Delaunay star area / 3, Voronoi area, status) of the origin among the points U[:K];
    # tri[i] <- the neighbour pairs (a, b) of the star's triangles, -1 after the last
    far = 0.0
    for j in range(K):
        far = max(far, math.hypot(U[j, 0], U[j, 1]))
    # far enough that the circumcentres of the thin triangles along an open boundary are kept
    box = 1e3 * far + 1e-300
    cap = K + 5
    px = np.empty(cap)
    py = np.empty(cap)
    gen = np.empty(cap, dtype=np.int64)
    qx = np.empty(cap)
    qy = np.empty(cap)
    qgen = np.empty(cap, dtype=np.int64)
    px[0], py[0], px[1], py[1] = -box, -box, box, -box
    px[2], py[2], px[3], py[3] = box, box, -box, box
    gen[:4] = -1
    nv = 4
    for j in range(K):
        ax, ay = U[j, 0], U[j, 1]
        b = 0.5 * (ax * ax + ay * ay)
        if b <= 0.0:
            continue
        nv = _clip(px, py, gen, nv, ax, ay, b, j, qx, qy, qgen)
        px, qx = qx, px
        py, qy = qy, py
        gen, qgen = qgen, gen
    voronoi = 0.0
    star = 0.0
    reach = 0.0
    bounded = True
    nt = 0
    tri[:] = -1
    for i in range(nv):
        i1 = i + 1 if i + 1 < nv else 0
        voronoi += px[i] * py[i1] - px[i1] * py[i]
        g0 = gen[i - 1] if i > 0 else gen[nv - 1]
        g1 = gen[i]
        if g1 < 0:
            bounded = False
        if g0 >= 0 and g1 >= 0 and g0 != g1:
            # vertex i is the circumcentre of the Delaunay triangle (origin, U[g0], U[g1])
            star += abs(U[g0, 0] * U[g1, 1] - U[g0, 1] * U[g1, 0])
            reach = max(reach, math.hypot(px[i], py[i]))
            if nt < tri.shape[0]:
                tri[nt, 0] = g0
                tri[nt, 1] = g1
                nt += 1
    status = _OK if (bounded and 2.0 * reach < far) else _INSECURE
    if not bounded:
        voronoi = math.inf
    return star / 6.0, 0.5 * abs(voronoi), status


@jit(parallel=True)
def _masses2(P, nbr, counts, kt, rows, out_star, out_vor, status, flat, tri):
    d = P.shape[1]
    for r in prange(len(rows)):
        p = rows[r]
        K = counts[r]
        T = np.empty((2, d))
        U = np.empty((K, 2))
        flat[r] = _tangent(P, p, nbr[r, :kt], 2, T)
        if flat[r] < _FLAT:
            status[r] = _DEGENERATE
            continue
        _project(P, p, nbr[r, :K], T, U)
        out_star[r], out_vor[r], status[r] = _star2(U, K, tri[r])


# -- k = 1: half the gap to the nearest neighbours on each side ---------------------------------
@jit(parallel=True)
def _masses1(P, nbr, counts, kt, rows, out, status, ends):
    d = P.shape[1]
    for r in prange(len(rows)):
        p = rows[r]
        K = counts[r]
        T = np.empty((1, d))
        U = np.empty((K, 1))
        if _tangent(P, p, nbr[r, :kt], 1, T) <= 0.0:
            status[r] = _DEGENERATE
            continue
        _project(P, p, nbr[r, :K], T, U)
        left = -math.inf
        right = math.inf
        far = 0.0
        for j in range(K):
            s = U[j, 0]
            far = max(far, abs(s))
            if s < 0.0:
                left = max(left, s)
            elif s > 0.0:
                right = min(right, s)
        one_side = not (math.isfinite(left) and math.isfinite(right))
        ends[r] = one_side
        gap = (0.0 if not math.isfinite(right) else right) - (0.0 if not math.isfinite(left) else left)
        out[r] = 0.5 * gap
        status[r] = _INSECURE if one_side else _OK


# -- k = 3: the Delaunay tetrahedra around the origin from the Voronoi cell's vertices ---------------
@jit()
def _star3(U, K):
    # Each vertex of the origin's Voronoi cell is where three bisector planes u·x = |u|²/2
    # meet without violating any other; it is the circumcentre of the Delaunay tetrahedron
    # (origin, u_a, u_b, u_c). Returns (Σ volumes / 4, status, open): the solid angles of the
    # tetrahedra at the origin add up to 4π when its star is closed; more than that means
    # cospherical neighbours (a vertex on four planes), which the caller resolves by Qhull.
    far = 0.0
    for j in range(K):
        far = max(far, math.sqrt(U[j, 0] ** 2 + U[j, 1] ** 2 + U[j, 2] ** 2))
    vol = 0.0
    omega = 0.0
    reach = 0.0
    for a in range(K):
        ax, ay, az = U[a, 0], U[a, 1], U[a, 2]
        ba = 0.5 * (ax * ax + ay * ay + az * az)
        for b in range(a + 1, K):
            bx, by, bz = U[b, 0], U[b, 1], U[b, 2]
            bb = 0.5 * (bx * bx + by * by + bz * bz)
            for c in range(b + 1, K):
                cx, cy, cz = U[c, 0], U[c, 1], U[c, 2]
                bc = 0.5 * (cx * cx + cy * cy + cz * cz)
                # the cross products give the solution by Cramer's rule
                x1, y1, z1 = by * cz - bz * cy, bz * cx - bx * cz, bx * cy - by * cx
                x2, y2, z2 = cy * az - cz * ay, cz * ax - cx * az, cx * ay - cy * ax
                x3, y3, z3 = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
                det = ax * x1 + ay * y1 + az * z1
                if abs(det) <= 1e-12 * (ba * bb * bc) ** 0.5 * 8.0:
                    continue
                vx = (ba * x1 + bb * x2 + bc * x3) / det
                vy = (ba * y1 + bb * y2 + bc * y3) / det
                vz = (ba * z1 + bb * z2 + bc * z3) / det
                ok = True
                for j in range(K):
                    if j == a or j == b or j == c:
                        continue
                    uj2 = U[j, 0] ** 2 + U[j, 1] ** 2 + U[j, 2] ** 2
                    if U[j, 0] * vx + U[j, 1] * vy + U[j, 2] * vz > 0.5 * uj2 * (1.0 + 1e-10):
                        ok = False
                        break
                if not ok:
                    continue
                vol += abs(det) / 6.0
                reach = max(reach, math.sqrt(vx * vx + vy * vy + vz * vz))
                # solid angle at the origin (Van Oosterom and Strackee)
                la = math.sqrt(2.0 * ba)
                lb = math.sqrt(2.0 * bb)
                lc = math.sqrt(2.0 * bc)
                dab = ax * bx + ay * by + az * bz
                dac = ax * cx + ay * cy + az * cz
                dbc = bx * cx + by * cy + bz * cz
                omega += 2.0 * math.atan2(abs(det), la * lb * lc + dab * lc + dac * lb + dbc * la)
    full = 4.0 * math.pi
    if omega > full * (1.0 + 1e-6):
        return vol / 4.0, _DEGENERATE, False
    closed = omega > full * (1.0 - 1e-6)
    status = _OK if (closed and 2.0 * reach < far) else _INSECURE
    return vol / 4.0, status, not closed


@jit(parallel=True)
def _masses3(P, nbr, counts, kt, rows, out, status, hull):
    d = P.shape[1]
    for r in prange(len(rows)):
        p = rows[r]
        K = counts[r]
        T = np.empty((3, d))
        U = np.empty((K, 3))
        if _tangent(P, p, nbr[r, :kt], 3, T) < _FLAT:
            status[r] = _DEGENERATE
            continue
        _project(P, p, nbr[r, :K], T, U)
        out[r], status[r], hull[r] = _star3(U, K)


# -- k >= 4 (and cospherical k = 3 neighbourhoods): Qhull's Delaunay of each neighbourhood -------
def _star_k(U: np.ndarray, k: int) -> tuple[float, int, bool]:
    X = np.vstack([np.zeros((1, k)), U])
    try:
        tri = Delaunay(X)
    except QhullError:
        return 0.0, _DEGENERATE, False
    around = tri.simplices[(tri.simplices == 0).any(axis=1)]
    if not len(around):
        return 0.0, _DEGENERATE, False
    E = X[around[:, 1:]] - X[around[:, :1]]
    vol = np.abs(np.linalg.det(E)) / math.factorial(k)
    # circumcentres c of the simplices around the origin: 2 c·(x_i) = |x_i|², relative to x_0 = 0
    hull = bool(np.isin(0, tri.convex_hull))
    reach = 0.0
    for s in around:
        A = X[s]
        B = 2.0 * (A[1:] - A[0])
        rhs = (A[1:] ** 2).sum(axis=1) - (A[0] ** 2).sum()
        try:
            c = np.linalg.solve(B, rhs)
        except np.linalg.LinAlgError:
            continue
        reach = max(reach, float(np.linalg.norm(c)))
    far = float(np.linalg.norm(U, axis=1).max())
    status = _OK if (not hull and 2.0 * reach < far) else _INSECURE
    return float(vol.sum()) / (k + 1), status, hull


def _masses_k(P: np.ndarray, nbr: np.ndarray, counts: np.ndarray, kt: int, rows: np.ndarray, k: int):
    n = len(rows)
    out = np.zeros(n)
    status = np.zeros(n, dtype=np.int64)
    hull = np.zeros(n, dtype=bool)
    T = np.empty((k, P.shape[1]))
    for r, p in enumerate(rows):
        K = counts[r]
        nb = nbr[r, :K]
        if _tangent(P, p, nb[:kt], k, T) < _FLAT:
            status[r] = _DEGENERATE
            continue
        U = (P[nb] - P[p]) @ T.T
        out[r], status[r], hull[r] = _star_k(U, k)
    return out, status, hull


# -- the driver ----------------------------------------------------------------------------------
def _merge_duplicates(P: np.ndarray, merge_tol: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Representative of each point (points within merge_tol·median spacing share one)."""
    n = len(P)
    kk = min(8, n)
    dist, idx = KDTree(P).query(P, k=kk)
    dist, idx = np.asarray(dist, np.float64), np.asarray(idx, np.int64)
    spacing = float(np.median(dist[:, 1])) if kk > 1 else 0.0
    if spacing == 0.0:  # more than half the points coincide with another: use the mean
        spacing = float(dist[:, 1].mean()) if kk > 1 else 0.0
    close = (dist <= merge_tol * spacing) & (idx != np.arange(n)[:, None]) & (idx < n)
    if not close.any():
        return np.arange(n), np.ones(n, dtype=np.int64), spacing
    rows = np.repeat(np.arange(n), kk)[close.ravel()]
    G = sp.coo_matrix((np.ones(len(rows)), (rows, idx.ravel()[close.ravel()])), shape=(n, n))
    _, label = connected_components(G, directed=False)
    # representative: the first point of each group
    first = np.full(label.max() + 1, n, dtype=np.int64)
    np.minimum.at(first, label, np.arange(n))
    rep = first[label]
    return rep, np.bincount(rep, minlength=n)[rep], spacing


def _neighbours(tree: KDTree, Q: np.ndarray, K: int) -> tuple[np.ndarray, np.ndarray]:
    dist, idx = tree.query(Q, k=K + 1)
    return np.asarray(dist, np.float64), np.asarray(idx, np.int64)


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
        needs more neighbours.
    merge_tol : float, default 1e-6
        Points closer than ``merge_tol`` times the median nearest-neighbour distance are one.
    outlier_ratio : float, default 10
        A point whose nearest neighbour is this many times farther than its neighbours'
        typical distance to their 8 nearest neighbours (the median of the means) is an
        outlier and gets mass 0.

    Returns
    -------
    mass : (n,) ndarray
        The masses; they sum to about the measure (length, area, volume) of the manifold.
    info : dict
        ``spacing`` (equivalent lattice spacing), ``duplicates``, ``outliers``,
        ``degenerate``, ``insecure`` (point counts), ``boundary`` ((n,) bool: cells that
        stay open, e.g. on the rim of an open surface), ``triangles`` (k = 2: the local
        Delaunay triangles, each once from its corner of smallest index; a triangle soup,
        not a manifold mesh, used to precondition eigensolvers).

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
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
        raise MeshError(f"k (the intrinsic dimension) must be a positive integer; got {k!r}")
    k = int(k)
    if d < k:
        raise MeshError(f"points in R^{d} cannot sample a {k}-dimensional manifold (k={k} > d={d})")
    rep, share, spacing0 = _merge_duplicates(P, merge_tol)
    uniq = np.flatnonzero(rep == np.arange(n))
    n_dup = n - len(uniq)
    if len(uniq) < k + 2:
        raise MeshError(f"a point cloud of intrinsic dimension {k} needs at least {k + 2} distinct "
                        f"points; got {len(uniq)}")
    Q = np.ascontiguousarray(P[uniq])
    nu = len(Q)
    tree = KDTree(Q)
    K = min(neighbors or _NEIGHBORS.get(k, 20 * k), nu - 1)
    # the tangent space comes from the first neighbourhood, however far the star search grows
    kt = K
    if K < k + 1:
        raise MeshError(f"neighbors must be at least k + 1 = {k + 1}; got {K}")
    mass = np.zeros(nu)
    status = np.full(nu, _INSECURE, dtype=np.int64)
    open_cell = np.zeros(nu, dtype=bool)
    nn1 = np.zeros(nu)
    star_parts: list[tuple[int, np.ndarray]] = []
    last = np.zeros(nu, dtype=np.int64)
    todo = np.arange(nu)
    for it in range(64):
        if not len(todo):
            break
        dist, idx = _neighbours(tree, Q[todo], K)
        if it == 0:
            nn1[:] = dist[:, 1]
            reach8 = dist[:, 1:9].mean(axis=1)
        # drop each point itself from its list (it is the first hit: duplicates are merged)
        not_self = idx != todo[:, None]
        order = np.argsort(~not_self, axis=1, kind="stable")
        nbr = np.ascontiguousarray(np.take_along_axis(idx, order, axis=1)[:, :K])
        if it == 0:
            first_nbr = nbr
        counts = np.full(len(todo), K, dtype=np.int64)
        if k == 1:
            m, st, ends = np.zeros(len(todo)), np.zeros(len(todo), np.int64), np.zeros(len(todo), bool)
            _masses1(Q, nbr, counts, kt, todo, m, st, ends)
            open_cell[todo] = ends
        elif k == 2:
            m, vor, st, flat = (np.zeros(len(todo)), np.zeros(len(todo)),
                                np.zeros(len(todo), np.int64), np.zeros(len(todo)))
            tri = np.full((len(todo), _STAR_SLOTS, 2), -1, dtype=np.int64)
            _masses2(Q, nbr, counts, kt, todo, m, vor, st, flat, tri)
            open_cell[todo] = ~np.isfinite(vor)
            # each triangle of the local stars once, from its corner of smallest index
            r, slot = np.nonzero(tri[:, :, 0] >= 0)
            a = nbr[r, tri[r, slot, 0]]
            b = nbr[r, tri[r, slot, 1]]
            own = (todo[r] < a) & (todo[r] < b)
            last[todo] = it
            star_parts.append((it, np.column_stack([todo[r], a, b])[own]))
        elif k == 3:
            m, st, hull = np.zeros(len(todo)), np.zeros(len(todo), np.int64), np.zeros(len(todo), bool)
            _masses3(Q, nbr, counts, kt, todo, m, st, hull)
            # cospherical neighbours: Qhull (with its joggle) decides the star
            tie = np.flatnonzero(st == _DEGENERATE)
            if len(tie):
                m[tie], st[tie], hull[tie] = _masses_k(Q, nbr[tie], counts[tie], kt, todo[tie], k)
            open_cell[todo] = hull
        else:
            m, st, hull = _masses_k(Q, nbr, counts, kt, todo, k)
            open_cell[todo] = hull
        mass[todo], status[todo] = m, st
        if K >= min(_MAX_NEIGHBORS, nu - 1):
            break
        todo = todo[st == _INSECURE]
        K = min(2 * K, _MAX_NEIGHBORS, nu - 1)
    # outliers: isolated far beyond the spacing usual around them
    _, idx = _neighbours(tree, Q, min(8, nu - 1))
    local = np.median(reach8[idx[:, 1:]], axis=1)
    outlier = nn1 > outlier_ratio * np.maximum(local, 1e-300)
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
    # a recomputed star replaces the earlier one
    tris = [t[last[t[:, 0]] == it] for it, t in star_parts]
    triangles = uniq[np.concatenate(tris)] if tris else np.zeros((0, 3), np.int64)
    full = mass[np.searchsorted(uniq, rep)] / share
    boundary = open_cell[np.searchsorted(uniq, rep)]
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
    }
    return full, info


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


def project_to_tangent(P: Any, k: int = 2, neighbors: int | None = None) -> np.ndarray:
    """Move every point onto the k-plane fitted (PCA) to it and its nearest neighbours.

    One step of local plane projection: noise normal to the manifold drops from σ to about
    σ/sqrt(K), at the price of a shrink of about the neighbourhood's sagitta on curved
    parts (0.1% of the radius for 16,000 points on the unit sphere).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> P = meshlap.samples.sphere_points(4000, "noisy", seed=0)
    >>> r = np.linalg.norm(project_to_tangent(P), axis=1)
    >>> bool(r.std() < 0.5 * np.linalg.norm(P, axis=1).std())
    True
    """
    P = check_points(P)
    K = min(neighbors or _NEIGHBORS.get(k, 20 * k), len(P) - 1)
    _, idx = KDTree(P).query(P, k=K + 1)
    out = np.empty_like(P)
    for a in range(0, len(P), 65536):  # blocks bound the (block, K+1, d) temporaries
        nb = P[np.asarray(idx[a:a + 65536], np.int64)]
        c = nb.mean(axis=1)
        X = nb - c[:, None]
        _, v = np.linalg.eigh(np.einsum("nki,nkj->nij", X, X))
        T = v[:, :, -k:]  # (block, d, k) tangent basis
        rel = P[a:a + 65536] - c
        out[a:a + 65536] = c + np.einsum("ndk,nk->nd", T, np.einsum("ndk,nd->nk", T, rel))
    return out


def point_cloud_geometry(P: Any, k: int = 2, *, denoise: bool = False, **kwargs: Any) -> Geometry:
    """The :class:`~meshlap.geometry.Geometry` of a point cloud: points, masses from
    :func:`point_masses`, intrinsic dimension k, open cells as boundary.

    ``denoise=True`` first moves the points onto their local tangent planes
    (:func:`project_to_tangent`); the kernel then sees distances without most of the normal
    noise, which otherwise scales its weights by about (1 + σ²/h)^{-1/2}.

    Examples
    --------
    >>> import meshlap
    >>> g = point_cloud_geometry(meshlap.shapes.fibonacci_sphere(1000))
    >>> g.dim, g.source, round(g.spacing, 3)
    (2, 'point cloud', 0.12)
    """
    P = check_points(P)
    if denoise:
        P = project_to_tangent(P, k, kwargs.get("neighbors"))
    mass, info = point_masses(P, k, **kwargs)
    cells = info.get("triangles") if k == 2 else None
    return Geometry(P, mass, int(k), info["spacing"], boundary=info["boundary"], cells=cells,
                    source="point cloud")


def point_cloud_laplacian(P: Any, h: float | None = None, k: int = 2, tol: float = DEFAULT_TOL, *,
                          denoise: bool = False, neighbors: int | None = None, merge_tol: float = 1e-6,
                          outlier_ratio: float = 10.0, **kwargs: Any) -> MeshLaplacian:
    """The heat-kernel Laplacian of a point cloud (Belkin, Sun and Wang, SODA 2009).

    L f(w) = Σ_p m_p exp(-|p-w|²/4h) (f(p) - f(w)) / (h (4πh)^{k/2}), with the masses m_p of
    :func:`point_masses`. The result is a :class:`~meshlap.MeshLaplacian` (``L``, ``M``,
    ``S``, ``mass``, ``h``, ``op @ f``, ``as_linear_operator``), so :mod:`meshlap.spectral`,
    :mod:`meshlap.heat` and :mod:`meshlap.curvature` take it as they take a mesh's.

    Parameters
    ----------
    P : (n, d) array_like, or a point cloud object
        Points in R^d, d ≥ k (d > 3 uses a k-d tree instead of the cell grid); or an
        ``open3d.geometry.PointCloud``, ``pyvista.PolyData``, ``trimesh.PointCloud`` or a
        file path (:func:`meshlap.inputs.as_geometry_input`; a mesh gives its vertices).
    h : float, optional
        Kernel width. Default (2a)², a the neighbour distance of a regular lattice with the
        cloud's mean mass (as (2·mean edge)² on a mesh); ``op.h`` and ``op.h_auto`` report it.
    k : int, default 2
        Intrinsic dimension: 1 curve, 2 surface, 3 volume or 3-manifold.
    tol : float, default 1e-8
        Kernel tolerance, as for meshes.
    denoise : bool, default False
        Project the points onto their local tangent planes first (for noisy scans): on the
        unit sphere with 1% radial noise this takes the error of the first 16 eigenvalues
        from 3% (h = 0.004) to 1.0-1.1% (h = 0.002), on 16,000 points. ``op.V`` then holds the moved points.
    neighbors, merge_tol, outlier_ratio
        See :func:`point_masses`.
    **kwargs
        ``exact``, ``dtype``, ``matrix_free``, ``max_memory``, ``progress`` as for
        :class:`~meshlap.MeshLaplacian`.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> P = np.random.default_rng(0).normal(size=(3000, 3))
    >>> P /= np.linalg.norm(P, axis=1, keepdims=True)
    >>> op = meshlap.point_cloud_laplacian(P, h=0.02)
    >>> err = np.linalg.norm(op @ P[:, 0] + 2 * P[:, 0]) / np.linalg.norm(2 * P[:, 0])
    >>> bool(err < 0.05)                             # Δx = -2x on the unit sphere
    True
    """
    if not isinstance(P, (np.ndarray, list)):  # open3d, pyvista, trimesh point clouds (or meshes)
        P = _held_points(P)
    geo = point_cloud_geometry(P, k, denoise=denoise, neighbors=neighbors, merge_tol=merge_tol,
                               outlier_ratio=outlier_ratio)
    return MeshLaplacian(geo, None, h=h, tol=tol, **kwargs)


def _held_points(obj: Any) -> np.ndarray:
    from .inputs import as_geometry_input

    return as_geometry_input(obj)[0]


def point_cloud_matrices(P: Any, h: float | None = None, k: int = 2, **kwargs: Any
                         ) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """The pair ``(L, M)`` of :func:`point_cloud_laplacian`, for code written for robust-laplacian.

    Note the sign: L is negative semidefinite (L ≈ +Δ); robust-laplacian's L is the positive
    weak form, which corresponds to ``-M @ L`` here.

    Examples
    --------
    >>> import meshlap
    >>> L, M = point_cloud_matrices(meshlap.samples.sphere_points(1000), h=0.02)
    >>> L.shape, bool(abs(M.diagonal().sum() - 4 * 3.1416) < 0.2)     # the sphere's area
    ((1000, 1000), True)
    """
    op = point_cloud_laplacian(P, h=h, k=k, **kwargs)
    return op.L, op.M
