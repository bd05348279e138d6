"""Which way is up, and the colour range of values: what the figures (:mod:`meshlap.plot`)
and the interactive views (:mod:`meshlap.viewer`) share.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .errors import MeshError
from .geometry.validation import check_faces, check_vertices

__all__ = ["colour_range", "parse_up", "to_z_up", "up_axis"]


# A facet of the convex hull counts towards the support on a side when its outward normal is
# within this angle of that side's axis direction.
_SUPPORT_ANGLE = 10.0
# Least difference between the supports of an axis's two sides (as fractions of the hull's
# area) that makes one side a base; below it the up axis stays z.
_MIN_BASE = 0.02


def up_axis(V: Any, F: Any = None) -> str:
    """The direction that points up when the mesh stands on its base: ``"+y"``, ``"-z"``, ...

    An object at rest stands on a flat base: the convex hull has much surface facing down
    along the up axis and little facing up. Left and right (and front and back) of most
    objects mirror each other and cancel. So for each axis this compares the hull area that
    faces its two sides (normals within 10° of the axis) and takes the axis where the two
    differ most, up being away from the flatter side. Shapes with no base (a sphere, a torus
    lying flat, whose top and bottom match) keep z up. Only vertices that faces use count.

    Parameters
    ----------
    V : (n, 3) array_like
        Vertex positions.
    F : array_like or Polygons, optional
        Faces; vertices that no face uses are left out.

    Returns
    -------
    str
        A sign and an axis name.

    Examples
    --------
    >>> import numpy as np
    >>> import meshlap
    >>> V, F = meshlap.shapes.sphere(500, seed=0)
    >>> up_axis(V, F)
    '+z'
    >>> V[:, 1] = np.maximum(V[:, 1], -0.5)  # cut flat at y = -0.5: it stands on that base
    >>> up_axis(V, F)
    '+y'
    """
    from scipy.spatial import ConvexHull, QhullError

    V = check_vertices(V)
    if F is not None:
        used = np.unique(check_faces(F, len(V)).indices)
        V = V[used]
    try:
        hull = ConvexHull(V)
    except (QhullError, ValueError):  # flat or too few points: no base to stand on
        return "+z"
    P = V[hull.simplices]
    area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    normal = hull.equations[:, :3]
    near = np.cos(np.radians(_SUPPORT_ANGLE))
    facing = np.array([[area[normal[:, a] * s > near].sum() for s in (1.0, -1.0)] for a in range(3)])
    facing /= area.sum()
    diff = facing[:, 0] - facing[:, 1]  # > 0: the + side is the flatter, so it is the base
    a = int(np.argmax(np.abs(diff)))
    if abs(diff[a]) < _MIN_BASE:
        return "+z"
    return ("-" if diff[a] > 0 else "+") + "xyz"[a]


# Rotations taking each signed axis to +z, as (source column, sign) for the new x, y, z; the
# y-up one keeps the view of spot and the bunny that the notebooks were drawn with.
_UP_ROTATIONS = {
    "+z": ((0, 1), (1, 1), (2, 1)),
    "-z": ((0, 1), (1, -1), (2, -1)),
    "+y": ((0, 1), (2, -1), (1, 1)),
    "-y": ((0, 1), (2, 1), (1, -1)),
    "+x": ((1, 1), (2, 1), (0, 1)),
    "-x": ((1, 1), (2, -1), (0, -1)),
}


def to_z_up(V: np.ndarray, up: str) -> np.ndarray:
    """``V`` rotated so that the signed axis ``up`` ("+y", "-z", ...) points along +z.

    Examples
    --------
    >>> to_z_up(np.array([[0.0, 2.0, 0.0]]), "+y")[0, 2]   # y becomes z
    np.float64(2.0)
    """
    return np.column_stack([s * V[:, c] for c, s in _UP_ROTATIONS[up]])


def parse_up(up: str, V: np.ndarray, F: Any) -> str:
    """The signed axis that ``up`` names: "auto" (:func:`up_axis`), "y", "+z", "-x", ...

    Examples
    --------
    >>> parse_up("y", None, None), parse_up("-x", None, None)
    ('+y', '-x')
    """
    if up == "auto":
        return up_axis(V, F)
    key = up if isinstance(up, str) and up[:1] in "+-" else f"+{up}"
    if key not in _UP_ROTATIONS:
        raise MeshError(f"up must be 'auto' or an axis such as 'y', '+z', '-x'; got {up!r}")
    return key


def colour_range(f: np.ndarray, vmin: float | None, vmax: float | None, symmetric: bool) -> list[float]:
    """The colour range ``[lo, hi]`` of values ``f``: given ends win, ``symmetric`` centres it on 0,
    and a constant function gets a range of 1 around its value.

    Examples
    --------
    >>> colour_range(np.array([-1.0, 3.0]), None, None, True), colour_range(np.ones(3), None, None, False)
    ([-3.0, 3.0], [0.5, 1.5])
    """
    lo = float(np.nanmin(f)) if vmin is None else float(vmin)
    hi = float(np.nanmax(f)) if vmax is None else float(vmax)
    if symmetric:
        hi = max(abs(lo), abs(hi))
        lo = -hi
    if hi <= lo:  # a constant function: any non-empty range draws it in one colour
        lo, hi = lo - 0.5, hi + 0.5
    return [lo, hi]
