"""LOBPCG where λ_k's cluster of near-equal eigenvalues is wider than the start block.

    python benchmarks/bench_clusters.py [--no-write] [--title TITLE] [--n 20000]

Copies of one part (a mesh's identical bolts, two spheres) and a sphere's (2l+1)-fold values
make clusters; a block that ends inside one converges at the tiny gap within it. Each row is
``meshlap.spectral.eigs(op, k)`` (LOBPCG: the matrix-free cloud Laplacian of points on unit
spheres, and the stored heat-kernel pencil of two sphere meshes), with its iterations, wall and
CPU seconds, and the largest relative error of its nonzero eigenvalues against the sphere's
exact l(l+1) (each sphere's multiplicities, times the number of spheres). Beside each cloud,
robust-laplacian's point-cloud Laplacian with scipy's shift-invert eigsh, in the same process.
Only public calls are timed, so an older checkout runs the same script
(``PYTHONPATH=/path/to/old python benchmarks/bench_clusters.py --no-write``).
"""

from __future__ import annotations

import argparse
import datetime
import os
import time

import numpy as np
import robust_laplacian
from results_file import write_section
from scipy.sparse.linalg import eigsh

import meshlap
from meshlap import samples, shapes, spectral


def on_spheres(n: int, copies: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    X = rng.standard_normal((n * copies, 3))
    X /= np.linalg.norm(X, axis=1)[:, None]
    return X + np.repeat(3.0 * np.arange(copies), n)[:, None] * [1.0, 0.0, 0.0]


def error(lam: np.ndarray, ref: np.ndarray) -> float:
    nz = ref > 0
    return float((np.abs(lam[nz] - ref[nz]) / ref[nz]).max()) if nz.any() else 0.0


def timed(fn):
    t, c = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - t, time.process_time() - c


def solved(op, k: int, **kw) -> tuple[np.ndarray, int, float, float]:
    """eigs(op, k): eigenvalues, iterations, wall and CPU seconds."""
    info: dict = {}
    (lam, _), wall, cpu = timed(lambda: spectral.eigs(op, k, info=info, **kw))
    return lam, info["iterations"], wall, cpu


def peer(P: np.ndarray, k: int) -> tuple[np.ndarray, float]:
    """robust-laplacian's point-cloud Laplacian and eigsh: eigenvalues and CPU seconds."""
    def run():
        L, M = robust_laplacian.point_cloud_laplacian(P)
        return np.sort(eigsh(L, k, M, sigma=-1e-8)[0])
    lam, _, cpu = timed(run)
    return lam, cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=20_000, help="points per sphere of the clouds")
    ap.add_argument("--mesh-n", type=int, default=3_000, help="vertices per sphere of the meshes")
    ap.add_argument("--title", default="after", help="subsection of RESULTS.md")
    ap.add_argument("--no-write", action="store_true")
    args = ap.parse_args()
    spectral.eigs(meshlap.point_cloud_laplacian(on_spheres(500, 1), matrix_free=True), 4)  # compile
    rows = ["| input | k | operator | iterations | wall s | CPU s | error vs l(l+1) | "
            "robust-laplacian + eigsh: CPU s, error | CPU ratio |", "|---|---|---|---|---|---|---|---|---|"]
    for copies, n, k in [(1, 2 * args.n, 7), (1, 2 * args.n, 10), (2, args.n, 10), (2, args.n, 20)]:
        P = on_spheres(n, copies)
        lam, it, wall, cpu = solved(meshlap.point_cloud_laplacian(P, matrix_free=True), k)
        lam_r, cpu_r = peer(P, k)
        ref = samples.sphere_eigenvalues(k, copies)
        rows.append(f"| {copies} × {n:,} points | {k} | cloud, matrix-free | {it} | {wall:.1f} | {cpu:.1f} | "
                    f"{100 * error(lam, ref):.2f}% | {cpu_r:.1f}, {100 * error(lam_r, ref):.2f}% | "
                    f"{cpu / cpu_r:.1f}× |")
        print(rows[-1], flush=True)
    V, F = shapes.sphere(args.mesh_n, seed=3)
    op = meshlap.laplacian(np.vstack([V, V + [3.0, 0.0, 0.0]]), np.vstack([F, F + len(V)]), operator="kernel")
    for k in (10, 20):
        lam, it, wall, cpu = solved(op, k, method="lobpcg")
        err = error(lam, samples.sphere_eigenvalues(k, 2))
        rows.append(f"| 2 × {args.mesh_n:,}-vertex meshes | {k} | heat-kernel pencil, stored | {it} | "
                    f"{wall:.1f} | {cpu:.1f} | {100 * err:.2f}% | — | — |")
        print(rows[-1], flush=True)
    now = datetime.datetime.now(datetime.UTC)
    head = [f"Command: `python benchmarks/bench_clusters.py --title \"{args.title}\"` (written "
            f"{now:%Y-%m-%d %H:%M} UTC; load average {os.getloadavg()[0]:.1f} at the end). CPU is the "
            "process's; the ratio is meshlap's CPU over robust-laplacian's build and eigsh on the"
            " same cloud.",
            ""]
    if not args.no_write:
        write_section(args.title, head + rows)


if __name__ == "__main__":
    main()
