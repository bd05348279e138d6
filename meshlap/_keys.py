"""Sets of integer keys (edges and triangles coded as one int64) by sorting.

numpy 2.4's ``np.unique`` without counts hashes, and ``np.isin`` on keys spanning more than a
small range compares in unsorted order: on 2.7 million edge keys of a 100,000-point cloud
0.46-1.6 s and 1.3-1.8 s against 0.05 s and 0.1 s for a sort and a sorted search (by hand;
`benchmarks/bench_pointcloud.py --timing` times the whole build).
"""

from __future__ import annotations

import numpy as np

__all__ = ["in_set", "key_set"]


def key_set(keys: np.ndarray) -> np.ndarray:
    """The distinct ``keys``, sorted (``np.unique(keys)``).

    >>> key_set(np.array([5, 1, 5, 3, 1]))
    array([1, 3, 5])
    """
    keys = np.sort(np.asarray(keys).ravel())
    return keys[np.concatenate(([True], keys[1:] != keys[:-1]))] if len(keys) else keys


def in_set(keys: np.ndarray, of: np.ndarray, *, of_sorted: bool = False) -> np.ndarray:
    """Which ``keys`` are among ``of`` (``np.isin(keys, of)``); ``of_sorted``: ``of`` is sorted.

    >>> in_set(np.array([4, 1, 7, 1]), np.array([7, 1, 2]))
    array([False,  True,  True,  True])
    """
    keys = np.asarray(keys).ravel()
    if not len(keys) or not len(of):
        return np.zeros(len(keys), dtype=bool)
    of = np.asarray(of).ravel() if of_sorted else np.sort(np.asarray(of).ravel())
    order = np.argsort(keys)  # a sorted search walks ``of`` once
    at = np.minimum(np.searchsorted(of, keys[order]), len(of) - 1)
    found = np.empty(len(keys), dtype=bool)
    found[order] = of[at] == keys[order]
    return found
