"""Stages 3 and 4 of the pipeline: the kernel, and its rows assembled into CSR.

:class:`Kernel` says what each pair's weight is (intrinsic dimension k for the normalization
1/(h (4πh)^{k/2}), plain Gaussian or difference of Gaussians, Euclidean or arc distance, the
tolerance that cuts it off); :func:`assemble` evaluates it for positions, masses and widths
and knows nothing else about where they came from. Three paths, one result:

* :mod:`~meshlap.assembly.grid`: a cell grid for points in at most 3 dimensions, the
  paper's operator at one h (count, then fill; also the matrix-free product);
* :mod:`~meshlap.assembly.variable`: the same grid with per-point widths, the difference of
  Gaussians and arc distances;
* :mod:`~meshlap.assembly.pairs`: a k-d tree's close pairs for points in R^d, d > 3.

A memory guard counts the entries before anything is allocated.
"""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from ..errors import OperatorTooLargeError, user_stacklevel
from ..widths import Widths
from . import grid, pairs, variable
from .grid import cutoff_radius, normalization, truncation_bound

__all__ = ["Kernel", "MatrixFree", "MemoryGuard", "assemble", "available_memory", "csr", "cutoff_radius",
           "fmt_bytes", "grid", "normalization", "pairs", "refuse_early", "reweigh", "truncation_bound",
           "variable"]

_INT32_MAX = np.iinfo(np.int32).max


@dataclass(frozen=True)
class Kernel:
    """What a pair's weight is: k, plain or difference of Gaussians, distances, cut-off."""

    dim: int
    dog: bool = False
    normals: np.ndarray | None = None
    tol: float = 1e-8

    @property
    def plain(self) -> bool:
        """The paper's kernel: one Gaussian of Euclidean distance."""
        return not self.dog and self.normals is None


def available_memory() -> int:
    """Bytes of memory available to this process now (MemAvailable on Linux)."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return 8 << 30


def fmt_bytes(b: float) -> str:
    """``1536`` → ``'1.5 KiB'``."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if b < 1024 or unit == "TiB":
            return f"{b:.1f} {unit}" if unit != "B" else f"{int(b)} B"
        b /= 1024
    return f"{b:.1f} TiB"


def csr(data: np.ndarray, indices: np.ndarray, indptr: np.ndarray, n: int) -> sp.csr_matrix:
    """Wrap CSR arrays without copying them. scipy's constructor would copy int64 index arrays
    down to int32 when their contents fit; setting the arrays directly keeps the type chosen
    here. Rows start with their diagonal, so the indices are not sorted."""
    L = sp.csr_matrix((n, n), dtype=data.dtype)
    L.data, L.indices, L.indptr = data, indices, indptr
    L.check_format(full_check=False)
    L.has_sorted_indices = False
    return L


@dataclass
class MemoryGuard:
    """Refuses, before allocating, a build whose matrices would exceed ``max_memory`` bytes.

    The guard counts every matrix the build holds at its peak, not only L: ``values`` bytes
    of values and ``patterns`` index arrays (indices and row pointers) per entry of the
    kernel's pattern. :meth:`for_build` says what those are for one build.
    """

    n: int
    dtype: np.dtype
    max_memory: int
    h: float
    values: int | None = None
    patterns: int = 1

    @classmethod
    def for_build(cls, n: int, dtype: np.dtype, max_memory: int, h: float, *, images: bool,
                  pointwise: bool | str, own_pattern: bool = False) -> MemoryGuard:
        """The guard of one build: the kernel's rows (``dtype``); with mirror images at a
        boundary a second matrix, worked in float64 and cast back; with point-wise rows a
        third value array on the kernel's pattern, or float64 values with an index array of
        their own (``own_pattern``, the fixed-degree rows).

        Examples
        --------
        >>> g = MemoryGuard.for_build(1000, np.dtype(np.float64), 1 << 30, 0.01, images=True, pointwise=True)
        >>> g.values, g.patterns      # L without and with images, the point-wise values; two patterns
        (24, 2)
        """
        size = np.dtype(dtype).itemsize
        values, patterns = size, 1
        if images:
            values += 8 + (size if size != 8 else 0)
            patterns += 1
        if pointwise:
            values += 8 if own_pattern else size
            patterns += 1 if own_pattern else 0
        return cls(n, np.dtype(dtype), max_memory, h, values, patterns)

    def bytes_for(self, nnz: float) -> float:
        """Bytes of the build's value arrays and index structures for ``nnz`` entries."""
        idx = 4 if (nnz <= _INT32_MAX and self.n <= _INT32_MAX) else 8
        values = self.dtype.itemsize if self.values is None else self.values
        return nnz * (values + self.patterns * idx) + self.patterns * (self.n + 1) * idx

    def __call__(self, nnz: float, estimated: bool = False) -> None:
        need = self.bytes_for(nnz)
        if need > self.max_memory:
            how = "at least about" if estimated else "exactly"
            raise OperatorTooLargeError(
                f"the operator would hold {how} {int(nnz):,} entries: with every matrix the build "
                f"keeps, {fmt_bytes(need)}, more than max_memory={fmt_bytes(self.max_memory)}; use a "
                f"smaller h (now {self.h:.4g}) or tol, dtype=float32, or matrix_free=True")


def sample_counts(points: np.ndarray, g: grid.Grid, sample: int = 512, seed: int = 0,
                  count: Callable[[np.ndarray | None], np.ndarray] | None = None) -> tuple[float, float]:
    """Mean total entries and its standard error from ``sample`` rows drawn with replacement:
    O(sample) memory and O(sample × row length) time, even when the matrix would be dense.
    ``count(rows)`` counts the entries of those rows (None: all); default the one-h kernel's."""
    n = len(points)
    if count is None:
        def count(rows):
            return grid.count_entries(points, g, rows=rows)
    if n <= sample:
        return float(count(None).sum()), 0.0
    rows = np.random.default_rng(seed).integers(0, n, size=sample)
    counts = count(rows).astype(np.float64)
    return counts.mean() * n, counts.std(ddof=1) / math.sqrt(sample) * n


def pad3(P: np.ndarray) -> np.ndarray:
    """The grid bins three coordinates: points in fewer dimensions get zeros."""
    return P if P.shape[1] >= 3 else np.ascontiguousarray(np.pad(P, ((0, 0), (0, 3 - P.shape[1]))))


def _sampled(points: np.ndarray, mass: np.ndarray, widths: Widths, kernel: Kernel,
             guard: MemoryGuard | None, chords: bool = False) -> tuple:
    # the cell grid and the sampled entry count of one build (d <= 3), checked by the guard;
    # ``chords``: the per-point kernel's count without its arc factor, even at one h
    P = pad3(points)
    g = grid.build_grid(P, mass, cutoff_radius(widths.largest, kernel.tol))
    normals = None if kernel.normals is None else pad3(kernel.normals)
    one_h = kernel.plain and not chords and widths.h_vertex is None
    hv = None if one_h else widths.per_point(len(points))
    # the sample is counted by the kernel that then builds (one fewer to compile)
    mean, err = sample_counts(P, g, count=None if hv is None else (
        lambda rows: variable.count_entries(P, g, hv, kernel.tol, normals, kernel.dim, rows)))
    if guard is not None:
        # fail fast only when the sample leaves no doubt; the exact count decides otherwise
        guard(max(mean - 4.0 * err, 0.0), estimated=True)
    return P, g, normals, hv, mean


def refuse_early(points: np.ndarray, mass: np.ndarray, widths: Widths, kernel: Kernel,
                 guard: MemoryGuard, normals: Callable[[], np.ndarray] | None = None) -> None:
    """Raise :class:`OperatorTooLargeError` now where the rows of ``kernel`` would not fit the
    guard's budget, from the same sample of rows :func:`assemble` counts first (in more than 3
    dimensions its exact count, which the k-d tree makes without listing the pairs): an
    operator refuses at construction what its pencil, built on first use, could not hold.

    ``normals`` (a kernel without normals of its own then) makes the normals of a kernel with
    arc distances, called only where the sampled rows' chord count does not fit: the arc
    factor is at least 1, so each row holds at most its chord count's entries, and the
    sample's mean at most the chord mean. The decision is the arc kernel's either way.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> from meshlap.widths import Widths
    >>> g = meshlap.geometry.from_mesh(*meshlap.shapes.sphere(500, seed=0))
    >>> guard = MemoryGuard.for_build(500, np.dtype(np.float64), 1000, 0.01, images=False, pointwise=False)
    >>> refuse_early(g.points, g.mass, Widths(0.01, None, False), Kernel(dim=2), guard)
    Traceback (most recent call last):
    ...
    meshlap.errors.OperatorTooLargeError: the operator would hold at least about ...
    """
    if points.shape[1] > 3:
        guard(pairs.count_entries(points, cutoff_radius(widths.largest, kernel.tol)))
        return
    if normals is not None and kernel.normals is None:
        # the chord count bounds the arc kernel's: no normals (0.22 s of CPU at 400k vertices)
        if guard.bytes_for(_sampled(points, mass, widths, kernel, None, chords=True)[4]) <= guard.max_memory:
            return
        kernel = replace(kernel, normals=normals())
    _sampled(points, mass, widths, kernel, guard)


def assemble(points: np.ndarray, mass: np.ndarray, widths: Widths, kernel: Kernel, *,
             dtype=np.float64, guard: MemoryGuard | None = None,
             progress: Callable[[float, str], None] | None = None,
             times: np.ndarray | None = None) -> sp.csr_matrix | tuple[sp.csr_matrix, np.ndarray | None]:
    """The kernel operator L = (K M − diag(K m)) · normalization, as CSR (rows start with
    their diagonal).

    Parameters
    ----------
    points : (n, d) ndarray
        Positions (d ≤ 3 on the cell grid; larger d on the k-d tree path).
    mass : (n,) ndarray
        Masses; points of mass 0 are rows but never sources.
    widths : Widths
        One h, or one per point (pair width (h_w + h_p)/2).
    kernel : Kernel
        Dimension, kernel type, distances and tolerance.
    dtype : numpy dtype, default float64
    guard : MemoryGuard, optional
        Called with the entry count before the arrays are allocated.
    progress : callable, optional
        ``progress(fraction, stage)``.
    times : (n, c) ndarray, optional
        A block to multiply L with while its rows are filled (the moment scale's |x|² and x,
        :func:`meshlap.corrections.moments.moment_block`): then
        ``(L, L @ times)`` is returned, the product equal to the bit to scipy's ``L @ times``,
        or ``(L, None)`` where the rows are not filled in float64 on the per-point path or
        ``times`` has more than :data:`variable.BLOCK` columns.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> from meshlap.widths import Widths
    >>> V, F = meshlap.shapes.sphere(500, seed=0)
    >>> g = meshlap.geometry.from_mesh(V, F)
    >>> L = assemble(g.points, g.mass, Widths(0.01, None, False), Kernel(dim=2))
    >>> bool(np.allclose(L @ np.ones(500), 0))
    True
    >>> L, Y = assemble(g.points, g.mass, Widths(0.01, np.full(500, 0.01), False), Kernel(2, dog=True),
    ...                 times=V)
    >>> bool(np.array_equal(Y, L @ V))
    True
    """
    n = len(points)
    radius = cutoff_radius(widths.largest, kernel.tol)
    one_h = kernel.plain and widths.h_vertex is None
    fused = (times is not None and points.shape[1] <= 3 and not one_h and np.dtype(dtype) == np.float64
             and times.shape[1] <= variable.BLOCK)
    if times is not None and not fused:
        return assemble(points, mass, widths, kernel, dtype=dtype, guard=guard, progress=progress), None
    if points.shape[1] > 3:
        if guard is not None:
            guard(pairs.count_entries(points, radius))
        if one_h:
            return pairs.assemble(points, mass, widths.h, radius, kernel.dim, dtype)
        return pairs.assemble_variable(points, mass, widths.per_point(n), kernel.tol, kernel.dim,
                                       kernel.dog, kernel.normals, dtype)
    P, g, normals, hv, mean = _sampled(points, mass, widths, kernel, guard)
    index_dtype = np.int32 if n <= _INT32_MAX else np.int64
    if one_h:
        count_cb = None if progress is None else (lambda f: progress(0.3 * f, "count"))
        fill_cb = None if progress is None else (lambda f: progress(0.3 + 0.7 * f, "fill"))
        counts = grid.count_entries(P, g, progress=count_cb, expected_nnz=mean)
        nnz = int(counts.sum())
        if guard is not None:
            guard(nnz)
        if nnz > _INT32_MAX:
            index_dtype = np.int64
        indptr = np.zeros(n + 1, dtype=index_dtype)
        np.cumsum(counts, out=indptr[1:])
        _warn_lonely(counts, mass, radius, widths.h)
        indices, data = grid.fill_csr(P, g, widths.h, indptr, index_dtype, np.dtype(dtype),
                                      progress=fill_cb, dim=kernel.dim)
        return csr(data, indices, indptr, n)

    def check(nnz: int) -> None:
        if guard is not None:
            guard(nnz)
        if nnz > _INT32_MAX:
            raise OperatorTooLargeError(f"{nnz:,} entries need 64-bit indices; use a smaller h")

    if progress is not None:
        progress(0.0, "kernel rows")
    product = np.empty((n, times.shape[1])) if fused else None
    indptr, indices, data = variable.variable_csr(P, g, hv, kernel.tol, normals,
                                                  kernel.dog, index_dtype, np.dtype(dtype), max_nnz=check,
                                                  dim=kernel.dim, times=times, product=product)
    # unsorted, as on the one-h path: sorting cost as much as the fill (issue 19), and a matrix
    # that shares these index arrays sorts them first (meshlap.pipeline)
    L = csr(data, indices, indptr, n)
    return (L, product) if fused else L


def reweigh(L: sp.csr_matrix, points: np.ndarray, mass: np.ndarray, widths: Widths, kernel: Kernel) -> bool:
    """Give ``L``, as :func:`assemble` built it for another kernel of the same widths, normals
    and tolerance, the weights of ``kernel``, in place (:func:`variable.revalue`): the result
    of ``assemble(points, mass, widths, kernel)`` to the bit, without its neighbour search.
    False (and ``L`` untouched) where that does not apply: points in more than 3 dimensions,
    the one-h kernel's own path, or rows no longer in their assembled order.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> from meshlap.widths import Widths
    >>> V, F = meshlap.shapes.sphere(300, seed=0)
    >>> g = meshlap.geometry.from_mesh(V, F)
    >>> w = Widths(0.01, np.full(300, 0.01), False)
    >>> L = assemble(g.points, g.mass, w, Kernel(dim=2, dog=True))
    >>> reweigh(L, g.points, g.mass, w, Kernel(dim=2))
    True
    >>> bool(np.array_equal(L.data, assemble(g.points, g.mass, w, Kernel(dim=2)).data))
    True
    """
    n = len(points)
    if points.shape[1] > 3 or (kernel.plain and widths.h_vertex is None) or L.has_sorted_indices:
        return False
    starts = L.indptr[:-1]
    if np.any(np.diff(L.indptr) < 1) or not np.array_equal(L.indices[starts], np.arange(n)):
        return False
    normals = None if kernel.normals is None else pad3(kernel.normals)
    variable.revalue(pad3(points), mass, widths.per_point(n), normals, kernel.dog, L.indptr, L.indices,
                     L.data, kernel.dim)
    return True


@dataclass
class MatrixFree:
    """The kernel operator applied without storing it: the grid is built once, each product
    recomputes the weights (one h; the Richardson kernel as 2 L_{h/2} − L_h, both cut at
    r(h), the pairs of the assembled operator), plus ``images``, the stored mirror images of
    the boundary band (:func:`meshlap.corrections.images.band_images`) where there are any.
    ``pieces``: (indices, points, grid) of each part of a mesh (indices None: one part, all
    the points), which pairs only within itself; a part of one point has a zero row."""

    pieces: list[tuple[np.ndarray | None, np.ndarray, grid.Grid]]
    h: float
    dim: int
    dog: bool
    scale: float = 1.0
    images: sp.csr_matrix | None = None

    @classmethod
    def build(cls, points: np.ndarray, mass: np.ndarray, widths: Widths, kernel: Kernel,
              label: np.ndarray | None = None) -> MatrixFree:
        """Bin the points for the cut-off of ``widths.h``; with ``label`` (a part per point),
        each part of two points or more on its own grid."""
        P, r = pad3(points), cutoff_radius(widths.h, kernel.tol)
        if label is None:
            pieces = [(None, P, grid.build_grid(P, mass, r))]
        else:
            order = np.argsort(label, kind="stable")
            groups = np.split(order, np.flatnonzero(np.diff(label[order])) + 1)
            pieces = [(idx, P[idx], grid.build_grid(P[idx], mass[idx], r)) for idx in groups if len(idx) > 1]
        return cls(pieces, widths.h, kernel.dim, kernel.dog)

    def _kernel(self, P: np.ndarray, g: grid.Grid, f: np.ndarray) -> np.ndarray:
        if not self.dog:
            return grid.apply(P, g, self.h, f, self.dim)
        return 2.0 * grid.apply(P, g, 0.5 * self.h, f, self.dim) - grid.apply(P, g, self.h, f, self.dim)

    def __call__(self, f: np.ndarray) -> np.ndarray:
        if len(self.pieces) == 1 and self.pieces[0][0] is None:
            out = self._kernel(self.pieces[0][1], self.pieces[0][2], f)
        else:
            out = np.zeros(f.shape)
            for idx, P, g in self.pieces:
                out[idx] = self._kernel(P, g, np.ascontiguousarray(f[idx]))
        if self.images is not None:
            out += self.images @ f
        return self.scale * out if self.dog else out

    def count_entries(self, sample: int = 512, seed: int = 0) -> float:
        """Estimated entries of the operator it does not store (:func:`sample_counts`)."""
        return float(sum(sample_counts(P, g, sample, seed)[0] for _, P, g in self.pieces))


def _warn_lonely(counts: np.ndarray, mass: np.ndarray, radius: float, h: float) -> None:
    lonely = np.flatnonzero((counts == 1) & (mass > 0))
    if len(lonely):
        warnings.warn(f"{len(lonely)} of {len(counts)} vertices have no neighbour within the cut-off "
                      f"radius {radius:.3g} (h={h:.3g}); L is 0 there. Use a larger h.", RuntimeWarning,
                      stacklevel=user_stacklevel())
