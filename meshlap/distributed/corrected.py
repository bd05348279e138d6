"""The corrected operator on one rank: the single machine's stages 4 and 5 on its own rows.

Stages 1 and 2 (geometry, widths) give every point its attributes: width h_w, normal n_w (arc
distances), and, near the boundary, its nearest boundary sample b_w with the outward
conormal ν_w (mirror images). :class:`PointAttributes` packs them into one array that
travels with the points to their owner and into the halos, so that a rank holds, for its
own rows and for every source within the cut-off, exactly what the single machine holds.
:func:`local_rows` then runs the same kernel (:mod:`meshlap.assembly.variable`), the same
mirror images and the same moment corrections (:mod:`meshlap.corrections`) on the rank's
rows; the global quantities (the second-moment scale, the semidefiniteness check) are
reduced over the ranks.

The semidefiniteness check on many ranks is the check of each rank's principal block
(own rows and columns of −S): a principal submatrix of a semidefinite matrix is
semidefinite, so a negative eigenvalue there proves −S indefinite and every rank falls back
to the plain kernel, as the single machine does. A negative mode that no rank's block holds
is not caught (the single machine's check on the whole pencil would).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .. import assembly, corrections, fem
from ..geometry import Geometry
from ..options import Options
from ..pencil import part_label
from ..widths import Widths

__all__ = ["PointAttributes", "attributes", "local_rows"]


@dataclass(frozen=True)
class PointAttributes:
    """What the corrected kernel reads of each point besides position and mass, as columns
    of one (n, 2 + 3d) array: h_w, the band flag, n_w (d), b_w (d), ν_w (d); then a denoised
    cloud's input points (d, ``raw``) and the part of a mesh of several parts (1, ``parts``)."""

    table: np.ndarray
    dim: int  # intrinsic dimension k
    dog: bool
    arc: bool
    neumann: bool
    pointwise: bool | str
    check_psd: bool
    tol: float
    points_dim: int = 0  # the geometry's own dimension d (0: 3)

    raw: bool = False  # d more columns: a denoised cloud's input points, where f was sampled
    degree: int | None = None  # pointwise_degree: fitted rows of that degree on the kernel's stencil
    parts: bool = False  # the last column: each point's part (no pairs between parts)

    @property
    def d(self) -> int:
        return (self.table.shape[1] - 2 - self.parts) // (4 if self.raw else 3)

    def part(self, T: np.ndarray) -> np.ndarray | None:
        """Each row's part (:func:`meshlap.pencil.part_label`), or None: pairs between all."""
        return T[:, -1].astype(np.int64) if self.parts else None

    def columns(self, T: np.ndarray) -> tuple[np.ndarray, ...]:
        """(h, band, normals, b, ν) of a table with these columns (this one's rows or a halo's)."""
        d = self.d
        return (np.ascontiguousarray(T[:, 0]), T[:, 1] > 0, np.ascontiguousarray(T[:, 2:2 + d]),
                np.ascontiguousarray(T[:, 2 + d:2 + 2 * d]), np.ascontiguousarray(T[:, 2 + 2 * d:2 + 3 * d]))

    def fit_points(self, T: np.ndarray, P: np.ndarray) -> np.ndarray:
        """Where the fitted rows fit f: the input points of a denoised cloud, else P."""
        d = self.d
        return np.ascontiguousarray(T[:, 2 + 3 * d:2 + 4 * d]) if self.raw else P


def attributes(geo: Geometry, widths: Widths, opts: Options) -> PointAttributes:
    """Stage 1-2 results of the whole geometry as per-point columns (every rank the same)."""
    # the ranks work in three coordinates: lower dimensions are padded with zeros, which
    # leaves distances, normals and reflections as they are
    n, d0 = geo.points.shape
    d = 3
    T = np.zeros((n, 2 + 3 * d))
    T[:, 0] = widths.per_point(n)
    radius = assembly.cutoff_radius(widths.largest, opts.tol)
    frames = geo.boundary_frames(radius) if (opts.neumann or not opts.plain) else None
    if frames is not None:
        band, b, nu = frames
        T[band, 1] = 1.0
        T[band, 2 + d:2 + d + d0] = b
        T[band, 2 + 2 * d:2 + 2 * d + d0] = nu
    if opts.arc_distance:
        T[:, 2:2 + d0] = geo.normals()
    raw = geo._cache.get("input_points") if opts.pointwise == "fit" else None
    if raw is not None:
        T = np.column_stack([T, assembly.pad3(raw)])
    label = part_label(geo, opts)
    if label is not None:
        T = np.column_stack([T, label])
    return PointAttributes(T, geo.dim, not opts.plain, opts.arc_distance, opts.neumann,
                           opts.pointwise, opts.check_psd, opts.tol, d0, raw is not None,
                           opts.pointwise_degree, label is not None)


def _rows_csr(P, mass, g, rows, hv, attrs: PointAttributes, normals, dog: bool) -> sp.csr_matrix:
    n = len(P)
    indptr, indices, data = assembly.variable.variable_csr(
        P, g, hv, attrs.tol, normals if attrs.arc else None, dog, np.int64, np.float64, dim=attrs.dim,
        rows=rows)
    assembly.variable.sort_rows(indptr, indices, data)  # as the single machine's
    L = assembly.csr(data, indices, indptr, n)
    L.has_sorted_indices = True
    return L


def local_rows(comm, P: np.ndarray, mass: np.ndarray, table: np.ndarray, n_own: int, g, rows: np.ndarray,
               attrs: PointAttributes, ids: np.ndarray | None = None,
               report: Callable[[float, str], None] | None = None,
               ) -> tuple[sp.csr_matrix, sp.csr_matrix, dict]:
    """The own rows (local indices < n_own) of L_sym and of the point-wise L over the local
    points P (own, then halo) with their attribute ``table`` (collective: reductions).

    The fitted point-wise rows (the default) come from
    :func:`meshlap.corrections.rowchoice.choose_rows` on the local points, the halo serving as
    the neighbours of the own rows, with the global figures reduced over the ranks and the
    subsets of its wide stencils drawn by global id (``ids``): the single machine's rows,
    wherever the halo (the kernel's cut-off radius) holds the widest stencil.

    Returns CSR matrices over all local points (rows beyond n_own empty) and a dict with the
    correction in effect, the moment scale, the PSD margin, the fallback reason and the
    fitted rows' choice. ``report(fraction, stage)`` is called at each stage's start (the same
    on every rank).
    """
    from mpi4py import MPI

    def tell(fraction: float, what: str) -> None:
        if report is not None:
            report(fraction, what)

    hv, band, normals, b, nu = attrs.columns(table)
    frames = (np.flatnonzero(band), b[band], nu[band]) if band.any() else None
    info: dict = {"correction": "richardson" if attrs.dog else "none", "moment_scale": 1.0,
                  "psd_margin": None, "fallback_reason": None, "pointwise_choice": None}

    def stage(dog: bool) -> tuple[sp.csr_matrix, sp.csr_matrix]:
        free = _rows_csr(P, mass, g, rows, hv, attrs, normals, dog)
        L = corrections.neumann_images(free, P, frames, mass, hv, dog, attrs.dim) if attrs.neumann else free
        return free, L

    label = attrs.part(table)
    tell(0.0, "kernel rows")
    free, L = stage(attrs.dog)
    kept, L = fem.separate_rows(free, L, label)  # as the single machine's: checked as it is used
    if attrs.dog and attrs.check_psd:
        tell(0.5, "semidefinite check")
        block = sp.csr_matrix(L[:n_own, :n_own])
        margin, reason = (0.0, None) if n_own == 0 else corrections.psd.check(
            block, mass[:n_own], P[:n_own], None, "geometry")
        worst = comm.allreduce(margin, op=MPI.MIN)
        info["psd_margin"] = worst
        failed = comm.allreduce(reason is not None, op=MPI.LOR)
        if failed:
            info["fallback_reason"] = reason or (
                f"the Richardson operator is not negative semidefinite on another rank's block "
                f"(margin {worst:.3g}); using the plain kernel (O(h) bias)")
            info["correction"] = "none"
            tell(0.6, "plain kernel rows")
            free, L = stage(False)
            kept, L = fem.separate_rows(free, L, label)
    if info["correction"] != "none":
        tell(0.8, "moment scale")
        Y = kept @ np.column_stack([(P**2).sum(axis=1), P])
        mu = Y[:n_own, 0] - 2.0 * (P[:n_own] * Y[:n_own, 1:]).sum(axis=1)
        use = (mass[:n_own] > 0) & ~band[:n_own]
        num = comm.allreduce(float((mu[use] * mass[:n_own][use]).sum()), op=MPI.SUM)
        den = comm.allreduce(float(mass[:n_own][use].sum()), op=MPI.SUM)
        mean = num / den if den > 0 else 0.0
        info["moment_scale"] = scale = 2.0 * attrs.dim / mean if mean > 0 else 1.0
        L.data *= scale
    Lp = L
    if attrs.pointwise:
        tell(0.9, "point-wise rows")
    if attrs.pointwise == "fit":
        d0 = attrs.points_dim or P.shape[1]  # the ranks pad lower dimensions with zeros
        Lp, info["pointwise_choice"] = _fitted_rows(
            comm, np.ascontiguousarray(attrs.fit_points(table, P)[:, :d0]), n_own, ids, attrs.dim)
    elif attrs.degree is not None:  # the single machine's rows of that degree on the kernel's stencil
        ptr, idx = free.indptr[:n_own + 1], free.indices[:free.indptr[n_own]]
        if ids is not None:  # each row's neighbours in global order: the single machine's sums
            idx = idx[np.lexsort((ids[idx], np.repeat(np.arange(n_own), np.diff(ptr))))]
        Lp = corrections.highorder.pointwise_rows(
            np.ascontiguousarray(P[:, :attrs.points_dim or P.shape[1]]), ptr, idx, hv[:n_own], attrs.degree,
            k=attrs.dim, centers=np.arange(n_own))
    elif attrs.pointwise:
        Lp, _ = corrections.moment_correction(free, P, attrs.dim)
    return L, Lp, info


def _fitted_rows(comm, Q: np.ndarray, n_own: int, ids: np.ndarray | None, k: int
                 ) -> tuple[sp.csr_matrix, object]:
    # the single machine's fitted rows (meshlap.pipeline.fitted_rows): on the distinct points,
    # given to coincident copies (meshlap.corrections.copies). Every copy of a local point is
    # local (the halo holds all within the cut-off, copies at distance 0); a distinct point is
    # its copy of least global id, counted by that copy's owner and numbered among the distinct
    # points as on the single machine, so that the wide rows draw the same subsets
    from ..corrections._ranks import _bounds
    from ..geometry.topology import DUPLICATE_RTOL, _duplicate_rep

    n = len(Q)
    uid = np.arange(n, dtype=np.int64) if ids is None else np.asarray(ids, dtype=np.int64)
    lo, hi = _bounds(comm, Q[:n_own])
    span = float(np.linalg.norm(Q.max(axis=0) - Q.min(axis=0))) if n else 0.0
    rtol = min(DUPLICATE_RTOL * float(np.linalg.norm(hi - lo)) / span, 0.5) if span > 0 else 0.0
    group = _duplicate_rep(np.pad(Q, ((0, 0), (0, max(3 - Q.shape[1], 0)))), rtol)  # (in 3-D)
    order = np.lexsort((uid, group))  # by group, then global id
    g = group[order]
    head = np.r_[True, g[1:] != g[:-1]] if n else np.zeros(0, dtype=bool)
    first = np.empty(n, dtype=np.int64)  # each group's copy of least global id
    first[g] = order[np.flatnonzero(head)][np.cumsum(head) - 1]
    rep = first[group]
    copies = comm.allgather(uid[:n_own][rep[:n_own] != np.arange(n_own)])
    if not sum(len(c) for c in copies):
        return corrections.rowchoice.choose_rows(Q, k=k, rows=np.arange(n_own), ids=ids, comm=comm)
    later = np.sort(np.concatenate(copies))  # global ids of the copies that are not the first
    distinct = np.flatnonzero(rep == np.arange(n))
    index = np.searchsorted(distinct, rep)
    need = np.unique(index[:n_own])
    L, choice = corrections.rowchoice.choose_rows(
        Q[distinct], k=k, rows=need, counted=need[distinct[need] < n_own],
        ids=uid[distinct] - np.searchsorted(later, uid[distinct]), comm=comm)
    L, choice = corrections.copies.on_copies(L, choice, index)
    return sp.vstack([L[:n_own], sp.csr_matrix((n - n_own, n))], format="csr"), choice  # halo rows empty
