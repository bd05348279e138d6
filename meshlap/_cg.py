"""Preconditioned conjugate gradients on a block of right-hand sides, each column its own
iteration: the one CG behind implicit heat steps, Poisson solves and the denoising step."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["block_pcg"]


def block_pcg(apply: Callable[[np.ndarray], np.ndarray], precondition: Callable[[np.ndarray], np.ndarray],
              B: np.ndarray, rtol: float, maxiter: int, X: np.ndarray | None = None, *,
              give_up: Callable[[int, float], bool] | None = None) -> tuple[np.ndarray, int, bool]:
    """Solve A X = B (A symmetric positive definite, or semidefinite with B in its range) from
    ``X`` (zero if not given; overwritten), every column until its residual is within ``rtol``
    of its right-hand side; ``give_up(iteration, worst residual over its goal)`` True stops it
    unconverged (:class:`meshlap._multigrid.Stall`).

    Returns
    -------
    X : ndarray
        The solution.
    iterations : int
        Iterations of the slowest column.
    converged : bool
        Whether every column reached ``rtol`` within ``maxiter``.

    Examples
    --------
    >>> A = np.array([[4.0, 1.0], [1.0, 3.0]])
    >>> X, it, ok = block_pcg(lambda V: A @ V, lambda R: R / np.diag(A)[:, None], np.eye(2), 1e-12, 10)
    >>> bool(np.allclose(X, np.linalg.inv(A))), ok
    (True, True)
    """
    X = np.zeros_like(B) if X is None else X
    R = B - apply(X) if X.any() else B.copy()
    goal = rtol * np.maximum(np.linalg.norm(B, axis=0), 1e-300)
    Z = precondition(R)
    D = Z.copy()
    rz = np.sum(R * Z, axis=0)
    it = 0
    while True:
        ratio = np.linalg.norm(R, axis=0) / goal
        active = ratio > 1.0
        if not active.any():
            return X, it, True
        if it == maxiter or (give_up is not None and give_up(it, float(ratio.max()))):
            return X, it, False
        it += 1
        AD = apply(D[:, active])
        alpha = rz[active] / np.sum(D[:, active] * AD, axis=0)
        X[:, active] += alpha * D[:, active]
        R[:, active] -= alpha * AD
        Z = precondition(R[:, active])
        rz_new = np.sum(R[:, active] * Z, axis=0)
        D[:, active] = Z + (rz_new / rz[active]) * D[:, active]
        rz[active] = rz_new
