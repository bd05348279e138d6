"""MNI (BIC) object files, the ``.obj`` surfaces of MNI's and CIVET's brain-imaging tools.

They share the suffix with Wavefront OBJ but are a stream of numbers after one letter: ``P``
(polygons), then the surface's ambient, diffuse, specular, specular exponent and opacity, the
number of points n, n points, n normals, the number of polygons m, a colour flag with its
colours (0: one, 1: one per polygon, 2: one per point, four values each), each polygon's end in
the index list, and the index list. meshlap reads the points and the polygons.
"""

from __future__ import annotations

import numpy as np

from .errors import MeshError

__all__: list[str] = []


def is_mni(text: str) -> bool:
    """Whether ``text`` starts as an MNI polygon object: ``P`` and five numbers and a count.

    >>> is_mni("P 0.3 0.3 0.4 10 1 3\\n"), is_mni("v 0 0 0\\n")
    (True, False)
    """
    head = text[:200].split()
    if len(head) < 7 or head[0] != "P":
        return False
    try:
        [float(x) for x in head[1:6]]
        return int(head[6]) >= 0
    except ValueError:
        return False


def read(text: str, name: str) -> tuple[np.ndarray, np.ndarray | list[list[int]]]:
    """``(V, F)`` of an MNI polygon object's text: the (n, 3) points and the polygons' corners (an
    (m, k) array where all have k, else a list).

    >>> text = "P 0.3 0.3 0.4 10 1 3  0 0 0 1 0 0 0 1 0  0 0 1 0 0 1 0 0 1  1 0 1 1 1 1  3  0 1 2"
    >>> V, F = read(text, "t.obj")
    >>> V.shape, F.tolist()
    ((3, 3), [[0, 1, 2]])
    """
    words = text.split()
    n = int(words[6])
    at = 7

    def take(count: int, what: str, kind: type) -> np.ndarray:
        nonlocal at
        if at + count > len(words):
            raise MeshError(f"{name}: the file ends inside its {what} (an MNI surface)")
        try:
            out = np.array(words[at:at + count], dtype=kind)
        except ValueError as exc:
            raise MeshError(f"{name}: a value of its {what} is not a number ({exc}; an MNI surface)"
                            ) from None
        at += count
        return out

    V = take(3 * n, "points", np.float64).reshape(n, 3)
    take(3 * n, "normals", np.float64)
    m, flag = (int(x) for x in take(2, "polygon count and colour flag", np.int64))
    if flag not in (0, 1, 2):
        raise MeshError(f"{name}: colour flag {flag} (0, 1 or 2 expected; an MNI surface)")
    take(4 * (1, m, n)[flag], "colours", np.float64)
    ends = take(m, "polygon ends", np.int64)
    if m and (ends[0] < 3 or np.any(np.diff(ends) < 3)):
        raise MeshError(f"{name}: a polygon with fewer than 3 corners (an MNI surface)")
    index = take(int(ends[-1]) if m else 0, "index list", np.int64)
    sizes = np.diff(np.r_[0, ends])
    if m and np.all(sizes == sizes[0]):
        return V, index.reshape(m, int(sizes[0]))
    return V, [f.tolist() for f in np.split(index, ends[:-1])]
