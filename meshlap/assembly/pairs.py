"""The heat-kernel operator in any ambient dimension, from a k-d tree's list of close pairs.

The cell grid of :mod:`meshlap.assembly.grid` bins three coordinates; points in R^d with d > 3 (the
flat torus in R⁴, S³ ⊂ R⁴) take this path instead: scipy's ``cKDTree.query_pairs`` lists every
pair within the cut-off radius once, and both orientations of a pair pass the same exact
distance test, so S = M L is symmetric to the last bit as on the grid path.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from .grid import normalization
from .variable import dog_factor

__all__ = ["assemble", "assemble_variable", "count_entries"]


def assemble(X: np.ndarray, mass: np.ndarray, h: float, radius: float, dim: int,
             dtype=np.float64) -> sp.csr_matrix:
    """L = normalization(h, k) (K M − diag(K m)) for points X of any dimension, truncated at radius.

    Parameters
    ----------
    X : (n, d) ndarray
        Points.
    mass : (n,) ndarray
        Masses; points of mass 0 are never sources.
    h, radius : float
        Kernel width and cut-off radius (inf: every pair).
    dim : int
        Intrinsic dimension k of the normalization 1/(h (4πh)^{k/2}).

    Examples
    --------
    >>> import numpy as np
    >>> X = np.random.default_rng(0).normal(size=(50, 4))
    >>> L = assemble(X, np.ones(50), 0.5, 3.0, 4)
    >>> bool(abs(L.sum(axis=1)).max() < 1e-12), bool(abs(L - L.T).max() < 1e-15)
    (True, True)
    """
    n = len(X)
    if not np.isfinite(radius):
        radius = 2.0 * float(np.ptp(X, axis=0).max()) + 1.0
    i, j = _close_pairs(X, radius)
    d2 = np.zeros(len(i))
    for c in range(X.shape[1]):  # column by column: fast and the same rounding for (i, j) and (j, i)
        d2 += (X[i, c] - X[j, c]) ** 2
    # the exact test on both orientations alike keeps S symmetric to the last bit
    keep = (d2 <= radius * radius) & (mass[j] > 0)
    i, j, d2 = i[keep], j[keep], d2[keep]
    w = normalization(h, dim) * mass[j] * np.exp(-d2 / (4.0 * h))
    off = sp.csr_matrix((w, (i, j)), shape=(n, n))
    L = off - sp.diags(np.asarray(off.sum(axis=1)).ravel())
    return sp.csr_matrix(L, dtype=dtype)


def count_entries(X: np.ndarray, radius: float) -> int:
    """Entries L will store (each point's neighbours within the radius, itself included),
    counted without listing them, so that a memory guard can run first.

    Examples
    --------
    >>> import numpy as np
    >>> count_entries(np.array([[0.0, 0, 0, 0], [0.1, 0, 0, 0], [5, 0, 0, 0]]), 1.0)
    5
    """
    tree = cKDTree(X)
    return int(tree.count_neighbors(tree, radius * (1.0 + 1e-7))) if np.isfinite(radius) else len(X) ** 2


def _close_pairs(X: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    # both orientations of every pair within the radius
    pairs = cKDTree(X).query_pairs(radius * (1.0 + 1e-7), output_type="ndarray")
    return np.concatenate([pairs[:, 0], pairs[:, 1]]), np.concatenate([pairs[:, 1], pairs[:, 0]])


def assemble_variable(X: np.ndarray, mass: np.ndarray, hv: np.ndarray, tol: float, dim: int,
                      dog: bool, normals: np.ndarray | None = None, dtype=np.float64) -> sp.csr_matrix:
    """The corrected kernel of :func:`meshlap.assembly.variable.variable_csr` in any dimension:
    per-point widths (pair width (h_w + h_p)/2), the difference of Gaussians when ``dog``,
    and d² scaled by the squared arc/chord ratio of the pair's unit ``normals`` when given.

    Examples
    --------
    >>> import numpy as np
    >>> X = np.random.default_rng(0).normal(size=(60, 4))
    >>> L = assemble_variable(X, np.ones(60), np.full(60, 0.5), 1e-8, 4, True)
    >>> bool(abs(L.sum(axis=1)).max() < 1e-12), bool(abs(L - L.T).max() < 1e-13)
    (True, True)
    """
    n = len(X)
    lnt4 = math.inf if tol == 0 else 4.0 * math.log(1.0 / tol)
    if math.isfinite(lnt4):
        radius = math.sqrt(lnt4 * float(hv.max()))
    else:
        radius = 2.0 * float(np.ptp(X, axis=0).max()) + 1.0
    i, j = _close_pairs(X, radius)
    d2 = np.zeros(len(i))
    for c in range(X.shape[1]):
        d2 += (X[i, c] - X[j, c]) ** 2
    if normals is not None:
        cos = np.clip((normals[i] * normals[j]).sum(axis=1), -1.0, 1.0)
        s = np.sqrt(np.clip(0.5 * (1.0 - cos), 0.0, 1.0))
        q = np.where(s > 1e-8, np.arcsin(s) / np.maximum(s, 1e-300), 1.0)
        d2 = d2 * q * q
    hp = 0.5 * (hv[i] + hv[j])
    keep = (d2 <= lnt4 * hp) & (mass[j] > 0)
    i, j, d2, hp = i[keep], j[keep], d2[keep], hp[keep]
    e = np.exp(-d2 / (4.0 * hp))
    kern = e * (dog_factor(dim) * e - 1.0) if dog else e
    w = mass[j] * kern / (hp * (4.0 * math.pi * hp) ** (0.5 * dim))
    off = sp.csr_matrix((w, (i, j)), shape=(n, n))
    L = off - sp.diags(np.asarray(off.sum(axis=1)).ravel())
    return sp.csr_matrix(L, dtype=dtype)
