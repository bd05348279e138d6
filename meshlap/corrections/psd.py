"""The semidefiniteness check of the corrected operator.

The difference of Gaussians has negative weights, so −S = −M L positive semidefinite is not
automatic: on a geometry too coarse for the narrow kernel h/2 it fails, and spectra and heat
flow would blow up. :func:`check` finds the smallest eigenvalue of the pencil (−S, M) and
compares it with the operator's scale.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import scipy.sparse as sp

from ..geometry import Polygons
from ..lumped import SparseLaplacian

__all__ = ["PSD_RTOL", "check", "smallest_eigenvalue"]

# points up to which a failed iterative check is repeated with a dense eigensolver
_DENSE_MAX = 4000
#: −S counts as semidefinite when λ_min ≥ −PSD_RTOL · max_w(−L_ww).
PSD_RTOL = 1e-6


def smallest_eigenvalue(L: sp.csr_matrix, mass: np.ndarray, V: np.ndarray, faces: Polygons | None,
                        tol: float = 1e-4) -> tuple[float, float]:
    """The two ends that decide whether −S = −M L is positive semidefinite.

    Returns (λ_min, λ_scale): the smallest eigenvalue of the pencil (−S, M) on the points
    with mass, from :func:`meshlap.spectral.eigs` (LOBPCG, cotangent preconditioner when
    ``faces`` are triangles in R³, a few vectors), and the scale ``max_w −L_ww`` it is to be
    compared with. A negative mode of the difference of Gaussians lives at high frequency;
    LOBPCG minimizes the Rayleigh quotient over the whole space, so it finds such a mode if
    there is one.
    """
    from ..spectral import eigs  # the uses sit above the corrections; only this check needs one

    op = SparseLaplacian(L, mass)
    n = int((mass > 0).sum())
    scale = float(np.max(-L.diagonal()))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        try:
            lam, _ = eigs(op, 2, tol=tol, maxiter=60, mesh=None if faces is None else (V, faces),
                          method="lobpcg" if n > 1200 else "dense")
        except np.linalg.LinAlgError:
            # LOBPCG's Gram matrices break down on a strongly indefinite pencil: decide densely
            # where that is affordable, else count it as failed (the plain kernel is safe)
            if n > _DENSE_MAX:
                return -math.inf, scale
            lam, _ = eigs(op, 2, method="dense")
    return float(lam.min()), scale


def check(L: sp.csr_matrix, mass: np.ndarray, V: np.ndarray, faces: Polygons | None,
          what: str) -> tuple[float, str | None]:
    """``(margin, reason)``: λ_min/scale, and why the operator fails (None when it passes).

    Examples
    --------
    >>> import meshlap
    >>> V, F = meshlap.shapes.sphere(800, seed=0)
    >>> op = meshlap.laplacian(V, F, correction="none")
    >>> margin, reason = check(op.L, op.mass, V, op.faces, "mesh")
    >>> reason is None
    True
    """
    lam_min, scale = smallest_eigenvalue(L, mass, V, faces)
    if lam_min < -PSD_RTOL * scale:
        return lam_min / scale, (
            f"the Richardson operator is not negative semidefinite here (eigenvalue {lam_min:.3g} of "
            f"-S against the scale {scale:.3g}): h is too small for the {what} to resolve the narrow "
            f"kernel h/2; using the plain kernel (O(h) bias)")
    return lam_min / scale, None
