"""Geodesic distance by the heat method (Crane, Weischedel and Wardetzky, "Geodesics in heat",
ACM TOG 2013), on every input meshlap builds: surface meshes, point clouds of any intrinsic
dimension in any R^d, curves and tetrahedral meshes.

Three steps with the operator's symmetric pencil (S ≈ MΔ, negative semidefinite; M lumped):

1. one backward-Euler heat step from the sources, ``(M - tS) u = δ`` with δ the sources'
   indicator divided by their mass (a unit of heat at each), by :class:`~meshlap.heat.ImplicitHeat`;
2. the unit field pointing away from the sources, ``X = -∇ log u / |∇ log u|``, with the gradient
   of :mod:`meshlap.gradients` (per simplex on meshes and on a surface cloud's local triangles,
   those measured in a tangent plane; weighted least squares in the tangent frame on other
   clouds); on the elements at each source's 32 nearest points, the chord's direction (below);
3. the Poisson problem ``Δφ = div X``: ``(-S) φ = Gᵀ W X`` (the divergence is the gradient's
   adjoint), by :class:`~meshlap.solve.PoissonSolver`, then φ shifted to match the planar
   distance to the nearest source on each source's 32 nearest points, and 0 at the sources.

Where the pencil is sparse, both solves use ``op.S``; where it has the heat-kernel operator's
dense rows, the geometry's own sparse matrices (:func:`_sparse_pencils`). Both are factorised
once (sparse LDLᵀ, :mod:`meshlap._ldl`) and reused for every source.

Why log u. ∇ log u = ∇u / u has the direction of ∇u, but the discrete gradients are exact
only for functions linear on an element. One backward-Euler step from a point is the resolvent
kernel, u ∝ K_0(r/√t) in the plane, log u = -r/√t - ½ log r + O(1): nearly linear in the
distance r, so the direction of its P1 gradient is off by O(h/r) (the level sets' curvature),
where that of u itself, which falls by a factor e^(h/√t) across an element, is off by O(h/√t)
at every distance. Measured on 10,000 vertices: the heat method's mean relative error falls from
0.95% to 0.22% on a sphere mesh, from 1.3% to 0.44% on a sphere cloud and from 0.69% to 0.35%
on a flat square (docs/uses.md).

Near a source. There the O(h/r) above is large (r a few spacings), and the chord from the source
is a better direction: the gradient of x ↦ x·ĉ (ĉ the unit chord to the element's centre) as
the element sees it, exact on every element, is the geodesic's direction to O(r²) (the chord
leaves the surface by r/2 times the normal curvature, which the element's plane drops). It is
used on the elements at the source's 32 nearest points, the neighbourhood on which φ is matched
to the planar distance and whose agreement with the geodesic distance that match assumes.
Measured (largest relative error at d ≥ 0.1, three sources, 10,000 vertices): a sphere mesh
3.5% → 1.8%, a random sphere cloud 10.5% → 4.7%, the same with 0.5% radial noise 14.5% → 7.3%
(potpourri3d 12.0%); the mean errors unchanged or lower. Over 100 sources of the noisy cloud
each source's largest error has median 7.9% → 6.2% and maximum 17.2% → 12.7% (potpourri3d's
9.0% and 17.6%).

Denoised meshes. An operator whose pencil was built after a denoising step of the positions
(:mod:`meshlap.denoise`; ``op.decision.denoise``: where noise dominates what smoothing takes out,
or ``denoise=True``) carries the positions it was built on (``op.pencil_points``);
the gradient, the source neighbourhoods and the shift read those, and the gradient measures each
triangle in the mean tangent plane of its corners (:func:`~meshlap.gradients.gradient_operator`),
as on a point cloud: the step damps the noise enough for the spectrum but leaves the
triangles tilted, and tilt lengthens every path (a 50,000-vertex sphere with 0.23 mean edges of
radial noise: its area is 15.9% over 4π as given, 6.4% after the step, 0.72% in the
tangent planes). Both solves then take the gradient's stiffness ``Gᵀ W G``, the one whose metric
X is a unit field of. Otherwise (a clean mesh, or ``denoise=False``) the distance is the mesh's
as given (its own polyhedral distance, 0.44% off libigl's exact one on the 10,000-vertex noisy
sphere built with ``denoise=False``, where tilt lengthens a path by about σ̂²/ē², 1.3%).

Parts. Heat does not cross from one connected part of the pencil to another, and each part's
Poisson solution has its own constant: φ is matched to the planar distance on each part
separately (on the source neighbourhood points of the same part), and a part that holds no
source is at distance ``inf``. Matched once per column, two spheres with a source each were 0.39
off on both (0.003 and 0.0015 each alone), and a part without a source read 1.5-1.6. A point
cloud's outliers (:func:`~meshlap.geometry.point_masses`) are off the surface: ``inf`` too, where
a fit to their neighbours had given them a value that was no distance.

The time step ``t = c ē²``, ē the geometry's mean spacing (``op.geometry.spacing``), c = 1:
Crane et al.'s rule, and potpourri3d's, LaPy's and libigl's default. With log u the gradient's
own error no longer asks for a large t; what bounds t from below is the discrete flow itself:
for √t below the spacing, one implicit step moves heat edge by edge, u ~ (t/ē²)^(hops), and its
logarithm measures hops along the edge graph rather than distance. Above, the step's kernel
feels the surface beyond the source's neighbourhood: on a curved or bounded domain the
resolvent's level sets are not the distance's (an O(t) error, largest near the cut locus and
far sources). Between the two, t = ē², the smallest t whose diffusion length √t spans an
element. Measured with c = 0.5, 1, 2, 4 (10,000 vertices): a flat square's mean error 0.32%,
0.35%, 0.47%, 0.65% (the O(t) error from c = 1 on); a sphere mesh's 0.38%, 0.22%, 0.13%,
0.08% (its kernel is radial, so there t only smooths the discretisation).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from .errors import MeshError
from .geometry.validation import check_int
from .gradients import Gradient, gradient_operator
from .heat import ImplicitHeat
from .lumped import SparseLaplacian
from .progress import ProgressLike, make_progress
from .solve import PoissonSolver, _indices
from .spectral import _SPARSE_ROW_MAX, _check_mass

__all__ = ["HeatDistance", "geodesic_distance"]

#: Crane et al.'s t = c ē² with c = 1 (module notes).
TIME_FACTOR = 1.0
# points nearest each source over which φ is matched to the straight-line distance
_SHIFT_POINTS = 32


def _wrapped(K: sp.spmatrix, mass: np.ndarray) -> SparseLaplacian:
    inv = np.divide(1.0, mass, out=np.zeros_like(mass), where=mass > 0)
    S = sp.csr_matrix(-K)
    return SparseLaplacian(sp.diags(inv) @ S, mass, name="P1", S=S)


def _graph_stiffness(geo: Any) -> sp.csr_matrix:
    """The plain heat kernel (h = ē²) on the 16-nearest-neighbour graph: an M-matrix."""
    P, k, mass = geo.points, geo.dim, np.asarray(geo.mass, dtype=np.float64)
    _, idx = geo._pca()
    h = geo.spacing**2
    rows = np.repeat(np.arange(len(P)), idx.shape[1] - 1)
    cols = idx[:, 1:].ravel()
    r2 = ((P[rows] - P[cols]) ** 2).sum(axis=1)
    w = mass[rows] * mass[cols] * np.exp(-r2 / (4 * h)) / (h * (4 * np.pi * h) ** (k / 2))
    W = sp.csr_matrix((w, (rows, cols)), shape=(len(P), len(P)))
    W = W.maximum(W.T)
    return sp.csr_matrix(sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W)


def _sparse_pencils(op: Any, grad: Gradient) -> tuple[Any, Any]:
    """The operators of the heat step and of the Poisson solve.

    The operator itself where its pencil is sparse (at most 40 entries per row: linear FEM,
    cotangent, curves), solved by sparse LU. Where S has the heat-kernel operator's hundreds
    of entries per row, a conjugate gradient would leave the heat's exponentially small far
    field to its residual (the direction of ∇u there is noise) and the corrected kernel's
    negative lobes make u change sign for t below its width; so the heat step runs on the
    geometry's own sparse M-matrix (the P1 stiffness of the simplices, of a cloud's local
    Delaunay triangles, or the plain heat kernel on the 16-neighbour graph) and the Poisson
    solve on the stiffness Gᵀ W G of the gradient, the one operator for which the adjoint
    divergence is consistent: φ minimises Σ_e w_e |∇φ_e - X_e|². A denoised mesh's solves take
    the same two (its gradient's triangles are measured in their tangent planes, module notes).
    """
    S, geo = op.S, op.geometry
    if S.nnz <= _SPARSE_ROW_MAX * op.n_vertices and not (grad.tangent and geo.tiled):
        return op, op
    mass = np.asarray(op.mass, dtype=np.float64)
    K = grad.stiffness()
    K_heat = K if grad.kind == "simplices" else _graph_stiffness(geo)
    return _wrapped(K_heat, mass), _wrapped(K, mass)


def _parts(label: np.ndarray, lonely: np.ndarray, fill: sp.csr_matrix) -> np.ndarray:
    """Each point's connected part of the pencil (``label``, the Poisson solver's; a point
    without mass a part of its own); a point in no element belongs to the part of the neighbour
    its value is filled from with the largest weight."""
    label = label.copy()
    alone = label < 0
    label[alone] = label.max() + 1 + np.arange(int(alone.sum()))
    if len(lonely):
        label[lonely] = label[np.asarray(abs(fill).argmax(axis=1)).ravel()]
    return label


def _nearest(tree: cKDTree, Q: np.ndarray, k: int) -> np.ndarray:
    """Indices ((len(Q), k)) of each query point's k nearest points of the tree."""
    return np.asarray(tree.query(Q, k=k)[1], dtype=np.int64).reshape(len(Q), k)


def _row_entries(A: sp.csr_matrix, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where the entries of A's ``rows`` lie in ``A.data`` / ``A.indices``, and the index in
    ``rows`` of each: ``A[rows]`` without building it (scipy's row indexing costs 0.1 ms a call)."""
    start = A.indptr[rows]
    count = A.indptr[rows + 1] - start
    owner = np.repeat(np.arange(len(rows)), count)
    return np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count - start, count), owner


def _principal(local: np.ndarray, k: int) -> np.ndarray:
    """The k principal axes ((m, k, d)) of each of m sets of offsets (m, p, d)."""
    return np.linalg.svd(local - local.mean(axis=1, keepdims=True), full_matrices=False)[2][:, :k]


def _tangent_interpolation(P: np.ndarray, covered: np.ndarray, lonely: np.ndarray, k: int) -> sp.csr_matrix:
    """Weights ((len(lonely), n)) of the value at each lonely point of the least-squares linear
    fit to its 2(k+1) nearest covered points, in their k-dimensional principal frame: exact for
    a function linear there (a distance away from its source, to O(h²)), where taking one
    neighbour's value plus the step to it is an upper bound off by the step's component across
    the distance's gradient (up to a spacing)."""
    if not len(lonely):
        return sp.csr_matrix((0, len(P)))
    m = min(2 * (k + 1), len(covered))
    near = covered[_nearest(cKDTree(P[covered]), P[lonely], m)]
    local = P[near] - P[lonely][:, None, :]  # (L, m, d)
    A = np.concatenate([np.ones((len(lonely), m, 1)), np.einsum("lmd,lkd->lmk", local, _principal(local, k))],
                       axis=2)
    w = np.linalg.pinv(A)[:, 0, :]  # the fit's constant term: its value at the lonely point
    rows = np.repeat(np.arange(len(lonely)), m)
    return sp.csr_matrix((w.ravel(), (rows, near.ravel())), shape=(len(lonely), len(P)))


class HeatDistance:
    r"""Geodesic distance from any sources by the heat method, prepared once for an operator.

    Parameters
    ----------
    op : MeshLaplacian or SparseLaplacian
        An operator with ``.S``, ``.mass`` and ``.geometry`` (:func:`meshlap.laplacian`,
        :func:`meshlap.point_cloud_laplacian`); where its pencil was denoised
        (``op.decision.denoise``), the distance is that of the denoised surface, measured at
        ``op.pencil_points`` (module notes).
    t : float, optional
        Heat time; default ``TIME_FACTOR · ē²`` with ē = ``op.geometry.spacing`` (module notes).
    solver : {"auto", "direct", "cg"}
        For both solves (:class:`~meshlap.heat.ImplicitHeat`, :class:`~meshlap.solve.PoissonSolver`);
        ``"auto"`` factors the heat step (its far field lies below any iterative residual) and
        lets the Poisson solve choose (multigrid on a volume too costly to factor:
        :mod:`meshlap._multigrid`).
    gradient : {"auto", "simplices", "least squares"}
        See :func:`~meshlap.gradients.gradient_operator`.

    Attributes
    ----------
    t : float
        The heat time in use.
    sparse : bool
        Whether both solves use the operator's own pencil (sparse S) rather than the
        geometry's sparse matrices (module notes).

    Notes
    -----
    Memory: the preparation holds the gradient (about (k+1)·d entries per simplex, or
    (K+1)·d per point of a cloud, K = 16), the two factorisations or preconditioners and a k-d
    tree of the points (about (d + 2)·8 bytes per point), and the simplices' centres and
    incidence (about (d + 2(k+1))·8 bytes per simplex).
    :meth:`compute_many` works on ``batch`` sources at a time, with about
    ``(4 + 3·E·d / n) · 8 · n · batch`` bytes of temporaries (E elements; about 150 n · batch
    bytes on a triangle mesh in R³), and returns a ``len(sources) × n`` float64 matrix.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(3000, seed=0)
    >>> d = HeatDistance(meshlap.laplacian(V, F)).compute(0)
    >>> exact = np.arccos(np.clip(V @ V[0], -1, 1))      # great-circle distance
    >>> bool(np.abs(d - exact).mean() < 0.02)
    True
    """

    def __init__(self, op: Any, t: float | None = None, *, solver: str = "auto",
                 gradient: str = "auto") -> None:
        geo = getattr(op, "geometry", None)
        if geo is None:
            raise MeshError("HeatDistance needs an operator that carries its geometry (op.geometry)")
        self.op = op
        self.mass, _ = _check_mass(op)
        self.n = op.n_vertices
        self.t = float(TIME_FACTOR * geo.spacing**2 if t is None else t)
        if not np.isfinite(self.t) or self.t <= 0:
            raise MeshError(f"t must be finite and > 0; got {t!r}")
        self.grad = gradient_operator(op, gradient)
        heat_op, poisson_op = _sparse_pencils(op, self.grad)
        self.sparse = heat_op is op
        # factored even where a large volume's Poisson solve takes multigrid: an iterative step
        # would leave the exponentially small far field to its residual (_sparse_pencils)
        self._heat = ImplicitHeat(heat_op, self.t, solver="direct" if solver == "auto" else solver)
        self._poisson = PoissonSolver(poisson_op, solver=solver)
        # the positions the pencil was built on (denoise=True: after its heat step)
        self._points = np.asarray(getattr(op, "pencil_points", geo.points), dtype=np.float64)
        # vertices in no element (a cloud point left out of every local triangle) take the value of
        # a linear fit to their covered neighbours (no gradient reads them)
        lonely = np.asarray(abs(self.grad.G).sum(axis=0)).ravel() == 0
        if lonely.all():
            raise MeshError("the geometry has no element with a positive measure to carry heat")
        self._lonely = np.flatnonzero(lonely)
        self._fill = _tangent_interpolation(self._points, np.flatnonzero(~lonely), self._lonely, geo.dim)
        # a source in no element starts from a copy of it that is in one (a pole repeated per
        # segment, whose own faces collapse)
        self._stand_in = np.arange(self.n)
        rep = geo.copies() if len(self._lonely) else None
        if rep is not None:
            covered = np.flatnonzero(~lonely)
            first = np.full(self.n, -1)
            first[rep[covered[::-1]]] = covered[::-1]  # each point's first copy in an element
            sub = first[rep[self._lonely]]
            self._stand_in[self._lonely[sub >= 0]] = sub[sub >= 0]
        self._part = _parts(self._poisson.part_label, self._lonely, self._fill)
        # a cloud's outliers are off the surface (no value a neighbour's fit gives is a distance)
        self._off_surface = geo._cache.get("outliers", np.zeros(self.n, dtype=bool))
        self._tree = cKDTree(self._points)
        cells = self.grad.cells  # the elements' centres, and for each vertex the elements at it
        self._centres = self._points if cells is None else self._points[cells].mean(axis=1)
        self._touch = None if cells is None else sp.csr_matrix(
            (np.ones(cells.size), (cells.ravel(), np.repeat(np.arange(len(cells)), cells.shape[1]))),
            shape=(self.n, len(cells)))

    def _sources(self, sources: Any) -> np.ndarray:
        idx = _indices(np.atleast_1d(np.asarray(sources)), self.n, "source")
        if not len(idx):
            raise MeshError("no source vertex given")
        idx = self._stand_in[idx]
        if np.isin(idx, self._lonely).any():
            raise MeshError(f"source vertex {int(idx[np.isin(idx, self._lonely)][0])} lies in no element "
                            "of the geometry (a vertex in no face, or a point cloud's outlier): heat "
                            "cannot start there")
        if (self.mass[idx] == 0).any():
            raise MeshError(f"source vertex {int(idx[self.mass[idx] == 0][0])} has zero mass (an "
                            "unreferenced vertex or an outlier): heat cannot start there")
        return idx

    def _distances(self, groups: list[np.ndarray]) -> np.ndarray:
        """One distance field (n, len(groups)) per group of sources."""
        delta = np.zeros((self.n, len(groups)))
        for j, g in enumerate(groups):
            delta[g, j] = 1.0 / self.mass[g]
        heat = self._heat
        if heat.solver == "direct" and len(heat.Z) == 0:  # the step's solve, without its set-up per call
            u = heat._lu.solve(np.asfortranarray(heat.m[:, None] * delta))
        else:
            u = heat.step(delta)
        # the direction of ∇u from log u, nearly linear in the distance (module notes)
        g = self.grad(np.log(np.maximum(u, np.finfo(float).tiny)))  # (E, d, s)
        norm = np.sqrt(np.einsum("eds,eds->es", g, g))[:, None, :]
        X = g * np.divide(-1.0, norm, out=np.zeros_like(norm), where=norm > 0)
        src = np.concatenate(groups)
        col = np.repeat(np.arange(len(groups)), [len(g) for g in groups])  # each source's group
        near = _nearest(self._tree, self._points[src], min(_SHIFT_POINTS, self.n))
        self._radial(X, src, col, near)
        phi = self._poisson.solve(-self.grad.divergence(X), compatible=True)  # Σ_j ∇λ_j = 0: sums to 0
        if len(self._lonely):
            phi[self._lonely] = self._fill @ phi
        phi[self._off_surface] = np.inf
        offsets = self._offsets(phi, groups, src, col, near)
        phi = np.where(np.isfinite(offsets), phi - offsets, np.inf)  # inf: a part without a source
        for j, grp in enumerate(groups):
            phi[grp, j] = 0.0
        return np.maximum(phi, 0.0)

    def _radial(self, X: np.ndarray, src: np.ndarray, col: np.ndarray, near: np.ndarray) -> None:
        """On the elements at each source's nearest points (``near``, one row per source ``src``
        of group ``col``), X becomes the direction away from the group's nearest source along the
        chord to the element's centre, as the element sees it: the gradient of the linear
        function x·ĉ (ĉ the unit chord), exact on every element. There the direction of ∇log u
        is off by O(h/r), the level sets' curvature across an element (module notes), where the
        chord's is off the geodesic's by O(r²): it leaves the surface by r/2 times the normal
        curvature, which the element's plane drops. The neighbourhood is the one on which φ is
        matched to the planar distance (:meth:`_offsets`), whose agreement with the geodesic
        distance it assumes."""
        P, G, d = self._points, self.grad.G, self.grad.d
        who = np.repeat(np.arange(len(src)), near.shape[1])  # (source, point) pairs, then (source, element)
        if self._touch is None:  # the elements are the points
            els = near.ravel()
        else:
            pos, owner = _row_entries(self._touch, near.ravel())
            _, once = np.unique(who[owner] * len(self._centres) + self._touch.indices[pos], return_index=True)
            els, who = self._touch.indices[pos[once]], who[owner[once]]  # each element once per source
        chord = np.take(self._centres, els, axis=0) - np.take(P, src[who], axis=0)
        if len(src) > col[-1] + 1:  # an element near several sources of a group: the nearest one's
            order = np.lexsort((np.einsum("md,md->m", chord, chord), els, col[who]))
            key = col[who][order] * len(self._centres) + els[order]
            first = order[np.r_[True, key[1:] != key[:-1]]]
            els, chord, who = els[first], chord[first], who[first]
        pos, owner = _row_entries(G, (els[:, None] * d + np.arange(d)).ravel())
        # ∇(x·chord) on each element (|chord| cancels in the normalisation); np.take: 3× faster here
        along = np.einsum("md,md->m", np.take(P, G.indices[pos], axis=0), np.take(chord, owner // d, axis=0))
        v = np.bincount(owner, G.data[pos] * along, minlength=len(els) * d).reshape(len(els), d)
        size = np.linalg.norm(v, axis=1, keepdims=True)
        v = np.divide(v, size, out=np.zeros_like(v), where=size > 0)
        flat = (els[:, None] * d + np.arange(d)) * X.shape[2] + col[who][:, None]  # X[els, :, col[who]]
        np.put(X, flat, v)

    def _offsets(self, phi: np.ndarray, groups: list[np.ndarray], src: np.ndarray, col: np.ndarray,
                 idx: np.ndarray) -> np.ndarray:
        """The constants that make each column of φ the distance to its nearest source on each
        source's nearest points of its own part (``idx``; sources ``src`` of groups ``col``),
        measured in those points' own k-dimensional principal plane (geodesic and planar distance
        agree to O(r³) there, and the plane drops the noise across the surface): one per part and
        column, (n, len(groups)), ``inf`` on a part that holds none of the column's sources."""
        P = self._points
        local = P[idx] - P[src][:, None, :]  # (sources, near, d)
        axes = _principal(local, self.op.geometry.dim)  # (sources, k, d)
        planar = np.linalg.norm(np.einsum("snd,skd->snk", local, axes), axis=2)
        for j, grp in enumerate(groups):  # several sources: to the nearest, in each one's plane
            if len(grp) == 1:
                continue
            mine = np.flatnonzero(col == j)
            for s in grp:
                other = np.linalg.norm(np.einsum("snd,skd->snk", P[idx[mine]] - P[s], axes[mine]), axis=2)
                planar[mine] = np.minimum(planar[mine], other)
        part = self._part
        same = part[idx] == part[src][:, None]  # the source itself is always one
        shift = ((phi[idx, col[:, None]] - planar) * same).sum(axis=1) / same.sum(axis=1)
        n_parts = int(part.max()) + 1
        key = col * n_parts + part[src]
        total = np.bincount(key, shift, minlength=len(groups) * n_parts)
        count = np.bincount(key, minlength=len(groups) * n_parts)
        per = np.divide(total, count, out=np.full(len(total), np.inf), where=count > 0)
        return per.reshape(len(groups), n_parts)[:, part].T

    def compute(self, sources: Any) -> np.ndarray:
        """Distance to the nearest of ``sources`` (one vertex index or several): (n,).

        Examples
        --------
        >>> import meshlap, numpy as np
        >>> V, F = meshlap.shapes.plane(1500, kind="stratified")
        >>> op = meshlap.laplacian(V, F)
        >>> d = HeatDistance(op).compute([0, 1])
        >>> exact = np.minimum(*(np.linalg.norm(V - V[i], axis=1) for i in (0, 1)))
        >>> bool(np.abs(d - exact).mean() < 0.02)
        True
        """
        return self._distances([self._sources(sources)])[:, 0]

    def compute_many(self, sources: Any, *, batch: int = 64, progress: ProgressLike = None) -> np.ndarray:
        """The distance from each source separately: rows of a distance matrix, (len(sources), n).

        Parameters
        ----------
        sources : array_like of int
            One row per source.
        batch : int, default 64
            Sources solved together (memory in the class notes).
        progress : bool or callable, optional
            ``True`` draws a bar on stderr; a callable gets ``(fraction, "distances")``.

        Examples
        --------
        >>> import meshlap, numpy as np
        >>> V, F = meshlap.shapes.plane(800, kind="stratified")
        >>> D = HeatDistance(meshlap.laplacian(V, F)).compute_many([0, 5, 9])
        >>> D.shape, bool(np.allclose(np.diag(D[:, [0, 5, 9]]), 0))
        ((3, 784), True)
        """
        idx = self._sources(sources)
        batch = check_int(batch, "batch", 1)
        report = make_progress(progress)
        out = np.empty((len(idx), self.n))
        for a in range(0, len(idx), batch):
            part = idx[a:a + batch]
            out[a:a + len(part)] = self._distances([np.array([s]) for s in part]).T
            if report is not None:
                report((a + len(part)) / len(idx), "distances")
        if report is not None:
            report(1.0, "done")
        return out


def geodesic_distance(op: Any, sources: Any, *, t: float | None = None, solver: str = "auto") -> np.ndarray:
    """Distance from the nearest of ``sources`` to every vertex, by the heat method: (n,).

    A shortcut for ``HeatDistance(op, t).compute(sources)``; keep a :class:`HeatDistance` to
    reuse its factorisations across sources.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> P = meshlap.shapes.fibonacci_sphere(2000)
    >>> d = geodesic_distance(meshlap.point_cloud_laplacian(P), 0)
    >>> exact = np.arccos(np.clip(P @ P[0], -1, 1))
    >>> bool(np.abs(d - exact).mean() < 0.05)
    True
    """
    return HeatDistance(op, t, solver=solver).compute(sources)
