"""The real corpus's point clouds: what the stars' search bound and their assembly change (issue 35).

    python benchmarks/bench_cloud_stars.py                 # all surface rows; RESULTS.md
    python benchmarks/bench_cloud_stars.py --only beetle-igl,cow,inspired-mesh --no-write

The vertices of each surface mesh of the corpus (benchmarks/corpus.toml, as bench_real.py reads
it) as a point cloud; error = the largest relative error of eigenvalues 1-9 after the zero ones
against the mesh's refined-FEM reference (bench_real.py's cache). Columns, all in one process:

- ``default``: ``spectral.eigs(meshlap.point_cloud_laplacian(P), k)``, linear FEM on every
  point's local Delaunay star, each star triangle weighted a third;
- ``FEM, 64``: the same FEM on the stars searched with at most 64 neighbours instead of
  :data:`meshlap.geometry.pointcloud._MAX_NEIGHBORS` (256);
- ``tufted``: meshlap's stars given to robust-laplacian's ``mesh_laplacian`` (its tufted cover of
  the triangle soup, flipped to intrinsic Delaunay: Sharp & Crane 2020), L and M divided by 3;
- ``tufted, 64``: both;
- ``robust``: robust-laplacian's ``point_cloud_laplacian`` (its own stars, 30 neighbours).

Each variant's count of rows within 1.5x of robust-laplacian and ahead of it, and the geometric
mean of the ratio, show what a change would buy and what it would cost elsewhere.
"""

from __future__ import annotations

import argparse
import contextlib
import datetime
import sys
import time
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, str(Path(__file__).resolve().parent))
import real_corpus as rc  # noqa: E402
import robust_laplacian  # noqa: E402
from bench_real import REF_VERSION, RefCache, log, pct  # noqa: E402
from results_file import publish  # noqa: E402

import meshlap  # noqa: E402
from meshlap import spectral  # noqa: E402
from meshlap.geometry import pointcloud  # noqa: E402

COLUMNS = ("default", "FEM, 64", "tufted", "tufted, 64", "robust")
#: the smaller search bound measured beside the default's
CAP = 64


@contextlib.contextmanager
def bounded(cap: int) -> Iterator[None]:
    """meshlap's star search bounded at ``cap`` neighbours (its warnings silenced) inside the block."""
    kept = pointcloud._MAX_NEIGHBORS
    pointcloud._MAX_NEIGHBORS = cap
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            yield
    finally:
        pointcloud._MAX_NEIGHBORS = kept


def stars(P: np.ndarray, cap: int) -> np.ndarray:
    """meshlap's local Delaunay stars of P, searched with at most ``cap`` neighbours."""
    with bounded(cap):
        return pointcloud.point_masses(P)[1]["stars"]


def default(P: np.ndarray, k: int, cap: int = pointcloud._MAX_NEIGHBORS) -> np.ndarray:
    with bounded(cap):
        return spectral.eigs(meshlap.point_cloud_laplacian(P), k)[0]


def tufted(P: np.ndarray, k: int, cap: int) -> np.ndarray:
    L, M = robust_laplacian.mesh_laplacian(P, stars(P, cap))
    m = M.diagonal().copy()
    m[m <= 0] = m[m > 0].min() * 1e-3  # a point in no star (an outlier): a tiny mass, not a singular pencil
    return rc.pencil_eigs(L / 3, sp.diags(m / 3), k)


def robust(P: np.ndarray, k: int) -> np.ndarray:
    L, M = robust_laplacian.point_cloud_laplacian(P)
    return rc.pencil_eigs(L, M, k)


VARIANTS: dict[str, Callable[[np.ndarray, int], np.ndarray]] = {
    "default": default, "FEM, 64": lambda P, k: default(P, k, CAP), "tufted": lambda P, k: tufted(P, k, 256),
    "tufted, 64": lambda P, k: tufted(P, k, CAP), "robust": robust}


def summary(rows: list[dict], name: str) -> str:
    r = np.array([x[name] / x["robust"] for x in rows])
    return (f"| {name} | {int((r <= 1.5).sum())} of {len(r)} | {int((r <= 1.0).sum())} | "
            f"{float(np.exp(np.log(r).mean())):.3g} | {float(r.max()):.3g} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", default="", help="comma-separated corpus names")
    ap.add_argument("--corpus", default=None)
    ap.add_argument("--no-write", action="store_true", help="print, do not write RESULTS.md")
    args = ap.parse_args()
    folder = rc.corpus_dir(args.corpus)
    cache = RefCache(folder)
    only = {s for s in args.only.split(",") if s}
    rows: list[dict] = []
    start = time.time()
    for entry, mesh in rc.surfaces(folder, only):
        n_parts = rc.parts(mesh.Cw, len(mesh.Vw))
        k = 10 + n_parts
        R = np.array(cache.get(entry["sha256"], mesh, k)["ref"])
        row = {"name": entry["name"], "n": len(mesh.Vw)}
        for name, fn in VARIANTS.items():
            row[name] = rc.spectrum_error(np.sort(fn(mesh.Vw, k)), R, n_parts)
        rows.append(row)
        log(f"{row['name']}: " + ", ".join(f"{c} {pct(row[c])}" for c in COLUMNS)
            + f" ({time.time() - start:.0f} s)")
    if not rows:
        raise SystemExit(f"no corpus mesh found in {folder} (benchmarks/build_corpus.py makes them)")
    worst = sorted(rows, key=lambda x: -x["default"] / x["robust"])[:3]
    lines = [f"`python benchmarks/bench_cloud_stars.py` on {datetime.date.today()} "
             f"({time.time() - start:.0f} s, references v{REF_VERSION}): the {len(rows)} surface meshes' "
             "vertices as clouds; the ratio is each column's error over robust-laplacian's.", "",
             "| variant | within 1.5x | ahead | geometric mean ratio | worst ratio |",
             "|---|---|---|---|---|"]
    lines += [summary(rows, c) for c in COLUMNS[:-1]]
    lines += ["", "| cloud | n | " + " | ".join(COLUMNS) + " |", "|---|---|" + "---|" * len(COLUMNS)]
    moved = sorted(rows, key=lambda x: -max(x[c] / x["default"] for c in COLUMNS[1:4]))[:6]
    for x in worst + [x for x in moved if x not in worst]:
        lines.append(f"| {x['name']} | {x['n']:,} | " + " | ".join(pct(x[c]) for c in COLUMNS) + " |")
    lines += ["", "The rows: the default's three worst against robust-laplacian, then those a variant "
              "worsens most."]
    publish(lines, args.no_write)


if __name__ == "__main__":
    main()
