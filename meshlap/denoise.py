"""Noise along the normals of a surface mesh, and the step that takes it out of the metric.

Normal noise of size σ on a mesh of mean edge ē tilts its triangles by about σ/ē, which inflates
their areas and shortens their cotangent paths: linear FEM on the noisy mesh is off by
O(σ²/ē²) (0.1 ē of noise: 2.5% on eigenvalues 1-9 of spot and fandisk; 0.3 ē: 16%), whatever
its resolution. One implicit step of the bi-Laplacian flow of time τ = (c σ̂)²,
``(M + τ²SM⁻¹S) X' = M X``, takes it out: it damps a displacement of eigenvalue μ by
1/(1 + τ²μ²), the vertex-scale noise (μ of order 1/ē²) by a factor set by (σ/ē)⁴, while it moves
a smooth shape of curvature κ by O(τ²κ⁴) of its size, where the heat step (M − τS) X' = M X
moves it by O(τκ²): on a cylinder of radius r a few edges across (a coarse model's leg) the heat
step shrinks the shape as much as it removes noise, this one by (σ̂/r)² less. On five real
meshes with noise (``benchmarks/bench_real.py``) the two are alike where the shape is resolved
(0.3 ē: 1.9-4.9% against the heat step's 1.1-4.2%) and this one keeps the coarse cow (11% against
20%; COT 17%). σ̂ is measured, not set: the residual of local cubic height fits, whose misfit on
a clean surface is a quartic term far below any noise that matters (a clean 4,000-vertex sphere:
below 1e-4).

Whether noise is there is measured too: where it dominates what smoothing takes out, its
bi-Laplacian alternates across edges as white noise's does, where shape dominates it is smooth
(:func:`noise_extent`, which counts edges, so a coarse model's few unresolved ones do not
outweigh the rest). The step leaves part of the noise, whose area still inflates the metric by
the same mechanism (eigenvalues 1.2-1.9% low after it at 0.1 mean edges): that area is read
from what the step took out (:func:`noise_share`, :func:`area_left`) and divided out of the
pencil's masses.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from . import fem
from ._cg import block_pcg
from ._ldl import factor
from .geometry import frames
from .tuned import NOISE_AREA, NOISE_QUANTILE, NOISE_STEP

__all__ = ["NEIGHBOURS", "SAMPLE", "STEP_ITERATIONS", "NoiseStep", "area_left", "kept_shapes", "noise_extent",
           "noise_share", "noise_step", "normal_noise", "step_solver", "surface_noise", "white_noise"]

#: Neighbours of each cubic height fit: 10 coefficients, 14 degrees of freedom left.
NEIGHBOURS = 24
#: At most this many vertices are fitted (evenly spaced in the input order): the median of
#: their variances is read, and it is stable well before this count.
SAMPLE = 20000


def normal_noise(P: np.ndarray, normals: np.ndarray | None = None) -> float:
    """σ̂: the normal noise seen by cubic height fits, at the lower quartile over the vertices.

    Each fitted vertex takes its :data:`NEIGHBOURS` nearest vertices, their principal frame
    (the smallest principal direction the normal), and fits the heights by a cubic in the
    two tangent coordinates; the residual's variance over its degrees of freedom estimates
    σ² there, and the :data:`~meshlap.tuned.NOISE_QUANTILE` over the vertices passes over
    creases and corners, which a cubic does not fit.

    Parameters
    ----------
    P : (n, 3) ndarray
        Vertex positions of a surface.
    normals : (n, 3) ndarray, optional
        Unused unless given: the frame's normal where the principal one is ambiguous.

    Returns
    -------
    float
        σ̂ in the units of P (0 for fewer than NEIGHBOURS points).

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(4000, seed=0)
    >>> noisy = V * (1 + 0.004 * np.random.default_rng(0).standard_normal((4000, 1)))
    >>> bool(0.7 < normal_noise(noisy) / 0.004 < 1.1), normal_noise(V) < 1e-4   # its lower quartile
    (True, True)
    """
    P = np.asarray(P, dtype=np.float64)
    n = len(P)
    if n < NEIGHBOURS or P.shape[1] != 3:
        return 0.0
    rows = np.arange(0, n, max(1, n // SAMPLE))
    T, idx = frames.pca_frames(P, 2, NEIGHBOURS - 1, rows)
    res, dof = frames.height_residuals(P, T, idx, 2, (3,))
    return float(np.sqrt(np.quantile(res[0] / dof[0], NOISE_QUANTILE)))


def surface_noise(geo: Any) -> float:
    """The normal noise σ̂ of a surface mesh in R³ (:func:`normal_noise`), once
    per geometry; 0 for other inputs and where it is below a thousandth of the mean edge (its
    step would move nothing).

    Examples
    --------
    >>> import meshlap
    >>> surface_noise(meshlap.geometry.from_mesh(*meshlap.shapes.sphere(2000, seed=0)))
    0.0
    """
    def make() -> float:
        if geo.faces is None or geo.ambient_dim != 3:
            return 0.0
        sigma = normal_noise(geo.points)
        return sigma if sigma > 1e-3 * geo.spacing else 0.0

    return geo._cached("normal_noise", make)


#: Conjugate-gradient iterations of the step before it is solved by a sparse LU instead
STEP_ITERATIONS = 500


def step_solver(S: sp.spmatrix, m: np.ndarray, tau: float) -> Callable[[np.ndarray], np.ndarray]:
    """X ↦ X': one implicit step of the bi-Laplacian flow, (M + τ²SM⁻¹S) X' = M X (S ≈ MΔ,
    negative semidefinite; M = diag(m)).

    A displacement along an eigenvector of (−S, M) of eigenvalue μ is damped by 1/(1 + τ²μ²):
    vertex-scale noise (τμ of order one or more) is taken out while a shape of curvature κ
    moves by O(τ²κ⁴) of its size, against the heat step's O(τκ²) (module docstring). The step
    keeps the centroid of every part. The system is symmetric positive definite and, at the
    steps noise asks for, well conditioned: conjugate gradients with its diagonal as
    preconditioner, from X, solve it to 1e-12 (a 100,000-vertex sphere: 0.18 s with
    :func:`noise_share`). Where they do not converge in :data:`STEP_ITERATIONS` (tiny elements
    beside large ones), it is solved
    exactly as the real part of (M − iτS)⁻¹ M X, since 1/(1 + τ²μ²) = Re 1/(1 − iτμ): one
    complex sparse LU with the sparsity of S (22 s at 100,000 vertices). Vertices without mass
    keep their positions.

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> S = sp.csr_matrix(np.array([[-1.0, 1], [1, -1]]))     # μ = 2 for (-1, 1)
    >>> np.round(step_solver(S, np.ones(2), 0.5)(np.array([[0.0], [1.0]])), 12).ravel().tolist()  # 1/2
    [0.25, 0.75]
    """
    m = np.asarray(m, dtype=np.float64)
    massless = m <= 0
    S = sp.csr_matrix(S)
    inv = np.divide(1.0, m, out=np.zeros_like(m), where=~massless)
    weight = np.where(massless, 1.0, m)  # a massless vertex's row: x = X

    def apply(X: np.ndarray) -> np.ndarray:
        return weight[:, None] * X + tau * tau * (S @ (inv[:, None] * (S @ X)))

    jacobi = 1.0 / (weight + tau * tau * (S.multiply(S) @ inv))
    # complex symmetric with a positive definite real part: no pivoting is needed
    exact = functools.cache(lambda: factor(sp.diags(weight) - 1j * tau * S))

    def solve(X: np.ndarray) -> np.ndarray:
        X = np.asarray(X, dtype=np.float64)
        X2 = X.reshape(len(m), -1)
        B = weight[:, None] * X2
        out, _, converged = block_pcg(apply, lambda R: jacobi[:, None] * R, B, 1e-12, STEP_ITERATIONS,
                                      X2.copy())
        if not converged:
            out = exact().solve(B.astype(np.complex128)).real
        out[massless] = X2[massless]
        return out.reshape(X.shape)

    return solve


def white_noise(solve: Callable[[np.ndarray], np.ndarray], n: int) -> tuple[np.ndarray, np.ndarray]:
    """Seeded unit white noise on ``n`` vertices, and what the step ``solve`` leaves of it.

    Examples
    --------
    >>> w, left = white_noise(lambda X: 0.5 * X, 4)
    >>> bool(np.allclose(left, 0.5 * w))
    True
    """
    w = _seeded_white(n)
    return w, solve(w[:, None])[:, 0]


def _seeded_white(n: int) -> np.ndarray:
    # the same unit white noise for every reading of the same mesh
    return np.random.default_rng(0).standard_normal(n)


def _share_bound(rho: float, rho_white: float) -> float:
    # ρ = qρ_w + (1 − q)ρ_s with ρ_s ≥ 0 and ρ_w < 0 gives q ≥ ρ/ρ_w
    return float(np.clip(rho / rho_white, 0.0, 1.0)) if rho_white < 0 else 0.0


def _edge_correlation(f: np.ndarray, edges: np.ndarray) -> float:
    a, b = f[edges[:, 0]], f[edges[:, 1]]
    return float((a * b).sum() / max(0.5 * (a * a + b * b).sum(), 1e-300))


def noise_extent(P: np.ndarray, normals: np.ndarray, S: sp.spmatrix, m: np.ndarray,
                 edges: np.ndarray) -> float:
    """A lower bound on the share of a surface's edges across which independent noise, not
    shape, is what a smoothing step takes out.

    For a small step any smoothing flow takes out the bi-Laplacian of the positions, B X with
    B = (M⁻¹S)², first. Across an edge where the noise's part of it dominates, its signs at the
    two ends agree as white noise's do (mean sign product ρ_w < 0, measured with the same B on
    seeded white noise); where the shape's dominates, as a smooth field's do (ρ_s ≥ 0). With f
    the share of the former edges, the mean sign product along the normals is
    ρ = fρ_w + (1 − f)ρ_s ≥ fρ_w, so f ≥ ρ/ρ_w: no constant. Signs count every edge alike, so a
    coarse model's unresolved parts (legs a few edges around), which carry most of the shape's
    energy on a few edges, do not outweigh noise over the rest of the surface. Noise too small to
    matter is the amplitude's question, not this one (``NOISE_FLOOR``).

    Parameters
    ----------
    P, normals : (n, 3) ndarray
        Positions and unit vertex normals.
    S, m : sparse matrix, (n,) ndarray
        The surface's pencil (S ≈ MΔ, M = diag(m)); massless vertices are left out.
    edges : (e, 2) int ndarray
        The mesh's edges.

    Returns
    -------
    float
        In [0, 1].

    Examples
    --------
    >>> import meshlap
    >>> from meshlap import fem
    >>> V, F = meshlap.shapes.sphere(2000, seed=0)
    >>> def extent(P):
    ...     g = meshlap.geometry.from_mesh(P, F)
    ...     return noise_extent(g.points, g.normals(), *fem.lumped_pencil(g), g.edges())
    >>> noisy = V * (1 + 0.01 * np.random.default_rng(1).standard_normal((2000, 1)))   # 0.1 mean edges
    >>> bool(extent(noisy) > 0.9), extent(V)
    (True, 0.0)
    """
    m = np.asarray(m, dtype=np.float64)
    inv = np.divide(1.0, m, out=np.zeros_like(m), where=m > 0)
    S = sp.csr_matrix(S)

    def bilaplacian(X: np.ndarray) -> np.ndarray:
        return inv[:, None] * (S @ (inv[:, None] * (S @ X)))

    live = m > 0
    edges = edges[live[edges[:, 0]] & live[edges[:, 1]]]

    def sign_product(f: np.ndarray) -> float:
        return float(np.mean(np.sign(f[edges[:, 0]]) * np.sign(f[edges[:, 1]]))) if len(edges) else 0.0

    d = np.einsum("ij,ij->i", bilaplacian(np.asarray(P, dtype=np.float64)), normals)
    return _share_bound(sign_product(d), sign_product(bilaplacian(_seeded_white(len(m))[:, None])[:, 0]))


def noise_share(removed: np.ndarray, white_removed: np.ndarray, edges: np.ndarray) -> float:
    """A lower bound on the share of independent noise in what a step took out along the
    normals, from its correlation across the mesh's edges.

    ``removed``, the normal part of what the step took out, is the noise's part, which the step
    passes as it passes white noise (its edge correlation ρ_w, negative: the step keeps each
    vertex's average with its neighbours), plus the shape's part, smooth across an edge
    (ρ_s ≥ 0). With q the noise's share, its correlation is ρ = qρ_w + (1 − q)ρ_s ≥ qρ_w, so
    q ≥ ρ/ρ_w. ρ_w is measured by the same step on white noise (:func:`white_noise`), so the
    bound needs no constant.

    Parameters
    ----------
    removed : (n,) ndarray
        The normal part of what the step took out of the positions.
    white_removed : (n,) ndarray
        What the same step took out of seeded white noise (:func:`white_noise`: w − left).
    edges : (e, 2) int ndarray
        The mesh's edges.

    Returns
    -------
    float
        In [0, 1]; 0 where the removed field is no rougher than white noise after the step.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> from meshlap import fem
    >>> V, F = meshlap.shapes.sphere(2000, seed=0)
    >>> noisy = V * (1 + 0.01 * np.random.default_rng(1).standard_normal((2000, 1)))
    >>> def share(P):
    ...     g = meshlap.geometry.from_mesh(P, F)
    ...     solve = step_solver(*fem.fem_pencil(g), 4e-4)
    ...     w, left = white_noise(solve, len(P))
    ...     removed = np.einsum("ij,ij->i", P - solve(P), g.normals())
    ...     return noise_share(removed, w - left, g.edges())
    >>> bool(share(noisy) > 0.5), bool(share(V) < 0.1)
    (True, True)
    """
    return _share_bound(_edge_correlation(removed, edges), _edge_correlation(white_removed, edges))


def area_left(removed: np.ndarray, white: np.ndarray, white_left: np.ndarray, S: sp.spmatrix,
              m: np.ndarray, share: float) -> float:
    """The share of a surface's area that the noise a step left still adds.

    Normal noise n over a surface adds ∫|∇n|²/2 to its area, nᵀ(−S)n/2 on the mesh, and the
    metric it leaves is inflated that much. The noise's variance is read from what the step took
    out: its share (at least ``share``, :func:`noise_share`) of the removed normal energy, over
    the share of white noise's energy the step takes out. What the step leaves of the noise is
    what it leaves of white noise at that variance.

    Parameters
    ----------
    removed : (n,) ndarray
        The normal part of what the step took out of the positions.
    white, white_left : (n,) ndarray
        Seeded white noise and what the step left of it (:func:`white_noise`).
    S, m : sparse matrix, (n,) ndarray
        The pencil the step was taken with (S ≈ MΔ, negative semidefinite; M = diag(m)).
    share : float
        The noise's share of ``removed``.

    Returns
    -------
    float
        Area added over the surface's area (0 where no noise was read).

    Examples
    --------
    >>> import meshlap
    >>> from meshlap import fem
    >>> V, F = meshlap.shapes.sphere(2000, seed=0)
    >>> noisy = V * (1 + 0.01 * np.random.default_rng(1).standard_normal((2000, 1)))   # 0.1 mean edges
    >>> g = meshlap.geometry.from_mesh(noisy, F)
    >>> S, m = fem.lumped_pencil(g)
    >>> solve = step_solver(S, m, 4e-4)
    >>> w, left = white_noise(solve, 2000)
    >>> removed = np.einsum("ij,ij->i", noisy - solve(noisy), g.normals())
    >>> share = noise_share(removed, w - left, g.edges())
    >>> round(float(m.sum()) / (4 * np.pi) - 1, 3), round(area_left(removed, w, left, S, m, share), 3)
    (0.027, 0.02)

    The noise added 2.7% to the sphere's area; the step leaves 2.3% (the area of its output).
    """
    white_removed = white - white_left
    variance = share * float(m @ removed**2) / max(float(m @ white_removed**2), 1e-300)
    return 0.5 * variance * float(white_left @ -(S @ white_left)) / float(m.sum())


@dataclass(frozen=True)
class NoiseStep:
    """The denoising step of a surface mesh (:func:`noise_step`).

    Attributes
    ----------
    points : (n, 3) ndarray
        The positions after the step (the input's where no noise was seen).
    sigma : float
        σ̂ (:func:`normal_noise`; 0 below a thousandth of the mean edge).
    share : float
        :func:`noise_share` of what the step took out.
    area_left : float
        :func:`area_left`: the share of the area the noise the step left still adds, at most
        what all the noise σ̂ reads adds, NOISE_AREA·(σ̂/ē)²; the denoised pencil's masses are
        divided by 1 + area_left.
    """

    points: np.ndarray
    sigma: float
    share: float
    area_left: float = 0.0


def noise_step(geo: Any) -> NoiseStep:
    """The step of time (NOISE_STEP·σ̂)² on a surface mesh's vertices, with the lumped linear-FEM
    pencil, and the share of noise in what it took out; once per geometry.

    Examples
    --------
    >>> import meshlap, numpy as np
    >>> V, F = meshlap.shapes.sphere(2000, seed=0)
    >>> noise_step(meshlap.geometry.from_mesh(V, F)).sigma           # a clean sphere: nothing to take out
    0.0
    >>> noisy = V * (1 + 0.01 * np.random.default_rng(1).standard_normal((2000, 1)))   # 0.1 mean edges
    >>> g = meshlap.geometry.from_mesh(noisy, F)
    >>> step = noise_step(g)
    >>> round(step.sigma / g.spacing, 2), step.share      # σ̂ in mean edges; all it took out is noise
    (0.1, 1.0)
    """
    def make() -> NoiseStep:
        sigma = surface_noise(geo)
        if sigma <= 0:
            return NoiseStep(geo.points, 0.0, 0.0)
        S, m = fem.lumped_pencil(geo)
        solve = step_solver(S, m, (NOISE_STEP * sigma) ** 2)
        X = solve(geo.points)
        # the input's normals: a vertex whose faces nearly cancel has no normal to speak of, and
        # those of the step's output would turn with the roundoff of its solve
        removed = np.einsum("ij,ij->i", geo.points - X, geo.normals())
        w, left = white_noise(solve, len(m))
        share = noise_share(removed, w - left, geo.edges())
        # what the step left of the noise adds no more area than all the noise σ̂ reads adds: where
        # the removed energy says more, its share of noise was shape that looks like noise
        whole = NOISE_AREA * (sigma / geo.spacing) ** 2
        return NoiseStep(X, sigma, share, min(area_left(removed, w, left, S, m, share), whole))

    return geo._cached("noise_step", make)


def kept_shapes(P: np.ndarray, X: np.ndarray, area: np.ndarray, area_after: np.ndarray, label: np.ndarray,
                noise: float) -> tuple[np.ndarray, np.ndarray]:
    """``X`` with every part that the step shrank by more than noise could have inflated it
    back at ``P`` (its shape, not its noise, was moved), and which vertices those are.

    Normal noise σ inflates a surface's area by about 1 + NOISE_AREA·(σ/ē)², which the step
    takes back (it leaves 0.84-0.90 of the area at 0.3ē on five scans; the clean meshes have
    0.82-0.86). A part that loses more than noise of 2σ̂ would have added,
    1/(1 + NOISE_AREA·(2σ̂/ē)²), is one the mesh does not resolve (two 7-vertex legs of a coarse
    ant keep 0.017 of their area): the step is a denoiser only where the shape is resolved.

    Parameters
    ----------
    P, X : (n, d) ndarray
        The positions before and after the step.
    area, area_after : (n,) ndarray
        The vertices' masses (areas) before and after.
    label : (n,) int ndarray
        The part of every vertex.
    noise : float
        σ̂ / ē.

    Returns
    -------
    points : (n, d) ndarray
        ``X`` itself where no part was kept, else a copy with the kept parts at ``P``.
    kept : (n,) bool ndarray
        The vertices of the kept parts.

    Examples
    --------
    >>> P, X, part = np.zeros((4, 3)), np.ones((4, 3)), np.array([0, 0, 1, 1])
    >>> points, kept = kept_shapes(P, X, np.ones(4), np.array([0.9, 0.9, 0.1, 0.1]), part, 0.2)
    >>> points[:, 0], kept
    (array([1., 1., 0., 0.]), array([False, False,  True,  True]))
    """
    before = np.bincount(label, area)
    after = np.bincount(label, area_after, minlength=len(before))
    kept = (after < before / (1.0 + NOISE_AREA * (2.0 * noise) ** 2))[label]
    if not kept.any():
        return X, kept
    out = np.array(X, copy=True)
    out[kept] = P[kept]
    return out, kept
