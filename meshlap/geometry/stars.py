"""Compiled local Delaunay stars of a point cloud: the measure each point's star gives it.

:func:`meshlap.geometry.pointcloud.point_masses` projects each neighbourhood onto its
tangent space and asks these kernels for the star of the point: k = 1 half the gaps to the
neighbours on each side, k = 2 the Voronoi cell by half-plane clipping, k = 3 the Delaunay
tetrahedra from the Voronoi cell's vertices, k ≥ 4 Qhull; :func:`_soup` gathers the stars of
all the search rounds into one soup of triangles, :func:`_consistent` gives its cocircular quads
one split, :func:`_off_surface` finds the lines off a surface, and :func:`star_pieces` gives the
soup's connected pieces.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import Delaunay, QhullError

from .._dense import sym_eigh
from .._jit import jit
from .._keys import in_set, key_set
from ..tuned import STAR_SCATTER
from .polygons import Polygons
from .topology import _components

__all__ = ["star_pieces"]

# A neighbourhood whose k-th principal variance is below this fraction of the first has no
# k-dimensional extent.
_FLAT = 1e-10
#: tan of the steepest chord from a point to a neighbour on its own sheet (60°; a 90° crease
#: tilts its chords 45° from the fitted plane)
_STEEP = 3.0**0.5
# Triangles kept per star (a star in a Delaunay triangulation has 6 on average).
_STAR_SLOTS = 24
# cotangent sums this close are a tie: four points cocircular in 3-D up to the 6-7 significant
# digits files store (a CAD torus's grid: up to 8e-6; a scan's disagreements are 1e-4 and more)
_TIE = 1e-5
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
    w = np.empty(d)
    v = np.empty((d, d))
    sym_eigh(C, w, v)
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


@jit()
def _drop_steep(P, p, nbr, U, kt, z):
    # a neighbour whose chord leaves the tangent plane more steeply than _STEEP is on another
    # sheet (a part or layer across the air, the far wall of a thin solid): it takes no part in
    # the star (U = 0 is skipped). A chord of length ρ on a surface of curvature κ leaves it at
    # about ρκ/2, so this sheet's own points stay well below that. Among the first kt (those the
    # plane comes from) noise also makes short chords steep, so there the height must also stand
    # out from the neighbourhood's: beyond STAR_SCATTER times its median (Gaussian noise
    # puts 4% of heights beyond 3 medians, 2 standard deviations). z: room for len(nbr) squared
    # heights
    steep_first = False
    for j in range(len(nbr)):
        r2 = 0.0
        for b in range(P.shape[1]):
            r2 += (P[nbr[j], b] - P[p, b]) ** 2
        t2 = U[j, 0] ** 2 + U[j, 1] ** 2
        z[j] = r2 - t2
        if z[j] > _STEEP * _STEEP * t2:
            if j >= kt:
                U[j, 0] = 0.0
                U[j, 1] = 0.0
            else:
                steep_first = True
    if not steep_first:
        return
    scatter = STAR_SCATTER * STAR_SCATTER * np.median(z[:kt])
    for j in range(kt):
        if z[j] > scatter and z[j] > _STEEP * _STEEP * (U[j, 0] ** 2 + U[j, 1] ** 2):
            U[j, 0] = 0.0
            U[j, 1] = 0.0


def _tie_cut(dist: np.ndarray, kt: np.ndarray, unsettled: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where a point's first ``kt`` neighbours end among equidistant ones (``dist``: sorted, the
    point first, at least one more column than ``kt``), the plane of an arbitrary part of them
    tilts: a pole's ring of 60 seen through 16 of them tilts 1.4° and its projection is no longer
    a circle around it (its star a fan no more). A point whose plane is not ``unsettled`` keeps
    ``kt``; the others stop before the tie where half of ``kt`` is left, else are ``tied``: their
    plane waits for a wider neighbourhood (as a line's does).

    Examples
    --------
    >>> import numpy as np
    >>> d = np.array([[0, 1, 1, 1, 1, 2, 2, 2, 2, 2], [0, 1, 1, 1, 1, 1, 1, 1, 1, 1.]])
    >>> _tie_cut(d, np.array([6, 6]), np.array([True, True]))
    (array([4, 6]), array([False,  True]))
    """
    rows = np.arange(len(kt))
    kth = dist[rows, kt]
    cut = unsettled & (kt + 1 < dist.shape[1])
    cut[cut] = dist[rows[cut], kt[cut] + 1] <= kth[cut] * (1.0 + _TIE)
    before = (dist[:, 1:] < (kth * (1.0 - _TIE))[:, None]).sum(axis=1)
    trim = cut & (2 * before >= kt)
    return np.where(trim, before, kt), cut & ~trim


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
    # (Delaunay star area / 3, Voronoi area, status, triangle count) of the origin among the
    # points U[:K]; tri[i] <- the neighbour pairs (a, b) of the star's first len(tri) triangles,
    # -1 after the last
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
    return star / 6.0, 0.5 * abs(voronoi), status, nt


@jit()
def _masses2(start, stop, P, nbr, counts, kts, rows, out_star, out_vor, status, width, axes, tri, ntri):
    # width: the first kts neighbours' median distance across the plane's first axis over along
    # it; axes: the plane's two axes; ntri: the star's triangle count (more than tri holds: a fan)
    z = np.empty(nbr.shape[1])
    for r in range(start, stop):
        p = rows[r]
        K = counts[r]
        kt = kts[r]
        T = axes[r]
        U = np.empty((K, 2))
        if _tangent(P, p, nbr[r, :kt], 2, T) < _FLAT:
            status[r] = _DEGENERATE
            continue
        _project(P, p, nbr[r, :K], T, U)
        along = np.median(np.abs(U[:kt, 0]))
        width[r] = np.median(np.abs(U[:kt, 1])) / along if along > 0.0 else 0.0
        _drop_steep(P, p, nbr[r, :K], U, kt, z)
        out_star[r], out_vor[r], status[r], ntri[r] = _star2(U, K, tri[r])


# -- k = 1: half the gap to the nearest neighbours on each side (side: their columns in nbr, or -1)
@jit()
def _masses1(start, stop, P, nbr, counts, kt, rows, out, status, ends, side):
    d = P.shape[1]
    for r in range(start, stop):
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
        side[r, 0] = side[r, 1] = -1
        for j in range(K):
            s = U[j, 0]
            if 0.0 > s > left:
                left, side[r, 0] = s, j
            elif 0.0 < s < right:
                right, side[r, 1] = s, j
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


@jit()
def _masses3(start, stop, P, nbr, counts, kt, rows, out, status, hull):
    d = P.shape[1]
    for r in range(start, stop):
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
    hull = bool(np.isin(0, tri.convex_hull))
    radius = _circumradii(X[around])  # the origin is a corner of each: its circumcentres' distance
    reach = float(radius[np.isfinite(radius)].max(initial=0.0))
    far = float(np.linalg.norm(U, axis=1).max())
    status = _OK if (not hull and 2.0 * reach < far) else _INSECURE
    return float(vol.sum()) / (k + 1), status, hull


def _circumradii(A: np.ndarray) -> np.ndarray:
    """Circumradii of the simplices ``A`` (m, k + 1, d), d ≥ k (a cloud's triangles in R³ too);
    inf for a flat one. Segments and triangles in closed form; a larger simplex in its own span
    (Eᵀ = QR, E the edges x_i - x_0, so e_i = Rᵀ's rows there), where the circumcentre y solves
    2 Rᵀ y = |e_i|²: a k × k system as well conditioned as the edges themselves."""
    E = A[:, 1:] - A[:, :1]
    if A.shape[1] == 2:  # a segment
        return 0.5 * np.linalg.norm(E[:, 0], axis=1)
    if A.shape[1] == 3:  # a triangle: |a| |b| |a - b| / (2 |a × b|), |a × b|² = |a|² |b|² - (a·b)²
        aa, bb, ab = (E[:, 0] ** 2).sum(1), (E[:, 1] ** 2).sum(1), (E[:, 0] * E[:, 1]).sum(1)
        cross2 = aa * bb - ab**2
        with np.errstate(divide="ignore", invalid="ignore"):
            radius = np.sqrt(aa * bb * (aa + bb - 2 * ab)) / (2 * np.sqrt(cross2))
        return np.where(cross2 > 0, radius, np.inf)
    R = np.linalg.qr(E.transpose(0, 2, 1), mode="r")
    Rt = R.transpose(0, 2, 1)
    rhs = 0.5 * (E**2).sum(axis=2)
    radius = np.full(len(A), np.inf)
    solvable = np.linalg.det(Rt) != 0.0
    y = np.linalg.solve(Rt[solvable], rhs[solvable][..., None])[..., 0]
    radius[solvable] = np.linalg.norm(y, axis=1)
    return radius


def _masses_k(start, stop, P, nbr, counts, kt, rows, k, out, status, hull):
    # Qhull releases the GIL, so in_blocks overlaps these calls on threads
    T = np.empty((k, P.shape[1]))
    for r in range(start, stop):
        p = rows[r]
        nb = nbr[r, :counts[r]]
        if _tangent(P, p, nb[:kt], k, T) < _FLAT:
            status[r] = _DEGENERATE
            continue
        U = (P[nb] - P[p]) @ T.T
        out[r], status[r], hull[r] = _star_k(U, k)


def _global_stars3(X: np.ndarray, rows: np.ndarray, far: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stars of ``rows`` from one Delaunay tetrahedralization of all the points (d = k = 3).

    A local star is secure when every circumsphere of its tetrahedra lies within half the
    distance ``far`` of the farthest neighbour searched; it then equals the star in the whole
    cloud's Delaunay tetrahedralization. So the global star with all circumradii below far/2
    (and off the convex hull) is the star the neighbourhood search would find, at Qhull's cost
    for all points instead of one call per point. Returns (Σ volumes / 4, secure mask).
    """
    mass = np.zeros(len(rows))
    try:
        tri = Delaunay(X)
    except QhullError:
        return mass, np.zeros(len(rows), dtype=bool)
    S = tri.simplices
    n = len(X)
    reach = np.zeros(n)
    np.maximum.at(reach, S.ravel(), np.repeat(_circumradii(X[S]), 4))
    det = np.linalg.det(X[S[:, 1:]] - X[S[:, :1]])
    vol = np.bincount(S.ravel(), np.repeat(np.abs(det) / 6.0, 4), minlength=n)
    hull = np.zeros(n, dtype=bool)
    hull[tri.convex_hull.ravel()] = True
    secure = (2.0 * reach[rows] < far) & ~hull[rows]
    mass[secure] = vol[rows[secure]] / 4.0
    return mass, secure


def _rows_in(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Which rows of ``a`` are rows of ``b``."""
    if not len(a) or not len(b):
        return np.zeros(len(a), dtype=bool)
    inv = np.unique(np.vstack([b, a]), axis=0, return_inverse=True)[1].ravel()
    return in_set(inv[len(b):], inv[:len(b)])


def _soup(parts: list[tuple[int, np.ndarray]], use: np.ndarray, rim: np.ndarray, base: np.ndarray
          ) -> np.ndarray:
    """Every point's star, its centre first: the one of search round ``use`` (``base``: its first).

    A star the wider search secured replaces the first; one that stayed insecure keeps the first,
    local star (the wider one reaches other sheets: a petal's rim takes triangles across to the
    next petal). A point on the hull of its first neighbours (``rim``) keeps its first star, and
    of its wider star only the triangles that a point whose first star closed also holds: across
    what the sampling leaves empty (a flat figure's notch) only rim points see them, while a
    lopsided neighbourhood's wider triangles are its neighbours' own.
    """
    if not parts:  # k != 2
        return np.zeros((0, 3), np.int64)
    stars = np.concatenate([t[use[t[:, 0]] == it] for it, t in parts])
    widened = rim & (use > base)
    if not widened.any():
        return stars
    wide = widened[stars[:, 0]]
    held = stars[~wide]
    held = np.sort(held[widened[held].any(axis=1)], axis=1)  # only these can hold a rim triangle
    extra = stars[wide]
    extra = extra[_rows_in(np.sort(extra, axis=1), held)]
    first = np.concatenate([t[base[t[:, 0]] == it] for it, t in parts])
    rim_stars = np.concatenate([first[widened[first[:, 0]]], extra])
    # a triangle in both of a rim point's stars, once
    _, once = np.unique(np.column_stack([rim_stars[:, 0], np.sort(rim_stars[:, 1:], axis=1)]), axis=0,
                        return_index=True)
    return np.concatenate([stars[~wide], rim_stars[np.sort(once)]])


def star_pieces(stars: np.ndarray, rep: np.ndarray) -> tuple[int, np.ndarray]:
    """The connected pieces of a point cloud's local Delaunay stars (a duplicate ``rep``-resented
    by its point, in that point's piece): their number and each point's piece (-1: in no star),
    as :func:`~meshlap.geometry.topology.connected_components` gives a mesh's. The FEM pencil on
    the stars has one zero eigenvalue per piece; a point in no star (an outlier, a degenerate
    neighbourhood's) has a stiff mode of its own instead (:func:`meshlap.fem.expand_copies`).

    Examples
    --------
    >>> import numpy as np
    >>> star_pieces(np.array([[0, 1, 2], [3, 4, 5]]), np.r_[0:6, 0, 7])
    (2, array([ 0,  0,  0,  1,  1,  1,  0, -1]))
    """
    cells = Polygons(stars.ravel().astype(np.int64), np.arange(0, stars.size + 1, stars.shape[1]))
    return _components(cells, len(rep), rep)


def _cot(P: np.ndarray, at: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    # cotangent of the angle at ``at`` of the triangles (at, b, c), from the 3-D positions
    u, v = P[b] - P[at], P[c] - P[at]
    return (u * v).sum(axis=1) / np.maximum(np.linalg.norm(np.cross(u, v), axis=1), 1e-300)


def _consistent(stars: np.ndarray, P: np.ndarray) -> np.ndarray:
    """The stars with one split for every cocircular quadrilateral that two of them split differently.

    Each star is Delaunay in its own point's tangent plane, so where four points are cocircular
    in space (a grid sampled on a curved surface: its quads are isosceles trapezoids) the stars
    of its corners split the quad as their planes' projections tip it, and the soup holds both
    splits, overlapping (a torus's 80 × 40 grid: 10% too much area, 14% off on λ1..λ9). Where
    two triangles on one side of an edge are the halves of the two splits of a convex quad whose
    cotangent sums (opposite either diagonal, from the 3-D lengths) tie, every star takes the
    diagonal at the quad's smallest index. Quads that are not cocircular keep both splits: a
    scan's stars disagree there too, and choosing one by the 3-D criterion was worse
    (docs/pointclouds.md).
    """
    if len(stars) < 2 or P.shape[1] != 3:
        return stars
    n = len(P)
    key = _triangle_keys(np.sort(stars, axis=1), n)
    tri = _triangles_of(key_set(key), n)
    e = np.concatenate([tri[:, [0, 1, 2]], tri[:, [0, 2, 1]], tri[:, [1, 2, 0]]])
    e = e[np.argsort(e[:, 0] * n + e[:, 1], kind="stable")]
    edge = e[:, 0] * n + e[:, 1]
    first, second = [], []
    for gap in range(1, 4):  # the triangles on one edge, pairwise
        same = np.flatnonzero(edge[gap:] == edge[:-gap])
        first.append(same)
        second.append(same + gap)
    a, b = np.concatenate(first), np.concatenate(second)
    i, j, r, s = e[a, 0], e[a, 1], e[a, 2], e[b, 2]
    u = P[j] - P[i]
    u /= np.maximum(np.linalg.norm(u, axis=1), 1e-300)[:, None]
    wr = P[r] - P[i] - ((P[r] - P[i]) * u).sum(axis=1)[:, None] * u
    ws = P[s] - P[i] - ((P[s] - P[i]) * u).sum(axis=1)[:, None] * u
    # one side: the two half-planes within 60° (_STEEP: steeper is another sheet, or a fold)
    cos = (wr * ws).sum(axis=1) / np.maximum(np.linalg.norm(wr, axis=1) * np.linalg.norm(ws, axis=1), 1e-300)
    keep = cos > 1.0 / math.sqrt(1.0 + _STEEP * _STEEP)
    i, j, r, s, u, wr = i[keep], j[keep], r[keep], s[keep], u[keep], wr[keep]
    # the four points in the plane of (i, j, r)
    v = wr / np.maximum(np.linalg.norm(wr, axis=1), 1e-300)[:, None]
    x = np.stack([((P[q] - P[i]) * u).sum(axis=1) for q in (j, r, s)], axis=1)
    y = np.stack([((P[q] - P[i]) * v).sum(axis=1) for q in (j, r, s)], axis=1)
    # segment i–r crosses j–s: quad (i, j, r, s); i–s crosses j–r: quad (i, j, s, r); else nested
    ir_js = _crosses(0.0, 0.0, x[:, 1], y[:, 1], x[:, 0], y[:, 0], x[:, 2], y[:, 2])
    is_jr = _crosses(0.0, 0.0, x[:, 2], y[:, 2], x[:, 0], y[:, 0], x[:, 1], y[:, 1])
    quad = np.where(ir_js[:, None], np.column_stack([i, j, r, s]), np.column_stack([i, j, s, r]))
    quad = quad[ir_js | is_jr]
    q0, q1, q2, q3 = quad.T
    ac = _cot(P, q1, q0, q2) + _cot(P, q3, q2, q0)  # diagonal q0–q2
    bd = _cot(P, q0, q1, q3) + _cot(P, q2, q3, q1)  # diagonal q1–q3
    quad = quad[np.abs(ac - bd) <= _TIE * (1.0 + np.abs(ac) + np.abs(bd))]
    if not len(quad):
        return stars
    keep_ac = (quad.argmin(axis=1) % 2) == 0
    split_ac = np.stack([quad[:, [0, 1, 2]], quad[:, [0, 2, 3]]], axis=1)
    split_bd = np.stack([quad[:, [0, 1, 3]], quad[:, [1, 2, 3]]], axis=1)
    win = np.where(keep_ac[:, None, None], split_ac, split_bd).reshape(-1, 3)
    lose = np.where(keep_ac[:, None, None], split_bd, split_ac).reshape(-1, 3)
    win, lose = _triangle_keys(np.sort(win, axis=1), n), _triangle_keys(np.sort(lose, axis=1), n)
    lose = key_set(lose)
    win = key_set(win)
    win = win[~in_set(win, lose, of_sorted=True)]  # a triangle one quad keeps and another drops: dropped
    rows = stars[~in_set(key, lose, of_sorted=True)]
    win = _triangles_of(win, n)
    add = np.concatenate([win[:, [0, 1, 2]], win[:, [1, 2, 0]], win[:, [2, 0, 1]]])
    have = _triangle_keys(np.column_stack([rows[:, 0], np.sort(rows[:, 1:], axis=1)]), n)
    new = _triangle_keys(np.column_stack([add[:, 0], np.sort(add[:, 1:], axis=1)]), n)
    return np.concatenate([rows, add[~in_set(new, have)]])


def _off_surface(stars: np.ndarray, lined: np.ndarray, axes: np.ndarray, line: np.ndarray) -> np.ndarray:
    """The points on a line (``lined``: whose first neighbours lie along ``line``, so that their
    plane ``axes`` came from a wider neighbourhood) whose star reaches only points of a surface
    of their own that the line leaves steeply (more than 60°, _STEEP; a whisker off a plane): the
    line is not on that surface and has no 2-D neighbourhood."""
    normal = np.cross(axes[:, 0], axes[:, 1])
    centre, other = np.repeat(stars[:, 0], 2), stars[:, 1:].ravel()
    ask = lined[centre] & ~lined[other]
    steep = np.abs((normal[other[ask]] * line[centre[ask]]).sum(axis=1)) > math.sin(math.atan(_STEEP))
    asked = np.bincount(centre[ask], minlength=len(lined))
    return (asked > 0) & (np.bincount(centre[ask], steep, minlength=len(lined)) == asked)


def _triangle_keys(t: np.ndarray, n: int) -> np.ndarray:
    # one integer per row (a, b, c) of indices below n; rows of three 21-bit fields beyond 2^21
    # points would overflow, so larger clouds key by the rows' bytes
    t = np.ascontiguousarray(t, dtype=np.int64)
    if n < 2**21:
        return (t[:, 0] * n + t[:, 1]) * n + t[:, 2]
    return t.view(np.dtype((np.void, 24))).ravel()


def _triangles_of(keys: np.ndarray, n: int) -> np.ndarray:
    if keys.dtype.kind == "V":
        return np.frombuffer(keys.tobytes(), dtype=np.int64).reshape(-1, 3)
    return np.column_stack([keys // (n * n), keys // n % n, keys % n])


def _crosses(ax, ay, bx, by, cx, cy, dx, dy):
    # whether the open segments a–b and c–d cross (arrays)
    def side(px, py, qx, qy, rx, ry):
        return (qx - px) * (ry - py) - (qy - py) * (rx - px)
    return (side(ax, ay, bx, by, cx, cy) * side(ax, ay, bx, by, dx, dy) < 0) & \
        (side(cx, cy, dx, dy, ax, ay) * side(cx, cy, dx, dy, bx, by) < 0)
