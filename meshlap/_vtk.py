"""Legacy VTK ``POLYDATA`` files (``.vtk``), ASCII or binary, of file versions up to 5.1.

meshio refuses the ``POLYDATA`` data set, which is what pyvista's ``PolyData.save("x.vtk")``
writes (binary, version 5.1: cells as ``OFFSETS`` and ``CONNECTIVITY`` arrays) and what LaPy's
``TriaMesh.write_vtk`` and ``TetMesh.write_vtk`` write (ASCII, triangles or tetrahedra as
``POLYGONS`` of 3 or 4 indices, a count before each cell). meshlap reads these itself: a
``POLYGONS`` block of 4-index cells whose corners span a volume is read as tetrahedra; one whose
corners are coplanar (quads of a surface) as polygons; triangle strips as their triangles; a
file with ``LINES`` and no faces (well tracks, contours, strokes) as a curve's segments.
Attributes (``POINT_DATA``, ``CELL_DATA``, ``FIELD``) are not read. Past its first three lines an
ASCII file is a stream of words, as VTK reads it: a block's values may begin on its key's line.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .errors import MeshError

# sections of a POLYDATA data set after POINTS: "KEY m size" followed by size integers
_CELL_SECTIONS = ("VERTICES", "LINES", "POLYGONS", "TRIANGLE_STRIPS")
# a tetrahedron's volume against the cube of its mean edge: 0.118 for a regular one; a planar quad's is 0
_SOLID = 1e-3
# the value types of the legacy format, big-endian in binary files
_TYPES = {"float": ">f4", "double": ">f8", "int": ">i4", "unsigned_int": ">u4", "long": ">i8",
          "unsigned_long": ">u8", "short": ">i2", "unsigned_short": ">u2", "char": ">i1",
          "unsigned_char": ">u1", "vtktypeint64": ">i8", "vtktypeint32": ">i4", "vtkidtype": ">i8"}


class _Cursor:
    """Lines and arrays of a legacy VTK file, read in order from its bytes."""

    def __init__(self, data: bytes, binary: bool, name: str) -> None:
        self.data, self.pos, self.binary, self.name = data, 0, binary, name
        self.held: list[str] = []  # words of a key's line past its own: the block's first values

    def line(self) -> bytes | None:
        """The next line (b"" if blank), or None at the end."""
        if self.pos >= len(self.data):
            return None
        end = self.data.find(b"\n", self.pos)
        end = len(self.data) if end < 0 else end
        out, self.pos = self.data[self.pos:end].strip(), end + 1
        return out

    def words(self) -> list[str]:
        """The words of the next line that has any ([] at the end)."""
        while (line := self.line()) is not None:
            if line:
                return line.decode("latin-1").split()
        return []

    def array(self, count: int, kind: str, what: str) -> np.ndarray:
        """``count`` values of type ``kind`` (of a ``what`` block): raw big-endian bytes in a binary
        file, words in an ASCII one."""
        if self.binary:
            if kind.lower() not in _TYPES:
                raise MeshError(f"{self.name}: unknown VTK value type {kind!r}")
            dtype = np.dtype(_TYPES[kind.lower()])
            raw = self.data[self.pos:self.pos + count * dtype.itemsize]
            if len(raw) < count * dtype.itemsize:
                raise MeshError(f"{self.name}: the file ends inside its {what} block ({count} values)")
            self.pos += len(raw)
            return np.frombuffer(raw, dtype=dtype)
        words, self.held = self.held, []
        while len(words) < count and (more := self.words()):
            words += more
        if len(words) != count:
            found = len(words) if len(words) < count else "more"
            raise MeshError(f"{self.name}: malformed {what} block ({found} values; it announces {count})")
        return np.array(words, dtype=np.float64 if kind.lower() in ("float", "double") else np.int64)


def read_polydata(path: Path) -> tuple[np.ndarray, np.ndarray | list, int] | None:
    """``(V, cells, k)`` of a legacy VTK POLYDATA file, or None if ``path`` is not one.

    ``k`` is 3 when the cells are tetrahedra (4 indices each, spanning a volume), 1 when the file
    has lines and no faces (the cells are then segments), else 2.

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
        data = f.read()
    cur = _Cursor(data, False, path.name)
    head = [cur.line() or b"" for _ in range(3)]
    mode = head[2].upper()
    if not head[0].startswith(b"# vtk DataFile") or mode not in (b"ASCII", b"BINARY") \
            or [w.upper() for w in cur.words()[:2]] != ["DATASET", "POLYDATA"]:
        return None
    cur.binary = mode == b"BINARY"
    version = head[0].split()[-1].decode("latin-1")
    offsets = not version[:1].isdigit() or int(version.split(".")[0]) >= 5  # 5.x: OFFSETS, CONNECTIVITY
    V, cells, lines = None, [], []
    try:
        while words := cur.words():
            key = words[0].upper()
            if key == "POINTS":
                cur.held = [] if cur.binary else words[3:]
                V = cur.array(3 * int(words[1]), words[2], key).astype(np.float64).reshape(-1, 3)
            elif key in _CELL_SECTIONS:
                cur.held = [] if cur.binary or offsets else words[3:]
                block = _offset_cells(cur, int(words[1]), key) if offsets else \
                    _cells(cur.array(int(words[2]), "int", key), path.name, key)
                if key in ("POLYGONS", "TRIANGLE_STRIPS"):  # vertices bound nothing, lines no surface
                    cells += block if key == "POLYGONS" else strip_triangles(block).tolist()
                elif key == "LINES":
                    lines += [[a, b] for c in block for a, b in zip(c[:-1], c[1:], strict=False)]
            elif key == "METADATA":  # field names and information keys, up to a blank line
                while cur.line():
                    pass
            else:  # POINT_DATA, CELL_DATA, FIELD: attributes, not geometry
                break
    except MeshError:  # already says what and where
        raise
    except (ValueError, IndexError) as exc:  # a short or non-numeric section
        raise MeshError(f"{path.name}: malformed VTK POLYDATA file ({exc})") from None
    if V is not None and not cells and lines:  # a curve: each polyline's consecutive pairs
        return V, np.array(lines, dtype=np.int64), 1
    if V is None or not cells:
        raise MeshError(f"{path.name}: a VTK POLYDATA file without "
                        f"{'POINTS' if V is None else 'POLYGONS or LINES'}")
    sizes = {len(c) for c in cells}
    if sizes == {4} and _solid(V, np.array(cells)):
        return V, np.array(cells), 3
    return V, np.array(cells) if len(sizes) == 1 else cells, 2


def _offset_cells(cur: _Cursor, n_offsets: int, what: str) -> list[list[int]]:
    # version 5: "OFFSETS type" (n_offsets values), then "CONNECTIVITY type" (the indices)
    key, kind = cur.words()[:2]
    offsets = cur.array(n_offsets, kind, what).astype(np.int64)
    key2, kind2 = cur.words()[:2]
    if (key.upper(), key2.upper()) != ("OFFSETS", "CONNECTIVITY") or len(offsets) < 1 or offsets[0] != 0 \
            or np.any(np.diff(offsets) < 1):
        raise MeshError(f"{cur.name}: malformed {what} block (OFFSETS and CONNECTIVITY expected, offsets "
                        "rising from 0)")
    flat = cur.array(int(offsets[-1]), kind2, what).astype(np.int64)
    return [flat[a:b].tolist() for a, b in zip(offsets[:-1], offsets[1:], strict=True)]


def strip_triangles(strips: list[list[int]]) -> np.ndarray:
    """The triangles of triangle strips, (m, 3): a strip's i-th triangle is (s[i], s[i+1], s[i+2]),
    every other one flipped to keep the orientation; those with a repeated corner, which strips
    use to turn or to change parity, cover nothing and are left out.

    >>> strip_triangles([[0, 1, 2, 3], [4, 5, 5, 6, 7]]).tolist()
    [[0, 1, 2], [2, 1, 3], [5, 6, 7]]
    """
    out = []
    for s in strips:
        s = np.asarray(s, dtype=np.int64)
        if len(s) < 3:
            continue
        a, b, odd = s[:-2], s[1:-1], np.arange(len(s) - 2) % 2 == 1
        out.append(np.column_stack([np.where(odd, b, a), np.where(odd, a, b), s[2:]]))
    T = np.concatenate(out) if out else np.zeros((0, 3), dtype=np.int64)
    return T[(T[:, 0] != T[:, 1]) & (T[:, 1] != T[:, 2]) & (T[:, 0] != T[:, 2])]


def _cells(flat: np.ndarray, name: str, what: str) -> list[list[int]]:
    out, i = [], 0
    while i < len(flat):
        c = int(flat[i])
        if c < 1 or i + 1 + c > len(flat):
            raise MeshError(f"{name}: malformed {what} block (a cell of {c} indices at entry {i})")
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
