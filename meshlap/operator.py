"""Stage 6 of the pipeline: the operator, which holds what the stages built.

Belkin, Sun and Wang, "Discrete Laplace operator on meshed surfaces", SoCG 2008, eq. (1):

    L f(w) = 1/(4πh²) Σ_t Area(t)/#t Σ_{p∈V(t)} exp(-|p-w|²/4h) (f(p) - f(w))

Grouping the face sums by vertex gives the lumped mass m_p = Σ_{t∋p} Area(t)/#t and

    L = (K M - diag(K m)) / (4πh²),   K_wp = exp(-|p-w|²/4h),  M = diag(m).

:class:`MeshLaplacian` wires the stages (:mod:`meshlap.geometry` → :mod:`meshlap.widths` →
:mod:`meshlap.assembly` → :mod:`meshlap.corrections`, run by :mod:`meshlap.pipeline`) and
computes nothing itself.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Literal

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import LinearOperator

from . import pipeline, policy
from . import widths as widths_mod
from .assembly import cutoff_radius, fmt_bytes
from .errors import MeshError, OperatorTooLargeError
from .geometry import Geometry, from_mesh
from .geometry.validation import check_function
from .lumped import LumpedLaplacian
from .pipeline import CORRECTED_TOL, CORRECTIONS, DEFAULT_TOL
from .progress import ProgressLike, make_progress
from .tuned import CURVATURE_LIMIT
from .widths import DEFAULT_H_SCALE, default_h

__all__ = [
    "CORRECTED_TOL",
    "CORRECTIONS",
    "CURVATURE_LIMIT",
    "DEFAULT_H_SCALE",
    "DEFAULT_TOL",
    "MeshLaplacian",
    "OperatorTooLargeError",
    "as_geometry",
    "default_h",
]


def as_geometry(V: Any, F: Any = None, k: int | None = None) -> Geometry:
    """Stage 1's entry: a :class:`~meshlap.geometry.Geometry` as it is, or one from a mesh.

    Examples
    --------
    >>> import meshlap
    >>> as_geometry(*meshlap.shapes.sphere(200, seed=0)).dim
    2
    """
    if isinstance(V, Geometry):
        if F is not None or k not in (None, V.dim):
            raise MeshError("pass either a Geometry alone or vertices V with cells F")
        return V
    if F is None:
        raise MeshError("F must be an (m, k) index array of faces, edges or tetrahedra, or a list of "
                        "polygons; got None (for points alone use meshlap.point_cloud_laplacian)")
    return from_mesh(V, F, k)


class MeshLaplacian(LumpedLaplacian):
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
        Area(t)/#t to each of its #t corners; (m, 2) edges of a curve; (m, 4) tetrahedra,
        told from quads by how they meet (:func:`meshlap.geometry.from_mesh`; ``k`` overrides).
    h : float or (n,) array_like, optional
        Kernel width; the Gaussian is exp(-d²/4h). An explicit value always wins; an array
        gives each vertex its own width (pair width (h_w + h_p)/2; not with
        ``correction="none"``). Without one: 4ē² (ē the geometry's spacing, the mean edge
        length of a mesh), narrowed where the geometry bends (``curvature_limit``); with
        ``correction="none"`` the paper's (2ē)².
    correction : {"richardson", "none"}, default "richardson"
        "richardson", for every geometry: the kernel 2K_{h/2} − K_h, second order in h, with
        −S checked to be semidefinite (otherwise ``fallback_reason`` and the plain kernel, and a
        :class:`MeshWarning` where that pencil is used: not when the Galerkin pencil and the
        fitted rows replace it). "none": the paper's operator, eq. (1), and none of the
        options below unless asked for. docs/accuracy.md has the measurements.
    adaptive : bool, default False
        Per-vertex widths 4ℓ_w² from the local edge lengths.
    arc_distance, neumann : bool, optional
        Default True with the correction (``arc_distance`` only where normals exist,
        codimension 1, and not matrix-free): distances scaled by the arc/chord ratio of the
        normals; mirror images at the boundary (Neumann spectra) for curves, surfaces,
        volumes and clouds.
    pointwise : {"fit", True, False}, optional
        What ``op @ f`` (``op.L``) applies. Default "fit" with the correction: rows exact for
        polynomials up to degree 6 in local coordinates of the fitted manifold, their width
        and degree chosen per point from the data (compact and high degree where clean, wide
        and low where noisy; :func:`meshlap.corrections.rowchoice.choose_rows`,
        ``op.pointwise_choice``, summarized in the repr). True: the kernel's own rows
        corrected to be exact for quadratics (moments). False: ``op.L`` is ``op.L_sym``.
    pointwise_degree : int, optional
        Rows exact for polynomials of this degree (2-6) fitted on the kernel's own stencil
        with its Gaussian weights (:func:`meshlap.corrections.highorder.pointwise_rows`).
    curvature_limit : float, optional
        β of h_w = min(h, β/κ_w²); default 0.05 with the correction, automatic h and
        normals, else 0. On a surface's point cloud h_w stays at least half of h
        (:data:`meshlap.tuned.CLOUD_CAP_FLOOR`).
    check_psd : bool, default True
        Check that −S is positive semidefinite (Richardson only), else fall back to the plain
        kernel (``fallback_reason`` says why). False builds the Richardson operator as is.
    tol : float, optional
        Default 1e-6 for the corrected operators, 1e-8 for the paper's (``correction="none"``)
        and for the Galerkin pencil (of meshes and curves), where 1e-6 costs measurable accuracy.
        Kernel tolerance: weights exp(-d²/4h) < tol are dropped, which cuts the sums off at
        r = sqrt(4h ln(1/tol)). For every vertex w the truncated operator differs from the
        exact one by at most ``tol * A * max_p |f(p) - f(w)| / (4π h²)`` with A the total
        area (sum of masses). ``tol=0`` keeps every pair (dense; small meshes only).
    exact : bool, default False
        Same as ``tol=0``.
    dtype : {numpy.float64, numpy.float32}
        Value type of the stored matrix (float32 halves the memory of the values).
    matrix_free : bool, default False
        Do not store the kernel (a pencil too large for memory): spectra and heat flow recompute
        it on the fly (:meth:`sym_product`), adding a boundary band's mirror images, stored;
        ``op @ f`` applies the fitted rows, stored (about 50 entries a row), or with
        ``correction="none"`` the kernel recomputed.
    max_memory : int, optional
        Bytes the stored matrix may take; default 80% of the memory available now. A build
        that would exceed it raises :class:`OperatorTooLargeError` before allocating: at
        construction where a sample of rows leaves no doubt, else when the pencil is built.
    progress : bool or callable, optional
        ``True`` draws a bar on stderr; a callable gets ``(fraction, stage)``.
    quadrature : {"vertex", "galerkin"}, default "vertex"
        How the symmetric pencil (``L_sym``, ``S``: spectra, heat flow, smoothing) integrates
        the kernel. "vertex": one point per vertex, the lumped masses. "galerkin": over the
        triangles (segments, tetrahedra) with the hat functions, 3 points per triangle, at
        h = 0.5·ē² unless ``h`` is given (:mod:`meshlap.corrections.galerkin`); ``op.L``
        keeps the vertex rows. ``op.quadrature`` says which is in effect ("fem", linear FEM on
        the same cells, where the Galerkin one's -S is not semidefinite, with a
        :class:`MeshWarning`).
    feature_width : bool, optional
        With ``quadrature="galerkin"``: its width follows feature size: narrower (to h/2, its
        triangles cut in 4) within 2 kernel widths of a groove (a concave crease) and on parts
        thinner than 3 widths (:mod:`meshlap.corrections.features`; fandisk 0.142% → 0.087%,
        spot 1.32% → 0.96%). Default: where h is automatic and the normals are not noise;
        False: one width; True: also at an explicit h.
    denoise, mass
        Options of the FEM pencil (``quadrature="fem"``): :func:`meshlap.laplacian`.
    k : {1, 2, 3}, optional
        Intrinsic dimension of the mesh, inferred from ``F`` when not given; the kernel's
        normalization is 1/(h (4πh)^{k/2}) (1/(4πh²) on surfaces).

    Attributes
    ----------
    L : scipy.sparse.csr_matrix
        What ``op @ f`` applies, the accurate L f ≈ Δf at every point: by default the
        fitted point-wise rows (not symmetric in M; their own sparsity pattern), fitted on first
        use (:meth:`fit_rows`); eq. (1) of the paper with ``correction="none"``.
    L_sym : scipy.sparse.csr_matrix
        The symmetric pencil's L, S = M L_sym: the Richardson kernel with mirror images at the
        boundary (Neumann); ``L`` itself without point-wise rows. Spectra, heat flow and
        smoothing use it (through ``S`` and ``M``). Built on first use (:meth:`assemble`), with
        the facts below that describe it (correction, fallback, margin, scale).
    M : scipy.sparse.csr_matrix
        Diagonal lumped mass matrix.
    S : scipy.sparse.csr_matrix
        ``M @ L_sym``, symmetric, negative semidefinite.
    mass : (n,) ndarray
        Vertex masses m_p = Σ_{t∋p} Area(t)/#t (length, volume shares for curves, volumes).
    geometry : Geometry
        What the kernel was built from; ``dim`` is its intrinsic dimension k.
    faces : Polygons or None
        The faces of a surface mesh; None for curves, volumes and point clouds.
    options, widths : Options, Widths
        What the build resolved (:mod:`meshlap.pipeline`, :mod:`meshlap.widths`).
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
        tol: float | None = None,
        *,
        exact: bool = False,
        dtype: Any = np.float64,
        matrix_free: bool = False,
        max_memory: int | None = None,
        progress: ProgressLike = None,
        correction: Literal["richardson", "none"] | None = None,
        adaptive: bool = False,
        arc_distance: bool | None = None,
        pointwise: bool | Literal["fit"] | None = None,
        neumann: bool | None = None,
        curvature_limit: float | None = None,
        check_psd: bool = True,
        k: int | None = None,
        pointwise_degree: int | None = None,
        quadrature: Literal["vertex", "galerkin", "fem"] | None = None,
        feature_width: bool | None = None,
        denoise: bool = False,
        mass: Literal["lumped", "blend", "consistent"] = "lumped",
    ) -> None:
        self.geometry = as_geometry(V, F, k)
        self.options = pipeline.Options.resolve(
            self.geometry, h, correction=correction, adaptive=adaptive, arc_distance=arc_distance,
            pointwise=pointwise, neumann=neumann, curvature_limit=curvature_limit, check_psd=check_psd,
            matrix_free=matrix_free, tol=tol, exact=exact, dtype=dtype, max_memory=max_memory,
            pointwise_degree=pointwise_degree, quadrature=quadrature, feature_width=feature_width,
            denoise=denoise, mass=mass)
        self.widths = widths_mod.choose(self.geometry, h, plain=self.options.plain, adaptive=adaptive,
                                        curvature_limit=self.options.curvature_limit)
        # the symmetric pencil and the fitted rows are made on first use, each once (assemble,
        # fit_rows); the pencil's warnings come then, pointed at the line that asked for it
        self._built = pipeline.build(self.geometry, self.widths, self.options, make_progress(progress),
                                     review=True)
        self._half: pipeline.Built | None = None
        self._S = None
        self._decision: policy.Decision | None = None

    # -- what the stages decided ---------------------------------------------------------
    dim = property(lambda self: self.geometry.dim, doc="Intrinsic dimension k.")
    faces = property(lambda self: self.geometry.faces, doc="The faces of a surface mesh, else None.")
    @property
    def mass(self) -> np.ndarray:
        """Lumped masses m_p: the pencil's own (FEM's; Galerkin's on welded copies), else the geometry's."""
        own = self._built.assemble().mass if self.options.quadrature in ("fem", "galerkin") else None
        return self.geometry.mass if own is None else own

    @property
    def pencil_points(self) -> np.ndarray:
        """Positions the pencil was built on, which gradients, divergences and distances use: with
        ``denoise=True`` those after its denoising step (builds the pencil), else the geometry's."""
        moved = self._built.assemble().points if self.options.denoise else None
        return self.geometry.points if moved is None else moved

    area_scale = property(lambda self: self._built.assemble().area_scale if self.options.denoise else None,
                          doc="denoise=True's mass factors: 1/(1 + :func:`meshlap.denoise.area_left`).")

    n_vertices = property(lambda self: self.geometry.n_points, doc="Rows of the operator (builds nothing).")
    decision = property(lambda self: policy.as_built(self._decision or policy.decide(self.geometry, _named(
        self.options)), getattr(self._built.held_pencil, "quadrature", None)), doc="What was built and why.")
    elements = property(lambda self: self.decision.elements, doc="What spectral.eigs solves (policy).")

    h = property(lambda self: self.widths.h, doc="Kernel width (the base width with per-point widths).")
    h_vertex = property(lambda self: self.widths.h_vertex, doc="Per-point widths, when they differ.")
    h_auto = property(lambda self: self.widths.h_auto, doc="Whether h was chosen automatically.")
    adaptive = property(lambda self: self.widths.adaptive)
    curvature_limit = property(lambda self: self.widths.curvature_limit)
    tol = property(lambda self: self.options.tol, doc="Kernel tolerance (0: untruncated).")
    exact = property(lambda self: self.options.tol == 0.0)
    dtype = property(lambda self: self.options.dtype)
    matrix_free = property(lambda self: self.options.matrix_free)
    max_memory = property(lambda self: self.options.max_memory)
    neumann = property(lambda self: self.options.neumann)
    arc_distance = property(lambda self: self.options.arc_distance, doc="Whether the kernel measures arcs.")
    # the symmetric pencil's facts (built on first read: assemble)
    correction = property(lambda self: self._built.assemble().correction, doc="The correction in effect.")
    fallback_reason = property(lambda self: self._built.assemble().fallback_reason)
    psd_margin = property(lambda self: self._built.assemble().psd_margin)
    moment_scale = property(lambda self: self._built.assemble().moment_scale)
    boundary_rows = property(lambda self: self._built.assemble().boundary_rows)
    quadrature = property(lambda self: self._built.assemble().quadrature,
                          doc="The symmetric pencil's quadrature in effect: 'vertex' or 'galerkin'.")
    quadrature_h = property(lambda self: self._built.assemble().quadrature_h,
                            doc="The Galerkin pencil's h, else None.")
    # the rows op @ f applies (made on first read: fit_rows)
    pointwise_unchanged = property(lambda self: self._built.fit_rows().unchanged)
    pointwise_choice = property(lambda self: self._built.fit_rows().choice,
                                doc="Per-point width and degree of the fitted rows (the default), else None.")
    pointwise = property(lambda self: bool(self.options.pointwise),
                         doc="Whether ``L`` holds point-wise rows distinct from ``L_sym`` (made or not yet).")

    def fit_rows(self) -> MeshLaplacian:
        """Compute the rows ``op @ f`` applies now; returns the operator.

        The default's rows (``pointwise="fit"``) read the points alone and are fitted on first
        use: the first ``op @ f``, ``op.L``, :meth:`matvec`, :meth:`as_linear_operator`,
        :meth:`error_estimate`, ``op.pointwise_choice``, curvature or saving fits them, once
        (under a lock, whichever thread comes first), with the same bits a fit at build time
        gives. Spectra, heat flow and smoothing use the symmetric pencil (:meth:`assemble`) and
        never fit them. Rows on the kernel's own stencil (``pointwise=True``,
        ``pointwise_degree``) and the paper's operator (whose ``L`` is ``L_sym``) come with the
        pencil: for them this builds the pencil. Call this to pay for the rows at a time of your
        choosing (e.g. before timing ``op @ f``, or before threads share the operator); it does
        nothing when they are held.

        Examples
        --------
        >>> import meshlap
        >>> op = meshlap.laplacian(*meshlap.shapes.sphere(800, seed=0))
        >>> "fitted on first use" in repr(op), "fitted on first use" in repr(op.fit_rows())
        (True, False)
        """
        self._built.fit_rows()
        return self

    def assemble(self) -> MeshLaplacian:
        """Build the symmetric pencil now; returns the operator.

        The pencil (``L_sym``, ``S``: what spectra, heat flow and smoothing read; with it the
        semidefiniteness check and its fallback, the moment scale, the Galerkin pencil) is built
        on first use: the first ``op.L_sym``, ``op.S``, :func:`~meshlap.spectral.eigs`, heat flow,
        smoothing, a fact of the pencil (``op.correction``, ``op.fallback_reason``, ...) or saving
        builds it, once (under a lock, whichever thread comes first), with the same bits as a
        build at construction; its warning (the fallback) comes then. ``op @ f`` of the default
        (the fitted rows, :meth:`fit_rows`) never builds it. Call this to pay for it at a time of
        your choosing (e.g. before timing eigs); it does nothing when it is held. The memory
        guard still refuses at construction a pencil over ``max_memory``.

        Examples
        --------
        >>> import meshlap
        >>> op = meshlap.laplacian(*meshlap.shapes.sphere(800, seed=0))
        >>> op.assemble() is op
        True
        >>> "pencil=fem, on first use" in repr(meshlap.laplacian(*meshlap.shapes.sphere(800, seed=0)))
        True
        >>> op.correction          # the default's pencil: linear FEM on the faces
        'fem'
        """
        self._built.assemble()
        return self

    @property
    def radius(self) -> float:
        """Cut-off radius r = sqrt(4 h ln(1/tol)) of the largest width."""
        return cutoff_radius(self.widths.largest, self.tol)

    @property
    def V(self) -> np.ndarray:
        """Positions, padded with zero columns to 3 in fewer dimensions (the grid's view)."""
        P = self.geometry.points
        return P if P.shape[1] >= 3 else np.pad(P, ((0, 0), (0, 3 - P.shape[1])))

    # -- the matrices -------------------------------------------------------------------
    def _stored(self, M: sp.csr_matrix | None) -> sp.csr_matrix:
        if M is None:
            raise MeshError("this operator is matrix-free (matrix_free=True): its matrices are not stored. "
                            "op @ f, eigs and implicit heat flow work without them; for op.L, op.S and what "
                            "factors them (poisson, distances) build it without matrix_free")
        return M

    @property
    def L(self) -> sp.csr_matrix:
        """What ``op @ f`` applies: L f ≈ Δf at every point (the point-wise rows by default,
        fitted on first use: :meth:`fit_rows`)."""
        return self._stored(self._built.fit_rows().L)

    @property
    def L_sym(self) -> sp.csr_matrix:
        """The symmetric pencil's L: ``S = M @ L_sym`` (spectra, heat flow, smoothing; built on
        first use: :meth:`assemble`)."""
        return self._stored(self._built.assemble().L_sym)

    @property
    def M(self) -> sp.csr_matrix:
        """Diagonal lumped mass matrix (also for a matrix-free operator)."""
        return sp.diags(self.mass.astype(self.dtype), format="csr")

    @property
    def nnz(self) -> int:
        """Stored entries of L_sym (0 when matrix-free; builds the pencil)."""
        return 0 if self.matrix_free else int(self.L_sym.nnz)

    @property
    def nbytes(self) -> int:
        """Bytes held by L_sym's CSR arrays (matrix-free: the boundary's mirror images) and the point-
        wise values: the pencil once built (:meth:`assemble`), the rows once fitted (:meth:`fit_rows`)."""
        pencil, rows = self._built.held_pencil, self._built.held_rows
        L = None if pencil is None else pencil.L_sym
        if L is None and pencil is not None and pencil.matrix_free is not None:
            L = pencil.matrix_free.images
        P = None if rows is None else rows.L
        total = 0 if L is None else L.data.nbytes + L.indices.nbytes + L.indptr.nbytes
        if P is not None and P is not L:
            # the moment rows share L_sym's indices; the fitted rows and a Galerkin pencil have their own
            shared = L is not None and P.indices is L.indices
            total += P.data.nbytes + (0 if shared else P.indices.nbytes + P.indptr.nbytes)
        return int(total)

    def estimate_nnz(self, sample: int = 512, seed: int = 0) -> int:
        """Estimated stored entries from the neighbour counts of a random row sample.

        Exact when the geometry has at most ``sample`` points; cheap even when h is so large
        that L would be dense. A stored operator reports its count.

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
        if not self.matrix_free:
            return self.nnz
        return int(round(self._built.assemble().matrix_free.count_entries(sample, seed)))

    # -- application --------------------------------------------------------------------
    def __matmul__(self, f: Any) -> np.ndarray:
        f = check_function(f, self.n_vertices)
        rows = self._built.fit_rows().L
        return self.sym_product(f) if rows is None else np.asarray(rows @ f)

    def sym_product(self, f: Any) -> np.ndarray:
        """``L_sym @ f`` (the symmetric pencil's L), also when matrix-free: the kernel recomputed.

        Examples
        --------
        >>> import meshlap, numpy as np
        >>> V, F = meshlap.shapes.sphere(300, seed=0)
        >>> free = meshlap.laplacian(V, F, h=0.02, matrix_free=True)
        >>> err = lambda y: np.linalg.norm(y + 2 * V[:, 0]) / np.linalg.norm(2 * V[:, 0])  # Δx = -2x
        >>> bool(err(free.sym_product(V[:, 0])) < 0.4), bool(err(free @ V[:, 0]) < 0.002)  # pencil, rows
        (True, True)
        """
        f = check_function(f, self.n_vertices)
        if self.matrix_free:
            return self._built.assemble().matrix_free(np.asarray(f, dtype=np.float64))
        return np.asarray(self.L_sym @ f)

    def matvec(self, f: Any) -> np.ndarray:
        """``L @ f`` for a vector or an (n, k) block of functions."""
        return self @ f

    def as_linear_operator(self) -> LinearOperator:
        """``op @ f`` (the point-wise L) as a :class:`scipy.sparse.linalg.LinearOperator`
        (matrix-free when not stored). It is not symmetric: for ``eigsh`` or ``lobpcg`` use the
        symmetric pencil, ``eigsh(-op.S, k, op.M, sigma=...)`` or :func:`meshlap.mesh_laplacian`,
        or :func:`meshlap.spectral.eigs`.

        Examples
        --------
        >>> import meshlap, numpy as np
        >>> V, F = meshlap.shapes.sphere(800, seed=0)
        >>> A = meshlap.laplacian(V, F).as_linear_operator()
        >>> bool(np.allclose(A @ V[:, 2], -2 * V[:, 2], atol=0.02))   # Δz = -2z
        True
        """
        rows = self._built.fit_rows().L
        if rows is not None:
            return sp.linalg.aslinearoperator(rows)
        free = self._built.assemble().matrix_free
        return LinearOperator(self.shape, matvec=lambda x: free(np.asarray(x, np.float64).reshape(-1)),
                              matmat=lambda X: free(np.asarray(X, np.float64)), dtype=np.float64)

    def error_estimate(self, f: Any) -> np.ndarray:
        """Estimated error |L f − Δf| at every vertex, from a second operator.

        With the fitted point-wise rows (the default) the second operator holds the same rows
        twice as wide (:func:`meshlap.corrections.rowchoice.wider_rows`: each row's degree q
        on twice its neighbours and width), and the estimate is |op @ f − wide @ f| /
        (2^{(q−1)/2} − 1), the error of a degree-q row growing as its radius to the power
        q − 1 on clean data; where noise dominates, the difference is the noise the wider
        row averages out. Its norm was 0.6-2.8 times the norm of the exact error on a random
        sphere (clean, 0.1% and 1% noise), the torus and the plane (tests/test_accuracy.py).

        Otherwise it builds (once, then kept) the operator with every width halved and the
        same options, and returns |op @ f − op_half @ f|, doubled for ``correction="none"``
        (whose error is O(h), so e(h) ≈ 2 (e(h) − e(h/2))); with ``pointwise=True`` the error
        is dominated by the quadrature, which grows as h shrinks, and the difference follows
        it (0.4-2.1 times the exact error's norm, docs/accuracy.md). Read it as the size of
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
        choice = self.pointwise_choice
        if choice is not None:  # the fitted rows: against the same rows twice as wide
            if self._half is None:
                self._half = pipeline.wider_rows(self.geometry, choice)
            r = np.where(choice.degree >= 2, 2.0 ** ((np.maximum(choice.degree, 2) - 1) / 2.0) - 1.0, np.inf)
            diff = np.abs(self @ f - np.asarray(self._half @ f))
            return diff / (r if diff.ndim == 1 else r[:, None])
        if self._half is None:
            w = self.widths
            half = replace(w, h=0.5 * w.h, h_vertex=None if w.h_vertex is None else 0.5 * w.h_vertex)
            opts = replace(self.options, correction=self.correction, check_psd=False, quadrature="vertex")
            self._half = pipeline.build(self.geometry, half, opts)
        half = self._half.assemble()
        half_f = half.matrix_free(f) if half.matrix_free is not None else half.L @ f
        diff = np.abs(self @ f - np.asarray(half_f))
        return 2.0 * diff if self.correction == "none" else diff

    # -- display ------------------------------------------------------------------------
    def _summary(self) -> list[tuple[str, str]]:
        geo = self.geometry
        spacing = "mean edge" if geo.faces is not None else "spacing"
        h_note = ""
        if self.h_auto:
            c = widths_mod.h_scale(self.geometry)
            scale = f"(2·{spacing})²" if self.options.plain else f"{c:g}·{spacing}²"
            h_note = f" (auto: {scale})"
        if self.adaptive:
            h_note = " (median of the per-vertex widths, adaptive)"
        elif self.h_vertex is not None:
            h_note += f"; narrower where the geometry bends, down to {self.h_vertex.min():.3g}"
        rows = [("vertices", f"{self.n_vertices:,}")]
        if geo.faces is not None:
            rows.append(("faces", f"{self.faces.n_faces:,}"))
        else:
            note = f" ({geo.notes})" if geo.notes else ""
            rows.append(("geometry", f"{geo.source}, k={geo.dim} in R^{geo.ambient_dim}{note}"))
        # read without building: a repr must not cost the pencil nor the fit
        pencil = self._built.held_pencil
        rows += [
            ("h", f"{self.h:.6g}{h_note}"),
            ("correction", (self.options.correction if pencil is None else pencil.correction)
             + self._pointwise_note()),
            ("tol", "0 (exact)" if self.exact else f"{self.tol:.3g}"),
            ("radius", "∞" if self.exact else f"{self.radius:.6g}"),
        ]
        if pencil is None:  # the builder the options name (laplacian's operator=), not built yet
            rows.append(("pencil", f"{_named(self.options)}, on first use"))
        elif pencil.quadrature == "fem":
            rows.append(("pencil", f"linear FEM on the cells (intrinsic Delaunay, {self.options.mass} mass)"))
        elif pencil.quadrature == "galerkin":
            narrow = pencil.narrowed
            rows.append(("pencil", f"Galerkin over the cells, h={pencil.quadrature_h:.4g}"
                         + (f", narrower on {narrow:.1%} of the area (feature size)" if narrow else "")))
        if self.matrix_free:
            rows.append(("storage", "matrix-free"))
        else:
            if pencil is not None:
                rows.append(("nnz", f"{self.nnz:,} ({self.nnz / self.n_vertices:.1f} per row)"))
            later = [what for what, pending in (("the pencil", pencil is None),
                                                ("the fitted rows", self._fit_pending())) if pending]
            rows.append(("memory", f"{fmt_bytes(self.nbytes)} ({self.dtype.name}"
                         + (f"; {' and '.join(later)} not yet)" if later else ")")))
        return rows

    def _fit_pending(self) -> bool:
        return self.options.pointwise == "fit" and self._built.rows_pending

    def _pointwise_note(self) -> str:
        if not self.pointwise:
            return ""
        if self._fit_pending():
            return " + fitted rows (fitted on first use)"
        rows = self._built.held_rows
        if rows is not None and rows.choice is not None:
            per_row = rows.L.nnz / max(self.n_vertices, 1)
            return f" + fitted rows ({per_row:.0f} entries per row; {rows.choice.summary()})"
        if self.options.pointwise_degree is not None:
            return f" + fitted rows of degree {self.options.pointwise_degree}"
        return " + point-wise moments"

    def __repr__(self) -> str:
        return "MeshLaplacian(" + ", ".join(f"{k}={v}" for k, v in self._summary()) + ")"

    def _repr_html_(self) -> str:
        body = "".join(f"<tr><th style='text-align:left'>{k}</th><td>{v}</td></tr>"
                       for k, v in self._summary())
        return f"<table><caption>MeshLaplacian (Belkin–Sun–Wang)</caption>{body}</table>"


def _named(opts: pipeline.Options) -> str:
    # the named builder an operator's options amount to
    if opts.quadrature in ("fem", "galerkin"):
        return opts.quadrature
    return "paper" if opts.plain else "kernel"
