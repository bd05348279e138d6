"""Width and degree of the point-wise rows, chosen per point from the data.

High-degree rows on compact stencils are accurate on clean samples (third order in the
spacing at degree 4, fifth at degree 6) but amplify noise: a row's weights are of size
1/ρ² on a stencil of radius ρ, so independent noise of size σ in f reaches Δf as σ‖row‖₂.
Wide, low-degree rows average noise out at the price of a bias that grows with the width.
:func:`choose_rows` weighs the two for every point, from quantities the fits measure:

* the **noise** σ̂_w: the normal residual of the local height fits, corrected for the degrees
  of freedom the fit used, the smallest over the compact fits built at w and the wide one (a
  fit of too low a degree also leaves the surface's own shape in its residual) and then the
  median over w's nearest neighbours;
* the **geometric scale** ℓ_w = 1/κ_w, κ_w the curvature of a degree-2 fit on 64 neighbours
  (where the data are noisy, on 256 held by 96 of them: the ladder's first rung, whose
  degree-2 rows that fit's are), the median over w's nearest neighbours, at most the
  diameter of the data;
* for each candidate (degree q, K nearest neighbours, Gaussian weights reaching e^{−c} at the
  K-th): its noise factor ‖row‖₂ and its probes, the row applied to the monomials of degree
  q + 1 and q + 2, which measure how far from exact it is on what it does not reproduce.

The predicted relative error of a candidate, for a function that varies on the scale ℓ, is

    E = β Σ_{e=0,1} probe_e ℓ^{1 − q − e}  +  γ σ̂ ℓ ‖row‖₂

with β = 0.1 and γ = 0.6 measured on spheres (the prediction is within a factor of about
two of the error of x² and eˣ from 2,000 to 16,000 points, 0 to 1% noise). Each point takes
the candidate of least E; the ladder of widths grows (×4 in K, up to 1,000 neighbours) only
at the points whose noise term still dominates. The widest rungs hold the
paper's width and more, so a noisy input gets rows at least as wide as the heat-kernel
operator's at h = (2ē)².

The probes are polynomials and miss a surface rough at the spacing: spot's Loop limit surface
(C² only) where its curvature turns within a few spacings, next to the horns. There a fit's
own residual r exceeds σ̂ by far; the excess is shape the fit misses, it reaches Δf as noise of
that size would, so E takes σ̂ + max(r − 2σ̂, 0) in its noise term and counts the excess as
bias (2σ̂: a residual's own noise estimate fluctuates well within it, so noisy data keep their
wide rows). With it and compact rows whose weights reach e^{−12} at the K-th neighbour (e^{−8}
before), the clean spot of bench_pointwise, Δf exact: E2 0.080 → 0.035 (cotangent: 0.042).

The noise term assumes f sampled at the noisy points (its noise σ|∇f|). A smooth f on a
noisy surface (the paper's Table 4: f of the clean sphere at the noisy vertices) has none, and
there the least-error row, often degree 2 and wide, errs by its bias. So each point takes,
among the candidates within :data:`~meshlap.tuned.ROW_ROBUST` (2×) of the least predicted
error, the one of least bias: on Table 4's 8,000-vertex sphere E2 0.025 → 0.0097 (the paper's
operator 0.015), at most 2× the predicted error where f is noisy.

A wide rung holds at most :data:`~meshlap.tuned.ROW_SAMPLE` points, drawn from a random subset
of the cloud whose nearest points span the rung's width (:class:`_Spread`): the bias of a row is set by
its width, its noise factor falls only as the square root of the points it holds, so on
16,000 noisy sphere points 96 points spread over the width of 1,000 lose 10-40% of the
accuracy of all 1,000 at a sixth of the cost (build and ``op @ f``).

The compact rows of degree 4 and 6 are built only where they can win: a lower bound of their
predicted error, the noise term γ σ̂ ℓ ‖row‖₂ and the bias β Σ_e probe_e ℓ^{1−q−e}, with ‖row‖₂
and the probes bounded below by the rows of a sample of the points (:func:`_compact`), must
come within ROW_ROBUST of the least predicted error of the rows built before (degree 6 first, then
4, then the ladder, which only lowers it). On the noisy spheres and tori of bench_pointwise
they are built almost nowhere; on clean data degree 6 everywhere and degree 4 where degree 6's
lead is small (16,000 sphere points: 13% of them, the same rows as building it everywhere).
Clean regions fit one candidate (:func:`_clean`). Every candidate is fitted first at the sample
(every 16th point); where the sample points among a point's 64 nearest, and among its 16 nearest
points' 64, all predict the compact rows of degree > 2 :data:`~meshlap.tuned.ROW_MARGIN` (10×)
more accurate than the degree-2 candidates, the point fits the top degree alone (its residual
not corrected for the degrees of freedom: it measures shape there), and takes its noise level
and scale from it (ℓ = 1.000 on the unit sphere, the wide fit's 0.916); the other points'
medians keep their numbers.
A clean point whose row turns out noise-dominated, or whose residual exceeds twice its level (a
crease, a noisy patch between the sample's points), has the degree-2 candidates fitted after all.
bench_pointwise's 15 inputs: E2 unchanged (L the same in 14); the row choice at 400,000 clean
points 6.4 s of CPU instead of 10.1, at 1,000,000 16.1 s instead of 29.6.

With the ladder reusing the curvature fit and one stencil serving a rung's two degrees
(:func:`meshlap.corrections.highorder.fit_rows`), the row choice on 16,000 points with 1%
radial noise costs 1.0 s of CPU instead of 1.9 (E2 0.180 → 0.175), on the clean sphere 0.52
s instead of 0.67 (the same rows).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from ..errors import MeshError, MeshWarning
from ..geometry import check_points
from ..geometry.validation import check_int
from ..tuned import (
    ROW_BETA,
    ROW_C_COMPACT,
    ROW_C_WIDE,
    ROW_EXCESS,
    ROW_FLOORS,
    ROW_GAMMA,
    ROW_K_NOISE,
    ROW_K_PER_MONOMIAL,
    ROW_LADDER,
    ROW_MARGIN,
    ROW_NOISY,
    ROW_ROBUST,
    ROW_ROUNDING,
    ROW_SAMPLE,
)
from ._gather import _assemble, _restrict, _table
from ._levels import _local_noise, _scale
from ._neighbours import _nearest, _Spread
from ._ranks import _bounds, _min, _sum
from .highorder import RowFit, fewest_points, fit_rows, knn_pattern, monomials, pointwise_rows  # noqa: F401

__all__ = ["RowChoice", "choose_rows", "predicted_error", "wider_rows"]

# The compact rows of every 16th point, and of at least 64, measure how small a row's noise
# factor can be (_compact)
_CALIBRATE = (64, 16)
# From this many points the rows are fitted in the k-d tree's order (their neighbours near in
# memory; CPU at 16,000 points 3-5% more, where the points fit in the cache and the rows' own
# arrays are better read in order; 5% less at 40,000, 17% at 100,000)
_IN_ORDER = 30_000


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
    err = ROW_BETA * bias + ROW_GAMMA * noise * scale * fit.amplification
    err[fit.degree < 2] = np.inf
    return err


def _candidate(P, near, K, rows, degree, c, k, normals, centers, noise_dof=True, place=None, keep=True,
               skip=None):
    # rows of the given degree (a tuple: of each, on the same stencils) on the K nearest
    # neighbours of the centres: the first K of the rows `rows` (None: all, the centres' own) of
    # the table near[0], ascending, read in place (near[1](K): the K-th one's distances, from
    # _table); computed in the order of place (a k-d tree's, _Spread.place) or, without it, in
    # their own; keep=False: measured only (fit_rows' keep_rows); skip: the rows left empty
    idx, kth = near
    width = idx.shape[1]
    sel = np.arange(len(idx)) if rows is None else rows
    h = np.maximum(kth(K)[sel], 1e-300) ** 2 / (4.0 * c)
    indptr = np.arange(len(sel) + 1, dtype=np.int64) * K
    order = np.arange(len(sel)) if place is None else np.argsort(place[centers], kind="stable")
    fits = fit_rows(P, indptr, np.ascontiguousarray(idx).ravel(), h, degree if isinstance(degree, tuple) else
                    (degree,), k=k, normals=normals, centers=centers, noise_dof=noise_dof,
                    order=order if skip is None else order[~skip[order]],
                    starts=None if K == width and rows is None else sel * width, keep_rows=keep)
    return fits if isinstance(degree, tuple) else fits[0]


def _errors(fit: RowFit, sig: np.ndarray, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    # the predicted error of each row and its bias part. A fit's residual well beyond the noise
    # level is shape its polynomials miss (a surface rough at the spacing): it reaches Δf as
    # noise of that size would, and is bias
    excess = np.maximum(np.nan_to_num(fit.residual, posinf=0.0) - ROW_EXCESS * sig, 0.0)
    return predicted_error(fit, sig + excess, scale), predicted_error(fit, excess, scale)


def _clean(wide: RowFit, low: RowFit, highs: list, near: np.ndarray, width: int, nb: np.ndarray, k: int,
           d: int, diameter: float, spacing: float) -> np.ndarray:
    # the points whose `width` nearest, and their nb's, hold no sample point (these fits' centres)
    # but clean ones: where degree > 2 predicts an error ROW_MARGIN times below the degree-2
    # candidates', with the sample point's own least residual and wide curvature for σ̂ and ℓ (no
    # medians: a sample point stands for 16 spacings²). The nb condition leaves the other points'
    # noise level and scale, medians over nb, the numbers they had with every fit everywhere
    fits = [wide, low, *highs]
    sig = np.min([np.where(np.isfinite(f.residual), f.residual, np.inf) for f in fits], axis=0)
    scale = _scale(wide.curvature, None, k, d, diameter, spacing)
    lo = np.minimum(*(_errors(f, sig, scale)[0] for f in (wide, low)))
    hi = np.min([_errors(f, sig, scale)[0] for f in highs], axis=0)
    status = np.zeros(len(nb), dtype=np.int8)  # 1: a clean sample point, 2: another sample point
    status[wide.centers] = np.where(np.isfinite(sig) & (ROW_MARGIN * hi <= lo), 1, 2)
    if not (status == 1).any():
        return np.zeros(len(nb), dtype=bool)
    out = np.ones(len(nb), dtype=bool)
    if (status == 2).any():  # (in blocks: one table of bytes of the neighbours' size is 64 MB at 1M)
        for a in range(0, len(nb), 1 << 16):
            out[a:a + (1 << 16)] = (status[near[a:a + (1 << 16), :width]] < 2).all(axis=1)
    return out & out[nb].all(axis=1)


def _whole(P, near, K, q, k, normals, fit, place, noise_dof=True) -> RowFit:
    # the compact rows of degree q at every point, one fit that takes those of `fit` (a sample's:
    # the same stencils, the same numbers) in their places, so that _assemble can take its
    # matrix whole
    skip = np.zeros(len(near[0]), dtype=bool)
    skip[fit.centers] = True
    whole = _candidate(P, near, K, None, q, ROW_C_COMPACT, k, normals, np.arange(len(skip)), noise_dof, place,
                       skip=skip)
    whole.matrix.data.reshape(-1, K)[fit.centers] = fit.matrix.data.reshape(-1, K)
    for name in ("degree", "residual", "amplification", "probes", "curvature"):
        getattr(whole, name)[fit.centers] = getattr(fit, name)
    return whole


def _compact(P, near, K, q, k, normals, done, level, scale, sampled, todo, own, comm, place) -> list:
    # compact rows of degree q where they can win (the module's docstring), among the points
    # todo: ‖row‖₂ ≥ R/ρ², ρ the K-th neighbour's distance, R half the least ‖row‖₂ ρ² of the
    # sample's rows, `sampled` (bench_pointwise's inputs: 12-20 at degree 4, 22-38 at degree 6);
    # and its probes probe_e ≥ F ρ^{q−1+e}, F from the sample's least probe_e / ρ^{q−1+e}: the
    # bias that rules degree 4 out where degree 6, built before it, is far ahead (clean data).
    # The fits built, the sample's first
    best = np.full(len(near[0]), np.inf)
    for fit, _ in done:
        err = _errors(fit, level[fit.centers], scale[fit.centers])[0]
        best[fit.centers] = np.minimum(best[fit.centers], err)
    first = sampled.centers
    ok = (sampled.degree == q) & own[first]
    rho = np.maximum(near[1](K), 1e-300)
    lows = [sampled.amplification[ok] * rho[first[ok]] ** 2] + [
        np.nan_to_num(sampled.probes[ok, e], nan=np.inf) / rho[first[ok]] ** (q - 1 + e) for e in (0, 1)]
    least = [_min(comm, float(v.min()) if len(v) else math.inf) for v in lows]
    floor = [f * x if math.isfinite(x) else 0.0 for f, x in zip(ROW_FLOORS, least, strict=True)]
    bound = ROW_GAMMA * level * scale * floor[0] / rho ** 2 + ROW_BETA * (
        floor[1] * (rho / scale) ** (q - 1) + floor[2] * (rho / scale) ** q)
    rest = np.flatnonzero(todo & (bound <= ROW_ROBUST * best))
    if len(rest) + len(first) == len(best):  # every point (clean data)
        return [(_whole(P, near, K, q, k, normals, sampled, place), K)]
    fits = [(sampled, K)]
    if len(rest):
        fits.append((_candidate(P, near, K, rest, q, ROW_C_COMPACT, k, normals, rest, place=place), K))
    return fits


def choose_rows(P: Any, normals: Any = None, *, k: int = 2, max_degree: int = 6,
                max_neighbors: int | None = None, noise: float | None = None,
                sample: int = ROW_SAMPLE, rows: Any = None, ids: Any = None, comm: Any = None,
                counted: Any = None, progress: Callable[[str], None] | None = None
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
        Widest stencil of the ladder, in neighbours of the whole cloud (default
        min(1000, n/4)).
    noise : float, optional
        Known normal noise level σ; default: estimated per point from the fits.
    sample : int
        Most points a row holds: a wider stencil takes them from a random subset of the
        points (see :class:`_Spread`), so that noisy inputs cost little more than clean ones.
    rows, ids, comm, counted : optional
        For one MPI rank's share (:mod:`meshlap.distributed`): ``rows`` the local points
        whose rows are built (default all; the others are neighbours only, a halo wide
        enough for the widest stencil), ``ids`` the global ids of all local points and
        ``comm`` the communicator over which the global figures (spacing, noise median,
        extent, number of points) are reduced, each point counted by the rank that owns it:
        ``counted``, the rows of ``rows`` this rank owns (default all; a row two ranks build,
        as coincident copies on both need it, is counted by one). The rows are then those of
        the single machine.
    progress : callable, optional
        ``progress(stage)`` as each stage starts ("queries", "sample", "compact 6", "noise fit",
        "rung 1000", ...).

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
    max_degree = check_int(max_degree, "max_degree", 2, 6)
    if noise is not None and not (math.isfinite(noise) and noise >= 0):
        raise MeshError(f"noise must be a finite level >= 0; got {noise!r}")
    count = monomials(k, max_degree)[1] if 1 <= k <= d else None
    if count is None:
        raise MeshError(f"k must be between 1 and the dimension {d}; got {k!r}")
    sample = check_int(sample, "sample", int(count[-1]) + 2)
    own = np.ones(n, dtype=bool) if rows is None else np.zeros(n, dtype=bool)
    if rows is not None:
        own[np.asarray(rows, dtype=np.int64)] = True
    owned = own
    if counted is not None:
        owned = np.zeros(n, dtype=bool)
        owned[np.asarray(counted, dtype=np.int64)] = True
    ids = None if ids is None else np.asarray(ids, dtype=np.int64)
    total = n if comm is None else comm.allreduce(int(owned.sum()))
    least = fewest_points(k)
    if total < least:
        raise MeshError(f"choose_rows needs at least {least} points for k = {k}; got {total}")
    notes: list[str] = []
    tick = progress or (lambda stage: None)
    tick("queries")
    tree = cKDTree(P)
    spread = _Spread(P, tree, int(sample), ids, total)
    # the fits in the k-d tree's order where the points outgrow the cache (fit_rows)
    place = spread.place if n >= _IN_ORDER else None
    everyone = np.arange(n)
    degrees = sorted({max_degree, *range(2, max_degree + 1, 2)}, reverse=True)
    Ks = [min(n, int(round(ROW_K_PER_MONOMIAL * count[q] + 4))) for q in degrees]
    Kn = min(n, ROW_K_NOISE)
    if comm is not None:  # a rank's share and its halo: as many neighbours as the whole would give
        Ks, Kn = [min(total, K) for K in Ks], min(total, ROW_K_NOISE)
    # one query serves every compact candidate, the spacing and the neighbourhood medians:
    # the K nearest are a prefix of the Kq nearest
    # (the distances of the spacing's neighbours and of each width's last one only)
    ranks = sorted({*range(1, min(7, n)), *(K - 1 for K in Ks + [Kn])})
    idx_all, dist_all = _nearest(spread.near, P, max(Ks + [Kn, min(16, n)]), everyone, spread.place,
                                 np.asarray(ranks))
    table = _table(idx_all, dist_all, ranks)
    spacing = _sum(comm, float(dist_all[owned, :min(7, n) - 1].mean(axis=1).sum())) / total
    nb = np.ascontiguousarray(idx_all[:, :min(16, n)])
    lo, hi = _bounds(comm, P[own])
    diameter = float(np.linalg.norm(hi - lo))
    # a noise level at the coordinates' own rounding widens no row (ROW_ROUNDING)
    rounding = ROW_ROUNDING * np.finfo(np.float64).eps * float(np.maximum(np.abs(lo), np.abs(hi)).max())
    # every candidate at the sample first (it bounds _compact, and _clean reads it); the clean
    # points fit the top degree alone, the others the degree-2 candidates, then the compact rows
    # of higher degree where they can win. (The degree-2 rows measured, not kept: 250 MB at
    # 400,000 points cost more than fitting again the rows noisy data do choose)
    tick("sample")
    sample = spread.rank < max(_CALIBRATE[0], total // _CALIBRATE[1])
    first = np.flatnonzero(sample)
    K2 = Ks[-1]
    refit: dict[int, Callable[[np.ndarray], RowFit]] = {}

    def measured(K: int, c: float, rows: np.ndarray) -> tuple[RowFit, int]:
        fit = _candidate(P, table, K, rows, 2, c, k, normals, rows, place=place, keep=False)
        refit[id(fit)] = lambda again: _candidate(P, table, K, again, 2, c, k, normals, again, False, place)
        return fit, K

    highs = list(zip(degrees[:-1], Ks[:-1], strict=True))  # (q, K) of degree > 2, the highest first
    wide, low = [measured(Kn, ROW_C_WIDE, first)], [measured(K2, ROW_C_COMPACT, first)]
    sampled = {q: _candidate(P, table, K, first, q, ROW_C_COMPACT, k, normals, first, place=place)
               for q, K in highs}
    fast = _clean(wide[0][0], low[0][0], list(sampled.values()), idx_all, Kn, nb, k, d, diameter, spacing) \
        & ~sample if highs else np.zeros(n, dtype=bool)
    # the clean points' rows of the top degree: one fit of every point but the sample's, that
    # takes the sample's rows (_whole), where every other point is clean
    clean: list = []
    if fast.any():
        q, K = highs[0]
        tick(f"compact {q}")
        rows = np.flatnonzero(fast)
        whole = len(rows) + len(first) == n
        clean = [(_whole(P, table, K, q, k, normals, sampled[q], place, False) if whole else
                  _candidate(P, table, K, rows, q, ROW_C_COMPACT, k, normals, rows, False, place), K)]
    slow = np.flatnonzero(~fast & ~sample)
    if len(slow):
        tick("noise fit")
        wide.append(measured(Kn, ROW_C_WIDE, slow))
        low.append(measured(K2, ROW_C_COMPACT, slow))
    # the noise level as the fits everywhere gave it before the compact rows of degree > 2 (the
    # clean points: of their top degree's); the curvature of the wide fit, else of the top degree
    resid = np.full(n, np.inf)
    curvature = np.full(n, np.nan)
    for fit, _ in clean + low + wide:
        resid[fit.centers] = np.minimum(resid[fit.centers], fit.residual)
    for fit, _ in clean + wide:
        curvature[fit.centers] = fit.curvature
    first_scale = _scale(curvature, nb, k, d, diameter, spacing)
    compact: dict[int, list] = {2: low}
    for q, K in highs:  # the highest first: it rules lower ones out
        mine = clean if q == highs[0][0] else []
        todo = ~sample & ~fast if mine else ~sample
        if _sum(comm, float(todo.any())):  # (on every rank alike: _compact's reductions are collective)
            tick(f"compact {q}")
            level = _local_noise(resid, nb, comm, owned, noise)[0]
            done = wide + mine + [c for fits in compact.values() for c in fits]
            built = _compact(P, table, K, q, k, normals, done, level, first_scale, sampled[q], todo, own,
                             comm, place)
        else:
            built = [(sampled[q], K)]
        if mine and len(mine[0][0].centers) == n:  # (the whole fit holds the sample's rows)
            built = [c for c in built if c[0] is not sampled[q]]
        for c, _ in built:
            resid[c.centers] = np.minimum(resid[c.centers], c.residual)
        compact[q] = built[:1] + mine + built[1:]  # (the sample's first, as before)
    cands = [c for q in degrees for c in compact[q]] + wide
    sig, typical = _local_noise(resid, nb, comm, owned, noise)
    # the scale comes from the curvature of a degree-2 fit: on 64 neighbours where the data
    # are clean (where clean points fitted none, of their rows of the top degree); where noise
    # would inflate the curvature of a small fit, on the ladder's first rung (256), whose
    # degree-2 rows that fit then is
    Kmax = min(total, max_neighbors or min(1000, total // 4))
    curv_fit, Kc = None, max(Kn, min(Kmax, int(round(Kn * ROW_LADDER))))
    if typical is not None and typical > ROW_NOISY * spacing:
        tick("curvature fit")
        idx_c, dist_c, _ = spread(Kc, everyone)
        held = idx_c.shape[1]  # (at most ROW_SAMPLE of the Kc nearest)
        curv_fit = _candidate(P, _table(idx_c, dist_c), held, None, 2, ROW_C_WIDE, k, normals, everyone,
                              False, place)
    if typical is None:
        notes.append("no fit left degrees of freedom to estimate the noise: assumed clean")
    scale = first_scale if curv_fit is None else _scale(curv_fit.curvature, nb, k, d, diameter, spacing)

    best = np.full(n, np.inf)
    pick = np.full(n, -1)
    dominated = np.zeros(n, dtype=bool)  # the chosen row's error is mostly noise
    local = []  # (fit, K) of every candidate, in the order pick refers to
    scores = []  # (rows, predicted error, its bias part) of every candidate
    widths = np.zeros(n, dtype=np.int64)  # neighbours of the whole cloud the chosen row spans

    def consider(fit: RowFit, K: int) -> np.ndarray:
        rows = fit.centers
        err, bias = _errors(fit, sig[rows], scale[rows])
        scores.append((rows, err, bias))
        better = err < best[rows]
        best[rows[better]] = err[better]
        pick[rows[better]] = len(local)
        widths[rows[better]] = K
        local.append((fit, K))
        noisy = (ROW_GAMMA * sig[rows] * scale[rows] * fit.amplification > 0.5 * err) & (sig[rows] > rounding)
        dominated[rows[better]] = noisy[better]
        return rows[better & noisy]

    tick("compare")
    for fit, K in cands:
        consider(fit, K)
    # a clean point whose row turns out noise-dominated (noise between the sample's points), or
    # whose top-degree fit leaves shape in its residual (a crease), has the degree-2 candidates
    # fitted after all
    rough = np.zeros(n, dtype=bool)
    for fit, _ in clean:
        rough[fit.centers] = fit.residual > ROW_EXCESS * sig[fit.centers]
    suspect = np.flatnonzero(fast & (dominated | rough) & own)
    if len(suspect):
        tick("noise fit")
        consider(*measured(K2, ROW_C_COMPACT, suspect))
        consider(*measured(Kn, ROW_C_WIDE, suspect))
    K = Kn
    pick[~own] = -1  # the halo's rows are not built here
    active = np.flatnonzero(dominated & own)
    while len(active) and K < Kmax:
        K = min(Kmax, int(round(K * ROW_LADDER)))
        tick(f"rung {K}")
        grown = []
        # (its degree-2 rows at the curvature fit's width are that fit's)
        reuse = K == Kc and curv_fit is not None
        near, rows = (_table(idx_c, dist_c), active) if reuse else (_table(*spread(K, active)[:2]), None)
        want = tuple(q for q in ((4, 2) if max_degree >= 4 else (2,)) if not (reuse and q == 2))
        fits = _candidate(P, near, near[0].shape[1], rows, want, ROW_C_WIDE, k, normals, active, False,
                          place) if want else []
        for fit in ([_restrict(curv_fit, active)] if reuse else []) + fits[::-1]:  # degree 2 first
            grown.append(consider(fit, K))
        active = np.unique(np.concatenate(grown))
    # robust to clean f on a noisy surface: among the candidates within ROW_ROBUST of the least
    # predicted error, the one of least bias (the noise term assumes f sampled at the noisy
    # points; a smooth f there is served by the lower bias)
    least_bias = np.full(n, np.inf)
    least = best.copy()
    for i, (rows, err, bias) in enumerate(scores):
        ok = (err <= ROW_ROBUST * least[rows]) & (bias < least_bias[rows]) & (pick[rows] >= 0)
        least_bias[rows[ok]] = bias[ok]
        pick[rows[ok]] = i
        widths[rows[ok]] = local[i][1]
        best[rows[ok]] = err[ok]
    capped = len(active) and Kmax < total
    if capped:
        notes.append(f"{len(active)} points would take rows wider than {Kmax} neighbours: the noise is "
                     "more than the widest stencil averages out; pass max_neighbors or a fixed h")
    failed = (pick < 0) & own
    if failed.any():
        notes.append(f"{int(failed.sum())} points have no row of degree >= 2 (degenerate neighbourhoods)")
    # reaching the widest rung is reported (RowChoice.notes), not warned: the rows are then
    # those of the widest stencil, still the best of the ladder
    for note in notes:
        if not note.startswith(f"{len(active)} points would take"):
            warnings.warn(f"choose_rows: {note}", MeshWarning, stacklevel=2)

    tick("assemble")
    degree = np.full(n, -1)
    hv = np.zeros(n)
    for i, (fit, _) in enumerate(local):
        rows = np.flatnonzero(pick == i)
        if len(rows):
            pos = np.searchsorted(fit.centers, rows)
            degree[rows] = fit.degree[pos]
            hv[rows] = fit.h[pos]
    L = _assemble(n, pick, local, refit)
    return L, RowChoice(degree, widths, hv, sig, scale, best, spacing, notes)


def wider_rows(P: Any, choice: RowChoice, *, k: int = 2, normals: Any = None, factor: float = 2.0
               ) -> sp.csr_matrix:
    """The rows of ``choice`` again, each of its degree on ``factor`` times its neighbours and
    width h: the second operator of :meth:`meshlap.MeshLaplacian.error_estimate`.

    A row of degree q errs as ρ^{q−1} on clean data (ρ its radius, measured orders 1.0, 3.0,
    5.1 for q = 2, 4, 6), so its error is about |L f − L' f| / (factor^{(q−1)/2} − 1); where
    noise dominates, the wider row averages more of it and the difference is the noise.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> P = meshlap.shapes.fibonacci_sphere(2000)
    >>> L, choice = choose_rows(P)
    >>> W = wider_rows(P, choice)
    >>> x = P[:, 0]
    >>> bool(np.abs(W @ x**2 - (2 - 6 * x**2)).max() < 1e-3)
    True
    """
    P = np.ascontiguousarray(check_points(P, "P"), dtype=np.float64)
    n = len(P)
    tree = cKDTree(P)
    spread = _Spread(P, tree, ROW_SAMPLE)
    out = sp.csr_matrix((n, n))
    ok = choice.degree >= 2
    for q, K in sorted(set(zip(choice.degree[ok].tolist(), choice.neighbors[ok].tolist(), strict=True))):
        centers = np.flatnonzero(ok & (choice.degree == q) & (choice.neighbors == K))
        idx, _, Kw = spread(int(round(factor * K)), centers)
        indptr = np.arange(len(centers) + 1, dtype=np.int64) * Kw
        out = out + pointwise_rows(P, indptr, idx.ravel(), factor * choice.h[centers], q, k=k,
                                   normals=normals, centers=centers)
    return sp.csr_matrix(out)
