"""Eigenpairs of a sparse pencil whose graph falls into connected parts, solved part by part
where :func:`meshlap.spectral.eigs` cannot verify the whole.

The parts share no entry of S or M, so the pencil's spectrum is the union of theirs, and an
eigenvector of a part, zero elsewhere, is one of the whole. Solved together, each part's scale
still enters every solve: a part 10⁻⁵ the size of another has its first nonzero eigenvalue
10¹⁰ times higher, and its zero mode, resolved to the other part's yardstick, asks for more
digits than a shift-invert solve whose matrix has a condition number of 10¹³ there keeps
(measured: a unit sphere beside one of radius 10⁻⁵ raised EigenError; 10⁻⁴ passed). Alone,
each part is solved and checked at its own scale. The k lowest of the whole are among each
part's k lowest, so each part is asked for k pairs (all of its own where it has no more than
k + 1 rows, densely) and the merged k lowest are returned. It is the fallback, where the whole's
check fails or roundoff leaves it uncertified (:func:`meshlap._eigcheck.uncertified`), not the
first try: 50 solves cost more than one (the corpus's 50-part truck: 0.14-0.16 s whole, 0.75-0.86 s
by part; ``benchmarks/bench_degenerate.py``).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ._eigcheck import lumped_eigh
from .errors import MeshWarning, user_stacklevel
from .lumped import SparseLaplacian

__all__ = ["by_part", "part_labels"]

# rows summing to zero up to this relative roundoff have the constant as an exact null vector
_NULL = 1e3 * float(np.finfo(np.float64).eps)


def part_labels(S: sp.spmatrix) -> tuple[int, np.ndarray]:
    """The connected parts of the graph of S's off-diagonal entries: their number and each
    row's part.

    Examples
    --------
    >>> S = sp.block_diag([-np.array([[1.0, -1.0], [-1.0, 1.0]])] * 2).tocsr()
    >>> n, label = part_labels(S)
    >>> n, label.tolist()
    (2, [0, 0, 1, 1])
    """
    return connected_components(sp.csr_matrix(S), directed=False)


def by_part(S: sp.csr_matrix, labels: np.ndarray, m: np.ndarray, k: int,
            solve: Callable[..., tuple[np.ndarray, np.ndarray]], info: dict | None = None
            ) -> tuple[np.ndarray, np.ndarray]:
    """The k smallest eigenpairs of ``-S φ = λ diag(m) φ`` from those of each part (``labels``,
    :func:`part_labels`').

    ``solve(pencil, k, info=info_p)`` returns the k smallest pairs of a part's pencil (a
    :class:`~meshlap.lumped.SparseLaplacian`; verified, M-orthonormal) and fills ``info_p``
    (:func:`meshlap.spectral.eigs`); parts of at most k + 1 rows are solved here, densely and
    whole. ``info`` gets ``parts``, ``method`` and ``tried`` (those of the parts),
    ``iterations`` (their sum), ``residuals`` and ``bounds`` of the returned pairs (each from its
    part), ``orthogonality`` (the largest), ``count`` (the parts' counts summed, or None),
    ``shift`` (None: each part has its own), ``complete`` (every part's) and ``uncertified``
    (the largest).

    Examples
    --------
    >>> A = sp.block_diag([np.array([[1.0, -1.0], [-1.0, 1.0]]), 1e6 * np.array([[1.0, -1.0], [-1.0, 1.0]])])
    >>> S, m = -A.tocsr(), np.ones(4)
    >>> lam, X = by_part(S, part_labels(S)[1], m, 3, lambda *a, **kw: None)
    >>> lam.round(6).tolist()
    [0.0, 0.0, 2.0]
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        lam, X = _merged(S, labels, m, k, solve, info)
    _rewarn(caught, int(labels.max()) + 1)
    return lam, X


def _rewarn(caught: list[warnings.WarningMessage], n_parts: int) -> None:
    # one MeshWarning for the parts that warned (50 parts could give 50), the others as they came
    mesh = [w for w in caught if issubclass(w.category, MeshWarning)]
    for w in caught:
        if w not in mesh:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if mesh:
        warnings.warn(f"eigs, solved part by part: {len(mesh)} warning(s) from the {n_parts} parts; "
                      f"the first: {mesh[0].message}", MeshWarning, stacklevel=user_stacklevel())


def _merged(S: sp.csr_matrix, labels: np.ndarray, m: np.ndarray, k: int,
            solve: Callable[..., tuple[np.ndarray, np.ndarray]], info: dict | None
            ) -> tuple[np.ndarray, np.ndarray]:
    cols: list[tuple[float, int, int]] = []  # (λ, part, column)
    parts: list[tuple[np.ndarray, np.ndarray, np.ndarray, dict]] = []
    for p in range(int(labels.max()) + 1):
        rows = np.flatnonzero(labels == p)
        S_p, m_p = S[rows][:, rows], m[rows]
        record: dict = {}
        if len(rows) <= k + 1:
            A = -0.5 * (S_p + S_p.T).toarray()
            lam, X = lumped_eigh(A, m_p)
            record = dict(method="dense", tried=["dense"], iterations=0, complete=True, uncertified=0.0,
                          residuals=np.zeros(len(lam)), bounds=np.zeros(len(lam)), orthogonality=0.0,
                          count=len(lam))
        else:
            lam, X = solve(SparseLaplacian(sp.diags(1.0 / m_p) @ S_p, m_p, S=S_p), k, info=record)
        if abs(S_p @ np.ones(len(rows))).max() <= _NULL * abs(S_p).max():
            # rows summing to zero: the constant is the part's exact null vector, λ = 0 the lowest
            # (S is negative semidefinite), where the solve has roundoff of the part's own scale
            lam[0], X[:, 0] = 0.0, 1.0 / np.sqrt(m_p.sum())
        parts.append((rows, lam, X, record))
        cols.extend((float(v), p, j) for j, v in enumerate(lam))
    chosen = sorted(cols)[:k]
    lam = np.array([c[0] for c in chosen])
    X = np.zeros((len(m), k))
    for i, (_, p, j) in enumerate(chosen):
        rows, _, Xp, _ = parts[p]
        X[rows, i] = Xp[:, j]
    if info is not None:
        records = [r for *_, r in parts]
        counts = [r.get("count") for r in records]
        info.update(
            parts=len(parts), method=", ".join(sorted({r["method"] for r in records})),
            tried=sorted({t for r in records for t in r.get("tried", [])}),
            iterations=int(sum(r.get("iterations") or 0 for r in records)),
            residuals=np.array([np.asarray(parts[p][3]["residuals"])[j] for _, p, j in chosen]),
            bounds=np.array([np.asarray(parts[p][3]["bounds"])[j] for _, p, j in chosen]),
            orthogonality=max(float(r.get("orthogonality", 0.0)) for r in records),
            count=None if None in counts else int(sum(counts)), shift=None,
            complete=all(r.get("complete", False) for r in records),
            uncertified=max(float(r.get("uncertified", 0.0)) for r in records))
    return lam, X
