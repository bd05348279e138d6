"""The Belkin–Sun–Wang mesh Laplacian as a reusable operator.

Belkin, Sun and Wang, "Discrete Laplace operator on meshed surfaces", SoCG 2008, eq. (1):

    L f(w) = 1/(4πh²) Σ_t Area(t)/#t Σ_{p∈V(t)} exp(-|p-w|²/4h) (f(p) - f(w))

Grouping the face sums by vertex gives the lumped mass m_p = Σ_{t∋p} Area(t)/#t and

    L = (K M - diag(K m)) / (4πh²),   K_wp = exp(-|p-w|²/4h),  M = diag(m).
"""

from __future__ import annotations

import math
import os
import warnings
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import LinearOperator

from . import correction as _corr
from . import geometry, kernel, pairs
from .geometry import Geometry
from .mass import _mean_edge_length
from .progress import ProgressLike, make_progress
from .validation import (
    MeshError,
    MeshWarning,
    check_faces,
    check_function,
    check_h,
    check_positive,
    check_tol,
    check_vertices,
)

__all__ = [
    "CORRECTIONS",
    "DEFAULT_H_SCALE",
    "DEFAULT_TOL",
    "MeshLaplacian",
    "OperatorTooLargeError",
    "available_memory",
    "default_h",
    "laplacian",
    "mesh_laplacian",
    "truncation_bound",
]

#: Default kernel tolerance: Gaussian weights below 1e-8 of the peak are dropped.
DEFAULT_TOL = 1e-8
#: ``correction`` values: the Richardson (difference of Gaussians) kernel, or the paper's.
CORRECTIONS = ("richardson", "none")
#: With the default correction h = DEFAULT_H_SCALE · ē² (ē the mean edge length), or per vertex
#: h_w = DEFAULT_H_SCALE · ℓ_w² with ``adaptive=True``; docs/accuracy.md has the measurements.
DEFAULT_H_SCALE = 4.0
#: With the default correction the width is also capped at β/κ_w² (κ_w² the squared normal
#: variation per length at w), β = CURVATURE_LIMIT: the kernel narrows where the surface bends.
CURVATURE_LIMIT = 0.05
_INT32_MAX = np.iinfo(np.int32).max


class OperatorTooLargeError(MemoryError):
    """The assembled matrix would not fit in the memory the caller allows."""


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


def default_h(V: Any, F: Any, k: int | None = None) -> float:
    """The automatic kernel width: h = (2 ē)², ē the mean edge length of the cells.

    The Gaussian's standard deviation sqrt(2h) then spans about 2.8 mean edges, so each row
    averages over a few rings of neighbours (hundreds of vertices with ``tol = 1e-8``).
    Pass ``h`` explicitly for convergence studies: the operator's bias grows like O(h).

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    >>> round(default_h(V, [[0, 1, 2]]), 4)
    5.1808
    """
    if k in (1, 3) or geometry.cell_columns(F) == 2:
        return geometry.from_mesh(V, F, k).default_h
    V = check_vertices(V)
    faces = check_faces(F, len(V))
    return (2.0 * _mean_edge_length(V, faces)) ** 2


def _fmt_bytes(b: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if b < 1024 or unit == "TiB":
            return f"{b:.1f} {unit}" if unit != "B" else f"{int(b)} B"
        b /= 1024
    return f"{b:.1f} TiB"


def _csr(data: np.ndarray, indices: np.ndarray, indptr: np.ndarray, n: int) -> sp.csr_matrix:
    """Wrap CSR arrays without copying them. scipy's constructor would copy int64 index arrays
    down to int32 when their contents fit; setting the arrays directly keeps the type chosen
    (and tested) here. Rows start with their diagonal, so the indices are not sorted."""
    L = sp.csr_matrix((n, n), dtype=data.dtype)
    L.data, L.indices, L.indptr = data, indices, indptr
    L.check_format(full_check=False)
    L.has_sorted_indices = False
    return L


class _LumpedLaplacian:
    """What every Laplacian with a lumped (diagonal) mass shares: ``M`` and ``S = M L``."""

    mass: np.ndarray
    L: sp.csr_matrix
    _S: sp.csr_matrix | None = None

    @property
    def M(self) -> sp.csr_matrix:
        """Diagonal lumped mass matrix, in the value type of L."""
        return sp.diags(self.mass.astype(self.L.dtype), format="csr")

    @property
    def S(self) -> sp.csr_matrix:
        """``M @ L``: symmetric and negative semidefinite."""
        if self._S is None:
            self._S = sp.csr_matrix(self.M @ self.L)
        return self._S


class MeshLaplacian(_LumpedLaplacian):
    r"""The heat-kernel mesh Laplacian of Belkin, Sun and Wang (SoCG 2008), built once.

    ``L`` approximates the Laplace–Beltrami operator :math:`+\Delta` (negative
    semidefinite: :math:`L x^2 = 2` on the plane). ``S = M L`` is symmetric, so
    ``(S, M)`` is a symmetric generalized pair for :func:`scipy.sparse.linalg.eigsh`.

    Parameters
    ----------
    V : (n, d) array_like, or Geometry
        Vertex positions, or a :class:`~meshlap.geometry.Geometry` (then ``F`` is None):
        positions, masses and intrinsic dimension from any source, e.g. a point cloud.
    F : (m, c) array_like, or list of sequences
        Cells: faces of any size (triangles, quads, mixed polygons), each giving
        Area(t)/#t to each of its #t corners; (m, 2) edges of a curve; tetrahedra with
        ``k=3`` (see :func:`meshlap.geometry.from_mesh`).
    h : float or (n,) array_like, optional
        Kernel width; the Gaussian is exp(-d²/4h). An explicit value always wins; an array
        gives each vertex its own width (pair width (h_w + h_p)/2; not with
        ``correction="none"``). Without one, on a surface mesh: 4ē² (ē the mean edge length),
        narrowed where the surface bends (``curvature_limit``); with ``correction="none"``
        and on other geometries (curves, volumes, point clouds) the paper's (2ē)², ē the
        geometry's spacing.
    correction : {"richardson", "none"}, optional
        Default "richardson" on surface meshes (with faces), "none" on other geometries.
        "richardson": the kernel 2K_{h/2} − K_h, second order in h, with −S checked to be
        semidefinite (otherwise a :class:`MeshWarning`, ``fallback_reason``, and the plain
        kernel); it needs faces (normals, boundary) and is not available on curves, volumes
        and point clouds yet. "none": the paper's operator, eq. (1), and none of the options
        below unless asked for. docs/accuracy.md has the measurements.
    adaptive : bool, default False
        Per-vertex widths 4ℓ_w² from the local edge lengths (surface meshes).
    arc_distance, pointwise, neumann : bool, optional
        Default True with the correction (False when matrix-free): distances scaled by the
        arc/chord ratio of the vertex normals; ``op @ f`` applies the row-wise moment
        correction ``L_pointwise``; mirror images at the boundary (Neumann spectra).
    curvature_limit : float, optional
        β of h_w = min(h, β/κ_w²); default 0.05 with the correction and automatic h, else 0.
    check_psd : bool, default True
        Check that −S is positive semidefinite (Richardson only).
    tol : float, default 1e-8
        Kernel tolerance: weights exp(-d²/4h) < tol are dropped, which cuts the sums off at
        r = sqrt(4h ln(1/tol)). For every vertex w the truncated operator differs from the
        exact one by at most ``tol * A * max_p |f(p) - f(w)| / (4π h²)`` with A the total
        area (sum of masses). ``tol=0`` keeps every pair (dense; small meshes only).
    exact : bool, default False
        Same as ``tol=0``.
    dtype : {numpy.float64, numpy.float32}
        Value type of the stored matrix (float32 halves the memory of the values).
    matrix_free : bool, default False
        Do not store L; ``op @ f`` and :meth:`as_linear_operator` recompute the kernel
        on the fly, for meshes whose matrix does not fit in memory.
    max_memory : int, optional
        Bytes the stored matrix may take; default 80% of the memory available now. A build
        that would exceed it raises :class:`OperatorTooLargeError` before allocating.
    progress : bool or callable, optional
        ``True`` draws a bar on stderr; a callable gets ``(fraction, stage)``.
    k : {1, 2, 3}, optional
        Intrinsic dimension of the mesh, inferred from ``F`` when not given; the kernel's
        normalization is 1/(h (4πh)^{k/2}) (1/(4πh²) on surfaces).

    Attributes
    ----------
    L : scipy.sparse.csr_matrix
        The symmetric operator (S = M L): eq. (1) of the paper with ``correction="none"``;
        by default the Richardson kernel with mirror images at the boundary (Neumann).
    L_pointwise : scipy.sparse.csr_matrix
        What ``op @ f`` applies: L's rows corrected to be exact for quadratics (not
        symmetric); L itself when ``pointwise`` is off.
    M : scipy.sparse.csr_matrix
        Diagonal lumped mass matrix.
    S : scipy.sparse.csr_matrix
        ``M @ L``, symmetric, negative semidefinite.
    mass : (n,) ndarray
        Vertex masses m_p = Σ_{t∋p} Area(t)/#t (length, volume shares for curves, volumes).
    geometry : Geometry
        What the kernel was built from; ``dim`` is its intrinsic dimension k.
    faces : Polygons or None
        The faces of a surface mesh; None for curves, volumes and point clouds.
    h, tol, radius : float
        Kernel width (the largest, with per-vertex widths), tolerance and the cut-off radius.
    h_vertex : (n,) ndarray or None
        Per-vertex widths, when they differ.
    correction, fallback_reason : str, str or None
        The correction in effect, and why the Richardson kernel was given up if it was.
    psd_margin, moment_scale : float or None, float
        Smallest eigenvalue of (−S, M) over the largest diagonal entry of −L (the check),
        and the global second-moment factor (docs/accuracy.md).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(500, seed=0)
    >>> op = meshlap.laplacian(V, F, h=0.01)
    >>> Lx = op @ V[:, 0]            # ≈ -2x on the unit sphere
    >>> bool(np.linalg.norm(Lx + 2 * V[:, 0]) < 0.1 * np.linalg.norm(2 * V[:, 0]))
    True
    """

    def __init__(
        self,
        V: Any,
        F: Any = None,
        h: float | None = None,
        tol: float = DEFAULT_TOL,
        *,
        exact: bool = False,
        dtype: Any = np.float64,
        matrix_free: bool = False,
        max_memory: int | None = None,
        progress: ProgressLike = None,
        correction: str | None = None,
        adaptive: bool = False,
        arc_distance: bool | None = None,
        pointwise: bool | None = None,
        neumann: bool | None = None,
        curvature_limit: float | None = None,
        check_psd: bool = True,
        k: int | None = None,
    ) -> None:
        if isinstance(V, Geometry):
            if F is not None or k not in (None, V.dim):
                raise MeshError("pass either a Geometry alone or vertices V with cells F")
            geo = V
        else:
            if F is None:
                raise MeshError("F must be an (m, k) index array of faces, edges or tetrahedra, or a "
                                "list of polygons; got None (for points alone use "
                                "meshlap.point_cloud_laplacian)")
            geo = geometry.from_mesh(V, F, k)
        self.geometry = geo
        self.dim = geo.dim
        self.faces = geo.faces
        P = geo.points
        # the grid kernel bins three coordinates: lower dimensions get zeros
        self.V = P if P.shape[1] >= 3 else np.ascontiguousarray(np.pad(P, ((0, 0), (0, 3 - P.shape[1]))))
        # the accuracy options need a surface mesh: normals, boundary curves, edge lengths
        surface = geo.faces is not None and geo.dim == 2 and P.shape[1] <= 3
        if correction is None:
            correction = "richardson" if surface else "none"
        if correction not in CORRECTIONS:
            raise MeshError(f"correction must be one of {', '.join(CORRECTIONS)}; got {correction!r}")
        plain = correction == "none"
        if not surface and (adaptive or arc_distance or pointwise or neumann or curvature_limit
                            or np.ndim(h) == 1):
            raise MeshError(f"adaptive, arc_distance, pointwise, neumann, curvature_limit and a "
                            f"per-vertex h need a surface mesh with faces; this geometry is a "
                            f"{geo.source} (k={geo.dim})")
        # the accuracy options follow the correction unless given; matrix-free keeps a fixed h
        adaptive = bool(adaptive)
        on = not plain and not matrix_free and surface
        arc_distance = on if arc_distance is None else bool(arc_distance)
        pointwise = on if pointwise is None else bool(pointwise)
        neumann = on if neumann is None else bool(neumann)
        if matrix_free and (adaptive or arc_distance or pointwise or neumann or np.ndim(h) == 1):
            raise MeshError("matrix_free=True supports a fixed h and Euclidean distances only: "
                            "pass adaptive=False, arc_distance=False, pointwise=False, neumann=False")
        if curvature_limit is None:
            curvature_limit = CURVATURE_LIMIT if (on and h is None) else 0.0
        if curvature_limit and matrix_free:
            raise MeshError("matrix_free=True supports a fixed h only: pass curvature_limit=0")
        if adaptive and h is not None:
            raise MeshError("adaptive=True chooses h per vertex; do not pass h with it")
        self.correction = correction
        self._options = {"correction": correction, "arc_distance": arc_distance,
                         "pointwise": pointwise, "neumann": neumann, "matrix_free": matrix_free,
                         "dtype": dtype, "tol": tol, "exact": exact}
        self._half: MeshLaplacian | None = None
        self.adaptive = adaptive
        self.arc_distance = arc_distance
        self.fallback_reason: str | None = None
        self.tol = 0.0 if exact else check_tol(tol)
        self.exact = self.tol == 0.0
        try:
            self.dtype = np.dtype(dtype)
        except TypeError as exc:
            raise MeshError(f"dtype must be float64 or float32; got {dtype!r}") from exc
        if self.dtype not in (np.float64, np.float32):
            raise MeshError(f"dtype must be float64 or float32; got {self.dtype}")
        self.mass = geo.mass
        self.h_auto = h is None
        h_given: np.ndarray | None = None
        if h is not None and np.ndim(h) == 1 and not plain:
            h_given = np.asarray(h, dtype=np.float64)
            if h_given.shape != (len(self.V),):
                raise MeshError(f"a per-vertex h needs one value per vertex ({len(self.V)}); "
                                f"got {h_given.shape}")
            for x in (float(h_given.min()), float(h_given.max())):
                check_h(x, "the per-vertex h")
            self.h = float(h_given.max())
        elif h is not None:
            self.h = check_h(h)
        elif plain:
            self.h = check_h(geo.default_h, "the automatic h = (2·spacing)²")
        else:
            self.h = check_h(DEFAULT_H_SCALE * geo.spacing**2, "the automatic h = 4·(mean edge)²")
        self.h_vertex: np.ndarray | None = h_given
        if adaptive:
            hv = _corr.local_h(self.V, self.faces, DEFAULT_H_SCALE)
            check_h(float(hv.min()), "the smallest local h")
            check_h(float(hv.max()), "the largest local h")
            self.h_vertex = hv
            self.h = float(np.median(hv[self.mass > 0])) if (self.mass > 0).any() else self.h
        if curvature_limit:
            normals = _corr.vertex_normals(self.V, self.faces)
            hv = _corr.curvature_h(self.V, self.faces, normals,
                                   self.h if self.h_vertex is None else self.h_vertex,
                                   check_positive(curvature_limit, "curvature_limit"))
            if (hv != (self.h if self.h_vertex is None else self.h_vertex)).any():
                check_h(float(hv.min()), "the smallest curvature-limited h")
                self.h_vertex = hv
        self.curvature_limit = float(curvature_limit)
        self.radius = kernel.cutoff_radius(self.h if self.h_vertex is None
                                           else float(self.h_vertex.max()), self.tol)
        self.matrix_free = bool(matrix_free)
        self.max_memory = (int(available_memory() * 0.8) if max_memory is None
                           else int(check_positive(max_memory, "max_memory")))
        self._L: sp.csr_matrix | None = None
        self._S: sp.csr_matrix | None = None
        self._L_pointwise: sp.csr_matrix | None = None
        self.pointwise = False
        self.neumann = neumann
        self.moment_scale = 1.0
        self.psd_margin: float | None = None
        self._frames = None
        self.boundary_rows = 0
        if self.V.shape[1] > 3:  # points in R^d, d > 3: the k-d tree assembly (plain operator)
            if self.matrix_free:
                raise MeshError(f"matrix_free=True needs points in at most 3 dimensions; these have "
                                f"{self.V.shape[1]}")
            self._grid = None
            self._guard(pairs.count_entries(self.V, self.radius), estimated=False)
            self._L = pairs.assemble(self.V, self.mass, self.h, self.radius, self.dim, self.dtype)
            if not plain:
                self._richardson_of_plain(check_psd)
            return
        self._grid = kernel.build_grid(self.V, self.mass, self.radius)
        if not surface and not plain and not self.matrix_free:
            self._L = self._assemble(make_progress(progress))
            self._richardson_of_plain(check_psd)
            return
        if self.matrix_free:
            if not plain and surface:
                self._frames = _corr.boundary_frames(self.V, self.faces, self.radius)
                self.moment_scale = _corr.second_moment_scale(self._apply_free, self.V, self.mass,
                                                              self._band())
            return
        report = make_progress(progress)
        if plain and not adaptive and not arc_distance and not neumann:
            self._L = self._assemble(report)  # the paper's operator, unchanged
            free = self._L
        else:
            self._frames = _corr.boundary_frames(self.V, self.faces, self.radius)
            free = self._assemble_variable(not plain)
            self._L = self._with_images(free, not plain)
            if not plain and check_psd and not self._psd_ok():
                free = self._assemble_variable(False)
                self._L = self._with_images(free, False)
            if not plain:
                self.moment_scale = _corr.second_moment_scale(lambda X: free @ X, self.V,
                                                              self.mass, self._band())
                self._L.data *= self.moment_scale
        if pointwise:
            # point-wise rows from the operator without mirror images: f need not satisfy
            # Neumann conditions, and the moment correction handles the one-sided rows
            self._L_pointwise, unchanged = _corr.moment_correction(free, self.V)
            self.pointwise = True
            self.pointwise_unchanged = unchanged
        if report is not None:
            report(1.0, "done")

    # -- assembly -----------------------------------------------------------------------
    def _bytes_for(self, nnz: float) -> float:
        idx = 4 if (nnz <= _INT32_MAX and self.n_vertices <= _INT32_MAX) else 8
        return nnz * (self.dtype.itemsize + idx) + (self.n_vertices + 1) * idx

    def _sample_counts(self, sample: int, seed: int) -> tuple[float, float]:
        # Mean and standard error of the row counts of `sample` rows drawn with replacement:
        # O(sample) memory and O(sample * row length) time, even when the matrix is dense.
        n = self.n_vertices
        if self._grid is None:  # points in more than 3 dimensions: L is already stored
            return float(self.nnz), 0.0
        if n <= sample:
            return float(kernel.count_entries(self.V, self._grid).sum()), 0.0
        rows = np.random.default_rng(seed).integers(0, n, size=sample)
        counts = kernel.count_entries(self.V, self._grid, rows=rows).astype(np.float64)
        return counts.mean() * n, counts.std(ddof=1) / math.sqrt(sample) * n

    def estimate_nnz(self, sample: int = 512, seed: int = 0) -> int:
        """Estimated stored entries of L from the neighbour counts of a random row sample.

        Exact when the mesh has at most ``sample`` vertices. Costs ``sample`` rows of the
        count pass, so it is cheap even when h is so large that L would be dense.

        Examples
        --------
        >>> import meshlap
        >>> V, F = meshlap.shapes.sphere(2000, seed=0)
        >>> op = meshlap.laplacian(V, F, h=0.01, matrix_free=True, correction="none")
        >>> est = op.estimate_nnz()
        >>> exact = meshlap.laplacian(V, F, h=0.01, correction="none").nnz
        >>> abs(est - exact) < 0.05 * exact
        True
        """
        return int(round(self._sample_counts(sample, seed)[0]))

    def _guard(self, nnz: float, estimated: bool) -> None:
        need = self._bytes_for(nnz)
        if need > self.max_memory:
            how = "at least about" if estimated else "exactly"
            raise OperatorTooLargeError(
                f"the operator would hold {how} {int(nnz):,} entries ({_fmt_bytes(need)}), more than "
                f"max_memory={_fmt_bytes(self.max_memory)}; use a smaller h (now {self.h:.4g}) or "
                f"tol, dtype=float32, or matrix_free=True"
            )

    def _assemble(self, report) -> sp.csr_matrix:
        n = self.n_vertices
        # Fail fast, before the full count pass, only when the sample leaves no doubt (mean
        # four standard errors over the limit); the exact count decides otherwise.
        mean, err = self._sample_counts(512, 0)
        self._guard(max(mean - 4.0 * err, 0.0), estimated=True)
        count_cb = None if report is None else (lambda f: report(0.3 * f, "count"))
        fill_cb = None if report is None else (lambda f: report(0.3 + 0.7 * f, "fill"))
        counts = kernel.count_entries(self.V, self._grid, progress=count_cb, expected_nnz=mean)
        nnz = int(counts.sum())
        self._guard(nnz, estimated=False)
        index_dtype = np.int32 if (nnz <= _INT32_MAX and n <= _INT32_MAX) else np.int64
        indptr = np.zeros(n + 1, dtype=index_dtype)
        np.cumsum(counts, out=indptr[1:])
        lonely = np.flatnonzero((counts == 1) & (self.mass > 0))
        if len(lonely):
            warnings.warn(
                f"{len(lonely)} of {n} vertices have no neighbour within the cut-off radius "
                f"{self.radius:.3g} (h={self.h:.3g}); L is 0 there. Use a larger h.",
                RuntimeWarning,
                stacklevel=3,
            )
        indices, data = kernel.fill_csr(self.V, self._grid, self.h, indptr, index_dtype,
                                        self.dtype, progress=fill_cb, dim=self.dim)
        if report is not None:
            report(1.0, "done")
        return _csr(data, indices, indptr, n)

    def _assemble_variable(self, dog: bool) -> sp.csr_matrix:
        n = self.n_vertices
        hv = np.full(n, self.h) if self.h_vertex is None else self.h_vertex
        normals = _corr.vertex_normals(self.V, self.faces) if self.arc_distance else None
        mean, err = self._sample_counts(512, 0)
        self._guard(max(mean - 4.0 * err, 0.0), estimated=True)
        index_dtype = np.int32 if n <= _INT32_MAX else np.int64

        def guard(nnz: int) -> None:
            self._guard(nnz, estimated=False)
            if nnz > _INT32_MAX:
                raise OperatorTooLargeError(f"{nnz:,} entries need 64-bit indices; use a smaller h")

        indptr, indices, data = kernel.variable_csr(self.V, self._grid, hv, self.tol, normals, dog,
                                                    index_dtype, self.dtype, max_nnz=guard)
        return _csr(data, indices, indptr, n)

    def _richardson_of_plain(self, check_psd: bool) -> None:
        # Curves, volumes, point clouds: 2 L_{h/2} − L_h from two plain operators of the same
        # geometry (normalized for its dimension k; no normals or boundary curves needed).
        plain = self._L
        half = MeshLaplacian(self.geometry, h=0.5 * self.h, tol=self.tol, dtype=self.dtype,
                             max_memory=self.max_memory, correction="none")
        self._L = sp.csr_matrix(2.0 * half.L - plain)
        cells = self.geometry.cells
        faces = cells if cells is not None and cells.shape[1] == 3 and self.V.shape[1] == 3 else None
        if check_psd and not self._psd_ok(faces, "points", stacklevel=5):
            self._L = plain

    def _band(self) -> np.ndarray | None:
        return None if self._frames is None else self._frames[0]

    def _with_images(self, L: sp.csr_matrix, dog: bool) -> sp.csr_matrix:
        if not self.neumann:
            return L
        hv = np.full(self.n_vertices, self.h) if self.h_vertex is None else self.h_vertex
        if self._frames is not None:
            self.boundary_rows = len(self._frames[0])
        return _corr.neumann_images(L, self.V, self._frames, self.mass, hv, dog)

    def _psd_ok(self, faces: Any = None, what: str = "mesh", stacklevel: int = 4) -> bool:
        # faces only precondition the eigen-solver (None: none)
        lam_min, scale = _corr.smallest_eigenvalue(self._L, self.mass, self.V,
                                                   self.faces if what == "mesh" else faces)
        self.psd_margin = lam_min / scale
        if lam_min < -1e-6 * scale:
            self.fallback_reason = (
                f"the Richardson operator is not negative semidefinite here (eigenvalue "
                f"{lam_min:.3g} of -S against the scale {scale:.3g}): h is too small for the "
                f"{what} to resolve the narrow kernel h/2; using the plain kernel (O(h) bias)")
            warnings.warn(self.fallback_reason + "; pass a larger h to keep the correction",
                          MeshWarning, stacklevel=stacklevel)
            self.correction = "none"
            return False
        return True

    # -- the matrices -------------------------------------------------------------------
    @property
    def L(self) -> sp.csr_matrix:
        if self._L is None:
            raise MeshError(
                "this operator is matrix-free (matrix_free=True): L is not stored; use op @ f "
                "or op.as_linear_operator()"
            )
        return self._L

    @property
    def M(self) -> sp.csr_matrix:
        # also for a matrix-free operator, which has no L to take the value type from
        return sp.diags(self.mass.astype(self.dtype), format="csr")

    # -- sizes --------------------------------------------------------------------------
    @property
    def n_vertices(self) -> int:
        return len(self.V)

    @property
    def shape(self) -> tuple[int, int]:
        return (self.n_vertices, self.n_vertices)

    @property
    def nnz(self) -> int:
        """Stored entries of L (0 when matrix-free)."""
        return 0 if self._L is None else int(self._L.nnz)

    @property
    def nbytes(self) -> int:
        """Bytes held by the CSR arrays of L and L_pointwise (0 when matrix-free)."""
        if self._L is None:
            return 0
        extra = 0 if self._L_pointwise is None else self._L_pointwise.data.nbytes  # shares the indices
        return int(self._L.data.nbytes + self._L.indices.nbytes + self._L.indptr.nbytes + extra)

    # -- application --------------------------------------------------------------------
    def __matmul__(self, f: Any) -> np.ndarray:
        f = check_function(f, self.n_vertices)
        if self._L is None:
            return self._apply_free(f)
        if self._L_pointwise is not None:
            return np.asarray(self._L_pointwise @ f)
        return np.asarray(self._L @ f)

    def _apply_free(self, f: np.ndarray) -> np.ndarray:
        if self.correction == "none":
            return kernel.apply(self.V, self._grid, self.h, f, self.dim)
        # the same pairs as the assembled Richardson operator: both widths cut at r(h)
        return self.moment_scale * (2.0 * kernel.apply(self.V, self._grid, 0.5 * self.h, f, self.dim)
                                    - kernel.apply(self.V, self._grid, self.h, f, self.dim))

    def error_estimate(self, f: Any) -> np.ndarray:
        """Estimated error |L f − Δf| at every vertex, from the same operator at half the width.

        Builds (once, then kept) the operator with every width halved and the same options,
        and returns |op @ f − op_half @ f|, doubled for ``correction="none"`` (whose error is
        O(h), so e(h) ≈ 2 (e(h) − e(h/2))). For the default operator the error is no longer
        dominated by a power of h but by the quadrature, which grows as h shrinks, and the
        difference follows it: the norm of the estimate was 0.4-2.1 times the norm of the
        exact error on the spheres (uniform, random; 4,000 and 16,000 vertices), the torus
        and the plane (tests/test_accuracy.py, docs/accuracy.md). Read it as the size of
        the error, not as a bound or a correction.

        Examples
        --------
        >>> import meshlap, numpy as np
        >>> V, F = meshlap.shapes.sphere(2000, kind="random", seed=0)
        >>> op = meshlap.laplacian(V, F)
        >>> est = op.error_estimate(V[:, 0] ** 2)
        >>> err = op @ V[:, 0] ** 2 - (2 - 6 * V[:, 0] ** 2)
        >>> bool(0.3 < np.linalg.norm(est) / np.linalg.norm(err) < 3)
        True
        """
        f = check_function(f, self.n_vertices)
        if self._half is None:
            h = 0.5 * (self.h if self.h_vertex is None else self.h_vertex)
            opts = dict(self._options)
            opts["correction"] = self.correction  # after a fallback: the plain kernel
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", MeshWarning)
                if self.faces is not None and self.dim == 2:
                    self._half = MeshLaplacian(self.V, self.faces, h=h, check_psd=False,
                                               curvature_limit=0, max_memory=self.max_memory, **opts)
                else:  # curves, volumes, point clouds: the same geometry at half the width
                    self._half = MeshLaplacian(self.geometry, h=h, max_memory=self.max_memory,
                                               **opts)
        diff = np.abs(self @ f - self._half @ f)
        return 2.0 * diff if self.correction == "none" else diff

    @property
    def L_pointwise(self) -> sp.csr_matrix:
        """The point-wise operator that ``op @ f`` applies: L with each row corrected to be
        exact for quadratics in the tangent plane (:func:`meshlap.correction.moment_correction`);
        ``L`` itself when the correction is off. Not symmetric: spectra use ``S``."""
        return self.L if self._L_pointwise is None else self._L_pointwise

    def matvec(self, f: Any) -> np.ndarray:
        """``L @ f`` for a vector or an (n, k) block of functions."""
        return self @ f

    def as_linear_operator(self) -> LinearOperator:
        """L as a :class:`scipy.sparse.linalg.LinearOperator` (matrix-free when not stored)."""
        if self._L is not None:
            return sp.linalg.aslinearoperator(self._L)
        return LinearOperator(
            self.shape,
            matvec=lambda x: self._apply_free(np.asarray(x, np.float64).reshape(-1)),
            matmat=lambda X: self._apply_free(np.asarray(X, np.float64)),
            dtype=np.float64,
        )

    # -- display ------------------------------------------------------------------------
    def _summary(self) -> list[tuple[str, str]]:
        scale = "(2·mean edge)²"
        h_note = f" (auto: {scale})" if self.h_auto else ""
        if self.adaptive:
            h_note = " (median of the per-vertex widths, adaptive)"
        elif self.h_vertex is not None:
            h_note += f"; narrower where the surface bends, down to {self.h_vertex.min():.3g}"
        geo = self.geometry
        if geo.faces is None:
            h_note = h_note.replace("mean edge", "spacing")
        rows = [("vertices", f"{self.n_vertices:,}")]
        if geo.faces is not None:
            rows.append(("faces", f"{self.faces.n_faces:,}"))
        else:
            rows.append(("geometry", f"{geo.source}, k={geo.dim} in R^{geo.ambient_dim}"))
        rows += [
            ("h", f"{self.h:.6g}{h_note}"),
            ("correction", self.correction + (" + point-wise moments" if self.pointwise else "")),
            ("tol", "0 (exact)" if self.exact else f"{self.tol:.3g}"),
            ("radius", "∞" if self.exact else f"{self.radius:.6g}"),
        ]
        if self._L is None:
            rows.append(("storage", "matrix-free"))
        else:
            rows += [
                ("nnz", f"{self.nnz:,} ({self.nnz / self.n_vertices:.1f} per row)"),
                ("memory", f"{_fmt_bytes(self.nbytes)} ({self.dtype.name})"),
            ]
        return rows

    def __repr__(self) -> str:
        inner = ", ".join(f"{k}={v}" for k, v in self._summary())
        return f"MeshLaplacian({inner})"

    def _repr_html_(self) -> str:
        body = "".join(f"<tr><th style='text-align:left'>{k}</th><td>{v}</td></tr>"
                       for k, v in self._summary())
        return f"<table><caption>MeshLaplacian (Belkin–Sun–Wang)</caption>{body}</table>"


def laplacian(
    V: Any,
    F: Any = None,
    h: float | None = None,
    tol: float = DEFAULT_TOL,
    **kwargs: Any,
) -> MeshLaplacian:
    """Build the Belkin–Sun–Wang mesh Laplacian of a mesh (SoCG 2008, eq. 1).

    Parameters
    ----------
    V : (n, d) array_like, Geometry, or a mesh object
        Vertex positions (or a :class:`~meshlap.geometry.Geometry`, with ``F`` None), or,
        with ``F`` None, a ``trimesh.Trimesh``, ``pyvista.PolyData`` / ``UnstructuredGrid``,
        ``open3d`` ``TriangleMesh`` / ``TetraMesh``, ``meshio.Mesh`` or a file path
        (:func:`meshlap.inputs.as_geometry_input`).
    F : (m, c) array_like or list of sequences
        Faces of any size; (m, 2) edges of a curve; tetrahedra with ``k=3``.
    h : float or (n,) array_like, optional
        Kernel width (exp(-d²/4h)); default on surface meshes 4ē² narrowed where the surface
        bends, else (and with ``correction="none"``) :func:`default_h` = (2ē)².
    tol : float, default 1e-8
        Kernel tolerance; 0 for the untruncated operator.
    **kwargs
        ``k``, ``exact``, ``dtype``, ``matrix_free``, ``max_memory``, ``progress`` and the
        accuracy options ``correction`` (default "richardson" on surface meshes; "none" is
        the paper's operator), ``adaptive``, ``arc_distance``, ``pointwise``, ``neumann``,
        ``curvature_limit``, ``check_psd``: see :class:`MeshLaplacian` and docs/accuracy.md.

    Returns
    -------
    MeshLaplacian
        Holds ``L``, ``M``, ``S``, ``mass``, ``h``, ``radius``; ``op @ f`` applies L.

    Examples
    --------
    >>> import meshlap
    >>> V, F = meshlap.shapes.plane(2000, seed=0)
    >>> op = meshlap.laplacian(V, F, h=0.01)
    >>> op.L.shape
    (2000, 2000)
    """
    if F is None and not isinstance(V, (Geometry, np.ndarray, list)):  # trimesh, pyvista, meshio, open3d
        V, F, kwargs["k"] = _held_input(V, kwargs.get("k"))
    return MeshLaplacian(V, F, h=h, tol=tol, **kwargs)


def _held_input(obj: Any, k: int | None) -> tuple[Any, Any, int | None]:
    from .inputs import as_geometry_input

    V, F, k_cells = as_geometry_input(obj)
    return V, F, k if k is not None else k_cells


def mesh_laplacian(V: Any, F: Any = None, h: float | None = None, tol: float = DEFAULT_TOL,
                   **kwargs: Any) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """The pair ``(L, M)``: the Belkin–Sun–Wang Laplacian and its lumped mass matrix.

    A shortcut for ``op = laplacian(V, F, h, tol); (op.L, op.M)``. Note the sign: L is
    negative semidefinite (L ≈ +Δ), like libigl's ``cotmatrix`` and unlike
    robust-laplacian's positive weak form.

    Examples
    --------
    >>> import meshlap
    >>> V, F = meshlap.shapes.sphere(300, seed=0)
    >>> L, M = meshlap.mesh_laplacian(V, F, h=0.02)
    >>> bool(abs(M.diagonal().sum() - 4 * 3.14159) < 0.2)
    True
    """
    op = MeshLaplacian(V, F, h=h, tol=tol, **kwargs)
    return op.L, op.M


def truncation_bound(op: MeshLaplacian, f: np.ndarray) -> np.ndarray:
    """Per-vertex bound on |L_exact f - L_tol f| = tol·A·max_p|f(p)-f(w)| / (h (4πh)^{k/2})."""
    f = check_function(f, op.n_vertices)
    spread = np.maximum(np.abs(f.max(axis=0) - f), np.abs(f - f.min(axis=0)))
    return op.tol * op.mass.sum() * spread * kernel.normalization(op.h, op.dim)
