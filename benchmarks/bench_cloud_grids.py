"""Point clouds sampled on grids: a curved surface's (u, v) grid and a plane's scan lines.

    python benchmarks/bench_cloud_grids.py            # writes its section of RESULTS.md
    python benchmarks/bench_cloud_grids.py --no-write    # prints it only

Each cloud is the vertices of a grid mesh: a torus's 80 x 40 (u, v) grid (and the same grid
jittered by a tenth of a cell), latitude-longitude spheres with their poles, and the unit
square sampled on lines 8-50x denser along than across. Largest relative error of eigenvalues
1-9 of meshlap.point_cloud_laplacian (the default), robust-laplacian's point_cloud_laplacian
and libigl's cotangent Laplacian on the grid's own triangles (linear FEM on the mesh the points
came from: what a cloud method can at best recover), all in this process, against the exact
spectrum (sphere, Neumann square) or, for the torus, meshlap's quadratic elements on the grid
mesh; the pencils' total mass against the grid mesh's area; CPU seconds of build + 10 pairs.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import igl
import numpy as np
import robust_laplacian
import scipy.sparse.linalg as sla

sys.path.insert(0, str(Path(__file__).resolve().parent))
from results_file import write_section  # noqa: E402

import meshlap  # noqa: E402
from meshlap import samples, spectral  # noqa: E402

K = 10


def _quads(rows: int, cols: int, wrap_u: bool, wrap_v: bool) -> np.ndarray:
    """Two triangles per cell of a rows x cols vertex grid (index r * cols + c)."""
    r, c = np.meshgrid(np.arange(rows if wrap_u else rows - 1), np.arange(cols if wrap_v else cols - 1),
                       indexing="ij")
    a, b = r * cols + c, (r + 1) % rows * cols + c
    d, e = r * cols + (c + 1) % cols, (r + 1) % rows * cols + (c + 1) % cols
    a, b, d, e = (x.ravel() for x in (a, b, d, e))
    return np.vstack([np.column_stack([a, b, e]), np.column_stack([a, e, d])])


def torus(nu: int, nv: int, jitter: float) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(1)
    u = (np.arange(nu)[:, None] + jitter * rng.uniform(-1, 1, (nu, nv))) * 2 * np.pi / nu
    v = (np.arange(nv)[None, :] + jitter * rng.uniform(-1, 1, (nu, nv))) * 2 * np.pi / nv
    ring = 1 + 0.4 * np.cos(v)
    P = np.column_stack([(ring * np.cos(u)).ravel(), (ring * np.sin(u)).ravel(), (0.4 * np.sin(v)).ravel()])
    return P, _quads(nu, nv, True, True)


def scan_lines(lines: int, per: int) -> tuple[np.ndarray, np.ndarray]:
    X, Y = np.meshgrid(np.linspace(0, 1, per), np.linspace(0, 1, lines))
    return np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)]), _quads(lines, per, False, False)


def cases():
    sphere = np.array([j * (j + 1) for j in range(5) for _ in range(2 * j + 1)], float)[:K]
    square = np.sort([np.pi**2 * (a * a + b * b) for a in range(8) for b in range(8)])[:K]
    yield "torus, 80 x 40 (u, v) grid", *torus(80, 40, 0.0), None
    yield "torus, the same jittered by 0.1 cell", *torus(80, 40, 0.1), None
    for rings, per in ((19, 40), (29, 60), (39, 80)):
        yield (f"sphere, {rings} rings x {per} and the poles", *samples.latitude_longitude_sphere(rings, per),
               sphere)
    for lines, per in ((11, 101), (6, 41), (5, 81), (3, 100)):
        yield f"unit square, {lines} lines x {per}", *scan_lines(lines, per), square


def _timed(fn):
    t = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = fn()
    return out, time.process_time() - t


def _pencil(L, M) -> np.ndarray:
    return np.sort(sla.eigsh(L, K, M, sigma=-1e-8, return_eigenvectors=False))


def _error(lam: np.ndarray, exact: np.ndarray) -> float:
    return float(np.abs(np.sort(lam)[1:K] / exact[1:K] - 1).max())


def row(name: str, P: np.ndarray, F: np.ndarray, exact: np.ndarray | None) -> str:
    area = igl.doublearea(P, F).sum() / 2
    if exact is None:
        exact = spectral.eigs(meshlap.laplacian(P, F), K)[0]
    cot = _pencil(-igl.cotmatrix(P, F), igl.massmatrix(P, F, igl.MASSMATRIX_TYPE_VORONOI))

    def ours():
        op = meshlap.point_cloud_laplacian(P)
        return spectral.eigs(op, K)[0], op.M.sum()

    def robust():
        L, M = robust_laplacian.point_cloud_laplacian(P)
        return _pencil(L, M), M.sum()

    try:
        (lam, m_ours), t_ours = _timed(ours)
        ours_cells = f"{_error(lam, exact):.2%} | {m_ours / area:.3f} | {t_ours:.2f}"
    except meshlap.MeshError as exc:  # an older version that could not build it
        ours_cells = f"raises ({str(exc)[:30]}) | - | -"
    try:
        (lr, m_rob), t_rob = _timed(robust)
        rob = f"{_error(lr, exact):.2%} | {m_rob / area:.3f} | {t_rob:.2f}"
    except RuntimeError as exc:  # geometry-central's assertion on a cloud it cannot triangulate
        rob = f"raises ({str(exc).split(' - ')[-1][:30]}) | - | -"
    return f"| {name} | {len(P)} | {ours_cells} | {rob} | {_error(cot, exact):.2%} |"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-write", action="store_true", help="print the table, do not write RESULTS.md")
    args = ap.parse_args()
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    lines = [f"`python benchmarks/bench_cloud_grids.py` ({when}). "
             "Error: largest relative error of λ1..λ9; mass: the pencil's total over the grid mesh's "
             "area; CPU: seconds of build + 10 pairs. COT: libigl's cotangent Laplacian on the grid's own "
             "triangles.",
             "", "| cloud | n | meshlap | mass | CPU | robust-laplacian | mass | CPU | COT on the grid |",
             "|---|---|---|---|---|---|---|---|---|"]
    _timed(lambda: spectral.eigs(meshlap.point_cloud_laplacian(scan_lines(6, 41)[0]), K))  # compiled first
    for case in cases():
        lines.append(row(*case))
        print(lines[-1], flush=True)
    if not args.no_write:
        write_section("bench_cloud_grids.py", lines)
    return 0


if __name__ == "__main__":
    sys.exit(main())
