"""The builders: from a mesh or a point cloud to a :class:`~meshlap.MeshLaplacian`.

``laplacian`` and ``mesh_laplacian`` take vertices and cells (faces of any size, edges of a
curve, tetrahedra); ``point_cloud_laplacian`` and ``point_cloud_matrices`` take points alone;
``pointwise_laplacian`` takes either. All of them run the same pipeline (:mod:`meshlap.pipeline`)
with the same default. ``laplacian`` and ``point_cloud_laplacian`` return the operator
(``op @ f`` ≈ Δf); ``mesh_laplacian`` and ``point_cloud_matrices`` return robust-laplacian's pair
(L positive semidefinite and symmetric, M the mass: for ``eigsh``); ``pointwise_laplacian``
returns the matrix that ``op @ f`` applies.
"""

from __future__ import annotations

import warnings
from typing import Any, Literal

import numpy as np
import scipy.sparse as sp

from .errors import MeshError
from .geometry import Geometry, point_cloud_geometry
from .operator import MeshLaplacian, as_geometry
from .policy import Operator, decide
from .progress import ProgressLike

__all__ = ["laplacian", "mesh_laplacian", "point_cloud_laplacian", "point_cloud_matrices",
           "pointwise_laplacian"]


def laplacian(
    V: Any,
    F: Any = None,
    h: float | None = None,
    *,
    operator: Operator = "auto",
    k: int | None = None,
    tol: float | None = None,
    matrix_free: bool = False,
    dtype: Literal["float64", "float32"] | type = np.float64,
    progress: ProgressLike = None,
    denoise: bool | None = None,
    mass: Literal["lumped", "blend"] = "lumped",
    **kernel_options: Any,
) -> MeshLaplacian:
    """The Laplacian of a mesh, curve, volume or point cloud, chosen by :mod:`meshlap.policy`.

    With cells, the symmetric pencil ``(op.S, op.M)`` (spectra, heat flow, smoothing) is linear
    FEM on them (intrinsic Delaunay, lumped mass: :mod:`meshlap.fem`), whose worst case is
    linear FEM on the same mesh; without cells it is the corrected heat kernel of Belkin, Sun
    and Wang (SoCG 2008, eq. 1). ``op @ f`` applies point-wise rows fitted to the points, exact
    for polynomials to degree 6 where the data are clean. ``op.decision`` says what was built
    and why.

    Parameters
    ----------
    V : (n, d) array_like, Geometry, or a mesh object
        Vertex positions (or a :class:`~meshlap.geometry.Geometry`, with ``F`` None), or,
        with ``F`` None, a ``trimesh.Trimesh``, ``pyvista.PolyData`` / ``UnstructuredGrid``,
        ``open3d`` mesh, ``meshio.Mesh`` or a file path (:func:`meshlap.inputs.as_geometry_input`);
        one that holds points alone is a point cloud, as :func:`point_cloud_laplacian` reads it.
    F : (m, c) array_like or list of sequences
        Faces of any size; (m, 2) edges of a curve; (m, 4) tetrahedra (told from quads by how
        they meet: :func:`meshlap.geometry.from_mesh`).
    h : float or (n,) array_like, optional
        A kernel width (exp(-d²/4h)): asks for the heat kernel at that width. Near the
        squared spacing the corrected kernel's narrow half h/2 can fall between the samples of
        an i.i.d. random sampling (``benchmarks/bench_narrow.py``).
    operator : {"auto", "fem", "kernel", "galerkin", "paper"}, default "auto"
        The symmetric pencil: "fem" linear FEM on the cells; "kernel" the corrected heat kernel
        on the vertices; "galerkin" the kernel integrated over the cells; "paper" the paper's
        operator, eq. (1), bit for bit (its ``op.L`` is eq. (1) too). "auto": :mod:`meshlap.policy`.
    k : {1, 2, 3}, optional
        Intrinsic dimension, inferred from ``F``: 1 for edges, 2 for faces, 3 for (m, 4) cells
        that meet across triangles as tetrahedra do. Pass it to read (m, 4) cells one way.
    tol : float, optional
        The kernel's tolerance: weights below it are dropped (default 1e-6, 1e-8 for "paper").
    matrix_free : bool, default False
        The kernel's pencil (one h, Euclidean distances), not stored: spectra and heat flow
        recompute it (a boundary's mirror images stored); ``op @ f`` applies the fitted rows,
        stored (the kernel's own with ``operator="paper"``). Meant for large clouds: on a mesh
        the default pencil, linear FEM, stores no kernel (7 entries a row on triangles) and is
        the more accurate.
    dtype : {"float64", "float32"}, default float64
        Value type of the stored matrices.
    progress : bool or callable, optional
        ``True`` draws a bar on stderr; a callable gets ``(fraction, stage)``.
    denoise : bool, optional
        "fem" on a surface: FEM on the positions after a bi-Laplacian step of time (2σ̂)², σ̂
        the normal noise measured on the vertices (``op.decision.measured``; :mod:`meshlap.denoise`):
        its masses less the area the noise it left adds: on five real meshes with 0.3 mean edges
        of normal noise, 1.2-11% on eigenvalues 1-9 against the clean mesh (libigl's cotangent
        Laplacian 16-19%). Default: where that noise adds area and dominates what smoothing takes
        out across at least half of the edges (:func:`~meshlap.denoise.noise_extent`;
        ``op.decision.denoise``); ``False`` keeps the mesh as given.
    mass : {"lumped", "blend"}, default "lumped"
        "fem": the mass of the pencil, lumped (on triangles the mixed Voronoi areas, as libigl's).
        "blend", ½(consistent + lumped), puts every eigenvalue
        between the lumped and the consistent FEM's: 4× more accurate on irregular fine meshes
        (a random sphere), 1.2-2× less on coarse real ones (:mod:`meshlap.fem`). A named mass
        keeps :func:`~meshlap.spectral.eigs` on the pencil (``op.elements``: "linear").
    **kernel_options
        Options of the kernel builder (:class:`MeshLaplacian`: ``correction``, ``quadrature``,
        ``pointwise``, ``neumann``, ...); giving one asks for the kernel.

    Returns
    -------
    MeshLaplacian
        ``op.S``, ``op.M`` (symmetric pencil), ``op @ f`` / ``op.L`` (point-wise rows),
        ``op.decision``.

    Examples
    --------
    >>> import meshlap
    >>> V, F = meshlap.shapes.sphere(2000, seed=0)
    >>> op = meshlap.laplacian(V, F)
    >>> op.decision.operator
    'fem'
    >>> lam, _ = meshlap.spectral.eigs(op, 4)
    >>> (lam.round(2) + 0.0).tolist()          # 0, then l(l+1) = 2 three times
    [0.0, 2.0, 2.0, 2.0]
    """
    if F is None and not isinstance(V, (Geometry, np.ndarray, list)):  # trimesh, pyvista, meshio, open3d
        V, F, k = _held_input(V, k)
    geo = as_geometry(V, F, k)
    chosen = decide(geo, operator, h, {**kernel_options, "matrix_free": matrix_free or None,
                                       "denoise": denoise, "mass": None if mass == "lumped" else mass})
    named = {"fem": {"quadrature": "fem"}, "galerkin": {"quadrature": "galerkin"},
             "paper": {"correction": "none"}, "kernel": {}}[chosen.operator]
    if chosen.rows == "pencil" and not {"pointwise", "pointwise_degree"} & set(kernel_options) and \
            chosen.operator != "paper":
        named["pointwise"] = False  # too few points to fit rows on: op @ f applies the pencil
    op = MeshLaplacian(geo, None, h=h, tol=tol, matrix_free=matrix_free, dtype=dtype, progress=progress,
                       denoise=chosen.denoise, mass=mass, **{**kernel_options, **named})
    op._decision = chosen
    return op


def _held_input(obj: Any, k: int | None) -> tuple[Any, Any, int | None]:
    # (V, F, k) of a file or an object; one of points alone is a cloud's Geometry, as the command
    # line reads it
    from .inputs import as_geometry_input

    V, F, k_cells = as_geometry_input(obj)
    k = k if k is not None else k_cells
    if F is None:
        return point_cloud_geometry(V, 2 if k is None else k), None, None
    return V, F, k


def mesh_laplacian(V: Any, F: Any = None, h: float | None = None, tol: float | None = None, *,
                   form: Literal["weak", "pointwise"] = "weak",
                   **kwargs: Any) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """The pair ``(L, M)`` in robust-laplacian's convention: for ``eigsh`` and heat flow.

    ``L = -op.S`` is the symmetric positive semidefinite weak stiffness and ``M = op.M`` the
    diagonal mass of ``op = laplacian(V, F, h, tol=tol)``, so robust-laplacian's idiom
    ``eigsh(L, k, M, sigma=1e-8)`` gives the spectrum of −Δ (0, then l(l+1) on the unit
    sphere) and ``(M + t L) u = M u0`` is an implicit heat step. ``L`` is not Δ: the accurate
    Δf at every point is ``laplacian(V, F) @ f`` (or :func:`pointwise_laplacian`).

    Parameters
    ----------
    V, F, h, tol, **kwargs
        As for :func:`laplacian`.
    form : {"weak", "pointwise"}, default "weak"
        ``"pointwise"`` returns what this function returned in 0.1.0, ``(op.L, op.M)`` with
        ``op.L @ f`` ≈ +Δf (not symmetric: not for ``eigsh``); deprecated, it goes in the next
        release: use :func:`pointwise_laplacian` or ``laplacian(V, F).L``.

    Returns
    -------
    L : (n, n) csr_matrix
        Symmetric positive semidefinite; ``L @ 1 = 0``.
    M : (n, n) csr_matrix
        Diagonal, positive: the vertex areas.

    Examples
    --------
    >>> import meshlap, numpy as np, scipy.sparse.linalg as sla
    >>> V, F = meshlap.shapes.sphere(500, seed=0)
    >>> L, M = meshlap.mesh_laplacian(V, F)
    >>> lam = sla.eigsh(L, 4, M, sigma=1e-8)[0]          # robust-laplacian's idiom
    >>> print(np.abs(lam).round(1))                      # 0, then l(l+1) = 2 three times
    [0. 2. 2. 2.]
    """
    return _pair(laplacian(V, F, h, tol=tol, **kwargs), form, "mesh_laplacian")


def _pair(op: MeshLaplacian, form: str, name: str) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    if form == "weak":
        return sp.csr_matrix(-op.S), op.M
    if form == "pointwise":
        warnings.warn(f"{name}(..., form='pointwise') is deprecated and goes in the next release: it returns "
                      "(op.L, op.M), op.L @ f ≈ +Δf, not symmetric. Use meshlap.pointwise_laplacian for "
                      f"Δf, and {name}'s default pair (L = -op.S, M) for eigsh and heat flow",
                      DeprecationWarning, stacklevel=3)
        return op.L, op.M
    raise MeshError(f"form must be 'weak' or 'pointwise'; got {form!r}")


def pointwise_laplacian(V: Any, F: Any = None, h: float | None = None, tol: float | None = None,
                        **kwargs: Any) -> sp.csr_matrix:
    """The point-wise Laplacian: ``Lp @ f`` ≈ +Δf at every vertex (or point).

    The matrix ``op.L`` that ``op @ f`` applies (the fitted rows by default), for meshes as
    :func:`laplacian` builds them and, with ``F`` None and an array of points, for point clouds
    as :func:`point_cloud_laplacian` does. Its rows are not symmetric in any mass: for
    ``eigsh``, heat flow and smoothing take the pair of :func:`mesh_laplacian` (or
    :func:`point_cloud_matrices`), or :func:`meshlap.spectral.eigs` on the operator.

    Parameters
    ----------
    V, F, h, tol, **kwargs
        As for :func:`laplacian`; ``F`` None with an (n, d) array: a point cloud (``k`` and the
        cloud's options as for :func:`point_cloud_laplacian`).

    Returns
    -------
    (n, n) csr_matrix
        ≈ +Δ (the sign of libigl's ``cotmatrix``, without its mass): ``Lp @ x`` ≈ −2x on the
        unit sphere.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(1000, seed=0)
    >>> Lp = meshlap.pointwise_laplacian(V, F)
    >>> x = V[:, 0]
    >>> bool(np.linalg.norm(Lp @ x + 2 * x) < 1e-3 * np.linalg.norm(2 * x))   # Δx = -2x
    True
    """
    if F is None and isinstance(V, (np.ndarray, list)):
        return point_cloud_laplacian(V, h, tol=tol, **kwargs).L
    return laplacian(V, F, h, tol=tol, **kwargs).L


def point_cloud_laplacian(P: Any, h: float | None = None, k: int = 2, tol: float | None = None, *,
                          denoise: bool | None = None, neighbors: int | None = None, merge_tol: float = 1e-6,
                          outlier_ratio: float = 10.0, **kwargs: Any) -> MeshLaplacian:
    """The Laplacian of a point cloud, chosen as for a mesh by :mod:`meshlap.policy`.

    A surface's cloud gets linear FEM on every point's local Delaunay star (a third each) as its
    symmetric pencil, a curve's on every point's segments to its nearest neighbours on either
    side (a half each); a noisy one (or a volume's) the heat-kernel Laplacian of Belkin, Sun and
    Wang (SODA 2009; ``operator="kernel"`` asks for it):

    L f(w) = Σ_p m_p exp(-|p-w|²/4h) (f(p) - f(w)) / (h (4πh)^{k/2}), with the masses m_p of
    :func:`~meshlap.geometry.point_masses`, corrected as for a mesh (the Richardson kernel,
    mirror images at the boundary, point-wise rows; ``correction="none"`` for the plain
    one). The result is a :class:`~meshlap.MeshLaplacian` (``L``, ``M``, ``S``, ``mass``,
    ``h``, ``op @ f``, ``as_linear_operator``), so :mod:`meshlap.spectral`,
    :mod:`meshlap.heat` and :mod:`meshlap.curvature` take it as they take a mesh's.

    Parameters
    ----------
    P : (n, d) array_like, or a point cloud object
        Points in R^d, d ≥ k (d > 3 uses a k-d tree instead of the cell grid); or an
        ``open3d.geometry.PointCloud``, ``pyvista.PolyData``, ``trimesh.PointCloud`` or a
        file path (:func:`meshlap.inputs.as_geometry_input`; a mesh gives its vertices).
    h : float, optional
        Kernel width. Default 4a², a the neighbour distance of a regular lattice with the
        cloud's mean mass ((2a)² with ``correction="none"``, as on a mesh); ``op.h`` and
        ``op.h_auto`` report it.
    k : int, default 2
        Intrinsic dimension: 1 curve, 2 surface, 3 volume or 3-manifold.
    tol : float, optional
        Kernel tolerance, as for meshes: default 1e-6 for the corrected operators, 1e-8 for
        the paper's.
    denoise : bool, optional
        Project the points onto their local tangent planes first (for noisy scans; ``op.V``
        then holds the moved points). Default: when the cloud's normal noise exceeds about
        14% of its spacing and cubic fits do not explain it
        (:func:`~meshlap.geometry.noise.noise_reading`), noted in the repr. On 16,000
        unit-sphere points with 1% radial noise the default's first 9 eigenvalues are 0.29%
        off with it, the kernel's 5.6% without (the paper's operator: 2.0%).
    neighbors, merge_tol, outlier_ratio
        See :func:`~meshlap.geometry.point_masses`.
    **kwargs
        ``operator`` and the other options of :func:`laplacian`; ``correction``, ``exact``,
        ``max_memory`` and the accuracy options of the kernel, as for :class:`~meshlap.MeshLaplacian`.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> P = np.random.default_rng(0).normal(size=(3000, 3))
    >>> P /= np.linalg.norm(P, axis=1, keepdims=True)
    >>> op = meshlap.point_cloud_laplacian(P, h=0.02)
    >>> err = np.linalg.norm(op @ P[:, 0] + 2 * P[:, 0]) / np.linalg.norm(2 * P[:, 0])
    >>> bool(err < 0.05)                             # Δx = -2x on the unit sphere
    True
    """
    if not isinstance(P, (np.ndarray, list)):  # open3d, pyvista, trimesh point clouds (or meshes)
        from .inputs import as_geometry_input

        P = as_geometry_input(P)[0]
    geo = point_cloud_geometry(P, k, denoise=denoise, neighbors=neighbors, merge_tol=merge_tol,
                               outlier_ratio=outlier_ratio)
    return laplacian(geo, None, h, tol=tol, **kwargs)


def point_cloud_matrices(P: Any, h: float | None = None, k: int = 2, *,
                         form: Literal["weak", "pointwise"] = "weak", **kwargs: Any
                         ) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """The pair ``(L, M)`` of a point cloud in robust-laplacian's convention.

    What ``robust_laplacian.point_cloud_laplacian(P)`` returns, in meaning: ``L = -op.S``
    symmetric positive semidefinite and ``M = op.M`` the diagonal point masses of
    ``op = point_cloud_laplacian(P, h, k)``, for ``eigsh(L, k, M, sigma=1e-8)`` and heat flow.
    meshlap's own :func:`point_cloud_laplacian` returns the operator (``op @ f`` ≈ Δf).

    Parameters
    ----------
    P, h, k, **kwargs
        As for :func:`point_cloud_laplacian`.
    form : {"weak", "pointwise"}, default "weak"
        ``"pointwise"``, deprecated, returns 0.1.0's ``(op.L, op.M)``: use
        :func:`pointwise_laplacian` (``pointwise_laplacian(P)``) for Δf.

    Examples
    --------
    >>> import meshlap
    >>> L, M = meshlap.point_cloud_matrices(meshlap.samples.sphere_points(1000), h=0.05)
    >>> L.shape, bool(abs(M.diagonal().sum() - 4 * 3.1416) < 0.2)     # the sphere's area
    ((1000, 1000), True)
    >>> bool(abs(L - L.T).max() < 1e-12 and abs(L.sum(axis=1)).max() < 1e-9)   # symmetric, L @ 1 = 0
    True
    """
    return _pair(point_cloud_laplacian(P, h=h, k=k, **kwargs), form, "point_cloud_matrices")
