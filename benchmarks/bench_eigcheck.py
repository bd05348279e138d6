"""Verified eigenpairs against dense eigh on inputs with repeated and rescaled parts.

    python benchmarks/bench_eigcheck.py [--no-write]

Copies of one part give every eigenvalue twice, a part a tenth the size of another puts tight
clusters in the spectrum: where a solver skips a copy or stops inside a cluster, its pairs can
pass a residual check. For each input and operator, ``meshlap.spectral.eigs(op, k, method=m)``
for three methods and five k, against ``scipy.linalg.eigh`` on the same dense pencil; beside it
scipy's ``eigsh`` (shift-invert, the same k) on the same pencil, in the same process. A value is
wrong where it is more than 1e-7·λ_k from the dense one (``eigs``' tol is 1e-8); "refused":
``meshlap.EigenError``. Times are the sums of CPU seconds over the solves of a row.
"""

from __future__ import annotations

import argparse
import datetime
import itertools
import time
import warnings

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from results_file import write_section
from scipy.sparse.linalg import eigsh

import meshlap
from meshlap import shapes, spectral

METHODS, KS = ("auto", "lobpcg", "shift-invert"), (5, 8, 10, 12, 16)


def parts(V: np.ndarray, F: np.ndarray, scales: list[float], gap: float = 3.0):
    return (np.vstack([s * V + [gap * i, 0.0, 0.0] for i, s in enumerate(scales)]),
            np.vstack([F + i * len(V) for i in range(len(scales))]))


def cpu(fn):
    t = time.process_time()
    out = fn()
    return out, time.process_time() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=400, help="vertices per part")
    ap.add_argument("--no-write", action="store_true")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    S, SF = shapes.sphere(args.n, seed=0)
    T, TF = shapes.torus(args.n, seed=0)
    inputs = {"2 spheres": parts(S, SF, [1, 1]), "3 spheres": parts(S, SF, [1, 1, 1]),
              "sphere + 0.1 sphere": parts(S, SF, [1, 0.1]), "2 tori": parts(T, TF, [1, 1], gap=5.0)}
    rows = ["| input | operator | meshlap eigs: wrong, refused of 15 | CPU s | scipy eigsh: wrong of 5 "
            "| CPU s |",
            "|---|---|---|---|---|---|"]
    totals = np.zeros(3, dtype=int)
    operators = ["auto", "kernel", "paper", "galerkin"]
    for (name, (V, F)), operator in itertools.product(inputs.items(), operators):
        op = meshlap.laplacian(V, F, operator=operator)
        S_, m = -op.S.toarray(), op.mass
        ref = sla.eigh(0.5 * (S_ + S_.T), np.diag(m), eigvals_only=True, subset_by_index=[0, max(KS)])
        wrong = refused = 0
        t_ours = 0.0
        for method, k in itertools.product(METHODS, KS):
            try:
                (lam, _), t = cpu(lambda op=op, k=k, method=method:
                                  spectral.eigs(op, k, method=method, elements="linear"))
                wrong += int(np.abs(lam - ref[:k]).max() > 1e-7 * ref[k - 1])
            except meshlap.EigenError:
                t, refused = 0.0, refused + 1
            t_ours += t
        peer_wrong, t_peer = 0, 0.0
        A, M = sp.csc_matrix(-op.S), sp.diags(m).tocsc()
        for k in KS:
            lam, t = cpu(lambda A=A, M=M, k=k: np.sort(eigsh(A, k, M, sigma=-1e-8,
                                                                 return_eigenvectors=False)))
            peer_wrong += int(np.abs(lam - ref[:k]).max() > 1e-7 * ref[k - 1])
            t_peer += t
        totals += [wrong, refused, peer_wrong]
        rows.append(f"| {name} | {operator} | {wrong}, {refused} | {t_ours:.1f} | {peer_wrong} | "
                    f"{t_peer:.1f} |")
        print(rows[-1], flush=True)
    rows.append(f"| all {len(rows) - 2} | | {totals[0]}, {totals[1]} of {15 * (len(rows) - 2)} | | "
                f"{totals[2]} of {5 * (len(rows) - 2)} | |")
    print(rows[-1])
    now = datetime.datetime.now(datetime.UTC)
    head = [f"Command: `python benchmarks/bench_eigcheck.py` (written {now:%Y-%m-%d %H:%M} UTC; "
            f"{args.n} vertices a part).", ""]
    if not args.no_write:
        write_section("bench_eigcheck.py", head + rows)


if __name__ == "__main__":
    main()
