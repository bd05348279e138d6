"""What users already hold, as the builders' input: ``(points, cells, k)``.

:func:`as_geometry_input` takes a file path or an object of another library and returns
the points, the cells (None for a point cloud) and the intrinsic dimension k of the cells
(None where the builder infers it). The objects are read through their attributes only, so
none of these libraries is needed, or imported, by meshlap:

* ``trimesh.Trimesh`` and ``trimesh.PointCloud`` (``vertices``, ``faces``);
* ``pyvista.PolyData`` (``points`` and its flat ``faces`` / ``lines`` arrays) and
  ``pyvista.UnstructuredGrid`` (``points``, ``cells_dict``: tetrahedra);
* ``open3d.geometry.TriangleMesh`` (``vertices``, ``triangles``), ``TetraMesh``
  (``vertices``, ``tetras``) and ``PointCloud`` (``points``);
* ``meshio.Mesh`` (``points``, ``cells_dict``);
* ``pyvista.MultiBlock`` and ``trimesh.Scene``: their parts as one input (``combine``; the
  scene's meshes where its transforms place them), each part a part of the operator;
* pyvista's grids of hexahedra or voxels, split into tetrahedra by VTK (``triangulate``).

Cells meshlap does not take (hexahedra, wedges, ...) in a meshio mesh raise a MeshError naming
them, never dropped.

:func:`read_input` reads any file the command line takes: surface meshes, point clouds,
TetGen's ``.node``/``.ele``, legacy VTK POLYDATA and, with meshio installed (``pip install
"meshlap[io]"``), every format meshio reads (VTK, VTU, Gmsh ``.msh``, ...); VTK's XML formats
with pyvista, scene formats with trimesh.
"""

from __future__ import annotations

import contextlib
import os
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from . import _freesurfer, _meshio, _mni, _ply
from ._vtk import read_polydata
from .errors import MeshError, first_line
from .geometry import Polygons
from .geometry.validation import check_faces, check_vertices, existing_file
from .io import MESH_FORMATS, POINT_FORMATS, read_mesh, read_points, read_polyline, read_tetrahedra

__all__ = ["TETGEN_FORMATS", "as_geometry_input", "boundary_triangles", "read_input"]

#: TetGen's pair of files, read without meshio.
TETGEN_FORMATS = (".node", ".ele")

# cell type names (meshio) and VTK cell type codes (pyvista) → intrinsic dimension
_CELL_DIMS = {"tetra": 3, "triangle": 2, "quad": 2, "line": 1}
_VTK_NAMES = {10: "tetra", 5: "triangle", 9: "quad", 3: "line"}
#: cells meshlap does not take, by their dimension (meshio's names; VTK's cell type numbers below);
#: a kind named in neither table counts as a volume's, so that it is never dropped unsaid
_OTHER_DIMS = {"vertex": 0, "poly_vertex": 0, "poly_line": 1, "line3": 1, "triangle_strip": 2,
               "polygon": 2, "pixel": 2, "triangle6": 2, "quad8": 2, "quad9": 2, "voxel": 3, "hexahedron": 3,
               "wedge": 3, "pyramid": 3, "tetra10": 3, "hexahedron20": 3, "hexahedron27": 3, "wedge15": 3,
               "pyramid13": 3}
_VTK_OTHER = {1: "vertex", 2: "poly_vertex", 4: "poly_line", 21: "line3", 6: "triangle_strip", 7: "polygon",
              8: "pixel", 22: "triangle6", 23: "quad8", 28: "quad9", 11: "voxel", 12: "hexahedron",
              13: "wedge", 14: "pyramid", 24: "tetra10", 25: "hexahedron20", 29: "hexahedron27",
              26: "wedge15", 27: "pyramid13"}

GeometryInput = tuple[np.ndarray, "np.ndarray | Polygons | None", "int | None"]


def _has_faces(path: Path) -> bool:
    # a PLY file is a mesh when its header declares faces, else a point cloud
    elements = _ply.header(path.read_bytes()[:1 << 16], path.name)[1]
    return any(element == "face" and count > 0 for element, count, _ in elements)


def _obj_kind(path: Path) -> str:
    text = path.read_text(errors="replace")
    if _mni.is_mni(text):  # an MNI polygon object
        return "surface"
    keys = {ln.split(maxsplit=1)[0] for ln in text.splitlines() if ln.strip()}
    return "surface" if "f" in keys else ("polyline" if "l" in keys else "points")


def _from_cell_blocks(points: Any, blocks: dict[Any, Any], name: str) -> GeometryInput:
    # the highest-dimensional cells present: tetrahedra, else faces, else lines, else none
    named = {t if isinstance(t, str) else (_VTK_NAMES | _VTK_OTHER).get(int(t), f"VTK cell type {t}"): c
             for t, c in blocks.items()}
    P = check_vertices(np.asarray(points, dtype=np.float64), name=f"points of {name}")
    dim = max((k for kind, k in _CELL_DIMS.items() if kind in named), default=0)
    taken = max(dim, 1)  # cells below it (vertices; a volume's faces) add nothing; the rest is said
    if other := [kind for kind in named if kind not in _CELL_DIMS and _OTHER_DIMS.get(kind, 3) >= taken]:
        raise MeshError(f"{name} holds {', '.join(f'{len(named[kind]):,} {kind}' for kind in other)} cells, "
                        "which meshlap does not take: split them into tetrahedra or triangles (pyvista: "
                        "mesh.triangulate()), or pass the pyvista object itself")
    for kind, k in sorted(_CELL_DIMS.items(), key=lambda kv: -kv[1]):
        if kind in named:
            if k == 2:  # triangles and quads together as polygons
                faces = [f for key in ("triangle", "quad") if key in named
                         for f in np.asarray(named[key]).tolist()]
                return P, check_faces(faces, len(P), name=f"faces of {name}"), 2
            return P, np.asarray(named[kind]).astype(np.int64), k
    return P, None, None


def _pyvista_polys(flat: np.ndarray) -> list[list[int]]:
    # VTK's flat cell array: [n, i_1, ..., i_n, m, j_1, ...]
    out, i = [], 0
    while i < len(flat):
        n = int(flat[i])
        out.append(flat[i + 1:i + 1 + n].tolist())
        i += n + 1
    return out


def as_geometry_input(obj: Any) -> GeometryInput:
    """``(points, cells, k)`` from a path or from an object of trimesh, pyvista, open3d or meshio.

    Parameters
    ----------
    obj : str, path-like, (V, F) pair, (n, d) array or mesh object
        See the module's description for the objects understood.

    Returns
    -------
    points : (n, d) float64 ndarray
    cells : (m, c) int64 ndarray, Polygons, or None
        Faces, tetrahedra or edges; None for a point cloud.
    k : int or None
        Intrinsic dimension of the cells (3 for tetrahedra); None where the builder
        infers it (a (V, F) pair, a point cloud).

    Raises
    ------
    MeshError
        For objects that hold neither points nor vertices.

    Examples
    --------
    >>> import numpy as np
    >>> class Grid:   # stands in for a pyvista.UnstructuredGrid of one tetrahedron
    ...     points = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    ...     cells_dict = {10: np.array([[0, 1, 2, 3]])}
    >>> P, T, k = as_geometry_input(Grid())
    >>> T.tolist(), k
    ([[0, 1, 2, 3]], 3)
    """
    if isinstance(obj, (str, os.PathLike)):
        return read_input(obj)
    if isinstance(obj, tuple) and len(obj) == 2:
        return check_vertices(np.asarray(obj[0]), name="mesh vertices"), obj[1], None
    name = type(obj).__name__
    if isinstance(obj, (np.ndarray, list)):
        return np.asarray(obj, dtype=np.float64), None, None
    if hasattr(obj, "combine") and hasattr(obj, "n_blocks"):  # pyvista.MultiBlock: its blocks as one grid
        return as_geometry_input(obj.combine())
    if hasattr(obj, "geometry") and hasattr(obj, "dump"):  # trimesh.Scene: its meshes where it places them
        placed = obj.to_geometry() if hasattr(obj, "to_geometry") else obj.dump(concatenate=True)
        return as_geometry_input(placed)
    if hasattr(obj, "cast_to_unstructured_grid") and not hasattr(obj, "faces"):  # pyvista's grids
        grid = obj.cast_to_unstructured_grid()
        if {int(t) for t in grid.cells_dict} - set(_VTK_NAMES):  # hexahedra, voxels, ...: VTK splits them
            grid = grid.triangulate()
        return _from_cell_blocks(grid.points, dict(grid.cells_dict), name)
    if hasattr(obj, "points") and hasattr(obj, "cells_dict"):  # meshio.Mesh
        return _from_cell_blocks(obj.points, dict(obj.cells_dict), name)
    if hasattr(obj, "points") and hasattr(obj, "faces") and hasattr(obj, "n_points"):  # pyvista.PolyData
        faces, lines = np.asarray(obj.faces).ravel(), np.asarray(getattr(obj, "lines", [])).ravel()
        blocks: dict[str, Any] = {}
        if len(faces):
            blocks["quad"] = _pyvista_polys(faces)  # polygons of any size
        elif len(lines):
            polylines = _pyvista_polys(lines)
            blocks["line"] = [e for pl in polylines for e in zip(pl[:-1], pl[1:], strict=True)]
        if "quad" in blocks:
            P = check_vertices(np.asarray(obj.points, dtype=np.float64), name=f"points of {name}")
            return P, check_faces(blocks["quad"], len(P), name=f"faces of {name}"), 2
        return _from_cell_blocks(obj.points, blocks, name)
    if hasattr(obj, "vertices"):  # trimesh, open3d meshes, trimesh.PointCloud
        V = np.asarray(obj.vertices, dtype=np.float64)
        for attr, k in (("tetras", 3), ("faces", None), ("triangles", None)):
            cells = getattr(obj, attr, None)
            if cells is not None and len(np.asarray(cells)):
                cells = np.asarray(cells, dtype=np.int64)
                return check_vertices(V, name=f"vertices of {name}"), cells, k
        return V, None, None
    if hasattr(obj, "points"):  # open3d.geometry.PointCloud
        return np.asarray(obj.points, dtype=np.float64), None, None
    raise MeshError(f"cannot read a mesh or point cloud from a {name}: pass a file path, a (V, F) pair, "
                    "an (n, d) array, or a trimesh, pyvista, open3d or meshio object")


def read_input(path: str | os.PathLike) -> GeometryInput:
    """Read any geometry file the command line takes, as ``(points, cells, k)``.

    Surface meshes (.obj, .off, .ply with faces, .stl; FreeSurfer's ``lh.pial`` and the like, told
    by their first bytes; GIfTI .surf.gii with nibabel), point clouds (.ply without faces, .pcd,
    .xyz, .csv, .txt, .pts, .npy; an .obj without faces), curves (an .obj with only ``l``
    lines), TetGen's .node/.ele, legacy VTK POLYDATA, ASCII or binary (pyvista's ``save``; LaPy's
    tetrahedra: polygons of 4 corners spanning a volume), and with meshio installed every format
    meshio reads; VTK's XML formats (.vtp, ...) with pyvista, scenes (.glb, .gltf, .3mf, .dae) with
    trimesh. A .vtk or .vtu file that meshio cannot read, or whose cells meshlap does not take
    (hexahedra, wedges, quadratic tetrahedra), is read by pyvista where it is installed, its cells
    split into tetrahedra by VTK.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "cloud.xyz"
    >>> _ = path.write_text("0 0 0\\n1 0 0\\n0 1 0\\n")
    >>> P, cells, k = read_input(path)
    >>> P.shape, cells
    ((3, 3), None)
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in TETGEN_FORMATS:
        V, T = read_tetrahedra(path)
        return V, T, 3
    existing_file(path, "mesh" if suffix in MESH_FORMATS else
                  "point cloud" if suffix in POINT_FORMATS else "input")
    with open(path, "rb") as fh:
        if _freesurfer.is_surface(fh.read(3)):  # lh.pial, rh.white, ...: no suffix tells them
            return (*read_mesh(path), 2)
    if suffix == ".obj" and _obj_kind(path) != "surface":
        if _obj_kind(path) == "polyline":
            V, E = read_polyline(path)
            return V, E, 1
        return read_points(path), None, None
    if suffix in MESH_FORMATS and (suffix != ".ply" or _has_faces(path)):
        V, F = read_mesh(path)
        return V, F, 2
    if suffix in POINT_FORMATS:
        return read_points(path), None, None
    polydata = read_polydata(path) if suffix == ".vtk" else None  # LaPy's tetrahedra, legacy surfaces
    if polydata is not None:
        return polydata
    if suffix in _OTHER_READERS:  # formats meshio does not read
        package, reader = _OTHER_READERS[suffix]
        try:
            return reader(path)
        except ImportError:
            raise MeshError(f"{path.name}: meshlap reads {suffix} files with {package}: pip install {package}"
                            ) from None
    try:
        return _by_meshio(path)
    except (ImportError, MeshError) as exc:
        # VTK's own reader takes the files meshio cannot, and VTK splits the cells meshlap does not
        # take (hexahedra, wedges, quadratic tetrahedra) into tetrahedra, as for a pyvista object
        if suffix in (".vtk", ".vtu"):
            with contextlib.suppress(ImportError, MeshError):
                return _by_pyvista(path)
        if isinstance(exc, MeshError):
            raise
        known = ", ".join(MESH_FORMATS + POINT_FORMATS + TETGEN_FORMATS + tuple(_OTHER_READERS))
        what = suffix or "files without a suffix"
        raise MeshError(f"{path.name}: meshlap reads {known} itself; for {what} "
                        'install meshio (pip install "meshlap[io]")') from None


def _by_meshio(path: Path) -> GeometryInput:
    mesh = _meshio.read(path)
    return _from_cell_blocks(mesh.points, mesh.cells_dict, path.name)


def _by_pyvista(path: Path) -> GeometryInput:
    # VTK's own formats (.vtp XML polydata, ...), which meshio does not read
    import pyvista

    try:
        with _quiet_stderr(), warnings.catch_warnings():  # a bad file's VTK errors: logged, and warned
            warnings.simplefilter("ignore")
            mesh = pyvista.read(path)
    except Exception as exc:  # pyvista raises ValueError, IOError, VTK errors, ...
        raise MeshError(f"{path.name}: pyvista could not read it ({first_line(exc)})") from None
    if not mesh.n_points:
        raise MeshError(f"{path.name}: pyvista read no points from it")
    return as_geometry_input(mesh)


def _by_trimesh(path: Path) -> GeometryInput:
    # scene formats (.glb, .gltf, .3mf, .dae), their meshes concatenated
    import trimesh

    try:
        mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:  # trimesh raises ValueError, KeyError, NotImplementedError, ...
        raise MeshError(f"{path.name}: trimesh could not read it ({first_line(exc)})") from None
    V, F, _ = as_geometry_input(mesh)
    return V, F, None if F is None else 2  # trimesh's faces are triangles


@contextlib.contextmanager
def _quiet_stderr() -> Any:
    try:
        saved, null = os.dup(2), os.open(os.devnull, os.O_WRONLY)
    except OSError:  # no file descriptor 2 to quiet (a GUI process)
        yield
        return
    try:
        os.dup2(null, 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(null)


def _by_nibabel(path: Path) -> GeometryInput:
    # GIfTI (.surf.gii): the array of intent NIFTI_INTENT_POINTSET (1008), its triangles the one of
    # NIFTI_INTENT_TRIANGLE (1009); a .gii of other intents holds data on a surface, not the surface
    import nibabel

    arrays = {int(a.intent): a.data for a in nibabel.load(str(path)).darrays}
    if 1008 not in arrays:
        raise MeshError(f"{path.name}: a GIfTI file without a point set (NIFTI_INTENT_POINTSET): data on a "
                        "surface, not the surface; pass the .surf.gii")
    P = check_vertices(np.asarray(arrays[1008], dtype=np.float64), name=f"points of {path.name}")
    if 1009 not in arrays:
        return P, None, None
    return P, check_faces(np.asarray(arrays[1009], dtype=np.int64), len(P), name=f"faces of {path.name}"), 2


#: suffixes meshio does not read: VTK's XML formats (pyvista), scene formats (trimesh), GIfTI (nibabel)
_OTHER_READERS = {suffix: ("pyvista", _by_pyvista) for suffix in (".vtp", ".vts", ".vtr", ".vti", ".vtm")} | \
    {suffix: ("trimesh", _by_trimesh) for suffix in (".glb", ".gltf", ".3mf", ".dae")} | \
    {".gii": ("nibabel", _by_nibabel)}


def boundary_triangles(T: Any) -> np.ndarray:
    """The triangles on the hull of a tetrahedral mesh (faces of one tetrahedron only), for drawing.

    Examples
    --------
    >>> boundary_triangles([[0, 1, 2, 3]]).shape
    (4, 3)
    """
    T = np.asarray(T, dtype=np.int64)
    tri = np.concatenate([T[:, [1, 2, 3]], T[:, [0, 3, 2]], T[:, [0, 1, 3]], T[:, [0, 2, 1]]])
    _, first, count = np.unique(np.sort(tri, axis=1), axis=0, return_index=True, return_counts=True)
    return tri[np.sort(first[count == 1])]
