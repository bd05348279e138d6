"""Test surfaces with known Laplace–Beltrami operators, and the exact Laplacians of test
functions on them. Every generator takes a seed, so every mesh is reproducible.

The surfaces are the ones of Belkin, Sun and Wang's experiments (SoCG 2008, Section 5):
the square [-1, 1]², the unit sphere in several samplings (uniform, random, non-uniform,
noisy), and in addition a torus, whose two principal curvatures differ.

For a smooth f on R³ restricted to a surface with unit normal n and mean-curvature sum
κ = κ₁ + κ₂ (positive on the sphere with the outward normal) the Laplace–Beltrami operator is

    Δ_S f = tr(∇²f) − nᵀ(∇²f)n − κ ∂f/∂n,

which is how the exact values of the sphere and torus functions below are computed.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.spatial import ConvexHull, Delaunay

from .errors import MeshError

__all__ = [
    "NOISE_FRACTION",
    "NONUNIFORM_RATIO",
    "PLANE_KINDS",
    "SPHERE_KINDS",
    "disc",
    "fibonacci_sphere",
    "loop_limit",
    "mean_edge_estimate",
    "near_copies",
    "plane",
    "plane_functions",
    "sphere",
    "sphere_functions",
    "torus",
    "torus_angles",
    "torus_functions",
    "triangle_angles",
    "x_functions",
]

#: Plane samplings understood by :func:`plane`.
PLANE_KINDS = ("random", "stratified")

#: Sphere samplings understood by :func:`sphere`.
SPHERE_KINDS = ("uniform", "random", "nonuniform", "noisy")

#: Standard deviation of the noisy sphere's shift, as a fraction of the mean edge length.
NOISE_FRACTION = 0.05

#: Density ratio between the densest and the sparsest point of the non-uniform sphere.
NONUNIFORM_RATIO = 50.0


def _check_count(n: int, least: int, what: str) -> int:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise MeshError(f"{what}: n must be an integer; got {n!r}")
    if n < least:
        raise MeshError(f"{what} needs n >= {least} vertices; got {n}")
    return int(n)


def plane(n: int, seed: int = 0, kind: str = "random") -> tuple[np.ndarray, np.ndarray]:
    """Delaunay triangulation of the square [-1, 1]² from n samples.

    ``kind="random"``: the four corners and n − 4 uniform random samples (many skinny
    triangles). ``kind="stratified"``: an m × m grid, m = round(√n) (so m² ≈ n vertices),
    whose edge nodes stay on the square's edges and whose interior nodes each move to a
    uniform random point of the grid cell around them: as random, but evenly spread. Either
    mesh covers the whole square. Faces are counter-clockwise seen from +z.

    Examples
    --------
    >>> V, F = plane(100, seed=1)
    >>> V.shape, float(V[:, 2].max())
    ((100, 3), 0.0)
    >>> plane(500, kind="stratified")[0].shape   # 22² vertices
    (484, 3)
    """
    n = _check_count(n, 4, "plane")
    rng = np.random.default_rng(seed)
    if kind == "random":
        xy = np.vstack([[[-1, -1], [1, -1], [1, 1], [-1, 1]], rng.uniform(-1, 1, size=(n - 4, 2))])
    elif kind == "stratified":
        m = max(2, round(math.sqrt(n)))
        t = np.linspace(-1.0, 1.0, m)
        xy = np.column_stack([np.repeat(t, m), np.tile(t, m)])
        inner = np.abs(xy).max(axis=1) < 1.0
        step = 2.0 / (m - 1)
        xy[inner] += rng.uniform(-step / 2, step / 2, size=(int(inner.sum()), 2))
    else:
        raise MeshError(f"unknown plane kind {kind!r}; use one of {', '.join(PLANE_KINDS)}")
    return _flat_mesh(xy)


def _flat_mesh(xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The Delaunay triangulation of planar points, as a mesh in the plane z = 0."""
    F = Delaunay(xy).simplices.astype(np.int64)
    # counter-clockwise, so that normals point to +z
    a, b, c = xy[F[:, 0]], xy[F[:, 1]], xy[F[:, 2]]
    cw = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) < 0
    F[cw] = F[cw][:, ::-1]
    return np.column_stack([xy, np.zeros(len(xy))]), F


def disc(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Delaunay triangulation of the unit disc from about n points on concentric rings.

    Ring j of m = round(√(n/π)) holds round(2πj) points at radius j/m (the outer ring on
    the unit circle), each ring turned by a random angle; the centre is vertex 0. Faces are
    counter-clockwise seen from +z.

    Examples
    --------
    >>> V, F = disc(300)
    >>> bool(np.isclose(np.linalg.norm(V, axis=1).max(), 1.0)), bool(np.allclose(V[0], 0))
    (True, True)
    """
    n = _check_count(n, 7, "disc")
    rng = np.random.default_rng(seed)
    m = max(1, round(math.sqrt(n / math.pi)))
    rings = [np.zeros((1, 2))]
    for j in range(1, m + 1):
        count = max(6, round(2 * np.pi * j))
        a = rng.uniform(0, 2 * np.pi) + np.linspace(0, 2 * np.pi, count, endpoint=False)
        rings.append(j / m * np.column_stack([np.cos(a), np.sin(a)]))
    xy = np.vstack(rings)
    return _flat_mesh(xy)


def fibonacci_sphere(n: int) -> np.ndarray:
    """n evenly spread points on the unit sphere (the golden-angle spiral).

    Examples
    --------
    >>> P = fibonacci_sphere(10)
    >>> bool(np.allclose(np.linalg.norm(P, axis=1), 1))
    True
    """
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    r = np.sqrt(1 - z * z)
    phi = np.pi * (3 - np.sqrt(5)) * i
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def mean_edge_estimate(area: float, n: int) -> float:
    """Edge length of a regular triangulation of a surface of this area with n vertices.

    Each vertex of a regular triangulation owns (√3/2)·a² of area, so a = sqrt(2A/(√3 n)).

    Examples
    --------
    >>> round(mean_edge_estimate(4 * math.pi, 2000), 4)
    0.0852
    """
    return math.sqrt(2.0 * area / (math.sqrt(3.0) * n))


def _hull_mesh(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    # The convex hull of points on a sphere is their spherical Delaunay triangulation.
    F = ConvexHull(P).simplices.astype(np.int64)
    normal = np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]])
    inward = np.einsum("ij,ij->i", normal, P[F].mean(axis=1)) < 0
    F[inward] = F[inward][:, ::-1]
    return np.ascontiguousarray(P), F


def _nonuniform_points(n: int, rng: np.random.Generator) -> np.ndarray:
    # Density ∝ exp(β z) on the sphere: since area is uniform in z, z itself has density
    # ∝ exp(β z) on [-1, 1] and is drawn by inverting its CDF.
    beta = 0.5 * math.log(NONUNIFORM_RATIO)
    u = rng.uniform(size=n)
    z = np.log(math.exp(-beta) + u * (math.exp(beta) - math.exp(-beta))) / beta
    z = np.clip(z, -1.0, 1.0)
    phi = rng.uniform(0, 2 * math.pi, size=n)
    r = np.sqrt(1 - z * z)
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def sphere(n: int, kind: str = "uniform", seed: int = 0,
           noise: float = NOISE_FRACTION) -> tuple[np.ndarray, np.ndarray]:
    """A triangulated unit sphere with n vertices, faces oriented outward.

    Parameters
    ----------
    n : int
        Number of vertices.
    kind : {"uniform", "random", "nonuniform", "noisy"}
        "uniform": evenly spread (Fibonacci) points under a random rotation (near-regular
        triangles); "random": independent uniform samples (the triangles of a random
        Delaunay triangulation, many of them skinny); "nonuniform": independent samples
        with density ∝ exp(β z), 50 times denser at the north pole than at the south pole,
        so triangle sizes vary by that factor and skinny triangles abound; "noisy": the
        "uniform" mesh with each vertex then moved by an isotropic Gaussian shift of
        standard deviation ``noise`` (default ``NOISE_FRACTION``, 0.05) times the mean edge
        length a of a regular mesh with n vertices (see :func:`mean_edge_estimate`). The shift
        scales with a, so the roughness of the normals (≈ 4° at 0.05) does not vanish under refinement, as for
        scanned data, while every face keeps its orientation (the shift is far below the
        edge length). The vertices of the noisy sphere are not on the unit sphere: evaluate
        test functions at ``V / |V|``.
    seed : int
        Random seed; the same (n, kind, seed) gives the same mesh.
    noise : float
        The noisy sphere's shift as a fraction of a (ignored by the other kinds). The same
        seed gives the same points and shift directions for every ``noise``: only the
        amplitude changes (the paper does not state its noise, see meshlap.reproduce).

    Returns
    -------
    V : (n, 3) ndarray
    F : (2n - 4, 3) ndarray of int64

    Examples
    --------
    >>> V, F = sphere(500, seed=0)
    >>> V.shape, F.shape
    ((500, 3), (996, 3))
    """
    n = _check_count(n, 4, "sphere")
    rng = np.random.default_rng(seed)
    if kind in ("uniform", "noisy"):
        P = fibonacci_sphere(n)
        # a random rotation keeps the spiral's poles from being special
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        P = P @ q.T
    elif kind == "random":
        P = rng.normal(size=(n, 3))
    elif kind == "nonuniform":
        P = _nonuniform_points(n, rng)
    else:
        raise MeshError(f"unknown sphere kind {kind!r}; use one of {', '.join(SPHERE_KINDS)}")
    P /= np.linalg.norm(P, axis=1, keepdims=True)
    V, F = _hull_mesh(P)
    if kind == "noisy":
        # Triangulate the clean samples, then move them: the connectivity stays a spherical
        # Delaunay triangulation while the geometry becomes rough at the scale of the edges.
        if not (math.isfinite(noise) and noise >= 0):
            raise MeshError(f"sphere: noise must be a finite fraction >= 0; got {noise!r}")
        sigma = noise * mean_edge_estimate(4 * math.pi, n)
        V = V + rng.normal(scale=sigma, size=V.shape)
    return V, F


def torus(n: int, R: float = 1.0, r: float = 0.4, seed: int = 0,
          jitter: float = 0.25) -> tuple[np.ndarray, np.ndarray]:
    """A triangulated torus of radii (R, r) with about n vertices, faces oriented outward.

    The torus is ((R + r cos θ) cos φ, (R + r cos θ) sin φ, r sin θ). Vertices sit on a
    periodic grid in (θ, φ) with nθ·nφ ≈ n and nφ/nθ ≈ R/r (so that grid cells are roughly
    square near the outer equator), each moved inside its cell by up to ``jitter`` cells;
    every cell is split into two triangles. All vertices lie on the torus.

    Examples
    --------
    >>> V, F = torus(400, seed=0)        # a 13 × 31 grid
    >>> V.shape, F.shape
    ((403, 3), (806, 3))
    """
    n = _check_count(n, 9, "torus")
    if not (0 < r < R):
        raise MeshError(f"torus needs 0 < r < R; got R={R}, r={r}")
    if not (0 <= jitter < 0.5):
        raise MeshError(f"torus jitter must be in [0, 0.5); got {jitter}")
    n_theta = max(3, round(math.sqrt(n * r / R)))
    n_phi = max(3, round(n / n_theta))
    rng = np.random.default_rng(seed)
    i, j = np.meshgrid(np.arange(n_theta), np.arange(n_phi), indexing="ij")
    t = (i + rng.uniform(-jitter, jitter, size=i.shape)) * (2 * math.pi / n_theta)
    p = (j + rng.uniform(-jitter, jitter, size=j.shape)) * (2 * math.pi / n_phi)
    V = _torus_point(t.ravel(), p.ravel(), R, r)
    idx = np.arange(n_theta * n_phi).reshape(n_theta, n_phi)
    a = idx
    b = np.roll(idx, -1, axis=0)          # θ + 1
    c = np.roll(np.roll(idx, -1, axis=0), -1, axis=1)
    d = np.roll(idx, -1, axis=1)          # φ + 1
    # (∂/∂φ × ∂/∂θ) points outward, so the order a → d → c is counter-clockwise from outside
    F = np.vstack([np.column_stack([a.ravel(), d.ravel(), c.ravel()]),
                   np.column_stack([a.ravel(), c.ravel(), b.ravel()])]).astype(np.int64)
    return V, F


def _torus_point(theta: np.ndarray, phi: np.ndarray, R: float, r: float) -> np.ndarray:
    rho = R + r * np.cos(theta)
    return np.column_stack([rho * np.cos(phi), rho * np.sin(phi), r * np.sin(theta)])


def torus_angles(V: np.ndarray, R: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """The angles (θ, φ) of points on the torus of major radius R.

    Examples
    --------
    >>> th, ph = torus_angles(np.array([[1.4, 0.0, 0.0]]))
    >>> float(th[0]), float(ph[0])
    (0.0, 0.0)
    """
    V = np.asarray(V, dtype=np.float64)
    rho = np.hypot(V[:, 0], V[:, 1])
    return np.arctan2(V[:, 2], rho - R), np.arctan2(V[:, 1], V[:, 0])


def triangle_angles(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """The three corner angles (radians) of every triangle, shape (m, 3).

    Examples
    --------
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    >>> np.degrees(triangle_angles(V, np.array([[0, 1, 2]]))).round(6)
    array([[90., 45., 45.]])
    """
    P = np.asarray(V)[np.asarray(F)]
    out = np.empty(P.shape[:2])
    for k in range(3):
        u = P[:, (k + 1) % 3] - P[:, k]
        w = P[:, (k + 2) % 3] - P[:, k]
        cos = np.einsum("ij,ij->i", u, w) / (np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1))
        out[:, k] = np.arccos(np.clip(cos, -1.0, 1.0))
    return out


def near_copies(V: np.ndarray, F: np.ndarray, d: float, split: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """The triangles ``split`` (indices; default every 10th) split at a new vertex ``d`` of the
    way from their first corner towards the opposite side's midpoint: nearly coincident
    vertices, joined by needles and caps (a test of degenerate input;
    ``benchmarks/bench_degenerate.py``).

    Examples
    --------
    >>> V, F = sphere(200, seed=0)
    >>> W, G = near_copies(V, F, 1e-6)
    >>> len(W) - len(V), len(G) - len(F), bool(np.linalg.norm(W[200:] - V[F[::10, 0]], axis=1).max() < 1e-6)
    (40, 80, True)
    """
    V, F = np.asarray(V, dtype=np.float64), np.array(F, dtype=np.int64)
    split = np.arange(0, len(F), 10) if split is None else np.asarray(split, dtype=np.int64)
    a, b, c = F[split].T
    q = len(V) + np.arange(len(split))
    added = V[a] + d * ((V[b] + V[c]) / 2 - V[a])
    F[split] = np.c_[a, b, q]
    return np.vstack([V, added]), np.vstack([F, np.c_[b, c, q], np.c_[c, a, q]])


Func = tuple[Callable[[np.ndarray], np.ndarray], Callable[[np.ndarray], np.ndarray]]


def plane_functions() -> dict[str, Func]:
    """Test functions on the plane z = 0 and their exact Laplacians, as (f, Δf) of V.

    Examples
    --------
    >>> f, lap = plane_functions()["x^2"]
    >>> lap(np.zeros((2, 3)))
    array([2., 2.])
    """
    return {
        "x^2": (lambda V: V[:, 0] ** 2, lambda V: np.full(len(V), 2.0)),
        "exp(x+y)": (
            lambda V: np.exp(V[:, 0] + V[:, 1]),
            lambda V: 2.0 * np.exp(V[:, 0] + V[:, 1]),
        ),
    }


def sphere_functions() -> dict[str, Func]:
    """Test functions on the unit sphere and their exact Laplace–Beltrami values.

    With n = x/|x| and κ = 2, Δ_S f = Δf − ∂²f/∂r² − 2 ∂f/∂r:
    Δ_S x = −2x, Δ_S x² = 2 − 6x², Δ_S eˣ = eˣ (1 − 2x − x²).

    Examples
    --------
    >>> f, lap = sphere_functions()["x"]
    >>> lap(np.array([[1.0, 0, 0]]))
    array([-2.])
    """
    return {
        "x": (lambda V: V[:, 0].copy(), lambda V: -2.0 * V[:, 0]),
        "x^2": (lambda V: V[:, 0] ** 2, lambda V: 2.0 - 6.0 * V[:, 0] ** 2),
        "exp(x)": (
            lambda V: np.exp(V[:, 0]),
            lambda V: np.exp(V[:, 0]) * (1.0 - 2.0 * V[:, 0] - V[:, 0] ** 2),
        ),
    }


def torus_functions(R: float = 1.0, r: float = 0.4) -> dict[str, Func]:
    """Test functions on the torus (R, r) and their exact Laplace–Beltrami values.

    Uses Δ_S f = tr(∇²f) − nᵀ(∇²f)n − κ ∂f/∂n with the outward normal
    n = (cos θ cos φ, cos θ sin φ, sin θ) and κ = 1/r + cos θ/(R + r cos θ).
    Points are taken as on the torus (their angles decide n and κ).

    Examples
    --------
    >>> V, F = torus(400, seed=0)
    >>> f, lap = torus_functions()["z"]
    >>> bool(np.isfinite(lap(V)).all())
    True
    """

    def frame(V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        th, ph = torus_angles(V, R)
        nrm = np.column_stack([np.cos(th) * np.cos(ph), np.cos(th) * np.sin(ph), np.sin(th)])
        kappa = 1.0 / r + np.cos(th) / (R + r * np.cos(th))
        return nrm, kappa

    def lap_z(V: np.ndarray) -> np.ndarray:
        # ∇z = e_z, ∇²z = 0
        nrm, kappa = frame(V)
        return -kappa * nrm[:, 2]

    def lap_x2(V: np.ndarray) -> np.ndarray:
        # ∇x² = 2x e_x, ∇²x² = 2 e_x e_xᵀ
        nrm, kappa = frame(V)
        return 2.0 - 2.0 * nrm[:, 0] ** 2 - kappa * 2.0 * V[:, 0] * nrm[:, 0]

    def lap_exp(V: np.ndarray) -> np.ndarray:
        # ∇eˣ = eˣ e_x, ∇²eˣ = eˣ e_x e_xᵀ
        nrm, kappa = frame(V)
        return np.exp(V[:, 0]) * (1.0 - nrm[:, 0] ** 2 - kappa * nrm[:, 0])

    return {
        "z": (lambda V: V[:, 2].copy(), lap_z),
        "x^2": (lambda V: V[:, 0] ** 2, lap_x2),
        "exp(x)": (lambda V: np.exp(V[:, 0]), lap_exp),
    }


def _rings(F: np.ndarray, n: int) -> np.ndarray:
    # the ring of every vertex of valence 6 in cyclic order, (n, 6); −1 rows elsewhere. In a
    # face (i, j, k) the ring of i steps from j to k (closed, consistently oriented mesh)
    w = F.T.ravel()
    a, b = np.roll(F, -1, axis=1).T.ravel(), np.roll(F, -2, axis=1).T.ravel()
    order = np.argsort(w * n + a, kind="stable")
    key, nxt = (w * n + a)[order], b[order]
    regular = np.flatnonzero(np.bincount(w, minlength=n) == 6)
    R = np.empty((len(regular), 6), dtype=np.int64)
    R[:, 0] = a[order][np.searchsorted(key, regular * n)]
    for i in range(1, 6):
        R[:, i] = nxt[np.searchsorted(key, regular * n + R[:, i - 1])]
    out = np.full((n, 6), -1, dtype=np.int64)
    out[regular] = R
    return out


def loop_limit(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The limit surface of Loop subdivision at the vertices of a closed triangle mesh.

    Where a vertex and its ring have valence 6 the limit surface around it is Loop's quartic
    box spline (C²), and its tangents and second derivatives at the vertex are exact masks of
    the ring: the left eigenvectors of the subdivision matrix for the eigenvalues 1/2 and 1/4,
    on a lattice of unit spacing the masks exact for quadratics with the lattice's symmetries.

    Parameters
    ----------
    V : (n, 3) ndarray
        Control points.
    F : (m, 3) int ndarray
        Consistently oriented triangles of a closed mesh.

    Returns
    -------
    points : (n, 3) ndarray
        The limit points (the Loop limit mask, Warren's β = 3/(8n), libigl's ``loop``).
    normals : (n, 3) ndarray
        Unit normals where ``exact`` (NaN elsewhere).
    mean_curvature_normal : (n, 3) ndarray
        ΔX = −κ n, κ = κ₁ + κ₂, where ``exact`` (NaN elsewhere).
    exact : (n,) bool ndarray
        The vertex and its ring have valence 6.

    Examples
    --------
    >>> V = np.array([[1.0, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]])
    >>> F = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5],
    ...               [0, 3, 5]])
    >>> X, N, HN, exact = loop_limit(V, F)      # an octahedron: every vertex of valence 4
    >>> bool(exact.any()), bool(np.allclose(np.linalg.norm(X, axis=1), 1 / 2))
    (False, True)
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    n = len(V)
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    adj = sp.csr_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    adj = ((adj + adj.T) > 0).astype(np.float64).tocsr()
    adj.sort_indices()
    val = np.diff(adj.indptr).astype(np.float64)
    ring_sum = adj @ V
    # v∞ = (1 − nχ) v + χ Σ ring, χ = 1/(n + 3/(8β)), β = 3/(8n) (3/16 at n = 3)
    beta = np.where(val > 3, 3 / (8 * np.maximum(val, 1)), 3 / 16)
    chi = 1 / (val + 3 / (8 * beta))
    X = (1 - val * chi)[:, None] * V + chi[:, None] * ring_sum
    R = _rings(F, n)
    exact = (R >= 0).all(axis=1)
    exact &= (R[np.maximum(R, 0)] >= 0).all(axis=(1, 2))
    th = np.pi * np.arange(6) / 3  # ring i at angle 2πi/6
    Vr = V[np.maximum(R, 0)]

    def ring(c: np.ndarray) -> np.ndarray:
        return np.einsum("i,nid->nd", c, Vr)

    Xs, Xt = ring(np.cos(th)) / 3, ring(np.sin(th)) / 3
    lap = (2 / 3) * (Vr.sum(axis=1) - 6 * V)
    aniso, Xst = (4 / 3) * ring(np.cos(2 * th)), (2 / 3) * ring(np.sin(2 * th))
    Xss, Xtt = (lap + aniso) / 2, (lap - aniso) / 2
    N = np.cross(Xs, Xt)
    N /= np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-300)
    E, Fm, G = (Xs * Xs).sum(1), (Xs * Xt).sum(1), (Xt * Xt).sum(1)
    det = np.where(exact, E * G - Fm**2, 1.0)
    trace = (G * (Xss * N).sum(1) - 2 * Fm * (Xst * N).sum(1) + E * (Xtt * N).sum(1)) / det
    N[~exact] = np.nan
    return X, N, trace[:, None] * N, exact


def x_functions(X: np.ndarray, normals: np.ndarray, mean_curvature_normal: np.ndarray
                ) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """x² and eˣ at points of a surface with their Laplace–Beltrami values, from the unit
    normals n and ΔX there: Δ_S φ(x) = φ''(x)(1 − n_x²) + φ'(x) (ΔX)_x.

    Examples
    --------
    >>> X = fibonacci_sphere(100)                   # the unit sphere: n = X, ΔX = −2X
    >>> f, lap = x_functions(X, X, -2 * X)["x^2"]
    >>> bool(np.allclose(lap, sphere_functions()["x^2"][1](X)))
    True
    """
    x, t, hx = X[:, 0], 1 - normals[:, 0] ** 2, mean_curvature_normal[:, 0]
    return {"x^2": (x**2, 2 * t + 2 * x * hx), "exp(x)": (np.exp(x), np.exp(x) * (t + hx))}
