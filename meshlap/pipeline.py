"""The data flow from a Geometry to the operator's matrices, one stage after the other.

    Geometry ─▶ widths.choose ─▶ Kernel ─▶ assembly.assemble ─▶ corrections ─▶ Built

:class:`Options` resolves what the caller asked for against what the geometry allows (one
default for every input: the Richardson kernel, arc distances and the curvature cap where
normals exist, mirror images where there is a boundary, point-wise rows); :func:`build` runs
the stages and returns :class:`Built`, which the operator only holds. Every stage reads the
Geometry's points, masses, dimension and frames, never where they came from, so meshes,
clouds, curves, volumes and one MPI rank's rows go through the same code.
"""

from __future__ import annotations

import threading
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import scipy.sparse as sp

from . import assembly, corrections, resolution
from .assembly import Kernel, MemoryGuard, cutoff_radius
from .errors import MeshError, MeshWarning
from .geometry import Geometry
from .geometry.validation import check_positive, check_tol
from .widths import CURVATURE_LIMIT, Widths

__all__ = ["CORRECTED_TOL", "CORRECTIONS", "DEFAULT_TOL", "PLAIN_MARGIN", "POINTWISE", "QUADRATURES",
           "THIN_SAMPLE", "Built", "Options", "build", "default_tol", "plain_arcs", "plain_predicted"]

#: ``correction`` values: the Richardson (difference of Gaussians) kernel, or the paper's.
CORRECTIONS = ("richardson", "none")
#: ``pointwise`` values: rows whose width and degree are chosen per point from the data ("fit",
#: :mod:`meshlap.corrections.rowchoice`; the default), the degree-2 moment rows of the kernel's
#: stencil (True), or none (False).
POINTWISE = (True, False, "fit")
#: ``quadrature`` values for the symmetric pencil: one point per vertex (the lumped masses),
#: or the kernel integrated over the cells (:mod:`meshlap.corrections.galerkin`); None chooses.
QUADRATURES = ("vertex", "galerkin")
#: Up to this irregularity (spread of the edge lengths) of a surface mesh the build compares the
#: resolution model's predictions of the two kernels at an explicit width before it builds either:
#: both were fitted on 0.12-0.50 (uniform to random spheres) and checked on a nonuniform sphere
#: (0.77: the plain kernel more accurate at every width from 0.3 to 4 ē², taken up to 2 ē²); past
#: that they extrapolate (a random plane, 1.41: 58% predicted at 2ē², 2.9% measured;
#: benchmarks/RESULTS.md, i19c and i20r).
PREDICT_MAX_IRREGULARITY = 0.8
#: The plain kernel is built where the Richardson kernel's predicted error is more than this times
#: its own: each prediction is off by up to 2-4×, and of the 99 rows of
#: ``calibrate_resolution.py --kernels`` those the Richardson kernel wins reach 1.45 (a 20,000-vertex
#: torus at ē², 0.55% against 0.69%), those the plain kernel wins by more than 10% start at 1.85.
PLAIN_MARGIN = 1.6
#: The plain kernel that :func:`plain_predicted` takes measures chords, as the paper's does, where
#: no vertex of at most this many (a sample of a larger mesh) has the surface's other side within
#: its reach (:func:`plain_arcs`); the thickness of all 400,000 would cost 3 s of CPU at h = ē².
THIN_SAMPLE = 20000
#: Kernel tolerance of the paper's operator: Gaussian weights below 1e-8 of the peak are dropped.
DEFAULT_TOL = 1e-8
#: Kernel tolerance of the corrected operators when none is given. Against 1e-8 on a 16k-vertex
#: sphere: 24.5% fewer entries, eigenvalues moved by at most 1.9e-6 relative, against the
#: operator's own 1.8e-3 error; ``op @ f`` (the fitted rows) does not use the kernel. The
#: Galerkin pencil keeps 1e-8 (``Options.pencil_tol``): there 1e-6 grew a circle's eigenvalue
#: error (3e-5) by 15% and moved spot's by 8% (issue 19, benchmarks/RESULTS.md).
CORRECTED_TOL = 1e-6


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
    quadrature: str | None = None
    #: the Galerkin pencil's tolerance: ``tol`` when given, else 1e-8 (at 1e-6 its short-cut
    #: test moves spot's eigenvalue 5 by 8% of its error, issue 19)
    pencil_tol: float = DEFAULT_TOL
    #: the Galerkin pencil's width narrower next to creases and on thin parts
    #: (:mod:`meshlap.corrections.features`): None where its width is automatic
    feature_width: bool | None = None

    @property
    def plain(self) -> bool:
        """The paper's operator: no correction of any kind."""
        return self.correction == "none"

    @classmethod
    def resolve(cls, geo: Geometry, h: Any, *, correction: str | None = None, adaptive: bool = False,
                arc_distance: bool | None = None, pointwise: bool | None = None,
                neumann: bool | None = None, curvature_limit: float | None = None,
                check_psd: bool = True, matrix_free: bool = False, tol: float | None = None,
                exact: bool = False, dtype: Any = np.float64, max_memory: int | None = None,
                pointwise_degree: int | None = None, quadrature: str | None = None,
                feature_width: bool | None = None) -> Options:
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
        # the default: rows whose width and degree follow the data (issue 20); True keeps the
        # degree-2 moment rows of the kernel's own stencil
        pointwise = ("fit" if on else False) if pointwise is None else (
            "fit" if pointwise == "fit" else bool(pointwise))
        neumann = on if neumann is None else bool(neumann)
        if curvature_limit is None:
            curvature_limit = CURVATURE_LIMIT if (on and h is None and has_normals) else 0.0
        elif curvature_limit:
            check_positive(curvature_limit, "curvature_limit")
        if matrix_free and (adaptive or arc_distance or pointwise or neumann or curvature_limit
                            or np.ndim(h) == 1):
            raise MeshError("matrix_free=True supports a fixed h and Euclidean distances only: pass "
                            "adaptive=False, arc_distance=False, pointwise=False, neumann=False, "
                            "curvature_limit=0")
        if matrix_free and geo.ambient_dim > 3:
            raise MeshError(f"matrix_free=True needs points in at most 3 dimensions; these have "
                            f"{geo.ambient_dim}")
        if correction == "none" and np.ndim(h) == 1:
            raise MeshError("a per-point h needs the corrected kernel; correction='none' is the paper's "
                            "operator at one h")
        if quadrature is not None and quadrature not in QUADRATURES:
            raise MeshError(f"quadrature must be one of {', '.join(QUADRATURES)} or None; got {quadrature!r}")
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
        if feature_width and quadrature == "vertex":
            raise MeshError("feature_width narrows the Galerkin pencil's kernel: "
                            "not with quadrature='vertex'")
        from .assembly import available_memory

        return cls(correction, arc_distance, pointwise, neumann, bool(adaptive), float(curvature_limit),
                   bool(check_psd), bool(matrix_free), 0.0 if exact else check_tol(tol), dt,
                   int(available_memory() * 0.8) if max_memory is None
                   else int(check_positive(max_memory, "max_memory")),
                   None if pointwise_degree is None else int(pointwise_degree), quadrature,
                   0.0 if exact else check_tol(pencil_tol), feature_width)


@dataclass
class Built:
    """The matrices and facts of one build: ``L_sym`` (symmetric pencil's L, None when
    matrix-free), ``L`` (what ``op @ f`` applies: the point-wise rows, or ``L_sym``; the
    fitted rows only after :meth:`fit_rows`), the correction in effect and what the
    corrections measured."""

    L_sym: sp.csr_matrix | None
    L: sp.csr_matrix | None
    correction: str
    moment_scale: float = 1.0
    psd_margin: float | None = None
    fallback_reason: str | None = None
    pointwise_unchanged: np.ndarray | None = None
    boundary_rows: int = 0
    matrix_free: assembly.MatrixFree | None = None
    pointwise_choice: Any = None  # the per-point width and degree of pointwise="fit" rows
    quadrature: str = "vertex"  # the symmetric pencil's quadrature in effect
    quadrature_h: float | None = None  # the Galerkin pencil's width
    galerkin_regime: bool = False  # the Galerkin pencil is in effect, where galerkin.wins measured it
    shortcuts: float = 0.0  # the Galerkin pencil's area that lost pairs to corrections.shortcuts
    thin: float = 0.0  # the Galerkin pencil's area on parts thinner than its kernel (corrections.shortcuts)
    narrowed: float = 0.0  # the Galerkin pencil's area whose width its feature size narrowed
    chords: bool = False  # the plain kernel taken before the rows measures chords (plain_arcs)
    #: what computes the fitted rows (L, pointwise_unchanged, pointwise_choice) until
    #: :meth:`fit_rows` has run it; None once they are held
    pending: Callable[[], tuple] | None = field(default=None, repr=False)
    #: the resolution report of the kernel in effect, from the figures measured before the rows
    #: (:func:`plain_predicted`; None where none were), for the operator to keep
    resolution: Any = field(default=None, repr=False)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False, compare=False)

    def fit_rows(self) -> Built:
        """The point-wise rows, computed here on the first call only (under a lock: once,
        whichever thread asks first); returns self."""
        if self.pending is not None:
            with self._lock:
                if self.pending is not None:
                    self.L, self.pointwise_unchanged, self.pointwise_choice = self.pending()
                    self.pending = None
        return self

    def __getstate__(self) -> dict:
        # a pickle (or a copy) holds the rows, not the closure that fits them, nor the lock
        state = dict(self.fit_rows().__dict__)
        del state["_lock"]
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state, _lock=threading.Lock())


def plain_predicted(geo: Geometry, widths: Widths) -> tuple[Any, str | None]:
    """``(report, reason)``: the resolution report of the Richardson kernel at an explicit width on
    a surface mesh (None elsewhere), and why the plain kernel is built instead (None to build
    the Richardson one): where the model (:func:`meshlap.resolution.default_terms`) predicts the
    plain kernel at this width more accurate by :data:`PLAIN_MARGIN`. Decided before any row: a
    narrow width costs neither the Richardson rows nor the semidefiniteness check (400,000 random vertices at
    h = ē²: the check passes after 29 s of CPU, and the operator is 5% off where the plain
    kernel is 0.9%; benchmarks/RESULTS.md, i19c).

    Examples
    --------
    >>> import meshlap
    >>> g = meshlap.geometry.from_mesh(*meshlap.shapes.sphere(2000, kind="random", seed=0))
    >>> report, reason = plain_predicted(g, meshlap.widths.choose(g, 0.5 * g.spacing**2, plain=False))
    >>> "predicted less accurate" in reason
    True
    >>> plain_predicted(g, meshlap.widths.choose(g, 2 * g.spacing**2, plain=False))[1] is None
    True
    """
    if widths.h_auto or geo.faces is None or geo.dim != 2:
        return None, None
    report = resolution.assess(geo, widths, "richardson")
    if report.irregularity > PREDICT_MAX_IRREGULARITY:
        return report, None
    rich = sum(resolution.default_terms(report).values())
    plain = sum(resolution.default_terms(replace(report, fallback=True)).values())
    if rich <= PLAIN_MARGIN * plain:
        return report, None
    return report, (f"at h = {report.width:.2f}² mean edges the Richardson operator is predicted less "
                    f"accurate than the plain kernel ({rich:.1%} against {plain:.1%} for eigenvalues 1-9): h "
                    f"is too small for the mesh to resolve the narrow kernel h/2; using the plain kernel "
                    f"(O(h) bias)")


def plain_arcs(geo: Geometry, widths: Widths) -> bool:
    """Whether the plain kernel that :func:`plain_predicted` takes keeps the default's arc
    distances: where part of the surface is thinner than
    :data:`~meshlap.corrections.shortcuts.THIN_WIDTHS` of its widths √(2h), whose chords would
    cross to the other side (spot at h = ē²/2: 4.4% of its area, 12.8% off with chords against
    2.0% with arcs); elsewhere chords (spheres 1.0-1.3×, tori 1.1-2.2× more accurate than arcs
    where the plain kernel is taken; benchmarks/RESULTS.md, i20r).

    Examples
    --------
    >>> import meshlap
    >>> g = meshlap.geometry.from_mesh(*meshlap.shapes.sphere(2000, kind="random", seed=0))
    >>> plain_arcs(g, meshlap.widths.choose(g, g.spacing**2, plain=False))
    False
    """
    n = geo.n_points
    rows = None if n <= THIN_SAMPLE else np.arange(0, n, -(-n // THIN_SAMPLE))
    width = float(np.sqrt(2 * widths.largest))
    return corrections.shortcuts.thin_fraction(geo.points, geo.normals(), geo.mass, width, rows=rows) > 0


def _psd_faces(geo: Geometry) -> Any:
    # triangles in R³ precondition the check's eigensolver: a mesh's faces, a cloud's local
    # Delaunay triangles
    if geo.ambient_dim != 3:
        return None
    if geo.faces is not None:
        return geo.faces
    if geo.cells is not None and geo.cells.shape[1] == 3:
        return geo.cells
    return None


def _pointwise(geo: Geometry, free: sp.csr_matrix | None, hv: np.ndarray | None, opts: Options,
               report: Callable[[float, str], None] | None) -> tuple:
    # the rows op @ f applies: width and degree chosen per point ("fit", the default), fitted
    # rows of a fixed degree on the kernel's stencil, or degree-2 moments of the kernel's rows
    if opts.pointwise == "fit":
        # the positions f was sampled at: a denoised cloud's input points, whose noise the rows
        # must average out (the projected points would hide it)
        P = geo._cache.get("input_points", geo.points)
        tick = None if report is None else (lambda stage: report(0.9, f"point-wise rows: {stage}"))
        L, choice = corrections.rowchoice.choose_rows(P, k=geo.dim, progress=tick)
        if L.dtype != opts.dtype:
            L.data = L.data.astype(opts.dtype)
        return L, None, choice
    # the rows below share free's index arrays: canonical first, or scipy's in-place sort of
    # one matrix would reorder the other's columns under its values
    if not free.has_sorted_indices:
        assembly.variable.sort_rows(free.indptr, free.indices, free.data)
        free.has_sorted_indices = True
    if opts.pointwise_degree is not None:
        L = corrections.highorder.pointwise_rows(geo.points, free.indptr, free.indices, hv,
                                                 opts.pointwise_degree, k=geo.dim)
        return L, None, None
    # from the operator without mirror images: f need not satisfy Neumann conditions, and the
    # moment correction handles the one-sided rows
    L, unchanged = corrections.moment_correction(free, geo.points, geo.dim)
    return L, unchanged, None


def _fit_later(geo: Geometry, opts: Options, report: Callable[[float, str], None] | None
               ) -> Callable[[], tuple]:
    # the first use reports its stages to the build's progress, and is done again at 1.0
    def fit() -> tuple:
        if report is not None:
            report(0.9, "point-wise rows")
        rows = _pointwise(geo, None, None, opts, report)
        if report is not None:
            report(1.0, "done")
        return rows
    return fit


def _galerkin(geo: Geometry, widths: Widths, opts: Options, out: Built,
              report: Callable[[float, str], None] | None) -> None:
    # the symmetric pencil from the kernel integrated over the cells, where asked for or where
    # the automatic choice measures it ahead; op.L keeps the vertex rows
    gal = corrections.galerkin
    if opts.quadrature == "vertex" or (opts.quadrature is None and not widths.h_auto):
        return
    regime = gal.wins(geo)  # where it was measured ahead; the resolution report reads it too
    if opts.quadrature is None and not regime:
        return
    if report is not None:
        report(0.95, "Galerkin pencil")
    tri = gal.simplices(geo)
    h = gal.H_SCALE * geo.spacing**2 if widths.h_auto else widths.h
    dog = not opts.plain  # its own semidefinite check below, whatever the vertex pencil's fell back to
    # the vertex pencil's boundary samples (one sampling per build), reflected across for the
    # quadrature points within the Galerkin kernel's cut-off
    boundary = geo.boundary_samples(cutoff_radius(widths.largest, opts.tol)) if opts.neumann else None
    guard = MemoryGuard(len(tri) * tri.shape[1], opts.dtype, opts.max_memory, h)
    surface = geo.faces is not None and geo.ambient_dim == 3
    folds = gal.creases(geo.points, tri) if surface else None
    hv = None
    # the feature width where the width is automatic (an explicit h, as the smoothing flow's, is
    # kept), never on noise: its fake creases and opposite sides would narrow it
    if surface and opts.feature_width is not False and (widths.h_auto or opts.feature_width) \
            and gal.shape_measures(geo.points, tri)[1] <= gal.AUTO_MAX_ROUGHNESS:
        grooves = gal.creases(geo.points, tri, concave=True)
        hv = corrections.features.feature_widths(geo.points, geo.normals(), grooves, h)
    info: dict = {}
    S, m = gal.galerkin_pencil(geo.points, tri, h, geo.dim, dog=dog, crease_edges=folds, boundary=boundary,
                               tol=opts.pencil_tol, guard=guard, info=info, h_vertex=hv)
    inv = np.divide(1.0, m, out=np.zeros_like(m), where=m > 0)
    L = (sp.diags(inv) @ S).tocsr().astype(opts.dtype)
    if dog and opts.check_psd:
        margin, reason = corrections.psd.check(L, geo.mass, geo.points, _psd_faces(geo), "Galerkin pencil")
        if reason is not None:
            if opts.quadrature == "galerkin":  # asked for: say why it is not in effect
                warnings.warn(f"quadrature='galerkin': -S of the Galerkin pencil is not semidefinite "
                              f"(margin {margin:.3g}); keeping the vertex pencil", MeshWarning, stacklevel=4)
            return  # the vertex pencil stays
        out.psd_margin = margin
    out.L_sym, out.quadrature, out.quadrature_h, out.galerkin_regime = L, "galerkin", float(h), regime
    out.narrowed = 0.0 if hv is None else float(geo.mass[hv < h].sum() / geo.mass.sum())
    out.shortcuts = info.get("shortcuts", 0.0)
    if surface:
        out.thin = corrections.shortcuts.thin_fraction(geo.points, geo.normals(), geo.mass,
                                                       float(np.sqrt(2 * h)), info.get("shortcut_vertices"))
    if not opts.pointwise:
        out.L = L


def build(geo: Geometry, widths: Widths, opts: Options,
          report: Callable[[float, str], None] | None = None) -> Built:
    """Stages 3-5 for one geometry and its widths: kernel, assembly, corrections.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> from meshlap import widths
    >>> g = meshlap.geometry.from_mesh(*meshlap.shapes.sphere(800, seed=0))
    >>> opts = Options.resolve(g, None)
    >>> b = build(g, widths.choose(g, None, plain=False, curvature_limit=opts.curvature_limit), opts)
    >>> b.L is None, b.correction, b.fallback_reason  # the fitted rows: on first use
    (True, 'richardson', None)
    >>> bool(np.allclose(b.fit_rows().L @ np.ones(800), 0))
    True
    """
    radius = cutoff_radius(widths.largest, opts.tol)
    checked = not opts.plain and opts.check_psd and not opts.matrix_free
    if checked and report is not None and not widths.h_auto:
        report(0.0, "kernel choice")  # the resolution report's figures: 1.6-2 s at 400,000 vertices
    figures, reason = plain_predicted(geo, widths) if checked else (None, None)
    dog = not opts.plain and reason is None
    chords = reason is not None and opts.arc_distance and not plain_arcs(geo, widths)
    kern = Kernel(geo.dim, dog=dog, normals=geo.normals() if opts.arc_distance and not chords else None,
                  tol=opts.tol)
    frames = geo.boundary_frames(radius) if (opts.neumann or dog) else None
    band = None if frames is None else frames[0]
    if opts.matrix_free:
        apply = assembly.MatrixFree.build(geo.points, geo.mass, widths, kern)
        if dog:
            apply.scale = corrections.second_moment_scale(apply, geo.points, geo.mass, band, geo.dim)
        return Built(None, None, opts.correction, moment_scale=apply.scale, matrix_free=apply)
    guard = MemoryGuard.for_build(geo.n_points, opts.dtype, opts.max_memory, widths.h,
                                  images=opts.neumann and frames is not None, pointwise=opts.pointwise,
                                  own_pattern=opts.pointwise_degree is not None)
    hv = widths.per_point(geo.n_points)

    moments: list = []  # the moment scale's product with the rows, where the fill made it

    def stage(k: Kernel, what: str, held: list | None = None) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        # held: [the rows of another kernel], given the weights of k in place where
        # assembly.reweigh can (the same pairs: no neighbour search, no new arrays), else
        # let go before the new ones are built
        if report is not None:
            report(0.0, what)
        free = held.pop() if held else None
        if free is None or not assembly.reweigh(free, geo.points, geo.mass, widths, k):
            free = None
            # the Richardson rows also give, while each row is in cache, the moment scale's
            # product and the check's with the constant and its start's random vectors (on a
            # 16k sphere the moment scale 0.05 -> 0.00 s and the check 0.105 -> 0.03 s)
            times = np.column_stack([corrections.moments.moment_block(geo.points)]
                                    + ([corrections.psd.fill_columns(geo.points, geo.mass)] if opts.check_psd
                                       else [])) if k.dog else None
            free = assembly.assemble(geo.points, geo.mass, widths, k, dtype=opts.dtype, guard=guard,
                                     progress=None if report is None else (lambda f, s: report(0.6 * f, s)),
                                     times=times)
            if k.dog:
                free, product = free
                moments.append(product)
        if report is not None and opts.neumann:
            report(0.6, "boundary images")
        L = (corrections.neumann_images(free, geo.points, frames, geo.mass, hv, k.dog, geo.dim)
             if opts.neumann else free)
        return free, L

    free, L = stage(kern, "kernel rows")
    out = Built(L, L, "none" if reason else opts.correction, fallback_reason=reason, chords=chords,
                resolution=resolution.as_fallback(figures, geo) if reason else figures,
                boundary_rows=0 if frames is None or not opts.neumann else len(band))
    if dog and opts.check_psd:
        if report is not None:
            report(0.7, "semidefinite check")
        what = "mesh" if geo.faces is not None else geo.source
        # what the fill made, where the checked rows are the filled ones (no mirror images):
        # their diagonal (each row's first entry) and product with [x, fill_columns]
        fused = L is free and moments[0] is not None
        known = (free.data[free.indptr[:-1]], moments[0][:, 1:]) if fused else None
        out.psd_margin, out.fallback_reason = corrections.psd.check(L, geo.mass, geo.points, _psd_faces(geo),
                                                                    what, known)
        if out.fallback_reason is not None:
            out.correction = "none"
            out.resolution = None if out.resolution is None else resolution.as_fallback(out.resolution, geo)
            held, out.L_sym, out.L, L, free = [free], None, None, None, None
            free, L = stage(replace(kern, dog=False), "plain kernel rows", held)
            out.L_sym = out.L = L
    if out.correction != "none":
        if report is not None:
            report(0.8, "moment scale")
        out.moment_scale = corrections.second_moment_scale(
            lambda X: free @ X, geo.points, geo.mass, band, geo.dim,
            None if moments[0] is None else moments[0][:, :1 + geo.points.shape[1]])
        L.data *= out.moment_scale
    if opts.pointwise == "fit":
        # the fitted rows read the points alone: fitted on first use (Built.fit_rows), so spectra,
        # heat flow and smoothing do not pay for them (0.5 s of a 1.1 s build at 16k vertices)
        out.L, out.pending = None, _fit_later(geo, opts, report)
    elif opts.pointwise:
        if report is not None:
            report(0.9, "point-wise rows")
        out.L, out.pointwise_unchanged, out.pointwise_choice = _pointwise(geo, free, hv, opts, report)
    if not opts.plain or opts.quadrature == "galerkin":
        _galerkin(geo, widths, opts, out, report)
    if report is not None:
        report(1.0, "done")
    return out
