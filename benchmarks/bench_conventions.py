"""The peers' eigen-idioms on meshlap's pair against ``meshlap.spectral.eigs`` (issue 36).

On a unit sphere (``meshlap.shapes.sphere(n, seed=0)``) the default operator is built and its
pencil assembled once (not timed); then, each timed alone: ``spectral.eigs(op, k,
elements="linear")`` (the pair's own pencil);
robust-laplacian's and LaPy's idiom ``eigsh(L, k, M, sigma=-0.01)`` on
``L, M = meshlap.mesh_laplacian(V, F)`` (L = -op.S); and scipy's ``lobpcg`` on the pair,
preconditioned by a sparse LU of L + 0.01 M, with a block of 16 (l ≤ 3 on the sphere); and
``spectral.eigs(op, k)`` itself, which solves quadratic elements on the same triangles.
Every method's first 9 nonzero eigenvalues are checked against l(l+1).

    python benchmarks/bench_conventions.py            # n = 8,000, k = 10; updates RESULTS.md
    python benchmarks/bench_conventions.py --n 2000 --no-write

Times are wall clock with the process's CPU time in parentheses, best of ``--repeat``.
"""

from __future__ import annotations

import argparse
import datetime
import os
import time

import numpy as np
from results_file import write_section
from scipy.sparse.linalg import LinearOperator, eigsh, lobpcg, splu

import meshlap

EXACT = np.array([2.0] * 3 + [6.0] * 5 + [12.0])


def timed(fn, repeat):
    best = None
    for _ in range(repeat):
        w, c = time.perf_counter(), time.process_time()
        out = fn()
        t = (time.perf_counter() - w, time.process_time() - c)
        best = t if best is None or t[0] < best[0] else best
    return out, best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=8000)
    ap.add_argument("--k", type=int, default=10)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--no-write", action="store_true")
    args = ap.parse_args()
    V, F = meshlap.shapes.sphere(args.n, seed=0)
    op = meshlap.laplacian(V, F)
    L, M = meshlap.mesh_laplacian(V, F)
    op.assemble()

    def scipy_lobpcg():
        lu = splu((L + 0.01 * M).tocsc())
        pre = LinearOperator(L.shape, matvec=lu.solve, matmat=lu.solve, dtype=np.float64)
        X = np.random.default_rng(0).normal(size=(args.n, max(16, args.k)))
        return lobpcg(L, X, B=M, M=pre, largest=False, tol=1e-6, maxiter=200)[0][:args.k]

    runs = {
        'meshlap.spectral.eigs(op, k, elements="linear")':
            lambda: meshlap.spectral.eigs(op, args.k, elements="linear")[0],
        "eigsh(L, k, M, sigma=-0.01) on mesh_laplacian's pair": lambda: eigsh(L.tocsc(), args.k, M.tocsc(),
                                                                              sigma=-0.01)[0],
        "lobpcg(L, X, B=M, M=splu(L + 0.01 M)) on the pair": scipy_lobpcg,
        "meshlap.spectral.eigs(op, k): quadratic elements": lambda: meshlap.spectral.eigs(op, args.k)[0],
    }
    rows, base = [], None
    for name, fn in runs.items():
        lam, (wall, cpu) = timed(fn, args.repeat)
        err = np.abs(np.sort(lam)[1:10] / EXACT - 1).max()
        base = base or (wall, cpu)
        rows.append(f"| {name} | {wall:.2f} s ({cpu:.2f} s) | {wall / base[0]:.2f}× ({cpu / base[1]:.2f}×) "
                    f"| {err:.3%} |")
        print(rows[-1], flush=True)
    lines = [f"`python benchmarks/bench_conventions.py --n {args.n} --k {args.k} --repeat {args.repeat}`, "
             f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, {os.cpu_count()} cores "
             f"(shared); unit sphere of {args.n:,} vertices, {args.k} eigenpairs, the default operator "
             f"({op.quadrature} pencil, nnz(S) = {op.S.nnz:,}), its pencil assembled before the timings.", "",
             "| method | wall (CPU) | against the first row | eigenvalues 1-9 vs l(l+1) |",
             "|---|---|---|---|", *rows]
    if not args.no_write:
        write_section("bench_conventions.py", lines)


if __name__ == "__main__":
    main()
