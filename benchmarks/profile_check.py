"""Where the semidefiniteness check's time goes (issue 19, branch i19c).

Builds the corrected kernel on a random n-vertex sphere at h = f · ē² with ``check_psd=False``
(the Richardson rows, unchecked), then runs the check on its rows under cProfile: its CPU and
wall seconds, LOBPCG's iterations and error ratios, the verdict, and the split among the
cotangent factor, its solves, the block products and the rest.

    python benchmarks/profile_check.py --n 100000 --h-edges 1
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time
import warnings

import meshlap
from meshlap import _lobpcg
from meshlap.corrections import psd

PARTS = {"cotangent factor": "splu", "factor solves": "precond", "block products": "apply_block"}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100000)
    ap.add_argument("--h-edges", type=float, default=1.0)
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    V, F = meshlap.shapes.sphere(args.n, kind="random", seed=0)
    h = args.h_edges * meshlap.geometry.from_mesh(V, F).spacing ** 2
    op = meshlap.laplacian(V, F, h=h, check_psd=False, pointwise=False)
    L = op.L_sym / op.moment_scale  # the rows the build checks, before the moment scale
    ratios = []
    real = _lobpcg.lobpcg
    _lobpcg.lobpcg = lambda *a, **kw: real(*a, **kw, report=lambda it, r: ratios.append(r))
    prof = cProfile.Profile()
    t, c = time.perf_counter(), time.process_time()
    prof.enable()
    lam, scale = psd.smallest_eigenvalue(L, op.mass, op.geometry.points, op.geometry.faces)
    prof.disable()
    wall, cpu = time.perf_counter() - t, time.process_time() - c
    verdict = "fails" if lam < -psd.PSD_RTOL * scale else "passes"
    print(f"{args.n:,} vertices, h = {args.h_edges:g} ē²: {verdict} (λ_min / scale {lam / scale:+.1e}), "
          f"{len(ratios) - 1} iterations, {cpu:.2f} s CPU, {wall:.2f} s wall; error ratios "
          + " ".join(f"{r:.3g}" for r in ratios))
    stats = pstats.Stats(prof).stats
    split = {}
    for part, name in PARTS.items():
        split[part] = sum(s[3] for (_, _, fn), s in stats.items() if fn == name)
    split["factor solves"] -= split["cotangent factor"]  # the factor is made on the first use
    split["the rest"] = wall - sum(split.values())
    print("wall split: " + ", ".join(f"{k} {v:.2f} s ({v / wall:.0%})" for k, v in split.items()))


if __name__ == "__main__":
    main()
