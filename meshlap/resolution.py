"""Can the kernel resolve this input? A report at build time, and a warning when its peer will win.

The heat kernel of width h averages over a disc of radius about √(2h). Where the input is
coarse against that width, the default operator's eigenvalues are less accurate than those of
linear finite elements (the cotangent Laplacian of a surface mesh, LaPy's on tetrahedra).
:func:`assess` reads the geometry and the chosen widths, measures what decides it, and
predicts the largest relative error of eigenvalues 1..:data:`EIGENVALUES` for the default and
for its peer (linear FEM; on a surface's point cloud, robust-laplacian):

* the default: ``A_H·b·hλ + A_2·b·(hλ)² + A_Q·hλ·(q/0.3)²·min(ρ/R_0, 1)^-P_Q +
  A_W·(q/0.3)^Q_W·max(1/ρ − 1/R_W, 0)^P_W + A_B·β·(hλ)^1.5 + A_K·hλ·κ_b + A_C·c·√(hλ) +
  A_N·ν²``, with hλ the mean width times Weyl's estimate of λ_9 (the width against the
  wavelength), b how much the surface bends (1 − |mean normal|: 0 on a flat domain), q the
  irregularity of the sampling (spread of the edge lengths), ρ the width in squared edges over
  its default ratio (below 1 where the curvature cap narrowed it or an explicit h is narrower:
  the A_W term, the sampling's quadrature error, does not shrink with hλ; on a point cloud,
  whose nearest-neighbour edges spread more than a mesh's, it is ``C_W·(max(q − Q_C, 0)/0.1)^P_C
  ·max(1/ρ − 1/R_W, 0)^P_W·(1 + C_E·ē²λ)``), β the mass within
  √(2h) of the boundary, κ_b the boundary's curvature times √(2h), c the mass within √(2h) of
  a crease and ν the noise in mean edges; where the build took the plain kernel (the
  corrected kernel's -S not semidefinite, or predicted less accurate at an explicit width), on a
  surface mesh ``S_F·(q/0.3)^S_Q·(1 + S_E·ē²λ)·w^-S_PF + (S_P + S_PB·b + S_PC·c)·hλ``, w the width in
  mean edges (its quadrature, and its O(h) bias, larger on curved surfaces and near creases),
  elsewhere ``A_F·w^-P_F + A_P·b·hλ`` (on a point cloud ``C_F·(1 + C_FE·ē²λ)`` in place of ``A_F``);
* linear FEM: ``(F_E + F_Q·q²)·ē²λ·(1 + ē²λ) + F_N·ν²``, ē the mean edge (``F_T·ē²λ`` on
  tetrahedra, ``(F_S + F_SQ·q²)·ē²λ`` on a polyline's segments);
* a surface's point cloud has no cells and no FEM: its peer is robust-laplacian's
  ``point_cloud_laplacian`` (the best of the point-cloud Laplacians measured), ``R_E·ē²λ +
  (R_Q·b + R_F·(1 − b))·max(q − Q_0, 0)^P_R + R_N·σ̂²/a²`` with σ̂²/a² the cloud's normal
  noise over its squared spacing (:func:`meshlap.geometry.pointcloud.noise_ratio`, of the
  points as given): its error on random samplings (q ≈ 0.39) stays near 6-8% on curved
  surfaces however fine, and grows with noise that the default projects away.

The predictions are fits, not bounds: the constants below were calibrated on the rows of
``benchmarks/bench_spectra.py``, on coarser and finer variants of them, on explicit widths of
ē²/2 to 2ē², on the vertex pencil where the default takes the Galerkin one and on point
clouds (docs/spectral.md has the tables, measured and predicted); re-calibrate them here when the
numerics change.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from ._jit import in_blocks, jit
from .corrections.shortcuts import THIN_WIDTHS
from .errors import MeshWarning
from .geometry import Geometry, spatial_order
from .geometry.pointcloud import noise_ratio
from .widths import h_scale

__all__ = ["CLOUD_PEER", "CLOUD_PEER_MODEL", "DEFAULT_MODEL", "EIGENVALUES", "FEM_MODEL",
           "GALERKIN_FEM_RATIO", "GALERKIN_SHORTCUT", "GALERKIN_THIN", "RATIO_LIMIT", "Resolution",
           "ResolutionWarning", "as_fallback", "assess", "default_terms", "fem_error", "peer_error"]

#: The report predicts the largest relative error of eigenvalues 1..EIGENVALUES.
EIGENVALUES = 9
#: The warning fires when the default's predicted error exceeds FEM's by this factor.
RATIO_LIMIT = 1.5
#: A crease vertex sits this many times farther from its neighbours' mean, along its normal,
#: than the median vertex does (noise moves every vertex alike; a crease only its line) ...
CREASE_RATIO = 5.0
#: ... and at least this fraction of its mean edge (a smooth surface's own bending stays below).
CREASE_HEIGHT = 0.1
#: The constants of the default's error model (module docstring), fitted on 71 rows (inputs,
#: explicit widths, pencils) by ``benchmarks/calibrate_resolution.py``, which prints new ones
#: after a change of the numerics; A_K and A_C are kept from the fit on the vertex pencil's
#: inputs (no input there constrains them now). The plain kernel's on surface meshes (``S_*``)
#: are fitted by its ``--kernels`` on 91 rows, both kernels measured at h = 0.3-4 ē² (spheres,
#: tori, spot, a square and a disc of 1,000-100,000 vertices; 0.73-2.4× the measured error).
DEFAULT_MODEL = {"A_H": 0.0131, "A_2": 0.142, "A_Q": 0.00366, "P_Q": 0.571, "R_0": 0.992,
                 "A_B": 0.0789, "A_K": 0.25, "A_C": 0.18, "A_N": 1.24,
                 "A_W": 0.000641, "Q_W": 3.76, "P_W": 2.19, "R_W": 1.0,
                 "A_F": 0.0374, "P_F": 0.548, "A_P": 3.54,
                 # the plain kernel's on surface meshes (``--kernels``)
                 "S_F": 0.0013, "S_Q": 4.09, "S_E": 4.01, "S_PF": 4.68, "S_P": 0.45, "S_PB": 0.317,
                 "S_PC": 8.13,
                 # point clouds' sampling and fallback terms, fitted on their rows alone (``--clouds``)
                 "C_W": 6.23e-05, "Q_C": 0.156, "P_C": 4.24, "C_E": 14.2, "C_F": 0.0417, "C_FE": 7.95}
#: The Galerkin pencil's error over linear FEM's: at most 0.52 on the seven inputs of
#: benchmarks/bench_spectra.py where it is chosen (coarse torus, coarse sphere, cube surface,
#: squares and discs; 0.19-0.52), rounded up; on curves 0.02-0.47 (circles, an ellipse, a
#: trefoil knot and an open arc of 60-1,000 uniform and random vertices).
GALERKIN_FEM_RATIO = 0.55
#: The Galerkin pencil's error per unit of area next to a short cut (``shortcuts``). Pairs are
#: dropped at a path of 1.25 chords (:data:`meshlap.corrections.shortcuts.SHORTCUT_RATIO`):
#: fandisk, 16.2% of its area next to a short cut, 0.142% measured against the 0.042% of the
#: term above, would give at most 0.0062; the cube surface, 23% (pairs across its creases),
#: 0.043% measured, would be warned from 0.0072 on. 0.004 keeps it clear of that.
GALERKIN_SHORTCUT = 0.004
#: The Galerkin pencil's error per unit of area on parts thinner than its kernel whose two
#: sides the short cuts do not separate (:func:`meshlap.corrections.shortcuts.thin_fraction`),
#: fitted on spot: 2.68% of its area (its eigenvalue 5 lives on the teats, 2.4 kernel widths
#: across at their base), 1.32% measured against the 0.44% of the terms above (COT 0.41%,
#: robust-laplacian 0.37%: warned). Fandisk's 0.49% adds 0.16% to an input warned already
#: (0.27% predicted, 0.142% measured); the other Galerkin inputs of the bench have none.
#: Since the width narrows on thin parts (:mod:`meshlap.corrections.features`) spot has 2.1%
#: there, measured 0.96% against COT's 0.41%; this model's FEM prediction for spot is 0.81%,
#: so 0.33 would predict 1.17% (1.45× FEM's: silent); 0.4 (1.32%) keeps it warned.
GALERKIN_THIN = 0.4
#: The constants of linear FEM's, fitted on the same inputs.
FEM_MODEL = {"F_E": 0.0193, "F_Q": 0.418, "F_T": 0.0384, "F_N": 5.68,
             # on segments (1-D linear FEM, lumped: ē²λ/12 on a uniform circle), fitted on circles,
             # an ellipse, a trefoil and an open arc of 60-1,000 uniform and random vertices
             # (benchmarks/bench_curves.py: 0.86-1.87× the measured error)
             "F_S": 0.1, "F_SQ": 0.7}

#: The constants of robust-laplacian's ``point_cloud_laplacian`` on a surface's cloud, fitted by
#: ``benchmarks/calibrate_resolution.py`` on its cloud rows (module docstring).
CLOUD_PEER_MODEL = {"R_E": 0.116, "R_Q": 0.191, "R_F": 0.097, "Q_0": 0.275, "P_R": 0.5, "R_N": 1.74}
#: What a surface's point cloud is compared against, and what the warning names.
CLOUD_PEER = "robust_laplacian.point_cloud_laplacian(P)"


class ResolutionWarning(MeshWarning):
    """The input is too coarse for the kernel: linear FEM (on a point cloud, robust-laplacian's
    point-cloud Laplacian) is expected to be more accurate."""


@dataclass(frozen=True)
class Resolution:
    """What the build measured about resolving the input, and what it predicts.

    Attributes
    ----------
    spacing : float
        ē, the mean edge length (a cloud's spacing).
    width : float
        √h̄/ē: the mass-weighted mean width in mean edges (2 for the default 4ē²).
    narrowed : float
        ρ, the mass-weighted geometric mean of h_w/ℓ_w² (ℓ_w² the mean squared edge at w)
        over the default ratio h/ē²: about 1 where the kernel was not narrowed, less where
        the curvature cap narrowed it or an explicit h is narrower than the default.
    wavelength : float
        h̄·λ, λ Weyl's estimate of eigenvalue 9 from the total mass.
    irregularity : float
        Standard deviation over mean of the edge lengths.
    bend : float
        1 − |mass-weighted mean normal|: 0 on a flat domain, 1 on a closed surface (and
        where there is no normal).
    noise : float
        Height of the vertices over their neighbours, along the normal, that the smooth
        bending does not explain, in mean edges (0 on a clean mesh; meshes only).
    boundary : float
        Mass fraction within √(2h̄) of the boundary (0 without one).
    boundary_curvature : float
        Median curvature of a surface's boundary times √(2h̄) (0 for a straight one).
    creases : float
        Mass fraction within √(2h̄) of a crease vertex.
    predicted_error, fem_error : float, float or None
        Predicted largest relative error of eigenvalues 1-9: the operator's, and linear
        FEM's on the same mesh (None without cells: a point cloud).
    verdict : str
        "resolved", or "too coarse" when ``predicted_error > RATIO_LIMIT · fem_error`` (on a
        surface's point cloud, ``RATIO_LIMIT · peer_error``).
    alternative : str or None
        The operator to use instead when too coarse.
    reason : str
        The figure behind most of the predicted error.
    shortcuts : float
        The Galerkin pencil's area fraction whose pairs through the air (across a groove or a
        thin wall) were dropped (:mod:`meshlap.corrections.shortcuts`; 0 for the vertex pencil).
    thin : float
        The Galerkin pencil's area fraction on parts thinner than :data:`~meshlap.corrections.
        shortcuts.THIN_WIDTHS` of its kernel widths, not next to a short cut (0 for the vertex
        pencil).
    fallback : bool
        Whether the build took the plain kernel (which the prediction then models): the
        corrected kernel's -S not semidefinite at these widths, or predicted less accurate at an
        explicit width (:func:`meshlap.pipeline.plain_predicted`).
    cloud : bool
        Whether the input is a surface's point cloud (its sampling term and its peer differ).
    cloud_noise : float
        A point cloud's σ̂²/a², its normal noise over its squared spacing as given (before the
        default's projection; :func:`meshlap.geometry.pointcloud.noise_ratio`), 0 for meshes.
    peer_error : float or None
        The predicted error of :data:`CLOUD_PEER` on a surface's point cloud (None otherwise).
    surface : bool
        Whether the input is a surface mesh, whose plain kernel has its own model (False in
        reports stored before it had one: they keep the former).

    Examples
    --------
    >>> import meshlap
    >>> op = meshlap.laplacian(*meshlap.shapes.plane(4000, seed=0, kind="stratified"), operator="kernel")
    >>> op.resolution.verdict, op.resolution.alternative    # 0.08% against FEM's 0.23%
    ('resolved', None)
    """

    spacing: float
    width: float
    narrowed: float
    wavelength: float
    irregularity: float
    bend: float
    noise: float
    boundary: float
    boundary_curvature: float
    creases: float
    predicted_error: float
    fem_error: float | None
    verdict: str
    alternative: str | None
    reason: str
    shortcuts: float = 0.0
    thin: float = 0.0
    fallback: bool = False
    cloud: bool = False
    cloud_noise: float = 0.0
    peer_error: float | None = None
    surface: bool = False

    @property
    def too_coarse(self) -> bool:
        """Whether FEM is expected to be more accurate by more than :data:`RATIO_LIMIT`."""
        return self.verdict == "too coarse"

    def _peer(self) -> tuple[str, float | None]:
        # what the default is compared against: linear FEM, or on a cloud robust-laplacian's
        if self.fem_error is None and self.peer_error is not None:
            return "robust-laplacian's point_cloud_laplacian", self.peer_error
        return "linear FEM", self.fem_error

    def message(self) -> str:
        """The warning's text."""
        name, peer = self._peer()
        return (f"the input is too coarse for the heat kernel ({self.reason}): predicted eigenvalue "
                f"error {self.predicted_error:.2%} against {peer:.2%} for {name}; use "
                f"{self.alternative} (op.resolution has the figures)")

    def to_json(self) -> str:
        """The report as JSON (floats exactly), for :mod:`meshlap.store`."""
        return json.dumps(asdict(self))

    @classmethod
    def from_json(cls, text: str) -> Resolution:
        """The report written by :meth:`to_json`."""
        return cls(**json.loads(text))

    def __repr__(self) -> str:
        name, peer = self._peer()
        rows = [f"Resolution: {self.verdict} (predicted eigenvalue error {self.predicted_error:.2%}, "
                f"{name} {'–' if peer is None else f'{peer:.2%}'})",
                f"  width {self.width:.2f} mean edges (ē = {self.spacing:.4g}); narrowed to "
                f"{self.narrowed:.2f} of the default; h·λ₉ = {self.wavelength:.3g}; irregularity "
                f"{self.irregularity:.2f}; bend {self.bend:.2f}; noise "
                + (f"σ̂²/a² {self.cloud_noise:.3g}" if self.cloud else f"{self.noise:.2f} edges"),
                f"  near the boundary {self.boundary:.0%} of the mass (curvature × width "
                f"{self.boundary_curvature:.2f}); near creases {self.creases:.0%}; next to a short cut "
                f"{self.shortcuts:.0%}; on thin parts {self.thin:.0%}",
                f"  most of it: {self.reason}"]
        if self.alternative:
            rows.append(f"  use instead: {self.alternative}")
        return "\n".join(rows)


def _weyl(geo: Geometry) -> float:
    # λ_j ≈ (2π)² (j / (ω_k Vol))^{2/k}, ω_k the volume of the unit k-ball
    k = geo.dim
    omega = math.pi ** (k / 2) / math.gamma(k / 2 + 1)
    return (2 * math.pi) ** 2 * (EIGENVALUES / (omega * float(geo.mass.sum()))) ** (2 / k)


def _near(P: np.ndarray, where: np.ndarray, weight: np.ndarray, radius: float) -> float:
    # the weight of the points within radius of the marked ones
    if not where.any():
        return 0.0
    d, _ = cKDTree(P[where]).query(P, distance_upper_bound=radius)
    return float(weight[np.isfinite(d)].sum())


def _boundary_curvature(P: np.ndarray, geo: Geometry) -> float:
    # turning angle over length at the vertices of a surface's boundary loops
    e = np.sort(geo.faces.edges(), axis=1)
    key, count = np.unique(e, axis=0, return_counts=True)
    b = key[count == 1]
    flat = b.ravel()
    deg = np.bincount(flat, minlength=len(P))
    order = np.argsort(flat, kind="stable")
    v = np.flatnonzero(deg == 2)
    if not len(v):
        return 0.0
    first = np.searchsorted(flat[order], v)
    ends = []
    for j in (0, 1):
        edge = b[order[first + j] // 2]
        ends.append(P[np.where(edge[:, 0] == v, edge[:, 1], edge[:, 0])] - P[v])
    l1, l2 = (np.linalg.norm(u, axis=1) for u in ends)
    cos = np.clip((ends[0] * ends[1]).sum(axis=1) / np.maximum(l1 * l2, 1e-300), -1.0, 1.0)
    return float(np.median((math.pi - np.arccos(cos)) / np.maximum(0.5 * (l1 + l2), 1e-300)))


def _heights(P: np.ndarray, geo: Geometry, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    # each vertex's height over the mean of its neighbours, and of its two rings, along its normal
    n = len(P)
    A = sp.csr_matrix((np.ones(2 * len(edges)), (edges.ravel(), edges[:, ::-1].ravel())), shape=(n, n))
    one, two = np.empty(n), np.empty(n)
    # compiled, the vertices visited in space order (their rings then share the cache): at 400k
    # random vertices 0.44 s of CPU where scipy's A @ A + A and its products took 1.70 s
    in_blocks(_ring_heights, n, spatial_order(P), np.ascontiguousarray(P, dtype=np.float64),
              np.ascontiguousarray(geo.normals(), dtype=np.float64), A.indptr, A.indices, one, two)
    return one, two


@jit()
def _ring_heights(start, stop, order, P, N, indptr, nbr, one, two):  # pragma: no cover - compiled
    # one[v], two[v] for v = order[start:stop]: |(P_v − mean) · N_v| for the mean over v's
    # neighbours, and over the vertices within two edges of v (v excluded), in R³;
    # seen[u] == v: u is counted for v
    seen = np.full(len(P), -1, dtype=np.int64)
    for i in range(start, stop):
        v = order[i]
        seen[v] = v
        sx = sy = sz = 0.0
        for e in range(indptr[v], indptr[v + 1]):
            u = nbr[e]
            seen[u] = v
            sx += P[u, 0]
            sy += P[u, 1]
            sz += P[u, 2]
        k = indptr[v + 1] - indptr[v]
        one[v] = _height(P, N, v, sx, sy, sz, k)
        for e in range(indptr[v], indptr[v + 1]):
            u = nbr[e]
            for f in range(indptr[u], indptr[u + 1]):
                t = nbr[f]
                if seen[t] != v:
                    seen[t] = v
                    k += 1
                    sx += P[t, 0]
                    sy += P[t, 1]
                    sz += P[t, 2]
        two[v] = _height(P, N, v, sx, sy, sz, k)


@jit(inline="always")
def _height(P, N, v, sx, sy, sz, k):  # pragma: no cover - compiled
    # |(P_v − s/k) · N_v|, k counted at least 1
    k = max(k, 1)
    return abs((P[v, 0] - sx / k) * N[v, 0] + (P[v, 1] - sy / k) * N[v, 1] + (P[v, 2] - sz / k) * N[v, 2])


def default_terms(fig: Resolution, model: dict[str, float] = DEFAULT_MODEL) -> dict[str, float]:
    """The default's predicted error, term by term (named for the report's reason), from the
    figures of ``fig`` (its predictions are not read).

    Examples
    --------
    >>> import meshlap
    >>> V, F = meshlap.shapes.plane(400, seed=0, kind="stratified")
    >>> r = meshlap.laplacian(V, F, quadrature="vertex").resolution    # the vertex pencil's model
    >>> bool(abs(sum(default_terms(r).values()) - r.predicted_error) < 1e-15)
    True
    """
    c, hl = model, fig.wavelength
    narrowed = min(fig.narrowed / c["R_0"], 1.0) ** -c["P_Q"]
    if fig.fallback and fig.surface:  # the plain kernel at these widths: its quadrature and its O(h) bias
        # (fitted by calibrate_resolution.py --kernels; 2,000 random vertices at h = ē²: 6.9% for 7.8%)
        e2l = hl / max(fig.width, 1e-3) ** 2
        return {f"the plain kernel's quadrature at {fig.width:.2f} mean edges":
                    c["S_F"] * (fig.irregularity / 0.3) ** c["S_Q"] * (1 + c["S_E"] * e2l)
                    * max(fig.width, 1e-3) ** -c["S_PF"],
                "the plain kernel's O(h) bias":
                    (c["S_P"] + c["S_PB"] * fig.bend + c["S_PC"] * fig.creases) * hl}
    if fig.fallback:  # elsewhere (tetrahedra, curves, clouds): fitted on a 13³ cube of tetrahedra at
        # ē²/16 and a 20,000-vertex random sphere at ē²/2 (which the surfaces' model now covers). A
        # cloud's point masses are a coarser quadrature than a mesh's, and more so the fewer
        # points a wavelength holds (random squares at ē²/2: 15% at 1,000 points, 8.7% at 4,000)
        quad = (c["C_F"] * (1 + c["C_FE"] * hl / max(fig.width, 1e-3) ** 2) if fig.cloud else c["A_F"])
        return {f"the correction fell back to the plain kernel: its quadrature at {fig.width:.2f} mean edges":
                    quad * max(fig.width, 1e-3) ** -c["P_F"],
                "the correction fell back to the plain kernel: its O(h) bias": c["A_P"] * hl * fig.bend}
    # below about R_W of the default width in squared edges the sampling's quadrature error takes
    # over, and refining at a fixed width in edges does not shrink it (at h = ē² on random spheres:
    # 12.9% at 2,000 vertices, 6.7% at 20,000; the plain kernel 0.9% at 400,000 and at 1,000,000)
    below = max(1.0 / max(fig.narrowed, 1e-6) - 1.0 / c["R_W"], 0.0)
    if fig.cloud:  # nearest-neighbour edges: uniform clouds spread 0.2, random ones 0.39
        sampled = (c["C_W"] * (max(fig.irregularity - c["Q_C"], 0.0) / 0.1) ** c["P_C"] * below ** c["P_W"]
                   * (1 + c["C_E"] * hl / fig.width**2))
    else:
        sampled = c["A_W"] * (fig.irregularity / 0.3) ** c["Q_W"] * below ** c["P_W"]
    return {"the width against the eigenfunctions' wavelength": (c["A_H"] + c["A_2"] * hl) * hl * fig.bend,
            f"the kernel narrowed to {fig.narrowed:.2f} of its width on an irregular sampling":
                c["A_Q"] * hl * (fig.irregularity / 0.3) ** 2 * narrowed,
            f"the width, {fig.width:.2f} mean edges, against the sampling ({fig.narrowed:.2f} of the "
            f"default's width in squared edges)": sampled,
            f"{fig.boundary:.0%} of the mass near the boundary":
                c["A_B"] * fig.boundary * hl**1.5 + c["A_K"] * hl * fig.boundary_curvature,
            f"{fig.creases:.0%} of the mass near creases": c["A_C"] * fig.creases * math.sqrt(hl),
            f"noise of {fig.noise:.2f} mean edges": c["A_N"] * fig.noise**2}


def fem_error(fig: Resolution, source: str, faces: bool, model: dict[str, float] = FEM_MODEL) -> float | None:
    """Linear FEM's predicted error on the same cells (None without: a point cloud).

    ``source`` is the geometry's (``"tetrahedra"`` for volumes); ``faces``, whether it has
    faces; ē²λ is ``wavelength / width²``.
    """
    e2l = fig.wavelength / fig.width**2
    if source == "tetrahedra":
        return model["F_T"] * e2l
    if source == "polyline":
        return (model["F_S"] + model["F_SQ"] * fig.irregularity**2) * e2l
    if not faces:
        return None
    return (model["F_E"] + model["F_Q"] * fig.irregularity**2) * e2l * (1 + e2l) + model["F_N"] * fig.noise**2


def peer_error(fig: Resolution, model: dict[str, float] = CLOUD_PEER_MODEL) -> float:
    """:data:`CLOUD_PEER`'s predicted error on a surface's point cloud of the figures ``fig``
    (ē²λ is ``wavelength / width²``; the cloud's noise is ``fig.cloud_noise``).

    Examples
    --------
    >>> import meshlap
    >>> P = meshlap.samples.sphere_points(4000, "random", seed=0)
    >>> r = meshlap.point_cloud_laplacian(P).resolution
    >>> bool(peer_error(r) == r.peer_error)
    True
    """
    c = model
    spread = max(fig.irregularity - c["Q_0"], 0.0) ** c["P_R"]
    sampling = (c["R_Q"] * fig.bend + c["R_F"] * (1 - fig.bend)) * spread
    return c["R_E"] * fig.wavelength / fig.width**2 + sampling + c["R_N"] * fig.cloud_noise


def assess(geo: Geometry, widths: Any, correction: str, galerkin_regime: bool = False,
           shortcuts: float = 0.0, thin: float = 0.0, fallback: bool = False) -> Resolution | None:
    """The resolution report of an operator built on ``geo`` with ``widths``.

    None for the paper's operator (``correction="none"``), which the model does not cover.
    ``galerkin_regime``: the Galerkin pencil is in effect; the prediction is then
    :data:`GALERKIN_FEM_RATIO` times linear FEM's, plus the terms of ``shortcuts`` and ``thin``
    (its area next to a short cut, and on thin parts), else the vertex pencil's model.
    ``fallback``: the corrected kernel's semidefiniteness check failed and the build took the
    plain kernel at the same widths (which the report then covers).

    Examples
    --------
    >>> import meshlap
    >>> V, F = meshlap.shapes.plane(400, seed=0, kind="stratified")
    >>> meshlap.laplacian(V, F, operator="kernel").resolution.too_coarse   # the Galerkin pencil: 0.57%
    False
    >>> r = meshlap.laplacian(V, F, quadrature="vertex").resolution   # 11% against FEM's 2.5%
    >>> r.too_coarse, r.alternative
    (True, 'meshlap.baselines.cotangent(V, F)')
    """
    if correction == "none":
        return None
    P, m = geo.points, geo.mass
    n = len(P)
    w = m / m.sum()
    edges = geo.edges()
    l2 = ((P[edges[:, 0]] - P[edges[:, 1]]) ** 2).sum(axis=1)
    deg = np.bincount(edges.ravel(), minlength=n)
    ell2 = (np.bincount(edges[:, 0], l2, n) + np.bincount(edges[:, 1], l2, n)) / np.maximum(deg, 1)
    hv = widths.per_point(n)
    h_mean = float((w * hv).sum())
    sigma = math.sqrt(2 * h_mean)
    ratio = np.maximum(hv / np.maximum(ell2, 1e-300), 1e-12)
    rho = float(np.exp((w * np.log(ratio)).sum())) / h_scale(geo)
    hl = h_mean * _weyl(geo)
    length = np.sqrt(l2)
    q = float(length.std() / length.mean()) if len(length) else 0.0
    normals = geo.normals()
    bend = 1.0 if normals is None else 1.0 - float(np.linalg.norm(w @ normals))
    band = curv = crease = noise = 0.0
    if geo.boundary is not None and geo.boundary.any():
        band = _near(P, geo.boundary, w, sigma)
        if geo.faces is not None:
            curv = _boundary_curvature(P, geo) * sigma
    if geo.faces is not None and normals is not None:
        one, two = _heights(P, geo, edges)
        # a smooth surface rises 4× as far over two rings as over one; noise alike over both
        noise = max(0.0, (4 * float(np.median(one)) - float(np.median(two))) / 3) / geo.spacing
        # a crease lifts its own line only, far above the median vertex
        rel = one / np.sqrt(np.maximum(ell2, 1e-300))
        crease = _near(P, (rel > CREASE_RATIO * np.median(rel)) & (rel > CREASE_HEIGHT), w, sigma)
    surface_cloud = geo.source == "point cloud" and geo.dim == 2 and P.shape[1] == 3
    cloud_noise = 0.0
    if surface_cloud:  # robust-laplacian sees the points as given, not the default's projection
        cloud_noise = geo._cache.get("noise_ratio")
        if cloud_noise is None:  # denoise given explicitly: not measured at the build
            raw = geo._cache.get("input_points")
            cloud_noise = noise_ratio(P, 2, geo._cache.get("pca")) if raw is None else noise_ratio(raw, 2)
    fig = Resolution(geo.spacing, math.sqrt(h_mean) / geo.spacing, rho, hl, q, bend, noise, band, curv,
                     crease, 0.0, None, "", None, "", shortcuts, thin, fallback, surface_cloud, cloud_noise,
                     surface=geo.faces is not None and geo.dim == 2)
    terms = default_terms(fig)
    fem = fem_error(fig, geo.source, geo.faces is not None)
    peer = peer_error(fig) if surface_cloud else None
    if galerkin_regime and fem is not None:
        terms = {"the Galerkin pencil, measured below linear FEM's error": GALERKIN_FEM_RATIO * fem,
                 f"{shortcuts:.1%} of the area next to a groove or thin wall (pairs through the air dropped)":
                     GALERKIN_SHORTCUT * shortcuts,
                 f"{thin:.1%} of the area on parts thinner than {THIN_WIDTHS:g} kernel widths √(2h)":
                     GALERKIN_THIN * thin}
    return _concluded(replace(fig, fem_error=fem, peer_error=peer), terms, geo)


def as_fallback(report: Resolution, geo: Geometry) -> Resolution:
    """The report of the plain kernel at the same widths, from ``report``, the Richardson
    kernel's on ``geo``: what ``assess(geo, widths, "richardson", fallback=True)`` gives, without
    measuring the figures again (2 s of CPU at 400,000 vertices).

    Examples
    --------
    >>> import meshlap
    >>> g = meshlap.geometry.from_mesh(*meshlap.shapes.sphere(2000, kind="random", seed=0))
    >>> w = meshlap.widths.choose(g, 0.5 * g.spacing**2, plain=False)
    >>> as_fallback(assess(g, w, "richardson"), g) == assess(g, w, "richardson", fallback=True)
    True
    """
    fig = replace(report, fallback=True)
    return _concluded(fig, default_terms(fig), geo)


def _concluded(fig: Resolution, terms: dict[str, float], geo: Geometry) -> Resolution:
    # the prediction from its terms, the verdict against FEM's (or the cloud peer's) error and
    # the peer to use where it is too coarse
    predicted = float(sum(terms.values()))
    alternative = ("linear FEM (lapy.Solver(lapy.TetMesh(V, T)))" if geo.source == "tetrahedra"
                   else "meshlap.baselines.cotangent(V, E)" if geo.source == "polyline"
                   else CLOUD_PEER if fig.cloud else "meshlap.baselines.cotangent(V, F)")
    against = fig.fem_error if fig.fem_error is not None else fig.peer_error
    coarse = against is not None and predicted > RATIO_LIMIT * against
    return replace(fig, predicted_error=predicted, verdict="too coarse" if coarse else "resolved",
                   alternative=alternative if coarse else None, reason=max(terms, key=terms.get))
