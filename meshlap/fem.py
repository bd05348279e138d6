"""Linear finite elements on the mesh's own cells: the symmetric pencil of the default.

For hat functions φ_i on simplices of any dimension k (segments, triangles, tetrahedra) in any
ambient dimension, the stiffness and the consistent mass of one cell need only its Gram matrix
G = E Eᵀ (E the k edge vectors from corner 0):

    K_cell = vol · B G⁻¹ Bᵀ,   C_cell = vol / ((k+1)(k+2)) · (1 + δ_ij),   vol = √det G / k!

with B = [−1ᵀ; I] the gradients of the barycentric coordinates in the edge basis. A triangle's
Gram matrix comes from its three edge lengths, so triangle meshes are first flipped to their
intrinsic Delaunay triangulation (Bobenko and Springborn 2007): the same surface, whose cotangent
weights are non-negative, so that slivers and obtuse triangles of scans and CAD exports cost
nothing.

Triangles are computed from their side lengths a ≥ b ≥ c alone, by Kahan's form of Heron's
formula, whose area is good to a few ulps even for needles and caps (the textbook form, or a Gram
determinant, loses it to cancellation: a triangle of two vertices 10⁻⁶ of an edge apart was
judged flat and dropped, 3% off the first eigenvalue). Sides known to ε cannot tell a triangle
whose detour c − (a − b) is below ``_FLAT`` = 8ε·a from a flat one (its computed area would be
O(√ε) of a², all roundoff): such a triangle is degenerate, zero stiffness and area. Flips unfold
with atan2 angles for the same reason (acos keeps half the digits of a small angle). Segments
and tetrahedra are degenerate where det G is within ``_FLAT`` of its scale^k, its own roundoff.

The default mass is lumped: on triangles each vertex's mixed Voronoi area (Meyer, Desbrun,
Schröder and Barr 2003; libigl's default mass, with the cotangent stiffness its pencil), on
segments and tetrahedra the row sums D = diag(C·1) of the consistent mass C. Read point-wise,
M⁻¹ S f, the Voronoi areas keep the cotangent Laplacian's accuracy at the vertices (0.37% on a
2,000-vertex sphere, where D gives 8.2%). The option "blend" takes ½(C + D): since D − C is a
graph Laplacian with weights C_ij > 0, C ⪯ ½(C + D) ⪯ D, so by min-max every eigenvalue of the
blended pencil lies between the lumped one and the consistent (Galerkin, upper-bound) one, and
on a uniform mesh their leading O(ē²λ) terms, equal and opposite, cancel. It is moved onto the
diagonal D (what every solver here expects) by the congruence S' = Bᵀ S B, B = I + ¼ D⁻¹(D − C),
exact to first order in D⁻¹(D − C) = O(ē²λ) on a mode of eigenvalue λ; it keeps one zero
eigenvalue per part.
Measured against FEM refined 16× (docs/default.md): 4× ahead of the lumped mass on a random
sphere, but 1.2-2× behind it on coarse real meshes (spot, fandisk, decimated spot), whose
error is the shape the coarse elements miss, not the mass: hence not the default.
"""

from __future__ import annotations

import math
from typing import Any, Literal

import numpy as np
import scipy.sparse as sp

from ._jit import jit
from .errors import MeshError
from .tuned import FEM_TIE as TIE

# sides (or a Gram determinant) known to ε: what is within this of flat is flat (module notes)
_FLAT = 8.0 * float(np.finfo(np.float64).eps)

__all__ = ["FEM_MASSES", "cell_matrices", "expand_copies", "fem_pencil", "intrinsic_delaunay",
           "lumped_pencil", "part_labels", "separate_parts", "separate_rows", "simplicial_cells",
           "triangle_areas", "voronoi_areas", "welded_cells"]

#: ``mass`` values of :func:`fem_pencil`: the lumped diagonal (the default: the cotangent
#: Laplacian's pencil), ½(consistent + lumped) moved onto it, or the consistent mass moved onto
#: it by the same congruence.
FEM_MASSES = ("lumped", "blend", "consistent")


def _halfedge_twins(F: np.ndarray) -> np.ndarray:
    # twin[f, c] = 3 f' + c' for the halfedge F[f,c] -> F[f,c+1] whose reverse is (f', c'),
    # where exactly one reverse exists and the edge has two faces; -1 elsewhere (boundary,
    # non-manifold or inconsistently oriented edges are never flipped)
    m = len(F)
    a, b = F.ravel(), np.roll(F, -1, axis=1).ravel()
    n = int(F.max()) + 1 if m else 0
    key = np.minimum(a, b) * n + np.maximum(a, b)
    order = np.argsort(key, kind="stable")
    ks = key[order]
    start = np.flatnonzero(np.r_[True, ks[1:] != ks[:-1]])
    count = np.diff(np.r_[start, len(ks)])
    twin = np.full(3 * m, -1, dtype=np.int64)
    pair = start[count == 2]
    h0, h1 = order[pair], order[pair + 1]
    opposite = a[h0] == b[h1]
    twin[h0[opposite]], twin[h1[opposite]] = h1[opposite], h0[opposite]
    return twin.reshape(m, 3)


@jit()
def _area(a, b, c):  # pragma: no cover - compiled
    # Kahan's Heron: the area to a few ulps of the sides, needles and caps too; 0 where the
    # sides, known to ε, do not tell the triangle from a flat one (module notes)
    if a < b:
        a, b = b, a
    if b < c:
        b, c = c, b
    if a < b:
        a, b = b, a
    if c - (a - b) <= _FLAT * a:
        return 0.0
    return 0.25 * math.sqrt((a + (b + c)) * (c - (a - b)) * (c + (a - b)) * (a + (b - c)))


@jit()
def _cot(a, b, c):  # pragma: no cover - compiled
    # cotangent of the angle opposite side a in the triangle of sides a, b, c
    floor = 1e-14 * max(a, b, c) ** 2
    return (b * b + c * c - a * a) / (4.0 * max(_area(a, b, c), floor))


@jit()
def _angle(a, b, c):  # pragma: no cover - compiled
    # the angle opposite side a, by atan2: small angles keep their digits (acos loses half)
    return math.atan2(4.0 * _area(a, b, c), b * b + c * c - a * a)


@jit()
def _flip(F, L, twin, max_passes):  # pragma: no cover - compiled
    flips = 0
    for _ in range(max_passes):
        done = True
        for f in range(F.shape[0]):
            for c in range(3):
                t = twin[f, c]
                if t < 0:
                    continue
                g, d = t // 3, t % 3
                c1, c2, d1, d2 = (c + 1) % 3, (c + 2) % 3, (d + 1) % 3, (d + 2) % 3
                w = _cot(L[f, c], L[f, c1], L[f, c2]) + _cot(L[g, d], L[g, d1], L[g, d2])
                if w >= -1e-12:
                    continue
                a, b, cc, dd = F[f, c], F[f, c1], F[f, c2], F[g, d2]
                if cc == dd:
                    continue
                lab, lbc, lca, lad, ldb = L[f, c], L[f, c1], L[f, c2], L[g, d1], L[g, d2]
                # the quad unfolded about ab: the angles at a on either side, then cd across
                # (law of cosines in the form without cancellation when c and d nearly meet)
                half = 0.5 * (_angle(lbc, lab, lca) + _angle(ldb, lab, lad))
                lcd = math.sqrt((lca - lad) ** 2 + 4.0 * lca * lad * math.sin(half) ** 2)
                if lcd <= 0.0:
                    continue
                tw_ca, tw_ad, tw_db, tw_bc = twin[f, c2], twin[g, d1], twin[g, d2], twin[f, c1]
                # f = (cc, a, dd), g = (dd, b, cc); slot 2 of each is the new diagonal
                F[f, 0], F[f, 1], F[f, 2] = cc, a, dd
                L[f, 0], L[f, 1], L[f, 2] = lca, lad, lcd
                F[g, 0], F[g, 1], F[g, 2] = dd, b, cc
                L[g, 0], L[g, 1], L[g, 2] = ldb, lbc, lcd
                twin[f, 0], twin[f, 1], twin[f, 2] = tw_ca, tw_ad, 3 * g + 2
                twin[g, 0], twin[g, 1], twin[g, 2] = tw_db, tw_bc, 3 * f + 2
                for slot, tw in ((3 * f, tw_ca), (3 * f + 1, tw_ad), (3 * g, tw_db), (3 * g + 1, tw_bc)):
                    if tw >= 0:
                        twin[tw // 3, tw % 3] = slot
                flips += 1
                done = False
        if done:
            break
    return flips


def intrinsic_delaunay(P: np.ndarray, tri: np.ndarray, max_passes: int = 1000
                       ) -> tuple[np.ndarray, np.ndarray]:
    """The intrinsic Delaunay triangulation of a triangle mesh, by edge flips on edge lengths.

    Each interior edge whose opposite angles sum to more than π is replaced by the other
    diagonal of its two triangles unfolded into the plane (Lawson's flips, which end at the
    intrinsic Delaunay triangulation of the same polyhedral surface: Bobenko and Springborn
    2007). Boundary, non-manifold and inconsistently oriented edges stay.

    Parameters
    ----------
    P : (n, d) ndarray
        Vertex positions.
    tri : (m, 3) int ndarray
        Triangles.
    max_passes : int, default 1000
        Sweeps over the edges at most.

    Returns
    -------
    tri : (m, 3) int64 ndarray
        The flipped triangles (the same vertices).
    lengths : (m, 3) ndarray
        ``lengths[f, c]`` the intrinsic length of the edge from corner c to corner c + 1.

    Examples
    --------
    >>> import numpy as np
    >>> P = np.array([[0, 0, 0], [2, 0, 0], [1, 0.2, 0], [1, -0.2, 0]], float)
    >>> T, lengths = intrinsic_delaunay(P, np.array([[0, 1, 2], [1, 0, 3]]))
    >>> sorted(map(int, T[0])), round(float(lengths.max()), 3)  # the short diagonal 2-3
    ([0, 2, 3], 1.02)
    """
    F = np.array(tri, dtype=np.int64, copy=True)
    L = np.linalg.norm(P[np.roll(F, -1, axis=1)] - P[F], axis=2)
    if len(F):
        _flip(F, L, _halfedge_twins(F), int(max_passes))
    return F, L


def triangle_areas(lengths: np.ndarray) -> np.ndarray:
    """Triangles' areas from their side lengths, by Kahan's form of Heron's formula (module
    notes): good to a few ulps for needles and caps; 0 for a triangle its sides, known to ε, do
    not tell from a flat one.

    Parameters
    ----------
    lengths : (m, 3) ndarray
        Each triangle's three side lengths, in any order.

    Returns
    -------
    (m,) ndarray

    Examples
    --------
    >>> triangle_areas(np.array([[3.0, 5.0, 4.0], [1.0, 1.0, 1e-9], [2.0, 1.0, 1.0]])).tolist()
    [6.0, 5e-10, 0.0]
    """
    L = np.sort(np.asarray(lengths, dtype=np.float64), axis=1)
    c, b, a = L[:, 0], L[:, 1], L[:, 2]
    detour = c - (a - b)
    product = (a + (b + c)) * detour * (c + (a - b)) * (a + (b - c))
    return np.where(detour > _FLAT * a, 0.25 * np.sqrt(np.maximum(product, 0.0)), 0.0)


def voronoi_areas(lengths: np.ndarray) -> np.ndarray:
    """Each triangle corner's mixed Voronoi area (Meyer, Desbrun, Schröder and Barr 2003).

    In a triangle without an obtuse angle, corner i gets the part of the triangle nearer to it
    than to the other corners (its circumcentric area, (l_ij² cot θ_k + l_ik² cot θ_j) / 8); in
    an obtuse one, whose circumcentre lies outside, the obtuse corner gets half the area and the
    others a quarter. The three parts sum to the area.

    Parameters
    ----------
    lengths : (m, 3) ndarray
        ``lengths[f, c]`` the length of the side from corner c to corner c + 1.

    Returns
    -------
    (m, 3) ndarray

    Examples
    --------
    >>> import numpy as np
    >>> voronoi_areas(np.array([[1.0, 1.0, 1.0], [1.0, np.sqrt(2), 1.0]])).round(4).tolist()
    [[0.1443, 0.1443, 0.1443], [0.25, 0.125, 0.125]]
    """
    L = np.asarray(lengths, dtype=np.float64)
    l2 = L * L
    area = triangle_areas(L)
    prev = np.roll(l2, 1, axis=1)  # the side ending at corner c
    across = np.roll(l2, -1, axis=1)  # the side opposite corner c
    dot = (l2 + prev - across) / 2  # |side c| |side c-1| cos θ_c
    cot = dot / np.maximum(2 * area, 1e-300)[:, None]  # cos / sin, with 2 area = |c| |c-1| sin θ_c
    circum = (l2 * np.roll(cot, -2, axis=1) + prev * np.roll(cot, -1, axis=1)) / 8
    obtuse = dot < 0
    split = np.where(obtuse, area[:, None] / 2, area[:, None] / 4)
    return np.where(obtuse.any(axis=1)[:, None] | (area[:, None] == 0), split, circum)


def cell_matrices(P: np.ndarray | None, cells: np.ndarray, lengths: np.ndarray | None = None
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-cell P1 stiffness and consistent mass of simplices, and their volumes.

    Parameters
    ----------
    P : (n, d) ndarray or None
        Vertex positions (any ambient dimension d ≥ k); None when triangles' ``lengths`` are given.
    cells : (m, k + 1) int ndarray
        Segments, triangles or tetrahedra.
    lengths : (m, 3) ndarray, optional
        Triangles only: ``lengths[f, c]`` the side from corner c to c + 1 (e.g. intrinsic ones)
        instead of ``P``.

    Returns
    -------
    K : (m, k + 1, k + 1) ndarray
        ∫ ∇φ_i · ∇φ_j over each cell (positive semidefinite, rows summing to zero).
    C : (m, k + 1, k + 1) ndarray
        ∫ φ_i φ_j over each cell.
    vol : (m,) ndarray
        Length, area or volume (0 for a degenerate cell, whose K is 0: module notes).

    Examples
    --------
    >>> import numpy as np
    >>> K, C, vol = cell_matrices(np.array([[0, 0], [1, 0], [0, 1]], float), np.array([[0, 1, 2]]))
    >>> K[0].round(3).tolist(), float(vol[0]), round(float(C[0].sum()), 12)
    ([[1.0, -0.5, -0.5], [-0.5, 0.5, 0.0], [-0.5, 0.0, 0.5]], 0.5, 0.5)
    """
    cells = np.asarray(cells, dtype=np.int64)
    k = cells.shape[1] - 1
    if k == 2:
        if lengths is None:
            lengths = np.linalg.norm(P[np.roll(cells, -1, axis=1)] - P[cells], axis=2)
        K, vol = _triangle_stiffness(np.asarray(lengths, dtype=np.float64))
    else:
        if lengths is not None:
            raise MeshError(f"side lengths give triangles, not cells of {k + 1} corners")
        E = P[cells[:, 1:]] - P[cells[:, :1]]
        gram = E @ np.swapaxes(E, 1, 2)
        det = np.linalg.det(gram)
        ok = det > _FLAT * np.maximum(np.einsum("mii->m", gram) / k, 1e-300) ** k
        vol = np.sqrt(np.where(ok, det, 0.0)) / math.factorial(k)
        inv = np.zeros_like(gram)
        inv[ok] = np.linalg.inv(gram[ok])
        B = np.vstack([-np.ones((1, k)), np.eye(k)])
        K = vol[:, None, None] * (B @ inv @ B.T)
    C = (vol / ((k + 1) * (k + 2)))[:, None, None] * (np.ones((k + 1, k + 1)) + np.eye(k + 1))
    return K, C, vol


def _triangle_stiffness(L: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    # the cotangent form of vol · B G⁻¹ Bᵀ, from Kahan's area: side c -> c + 1 gets half the
    # cotangent of the angle at corner c + 2
    area = triangle_areas(L)
    l2 = L * L
    cot = (l2 + np.roll(l2, 1, axis=1) - np.roll(l2, -1, axis=1)) / np.maximum(4 * area, 1e-300)[:, None]
    K = np.zeros((len(L), 3, 3))
    for c in range(3):
        i, j = c, (c + 1) % 3
        w = np.where(area > 0, 0.5 * cot[:, (c + 2) % 3], 0.0)
        K[:, i, j] = K[:, j, i] = -w
        K[:, i, i] += w
        K[:, j, j] += w
    return K, area


def _scatter(cells: np.ndarray, local: np.ndarray, n: int) -> sp.csr_matrix:
    c = cells.shape[1]
    rows = np.repeat(cells, c, axis=1).ravel()
    cols = np.tile(cells, (1, c)).ravel()
    return sp.csr_matrix((local.ravel(), (rows, cols)), shape=(n, n))


def simplicial_cells(geo: Any) -> np.ndarray | None:
    """The geometry's cells as simplices: a surface's faces fan-triangulated, a curve's
    segments, tetrahedra; a surface cloud's local Delaunay stars (every point's own, so most
    triangles come three times: :func:`fem_pencil` weights them by a third); None for other
    point clouds.

    Examples
    --------
    >>> import meshlap
    >>> simplicial_cells(meshlap.geometry.from_mesh(*meshlap.shapes.sphere(100, seed=0))).shape[1]
    3
    """
    return _weighted_cells(geo)[0]


def _weighted_cells(geo: Any) -> tuple[np.ndarray | None, float]:
    # cells the geometry's own stage chose for FEM (a cloud's stars, each counted a third) first
    if "fem_cells" in geo._cache:
        return geo._cache["fem_cells"]
    return (geo.faces.triangles() if geo.faces is not None else geo.cells), 1.0


def welded_cells(cells: np.ndarray, rep: np.ndarray) -> np.ndarray:
    """``cells`` on the representatives ``rep`` of coincident copies
    (:meth:`~meshlap.geometry.Geometry.copies`), without the cells that welding collapses (two
    corners on one representative).

    Examples
    --------
    >>> welded_cells(np.array([[0, 1, 2], [3, 1, 0]]), np.array([0, 1, 2, 0])).tolist()
    [[0, 1, 2]]
    """
    c = rep[cells]
    s = np.sort(c, axis=1)
    return c[np.all(s[:, 1:] != s[:, :-1], axis=1)]


def part_labels(geo: Any) -> tuple[int, np.ndarray] | None:
    """``(parts, label)``: the connected parts of a mesh's cells, copies welded (vertices in no
    cell get their own label, not counted); None for a point cloud.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(200, seed=0)
    >>> g = meshlap.geometry.from_mesh(np.vstack([V, V + 3]), np.vstack([F, F + 200]))
    >>> part_labels(g)[0]
    2
    """
    def make() -> tuple[int, np.ndarray] | None:
        from scipy.sparse.csgraph import connected_components

        cells = simplicial_cells(geo)
        if cells is None or not geo.tiled:
            return None
        n = geo.n_points
        rep = geo.copies()
        c = cells if rep is None else rep[cells]
        i, j = np.repeat(c[:, :1], c.shape[1] - 1, axis=1).ravel(), c[:, 1:].ravel()
        if rep is not None:
            i, j = np.r_[i, np.arange(n)], np.r_[j, rep]
        graph = sp.coo_matrix((np.ones(len(i)), (i, j)), shape=(n, n))
        _, label = connected_components(graph, directed=False)
        used = np.zeros(n, dtype=bool)
        used[c.ravel()] = True
        return int(len(np.unique(label[used]))), label

    return geo._cached("parts", make)


def separate_rows(free: sp.csr_matrix, L: sp.csr_matrix, label: np.ndarray | None
                  ) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """A kernel pencil's rows without their pairs between parts (:func:`separate_parts`):
    ``free`` (the plain rows) and ``L`` (with mirror images, or ``free`` itself), unchanged where
    ``label`` is None. The pencil's semidefinite check must see these, as they are used: a positive
    pair removed moves onto the diagonal and can leave a row's negative ones uncovered.

    Examples
    --------
    >>> import numpy as np
    >>> L = sp.csr_matrix(np.array([[-2.0, 1, 1], [1, -2, 1], [1, 1, -2]]))
    >>> kept, same = separate_rows(L, L, np.array([0, 0, 1]))
    >>> same is kept, kept.diagonal().tolist()
    (True, [-1.0, -1.0, 0.0])
    """
    if label is None:
        return free, L
    kept = separate_parts(free, label)
    return kept, kept if L is free else separate_parts(L, label)


def separate_parts(L: sp.csr_matrix, label: np.ndarray) -> sp.csr_matrix:
    """``L`` without its entries between different parts, each row's removed sum moved onto its
    diagonal: rows still sum to zero, and the pencil has one zero eigenvalue per part.

    Examples
    --------
    >>> import numpy as np
    >>> L = sp.csr_matrix(np.array([[-2.0, 1, 1], [1, -2, 1], [1, 1, -2]]))
    >>> separate_parts(L, np.array([0, 0, 1])).toarray().tolist()
    [[-1.0, 1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 0.0, 0.0]]
    """
    A = L.tocoo()
    cross = label[A.row] != label[A.col]
    if not cross.any():
        return L
    lost = np.bincount(A.row[cross], A.data[cross], minlength=L.shape[0])
    keep = ~cross
    out = sp.csr_matrix((A.data[keep], (A.row[keep], A.col[keep])), shape=L.shape) + sp.diags(lost)
    return out.tocsr().astype(L.dtype)


def lumped_pencil(geo: Any) -> tuple[sp.csr_matrix, np.ndarray]:
    """:func:`fem_pencil` of the geometry with its copies welded and the lumped mass, once per
    geometry (the denoising step and the default's pencil share it).

    Examples
    --------
    >>> import meshlap
    >>> g = meshlap.geometry.from_mesh(*meshlap.shapes.sphere(500, seed=0))
    >>> lumped_pencil(g)[0] is lumped_pencil(g)[0]
    True
    """
    return geo._cached("lumped_pencil", lambda: fem_pencil(geo, weld=geo.copies()))


def fem_pencil(geo: Any, *, mass: Literal["blend", "lumped", "consistent"] = "lumped",
               intrinsic: bool = True, weld: np.ndarray | None = None, points: np.ndarray | None = None
               ) -> tuple[sp.csr_matrix, np.ndarray]:
    """The linear-FEM pencil ``(S, m)`` of a mesh: S symmetric negative semidefinite (≈ M Δ),
    m the lumped masses of its diagonal mass matrix.

    Parameters
    ----------
    geo : Geometry
        A surface (faces of any size, fan-triangulated), curve or tetrahedral mesh, or a
        surface's point cloud (its local Delaunay stars, each weighted by a third).
    mass : {"lumped", "blend", "consistent"}, default "lumped"
        The mass the stiffness pairs with (module docstring): "lumped", the cotangent
        Laplacian's pencil; "blend" and "consistent" are moved onto the lumped diagonal.
    intrinsic : bool, default True
        Flip a triangle mesh to its intrinsic Delaunay triangulation first.
    weld : (n,) int ndarray, optional
        For every vertex its representative (:func:`meshlap.topology.duplicate_vertices`):
        copies count as one vertex (one mass, shared equally), tied by a stiff spring.
    points : (n, d) ndarray, optional
        Positions to use instead of the geometry's (e.g. denoised ones).

    Returns
    -------
    S : (n, n) scipy.sparse.csr_matrix
    m : (n,) ndarray

    Examples
    --------
    >>> import meshlap, numpy as np, scipy.sparse.linalg as sla
    >>> g = meshlap.geometry.from_mesh(*meshlap.shapes.sphere(2000, seed=0))
    >>> S, m = fem_pencil(g)
    >>> lam = np.sort(sla.eigsh(-S, 4, sp.diags(m), sigma=-1e-6, return_eigenvectors=False))
    >>> (np.round(lam, 2) + 0.0).tolist()     # 0, then l(l + 1) = 2 three times
    [0.0, 2.0, 2.0, 2.0]
    """
    if mass not in FEM_MASSES:
        raise MeshError(f"mass must be one of {', '.join(FEM_MASSES)}; got {mass!r}")
    cells, weight = _weighted_cells(geo)
    if cells is None:
        raise MeshError(f"linear FEM needs cells (faces, segments or tetrahedra); this {geo.source} has none")
    P, n = (geo.points if points is None else points), geo.n_points
    rep = np.arange(n) if weld is None else np.asarray(weld, dtype=np.int64)
    cells = welded_cells(cells, rep)
    lengths = None
    if cells.shape[1] == 3 and intrinsic:
        cells, lengths = intrinsic_delaunay(P, cells)
    elif cells.shape[1] == 3:
        lengths = np.linalg.norm(P[np.roll(cells, -1, axis=1)] - P[cells], axis=2)
    K, C, _ = cell_matrices(P, cells, lengths)
    S = -_scatter(cells, weight * K, n)
    Cm = _scatter(cells, weight * C, n)
    m = np.asarray(Cm.sum(axis=1)).ravel()
    if mass == "lumped" and lengths is not None:
        m = np.bincount(cells.ravel(), weight * voronoi_areas(lengths).ravel(), minlength=n)
    if mass != "lumped":
        inv = np.divide(1.0, m, out=np.zeros_like(m), where=m > 0)
        w = 0.25 if mass == "blend" else 0.5
        B = sp.identity(n, format="csr") + w * (sp.identity(n) - sp.diags(inv) @ Cm)
        S = B.T @ S @ B
        S = 0.5 * (S + S.T)
    return expand_copies(sp.csr_matrix(S), m, rep)


def expand_copies(S: sp.csr_matrix, m: np.ndarray, rep: np.ndarray) -> tuple[sp.csr_matrix, np.ndarray]:
    """A pencil built on welded cells (``rep[cells]``) back on every vertex: copies share their
    representative's mass equally and are tied to it by a spring as stiff as its own diagonal
    entry; a vertex in no cell gets a small mass and a diagonal entry of the same ratio, so
    their modes lie above the mesh's own.

    Examples
    --------
    >>> S = sp.csr_matrix(np.array([[-1.0, 1, 0], [1, -1, 0], [0, 0, 0]]))
    >>> S2, m2 = expand_copies(S, np.array([1.0, 1.0, 0.0]), np.array([0, 1, 1]))
    >>> m2.tolist(), bool(abs(S2 @ np.ones(3)).max() < 1e-12)
    ([1.0, 0.5, 0.5], True)
    """
    n = len(m)
    lone = m[rep] <= 0
    if not (rep != np.arange(n)).any() and not lone.any():
        return S, m
    count = np.bincount(rep, minlength=n).astype(float)
    d = np.abs(S.diagonal())
    tiny = 1e-6 * (m[m > 0].mean() if (m > 0).any() else 1.0)
    share = np.where(lone, tiny, m[rep] / count[rep])
    ratio = float(np.max(d[m > 0] / m[m > 0])) if (m > 0).any() else 1.0
    copies = np.flatnonzero(rep != np.arange(n))
    i, j = copies, rep[copies]
    c = TIE * np.where(lone[i], ratio * tiny, d[j])
    R = sp.csr_matrix((1.0 / count[rep], (np.arange(n), rep)), shape=(n, n))
    tie = sp.csr_matrix((np.r_[-c, -c, c, c], (np.r_[i, j, i, j], np.r_[i, j, j, i])), shape=(n, n))
    alone = (lone & (rep == np.arange(n))).astype(float) * TIE * ratio * tiny
    out = R @ S @ R.T + tie - sp.diags(alone)
    return sp.csr_matrix(0.5 * (out + out.T)), share
