"""Reading meshes and saving built operators.

* :func:`read_mesh` reads OBJ, OFF, PLY and STL. OBJ and OFF go through small parsers of
  our own so that polygon faces stay polygons (the operator gives each face Area(t)/#t per
  corner, so splitting quads into triangles would change it); PLY and STL are read with
  libigl as triangles.
* :func:`read_points` reads point clouds (PLY with or without faces, XYZ/CSV/TXT columns,
  ``.npy``), :func:`read_polyline` the ``l`` lines of an OBJ file, and
  :func:`read_tetrahedra` TetGen's ``.node``/``.ele`` pair and LaPy's ``.vtk`` (other volume
  formats through meshio, when it is installed: it is optional, since meshlap needs no more).
* :func:`as_mesh` turns whatever the user holds (a path, a ``(V, F)`` pair, a
  ``trimesh.Trimesh`` or anything else with ``vertices`` and ``faces``) into ``(V, F)``.
* :func:`save_operator` / :func:`load_operator` (from :mod:`meshlap.store`) save a built
  operator to ``.npz`` and read it back bit for bit.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from . import _freesurfer, _meshio, _mni, _pcd, _ply
from ._vtk import read_polydata
from .errors import MeshError
from .geometry import Polygons
from .geometry.validation import check_faces, check_rows, check_vertices, existing_file
from .store import FORMAT_VERSION, OperatorFormatError, SavedLaplacian, load_operator, save_operator

__all__ = [
    "FORMAT_VERSION",
    "MESH_FORMATS",
    "OperatorFormatError",
    "POINT_FORMATS",
    "SavedLaplacian",
    "as_mesh",
    "load_operator",
    "parse_obj",
    "read_mesh",
    "read_points",
    "read_polyline",
    "read_tetrahedra",
    "save_operator",
    "write_mesh",
]

#: File suffixes :func:`read_mesh` understands.
MESH_FORMATS = (".obj", ".off", ".ply", ".stl")

#: File suffixes :func:`read_points` understands.
POINT_FORMATS = (".ply", ".pcd", ".xyz", ".csv", ".txt", ".pts", ".npy", ".obj", ".off")

PathLike = str | os.PathLike


def _faces_out(faces: Polygons) -> np.ndarray | Polygons:
    # One face size: a plain (m, k) array, which every library understands.
    return faces.as_array() if faces.uniform_size is not None else faces


def _polygons_from(lists: list[list[int]]) -> Polygons:
    sizes = np.fromiter((len(f) for f in lists), dtype=np.int64, count=len(lists))
    offsets = np.zeros(len(lists) + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    indices = np.fromiter((i for f in lists for i in f), dtype=np.int64, count=int(offsets[-1]))
    return Polygons(indices=indices, offsets=offsets)


def parse_obj(text: str, name: str = "<obj>") -> tuple[np.ndarray, np.ndarray | Polygons]:
    """Parse the vertices and faces of Wavefront OBJ text, keeping polygons as polygons.

    Face tokens may be ``i``, ``i/t``, ``i//n`` or ``i/t/n``; only the vertex index ``i``
    is used. Negative indices count back from the last vertex read so far, as the format
    specifies. Texture coordinates, normals, groups, materials, lines and points are
    ignored; a trailing backslash continues a line.

    Parameters
    ----------
    text : str
        The file's contents.
    name : str
        Used in error messages (usually the file name).

    Returns
    -------
    V : (n, 3) float64 ndarray
    F : (m, k) int64 ndarray, or Polygons
        An array when every face has the same number of corners, else :class:`Polygons`.

    Raises
    ------
    MeshError
        For malformed numbers, faces with fewer than 3 corners, index 0 or indices that
        refer to no vertex; the message names the line.

    Examples
    --------
    >>> V, F = parse_obj("v 0 0 0\\nv 1 0 0\\nv 1 1 0\\nv 0 1 0\\nv 2 0 0\\n"
    ...                  "f 1/1 2/2 3/3 4/4\\nf -4 -1 -3\\n")
    >>> F.sizes.tolist(), F.indices.tolist()
    ([4, 3], [0, 1, 2, 3, 1, 4, 2])
    """
    verts: list[list[float]] = []
    faces: list[list[int]] = []
    lines = text.replace("\\\r\n", " ").replace("\\\n", " ").splitlines()
    for lineno, line in enumerate(lines, start=1):
        parts = line.split()
        if not parts:
            continue
        key = parts[0]
        if key == "v":
            try:
                xyz = [float(s) for s in parts[1:4]]
            except ValueError as exc:
                raise MeshError(f"{name}, line {lineno}: bad vertex coordinate ({exc})") from exc
            if len(xyz) != 3:
                raise MeshError(f"{name}, line {lineno}: a vertex needs 3 coordinates; got {len(xyz)}")
            verts.append(xyz)
        elif key == "f":
            n = len(verts)
            face = []
            for tok in parts[1:]:
                head = tok.split("/", 1)[0]
                try:
                    i = int(head)
                except ValueError as exc:
                    raise MeshError(f"{name}, line {lineno}: bad face index {tok!r}") from exc
                j = i - 1 if i > 0 else n + i
                if i == 0 or not 0 <= j < n:
                    raise MeshError(
                        f"{name}, line {lineno}: face index {i} refers to no vertex "
                        f"({n} vertices read so far)"
                    )
                face.append(j)
            if len(face) < 3:
                raise MeshError(f"{name}, line {lineno}: a face needs at least 3 corners; got {len(face)}")
            faces.append(face)
    if not verts:
        raise MeshError(f"{name}: no vertices ('v' lines) found")
    if not faces:
        raise MeshError(f"{name}: no faces ('f' lines) found")
    return np.asarray(verts, dtype=np.float64), _faces_out(_polygons_from(faces))


def _parse_off(text: str, name: str) -> tuple[np.ndarray, np.ndarray | Polygons]:
    # Line based, so that per-face colours after the indices are simply ignored.
    lines = [ln.split("#", 1)[0].split() for ln in text.splitlines()]
    lines = [ln for ln in lines if ln]
    if not lines or lines[0][0] != "OFF":
        found = lines[0][0] if lines else "nothing"
        raise MeshError(f"{name}: not a plain OFF file (it must start with OFF; found {found!r})")
    head = lines[0][1:] or (lines[1] if len(lines) > 1 else [])
    body = lines[1:] if lines[0][1:] else lines[2:]
    try:
        nv, nf = int(head[0]), int(head[1])
        V = check_rows(body[:nv], 3, f"{name}: vertex")
        faces = [[int(t) for t in ln[1 : 1 + int(ln[0])]] for ln in body[nv : nv + nf]]
        short = next((i for i, ln in enumerate(body[nv : nv + nf]) if len(ln) <= int(ln[0])), None)
    except MeshError:  # names the row already
        raise
    except (IndexError, ValueError) as exc:
        raise MeshError(f"{name}: malformed OFF file ({exc})") from exc
    if nv == 0 or nf == 0:
        raise MeshError(f"{name}: the OFF file declares {nv} vertices and {nf} faces")
    if V.shape != (nv, 3) or len(faces) != nf:
        raise MeshError(f"{name}: truncated OFF file: expected {nv} vertices and {nf} faces")
    if short is not None:
        # a face may run over several lines (OFF is a stream of tokens): read the faces so, where
        # that uses up every token after the vertices (no per-face colours to tell apart)
        faces = _face_stream([t for ln in body[nv:] for t in ln], nf)
        if faces is None:
            raise MeshError(f"{name}: face {short} lists fewer corners than its count says")
    return V, _faces_out(check_faces(faces, nv, name=f"faces of {name}"))


def _face_stream(tokens: list[str], nf: int) -> list[list[int]] | None:
    """``nf`` faces, each its count and corners, read from a stream of tokens; None unless the
    faces use up exactly all of them."""
    faces, pos = [], 0
    try:
        for _ in range(nf):
            n = int(tokens[pos])
            if n < 1 or pos + 1 + n > len(tokens):
                return None
            faces.append([int(t) for t in tokens[pos + 1:pos + 1 + n]])
            pos += 1 + n
    except (IndexError, ValueError):
        return None
    return faces if pos == len(tokens) else None


def _parse_off_binary(data: bytes, name: str) -> tuple[np.ndarray, np.ndarray | Polygons]:
    """A binary OFF file: after the line ``OFF BINARY``, the counts (nv, nf, ne) as int32, nv
    float32 positions, then each face's count and corners as int32, in Geomview's layout (big
    endian, a colour count after each face's corners) or pmp-library's (little endian, none):
    the one whose counts fit the file's size and whose faces end where it does."""
    start = data.find(b"\n") + 1
    for order in ((">", "<") if start else ()):
        counts = np.frombuffer(data, f"{order}i4", 3, start) if len(data) >= start + 12 else None
        if counts is None or counts[0] < 1 or counts[1] < 1 or start + 12 + 12 * int(counts[0]) > len(data):
            continue
        nv, nf = int(counts[0]), int(counts[1])
        V = np.frombuffer(data, f"{order}f4", 3 * nv, start + 12).reshape(nv, 3).astype(np.float64)
        ints = np.frombuffer(data[start + 12 + 12 * nv:len(data) - (len(data) - start) % 4], f"{order}i4")
        for colours in (order == ">", order != ">"):
            faces, pos = [], 0
            while len(faces) < nf and pos < len(ints) and 0 < ints[pos] <= len(ints) - pos - 1:
                n = int(ints[pos])
                faces.append(ints[pos + 1:pos + 1 + n].astype(np.int64))
                pos += 1 + n
                if colours:
                    if pos >= len(ints) or ints[pos] < 0:
                        break
                    pos += 1 + int(ints[pos])
            if len(faces) == nf and 4 * pos == len(data) - start - 12 - 12 * nv:
                return check_vertices(V, name=f"vertices of {name}"), _faces_out(
                    check_faces(faces, nv, name=f"faces of {name}"))
    raise MeshError(f"{name}: a binary OFF file whose counts and faces do not fit its size (truncated?)")


def _suffix(path: Path, formats: Sequence[str], what: str, verb: str = "reads") -> str:
    suffix = path.suffix.lower()
    if suffix not in formats:
        raise MeshError(f"{path.name}: unknown {what} format {suffix or '(no suffix)'!r}; "
                        f"meshlap {verb} {', '.join(formats)}")
    return suffix


def read_mesh(path: PathLike, *, triangulate: bool = False) -> tuple[np.ndarray, np.ndarray | Polygons]:
    """Read a surface mesh from an OBJ, OFF, PLY or STL file, or a FreeSurfer surface.

    Parameters
    ----------
    path : str or path-like
        The file; its suffix picks the reader, except for FreeSurfer's triangle surfaces
        (``lh.pial``, ``rh.white``, ...), told by their first bytes. An ``.obj`` may be an MNI
        surface, a ``.ply`` may hold triangle strips.
    triangulate : bool, default False
        Split polygons into fans of triangles (for code that needs triangles, such as the
        cotangent Laplacian). By default OBJ, OFF and PLY polygons are kept.

    Returns
    -------
    V : (n, 3) float64 ndarray
        Vertex positions.
    F : (m, k) int64 ndarray, or Polygons
        Faces; :class:`~meshlap.Polygons` when the sizes are mixed. Both go straight into
        :func:`meshlap.laplacian`.

    Raises
    ------
    FileNotFoundError
        When the file does not exist.
    MeshError
        For unknown suffixes and files that cannot be parsed.

    Notes
    -----
    STL stores every triangle's corners separately; they are merged with libigl's
    ``remove_duplicate_vertices`` so that neighbouring triangles share vertices again.
    Vertices that no face uses are kept (they get zero mass in the operator).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "quad.obj"
    >>> _ = path.write_text("v 0 0 0\\nv 1 0 0\\nv 1 1 0\\nv 0 1 0\\nf 1/1 2/2 3/3 4/4\\n")
    >>> V, F = read_mesh(path)
    >>> V.shape, F.tolist()
    ((4, 3), [[0, 1, 2, 3]])
    """
    path = existing_file(path, "mesh")
    with open(path, "rb") as fh:
        head = fh.read(64)
    suffix = "" if _freesurfer.is_surface(head) else _suffix(path, MESH_FORMATS, "mesh")
    if not suffix:  # lh.pial, rh.white, ...: FreeSurfer's names carry no format
        V, F = _freesurfer.read(path.read_bytes(), path.name)
    elif suffix == ".off" and head.split(b"\n", 1)[0].split()[1:2] == [b"BINARY"]:
        V, F = _parse_off_binary(path.read_bytes(), path.name)
    elif suffix in (".obj", ".off"):
        try:
            text = path.read_text(encoding="utf-8", errors="replace")
        except UnicodeError as exc:  # pragma: no cover - errors="replace" makes this rare
            raise MeshError(f"{path.name}: not a text file ({exc})") from exc
        parse = _parse_off if suffix == ".off" else _mni.read if _mni.is_mni(text) else parse_obj
        V, F = parse(text, path.name)
    elif suffix == ".ply":  # meshlap's own reader: libigl's aborts the process on a file cut in its faces
        V, F = _ply.read(path.read_bytes(), path.name)
        if F is None or len(F) == 0:
            raise MeshError(f"{path.name}: a PLY file without faces (read it with read_points)")
    else:
        import igl

        try:
            V, F, _ = igl.readSTL(str(path))
            if len(F):
                V, _, _, F = igl.remove_duplicate_vertices(V, F, 0.0)
        except RuntimeError as exc:
            data = path.read_bytes()
            if data.lstrip().startswith(b"solid") and b"facet" not in data:  # libigl says "Failed to open"
                raise MeshError(f"{path.name}: an ASCII STL file without facets") from None
            raise MeshError(f"{path.name}: libigl could not read it ({exc})") from exc
        if V.size == 0 or F.size == 0:
            raise MeshError(f"{path.name}: no vertices or no faces could be read")
    V = check_vertices(V, name=f"vertices of {path.name}")
    faces = check_faces(F, len(V), name=f"faces of {path.name}")
    if triangulate:
        return V, faces.triangles()
    return V, _faces_out(faces)


def _text_columns(path: Path, columns: Any) -> np.ndarray:
    lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    rows = [ln.replace(",", " ").replace(";", " ").split() for ln in lines]
    rows = [r for r in rows if r and not r[0].startswith("#")]
    # a header line of names (x,y,z) is skipped
    if rows:
        try:
            float(rows[0][0])
        except ValueError:
            rows = rows[1:]
    if not rows:
        raise MeshError(f"{path.name}: no rows of numbers")
    width = min(len(r) for r in rows)
    try:
        table = np.array([r[:width] for r in rows], dtype=np.float64)
    except ValueError as exc:
        raise MeshError(f"{path.name}: a row holds something that is not a number ({exc})") from exc
    cols = list(range(min(3, width))) if columns is None else list(columns)
    if max(cols) >= width:
        raise MeshError(f"{path.name}: asked for columns {cols} but rows have {width} values")
    return table[:, cols]


def read_points(path: PathLike, *, columns: Any = None) -> np.ndarray:
    """Read a point cloud: the positions of a PLY, PCD, XYZ/CSV/TXT/PTS, NPY, OBJ or OFF file.

    Parameters
    ----------
    path : str or path-like
        The file; its suffix picks the reader. PLY may be ASCII or binary, with or without
        faces (only the vertices are read). PCD (the Point Cloud Library's) may be ascii, binary
        or binary_compressed; its points without a return (NaN) are left out. Text files hold one
        point per line, separated
        by spaces, commas or semicolons; a first line of column names and ``#`` comments
        are skipped. ``.npy`` holds an (n, d) array.
    columns : sequence of int, optional
        Text columns to read (default the first three; e.g. ``range(4)`` for R⁴ points).

    Returns
    -------
    (n, d) float64 ndarray
        For :func:`meshlap.point_cloud_laplacian`.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "cloud.csv"
    >>> _ = path.write_text("x,y,z,intensity\\n0,0,0,7\\n1,0,0,7\\n0,1,0,7\\n")
    >>> read_points(path).shape
    (3, 3)
    """
    from .geometry import check_points

    path = existing_file(path, "point cloud")
    suffix = _suffix(path, POINT_FORMATS, "point cloud")
    if suffix == ".ply":
        P = _ply.read(path.read_bytes(), path.name, faces=False)[0]
    elif suffix == ".pcd":
        P = _pcd.read(path.read_bytes(), path.name)
    elif suffix == ".npy":
        try:
            P = np.load(path, allow_pickle=False)
        except (ValueError, OSError, EOFError) as exc:
            raise MeshError(f"{path.name}: not a NumPy .npy file of numbers") from exc
    elif suffix == ".off":
        P = read_mesh(path)[0]
    elif suffix == ".obj":  # the 'v' lines, with or without faces
        text = path.read_text(encoding="utf-8", errors="replace")
        if _mni.is_mni(text):  # an MNI surface shares the suffix
            P = _mni.read(text, path.name)[0]
        else:
            rows = [ln.split()[1:4] for ln in text.splitlines() if ln.startswith("v ")]
            if not rows:
                raise MeshError(f"{path.name}: no 'v' lines, so no points: not a Wavefront OBJ file")
            P = check_rows(rows, 3, f"{path.name}: vertex")
    else:
        P = _text_columns(path, columns)
    return check_points(P, name=f"points of {path.name}")


def read_polyline(path: PathLike) -> tuple[np.ndarray, np.ndarray]:
    """Read the curves of an OBJ file: its ``v`` vertices and ``l`` lines as (m, 2) edges.

    A line ``l a b c`` is the polyline a-b-c; ``l 1 2 3 1`` closes a loop. Negative indices
    count back from the last vertex read, as for faces.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "tri.obj"
    >>> _ = path.write_text("v 0 0 0\\nv 1 0 0\\nv 0 1 0\\nl 1 2 3 1\\n")
    >>> read_polyline(path)[1].tolist()
    [[0, 1], [1, 2], [2, 0]]
    """
    path = existing_file(path, "polyline")
    verts, edges = [], []
    for lineno, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            verts.append(parts[1:4])
        elif parts[0] == "l":
            n = len(verts)
            try:
                idx = [int(t.split("/", 1)[0]) for t in parts[1:]]
            except ValueError as exc:
                raise MeshError(f"{path.name}, line {lineno}: bad line index ({exc})") from exc
            idx = [i - 1 if i > 0 else n + i for i in idx]
            if len(idx) < 2 or min(idx) < 0 or max(idx) >= n:
                raise MeshError(f"{path.name}, line {lineno}: a line needs 2 or more indices of "
                                f"vertices read so far ({n})")
            edges += list(zip(idx[:-1], idx[1:], strict=True))
    if not verts or not edges:
        raise MeshError(f"{path.name}: no vertices or no 'l' lines found")
    try:
        V = np.array(verts, dtype=np.float64)
    except ValueError as exc:
        raise MeshError(f"{path.name}: bad vertex coordinate ({exc})") from exc
    return check_vertices(V, name=f"vertices of {path.name}"), np.array(edges, dtype=np.int64)


def read_tetrahedra(path: PathLike) -> tuple[np.ndarray, np.ndarray]:
    """Read a tetrahedral mesh: TetGen's ``.node`` + ``.ele`` pair, LaPy's ``.vtk`` (legacy
    POLYDATA whose polygons are tetrahedra, as ``lapy.TetMesh.write_vtk`` writes them), or
    any volume format that meshio reads (``.vtk``, ``.vtu``, ``.msh``, ...) when it is installed.

    Pass either file of the TetGen pair. Returns ``(V, T)`` for
    ``meshlap.laplacian(V, T, k=3)``.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "t.node").write_text("4 3 0 0\\n1 0 0 0\\n2 1 0 0\\n3 0 1 0\\n4 0 0 1\\n")
    >>> _ = (d / "t.ele").write_text("1 4 0\\n1 1 2 3 4\\n")
    >>> read_tetrahedra(d / "t.ele")[1].tolist()
    [[0, 1, 2, 3]]
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in (".node", ".ele"):
        node, ele = path.with_suffix(".node"), path.with_suffix(".ele")
        for f in (node, ele):
            if not f.is_file():
                raise FileNotFoundError(f"no such TetGen file: {f}")

        def table(f: Path, width: int) -> np.ndarray:
            rows = [ln.split("#", 1)[0].split() for ln in f.read_text(errors="replace").splitlines()]
            rows = [r for r in rows if r]
            if not rows:
                raise MeshError(f"{f.name}: an empty TetGen file")
            try:
                count = int(rows[0][0])
            except ValueError as exc:
                raise MeshError(f"{f.name}: malformed TetGen header ({exc})") from exc
            table = check_rows(rows[1:count + 1], width, f"{f.name}: row")
            if count < 1 or table.shape != (count, width):
                raise MeshError(f"{f.name}: the header announces {count} rows of {width} numbers; "
                                f"found {len(rows) - 1} rows")
            return table

        nodes, eles = table(node, 4), table(ele, 5)
        first = int(nodes[0, 0])  # TetGen numbers from 0 or from 1
        V = nodes[:, 1:4]
        T = eles[:, 1:5].astype(np.int64) - first
        bad = np.flatnonzero(((T < 0) | (T >= len(V))).any(axis=1))
        if len(bad):
            raise MeshError(f"{ele.name}: tetrahedron {int(eles[bad[0], 0])} refers to a node that does not "
                            f"exist (the nodes are numbered {first} to {len(V) - 1 + first})")
        return check_vertices(V, name=f"vertices of {node.name}"), T
    existing_file(path, "mesh")
    polydata = read_polydata(path) if suffix == ".vtk" else None
    if polydata is not None:  # LaPy's TetMesh.write_vtk: POLYGONS of 4 corners
        if polydata[2] != 3:
            raise MeshError(f"{path.name}: no tetrahedra in the file (its POLYGONS are a surface's)")
        return check_vertices(polydata[0], name=f"vertices of {path.name}"), polydata[1]
    try:
        mesh = _meshio.read(path)
    except ImportError as exc:
        raise MeshError(f"{path.name}: meshlap reads TetGen .node/.ele and LaPy's .vtk itself; for "
                        f"{suffix} files install meshio (pip install meshio)") from exc
    T = [c.data for c in mesh.cells if c.type == "tetra"]
    if not T:
        raise MeshError(f"{path.name}: no tetrahedra in the file")
    return check_vertices(mesh.points[:, :3], name=f"vertices of {path.name}"), np.vstack(T).astype(np.int64)


def write_mesh(path: PathLike, V: Any, F: Any) -> Path:
    """Write a mesh; OBJ and OFF keep polygons, PLY and STL need triangles.

    Examples
    --------
    >>> import meshlap, tempfile, pathlib
    >>> V, F = meshlap.shapes.sphere(50, seed=0)
    >>> p = write_mesh(pathlib.Path(tempfile.mkdtemp()) / "s.obj", V, F)
    >>> read_mesh(p)[1].shape
    (96, 3)
    """
    path = Path(path)
    V = check_vertices(V)
    faces = check_faces(F, len(V))
    suffix = _suffix(path, MESH_FORMATS, "mesh", verb="writes")
    if suffix in (".obj", ".off"):
        sizes = faces.sizes
        split = np.split(faces.indices, faces.offsets[1:-1])
        with open(path, "w", encoding="utf-8") as fh:
            if suffix == ".off":
                fh.write(f"OFF\n{len(V)} {faces.n_faces} 0\n")
                fh.writelines(f"{x!r} {y!r} {z!r}\n" for x, y, z in V.tolist())
                fh.writelines(f"{k} {' '.join(map(str, f.tolist()))}\n"
                              for k, f in zip(sizes, split, strict=True))
            else:
                fh.write("# written by meshlap\n")
                fh.writelines(f"v {x!r} {y!r} {z!r}\n" for x, y, z in V.tolist())
                fh.writelines(f"f {' '.join(str(i + 1) for i in f.tolist())}\n" for f in split)
        return path
    if faces.uniform_size != 3:
        raise MeshError(f"{suffix} files hold triangles only; write polygons as .obj or .off")
    import igl

    igl.write_triangle_mesh(str(path), V, faces.as_array())
    return path


def as_mesh(mesh: Any) -> tuple[np.ndarray, np.ndarray | Polygons]:
    """``(V, F)`` from a path, a ``(V, F)`` pair or an object with ``vertices`` and ``faces``.

    Objects such as ``trimesh.Trimesh`` are used through their attributes only, so
    trimesh is not needed (or imported) here. Open3D's ``triangles`` attribute works too.

    Examples
    --------
    >>> import numpy as np
    >>> class Tri:   # stands in for trimesh.Trimesh
    ...     vertices = np.eye(3)
    ...     faces = np.array([[0, 1, 2]])
    >>> V, F = as_mesh(Tri())
    >>> V.shape, F.tolist()
    ((3, 3), [[0, 1, 2]])
    """
    if isinstance(mesh, (str, os.PathLike)):
        return read_mesh(mesh)
    if isinstance(mesh, tuple) and len(mesh) == 2:
        V, F = mesh
    elif hasattr(mesh, "vertices") and (hasattr(mesh, "faces") or hasattr(mesh, "triangles")):
        V = mesh.vertices
        F = mesh.faces if hasattr(mesh, "faces") else mesh.triangles
    else:
        raise MeshError(
            f"cannot read a mesh from a {type(mesh).__name__}: pass a file path, a (V, F) pair "
            "or an object with 'vertices' and 'faces' attributes"
        )
    V = check_vertices(np.asarray(V), name="mesh vertices")
    F = np.asarray(F) if not isinstance(F, (Polygons, list)) else F
    return V, _faces_out(check_faces(F, len(V), name="mesh faces"))
