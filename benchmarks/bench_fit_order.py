"""The fitted rows' kernel (:func:`meshlap.corrections.highorder.fit_rows`) alone on k-d-tree
k-NN stencils of a random sphere, CPU µs a row, best of ``--repeat``, alternated in one
process: rows computed in the tree's order as ``choose_rows`` passes them (outputs at the
centres' CSR positions), against the points, rows and indices renumbered into the tree's
order (each row's neighbours and outputs together in memory; the renumbering's cost
included). Checks that both give the same values.

    python benchmarks/bench_fit_order.py --n 16000 --k 60 --degree 6
    flock /work/wt/big.lock python benchmarks/bench_fit_order.py --n 400000 --k 64 --degree 2
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.spatial import cKDTree

import meshlap
from meshlap.corrections.highorder import fit_rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=16000)
    ap.add_argument("--k", type=int, default=60, help="neighbours a row")
    ap.add_argument("--degree", type=int, default=6)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    n, K, D = args.n, args.k, args.degree
    P = np.ascontiguousarray(meshlap.shapes.sphere(n, kind="random", seed=0)[0])
    tree = cKDTree(P)
    dist, idx = tree.query(P, K)
    h = dist[:, -1] ** 2 / (4.0 if D == 2 and K > 40 else 1.0)  # the wide fit's width, else the compact's
    perm = tree.indices.astype(np.int64)
    place = np.empty(n, np.int64)
    place[perm] = np.arange(n)
    indptr = np.arange(n + 1, dtype=np.int64) * K
    fit_rows(P[:3000], indptr[:3001], cKDTree(P[:3000]).query(P[:3000], K)[1].ravel(), h[:3000], (D,))

    def tree_order():
        return fit_rows(P, indptr, idx.ravel(), h, (D,), order=np.argsort(place, kind="stable"))[0].matrix

    def renumbered():
        Pp = np.ascontiguousarray(P[perm])
        return fit_rows(Pp, indptr, place[idx[perm]].ravel(), h[perm], (D,))[0].matrix

    best = {"tree order": np.inf, "renumbered": np.inf}
    for _ in range(args.repeat):
        for name, fn in (("tree order", tree_order), ("renumbered", renumbered)):
            c = time.process_time()
            A = fn()
            best[name] = min(best[name], time.process_time() - c)
            if name == "tree order":
                ref = A[perm][:, perm].tocsr()
            else:
                ref.sort_indices()
                A.sort_indices()
                assert np.array_equal(ref.data, A.data) and np.array_equal(ref.indices, A.indices)
    print(f"n = {n:,}, K = {K}, degree {D}: " + ", ".join(
        f"{name} {t:.3f} s ({t / n * 1e6:.2f} µs a row)" for name, t in best.items()) + "; the same values")


if __name__ == "__main__":
    main()
