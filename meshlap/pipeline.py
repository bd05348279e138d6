"""The data flow from a Geometry to the operator's matrices, one stage after the other.

    Geometry ─▶ widths.choose ─▶ Kernel ─▶ assembly.assemble ─▶ corrections ─▶ Built

:class:`Options` (:mod:`meshlap.options`, here too) resolves what the caller asked for against
what the geometry allows (one default for every input: the Richardson kernel, arc distances and
the curvature cap where normals exist, mirror images where there is a boundary, point-wise
rows); :func:`build` checks
what can refuse the build and returns :class:`Built`, which the operator only holds and which
makes each of its two parts on first use: the symmetric pencil (:mod:`meshlap.pencil`) and
the rows ``op @ f`` applies. Every stage reads the Geometry's points, masses, dimension and
frames, never where they came from, so meshes, clouds, curves, volumes and one MPI rank's
rows go through the same code (:mod:`meshlap.distributed` runs its stages eagerly: collectives
must not run at different times on different ranks).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np
import scipy.sparse as sp

from . import assembly, corrections, pencil
from .assembly import Kernel
from .geometry import Geometry
from .options import CORRECTED_TOL, CORRECTIONS, DEFAULT_TOL, POINTWISE, QUADRATURES, Options, default_tol
from .pencil import Pencil
from .widths import Widths

__all__ = ["CORRECTED_TOL", "CORRECTIONS", "DEFAULT_TOL", "POINTWISE", "QUADRATURES", "Built", "Once",
           "Options", "Rows", "build", "default_tol", "fitted_rows"]


class Once:
    """A value made on first use, once: under a lock, whichever thread asks first (the others
    wait for it); a pickle or a copy holds the value, made before it is written, not what
    makes it. An exception leaves it to be made on the next use.

    Examples
    --------
    >>> made = []
    >>> once = Once(lambda: made.append(1) or len(made))
    >>> once.pending, once.get(), once.get(), once.pending
    (True, 1, 1, False)
    """

    def __init__(self, make: Callable[[], Any]) -> None:
        self._make: Callable[[], Any] | None = make
        self._value: Any = None
        self._lock = threading.Lock()

    @property
    def pending(self) -> bool:
        """Whether the value is still to be made."""
        return self._make is not None

    def get(self) -> Any:
        """The value, made now on the first call."""
        if self._make is not None:
            with self._lock:
                if self._make is not None:
                    self._value = self._make()
                    self._make = None
        return self._value

    def held(self) -> Any:
        """The value when made, else None (makes nothing)."""
        return self._value

    def __getstate__(self) -> dict:
        return {"_value": self.get()}

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state, _make=None, _lock=threading.Lock())


class Rows(NamedTuple):
    """What ``op @ f`` applies: ``L`` (None when matrix-free), the rows the moment correction
    left unchanged, and the per-point width and degree of the fitted rows."""

    L: sp.csr_matrix | None
    unchanged: np.ndarray | None = None
    choice: Any = None


class Built:
    """The two parts of one build, each made on first use (:class:`Once`) with the bits an
    eager build gives: the symmetric pencil (:meth:`assemble`, a :class:`~meshlap.pencil.Pencil`)
    and the rows ``op @ f`` applies (:meth:`fit_rows`). The fitted rows read the points alone;
    other rows come with the pencil, so asking for them builds it.

    Examples
    --------
    >>> b = Built(lambda: Pencil(None, None, "none"))
    >>> b.pencil_pending, b.fit_rows().L, b.pencil_pending
    (True, None, False)
    """

    def __init__(self, make_pencil: Callable[[], Pencil],
                 make_rows: Callable[[], Rows] | None = None) -> None:
        self._pencil = Once(make_pencil)
        self._rows = Once(make_rows or _rows_of(self._pencil))

    pencil_pending = property(lambda self: self._pencil.pending, doc="Whether the pencil is to be built.")
    rows_pending = property(lambda self: self._rows.pending, doc="Whether the rows are still to be made.")
    held_pencil = property(lambda self: self._pencil.held(), doc="The pencil if built, else None.")
    held_rows = property(lambda self: self._rows.held(), doc="The rows if made, else None.")

    def assemble(self) -> Pencil:
        """The symmetric pencil, built on the first call."""
        return self._pencil.get()

    def fit_rows(self) -> Rows:
        """The rows ``op @ f`` applies, made on the first call."""
        return self._rows.get()


def _rows_of(pencil: Once) -> Callable[[], Rows]:
    # the rows that come with the pencil; the closure holds the pencil's Once, not the Built
    # (a bound method would make a cycle: the matrices held until a garbage collection)
    def rows() -> Rows:
        p = pencil.get()
        return Rows(p.L, p.pointwise_unchanged)
    return rows


def fitted_rows(geo: Geometry, opts: Options, report: Callable[[float, str], None] | None = None) -> Rows:
    """The default's rows ``op @ f`` applies (``pointwise="fit"``): width and degree chosen per
    point from the points alone (:func:`meshlap.corrections.rowchoice.choose_rows`), whose
    stages report to ``report`` as "point-wise rows: <stage>".

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> g = meshlap.geometry.from_mesh(*meshlap.shapes.sphere(800, seed=0))
    >>> rows = fitted_rows(g, Options.resolve(g, None))
    >>> bool(np.allclose(rows.L @ np.ones(800), 0)), rows.unchanged is None
    (True, True)
    """
    # the positions f was sampled at: a denoised cloud's input points, whose noise the rows
    # must average out (the projected points would hide it)
    P = geo._cache.get("input_points", geo.points)
    tick = None if report is None else (lambda stage: report(0.9, f"point-wise rows: {stage}"))
    # coincident copies (an unwelded seam, a pole repeated per segment) are one point to the
    # rows: as many copies as a row's neighbours put its last one at distance 0, and no width.
    # The FEM pencil's welding finds them (copies in the input points stay copies when denoised)
    L, choice = corrections.copies.distinct_rows(
        lambda d: corrections.rowchoice.choose_rows(P[d], k=geo.dim, progress=tick), geo.copies())
    if L.dtype != opts.dtype:
        L.data = L.data.astype(opts.dtype)
    return Rows(L, None, choice)


def wider_rows(geo: Geometry, choice: Any) -> sp.csr_matrix:
    """The fitted rows ``choice`` (:func:`fitted_rows`) again, twice as wide
    (:func:`meshlap.corrections.rowchoice.wider_rows`), on the same distinct points: the second
    operator of :meth:`meshlap.MeshLaplacian.error_estimate`.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> g = meshlap.geometry.from_mesh(*meshlap.shapes.sphere(800, seed=0))
    >>> rows = fitted_rows(g, Options.resolve(g, None))
    >>> bool(np.allclose(wider_rows(g, rows.choice) @ np.ones(800), 0))
    True
    """
    P = geo._cache.get("input_points", geo.points)
    copies = corrections.copies
    return copies.distinct_rows(lambda d: (corrections.rowchoice.wider_rows(
        P[d], copies.take(choice, d), k=geo.dim), None), geo.copies())[0]


def _fit_later(geo: Geometry, opts: Options, report: Callable[[float, str], None] | None
               ) -> Callable[[], Rows]:
    # the first use reports its stages to the build's progress, and is done again at 1.0
    def fit() -> Rows:
        if report is not None:
            report(0.9, "point-wise rows")
        rows = fitted_rows(geo, opts, report)
        if report is not None:
            report(1.0, "done")
        return rows
    return fit


def build(geo: Geometry, widths: Widths, opts: Options,
          report: Callable[[float, str], None] | None = None, *, review: bool = False) -> Built:
    """Stages 3-5 for one geometry and its widths, each part made on first use: the symmetric
    pencil (kernel, assembly, corrections: :func:`meshlap.pencil.assemble`, then
    :func:`meshlap.pencil.review` with ``review``) and the rows ``op @ f`` applies. What refuses
    the build comes now: the memory guard's estimate of the kernel's rows against
    ``opts.max_memory``, from a sample of rows (:func:`meshlap.assembly.refuse_early`).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> from meshlap import widths
    >>> g = meshlap.geometry.from_mesh(*meshlap.shapes.sphere(800, seed=0))
    >>> opts = Options.resolve(g, None)
    >>> b = build(g, widths.choose(g, None, plain=False, curvature_limit=opts.curvature_limit), opts)
    >>> b.pencil_pending, b.rows_pending  # neither made yet
    (True, True)
    >>> bool(np.allclose(b.fit_rows().L @ np.ones(800), 0)), b.pencil_pending  # the fitted rows alone
    (True, True)
    >>> b.assemble().correction, b.assemble().fallback_reason
    ('richardson', None)
    """
    if not opts.matrix_free and opts.quadrature != "fem":
        # the normals of arc distances only where the chord count does not fit (op @ f never reads them)
        kern = Kernel(geo.dim, dog=not opts.plain, tol=opts.tol)
        images = opts.neumann and geo.boundary is not None and bool(geo.boundary.any())
        guard = pencil.guard_for(geo, opts, widths.h, images)
        assembly.refuse_early(geo.points, geo.mass, widths, kern, guard,
                              geo.normals if opts.arc_distance else None)

    def make_pencil() -> Pencil:
        p = pencil.assemble(geo, widths, opts, report)
        return pencil.review(opts, p) if review else p

    # the fitted rows read the points alone (0.5 s of CPU at 16k vertices), the pencil the
    # kernel (0.4 s): spectra, heat flow and smoothing never fit the rows, op @ f never
    # builds the pencil
    rows = _fit_later(geo, opts, report) if opts.pointwise == "fit" else None
    if report is not None:
        report(1.0, "done")
    return Built(make_pencil, rows)
