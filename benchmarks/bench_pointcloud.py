"""Point clouds, curves and volumes (issue 13): accuracy against known spectra, beside
robust-laplacian (and LaPy on the cube), and the build time for 1,000,000 points.

    python benchmarks/bench_pointcloud.py --accuracy   # any time: errors only
    python benchmarks/bench_pointcloud.py --timing     # on a quiet machine: build times
    python benchmarks/bench_pointcloud.py --timing --n 20000 --no-write   # a small run, printed
    MESHLAP_CORPUS=/path/to/corpus python benchmarks/bench_pointcloud.py --volume  # a volume's cloud

Each part writes its own section of benchmarks/RESULTS.md (``--no-write``: prints it instead).
The default (``meshlap.point_cloud_laplacian``, ``meshlap.laplacian``) is named as such, with
the builder ``op.decision`` chose; "kernel" is the corrected heat kernel
(``meshlap.MeshLaplacian``) at the width given.
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import time
import warnings

import numpy as np
import scipy.sparse.linalg as sla
from pykdtree.kdtree import KDTree
from scipy.spatial import Delaunay

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import real_corpus  # noqa: E402
from results_file import write_section  # noqa: E402

import meshlap  # noqa: E402
from meshlap import samples, spectral  # noqa: E402
from meshlap.geometry import pointcloud  # noqa: E402
from meshlap.solve import PoissonSolver  # noqa: E402

L_SPHERE = np.repeat(np.arange(4), 2 * np.arange(4) + 1)
EIG_SPHERE = (L_SPHERE * (L_SPHERE + 1)).astype(float)
H_EIG = {"uniform": 1e-3, "random": 2e-3, "noisy": 4e-3}  # see the README for the trade-off
M2 = np.array([1, 1, 4, 4, 9, 9, 16, 16.0])  # a unit circle's eigenvalues m², m = 1..4
NO_WRITE = False  # --no-write


def _uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def _sphere_row(kind: str, n: int, denoise: bool = False) -> list[str]:
    import robust_laplacian

    P = samples.sphere_points(n, kind, seed=1)
    h_eig = 2e-3 if denoise else H_EIG[kind]
    U = P / np.linalg.norm(P, axis=1, keepdims=True)
    exact = 2 - 6 * U[:, 0] ** 2
    f = U[:, 0] ** 2
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", meshlap.MeshWarning)
        geo = pointcloud.point_cloud_geometry(P, denoise=denoise)
    lam = spectral.eigs(meshlap.MeshLaplacian(geo, h=h_eig), 16, tol=1e-4)[0]
    ours_eig = np.abs(lam[1:] / EIG_SPHERE[1:] - 1).max()
    lam = spectral.eigs(meshlap.MeshLaplacian(geo, h=h_eig, correction="none"), 16, tol=1e-4)[0]
    plain_eig = np.abs(lam[1:] / EIG_SPHERE[1:] - 1).max()
    auto = meshlap.MeshLaplacian(geo)
    lam = spectral.eigs(auto, 16, tol=1e-4)[0]
    auto_eig = np.abs(lam[1:] / EIG_SPHERE[1:] - 1).max()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", meshlap.MeshWarning)
        default = meshlap.point_cloud_laplacian(P, denoise=denoise or None)
    lam_d = spectral.eigs(default, 16)[0]
    d_eig = np.abs(lam_d[1:] / EIG_SPHERE[1:] - 1).max()
    d_e2 = np.linalg.norm(default @ f - exact) / np.linalg.norm(exact)
    # robust-laplacian: L is the positive weak form, so Δf ≈ -M⁻¹ L f
    L, M = robust_laplacian.point_cloud_laplacian(P)
    m = M.diagonal()
    lam_r = np.sort(sla.eigsh(L.tocsc(), k=16, M=M.tocsc(), sigma=-1e-6)[0])
    rl_eig = np.abs(lam_r[1:] / EIG_SPHERE[1:] - 1).max()
    rl_e2 = np.linalg.norm(-(L @ f) / m - exact) / np.linalg.norm(exact)
    name = f"{kind}, denoise=True" if denoise else kind
    return [f"| {name} | {n:,} | {100 * d_eig:.2f}% | {d_e2:.1e} | {default.decision.operator} | "
            f"{100 * auto_eig:.2f}% (h={auto.h:.2g}) | {100 * ours_eig:.2f}% (h={h_eig:g}) | "
            f"{100 * plain_eig:.2f}% | {100 * rl_eig:.2f}% | {rl_e2:.3f} |"]


def _circle_rows() -> list[str]:
    rows = []
    for kind, n, h_pw, h_eig in (("uniform", 1000, None, None), ("random", 4000, 3e-3, 5e-4)):
        for d in (2, 3):
            V, E, theta = samples.circle(n, d=d, kind=kind, seed=1)
            for what in ("polyline", "point cloud"):
                geo = (meshlap.geometry.polyline(V, E) if what == "polyline"
                       else pointcloud.point_cloud_geometry(V, k=1))
                op = meshlap.MeshLaplacian(geo, h=h_pw)
                f = np.sin(theta)
                pw = np.abs(op @ f + f).max()
                lam = spectral.eigs(meshlap.MeshLaplacian(geo, h=h_eig), 9)[0]
                rel = np.abs(lam[1:] / M2 - 1).max()
                default = (meshlap.laplacian(V, E) if what == "polyline"
                           else meshlap.point_cloud_laplacian(V, k=1))
                lam = spectral.eigs(default, 9)[0]
                pw_d = np.abs(default @ f + f).max()
                rows.append(f"| {kind} {what} in R^{d} | {n:,} | {100 * pw_d:.3f}% | "
                            f"{100 * np.abs(lam[1:] / M2 - 1).max():.3f}% | {default.decision.operator} | "
                            f"{op.h:.2g} / {h_eig or op.h:.2g} | {100 * pw:.3f}% | {100 * rel:.3f}% |")
    return rows


def _cube_rows() -> list[str]:
    rows = []
    V, T = samples.cube_tetrahedra(24)
    paper = meshlap.laplacian(V, T, k=3, h=7e-4, correction="none")
    kernel = meshlap.laplacian(V, T, k=3, operator="kernel")
    default = meshlap.laplacian(V, T, k=3)
    for name, o in (("BSW, the paper's kernel (h = 7e-4)", paper),
                    (f"BSW corrected kernel (mirror images, h = {kernel.h:.2g})", kernel),
                    (f"default (`meshlap.laplacian(V, T, k=3)`: {default.decision.operator})", default)):
        lam = spectral.eigs(o, 4, tol=1e-6)[0][1:] / math.pi**2
        rows.append(f"| {name} | {len(V):,} | {', '.join(f'{x:.4f}' for x in lam)} | "
                    f"{100 * np.abs(lam - 1).max():.2f}% |")
    try:
        from lapy import Solver, TetMesh

        lam = Solver(TetMesh(V, T)).eigs(k=4)[0][1:] / math.pi**2
        rows.append(f"| LaPy TetMesh (linear FEM) | {len(V):,} | "
                    f"{', '.join(f'{x:.4f}' for x in lam)} | {100 * np.abs(lam - 1).max():.2f}% |")
    except ImportError:
        rows.append("| LaPy | not installed | | |")
    return rows


def _r4_rows() -> list[str]:
    rows = []
    P, _, _ = samples.flat_torus_points(16000, seed=0)
    lam = spectral.eigs(meshlap.point_cloud_laplacian(P, h=6e-3), 9, tol=1e-5)[0][1:]
    rel = np.abs(lam / np.array([1, 1, 1, 1, 2, 2, 2, 2.0]) - 1)
    rows.append(f"| flat torus in R^4, k=2 | 16,000 random | 0.006 | {', '.join(f'{x:.4f}' for x in lam)} "
                f"| {100 * rel.max():.2f}% |")
    for n, h in ((16000, 8e-3), (32000, 6e-3)):
        P = samples.three_sphere_points(n, seed=0)
        t = time.perf_counter()
        op = meshlap.point_cloud_laplacian(P, h=h, k=3)
        build = time.perf_counter() - t
        lam = spectral.eigs(op, 6, tol=1e-5)[0][1:5]
        rows.append(f"| S^3 in R^4, k=3 | {n:,} random | {h:g} | {', '.join(f'{x:.4f}' for x in lam)} | "
                    f"{100 * np.abs(lam / 3 - 1).max():.2f}% (build {build:.0f} s) |")
    return rows


def write(title: str, lines: list[str]) -> None:
    if NO_WRITE:
        print("\n".join(lines))
    else:
        write_section(title, lines)


def accuracy() -> None:
    lines = ["Command: `python benchmarks/bench_pointcloud.py --accuracy` (errors; the S³ build times "
             "ran beside other work and are only indicative).", "",
             "Unit sphere point clouds (seed 1): first 16 eigenvalues' max relative error, and "
             "E2 = ‖L x² − Δx²‖/‖Δx²‖ point-wise; the default (`meshlap.point_cloud_laplacian(P)`, "
             "`denoise=True` where named; `eigs`, and `op @ f`, which applies the point-wise rows the "
             "kernel fits whichever builder made the pencil; the builder from `op.decision`), the "
             "corrected kernel (`meshlap.MeshLaplacian`) at its own h and at the h given, the paper's "
             "plain kernel (`correction='none'`) at the h given, and "
             "robust-laplacian 1.x with its defaults, same points. Where the corrected kernel's "
             "eigenvalues are further off than the plain kernel's, its narrow half (h/2) falls between "
             "the i.i.d. samples:",
             "", "| points | n | default: eigenvalues | default: E2 | default's builder "
             "| kernel: eigenvalues | kernel at the h given | plain kernel at the h given "
             "| robust-laplacian: eigenvalues | robust-laplacian: E2 |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for kind in ("uniform", "random", "noisy"):
        for n in (4000, 16000):
            lines += _sphere_row(kind, n)
    for n in (4000, 16000):
        lines += _sphere_row("noisy", n, denoise=True)
    lines += ["", "Unit circle (k = 1): max |L sin θ + sin θ| and the first 8 nonzero eigenvalues m², the "
              "default (`meshlap.laplacian(V, E)`, `meshlap.point_cloud_laplacian(V, k=1)`) and the kernel "
              "at the h given:", "",
              "| curve | n | default: L sin θ | default: eigenvalues | default's builder | kernel's h "
              "(point-wise / eigenvalues) | kernel: L sin θ | kernel: eigenvalues |",
              "|---|---|---|---|---|---|---|---|"]
    lines += _circle_rows()
    lines += ["", "Unit cube as 82,944 tetrahedra (n = 24, h = 7e-4): first Neumann eigenvalues / π²:", "",
              "| operator | vertices | λ₁..λ₃ / π² | max error |", "|---|---|---|---|"]
    lines += _cube_rows()
    lines += ["", "Points in R^4 (k-d tree path):", "",
              "| manifold | points | h | eigenvalues | max error |", "|---|---|---|---|---|"]
    lines += _r4_rows()
    write("Point clouds, curves and volumes: accuracy", lines)


def timing(n: int) -> None:
    import robust_laplacian

    P = samples.sphere_points(n, "random", seed=0)
    load = _uptime()
    # warm up the compiled kernels on a small cloud
    meshlap.point_cloud_laplacian(P[:5000])
    t = time.perf_counter()
    geo = pointcloud.point_cloud_geometry(P)
    t_mass = time.perf_counter() - t
    # what the masses spend on the hole test (pointcloud._holes), each corner's copy of a triangle
    cells = geo._cache["fem_cells"][0]
    reach8 = np.asarray(KDTree(P).query(P, k=9)[0], np.float64)[:, 1:].mean(axis=1)
    t = time.perf_counter()
    pointcloud._holes(cells, P, reach8, geo.boundary, 2)
    t_holes = time.perf_counter() - t
    # h = spacing², a quarter of the automatic h, as bench_assembly's 1,000,000-vertex mesh
    # (the automatic h would store ~1,100 entries per row, 13 GB)
    h = geo.default_h / 4
    t = time.perf_counter()
    op = meshlap.MeshLaplacian(geo, h=h).assemble()  # the matrix is built on first use
    t_op = time.perf_counter() - t
    nnz = op.nnz
    del op
    t = time.perf_counter()
    default = meshlap.point_cloud_laplacian(P)
    default.S  # noqa: B018  (the default's pencil, FEM on the stars, is built on first use)
    t_default = time.perf_counter() - t
    builder = default.decision.built
    del default
    t = time.perf_counter()
    L, M = robust_laplacian.point_cloud_laplacian(P)
    t_rl = time.perf_counter() - t
    lines = [f"Command: `python benchmarks/bench_pointcloud.py --timing --n {n}`", "",
             f"Load before the runs: `{load}`; after: `{_uptime()}` (2 cores shared with other work;"
             " the ratio from the same process is what counts).", "",
             f"{n:,} i.i.d. random points on the unit sphere:", "",
             "| step | seconds |", "|---|---|",
             f"| meshlap masses (local Delaunay stars, {len(geo.cells):,} triangles) | {t_mass:.1f} |",
             f"| the hole test alone (part of the masses) on the stars' {len(cells):,} corner triangles | "
             f"{t_holes:.1f} |",
             f"| meshlap kernel operator (`operator=\"kernel\"`) at h = spacing² = {h:.3g} ({nnz / n:.0f} "
             f"entries per row) | {t_op:.1f} |",
             f"| meshlap masses + kernel operator | {t_mass + t_op:.1f} |",
             f"| meshlap default, `point_cloud_laplacian(P)` and its S ({builder}; masses included) | "
             f"{t_default:.1f} |",
             f"| robust-laplacian point_cloud_laplacian ({L.nnz / n:.0f} entries per row) | {t_rl:.1f} |"]
    write("Point clouds: build time", lines)


_BEFORE = """
import sys, time, numpy as np
import meshlap
from meshlap.geometry import pointcloud
from meshlap.solve import PoissonSolver
P = np.load(sys.argv[1])
pointcloud.point_masses(np.random.default_rng(0).random((300, 3)), 3)  # compile or load the kernels
t = time.perf_counter()
m, _ = pointcloud.point_masses(P, 3)
t_mass = time.perf_counter() - t
op = meshlap.point_cloud_laplacian(P, k=3)
op.S
t = time.perf_counter()
PoissonSolver(op)
print(t_mass, time.perf_counter() - t)
np.save(sys.argv[2], m)
"""


def _masses_before(P: np.ndarray, before: str) -> tuple[float, float, np.ndarray]:
    """Seconds of ``point_masses(P, 3)`` and of a Neumann ``PoissonSolver``'s set-up, and the
    masses, by the checkout ``before`` in a subprocess."""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        src, out = os.path.join(tmp, "P.npy"), os.path.join(tmp, "m.npy")
        np.save(src, P)
        env = {**os.environ, "PYTHONPATH": before}
        # run in tmp: the working directory would come first on the path
        run = subprocess.run([sys.executable, "-W", "ignore", "-c", _BEFORE, src, out], env=env,
                             capture_output=True, text=True, cwd=tmp)
        if run.returncode:
            raise RuntimeError(f"{before}'s point_masses failed:\n{run.stderr}")
        t_mass, t_poisson = map(float, run.stdout.split()[-2:])
        return t_mass, t_poisson, np.load(out)


def _commit(path: str) -> str:
    return subprocess.run(["git", "-C", path, "rev-parse", "--short", "HEAD"], capture_output=True,
                          text=True).stdout.strip() or "?"


def _volume_row(name: str, P: np.ndarray, ref: np.ndarray, lapy_err: str, before: str | None) -> str:
    """Masses (now, and by the checkout ``before``), operator, eigs, error."""
    t = time.perf_counter()
    mass, _ = pointcloud.point_masses(P, 3)
    t_mass = time.perf_counter() - t
    was = set_up_before = "—"
    if before:
        t_before, t_set_up_before, m_before = _masses_before(P, before)
        diff = np.abs(mass - m_before).max() / np.abs(m_before).max()
        was, set_up_before = f"{t_before:.1f} (masses within {diff:.0e})", f"{t_set_up_before:.1f}"
    t = time.perf_counter()
    op = meshlap.point_cloud_laplacian(P, k=3)
    op.S  # noqa: B018  (the matrix is built on first use)
    t_build = time.perf_counter() - t
    t = time.perf_counter()
    lam = spectral.eigs(op, len(ref) + 1)[0][1:]
    t_eig = time.perf_counter() - t
    err = 100 * np.abs(lam / ref - 1).max()
    t = time.perf_counter()
    poisson = PoissonSolver(op)
    t_set_up = time.perf_counter() - t
    t = time.perf_counter()
    f = np.cos(np.pi * (P[:, 0] - P[:, 0].min()) / np.ptp(P[:, 0]))
    poisson.solve(-op.mass * (f - f @ op.mass / op.mass.sum()))  # integrates to zero
    t_solve = time.perf_counter() - t
    # linear FEM on the points' own Delaunay tetrahedralization, the obvious alternative
    K, M = real_corpus.p1_fem(P, Delaunay(P).simplices)
    dl = real_corpus.pencil_eigs(K, M, len(ref) + 1)[1:]
    return (f"| {name} | {len(P):,} | {t_mass:.1f} | {was} | {t_build:.1f} | {t_eig:.1f} | "
            f"{t_set_up:.1f} | {set_up_before} | {t_solve:.1f} | "
            f"{op.S.nnz / len(P):.0f} | {err:.1f}% | {100 * np.abs(dl / ref - 1).max():.0f}% | {lapy_err} |")


def volume(before: str | None) -> None:
    """A volume's cloud (k = 3 in R³): the unit cube's i.i.d. points and the corpus's tetrahedral
    meshes' vertices (with $MESHLAP_CORPUS); ``before``: a checkout whose masses to time beside."""
    import bench_real
    import lapy

    rng = np.random.default_rng(0)
    meshlap.point_cloud_laplacian(rng.random((500, 3)), k=3)  # compile
    cube = samples.cube_eigenvalues(10)[1:]
    rows = [_volume_row("unit cube, i.i.d. (seed 0)", rng.random((n, 3)), cube, "—", before)
            for n in (2000, 8000)]
    folder = os.environ.get("MESHLAP_CORPUS")
    if folder:
        cache = bench_real.RefCache(real_corpus.corpus_dir(folder))
        for entry in real_corpus.manifest():
            path = real_corpus.corpus_dir(folder) / entry["file"]
            if not path.exists() or not (mesh := real_corpus.load(path, entry["format"])).tet:
                continue
            ref = np.array(cache.get(entry["sha256"], mesh, 11)["ref"])[1:10]
            own = lapy.Solver(lapy.TetMesh(mesh.Vw, mesh.Cw)).eigs(k=10)[0][1:10]
            rows.append(_volume_row(f"{entry['name']}'s vertices", mesh.Vw, ref,
                                    f"{100 * np.abs(own / ref - 1).max():.1f}%", before))
    cmd = "MESHLAP_CORPUS=/path/to/corpus python benchmarks/bench_pointcloud.py --volume"
    if before:
        cmd = (f"git worktree add /tmp/before {_commit(before)} && {cmd} --before /tmp/before")
    lines = [f"Command: `{cmd}` (load before: `{_uptime()}`).", "",
             "`meshlap.point_cloud_laplacian(P, k=3)`: seconds of the masses (local Delaunay stars: the "
             "stars the first 32 neighbours leave insecure taken from one Delaunay tetrahedralization "
             "of the cloud where secure there, the rest searched by Qhull on threads), the same by the "
             "checkout `--before` (a subprocess, the same points), of the build "
             "(`point_cloud_laplacian` and its matrix, the masses included), of 10 eigenpairs, of a "
             "Neumann `PoissonSolver(op)`'s set-up (the same by the checkout `--before`) and of one "
             "solve; the "
             "largest relative error of λ1..λ9 (the cube's Neumann spectrum; a mesh's refined-FEM "
             "reference, bench_real.py's), beside linear FEM on the points' Delaunay tetrahedralization "
             "(scipy's) and LaPy's on the tetrahedra the points came from:", "",
             "| points | n | masses s | masses s before | build s | eigs s | Poisson set-up s | "
             "set-up s before | solve s | entries per row | error | FEM on the points' Delaunay | "
             "LaPy on the mesh |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    write("Point clouds: a volume's cloud", lines + rows)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--accuracy", action="store_true")
    ap.add_argument("--timing", action="store_true")
    ap.add_argument("--volume", action="store_true", help="a volume's cloud: times and errors")
    ap.add_argument("--before", default=None, help="with --volume: a checkout of an earlier commit whose "
                    "masses to time beside")
    ap.add_argument("--n", type=int, default=1_000_000)
    ap.add_argument("--no-write", action="store_true", help="print the sections instead")
    args = ap.parse_args()
    NO_WRITE = args.no_write
    if args.accuracy:
        accuracy()
    if args.timing:
        timing(args.n)
    if args.volume:
        volume(args.before)
    if not (args.accuracy or args.timing or args.volume):
        ap.print_help()
