"""PLY files, ASCII or binary, read by meshlap itself: the vertices' x, y, z and the faces' corners.

libigl's reader aborts the whole process on a file cut inside its faces (a double free in C++)
and reads a malformed ASCII vertex as zeros; this one says what is wrong and where. Elements
other than ``vertex`` and ``face`` (edges, materials, ...) and properties other than the
coordinates and the face's ``vertex_indices`` (colours, normals, ...) are read past. A file
without faces whose ``tristrips`` element holds triangle strips (-1 between strips, as some
scanners' tools wrote them: common-3d-test-models' igea.ply) is read as their triangles.
"""

from __future__ import annotations

import numpy as np

from ._vtk import strip_triangles
from .errors import MeshError
from .geometry.validation import check_rows

__all__: list[str] = []

_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
    "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}
_CORNERS = ("vertex_indices", "vertex_index")


def header(data: bytes, name: str) -> tuple[str, list[tuple[str, int, list]], int]:
    """``(format, [(element, count, [(property, type) or (property, (count type, item type))])],
    where the body starts)`` of a PLY file's bytes (its header, at least)."""
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise MeshError(f"{name}: not a PLY file (no 'ply' ... 'end_header' header)")
    fmt, elements = None, []
    for line in data[:end].decode("ascii", errors="replace").splitlines():
        parts = line.split()
        try:
            if parts and parts[0] == "format":
                fmt = parts[1]
            elif parts and parts[0] == "element":
                elements.append((parts[1], int(parts[2]), []))
            elif parts and parts[0] == "property" and elements:
                kind = (_TYPES[parts[2]], _TYPES[parts[3]]) if parts[1] == "list" else _TYPES[parts[1]]
                elements[-1][2].append((parts[-1], kind))
        except (IndexError, KeyError, ValueError):
            raise MeshError(f"{name}: malformed PLY header line {line.strip()!r}") from None
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise MeshError(f"{name}: unknown PLY format {fmt!r}")
    newline = data.find(b"\n", end)
    return fmt, elements, len(data) if newline < 0 else newline + 1


def read(data: bytes, name: str, faces: bool = True) -> tuple[np.ndarray, list | np.ndarray | None]:
    """``(V, F)`` of a PLY file's bytes: V the (n, 3) vertex coordinates, F the faces' corners (an
    (m, k) array where every face has k, else a list; None without a face element, or where
    ``faces`` is False).

    Examples
    --------
    >>> V, F = read(b"ply\\nformat ascii 1.0\\nelement vertex 3\\nproperty float x\\nproperty float y\\n"
    ...             b"property float z\\nelement face 1\\nproperty list uchar int vertex_indices\\n"
    ...             b"end_header\\n0 0 0\\n1 0 0\\n0 1 0\\n3 0 1 2\\n", "t.ply")
    >>> V.shape, F.tolist()
    ((3, 3), [[0, 1, 2]])
    """
    fmt, elements, start = header(data, name)
    props = {element: p for element, _, p in elements}
    if not {"x", "y", "z"} <= {p for p, _ in props.get("vertex", [])}:
        raise MeshError(f"{name}: no vertex element with x, y, z properties")
    if any(isinstance(kind, tuple) for _, kind in props["vertex"]):
        raise MeshError(f"{name}: a list property in the vertex element")
    cells = "face" if "face" in props or "tristrips" not in props else "tristrips"
    if faces and cells in props and not any(p in _CORNERS for p, _ in props[cells]):
        raise MeshError(f"{name}: the {cells} element has no vertex_indices list")
    read_element = _ascii_elements if fmt == "ascii" else _binary_elements
    got = read_element(data[start:], elements, "<" if fmt == "binary_little_endian" else ">", name,
                       {"vertex", cells} if faces else {"vertex"})
    V = np.column_stack([got["vertex"][c] for c in "xyz"]).astype(np.float64)
    if cells == "tristrips" and cells in got:
        # one row of strips parted by -1, or one strip a row: either way -1 parts them
        rows = [np.r_[np.asarray(r, dtype=np.int64).ravel(), -1] for r in got[cells]]
        flat = np.concatenate(rows) if rows else np.zeros(0, dtype=np.int64)
        return V, strip_triangles([s[s >= 0] for s in np.split(flat, np.flatnonzero(flat < 0))])
    return V, got.get(cells)


def _ascii_elements(body: bytes, elements: list, order: str, name: str, wanted: set) -> dict:
    # one element row per line, as the format has it
    lines, at, out = body.decode("ascii", errors="replace").splitlines(), 0, {}
    for element, count, props in elements:
        if element in wanted:
            rows = lines[at:at + count]
            if len(rows) < count:
                raise MeshError(f"{name}: the file ends at {element} {len(rows)} of {count}")
            if element == "vertex":
                out[element] = _ascii_table(rows, props, name)
            else:
                faces = [_ascii_face(r.split(), props, name, i) for i, r in enumerate(rows)]
                same = faces and len({len(f) for f in faces}) == 1
                out[element] = np.array(faces, dtype=np.int64) if same else faces
        at += count
    return out


def _ascii_table(rows: list[str], props: list, name: str) -> dict:
    table = check_rows([r.split() for r in rows], len(props), f"{name}: vertex")
    # each value at its declared precision, as a binary file holds it
    return {p: table[:, j].astype(kind).astype(np.float64) for j, (p, kind) in enumerate(props)}


def _ascii_face(values: list[str], props: list, name: str, row: int) -> list[int]:
    try:
        i, corners = 0, []
        for prop, kind in props:
            if isinstance(kind, tuple):
                n = int(values[i])
                if prop in _CORNERS:
                    corners = [int(v) for v in values[i + 1:i + 1 + n]]
                    if len(corners) < n:
                        raise ValueError(f"{n} corners announced, {len(corners)} given")
                i += 1 + n
            else:
                i += 1
    except (IndexError, ValueError) as exc:
        raise MeshError(f"{name}: bad face row {row} ({exc})") from None
    return corners


def _binary_elements(body: bytes, elements: list, order: str, name: str, wanted: set) -> dict:
    pos, out = 0, {}
    for element, count, props in elements:
        if not any(isinstance(kind, tuple) for _, kind in props):  # fixed size: read at once
            dtype = np.dtype([(p, order + kind) for p, kind in props])
            if len(body) - pos < count * dtype.itemsize:
                rows = {"vertex": "vertices", "face": "faces"}.get(element, f"{element} rows")
                raise MeshError(f"{name}: the file ends before its {count} {rows}")
            if element in wanted:
                table = np.frombuffer(body, dtype=dtype, count=count, offset=pos)
                out[element] = {p: table[p] for p, _ in props}
            pos += count * dtype.itemsize
        else:
            rows, pos = _binary_lists(body, pos, count, props, order, name, element)
            if element in wanted:
                out[element] = rows
        if wanted <= set(out):
            break
    return out


def _binary_lists(body: bytes, pos: int, count: int, props: list, order: str, name: str, element: str
                  ) -> tuple[list[list[int]] | np.ndarray, int]:
    lists = [i for i, (_, kind) in enumerate(props) if isinstance(kind, tuple)]
    if count and len(lists) == 1 and props[lists[0]][0] in _CORNERS:  # every row as long as the first
        kind = props[lists[0]][1]
        offset = pos + sum(np.dtype(k).itemsize for _, k in props[:lists[0]])
        if offset + np.dtype(kind[0]).itemsize <= len(body):
            first = int(np.frombuffer(body, order + kind[0], 1, offset)[0])
            fields = [(f"s{i}", order + k) for i, (_, k) in enumerate(props) if i != lists[0]]
            fields.insert(lists[0], ("n", order + kind[0]))
            fields.insert(lists[0] + 1, ("c", order + kind[1], (max(first, 0),)))
            dtype = np.dtype(fields)
            if first >= 0 and len(body) - pos >= count * dtype.itemsize:
                rows = np.frombuffer(body, dtype, count, pos)
                if (rows["n"] == first).all():
                    return rows["c"].astype(np.int64).reshape(count, first), pos + count * dtype.itemsize
    out: list[list[int]] = []
    for r in range(count):  # rows of different lengths: one at a time
        corners: list[int] = []
        for prop, kind in props:
            if isinstance(kind, tuple):
                size, item = np.dtype(kind[0]).itemsize, np.dtype(kind[1]).itemsize
                n = int(np.frombuffer(body, order + kind[0], 1, pos)[0]) if pos + size <= len(body) else -1
                if n < 0 or pos + size + n * item > len(body):
                    raise MeshError(f"{name}: the file ends inside {element} {r} of {count}")
                if prop in _CORNERS:
                    corners = np.frombuffer(body, order + kind[1], n, pos + size).astype(np.int64).tolist()
                pos += size + n * item
            else:
                pos += np.dtype(kind).itemsize
                if pos > len(body):
                    raise MeshError(f"{name}: the file ends inside {element} {r} of {count}")
        out.append(corners)
    if out and len({len(f) for f in out}) == 1:
        return np.array(out, dtype=np.int64), pos
    return out, pos
