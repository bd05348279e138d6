"""Saving a built operator and reading it back, bit for bit.

:func:`save_operator` writes one ``.npz`` file; :func:`load_operator` gives back an operator
whose ``op @ f``, ``L``, ``S``, ``M``, eigenpairs and heat functions are bit-identical to
those of the saved one. What is stored:

* the matrix ``op @ f`` applies, in scipy's own CSR layout (``format``, ``shape``, ``data``,
  ``indices``, ``indptr``), so that :func:`scipy.sparse.load_npz` reads it too;
* the symmetric pencil's L (``S = M L``) when it differs: only its values when it has the
  same sparsity pattern (the default surface operator's point-wise rows do), else the whole
  matrix;
* ``S`` itself for operators whose S is not ``M @ L`` to the bit (the cotangent Laplacian);
* the masses, the kernel parameters (h, tol, radius, correction, the moment factor,
  per-vertex widths) and the geometry (points, faces or cells, boundary, intrinsic
  dimension, a cloud's outliers), unless ``mesh=False``;
* the policy's decision (``op.decision``: what was built and why), as JSON;
* ``meshlap_format``, the layout's version: files of another version are refused with
  :class:`OperatorFormatError`.

A matrix-free operator holds no kernel: its geometry and parameters are saved and the loaded
operator is rebuilt from them (matrix-free again). A distributed operator is gathered on
rank 0 (:meth:`~meshlap.distributed.DistributedLaplacian.to_scipy`) and saved there.
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

from .assembly import csr as _csr
from .errors import MeshError
from .geometry import Geometry, Polygons
from .geometry.validation import check_faces, check_function, existing_file
from .lumped import LumpedLaplacian
from .operator import MeshLaplacian
from .policy import Decision
from .spectral import symmetric_L

__all__ = ["FORMAT_VERSION", "OperatorFormatError", "SavedLaplacian", "load_operator", "save_operator"]

#: Version of the file layout written by :func:`save_operator` (files without one are version 1).
FORMAT_VERSION = 2

_PARAMS = ("h", "tol", "radius", "moment_scale")


class OperatorFormatError(MeshError):
    """A saved operator file of a layout this version of meshlap does not read."""


def _applied(op: Any) -> sp.spmatrix:
    # the matrix op @ f applies
    return op.L


class SavedLaplacian(LumpedLaplacian):
    """An operator read back by :func:`load_operator`.

    Behaves like the operator it was saved from: ``op @ f``, ``L``, ``L_sym``, ``M``, ``S``,
    ``mass``, the kernel parameters ``h``, ``tol``, ``radius``, ``h_auto``, ``correction`` (None
    for operators without them, such as the cotangent Laplacian), and when the geometry was
    saved ``V``, ``faces``, ``geometry``, ``dim``, ``pencil_points``, ``area_scale`` and ``elements`` (what
    :func:`meshlap.spectral.eigs` solves; "linear" without the geometry); ``decision``, the
    policy's :class:`~meshlap.policy.Decision` (None for an operator without one).

    Examples
    --------
    >>> import meshlap, tempfile, pathlib, numpy as np
    >>> V, F = meshlap.shapes.sphere(200, seed=0)
    >>> op = meshlap.laplacian(V, F, h=0.02)
    >>> back = load_operator(save_operator(pathlib.Path(tempfile.mkdtemp()) / "op", op))
    >>> bool(np.array_equal(back @ V, op @ V)), back.correction, back.decision == op.decision
    (True, 'richardson', True)
    """

    matrix_free = False

    def __init__(self, applied: sp.csr_matrix, symmetric: sp.csr_matrix, mass: np.ndarray,
                 params: dict[str, Any], S: sp.csr_matrix | None = None,
                 geometry: Geometry | None = None, pencil_points: np.ndarray | None = None,
                 area_scale: np.ndarray | None = None, decision: Decision | None = None) -> None:
        self._applied, self._sym, self.mass, self._S = applied, symmetric, mass, S
        self.decision = decision
        self._exact_S = S is not None  # S stored as such (the cotangent Laplacian's), not M @ L_sym
        self.name = str(params.get("name", "BSW"))
        for key in _PARAMS:
            setattr(self, key, float(params[key]) if key in params else None)
        self.h_auto = bool(params.get("h_auto", False))
        self.correction = params.get("correction")
        self.pointwise = applied is not symmetric
        self.h_vertex = params.get("h_vertex")
        self.exact = self.tol == 0.0
        self.dtype = applied.dtype
        # what spectral.eigs solves: the quadratic elements need the saved geometry
        self.elements = str(params.get("elements") or "linear") if geometry is not None else "linear"
        if geometry is not None:  # only then: code that looks for op.V falls back without it
            self.geometry, self.dim, self.faces = geometry, geometry.dim, geometry.faces
            P = geometry.points
            self.V = P if P.shape[1] >= 3 else np.ascontiguousarray(np.pad(P, ((0, 0), (0, 3 - P.shape[1]))))
            self.pencil_points = P if pencil_points is None else pencil_points
            self.area_scale = area_scale

    @property
    def L(self) -> sp.csr_matrix:
        """What ``op @ f`` applies (the point-wise rows, when the operator has them)."""
        return self._applied

    @property
    def L_sym(self) -> sp.csr_matrix:
        """The symmetric pencil's L: ``S = M @ L_sym``."""
        return self._sym

    @property
    def S(self) -> sp.csr_matrix:
        """``M @ L_sym``: symmetric and negative semidefinite."""
        if self._S is None:
            self._S = sp.csr_matrix(self.M @ self._sym)
        return self._S

    @property
    def nbytes(self) -> int:
        """Bytes held by the CSR arrays (the moment rows' values share the pencil's indices; the
        fitted rows and a Galerkin pencil have patterns of their own)."""
        A, B = self._applied, self._sym
        own = 0 if A.indices is B.indices else A.indices.nbytes + A.indptr.nbytes
        extra = 0 if A is B else A.data.nbytes + own
        return int(B.data.nbytes + B.indices.nbytes + B.indptr.nbytes + extra)

    def __matmul__(self, f: Any) -> np.ndarray:
        return np.asarray(self._applied @ check_function(f, self.n_vertices))

    def matvec(self, f: Any) -> np.ndarray:
        """``op @ f`` for a vector or an (n, k) block of functions."""
        return self @ f

    def as_linear_operator(self) -> sp.linalg.LinearOperator:
        """The applied matrix as a :class:`scipy.sparse.linalg.LinearOperator`."""
        return sp.linalg.aslinearoperator(self._applied)

    def __repr__(self) -> str:
        h = "" if self.h is None else f", h={self.h:.6g}, tol={self.tol:.3g}"
        what = self.name if self.decision is None else self.decision.built
        return f"SavedLaplacian({what}, vertices={self.n_vertices:,}, nnz={self.nnz:,}{h})"


def _check_arguments(path: Any, op: Any) -> Path:
    if not isinstance(path, (str, os.PathLike)):
        if isinstance(op, (str, os.PathLike)) and hasattr(path, "mass"):
            raise MeshError("save_operator(path, op): the file comes first; got the operator first")
        raise MeshError(f"save_operator: path must be a str or os.PathLike; got {type(path).__name__}")
    # dir(), not hasattr(): a matrix-free operator's L is a property that raises
    if not hasattr(op, "mass") or not {"L", "to_scipy"} & set(dir(op)):
        raise MeshError(f"save_operator needs an operator with L and mass; got {type(op).__name__}")
    path = Path(path)
    return path if path.suffix == ".npz" else path.with_name(path.name + ".npz")


def _csr_arrays(prefix: str, L: sp.csr_matrix) -> dict[str, np.ndarray]:
    return {f"{prefix}data": L.data, f"{prefix}indices": L.indices, f"{prefix}indptr": L.indptr,
            f"{prefix}shape": np.array(L.shape)}


def _geometry_arrays(op: Any) -> dict[str, Any]:
    geo = getattr(op, "geometry", None)
    if geo is None:  # e.g. the cotangent Laplacian: its vertices and faces, when it has them
        V, faces = getattr(op, "V", None), getattr(op, "faces", None)
        if V is None or faces is None:
            return {}
        geo = Geometry(np.asarray(V, dtype=np.float64), np.asarray(op.mass), 2, 0.0, faces=faces,
                       source="surface")
    out: dict[str, Any] = {"points": geo.points, "dim": np.array(geo.dim), "spacing": np.array(geo.spacing),
                           "source": np.array(geo.source)}
    if geo.faces is not None:
        out["face_indices"], out["face_offsets"] = geo.faces.indices, geo.faces.offsets
    for key in ("boundary", "cells", "boundary_share"):
        if getattr(geo, key) is not None:
            out[key] = getattr(geo, key)
    if "outliers" in geo._cache:  # a cloud's points off the surface: no distance reaches them
        out["outliers"] = geo._cache["outliers"]
    moved = getattr(op, "pencil_points", None)
    if moved is not None and moved is not geo.points:  # denoise=True: gradients and distances read them
        out["pencil_points"] = moved
    if getattr(op, "area_scale", None) is not None:  # what the quadratic elements' masses carry
        out["area_scale"] = op.area_scale
    return out


def _distributed_arrays(op: Any) -> dict[str, Any] | None:
    # collective: every rank calls it; rank 0 gets the arrays, the others None
    if op.matrix_free:
        raise MeshError("a matrix-free distributed operator stores no matrix to save")
    separate = op.L_sym is not op.L  # the corrected default: point-wise rows and the pencil's L_sym
    L, mass, V = op.to_scipy(root=0), op.gather(op.mass, root=0), op.gather(op.V, root=0)
    L_sym = op.to_scipy(root=0, symmetric=True) if separate else L
    if L is None:
        return None
    out = _csr_arrays("", L)
    if L_sym is not L:
        same = np.array_equal(L.indptr, L_sym.indptr) and np.array_equal(L.indices, L_sym.indices)
        out.update({"sym_data": L_sym.data} if same else _csr_arrays("sym_", L_sym))
    out.update(mass=mass, h=np.array(op.h), tol=np.array(op.tol), radius=np.array(op.radius),
               moment_scale=np.array(op.moment_scale), correction=np.array(op.correction), points=V,
               dim=np.array(2), spacing=np.array(0.0), source=np.array("distributed"))
    return out


def save_operator(path: str | os.PathLike, op: Any, *, mesh: bool = True,
                  compress: bool = False) -> Path | None:
    """Save a built operator to ``.npz``, completely enough to reload it bit for bit.

    ``scipy.sparse.load_npz(path)`` returns the matrix ``op @ f`` applies;
    :func:`load_operator` gives back the whole operator.

    Parameters
    ----------
    path : str or path-like
        Target file; ``.npz`` is appended when missing.
    op : MeshLaplacian, SparseLaplacian or DistributedLaplacian
        Any operator with ``L`` and ``mass``: a mesh's, a point cloud's, a curve's, a
        volume's, the cotangent Laplacian, a matrix-free operator (its geometry and
        parameters are saved), or a distributed one (call on every rank; rank 0 writes).
    mesh : bool, default True
        Also store the geometry (vertices, faces or cells), for plotting, the cotangent
        preconditioner of :func:`meshlap.spectral.eigs` and curvature. Needed for
        matrix-free operators.
    compress : bool, default False
        Zip-compress the arrays (smaller, slower to write and read).

    Returns
    -------
    Path or None
        The file written (None on the ranks other than 0 of a distributed operator).

    Raises
    ------
    MeshError
        For arguments in the wrong order or of the wrong type.

    Examples
    --------
    >>> import meshlap, tempfile, pathlib, numpy as np
    >>> V, F = meshlap.shapes.sphere(200, seed=0)
    >>> op = meshlap.laplacian(V, F, h=0.02, correction="none")
    >>> p = save_operator(pathlib.Path(tempfile.mkdtemp()) / "op", op)
    >>> back = load_operator(p)
    >>> back.h, bool(np.array_equal((back @ V).ravel(), (op @ V).ravel()))
    (0.02, True)
    """
    from . import __version__

    path = _check_arguments(path, op)
    if hasattr(op, "to_scipy"):
        arrays = _distributed_arrays(op)
        if arrays is None:
            return None
    else:
        arrays = {"mass": np.asarray(op.mass, dtype=np.float64)}
        if getattr(op, "matrix_free", False):
            if not mesh:
                raise MeshError("a matrix-free operator is rebuilt from its geometry: save it with mesh=True")
            arrays.update(matrix_free=np.array(True), dtype=np.array(np.dtype(op.dtype).name),
                          pointwise=np.array(str(op.options.pointwise)), neumann=np.array(op.options.neumann))
        else:
            applied, sym = _applied(op), symmetric_L(op)
            arrays.update(_csr_arrays("", sp.csr_matrix(applied)))
            if sym is not applied:
                applied, sym = sp.csr_matrix(applied), sp.csr_matrix(sym)
                same = (np.array_equal(sym.indptr, applied.indptr)
                        and np.array_equal(sym.indices, applied.indices))
                arrays.update({"sym_data": sym.data} if same else _csr_arrays("sym_", sym))
            if not isinstance(op, MeshLaplacian) and getattr(op, "_exact_S", True):
                # S may be exact rather than M @ L (the cotangent Laplacian's)
                arrays.update(_csr_arrays("S_", sp.csr_matrix(op.S)))
        for key in _PARAMS:
            if getattr(op, key, None) is not None:
                arrays[key] = np.array(float(getattr(op, key)))
        if getattr(op, "correction", None) is not None:
            arrays["correction"] = np.array(op.correction)
        if getattr(op, "h_vertex", None) is not None:
            arrays["h_vertex"] = op.h_vertex
        if mesh:
            arrays.update(_geometry_arrays(op), elements=np.array(getattr(op, "elements", "linear")))
        if getattr(op, "decision", None) is not None:  # what the policy built and why, as JSON
            arrays["decision"] = np.array(json.dumps(asdict(op.decision), default=lambda v: v.item()))
    if "data" in arrays:
        arrays["format"] = np.array("csr")
    arrays.update(meshlap_format=np.array(FORMAT_VERSION), meshlap_version=np.array(__version__),
                  name=np.array(str(getattr(op, "name", "BSW"))),
                  h_auto=np.array(bool(getattr(op, "h_auto", False))))
    (np.savez_compressed if compress else np.savez)(path, **arrays)
    return path


def _matrix(data: Any, prefix: str, n_check: int, name: str) -> sp.csr_matrix:
    shape = tuple(int(s) for s in data[f"{prefix}shape"])
    if shape != (n_check, n_check):
        raise MeshError(f"{name}: a stored matrix has shape {shape}, expected ({n_check}, {n_check})")
    return _csr(data[f"{prefix}data"], data[f"{prefix}indices"], data[f"{prefix}indptr"], n_check)


def _geometry(data: Any, mass: np.ndarray, name: str) -> Geometry | None:
    if "points" not in data:
        return None
    P = data["points"]
    faces = None
    if "face_indices" in data:
        faces = check_faces(Polygons(indices=data["face_indices"], offsets=data["face_offsets"]),
                            len(P), name=f"faces in {name}")
    geo = Geometry(P, mass, int(data["dim"]), float(data["spacing"]),
                   boundary=data["boundary"] if "boundary" in data else None, faces=faces,
                   cells=data["cells"] if "cells" in data else None,
                   boundary_share=data["boundary_share"] if "boundary_share" in data else None,
                   source=str(data["source"]))
    if "outliers" in data:
        geo._cache["outliers"] = data["outliers"]
    return geo


def _rebuild_matrix_free(geo: Geometry | None, params: dict[str, Any], name: str) -> MeshLaplacian:
    if geo is None:
        raise MeshError(f"{name}: a matrix-free operator saved without its geometry")
    # older files: the kernel's rows, no mirror images
    rows = "fit" if params.get("pointwise") == "fit" else False
    op = MeshLaplacian(geo, h=params["h"], tol=params["tol"], matrix_free=True, pointwise=rows,
                       neumann=bool(params.get("neumann", False)), correction=params["correction"],
                       dtype=np.dtype(params["dtype"]))
    op.widths = replace(op.widths, h_auto=bool(params["h_auto"]))  # as it was built
    return op


def load_operator(path: str | os.PathLike) -> SavedLaplacian | MeshLaplacian:
    """Load an operator written by :func:`save_operator`.

    Returns
    -------
    SavedLaplacian or MeshLaplacian
        ``op @ f``, ``L``, ``L_sym``, ``M``, ``S``, ``mass``, ``h``, ``tol``, ``radius``,
        ``correction``, and ``V``, ``faces``, ``geometry`` when the geometry was saved
        (``hasattr(op, "V")``). A matrix-free operator comes back rebuilt, as a
        matrix-free :class:`~meshlap.MeshLaplacian`.

    Raises
    ------
    FileNotFoundError
        When the file does not exist.
    OperatorFormatError
        When the file was written in another layout version (save it again).
    MeshError
        When the file is not an operator saved by meshlap.

    Examples
    --------
    >>> import meshlap, tempfile, pathlib
    >>> P = meshlap.samples.sphere_points(500)
    >>> op = meshlap.point_cloud_laplacian(P, h=0.03)
    >>> back = load_operator(save_operator(pathlib.Path(tempfile.mkdtemp()) / "cloud", op))
    >>> back.geometry.source, (back.L != op.L).nnz
    ('point cloud', 0)
    """
    path = existing_file(path, "operator")
    try:
        data = np.load(path, allow_pickle=False)
    except (ValueError, OSError) as exc:
        raise MeshError(f"{path.name}: not an .npz file saved by meshlap") from exc
    with data:
        if "mass" not in data or "name" not in data:
            raise MeshError(f"{path.name}: not an operator saved by meshlap (no mass or name)")
        try:
            version = int(data["meshlap_format"]) if "meshlap_format" in data else 1
        except (TypeError, ValueError) as exc:
            raise OperatorFormatError(f"{path.name}: the format version {data['meshlap_format']!r} "
                                      "is not a number") from exc
        if version != FORMAT_VERSION:
            when = "an older" if version < FORMAT_VERSION else "a newer"
            raise OperatorFormatError(
                f"{path.name}: saved in {when} meshlap file layout (version {version}); this meshlap "
                f"reads version {FORMAT_VERSION}: build and save the operator again")
        mass = data["mass"]
        n = len(mass)
        keys = (*_PARAMS, "h_auto", "name", "correction", "dtype", "elements", "pointwise", "neumann")
        params = {k: data[k].item() for k in keys if k in data}
        if "h_vertex" in data:
            params["h_vertex"] = data["h_vertex"]
        # a "resolution" entry (the removed resolution report, as JSON) of older files is not read
        geo = _geometry(data, mass, path.name)
        if "matrix_free" in data:
            return _rebuild_matrix_free(geo, params, path.name)
        applied = _matrix(data, "", n, path.name)
        sym = applied
        if "sym_shape" in data:  # a pattern of its own (the fitted rows', a Galerkin pencil's)
            sym = _matrix(data, "sym_", n, path.name)
        elif "sym_data" in data:
            sym = _csr(data["sym_data"], applied.indices, applied.indptr, n)
        S = _matrix(data, "S_", n, path.name) if "S_shape" in data else None
        moved = data["pencil_points"] if "pencil_points" in data else None
        scale = data["area_scale"] if "area_scale" in data else None
        decision = Decision(**json.loads(str(data["decision"]))) if "decision" in data else None
    return SavedLaplacian(applied, sym, mass, params, S=S, geometry=geo, pencil_points=moved,
                          area_scale=scale, decision=decision)
