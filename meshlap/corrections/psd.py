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
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..geometry import Polygons
from ..lumped import SparseLaplacian

__all__ = ["PSD_RTOL", "check", "smallest_eigenvalue", "unit_constant"]

# points up to which a failed iterative check is repeated with a dense eigensolver, and up to
# which the check is dense from the start
_DENSE_MAX = 4000
_DENSE_DIRECT = 1200
#: −S counts as semidefinite when λ_min ≥ −PSD_RTOL · max_w(−L_ww).
PSD_RTOL = 1e-6


def unit_constant(mass: np.ndarray) -> float:
    """The value of the M-normalized constant on the points with mass, 1/√(Σ m): the vector
    the check deflates.

    Examples
    --------
    >>> unit_constant(np.array([1.0, 0.0, 3.0]))
    0.5
    """
    return 1.0 / math.sqrt(float(mass[mass > 0].sum()))


def smallest_eigenvalue(L: sp.csr_matrix, mass: np.ndarray, V: np.ndarray, faces: Polygons | None,
                        tol: float = 1e-3, maxiter: int = 40,
                        known: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[float, float]:
    """The two ends that decide whether −S = −M L is positive semidefinite.

    Returns (λ_min, λ_scale): the smallest eigenvalue of the pencil (−S, M) on the points
    with mass and the scale ``max_w −L_ww`` it is to be compared with. ``known``: L's
    diagonal and its product with the constant :func:`unit_constant` (scipy's product, to the
    bit), where the build made them while filling the rows: two passes over L saved (the
    check 0.105 -> 0.085 s of CPU on the 16k sphere); the product is used only where every
    point has mass.

    Where L's rows sum to zero (not on an MPI rank's diagonal block) the constant is an
    eigenvector with eigenvalue 0: it is deflated, and LOBPCG (:mod:`meshlap._lobpcg`) looks
    for the smallest eigenvalue on its M-orthogonal complement, one target vector and five
    guards: the coordinate functions (smooth, near the bottom of a semidefinite spectrum) and
    random vectors (every frequency, where a negative mode of the difference of Gaussians
    lives). The preconditioner is :func:`meshlap.spectral.eigs`'s (the cotangent factor when
    ``faces`` are triangles in R³, plus ½ D⁻¹). The iteration ends at the first Ritz value
    below −PSD_RTOL · scale, which proves the failure (a Ritz value bounds an eigenvalue from
    above), or when the smallest is known to ``tol`` relative (the Kato–Temple bound). Before
    it, a diagonal entry L_ww above PSD_RTOL · scale proves the failure at no cost: −L_ww is
    the Rayleigh quotient of the indicator of w, and that bound is returned.
    """
    from .. import _lobpcg
    from ..spectral import _cot_stiffness, _one_blas_thread, _scale_shift, apply_block

    diag = L.diagonal() if known is None else known[0]  # once: a pass over every entry
    scale = float(np.max(-diag))
    P = np.flatnonzero(mass > 0)
    m = mass[P]
    Lp = sp.csr_matrix(L if len(P) == len(mass) else L[P][:, P], dtype=np.float64)
    op = SparseLaplacian(Lp, m)
    one = np.full(len(P), unit_constant(mass))
    # L's rows sum to zero: the constant is in the kernel, up to rounding
    r = -(Lp @ one) if known is None or len(P) < len(mass) else -known[1]
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

    rng = np.random.default_rng(0)
    coords = V[P][:, :3] - (m @ V[P][:, :3]) / m.sum()
    smooth = coords if deflate else np.hstack([one[:, None], coords])
    X0 = project(np.hstack([smooth, rng.standard_normal((len(P), 6 - smooth.shape[1]))]))
    with _one_blas_thread(), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        try:
            # the search directions are kept off the constant; A X needs nothing (A 1 = 0)
            out = _lobpcg.lobpcg(lambda X: -m[:, None] * apply_block(op, X), m,
                                 precond, X0, 1 if deflate else 2, tol, maxiter,
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
    from ..spectral import _one_blas_thread

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
