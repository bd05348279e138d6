"""Stages 1 and 2 from scattered input: each rank holds a chunk of the points and any share
of the faces, and no rank ever holds the whole mesh.

Every per-point quantity of the corrected default comes from global reductions over the
faces each rank holds, in the same formulas as :mod:`meshlap.geometry` and
:mod:`meshlap.widths` (only the order of the sums differs, at the rounding level):

* masses m_p = Σ Area(t)/#t and area-weighted normals: each face's shares are sent to the
  owners of its corners, which add them up;
* the automatic width 4ē²: ē from the sum and count of the face sides, over all ranks;
* the curvature cap: κ_w² from the sides at w (normals fetched from their owners), then the
  ring averages over the sides, each pass one fetch and one scatter;
* the boundary: every side goes to the owner of its smaller vertex, which finds the sides
  that occur once and samples them; the samples (a curve's worth) are shared with all ranks,
  and each rank finds its points' nearest one;
* the parts: connected through the faces and through coincident copies (an unwelded seam, a
  triangle soup; found in cells of the tolerance's size, each cell on one rank), as
  :func:`meshlap.fem.part_labels`; each point's part is the smallest global index in it, from
  hooking and pointer jumping over the owners.
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np

from .. import assembly
from ..errors import MeshError
from ..geometry import Polygons, frames
from ..geometry.mass import _face_areas, paper_width
from ..geometry.topology import DUPLICATE_RTOL
from ..geometry.validation import check_faces, check_h
from ..pencil import keeps_parts
from ..pipeline import Options
from ..widths import DEFAULT_H_SCALE
from .comm import _box, _exchange, _reduce
from .corrected import PointAttributes

__all__ = ["scattered_attributes"]

# cells of this many copy distances: a point's ball meets one cell, but within that distance of
# a side (on average 1 + 3·2/64 cells a point)
_COPY_CELL = 64.0


class _Chunks:
    """Who owns which global point: the chunks in rank order."""

    def __init__(self, comm, n_local: int) -> None:
        self.comm = comm
        self.ends = np.cumsum(comm.allgather(n_local))
        self.start = int(self.ends[comm.Get_rank()] - n_local)
        self.n_local = n_local

    @property
    def n(self) -> int:
        return int(self.ends[-1])

    def owner(self, ids: np.ndarray) -> np.ndarray:
        return np.searchsorted(self.ends, ids, side="right")

    def fetch(self, ids: np.ndarray, own: np.ndarray) -> np.ndarray:
        """``own`` (a per-point array of this rank's chunk) at the global ``ids``, from their owners."""
        need, inv = np.unique(ids, return_inverse=True)
        rank = np.full(len(need), self.comm.Get_rank(), dtype=np.int64)
        asked, src = _exchange(self.comm, self.owner(need), need, rank)
        values, got = _exchange(self.comm, src, own[asked - self.start], asked)
        out = np.empty((len(need), *own.shape[1:]), dtype=own.dtype)
        out[np.searchsorted(need, got)] = values
        return out[inv.reshape(-1)]

    def add(self, ids: np.ndarray, values: np.ndarray) -> np.ndarray:
        """Σ of ``values`` by global id, on the owners: a per-point array of this chunk."""
        r_ids, r_vals = _exchange(self.comm, self.owner(ids), ids, values)
        local = r_ids - self.start
        out = np.zeros((self.n_local, *r_vals.shape[1:]))  # (bincount of nothing is an int array)
        if r_vals.ndim == 1:
            out += np.bincount(local, weights=r_vals, minlength=self.n_local)
            return out
        for c in range(r_vals.shape[1]):
            out[:, c] += np.bincount(local, weights=r_vals[:, c], minlength=self.n_local)
        return out


def _sum(comm, x: float) -> float:
    from mpi4py import MPI

    return comm.allreduce(float(x), op=MPI.SUM)


def scattered_attributes(comm, V: np.ndarray, F: Any, h: Any, tol: float, correction: str,
                         options: dict) -> tuple[np.ndarray, float, PointAttributes]:
    """Masses, the base width and the attributes of this rank's chunk ``V`` of a surface mesh
    whose faces ``F`` (global indices) are shared among the ranks in any way (collective)."""
    from mpi4py import MPI

    if options.get("adaptive") or np.ndim(h) == 1:
        raise MeshError("scattered input takes one h or the automatic one (no adaptive or per-point h)")
    ch = _Chunks(comm, len(V))
    F = np.asarray(F) if not isinstance(F, (list, Polygons)) else F
    empty = isinstance(F, np.ndarray) and F.size == 0
    faces = Polygons(np.zeros(0, np.int64), np.zeros(1, np.int64)) if empty else check_faces(F, ch.n)
    shape = SimpleNamespace(dim=2, ambient_dim=3, source="surface", codim=1)
    opts = Options.resolve(shape, h, correction=correction, tol=tol, **options)
    need = np.unique(faces.indices)
    Vn = ch.fetch(need, V)
    local = Polygons(np.searchsorted(need, faces.indices).astype(np.int64), faces.offsets)
    # masses and normals: each face's shares to the owners of its corners
    areas = _face_areas(Vn, local) if faces.n_faces else np.zeros(0)
    mass = ch.add(faces.indices, np.repeat(areas / faces.sizes, faces.sizes))
    if _sum(comm, mass.sum()) == 0:
        raise MeshError("every face has zero area: there is nothing to integrate over")
    T = local.triangles() if faces.n_faces else np.zeros((0, 3), np.int64)
    fn = np.cross(Vn[T[:, 1]] - Vn[T[:, 0]], Vn[T[:, 2]] - Vn[T[:, 0]]) if len(T) else np.zeros((0, 3))
    N = ch.add(need[T.reshape(-1)], np.repeat(fn, 3, axis=0))
    # copies weld where normals, the boundary or the parts are read (not in the paper's operator)
    welds = keeps_parts(opts) or opts.neumann or opts.arc_distance or opts.curvature_limit
    copies = _copies(ch, V) if welds else (np.zeros(0, np.int64), np.zeros(0, np.int64))
    rep = _components(ch, *copies) if comm.allreduce(len(copies[0]), op=MPI.SUM) else None
    if rep is not None:  # a copy's normal is its point's, from all the faces there
        N = ch.fetch(rep, ch.add(rep, N))
    norm = np.linalg.norm(N, axis=1, keepdims=True)
    normals = np.divide(N, norm, out=np.zeros_like(N), where=norm > 0)
    # the width: ē over all face sides of all ranks
    e = local.edges() if faces.n_faces else np.zeros((0, 2), np.int64)
    d2 = ((Vn[e[:, 0]] - Vn[e[:, 1]]) ** 2).sum(axis=1)
    count = comm.allreduce(len(e), op=MPI.SUM)
    spacing = _sum(comm, np.sqrt(d2).sum()) / max(count, 1)
    h0 = check_h(h) if h is not None else check_h(
        paper_width(spacing) if opts.plain else DEFAULT_H_SCALE * spacing**2, "the automatic h")
    hv = np.full(len(V), h0)
    gi = need[e] if len(e) else np.zeros((0, 2), np.int64)
    ends = gi if rep is None else ch.fetch(gi.reshape(-1), rep).reshape(gi.shape)  # on the welded cells
    if opts.curvature_limit:
        side = ends[:, 0] != ends[:, 1]  # a seam is no edge of the widths
        hv = _curvature_widths(ch, ends[side], d2[side], normals, h0, opts.curvature_limit)
        if rep is not None:  # each copy its point's
            hv = ch.fetch(rep, hv)
    widest = comm.allreduce(float(hv.max()) if len(hv) else 0.0, op=MPI.MAX)
    radius = assembly.cutoff_radius(widest, opts.tol)
    table = np.zeros((len(V), 11))
    table[:, 0] = hv
    if opts.arc_distance:
        table[:, 2:5] = normals
    if opts.neumann or not opts.plain:
        band = _boundary(ch, faces, local, Vn, ends, V, radius, max(radius / 16, spacing / 4))
        if band is not None:
            idx, b, nu = band
            table[idx, 1] = 1.0
            table[idx, 5:8] = b
            table[idx, 8:11] = nu
    label = _part_labels(ch, faces, rep) if keeps_parts(opts) else None
    if label is not None:
        table = np.column_stack([table, label])
    attrs = PointAttributes(table, 2, not opts.plain, opts.arc_distance, opts.neumann, opts.pointwise,
                            opts.check_psd, opts.tol, degree=opts.pointwise_degree, parts=label is not None)
    return mass, h0, attrs


def _part_labels(ch: _Chunks, faces: Polygons, rep: np.ndarray | None) -> np.ndarray | None:
    # each point's part where the mesh has two or more (points in no face: their own, uncounted),
    # from the copies' representatives (rep) on
    from mpi4py import MPI

    starts = faces.offsets[:-1]
    u = np.repeat(faces.indices[starts], faces.sizes - 1).astype(np.int64)  # each corner to its face's first
    v = np.delete(faces.indices, starts).astype(np.int64)
    label = _components(ch, u, v, rep)
    used = ch.add(faces.indices, np.ones(len(faces.indices))) > 0
    counted = ch.add(label[used], np.ones(int(used.sum()))) > 0  # on each part's root
    return label if ch.comm.allreduce(int(counted.sum()), op=MPI.SUM) >= 2 else None


def _copies(ch: _Chunks, V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pairs of global indices of points within DUPLICATE_RTOL of the bounding box's diagonal of
    each other (topology.duplicate_vertices' rule): each point goes to the ranks of the cells
    that its ball of that radius meets (one cell, but near a cell's side), so both ends of a pair
    meet in the cell of either."""
    from mpi4py import MPI
    from scipy.spatial import cKDTree

    box = _reduce(ch.comm, _box(V) * np.r_[np.ones(3), -np.ones(3)], MPI.MIN)
    lo, hi = box[:3], -box[3:]
    atol = DUPLICATE_RTOL * float(np.linalg.norm(hi - lo)) * (1 + 1e-9)
    cell = max(_COPY_CELL * atol, 1e-300)
    below = np.floor((V - atol - lo) / cell).astype(np.int64)
    above = np.floor((V + atol - lo) / cell).astype(np.int64)
    keys, gids = [], []
    for corner in np.ndindex(2, 2, 2):  # the distinct cells of the ball's eight corners
        up = np.array(corner, dtype=bool)
        on = np.all(above[:, up] != below[:, up], axis=1)
        keys.append(np.where(up, above, below)[on])
        gids.append(ch.start + np.flatnonzero(on))
    key, gid = np.concatenate(keys), np.concatenate(gids)
    # a hash of the cell (wrapping int64 products) picks its rank
    mixed = key[:, 0] * 73856093 ^ key[:, 1] * 19349663 ^ key[:, 2] * 83492791
    r_key, r_gid, r_pos = _exchange(ch.comm, mixed % ch.comm.Get_size(), key, gid, V[gid - ch.start])
    if len(r_pos) < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    a, b = cKDTree(r_pos).query_pairs(atol, output_type="ndarray").T
    keep = (r_gid[a] != r_gid[b]) & np.all(r_key[a] == r_key[b], axis=1)
    return r_gid[a[keep]], r_gid[b[keep]]


def _components(ch: _Chunks, u: np.ndarray, v: np.ndarray, start: np.ndarray | None = None) -> np.ndarray:
    """The smallest global index connected to each point of this chunk by the edges (u, v) any
    rank holds, from ``start`` on (each point's smallest so far; None: itself): the roots hook
    onto the smaller across every edge that still joins two, and pointer jumping brings every
    point to its root, until no edge joins two."""
    from mpi4py import MPI

    comm = ch.comm
    label = ch.start + np.arange(ch.n_local, dtype=np.int64) if start is None else start.copy()
    while True:
        while True:
            up = ch.fetch(label, label)
            if not comm.allreduce(bool((up != label).any()), op=MPI.LOR):
                break
            label = up
        lu, lv = ch.fetch(u, label), ch.fetch(v, label)
        apart = lu != lv  # joined once, an edge stays joined: it is not asked again
        if not comm.allreduce(bool(apart.any()), op=MPI.LOR):
            return label
        u, v, lu, lv = u[apart], v[apart], lu[apart], lv[apart]
        ids, low = _exchange(comm, ch.owner(np.maximum(lu, lv)), np.maximum(lu, lv), np.minimum(lu, lv))
        np.minimum.at(label, ids - ch.start, low)


def _curvature_widths(ch: _Chunks, gi: np.ndarray, d2: np.ndarray, normals: np.ndarray, h0: float,
                      beta: float) -> np.ndarray:
    # κ_w² = Σ|n_p − n_w|² / Σ|p − w|² over the sides at w, as meshlap.widths.curvature_h
    Nn = ch.fetch(gi.reshape(-1), normals).reshape(len(gi), 2, 3)  # collective: also with no sides here
    dn2 = ((Nn[:, 0] - Nn[:, 1]) ** 2).sum(axis=1)
    num = ch.add(gi[:, 0], dn2) + ch.add(gi[:, 1], dn2)
    den = ch.add(gi[:, 0], d2) + ch.add(gi[:, 1], d2)
    k2 = np.divide(num, den, out=np.zeros(ch.n_local), where=den > 0)
    capped = beta / np.maximum(k2, 1e-300)
    from mpi4py import MPI

    if not ch.comm.allreduce(bool((capped < h0).any()), op=MPI.LOR):
        return np.full(ch.n_local, h0)
    x = np.minimum(h0, capped)
    # the ring averages of meshlap.widths._ring_average over the face sides (each interior
    # edge once per face): each side adds each end's value to the other end
    deg = ch.add(gi[:, 0], np.ones(len(gi))) + ch.add(gi[:, 1], np.ones(len(gi)))
    for _ in range(3):
        xa, xb = ch.fetch(gi[:, 0], x), ch.fetch(gi[:, 1], x)
        x = (x + ch.add(gi[:, 0], xb) + ch.add(gi[:, 1], xa)) / (deg + 1)
    return x


def _boundary(ch: _Chunks, faces: Polygons, local: Polygons, Vn: np.ndarray, gi: np.ndarray,
              V: np.ndarray, radius: float, step: float):
    # each side (gi: its ends' representatives among copies), with its face's centroid, to the
    # owner of its smaller end; the sides that occur once there are the boundary (a seam
    # between copies is none), sampled as frames.boundary_samples_surface does
    if faces.n_faces:
        face_of = np.repeat(np.arange(faces.n_faces), faces.sizes)
        cen = np.zeros((faces.n_faces, 3))
        np.add.at(cen, face_of, Vn[local.indices])
        cen /= faces.sizes[:, None]
        e = local.edges()
        info = np.column_stack([Vn[e[:, 0]], Vn[e[:, 1]] - Vn[e[:, 0]], cen[face_of]])
    else:
        info = np.zeros((0, 9))
    key = np.sort(gi, axis=1)
    lo, hi, inf = _exchange(ch.comm, ch.owner(key[:, 0]), key[:, 0], key[:, 1], info)
    _, inv, cnt = np.unique(lo * np.int64(ch.n) + hi, return_inverse=True, return_counts=True)
    once = inf[(cnt[inv.reshape(-1)] == 1) & (lo != hi)]
    a, t, c = once[:, :3], once[:, 3:6], once[:, 6:]
    tu = t / np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-300)
    inward = c - a
    nu = -(inward - (inward * tu).sum(axis=1)[:, None] * tu)
    nu /= np.maximum(np.linalg.norm(nu, axis=1, keepdims=True), 1e-300)
    samples, seg = frames._sample_segments(a, t, step)
    parts = ch.comm.allgather((samples, nu[seg]))
    S = np.concatenate([p[0] for p in parts])
    nus = np.concatenate([p[1] for p in parts])
    return frames.frames_from_samples(V, S, nus, radius) if len(S) and len(V) else None
