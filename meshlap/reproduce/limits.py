"""The continuous heat-kernel operator on the square and the unit sphere: the limit of the
discrete operator at a fixed h."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.polynomial import legendre
from scipy import integrate, special

from ..errors import MeshError
from ..geometry.validation import check_h

__all__ = ["sphere_bias", "sphere_heat_limit", "square_heat_limit"]


# -- the continuous operator on the square ------------------------------------------------
def _gauss_moments(w: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    # ∫_{-1}^{1} (t − w)^k exp(−(t − w)²/4h) dt for k = 0, 1, 2
    a, b = (1 - w) / (2 * math.sqrt(h)), (1 + w) / (2 * math.sqrt(h))
    ea, eb = np.exp(-a * a), np.exp(-b * b)
    m0 = math.sqrt(math.pi * h) * (special.erf(a) + special.erf(b))
    m1 = 2 * h * (eb - ea)
    m2 = 2 * h * m0 - 2 * h * ((1 - w) * ea + (1 + w) * eb)
    return m0, m1, m2


def square_heat_limit(name: str, h: float, V: np.ndarray) -> np.ndarray:
    """The continuous heat-kernel operator on the square [-1, 1]² applied to a plane test function.

    L_h f(w) = 1/(4πh²) ∫_{[-1,1]²} exp(−|p − w|²/4h) (f(p) − f(w)) dp in closed form (error
    functions) for f = x² and f = exp(x + y): the limit of the BSW operator of a mesh of the
    square as n → ∞ at fixed h, boundary truncation included. Far from the boundary it is
    2 for x² (no bias) and (e^{2h} − 1)/h · f for exp(x + y) (relative bias ≈ h).

    Examples
    --------
    >>> w = np.zeros((1, 3))
    >>> bool(abs(square_heat_limit("x^2", 0.001, w)[0] - 2) < 1e-12)
    True
    >>> bool(square_heat_limit("x^2", 0.01, np.array([[0.9, 0, 0]]))[0] < 1.5)   # near the edge
    True
    """
    x, y = V[:, 0], V[:, 1]
    x0, _, _ = _gauss_moments(x, h)
    y0, _, _ = _gauss_moments(y, h)
    if name == "x^2":
        _, x1, x2 = _gauss_moments(x, h)
        # ∫ (t² − w²) g = ∫ ((t − w)² + 2w(t − w)) g
        inner = (x2 + 2 * x * x1) * y0
    elif name == "exp(x+y)":
        # ∫ e^t exp(−(t − w)²/4h) dt = e^{w + h} · (moment 0 of a Gaussian centred at w + 2h)
        ex = np.exp(x + h) * _gauss_moments(x + 2 * h, h)[0]
        ey = np.exp(y + h) * _gauss_moments(y + 2 * h, h)[0]
        inner = ex * ey - np.exp(x + y) * x0 * y0
    else:
        raise MeshError(f"square_heat_limit knows x^2 and exp(x+y); got {name!r}")
    return inner / (4 * math.pi * h * h)


# -- the continuous operator on the unit sphere --------------------------------------------
def sphere_bias(degree: int, h: float) -> float:
    r"""Eigenvalue c_l(h) of the continuous heat-kernel operator on degree-l harmonics.

    On the unit sphere the operator L_h f(w) = 1/(4πh²) ∫ exp(-|p-w|²/4h)(f(p) − f(w)) dp
    maps a spherical harmonic Y_l of degree l to c_l(h)·Y_l with

        c_l(h) = 1/(2h²) ∫₀² exp(−u/(2h)) (P_l(1−u) − 1) du,

    u = 1 − cos γ = |p − w|²/2 and P_l the Legendre polynomial. The exact Laplace–Beltrami
    eigenvalue is −l(l+1); c_2(h) = −6 + 12h + O(e^{−1/h}), so the relative bias of
    degree-2 functions such as x² is 2h.

    Parameters
    ----------
    degree : int
        The degree l ≥ 0.
    h : float
        Kernel width.

    Examples
    --------
    >>> round(sphere_bias(2, 0.01), 10)
    -5.88
    >>> round(sphere_bias(1, 0.01), 10)
    -2.0
    """
    if int(degree) != degree or degree < 0:
        raise MeshError(f"sphere_bias: l must be a non-negative integer; got {degree!r}")
    h = check_h(h)
    p_l = legendre.Legendre.basis(int(degree))

    def integrand(u: float) -> float:
        return math.exp(-u / (2 * h)) * (p_l(1 - u) - 1)

    # the Gaussian lives in u ≲ 2h·40; split there so that quad sees its scale
    cut = min(2.0, 80 * h)
    total = integrate.quad(integrand, 0.0, cut, limit=200, epsabs=0, epsrel=1e-12)[0]
    if cut < 2.0:
        total += integrate.quad(integrand, cut, 2.0, limit=200)[0]
    return total / (2 * h * h)


def sphere_heat_limit(g: Callable[[np.ndarray], np.ndarray], h: float, t: np.ndarray,
                      lmax: int = 30) -> np.ndarray:
    """The continuous heat-kernel operator L_h applied to a zonal function f(p) = g(p·e).

    g is expanded in Legendre polynomials, g = Σ a_l P_l, and L_h f = Σ a_l c_l(h) P_l(t)
    with t = p·e (e.g. the x coordinate of unit vectors). This is what the BSW operator
    converges to as the mesh is refined at fixed h.

    Examples
    --------
    >>> t = np.array([0.0, 0.5, 1.0])
    >>> bool(np.allclose(sphere_heat_limit(lambda s: s * s, 0.01, t), (-6 + 0.12) * (t**2 - 1 / 3)))
    True
    """
    nodes, weights = legendre.leggauss(lmax + 20)
    gv = g(nodes)
    out = np.zeros_like(np.asarray(t, dtype=np.float64))
    for deg in range(lmax + 1):
        basis = legendre.Legendre.basis(deg)
        a = (2 * deg + 1) / 2 * np.sum(weights * gv * basis(nodes))
        if abs(a) < 1e-16:
            continue
        out += a * sphere_bias(deg, h) * basis(t)
    return out
