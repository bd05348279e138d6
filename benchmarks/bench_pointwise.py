"""Issue 20: point-wise accuracy of Δf on clean, irregular and noisy inputs, with the peers
in the same process, and the convergence order of the new rows on clean spheres and tori.

    python benchmarks/bench_pointwise.py             # 16,000 points; writes RESULTS.md's
                                                     # section "Point-wise accuracy"
    python benchmarks/bench_pointwise.py --n 4000 --no-write    # a quick look
    python benchmarks/bench_pointwise.py --build-ratios         # the build-time table only

E2 = ‖Lf − Δf‖/‖Δf‖, the larger over two functions: x² and eˣ on the sphere and on spot,
sin(x + 2y) and cos(2x − z) on the torus (R = 1, r = 0.4). Noise moves every point along the
clean surface's normal by a Gaussian of standard deviation σ = level · √(A/4π) (the radius of
the sphere of the same area: radial noise on the unit sphere); f is evaluated at the noisy
positions and Δf is the exact value of the clean surface at the clean positions.

spot (tests/data, a real mesh) is replaced by the limit surface of its Loop subdivision, so that
Δf exists: the input is the level-1 mesh pushed to the limit (11,714 points). Where a vertex
and its ring have valence 6 the limit surface is Loop's quartic box spline, C², and its
tangents and second derivatives at the vertex are exact masks of the ring (the left
eigenvectors of the subdivision matrix, eigenvalues 1/2 and 1/4): Δf there is exact
(``meshlap.shapes.loop_limit``). The curvature is singular at the original vertices of valence
≠ 6 (about half of spot's), and Δf with it; E2 leaves out the points within 4 level-1 edges of
them. The
table states the share kept and how far from the exact Δf a degree-6 fit on the level-3 limit
points (187,000, four times finer; the reference before) is. "irregular" for spot is a random
subset of the level-3 limit points, as a cloud only, Δf exact at the level-3 vertices.

Peers skipped by name when missing: pycompadre (GMLS on the manifold, degrees 2–4, its default
power weight and neighbour search), robust-laplacian; libigl cotangent runs on meshes only.

Columns of meshlap: default = ``meshlap.laplacian(V, F)`` / ``point_cloud_laplacian(P)`` (the
fitted point-wise rows, issue 20); moments = the same with ``pointwise=True`` (the degree-2
moment rows, the default before, whose build time the default's is compared with in the same
run); paper = ``correction="none"``.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import igl
import numpy as np
from scipy.spatial import cKDTree

import meshlap
from meshlap import baselines, shapes
from meshlap.corrections import highorder

sys.path.insert(0, str(Path(__file__).parent))
from results_file import write_section  # noqa: E402

DATA = Path(__file__).resolve().parent.parent / "tests" / "data"
NOISE = (0.001, 0.005, 0.01)
R_TORUS, r_TORUS = 1.0, 0.4
NOTES: list[str] = []


@dataclass
class Case:
    shape: str
    condition: str
    V: np.ndarray
    F: np.ndarray | None
    funcs: list[tuple[np.ndarray, np.ndarray]]  # (f at the input points, exact Δf)
    mask: np.ndarray | None = None
    results: dict[str, tuple[float, float, float]] = field(default_factory=dict)  # E2, build s, nnz/row


def e2(case: Case, apply) -> float:
    err = 0.0
    for f, lap in case.funcs:
        y = np.asarray(apply(f))
        m = slice(None) if case.mask is None else case.mask
        err = max(err, float(np.linalg.norm(y[m] - lap[m]) / np.linalg.norm(lap[m])))
    return err


def timed(fn):
    t = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t


# -- inputs -----------------------------------------------------------------------------------
def _noisy(V0: np.ndarray, N: np.ndarray, level: float, area: float, seed: int) -> np.ndarray:
    sigma = level * math.sqrt(area / (4 * math.pi))
    return V0 + np.random.default_rng(seed).normal(scale=sigma, size=(len(V0), 1)) * N


def _ambient_trig(X0: np.ndarray, N: np.ndarray, kappa: np.ndarray, X: np.ndarray):
    # Δ_S f = tr ∇²f − nᵀ∇²f n − κ ∂f/∂n for f = sin(a·x) and cos(a·x)
    out = []
    for a, trig in (((1.0, 2.0, 0.0), np.sin), ((2.0, 0.0, -1.0), np.cos)):
        a = np.array(a)
        an = N @ a
        s = trig(X0 @ a)
        ds = np.cos(X0 @ a) if trig is np.sin else -np.sin(X0 @ a)
        out.append((trig(X @ a), -s * (a @ a - an**2) - kappa * ds * an))
    return out


def sphere_cases(n: int) -> list[Case]:
    fs = shapes.sphere_functions()
    out = []
    for cond, kind in (("clean", "uniform"), ("irregular", "random")):
        V, F = shapes.sphere(n, kind=kind, seed=1)
        out.append(Case("sphere", cond, V, F, [(fs[k][0](V), fs[k][1](V)) for k in ("x^2", "exp(x)")]))
    V0, F = shapes.sphere(n, kind="random", seed=1)
    for i, level in enumerate(NOISE):
        V = _noisy(V0, V0, level, 4 * math.pi, seed=10 + i)
        out.append(
            Case(
                "sphere",
                f"noise {100 * level:g}%",
                V,
                F,
                [(fs[k][0](V), fs[k][1](V0)) for k in ("x^2", "exp(x)")],
            )
        )
    return out


def _torus_frame(V: np.ndarray):
    th, ph = shapes.torus_angles(V, R_TORUS)
    N = np.column_stack([np.cos(th) * np.cos(ph), np.cos(th) * np.sin(ph), np.sin(th)])
    return N, 1.0 / r_TORUS + np.cos(th) / (R_TORUS + r_TORUS * np.cos(th))


def torus_cases(n: int) -> list[Case]:
    out = []
    area = 4 * math.pi**2 * R_TORUS * r_TORUS
    for cond, jitter in (("clean", 0.0), ("irregular", 0.45)):
        V, F = shapes.torus(n, R_TORUS, r_TORUS, seed=1, jitter=jitter)
        N, kap = _torus_frame(V)
        out.append(Case("torus", cond, V, F, _ambient_trig(V, N, kap, V)))
    V0, F = shapes.torus(n, R_TORUS, r_TORUS, seed=1, jitter=0.45)
    N, kap = _torus_frame(V0)
    for i, level in enumerate(NOISE):
        V = _noisy(V0, N, level, area, seed=20 + i)
        out.append(Case("torus", f"noise {100 * level:g}%", V, F, _ambient_trig(V0, N, kap, V)))
    return out


def spot_cases() -> list[Case]:
    V, F = meshlap.io.read_mesh(DATA / "spot.obj")
    F = np.asarray(F, dtype=np.int64)
    V = V - V.mean(axis=0)
    V *= math.sqrt(4 * math.pi / igl.doublearea(V, F).sum() * 2)  # area 4π
    levels = [(V, F)]
    for _ in range(3):
        levels.append(igl.loop(*levels[-1], 1))
    (V1, F1), (V3, F3) = levels[1], levels[3]
    (L1, N1, H1, ok1), (L3, N3x, H3, ok3) = shapes.loop_limit(V1, F1), shapes.loop_limit(V3, F3)
    N3 = igl.per_vertex_normals(L3, F3)
    extraordinary = np.flatnonzero(np.diff(igl.adjacency_matrix(F).tocsr().indptr) != 6)
    edge1 = float(np.mean(np.linalg.norm(L1[F1[:, 0]] - L1[F1[:, 1]], axis=1)))
    # the vertices of a level come first in the next, and a vertex's limit point stays put
    assert np.abs(L3[: len(L1)] - L1).max() < 1e-8
    near_bad = cKDTree(L3[extraordinary])
    idx1 = np.arange(len(L1))
    mask1 = near_bad.query(L1, k=1)[0] > 4 * edge1
    assert ok1[mask1].all()  # 4 edges from valence ≠ 6: the box spline, Δf exact
    ref1 = [lap for _, lap in shapes.x_functions(L1, N1, H1).values()]
    f3s = [L3[:, 0] ** 2, np.exp(L3[:, 0])]
    # the reference before: a degree-6 fit on the level-3 limit points
    indptr, indices, dist = highorder.knn_pattern(L3, 52, centers=idx1)
    Lr = highorder.pointwise_rows(L3, indptr, indices, dist.reshape(len(idx1), -1)[:, -1] ** 2 / 32, 6,
                                  centers=idx1)
    fitted = max(np.linalg.norm((np.asarray(Lr @ f3)[idx1] - r)[mask1]) / np.linalg.norm(r[mask1])
                 for f3, r in zip(f3s, ref1, strict=True))
    NOTES.append(
        f"spot: E2 over {mask1.mean():.0%} of the points (Δf exact there: the limit surface is the regular "
        f"box spline); a degree-6 fit on the level-3 limit points, the reference before, is {fitted:.2g} "
        "from it"
    )
    out = [Case("spot", "clean", L1, F1, [(f3[idx1], r) for f3, r in zip(f3s, ref1, strict=True)], mask1)]
    sub = np.sort(np.random.default_rng(3).choice(len(L3), len(L1), replace=False))
    mask_sub = near_bad.query(L3[sub], k=1)[0] > 4 * edge1
    assert ok3[sub][mask_sub].all()
    refs = [lap for _, lap in shapes.x_functions(L3[sub], N3x[sub], H3[sub]).values()]
    funcs = [(f3[sub], r) for f3, r in zip(f3s, refs, strict=True)]
    out.append(Case("spot", "irregular", L3[sub], None, funcs, mask_sub))
    for i, level in enumerate(NOISE):
        Vn = _noisy(L1, N3[idx1], level, 4 * math.pi, seed=30 + i)
        out.append(
            Case(
                "spot",
                f"noise {100 * level:g}%",
                Vn,
                F1,
                [(Vn[:, 0] ** 2, ref1[0]), (np.exp(Vn[:, 0]), ref1[1])],
                mask1,
            )
        )
    return out


# -- methods ----------------------------------------------------------------------------------
def build(case: Case, mesh: bool, kw: dict) -> meshlap.MeshLaplacian:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", meshlap.MeshWarning)
        op = meshlap.laplacian(case.V, case.F, **kw) if mesh else meshlap.point_cloud_laplacian(case.V, **kw)
        op @ case.funcs[0][0]  # the point-wise rows may be built lazily
    return op


def run_meshlap(case: Case, mesh: bool, kw: dict, summary: list | None = None) -> tuple[float, float, float]:
    op, t = timed(lambda: build(case, mesh, kw))
    if summary is not None:
        summary.append(op.pointwise_choice.summary() if op.pointwise_choice is not None else "—")
    return e2(case, lambda f: op @ f), t, op.L.nnz / len(case.V)


def run_cot(case: Case) -> tuple[float, float, float]:
    op, t = timed(lambda: baselines.cotangent(case.V, case.F))
    return e2(case, lambda f: op @ f), t, op.L.nnz / len(case.V)


def run_robust(case: Case, mesh: bool) -> tuple[float, float, float]:
    import robust_laplacian

    if mesh:
        (L, M), t = timed(lambda: robust_laplacian.mesh_laplacian(case.V, case.F))
    else:
        (L, M), t = timed(lambda: robust_laplacian.point_cloud_laplacian(case.V))
    m = M.diagonal()
    return e2(case, lambda f: -(L @ f) / m), t, L.nnz / len(case.V)


def run_gmls(case: Case, degree: int) -> tuple[float, float, float]:
    import pycompadre as pc

    def build():
        g = pc.GMLS(degree, 3, "QR", "MANIFOLD", "NO_CONSTRAINT", degree)
        g.setWeightingParameter(2)
        g.setWeightingType("power")
        helper = pc.ParticleHelper(g)
        helper.generateKDTree(case.V)
        g.addTargets(pc.TargetOperation.LaplacianOfScalarPointEvaluation)
        helper.generateNeighborListsFromKNNSearchAndSet(case.V, degree, 2, 1.6)
        g.generateAlphas(1, False)
        return g, helper

    (g, helper), t = timed(build)
    nl = helper.getNeighborLists()
    per_row = nl.getTotalNeighborsOverAllLists() / len(case.V)
    del nl
    stencil = helper.applyStencil
    op = pc.TargetOperation.LaplacianOfScalarPointEvaluation
    err = e2(case, lambda f, apply=stencil: apply(np.ascontiguousarray(f, dtype=np.float64), op))
    del stencil, helper, g
    return err, t, per_row


def evaluate(case: Case, mesh: bool, have_gmls: bool, have_robust: bool) -> str:
    r = case.results
    summary: list[str] = []
    r["moments"] = run_meshlap(case, mesh, {"pointwise": True})
    r["default"] = run_meshlap(case, mesh, {}, summary)
    r["paper"] = run_meshlap(case, mesh, {"correction": "none"})
    if mesh:
        r["COT"] = run_cot(case)
    if have_robust:
        r["robust"] = run_robust(case, mesh)
    if have_gmls:
        for q in (2, 3, 4):
            r[f"GMLS{q}"] = run_gmls(case, q)
    return summary[0]


def build_ratios(n: int, repeat: int = 3) -> list[str]:
    """CPU seconds of the builds (with one ``op @ f``): the default, ``pointwise=True`` and the
    paper's, alternated in this process, the best of ``repeat`` each."""
    cases = {f"{c.shape} {c.condition}": c for c in sphere_cases(n) + torus_cases(n)}
    inputs = [(f"{name.split()[0]} {'mesh' if mesh else 'cloud'}, {name.split(' ', 1)[1]}", cases[name], mesh)
              for name, mesh in (("sphere clean", True), ("sphere noise 0.5%", True),
                                 ("sphere noise 1%", True), ("sphere clean", False), ("torus clean", True),
                                 ("torus noise 1%", True))]
    kws = {"default": {}, "pointwise=True": {"pointwise": True}, "paper": {"correction": "none"}}
    lines = ["| input | default | `pointwise=True` | paper | default / `pointwise=True` | default / paper |",
             "|---|---|---|---|---|---|"]
    for label, case, mesh in inputs:
        best = dict.fromkeys(kws, math.inf)
        for _ in range(repeat):
            for name, kw in kws.items():
                t = time.process_time()
                build(case, mesh, kw)
                best[name] = min(best[name], time.process_time() - t)
        d, m, p = best["default"], best["pointwise=True"], best["paper"]
        lines.append(f"| {label} | {d:.2f} s | {m:.2f} s | {p:.2f} s | {d / m:.2f} | {d / p:.2f} |")
        print(lines[-1], flush=True)
    return lines


# -- convergence ------------------------------------------------------------------------------
def convergence(ns: list[int]) -> list[str]:
    lines = [
        "| surface | degree | " + " | ".join(f"n = {n:,}" for n in ns) + " | order in the spacing |",
        "|---|---|" + "---|" * len(ns) + "---|",
    ]
    for surface in ("sphere", "torus"):
        for degree, K in ((2, 20), (4, 30), (6, 52), ("default", 0)):
            errs, hs = [], []
            for n in ns:
                case = sphere_cases(n)[1] if surface == "sphere" else torus_cases(n)[0]
                if degree == "default":  # the operator itself: meshlap.laplacian(V, F) @ f
                    L = meshlap.laplacian(case.V, case.F).L
                else:
                    indptr, indices, dist = highorder.knn_pattern(case.V, K)
                    h = dist.reshape(len(case.V), K)[:, -1] ** 2 / 32
                    L = highorder.pointwise_rows(case.V, indptr, indices, h, degree)
                errs.append(e2(case, lambda f, L=L: L @ f))
                hs.append(math.sqrt(1.0 / len(case.V)))
            order = np.polyfit(np.log(hs), np.log(errs), 1)[0]
            what = "the default (`meshlap.laplacian(V, F)`)" if degree == "default" else f"{degree} (K = {K})"
            lines.append(
                f"| {surface} ({'random' if surface == 'sphere' else 'grid'}) | {what} | "
                + " | ".join(f"{x:.2e}" for x in errs)
                + f" | {order:.2f} |"
            )
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=16000)
    ap.add_argument("--no-write", action="store_true")
    ap.add_argument("--shapes", default="sphere,torus,spot")
    ap.add_argument("--build-ratios", action="store_true", help="only the table of build times (no write)")
    args = ap.parse_args()
    if args.build_ratios:
        build_ratios(args.n)
        return
    load = os.getloadavg()[0]
    try:
        import pycompadre

        kokkos = pycompadre.KokkosParser()
        have_gmls = True
    except ImportError:
        print("pycompadre missing: GMLS skipped")
        have_gmls, kokkos = False, None
    try:
        import robust_laplacian  # noqa: F401

        have_robust = True
    except ImportError:
        print("robust-laplacian missing: skipped")
        have_robust = False
    builders = {
        "sphere": lambda: sphere_cases(args.n),
        "torus": lambda: torus_cases(args.n),
        "spot": spot_cases,
    }
    methods = (
        ["default", "moments", "paper", "COT"]
        + (["robust"] if have_robust else [])
        + (["GMLS2", "GMLS3", "GMLS4"] if have_gmls else [])
    )
    acc = [
        "| input | n | " + " | ".join(methods)
        + " | best peer | default ≤ 1.5× best peer | default ≤ paper |",
        "|---|---|" + "---|" * len(methods) + "---|---|---|",
    ]
    cost = ["| input | " + " | ".join(methods) + " | default / moments build |",
            "|---|" + "---|" * len(methods) + "---|"]
    ratios = []
    chosen = []
    for name in args.shapes.split(","):
        for case in builders[name]():
            for mesh in (True, False) if case.F is not None else (False,):
                summary = evaluate(case, mesh, have_gmls, have_robust)
                r = case.results
                label = f"{case.shape} {'mesh' if mesh else 'cloud'}, {case.condition}"
                best = min((v[0], k) for k, v in r.items() if k not in ("default", "moments"))
                cells = [f"{r[m][0]:.2g}" if m in r else "—" for m in methods]
                acc.append(
                    f"| {label} | {len(case.V):,} | " + " | ".join(cells) + f" | {best[1]} {best[0]:.2g} | "
                    f"{'yes' if r['default'][0] <= 1.5 * best[0] else 'no'} | "
                    f"{'yes' if r['default'][0] <= r['paper'][0] else 'no'} |"
                )
                ratios.append(r["default"][1] / r["moments"][1])
                cost.append(
                    f"| {label} | "
                    + " | ".join(f"{r[m][1]:.2f} s / {r[m][2]:.0f}" if m in r else "—" for m in methods)
                    + f" | {ratios[-1]:.2f} |"
                )
                chosen.append(f"| {label} | {summary} |")
                print(acc[-1], flush=True)
                case.results = {}
    ratio_table = build_ratios(args.n)
    conv = convergence([1000, 2000, 4000, 8000, 16000] if args.n >= 16000 else [1000, 2000, 4000])
    print("\n".join(conv))
    lines = [
        f"`python benchmarks/bench_pointwise.py --n {args.n}` (2 shared cores, load average {load:.1f} at "
        f"the start and {os.getloadavg()[0]:.1f} at the end; {time.strftime('%Y-%m-%d')}). "
        "default = `meshlap.laplacian(V, F)` / `point_cloud_laplacian(P)`, its `op @ f` (the fitted "
        "point-wise rows: PCA frames, the same rows for a mesh and its vertices as a cloud); moments = "
        "the same with `pointwise=True` (the degree-2 moment rows, the default before issue 20); paper = "
        '`correction="none"`; COT = libigl cotangent (meshes); robust = robust-laplacian; GMLSq = '
        "pycompadre, degree q. Conventions: see the benchmark's docstring.",
        "",
        "E2 = ‖Lf − Δf‖/‖Δf‖ (the larger over the two functions):",
        "",
        *acc,
        "",
        *NOTES,
        "",
        "Build time (wall clock, one build each: the load of other processes shows in it; the ratio "
        "of the CPU times, alternated, is the table after this one) / entries per row of what `op @ f` "
        f"applies (the default's build against the moment rows': at most {max(ratios):.2f}×, median "
        f"{float(np.median(ratios)):.2f}×):",
        "",
        *cost,
        "",
        "The build against the moment rows', CPU seconds (`time.process_time`, so other processes' load "
        "counts less), the best of 3 alternated in this process, one `op @ f` included "
        f"(`python benchmarks/bench_pointwise.py --n {args.n} --build-ratios` prints it alone):",
        "",
        *ratio_table,
        "",
        "What the default's rows chose (`op.pointwise_choice.summary()`):",
        "",
        "| input | degree, neighbours, width, noise |",
        "|---|---|",
        *chosen,
        "",
        "Convergence of the fitted rows with a fixed degree (K nearest, h = d_K²/32) on clean inputs, E2 "
        "against n; the order is the slope of log E2 against log √(1/n):",
        "",
        *conv,
    ]
    if not args.no_write:
        write_section("Point-wise accuracy", lines)
    sys.stdout.flush()
    del kokkos
    os._exit(0)  # pycompadre's Kokkos objects abort the interpreter's own shutdown


if __name__ == "__main__":
    main()
