"""What the caller asked for, resolved against what the geometry allows: :class:`Options`.

One default for every input: the Richardson kernel, arc distances and the curvature cap where
normals exist, mirror images where there is a boundary, point-wise rows; a clear error for a
combination the geometry cannot have. :mod:`meshlap.pipeline` builds from them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from . import corrections
from .errors import MeshError
from .geometry import Geometry
from .geometry.validation import check_positive, check_tol
from .tuned import CORRECTED_TOL, CURVATURE_LIMIT

__all__ = ["CORRECTED_TOL", "CORRECTIONS", "DEFAULT_TOL", "POINTWISE", "QUADRATURES", "Options",
           "default_tol"]

#: ``correction`` values: the Richardson (difference of Gaussians) kernel, or the paper's.
CORRECTIONS = ("richardson", "none")
#: ``pointwise`` values: rows whose width and degree are chosen per point from the data ("fit",
#: :mod:`meshlap.corrections.rowchoice`; the default), the degree-2 moment rows of the kernel's
#: stencil (True), or none (False).
POINTWISE = (True, False, "fit")
#: ``quadrature`` values for the symmetric pencil: the kernel with one point per vertex (the
#: lumped masses), the kernel integrated over the cells (:mod:`meshlap.corrections.galerkin`), or
#: no kernel: linear finite elements on the cells (:mod:`meshlap.fem`).
QUADRATURES = ("vertex", "galerkin", "fem")
#: Kernel tolerance of the paper's operator: Gaussian weights below 1e-8 of the peak are dropped.
DEFAULT_TOL = 1e-8


def default_tol(tol: Any, correction: str | None) -> Any:
    """``tol``, or when it is None the default for ``correction`` (None: the corrected default).

    >>> default_tol(None, "none"), default_tol(None, None), default_tol(0.0, None)
    (1e-08, 1e-06, 0.0)
    """
    if tol is not None:
        return tol
    return DEFAULT_TOL if correction == "none" else CORRECTED_TOL


@dataclass(frozen=True)
class Options:
    """The resolved choices of one build (see :class:`meshlap.MeshLaplacian` for each)."""

    correction: str
    arc_distance: bool
    pointwise: bool | str
    neumann: bool
    adaptive: bool
    curvature_limit: float
    check_psd: bool
    matrix_free: bool
    tol: float
    dtype: np.dtype
    max_memory: int
    pointwise_degree: int | None = None
    quadrature: str = "vertex"
    #: the Galerkin pencil's tolerance: ``tol`` when given, else 1e-8 (at 1e-6 its short-cut
    #: test moves spot's eigenvalue 5 by 8% of its error, issue 19)
    pencil_tol: float = DEFAULT_TOL
    #: the Galerkin pencil's width narrower next to creases and on thin parts
    #: (:mod:`meshlap.corrections.features`): None where its width is automatic
    feature_width: bool | None = None
    #: the FEM pencil on positions denoised by a bi-Laplacian step (:mod:`meshlap.denoise`)
    denoise: bool = False
    #: the FEM pencil's mass (:func:`meshlap.fem.fem_pencil`)
    mass: str = "lumped"

    @property
    def plain(self) -> bool:
        """The paper's operator: no correction of any kind."""
        return self.correction == "none"

    @classmethod
    def resolve(cls, geo: Geometry, h: Any, *, correction: str | None = None, adaptive: bool = False,
                arc_distance: bool | None = None, pointwise: bool | str | None = None,
                neumann: bool | None = None, curvature_limit: float | None = None,
                check_psd: bool = True, matrix_free: bool = False, tol: float | None = None,
                exact: bool = False, dtype: Any = np.float64, max_memory: int | None = None,
                pointwise_degree: int | None = None, quadrature: str | None = None,
                feature_width: bool | None = None, denoise: bool = False, mass: str = "lumped") -> Options:
        """Defaults for this geometry, and a clear error for a combination it cannot have."""
        correction = "richardson" if correction is None else correction
        pencil_tol = DEFAULT_TOL if tol is None else tol
        tol = default_tol(tol, correction)
        if correction not in CORRECTIONS:
            raise MeshError(f"correction must be one of {', '.join(CORRECTIONS)}; got {correction!r}")
        try:
            dt = np.dtype(dtype)
        except TypeError as exc:
            raise MeshError(f"dtype must be float64 or float32; got {dtype!r}") from exc
        if dt not in (np.float64, np.float32):
            raise MeshError(f"dtype must be float64 or float32; got {dt}")
        on = correction != "none" and not matrix_free
        has_normals = geo.codim == 1
        if arc_distance and not has_normals:
            raise MeshError(f"arc_distance needs normals (codimension 1); this {geo.source} has k={geo.dim} "
                            f"in R^{geo.ambient_dim}")
        arc_distance = on and has_normals if arc_distance is None else bool(arc_distance)
        if pointwise_degree is not None:
            if isinstance(pointwise_degree, bool) or pointwise_degree not in range(2, 7):
                raise MeshError(f"pointwise_degree must be an integer from 2 to 6; got {pointwise_degree!r}")
            if pointwise is False or pointwise == "fit":
                raise MeshError("pointwise_degree gives the rows of that degree on the kernel's own "
                                "stencil: not with pointwise=False or pointwise='fit'")
            pointwise = True
        if pointwise is not None and pointwise not in POINTWISE:
            raise MeshError(f"pointwise must be True, False or 'fit'; got {pointwise!r}")
        # the default: rows whose width and degree follow the data, read from the points alone
        # (so a matrix-free kernel has them too); True keeps the degree-2 moment rows of the
        # kernel's own stencil
        pointwise = ("fit" if correction != "none" else False) if pointwise is None else (
            "fit" if pointwise == "fit" else bool(pointwise))
        neumann = correction != "none" if neumann is None else bool(neumann)
        if curvature_limit is None:  # the kernel's widths; the FEM pencil reads none
            kernel_widths = on and h is None and has_normals and quadrature != "fem"
            curvature_limit = CURVATURE_LIMIT if kernel_widths else 0.0
        elif curvature_limit:
            check_positive(curvature_limit, "curvature_limit")
        if matrix_free and (adaptive or arc_distance or pointwise is True or curvature_limit
                            or np.ndim(h) == 1):
            raise MeshError("matrix_free=True supports a fixed h and Euclidean distances only: pass "
                            "adaptive=False, arc_distance=False, pointwise='fit' or False, curvature_limit=0")
        if matrix_free and geo.ambient_dim > 3:
            raise MeshError(f"matrix_free=True needs points in at most 3 dimensions; these have "
                            f"{geo.ambient_dim}")
        if correction == "none" and np.ndim(h) == 1:
            raise MeshError("a per-point h needs the corrected kernel; correction='none' is the paper's "
                            "operator at one h")
        quadrature = "vertex" if quadrature is None else quadrature
        if quadrature not in QUADRATURES:
            raise MeshError(f"quadrature must be one of {', '.join(QUADRATURES)} or None; got {quadrature!r}")
        if quadrature == "fem":
            if geo.faces is None and geo.cells is None:
                raise MeshError(f"the FEM pencil integrates over cells; this {geo.source} has none")
            if matrix_free or pointwise is True or pointwise_degree is not None:
                raise MeshError("the FEM pencil stores S and has no kernel stencil: not with matrix_free, "
                                "pointwise=True or pointwise_degree (use operator='kernel')")
        if mass not in ("lumped", "blend", "consistent"):
            raise MeshError(f"mass must be 'lumped', 'blend' or 'consistent'; got {mass!r}")
        if (denoise or mass != "lumped") and quadrature != "fem":
            raise MeshError("denoise=True and mass= are options of the FEM pencil (operator='fem'); a "
                            "point cloud's kernel denoises with point_cloud_laplacian(P, denoise=True)")
        if quadrature == "galerkin":
            if corrections.galerkin.simplices(geo) is None:
                raise MeshError("quadrature='galerkin' integrates over simplices: a triangle mesh, a curve's "
                                f"segments or tetrahedra; this {geo.source} has none")
            if matrix_free or adaptive or np.ndim(h) == 1:
                raise MeshError("quadrature='galerkin' uses one h and stores S: not with matrix_free, "
                                "adaptive or a per-point h")
        if feature_width is not None and not isinstance(feature_width, bool):
            raise MeshError(f"feature_width must be True, False or None; "
                            f"got {feature_width!r}")
        if feature_width and quadrature != "galerkin":
            raise MeshError("feature_width narrows the Galerkin pencil's kernel: only with "
                            "quadrature='galerkin' (operator='galerkin')")
        from .assembly import available_memory

        return cls(correction, arc_distance, pointwise, neumann, bool(adaptive), float(curvature_limit),
                   bool(check_psd), bool(matrix_free), 0.0 if exact else check_tol(tol), dt,
                   int(available_memory() * 0.8) if max_memory is None
                   else int(check_positive(max_memory, "max_memory")),
                   None if pointwise_degree is None else int(pointwise_degree), quadrature,
                   0.0 if exact else check_tol(pencil_tol), feature_width, bool(denoise), mass)
