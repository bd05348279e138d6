"""Curves, volumes and point clouds with known Laplace–Beltrami spectra, for tests and benchmarks.

Every generator takes a seed, so every sample is reproducible.

* the unit circle (k = 1) in R² or R³, as a polyline or as points: Δ sin θ = −sin θ, eigenvalues
  m² (0, 1, 1, 4, 4, ...);
* the unit sphere S² ⊂ R³ as points (evenly spread, i.i.d. random, random with radial noise):
  eigenvalues l(l + 1) with multiplicity 2l + 1;
* the unit cube as a tetrahedral mesh (k = 3): Neumann eigenvalues π²(a² + b² + c²);
* S³ ⊂ R⁴ as points (k = 3): eigenvalues l(l + 2) with multiplicity (l + 1)², so 3 (×4);
* the flat torus (cos θ, sin θ, cos φ, sin φ) ⊂ R⁴ (k = 2, isometric to [0, 2π)²):
  eigenvalues a² + b², so 1 (×4), 2 (×4);
* the torus of revolution of radii R and r in R³ as points: eigenvalues of separated 1-D
  problems (:func:`torus_eigenvalues`).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from scipy.integrate import quad
from scipy.special import eval_legendre

from .errors import MeshError
from .shapes import _check_count, fibonacci_sphere, torus, torus_angles

__all__ = [
    "CLOUD_KINDS",
    "circle",
    "cube_eigenvalues",
    "cube_tetrahedra",
    "flat_torus_points",
    "latitude_longitude_sphere",
    "sphere_eigenvalue",
    "sphere_eigenvalues",
    "sphere_points",
    "three_sphere_points",
    "torus_eigenvalues",
    "torus_points",
]

#: Samplings understood by :func:`sphere_points` and :func:`circle`.
CLOUD_KINDS = ("uniform", "random", "noisy")


def _rotation(d: int, rng: np.random.Generator) -> np.ndarray:
    q, _ = np.linalg.qr(rng.normal(size=(d, d)))
    return q


def circle(n: int, d: int = 2, kind: str = "uniform", seed: int = 0
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The unit circle as n points in R^d (d ≥ 2), in order, with the polyline's edges.

    Parameters
    ----------
    n : int
        Number of points.
    d : int, default 2
        Ambient dimension; for d > 2 the circle lies in a random plane through the origin.
    kind : {"uniform", "random"}
        Equal angular steps, or i.i.d. uniform angles (sorted).
    seed : int
        Random seed.

    Returns
    -------
    V : (n, d) ndarray
    E : (n, 2) int64 ndarray
        Edges between consecutive points, closing the loop.
    theta : (n,) ndarray
        The angle of each point.

    Examples
    --------
    >>> V, E, t = circle(100, d=3)
    >>> V.shape, E.shape, bool(np.allclose(np.linalg.norm(V, axis=1), 1))
    ((100, 3), (100, 2), True)
    """
    n = _check_count(n, 3, "circle")
    if d < 2:
        raise MeshError(f"a circle needs d >= 2 dimensions; got {d}")
    rng = np.random.default_rng(seed)
    if kind == "uniform":
        theta = 2 * math.pi * np.arange(n) / n
    elif kind == "random":
        theta = np.sort(rng.uniform(0, 2 * math.pi, size=n))
    else:
        raise MeshError(f"unknown circle kind {kind!r}; use 'uniform' or 'random'")
    V = np.zeros((n, d))
    V[:, 0], V[:, 1] = np.cos(theta), np.sin(theta)
    if d > 2:
        V = V @ _rotation(d, rng).T
    E = np.column_stack([np.arange(n), (np.arange(n) + 1) % n]).astype(np.int64)
    return V, E, theta


def sphere_points(n: int, kind: str = "random", seed: int = 0, noise: float = 0.01) -> np.ndarray:
    """n points on (or near) the unit sphere S² ⊂ R³.

    ``"uniform"``: the Fibonacci spiral under a random rotation; ``"random"``: i.i.d. uniform;
    ``"noisy"``: i.i.d. uniform, each moved along its radius by a Gaussian of standard
    deviation ``noise`` (1%): evaluate test functions at P / |P|.

    Examples
    --------
    >>> P = sphere_points(500, "noisy")
    >>> bool(0.95 < np.linalg.norm(P, axis=1).min() < 1.0)
    True
    """
    n = _check_count(n, 4, "sphere_points")
    rng = np.random.default_rng(seed)
    if kind == "uniform":
        return fibonacci_sphere(n) @ _rotation(3, rng).T
    if kind not in ("random", "noisy"):
        raise MeshError(f"unknown sphere sampling {kind!r}; use one of {', '.join(CLOUD_KINDS)}")
    P = rng.normal(size=(n, 3))
    P /= np.linalg.norm(P, axis=1, keepdims=True)
    if kind == "noisy":
        P *= 1.0 + noise * rng.normal(size=(n, 1))
    return P


def latitude_longitude_sphere(rings: int, per: int) -> tuple[np.ndarray, np.ndarray]:
    """The unit sphere's latitude-longitude grid: ``rings`` rings of ``per`` points at polar
    angles πi/(rings + 1), then the two poles, and its triangles (two per quad, a fan at each
    pole). A cloud of its points has cocircular quads and poles equidistant from their rings.

    Examples
    --------
    >>> V, F = latitude_longitude_sphere(19, 40)
    >>> V.shape, F.shape
    ((762, 3), (1520, 3))
    """
    rings = _check_count(rings, 2, "latitude_longitude_sphere rings")
    per = _check_count(per, 3, "latitude_longitude_sphere per")
    t, ph = np.meshgrid(np.arange(1, rings + 1) * np.pi / (rings + 1), np.arange(per) * 2 * np.pi / per,
                        indexing="ij")
    r = np.sin(t)
    body = np.column_stack([(r * np.cos(ph)).ravel(), (r * np.sin(ph)).ravel(), np.cos(t).ravel()])
    n = len(body)
    i, j = np.meshgrid(np.arange(rings - 1), np.arange(per), indexing="ij")
    a, b = (i * per + j).ravel(), ((i + 1) * per + j).ravel()
    c, d = ((i + 1) * per + (j + 1) % per).ravel(), (i * per + (j + 1) % per).ravel()
    k = np.arange(per)
    F = np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d]),
                   np.column_stack([np.full(per, n), (k + 1) % per, k]),
                   np.column_stack([np.full(per, n + 1), n - per + k, n - per + (k + 1) % per])])
    return np.vstack([body, [[0.0, 0, 1], [0, 0, -1]]]), F


def three_sphere_points(n: int, seed: int = 0) -> np.ndarray:
    """n i.i.d. uniform points on the unit 3-sphere S³ ⊂ R⁴ (volume 2π²).

    Examples
    --------
    >>> three_sphere_points(10).shape
    (10, 4)
    """
    n = _check_count(n, 5, "three_sphere_points")
    P = np.random.default_rng(seed).normal(size=(n, 4))
    return P / np.linalg.norm(P, axis=1, keepdims=True)


def flat_torus_points(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """n i.i.d. uniform points of the flat torus (cos θ, sin θ, cos φ, sin φ) ⊂ R⁴ (area 4π²).

    Returns the points and their angles θ, φ.

    Examples
    --------
    >>> P, theta, phi = flat_torus_points(10)
    >>> bool(np.allclose((P**2).sum(axis=1), 2))
    True
    """
    n = _check_count(n, 4, "flat_torus_points")
    theta, phi = np.random.default_rng(seed).uniform(0, 2 * math.pi, size=(2, n))
    return np.column_stack([np.cos(theta), np.sin(theta), np.cos(phi), np.sin(phi)]), theta, phi


def torus_points(n: int, kind: str = "random", seed: int = 0, R: float = 1.0, r: float = 0.4,
                 noise: float = 0.0) -> np.ndarray:
    """n points on the torus of revolution of radii (R, r) in R³.

    ``"random"``: i.i.d. uniform by area; ``"jittered"``: the vertices of
    :func:`meshlap.shapes.torus`, a grid each moved by up to a quarter cell (on the exact grid,
    a lattice of rings, point-cloud Laplacians are 15-25% off). ``noise``: each point moved
    along its normal by a Gaussian of that standard deviation.

    Examples
    --------
    >>> P = torus_points(500, noise=0.01)
    >>> rho = np.hypot(np.hypot(P[:, 0], P[:, 1]) - 1.0, P[:, 2])     # distance to the core circle
    >>> bool(0.35 < rho.min() and rho.max() < 0.45)
    True
    """
    n = _check_count(n, 4, "torus_points")
    rng = np.random.default_rng(seed)
    if kind == "jittered":
        th, ph = torus_angles(torus(n, R, r, seed=seed)[0], R)
    elif kind == "random":  # θ by rejection, its density ∝ R + r·cos θ
        th = rng.uniform(0, 2 * math.pi, 4 * n)
        th = th[rng.uniform(0, R + r, 4 * n) < R + r * np.cos(th)][:n]
        ph = rng.uniform(0, 2 * math.pi, n)
    else:
        raise MeshError(f"unknown torus sampling {kind!r}; use 'random' or 'jittered'")
    normal = np.column_stack([np.cos(th) * np.cos(ph), np.cos(th) * np.sin(ph), np.sin(th)])
    centre = R * np.column_stack([np.cos(ph), np.sin(ph), np.zeros_like(ph)])
    return centre + normal * (r + noise * rng.standard_normal((len(th), 1)))


def sphere_eigenvalues(k: int, copies: int = 1) -> np.ndarray:
    """The k smallest eigenvalues of -Δ on ``copies`` disjoint unit spheres: l(l + 1), each
    (2l + 1)·copies times.

    Examples
    --------
    >>> sphere_eigenvalues(5).tolist(), sphere_eigenvalues(4, copies=2).tolist()
    ([0.0, 2.0, 2.0, 2.0, 6.0], [0.0, 0.0, 2.0, 2.0])
    """
    degree = np.arange(math.isqrt(max(int(k), 1)) + 1)  # degrees below √k hold k values
    return np.repeat(degree * (degree + 1.0), copies * (2 * degree + 1))[:k]


def cube_eigenvalues(k: int) -> np.ndarray:
    """The k smallest Neumann eigenvalues of -Δ on the unit cube: π²(a² + b² + c²), a, b, c ≥ 0.

    Examples
    --------
    >>> (cube_eigenvalues(5) / np.pi**2).round(6).tolist()
    [0.0, 1.0, 1.0, 1.0, 2.0]
    """
    r = np.arange(math.isqrt(max(int(k), 1)) + 1)  # a² + b² + c² below k needs each below √k
    a, b, c = np.meshgrid(r, r, r, indexing="ij")
    return np.sort(math.pi**2 * (a * a + b * b + c * c).ravel().astype(float))[:k]


def torus_eigenvalues(k: int = 10, R: float = 1.0, r: float = 0.4, cells: int = 800) -> np.ndarray:
    """The first k eigenvalues of -Δ on the torus of radii (R, r), separated: e^{imφ}·g(θ)
    with -(ρg')'/(r²ρ) + m²g/ρ² = λg, ρ = R + r·cos θ, in second-order finite volumes on
    ``cells`` cells (within 5e-6 of 2,000 cells', 5e-4 of the cotangent Laplacian's on a
    20,000-vertex torus).

    Examples
    --------
    >>> lam = torus_eigenvalues(5)
    >>> float(lam[0]) < 1e-9, bool(np.allclose(lam[1], lam[2]))      # m = ±1: a pair
    (True, True)
    """
    t = np.arange(cells) * 2 * math.pi / cells
    dt = 2 * math.pi / cells
    rho, half = R + r * np.cos(t), R + r * np.cos(t + dt / 2)
    c = half / (r * r * dt)
    K = np.diag(c + np.roll(c, 1)) - np.diag(c[:-1], 1) - np.diag(c[:-1], -1)
    K[0, -1] = K[-1, 0] = -c[-1]
    lam: list[float] = []
    m = 0
    while True:  # the order m's eigenvalues grow with m²: stop above the k-th
        vals = np.linalg.eigvalsh((K + np.diag(m * m * dt / rho)) / np.sqrt(np.outer(rho * dt, rho * dt)))[:k]
        if len(lam) >= k and vals[0] > sorted(lam)[k - 1]:
            return np.sort(lam)[:k]
        lam += [float(v) for v in vals for _ in range(1 if m == 0 else 2)]
        m += 1


def cube_tetrahedra(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The unit cube [0, 1]³ as a tetrahedral mesh: an n×n×n grid of cubes, six tetrahedra each.

    Each cube is cut into the six tetrahedra along its main diagonal (Kuhn's subdivision),
    which fit together across neighbouring cubes.

    Returns
    -------
    V : ((n+1)³, 3) ndarray
    T : (6n³, 4) int64 ndarray

    Examples
    --------
    >>> from meshlap.geometry import simplex_volumes
    >>> V, T = cube_tetrahedra(3)
    >>> round(float(simplex_volumes(V, T).sum()), 12)
    1.0
    """
    n = _check_count(n, 1, "cube_tetrahedra")
    g = np.linspace(0.0, 1.0, n + 1)
    V = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    idx = np.arange((n + 1) ** 3).reshape(n + 1, n + 1, n + 1)

    def corner(i: int, j: int, k: int) -> np.ndarray:
        return idx[i:i + n, j:j + n, k:k + n].ravel()

    tets = []
    for order in itertools.permutations(range(3)):
        step = [0, 0, 0]
        path = [corner(0, 0, 0)]
        for axis in order:  # walk from (0,0,0) to (1,1,1) one axis at a time
            step[axis] = 1
            path.append(corner(*step))
        tets.append(np.column_stack(path))
    return V, np.vstack(tets).astype(np.int64)


def sphere_eigenvalue(l: int, h: float) -> float:  # noqa: E741 - l is the harmonic degree
    r"""Eigenvalue of the continuous heat-kernel operator on the unit sphere, degree l.

    The continuous Belkin–Sun–Wang operator (integral over the surface, no mesh) maps a
    spherical harmonic of degree l to ``c_l(h)`` times itself, with (Funk–Hecke, |p-w|² = 2u)

        c_l(h) = 1/(2h²) ∫₀² exp(-u/(2h)) (P_l(1-u) - 1) du  ≤ 0.

    This returns ``λ_l(h) = -c_l(h)``, the eigenvalue of ``-S φ = λ M φ`` that :func:`meshlap.spectral.eigs`
    approaches as the mesh is refined at fixed h; λ_l(h) → l(l+1) as h → 0, with
    λ_1(h) = 2(1 - e^{-1/h}(1 + 1/h)) in closed form.

    Examples
    --------
    >>> round(sphere_eigenvalue(1, 0.01), 12)
    2.0
    >>> round(sphere_eigenvalue(3, 0.01), 3)     # below l(l+1) = 12: the O(h) bias
    11.412
    """
    from .geometry.validation import check_h, check_int

    check_int(l, "l", 0)

    h = check_h(h)
    if l == 0:
        return 0.0
    a = 2.0 * h

    def integrand(u: float) -> float:
        return math.exp(-u / a) * (eval_legendre(l, 1.0 - u) - 1.0)

    # the weight lives on [0, ~40a]; split there so quad sees its scale
    cut = min(2.0, 40.0 * a)
    val, _ = quad(integrand, 0.0, cut, epsabs=0.0, epsrel=1e-13, limit=400)
    if cut < 2.0:
        tail, _ = quad(integrand, cut, 2.0, epsabs=0.0, epsrel=1e-10, limit=400)
        val += tail
    return -val / (2.0 * h * h)
