"""Figures of :func:`meshlap.corrections.rowchoice.choose_rows` over every MPI rank that
holds a share of the points (``comm`` None: the one process's own)."""

from __future__ import annotations

from typing import Any

import numpy as np


def _sum(comm: Any, x: float) -> float:
    # the sum of every rank's x
    return x if comm is None else float(comm.allreduce(x))


def _min(comm: Any, x: float) -> float:
    # the least of every rank's x
    return x if comm is None else float(min(comm.allgather(x)))


def _median(comm: Any, values: np.ndarray) -> float | None:
    # the median over every rank's values (None when there are none)
    if comm is not None:
        values = np.concatenate(comm.allgather(np.asarray(values, dtype=np.float64)))
    return float(np.median(values)) if len(values) else None


def _bounds(comm: Any, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    # the corners of the box that holds every rank's points
    d = P.shape[1]
    lo = P.min(axis=0) if len(P) else np.full(d, np.inf)
    hi = P.max(axis=0) if len(P) else np.full(d, -np.inf)
    if comm is not None:
        from mpi4py import MPI

        glo, ghi = np.empty(d), np.empty(d)
        comm.Allreduce(np.ascontiguousarray(lo, dtype=np.float64), glo, op=MPI.MIN)
        comm.Allreduce(np.ascontiguousarray(hi, dtype=np.float64), ghi, op=MPI.MAX)
        lo, hi = glo, ghi
    return lo, hi
