"""Regenerate the experiments of Belkin, Sun and Wang (SoCG 2008, Section 5, Tables 1–4).

The heat-kernel operator ("BSW", :func:`meshlap.laplacian`) and the cotangent scheme
("COT", :func:`meshlap.baselines.cotangent`) are applied to test functions with known
Laplacians on the square [-1, 1]² and on the unit sphere meshed in four ways, and their
normalized errors are tabulated against the number of vertices:

* Table 1: plane, normalized L2 error, 4h ∈ {0.01, 0.04, 0.09}, interior vertices only;
* Table 2: uniform sphere, normalized L2 error; Table 3: the same in L∞;
* Table 4: noisy sphere, normalized L2 error; and the non-uniform and random spheres.

Errors are ``‖Lf − Δf‖₂ / ‖Δf‖₂`` and ``max|Lf − Δf| / max|Δf|`` over the vertices that are
scored (all of them on the sphere; on the plane those at least ``PLANE_MARGIN``·√h from the
boundary). On the square and on the unit sphere the continuous heat operator L_h has a closed
form (:func:`square_heat_limit`, :func:`sphere_bias`), so the BSW rows also show the error
that remains as n → ∞ at fixed h (the "floor") and BSW's distance to L_h.

``run(...)`` computes everything and returns a :class:`Reproduction`; ``main(argv)`` is the
command-line entry (``python -m meshlap.reproduce --quick``).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.polynomial import legendre
from scipy import integrate, special

from . import baselines, shapes
from .operator import laplacian
from .progress import ProgressLike, make_progress
from .validation import MeshError, check_h

__all__ = [
    "FULL_NS",
    "PLANE_H",
    "PLANE_MARGIN",
    "QUICK_NS",
    "SPHERE_H",
    "Check",
    "Record",
    "Reproduction",
    "main",
    "run",
    "sphere_bias",
    "sphere_heat_limit",
    "square_heat_limit",
]

#: Vertex counts of the paper's tables.
FULL_NS = (500, 2000, 8000, 16000)
#: Vertex counts of the quick run (``meshlap demo``), a few seconds in all.
QUICK_NS = (500, 1000, 2000)
#: Kernel widths of the plane table: 4h = 0.01, 0.04, 0.09.
PLANE_H = (0.0025, 0.01, 0.0225)
#: Kernel width of the sphere tables (4h = 0.04).
SPHERE_H = 0.01
#: On the plane only vertices at least PLANE_MARGIN·√h from the boundary are scored.
PLANE_MARGIN = 5.0

_SPHERE_TABLES = {
    "uniform": "Table 2/3 — uniform sphere (Fibonacci points, near-regular triangles)",
    "noisy": "Table 4 — noisy sphere (uniform mesh, each vertex shifted by N(0, (0.05·a)²) per axis)",
    "nonuniform": "Non-uniform sphere (density ∝ exp(βz), 50:1 between the poles)",
    "random": "Random sphere (i.i.d. uniform samples, random Delaunay triangles)",
}
# the univariate profiles g of the zonal sphere test functions f = g(x)
_ZONAL = {"x": lambda t: t, "x^2": lambda t: t * t, "exp(x)": np.exp}


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


# -- results -------------------------------------------------------------------------------
@dataclass(frozen=True)
class Record:
    """One measured error: a table row (surface, h, function, method) at one n."""

    table: str
    h: float
    function: str
    method: str
    n: int
    l2: float
    linf: float
    scored: int
    floor_l2: float = math.nan
    floor_linf: float = math.nan
    disc_l2: float = math.nan


@dataclass(frozen=True)
class Check:
    """A claim of the paper (or of issue 3) tested on the measured numbers."""

    claim: str
    holds: bool
    detail: str


@dataclass
class Reproduction:
    """All measured errors, the claims checked on them, the markdown and the files written."""

    records: list[Record]
    ns: tuple[int, ...]
    checks: list[Check] = field(default_factory=list)
    markdown: str = ""
    files: list[Path] = field(default_factory=list)
    seconds: float = 0.0

    def select(self, **where: object) -> list[Record]:
        """Records whose fields equal the given values, in order of n."""
        out = [r for r in self.records if all(getattr(r, k) == v for k, v in where.items())]
        return sorted(out, key=lambda r: r.n)

    def errors(self, table: str, function: str, method: str, norm: str = "l2",
               h: float | None = None) -> np.ndarray:
        """The errors of one table row as an array over ``ns``."""
        where: dict[str, object] = {"table": table, "function": function, "method": method}
        if h is not None:
            where["h"] = h
        return np.array([getattr(r, norm) for r in self.select(**where)])

    @property
    def ok(self) -> bool:
        return all(c.holds for c in self.checks)


def _errors(A: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    d = A - T
    return (np.linalg.norm(d, axis=0) / np.linalg.norm(T, axis=0),
            np.abs(d).max(axis=0) / np.abs(T).max(axis=0))


def _other_methods(V: np.ndarray, F: np.ndarray, extra: bool) -> dict[str, baselines.SparseLaplacian]:
    ops = {"COT": baselines.cotangent(V, F)}
    if extra:
        ops["graph"] = baselines.uniform_graph(V, F)
        try:
            ops["IDT"] = baselines.intrinsic_delaunay(V, F)
        except ImportError:
            pass
    return ops


def _plane(n: int, hs: Sequence[float], seed: int, extra: bool) -> list[Record]:
    V, F = shapes.plane(n, seed=seed)
    funcs = shapes.plane_functions()
    X = np.column_stack([f(V) for f, _ in funcs.values()])
    T = np.column_stack([lap(V) for _, lap in funcs.values()])
    others = {name: op @ X for name, op in _other_methods(V, F, extra).items()}
    out = []
    for h in hs:
        inner = np.abs(V[:, :2]).max(axis=1) <= 1.0 - PLANE_MARGIN * math.sqrt(h)
        if inner.sum() < 3:
            raise MeshError(f"plane with n={n} has no vertex {PLANE_MARGIN}√h from the boundary at h={h}")
        # Matrix-free: at 4h = 0.09 the kernel reaches across the square and L would be dense.
        results = {"BSW": laplacian(V, F, h=h, matrix_free=True, correction="none") @ X, **others}
        limit = np.column_stack([square_heat_limit(name, h, V[inner]) for name in funcs])
        out += _records("plane", h, n, list(funcs), {m: A[inner] for m, A in results.items()},
                        T[inner], limit)
    return out


def _sphere(kind: str, n: int, h: float, seed: int, extra: bool) -> list[Record]:
    V, F = shapes.sphere(n, kind=kind, seed=seed)
    U = V / np.linalg.norm(V, axis=1, keepdims=True)  # noisy sphere: the surface point of each vertex
    funcs = shapes.sphere_functions()
    X = np.column_stack([f(U) for f, _ in funcs.values()])
    T = np.column_stack([lap(U) for _, lap in funcs.values()])
    limit = np.column_stack([sphere_heat_limit(_ZONAL[name], h, U[:, 0]) for name in funcs])
    results = {"BSW": laplacian(V, F, h=h, matrix_free=True, correction="none") @ X}
    results.update({name: op @ X for name, op in _other_methods(V, F, extra).items()})
    return _records(kind, h, n, list(funcs), results, T, limit)


def _records(table: str, h: float, n: int, names: list[str], results: dict[str, np.ndarray],
             T: np.ndarray, limit: np.ndarray) -> list[Record]:
    # limit: the continuous operator L_h f at the scored points, what BSW tends to at fixed h
    floor_l2, floor_linf = _errors(limit, T)
    out = []
    for method, A in results.items():
        l2, linf = _errors(A, T)
        disc = np.linalg.norm(A - limit, axis=0) / np.linalg.norm(T, axis=0)
        for k, name in enumerate(names):
            extra = ((float(floor_l2[k]), float(floor_linf[k]), float(disc[k])) if method == "BSW"
                     else ())
            out.append(Record(table, h, name, method, n, float(l2[k]), float(linf[k]), len(T), *extra))
    return out


# -- the claims ----------------------------------------------------------------------------
def _fmt(x: Sequence[float]) -> str:
    return " → ".join(f"{v:.3g}" for v in x)


def _checks(rep: Reproduction) -> list[Check]:
    ns = rep.ns
    out = []
    rising = []
    for table, h, fn in sorted({(r.table, r.h, r.function) for r in rep.records if r.method == "BSW"}):
        norms = ("l2", "linf") if table == "uniform" else ("l2",)
        for norm in norms:
            e = rep.errors(table, fn, "BSW", norm, h=h)
            if len(e) > 1 and not np.all(np.diff(e) < 0):
                rising.append(f"{table} h={h:g} {fn} {norm}: {_fmt(e)}")
    out.append(Check("every BSW row's error falls as n grows", not rising,
                     "; ".join(rising) if rising else f"all rows fall over n = {', '.join(map(str, ns))}"))
    rising = []
    for table, h, fn in sorted({(r.table, r.h, r.function) for r in rep.records if r.method == "BSW"}):
        e = rep.errors(table, fn, "BSW", "disc_l2", h=h)
        if len(e) > 1 and not np.all(np.diff(e) < 0):
            rising.append(f"{table} h={h:g} {fn}: {_fmt(e)}")
    out.append(Check("every BSW row's distance to the continuous operator L_h, ‖Lf − L_h f‖/‖Δf‖, "
                     "falls as n grows", not rising, "; ".join(rising) if rising else "all rows fall"))

    if "uniform" in {r.table for r in rep.records}:
        big = ns[-1]
        parts, holds = [], True
        for fn in ("x^2", "exp(x)"):
            b = rep.select(table="uniform", function=fn, method="BSW", n=big)[0].linf
            c = rep.select(table="uniform", function=fn, method="COT", n=big)[0].linf
            holds &= b < c
            parts.append(f"{fn}: BSW {b:.3g} vs COT {c:.3g}")
        out.append(Check(f"uniform sphere, n = {big:,}: BSW beats COT in L∞ for x² and eˣ", holds,
                         "; ".join(parts)))
        e = rep.errors("uniform", "x", "COT")
        slope = float(np.polyfit(np.log(ns), np.log(e), 1)[0]) if len(ns) > 1 else math.nan
        out.append(Check("COT converges for f = x on the uniform sphere",
                         bool(len(e) > 1 and np.all(np.diff(e) < 0)),
                         f"L2 error {_fmt(e)} (slope {slope:.2f} in log-log against n)"))

    if "noisy" in {r.table for r in rep.records} and ns[-1] >= 2000:
        bad, fine = [], 0
        for fn in shapes.sphere_functions():
            for n in (m for m in ns if m >= 2000):
                b = rep.select(table="noisy", function=fn, method="BSW", n=n)[0].l2
                c = rep.select(table="noisy", function=fn, method="COT", n=n)[0].l2
                fine += 1
                if not b < c:
                    bad.append(f"{fn} n={n}: BSW {b:.3g} vs COT {c:.3g}")
        out.append(Check("noisy sphere: BSW beats COT in L2 at every n ≥ 2,000 for all three functions",
                         not bad, "; ".join(bad) if bad else f"{fine} comparisons, all won"))
    return out


# -- output --------------------------------------------------------------------------------
def _row_table(rep: Reproduction, table: str, h: float, norm: str, methods: Sequence[str]) -> list[str]:
    # the floor (BSW rows) is L_h's error at the points of the largest mesh
    ns = rep.ns
    head = "| function | method | " + " | ".join(f"n = {n:,}" for n in ns) + " | floor (n → ∞) |"
    lines = [head, "|" + "---|" * (3 + len(ns))]
    functions = list(dict.fromkeys(r.function for r in rep.records if r.table == table))
    for fn in functions:
        for m in methods:
            rows = rep.select(table=table, h=h, function=fn, method=m)
            if not rows:
                continue
            cells = [f"{getattr(r, norm):.4f}" for r in rows]
            fl = getattr(rows[-1], f"floor_{norm}")
            floor = "–" if math.isnan(fl) else f"{fl:.4f}"
            lines.append(f"| {fn} | {m} | " + " | ".join(cells) + f" | {floor} |")
    return lines


def _disc_table(rep: Reproduction) -> list[str]:
    ns = rep.ns
    lines = ["| surface | h | function | " + " | ".join(f"n = {n:,}" for n in ns) + " |",
             "|" + "---|" * (3 + len(ns))]
    keys = dict.fromkeys((r.table, r.h, r.function) for r in rep.records if r.method == "BSW")
    for table, h, fn in keys:
        e = rep.errors(table, fn, "BSW", "disc_l2", h=h)
        lines.append(f"| {table} | {h:g} | {fn} | " + " | ".join(f"{v:.4f}" for v in e) + " |")
    return lines


def format_markdown(rep: Reproduction, command: str = "") -> str:
    """The tables and checks as markdown (also readable as plain text)."""
    methods = list(dict.fromkeys(r.method for r in rep.records))
    L: list[str] = ["# Belkin–Sun–Wang (SoCG 2008), Tables 1–4 reproduced", ""]
    if command:
        L += ["Made by:", "", "```bash", command, "```", ""]
    L += [
        f"Vertices n = {', '.join(f'{n:,}' for n in rep.ns)}; run time {rep.seconds:.0f} s. "
        "Errors are normalized: L2 = ‖Lf − Δf‖₂/‖Δf‖₂, L∞ = max|Lf − Δf| / max|Δf| over the scored "
        "vertices. BSW = meshlap.laplacian (tol 1e-8), COT = cotangent + Voronoi mass"
        + (", IDT = intrinsic Delaunay (robust-laplacian), graph = uniform graph Laplacian"
           if len(methods) > 2 else "") + ". The paper's published numbers are not included: "
        "they could not be obtained here (see docs/reproduction.md).",
        "",
    ]
    plane_hs = sorted({r.h for r in rep.records if r.table == "plane"})
    if plane_hs:
        L += ["## Table 1 — plane [-1, 1]², normalized L2 error", ""]
        for h in plane_hs:
            scored = rep.select(table="plane", h=h, method="BSW")
            counts = ", ".join(f"{r.scored}" for r in scored[:: max(1, len(set(x.function for x in scored)))])
            L += [f"4h = {4 * h:.2f} (h = {h:g}); scored: vertices with max(|x|, |y|) ≤ "
                  f"1 − {PLANE_MARGIN:g}√h = {1 - PLANE_MARGIN * math.sqrt(h):.2f} ({counts} of them)", ""]
            L += _row_table(rep, "plane", h, "l2", methods) + [""]
    for table, title in _SPHERE_TABLES.items():
        hs = sorted({r.h for r in rep.records if r.table == table})
        for h in hs:
            norms = ("l2", "linf") if table == "uniform" else ("l2",)
            for norm in norms:
                what = "normalized L2 error" if norm == "l2" else "normalized L∞ error (Table 3)"
                L += [f"## {title}: {what}, h = {h:g}", ""]
                L += _row_table(rep, table, h, norm, methods) + [""]
    L += ["The floor is the error of the continuous heat operator L_h at the same points, in closed "
          "form (`meshlap.reproduce.square_heat_limit` on the square, boundary truncation included; "
          "`sphere_bias`/`sphere_heat_limit` on the sphere): at fixed h, BSW converges to L_h, not "
          "to Δ, so its error tends to the floor, not to 0. The distance of BSW to L_h itself, "
          "‖Lf − L_h f‖₂/‖Δf‖₂:", ""]
    L += _disc_table(rep) + ["", "## Claims checked on these numbers", ""]
    for c in rep.checks:
        L.append(f"- [{'x' if c.holds else ' '}] **{c.claim}** — {'holds' if c.holds else 'DOES NOT HOLD'}: "
                 f"{c.detail}")
    L.append("")
    return "\n".join(L)


def plot_convergence(rep: Reproduction, path: Path) -> Path:
    """Log-log error against n for the main tables (BSW solid, COT dashed), saved as PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [("plane", PLANE_H[1], "l2", "plane, 4h = 0.04, L2"),
              ("uniform", SPHERE_H, "l2", "uniform sphere, L2"),
              ("uniform", SPHERE_H, "linf", "uniform sphere, L∞"),
              ("noisy", SPHERE_H, "l2", "noisy sphere, L2"),
              ("nonuniform", SPHERE_H, "l2", "non-uniform sphere, L2"),
              ("random", SPHERE_H, "l2", "random sphere, L2")]
    panels = [p for p in panels if rep.select(table=p[0], h=p[1])]
    cols = 3
    rows = max(1, math.ceil(len(panels) / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.4 * rows), squeeze=False)
    ns = np.array(rep.ns)
    for ax, (table, h, norm, title) in zip(axes.ravel(), panels, strict=False):
        functions = list(dict.fromkeys(r.function for r in rep.select(table=table, h=h)))
        for k, fn in enumerate(functions):
            color = f"C{k}"
            for method, style in (("BSW", "-o"), ("COT", "--s")):
                e = rep.errors(table, fn, method, norm, h=h)
                if len(e):
                    ax.loglog(ns, e, style, color=color, ms=4, label=f"{method} {fn}")
            fl = rep.select(table=table, h=h, function=fn, method="BSW")
            # a floor of (nearly) 0, e.g. for f = x on the sphere, has no place on a log axis
            if fl and getattr(fl[-1], f"floor_{norm}") > 1e-6:
                ax.axhline(getattr(fl[-1], f"floor_{norm}"), color=color, lw=0.8, ls=":")
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("vertices n")
        ax.set_ylabel("normalized error")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    for ax in axes.ravel()[len(panels):]:
        ax.axis("off")
    fig.suptitle("BSW (solid) vs COT (dashed); dotted: the BSW floor at fixed h", fontsize=11)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


# -- the entry points ----------------------------------------------------------------------
def run(ns: Sequence[int] = FULL_NS, out_dir: str | Path | None = None, quick: bool = False,
        progress: ProgressLike = None, *, seed: int = 0, plane_h: Sequence[float] = PLANE_H,
        sphere_h: float = SPHERE_H, sphere_kinds: Sequence[str] = tuple(_SPHERE_TABLES),
        extra_baselines: bool | None = None, command: str = "") -> Reproduction:
    """Compute Tables 1–4 of Belkin–Sun–Wang, check the claims, optionally write the files.

    Parameters
    ----------
    ns : sequence of int
        Vertex counts (default 500, 2,000, 8,000, 16,000 as in the paper).
    out_dir : path, optional
        Where to write ``tables.md`` and ``convergence.png``; nothing is written without it.
    quick : bool
        Small meshes (``QUICK_NS`` unless ``ns`` is given otherwise) and BSW/COT only: a few
        seconds, what ``meshlap demo`` runs.
    progress : bool or callable, optional
        ``True`` draws a bar on stderr; a callable gets ``(fraction, stage)``.
    seed : int
        Seed of every mesh.
    plane_h, sphere_h : kernel widths of the plane and sphere tables.
    sphere_kinds : which sphere tables to compute.
    extra_baselines : bool, optional
        Also run the uniform graph and intrinsic Delaunay Laplacians (default: not in quick mode).
    command : str
        The command line to print at the top of the markdown.

    Returns
    -------
    Reproduction
        ``.records`` (every error), ``.checks`` (the paper's claims, held or not),
        ``.markdown``, ``.files``.

    Examples
    --------
    >>> rep = run(ns=(300, 1200), plane_h=(0.01,), sphere_kinds=("uniform",), quick=True)
    >>> bool(rep.errors("uniform", "x", "BSW")[1] < rep.errors("uniform", "x", "BSW")[0])
    True
    """
    t0 = time.perf_counter()
    if quick and tuple(ns) == FULL_NS:
        ns = QUICK_NS
    ns = tuple(sorted(int(n) for n in ns))
    if not ns or ns[0] < 50:
        raise MeshError(f"ns must be vertex counts >= 50; got {ns}")
    for kind in sphere_kinds:
        if kind not in _SPHERE_TABLES:
            raise MeshError(f"unknown sphere kind {kind!r}; use some of {', '.join(_SPHERE_TABLES)}")
    extra = (not quick) if extra_baselines is None else bool(extra_baselines)
    report = make_progress(progress)
    jobs: list[tuple[str, int]] = [("plane", n) for n in ns if plane_h]
    jobs += [(kind, n) for kind in sphere_kinds for n in ns]
    work = np.array([n for _, n in jobs], dtype=float)
    done = 0.0
    records: list[Record] = []
    for table, n in jobs:
        if report is not None:
            report(done / work.sum(), f"{table} {n}")
        if table == "plane":
            records += _plane(n, plane_h, seed, extra)
        else:
            records += _sphere(table, n, sphere_h, seed, extra)
        done += n
    if report is not None:
        report(1.0, "done")
    rep = Reproduction(records=records, ns=ns)
    rep.checks = _checks(rep)
    rep.seconds = time.perf_counter() - t0
    rep.markdown = format_markdown(rep, command)
    if out_dir is not None:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        md = out / "tables.md"
        md.write_text(rep.markdown, encoding="utf-8")
        rep.files = [md, plot_convergence(rep, out / "convergence.png")]
    return rep


def main(argv: Sequence[str] | None = None) -> int:
    """Command-line entry: print the tables (and write them with ``--out``).

    ``--quick`` runs n = 500, 1,000, 2,000 in a few seconds; the default is the paper's
    n = 500, 2,000, 8,000, 16,000 (about a minute). Returns 0, or 1 with ``--strict`` when a
    claim does not hold.

    Examples
    --------
    From a shell (``meshlap reproduce`` takes the same arguments)::

        python -m meshlap.reproduce --quick
        python -m meshlap.reproduce --out benchmarks/tables --strict
    """
    ap = argparse.ArgumentParser(prog="meshlap reproduce", description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small meshes (n = 500, 1000, 2000)")
    ap.add_argument("--ns", type=int, nargs="+", help="vertex counts (default 500 2000 8000 16000)")
    ap.add_argument("--out", type=Path, help="folder for tables.md and convergence.png")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--strict", action="store_true", help="exit with 1 if a claim does not hold")
    ap.add_argument("--quiet", action="store_true", help="print only the claims")
    args = ap.parse_args(argv)
    ns = tuple(args.ns) if args.ns else (QUICK_NS if args.quick else FULL_NS)
    command = "python -m meshlap.reproduce " + " ".join(argv if argv is not None else sys.argv[1:])
    rep = run(ns=ns, out_dir=args.out, quick=args.quick, progress=not args.quiet and sys.stderr.isatty(),
              seed=args.seed, command=command.strip())
    if args.quiet:
        for c in rep.checks:
            print(f"[{'ok' if c.holds else 'FAIL'}] {c.claim}")
    else:
        print(rep.markdown)
        for f in rep.files:
            print(f"wrote {f}")
    return 1 if (args.strict and not rep.ok) else 0


if __name__ == "__main__":
    sys.exit(main())
