"""Checks on computed eigenpairs of the pencil ``-S φ = λ M φ`` (M = diag(m) > 0), made after
every solve of :func:`meshlap.spectral.eigs` and :func:`meshlap.distributed.lobpcg.eigs`.

**The pairs.** For returned ``(λ_i, φ_i)`` the check recomputes, with fresh products (not the
solver's own updated blocks), the mass Gram matrix ``ΦᵀMΦ`` and the residuals
``r_i = -S φ_i - λ_i M φ_i``, measured in the M⁻¹ norm (the norm in which the pencil is a
symmetric matrix). Every column must be M-orthonormal to ``_ORTHO``: a block whose columns
collapsed onto one vector (ten copies of the constant function have ten Rayleigh quotients
of zero) fails here, where a residual alone would pass it. Each eigenvalue then has an error
bound: ``‖r_i‖`` (Bauer–Fike, rigorous for M-orthonormal φ), or, for a cluster of returned
values with a gap δ to the nearest value outside it, ``‖R_c‖₂² / δ`` (Kato–Temple for the
cluster, as LOBPCG's own stopping test, :func:`meshlap._lobpcg.eig_error`). The gap of the
k-th eigenvalue's cluster is to the next value above: the solver's next Ritz value (an
estimate), or, after a count, the counted shift (a proven lower bound on λ_{k+1}). A pair
passes when the bound is at most ``tol · max(|λ_i|, λ_k / 100, floor)``: the meaning of ``tol``
in :func:`meshlap.spectral.eigs`, with ``floor`` (1% of 4π/area) so that a spectrum whose first
k eigenvalues are all zero (k connected parts) has a scale at all.

**Nothing skipped.** Sylvester's law of inertia: the number of eigenvalues of the pencil below
σ equals the number of negative pivots of an LDLᵀ factorization of ``-S - σM``
(:func:`count_below`). With σ between the returned k-th value's cluster and the next computed
value, a count equal to the number of returned values below σ proves (with the bounds above,
which place those values at distinct eigenvalues) that none is missing below σ. The
factorization is QDLDL's LDLᵀ without pivoting (:mod:`meshlap._ldl`), whose D is read directly;
where it meets an exact zero pivot, SuperLU's LU in a symmetric ordering without pivoting, whose
U's diagonal holds D where it did not pivot (``perm_r == perm_c``); where it did, the count
falls back to dense eigenvalues for small n or is not given.
The factorization costs about what a shift-invert solve's does: affordable for sparse pencils
(cotangent, linear FEM), not for the heat-kernel operator's hundreds of entries per row.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from . import _ldl, _lobpcg
from .errors import MeshWarning, user_stacklevel

__all__ = ["UNCERTIFIED", "Attempt", "Verdict", "count_below", "count_ceiling", "count_shift", "lumped_eigh",
           "certified", "first_verified", "residual_roundoff", "uncertified", "verify", "warn_roundoff"]

# the largest |ΦᵀMΦ - I| entry accepted (rounding leaves ~1e-13; a collapsed block, O(1))
_ORTHO = 1e-7
# pencils up to this many rows are counted densely where no factorization gives the pivots
_DENSE_COUNT = 3000
# relative distance within which a computed value is a tie of λ_k (the count's shift goes above)
_TIE = 1e-3
# ... or within twice verify's absolute yardstick tol · floor: two copies of one eigenvalue that
# both pass the check are that close
_TIE_CHECKS = 2.0
_EPS = float(np.finfo(np.float64).eps)
# relative accuracy of the smallest returned eigenvalue beyond which roundoff is warned of (0.1%)
UNCERTIFIED = 1e-3


class Verdict(NamedTuple):
    """What :func:`verify` found: the residual norms ‖r_i‖_{M⁻¹}, each eigenvalue's error bound
    over ``tol`` times its scale (a pair passes where ≤ 1), and the largest |ΦᵀMΦ - I| entry."""

    residuals: np.ndarray
    bounds: np.ndarray
    orthogonality: float

    @property
    def passed(self) -> np.ndarray:
        """The pairs that passed (all fail where the block is not M-orthonormal)."""
        ok = np.isfinite(self.bounds) & (self.bounds <= 1.0)
        return ok & (self.orthogonality <= _ORTHO)


def scales(lam: np.ndarray, floor: float) -> np.ndarray:
    """``max(|λ_i|, |λ_k| / 100, floor)``: each eigenvalue's yardstick for ``tol``.

    Examples
    --------
    >>> scales(np.array([0.0, 2.0, 6.0]), 0.01).tolist()
    [0.06, 2.0, 6.0]
    """
    top = abs(float(lam[-1])) if len(lam) else 0.0
    return np.maximum(np.abs(lam), max(0.01 * top, floor, 1e-300))


def roundoff_floor(stiff: float, tol: float, scale: float) -> float:
    """The yardstick ``floor`` of :func:`verify` for a pencil of scale ``scale`` whose stiffest
    row has ``A_ii / m_i = stiff``: 1% of the scale, or what roundoff leaves of ``A x`` there
    (4ε·stiff, over ``tol``), whichever is more. A mesh of tiny and large triangles has exact
    null vectors (its parts' indicators) whose computed residual is above ``tol`` times 1% of
    the scale.

    Examples
    --------
    >>> roundoff_floor(4.0, 1e-8, 1.0), roundoff_floor(1e8, 1e-8, 1.0) > 0.01
    (0.01, True)
    """
    return max(0.01 * scale, 4 * _EPS * stiff / max(tol, _EPS))


def uncertified(lam: np.ndarray, tol: float, floor: float, scale: float) -> float:
    """The check's absolute yardstick ``tol · floor`` over the smallest returned value above 1%
    of the scale (a part's zeros are certified absolutely); above ``UNCERTIFIED``, roundoff and
    not ``tol`` limits what the check certified (:func:`warn_roundoff`).

    Examples
    --------
    >>> uncertified(np.array([0.0, 2.0, 6.0]), 1e-8, 4e6, 1.0)   # a floor from roundoff
    0.02
    """
    nonzero = lam[lam > 0.01 * scale]
    return float(max(tol, _EPS) * floor / nonzero.min()) if len(nonzero) else 0.0


def residual_roundoff(apply_abs: Callable[[np.ndarray], np.ndarray], m: np.ndarray,
                      X: np.ndarray) -> np.ndarray:
    """What roundoff can leave in each column's computed residual (:func:`verify`): 4ε ‖|A| |x_i|‖
    in the M⁻¹ norm, ``apply_abs`` multiplying by |A|. Large only where the vector itself sits on
    a stiff row (a sliver's vertex, a near copy), where ``roundoff_floor``'s 4ε · max A_ii / m_i
    assumes it always does.

    Examples
    --------
    >>> A = np.diag([1.0, 1e12])                    # a stiff row the vector does not touch
    >>> float(residual_roundoff(lambda Y: np.abs(A) @ Y, np.ones(2), np.array([[1.0], [0.0]]))[0])
    8.881784197001252e-16
    """
    Y = apply_abs(np.abs(X))
    return 4 * _EPS * np.sqrt(np.maximum((Y * Y / m[:, None]).sum(axis=0), 0.0))


def certified(lam: np.ndarray, residuals: np.ndarray, bounds: np.ndarray, tol: float, floor: float,
              rho: np.ndarray) -> np.ndarray:
    """Each eigenvalue's error bound when its computed residual may be off by ``rho``
    (:func:`residual_roundoff`): Bauer–Fike on ``residual + rho``, or the check's Kato–Temple
    bound (``bounds`` over ``tol`` times the scale, as :func:`verify` returns it) grown as the
    square of the residual, whichever is less.

    Examples
    --------
    >>> b = certified(np.array([2.0, 6.0]), np.array([1e-6, 1e-6]), np.array([0.5, 1.0]), 1e-8, 0.01,
    ...               np.array([1e-9, 1e-6]))
    >>> [float(f"{x:.4g}") for x in b]     # Kato–Temple's 1e-8 and 6e-8, grown
    [1.002e-08, 2.4e-07]
    """
    err = bounds * tol * scales(lam, floor)
    grown = residuals + rho
    with np.errstate(divide="ignore", invalid="ignore"):
        kato = np.where(residuals > 0, err * (grown / residuals) ** 2, np.inf)
    return np.minimum(grown, kato)


def warn_roundoff(lam: np.ndarray, tol: float, floor: float, scale: float, stiff: float,
                  info: dict | None = None, bound: np.ndarray | None = None) -> float:
    """What the check certified of the returned eigenvalues where roundoff, not ``tol``, set it,
    relative to the values above 1% of the scale (a part's zeros are certified absolutely): each
    pair's ``bound`` (:func:`certified`) where given, else the absolute yardstick ``tol · floor``
    over the smallest. Beyond ``UNCERTIFIED`` a :class:`meshlap.MeshWarning` names the cause;
    ``info["uncertified"]`` gets the ratio.

    Examples
    --------
    >>> warn_roundoff(np.array([0.0, 2.0, 6.0]), 1e-8, 0.01, 1.0, 4.0)   # a plain sphere
    5e-11
    """
    ratio, yardstick = uncertified(lam, tol, floor, scale), max(tol, _EPS) * floor
    nonzero = lam > 0.01 * scale
    if bound is not None and nonzero.any():
        share = bound[nonzero] / lam[nonzero]
        ratio, yardstick = float(share.max()), float(bound[nonzero][share.argmax()])
    if info is not None:
        info["uncertified"] = ratio
    if ratio > UNCERTIFIED:
        warnings.warn(f"eigs: roundoff limits the check to ±{yardstick:.2g} ({ratio:.1%} of a nonzero "
                      f"eigenvalue returned, not tol = {tol:g}): a row of this pencil has "
                      f"S_ii/m_i = {stiff:.2g}, near-degenerate triangles or nearly coincident vertices; "
                      "weld or remove them for certified eigenvalues", MeshWarning,
                      stacklevel=user_stacklevel())
    return ratio


def verify(apply_A: Callable[[np.ndarray], np.ndarray], m: np.ndarray, lam: np.ndarray, X: np.ndarray,
           tol: float, floor: float, upper: float | None = None, allsum=_lobpcg._local) -> Verdict:
    """Check the pairs ``(lam[i], X[:, i])`` of ``A x = λ M x``, ``A = -S`` (module notes).

    ``apply_A`` multiplies a block; ``upper`` bounds the eigenvalues past ``lam`` from below as far as
    known (None: Bauer–Fike alone for the last cluster). The rows may be an MPI rank's share:
    ``allsum`` then adds the small Gram matrices over the ranks.

    Examples
    --------
    >>> m = np.ones(4)
    >>> A = np.diag([0.0, 1.0, 2.0, 3.0])
    >>> v = verify(lambda Y: A @ Y, m, np.array([0.0, 1.0]), np.eye(4)[:, :2], 1e-8, 0.01, 2.0)
    >>> v.passed.tolist(), float(v.orthogonality)
    ([True, True], 0.0)
    >>> twice = np.ones((4, 2)) / 2                   # a collapsed block: one vector twice
    >>> verify(lambda Y: A @ Y, m, np.array([1.5, 1.5]), twice, 1e-8, 0.01).passed.tolist()
    [False, False]
    """
    k = len(lam)
    mc = m[:, None]
    MX = mc * X
    G = allsum(_lobpcg.inner(X, MX))
    ortho = float(np.abs(G - np.eye(k)).max()) if k else 0.0
    R = apply_A(X) - MX * lam
    gram = allsum(_lobpcg.inner(R, R / mc))
    res = np.sqrt(np.maximum(np.diag(gram), 0.0))
    err = _lobpcg.eig_error(lam, res, gram, upper)  # no upper: the last cluster keeps Bauer–Fike's
    return Verdict(res, err / (tol * scales(lam, floor)), ortho)


def count_shift(lam: np.ndarray, k: int, floor: float, tol: float) -> tuple[float, int]:
    """The shift σ for the count and how many of the computed values ``lam`` (ascending, at
    least k) lie below it: halfway from λ_k's last tie to the first computed value that is not
    one, or beyond the ties where every computed value is one. A tie lies within ``_TIE`` of λ_k,
    or within twice what :func:`verify` lets a value be off (``tol · floor``), as two passing
    copies of one eigenvalue do (a part's zeros among them). Not ``_TIE`` times the floor: a
    mesh of slivers has a floor from roundoff far above its low eigenvalues, and every value in
    that window would cost a deflated rerun.

    Examples
    --------
    >>> s, j = count_shift(np.array([0.0, 0.0, 1e-12, 6.0]), 2, 0.01, 1e-8)   # λ_2's ties join
    >>> round(s, 6), j
    (3.0, 3)
    >>> count_shift(np.array([0.0, 2.0, 2.0015, 2.003]), 2, 0.01, 1e-8)   # σ above the last tie
    (2.00225, 3)
    >>> count_shift(np.array([0.0, 72.3, 89.7]), 2, 7e4, 1e-8)   # a floor from roundoff
    (81.0, 2)
    """
    top = float(lam[k - 1])
    tie = max(_TIE * abs(top), _yardstick(tol, floor))
    above = np.flatnonzero(lam[k:] > top + tie)
    if len(above):
        j = k + int(above[0])
        return 0.5 * (float(lam[j - 1]) + float(lam[j])), j
    # every computed value ties (no value above to halve the gap to): σ stands _TIE of the floor
    # clear too, where an LDLᵀ pivot's sign is safe from roundoff next to a cluster of zeros
    return top + max(tie, _TIE * floor), len(lam)


def count_ceiling(lam: np.ndarray, k: int, tol: float, floor: float) -> tuple[float, int] | None:
    """What a count makes of the Ritz values ``lam``: the shift σ it proves the values past the
    first j to lie above (:func:`count_shift`), the bound :func:`verify` then reads for the gap
    above λ_j's cluster; None where λ_k lies within the check's yardstick of 0 (the count's
    shift goes below 0 there) or every value ties.

    Examples
    --------
    >>> count_ceiling(np.array([0.0, 16.0, 16.0, 25.0]), 3, 1e-8, 0.01)   # halfway to 25
    (20.5, 3)
    """
    if float(lam[k - 1]) <= _yardstick(tol, floor):
        return None
    sigma, j = count_shift(lam, k, floor, tol)
    return (sigma, j) if j < len(lam) else None


def _yardstick(tol: float, floor: float) -> float:  # twice what verify lets a passing value be off
    return _TIE_CHECKS * max(tol, _EPS) * floor


def count_below(A: sp.spmatrix, m: np.ndarray, sigma: float, supernodal: bool = False,
                report: Any = None) -> int | None:
    """Eigenvalues of ``A x = λ diag(m) x`` below ``sigma`` (A symmetric, m > 0), from the signs
    of the pivots of a symmetric sparse factorization of ``A - σM`` (module notes); densely up to
    3,000 rows where neither factorization gives them; None beyond, or where A - σM is singular.
    ``supernodal``: :func:`meshlap._ldl.factor`'s; ``report(fraction, stage)``: progress.

    Examples
    --------
    >>> A = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(100, 100))
    >>> exact = 2 - 2 * np.cos(np.pi * np.arange(1, 101) / 101)
    >>> count_below(A, np.ones(100), 0.5), int((exact < 0.5).sum())
    (23, 23)
    """
    if report is not None:
        report(0.85, "inertia count")
    B = sp.csc_matrix(A - sp.diags(sigma * np.asarray(m, dtype=np.float64)))
    try:
        negative = _ldl.factor(B, supernodal).negative
    except RuntimeError:  # exactly singular: σ is an eigenvalue
        return None
    if negative is not None:
        return negative
    if B.shape[0] <= _DENSE_COUNT:
        w = lumped_eigh(sp.csr_matrix(A).toarray(), m, eigvals_only=True)
        return int((w < sigma).sum())
    return None


def lumped_eigh(A: np.ndarray, m: np.ndarray, subset: list[int] | None = None,
                eigvals_only: bool = False) -> Any:
    """``scipy.linalg.eigh(A, diag(m))`` without the n × n mass matrix: the pencil scaled by
    m^-1/2 on both sides (what LAPACK's reduction does with a diagonal B), ``A`` overwritten.

    Examples
    --------
    >>> lam, X = lumped_eigh(np.array([[2.0, -1.0], [-1.0, 2.0]]), np.array([1.0, 4.0]))
    >>> bool(np.allclose(X.T @ (np.array([1.0, 4.0])[:, None] * X), np.eye(2)))
    True
    """
    d = 1.0 / np.sqrt(np.asarray(m, dtype=np.float64))
    A *= d[:, None]
    A *= d[None, :]
    out = sla.eigh(A, subset_by_index=subset, eigvals_only=eigvals_only, overwrite_a=True)
    return out if eigvals_only else (out[0], d[:, None] * out[1])


class Attempt(NamedTuple):
    """One solver of the ladder: ``run(want)`` returns at least ``want`` eigenvalues (ascending,
    more where it computed them: guards, the next pair), their M-orthonormal vectors and its
    iterations; ``exact``: the lowest ones by construction (a dense solve), no count needed;
    ``when()``: whether it runs at all, asked when its turn comes (what the earlier ones found)."""

    name: str
    run: Callable[[int], tuple[np.ndarray, np.ndarray, int]]
    exact: bool = False
    when: Callable[[], bool] | None = None


def first_verified(attempts: list[Attempt], k: int, apply_A: Callable[[np.ndarray], np.ndarray],
                   m: np.ndarray, tol: float, floor: float,
                   counter: Callable[[float], int | None] | None = None, must_count: bool = False,
                   allsum=_lobpcg._local, info: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The k lowest pairs from the first attempt whose pairs all pass :func:`verify` (and, with
    ``counter(σ)`` — the eigenvalues below σ — whose count shows that none is missing).

    An attempt whose count exceeds its computed values below σ (it skipped some, or λ_k's
    cluster goes on past them) runs again, asked for that many. ``must_count``: an attempt that
    cannot be counted fails. Raises :class:`meshlap.EigenError` with the best attempt's pairs
    when none passes. ``info`` is filled with ``method``, ``tried``, ``iterations``, ``residuals``,
    ``bounds``, ``orthogonality``, ``count``, ``shift``, ``complete`` (a count, or the method,
    showed that the k values are the lowest) and ``check_seconds`` (the time of the checks).

    Examples
    --------
    >>> A = np.diag(np.arange(6.0))
    >>> bad = Attempt("bad", lambda w: (np.zeros(2), np.ones((6, 2)) / 6 ** 0.5, 9))
    >>> good = Attempt("good", lambda w: (np.arange(3.0), np.eye(6)[:, :3], 1))
    >>> info = {}
    >>> lam, _ = first_verified([bad, good], 2, lambda Y: A @ Y, np.ones(6), 1e-8, 0.01,
    ...                         lambda s: int((np.arange(6.0) < s).sum()), info=info)
    >>> lam.tolist(), info["tried"], info["count"], info["complete"]
    ([0.0, 1.0], ['bad', 'good'], 2, True)
    """
    from .errors import EigenError

    want, tried, best, spent, seen, known, again = k, [], None, 0.0, 0, None, None
    below: dict[str, int] = {}  # each solver's most values below the count's shift so far
    queue = list(attempts)
    while queue:
        attempt = queue.pop(0)
        if attempt.when is not None and not attempt.when():
            continue
        tried.append(attempt.name)
        try:
            lam, X, iterations = attempt.run(want)
        except EigenError:
            if again is None or again[0] is not attempt:
                raise
            lam, X, iterations = again[1]  # the run asked for λ_k's cluster whole did not converge
        again = None
        count = shift = None
        upper = float(lam[k]) if len(lam) > k else None
        proven = False
        j = k
        began = time.perf_counter()
        low = counter is not None and not attempt.exact and float(lam[k - 1]) <= _yardstick(tol, floor)
        if low:
            # λ_k lies within the check's yardstick of 0, where no shift separates values the check
            # cannot tell apart (chasing their ties could run to n); every eigenvalue of the
            # pencil is above a shift below 0 that counts none, and then the k values are the
            # lowest to within that yardstick
            shift = -_yardstick(tol, floor)
            count, j = counter(shift), int((lam < shift).sum())
            if count is not None and count > j and below.get(attempt.name + " < 0", -1) < j:
                # values below 0 the solver did not return: once more, asked for them too
                want = len(lam) + count - j + 1
                queue.insert(0, attempt)
            below[attempt.name + " < 0"] = j
        elif counter is not None and not attempt.exact:
            shift, j = count_shift(lam, k, floor, tol)
            if j == len(lam) > max(seen, k):
                # λ_k's cluster runs past every computed value: a count here would only ask for
                # more (in 3-D it costs what the solve does), so the solver runs again first
                seen, want = len(lam), 2 * len(lam) - k + 1
                queue.insert(0, attempt)
                continue
            if known is not None and not ((lam > min(shift, known[0])) & (lam < max(shift, known[0]))).any():
                shift, count = known  # no computed value between the two shifts: the same count
            else:
                count = counter(shift)
            known = (shift, count)
            if count is not None and count > j and (count + 1 > want or j > below.get(attempt.name, j)):
                # more eigenvalues below σ than computed (skipped, or ties of λ_k past the
                # block): the same solver again, asked for all of them, for as long as each run
                # finds more (a deflated run finds what the last skipped: a 50-part mesh's 50
                # zeros came 19, then 40, then all)
                want = max(count, len(lam) + count - j) + 1  # room for the count - j it missed
                queue.insert(0, attempt)
            below[attempt.name] = max(j, below.get(attempt.name, 0))
            if count == j:
                upper, proven = shift, True  # proven: λ_{j+1} ≥ σ
        complete = attempt.exact or (count is not None and count == j)
        j = max(j, k) if low else j
        e = j
        if not (proven or low):
            # unproven: the values computed within the window of λ_k join its cluster, with their
            # residuals, and the gap above is to the first beyond it; where the cluster runs past
            # every computed value, the solver runs again, asked for more, then Bauer–Fike
            e = int(np.searchsorted(lam, lam[j - 1] + _lobpcg._WINDOW * abs(float(lam[j - 1])), side="right"))
            if e >= len(lam) and not seen:  # once: a cluster may run on for hundreds of values
                seen, want, again = len(lam), 2 * len(lam) - k + 1, (attempt, (lam, X, iterations))
                queue.insert(0, attempt)
                continue
            upper = float(lam[e]) if e < len(lam) else None
        verdict = verify(apply_A, m, lam[:e], X[:, :e], tol, floor, upper, allsum)
        verdict = Verdict(verdict.residuals[:j], verdict.bounds[:j], verdict.orthogonality)
        spent += time.perf_counter() - began
        ok = bool(verdict.passed.all()) and (complete or not (must_count or count is not None))
        record = dict(method=attempt.name, tried=list(tried), iterations=iterations,
                      residuals=verdict.residuals[:k], bounds=verdict.bounds[:k],
                      orthogonality=verdict.orthogonality, count=count, shift=shift, complete=complete,
                      check_seconds=spent)
        if best is None or verdict.passed[:k].sum() > best[2].passed[:k].sum():
            best = (lam[:k], X[:, :k], verdict, record)
        if ok:
            if info is not None:
                info.update(record)
            return lam[:k], X[:, :k]
    lam, X, verdict, record = best
    if info is not None:
        info.update(record, tried=list(tried))
    failed = int((~verdict.passed[:k]).sum())
    raise EigenError(
        f"eigs: no solver verified the {k} lowest eigenpairs (tried {', '.join(tried)}); the best "
        f"({record['method']}) has {failed} pair(s) failing, error bound up to "
        f"{float(np.max(verdict.bounds[:k])):.2g} × tol, |ΦᵀMΦ - I| = {verdict.orthogonality:.1g}, "
        f"count {record['count']} below σ = {record['shift']}",
        eigenvalues=lam, vectors=X, residuals=verdict.residuals[:k], bounds=verdict.bounds[:k],
        count=record["count"], shift=record["shift"], tried=tuple(tried))
