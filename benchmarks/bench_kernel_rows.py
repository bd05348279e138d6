"""The default's kernel rows and the moment scale's product, before and after issue 19's
branch i19k, alternated in one process (CPU seconds, best of ``--repeat``).

    python benchmarks/bench_kernel_rows.py                     # 16k random sphere, default h
    python benchmarks/bench_kernel_rows.py --n 100000 --h-edges 1

Before: the per-point rows compiled with numba's default error model (a zero-divisor check
per division, which kept the weights loop scalar), the product L @ (|x|², x) by scipy after
the fill. After: the rows as the package compiles them (numpy's error model) with the
product made while each row is filled (``assemble(..., times=...)``). Both give the same
rows and product to the bit, which the script checks.
"""

from __future__ import annotations

import argparse
import os
import time

import igl
import numba
import numpy as np

import meshlap
from meshlap import assembly, pipeline
from meshlap import widths as widths_mod
from meshlap.assembly import variable
from meshlap.corrections.moments import moment_block
from meshlap.operator import as_geometry


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=16000)
    ap.add_argument("--h-edges", type=float, default=None, help="h = this times ē² (default: the default's)")
    ap.add_argument("--repeat", type=int, default=9)
    args = ap.parse_args()
    V, F = meshlap.shapes.sphere(args.n, kind="random", seed=0)
    geo = as_geometry(V, F, None)
    h = None if args.h_edges is None else args.h_edges * float(igl.edge_lengths(V, F).mean()) ** 2
    opts = pipeline.Options.resolve(geo, h)
    widths = widths_mod.choose(geo, h, plain=False, curvature_limit=opts.curvature_limit)
    kern = assembly.Kernel(geo.dim, dog=True, normals=geo.normals(), tol=opts.tol)
    X = moment_block(geo.points)
    after_rows = variable._var_rows
    before_rows = numba.njit(nogil=True)(after_rows.py_func)  # numba's default error model

    def before():
        variable._var_rows = before_rows
        L = assembly.assemble(geo.points, geo.mass, widths, kern)
        return L, L @ X

    def after():
        variable._var_rows = after_rows
        return assembly.assemble(geo.points, geo.mass, widths, kern, times=X)

    best = {"before": np.inf, "after": np.inf}
    same = True
    for i in range(args.repeat + 1):  # the first round compiles and is not counted
        got = {}
        for name, fn in (("before", before), ("after", after)):
            c = time.process_time()
            got[name] = fn()
            if i:
                best[name] = min(best[name], time.process_time() - c)
        (La, Ya), (Lb, Yb) = got["before"], got["after"]
        same &= bool(np.array_equal(La.data, Lb.data) and np.array_equal(La.indices, Lb.indices)
                     and np.array_equal(Ya, Yb))
        del got, La, Ya, Lb, Yb
    variable._var_rows = after_rows
    nnz = assembly.assemble(geo.points, geo.mass, widths, kern).nnz
    print(f"random sphere {args.n:,}, h = {widths.h:.4g}, {nnz:,} "
          f"entries; kernel rows + moment product, CPU best of {args.repeat}: before {best['before']:.3f} s, "
          f"after {best['after']:.3f} s ({best['after'] / best['before']:.2f}x); bit-identical: {same}; "
          f"load {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
