"""Mesh diagnostics for real, messy meshes: boundaries, components, non-manifold edges,
coincident and unreferenced vertices, zero-area faces.

The heat-kernel operator of Belkin, Sun and Wang (SoCG 2008) only uses vertex positions
and the lumped masses m_p = Σ_{t∋p} Area(t)/#t, so it is defined on all of these meshes.
What the diagnostics tell is where its values mean something different from the smooth
Laplace–Beltrami operator, or where a solver needs care:

* near a boundary the Gaussian neighbourhood is cut in half and L picks up a first-order
  term (see :func:`near_boundary`);
* unreferenced vertices have mass 0, so ``M`` is singular;
* components closer than the kernel's cut-off radius are coupled by L, because the kernel
  sees Euclidean distance, not connectivity.

Every function takes ``(V, F)`` in any form :func:`meshlap.laplacian` accepts.
"""

from __future__ import annotations

import math
import os
import sys
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp
from pykdtree.kdtree import KDTree
from scipy.sparse.csgraph import connected_components as _cc

from .._keys import in_set
from ..errors import MeshWarning
from .mass import _face_areas, _mean_edge_length
from .polygons import Polygons
from .validation import check_faces, check_h, check_vertices

__all__ = [
    "DEFAULT_BOUNDARY_WIDTH",
    "DUPLICATE_RTOL",
    "PRECISION_WARN",
    "ZERO_AREA_RTOL",
    "MeshReport",
    "boundary_edges",
    "boundary_loops",
    "boundary_vertices",
    "connected_components",
    "diagnose",
    "duplicate_vertices",
    "near_boundary",
    "nonmanifold_edges",
    "unreferenced_vertices",
    "warn_if_messy",
    "zero_area_faces",
]

#: Default width of :func:`near_boundary`, in units of √h. At distance c√h from a straight
#: boundary the first-order bias of L f is ∂f/∂n · e^(-c²/4) / √(πh): c = 3 leaves e^(-2.25) ≈ 11%
#: of its value at the boundary, c = 5 leaves e^(-6.25) ≈ 0.2%.
DEFAULT_BOUNDARY_WIDTH = 5.0
#: Vertices closer than this fraction of the bounding-box diagonal count as coincident.
DUPLICATE_RTOL = 1e-10
#: Faces with area below this fraction of the mean face area count as zero-area.
ZERO_AREA_RTOL = 1e-12


def _mesh(V: Any, F: Any) -> tuple[np.ndarray, Polygons]:
    V = check_vertices(V)
    return V, check_faces(F, len(V))


def _undirected_edges(faces: Polygons, rep: np.ndarray | None = None) -> np.ndarray:
    """Face edges as sorted pairs (one row per face side), with optional vertex welding."""
    e = faces.edges()
    if rep is not None:
        e = rep[e]
    e = e[e[:, 0] != e[:, 1]]
    return np.sort(e, axis=1)


def _edge_counts(edges: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Distinct undirected edges and how many face sides use each."""
    keys = edges[:, 0] * np.int64(n) + edges[:, 1]
    uniq, counts = np.unique(keys, return_counts=True)
    return np.stack([uniq // n, uniq % n], axis=1), counts


_HASH = np.array([0x9E3779B97F4A7C15, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9], dtype=np.uint64)
# Near-duplicate clusters larger than this (distinct points within the tolerance) are merged
# through their 16 nearest members only; exact copies are grouped first, in any number.
_MAX_CLUSTER_K = 16
# The sweep's direction: points within the tolerance are within it along any unit vector, and
# along one that no coordinate plane or diagonal contains, a mesh's distinct vertices are
# seldom that close (28 of a 400,000-vertex random sphere's to the next along it, checked and
# found apart; none of a 100 x 100 grid's)
_SWEEP = np.array([0.5393, 0.6107, 0.5802]) / np.linalg.norm([0.5393, 0.6107, 0.5802])


def _exact_rep(V: np.ndarray) -> np.ndarray:
    """First index of each exactly repeated position, by hashing the coordinates' bits."""
    W = V + 0.0  # -0.0 and 0.0 are the same position
    key = np.bitwise_xor.reduce(W.view(np.uint64) * _HASH, axis=1)
    _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    rep = first[inverse]
    clash = np.any(W[rep] != W, axis=1)  # a hash collision: keep those apart
    rep[clash] = np.flatnonzero(clash)
    return rep


def _near_pairs(P: np.ndarray, atol: float) -> tuple[np.ndarray, np.ndarray] | None:
    # the pairs of P's points closer than atol (the k-d tree's exclusive bound below), by a sweep
    # along _SWEEP: sorted by their projections, a point's partners follow it within atol, so a
    # pass over the points k places ahead, for k = 1, 2, ... until none is that close, finds them
    # all (at 400,000 points 0.05 s of CPU against 0.26 s for the tree and its query). None
    # where a run of projections that close holds more than _MAX_CLUSTER_K points: the tree then
    bound = atol * (1 + 1e-9)
    proj = P @ _SWEEP
    order = np.argsort(proj, kind="stable")
    line = proj[order]
    # (a projection's rounding, which the coordinates' differences do not have)
    slack = bound + 8 * np.finfo(np.float64).eps * float(np.abs(line).max())
    pi, pj = [np.zeros(0, np.int64)], [np.zeros(0, np.int64)]
    for k in range(1, len(P)):
        close = np.flatnonzero(line[k:] - line[:-k] <= slack)
        if not len(close):
            break
        if k > _MAX_CLUSTER_K:
            return None
        a, b = order[close], order[close + k]
        near = ((P[a] - P[b]) ** 2).sum(axis=1) < bound * bound
        pi.append(a[near])
        pj.append(b[near])
    return np.concatenate(pi), np.concatenate(pj)


def _duplicate_rep(V: np.ndarray, rtol: float) -> np.ndarray:
    n = len(V)
    if n < 2:
        return np.arange(n)
    exact = _exact_rep(V)
    # kd-trees degrade on many identical points, so only distinct positions go into the tree
    uniq = np.flatnonzero(exact == np.arange(n))
    pairs_i, pairs_j = [np.arange(n)], [exact]  # each copy to its first
    atol = rtol * float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    swept = _near_pairs(V[uniq], atol) if atol > 0 and len(uniq) > 1 else None
    if swept is not None:
        pairs_i.append(uniq[swept[0]])
        pairs_j.append(uniq[swept[1]])
    elif atol > 0 and len(uniq) > 1:
        P = V[uniq]
        tree = KDTree(P)
        todo, k = np.arange(len(uniq)), 2  # itself and its nearest neighbour
        while len(todo):
            # pykdtree's bound is exclusive
            _, idx = tree.query(P[todo], k=k, distance_upper_bound=atol * (1 + 1e-9))
            idx = idx.reshape(len(todo), k).astype(np.int64)
            hit = idx < len(uniq)
            pairs_i.append(uniq[np.repeat(todo, k).reshape(len(todo), k)[hit]])
            pairs_j.append(uniq[idx[hit]])
            # a cluster larger than k fills every slot: ask those points again with a larger k
            full = hit.all(axis=1)
            if k >= min(len(uniq), _MAX_CLUSTER_K) or not full.any():
                break
            todo, k = todo[full], min(len(uniq), 2 * k)
    i, j = np.concatenate(pairs_i), np.concatenate(pairs_j)
    keep = i != j
    if not keep.any():
        return np.arange(n)
    i, j = i[keep], j[keep]
    g = sp.coo_matrix((np.ones(len(i)), (i, j)), shape=(n, n))
    _, label = _cc(g, directed=False)
    first = np.full(label.max() + 1, n)
    np.minimum.at(first, label, np.arange(n))
    return first[label]


def duplicate_vertices(V: Any, rtol: float = DUPLICATE_RTOL) -> np.ndarray:
    """For every vertex, the lowest index of a vertex at the same position.

    Vertices count as coincident when they lie closer than ``rtol`` times the bounding-box
    diagonal (chains of such pairs are merged). Exact copies are grouped by hashing their
    coordinates, then a sweep along one direction finds near copies in O(n log n) (a pykdtree
    nearest-neighbour search where more than 16 points lie within the tolerance of each other).
    Duplicated vertices (UV seams, STL soups, merged parts) do not change L, which only sees
    positions and masses, but they split the connectivity: a seam looks like a boundary
    unless the vertices are welded.

    Parameters
    ----------
    V : (n, 3) array_like
        Vertex positions.
    rtol : float, default 1e-10
        Distance tolerance relative to the bounding-box diagonal; 0 finds exact copies only.

    Returns
    -------
    (n,) int64 ndarray
        ``rep[i] == i`` for a vertex that is not a copy of an earlier one.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    >>> duplicate_vertices(V)
    array([0, 1, 0, 1, 4])
    """
    V = check_vertices(V)
    if not (math.isfinite(rtol) and 0 <= rtol < 1):
        raise ValueError(f"rtol must lie in [0, 1); got {rtol}")
    return _duplicate_rep(V, rtol)


def unreferenced_vertices(V: Any, F: Any) -> np.ndarray:
    """Indices of the vertices that no face uses (mass 0).

    L is still defined there (its row averages the neighbours' values), but their column
    of L is zero, their row of ``S = M L`` is zero and ``M`` is singular.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.eye(4, 3)
    >>> unreferenced_vertices(V, [[0, 1, 2]])
    array([3])
    """
    V, faces = _mesh(V, F)
    return np.flatnonzero(np.bincount(faces.indices, minlength=len(V)) == 0)


def zero_area_faces(V: Any, F: Any, rtol: float = ZERO_AREA_RTOL) -> np.ndarray:
    """Indices of faces whose area is below ``rtol`` times the mean face area.

    Such faces (collinear or repeated corners) give nothing to the lumped mass; their
    corners simply receive no share from them.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]], float)
    >>> zero_area_faces(V, [[0, 1, 2], [0, 1, 3]])
    array([1])
    """
    V, faces = _mesh(V, F)
    area = _face_areas(V, faces)
    return np.flatnonzero(area <= rtol * area.mean())


def nonmanifold_edges(V: Any, F: Any) -> np.ndarray:
    """Undirected edges shared by more than two faces, as an (k, 2) array (i < j).

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], float)
    >>> nonmanifold_edges(V, [[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    array([[0, 1]])
    """
    V, faces = _mesh(V, F)
    edges, counts = _edge_counts(_undirected_edges(faces), len(V))
    return edges[counts > 2]


def boundary_edges(V: Any, F: Any, weld: bool = True) -> np.ndarray:
    """Undirected edges used by exactly one face, as an (k, 2) array.

    With ``weld=True`` coincident vertices (:func:`duplicate_vertices`) are merged first, so
    that seams of duplicated vertices are not reported as boundary; the edges are returned
    in the original indices.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    >>> boundary_edges(V, [[0, 1, 2], [0, 2, 3]]).tolist()
    [[0, 1], [0, 3], [1, 2], [2, 3]]
    """
    V, faces = _mesh(V, F)
    return _boundary_edges(faces, len(V), _weld(V, weld))


def _weld(V: np.ndarray, weld: bool) -> np.ndarray | None:
    return _duplicate_rep(V, DUPLICATE_RTOL) if weld else None


def _boundary_edges(faces: Polygons, n: int, rep: np.ndarray | None) -> np.ndarray:
    """Boundary edges in original indices; ``rep`` (or None) welds coincident vertices."""
    welded, counts = _edge_counts(_undirected_edges(faces, rep), n)
    on_boundary = welded[counts == 1]
    if rep is None:
        return on_boundary
    # map welded edges back to one original face side each
    sides = _undirected_edges(faces)
    keys_w = np.sort(rep[sides], axis=1)
    kw = keys_w[:, 0] * np.int64(n) + keys_w[:, 1]
    kb = on_boundary[:, 0] * np.int64(n) + on_boundary[:, 1]
    sel = in_set(kw, kb)
    _, first = np.unique(kw[sel], return_index=True)
    return sides[sel][first]


def boundary_vertices(V: Any, F: Any, weld: bool = True) -> np.ndarray:
    """Boolean mask of the vertices on a boundary edge (see :func:`boundary_edges`).

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 0]], float)
    >>> boundary_vertices(V, [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]).tolist()
    [True, True, True, True, False]
    """
    V, faces = _mesh(V, F)
    mask = np.zeros(len(V), dtype=bool)
    rep = _weld(V, weld)
    mask[_boundary_edges(faces, len(V), rep).reshape(-1)] = True
    if rep is not None:  # every copy of a boundary vertex is on the boundary
        mask = np.isin(rep, rep[mask])
    return mask


def boundary_loops(V: Any, F: Any, weld: bool = True) -> int:
    """Number of boundary curves (holes and outer rims), as connected sets of boundary edges.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    >>> boundary_loops(V, [[0, 1, 2], [0, 2, 3]])
    1
    """
    V, faces = _mesh(V, F)
    rep = _weld(V, weld)
    return _count_edge_components(_boundary_edges(faces, len(V), rep), len(V), rep)


def _count_edge_components(edges: np.ndarray, n: int, rep: np.ndarray | None) -> int:
    if len(edges) == 0:
        return 0
    if rep is not None:
        edges = rep[edges]
    g = sp.coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    _, label = _cc(g, directed=False)
    return len(np.unique(label[edges[:, 0]]))


def near_boundary(V: Any, F: Any, h: float, width: float = DEFAULT_BOUNDARY_WIDTH) -> np.ndarray:
    """Boolean mask of the vertices within ``width·√h`` of a boundary vertex.

    There the operator is biased: the Gaussian neighbourhood of a vertex at distance d from
    a straight boundary lacks the far half-plane, and L f gains a first-order term
    ∂f/∂n · e^(-d²/4h)/√(πh) that does not vanish as the mesh is refined. At d = c√h it is
    e^(-c²/4) of its size on the boundary; the default c = 5 leaves about 0.2% (c = 3:
    11%). Use the complement of the mask to compare L against the Laplace–Beltrami
    operator, or to exclude boundary rows from error measures.

    Distances are Euclidean (what the kernel sees) to the boundary curves: the boundary
    edges are sampled at spacing s ≤ width·√h/16 and a pykdtree search finds the nearest
    sample, so every vertex within ``width·√h - s/2`` of the boundary is in the mask and none
    beyond ``width·√h``.

    Parameters
    ----------
    V : (n, 3) array_like
        Vertex positions.
    F : (m, k) array_like or list of sequences
        Faces.
    h : float
        Kernel width of the operator (``op.h``).
    width : float, default 5
        Width of the band in units of √h.

    Returns
    -------
    (n,) bool ndarray
        True for vertices in the band (boundary vertices included); all False on closed
        meshes.

    Examples
    --------
    >>> import meshlap
    >>> V, F = meshlap.shapes.plane(2000, seed=0)
    >>> mask = near_boundary(V, F, h=0.001)            # band 5·√0.001 ≈ 0.16 wide
    >>> bool(mask[[0, 1, 2, 3]].all()), round(float(mask.mean()), 2)
    (True, 0.28)
    """
    V, faces = _mesh(V, F)
    h = check_h(h)
    if not (math.isfinite(width) and width >= 0):
        raise ValueError(f"width must be finite and >= 0; got {width}")
    rep = _duplicate_rep(V, DUPLICATE_RTOL)
    edges = _boundary_edges(faces, len(V), rep)
    on = np.zeros(len(V), dtype=bool)
    on[edges.reshape(-1)] = True
    on = np.isin(rep, rep[on])
    radius = width * math.sqrt(h)
    if not on.any() or radius == 0:
        return on
    a, b = V[edges[:, 0]], V[edges[:, 1]]
    length = np.linalg.norm(b - a, axis=1)
    # sample spacing: radius/16, coarser only if that would mean more than 4 samples per vertex
    step = max(radius / 16, length.sum() / (4 * len(V)))
    pieces = np.maximum(np.ceil(length / step).astype(np.int64), 1)
    edge = np.repeat(np.arange(len(edges)), pieces + 1)
    start = np.repeat(np.cumsum(pieces + 1) - (pieces + 1), pieces + 1)
    frac = (np.arange(len(edge)) - start) / pieces[edge]
    samples = a[edge] + frac[:, None] * (b - a)[edge]
    dist, _ = KDTree(samples).query(V, k=1, distance_upper_bound=radius * (1 + 1e-12))
    return (dist <= radius) | on


def connected_components(V: Any, F: Any, weld: bool = True) -> tuple[int, np.ndarray]:
    """Connected components of the faces (vertices linked by face edges).

    Returns ``(count, labels)``; unreferenced vertices get label -1 and are not counted.
    With ``weld=True`` coincident vertices join their copies' component.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.arange(21.0).reshape(7, 3) ** 2
    >>> connected_components(V, [[0, 1, 2], [3, 4, 5]])
    (2, array([ 0,  0,  0,  1,  1,  1, -1]))
    """
    V, faces = _mesh(V, F)
    return _components(faces, len(V), _weld(V, weld))


def _components(faces: Polygons, n: int, rep: np.ndarray | None) -> tuple[int, np.ndarray]:
    e = faces.edges()
    if rep is not None:
        e = np.vstack([e, np.stack([np.arange(n), rep], axis=1)])
    g = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    _, label = _cc(g, directed=False)
    used = np.zeros(n, dtype=bool)
    used[faces.indices] = True
    if rep is not None:
        used = np.isin(label, label[used])
    # renumber the components that hold a face, in order of first vertex
    _, first, inverse = np.unique(label[used], return_index=True, return_inverse=True)
    order = np.argsort(np.argsort(first))
    out = np.full(n, -1, dtype=np.int64)
    out[used] = order[inverse]
    return len(first), out


@dataclass
class MeshReport:
    """What :func:`diagnose` found; ``str(report)`` is a short, readable summary."""

    n_vertices: int
    n_faces: int
    unreferenced: np.ndarray  # vertex indices
    zero_area: np.ndarray  # face indices
    duplicates: np.ndarray  # vertex indices that repeat an earlier vertex's position
    nonmanifold: np.ndarray  # (k, 2) edges
    isolated: np.ndarray  # face indices: faces that share no corner with another face
    n_components: int
    n_boundary_vertices: int
    n_boundary_loops: int
    precision_loss: float  # relative rounding of edge vectors: eps * max|V| / mean edge
    problems: list[str] = field(default_factory=list)

    def __str__(self) -> str:
        lines = [
            f"{self.n_vertices:,} vertices, {self.n_faces:,} faces, {self.n_components} component(s), "
            f"{self.n_boundary_loops} boundary loop(s) ({self.n_boundary_vertices:,} boundary vertices)"
        ]
        lines += [f"- {p}" for p in self.problems] or ["- no problems found"]
        return "\n".join(lines)


#: Relative rounding of edge vectors (eps·max|V|/mean edge) above which :func:`diagnose`
#: reports the coordinates. Measured on spot translated by 1e6 ... 1e10: L's relative error
#: is about 0.08 times this number and the masses' about 0.2 times, so 1e-6 flags meshes
#: whose operator is no longer good to float32 precision.
PRECISION_WARN = 1e-6


def _problems(V: np.ndarray, faces: Polygons, area: np.ndarray,
              mean_edge: float | None = None) -> dict[str, Any]:
    """The checks shared by :func:`diagnose` and the build-time warning of the operator."""
    n = len(V)
    unref = np.flatnonzero(np.bincount(faces.indices, minlength=n) == 0)
    zero = np.flatnonzero(area <= ZERO_AREA_RTOL * area.mean())
    rep = _duplicate_rep(V, DUPLICATE_RTOL)
    dup = np.flatnonzero(rep != np.arange(n))
    edges, counts = _edge_counts(_undirected_edges(faces), n)
    nonman = edges[counts > 2]
    if mean_edge is None:
        mean_edge = _mean_edge_length(V, faces)
    loss = np.finfo(np.float64).eps * float(np.abs(V).max()) / mean_edge if mean_edge > 0 else math.inf
    problems = []
    if len(unref):
        problems.append(
            f"{len(unref):,} unreferenced vertices (in no face): mass 0 for the kernel (the FEM pencil "
            "gives each a tiny mass and a stiff mode of its own); they enter no other row"
        )
    if len(zero):
        problems.append(f"{len(zero):,} zero-area faces: they add nothing to the vertex masses")
    if len(dup):
        problems.append(
            f"{len(dup):,} duplicate vertices (coincident with another vertex): welded wherever "
            "connectivity counts (boundary, normals, widths, parts, the FEM pencil), so a seam is no hole"
        )
    if len(nonman):
        problems.append(f"{len(nonman):,} non-manifold edges (shared by more than two faces)")
    isolated = _isolated_faces(faces, rep)
    if len(isolated):
        problems.append(
            f"{len(isolated):,} isolated faces (no corner shared with another face): each is a part of "
            "its own, with a zero eigenvalue; a triangle soup whose copies of a corner do not coincide "
            f"(the nearest corner of another face lies {_gap(V, faces, isolated) / mean_edge:.2g} mean "
            "edges away)?"
        )
    if loss > PRECISION_WARN:
        problems.append(
            f"coordinates up to {np.abs(V).max():.3g} are large next to the mean edge {mean_edge:.3g}: "
            f"edge vectors keep a relative precision of only {loss:.1e}; translate the mesh near "
            "the origin before converting it to floating point"
        )
    return dict(unreferenced=unref, zero_area=zero, duplicates=dup, nonmanifold=nonman, isolated=isolated,
                precision_loss=loss, problems=problems, rep=rep)


def _isolated_faces(faces: Polygons, rep: np.ndarray) -> np.ndarray:
    """The faces none of whose corners (copies welded) is in another face (none in a one-face mesh)."""
    if faces.n_faces < 2:
        return np.zeros(0, dtype=np.int64)
    corner = rep[faces.indices]
    uses = np.bincount(corner, minlength=len(rep))[corner]
    return np.flatnonzero(np.maximum.reduceat(uses, faces.offsets[:-1]) == 1)


def _gap(V: np.ndarray, faces: Polygons, isolated: np.ndarray) -> float:
    """The median distance from a corner of an isolated face to the nearest corner of another face."""
    owner = np.repeat(np.arange(faces.n_faces), faces.sizes)
    at = np.full(len(V), -1)
    at[faces.indices] = owner
    corners = faces.indices[np.isin(owner, isolated)]
    size = int(faces.sizes.max())
    d, i = KDTree(V).query(V[corners], k=min(size + 1, len(V)))
    d, i = np.atleast_2d(d.T).T, np.atleast_2d(i.T).T
    other = np.where(at[i] != at[corners][:, None], d, np.inf).min(axis=1)
    return float(np.median(other))


def diagnose(V: Any, F: Any) -> MeshReport:
    """Check a mesh for everything that makes it messy, in one pass.

    Reports unreferenced vertices, zero-area faces, duplicate vertices, non-manifold edges,
    isolated faces (a soup whose corners were not merged), components and boundary loops (after
    welding duplicates), and whether the coordinates are so large next to the edges that they lost
    precision. :func:`meshlap.laplacian` runs the same checks and warns once per build with the
    counts of the problems found.

    Examples
    --------
    >>> import meshlap
    >>> V, F = meshlap.shapes.plane(100, seed=0)
    >>> print(diagnose(V, F))
    100 vertices, 194 faces, 1 component(s), 1 boundary loop(s) (4 boundary vertices)
    - no problems found
    """
    V, faces = _mesh(V, F)
    found = _problems(V, faces, _face_areas(V, faces))
    rep = found.pop("rep")
    bedges = _boundary_edges(faces, len(V), rep)
    on = np.zeros(len(V), dtype=bool)
    on[bedges.reshape(-1)] = True
    on = np.isin(rep, rep[on])
    n_comp, _ = _components(faces, len(V), rep)
    return MeshReport(
        n_vertices=len(V),
        n_faces=faces.n_faces,
        n_components=n_comp,
        n_boundary_vertices=int(on.sum()),
        n_boundary_loops=_count_edge_components(bedges, len(V), rep),
        **found,
    )


def warn_if_messy(V: np.ndarray, faces: Polygons, area: np.ndarray | None = None,
                  mean_edge: float | None = None) -> None:
    """Issue one :class:`~meshlap.validation.MeshWarning` listing the problems :func:`diagnose`
    finds in checked input (unreferenced, duplicate vertices, zero-area faces, non-manifold
    edges, coordinates that lost precision); silent on a clean mesh."""
    if area is None:
        area = _face_areas(V, faces)
    problems = _problems(V, faces, area, mean_edge)["problems"]
    if problems:
        warnings.warn("messy mesh: " + "; ".join(problems) + " (meshlap.topology.diagnose tells more)",
                      MeshWarning, stacklevel=_caller_level())


def _caller_level() -> int:
    """The stacklevel of the first frame outside meshlap, so warnings point at user code."""
    here = os.path.dirname(os.path.abspath(__file__))
    frame, level = sys._getframe(1), 1
    while frame is not None and os.path.dirname(os.path.abspath(frame.f_code.co_filename)) == here:
        frame, level = frame.f_back, level + 1
    return level
