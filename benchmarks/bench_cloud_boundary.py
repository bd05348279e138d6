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
"""

from __future__ import annotations

import argparse
import datetime
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import real_corpus as rc  # noqa: E402
from bench_real import log  # noqa: E402
from results_file import write_section  # noqa: E402

from meshlap import samples  # noqa: E402
from meshlap.geometry.pointcloud import point_masses  # noqa: E402


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
    if args.no_write:
        print("\n".join(lines))
    else:
        write_section("bench_cloud_boundary.py", lines)


if __name__ == "__main__":
    main()
