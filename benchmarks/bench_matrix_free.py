"""A matrix-free operator's ``op @ f``: the fitted rows it stores against the kernel it recomputes.

    python benchmarks/bench_matrix_free.py            # a 200,000-vertex sphere
    python benchmarks/bench_matrix_free.py --n 50000 --square 5000

``meshlap.laplacian(V, F, matrix_free=True)`` keeps no kernel; its ``op @ f`` applies the fitted
point-wise rows, which read the points alone and are stored. ``pointwise=False`` applies the
kernel's own rows instead, recomputed at every product (what ``matrix_free=True`` did before);
the paper's operator (``correction="none"``, its own default width) is the peer, matrix-free too.
For both this prints the construction, the first product (the rows' fit, for the default), the
best of ``--repeat`` products of three columns, the bytes held and the error of Δx = -2x on the
unit sphere (relative, 2-norm); then 10 eigenpairs of the default (the kernel recomputed, as for
both). CPU seconds of the process in parentheses.

Then a bounded domain: ``--square`` random points of the unit square, whose Neumann eigenvalues
are π²(a² + b²). A matrix-free pencil recomputes the kernel and adds the mirror images of the
boundary band, stored; this prints the largest relative error of λ1..λ9 and the time of the
build and 10 eigenpairs for the matrix-free default, the same without images
(``neumann=False``, what ``matrix_free=True`` built before), the stored default, the paper's
operator matrix-free and robust-laplacian's point-cloud Laplacian (the peer, same process).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import meshlap

try:
    import robust_laplacian
except ImportError:  # the bench extra
    robust_laplacian = None


def timed(fn):
    w, c = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w, time.process_time() - c


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--square", type=int, default=20_000, help="points of the bounded case")
    args = ap.parse_args()
    V, F = meshlap.shapes.sphere(args.n, seed=0)
    x = V[:, 0]
    f = np.ascontiguousarray(V)
    meshlap.laplacian(*meshlap.shapes.sphere(2000, seed=1), matrix_free=True) @ f[:2000]  # compile
    print(f"sphere, {args.n:,} vertices; seconds wall (CPU)")
    print("| op @ f applies | build | first op @ f | op @ f (3 columns) | held | Δx error |")
    print("|---|---|---|---|---|---|")
    for label, kw in (("fitted rows (default)", {}), ("kernel rows (pointwise=False)", {"pointwise": False}),
                      ("the paper's operator (correction='none')", {"correction": "none"})):
        op, bw, bc = timed(lambda kw=kw: meshlap.laplacian(V, F, matrix_free=True, **kw))
        _, fw, fc = timed(lambda op=op: op @ f)
        best = min((timed(lambda op=op: op @ f)[1:] for _ in range(args.repeat)), key=lambda t: t[0])
        err = np.linalg.norm(op @ x + 2 * x) / np.linalg.norm(2 * x)
        print(f"| {label} | {bw:.2f} ({bc:.2f}) | {fw:.2f} ({fc:.2f}) | {best[0]:.3f} ({best[1]:.3f}) | "
              f"{op.nbytes / 2**20:.0f} MiB | {err:.2g} |")
        if not kw:
            default = op
    (lam, _), ew, ec = timed(lambda: meshlap.spectral.eigs(default, 10))
    print(f"\n10 eigenpairs of the default's matrix-free pencil (the kernel rows' too): {ew:.1f} s "
          f"({ec:.1f}); λ1..λ3 {lam[1]:.4f} {lam[2]:.4f} {lam[3]:.4f} (exact 2)")

    square(args.square)


def square(n: int) -> None:
    """The unit square's Neumann spectrum from ``n`` random points, matrix-free and stored."""
    import scipy.sparse.linalg as sla

    P = np.random.default_rng(0).random((n, 2))
    exact = np.pi**2 * np.array([1, 1, 2, 4, 4, 5, 5, 8, 9])
    print(f"\nunit square, {n:,} random points: Neumann λ1..λ9 against π²(a² + b²); seconds wall (CPU)")
    print("| pencil | build + 10 eigenpairs | held | λ1 / π² | largest error λ1..λ9 |")
    print("|---|---|---|---|---|")
    runs = [("matrix-free default (mirror images)", {"matrix_free": True}),
            ("matrix-free, neumann=False", {"matrix_free": True, "neumann": False}),
            ("stored default", {}),
            ("the paper's operator, matrix-free", {"matrix_free": True, "correction": "none"})]
    for label, kw in runs:
        def run(kw=kw):
            op = meshlap.point_cloud_laplacian(P, **kw)
            return op, meshlap.spectral.eigs(op, 10)[0]
        (op, lam), w, c = timed(run)
        err = np.abs(lam[1:] / exact - 1).max()
        print(f"| {label} | {w:.1f} ({c:.1f}) | {op.nbytes / 2**20:.1f} MiB | {lam[1] / np.pi**2:.4f} | "
              f"{err:.2%} |")
    if robust_laplacian is not None:
        def peer():
            L, M = robust_laplacian.point_cloud_laplacian(np.column_stack([P, np.zeros(n)]))
            return sla.eigsh(L, 10, M, sigma=-1e-8)[0]
        lam, w, c = timed(peer)
        lam = np.sort(lam)
        print(f"| robust-laplacian point cloud (peer) | {w:.1f} ({c:.1f}) | — | {lam[1] / np.pi**2:.4f} | "
              f"{np.abs(lam[1:] / exact - 1).max():.2%} |")


if __name__ == "__main__":
    main()
