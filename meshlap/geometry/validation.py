"""Input checks shared by every public entry point.

Each check either returns a clean, canonical array or raises an error that names the
argument and the problem, so that bad input never reaches numpy, scipy, libigl or the
compiled kernels.
"""

from __future__ import annotations

import math
import numbers
import os
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import MeshError, MeshWarning, user_stacklevel
from .polygons import Polygons

__all__ = [
    "MeshError",
    "MeshWarning",
    "check_vertices",
    "check_faces",
    "check_h",
    "check_int",
    "check_k",
    "check_solver",
    "check_positive",
    "check_rows",
    "check_tol",
    "check_function",
    "existing_file",
]

# Beyond these magnitudes squared distances and 1/(4πh²) leave the float64 range.
_MAX_COORD = 1e150
_H_RANGE = (1e-150, 1e150)
# libigl's doublearea squares 2D double areas: below this extent they underflow to zero.
_MIN_SPAN = 1e-60
# an array of 3 or 4 rows of at least this many corners is warned of as faces given as columns
_WIDE = 12


def _as_real_array(x: Any, name: str) -> np.ndarray:
    try:
        a = np.asarray(x)
    except Exception as exc:  # ragged lists and foreign objects
        raise MeshError(f"{name} could not be read as an array: {exc}") from exc
    if a.dtype == object:
        raise MeshError(
            f"{name} must be a numeric array; got an object array (rows of different lengths, "
            "None, or integers beyond the int64 range)"
        )
    if a.dtype.kind == "c":
        raise MeshError(f"{name} must be real; got complex dtype {a.dtype}")
    if a.dtype.kind not in "fiub":
        raise MeshError(f"{name} must be numeric; got dtype {a.dtype}")
    return a


def _first_nonfinite(a: np.ndarray) -> tuple[int, tuple[int, ...]]:
    bad = ~np.isfinite(a)
    return int(bad.sum()), tuple(int(i) for i in np.argwhere(bad)[0])


def check_vertices(V: Any, name: str = "V") -> np.ndarray:
    """Return vertex positions as a C-contiguous float64 (n, 3) array.

    Planar (n, 2) input gets z = 0. Raises :class:`MeshError` for other shapes, an empty
    array, non-numeric dtypes and NaN or infinite coordinates.
    """
    a = _as_real_array(V, name)
    if a.dtype.kind == "b":
        raise MeshError(f"{name} must hold coordinates; got a boolean array")
    if a.ndim != 2 or a.shape[1] not in (2, 3):
        hint = " (the transpose of what is expected?)" if a.ndim == 2 and a.shape[0] in (2, 3) else ""
        raise MeshError(f"{name} must have shape (n, 3) or (n, 2); got {a.shape}{hint}")
    if a.shape[0] == 0:
        raise MeshError(f"{name} is empty: the mesh has no vertices")
    a = np.ascontiguousarray(a, dtype=np.float64)
    if not np.isfinite(a).all():
        count, where = _first_nonfinite(a)
        raise MeshError(f"{name} has {count} NaN or infinite coordinate(s), first at {name}{list(where)}")
    big = float(np.abs(a).max())
    if big > _MAX_COORD:
        raise MeshError(
            f"{name} has coordinates up to {big:.3g}: squared distances would overflow float64; "
            f"rescale the mesh (the operator scales as L(sV, s²h) = L(V, h)/s²)"
        )
    span = float(np.max(a.max(axis=0) - a.min(axis=0)))
    if 0 < span < _MIN_SPAN:
        raise MeshError(
            f"{name} spans only {span:.3g}: face areas would underflow float64; rescale the mesh "
            f"(the operator scales as L(sV, s²h) = L(V, h)/s²)"
        )
    if a.shape[1] == 2:
        a = np.ascontiguousarray(np.column_stack([a, np.zeros(len(a))]))
    return a


def _integral(a: np.ndarray, name: str) -> np.ndarray:
    if a.dtype.kind == "u" and a.size and a.max() > np.iinfo(np.int64).max:
        raise MeshError(f"{name} holds index {a.max()}, beyond the int64 range of vertex indices")
    if a.dtype.kind in "iu":
        return a.astype(np.int64, copy=False)
    if a.dtype.kind == "b":
        raise MeshError(f"{name} must hold vertex indices; got a boolean array")
    if not np.isfinite(a).all():
        raise MeshError(f"{name} holds NaN or infinite values; face entries must be vertex indices")
    if np.any(a != np.round(a)):
        raise MeshError(f"{name} must hold integer vertex indices; got non-integral {a.dtype} values")
    return a.astype(np.int64)


def check_faces(F: Any, n_vertices: int, name: str = "F") -> Polygons:
    """Return faces as :class:`Polygons` after checking them against ``n_vertices``.

    Accepts an (m, k) integer array (k >= 3: triangles, quads, ...), a list of index
    sequences of mixed sizes, or a :class:`Polygons`. Integral float arrays are converted;
    anything else, faces with fewer than 3 corners and indices outside [0, n_vertices)
    raise :class:`MeshError`.

    A corner repeated at the next position of its face (a triangle stored as the quad
    ``[a, b, c, c]``) is dropped: the operator's #t counts the face's distinct vertices.
    Faces left with fewer than 3 corners have zero area and are kept as given.

    Examples
    --------
    >>> check_faces([[0, 1, 2, 2], [0, 2, 3, 4]], 5).sizes
    array([3, 4])
    """

    if isinstance(F, (str, bytes)):
        raise MeshError(f"{name} must be an (m, k) index array or a list of polygons; got a string")
    if isinstance(F, Polygons):
        indices = np.asarray(F.indices, dtype=np.int64)
        offsets = np.asarray(F.offsets, dtype=np.int64)
        if offsets.ndim != 1 or len(offsets) < 2:
            raise MeshError(f"{name} is empty: the mesh has no faces")
        if offsets[0] != 0 or offsets[-1] != len(indices) or np.any(np.diff(offsets) < 3):
            raise MeshError(f"{name} has inconsistent offsets: they must start at 0, end at "
                            f"len(indices) and step by at least 3 corners per face")
    elif isinstance(F, np.ndarray) or (
        isinstance(F, Sequence) and len(F) and not isinstance(F[0], (Sequence, np.ndarray))
    ):
        a = _as_real_array(F, name)
        if a.ndim != 2:
            raise MeshError(f"{name} must have shape (m, k) with k >= 3 corners per face; got {a.shape}")
        if a.shape[0] == 0:
            raise MeshError(f"{name} is empty: the mesh has no faces")
        if a.shape[1] < 3:
            raise MeshError(f"faces need at least 3 corners; {name} has shape {a.shape}")
        if a.shape[0] in (3, 4) and a.shape[1] >= _WIDE:  # more likely triangles or quads as columns
            warnings.warn(f"{name} has shape {a.shape}: {a.shape[0]} faces of {a.shape[1]} corners each; if "
                          f"its columns are the faces, pass {name}.T", MeshWarning,
                          stacklevel=user_stacklevel())
        a = _integral(a, name)
        indices = np.ascontiguousarray(a.reshape(-1))
        offsets = np.arange(0, a.size + 1, a.shape[1], dtype=np.int64)
    elif isinstance(F, Sequence):
        if len(F) == 0:
            raise MeshError(f"{name} is empty: the mesh has no faces")
        sizes = np.fromiter((len(f) for f in F), dtype=np.int64, count=len(F))
        if sizes.min() < 3:
            i = int(np.argmin(sizes))
            raise MeshError(f"face {i} of {name} has {sizes[i]} corner(s); faces need at least 3")
        flat = _as_real_array(np.concatenate([np.asarray(f).reshape(-1) for f in F]), name)
        indices = _integral(flat, name)
        offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    else:
        raise MeshError(f"{name} must be an (m, k) index array or a list of polygons; got {type(F).__name__}")
    if len(indices):
        lo, hi = int(indices.min()), int(indices.max())
        if lo < 0 or hi >= n_vertices:
            bad = np.flatnonzero((indices < 0) | (indices >= n_vertices))[0]
            face = int(np.searchsorted(offsets, bad, side="right") - 1)
            raise MeshError(
                f"{name} refers to vertex {int(indices[bad])} in face {face}, but vertex indices must "
                f"lie in [0, {n_vertices - 1}] for {n_vertices} vertices"
            )
    return _drop_repeated_corners(indices, offsets)


def _drop_repeated_corners(indices: np.ndarray, offsets: np.ndarray) -> Polygons:

    sizes = np.diff(offsets)
    nxt = np.arange(1, len(indices) + 1)
    nxt[offsets[1:] - 1] = offsets[:-1]
    keep = indices != indices[nxt]
    if keep.all():
        return Polygons(indices=indices, offsets=offsets)
    new_sizes = np.add.reduceat(keep.astype(np.int64), offsets[:-1])
    short = new_sizes < 3  # degenerate faces: zero area whatever their corners
    keep[np.repeat(short, sizes)] = True
    new_sizes = np.where(short, sizes, new_sizes)
    offsets = np.concatenate([[0], np.cumsum(new_sizes)]).astype(np.int64)
    return Polygons(indices=np.ascontiguousarray(indices[keep]), offsets=offsets)


def _real_scalar(value: Any, name: str, what: str) -> float:
    if isinstance(value, (bool, np.bool_)):
        raise MeshError(f"{name} must be {what}; got the boolean {value!r}")
    try:
        return float(value)
    except (TypeError, ValueError) as exc:
        raise MeshError(f"{name} must be {what}; got {value!r}") from exc


def check_positive(value: Any, name: str) -> float:
    """Return ``value`` as a float after checking that it is finite and > 0.

    Examples
    --------
    >>> check_positive(2, "t")
    2.0
    """
    x = _real_scalar(value, name, "a positive number")
    if not math.isfinite(x) or x <= 0:
        raise MeshError(f"{name} must be finite and > 0; got {x}")
    return x


def check_h(h: Any, name: str = "h") -> float:
    """Return the kernel width ``h`` as a float.

    It must be finite, positive and within [1e-150, 1e150], where the kernel's factor
    1/(4πh²) is a finite, non-zero float64 (rescale meshes outside that range).

    Examples
    --------
    >>> check_h(0.01)
    0.01
    """
    value = check_positive(h, name)
    if not _H_RANGE[0] <= value <= _H_RANGE[1]:
        raise MeshError(
            f"{name} = {value:.3g} is outside [{_H_RANGE[0]:g}, {_H_RANGE[1]:g}], where 1/(4πh²) "
            "stays a finite, non-zero float64; rescale the mesh"
        )
    return value


def check_int(value: Any, name: str, least: int | None = None, most: int | None = None) -> int:
    """Return ``value`` as an int in [least, most] (None: unbounded), or raise a MeshError that
    names the option and what it must be. Booleans are refused.

    Examples
    --------
    >>> check_int(3, "steps", 1)
    3
    >>> check_int(True, "steps", 1)
    Traceback (most recent call last):
        ...
    meshlap.errors.MeshError: steps must be a positive integer; got True
    """
    ok = not isinstance(value, (bool, np.bool_)) and isinstance(value, numbers.Integral)
    if ok and (least is None or value >= least) and (most is None or value <= most):
        return int(value)
    if most is not None:
        what = f"an integer from {least} to {most}"
    elif least is None:
        what = "an integer"
    else:
        named = {0: "a non-negative integer", 1: "a positive integer"}
        what = named.get(least, f"an integer of at least {least}")
    raise MeshError(f"{name} must be {what}; got {value!r}")


def check_solver(tol: Any, maxiter: Any, extra: Any = None, seed: Any = 0) -> float:
    """Check an eigensolver's options; return ``tol``, where 0 (as for eigsh) and anything below
    machine precision ask for machine precision.

    Examples
    --------
    >>> check_solver(1e-8, 200), check_solver(0, 200)
    (1e-08, 2.220446049250313e-16)
    """
    if not 0 <= _real_scalar(tol, "tol", "a number in [0, 1)") < 1:
        raise MeshError(f"tol must be a number in [0, 1); got {tol!r}")
    check_int(maxiter, "maxiter", 1)
    check_int(seed, "seed", 0)
    if extra is not None:
        check_int(extra, "extra", 0)
    return max(float(tol), float(np.finfo(float).eps))


def check_k(k: Any, n: int, name: str = "k") -> int:
    """Return the number of eigenpairs ``k`` as an int in [1, n - 1].

    ``n`` is the size of the eigenproblem (vertices with positive mass, for a generalized
    problem with a singular M): ARPACK's ``eigsh`` needs k < n.

    Examples
    --------
    >>> check_k(10, 500)
    10
    """
    k = check_int(k, name)
    if n < 2:
        raise MeshError(f"the eigenproblem has size {n}: eigenpairs need at least 2 vertices with mass")
    if not 1 <= k <= n - 1:
        raise MeshError(f"{name} must lie in [1, {n - 1}] for an eigenproblem of size {n}; got {k}")
    return k


def check_tol(tol: Any) -> float:
    """Return the kernel tolerance; 0 means untruncated, otherwise it must lie in (0, 1)."""
    value = _real_scalar(tol, "tol", "a number in (0, 1), or 0 for the exact operator")
    if not (value == 0 or 0 < value < 1):
        raise MeshError(f"tol must lie in (0, 1), or be 0 for the exact operator; got {value}")
    return value


def check_function(f: Any, n: int, name: str = "f") -> np.ndarray:
    """Return a per-vertex function as float64 of shape (n,) or (n, k)."""
    a = _as_real_array(f, name)
    if a.ndim not in (1, 2) or a.shape[0] != n:
        raise MeshError(f"{name} must have shape ({n},) or ({n}, k), one value per vertex; got {a.shape}")
    a = np.asarray(a, dtype=np.float64)
    if not np.isfinite(a).all():
        count, where = _first_nonfinite(a)
        raise MeshError(f"{name} has {count} NaN or infinite value(s), first at {name}{list(where)}")
    return a


def check_rows(rows: Sequence[Sequence[str]], width: int, what: str) -> np.ndarray:
    """The first ``width`` values of every row of a text file's words as a float64 array; a row
    that is short or not numeric raises :class:`MeshError` naming it (``what`` is its name, e.g.
    ``"mesh.off: vertex"``).

    Examples
    --------
    >>> check_rows([["0", "1", "2", "7"], ["3", "4", "5"]], 3, "t.xyz: point").tolist()
    [[0.0, 1.0, 2.0], [3.0, 4.0, 5.0]]
    """
    short = next((i for i, r in enumerate(rows) if len(r) < width), None)
    if short is not None:
        raise MeshError(f"{what} {short} has {len(rows[short])} of its {width} values")
    try:
        return np.array([r[:width] for r in rows], dtype=np.float64).reshape(len(rows), width)
    except ValueError:
        for i, r in enumerate(rows):  # the first value that is not a number, found only on failure
            for value in r[:width]:
                try:
                    float(value)
                except ValueError:
                    raise MeshError(f"{what} {i}: {value!r} is not a number") from None
        raise


def existing_file(path: str | os.PathLike, what: str) -> Path:
    """Return ``path`` as a Path, or raise FileNotFoundError naming the kind of file (MeshError
    if the file is empty).

    Examples
    --------
    >>> existing_file("no-such.obj", "mesh")
    Traceback (most recent call last):
    ...
    FileNotFoundError: no such mesh file: no-such.obj
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no such {what} file: {path}")
    if path.stat().st_size == 0:
        raise MeshError(f"{path}: the file is empty")
    return path
