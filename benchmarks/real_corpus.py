"""The real-mesh corpus of bench_real.py: reading, welding, refining, and the refined-FEM reference.

The corpus files are not in the repository (they belong to their authors); ``corpus.toml`` beside
this file lists each one with its source, commit, licence and sha256, and ``build_corpus.py``
writes them from clones of the source repositories. The reference spectrum of a mesh is linear
FEM (P1 stiffness, consistent mass) on its midpoint refinements, Richardson-extrapolated.

>>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0]])
>>> Vr, Cr = refine(V, np.array([[0, 1, 2]]), 1)
>>> Vr.shape, Cr.shape
((6, 3), (4, 3))
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, dijkstra
from scipy.sparse.linalg import eigsh
from scipy.spatial import cKDTree

MANIFEST = Path(__file__).resolve().parent / "corpus.toml"
#: Vertices closer than this fraction of the bounding-box diagonal are one vertex (as meshlap's
#: topology.DUPLICATE_RTOL).
WELD_RTOL = 1e-10
#: Largest vertex count of the finest refinement: beyond it the reference uses one level less.
FINEST_MAX = {3: 400_000, 4: 120_000}


@dataclass
class Mesh:
    """A corpus mesh as published (``V``, ``faces``: a list of polygons, or (m, 4) tetrahedra)
    and welded (``Vw``, ``Cw``: triangles or tetrahedra, duplicates merged, unreferenced vertices
    and collapsed cells dropped)."""

    V: np.ndarray
    faces: list[np.ndarray] | np.ndarray
    Vw: np.ndarray
    Cw: np.ndarray

    @property
    def tet(self) -> bool:
        return self.Cw.shape[1] == 4


def corpus_dir(arg: str | None = None) -> Path:
    """The corpus folder: ``arg``, else $MESHLAP_CORPUS, else benchmarks/corpus (git ignores it)."""
    if arg:
        return Path(arg)
    if os.environ.get("MESHLAP_CORPUS"):
        return Path(os.environ["MESHLAP_CORPUS"])
    return Path(__file__).resolve().parent / "corpus"


def manifest() -> list[dict]:
    """The corpus entries of corpus.toml, in order."""
    import tomllib  # Python 3.11+, as the benchmarks

    with open(MANIFEST, "rb") as fh:
        return tomllib.load(fh)["mesh"]


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def read(path: Path, fmt: str = "") -> tuple[np.ndarray, list[np.ndarray] | np.ndarray]:
    """Vertices and cells of a mesh file as published: tetrahedra as an (m, 4) array if it has
    any, else its polygons (triangles, quads, n-gons) as a list of index arrays. ``fmt``
    ``"lapy-tet"``: LaPy's VTK files, whose 4-gons are tetrahedra."""
    if fmt == "lapy-tet":
        from lapy import TetMesh

        t = TetMesh.read_vtk(str(path))
        return np.asarray(t.v, dtype=np.float64), np.asarray(t.t, dtype=np.int64)
    suffix = path.suffix.lower()
    if suffix in (".obj", ".off"):
        return _read_polygons(path)
    if suffix in (".vtk", ".vtp", ".ply", ".stl"):  # VTK's readers (STL: coincident points merged)
        import pyvista as pv

        pd = pv.read(str(path))
        return np.asarray(pd.points, dtype=np.float64), [np.asarray(f, np.int64) for f in pd.irregular_faces]
    import meshio  # MEDIT .mesh, Gmsh .msh

    m = meshio.read(str(path))
    tets = [c.data for c in m.cells if c.type == "tetra"]
    if not tets:
        raise ValueError(f"{path.name}: no tetrahedra")
    return np.asarray(m.points, dtype=np.float64), np.concatenate(tets).astype(np.int64)


def _read_polygons(path: Path) -> tuple[np.ndarray, list[np.ndarray]]:
    # OBJ (v and f lines, 1-based or negative indices, "i/t/n" corners) or OFF, polygons kept
    lines = path.read_text(errors="replace").splitlines()
    if path.suffix.lower() == ".off":
        words = " ".join(ln.split("#")[0] for ln in lines).split()
        start = 1 if words[0].upper().endswith("OFF") else 0
        nv, nf = int(words[start]), int(words[start + 1])
        at = start + 3
        V = np.array(words[at:at + 3 * nv], dtype=np.float64).reshape(nv, 3)
        at += 3 * nv
        faces = []
        for _ in range(nf):
            c = int(words[at])
            faces.append(np.array(words[at + 1:at + 1 + c], dtype=np.int64))
            at += 1 + c  # OFF colours after a face's indices are not supported
        return V, faces
    verts, faces = [], []
    for ln in lines:
        w = ln.split()
        if not w:
            continue
        if w[0] == "v":
            verts.append([float(x) for x in w[1:4]])
        elif w[0] == "f":
            idx = np.array([int(c.split("/")[0]) for c in w[1:]], dtype=np.int64)
            faces.append(np.where(idx < 0, len(verts) + idx, idx - 1))
    return np.array(verts, dtype=np.float64), faces


def triangulate(faces: list[np.ndarray] | np.ndarray) -> np.ndarray:
    """Fan triangulation of polygons (triangles unchanged)."""
    if isinstance(faces, np.ndarray):
        return faces
    tris = [np.column_stack([np.full(len(f) - 2, f[0]), f[1:-1], f[2:]]) for f in faces]
    return np.concatenate(tris)


def weld(V: np.ndarray, C: np.ndarray, rtol: float = WELD_RTOL) -> tuple[np.ndarray, np.ndarray]:
    """Merge vertices within ``rtol`` of the bounding-box diagonal, drop cells that collapse
    (tetrahedra also where flat: 10⁻¹² of their longest edge cubed, the zero-volume pieces a
    degenerate hexahedron splits into) and vertices no cell uses."""
    one = _coincident(V, rtol)
    C = C if one is None else one[C]
    s = np.sort(C, axis=1)
    C = C[np.all(s[:, 1:] != s[:, :-1], axis=1)]
    if C.shape[1] == 4:
        E = V[C[:, 1:]] - V[C[:, :1]]
        sides = V[C[:, [1, 2, 3, 2, 3, 3]]] - V[C[:, [0, 0, 0, 1, 1, 2]]]
        longest = np.linalg.norm(sides, axis=2).max(axis=1)
        C = C[np.abs(np.linalg.det(E)) > 1e-12 * longest**3]
    used, C = np.unique(C, return_inverse=True)
    return V[used], C.reshape(-1, s.shape[1])


def load(path: Path, fmt: str = "") -> Mesh:
    V, faces = read(path, fmt)
    Vw, Cw = weld(V, triangulate(faces))
    return Mesh(V, faces, Vw, Cw)


def surfaces(folder: Path, only: set[str] | frozenset[str] = frozenset()) -> Iterator[tuple[dict, Mesh]]:
    """The corpus's surface meshes in ``folder`` whose file matches corpus.toml's sha256 (those
    named in ``only``, where given), each with its manifest entry."""
    for entry in manifest():
        path = folder / entry["file"]
        if only and entry["name"] not in only or not path.exists() or sha256(path) != entry["sha256"]:
            continue
        mesh = load(path, entry["format"])
        if not mesh.tet:
            yield entry, mesh


def parts(C: np.ndarray, n: int) -> int:
    """Connected parts of the cells (vertices sharing a cell are connected)."""
    i = np.repeat(C[:, :1], C.shape[1] - 1, axis=1).ravel()
    g = sp.coo_matrix((np.ones(len(i)), (i, C[:, 1:].ravel())), shape=(n, n))
    return int(connected_components(g, directed=False)[0])


def mean_edge(V: np.ndarray, C: np.ndarray) -> float:
    e = np.concatenate([C[:, [a, b]] for a in range(C.shape[1]) for b in range(a + 1, C.shape[1])])
    e = np.unique(np.sort(e, axis=1), axis=0)
    return float(np.linalg.norm(V[e[:, 0]] - V[e[:, 1]], axis=1).mean())


def touching(V: np.ndarray, C: np.ndarray, neighbours: int = 16, detour: float = 4.0) -> int:
    """Vertices one of whose ``neighbours`` nearest vertices is at least ``detour`` times farther
    along the mesh's edges than through space: there the vertices alone, as a point cloud, do
    not tell the surface (two parts or sheets closer than its sampling: a limb against the body,
    boxes in contact).

    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 0.1], [1, 0, 0.1], [0, 1, 0.1]])
    >>> touching(V, np.array([[0, 1, 2], [3, 4, 5]]), neighbours=3)   # two sheets 0.1 apart
    6
    """
    e = np.concatenate([C[:, [a, b]] for a in range(C.shape[1]) for b in range(a + 1, C.shape[1])])
    e = np.unique(np.sort(e, axis=1), axis=0)
    length = np.linalg.norm(V[e[:, 0]] - V[e[:, 1]], axis=1)
    graph = sp.coo_matrix((length, (e[:, 0], e[:, 1])), shape=(len(V),) * 2).tocsr()
    dist, idx = cKDTree(V).query(V, k=min(neighbours + 1, len(V)))
    count = 0
    for start in range(0, len(V), 500):  # graph distances a chunk of sources at a time, cut off
        rows = np.arange(start, min(start + 500, len(V)))
        near = dist[rows, -1].max() * detour
        D = dijkstra(graph, directed=False, indices=rows, limit=near)
        along = D[np.arange(len(rows))[:, None], idx[rows]]
        count += int((along > detour * dist[rows]).any(axis=1).sum())
    return count


def vertex_normals(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals of a triangle mesh."""
    fn = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    N = np.zeros_like(V)
    for j in range(3):
        np.add.at(N, F[:, j], fn)
    return N / np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-300)


def refine(V: np.ndarray, C: np.ndarray, levels: int,
           project: Callable[[np.ndarray], np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Midpoint refinement ``levels`` times: each triangle into 4, each tetrahedron into 8
    (Bey's split along the 0-5 diagonal of the new octahedron). ``project`` maps the new
    vertex positions after each level (e.g. onto a sphere); by default they stay on the cells.
    A tetrahedral mesh's midpoints that coincide (within ``weld``'s tolerance) are one vertex:
    the two diagonals of a flat quadrilateral whose zero-volume tetrahedra ``weld`` dropped, each
    an edge of the cells on one side, would otherwise open a crack between the sides that the
    unrefined mesh does not have (notch_stress: 14,237 vertices of its first refinement). A
    surface's coincident midpoints are its own (T-junctions, overlapping sheets) and stay apart."""
    for _ in range(levels):
        d = C.shape[1]
        pairs = [(a, b) for a in range(d) for b in range(a + 1, d)]
        e = np.sort(np.concatenate([C[:, p] for p in pairs]), axis=1)
        uniq, inv = np.unique(e, axis=0, return_inverse=True)
        mid = len(V) + inv.reshape(len(pairs), len(C)).T  # mid[:, j]: midpoint of pairs[j]
        V = np.vstack([V, 0.5 * (V[uniq[:, 0]] + V[uniq[:, 1]])])
        if project is not None:
            V = project(V)
        one = _coincident(V) if d == 4 else None
        if one is not None:
            mid, C = one[mid], one[C]
        m = {p: mid[:, j] for j, p in enumerate(pairs)}
        x = [C[:, i] for i in range(d)]
        if d == 3:
            kids = [(x[0], m[0, 1], m[0, 2]), (x[1], m[1, 2], m[0, 1]), (x[2], m[0, 2], m[1, 2]),
                    (m[0, 1], m[1, 2], m[0, 2])]
        else:
            a, b, c, f, g, h = m[0, 1], m[0, 2], m[0, 3], m[1, 2], m[1, 3], m[2, 3]
            kids = [(x[0], a, b, c), (a, x[1], f, g), (b, f, x[2], h), (c, g, h, x[3]),
                    (a, b, c, g), (a, b, f, g), (b, c, g, h), (b, f, g, h)]
        C = np.concatenate([np.column_stack(k) for k in kids])
        if one is not None:
            used, C = np.unique(C, return_inverse=True)
            V, C = V[used], C.reshape(-1, d)
    return V, C


def _coincident(V: np.ndarray, rtol: float = WELD_RTOL) -> np.ndarray | None:
    # each vertex's first coincident one (within rtol of the bounding-box diagonal); None if none
    diag = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    pairs = cKDTree(V).query_pairs(rtol * diag, output_type="ndarray")
    if not len(pairs):
        return None
    n = len(V)
    _, label = connected_components(sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])),
                                                  shape=(n, n)), directed=False)
    first = np.full(label.max() + 1, n)
    np.minimum.at(first, label, np.arange(n))
    return first[label]


def p1_fem(V: np.ndarray, C: np.ndarray) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """Linear FEM stiffness K (positive semidefinite) and consistent mass M of triangles or
    tetrahedra in R³."""
    d = C.shape[1] - 1
    E = V[C[:, 1:]] - V[C[:, :1]]  # (m, d, 3) edge vectors
    G = E @ E.transpose(0, 2, 1)  # Gram matrices
    vol = np.sqrt(np.abs(np.linalg.det(G))) / (2.0 if d == 2 else 6.0)
    ok = vol > 0
    E, G, vol, C = E[ok], G[ok], vol[ok], C[ok]
    D = np.linalg.solve(G, E)  # rows: gradients of barycentrics 1..d
    grads = np.concatenate([-D.sum(axis=1, keepdims=True), D], axis=1)
    Kloc = vol[:, None, None] * (grads @ grads.transpose(0, 2, 1))
    Mloc = vol[:, None, None] * (np.ones((d + 1, d + 1)) + np.eye(d + 1)) / ((d + 1) * (d + 2))
    i = np.repeat(C, d + 1, axis=1).ravel()
    j = np.tile(C, (1, d + 1)).ravel()
    n = len(V)
    K = sp.csr_matrix((Kloc.ravel(), (i, j)), shape=(n, n))
    M = sp.csr_matrix((Mloc.ravel(), (i, j)), shape=(n, n))
    return K, M


def pencil_eigs(K: sp.spmatrix, M: sp.spmatrix, k: int) -> np.ndarray:
    """The k smallest eigenvalues of K x = λ M x (K semidefinite), by shift-invert below zero; the
    rows without mass (a vertex in no cell of positive measure: no part of the surface) left out."""
    keep = np.flatnonzero(M.diagonal() > 0)
    if len(keep) < M.shape[0]:
        K, M = sp.csr_matrix(K)[keep][:, keep], sp.csr_matrix(M)[keep][:, keep]
    scale = K.diagonal().sum() / M.diagonal().sum()
    # a fixed start: ARPACK's own depends on what ran before in the process, and 1 start in 100
    # missed a copy of the 6-fold λ = 2 of two 66-vertex spheres (tests/test_bench_real.py failed
    # one CI run so)
    v0 = np.random.default_rng(0).standard_normal(K.shape[0])
    lam = eigsh(sp.csc_matrix(K), k, sp.csc_matrix(M), sigma=-1e-6 * scale, which="LM", v0=v0,
                return_eigenvectors=False)
    return np.sort(np.maximum(lam, 0.0))


def reference(V: np.ndarray, C: np.ndarray, k: int,
              project: Callable[[np.ndarray], np.ndarray] | None = None) -> dict:
    """Linear FEM's k smallest eigenvalues on two successive midpoint refinements (levels 1
    and 2 where the finer has at most FINEST_MAX vertices, else 0 and 1) and their Richardson
    extrapolation ``(4 λ_fine - λ_coarse) / 3`` (errors O(h²)).

    Returns ``levels``, ``coarse``, ``fine``, ``ref`` and ``n_fine`` (vertices of the finer)."""
    grow = 4 if C.shape[1] == 3 else 8
    levels = (1, 2)
    if len(V) * grow**2 > FINEST_MAX[C.shape[1]]:  # a level multiplies n by about grow
        levels = (0, 1)
    Vc, Cc = refine(V, C, levels[0], project)
    Vf, Cf = refine(Vc, Cc, 1, project)
    coarse = pencil_eigs(*p1_fem(Vc, Cc), k)
    fine = pencil_eigs(*p1_fem(Vf, Cf), k)
    return {"levels": list(levels), "coarse": coarse, "fine": fine,
            "ref": (4 * fine - coarse) / 3, "n_fine": len(Vf)}


def spectrum_error(lam: np.ndarray, ref: np.ndarray, n_parts: int, count: int = 9) -> float:
    """Largest relative error of eigenvalues 1..count after the ``n_parts`` zero ones (both
    sorted ascending); inf where ``lam`` has too few."""
    lam = np.sort(np.asarray(lam))
    if len(lam) < n_parts + count or not np.all(np.isfinite(lam[:n_parts + count])):
        return float("inf")
    a = lam[n_parts:n_parts + count]
    b = np.asarray(ref)[n_parts:n_parts + count]
    return float(np.max(np.abs(a - b) / b))
