"""Eigenpairs of a sparse pencil whose graph falls into connected parts, solved part by part.

The parts share no entry of S or M, so the pencil's spectrum is the union of theirs, and an
eigenvector of a part, zero elsewhere, is one of the whole. Solved together, each part's scale
still enters every solve: a part 10⁻⁵ the size of another has its first nonzero eigenvalue
10¹⁰ times higher, and its zero mode, resolved to the other part's yardstick, asks for more
digits than a shift-invert solve whose matrix has a condition number of 10¹³ there keeps
(measured: a unit sphere beside one of radius 10⁻⁵ raised EigenError; 10⁻⁴ passed). And parts
alike (the gears and screws of an assembly) give the whole every eigenvalue once per copy,
clusters that a Lanczos solve resolves slowly and its count check rejects (the corpus's gears,
7 parts: 4.1 s whole, 0.5 s part by part; ``benchmarks/bench_degenerate.py``).
Alone, each part is solved and checked at its own scale.

The k lowest of the whole are among each part's k lowest, but most parts hold few of them. By
Weyl's law a part's share of the eigenvalues below a value is its share of the measure, so each
part is first asked for twice its share of k and two more, and asked again for twice as many
wherever the merge shows that it could hold more (its highest below the k-th of all), up to k.
Parts of at most k + 1 rows are solved densely and whole.
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
            solve: Callable[..., tuple[np.ndarray, np.ndarray]], info: dict | None = None,
            report: Callable[[float, str], None] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The k smallest eigenpairs of ``-S φ = λ diag(m) φ`` from those of each part (``labels``,
    :func:`part_labels`').

    ``solve(pencil, j, info=info_p)`` returns the j smallest pairs of a part's pencil (a
    :class:`~meshlap.lumped.SparseLaplacian`; verified, M-orthonormal) and fills ``info_p``
    (:func:`meshlap.spectral.eigs`), j ≤ k as many as the part could hold (module notes); parts
    of at most k + 1 rows are solved here, densely and whole. ``report(fraction, stage)``, if
    given, hears of each part's solve. ``info`` gets ``parts``, ``method`` and ``tried`` (those of the parts),
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
        lam, X = _merged(S, labels, m, k, solve, info, report)
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
            solve: Callable[..., tuple[np.ndarray, np.ndarray]], info: dict | None,
            report: Callable[[float, str], None] | None) -> tuple[np.ndarray, np.ndarray]:
    n_parts = int(labels.max()) + 1
    order = np.argsort(labels, kind="stable")
    bounds = np.searchsorted(labels[order], np.arange(n_parts + 1))
    S = sp.csr_matrix(S)[order][:, order]  # each part a diagonal block
    # Weyl's law: a part's share of the k lowest is about its share of the measure. Each part is
    # asked for twice that and two more, then for twice as many wherever the merge shows that
    # it could hold more of the k lowest (its highest below the k-th of all), up to k
    share = np.add.reduceat(m[order], bounds[:-1]) / m.sum()
    # copies of one part differ in area by roundoff: the same share, the same want
    want = np.minimum(k, np.ceil(2 * k * share * (1 - 1e-12)).astype(np.int64) + 2)
    parts: list[tuple[np.ndarray, np.ndarray, np.ndarray, dict, bool]] = [None] * n_parts  # type: ignore[list-item]
    todo = list(range(n_parts))
    while todo:
        for i, p in enumerate(todo):
            if report is not None:
                report(i / len(todo), f"part {p + 1} of {n_parts}")
            parts[p] = _part(S, order[bounds[p]:bounds[p + 1]], slice(bounds[p], bounds[p + 1]), m,
                             int(want[p]), k, solve)
        kth = np.sort(np.concatenate([part[1] for part in parts]))[:k][-1]
        todo = [p for p, (_, lam, _, _, every) in enumerate(parts) if not every and lam[-1] < kth]
        want[todo] = np.minimum(k, 2 * want[todo])
    cols = [(float(v), p, j) for p, part in enumerate(parts) for j, v in enumerate(part[1])]
    chosen = sorted(cols)[:k]
    lam = np.array([c[0] for c in chosen])
    X = np.zeros((len(m), k))
    for i, (_, p, j) in enumerate(chosen):
        rows, _, Xp, _, _ = parts[p]
        X[rows, i] = Xp[:, j]
    if info is not None:
        records = [part[3] for part in parts]
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


def _part(S: sp.csr_matrix, rows: np.ndarray, block: slice, m: np.ndarray, want: int, k: int,
          solve: Callable[..., tuple[np.ndarray, np.ndarray]]
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict, bool]:
    """A part's ``want`` lowest pairs: ``(rows, λ, X, record, every)``, ``every`` where no other
    of its pairs can be among the k lowest of the whole (all of them, or k)."""
    S_p, m_p = S[block, block], m[rows]
    if len(rows) <= k + 1:
        A = -0.5 * (S_p + S_p.T).toarray()
        lam, X = lumped_eigh(A, m_p)
        record = dict(method="dense", tried=["dense"], iterations=0, complete=True, uncertified=0.0,
                      residuals=np.zeros(len(lam)), bounds=np.zeros(len(lam)), orthogonality=0.0,
                      count=len(lam))
    else:
        record = {}
        lam, X = solve(SparseLaplacian(sp.diags(1.0 / m_p) @ S_p, m_p, S=S_p), want, info=record)
    if abs(S_p @ np.ones(len(rows))).max() <= _NULL * abs(S_p).max():
        # rows summing to zero: the constant is the part's exact null vector, λ = 0 the lowest
        # (S is negative semidefinite), where the solve has roundoff of the part's own scale
        lam[0], X[:, 0] = 0.0, 1.0 / np.sqrt(m_p.sum())
    return rows, lam, X, record, len(lam) >= min(k, len(rows))
