"""The paper's operator (``correction="none"``) on a sphere, its cell grid against another copy of
``meshlap/assembly/grid.py`` (an earlier commit's), alternated in one process, CPU seconds,
best of ``--repeat``: the count pass, count and fill (:func:`meshlap.assembly.assemble`), the
whole build, and a matrix-free product with three columns; user CPU seconds in parentheses
(the system's share is page faults of the matrix's arrays, which scatter on a busy machine).
Checks that both give the same matrix and product to the bit.

    git show 35df36b:meshlap/assembly/grid.py > /tmp/grid_35df36b.py
    python benchmarks/bench_grid_rows.py --baseline /tmp/grid_35df36b.py            # 16k, h = 0.01
    python benchmarks/bench_grid_rows.py --baseline /tmp/grid_35df36b.py --n 100000 --h-edges 4
"""

from __future__ import annotations

import argparse
import gc
import hashlib
import os
import resource
import time

import igl
import numpy as np
from bench_kernel_rows import _load

import meshlap
from meshlap import assembly
from meshlap.operator import as_geometry
from meshlap.widths import Widths


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--baseline", required=True, help="a copy of meshlap/assembly/grid.py to compare with")
    ap.add_argument("--n", type=int, default=16000)
    ap.add_argument("--h-edges", type=float, default=None, help="h = this times ē² (default: h = 0.01)")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    V, F = meshlap.shapes.sphere(args.n, seed=0)  # bench_assembly.py's sphere16k
    h = 0.01 if args.h_edges is None else args.h_edges * float(igl.edge_lengths(V, F).mean()) ** 2
    geo = as_geometry(V, F, None)
    kern = assembly.Kernel(dim=2)
    P = assembly.pad3(geo.points)
    g = assembly.grid.build_grid(P, geo.mass, assembly.cutoff_radius(h, kern.tol))
    f = np.random.default_rng(0).standard_normal((args.n, 3))
    mods = {"before": _load(args.baseline), "after": assembly.grid}
    stages = {
        "count pass": lambda: assembly.grid.count_entries(P, g),
        "count + fill": lambda: assembly.assemble(geo.points, geo.mass, Widths(h, None, False), kern),
        "whole build": lambda: meshlap.laplacian(V, F, h=h, correction="none").assemble().L_sym,
        "matrix-free op @ f (3 columns)": lambda: free @ f,
    }
    free = meshlap.laplacian(V, F, h=h, correction="none", matrix_free=True)
    best = {(s, m, k): np.inf for s in stages for m in mods for k in ("cpu", "user")}
    same = True
    saved = assembly.grid
    try:
        for i in range(args.repeat + 1):  # the first round compiles and is not counted
            order = list(mods) if i % 2 else list(mods)[::-1]
            for stage, fn in stages.items():
                got = {}
                for name in order:
                    assembly.grid = mods[name]
                    c, u = time.process_time(), os.times().user
                    res = fn()
                    t, tu = time.process_time() - c, os.times().user - u
                    got[name] = _digest(res)  # not the matrix: one at a time in memory
                    del res
                    gc.collect()  # an operator's cycles would keep its matrices
                    if i:
                        best[stage, name, "cpu"] = min(best[stage, name, "cpu"], t)
                        best[stage, name, "user"] = min(best[stage, name, "user"], tu)
                same &= got["before"] == got["after"]
    finally:
        assembly.grid = saved
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
    print(f"random sphere {args.n:,}, h = {h:.4g}, CPU (user) best of {args.repeat}, same bits: {same}, "
          f"load {os.getloadavg()[0]:.1f}, peak RSS {peak:.1f} GiB")
    for stage in stages:
        b, a = best[stage, "before", "cpu"], best[stage, "after", "cpu"]
        bu, au = best[stage, "before", "user"], best[stage, "after", "user"]
        print(f"  {stage}: before {b:.3f} ({bu:.2f}) s, after {a:.3f} ({au:.2f}) s, {a / b:.2f}x")


def _digest(a) -> str:
    # the result's bits (a CSR matrix's data, indices and pointer, with their types)
    parts = [a.data, a.indices, a.indptr] if hasattr(a, "indptr") else [np.asarray(a)]
    h = hashlib.sha256()
    for p in parts:
        h.update(str(p.dtype).encode())
        h.update(np.ascontiguousarray(p))  # the buffer, not a copy
    return h.hexdigest()


if __name__ == "__main__":
    main()
