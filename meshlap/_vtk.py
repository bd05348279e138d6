"""Legacy ASCII VTK ``POLYDATA`` files, as LaPy and FreeSurfer-era tools write them.

LaPy's ``TriaMesh.write_vtk`` writes triangles as ``POLYGONS`` of 3 indices and its
``TetMesh.write_vtk`` writes tetrahedra as ``POLYGONS`` of 4 indices in a ``POLYDATA`` dataset,
which meshio refuses (a polygon data set holds no volume cells). meshlap reads such files
itself: a ``POLYGONS`` block of 4-index cells whose corners span a volume is read as
tetrahedra; one whose corners are coplanar (quads of a surface) as polygons.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .errors import MeshError

# sections of a POLYDATA data set after POINTS: "KEY m size" followed by size integers
_CELL_SECTIONS = ("VERTICES", "LINES", "POLYGONS", "TRIANGLE_STRIPS")
# a tetrahedron's volume against the cube of its mean edge: 0.118 for a regular one; a planar quad's is 0
_SOLID = 1e-3


def read_polydata(path: Path) -> tuple[np.ndarray, np.ndarray, int] | None:
    """``(V, cells, k)`` of a legacy ASCII VTK POLYDATA file, or None if ``path`` is not one.

    ``k`` is 3 when the cells are tetrahedra (4 indices each, spanning a volume), else 2.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "tet.vtk"
    >>> _ = path.write_text("# vtk DataFile Version 1.0\\nvtk output\\nASCII\\nDATASET POLYDATA\\n"
    ...                     "POINTS 4 float\\n0 0 0\\n1 0 0\\n0 1 0\\n0 0 1\\nPOLYGONS 1 5\\n4 0 1 2 3\\n")
    >>> V, T, k = read_polydata(path)
    >>> T.tolist(), k
    ([[0, 1, 2, 3]], 3)
    """
    with open(path, "rb") as f:
        head = [f.readline() for _ in range(4)]
    if not head[0].startswith(b"# vtk DataFile") or head[2].strip().upper() != b"ASCII" \
            or head[3].split()[:2] != [b"DATASET", b"POLYDATA"]:
        return None
    tokens = path.read_text(errors="replace").split("\n", 4)[4].split()
    V, cells, i = None, [], 0
    try:
        while i < len(tokens):
            key = tokens[i].upper()
            if key == "POINTS":
                n = int(tokens[i + 1])
                V = np.array(tokens[i + 3:i + 3 + 3 * n], dtype=np.float64).reshape(n, 3)
                i += 3 + 3 * n
            elif key in _CELL_SECTIONS:
                size = int(tokens[i + 2])
                if key == "POLYGONS":
                    cells += _cells(np.array(tokens[i + 3:i + 3 + size], dtype=np.int64), path.name)
                i += 3 + size
            else:  # POINT_DATA, CELL_DATA, FIELD, METADATA: attributes, not geometry
                break
    except ValueError as exc:  # a short or non-numeric section
        raise MeshError(f"{path.name}: malformed VTK POLYDATA file ({exc})") from None
    if V is None or not cells:
        raise MeshError(f"{path.name}: a VTK POLYDATA file without {'POINTS' if V is None else 'POLYGONS'}")
    sizes = {len(c) for c in cells}
    if sizes == {4} and _solid(V, np.array(cells)):
        return V, np.array(cells), 3
    return V, np.array(cells) if len(sizes) == 1 else cells, 2


def _cells(flat: np.ndarray, name: str) -> list[list[int]]:
    out, i = [], 0
    while i < len(flat):
        c = int(flat[i])
        if c < 1 or i + 1 + c > len(flat):
            raise MeshError(f"{name}: malformed POLYGONS block (a cell of {c} indices at entry {i})")
        out.append(flat[i + 1:i + 1 + c].tolist())
        i += 1 + c
    return out


def _solid(V: np.ndarray, C: np.ndarray) -> bool:
    """Whether 4-index cells are tetrahedra: their median volume is not that of flat quads."""
    if C.min() < 0 or C.max() >= len(V):
        return False  # the builder names the bad index
    P = V[C]
    vol = np.abs(np.einsum("ij,ij->i", P[:, 1] - P[:, 0], np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 0]))) / 6
    edge = np.linalg.norm(P[:, [1, 2, 3, 2, 3, 3]] - P[:, [0, 0, 0, 1, 1, 2]], axis=2).mean(axis=1)
    return bool(np.median(vol / np.maximum(edge, 1e-300) ** 3) > _SOLID)
