"""The corrected kernel's rows (``operator="kernel"``) and the moment scale's product, before and
after issue 19's branch i19k, alternated in one process (CPU seconds, best of ``--repeat``).

    python benchmarks/bench_kernel_rows.py                     # 16k random sphere, default h
    python benchmarks/bench_kernel_rows.py --n 100000 --h-edges 1
    git show c5b12b1:meshlap/assembly/variable.py > /tmp/variable_c5b12b1.py
    python benchmarks/bench_kernel_rows.py --baseline /tmp/variable_c5b12b1.py --threads 1

Before: the per-point rows compiled with numba's default error model (a zero-divisor check
per division, which kept the weights loop scalar), the product L @ (|x|², x) by scipy after
the fill. After: the rows as the package compiles them (numpy's error model) with the
product made while each row is filled (``assemble(..., times=...)``). Both give the same
rows and product to the bit, which the script checks. ``--baseline FILE``: before is instead
another copy of ``meshlap/assembly/variable.py`` (an earlier commit's), with the product made
during the fill as well; the count pass alone is timed too.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import sys
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
    ap.add_argument("--baseline", help="a copy of meshlap/assembly/variable.py to compare with")
    ap.add_argument("--threads", type=int, default=None, help="numba threads (default: all)")
    args = ap.parse_args()
    if args.threads:
        numba.set_num_threads(args.threads)
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

    if args.baseline:
        base = _load(args.baseline)
        before = _with_module(base, geo, widths, kern, X)
        after = _with_module(variable, geo, widths, kern, X)
        P, normals, hv = assembly.pad3(geo.points), assembly.pad3(kern.normals), widths.per_point(args.n)
        g = assembly.grid.build_grid(P, geo.mass, assembly.cutoff_radius(widths.largest, kern.tol))
        counts = {name: (lambda mod=mod: mod.count_entries(P, g, hv, kern.tol, normals))
                  for name, mod in (("before", base), ("after", variable))}
        fast = {"before": np.inf, "after": np.inf}
        for i in range(args.repeat + 1):
            for name, fn in counts.items():
                c = time.process_time()
                fn()
                if i:
                    fast[name] = min(fast[name], time.process_time() - c)
        print(f"count pass alone, CPU best of {args.repeat}: before {fast['before']:.3f} s, "
              f"after {fast['after']:.3f} s")

    best = {"before": np.inf, "after": np.inf}
    same = True
    for i in range(args.repeat + 1):  # the first round compiles and is not counted
        got = {}
        # the order alternates: the second build of a round runs while the first one's
        # matrix is held (measured at 100,000 vertices: its CPU time a third more)
        for name, fn in (("before", before), ("after", after))[::1 if i % 2 else -1]:
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
          f"threads {numba.get_num_threads()}; load {os.getloadavg()[0]:.1f}")


def _load(path: str):
    # another copy of the module, imported inside the package (its relative imports)
    spec = importlib.util.spec_from_file_location("meshlap.assembly._baseline", path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


def _with_module(mod, geo, widths, kern, X):
    # the default's kernel rows and product with assembly.variable set to mod for the call
    def run():
        saved, assembly.variable = assembly.variable, mod
        try:
            return assembly.assemble(geo.points, geo.mass, widths, kern, times=X)
        finally:
            assembly.variable = saved
    return run


if __name__ == "__main__":
    main()
