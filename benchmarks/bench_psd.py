"""The semidefiniteness check against LAPACK near the sampling limit (issue 19, branch i19p).

For 2,000-vertex random sphere, plane and torus, spot and a 12³ tetrahedral cube, at
h = f · ē² for f from 0.3 to 1: the smallest eigenvalue of (−S, M) by LAPACK (dense), and
``meshlap.corrections.psd.smallest_eigenvalue`` at the stopping tolerance before issue 19
(1e-3), at its default and at a looser one: verdict, LOBPCG iterations, CPU seconds. A row is
wrong where the verdict differs from LAPACK's.

    python benchmarks/bench_psd.py             # the table (about 3 minutes on 2 cores)
    python benchmarks/bench_psd.py --tol 0.01  # another loose tolerance beside the default's
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import igl
import numpy as np
import scipy.linalg as sla

import meshlap
from meshlap import _lobpcg, shapes, tuned
from meshlap.corrections import psd

DATA = Path(__file__).resolve().parents[1] / "tests" / "data"
FRACTIONS = (0.3, 0.35, 0.4, 0.5, 0.6, 0.7, 1.0)


def inputs():
    yield "sphere", shapes.sphere(2000, kind="random", seed=1), 2
    yield "plane", shapes.plane(2000, seed=0), 2
    yield "torus", shapes.torus(2000, seed=0), 2
    yield "spot", igl.read_triangle_mesh(str(DATA / "spot.obj")), 2
    yield "cube 12³", meshlap.samples.cube_tetrahedra(12), 3


def dense_min(L, m):
    S = m[:, None] * L.toarray()
    return float(sla.eigh(-0.5 * (S + S.T), np.diag(m), eigvals_only=True, subset_by_index=[0, 0])[0])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tol", type=float, default=0.1, help="the loose tolerance beside the default's")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    iterations = []
    real = _lobpcg.lobpcg
    _lobpcg.lobpcg = lambda *a, **kw: _record(real, iterations, *a, **kw)
    wrong = dict.fromkeys((1e-3, tuned.PSD_STOP_TOL, args.tol), 0)
    print("| input | h / ē² | LAPACK λ_min / scale | " + " | ".join(f"tol {t:g}" for t in wrong) + " |")
    print("|---|---|---|" + "---|" * len(wrong))
    for name, (V, F), k in inputs():
        kw = {"k": 3} if k == 3 else {}
        geo = meshlap.geometry.from_mesh(V, F, **kw)
        for f in FRACTIONS:
            op = meshlap.laplacian(V, F, h=f * geo.spacing**2, check_psd=False, pointwise=False, **kw)
            L, m = op.L_sym, op.mass
            scale = float(np.max(-L.diagonal()))
            exact = dense_min(L, m) / scale
            cells = []
            for tol in wrong:
                iterations.clear()
                t = time.process_time()
                lam, _ = psd.smallest_eigenvalue(L, m, op.geometry.points, op.geometry.faces, tol=tol)
                cpu = time.process_time() - t
                fails = lam < -psd.PSD_RTOL * scale
                wrong[tol] += fails != (exact < -psd.PSD_RTOL)
                how = f"{iterations[0]} it" if iterations else "diagonal"
                cells.append(f"{'fails' if fails else 'passes'} {lam / scale:+.1e} ({how}, {cpu:.2f} s)")
            print(f"| {name} | {f:g} | {exact:+.1e} | " + " | ".join(cells) + " |", flush=True)
    print("verdicts unlike LAPACK's: " + ", ".join(f"tol {t:g}: {n}" for t, n in wrong.items()))


def _record(real, iterations, *a, **kw):  # LOBPCG, its iterations noted
    out = real(*a, **kw)
    iterations.append(out.iterations)
    return out


if __name__ == "__main__":
    main()
