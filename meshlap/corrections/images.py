"""Mirror images across the boundary: Neumann conditions for curves, surfaces and volumes alike.

On a half-space the heat kernel with natural (Neumann) boundary conditions is
K(x, y) + K(x, R y), R the reflection across the boundary. Near a boundary the kernel
operator therefore gains, for each pair (w, p) of points within the cut-off of it, the
weight of p's mirror image across the hyperplane through w's nearest boundary sample b with
the outward conormal ν there (:meth:`meshlap.geometry.Geometry.boundary_frames`). The pair
gets ½(K(|w − R_w p|) + K(|p − R_p w|)), which keeps S = M L symmetric, and the rows keep
summing to zero. One mechanism for every intrinsic dimension k: the frames say where the
boundary is, this module only reflects. A matrix-free pencil adds the images alone
(:func:`band_images`, pairs of the band only) to the kernel it recomputes.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from .._jit import in_blocks, jit
from ..assembly._intrinsics import zero_row_sum
from ..assembly.grid import normalization
from ..assembly.variable import dog_factor
from ..geometry.frames import BoundaryFrames

__all__ = ["band_images", "neumann_images"]


@jit(inline="always")
def _pair_image(P, w, p, bpt, nu, iw, ip, hp, dogc):  # pragma: no cover
    """½(K(|w − R_w p|) + K(|p − R_p w|)) without the normalization, R the reflection across
    the hyperplane of each one's boundary sample; 0 where the half-space picture fails: each
    point must lie on the inner side of the other's hyperplane (across a small hole or a thin
    strip it does not, and the image would fall inside the geometry)."""
    d = P.shape[1]
    sp_ = 0.0
    sw_ = 0.0
    for c in range(d):
        sp_ += (P[p, c] - bpt[iw, c]) * nu[iw, c]
        sw_ += (P[w, c] - bpt[ip, c]) * nu[ip, c]
    if sp_ > 0.0 or sw_ > 0.0:
        return 0.0
    d2w = 0.0
    d2p = 0.0
    for c in range(d):
        rp = P[p, c] - 2.0 * sp_ * nu[iw, c]
        rw = P[w, c] - 2.0 * sw_ * nu[ip, c]
        d2w += (P[w, c] - rp) ** 2
        d2p += (P[p, c] - rw) ** 2
    ew = math.exp(-d2w / (4.0 * hp))
    ep = math.exp(-d2p / (4.0 * hp))
    if dogc != 0.0:
        ew = ew * (dogc * ew - 1.0)
        ep = ep * (dogc * ep - 1.0)
    return 0.5 * (ew + ep)


@jit(inline="always")
def _norm(hp, half_k):  # pragma: no cover
    if half_k == 1.0:
        return 1.0 / (4.0 * math.pi * hp * hp)
    return 1.0 / (hp * (4.0 * math.pi * hp) ** half_k)


@jit()
def _image_rows(start, stop, indptr, indices, data, P, pos, bpt, nu, mass, hv, dogc,
                half_k):  # pragma: no cover
    for w in range(start, stop):
        iw = pos[w]
        if iw < 0:
            continue
        for q in range(indptr[w], indptr[w + 1]):
            p = indices[q]
            if p == w or pos[p] < 0:
                continue
            hp = 0.5 * (hv[w] + hv[p])
            data[q] += mass[p] * _pair_image(P, w, p, bpt, nu, iw, pos[p], hp, dogc) * _norm(hp, half_k)
        zero_row_sum(w, indptr, indices, data)  # rows keep summing to zero


@jit()
def _pair_images(start, stop, pairs, P, pos, bpt, nu, h, dogc, out):  # pragma: no cover
    for e in range(start, stop):
        w = pairs[e, 0]
        p = pairs[e, 1]
        out[e] = _pair_image(P, w, p, bpt, nu, pos[w], pos[p], h, dogc)


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


def band_images(P: np.ndarray, frames: BoundaryFrames, mass: np.ndarray, h: float, radius: float,
                dog: bool, dim: int = 2, tol: float = 0.0) -> sp.csr_matrix | None:
    """The mirror images alone at one width ``h``: what :func:`neumann_images` adds to a kernel
    operator whose pairs are those within ``radius``, as a matrix on the boundary band's pairs.

    A matrix-free pencil recomputes the kernel and adds this small stored matrix (the band holds
    the points within ``radius`` of the boundary). Images whose weight is below ``tol`` of the
    kernel's peak are dropped, as the kernel's own pairs are beyond ``radius``: most pairs of the
    band are too far from each other's image (63% of them on a random plane). None without a
    boundary.

    Examples
    --------
    >>> import numpy as np
    >>> from meshlap import geometry, laplacian, shapes
    >>> V, F = shapes.plane(600, seed=0)
    >>> g, op = geometry.from_mesh(V, F), laplacian(V, F, h=0.01, correction="none")
    >>> frames = g.boundary_frames(op.radius)
    >>> B = band_images(V, frames, g.mass, 0.01, op.radius, False)     # the images alone
    >>> full = neumann_images(op.L, V, frames, g.mass, np.full(600, 0.01), False)
    >>> float(abs(op.L + B - full).max()) < 1e-12, B.nnz < op.L.nnz
    (True, True)
    """
    if frames is None:
        return None
    band, bpt, nu = frames
    band = np.asarray(band, dtype=np.int64)
    n = len(P)
    pos = np.full(n, -1, dtype=np.int64)
    pos[band] = np.arange(len(band))
    pairs = band[cKDTree(P[band]).query_pairs(radius, output_type="ndarray")]
    half = np.empty(len(pairs))
    in_blocks(_pair_images, len(pairs), pairs, np.ascontiguousarray(P, dtype=np.float64), pos,
              np.ascontiguousarray(bpt, dtype=np.float64), np.ascontiguousarray(nu, dtype=np.float64),
              float(h), dog_factor(dim) if dog else 0.0, half)
    keep = np.abs(half) >= tol
    pairs, weight = pairs[keep], half[keep] * normalization(h, dim)
    w, p = pairs[:, 0], pairs[:, 1]
    # (w, p) weighs p's value by its mass and (p, w) w's: S = M L stays symmetric
    vals = np.concatenate([mass[p] * weight, mass[w] * weight])
    rows, cols = np.concatenate([w, p]), np.concatenate([p, w])
    diag = -np.bincount(rows, weights=vals, minlength=n)[band]  # rows keep summing to zero
    return sp.csr_matrix((np.concatenate([vals, diag]), (np.concatenate([rows, band]),
                                                          np.concatenate([cols, band]))), shape=(n, n))
