"""Shift-invert Lanczos for :func:`meshlap.spectral.eigs`: one sparse factorization of the
shifted pencil, reused by every run, and runs that deflate the pairs found before."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg  # noqa: F401 - sp.linalg

from ._ldl import factor
from .errors import EigenError

__all__ = ["shift_invert", "shift_operator", "until_none_new", "without_skips"]

# ARPACK's restarts at most (its default, 10 n, is hours at 10⁵ unknowns): a solve that converges
# takes a few; one that does not ends in EigenError rather than a hang
_RESTARTS = 300


def shift_operator(S: sp.csr_matrix, m: np.ndarray, sigma: float, supernodal: bool = False,
                   report=None):
    """-S, σ and the solve with -S + σM: the shift -σ lies below the zero eigenvalues
    (``supernodal``: :func:`meshlap._ldl.factor`'s; ``report(fraction, stage)``: progress)."""
    if report is not None:
        report(0.02, "shift-invert: factoring")
    A = sp.csc_matrix(-0.5 * (S + S.T))
    return A, sigma, factor(A + sp.diags(sigma * m), supernodal).solve


def shift_invert(A: sp.csc_matrix, sigma: float, solve, m: np.ndarray, k: int, tol: float, seed: int,
                 known: tuple[np.ndarray, np.ndarray] | None = None, report=None):
    """The k + 1 eigenpairs nearest the shift (the last one: the gap above λ_k). ``known``:
    pairs of an earlier run, kept, and the Lanczos runs on their M-orthogonal complement
    (deflated), where it finds what that run skipped: Lanczos from one start vector sees one
    vector of an eigenspace, and a symmetric mesh has exactly equal eigenvalues."""
    n = len(m)
    if report is not None:  # a deflated run looks for pairs an earlier one skipped (count, ties)
        report(0.3 if known is None else 0.6, "Lanczos" if known is None else "Lanczos, deflated")
    lam0, X0 = (np.zeros(0), np.zeros((n, 0))) if known is None else known
    want = min(k + 1, n - 1) - len(lam0) + 1 if len(lam0) else min(k + 1, n - 1)
    MX0 = m[:, None] * X0

    def apply(y: np.ndarray) -> np.ndarray:  # P (A + σM)⁻¹ Pᵀ, P = I - X₀X₀ᵀM
        z = solve(y - MX0 @ (X0.T @ y))
        return z - X0 @ (MX0.T @ z)

    OPinv = sp.linalg.LinearOperator(A.shape, matvec=apply, dtype=np.float64)
    v0 = np.random.default_rng(seed).standard_normal(n)
    v0 -= X0 @ (MX0.T @ v0)
    try:
        lam, X = sp.linalg.eigsh(A, k=min(want, n - 1 - len(lam0)), M=sp.diags(m).tocsc(), sigma=-sigma,
                                 OPinv=OPinv, tol=tol, v0=v0, maxiter=_RESTARTS)
    except sp.linalg.ArpackNoConvergence as exc:
        raise EigenError(f"shift-invert: ARPACK converged {len(exc.eigenvalues)} of {want} pairs in "
                         f"{_RESTARTS} restarts", eigenvalues=exc.eigenvalues, vectors=exc.eigenvectors,
                         tried=("shift-invert",)) from exc
    lam, X = np.concatenate([lam0, lam]), np.hstack([X0, X])
    order = np.argsort(lam)
    return lam[order], X[:, order], 0


def without_skips(A: sp.csc_matrix, sigma: float, solve, m: np.ndarray, k: int, tol: float, seed: int,
                  known: tuple[np.ndarray, np.ndarray] | None = None, report=None):
    """:func:`shift_invert`, then deflated runs until one finds no value at or below the k-th:
    where no inertia count will show that none is missing (a dense-row pencil), this finds what
    Lanczos skipped. Two copies of one part have every eigenvalue twice, and a run from one start
    vector sees one vector of each eigenspace (below: λ₉ of two copies of a sphere, skipped; two
    2,000-vertex spheres' heat-kernel pencil, k = 10, gave 5.978252 for λ₉ = λ₈ = 5.978069).

    Examples
    --------
    >>> import igl, meshlap
    >>> V, F = meshlap.shapes.sphere(100, seed=0)
    >>> C, mass = igl.cotmatrix(V, F), igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI).diagonal()
    >>> A, s, solve = shift_operator(sp.block_diag([C, C]).tocsr(), np.r_[mass, mass], 0.5)   # two copies
    >>> shift_invert(A, s, solve, np.r_[mass, mass], 10, 1e-12, 0)[0][8:10].round(4).tolist()
    [5.7459, 5.7756]
    >>> without_skips(A, s, solve, np.r_[mass, mass], 10, 1e-12, 0)[0][8:10].round(4).tolist()
    [5.7459, 5.7459]
    """
    lam, X = until_none_new(lambda: shift_invert(A, sigma, solve, m, k, tol, seed, known, report)[:2],
                            lambda lam, X, extra: shift_invert(A, sigma, solve, m, len(lam) + extra, tol,
                                                               seed + len(lam), (lam, X), report)[:2],
                            k, len(m))
    return lam, X, 0


def until_none_new(first, more, k: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The pairs of ``first()``, then of ``more(lam, X, extra)`` (those pairs and ``extra`` more
    from a run deflated of them, at most n - 2 in all) until a run finds no value at or below the
    k-th of the first: the serial shift-invert's and SLEPc's (:func:`meshlap.distributed.eigs`).

    Examples
    --------
    >>> spectrum = np.r_[0.0, 1.0, 1.5, np.arange(2.0, 30.0)]
    >>> first = lambda: (np.r_[0.0, 1.0, 2.0, 3.0, 4.0], None)    # 1.5 skipped
    >>> more = lambda lam, X, extra: (np.sort(np.r_[lam, np.setdiff1d(spectrum, lam)[:extra]]), None)
    >>> until_none_new(first, more, 4, len(spectrum))[0][:5].tolist()
    [0.0, 1.0, 1.5, 2.0, 3.0]
    """
    lam, X = first()
    top = float(np.sort(lam)[min(k, len(lam)) - 1])
    while len(lam) < n - 2:
        below = int((lam <= top).sum())
        lam, X = more(lam, X, min(max(4, k // 10), n - 2 - len(lam)))
        if int((lam <= top).sum()) == below:
            break
    return lam, X
