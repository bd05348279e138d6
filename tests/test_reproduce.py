"""The reproduction of Belkin–Sun–Wang's tables: the closed-form continuous operator on the
sphere, and a small run whose numbers are asserted."""

import math

import numpy as np
import pytest
import sympy as sy
from scipy import integrate

import meshlap
from meshlap import MeshError, reproduce, shapes


@pytest.mark.parametrize("h", [0.0025, 0.01, 0.05])
def test_sphere_bias_closed_forms(h):
    # the integrals stop at u = 2 (the antipode): the closed forms hold up to O(e^(-1/h))
    tail = max(1e-10, 50 * math.exp(-1 / h))
    assert reproduce.sphere_bias(0, h) == 0
    assert reproduce.sphere_bias(1, h) == pytest.approx(-2.0, rel=tail)
    # c_2(h) = -6 + 12h: the relative bias of degree-2 functions (x²) is 2h
    assert reproduce.sphere_bias(2, h) == pytest.approx(-6.0 + 12.0 * h, rel=tail)


def test_sphere_bias_matches_sympy_and_limit():
    u = sy.symbols("u", positive=True)
    h = sy.Rational(1, 20)
    for degree in (3, 6):
        expr = sy.exp(-u / (2 * h)) * (sy.legendre(degree, 1 - u) - 1)
        exact = float(sy.integrate(expr, (u, 0, 2)) / (2 * h * h))
        assert reproduce.sphere_bias(degree, 0.05) == pytest.approx(exact, rel=1e-10)
    # h → 0: the eigenvalue tends to -l(l+1)
    assert reproduce.sphere_bias(5, 1e-5) == pytest.approx(-30.0, rel=1e-3)
    with pytest.raises(MeshError):
        reproduce.sphere_bias(-1, 0.01)


def test_sphere_heat_limit_matches_direct_integral():
    # L_h f(w) = 1/(4πh²) ∫ exp(-|p-w|²/4h) (f(p) - f(w)) dp, integrated around w in (γ, ψ)
    h = 0.05
    w = np.array([0.6, 0.0, 0.8])
    e1, e2 = np.array([0.8, 0.0, -0.6]), np.array([0.0, 1.0, 0.0])

    def integrand(psi, gamma):
        p = math.cos(gamma) * w + math.sin(gamma) * (math.cos(psi) * e1 + math.sin(psi) * e2)
        d2 = 2 - 2 * math.cos(gamma)
        return math.exp(-d2 / (4 * h)) * (math.exp(p[0]) - math.exp(w[0])) * math.sin(gamma)

    direct = integrate.dblquad(integrand, 0, math.pi, 0, 2 * math.pi, epsabs=1e-11)[0] / (4 * math.pi * h * h)
    closed = reproduce.sphere_heat_limit(np.exp, h, np.array([w[0]]))[0]
    assert closed == pytest.approx(direct, rel=1e-8)


@pytest.mark.parametrize("w", [(0.9, 0.3), (0.2, -0.97), (0.0, 0.0)])
@pytest.mark.parametrize("name, f", [("x^2", lambda x, y: x * x), ("exp(x+y)", lambda x, y: math.exp(x + y))])
def test_square_heat_limit_matches_direct_integral(w, name, f):
    h = 0.01

    def integrand(y, x):
        return math.exp(-((x - w[0]) ** 2 + (y - w[1]) ** 2) / (4 * h)) * (f(x, y) - f(*w))

    direct = integrate.dblquad(integrand, -1, 1, -1, 1, epsabs=1e-12)[0] / (4 * math.pi * h * h)
    closed = reproduce.square_heat_limit(name, h, np.array([[w[0], w[1], 0.0]]))[0]
    assert closed == pytest.approx(direct, rel=1e-10, abs=1e-10)


def test_square_heat_limit_far_from_the_edge():
    V = np.zeros((1, 3))
    assert reproduce.square_heat_limit("x^2", 0.0025, V)[0] == pytest.approx(2.0, rel=1e-12)
    assert reproduce.square_heat_limit("exp(x+y)", 0.0025, V)[0] == pytest.approx(
        np.expm1(0.005) / 0.0025, rel=1e-12)
    with pytest.raises(MeshError):
        reproduce.square_heat_limit("sin(x)", 0.01, V)


def test_bsw_tends_to_the_floor_on_a_fine_sphere():
    # at fixed h the operator converges to L_h: for x² its error approaches the 2h bias floor
    V, F = shapes.sphere(6000, kind="uniform", seed=0)
    h = 0.04
    op = meshlap.laplacian(V, F, h=h, correction="none")
    x2 = V[:, 0] ** 2
    limit = reproduce.sphere_heat_limit(lambda t: t * t, h, V[:, 0])
    exact = 2 - 6 * x2
    err = np.linalg.norm(op @ x2 - exact) / np.linalg.norm(exact)
    assert err == pytest.approx(2 * h, rel=0.05)
    assert np.linalg.norm(op @ x2 - limit) / np.linalg.norm(exact) < 0.004


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("tables")
    return reproduce.run(ns=(500, 1000, 2000), out_dir=out, quick=True), out


def test_quick_run_numbers(quick):
    rep, _ = quick
    assert rep.ns == (500, 1000, 2000)
    # every BSW error falls with n, on every table and in both norms where tabulated
    for table, h, fn in {(r.table, r.h, r.function) for r in rep.records if r.method == "BSW"}:
        assert np.all(np.diff(rep.errors(table, fn, "BSW", "l2", h=h)) < 0), (table, h, fn)
        assert np.all(np.diff(rep.errors(table, fn, "BSW", "disc_l2", h=h)) < 0), (table, h, fn)
    # measured (seed 0): uniform sphere x 0.0626 → 0.0338, COT x 0.0066 → 0.0037
    assert rep.errors("uniform", "x", "BSW")[-1] < 0.04
    assert np.all(np.diff(rep.errors("uniform", "x", "COT")) < 0)
    assert rep.errors("uniform", "x", "COT")[-1] < 0.005
    # the x² floor is 2h for every sphere kind
    floor = rep.select(table="uniform", function="x^2", method="BSW")[-1].floor_l2
    assert floor == pytest.approx(2 * reproduce.SPHERE_H, rel=1e-3)
    # noisy sphere at n = 2,000: BSW beats COT for every function (measured 0.038 vs 0.067 for x)
    for fn in shapes.sphere_functions():
        assert rep.errors("noisy", fn, "BSW")[-1] < rep.errors("noisy", fn, "COT")[-1]
    # plane, 4h = 0.04: BSW 0.116 → 0.022 on x², COT stays near 0.37
    assert rep.errors("plane", "x^2", "BSW", h=0.01)[-1] < 0.04
    assert rep.errors("plane", "x^2", "COT", h=0.01)[-1] > 0.2
    assert rep.ok, [c for c in rep.checks if not c.holds]


def test_quick_run_outputs(quick):
    rep, out = quick
    md = (out / "tables.md").read_text(encoding="utf-8")
    assert "Table 1" in md and "noisy sphere" in md and "Claims checked" in md
    assert md == rep.markdown
    png = (out / "convergence.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000


def test_main_strict_reports_claims(capsys):
    # with --strict the exit status says whether every claim held; at n = 600 the L∞ claim,
    # which the paper makes at 16,000 vertices, does not hold yet (COT still wins)
    assert reproduce.main(["--ns", "300", "600", "--quiet", "--strict"]) == 1
    lines = capsys.readouterr().out.splitlines()
    # n < 2,000: the noisy-sphere claim (n ≥ 2,000) is not applicable, the other four are checked
    assert len(lines) == 4
    assert lines[0] == "[ok] every BSW row's error falls as n grows"
    assert lines[2].startswith("[FAIL] uniform sphere, n = 600")
    assert lines[3] == "[ok] COT converges for f = x on the uniform sphere"


def test_bad_arguments():
    with pytest.raises(MeshError, match="ns"):
        reproduce.run(ns=(10,))
    with pytest.raises(MeshError, match="sphere kind"):
        reproduce.run(ns=(300,), sphere_kinds=("cube",))
