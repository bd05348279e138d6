"""Regenerate the experiments of Belkin, Sun and Wang (SoCG 2008, Section 5, Tables 1–4).

The heat-kernel operator ("BSW", :func:`meshlap.laplacian`) and the cotangent scheme
("COT", :func:`meshlap.baselines.cotangent`) are applied to test functions with known
Laplacians on the square [-1, 1]² and on the unit sphere meshed in four ways, and their
normalized errors are tabulated against the number of vertices:

* Table 1: plane, normalized L2 error, 4h ∈ {0.01, 0.04, 0.09}, interior vertices only;
* Table 2: uniform sphere, normalized L2 error; Table 3: the same in L∞;
* Table 4: noisy sphere, normalized L2 error; and the non-uniform and random spheres.

The paper's own 104 published cells ship with the package (:func:`paper_tables`) and every
run puts them beside ours (:attr:`Reproduction.beside`) in the paper's metric, with the ratio
ours/paper, plus one measured row per choice the paper leaves open (``VARIANTS``).

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
from pathlib import Path

import numpy as np

from .. import baselines, shapes
from ..builders import laplacian
from ..errors import MeshError
from ..progress import ProgressLike, make_progress
from .limits import sphere_bias, sphere_heat_limit, square_heat_limit
from .paper import PAPER_METRICS, VARIANTS, PaperCell, paper_tables
from .report import format_markdown, plot_convergence
from .results import Beside, Check, Record, Reproduction, _beside
from .settings import _SPHERE_TABLES, _ZONAL, FULL_NS, PLANE_H, PLANE_MARGIN, QUICK_NS, SPHERE_H, STRONG_NOISE

__all__ = [
    "FULL_NS",
    "PAPER_METRICS",
    "PLANE_H",
    "PLANE_MARGIN",
    "QUICK_NS",
    "SPHERE_H",
    "STRONG_NOISE",
    "VARIANTS",
    "Beside",
    "Check",
    "PaperCell",
    "Record",
    "Reproduction",
    "main",
    "paper_tables",
    "run",
    "sphere_bias",
    "sphere_heat_limit",
    "square_heat_limit",
]




def _errors(A: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    # normalized L2, normalized L∞, absolute L∞
    d = A - T
    worst = np.abs(d).max(axis=0)
    return np.linalg.norm(d, axis=0) / np.linalg.norm(T, axis=0), worst / np.abs(T).max(axis=0), worst


def _bsw(V: np.ndarray, F: np.ndarray, h: float) -> Callable[[np.ndarray], np.ndarray]:
    # The one place the paper's operator is built: the plain BSW operator at the given h.
    # Matrix-free: at 4h = 0.09 the kernel reaches across the square and L would be dense.
    op = laplacian(V, F, h=h, matrix_free=True, correction="none")
    return lambda X: op @ X


def _other_methods(V: np.ndarray, F: np.ndarray, extra: bool) -> dict[str, baselines.SparseLaplacian]:
    ops = {"COT": baselines.cotangent(V, F)}
    if extra:
        ops["graph"] = baselines.uniform_graph(V, F)
        try:
            ops["IDT"] = baselines.intrinsic_delaunay(V, F)
        except ImportError:
            pass
    return ops


def _plane(n: int, hs: Sequence[float], seed: int, extra: bool, variants: bool,
           kind: str = "random", table: str = "plane") -> tuple[list[Record], list[Record]]:
    # the records on the interior vertices and (variants) the same over every vertex
    V, F = shapes.plane(n, seed=seed, kind=kind)
    funcs = shapes.plane_functions()
    X = np.column_stack([f(V) for f, _ in funcs.values()])
    T = np.column_stack([lap(V) for _, lap in funcs.values()])
    others = {name: op @ X for name, op in _other_methods(V, F, extra).items()}
    out: list[Record] = []
    alt: list[Record] = []
    for h in hs:
        inner = np.abs(V[:, :2]).max(axis=1) <= 1.0 - PLANE_MARGIN * math.sqrt(h)
        if inner.sum() < 3:
            raise MeshError(f"plane with n={n} has no vertex {PLANE_MARGIN}√h from the boundary at h={h}")
        results = {"BSW": _bsw(V, F, h)(X), **others}
        limit = np.column_stack([square_heat_limit(name, h, V) for name in funcs])
        out += _records(table, h, n, list(funcs), {m: A[inner] for m, A in results.items()},
                        T[inner], limit[inner])
        if variants:
            # COT does not depend on h: over every vertex it is recorded once, at the first h
            methods = ("BSW", "COT") if h == hs[0] else ("BSW",)
            alt += _records("plane-all", h, n, list(funcs), {m: results[m] for m in methods}, T, limit)
    return out, alt


def _sphere(kind: str, n: int, h: float, seed: int, extra: bool, table: str = "",
            noise: float = shapes.NOISE_FRACTION) -> list[Record]:
    V, F = shapes.sphere(n, kind=kind, seed=seed, noise=noise)
    U = V / np.linalg.norm(V, axis=1, keepdims=True)  # noisy sphere: the surface point of each vertex
    funcs = shapes.sphere_functions()
    X = np.column_stack([f(U) for f, _ in funcs.values()])
    T = np.column_stack([lap(U) for _, lap in funcs.values()])
    limit = np.column_stack([sphere_heat_limit(_ZONAL[name], h, U[:, 0]) for name in funcs])
    results = {"BSW": _bsw(V, F, h)(X)}
    results.update({name: op @ X for name, op in _other_methods(V, F, extra).items()})
    return _records(table or kind, h, n, list(funcs), results, T, limit)


def _records(table: str, h: float, n: int, names: list[str], results: dict[str, np.ndarray],
             T: np.ndarray, limit: np.ndarray) -> list[Record]:
    # limit: the continuous operator L_h f at the scored points, what BSW tends to at fixed h
    floor_l2, floor_linf, floor_abs = _errors(limit, T)
    out = []
    for method, A in results.items():
        l2, linf, worst = _errors(A, T)
        disc = np.linalg.norm(A - limit, axis=0) / np.linalg.norm(T, axis=0)
        for k, name in enumerate(names):
            bsw = method == "BSW"
            out.append(Record(table, h, name, method, n, float(l2[k]), float(linf[k]), len(T),
                              floor_l2=float(floor_l2[k]) if bsw else math.nan,
                              floor_linf=float(floor_linf[k]) if bsw else math.nan,
                              disc_l2=float(disc[k]) if bsw else math.nan,
                              abs_linf=float(worst[k]),
                              floor_abs_linf=float(floor_abs[k]) if bsw else math.nan))
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


# -- the entry points ----------------------------------------------------------------------
def run(ns: Sequence[int] = FULL_NS, out_dir: str | Path | None = None, quick: bool = False,
        progress: ProgressLike = None, *, seed: int = 0, plane_h: Sequence[float] = PLANE_H,
        sphere_h: float = SPHERE_H, sphere_kinds: Sequence[str] = tuple(_SPHERE_TABLES),
        extra_baselines: bool | None = None, variants: bool = True, command: str = "") -> Reproduction:
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
    variants : bool
        Also measure the rows of :data:`VARIANTS` (the plane over every vertex, free; the
        stratified plane and the noisy sphere with ``STRONG_NOISE``, one more mesh each per n;
        the random sphere is its own table).
    command : str
        The command line to print at the top of the markdown.

    Returns
    -------
    Reproduction
        ``.records`` (every error), ``.variants``, ``.beside`` (the paper's published cells
        beside ours), ``.checks`` (the paper's claims, held or not), ``.markdown``, ``.files``.

    Examples
    --------
    >>> rep = run(ns=(500, 1200), plane_h=(0.01,), sphere_kinds=("uniform",), quick=True)
    >>> bool(rep.errors("uniform", "x", "BSW")[1] < rep.errors("uniform", "x", "BSW")[0])
    True
    >>> b = next(b for b in rep.beside if b.table == "uniform" and b.paper.n == 500
    ...          and (b.paper.table, b.paper.function, b.paper.method) == (2, "x", "BSW"))
    >>> round(b.ours, 4), b.paper.error, round(b.ratio, 3)    # Table 2: ours is 10× smaller
    (0.0626, 0.606, 0.103)
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
    if variants and plane_h:
        jobs += [("plane-stratified", n) for n in ns]
    if variants and "noisy" in sphere_kinds:
        jobs += [("noisy-strong", n) for n in ns]
    work = np.array([n for _, n in jobs], dtype=float)
    done = 0.0
    records: list[Record] = []
    alt: list[Record] = []
    for table, n in jobs:
        if report is not None:
            report(done / work.sum(), f"{table} {n}")
        if table == "plane":
            rows, more = _plane(n, plane_h, seed, extra, variants)
            records += rows
            alt += more
        elif table == "plane-stratified":
            alt += _plane(n, plane_h, seed, False, False, kind="stratified", table=table)[0]
        elif table == "noisy-strong":
            alt += _sphere("noisy", n, sphere_h, seed, False, table=table, noise=STRONG_NOISE)
        else:
            records += _sphere(table, n, sphere_h, seed, extra)
        done += n
    if report is not None:
        report(1.0, "done")
    rep = Reproduction(records=records, ns=ns, variants=alt, beside=_beside(records + alt))
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
