"""The noise level σ̂ and the geometric scale ℓ of :func:`meshlap.corrections.rowchoice.choose_rows`
per point: medians, over each point's nearest, of what the fits measured there (the residuals
of the local height fits, the curvature of a degree-2 fit)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ._fit_kernel import neighbour_medians
from ._ranks import _median


def _local_noise(resid: np.ndarray, nb: np.ndarray, comm: Any, own: np.ndarray, noise: float | None
                 ) -> tuple[np.ndarray, float | None]:
    # σ̂ per point, the median of its neighbours' least residuals (one noisy fit does not decide
    # a point's row), or the noise given; and the median over the points (None: no fit left
    # degrees of freedom to estimate it, σ̂ then 0)
    typical = _median(comm, resid[own & np.isfinite(resid)])
    if noise is not None:
        return np.full(len(resid), float(noise)), typical
    if typical is None:
        return np.zeros(len(resid)), None
    # an all-NaN neighbourhood takes the typical level
    finite = np.where(np.isfinite(resid), resid, np.nan)
    return np.nan_to_num(_medians(finite, nb, True), nan=typical), typical


def _medians(values: np.ndarray, nb: np.ndarray, skip_nan: bool) -> np.ndarray:
    # np.nanmedian(values[nb], axis=1) (skip_nan) or np.median, the same numbers compiled
    out = np.empty(len(nb))
    neighbour_medians(np.ascontiguousarray(values, dtype=np.float64), nb, skip_nan, out)
    return out


def _scale(curvature: np.ndarray, nb: np.ndarray | None, k: int, d: int, diameter: float, spacing: float
           ) -> np.ndarray:
    # ℓ = 1/κ, κ the median of a fit's curvature over the neighbours nb (those a fit measured it
    # at: NaN elsewhere; nb None: each point's own), from 4 spacings to the diameter (a volume,
    # k = d, has no curvature: the diameter)
    if k >= d:
        kappa = np.zeros(len(curvature))
    else:
        kappa = curvature if nb is None else np.nan_to_num(_medians(curvature, nb, True), nan=0.0)
    return np.maximum(np.minimum(1.0 / np.maximum(kappa, 1e-300), diameter), 4.0 * spacing)
