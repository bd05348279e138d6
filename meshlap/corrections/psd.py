"""The semidefiniteness check of the corrected operator.

The difference of Gaussians has negative weights, so −S = −M L positive semidefinite is not
automatic: on a geometry too coarse for the narrow kernel h/2 it fails, and spectra and heat
flow would blow up. :func:`check` finds the smallest eigenvalue of the pencil (−S, M) and
compares it with the operator's scale. No cheaper proof covers the case: the continuous
Richardson symbol of −L, (1 − e^{−x/2})(3 − e^{−x/2})/h with x = hω², is positive, but the
sampled kernel has negative weights at every pair farther than √(4h ln 8) (on a surface), so
neither the weights' signs nor diagonal dominance decide it; the check is an eigensolver run
that stops as early as the answer is known. One failure is certain without it: a positive
diagonal entry of L (a point whose kernel weights sum below zero, where the narrow Gaussian
falls between the samples) is a vector with a negative Rayleigh quotient.

Cheaper certificates that were weighed (issue 19) and why none is used: Gershgorin's bound on
(−S, M) is −2 max_w Σ_p |L_wp⁻| (the row's negative weights), −0.043 of the scale on the 16k
random sphere and −0.85 on spot, against the −1e-6 needed, and no bound of that kind can
reach 0, which the constant attains exactly. Splitting −S into the graph Laplacians of its
positive and negative weights, L(W⁺) − L(W⁻), does not help either: the negative part is
not small on smooth functions (its second moment is 18% of the positive part's on the sphere,
the continuum's 0.224/1.224, and 33% on spot), so comparing the two needs the negative pairs
routed through positive ones, and routing a pair through a midpoint (Cauchy–Schwarz,
(a + b)² ≤ 2a² + 2b²) loses exactly the factor 2 by which 2K_{h/2} dominates K_h in the
continuum (the symbols' ratio (1 + e^{−hω²/2})/4 ≤ 1/2): a proof with no slack left for the
sampling, at O(entries × row length). Hence an eigensolver.

What it certifies. A failure is proved: the value returned is the Rayleigh quotient of a
vector (a point's indicator, or a Ritz vector), an upper bound of λ_min. A pass is not a
proof: LOBPCG stopped when the smallest Ritz value's Kato–Temple estimate, with the next Ritz
value standing in for the gap, was within ``tol``, and a negative mode outside the search
space goes unseen. Nor is it a probabilistic certificate: the random columns are guards, and a
random start's guarantee (Kuczyński–Woźniakowski) would need about 10⁴ products to resolve
−PSD_RTOL of the scale. What is measured instead (``benchmarks/RESULTS.md``, i19p): over 35
inputs near the sampling limit (2,000-vertex random sphere, plane and torus, spot, a 12³
tetrahedral cube; h = 0.3-1 ē²) against LAPACK's smallest eigenvalue, the 9 indefinite ones
fail (3 by a positive diagonal) and the 26 semidefinite ones pass; the negative modes are
localized (1-40 points of participation) at points of large mass, where the narrow kernel
falls between samples. Its margin is thin in places: on the plane at 0.35 ē² it proves
−1.4e-6 of the scale against a true −1.7e-3.

The stopping tolerance (issue 19). It decides how long the search runs where no failure shows:
LOBPCG ends once the smallest Ritz value's estimate is within ``tol`` of it, and the poorer
the sampling the poorer the coordinate functions are as eigenvectors, so the longer it
searches. Looser tolerances were measured and rejected. 3e-2 finds every failure of the sweep
above, of 13 more inputs near its boundary (spot at 0.45 and 0.55 ē², two more random spheres,
a plane, a thin torus) and of 50,000- and 100,000-vertex random spheres at 0.5 ē², at the same
iteration as 1e-3, and stops at the start where the operator is well resolved (100,000
vertices at h = ē²: 8 iterations and 3.5 s of CPU at 1e-3, none and 0.13 s at 3e-2, which
would meet issue 19's budget at 400,000), but it passes ``tests/test_psd.py``'s mode at two
neighbouring vertices (−1e-2 of its energy, 1,300 vertices) that 1e-3 finds. 0.1, a rule that
only decides the sign, also passes spot at 0.5 ē² (λ_min −6.9e-4 of the scale, found at 1e-3
after 9 iterations, missed at 0.1 after 6). Also rejected: start vectors aimed at the
large-mass points (random vectors weighted by mass or restricted to its top 3-10%) miss that
mode at 0.1 too; a Jacobi preconditioner (no cotangent factor) needs 20-40 iterations where
the factor needs 3-5; principal submatrices of 16-64 points (Cauchy interlacing: a negative
one proves the failure) around the heaviest points or over grid cells miss spot's mode in
every variant tried. What changed is the start: the build hands over, besides L's diagonal,
L's products with the coordinates and the random start columns, made while each row is in
cache (:func:`fill_columns`), so LOBPCG's start costs no product: where the start decides (the
16k sphere at the default width) the check takes 0.02-0.04 s of CPU instead of 0.08-0.10 s;
where LOBPCG iterates (spot, fandisk, 400,000 points at h = ē²) the first of its 6-10 block
products is saved.

At scale (i19c). On 400,000 random vertices at h = ē² the check passes (λ_min 9e-15 of the
scale) after 10 iterations and 38 s of CPU, 5.7× the paper's whole build: of its wall time the
10 block products 55%, the cotangent factor 22%, its solves 16%, the rest (Rayleigh–Ritz,
orthogonalization) 7%; 100,000 vertices: 8 iterations, 3.9 s. A pass is the costly verdict, not
a failure: a failure ends at the first negative Ritz value or diagonal entry (100,000 vertices
at 0.5 ē²: 11 iterations, 3.3 s). There the operator it certifies is 5.3% off where the plain
kernel is 0.9%: an explicit width that narrow is the caller's choice (``correction="none"``
builds the plain kernel).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..geometry import Polygons
from ..lumped import SparseLaplacian
from ..tuned import PSD_RTOL, PSD_STOP_TOL

__all__ = ["check", "fill_columns", "smallest_eigenvalue", "unit_constant"]

# points up to which a failed iterative check is repeated with a dense eigensolver, and up to
# which the check is dense from the start
_DENSE_MAX = 4000
_DENSE_DIRECT = 1200
# columns of the start block: the coordinate functions and random vectors up to this many
_START = 6


def unit_constant(mass: np.ndarray) -> float:
    """The value of the M-normalized constant on the points with mass, 1/√(Σ m): the vector
    the check deflates.

    Examples
    --------
    >>> unit_constant(np.array([1.0, 0.0, 3.0]))
    0.5
    """
    return 1.0 / math.sqrt(float(mass[mass > 0].sum()))


def fill_columns(V: np.ndarray, mass: np.ndarray) -> np.ndarray:
    """The columns whose product with L the build makes while it fills the rows, after the
    coordinates' (which the moment scale has): the constant :func:`unit_constant` and the
    start block's random vectors, the ones :func:`smallest_eigenvalue` draws itself.

    Examples
    --------
    >>> B = fill_columns(np.zeros((4, 3)), np.full(4, 0.25))
    >>> B.shape, B[:, 0].tolist()
    ((4, 4), [1.0, 1.0, 1.0, 1.0])
    """
    random = _guards(len(mass), _START - min(V.shape[1], 3))
    return np.column_stack([np.full(len(mass), unit_constant(mass)), random])


def _guards(n: int, count: int) -> np.ndarray:
    # the start block's random columns: one seeded draw, the same for the fill and the check
    return np.random.default_rng(0).standard_normal((n, count))


def smallest_eigenvalue(L: sp.csr_matrix, mass: np.ndarray, V: np.ndarray, faces: Polygons | None,
                        tol: float = PSD_STOP_TOL, maxiter: int = 40,
                        known: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[float, float]:
    """The two ends that decide whether −S = −M L is positive semidefinite.

    Returns (λ_min, λ_scale): the smallest eigenvalue of the pencil (−S, M) on the points
    with mass (an upper bound of it where the iteration stops early, below) and the scale
    ``max_w −L_ww`` it is to be compared with. ``known``: what the build made while filling
    the rows, L's diagonal and L's product with the block ``[V, fill_columns(V, mass)]``
    (scipy's product, to the bit); used where every point has mass, it leaves LOBPCG's start
    no product to make (the check's only one where the start decides, as on the 16k sphere at
    the default width: 0.085 -> 0.03 s of CPU).

    Where L's rows sum to zero (not on an MPI rank's diagonal block) the constant is an
    eigenvector with eigenvalue 0: it is deflated, and LOBPCG (:mod:`meshlap._lobpcg`) looks
    for the smallest eigenvalue on its M-orthogonal complement, one target vector and five
    guards: the coordinate functions (smooth, near the bottom of a semidefinite spectrum) and
    random vectors (every frequency). The preconditioner is :func:`meshlap.spectral.eigs`'s
    (the cotangent factor when ``faces`` are triangles in R³, plus ½ D⁻¹). The iteration ends
    at the first Ritz value below −PSD_RTOL · scale, which proves the failure (a Ritz value
    bounds an eigenvalue from above), or when the smallest Ritz value's error estimate (the
    Kato–Temple bound with the next Ritz value standing in for the gap) is ``tol`` of it: an
    estimate, not a bound (module notes). Before it, a diagonal entry L_ww above
    PSD_RTOL · scale proves the failure at no cost: −L_ww is the Rayleigh quotient of the
    indicator of w, and that bound is returned.
    """
    from .. import _lobpcg
    from .._jit import one_blas_thread as _one_blas_thread
    from ..spectral import _cot_stiffness, _scale_shift, apply_block

    diag = L.diagonal() if known is None else known[0]  # once: a pass over every entry
    scale = float(np.max(-diag))
    P = np.flatnonzero(mass > 0)
    m = mass[P]
    Lp = sp.csr_matrix(L if len(P) == len(mass) else L[P][:, P], dtype=np.float64)
    op = SparseLaplacian(Lp, m)
    u = unit_constant(mass)
    one = np.full(len(P), u)
    fill = None if known is None or len(P) < len(mass) else known[1]
    # L's rows sum to zero: the constant is in the kernel, up to rounding
    r = -(Lp @ one) if fill is None else -fill[:, V.shape[1]]
    const = float(one @ (m * r))
    deflate = math.sqrt(float(m @ (r * r))) <= 1e-10 * scale
    if len(P) <= _DENSE_DIRECT:
        return _dense_lowest(Lp, m), scale
    worst = float(np.max(diag[P]))
    if worst > PSD_RTOL * scale:
        # the Rayleigh quotient of a point's own indicator, -L_ww, bounds the smallest
        # eigenvalue from above: a positive diagonal entry proves the failure without an
        # eigensolver (7 of the 9 failing inputs of a sweep over spheres, a plane, the bunny
        # and fandisk at 0.25-0.5 e-bar squared)
        return -worst, scale

    def project(X: np.ndarray) -> np.ndarray:  # onto the M-orthogonal complement of the constant
        return X - one[:, None] * (one @ (m[:, None] * X))[None, :] if deflate else X

    made: list = []

    def precond(R: np.ndarray) -> np.ndarray:
        # made on the first use: where the start block already decides (the coordinate
        # functions on a sphere-like surface) the cotangent factor is never needed (0.06 s of
        # CPU on a 16k sphere)
        if not made:
            tri = None if faces is None else (faces.triangles() if isinstance(faces, Polygons) else faces)
            K = None if tri is None or V.shape[1] != 3 else _cot_stiffness(V, tri, P)
            made.append(_lobpcg.CotPreconditioner(K, m, -m * diag[P], _scale_shift(m)))
        return project(made[0](R))

    d = min(V.shape[1], 3)
    coords = V[P][:, :d] - (m @ V[P][:, :d]) / m.sum()
    smooth = coords if deflate else np.hstack([one[:, None], coords])
    raw = np.hstack([smooth, _guards(len(P), _START - smooth.shape[1])])
    X0 = project(raw)
    start: list = []
    if deflate and fill is not None:
        # the start's product from the fill's, by linearity: with L·one = −r, the centred
        # coordinates' L(V − 1cᵀ) = LV + (r/u)cᵀ, and the projection's L(X − one·oneᵀMX) =
        # LX + r·oneᵀMX
        LX = np.hstack([fill[:, :d] + (r / u)[:, None] * ((m @ V[:, :d]) / m.sum())[None, :],
                        fill[:, V.shape[1] + 1:]])
        LX += r[:, None] * (one @ (m[:, None] * raw))[None, :]
        X, T = _lobpcg.svqb(X0, m)
        start.append((X, -m[:, None] * _lobpcg.matmul(LX, T)))
        X0 = X

    def apply(X: np.ndarray) -> np.ndarray:
        if start:  # LOBPCG's first product, of its start: our M-orthonormal X0 recombined
            S, AS = start.pop()
            return _lobpcg.matmul(AS, _lobpcg.inner(S, m[:, None] * X))
        return -m[:, None] * apply_block(op, X)

    with _one_blas_thread(), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        try:
            # the search directions are kept off the constant; A X needs nothing (A 1 = 0)
            out = _lobpcg.lobpcg(apply, m, precond, X0, 1 if deflate else 2, tol, maxiter,
                                 floor=-PSD_RTOL * scale)
        except np.linalg.LinAlgError:
            # the Gram matrices break down on a strongly indefinite pencil: decide densely where
            # that is affordable, else count it as failed (the plain kernel is safe)
            if len(P) > _DENSE_MAX:
                return -math.inf, scale
            return _dense_lowest(Lp, m), scale
    return min(const, float(out.lam[0])), scale


def _dense_lowest(Lp: sp.csr_matrix, m: np.ndarray) -> float:
    # the smallest eigenvalue of (-S, M) by LAPACK, on one BLAS thread: a threaded BLAS on a
    # busy machine spins while it waits for its other threads, and the first build's check of
    # a 500-vertex mesh took 1-2 s of CPU instead of 0.05 s
    from .._jit import one_blas_thread as _one_blas_thread

    S = m[:, None] * Lp.toarray()
    with _one_blas_thread():
        low = sla.eigh(-0.5 * (S + S.T), np.diag(m), eigvals_only=True, subset_by_index=[0, 0])
    return float(low[0])


def check(L: sp.csr_matrix, mass: np.ndarray, V: np.ndarray, faces: Polygons | None,
          what: str, known: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[float, str | None]:
    """``(margin, reason)``: λ_min/scale, and why the operator fails (None when it passes);
    ``known`` as for :func:`smallest_eigenvalue`.

    Examples
    --------
    >>> import meshlap
    >>> V, F = meshlap.shapes.sphere(800, seed=0)
    >>> op = meshlap.laplacian(V, F, correction="none")
    >>> margin, reason = check(op.L, op.mass, V, op.faces, "mesh")
    >>> reason is None
    True
    """
    lam_min, scale = smallest_eigenvalue(L, mass, V, faces, known=known)
    if lam_min < -PSD_RTOL * scale:
        return lam_min / scale, (
            f"the Richardson operator is not negative semidefinite here (an eigenvalue at most {lam_min:.3g} "
            f"of -S against the scale {scale:.3g}): h is too small for the {what} to resolve the narrow "
            f"kernel h/2; using the plain kernel (O(h) bias)")
    return lam_min / scale, None
