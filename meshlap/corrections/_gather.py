"""The candidates' rows of :func:`meshlap.corrections.rowchoice.choose_rows` gathered: a
candidate's stencils read from one table of nearest neighbours, a fit's figures at some of its
centres, and the rows chosen, one candidate's or another's at each point, in one matrix."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ._fit_kernel import copy_rows
from .highorder import RowFit


def _table(idx: np.ndarray, dist: np.ndarray, ranks: list[int] | None = None) -> tuple:
    # (idx, kth) for _candidate: kth(K) the K-th nearest's distances, from dist's columns (those
    # of the ranks given, or all)
    where = {r: i for i, r in enumerate(ranks)} if ranks is not None else None
    return idx, (lambda K: dist[:, K - 1]) if where is None else (lambda K: dist[:, where[K - 1]])


def _restrict(fit: RowFit, rows: np.ndarray) -> RowFit:
    # the fit's rows at these centres (its matrix keeps the others, which no pick refers to)
    pos = np.searchsorted(fit.centers, rows)
    return RowFit(fit.matrix, rows, *(getattr(fit, name)[pos] for name in
                                      ("degree", "residual", "amplification", "probes", "curvature", "h")))


def _assemble(n: int, pick: np.ndarray, local: list, refit: dict) -> sp.csr_matrix:
    # the chosen rows gathered from their candidates' CSR arrays, without a sort through COO;
    # a candidate of every row chosen everywhere is the matrix itself (at 400,000 clean points
    # 250 MB neither written nor copied). A candidate measured only (its matrix None) fits the
    # rows chosen of it again: refit[id(fit)](rows)
    def rows_of(fit: RowFit, rows: np.ndarray) -> sp.csr_matrix:
        return fit.matrix if fit.matrix is not None else refit[id(fit)](rows).matrix

    if n and pick[0] >= 0 and len(local[pick[0]][0].centers) == n and (pick == pick[0]).all():
        return rows_of(local[pick[0]][0], np.arange(n))
    counts = np.zeros(n, dtype=np.int64)
    chosen = []
    for i, (fit, _) in enumerate(local):
        rows = np.flatnonzero(pick == i)
        if len(rows):
            M = rows_of(fit, rows)
            counts[rows] = M.indptr[rows + 1] - M.indptr[rows]
            chosen.append((rows, M))
    total = int(counts.sum())
    # 32-bit indices where they fit (12 bytes an entry, as the kernel's rows)
    index = np.int32 if max(n, total) < np.iinfo(np.int32).max else np.int64
    indptr = np.zeros(n + 1, dtype=index)
    np.cumsum(counts, out=indptr[1:])
    data = np.empty(total)
    indices = np.empty(total, dtype=index)
    for rows, M in chosen:
        copy_rows(rows, M.indptr, M.indices, M.data, indptr, indices, data)
    L = sp.csr_matrix((n, n))  # consistent by construction: no check, no copy
    L.data, L.indices, L.indptr = data, indices, indptr
    return L
