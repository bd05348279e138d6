"""What users build on a Laplacian: meshlap beside its peers, in one process.

    python benchmarks/bench_uses.py [--sizes 1000,10000,50000]

1. Geodesic distance by the heat method against the exact distance: unit spheres (mesh and
   cloud, clean and with 0.5% radial noise; the exact distance is the great circle between
   the points' projections on the sphere) and the stratified flat square [-1, 1]² (Euclidean).
   Relative error |d - d*| / d* over the vertices with d* ≥ 0.1, mean and max, over three
   sources; time per source after the set-up (meshlap: ``HeatDistance.compute_many``; every
   method: the fastest of up to ten runs within about a second), and the set-up (meshlap:
   operator build + ``HeatDistance``). Peers: potpourri3d's ``MeshHeatMethodDistanceSolver`` /
   ``PointCloudHeatSolver``, LaPy's heat diffusion + ``compute_geodesic_f``, libigl's
   ``heat_geodesics_precompute/solve`` (all at their default t). On the sphere meshes meshlap
   also runs with ``laplacian(V, F, denoise=True)``, its row labelled so (the default's row
   stays). The noisy sphere meshes also against their own exact (polyhedral) geodesic distance,
   libigl's ``exact_geodesic``: the great circle is not the geodesic of a surface that rough.
2. Dirichlet problems on the unit disc (``meshlap.shapes.disc``): the harmonic x² - y² from
   its boundary values and Δφ = 4 with φ = x² + y² on the boundary; max error. meshlap with its
   default operator and with the cotangent baseline; LaPy ``Solver.poisson``; libigl ``harmonic``.
3. Descriptors of a real mesh (tests/data/spot.obj): ShapeDNA beside LaPy's normalize_ev +
   reweight_ev fed the same eigenvalues, the WKS beside pyFM's published formula (pyFM is not
   installed: its auto_WKS written out here); and the normalised ShapeDNA / area-normalised
   WKS of the mesh against those of its vertices as a point cloud.
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, str(Path(__file__).resolve().parent))
from results_file import write_section  # noqa: E402

import meshlap  # noqa: E402
from meshlap import HeatDistance, harmonic, poisson  # noqa: E402
from meshlap.baselines import cotangent  # noqa: E402
from meshlap.descriptors import shape_dna, wave_kernel_signature  # noqa: E402
from meshlap.solve import boundary_measure  # noqa: E402

SOURCES = 3
NEAR = 0.1


def _errors(D: np.ndarray, exact: np.ndarray) -> tuple[float, float]:
    far = exact >= NEAR
    r = np.abs(D - exact)[far] / exact[far]
    return float(r.mean()), float(r.max())


def _timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def _best(fn):
    """fn's output and its fastest of up to ten runs (within about a second): one run of a few
    milliseconds on shared cores measures the neighbours' load as much as the method, and so
    do three (the 1,000-vertex rows moved by 2× between runs of this script)."""
    out, best = _timed(fn)
    spent = best
    for _ in range(9):
        if spent > 1.0:
            break
        t = _timed(fn)[1]
        spent, best = spent + t, min(best, t)
    return out, best


def _sphere_exact(P: np.ndarray, src: np.ndarray) -> np.ndarray:
    Q = P / np.linalg.norm(P, axis=1, keepdims=True)
    return np.arccos(np.clip(Q[src] @ Q.T, -1.0, 1.0))


def _meshlap(op_fn, src):
    (op, hd), setup = _timed(lambda: (lambda o: (o, HeatDistance(o)))(op_fn()))
    D, t = _best(lambda: hd.compute_many(src))
    return D, setup, t / len(src)


def _pp3d_mesh(V, F, src):
    import potpourri3d as pp3d

    s, setup = _timed(lambda: pp3d.MeshHeatMethodDistanceSolver(V, F))
    D, t = _best(lambda: np.array([s.compute_distance(int(i)) for i in src]))
    return D, setup, t / len(src)


def _pp3d_cloud(P, src):
    import potpourri3d as pp3d

    s, setup = _timed(lambda: pp3d.PointCloudHeatSolver(P))
    D, t = _best(lambda: np.array([s.compute_distance(int(i)) for i in src]))
    return D, setup, t / len(src)


def _lapy(V, F, src):
    from lapy import TriaMesh
    from lapy.diffgeo import compute_geodesic_f
    from lapy.heat import diffusion

    mesh, setup = _timed(lambda: TriaMesh(V, F))

    def run():
        u = diffusion(mesh, [[int(i)] for i in src])
        return compute_geodesic_f(mesh, u).T

    D, t = _best(run)
    return D, setup, t / len(src)


def _igl(V, F, src):
    import igl

    def pre():
        data = igl.HeatGeodesicsData()
        igl.heat_geodesics_precompute(V, F, data)
        return data

    data, setup = _timed(pre)
    D, t = _best(lambda: np.array([igl.heat_geodesics_solve(data, np.array([i], dtype=np.int64))
                                   for i in src]))
    return D, setup, t / len(src)


def _row(lines, case, who, D, exact, setup, per):
    mean, worst = _errors(D, exact)
    lines.append(f"| {case} | {who} | {mean:.4f} | {worst:.3f} | {setup:.2f} | {per * 1e3:.1f} |")
    print(lines[-1], flush=True)


def _mesh_methods(V, F, src, denoise=False):
    """(who, D, set-up, per source) of meshlap and each peer on one mesh; with ``denoise`` also
    meshlap's operator built with ``denoise=True`` (the user's option for a noisy surface)."""
    out = [("meshlap", *_meshlap(lambda: meshlap.laplacian(V, F), src))]
    if denoise:
        out.append(("meshlap (denoise=True)", *_meshlap(lambda: meshlap.laplacian(V, F, denoise=True), src)))
    return out + [(who, *fn(V, F, src)) for who, fn in (("potpourri3d", _pp3d_mesh), ("LaPy", _lapy),
                                                         ("libigl", _igl))]


def _polyhedral(V, F, src):
    """The mesh's own exact geodesic distance from each source (libigl's exact_geodesic, MMP)."""
    import igl

    none = np.zeros(0, dtype=np.int64)
    return np.array([igl.exact_geodesic(V, F, np.array([i], dtype=np.int64), none, np.arange(len(V)), none)
                     for i in src])


def geodesics(sizes: list[int]) -> tuple[list[str], list[str]]:
    lines = ["| input | method | mean rel. error | max rel. error | set-up (s) | per source (ms) |",
             "|---|---|---|---|---|---|"]
    own = ["| input | method | mean rel. error | max rel. error |", "|---|---|---|---|"]
    rng = np.random.default_rng(0)
    for n in sizes:
        for noise in (0.0, 0.005):
            V, F = meshlap.shapes.sphere(n, seed=0)
            if noise:
                V = V * (1 + noise * rng.standard_normal((len(V), 1)))
            src = np.array([0, n // 3, 2 * n // 3])
            exact = _sphere_exact(V, src)
            case = f"sphere mesh {n:,}" + (" noise 0.5%" if noise else "")
            results = _mesh_methods(V, F, src, denoise=True)
            for who, D, setup, per in results:
                _row(lines, case, who, D, exact, setup, per)
            if noise:  # the great circle is not this rough surface's geodesic: its own exact one
                poly = _polyhedral(V, F, src)
                for who, D in [("great circle (the reference above)", exact)] + [r[:2] for r in results]:
                    own.append("| {} | {} | {:.4f} | {:.3f} |".format(case, who, *_errors(D, poly)))
                    print(own[-1], flush=True)
            P = meshlap.samples.sphere_points(n, "noisy" if noise else "random", noise=noise)
            exact = _sphere_exact(P, src)
            case = f"sphere cloud {n:,}" + (" noise 0.5%" if noise else "")
            D, setup, per = _meshlap(lambda P=P: meshlap.point_cloud_laplacian(P), src)
            _row(lines, case, "meshlap", D, exact, setup, per)
            D, setup, per = _pp3d_cloud(P, src)
            _row(lines, case, "potpourri3d", D, exact, setup, per)
    V, F = meshlap.shapes.plane(10000, kind="stratified")
    src = np.array([int(np.argmin(np.linalg.norm(V, axis=1))), 0, len(V) // 3])
    exact = np.linalg.norm(V[src][:, None] - V[None], axis=2)
    case = f"flat square mesh {len(V):,}"
    for who, D, setup, per in _mesh_methods(V, F, src):
        _row(lines, case, who, D, exact, setup, per)
    case = f"flat square cloud {len(V):,}"
    D, setup, per = _meshlap(lambda: meshlap.point_cloud_laplacian(V), src)
    _row(lines, case, "meshlap", D, exact, setup, per)
    D, setup, per = _pp3d_cloud(V, src)
    _row(lines, case, "potpourri3d", D, exact, setup, per)
    return lines, own


def dirichlet(n: int = 10000) -> list[str]:
    import igl
    from lapy import Solver, TriaMesh

    V, F = meshlap.shapes.disc(n)
    x, y = V[:, 0], V[:, 1]
    edge = np.flatnonzero(boundary_measure(meshlap.geometry.surface(V, F)))
    harm, quad = x**2 - y**2, x**2 + y**2
    lines = [f"Unit disc, {len(V):,} vertices, {len(edge)} on the boundary: max |φ - φ*|.", "",
             "| method | harmonic x² - y² | Δφ = 4, φ* = x² + y² | time (s) |", "|---|---|---|---|"]

    def add(who, fn):
        (a, b), t = _timed(fn)
        lines.append(f"| {who} | {np.abs(a - harm).max():.2e} | {np.abs(b - quad).max():.2e} | {t:.2f} |")
        print(lines[-1], flush=True)

    for who, op_fn in (("meshlap (default operator)", lambda: meshlap.laplacian(V, F)),
                       ("meshlap (cotangent baseline)", lambda: cotangent(V, F))):
        def run(op_fn=op_fn):
            op = op_fn()
            return (harmonic(op, edge, harm[edge]), poisson(op, 4.0, dirichlet=(edge, quad[edge])))
        add(who, run)

    def lapy_run():
        s = Solver(TriaMesh(V, F))
        return s.poisson(0.0, dtup=(edge, harm[edge])), s.poisson(-4.0, dtup=(edge, quad[edge]))

    add("LaPy Solver.poisson", lapy_run)

    def igl_run():
        a = igl.harmonic(V, F, edge, harm[edge][:, None], 1)[:, 0]
        L, M = igl.cotmatrix(V, F), igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI)
        B = (M @ np.full(len(V), 4.0))[:, None]  # minimise ½φᵀ(-L)φ + φᵀ(M f): -Lφ = -M f
        Aeq = sp.csc_matrix((0, len(V)))
        b = igl.min_quad_with_fixed(sp.csc_matrix(-L), B, edge, quad[edge][:, None], Aeq,
                                    np.zeros((0, 1)), True)
        return a, np.asarray(b)[:, 0]

    add("libigl harmonic / min_quad_with_fixed", igl_run)
    return lines


def _pyfm_wks(lam, phi, num_e):
    # pyFM's auto_WKS(evals, evects, num_E, scaled=True), written out from its published code
    keep = lam > 1e-5
    lam, phi = np.abs(lam[keep]), phi[:, keep]
    e_min, e_max = np.log(lam[0]), np.log(lam[-1])
    sigma = 7 * (e_max - e_min) / num_e
    e = np.linspace(e_min + 2 * sigma, e_max - 2 * sigma, num_e)
    coefs = np.exp(-np.square(e[:, None] - np.log(lam)[None, :]) / (2 * sigma**2))
    natural = np.einsum("tnk,nk->nt", phi[None] * coefs[:, None, :], phi)
    return natural / coefs.sum(1)[None, :]


def descriptors(k: int = 50) -> list[str]:
    from lapy import TriaMesh
    from lapy.shapedna import compute_shapedna, normalize_ev, reweight_ev

    V, F = meshlap.io.read_mesh(Path(__file__).resolve().parents[1] / "tests" / "data" / "spot.obj",
                                triangulate=True)
    mesh = TriaMesh(V, F)
    ev = compute_shapedna(mesh, k=k)
    lam, phi = ev["Eigenvalues"], ev["Eigenvectors"]
    ours = shape_dna(eig=(lam, phi), measure=mesh.area(), reweight=True)
    theirs = reweight_ev(normalize_ev(mesh, lam, method="geometry"))
    dna_diff = float(np.abs(ours[1:] - theirs[1:]).max() / np.abs(theirs[1:]).max())
    wks = wave_kernel_signature(eig=(lam, phi), n_energies=100)
    wks_diff = float(np.abs(wks - _pyfm_wks(lam, phi, 100)).max() / np.abs(wks).max())
    op_mesh = meshlap.laplacian(V, F)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        op_cloud = meshlap.point_cloud_laplacian(V)
    eig_m, eig_c = meshlap.spectral.eigs(op_mesh, k), meshlap.spectral.eigs(op_cloud, k)
    dna_m, dna_c = shape_dna(op_mesh, eig=eig_m), shape_dna(op_cloud, eig=eig_c)
    rel = np.abs(dna_m[1:] - dna_c[1:]) / dna_m[1:]
    w_m = wave_kernel_signature(op_mesh, 20, eig=eig_m, area_normalize=True)
    w_c = wave_kernel_signature(op_cloud, 20, eig=eig_c, area_normalize=True)
    w_rel = float(np.median(np.abs(w_m - w_c) / np.abs(w_m)))
    lines = [f"spot.obj ({len(V):,} vertices), k = {k} eigenpairs.", "",
             "| check | value |", "|---|---|",
             f"| ShapeDNA (normalised, re-weighted) vs LaPy on LaPy's eigenvalues: max rel. difference | "
             f"{dna_diff:.1e} |",
             f"| WKS (100 energies) vs pyFM's auto_WKS formula on LaPy's eigenpairs: max rel. difference | "
             f"{wks_diff:.1e} |",
             f"| ShapeDNA mesh vs its vertices as a cloud: mean / max rel. difference, λ_1..λ_{k - 1} | "
             f"{rel.mean():.3f} / {rel.max():.3f} |",
             f"| area-normalised WKS (20 energies) mesh vs cloud: median rel. difference | {w_rel:.3f} |"]
    for line in lines[4:]:
        print(line, flush=True)
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="1000,10000,50000")
    ap.add_argument("--no-write", action="store_true")
    args = ap.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    warnings.simplefilter("ignore", meshlap.MeshWarning)
    t0 = time.perf_counter()
    geo, own = geodesics(sizes)
    bvp = dirichlet()
    desc = descriptors()
    stamp = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    lines = [f"`python benchmarks/bench_uses.py --sizes {args.sizes}`, {stamp}, "
             f"{platform.machine()}, 2 shared cores, {time.perf_counter() - t0:.0f} s in all.", "",
             "### Geodesic distance (heat method)", "", *geo, "",
             "Noisy sphere meshes against their own exact geodesic distance (libigl's exact_geodesic, "
             "MMP), the same three sources:", "", *own, "",
             "### Dirichlet problems", "", *bvp, "", "### Descriptors", "", *desc]
    if not args.no_write:
        write_section("bench_uses.py", lines)


if __name__ == "__main__":
    main()
