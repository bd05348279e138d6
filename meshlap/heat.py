"""Heat flow on a mesh: u(t) = exp(tL) f, and implicit (backward Euler) steps.

Every function takes any operator with the common surface ``.L, .M, .S, .mass, .n_vertices``
and ``op @ f`` (the Belkin–Sun–Wang :class:`~meshlap.MeshLaplacian` or a
:class:`~meshlap.baselines.SparseLaplacian`).

Implicit steps solve ``(M - τS) u = M f`` on the vertices with mass. For the cotangent
Laplacian a sparse LU does it; for the heat-kernel operator, whose rows hold hundreds of
entries, the LU fills in, so a preconditioned conjugate gradient is used. Its preconditioner
models the heat-kernel symbol g(x) ≈ 2x / (2 + h x) in terms of the cotangent eigenvalue x
(see :mod:`meshlap.spectral`), which gives

    (M + τ A)⁻¹ ≈ a M⁻¹ + b (2M + c K)⁻¹,   c = h + 2τ,  a = h / c,  b = 4τ / c,

with K the cotangent stiffness of the same mesh (one sparse factorization per τ). A sparse
volume too costly to factor (:data:`meshlap._multigrid.MAX_FACTOR_WORK`) takes conjugate gradient
preconditioned by one multigrid V-cycle of ``M - τS`` itself (:mod:`meshlap._multigrid`): a step
on a 68,921-vertex tetrahedral cube in 0.47 s instead of 42 s.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import expm_multiply
from scipy.special import ive

from . import _ldl
from ._cg import block_pcg
from ._jit import one_blas_thread as _one_blas_thread
from ._ldl import factor as _factor
from ._multigrid import Multigrid, Stall, replaces_factor
from .errors import MeshError
from .geometry.validation import check_function, check_int
from .spectral import (
    _SPARSE_ROW_MAX,
    _check_mass,
    _cot_stiffness,
    _mesh_of,
    _restricted_S,
    apply_block,
    eigs,
    symmetric_L,
)

__all__ = ["heat_flow", "ImplicitHeat", "implicit_heat"]

# The trapezoid rule with this many nodes on Talbot's cotangent contour (Trefethen, Weideman and
# Schmelzer, BIT 46, 2006): exp(x) within 2.3e-14 for every x ≤ 0 (checked at 2,000 points up to
# -1e8), from half as many complex solves (the nodes come in conjugate pairs)
_CONTOUR_NODES = 24
# "auto" leaves the Chebyshev series for the contour beyond this many products with L: the 12
# factorizations cost what about 2,300 products do on a 16,000-vertex sphere (docs/spectral.md)
_CHEBYSHEV_MAX = 2000


def _check_times(t: Any) -> np.ndarray:
    times = np.asarray(t, dtype=np.float64)
    if times.ndim > 1 or not np.isfinite(times).all() or (times < 0).any():
        raise MeshError(f"t must be a finite time >= 0 or a 1-d array of them; got {t!r}")
    return times


def heat_flow(
    op: Any,
    f: Any,
    t: Any,
    *,
    method: str = "auto",
    k: int = 100,
    eig: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    r"""Solve the heat equation ∂u/∂t = L u from u(0) = f: u(t) = exp(tL) f.

    Parameters
    ----------
    op : MeshLaplacian or SparseLaplacian
        The Laplacian (L ≈ +Δ).
    f : (n,) or (n, m) array_like
        Initial values, one function or a block.
    t : float or (T,) array_like
        Time(s) ≥ 0, in any order.
    method : {"auto", "chebyshev", "rational", "krylov", "spectral"}
        ``"auto"`` (default): ``"chebyshev"`` while it needs at most 2,000 products with L, else
        ``"rational"``, except on a volume too costly to factor, whose factorizations cost
        more than any series (:mod:`meshlap._multigrid`). ``"chebyshev"``: the Chebyshev series of
        exp(tx) on the interval [-ρ, 0] that holds the spectrum of L (ρ = max row sum of |L|,
        Gershgorin), with modified Bessel coefficients; about sqrt(2tρ·37) + 10 products with L
        for the largest t, shared by all times, accurate to about 1e-14 relative to ‖f‖. The
        spectrum of L is real (L is similar to the symmetric M^(-1/2) S M^(-1/2)). ρ grows with
        the smallest mass: one sliver vertex can ask for 10⁵ products. ``"rational"``: the
        trapezoid rule on Talbot's contour (Trefethen, Weideman and Schmelzer 2006), exp(tL) f = Σ
        c_j (z_j M − tS)⁻¹ M f over 12 conjugate pairs of nodes, whatever ρ and t: 12 complex
        sparse LUs per time, within about 1e-13 of exp(tL) f; it needs a stored S and a mass at
        every vertex. ``"krylov"``:
        :func:`scipy.sparse.linalg.expm_multiply` (Al-Mohy and Higham), whose cost grows
        like t·‖L‖ ≈ 2t/h products; consecutive times restart from the previous result.
        ``"spectral"``: ``Φ exp(-Λt) Φᵀ M f`` from k eigenpairs (or ``eig``): cheap for
        many times and large t, but drops the part of f above the k-th frequency.
    k : int, default 100
        Eigenpairs for ``"spectral"`` when ``eig`` is not given.
    eig : (lam, phi), optional
        Precomputed :func:`~meshlap.spectral.eigs` result for ``"spectral"``.

    Returns
    -------
    ndarray
        Shape of f for a scalar t; (T,) + f.shape for an array of times.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(1000, seed=0)
    >>> op = meshlap.laplacian(V, F, h=0.01)
    >>> u = heat_flow(op, V[:, 2], [0.0, 0.5])      # z is a degree-1 harmonic: λ ≈ 2
    >>> ratio = np.linalg.norm(u[1]) / np.linalg.norm(u[0])
    >>> bool(abs(ratio - np.exp(-2 * 0.5)) < 0.01)
    True
    """
    f = check_function(f, op.n_vertices)
    times = _check_times(t)
    tt = np.atleast_1d(times)
    if method == "spectral":
        lam, phi = eigs(op, k) if eig is None else (np.asarray(eig[0]), np.asarray(eig[1]))
        coef = phi.T @ (op.mass[:, None] * f.reshape(len(f), -1))
        out = np.stack([phi @ (np.exp(-np.maximum(lam, 0.0) * s)[:, None] * coef) for s in tt])
    elif method in ("auto", "chebyshev", "rational"):
        if getattr(op, "matrix_free", False):
            raise MeshError(f"method={method!r} needs a stored pencil (the series' bound comes from the "
                            "rows of L, the contour solves with S); use method='spectral' for a "
                            "matrix-free operator")
        F = f.reshape(len(f), -1)
        rho = 0.0
        if method != "rational":
            L = sp.csr_matrix(symmetric_L(op), dtype=np.float64)
            rho = float(abs(L).sum(axis=1).max())  # Gershgorin: the spectrum of L lies in [-rho, 0]
        if method == "auto":
            long = _chebyshev_terms(rho, tt) > _CHEBYSHEV_MAX
            # a volume too costly to factor (meshlap._multigrid) keeps the series, however long
            contour = long and bool((np.asarray(op.mass) > 0).all()) and not replaces_factor(op)
            method = "rational" if contour else "chebyshev"
        out = _chebyshev_heat(op, F, tt, rho) if method == "chebyshev" else _rational_heat(op, F, tt)
    elif method == "krylov":
        if getattr(op, "matrix_free", False):
            raise MeshError("method='krylov' needs a stored L; use method='spectral' for a matrix-free "
                            "operator")
        L = sp.csr_matrix(symmetric_L(op), dtype=np.float64)
        order = np.argsort(tt, kind="stable")
        out = np.empty((len(tt), *f.shape))
        u, now = f, 0.0
        for i in order:
            if tt[i] > now:
                u = expm_multiply((tt[i] - now) * L, u)
                now = tt[i]
            out[i] = u
    else:
        raise MeshError("method must be 'auto', 'chebyshev', 'rational', 'krylov' or 'spectral'; "
                        f"got {method!r}")
    out = out.reshape(len(tt), *f.shape)
    return out[0] if times.ndim == 0 else out


def _chebyshev_terms(rho: float, times: np.ndarray) -> int:
    # ive(k, a) falls below 1e-16 once k² > 2a·37 (Gaussian tail of the Bessel coefficients)
    return int(math.ceil(math.sqrt(2.0 * 37.0 * 0.5 * rho * float(times.max())))) + 10


def _chebyshev_coefficients(rho: float, times: np.ndarray) -> np.ndarray:
    """(K + 1, T) coefficients c_k(t) with exp(tx) = Σ c_k(t) T_k(2x/ρ + 1) on x ∈ [-ρ, 0]."""
    # exp(t x) on x = (rho/2)(y - 1), y in [-1, 1]: e^{-a} e^{a y} = ive(0, a) + 2 Σ ive(k, a) T_k(y)
    a = 0.5 * rho * times
    K = _chebyshev_terms(rho, times)
    coef = ive(np.arange(K + 1)[:, None], a[None, :])  # (K + 1, T)
    coef[1:] *= 2.0
    return coef


def _chebyshev_heat(op: Any, f: np.ndarray, times: np.ndarray, rho: float) -> np.ndarray:
    """exp(tL) f for every t in ``times`` from one Chebyshev recurrence in L."""
    out = np.zeros((len(times), *f.shape))
    if rho == 0:
        out[:] = f
        return out
    coef = _chebyshev_coefficients(rho, times)
    K = len(coef) - 1

    def Y(x):  # the spectrum of L mapped onto [-1, 1]
        return (2.0 / rho) * apply_block(op, x) + x

    t_prev, t_cur = f, Y(f)
    out += coef[0][:, None, None] * t_prev
    out += coef[1][:, None, None] * t_cur
    for k in range(2, K + 1):
        if np.abs(coef[k]).max() < 1e-18:
            break
        t_prev, t_cur = t_cur, 2.0 * Y(t_cur) - t_prev
        out += coef[k][:, None, None] * t_cur
    return out


def _contour() -> tuple[np.ndarray, np.ndarray]:
    """Nodes z_j in the upper half plane and weights c_j with exp(x) ≈ Re Σ c_j / (z_j − x)."""
    N = _CONTOUR_NODES
    th = (2.0 * np.arange(N // 2, N) + 1.0 - N) * np.pi / N  # the θ > 0 half of -π + (2j - 1)π/N
    z = N * (0.5017 * th / np.tan(0.6407 * th) - 0.6122 + 0.2645j * th)
    dz = N * (0.5017 / np.tan(0.6407 * th) - 0.5017 * 0.6407 * th / np.sin(0.6407 * th) ** 2 + 0.2645j)
    return z, 2.0 * np.exp(z) * dz / (1j * N)  # twice: each node stands for its conjugate too


def _rational_heat(op: Any, f: np.ndarray, times: np.ndarray) -> np.ndarray:
    """exp(tL) f = Re Σ c_j (z_j M − tS)⁻¹ M f for every t in ``times`` (L = M⁻¹S)."""
    mass = np.asarray(op.mass, dtype=np.float64)
    if not (mass > 0).all():
        raise MeshError("method='rational' needs a mass at every vertex (M is singular); use "
                        "method='chebyshev'")
    S = sp.csc_matrix(op.S, dtype=np.complex128)
    M = sp.diags(mass.astype(np.complex128), format="csc")
    Mf = (mass[:, None] * f).astype(np.complex128)
    z, c = _contour()
    out = np.empty((len(times), *f.shape))
    for i, t in enumerate(times):
        if t == 0:
            out[i] = f
            continue
        acc = np.zeros(f.shape, dtype=np.complex128)
        for zj, cj in zip(z, c, strict=True):
            # Im z_j > 0 and M is positive: every principal minor of z_j M − tS is nonsingular,
            # so an LU without pivoting serves (_ldl.factor's for a complex matrix; 3.4x faster at
            # 16,000 vertices than with pivoting)
            acc += cj * _factor(zj * M - t * S).solve(Mf)
        out[i] = acc.real
    return out


class ImplicitHeat:
    r"""Backward-Euler heat steps ``(M - τS) u = M f``, set up once for a time step τ.

    Each step damps the eigencomponent of frequency λ by 1/(1 + τλ): unconditionally
    stable, and after s steps of τ = t/s it approaches exp(tL) f with error O(τ).

    Parameters
    ----------
    op : MeshLaplacian or SparseLaplacian
        The Laplacian.
    tau : float
        Time step (> 0).
    solver : {"auto", "direct", "cg"}
        ``"direct"``: sparse LU of ``M - τS`` (fine for the cotangent Laplacian, slow for
        dense rows). ``"cg"``: block preconditioned conjugate gradient (module notes); the
        preconditioner needs the mesh (``op.V``/``op.faces`` or ``mesh``), else it is the
        diagonal. ``"auto"``: direct up to 40 entries per row, CG otherwise and on a volume too
        costly to factor (with multigrid: module notes; factored after all where the V-cycle
        stalls, :class:`meshlap._multigrid.Stall`).
    rtol : float, default 1e-10
        Relative residual at which CG stops.
    mesh : (V, F), optional
        Mesh for the preconditioner when ``op`` does not carry one.

    Notes
    -----
    At vertices with zero mass the step solves their row of ``(I - τL) u = f`` instead,
    ``u_w = (f_w + τ Σ_{p≠w} L_wp u_p) / (1 - τ L_ww)``; for operators whose rows vanish
    there (cotangent) this keeps ``u_w = f_w``.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(1500, seed=0)
    >>> step = ImplicitHeat(meshlap.laplacian(V, F, h=0.01), tau=0.1)
    >>> u = step(V[:, 0])                           # x decays by 1/(1 + 0.1·2)
    >>> bool(abs(np.linalg.norm(u) / np.linalg.norm(V[:, 0]) - 1 / 1.2) < 0.005)
    True
    """

    def __init__(self, op: Any, tau: float, *, solver: str = "auto", rtol: float = 1e-10,
                 mesh: tuple[Any, Any] | None = None) -> None:
        if solver not in ("auto", "direct", "cg"):
            raise MeshError(f"solver must be 'auto', 'direct' or 'cg'; got {solver!r}")
        try:
            tau = float(tau)
        except (TypeError, ValueError) as exc:
            raise MeshError(f"tau must be a positive number; got {tau!r}") from exc
        if not np.isfinite(tau) or tau <= 0:
            raise MeshError(f"tau must be finite and > 0; got {tau}")
        self.op, self.tau, self.rtol = op, tau, float(rtol)
        mass, self.P = _check_mass(op)
        self.m = mass[self.P]
        n = op.n_vertices
        self.Z = np.setdiff1d(np.arange(n), self.P)
        matrix_free = getattr(op, "matrix_free", False)
        sparse = not matrix_free and symmetric_L(op).nnz <= _SPARSE_ROW_MAX * n
        multigrid = sparse and replaces_factor(op)  # a large volume's: not factored
        chosen = solver == "auto"
        if chosen:
            solver = "direct" if sparse and not multigrid else "cg"
        self.solver = solver
        self._stall = None
        if solver == "direct" or multigrid:
            S = _restricted_S(op, self.P)
            A = sp.diags(self.m) - tau * 0.5 * (S + S.T)
            if solver == "direct":
                self._lu = _factor(A, _ldl.supernodal(op))
            else:  # CG preconditioned by the V-cycle of the system itself; factored if it stalls
                self._A = sp.csr_matrix(A)
                self._precondition = Multigrid(self._A).solve
                self._stall = Stall(lambda: _ldl.least_work(self._A)) if chosen else None
        else:
            diag = self.m / op.h if matrix_free else -self.m * np.asarray(symmetric_L(op).diagonal())[self.P]
            geo = _mesh_of(op, mesh)
            K = None if geo is None else _cot_stiffness(geo[0], geo[1], self.P, geo[2])
            if K is None:
                w = 1.0 / (self.m + tau * diag)
                self._precondition = lambda R: w[:, None] * R
            else:
                self._precondition = self._cotangent(K, diag, op)
        if len(self.Z):
            ind = np.zeros(n)
            ind[self.Z] = 1.0
            self._diag_Z = apply_block(op, ind)[self.Z]  # the pencil's, as the step's sums below
        self.iterations: list[int] = []

    # (M + τA) x with A = -S on the vertices with mass
    def _apply(self, Xp: np.ndarray) -> np.ndarray:
        n = self.op.n_vertices
        X = np.zeros((n, Xp.shape[1]))
        X[self.P] = Xp
        LX = apply_block(self.op, X)[self.P]
        return self.m[:, None] * (Xp - self.tau * LX)

    def _cotangent(self, K: sp.spmatrix, diag: np.ndarray, op: Any) -> Callable[[np.ndarray], np.ndarray]:
        # the heat-kernel symbol's model a M⁻¹ + b (2M + c K)⁻¹ (module notes), one factorization
        m = self.m
        h = float(np.median(m / np.where(diag > 0, diag, np.inf)))
        c = h + 2.0 * self.tau
        a, b = h / c, 4.0 * self.tau / c
        inverse = _factor(2.0 * sp.diags(m) + c * K, _ldl.supernodal(op))
        return lambda R: a * R / m[:, None] + b * inverse.solve(np.asfortranarray(R))

    def _pcg(self, B: np.ndarray, X: np.ndarray) -> np.ndarray:
        X, it, converged = block_pcg(self._apply, self._precondition, B, self.rtol, 1000, X,
                                     give_up=self._stall)
        self.iterations.append(it)
        if self._stall is not None and self._stall.fired:  # this step and the next ones
            self._lu, self.solver = _factor(self._A, _ldl.supernodal(self.op)), "direct"
            return self._lu.solve(np.asfortranarray(B))
        if not converged:
            warnings.warn(f"ImplicitHeat: CG did not reach rtol={self.rtol:g} in 1000 iterations",
                          RuntimeWarning, stacklevel=3)
        return X

    def step(self, f: Any, steps: int = 1) -> np.ndarray:
        """Apply ``steps`` backward-Euler steps to f ((n,) or (n, m)); returns the result."""
        f = check_function(f, self.op.n_vertices)
        steps = check_int(steps, "steps", 0)
        u = f.reshape(len(f), -1).copy()
        with _one_blas_thread():
            for _ in range(steps):
                rhs = self.m[:, None] * u[self.P]
                if self.solver == "direct":
                    up = self._lu.solve(np.asfortranarray(rhs))
                else:
                    up = self._pcg(rhs, u[self.P].copy())
                new = np.empty_like(u)
                new[self.P] = up
                if len(self.Z):
                    known = new.copy()
                    known[self.Z] = 0.0
                    s = apply_block(self.op, known)[self.Z]
                    new[self.Z] = (u[self.Z] + self.tau * s) / (1.0 - self.tau * self._diag_Z[:, None])
                u = new
        return u.reshape(f.shape)

    __call__ = step


def implicit_heat(op: Any, f: Any, tau: float, steps: int = 1, **kwargs: Any) -> np.ndarray:
    """``steps`` backward-Euler heat steps of size ``tau``: a shortcut for :class:`ImplicitHeat`.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(500, seed=0)
    >>> from meshlap.baselines import cotangent
    >>> u = implicit_heat(cotangent(V, F), V[:, 1], tau=0.05, steps=4)
    >>> bool(abs(np.linalg.norm(u) / np.linalg.norm(V[:, 1]) - 1.1 ** -4) < 0.01)
    True
    """
    return ImplicitHeat(op, tau, **kwargs).step(f, steps)
