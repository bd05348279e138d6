"""What the heat kernel needs of any input: positions, masses, intrinsic dimension, boundary.

Every operator is built along one path,

    input (mesh of any cell type, point cloud) → :class:`Geometry` → kernel → operator,

and the kernel never learns where the masses came from. A k-dimensional mesh hands each
vertex the measure of its cells shared equally among their corners (Belkin, Sun and Wang,
SoCG 2008, eq. 1, for surfaces: m_p = Σ_{t∋p} Area(t)/#t):

* polylines (k = 1): m_p = Σ_{e∋p} length(e) / 2;
* surfaces (k = 2): polygons of any size, m_p = Σ_{t∋p} Area(t) / #t;
* tetrahedral volumes (k = 3): m_p = Σ_{T∋p} Volume(T) / 4;

in any ambient dimension d ≥ k. Point clouds get their masses from
:func:`meshlap.geometry.point_cloud_geometry`. The kernel's normalization
1/(h (4πh)^{k/2}) (Belkin, Sun and Wang, "Constructing Laplace operator from point clouds
in R^d", SODA 2009) depends on k alone.

Which k an index array means: 2 columns are edges (k = 1), 3 or more columns and lists of
polygons are faces (k = 2). A (m, 4) array is tetrahedra (k = 3) when most of its cells
meet another across a triangle, their fourth corners on opposite sides of it, as a tetrahedral
mesh's cells do (two quads of a surface share at most an edge); else quads. ``k`` overrides.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._keys import key_set
from ..errors import MeshError
from . import frames
from .mass import _face_areas, _mean_edge_length, _vertex_mass, paper_width
from .polygons import Polygons
from .topology import DUPLICATE_RTOL, _duplicate_rep, warn_if_messy
from .validation import _as_real_array, check_faces, check_vertices

__all__ = [
    "Geometry",
    "cell_columns",
    "check_points",
    "from_mesh",
    "polyline",
    "simplex_volumes",
    "spatial_order",
    "surface",
    "tetrahedra",
]

# Beyond this magnitude squared distances leave the float64 range (as for meshes).
_MAX_COORD = 1e150

@dataclass(frozen=True)
class Geometry:
    """Positions, masses and intrinsic dimension: everything the heat kernel uses.

    Attributes
    ----------
    points : (n, d) ndarray
        Positions in R^d, float64.
    mass : (n,) ndarray
        Non-negative mass (length, area, volume share) of each point; mass 0 points are
        rows of the operator but never sources of its sums.
    dim : int
        Intrinsic dimension k (1 curve, 2 surface, 3 volume); sets the kernel's
        normalization 1/(h (4πh)^{k/2}).
    spacing : float
        Typical distance between neighbouring points (mean edge length of a mesh); the
        automatic kernel width is h = (2·spacing)².
    boundary : (n,) bool ndarray or None
        Points on the boundary (polyline ends, surface boundary loops, tet mesh hull, a
        cloud's open stars); None when unknown.
    faces : Polygons or None
        The faces of a surface mesh (for normals and cotangent preconditioners), else None.
    cells : (m, k+1) ndarray or None
        Edges of a polyline or tetrahedra of a volume mesh, else None.
    boundary_share : (n,) ndarray or None
        Each point's share of the boundary's length where no cells tile the surface (a surface
        cloud: half its star's edges that no other of its triangles has), else None.
    source : str
        What the masses came from ("polyline", "surface", "tetrahedra", "point cloud").
    notes : str
        What the builder did to the input ("" when nothing), shown in the operator's repr.

    Examples
    --------
    >>> import numpy as np
    >>> g = polyline([[0, 0], [1, 0], [3, 0]], [[0, 1], [1, 2]])
    >>> g.mass.tolist(), g.dim, g.boundary.tolist()
    ([0.5, 1.5, 1.0], 1, [True, False, True])
    """

    points: np.ndarray
    mass: np.ndarray
    dim: int
    spacing: float
    boundary: np.ndarray | None = None
    faces: Polygons | None = None
    cells: np.ndarray | None = None
    boundary_share: np.ndarray | None = None
    source: str = "mesh"
    notes: str = ""  # what the builder did to the input, e.g. that it denoised a cloud
    # frames computed on first use and kept: a build asks for each once
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def n_points(self) -> int:
        return len(self.points)

    @property
    def tiled(self) -> bool:
        """Whether ``faces`` or ``cells`` tile the manifold, as a mesh's do (a point cloud's
        ``cells`` are its points' local triangles, which overlap)."""
        return (self.faces is not None or self.cells is not None) and self.source != "point cloud"

    @property
    def codim(self) -> int:
        """d − k: 1 for surfaces in R³ and plane curves, where a normal is defined."""
        return self.ambient_dim - self.dim

    def _cached(self, key: Any, make: Any) -> Any:
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]

    def copies(self) -> np.ndarray | None:
        """Each point's representative among coincident copies (an unwelded seam, a triangle
        soup: :func:`~meshlap.geometry.topology.duplicate_vertices`), computed once; None where
        there are none, and in more than three dimensions.

        Examples
        --------
        >>> import numpy as np
        >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 0, 0], [1, 1, 0]], float)
        >>> surface(V, [[0, 1, 2], [3, 4, 2]]).copies().tolist()
        [0, 1, 2, 1, 4]
        """
        return self._cached("weld", lambda: _copies(self.points))

    def _pca(self) -> tuple[np.ndarray, np.ndarray]:
        return self._cached("pca", lambda: frames.pca_frames(self.points, self.dim))

    def normals(self) -> np.ndarray | None:
        """Unit normals, consistently oriented, where the codimension is 1; else None.

        From the faces for a surface mesh in R³ (area-weighted), otherwise from local
        principal axes, oriented along the neighbour graph.
        """
        if self.codim != 1:
            return None

        def make() -> np.ndarray:
            if self.faces is not None and self.ambient_dim == 3:
                rep = self.copies()  # a copy's normal is its point's, from all the faces there
                if rep is None:
                    return frames.vertex_normals(self.points, self.faces)
                welded = Polygons(rep[self.faces.indices], self.faces.offsets)
                return frames.vertex_normals(self.points, welded)[rep]
            T, idx = self._pca()
            return frames.orient_normals(np.ascontiguousarray(T[:, :, self.dim]), idx)

        return self._cached("normals", make)

    def edges(self) -> np.ndarray:
        """Undirected neighbour edges (each once): the cells' sides, or nearest neighbours."""

        def make() -> np.ndarray:
            if self.faces is not None:
                e = self.faces.edges()
            elif self.tiled:
                c = self.cells.shape[1]
                e = np.concatenate([self.cells[:, [i, j]] for i in range(c) for j in range(i + 1, c)])
            else:
                return frames.knn_edges(self._pca()[1][:, :9])
            e = np.sort(e, axis=1)
            e = e[e[:, 0] != e[:, 1]].astype(np.int64)
            # one int64 key per edge, each once, sorted: the rows' lexicographic order
            n = self.n_points
            key = key_set(e[:, 0] * n + e[:, 1])
            return np.column_stack([key // n, key % n])

        return self._cached("edges", make)

    def boundary_samples(self, radius: float, cells: np.ndarray | None = None
                         ) -> tuple[np.ndarray, np.ndarray] | None:
        """Samples of the boundary and the outward conormal there, spaced for the cut-off
        ``radius`` (see :mod:`meshlap.geometry.frames`); None without a boundary. ``cells``:
        triangles or segments whose boundary to sample instead of the geometry's own (a pencil's
        welded cells, on which a seam between copies is no boundary)."""
        step = max(radius / 16, self.spacing / 4)
        if cells is not None:
            P = self.points
            samples = (frames.boundary_samples_curve(P, cells) if cells.shape[1] == 2 else
                       frames.boundary_samples_surface(P, check_faces(cells, self.n_points), step))
            return samples if len(samples[0]) else None

        def make() -> tuple[np.ndarray, np.ndarray] | None:
            P = self.points
            if self.boundary is None or not self.boundary.any():
                return None
            if self.faces is not None:
                return frames.boundary_samples_surface(P, self.faces, step, self.copies())
            if self.dim == 1 and self.cells is not None:
                return frames.boundary_samples_curve(P, self.cells, self.copies())
            if self.dim == 3 and self.tiled:
                return None if P.shape[1] > 3 else frames.boundary_samples_volume(P, self.cells, step,
                                                                                  self.copies())
            T, idx = self._pca()
            return frames.boundary_samples_cloud(P, self.boundary, T, idx, self.dim)

        return self._cached(("boundary samples", radius), make)

    def boundary_frames(self, radius: float) -> frames.BoundaryFrames:
        """``(band, b, ν)`` for the points within ``radius`` of the boundary (see
        :mod:`meshlap.geometry.frames`); None without a boundary."""

        def make() -> frames.BoundaryFrames:
            samples = self.boundary_samples(radius)
            return None if samples is None else frames.frames_from_samples(self.points, *samples, radius)

        return self._cached(("boundary", radius), make)

    @property
    def ambient_dim(self) -> int:
        return self.points.shape[1]

    @property
    def default_h(self) -> float:
        """The automatic kernel width h = (2·spacing)² (:func:`~meshlap.geometry.mass.paper_width`)."""
        return paper_width(self.spacing)


def check_points(P: Any, name: str = "P") -> np.ndarray:
    """Return points as a C-contiguous float64 (n, d) array, any d ≥ 1.

    Raises :class:`~meshlap.validation.MeshError` for other shapes, an empty array,
    non-numeric dtypes, NaN or infinite coordinates and magnitudes whose squares overflow.

    Examples
    --------
    >>> check_points([[0, 1, 2, 3]]).shape
    (1, 4)
    """
    a = _as_real_array(P, name)
    if a.dtype.kind == "b":
        raise MeshError(f"{name} must hold coordinates; got a boolean array")
    if a.ndim != 2 or a.shape[1] < 1:
        raise MeshError(f"{name} must have shape (n, d), one row per point; got {a.shape}")
    if a.shape[0] == 0:
        raise MeshError(f"{name} is empty: there are no points")
    a = np.ascontiguousarray(a, dtype=np.float64)
    bad = ~np.isfinite(a)
    if bad.any():
        where = [int(i) for i in np.argwhere(bad)[0]]
        raise MeshError(f"{name} has {int(bad.sum())} NaN or infinite coordinate(s), first at {name}{where}")
    big = float(np.abs(a).max())
    if big > _MAX_COORD:
        raise MeshError(f"{name} has coordinates up to {big:.3g}: squared distances would overflow "
                        "float64; rescale the points")
    return a


def simplex_volumes(P: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """k-dimensional volume of each simplex (k + 1 corners) in any ambient dimension.

    The Gram determinant of the edge vectors from the first corner: sqrt(det(EᵀE)) / k!.

    Examples
    --------
    >>> import numpy as np
    >>> P = np.array([[0, 0, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]], float)
    >>> simplex_volumes(P, np.array([[0, 1, 2, 3]])).round(6).tolist()
    [0.166667]
    """
    k = cells.shape[1] - 1
    E = P[cells[:, 1:]] - P[cells[:, :1]]  # (m, k, d)
    G = np.einsum("mid,mjd->mij", E, E)
    return np.sqrt(np.maximum(np.linalg.det(G), 0.0)) / math.factorial(k)


def _cells(C: Any, n: int, corners: int, name: str) -> np.ndarray:
    a = _as_real_array(C, name)
    if a.ndim != 2 or a.shape[1] != corners:
        raise MeshError(f"{name} must have shape (m, {corners}); got {a.shape}")
    if a.shape[0] == 0:
        raise MeshError(f"{name} is empty: there are no cells")
    if a.dtype.kind == "f":
        if not np.isfinite(a).all() or np.any(a != np.round(a)):
            raise MeshError(f"{name} must hold integer vertex indices")
    a = a.astype(np.int64)
    if a.min() < 0 or a.max() >= n:
        bad = np.argwhere((a < 0) | (a >= n))[0]
        raise MeshError(f"{name} refers to vertex {int(a[tuple(bad)])} in cell {int(bad[0])}, but vertex "
                        f"indices must lie in [0, {n - 1}] for {n} vertices")
    return np.ascontiguousarray(a)


def _lumped(n: int, cells: np.ndarray, measure: np.ndarray) -> np.ndarray:
    share = np.repeat(measure / cells.shape[1], cells.shape[1])
    return np.bincount(cells.reshape(-1), weights=share, minlength=n)


def _mean_cell_edge(P: np.ndarray, cells: np.ndarray) -> float:
    c = cells.shape[1]
    pairs = [(i, j) for i in range(c) for j in range(i + 1, c)]
    lengths = [np.linalg.norm(P[cells[:, i]] - P[cells[:, j]], axis=1) for i, j in pairs]
    return float(np.mean(lengths))


def _copies(P: np.ndarray) -> np.ndarray | None:
    if P.shape[1] > 3:
        return None
    rep = _duplicate_rep(np.pad(P, ((0, 0), (0, 3 - P.shape[1]))), DUPLICATE_RTOL)
    return None if bool((rep == np.arange(len(rep))).all()) else rep


def _welded(geo: Geometry, keys: np.ndarray) -> Geometry:
    # the boundary on the welded sub-cells (rows of keys): a seam between copies is none; the
    # copies are looked for only where the sub-cells as given leave a boundary
    if geo.boundary.any() and (rep := geo.copies()) is not None:
        k = np.sort(rep[keys], axis=1)
        k = k[np.all(k[:, 1:] != k[:, :-1], axis=1)]  # those welding collapses
        geo.boundary[:] = _once(k, geo.n_points)[rep]
    return geo


def _once(keys: np.ndarray, n: int) -> np.ndarray:
    # vertices of the sorted sub-cells (rows of keys) that occur exactly once
    srt = np.sort(keys, axis=1)
    flag = np.zeros(n, dtype=bool)
    c = srt.shape[1]
    if float(n) ** c >= 2.0**63:  # the rows' digits in base n do not fit in an int64
        uniq, counts = np.unique(srt, axis=0, return_counts=True)
        flag[uniq[counts == 1].reshape(-1)] = True
        return flag
    # each row as one int64 (its digits in base n), sorted: 14x faster than np.unique over
    # rows (0.048 s against 0.0035 s for a 16k sphere's edges, issue 19)
    code = srt[:, 0].astype(np.int64)
    for i in range(1, c):
        code = code * n + srt[:, i]
    uniq, counts = np.unique(code, return_counts=True)
    code = uniq[counts == 1]
    for _ in range(c):
        flag[code % n] = True
        code //= n
    return flag


def _nonempty(mass: np.ndarray, what: str, P: np.ndarray) -> None:
    if not mass.any():
        n, d = P.shape
        hint = f" (V has shape {P.shape}: the transpose of what is expected?)" if n <= d else ""
        raise MeshError(f"every {what} has zero {'area' if what == 'face' else 'measure'}: there is "
                        f"nothing to integrate over{hint}")


def polyline(V: Any, E: Any) -> Geometry:
    """A curve from its vertices and edges: k = 1, m_p = Σ_{e∋p} length(e) / 2.

    Parameters
    ----------
    V : (n, d) array_like
        Vertex positions, any d ≥ 1.
    E : (m, 2) array_like
        Edges as vertex index pairs.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 2 * np.pi, 100, endpoint=False)
    >>> V = np.column_stack([np.cos(t), np.sin(t)])
    >>> E = np.column_stack([np.arange(100), (np.arange(100) + 1) % 100])
    >>> round(float(polyline(V, E).mass.sum()), 4)       # the perimeter of the 100-gon
    6.2822
    """
    P = check_points(V, "V")
    cells = _cells(E, len(P), 2, "E")
    lengths = simplex_volumes(P, cells)
    mass = _lumped(len(P), cells, lengths)
    _nonempty(mass, "edge", P)
    return _welded(Geometry(P, mass, 1, float(lengths.mean()), boundary=_once(cells.reshape(-1, 1), len(P)),
                            cells=cells, source="polyline"), cells.reshape(-1, 1))


def tetrahedra(V: Any, T: Any) -> Geometry:
    """A volume from its vertices and tetrahedra: k = 3, m_p = Σ_{T∋p} Volume(T) / 4.

    Parameters
    ----------
    V : (n, d) array_like
        Vertex positions, d ≥ 3.
    T : (m, 4) array_like
        Tetrahedra as vertex index quadruples (any orientation).

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    >>> g = tetrahedra(V, [[0, 1, 2, 3]])
    >>> round(float(g.mass.sum()), 6), int(g.boundary.sum())
    (0.166667, 4)
    """
    P = check_points(V, "V")
    if P.shape[1] < 3:
        raise MeshError(f"tetrahedra need vertices in 3 or more dimensions; V has shape {P.shape}")
    cells = _cells(T, len(P), 4, "T")
    vol = simplex_volumes(P, cells)
    mass = _lumped(len(P), cells, vol)
    _nonempty(mass, "tetrahedron", P)
    tris = cells[:, [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]]].reshape(-1, 3)
    return _welded(Geometry(P, mass, 3, _mean_cell_edge(P, cells), boundary=_once(tris, len(P)),
                            cells=cells, source="tetrahedra"), tris)


def _ambient(V: Any) -> int:
    # the number of columns of V if it is a 2-D array; 3 otherwise, so that the mesh checks
    # report what is wrong with it
    try:
        a = np.asarray(V)
    except (ValueError, TypeError):
        return 3
    return int(a.shape[1]) if a.ndim == 2 else 3


def surface(V: Any, F: Any) -> Geometry:
    """A surface mesh with faces of any size: k = 2, m_p = Σ_{t∋p} Area(t) / #t.

    In R² and R³ this is today's mesh path (libigl areas, messy-mesh warnings); in higher
    dimensions polygons are fan-triangulated and measured by their Gram determinants.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    >>> surface(V, [[0, 1, 2, 3]]).mass.tolist()
    [0.25, 0.25, 0.25, 0.25]
    """
    if _ambient(V) <= 3:
        P = check_vertices(V)
        faces = check_faces(F, len(P))
        areas = _face_areas(P, faces)
        mass = _vertex_mass(P, faces, areas)
        _nonempty(mass, "face", P)
        mean_edge = _mean_edge_length(P, faces)
        warn_if_messy(P, faces, areas, mean_edge)
    else:
        P = check_points(V, "V")
        faces = check_faces(F, len(P))
        tris = faces.triangles()
        tri_area = simplex_volumes(P, tris)
        face_of_tri = np.repeat(np.arange(faces.n_faces), faces.sizes - 2)
        mass = _vertex_mass(P, faces, np.bincount(face_of_tri, tri_area, minlength=faces.n_faces))
        _nonempty(mass, "face", P)
        e = faces.edges()
        mean_edge = float(np.linalg.norm(P[e[:, 0]] - P[e[:, 1]], axis=1).mean())
    e = np.sort(faces.edges(), axis=1)
    return _welded(Geometry(P, mass, 2, mean_edge, boundary=_once(e, len(P)), faces=faces,
                            source="surface"), e)


def _tetrahedral(V: Any, F: np.ndarray) -> bool:
    # (m, 4) cells are tetrahedra when most of them meet another across a triangle with the two
    # fourth corners on opposite sides of it, as the cells of a tetrahedral mesh do. Two quads of a
    # surface share at most an edge (no triangle comes twice: the common case ends there); copies
    # of one quad share their corners (the same side).
    P = check_points(V, "V")
    n = len(P)
    if P.shape[1] != 3 or len(F) < 2 or F.min() < 0 or F.max() >= n:
        return False
    facet = np.sort(np.stack([np.delete(F, c, axis=1) for c in range(4)], axis=1), axis=2).reshape(-1, 3)
    if n < 2**21:  # a triangle as one integer
        key = (facet[:, 0] * n + facet[:, 1]) * n + facet[:, 2]
        _, inverse, count = np.unique(key, return_inverse=True, return_counts=True)
    else:
        _, inverse, count = np.unique(facet, axis=0, return_inverse=True, return_counts=True)
    twice = np.flatnonzero(count[inverse.ravel()] == 2)
    if not len(twice):
        return False
    a, b, c = (P[facet[twice, j]] for j in range(3))
    apex = F.ravel()[twice]  # the corner opposite facet c of cell i is F[i, c]
    side = np.sign(np.einsum("ij,ij->i", np.cross(b - a, c - a), P[apex] - a))
    other = np.zeros(len(count))
    np.add.at(other, inverse.ravel()[twice], side)  # the two sides cancel when opposite
    meets = np.zeros(len(facet), dtype=bool)
    meets[twice] = (other[inverse.ravel()[twice]] == 0) & (side != 0)
    return bool(np.count_nonzero(meets.reshape(-1, 4).any(axis=1)) * 2 >= len(F))


def cell_columns(F: Any) -> int | None:
    """Corners per cell when ``F`` is a rectangular (m, c) array or list, else None.

    Examples
    --------
    >>> cell_columns([[0, 1], [1, 2]]), cell_columns([[0, 1, 2], [0, 2, 3, 4]])
    (2, None)
    """
    if isinstance(F, (Polygons, str, bytes)):
        return None
    try:
        a = np.asarray(F)
    except (ValueError, TypeError):  # ragged lists of polygons
        return None
    return int(a.shape[1]) if a.ndim == 2 and a.dtype != object else None


def from_mesh(V: Any, F: Any, k: int | None = None) -> Geometry:
    """The geometry of a mesh: edges (k = 1), polygons (k = 2) or tetrahedra (k = 3).

    Parameters
    ----------
    V : (n, d) array_like
        Vertex positions.
    F : (m, c) array_like, list of polygons or Polygons
        Cells. Without ``k``: c = 2 edges, c ≥ 3 and lists of polygons faces. A (m, 4)
        array is tetrahedra when most cells meet another across a triangle from its other side,
        else quads.
    k : {1, 2, 3}, optional
        Intrinsic dimension, to read (m, 4) cells one way or to check the cells.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    >>> from_mesh(V, [[0, 1, 2, 3]], k=3).dim
    3
    """
    if k is not None and (isinstance(k, bool) or k not in (1, 2, 3)):
        raise MeshError(f"k must be 1 (curve), 2 (surface) or 3 (volume) for a mesh; got {k!r}")
    cols = cell_columns(F)
    if k is None:
        k = 1 if cols == 2 else 2
        if cols == 4 and _tetrahedral(V, np.asarray(F, dtype=np.int64)):
            k = 3
    if k == 1:
        return polyline(V, F)
    if k == 3:
        return tetrahedra(V, F)
    if cols == 2:
        raise MeshError("F has 2 columns (edges) but k=2 asks for a surface; pass k=1 for a curve")
    return surface(V, F)


def spatial_order(points: np.ndarray) -> np.ndarray:
    """A permutation that puts near points near each other (Morton order on a 1024³ grid).

    In that order the rows of a kernel operator that are close in memory hold nearly the
    same columns, so a block product reads the block from cache: on a random 16,000-vertex
    sphere, whose vertex numbers are random in space, the 36-column product takes half the time
    (:mod:`meshlap.spectral`).

    Examples
    --------
    >>> P = np.array([[1.0, 1, 0], [0, 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> spatial_order(P).tolist()
    [1, 2, 3, 0]
    """
    X = np.zeros((len(points), 3))
    X[:, :min(3, points.shape[1])] = points[:, :3]
    lo = X.min(axis=0)
    span = max(float((X.max(axis=0) - lo).max()), 1e-300)
    q = np.minimum((X - lo) / span * 1024, 1023).astype(np.int64)
    code = np.zeros(len(X), dtype=np.int64)
    for b in range(10):
        for a in range(3):
            code |= ((q[:, a] >> b) & 1) << (3 * b + a)
    return np.argsort(code, kind="stable")
