"""The one place that chooses which operator :func:`meshlap.laplacian` builds, and records why.

The builders are mechanisms, each deterministic and named (``operator=``):

========== =================================================================================
"fem"      linear finite elements on the mesh's cells, intrinsic Delaunay, lumped (Voronoi) mass
           (:mod:`meshlap.fem`): the symmetric pencil ``(S, M)``
"kernel"   the corrected heat kernel on the vertices (Richardson kernel, arc distances, mirror
           images; :class:`meshlap.MeshLaplacian`)
"galerkin" the corrected heat kernel integrated over the cells (:mod:`meshlap.corrections.galerkin`)
"paper"    Belkin, Sun and Wang's operator, eq. (1), bit for bit
========== =================================================================================

and ``op @ f`` of all but the paper's applies the fitted point-wise rows
(:mod:`meshlap.corrections.rowchoice`), which read the points alone.

The policy for ``operator="auto"`` reads its few thresholds from :mod:`meshlap.tuned`, each with
where it came from:

- an input with cells gets the "fem" pencil: linear FEM on the intrinsic Delaunay triangulation of
  its cells (:mod:`meshlap.fem`), so its worst case is linear FEM there, and parts stay apart
  (one zero eigenvalue per connected part); a surface whose vertices carry normal noise adding
  more than ``NOISE_FLOOR`` to the area gets FEM on the positions after a bi-Laplacian step
  that takes it out (:mod:`meshlap.denoise`; ``denoise=True`` or ``False`` decides instead)
  where the noise, not the shape, dominates what smoothing takes out across at least half of
  the surface's edges (:func:`meshlap.denoise.noise_extent`: a lower bound from the signs of the
  positions' bi-Laplacian against white noise's, no constant; recorded), and the masses carry
  the area the noise the step left still adds (:func:`meshlap.denoise.area_left`); the kernel
  keeps what FEM cannot give: ``op @ f``, point-wise convergent rows;
- a curve's segments get the "galerkin" pencil: the heat kernel integrated over the segments.
  Its failure on surfaces is a triangle too thin for the kernel's quadrature, and a segment has
  no shape; on the 24 synthetic curves of ``benchmarks/bench_curves.py`` it is 0.02-0.49× linear
  FEM's error, on the 47 boundary loops of 32 real meshes 0.05-0.84× (median 0.09×;
  ``benchmarks/bench_loops.py``);
- a surface's or a curve's point cloud gets the "fem" pencil on every point's local Delaunay
  star, each triangle weighted by a third (a segment by a half: most come from each of their
  corners): the triangles
  robust-laplacian's point-cloud Laplacian starts from, without its tufted cover; on 16,000
  random sphere points 0.20% off on eigenvalues 1-9 against the kernel's 0.29% and
  robust-laplacian's 7.8%;
- a cloud whose normal noise the geometry measured and projected away
  (:func:`meshlap.geometry.noise.noise_reading`, recorded: noise above about 14% of the
  spacing that cubic fits do not explain, where a coarse sampling's missed shape would be
  explained) gets the "kernel" pencil: the
  projected points keep a tangential jitter that makes the local triangles' shapes random,
  while the kernel's width averages over many points (1% radial noise, 16,000 points: 0.29%
  against FEM's 0.75%), as does a cloud filling a volume, whose Delaunay tetrahedra span its
  concavities and the slivers of its hull (FEM on them: better on 2 of 6 rows, but up to 580%
  off where the kernel is at most 69%; ``benchmarks/bench_pointcloud.py --volume``);
- a kernel width ``h`` or an option of the kernel (``correction``, ``quadrature``, ...) asks for
  the kernel: "paper" with ``correction="none"``, "galerkin" with ``quadrature="galerkin"``,
  else "kernel".

On a triangle or polygon mesh the FEM pencil's spectra come from the seven-node quadratic
elements on the same triangles (``Decision.elements``, :mod:`meshlap.quadratic`): the same
surface, at fourth order instead of second. The one limit is their cost: a sparse LDLᵀ of about
six unknowns per vertex, which grows faster than N; beyond ``QUADRATIC_MAX_UNKNOWNS`` (about
16,500 vertices, 6.6 s of CPU for 10 pairs) eigs solves the linear pencil, whose error is then
smallest, unless asked for ``elements="quadratic"``.

The decision, with what it read, is kept on the operator as ``op.decision``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace
from typing import Any, Literal

import numpy as np

from .corrections.highorder import fewest_points
from .denoise import noise_extent, surface_noise
from .errors import MeshError, MeshWarning, user_stacklevel
from .fem import lumped_pencil, part_labels
from .geometry.pointcloud import noise_reading
from .quadratic import unknowns as n_quadratic
from .tuned import NOISE_AREA, NOISE_FLOOR, QUADRATIC_MAX_UNKNOWNS

__all__ = ["OPERATORS", "Decision", "as_built", "decide"]

#: ``operator`` values of :func:`meshlap.laplacian`.
OPERATORS = ("auto", "fem", "kernel", "galerkin", "paper")
Operator = Literal["auto", "fem", "kernel", "galerkin", "paper"]

_REASONS = {
    "cells": "the input has cells: linear FEM on them (intrinsic Delaunay, Voronoi mass), point-wise rows "
             "fitted by the kernel",
    "tetrahedra": "the input has tetrahedra: linear FEM on them (lumped mass: the consistent mass's row "
                  "sums), point-wise rows fitted by the kernel",
    "segments": "a curve's segments: the corrected heat kernel integrated over them (consistent mass); a "
                "segment has no shape to resolve, unlike a thin triangle",
    "noisy surface": "the input has cells and normal noise that adds area and dominates what smoothing "
                     "takes out across most edges: linear FEM on the positions after a bi-Laplacian step "
                     "that takes it out, masses less the area the noise it left adds",
    "stars": "a surface's or a curve's point cloud: linear FEM on every point's local Delaunay star "
             "(a third or a half each), point-wise rows fitted by the kernel",
    "noisy": "a point cloud with normal noise (projected onto its tangent planes): the corrected "
             "heat kernel, whose width averages what the projection leaves",
    "cloud": "a point cloud without local stars to integrate over (a volume): the corrected heat kernel "
             "on the points",
    "h": "a kernel width h was given: the corrected heat kernel at that width",
    "options": "options of the kernel were given ({}): the kernel they configure",
    "asked": "operator={!r} was asked for",
    "floor": "{}; but -S of the Galerkin pencil was not semidefinite (its cells are too coarse for its "
             "kernel), so linear FEM on the same cells was built",
}


#: options of the FEM pencil itself, which do not ask for the kernel
_FEM_OWN = {"denoise", "mass"}


@dataclass(frozen=True)
class Decision:
    """What :func:`decide` chose and why.

    Attributes
    ----------
    operator : str
        The symmetric pencil built: "fem", "kernel", "galerkin" or "paper".
    rows : str
        What ``op @ f`` applies: "fitted" (point-wise rows from the points alone) or "pencil"
        (the pencil's own L: the paper's operator, or an option of the kernel's rows).
    reason : str
        Why, in a sentence.
    measured : dict
        The quantities read from the input (vertices, cells, parts, welded copies, noise).
    denoise : bool
        Whether the FEM pencil is built on the positions after a bi-Laplacian step that takes the
        normal noise out (asked for, or read: :func:`meshlap.geometry.noise.noise_reading`).
    elements : str
        What :func:`meshlap.spectral.eigs` solves: "quadratic" (the seven-node elements on the
        same triangles, :mod:`meshlap.quadratic`) for the FEM pencil of a triangle or polygon
        mesh of at most ``QUADRATIC_MAX_UNKNOWNS`` of their unknowns (about 16,500 vertices;
        recorded as ``measured["quadratic unknowns"]``), else "linear" (the pencil itself).

    Examples
    --------
    >>> import meshlap
    >>> d = meshlap.laplacian(*meshlap.shapes.sphere(300, seed=0)).decision
    >>> d.operator, d.rows, d.measured["parts"]
    ('fem', 'fitted', 1)
    """

    operator: str
    rows: str
    reason: str
    measured: dict = field(default_factory=dict)
    denoise: bool = False
    elements: str = "linear"

    @property
    def built(self) -> str:
        """What was built, in a few words (``"fem pencil, fitted rows"``): the repr's and the CLI's."""
        return f"{self.operator} pencil, {self.rows} rows"

    def __str__(self) -> str:
        facts = ", ".join(f"{k}={v}" for k, v in self.measured.items())
        return f"{self.built}: {self.reason} ({facts})"


def decide(geo: Any, operator: str = "auto", h: Any = None, kernel_options: dict | None = None
           ) -> Decision:
    """The operator :func:`meshlap.laplacian` builds for ``geo``, and why.

    Parameters
    ----------
    geo : Geometry
        The input.
    operator : {"auto", "fem", "kernel", "galerkin", "paper"}
        What was asked for.
    h : float or array_like, optional
        A kernel width, if given (it asks for the kernel).
    kernel_options : dict, optional
        The kernel's options given (``correction``, ``quadrature``, ...): they ask for it; the
        FEM pencil's own (``denoise``, ``mass``) do not, but a named mass keeps ``eigs`` on it.

    Examples
    --------
    >>> import meshlap
    >>> g = meshlap.geometry.point_cloud_geometry(meshlap.samples.sphere_points(500), 2)
    >>> decide(g).operator, decide(g, h=0.01).reason.startswith("a kernel width")
    ('fem', True)
    """
    if operator not in OPERATORS:
        raise MeshError(f"operator must be one of {', '.join(map(repr, OPERATORS))}; got {operator!r}")
    opts = {k: v for k, v in (kernel_options or {}).items() if v is not None}
    has_cells = geo.tiled
    stars = not has_cells and "fem_cells" in geo._cache
    projected = "input_points" in geo._cache  # the cloud's noise moved its points
    measured: dict = {"vertices": geo.n_points, "k": geo.dim}
    denoise = opts.get("denoise")
    read = denoise is None and operator == "auto" and h is None and not set(opts) - _FEM_OWN and \
        has_cells and geo.faces is not None and geo.dim == 2 and geo.ambient_dim == 3
    if read:  # how much area the noise adds (the height fits, as a cloud's) and where it dominates
        reading = geo._cached("noise_reading", lambda: noise_reading(geo.points, 2))

        def extent() -> float:
            return noise_extent(geo.points, geo.normals(), *lumped_pencil(geo), geo.edges())

        denoise = NOISE_AREA * reading.ratio >= NOISE_FLOOR and geo._cached("noise_extent", extent) >= 0.5
    if "noise_reading" in geo._cache:
        reading = geo._cache["noise_reading"]
        measured["normal noise / spacing²"] = round(reading.ratio, 4)
        measured["share cubic fits leave"] = round(reading.unexplained, 3)
        measured["spread over noise's"] = round(reading.spread, 3)
    if "noise_extent" in geo._cache:
        measured["edges where noise dominates ≥"] = round(geo._cache["noise_extent"], 3)
    if has_cells:
        measured["parts"] = part_labels(geo)[0]
        noise = surface_noise(geo) if denoise else 0.0
        if noise > 0:
            measured["normal noise / mean edge"] = round(noise / geo.spacing, 4)
        weld = geo.copies()
        measured["welded copies"] = 0 if weld is None else int((weld != np.arange(len(weld))).sum())
    if operator == "auto":
        if opts.get("correction") == "none":
            operator, reason = "paper", _REASONS["options"].format("correction='none'")
        elif opts.get("quadrature") == "galerkin":
            operator, reason = "galerkin", _REASONS["options"].format("quadrature='galerkin'")
        elif kernel := sorted(set(opts) - _FEM_OWN):
            operator, reason = "kernel", _REASONS["options"].format(", ".join(kernel))
        elif h is not None:
            operator, reason = "kernel", _REASONS["h"]
        elif has_cells and geo.dim == 1:
            operator, reason = "galerkin", _REASONS["segments"]
        elif has_cells or stars and not projected:
            cells = "tetrahedra" if geo.dim == 3 else "cells"
            operator, reason = "fem", _REASONS["noisy surface" if read and denoise else cells if has_cells
                                               else "stars"]
        else:
            operator, reason = "kernel", _REASONS["noisy" if stars else "cloud"]
    else:
        reason = _REASONS["asked"].format(operator)
    if operator == "fem" and not (has_cells or stars) or operator == "galerkin" and not has_cells:
        raise MeshError(f"operator={operator!r} integrates over cells; this {geo.source} has none "
                        "(use operator='kernel' or 'auto')")
    if stars and operator == "fem" and geo._cache.get("star_pieces") is not None:
        measured["parts"] = pieces = geo._cache["star_pieces"][0]
        if pieces > 1:  # a mesh's parts are in its cells; a cloud's are read from its stars: say so
            label = geo._cache["star_pieces"][1]
            sizes = np.sort(np.bincount(label[label >= 0]))[::-1]
            shown = ", ".join(f"{s:,}" for s in sizes[:6]) + (", ..." if len(sizes) > 6 else "")
            warnings.warn(f"the point cloud falls into {pieces} pieces that no local Delaunay star joins "
                          f"({shown} points), so its pencil has {pieces} zero eigenvalues: separate "
                          "objects, or parts of one whose surface between them has no points (a CAD "
                          "part's vertices leave its flat faces empty; pass its faces then, or "
                          "operator='kernel', whose support reaches across a gap of a few spacings)",
                          MeshWarning, stacklevel=user_stacklevel())
    pencil_rows = operator == "paper" or opts.get("pointwise") in (True, False) or \
        opts.get("pointwise_degree") is not None
    if not pencil_rows and geo.n_points < fewest_points(geo.dim):
        pencil_rows = True
        reason += (f"; but {geo.n_points} points are too few to fit point-wise rows on "
                   f"({fewest_points(geo.dim)} at least), so op @ f applies the pencil")
    # a mass named for the pencil asks for the pencil's own spectra
    quadratic = operator == "fem" and has_cells and geo.faces is not None and geo.dim == 2 and \
        "mass" not in opts
    if quadratic:  # n + edges + triangles, edges ≈ 1.5 triangles: the cost, not the accuracy, limits it
        measured["quadratic unknowns"] = unknowns = n_quadratic(geo)
        quadratic = unknowns <= QUADRATIC_MAX_UNKNOWNS
    return Decision(operator, "pencil" if pencil_rows else "fitted", reason, measured, bool(denoise),
                    "quadratic" if quadratic else "linear")


def as_built(decision: Decision, quadrature: str | None) -> Decision:
    """The decision as the build carried it out, given the pencil's ``quadrature`` in effect (None
    before the pencil is built): a Galerkin pencil that fails its semidefinite check is replaced
    by linear FEM on the same cells (:func:`meshlap.pencil.assemble`), and says so.

    Examples
    --------
    >>> d = Decision("galerkin", "fitted", "asked")
    >>> as_built(d, "galerkin") is d, as_built(d, "fem").operator
    (True, 'fem')
    """
    if decision.operator == "galerkin" and quadrature == "fem":
        return replace(decision, operator="fem", reason=_REASONS["floor"].format(decision.reason))
    return decision
