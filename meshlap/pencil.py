"""The symmetric pencil: what spectra, heat flow and smoothing read (``S = M L_sym``).

    Kernel ─▶ assembly.assemble ─▶ semidefinite check ─▶ moment scale ─▶ Galerkin

:func:`assemble` runs these stages for one geometry, its widths and options, and returns
:class:`Pencil`; :func:`meshlap.pipeline.build` calls it on the pencil's first use, not at
construction, so an operator that only applies ``op @ f`` (the fitted rows, which read the
points alone) never pays for it. Rows built on the kernel's own stencil (``pointwise=True``,
``pointwise_degree``) and the paper's operator (whose ``L`` is ``L_sym``) come with the pencil;
a matrix-free pencil stores none. :func:`review` gives the warning of a fallback to the plain
kernel, which comes when the pencil is built.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import scipy.sparse as sp

from . import assembly, corrections, denoise, fem
from .assembly import Kernel, MemoryGuard, cutoff_radius
from .errors import MeshWarning, user_stacklevel
from .geometry import Geometry
from .options import Options
from .tuned import GALERKIN_H_SCALE, NOISE_ROUGHNESS
from .widths import Widths

__all__ = ["Pencil", "assemble", "guard_for", "keeps_parts", "part_label", "review"]


@dataclass
class Pencil:
    """The symmetric pencil's matrix ``L_sym`` (None when matrix-free), the correction in effect
    and what the corrections measured; ``L`` the rows ``op @ f`` applies where they come with the
    pencil (``L_sym`` itself, the moment rows, the rows on the kernel's stencil; None for the
    fitted rows and matrix-free)."""

    L_sym: sp.csr_matrix | None
    L: sp.csr_matrix | None
    correction: str
    moment_scale: float = 1.0
    psd_margin: float | None = None
    fallback_reason: str | None = None
    pointwise_unchanged: np.ndarray | None = None
    boundary_rows: int = 0
    matrix_free: assembly.MatrixFree | None = None
    quadrature: str = "vertex"  # the symmetric pencil's quadrature in effect
    quadrature_h: float | None = None  # the Galerkin pencil's width
    narrowed: float = 0.0  # the Galerkin pencil's area whose width its feature size narrowed
    #: the masses the pencil goes with, where they are not the geometry's (the FEM pencil's)
    mass: np.ndarray | None = field(default=None, repr=False)
    #: the positions it was built on, where not the geometry's (the FEM pencil's with denoise=True)
    points: np.ndarray | None = field(default=None, repr=False)
    #: the factor on each vertex's mass: 1/(1 + the area the noise the denoising step left adds)
    area_scale: np.ndarray | None = field(default=None, repr=False)


def guard_for(geo: Geometry, opts: Options, h: float, images: bool) -> MemoryGuard:
    """The memory guard of the kernel's rows and what the build keeps beside them."""
    return MemoryGuard.for_build(geo.n_points, opts.dtype, opts.max_memory, h, images=images,
                                 pointwise=opts.pointwise, own_pattern=opts.pointwise_degree is not None)


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


def _stencil_rows(geo: Geometry, free: sp.csr_matrix, hv: np.ndarray | None, opts: Options
                  ) -> tuple[sp.csr_matrix, np.ndarray | None]:
    """``(L, unchanged)``: the rows ``op @ f`` applies that come with the pencil, on the kernel's
    stencil ``free``: fitted rows of a fixed degree (``pointwise_degree``) or degree-2 moments
    of the kernel's rows (the default's fitted rows read the points alone:
    :func:`meshlap.pipeline.fitted_rows`)."""
    # the rows below share free's index arrays: canonical first, or scipy's in-place sort of
    # one matrix would reorder the other's columns under its values
    if not free.has_sorted_indices:
        assembly.variable.sort_rows(free.indptr, free.indices, free.data)
        free.has_sorted_indices = True
    if opts.pointwise_degree is not None:
        L = corrections.highorder.pointwise_rows(geo.points, free.indptr, free.indices, hv,
                                                 opts.pointwise_degree, k=geo.dim)
        return L, None
    # from the operator without mirror images: f need not satisfy Neumann conditions, and the
    # moment correction handles the one-sided rows
    return corrections.moment_correction(free, geo.points, geo.dim)


def _galerkin(geo: Geometry, widths: Widths, opts: Options, out: Pencil, label: np.ndarray | None,
              report: Callable[[float, str], None] | None) -> None:
    # the symmetric pencil from the kernel integrated over the cells, where asked for
    # (quadrature="galerkin"); op.L keeps the vertex rows; label: each point's part, where the
    # pencil keeps them apart
    gal = corrections.galerkin
    if opts.quadrature != "galerkin":
        return
    if report is not None:
        report(0.95, "Galerkin pencil")
    tri, weld = gal.simplices(geo), geo.copies()
    if weld is not None:  # copies of a vertex welded, as FEM's: a seam is no boundary
        tri = fem.welded_cells(tri, weld)
    h = GALERKIN_H_SCALE * geo.spacing**2 if widths.h_auto else widths.h
    dog = not opts.plain  # its own semidefinite check below, whatever the vertex pencil's fell back to
    # the vertex pencil's boundary samples (one sampling per build), reflected across for the
    # quadrature points within the Galerkin kernel's cut-off
    radius = cutoff_radius(widths.largest, opts.tol)
    boundary = geo.boundary_samples(radius, None if weld is None else tri) if opts.neumann else None
    guard = MemoryGuard(len(tri) * tri.shape[1], opts.dtype, opts.max_memory, h)
    surface = geo.faces is not None and geo.ambient_dim == 3
    folds = gal.creases(geo.points, tri) if surface else None
    hv = None
    # the feature width where the width is automatic (an explicit h, as the smoothing flow's, is
    # kept), never on noise: its fake creases and opposite sides would narrow it
    if surface and opts.feature_width is not False and (widths.h_auto or opts.feature_width) \
            and gal.shape_measures(geo.points, tri)[1] <= NOISE_ROUGHNESS:
        grooves = gal.creases(geo.points, tri, concave=True)
        hv = corrections.features.feature_widths(geo.points, geo.normals(), grooves, h)
    S, m = gal.galerkin_pencil(geo.points, tri, h, geo.dim, dog=dog, crease_edges=folds, boundary=boundary,
                               tol=opts.pencil_tol, guard=guard, h_vertex=hv)
    if weld is not None:
        S, m = fem.expand_copies(sp.csr_matrix(S), m, weld)
    inv = np.divide(1.0, m, out=np.zeros_like(m), where=m > 0)
    L = (sp.diags(inv) @ S).tocsr().astype(opts.dtype)
    L = fem.separate_rows(L, L, label)[1]  # checked as it is used
    if dog and opts.check_psd:
        margin, reason = corrections.psd.check(L, m, geo.points, _psd_faces(geo), "Galerkin pencil")
        if reason is not None:
            # its cells are too coarse for its narrow kernel: linear FEM on the same cells, the
            # floor a pencil over cells is held to (the vertex pencil reads the same cells worse)
            warnings.warn(f"quadrature='galerkin': -S of the Galerkin pencil is not semidefinite "
                          f"(margin {margin:.3g}: the cells are too coarse for its kernel); linear FEM "
                          "on them instead", MeshWarning, stacklevel=user_stacklevel())
            floor = _fem(geo, opts, None)
            out.L_sym, out.quadrature, out.mass = floor.L_sym, "fem", floor.mass
            if not opts.pointwise:
                out.L = out.L_sym
            return
        out.psd_margin = margin
    out.L_sym, out.quadrature, out.quadrature_h = L, "galerkin", float(h)
    if weld is not None:  # copies share their representative's mass
        out.mass = m
    out.narrowed = 0.0 if hv is None else float(geo.mass[hv < h].sum() / geo.mass.sum())
    if not opts.pointwise:
        out.L = L


def _fem(geo: Geometry, opts: Options, report: Callable[[float, str], None] | None) -> Pencil:
    # no kernel: linear FEM on the cells, copies of a vertex welded (meshlap.fem)
    if report is not None:
        report(0.5, "FEM pencil")
    S, m = fem.lumped_pencil(geo) if opts.mass == "lumped" else \
        fem.fem_pencil(geo, weld=geo.copies(), mass=opts.mass)
    step = denoise.noise_step(geo) if opts.denoise else None
    points, scale = None, None
    if step is not None and step.sigma > 0:  # FEM on the positions after a step that takes the noise out
        if report is not None:
            report(0.7, "denoised positions")
        points = step.points
        S1, m1 = fem.fem_pencil(geo, weld=geo.copies(), mass=opts.mass, points=points)
        points, kept = denoise.kept_shapes(geo.points, points, m, m1, fem.part_labels(geo)[1],
                                           step.sigma / geo.spacing)
        if kept.any():  # parts the step shrank beyond the noise's share keep their positions
            S1, m1 = fem.fem_pencil(geo, weld=geo.copies(), mass=opts.mass, points=points)
        # the noise the step left still inflates the metric (denoise.area_left), and with it the
        # masses: eigenvalues 1.2-1.9% low at 0.1 mean edges on four scans, all nine low; a part
        # that kept its positions keeps its masses
        scale = np.where(kept, 1.0, 1.0 / (1.0 + step.area_left))
        S, m = S1, m1 * scale
    inv = np.divide(1.0, m, out=np.zeros_like(m), where=m > 0)
    L = (sp.diags(inv) @ S).tocsr().astype(opts.dtype)
    if report is not None:
        report(1.0, "done")
    return Pencil(L, None if opts.pointwise == "fit" else L, "fem", quadrature="fem", mass=m, points=points,
                  area_scale=scale)


def part_label(geo: Geometry, opts: Options) -> np.ndarray | None:
    """The part of each point where the pencil keeps a mesh's parts apart, else None.

    The kernel reaches across the air between the parts of a mesh: the pencil has no pairs
    between parts, so that each part keeps its own zero eigenvalue (a plain kernel after the
    semidefinite check's fallback too); the paper's operator, eq. (1), is left as it is.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(200, seed=0)
    >>> g = meshlap.geometry.from_mesh(np.vstack([V, V + 3]), np.vstack([F, F + 200]))
    >>> [None if (x := part_label(g, Options.resolve(g, None, correction=c))) is None else int(x.max())
    ...  for c in ("richardson", "none")]
    [1, None]
    """
    parts = fem.part_labels(geo)
    return None if parts is None or parts[0] < 2 or not keeps_parts(opts) else parts[1]


def keeps_parts(opts: Options) -> bool:
    """Whether the pencil of these options keeps a mesh's parts apart: all but the paper's
    operator, eq. (1), which is left as it is.

    Examples
    --------
    >>> import meshlap
    >>> g = meshlap.geometry.from_mesh(*meshlap.shapes.sphere(200, seed=0))
    >>> [keeps_parts(Options.resolve(g, None, correction=c)) for c in ("richardson", "none")]
    [True, False]
    """
    return not (opts.correction == "none" and opts.quadrature == "vertex")


def assemble(geo: Geometry, widths: Widths, opts: Options,
             report: Callable[[float, str], None] | None = None) -> Pencil:
    """The symmetric pencil of one geometry at its widths: kernel rows, the
    semidefinite check, the moment scale, the Galerkin pencil (and the rows that come with it).

    Examples
    --------
    >>> import meshlap
    >>> from meshlap import pipeline, widths
    >>> g = meshlap.geometry.from_mesh(*meshlap.shapes.sphere(800, seed=0))
    >>> opts = pipeline.Options.resolve(g, None)
    >>> p = assemble(g, widths.choose(g, None, plain=False, curvature_limit=opts.curvature_limit), opts)
    >>> p.correction, p.quadrature, p.L is None  # the fitted rows are not the pencil's
    ('richardson', 'vertex', True)
    """
    if opts.quadrature == "fem":
        return _fem(geo, opts, report)
    radius = cutoff_radius(widths.largest, opts.tol)
    dog = not opts.plain
    kern = Kernel(geo.dim, dog=dog, normals=geo.normals() if opts.arc_distance else None, tol=opts.tol)
    frames = geo.boundary_frames(radius) if (opts.neumann or dog) else None
    band = None if frames is None else frames[0]
    if opts.matrix_free:
        label = part_label(geo, opts)
        apply = assembly.MatrixFree.build(geo.points, geo.mass, widths, kern, label)
        if dog:
            apply.scale = corrections.second_moment_scale(apply, geo.points, geo.mass, band, geo.dim)
        if opts.neumann:
            images = corrections.images.band_images(geo.points, frames, geo.mass, widths.h, radius, dog,
                                                    geo.dim, opts.tol)
            apply.images = images if images is None or label is None else fem.separate_parts(images, label)
        return Pencil(None, None, opts.correction, moment_scale=apply.scale, matrix_free=apply,
                      boundary_rows=0 if frames is None or not opts.neumann else len(band))
    guard = guard_for(geo, opts, widths.h, opts.neumann and frames is not None)
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

    label = part_label(geo, opts)
    free, L = stage(kern, "kernel rows")
    kept, L = fem.separate_rows(free, L, label)  # checked as it is used
    out = Pencil(L, None if opts.pointwise == "fit" else L, opts.correction,
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
            held, out.L_sym, out.L, L, free = [free], None, None, None, None
            free, L = stage(replace(kern, dog=False), "plain kernel rows", held)
            kept, L = fem.separate_rows(free, L, label)
            out.L_sym, out.L = L, None if opts.pointwise == "fit" else L
    if out.correction != "none":
        if report is not None:
            report(0.8, "moment scale")
        out.moment_scale = corrections.second_moment_scale(
            lambda X: kept @ X, geo.points, geo.mass, band, geo.dim,
            None if moments[0] is None or kept is not free else moments[0][:, :1 + geo.points.shape[1]])
        L.data *= out.moment_scale
    if opts.pointwise is True:
        if report is not None:
            report(0.9, "point-wise rows")
        out.L, out.pointwise_unchanged = _stencil_rows(geo, free, hv, opts)
    if not opts.plain or opts.quadrature == "galerkin":
        _galerkin(geo, widths, opts, out, label, report)
    if report is not None:
        report(1.0, "done")
    return out


def review(opts: Options, p: Pencil) -> Pencil:
    """The warning of pencil ``p``'s fallback to the plain kernel where that pencil is used,
    pointed at the user's line that asked for the pencil. Returns ``p``."""
    # the vertex pencil's fallback matters where that pencil is used: as the symmetric pencil
    # or as the stencil of rows on the kernel's own pattern (the fitted rows have their own);
    # the Galerkin pencil checks its own Richardson kernel, whatever the vertex pencil fell back to
    if p.fallback_reason is not None and (p.quadrature == "vertex" or opts.pointwise is True):
        warnings.warn(p.fallback_reason + "; pass a larger h to keep the correction", MeshWarning,
                      stacklevel=user_stacklevel())
    return p
