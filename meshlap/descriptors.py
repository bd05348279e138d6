"""Spectral shape descriptors and spectral projection, from the eigenpairs of any operator.

Each function takes an operator (and computes its eigenpairs with :func:`meshlap.spectral.eigs`)
or precomputed ``eig=(lam, phi)``, with φ M-orthonormal (``phiᵀ M phi = I``), so that the
numbers can be compared with other libraries' when they are fed the same eigenpairs:

* :func:`shape_dna`: Reuter, Wolter and Peinecke's ShapeDNA (CAD 2006), the eigenvalues, with
  LaPy's normalisations (``lapy.shapedna.normalize_ev``: times the area for a surface, times
  the volume^(2/3) for a solid; generally times |Ω|^(2/k), which makes the spectrum of a
  k-dimensional shape scale-invariant) and re-weighting (``reweight_ev``: λ_i / i, i from 1);
* :func:`wave_kernel_signature`: Aubry, Schlickewei and Cremers' WKS (ICCV workshops 2011)
  with pyFM's conventions (``pyFM.signatures.WKS_functions.auto_WKS``): eigenvalues below 1e-5
  dropped, a grid of ``n_energies`` log-energies from log λ_1 to log λ_k (λ_1 the first
  non-zero eigenvalue) narrowed by 2σ at each end, σ = 7 (log λ_k - log λ_1) / n_energies,
  and each energy's signature divided by the sum of its filter's weights (``scaled=True``);
* :func:`~meshlap.spectral.heat_kernel_signature` (Sun, Ovsjanikov and Guibas 2009), kept in
  :mod:`meshlap.spectral` and re-exported here;
* :func:`project` and :func:`reconstruct`: a function's coefficients ``phiᵀ M f`` in the
  eigenbasis and back (pyFM's ``project`` and ``decode``).

``area_normalize=True`` multiplies the WKS by the measure |Ω| of the shape: the squared
eigenfunctions scale like |Ω|⁻¹, so the product is invariant under scaling (the log-energy
grid moves with the eigenvalues), as well as under rigid motions.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .errors import MeshError
from .geometry.validation import check_function, check_int
from .spectral import eigs, heat_kernel_signature

__all__ = ["heat_kernel_signature", "project", "reconstruct", "shape_dna", "wave_kernel_signature"]

# pyFM's threshold below which an eigenvalue counts as zero, on a shape of unit measure (so here
# λ|Ω|^(2/d) < 1e-5: a globe in metres has λ₁ = 5e-20); given eigenpairs alone, λ below 1e-8 of
# the largest (eigs' zeros lie near 1e-12 of it); and pyFM's filter width in grid steps
_ZERO = 1e-5
_ZERO_ALONE = 1e-8
_WKS_WIDTH = 7.0


def _eig(op: Any, k: int, eig: Any) -> tuple[np.ndarray, np.ndarray]:
    if eig is None:
        if op is None:
            raise MeshError("give an operator or precomputed eig=(lam, phi)")
        eig = eigs(op, k)
    lam, phi = (np.asarray(a, dtype=np.float64) for a in eig)
    if lam.ndim != 1 or phi.ndim != 2 or phi.shape[1] != len(lam) or not np.isfinite(lam).all():
        raise MeshError(f"eig must be (lam (k,), phi (n, k)), finite; got shapes {lam.shape} and {phi.shape}")
    return lam, phi


def _measure(op: Any, measure: float | None) -> float:
    if measure is not None:
        return float(measure)
    if op is None:
        raise MeshError("normalising needs the operator (its masses) or measure=|Ω|")
    return float(np.sum(op.mass))


def shape_dna(op: Any = None, k: int = 50, *, eig: Any = None, normalize: str | None = "geometry",
              reweight: bool = False, measure: float | None = None, dim: int | None = None) -> np.ndarray:
    """ShapeDNA: the k smallest eigenvalues of -Δ, normalised as LaPy does.

    Parameters
    ----------
    op : operator, optional
        The Laplacian; not needed with ``eig`` and ``measure`` (or ``normalize=None``).
    k : int, default 50
        Eigenvalues when ``eig`` is not given (the zero eigenvalue included, as in LaPy).
    eig : (lam, phi), optional
        Precomputed eigenpairs.
    normalize : {"geometry", None}
        ``"geometry"``: λ · |Ω|^(2/k) with |Ω| the total mass (area of a surface: LaPy's
        "surface"; volume of a solid: LaPy's "volume"/"geometry" for a TetMesh; length² of a
        curve); None: the raw eigenvalues.
    reweight : bool, default False
        Divide the i-th eigenvalue by i (1-based), LaPy's ``reweight_ev``.
    measure : float, optional
        |Ω| when ``op`` is not given (e.g. the area LaPy used).
    dim : int, optional
        Intrinsic dimension when ``op`` is not given (default 2).

    Returns
    -------
    (k,) ndarray

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(1000, seed=0)
    >>> op = meshlap.laplacian(V, F)
    >>> dna = shape_dna(op, k=4)                 # 4π · (0, 2, 2, 2) on the unit sphere
    >>> bool(np.allclose(dna, 4 * np.pi * np.array([0, 2, 2, 2]), atol=0.3))
    True
    """
    if normalize not in ("geometry", None):
        raise MeshError(f"normalize must be 'geometry' or None; got {normalize!r}")
    lam, _ = _eig(op, k, eig)
    out = lam.copy()
    if normalize == "geometry":
        kdim = int(dim if dim is not None else getattr(op, "dim", 2))
        out = out * _measure(op, measure) ** (2.0 / kdim)
    if reweight:
        out = out / np.arange(1, len(out) + 1)
    return out


def wave_kernel_signature(op: Any = None, n_energies: int = 100, k: int = 100, *, eig: Any = None,
                          scaled: bool = True, area_normalize: bool = False,
                          measure: float | None = None) -> np.ndarray:
    r"""Wave kernel signature WKS(x, e) = Σ_i φ_i(x)² f_e(λ_i)², f_e² a Gaussian in log λ.

    With pyFM's grid, width and scaling (module notes).

    Parameters
    ----------
    op : operator, optional
        The Laplacian; not needed when ``eig`` is given.
    n_energies : int, default 100
        Number of log-energies (pyFM's ``num_E``).
    k : int, default 100
        Eigenpairs when ``eig`` is not given.
    eig : (lam, phi), optional
        Precomputed eigenpairs (ascending).
    scaled : bool, default True
        Divide each energy's column by the sum of its filter's weights (pyFM's ``scaled``).
    area_normalize : bool, default False
        Multiply by |Ω| (total mass, or ``measure``): invariant under scaling.

    Returns
    -------
    (n, n_energies) ndarray

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(1500, seed=0)
    >>> w = wave_kernel_signature(meshlap.laplacian(V, F), n_energies=10, k=36)   # degrees ≤ 5
    >>> w.shape, bool((w.std(axis=0) < 0.01 * w.mean(axis=0)).all())    # alike everywhere
    ((1500, 10), True)
    """
    check_int(n_energies, "n_energies", 1)
    lam, phi = _eig(op, k, eig)
    if op is not None or measure is not None:
        d = getattr(op, "dim", 2)
        keep = lam * _measure(op, measure) ** (2.0 / d) > _ZERO
    else:
        keep = lam > _ZERO_ALONE * max(float(lam.max()), 0.0)
    if keep.sum() < 2:
        raise MeshError(f"the WKS needs at least two non-zero eigenvalues; {len(lam) - int(keep.sum())} of "
                        f"the {len(lam)} are zero (one per part): ask for more (k)")
    log_lam = np.log(np.abs(lam[keep]))
    phi = phi[:, keep]
    e_min, e_max = float(log_lam[0]), float(log_lam[-1])
    sigma = _WKS_WIDTH * (e_max - e_min) / n_energies
    energies = np.linspace(e_min + 2 * sigma, e_max - 2 * sigma, n_energies)
    coef = np.exp(-((energies[:, None] - log_lam[None, :]) ** 2) / (2 * sigma**2))  # (E, K)
    out = (phi * phi) @ coef.T
    if scaled:
        out /= coef.sum(axis=1)[None, :]
    if area_normalize:
        out *= _measure(op, measure)
    return out


def project(op: Any, f: Any, k: int = 100, *, eig: Any = None) -> np.ndarray:
    """Coefficients ``phiᵀ M f`` of f in the M-orthonormal eigenbasis: (k,) or (k, s).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(1000, seed=0)
    >>> op = meshlap.laplacian(V, F)
    >>> eig = meshlap.spectral.eigs(op, 9)
    >>> f = V[:, 2] + V[:, 0] * V[:, 1]                  # degrees 1 and 2
    >>> err = np.abs(reconstruct(eig, project(op, f, eig=eig)) - f).max()
    >>> bool(err < 0.02)
    True
    """
    lam, phi = _eig(op, k, eig)
    f = check_function(f, phi.shape[0])
    mass = np.asarray(op.mass, dtype=np.float64)
    return phi.T @ (mass.reshape(-1, *([1] * (f.ndim - 1))) * f)


def reconstruct(eig: Any, coef: Any) -> np.ndarray:
    """The function ``phi @ coef`` with the given coefficients (the first len(coef) eigenvectors)."""
    lam, phi = _eig(None, 0, eig)
    c = np.asarray(coef, dtype=np.float64)
    if c.ndim not in (1, 2) or c.shape[0] > phi.shape[1] or not np.isfinite(c).all():
        raise MeshError(f"coef must be (m,) or (m, s) with m ≤ {phi.shape[1]} finite values; got {c.shape}")
    return phi[:, : c.shape[0]] @ c
