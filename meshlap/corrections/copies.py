"""Point-wise rows fitted on distinct points, given to their coincident copies.

An unwelded seam or a pole repeated once per segment puts copies of one point into the rows'
neighbourhoods: with as many copies as a row has neighbours, its last one lies at distance 0
and the row has no width. So the rows are fitted on the distinct points; a copy takes its
point's row, and a point's column is shared by its copies (f averaged over them), so that
constants still map to 0.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.sparse as sp

__all__ = ["distinct_rows", "on_copies", "take"]


def on_copies(L: sp.csr_matrix, choice: Any, index: np.ndarray) -> tuple[sp.csr_matrix, Any]:
    """Rows ``L`` over distinct points, and their per-point ``choice`` (a dataclass of arrays, or None),
    given to every point: point i takes the row of distinct point ``index[i]``; each distinct
    point's column is split equally among its copies.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> L = sp.csr_matrix(np.array([[-1.0, 1.0], [1.0, -1.0]]))
    >>> L3, _ = on_copies(L, None, np.array([0, 1, 1]))  # point 2 is a copy of point 1
    >>> L3.toarray().tolist()
    [[-1.0, 0.5, 0.5], [1.0, -0.5, -0.5], [1.0, -0.5, -0.5]]
    """
    n = len(index)
    share = 1.0 / np.bincount(index)[index]
    spread = sp.csr_matrix((share, (index, np.arange(n))), shape=(L.shape[1], n))
    return sp.csr_matrix(L[index] @ spread), take(choice, index)


def take(choice: Any, index: np.ndarray) -> Any:
    """``choice`` (a dataclass of per-point arrays, or None) at the points ``index``.

    Examples
    --------
    >>> import numpy as np
    >>> from dataclasses import dataclass
    >>> @dataclass
    ... class Per:
    ...     h: np.ndarray
    ...     note: str = "kept"
    >>> take(Per(np.array([1.0, 2.0])), np.array([1, 1, 0]))
    Per(h=array([2., 2., 1.]), note='kept')
    """
    if choice is None:
        return None
    values = {f.name: getattr(choice, f.name) for f in dataclasses.fields(choice)}
    return dataclasses.replace(choice, **{name: v[index] for name, v in values.items()
                                          if isinstance(v, np.ndarray)})


def distinct_rows(make: Callable[[np.ndarray], tuple[sp.csr_matrix, Any]], rep: np.ndarray | None
                  ) -> tuple[sp.csr_matrix, Any]:
    """``make(distinct)``: rows (and a per-point choice) over the points ``distinct``, given
    to every point; ``rep`` each point's representative among its copies (None: no copies).

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> L = sp.csr_matrix(np.array([[-1.0, 1.0], [1.0, -1.0]]))
    >>> L3, _ = distinct_rows(lambda d: (L, None), np.array([0, 1, 1]))
    >>> L3.toarray().tolist()
    [[-1.0, 0.5, 0.5], [1.0, -0.5, -0.5], [1.0, -0.5, -0.5]]
    """
    if rep is None:
        return make(slice(None))
    distinct = np.flatnonzero(rep == np.arange(len(rep)))
    return on_copies(*make(distinct), np.searchsorted(distinct, rep))
