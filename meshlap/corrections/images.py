"""Mirror images across the boundary: Neumann conditions for curves, surfaces and volumes alike.

On a half-space the heat kernel with natural (Neumann) boundary conditions is
K(x, y) + K(x, R y), R the reflection across the boundary. Near a boundary the kernel
operator therefore gains, for each pair (w, p) of points within the cut-off of it, the
weight of p's mirror image across the hyperplane through w's nearest boundary sample b with
the outward conormal ν there (:meth:`meshlap.geometry.Geometry.boundary_frames`). The pair
gets ½(K(|w − R_w p|) + K(|p − R_p w|)), which keeps S = M L symmetric, and the rows keep
summing to zero. One mechanism for every intrinsic dimension k: the frames say where the
boundary is, this module only reflects.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from .._jit import in_blocks, jit
from ..assembly._intrinsics import zero_row_sum
from ..assembly.variable import dog_factor
from ..geometry.frames import BoundaryFrames

__all__ = ["neumann_images"]


@jit()
def _image_rows(start, stop, indptr, indices, data, P, pos, bpt, nu, mass, hv, dogc,
                half_k):  # pragma: no cover
    d = P.shape[1]
    for w in range(start, stop):
        iw = pos[w]
        if iw < 0:
            continue
        for q in range(indptr[w], indptr[w + 1]):
            p = indices[q]
            if p == w:
                continue
            ip = pos[p]
            if ip >= 0:
                # an image only where the half-space picture holds: each point on the inner
                # side of the other's boundary hyperplane (across a small hole or a thin strip
                # it does not, and the image would fall inside the geometry)
                sp_ = 0.0
                sw_ = 0.0
                for c in range(d):
                    sp_ += (P[p, c] - bpt[iw, c]) * nu[iw, c]
                    sw_ += (P[w, c] - bpt[ip, c]) * nu[ip, c]
                if sp_ <= 0.0 and sw_ <= 0.0:
                    # |w − R_w p|² and |p − R_p w|², R the reflection across the hyperplane
                    d2w = 0.0
                    d2p = 0.0
                    for c in range(d):
                        rp = P[p, c] - 2.0 * sp_ * nu[iw, c]
                        rw = P[w, c] - 2.0 * sw_ * nu[ip, c]
                        d2w += (P[w, c] - rp) ** 2
                        d2p += (P[p, c] - rw) ** 2
                    hp = 0.5 * (hv[w] + hv[p])
                    ew = math.exp(-d2w / (4.0 * hp))
                    ep = math.exp(-d2p / (4.0 * hp))
                    if dogc != 0.0:
                        ew = ew * (dogc * ew - 1.0)
                        ep = ep * (dogc * ep - 1.0)
                    if half_k == 1.0:
                        norm = 1.0 / (4.0 * math.pi * hp * hp)
                    else:
                        norm = 1.0 / (hp * (4.0 * math.pi * hp) ** half_k)
                    data[q] += mass[p] * 0.5 * (ew + ep) * norm
        zero_row_sum(w, indptr, indices, data)  # rows keep summing to zero


def neumann_images(L: sp.csr_matrix, P: np.ndarray, frames: BoundaryFrames, mass: np.ndarray,
                   hv: np.ndarray, dog: bool, dim: int = 2) -> sp.csr_matrix:
    """L with the mirror images of the neighbours of every point near the boundary added.

    Parameters
    ----------
    L : scipy.sparse.csr_matrix
        The kernel operator (its pattern is kept: images only add to existing pairs).
    P : (n, d) ndarray
        Positions.
    frames : (band, b, ν) or None
        Points near the boundary, their nearest boundary sample and its outward conormal.
    mass, hv : (n,) ndarray
        Masses and per-point widths (pair width (h_w + h_p)/2).
    dog : bool
        Difference of Gaussians (the Richardson kernel) instead of one Gaussian.
    dim : int, default 2
        Intrinsic dimension k of the normalization 1/(h (4πh)^{k/2}).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.plane(600, seed=0)
    >>> g = meshlap.geometry.from_mesh(V, F)
    >>> op = meshlap.laplacian(V, F, h=0.01, correction="none")
    >>> L = neumann_images(op.L, V, g.boundary_frames(op.radius), g.mass, np.full(600, 0.01), False)
    >>> S = g.mass[:, None] * L.toarray()
    >>> bool(np.allclose(S, S.T)), bool(np.allclose(L @ np.ones(600), 0))
    (True, True)
    """
    if frames is None:
        return L
    band, bpt, nu = frames
    pos = np.full(len(P), -1, dtype=np.int64)
    pos[band] = np.arange(len(band))
    out = sp.csr_matrix(L, dtype=np.float64, copy=True)
    in_blocks(_image_rows, out.shape[0], out.indptr, out.indices, out.data,
              np.ascontiguousarray(P, dtype=np.float64), pos,
              np.ascontiguousarray(bpt, dtype=np.float64), np.ascontiguousarray(nu, dtype=np.float64),
              np.ascontiguousarray(mass, dtype=np.float64), np.ascontiguousarray(hv, dtype=np.float64),
              dog_factor(dim) if dog else 0.0, 0.5 * dim)
    return out if out.dtype == L.dtype else out.astype(L.dtype)
