"""Width and degree of the point-wise rows, chosen per point from the data.

High-degree rows on compact stencils are accurate on clean samples (third order in the
spacing at degree 4, fifth at degree 6) but amplify noise: a row's weights are of size
1/ρ² on a stencil of radius ρ, so independent noise of size σ in f reaches Δf as σ‖row‖₂.
Wide, low-degree rows average noise out at the price of a bias that grows with the width.
:func:`choose_rows` weighs the two for every point, from quantities the fits measure:

* the **noise** σ̂_w: the normal residual of the local height fits, corrected for the degrees
  of freedom the fit used, the smallest over the fits tried at w (a fit of too low a degree
  also leaves the surface's own shape in its residual) and then the median over w's nearest
  neighbours;
* the **geometric scale** ℓ_w = 1/κ_w, κ_w the curvature of a degree-2 fit on 64 neighbours
  (on about 200 where the data are noisy), the median over w's nearest neighbours, at most
  the diameter of the data;
* for each candidate (degree q, K nearest neighbours, Gaussian weights reaching e^{−c} at the
  K-th): its noise factor ‖row‖₂ and its probes, the row applied to the monomials of degree
  q + 1 and q + 2, which measure how far from exact it is on what it does not reproduce.

The predicted relative error of a candidate, for a function that varies on the scale ℓ, is

    E = β Σ_{e=0,1} probe_e ℓ^{1 − q − e}  +  γ σ̂ ℓ ‖row‖₂

with β = 0.1 and γ = 0.6 measured on spheres (the prediction is within a factor of about
two of the error of x² and eˣ from 2,000 to 16,000 points, 0 to 1% noise). Each point takes
the candidate of least E; the ladder of widths grows (×2.5 in K) only at the points whose
noise term still dominates. The widest rungs hold the paper's width and more, so a noisy
input gets rows at least as wide as the heat-kernel operator's at h = (2ē)².
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from ..errors import MeshError, MeshWarning
from ..geometry import check_points
from .highorder import RowFit, knn_pattern, monomials, pointwise_rows  # noqa: F401

__all__ = ["RowChoice", "choose_rows", "predicted_error"]

#: Weight of the probes (bias) and of the noise factor in the predicted error.
BETA, GAMMA = 0.1, 0.6
# Gaussian width per candidate: the K-th neighbour gets weight e^{-c}
_C_COMPACT, _C_WIDE = 8.0, 3.0
# Neighbours of the compact rows, per monomial count, and of the noise and curvature fits
_K_PER_MONOMIAL = 1.7
_K_NOISE, _K_CURVATURE = 64, 200
# noise/spacing above which the scale is taken from the wider curvature fit
_NOISY = 1e-3
# The ladder of wide stencils: K grows by this factor up to max_neighbors
_LADDER = 2.5


@dataclass
class RowChoice:
    """What :func:`choose_rows` chose, per point.

    Attributes
    ----------
    degree, neighbors : (n,) int ndarray
        Polynomial degree and number of neighbours of each row (degree −1: no row).
    h : (n,) ndarray
        Width of each row's Gaussian weights.
    noise : (n,) ndarray
        Estimated normal noise σ̂ (same units as the positions).
    scale : (n,) ndarray
        Geometric scale ℓ = 1/κ.
    predicted : (n,) ndarray
        Predicted relative error of each chosen row.
    spacing : float
        Mean distance to the nearest neighbours.
    """

    degree: np.ndarray
    neighbors: np.ndarray
    h: np.ndarray
    noise: np.ndarray
    scale: np.ndarray
    predicted: np.ndarray
    spacing: float
    notes: list[str] = field(default_factory=list)

    def summary(self) -> str:
        """One line: the degrees and widths chosen, and the noise seen.

        Examples
        --------
        >>> import numpy as np
        >>> RowChoice(np.array([4, 4, 2]), np.array([32, 32, 400]), np.array([1e-3, 1e-3, 1e-2]),
        ...           np.zeros(3), np.ones(3), np.zeros(3), 0.05).summary()
        'degree 4: 67%, 2: 33%; neighbours 32-400 (median 32); h 0.001-0.01; noise/spacing median 0'
        """
        ok = self.degree >= 0
        deg, cnt = np.unique(self.degree[ok], return_counts=True)
        parts = ", ".join(f"{d}: {100 * c / max(ok.sum(), 1):.0f}%" for d, c in sorted(
            zip(deg.tolist(), cnt.tolist(), strict=True), key=lambda t: -t[0]))
        if not ok.any():
            return "no rows"
        nb, hh = self.neighbors[ok], self.h[ok]
        return (f"degree {parts}; neighbours {nb.min()}-{nb.max()} (median {int(np.median(nb))}); "
                f"h {hh.min():.3g}-{hh.max():.3g}; noise/spacing median "
                f"{np.median(self.noise[ok]) / self.spacing:.2g}")


def predicted_error(fit: RowFit, noise: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """The predicted relative error of each row of ``fit`` (see the module's docstring).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> P = meshlap.shapes.fibonacci_sphere(1000)
    >>> fit = pointwise_rows(P, *knn_pattern(P, 20)[:2], h=0.01, degree=2, return_fit=True)
    >>> bool(np.all(predicted_error(fit, np.zeros(1000), np.ones(1000)) < 0.05))
    True
    """
    q = np.maximum(fit.degree, 0).astype(np.float64)
    probes = np.nan_to_num(fit.probes, nan=0.0)
    bias = probes[:, 0] * scale ** (1.0 - q) + probes[:, 1] * scale ** (-q)
    err = BETA * bias + GAMMA * noise * scale * fit.amplification
    err[fit.degree < 2] = np.inf
    return err


def _candidate(P, idx, dist, degree, c, k, normals, centers, noise_dof=True):
    # rows of the given degree on the K nearest neighbours (idx, dist: (rows, K), ascending)
    rows, K = idx.shape
    h = np.maximum(dist[:, -1], 1e-300) ** 2 / (4.0 * c)
    indptr = np.arange(rows + 1, dtype=np.int64) * K
    return pointwise_rows(P, indptr, np.ascontiguousarray(idx).ravel(), h, degree, k=k, normals=normals,
                          centers=centers, return_fit=True, noise_dof=noise_dof)


def _nearest(tree: cKDTree, P: np.ndarray, K: int, centers: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    dist, idx = tree.query(P[centers], k=K, workers=-1)
    return np.asarray(idx, dtype=np.int64).reshape(len(centers), K), np.asarray(dist).reshape(len(centers), K)


def choose_rows(P: Any, normals: Any = None, *, k: int = 2, max_degree: int = 6,
                max_neighbors: int | None = None, noise: float | None = None
                ) -> tuple[sp.csr_matrix, RowChoice]:
    """Point-wise Laplacian rows whose width and degree follow the data at every point.

    Parameters
    ----------
    P : (n, d) array_like
        Positions (mesh vertices or a point cloud).
    normals : (n, d) array_like, optional
        Unit normals of a hypersurface for the frames (default: principal axes per row).
    k : int
        Intrinsic dimension.
    max_degree : int
        Highest degree tried (2 to 6); the compact candidates are the even degrees from 2 up
        to it and ``max_degree`` itself.
    max_neighbors : int, optional
        Widest stencil of the ladder (default min(1000, n/4)).
    noise : float, optional
        Known normal noise level σ; default: estimated per point from the fits.

    Returns
    -------
    L : scipy.sparse.csr_matrix
        (n, n), Δf ≈ L @ f.
    choice : RowChoice
        Per-point degree, neighbours, h, noise and predicted error.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> P = meshlap.shapes.fibonacci_sphere(3000)
    >>> L, choice = choose_rows(P)
    >>> x = P[:, 0]
    >>> bool(np.abs(L @ x**2 - (2 - 6 * x**2)).max() < 1e-4), int(np.median(choice.degree))
    (True, 6)
    """
    P = np.ascontiguousarray(check_points(P, "P"), dtype=np.float64)
    n, d = P.shape
    if isinstance(max_degree, bool) or not isinstance(max_degree, (int, np.integer)) \
            or not 2 <= max_degree <= 6:
        raise MeshError(f"max_degree must be an integer from 2 to 6; got {max_degree!r}")
    if noise is not None and not (math.isfinite(noise) and noise >= 0):
        raise MeshError(f"noise must be a finite level >= 0; got {noise!r}")
    count = monomials(k, max_degree)[1] if 1 <= k <= d else None
    if count is None:
        raise MeshError(f"k must be between 1 and the dimension {d}; got {k!r}")
    least = int(count[2]) + 2
    if n < least:
        raise MeshError(f"choose_rows needs at least {least} points for k = {k}; got {n}")
    notes: list[str] = []
    tree = cKDTree(P)
    spacing_d, _ = tree.query(P, k=min(7, n), workers=-1)
    spacing = float(np.asarray(spacing_d)[:, 1:].mean())
    everyone = np.arange(n)
    degrees = sorted({max_degree, *range(2, max_degree + 1, 2)}, reverse=True)
    cands: list[tuple[RowFit, int]] = []
    sig = np.full(n, np.inf)
    Ks = [min(n, int(round(_K_PER_MONOMIAL * count[q] + 4))) for q in degrees]
    Kn = min(n, _K_NOISE)
    # one query serves every compact candidate: the K nearest are a prefix of the Kq nearest
    idx_all, dist_all = _nearest(tree, P, max(Ks + [Kn]), everyone)
    for q, K in zip(degrees, Ks, strict=True):
        fit = _candidate(P, idx_all[:, :K], dist_all[:, :K], q, _C_COMPACT, k, normals, everyone)
        cands.append((fit, K))
        sig = np.minimum(sig, fit.residual)
    fit = _candidate(P, idx_all[:, :Kn], dist_all[:, :Kn], 2, _C_WIDE, k, normals, everyone)
    cands.append((fit, Kn))
    sig = np.minimum(sig, fit.residual)
    # the scale comes from the curvature of a degree-2 fit: on 64 neighbours where the data
    # are clean, on ~200 where noise would inflate the curvature of a small fit
    curv_fit = fit
    if np.median(sig[np.isfinite(sig)]) > _NOISY * spacing if np.isfinite(sig).any() else False:
        Kc = min(n, _K_CURVATURE, max(Kn, n // 10))
        idx, dist = _nearest(tree, P, Kc, everyone)
        curv_fit = _candidate(P, idx, dist, 2, _C_WIDE, k, normals, everyone, noise_dof=False)
    # neighbourhood medians: one noisy fit does not decide a point's row
    _, nb = tree.query(P, k=min(16, n), workers=-1)
    nb = np.asarray(nb, dtype=np.int64).reshape(n, -1)
    finite = np.where(np.isfinite(sig), sig, np.nan)
    if np.isnan(finite).all():
        sig = np.zeros(n)
        notes.append("no fit left degrees of freedom to estimate the noise: assumed clean")
    else:
        sig = np.nan_to_num(np.nanmedian(finite[nb], axis=1), nan=float(np.nanmedian(finite)))
    if noise is not None:
        sig = np.full(n, float(noise))
    diameter = float(np.linalg.norm(P.max(axis=0) - P.min(axis=0)))
    kappa = np.median(curv_fit.curvature[nb], axis=1) if k < d else np.zeros(n)
    scale = np.minimum(1.0 / np.maximum(kappa, 1e-300), diameter)
    scale = np.maximum(scale, 4.0 * spacing)

    best = np.full(n, np.inf)
    pick = np.full(n, -1)
    dominated = np.zeros(n, dtype=bool)  # the chosen row's error is mostly noise
    local = []  # (fit, K, rows the fit covers as positions in everyone)

    def consider(fit: RowFit, K: int) -> np.ndarray:
        rows = fit.centers
        err = predicted_error(fit, sig[rows], scale[rows])
        better = err < best[rows]
        best[rows[better]] = err[better]
        pick[rows[better]] = len(local)
        local.append((fit, K))
        noisy = GAMMA * sig[rows] * scale[rows] * fit.amplification > 0.5 * err
        dominated[rows[better]] = noisy[better]
        return rows[better & noisy]

    for fit, K in cands:
        consider(fit, K)
    Kmax = min(n, max_neighbors or min(1000, n // 4))
    K = Kn
    active = np.flatnonzero(dominated)
    while len(active) and K < Kmax:
        K = min(Kmax, int(round(K * _LADDER)))
        grown = []
        idx, dist = _nearest(tree, P, K, active)
        for q in (2, 4) if max_degree >= 4 else (2,):
            fit = _candidate(P, idx, dist, q, _C_WIDE, k, normals, active, noise_dof=False)
            grown.append(consider(fit, K))
        active = np.unique(np.concatenate(grown))
    capped = len(active) and Kmax < n
    if capped:
        notes.append(f"{len(active)} points would take rows wider than {Kmax} neighbours: the noise is "
                     "more than the widest stencil averages out; pass max_neighbors or a fixed h")
    failed = pick < 0
    if failed.any():
        notes.append(f"{int(failed.sum())} points have no row of degree >= 2 (degenerate neighbourhoods)")
    # reaching the widest rung is reported (RowChoice.notes), not warned: the rows are then
    # those of the widest stencil, still the best of the ladder
    for note in notes:
        if not note.startswith(f"{len(active)} points would take"):
            warnings.warn(f"choose_rows: {note}", MeshWarning, stacklevel=2)

    degree = np.full(n, -1)
    neighbors = np.zeros(n, dtype=np.int64)
    hv = np.zeros(n)
    blocks = []
    for i, (fit, K) in enumerate(local):
        rows = np.flatnonzero(pick == i)
        if not len(rows):
            continue
        pos = np.searchsorted(fit.centers, rows)
        degree[rows] = fit.degree[pos]
        neighbors[rows] = K
        hv[rows] = fit.h[pos]
        blocks.append(fit.matrix[rows].tocoo())
        blocks[-1].row = rows[blocks[-1].row]
    L = sp.coo_matrix((np.concatenate([b.data for b in blocks]),
                       (np.concatenate([b.row for b in blocks]), np.concatenate([b.col for b in blocks]))),
                      shape=(n, n)).tocsr() if blocks else sp.csr_matrix((n, n))
    return L, RowChoice(degree, neighbors, hv, sig, scale, best, spacing, notes)
