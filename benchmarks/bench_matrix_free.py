"""A matrix-free operator's ``op @ f``: the fitted rows it stores against the kernel it recomputes.

    python benchmarks/bench_matrix_free.py            # a 200,000-vertex sphere
    python benchmarks/bench_matrix_free.py --n 50000 --square 5000
    MESHLAP_CORPUS=/path/to/corpus python benchmarks/bench_matrix_free.py --real-only   # 6 min

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

``--real`` (or ``--real-only``) runs the real meshes of bench_real.py's corpus that have a
boundary (at most ``--max-n`` vertices): the spectrum error (bench_real.py's: λ1..λ9 against the
refined-FEM reference, cached) of the default, robust-laplacian's mesh Laplacian (the peer),
the matrix-free kernel pencil (``operator="kernel", matrix_free=True``) with the wall seconds of
its ``eigs`` and the solver whose pairs passed, the same without the mirror images, and the
paper's operator matrix-free.
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
    ap.add_argument("--real", action="store_true", help="also the corpus's meshes with a boundary")
    ap.add_argument("--real-only", action="store_true", help="only the corpus's meshes with a boundary")
    ap.add_argument("--max-n", type=int, default=12_000, help="largest corpus mesh (vertices)")
    args = ap.parse_args()
    if args.real_only:
        real(args.max_n)
        return
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

    if not args.real_only:
        square(args.square)
    if args.real or args.real_only:
        real(args.max_n)


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


def real(max_n: int) -> None:
    """The corpus's meshes with a boundary: the matrix-free kernel pencil against the default."""
    import sys
    import warnings
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import real_corpus as rc
    from bench_real import RefCache

    warnings.simplefilter("ignore")
    folder = rc.corpus_dir()
    cache = RefCache(folder)
    print("\nreal meshes with a boundary: largest relative error of λ1..λ9 against refined FEM")
    print("| mesh | n | band | default | robust-laplacian | kernel, matrix-free | its eigs (solver) "
          "| same, neumann=False | paper's, matrix-free |")
    print("|---|---|---|---|---|---|---|---|---|")
    for entry in rc.manifest():
        if entry["vertices"] > max_n or not (folder / entry["file"]).exists():
            continue
        mesh = rc.load(folder / entry["file"], entry["format"])
        V, F, kw = mesh.Vw, mesh.Cw, ({"k": 3} if mesh.tet else {})
        free = meshlap.laplacian(V, F, operator="kernel", matrix_free=True, **kw)
        if free.boundary_rows == 0:
            continue
        parts = rc.parts(F, len(V))
        ref = np.array(cache.get(entry["sha256"], mesh, 10 + parts)["ref"])

        def err(op, ref=ref, parts=parts, info=None) -> str:
            try:
                lam = meshlap.spectral.eigs(op, 10 + parts, info=info)[0]
                return f"{rc.spectrum_error(lam, ref, parts):.2%}"
            except meshlap.EigenError:  # refused: none of its solvers verified the pairs
                return "EigenError"

        peer = "—"
        if robust_laplacian is not None and not mesh.tet:
            L, M = robust_laplacian.mesh_laplacian(np.asarray(V, float), np.asarray(F))
            peer = f"{rc.spectrum_error(rc.pencil_eigs(L, M, 10 + parts), ref, parts):.2%}"
        bare = meshlap.laplacian(V, F, operator="kernel", matrix_free=True, neumann=False, **kw)
        paper = meshlap.laplacian(V, F, operator="paper", matrix_free=True, **kw)
        default = meshlap.laplacian(V, F, **kw)
        info: dict = {}
        free_err, wall, _ = timed(lambda op=free, info=info: err(op, info=info))
        solver = f"{wall:.1f} s, {info.get('method', '—')}"
        print(f"| {entry['name']} ({parts} parts) | {len(V):,} | {free.boundary_rows:,} | {err(default)} "
              f"| {peer} | {free_err} | {solver} | {err(bare)} | {err(paper)} |", flush=True)


if __name__ == "__main__":
    main()
