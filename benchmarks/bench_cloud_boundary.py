"""A point cloud's boundary against its mesh's: which points it marks, and the length it gives them.

    python benchmarks/bench_cloud_boundary.py              # the corpus's surfaces; RESULTS.md
    python benchmarks/bench_cloud_boundary.py --only beetle-igl,lilium --no-write

The vertices of each surface mesh of the corpus (benchmarks/corpus.toml, as bench_real.py reads
it) as a point cloud: ``meshlap.geometry.point_masses`` marks its boundary (``info["boundary"]``,
what ``op.geometry.boundary`` holds) and gives each point its share of the boundary's length
(``info["boundary_share"]``, the weights of Neumann data: ``meshlap.solve.boundary_measure``).
Against the welded mesh's boundary (the vertices of edges that one triangle has): how many of
them the cloud marks, how many points it marks elsewhere, and the lengths. Where the mesh is
closed, every mark is elsewhere: most are the rims of faces that carry no points (a CAD part's
flat faces, a cylinder's caps), which the cloud reads as holes, so its operator has a boundary
there. Then random unit spheres, where nothing should be marked.

Last, boundary problems that use it, every pencil given the same data in one process: on an
annulus cloud (3,000 random points of r0 < r < 1 and both rims), φ = log r from its values on
the cloud's boundary points (Dirichlet), and from φ = 0 on those nearer r = 1 and ∂φ/∂n = -1/r0
on those nearer the hole (Neumann, weighted by the cloud's boundary lengths); on the unit
disc's vertices with 0.1 spacings of normal noise (a cloud the default reads as noisy), x from
its boundary values and from ∂x/∂n = x; on the unit disc's mesh (2,000 vertices), x² − y² from
its boundary values and x from ∂x/∂n = x. Pencils:
the default, ``operator="kernel"``, the paper's operator (``operator="paper"``), and the peers'
(robust-laplacian's point-cloud Laplacian on the cloud, with meshlap's boundary and lengths, as
no peer gives a cloud's boundary; libigl's cotangent Laplacian on the mesh). Largest error.
"""

from __future__ import annotations

import argparse
import datetime
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import robust_laplacian
import scipy.sparse as sp

sys.path.insert(0, str(Path(__file__).resolve().parent))
import real_corpus as rc  # noqa: E402
from bench_real import log  # noqa: E402
from results_file import publish  # noqa: E402

import meshlap  # noqa: E402
from meshlap import samples  # noqa: E402
from meshlap.baselines import SparseLaplacian, cotangent  # noqa: E402
from meshlap.geometry.pointcloud import point_masses  # noqa: E402
from meshlap.solve import boundary_measure, poisson  # noqa: E402


def mesh_boundary(V: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, float]:
    """The vertices on edges that one triangle has, and those edges' total length."""
    E = np.sort(np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]), axis=1)
    edges, counts = np.unique(E, axis=0, return_counts=True)
    once = edges[counts == 1]
    on = np.zeros(len(V), dtype=bool)
    on[once.ravel()] = True
    return on, float(np.linalg.norm(V[once[:, 0]] - V[once[:, 1]], axis=1).sum())


def cloud_boundary(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mass, info = point_masses(P)
    share = info.get("boundary_share")  # before the cloud had one, boundary_measure gave √mass
    return info["boundary"], np.where(info["boundary"], np.sqrt(mass), 0.0) if share is None else share


#: the pencils that solve the boundary problems, the default's first
OPERATORS = ("fem", "kernel", "paper")


def annulus(r0: float, rim: int) -> np.ndarray:
    """3,000 i.i.d. points of the annulus r0 < r < 1 (z = 0), 200 evenly on r = 1, ``rim`` on r0."""
    X = np.random.default_rng(0).uniform(-1.0, 1.0, (6000, 2))
    X = X[(np.hypot(*X.T) > r0) & (np.hypot(*X.T) < 1.0)][:3000]
    t, u = np.linspace(0, 2 * np.pi, 200, endpoint=False), np.linspace(0, 2 * np.pi, rim, endpoint=False)
    X = np.vstack([X, np.c_[np.cos(t), np.sin(t)], r0 * np.c_[np.cos(u), np.sin(u)]])
    return np.c_[X, np.zeros(len(X))]


def robust(P: np.ndarray, geometry: object) -> SparseLaplacian:
    """robust-laplacian's point-cloud pencil, given meshlap's boundary (none of its own)."""
    L, M = robust_laplacian.point_cloud_laplacian(P)
    m = M.diagonal()
    op = SparseLaplacian(-sp.diags(1 / m) @ L, m, "robust-laplacian", S=-L.tocsr())
    op.geometry = geometry
    return op


def boundary_problems() -> list[str]:
    rows = []
    with warnings.catch_warnings():  # the kernels' own warning under boundary data is the point
        warnings.simplefilter("ignore")
        for r0, rim in ((0.5, 100), (0.15, 30)):
            P = annulus(r0, rim)
            r = np.hypot(P[:, 0], P[:, 1])
            ops = {name: meshlap.point_cloud_laplacian(P, operator=name) for name in OPERATORS}
            ops["peer"] = robust(P, ops["fem"].geometry)
            err = {}
            for name, op in ops.items():
                edge = np.flatnonzero(op.geometry.boundary)
                outer, hole = edge[r[edge] > (1 + r0) / 2], edge[r[edge] < (1 + r0) / 2]
                d = poisson(op, 0.0, dirichlet=(edge, np.log(r[edge])))
                n = poisson(op, 0.0, dirichlet=(outer, np.zeros(len(outer))),
                            neumann=(hole, np.full(len(hole), -1 / r0)))
                err[name] = (np.abs(d - np.log(r)).max(), np.abs(n - np.log(r)).max())
            rows.append((f"annulus cloud, hole of radius {r0:g}, {len(P):,} points", "robust-laplacian", err))
        V, F = meshlap.shapes.disc(2000)
        x, y = V[:, 0], V[:, 1]
        # the disc's vertices with 0.1 spacings of normal noise: a cloud the default reads as noisy
        P = V.copy()
        P[:, 2] += 0.1 * 2 * np.sqrt(np.pi / len(V)) * np.random.default_rng(0).normal(size=len(V))
        ops = {name: meshlap.point_cloud_laplacian(P, operator=name) for name in OPERATORS}
        ops["peer"] = robust(P, ops["fem"].geometry)
        err = {}
        for name, op in ops.items():
            rim = np.flatnonzero(op.geometry.boundary)
            d = poisson(op, 0.0, dirichlet=(rim, x[rim]))
            n = poisson(op, 0.0, neumann=(rim, x[rim]))
            err[name] = (np.abs(d - x).max(), np.abs(n - x).max())
        default = meshlap.point_cloud_laplacian(P).decision.operator
        rows.append((f"unit disc cloud, 0.1 spacings of noise, {len(P):,} points (default: {default})",
                     "robust-laplacian", err))
        edge = np.flatnonzero(boundary_measure(meshlap.geometry.surface(V, F)))
        ops = {name: meshlap.laplacian(V, F, operator=name) for name in OPERATORS}
        ops["peer"] = cotangent(V, F)
        ops["peer"].geometry = ops["fem"].geometry  # its Neumann weights: the mesh's boundary edges
        err = {}
        for name, op in ops.items():
            d = poisson(op, 0.0, dirichlet=(edge, (x**2 - y**2)[edge]))
            n = poisson(op, 0.0, neumann=(edge, x[edge]))
            err[name] = (np.abs(d - (x**2 - y**2)).max(), np.abs(n - x).max())
        rows.append((f"unit disc mesh, {len(V):,} vertices", "libigl COT", err))
    lines = ["", "Boundary problems (largest error, Dirichlet / Neumann):", "",
             "| input | FEM (the default, but where named) | operator=\"kernel\" | the paper's | peer |",
             "|---|---|---|---|---|"]
    for case, peer, err in rows:
        cells = [f"{err[k][0]:.2g} / {err[k][1]:.2g}" for k in (*OPERATORS, "peer")]
        lines.append(f"| {case} | " + " | ".join(cells[:-1]) + f" | {peer}: {cells[-1]} |")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", default="", help="comma-separated corpus names")
    ap.add_argument("--corpus", default=None)
    ap.add_argument("--spheres", default="16000,1000000", help="sizes of the random spheres, comma-separated")
    ap.add_argument("--no-write", action="store_true", help="print, do not write RESULTS.md")
    args = ap.parse_args()
    folder = rc.corpus_dir(args.corpus)
    only = {s for s in args.only.split(",") if s}
    rows: list[dict] = []
    start = time.time()
    for entry, mesh in rc.surfaces(folder, only):
        on, length = mesh_boundary(mesh.Vw, mesh.Cw)
        marked, share = cloud_boundary(mesh.Vw)
        rows.append({"name": entry["name"], "n": len(mesh.Vw), "open": bool(on.any()), "B": int(on.sum()),
                     "hit": int((marked & on).sum()), "elsewhere": int((marked & ~on).sum()),
                     "length": length, "share": float(share.sum()), "share_on": float(share[on].sum())})
        x = rows[-1]
        log(f"{x['name']}: {x['hit']} of {x['B']} marked, {x['elsewhere']} elsewhere; length "
            f"{x['share']:.4g} for {x['length']:.4g} ({time.time() - start:.0f} s)")
    if not rows:
        raise SystemExit(f"no corpus mesh found in {folder} (benchmarks/build_corpus.py makes them)")
    spheres = []
    for n in (int(x) for x in args.spheres.split(",") if x):
        marked, share = cloud_boundary(samples.sphere_points(n, "random", seed=0))
        spheres.append(f"{n:,} random points of the unit sphere: {int(marked.sum())} marked, "
                       f"length {share.sum():.3g}")
    opened = [x for x in rows if x["open"]]
    closed = [x for x in rows if not x["open"]]
    total = {key: sum(x[key] for x in opened) for key in ("B", "hit", "elsewhere")}
    lines = [f"`python benchmarks/bench_cloud_boundary.py` on {datetime.date.today()} "
             f"({time.time() - start:.0f} s): the {len(rows)} surface meshes' vertices as clouds.", "",
             f"- {len(opened)} open meshes: the cloud marks {total['hit']:,} of their {total['B']:,} "
             f"boundary vertices, and {total['elsewhere']:,} points elsewhere; the length it gives the "
             f"points on the mesh's boundary over that boundary's length: median "
             f"{np.median([x['share_on'] / x['length'] for x in opened]):.3g}, "
             f"{sum(x['share_on'] >= 0.9 * x['length'] for x in opened)} meshes above 0.9;",
             f"- {len(closed)} closed meshes: {sum(x['elsewhere'] for x in closed):,} points marked, "
             f"{sum(x['elsewhere'] > 0 for x in closed)} meshes with any;"]
    lines += [f"- {s};" for s in spheres[:-1]] + [f"- {spheres[-1]}."]
    lines += ["", "| cloud | n | boundary vertices | marked there | marked elsewhere | "
              "mesh boundary length | cloud's length | of it on the mesh's boundary |",
              "|---|---|---|---|---|---|---|---|"]
    for x in opened + sorted(closed, key=lambda x: -x["elsewhere"])[:8]:
        lines.append(f"| {x['name']} | {x['n']:,} | {x['B']:,} | {x['hit']:,} | {x['elsewhere']:,} | "
                     f"{x['length']:.4g} | {x['share']:.4g} | {x['share_on']:.4g} |")
    lines += ["", "The rows: every open mesh, then the eight closed ones with the most points marked."]
    lines += boundary_problems()
    publish(lines, args.no_write)


if __name__ == "__main__":
    main()
