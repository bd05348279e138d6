"""Boundary-value problems with a Laplacian: Poisson with Dirichlet and Neumann data, and
harmonic interpolation from values at a few vertices.

Every function takes the operator's symmetric pencil ``(S, M)`` (``S ≈ M Δ``, negative
semidefinite), so it works on every input meshlap builds: surface meshes, point clouds in
R^d, curves and tetrahedral meshes, and on :mod:`meshlap.baselines`' operators.

The problem Δφ = f with φ = g on the Dirichlet vertices D and ∂φ/∂n = q on the Neumann
vertices is solved in its weak form on the other vertices,

    (-S) φ = -M f + B q,    φ_D = g,

with B the boundary measure of each vertex (half the adjacent boundary edges on a surface,
a third of the adjacent hull triangles on a tetrahedral mesh, 1 at a curve's end; on a surface's
point cloud half the edges of each point's star where the star soup ends,
``geometry.boundary_share``; on a volume cloud m_i^(2/3) at the points it flags, an
estimate). The rest of the boundary is insulated (∂φ/∂n = 0). A connected part of the
geometry without Dirichlet vertices fixes φ only up to a constant: its data are made
compatible (a warning says when they were not) and φ has zero mean there.

:class:`PoissonSolver` prepares the matrix once for a set of Dirichlet vertices and solves
for any number of right-hand sides and Dirichlet values: a sparse LU (scipy's SuperLU,
symmetric mode; no SuiteSparse) when S has at most 40 entries per row (linear FEM, cotangent,
curves), a block conjugate gradient otherwise (the heat-kernel operator's hundreds of
entries per row fill an LU in), preconditioned as LOBPCG is in :mod:`meshlap.spectral`: the
P1 stiffness of the same geometry plus half the inverse diagonal. A sparse volume whose
factorization counts more than 10⁹ multiply-adds (a bulky one's fills as n^(4/3)) is solved by
conjugate gradient preconditioned by one multigrid V-cycle of the matrix itself
(:mod:`meshlap._multigrid`): 0.41 s instead of 110 s on a 68,921-vertex tetrahedral cube. Where
the V-cycle stalls (a graded volume: 254 iterations, 6.7 s on notch_stress refined to 96,029
vertices, against 1.3 s factored) the solver factors after all, for that solve and the next
ones. On such a volume the heat-kernel operator's preconditioner inverts its P1 stiffness by the
same V-cycle instead of factoring it.
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np
import scipy.sparse as sp

from . import _ldl, _lobpcg, _parts
from ._cg import block_pcg
from ._jit import one_blas_thread as _one_blas_thread
from ._ldl import factor as _factor
from ._multigrid import Multigrid, Stall, replaces_factor
from .errors import MeshError, MeshWarning, user_stacklevel
from .geometry import Geometry, simplex_volumes
from .geometry.validation import check_function
from .gradients import gradient_operator
from .spectral import _SPARSE_ROW_MAX, _check_mass, _extend

__all__ = ["PoissonSolver", "boundary_measure", "harmonic", "poisson"]

Indexed = dict[int, Any] | tuple[Any, Any] | None


def _indices(idx: Any, n: int, what: str) -> np.ndarray:
    a = np.asarray(idx)
    if a.size == 0:
        return np.zeros(0, dtype=np.int64)
    if a.dtype.kind not in "iu" or a.ndim > 1:
        raise MeshError(f"{what} vertices must be integer indices; got {idx!r}")
    a = a.astype(np.int64).ravel()
    if len(a) and (a.min() < -n or a.max() >= n):
        raise MeshError(f"{what} vertex indices must lie in [0, {n - 1}] (or [-{n}, -1], counted from the "
                        f"end as numpy's); got {a.min()}..{a.max()}")
    a = np.where(a < 0, a + n, a)
    if len(np.unique(a)) != len(a):
        raise MeshError(f"{what} vertices repeat an index")
    return a


def _indexed(data: Indexed, n: int, what: str) -> tuple[np.ndarray, np.ndarray]:
    """``{idx: value}`` or ``(idx, values)`` as (indices, values (len, ...))."""
    if data is None:
        return np.zeros(0, dtype=np.int64), np.zeros(0)
    if isinstance(data, dict):
        idx, vals = list(data.keys()), list(data.values())
    elif isinstance(data, tuple) and len(data) == 2:
        idx, vals = data
    else:
        raise MeshError(f"{what} must be a dict {{vertex: value}} or a pair (vertices, values); got "
                        f"{type(data).__name__}")
    idx = _indices(idx, n, what)
    vals = np.asarray(vals, dtype=np.float64)
    if vals.ndim == 0:
        vals = np.full(len(idx), float(vals))
    if vals.shape[0] != len(idx) or vals.ndim > 2 or not np.isfinite(vals).all():
        raise MeshError(f"{what} needs one finite value (or row of values) per vertex: {len(idx)} vertices, "
                        f"values of shape {vals.shape}")
    return idx, vals


def boundary_measure(geometry: Any) -> np.ndarray:
    """Each vertex's share of the boundary's (k-1)-measure: the weights of Neumann data (an
    operator's: at the positions its pencil was built on, ``op.pencil_points``).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    >>> boundary_measure(meshlap.geometry.surface(V, [[0, 1, 2], [0, 2, 3]])).tolist()
    [1.0, 1.0, 1.0, 1.0]
    >>> P = meshlap.shapes.disc(1500)[0]       # the unit disc's vertices, as a cloud: its rim, 2π
    >>> round(float(boundary_measure(meshlap.point_cloud_laplacian(P)).sum()), 3)
    6.283
    """
    geo = getattr(geometry, "geometry", geometry)
    if not isinstance(geo, Geometry):
        raise MeshError("Neumann data need the geometry's boundary: pass an operator that carries it "
                        "(op.geometry) or a Geometry")
    P, n = getattr(geometry, "pencil_points", geo.points), geo.n_points
    if geo.tiled:
        cells = geo.faces.triangles() if geo.faces is not None else geo.cells
        c = cells.shape[1]
        rep = geo.copies()  # a seam between copies is no boundary
        if c == 2:  # a curve: its ends
            ends = np.bincount(cells.ravel(), minlength=n) == 1
            return ends if rep is None else ends & (np.bincount(rep[cells].ravel(), minlength=n) == 1)[rep]
        sides = np.concatenate([np.delete(cells, j, axis=1) for j in range(c)])
        key = np.sort(sides if rep is None else rep[sides], axis=1)
        _, inv, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        once = sides[(counts[inv.ravel()] == 1) & np.all(key[:, 1:] != key[:, :-1], axis=1)]
        if not len(once):
            return np.zeros(n)
        share = np.repeat(simplex_volumes(P, once) / (c - 1), c - 1)
        return np.bincount(once.ravel(), weights=share, minlength=n)
    if geo.boundary_share is not None:
        return np.array(geo.boundary_share)
    if geo.boundary is None:
        return np.zeros(n)
    k = geo.dim
    if k >= 3 and geo.boundary.any():
        warnings.warn("a volume point cloud's boundary measure is an estimate, m^(2/3) at the points whose "
                      "star is open, and falls far short (a 13×13×13 grid of the unit cube: 0.27 for its "
                      "area 6); for Neumann data give the tetrahedra (meshlap.laplacian(V, T, k=3))",
                      MeshWarning, stacklevel=user_stacklevel())
    return np.where(geo.boundary, np.asarray(geo.mass) ** ((k - 1) / k), 0.0)


def _kernel_boundary(op: Any, idx: np.ndarray) -> str | None:
    """``op.decision.operator`` where it is a heat kernel ("kernel" or "paper") and ``idx`` holds
    a boundary vertex, else None."""
    operator = getattr(getattr(op, "decision", None), "operator", None)
    boundary = getattr(getattr(op, "geometry", None), "boundary", None)
    if operator in ("kernel", "paper") and boundary is not None and len(idx) and boundary[idx].any():
        return operator
    return None


def _warn_kernel_boundary(op: Any, idx: np.ndarray) -> None:
    """Warn where data on the boundary meet a heat-kernel pencil: its rows reach past the
    boundary vertices, so under boundary data it has a boundary layer that linear FEM has not
    (the unit disc, 2,000 vertices, x² − y² from its boundary values: 0.19 off with the corrected
    kernel, 0.56 with the paper's, 2e-4 with FEM)."""
    operator = _kernel_boundary(op, idx)
    if operator is not None:
        warnings.warn(f"boundary data on a heat-kernel pencil (operator={operator!r}) leave a boundary "
                      "layer (the unit disc from its boundary values: 0.19 off with the kernel, 2e-4 with "
                      "linear FEM); for boundary problems build the operator with operator='fem'",
                      MeshWarning, stacklevel=user_stacklevel())


class _FreeRows:
    """``-S`` on the free vertices as CG reads it, a product and a diagonal, without a copy of
    S: a heat kernel's S on a volume holds thousands of entries a row, and slicing and
    symmetrizing it took longer than the solve (cube-tet's 9,261 vertices as a cloud: 7.8 s
    against 2.8 s; ``benchmarks/bench_pointcloud.py --volume``)."""

    def __init__(self, S: sp.csr_matrix, free: np.ndarray) -> None:
        self.S, self.free = S, None if len(free) == S.shape[0] else free

    def __matmul__(self, X: np.ndarray) -> np.ndarray:
        if self.free is None:
            return -(self.S @ X)
        full = np.zeros((self.S.shape[0],) + X.shape[1:])
        full[self.free] = X
        return -(self.S @ full)[self.free]

    def diagonal(self) -> np.ndarray:
        d = -self.S.diagonal()
        return d if self.free is None else d[self.free]


class PoissonSolver:
    r"""Solve ``(-S) φ = b`` with φ given on a fixed set of Dirichlet vertices, prepared once.

    Parameters
    ----------
    op : MeshLaplacian or SparseLaplacian
        Any operator with the symmetric pencil ``.S``, ``.mass`` (and ``.geometry`` for the
        iterative solver's preconditioner).
    fixed : array_like of int, optional
        The Dirichlet vertices (none: the Neumann problem, φ up to a constant per connected
        part, returned with zero mean there).
    solver : {"auto", "direct", "cg"}
        ``"direct"``: sparse LU; ``"cg"``: block preconditioned conjugate gradient;
        ``"auto"``: direct up to 40 entries per row of S, except on a volume whose factorization
        counts more than 10⁹ multiply-adds: CG with multigrid, which factors after all where the
        V-cycle stalls (:class:`meshlap._multigrid.Stall`).
    rtol : float, default 1e-10
        Relative residual at which CG stops.

    Attributes
    ----------
    iterations : list of int
        CG iterations of each solve.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(800, seed=0)
    >>> op = meshlap.laplacian(V, F)                   # the FEM pencil: a sparse LDLᵀ
    >>> solver = PoissonSolver(op)
    >>> phi = solver.solve(-op.S @ V[:, 2])            # recovers z up to its mean (0)
    >>> bool(np.allclose(phi, V[:, 2] - V[:, 2] @ op.mass / op.mass.sum(), atol=1e-8))
    True
    """

    def __init__(self, op: Any, fixed: Any = None, *, solver: str = "auto", rtol: float = 1e-10) -> None:
        if solver not in ("auto", "direct", "cg"):
            raise MeshError(f"solver must be 'auto', 'direct' or 'cg'; got {solver!r}")
        self.op, self.rtol = op, float(rtol)
        mass, P = _check_mass(op)
        n = self.n = op.n_vertices
        self.mass = mass
        self.fixed = _indices([] if fixed is None else fixed, n, "fixed")
        _warn_kernel_boundary(op, self.fixed)
        is_fixed = np.zeros(n, dtype=bool)
        is_fixed[self.fixed] = True
        self.free = P[~is_fixed[P]]
        if not len(self.free):
            raise MeshError("every vertex with mass is a Dirichlet vertex: nothing is left to solve for")
        S = sp.csr_matrix(op.S, dtype=np.float64)
        sparse = S.nnz <= _SPARSE_ROW_MAX * n
        multigrid = sparse and replaces_factor(op)  # a large volume's: not factored
        chosen = solver == "auto"
        if chosen:
            solver = "direct" if sparse and not multigrid else "cg"
        if sparse or solver == "direct":
            S = 0.5 * (S + S.T)  # a factorization reads one triangle; multigrid needs the matrix
        self._S = S
        # connected parts of the geometry (through S) and those without a Dirichlet vertex
        ncomp, label = _parts.part_labels(S if len(P) == n else S[P][:, P])
        lab = np.full(n, -1)
        lab[P] = label
        self.part_label = lab  # each vertex's connected part through S (-1: no mass)
        anchored = np.zeros(ncomp, dtype=bool)
        anchored[lab[self.fixed][lab[self.fixed] >= 0]] = True
        # each floating part's free vertices, and the vertices without mass, found once for every solve
        self._parts: list[Any] = [np.flatnonzero(lab[self.free] == c) for c in np.flatnonzero(~anchored)]
        if len(self._parts) == 1 and len(self._parts[0]) == len(self.free):
            self._parts = [slice(None)]  # one part, all free: no copies
        self._missing = np.setdiff1d(np.flatnonzero(mass == 0), self.fixed)
        A: Any = _FreeRows(S, self.free)
        if sparse or solver == "direct":
            A = sp.csr_matrix(-S if len(self.free) == n else -S[self.free][:, self.free])
        self.solver = solver
        self.iterations: list[int] = []
        self._stall = Stall(lambda: _ldl.least_work(A)) if multigrid and chosen else None
        with _one_blas_thread():
            if solver == "direct":
                self._factor(A)
            else:
                self._A = A
                self._precond = Multigrid(A).solve if multigrid else self._preconditioner(op, A)

    def _factor(self, A: sp.csr_matrix) -> None:
        # one vertex of each floating part pinned at 0: A restricted to the others is SPD
        first = np.array([np.arange(len(self.free))[part][0] for part in self._parts], dtype=np.int64)
        self._keep = np.setdiff1d(np.arange(len(self.free)), first)
        self._lu = _factor(A[self._keep][:, self._keep], _ldl.supernodal(self.op))
        self.solver = "direct"

    def _preconditioner(self, op: Any, A: sp.csr_matrix) -> _lobpcg.CotPreconditioner:
        m = self.mass[self.free]
        K = None
        geo = getattr(op, "geometry", None)
        if geo is not None:
            K = sp.csc_matrix(gradient_operator(op).stiffness()[self.free][:, self.free])
        sigma = 1e-3 * 4.0 * math.pi / float(m.sum())
        inverse = Multigrid if replaces_factor(op, K) else None  # a large volume's K: not factored
        return _lobpcg.CotPreconditioner(K, m, np.asarray(A.diagonal()), sigma, inverse)

    def solve(self, b: Any, values: Any = None, *, compatible: bool = False) -> np.ndarray:
        """φ with ``(-S φ)_i = b_i`` at the free vertices and φ = ``values`` at the fixed ones.

        Parameters
        ----------
        b : (n,) or (n, s) array_like
            Integrated right-hand side (its entries at fixed vertices are ignored).
        values : (len(fixed),) or (len(fixed), s) array_like, optional
            Dirichlet values (default 0).
        compatible : bool, default False
            ``b`` is a finite float64 array known to sum to zero over every part without
            Dirichlet vertices (a divergence ``-Gᵀ W X``, as the heat method's): its check and
            projection are skipped.

        Returns
        -------
        (n,) or (n, s) ndarray
        """
        b = np.asarray(b) if compatible else check_function(b, self.n, "b")
        B = b.reshape(self.n, -1)
        s = B.shape[1]
        phi = np.zeros((self.n, s))
        if len(self.fixed):
            g = np.zeros((len(self.fixed), s)) if values is None else np.asarray(values, dtype=np.float64)
            if g.shape[0] != len(self.fixed) or not np.isfinite(g).all():
                raise MeshError(f"values must hold one finite value per fixed vertex ({len(self.fixed)}); "
                                f"got shape {g.shape}")
            phi[self.fixed] = g.reshape(len(self.fixed), -1)
            rhs = B[self.free] + (self._S @ phi)[self.free]
        else:
            rhs = B[self.free]
        if not compatible:
            self._compatible(rhs)
        if self.solver == "cg":
            with _one_blas_thread():
                x, it, converged = block_pcg(lambda X: self._A @ X, self._precond, rhs, self.rtol, 2000,
                                             give_up=self._stall)
                self.iterations.append(it)
                if self._stall is not None and self._stall.fired:
                    self._factor(self._A)  # this solve and the next ones
                elif not converged:
                    warnings.warn(f"conjugate gradient did not reach rtol={self.rtol:g} in 2000 iterations",
                                  RuntimeWarning, stacklevel=user_stacklevel())
        if self.solver == "direct":
            x = np.zeros_like(rhs)
            x[self._keep] = self._lu.solve(np.asfortranarray(rhs[self._keep]))
        m = self.mass[self.free]
        for sel in self._parts:  # zero mean on each part without Dirichlet data
            x[sel] -= (m[sel] @ x[sel]) / m[sel].sum()
        phi[self.free] = x
        if len(self._missing):  # vertices without mass: the kernel-weighted mean of their row
            known = np.flatnonzero(self.mass > 0)
            phi[self._missing] = _extend(self.op, known, phi[known])[self._missing]
        return phi.reshape(b.shape)

    def _compatible(self, rhs: np.ndarray) -> None:
        """Project the data of parts without Dirichlet vertices onto the range of S (in place)."""
        for sel in self._parts:
            total = rhs[sel].sum(axis=0)
            scale = np.abs(rhs[sel]).sum(axis=0)
            if np.any(np.abs(total) > 1e-8 * np.maximum(scale, 1e-300)):
                warnings.warn("the data of a part without Dirichlet vertices do not integrate to zero "
                              "(∫f ≠ ∮q): solving for their projection", MeshWarning,
                              stacklevel=user_stacklevel())
            rhs[sel] -= total / len(rhs[sel])


def poisson(op: Any, f: Any = 0.0, *, dirichlet: Indexed = None, neumann: Indexed = None,
            solver: str = "auto") -> np.ndarray:
    r"""Solve Δφ = f with φ = g on Dirichlet vertices and ∂φ/∂n = q on Neumann vertices.

    Parameters
    ----------
    op : MeshLaplacian or SparseLaplacian
        The operator (its symmetric pencil S ≈ MΔ, M).
    f : float or (n,) or (n, s) array_like, default 0
        The source term, one value per vertex (pointwise, not integrated).
    dirichlet : dict or (indices, values), optional
        ``{vertex: value}`` or ``(vertices, values)``; values (len,) or (len, s).
    neumann : dict or (indices, values), optional
        Outward normal derivative q at boundary vertices (weighted by
        :func:`boundary_measure`); the rest of the boundary has q = 0.
    solver : {"auto", "direct", "cg"}
        See :class:`PoissonSolver`.

    Returns
    -------
    (n,) or (n, s) ndarray

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> from meshlap.baselines import cotangent
    >>> V, F = meshlap.shapes.disc(1500)
    >>> edge = np.flatnonzero(boundary_measure(meshlap.geometry.surface(V, F)))
    >>> x, y = V[:, 0], V[:, 1]
    >>> phi = poisson(cotangent(V, F), 4.0, dirichlet=(edge, (x**2 + y**2)[edge]))
    >>> bool(abs(phi - (x**2 + y**2)).max() < 2e-3)
    True
    """
    n = op.n_vertices
    fixed, g = _indexed(dirichlet, n, "dirichlet")
    nidx, q = _indexed(neumann, n, "neumann")
    if _kernel_boundary(op, fixed) is None:  # Dirichlet data on the boundary: the solver says it
        _warn_kernel_boundary(op, nidx)
    f_arr = np.asarray(f, dtype=np.float64)
    width = [a.shape[1] for a in (f_arr, g, q) if a.ndim == 2]
    s = width[0] if width else None
    if f_arr.ndim == 0:
        f_arr = np.full((n,) if s is None else (n, s), float(f_arr))
    f_arr = check_function(f_arr, n, "f")
    b = -np.asarray(op.mass)[:, None] * f_arr.reshape(n, -1)
    if len(nidx):
        w = boundary_measure(op)
        b[nidx] += w[nidx, None] * q.reshape(len(nidx), -1)
    if s is not None and b.shape[1] == 1:
        b = np.repeat(b, s, axis=1)
    phi = PoissonSolver(op, fixed, solver=solver).solve(b, g.reshape(len(fixed), -1) if len(fixed) else None)
    return phi[:, 0] if s is None else phi


def harmonic(op: Any, idx: Any, values: Any, *, solver: str = "auto") -> np.ndarray:
    """The harmonic function (Δφ = 0) taking ``values`` at the vertices ``idx``.

    Insulated (∂φ/∂n = 0) on the rest of the boundary; values (len(idx),) or (len(idx), s).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> from meshlap.baselines import cotangent
    >>> V, F = meshlap.shapes.plane(800, kind="stratified")
    >>> edge = np.flatnonzero(boundary_measure(meshlap.geometry.surface(V, F)))
    >>> u = harmonic(cotangent(V, F), edge, V[edge, 0] - 2 * V[edge, 1])   # linear: exact
    >>> bool(np.allclose(u, V[:, 0] - 2 * V[:, 1]))
    True
    """
    if np.asarray(idx).size == 0:  # insulated everywhere: every constant is harmonic
        raise MeshError("harmonic needs at least one vertex with a value; got none")
    return poisson(op, 0.0, dirichlet=(idx, values), solver=solver)
