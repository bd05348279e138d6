"""Test surfaces with known Laplace–Beltrami operators, and the exact Laplacians of test
functions on them. Every generator takes a seed, so every mesh is reproducible.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.spatial import ConvexHull, Delaunay

__all__ = [
    "plane",
    "sphere",
    "fibonacci_sphere",
    "plane_functions",
    "sphere_functions",
]


def plane(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Delaunay triangulation of the square [-1, 1]² from n uniform random samples.

    The four corners are among the samples, so the mesh covers the whole square.

    Examples
    --------
    >>> V, F = plane(100, seed=1)
    >>> V.shape, float(V[:, 2].max())
    ((100, 3), 0.0)
    """
    if n < 4:
        raise ValueError(f"plane needs n >= 4 samples; got {n}")
    rng = np.random.default_rng(seed)
    xy = np.vstack([[[-1, -1], [1, -1], [1, 1], [-1, 1]], rng.uniform(-1, 1, size=(n - 4, 2))])
    F = Delaunay(xy).simplices.astype(np.int64)
    # counter-clockwise, so that normals point to +z
    a, b, c = xy[F[:, 0]], xy[F[:, 1]], xy[F[:, 2]]
    cw = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) < 0
    F[cw] = F[cw][:, ::-1]
    return np.column_stack([xy, np.zeros(n)]), F


def fibonacci_sphere(n: int) -> np.ndarray:
    """n evenly spread points on the unit sphere (the golden-angle spiral)."""
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    r = np.sqrt(1 - z * z)
    phi = np.pi * (3 - np.sqrt(5)) * i
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def _hull_mesh(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    # The convex hull of points on a sphere is their spherical Delaunay triangulation.
    F = ConvexHull(P).simplices.astype(np.int64)
    normal = np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]])
    inward = np.einsum("ij,ij->i", normal, P[F].mean(axis=1)) < 0
    F[inward] = F[inward][:, ::-1]
    return np.ascontiguousarray(P), F


def sphere(n: int, kind: str = "uniform", seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A triangulated unit sphere with n vertices, faces oriented outward.

    Parameters
    ----------
    n : int
        Number of vertices.
    kind : {"uniform", "random"}
        "uniform": evenly spread (Fibonacci) points, slightly jittered by ``seed``;
        "random": independent uniform samples.
    seed : int
        Random seed.

    Examples
    --------
    >>> V, F = sphere(500, seed=0)
    >>> V.shape, F.shape
    ((500, 3), (996, 3))
    """
    if n < 4:
        raise ValueError(f"sphere needs n >= 4 points; got {n}")
    rng = np.random.default_rng(seed)
    if kind == "uniform":
        P = fibonacci_sphere(n)
        # a tiny random rotation keeps the spiral's poles from being special
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        P = P @ q.T
    elif kind == "random":
        P = rng.normal(size=(n, 3))
    else:
        raise ValueError(f"unknown sphere kind {kind!r}; use 'uniform' or 'random'")
    P /= np.linalg.norm(P, axis=1, keepdims=True)
    return _hull_mesh(P)


Func = tuple[Callable[[np.ndarray], np.ndarray], Callable[[np.ndarray], np.ndarray]]


def plane_functions() -> dict[str, Func]:
    """Test functions on the plane z = 0 and their exact Laplacians, as (f, Δf) of V."""
    return {
        "x^2": (lambda V: V[:, 0] ** 2, lambda V: np.full(len(V), 2.0)),
        "exp(x+y)": (
            lambda V: np.exp(V[:, 0] + V[:, 1]),
            lambda V: 2.0 * np.exp(V[:, 0] + V[:, 1]),
        ),
    }


def sphere_functions() -> dict[str, Func]:
    """Test functions on the unit sphere and their exact Laplace–Beltrami values.

    For a smooth f on R³ restricted to the unit sphere, Δ_S f = Δf - ∂²f/∂r² - 2 ∂f/∂r:
    Δ_S x = -2x, Δ_S x² = 2 - 6x², Δ_S eˣ = eˣ (1 - 2x - x²).
    """
    return {
        "x": (lambda V: V[:, 0].copy(), lambda V: -2.0 * V[:, 0]),
        "x^2": (lambda V: V[:, 0] ** 2, lambda V: 2.0 - 6.0 * V[:, 0] ** 2),
        "exp(x)": (
            lambda V: np.exp(V[:, 0]),
            lambda V: np.exp(V[:, 0]) * (1.0 - 2.0 * V[:, 0] - V[:, 0] ** 2),
        ),
    }
