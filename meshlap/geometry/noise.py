"""A point cloud's normal noise: how much there is, whether it is noise at all, and one step
that removes most of it.

:func:`noise_reading` reads σ̂² from height fits over each point's tangent plane and tests the
residual against independent noise's χ² law, so that a coarse sampling's missed shape is not
taken for noise; :func:`project_to_tangent` moves every point onto its neighbours' plane
(the point-cloud default does where the reading finds noise,
:func:`meshlap.geometry.pointcloud.point_cloud_geometry`).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from pykdtree.kdtree import KDTree

from ..tuned import CLOUD_NOISY as NOISY
from ..tuned import NOISE_SPREAD as SPREAD
from ..tuned import NOISE_UNEXPLAINED as UNEXPLAINED
from ..tuned import STAR_NEIGHBORS
from . import frames
from .core import check_points

__all__ = ["NOISY", "UNEXPLAINED", "NoiseReading", "noise_reading", "project_to_tangent"]

# the standard normal's upper quartile
_Z75 = 0.6744897501960817
# noise_reading fits this many points' neighbourhoods
_NOISE_SAMPLE = 2048


def project_to_tangent(P: Any, k: int = 2, neighbors: int | None = None) -> np.ndarray:
    """Move every point onto the k-plane fitted (PCA) to it and its nearest neighbours.

    One step of local plane projection: noise normal to the manifold drops from σ to about
    σ/sqrt(K), at the price of a shrink of about the neighbourhood's sagitta on curved
    parts (0.1% of the radius for 16,000 points on the unit sphere).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> P = meshlap.samples.sphere_points(4000, "noisy", seed=0)
    >>> r = np.linalg.norm(project_to_tangent(P), axis=1)
    >>> bool(r.std() < 0.5 * np.linalg.norm(P, axis=1).std())
    True
    """
    P = check_points(P)
    K = min(neighbors or STAR_NEIGHBORS.get(k, 20 * k), len(P) - 1)
    _, idx = KDTree(P).query(P, k=K + 1)
    out = np.empty_like(P)
    for a in range(0, len(P), 65536):  # blocks bound the (block, K+1, d) temporaries
        nb = P[np.asarray(idx[a:a + 65536], np.int64)]
        c = nb.mean(axis=1)
        X = nb - c[:, None]
        _, v = np.linalg.eigh(np.einsum("nki,nkj->nij", X, X))
        T = v[:, :, -k:]  # (block, d, k) tangent basis
        rel = P[a:a + 65536] - c
        out[a:a + 65536] = c + np.einsum("ndk,nk->nd", T, np.einsum("ndk,nd->nk", T, rel))
    return out


class NoiseReading(NamedTuple):
    """What :func:`noise_reading` measured (its docstring): ``ratio`` σ̂²/a², ``unexplained`` the
    share of it that cubic fits leave, ``spread`` the cubic residuals' quartile ratio over
    independent noise's."""

    ratio: float
    unexplained: float
    spread: float

    @property
    def independent(self) -> bool:
        """Whether the residual looks like independent noise: fits of either order leave the
        same (``unexplained`` within UNEXPLAINED of 1) and it is spread as χ² is (``spread``
        within NOISE_SPREAD of 1). Shape the fits missed leaves less to the cubic and is
        spread unevenly; a residual at rounding level is spread too evenly."""
        return (UNEXPLAINED <= self.unexplained <= 1 / UNEXPLAINED) and (1 / SPREAD <= self.spread <= SPREAD)

    @property
    def noisy(self) -> bool:
        """Independent noise that matters to the kernel (``ratio > NOISY``)."""
        return self.ratio > NOISY and self.independent


def _chi2_quantile(nu: int, z: float = 0.0) -> float:
    # Wilson-Hilferty: the χ² quantile at the standard normal's z (the median at 0), within 1%
    # for ν ≥ 5
    c = 2.0 / (9.0 * nu)
    return nu * (1.0 - c + z * math.sqrt(c)) ** 3


def noise_reading(P: Any, k: int = 2, pca: tuple[np.ndarray, np.ndarray] | None = None) -> NoiseReading:
    """The points' normal noise, and whether it is noise rather than shape the fits missed.

    Height fits over each point's tangent k-plane (its PCA frame, 16 neighbours) leave, under
    independent normal noise of variance σ², residual sums distributed as σ²χ²_ν (ν the
    degrees of freedom left). Three readings test that model:

    - ``ratio``: σ̂²/a², σ̂² the quadratic fits' median residual over the median of χ²_ν, a the
      mean distance to the 6 nearest neighbours. The quadratic absorbs the surface's bending,
      which a plane's residual would read as noise (0.033 on 1,000 random points of a torus of
      tube radius 0.4, quadratic 1.5e-4).
    - ``unexplained``: the same reading of cubic fits over σ̂². Noise leaves it at 1 whatever
      the fit (0.96-1.03 on noisy spheres, 0.97-1.07 on five real scans with 0.3 mean edges of
      normal noise); a coarse sampling's missed shape drops it (0.33-0.87 on 7 of the 9 real
      meshes of benchmarks/corpus.toml whose vertices read above :data:`NOISY`), a residual at
      rounding level (a clean sphere) leaves it at 1.4-1.6.
    - ``spread``: the cubic residuals' upper over lower quartile, over χ²_ν's (2.1 for ν = 7).
      Noise is everywhere alike: 0.9-1.05 on the noisy spheres, 0.96-1.13 on the five noisy
      scans; shape is not: 1.45 and 2.7 on the other two of the 9 (a decimated knight and a
      multi-part ant), 1.7 to 10⁷ on the other clean meshes; rounding is too even (0.5).

    :attr:`NoiseReading.independent` asks both to be near 1; :attr:`NoiseReading.noisy` also
    asks the noise to matter to the kernel (``ratio > NOISY``).

    ``pca`` takes the frames of :func:`meshlap.geometry.frames.pca_frames` when they exist.

    Examples
    --------
    >>> import meshlap
    >>> noise_reading(meshlap.shapes.fibonacci_sphere(2000)).noisy
    False
    >>> r = noise_reading(meshlap.samples.sphere_points(16000, "noisy", seed=0))
    >>> r.noisy, bool(r.ratio > NOISY), bool(r.unexplained > 0.95), bool(r.spread < 1.1)
    (True, True, True, True)
    """
    P = check_points(P)
    # quartiles need no more than 2,048 evenly spread points (standard error about 4%): the
    # fits' cost stays bounded (0.1 s of CPU) whatever the size
    rows = np.unique(np.linspace(0, len(P) - 1, min(len(P), _NOISE_SAMPLE)).astype(np.int64))
    T, idx = frames.pca_frames(P, k, rows=rows) if pca is None else (pca[0][rows], pca[1][rows])
    res, nu = frames.height_residuals(P, T, idx, k, (2, 3))
    spacing = float(np.linalg.norm(P[idx[:, 1:7]] - P[idx[:, :1]], axis=2).mean())
    # fewer than 5 degrees of freedom left: no noise is seen
    quad, cubic = (float(np.median(res[i])) / _chi2_quantile(nu[i]) if nu[i] >= 5 else 0.0 for i in range(2))
    unexplained = spread = 1.0  # where cubic fits cannot be made, nothing tells noise from shape
    if nu[1] >= 5:
        q1, q3 = np.percentile(res[1], [25, 75])
        unexplained = cubic / quad if quad > 0 else 0.0  # fits that leave nothing: no noise
        chi2 = _chi2_quantile(nu[1], _Z75) / _chi2_quantile(nu[1], -_Z75)
        spread = float(q3 / q1) / chi2 if q1 > 1e-12 * q3 else math.inf
    return NoiseReading(float(quad / max(spacing * spacing, 1e-300)), float(unexplained), float(spread))
