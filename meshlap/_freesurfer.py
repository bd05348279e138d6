"""FreeSurfer surfaces (``lh.pial``, ``rh.white``, ...), told by their first bytes, not their names.

A triangle surface is three bytes ``FF FF FE``, a line saying who created it and when followed
by an empty line, the vertex and triangle counts as big-endian 32-bit integers, the vertices'
x, y, z as big-endian 32-bit floats and the triangles' corners as big-endian 32-bit integers;
whatever follows (the volume it came from) is not read. FreeSurfer's older quad surfaces
(``FF FF FF``, ``FF FF FD``) are named and refused.
"""

from __future__ import annotations

import numpy as np

from .errors import MeshError

__all__: list[str] = []

_TRIANGLES = b"\xff\xff\xfe"
_QUADS = (b"\xff\xff\xff", b"\xff\xff\xfd")


def is_surface(head: bytes) -> bool:
    """Whether a file that starts with ``head`` is a FreeSurfer surface.

    >>> is_surface(b"\\xff\\xff\\xfecreated by"), is_surface(b"ply")
    (True, False)
    """
    return head[:3] == _TRIANGLES or head[:3] in _QUADS


def read(data: bytes, name: str) -> tuple[np.ndarray, np.ndarray]:
    """``(V, F)`` of a FreeSurfer triangle surface's bytes: (n, 3) float64 and (m, 3) int64.

    >>> body = np.r_[3, 1].astype(">i4").tobytes() + np.eye(3).astype(">f4").tobytes()
    >>> body += np.arange(3).astype(">i4").tobytes()
    >>> V, F = read(b"\\xff\\xff\\xfecreated by me\\n\\n" + body, "lh.x")
    >>> V.shape, F.tolist()
    ((3, 3), [[0, 1, 2]])
    """
    if data[:3] in _QUADS:
        raise MeshError(f"{name}: a FreeSurfer quad surface; meshlap reads FreeSurfer's triangle surfaces "
                        "(mris_convert writes one)")
    end = data.find(b"\n\n", 3)
    if end < 0:
        raise MeshError(f"{name}: a FreeSurfer surface whose header line does not end")
    at = end + 2
    while at < len(data) and data[at] == 0x0A:  # a blank line more (some versions write one)
        at += 1
    if len(data) - at < 8:
        raise MeshError(f"{name}: the file ends before its vertex and triangle counts (a FreeSurfer surface)")
    n, m = (int(x) for x in np.frombuffer(data, ">i4", 2, at))
    at += 8
    if n <= 0 or m < 0 or len(data) - at < 12 * (n + m):
        raise MeshError(f"{name}: the file ends before its {n:,} vertices and {m:,} triangles "
                        "(a FreeSurfer surface)")
    V = np.frombuffer(data, ">f4", 3 * n, at).reshape(n, 3).astype(np.float64)
    F = np.frombuffer(data, ">i4", 3 * m, at + 12 * n).reshape(m, 3).astype(np.int64)
    return V, F
