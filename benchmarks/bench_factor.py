"""The sparse factorizations behind shift-invert, the inertia count and the implicit solves:
QDLDL's LDLᵀ (meshlap's choice on surfaces and curves) against scipy's SuperLU (its choice on
volumes, and the one used before), with libigl's cotangent Laplacian + scipy's eigsh beside them,
all in one process.

    python benchmarks/bench_factor.py                 # RESULTS.md; the corpus's camelhead if present
    python benchmarks/bench_factor.py --quick --no-write
    python benchmarks/bench_factor.py --volumes carotid.vtk dataset.vtu   # more volumes, ordering table

Table 1, the factorizations themselves (meshlap._ldl): factor time, stored entries of the
factors (SuperLU: L + U; LDLᵀ: L twice plus D, the LU it stands for), one solve and a 64-column
block. Table 2, ``spectral.eigs(meshlap.laplacian(V, F), 10)`` end to end (build + 10 verified
pairs) with the default's factorizations and with the other kind (``meshlap._ldl.supernodal``
answering the other way: SuperLU on a surface, LDLᵀ on a volume), against COT + eigsh. Times
are process CPU seconds of one run (solves: the best of three). Table 3, a volume's implicit
heat step and Poisson solve by each factorization, beside scipy's spsolve of the same matrix.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import igl
import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import eigsh, spsolve

sys.path.insert(0, str(Path(__file__).resolve().parent))
import real_corpus as rc  # noqa: E402
from results_file import write_section  # noqa: E402

import meshlap  # noqa: E402
from meshlap import _ldl, heat, quadratic, samples, shapes, solve, spectral  # noqa: E402


def cpu(fn, repeat: int = 1):
    best = None
    for _ in range(repeat):
        t = time.process_time()
        out = fn()
        c = time.process_time() - t
        if best is None or c < best[0]:
            best = (c, out)
    return best


def inputs(quick: bool, corpus: Path | None) -> list[tuple[str, np.ndarray, np.ndarray, int]]:
    out = [(f"random sphere {n:,}", *shapes.sphere(n, kind="random", seed=0), 2) for n in
           ((4000,) if quick else (16000, 32000))]
    out += [(f"tetrahedral cube {n}³", *samples.cube_tetrahedra(n), 3) for n in
            ((20,) if quick else (20, 30))]
    if corpus is not None:
        for e in rc.manifest():
            if e["name"] == "camelhead" and (corpus / e["file"]).exists():
                m = rc.load(corpus / e["file"], e["format"])
                out.append(("camelhead (corpus)", m.Vw, m.Cw, 2))
    return out


def _chosen(A: sp.csc_matrix) -> _ldl._LU:
    return _ldl._LU(A, _ldl.volume_order(A))


def nd_row(name: str, op) -> dict:
    """A volume's factorization in minimum degree and in the ordering ``_ldl.factor`` chooses
    (the ordering table), with both orderings' counted work."""
    A = sp.csc_matrix(-0.5 * (op.S + op.S.T) + sp.diags(1e-3 * op.mass))
    b = np.random.default_rng(0).standard_normal((A.shape[0], 64))
    row = {"input": name, "pencil": "linear", "n": A.shape[0]}
    md, nd = _ldl.minimum_degree(A), _ldl.nested_dissection(A)
    row["work"] = (_ldl.factor_work(A, md), _ldl.factor_work(A, nd))
    for label, make in (("SuperLU", _ldl._LU), ("SuperLU chosen", _chosen)):
        t, f = cpu(lambda make=make: make(A))
        one, _ = cpu(lambda f=f: f.solve(b[:, 0]), 3)
        block, x = cpu(lambda f=f: f.solve(b), 3)
        residual = float(np.abs(A @ x - b).max() / np.abs(b).max())
        row[label] = (t, f._lu.L.nnz + f._lu.U.nnz, one, block, residual)
        del f
    return row


def factor_rows(name: str, op) -> list[dict]:
    rows = []
    pencils = [("linear", op.S, op.mass)]
    if op.dim == 2:
        fine = quadratic.fine_pencil(op)
        pencils.append(("quadratic", fine.S, np.asarray(fine.M.diagonal())))
    for kind, S, m in pencils:
        A = sp.csc_matrix(-0.5 * (S + S.T) + sp.diags(1e-3 * m + (m == 0)))
        b = np.random.default_rng(0).standard_normal((A.shape[0], 64))
        row = {"input": name, "pencil": kind, "n": A.shape[0]}
        makers = [("SuperLU", _ldl._LU), ("LDLᵀ", _ldl._LDL)]
        if op.dim == 3:  # a volume's: SuperLU in the ordering factor() chooses (choice timed too)
            makers.append(("SuperLU chosen", _chosen))
            orders = (_ldl.minimum_degree(A), _ldl.nested_dissection(A))
            row["work"] = tuple(_ldl.factor_work(A, p) for p in orders)
        for label, make in makers:
            t, f = cpu(lambda make=make, A=A: make(A))
            if label.startswith("SuperLU"):
                fill = f._lu.L.nnz + f._lu.U.nnz
            else:
                fill = 2 * f._factors[0].nnz + A.shape[0]
            one, _ = cpu(lambda f=f, b=b: f.solve(b[:, 0]), 3)
            block, x = cpu(lambda f=f, b=b: f.solve(b), 3)
            row[label] = (t, fill, one, block, float(np.abs(A @ x - b).max() / np.abs(b).max()))
        rows.append(row)
    return rows


def eigs_row(name: str, V: np.ndarray, F: np.ndarray, k: int, elements: str | None = None) -> dict:
    def ours():
        op = meshlap.laplacian(V, F, k=k) if k == 3 else meshlap.laplacian(V, F)
        return spectral.eigs(op, 10, **({} if elements is None else {"elements": elements}))[0]

    row = {"input": name if elements is None else f"{name}, elements={elements!r}", "n": len(V)}
    plain = _ldl.supernodal
    try:  # the other choice: SuperLU on a surface, LDLᵀ on a volume
        _ldl.supernodal = lambda op: k == 2
        row["other"], lam_other = cpu(ours)
    finally:
        _ldl.supernodal = plain
    row["default"], lam = cpu(ours)
    row["agree"] = float(np.abs(lam - lam_other).max() / lam.max())
    if k == 2:
        def cot():
            L = -igl.cotmatrix(V, F)
            M = igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI)
            return np.sort(eigsh(L, 10, M, sigma=-1e-8, return_eigenvectors=False))
        row["COT"], _ = cpu(cot)
    row["factored by"] = ("SuperLU", "LDLᵀ") if k == 3 else ("LDLᵀ", "SuperLU")
    return row


def solve_rows(name: str, V: np.ndarray, T: np.ndarray) -> list[dict]:
    """A volume's implicit heat step and Poisson solve (prepare + one solve) with its own
    factorization and with the other kind, beside scipy's spsolve of the same matrix."""
    op = meshlap.laplacian(V, T, k=3)
    m, S = op.mass, sp.csr_matrix(op.S)
    f = V[:, 0] ** 2
    b = m * (f - f @ m / m.sum())
    tau = 1e-3
    uses = {"heat step (τ = 10⁻³)": (lambda: heat.ImplicitHeat(op, tau)(f),
                                     lambda: spsolve(sp.csc_matrix(sp.diags(m) - tau * S), m * f)),
            "Poisson solve": (lambda: solve.PoissonSolver(op).solve(b),
                              lambda: spsolve(sp.csc_matrix(-S[1:, 1:]), b[1:]))}
    rows = []
    for use, (ours, peer) in uses.items():
        row = {"input": name, "use": use}
        plain = _ldl.supernodal
        try:
            _ldl.supernodal = lambda op: False
            row["LDLᵀ"], x_other = cpu(ours)
        finally:
            _ldl.supernodal = plain
        row["SuperLU"], x = cpu(ours)
        row["scipy"], _ = cpu(peer)
        row["agree"] = float(np.abs(x - x_other).max() / np.abs(x).max())
        rows.append(row)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a 4,000-vertex sphere and the 20³ cube only")
    ap.add_argument("--corpus", default=None,
                    help="corpus folder (default: $MESHLAP_CORPUS, benchmarks/corpus)")
    ap.add_argument("--no-write", action="store_true", help="print; leave RESULTS.md")
    ap.add_argument("--volumes", nargs="*", default=[], help="volume files (any meshlap reads): rows of "
                    "the ordering table")
    args = ap.parse_args()
    folder = rc.corpus_dir(args.corpus)
    warnings.simplefilter("ignore")
    spectral.eigs(meshlap.laplacian(*shapes.sphere(300, seed=0)), 4)  # compile first
    start = time.time()
    frows, erows, srows = [], [], []
    for name, V, F, k in inputs(args.quick, folder if folder.exists() else None):
        op = meshlap.laplacian(V, F, k=k) if k == 3 else meshlap.laplacian(V, F)
        frows += factor_rows(name, op)
        erows.append(eigs_row(name, V, F, k))
        if k == 2 and len(V) > 16500:  # beyond QUADRATIC_MAX_UNKNOWNS the default is linear: both
            erows.append(eigs_row(name, V, F, k, "quadratic"))
        if k == 3:
            srows += solve_rows(name, V, F)
            if not args.quick and len(V) == 29791:  # then larger cubes, in the ordering table only
                for m in (35, 40):
                    big = samples.cube_tetrahedra(m)
                    frows.append(nd_row(f"tetrahedral cube {m}³", meshlap.laplacian(*big, k=3)))
        print(f"{name}: done ({time.time() - start:.0f} s)", file=sys.stderr, flush=True)
    if folder.exists():  # the corpus's tetrahedral meshes, in the ordering table
        for e in rc.manifest():
            if "tet" in e["name"] and (folder / e["file"]).exists():
                m = rc.load(folder / e["file"], e["format"])
                if m.tet:
                    frows.append(nd_row(f"{e['name']} (corpus)", meshlap.laplacian(m.Vw, m.Cw)))
    for path in args.volumes:
        frows.append(nd_row(Path(path).name, meshlap.laplacian(path)))
        print(f"{path}: done ({time.time() - start:.0f} s)", file=sys.stderr, flush=True)
    lines = ["Factorizations of −S + 10⁻³M: CPU seconds, stored entries, one "
             "solve and a 64-column block (residual of the block, relative).", "",
             "| input | pencil | n | SuperLU factor s | entries | 1 solve ms | 64 solves ms | "
             "LDLᵀ factor s | entries | 1 solve ms | 64 solves ms | residual |", "|" + "---|" * 12]
    for r in [r for r in frows if "LDLᵀ" in r]:
        lu, ldl = r["SuperLU"], r["LDLᵀ"]
        lines.append(f"| {r['input']} | {r['pencil']} | {r['n']:,} | {lu[0]:.3f} | {lu[1] / 1e6:.2f} M | "
                     f"{1e3 * lu[2]:.1f} | {1e3 * lu[3]:.0f} | {ldl[0]:.3f} | {ldl[1] / 1e6:.2f} M | "
                     f"{1e3 * ldl[2]:.1f} | {1e3 * ldl[3]:.0f} | {max(lu[4], ldl[4]):.0e} |")
    nd = [r for r in frows if "work" in r]
    lines += ["", "A volume's SuperLU in the ordering `_ldl.factor` chooses (`_ldl.volume_order`: minimum "
              "degree or nested dissection, whichever `_ldl.factor_work` counts the fewer multiply-adds "
              "for; both orderings and both counts included in its time), beside minimum degree alone "
              "(SuperLU's own):", "",
              "| input | n | minimum degree: factor s | entries | work G | nested dissection: work G | "
              "chosen | factor s | entries | 1 solve ms | 64 solves ms | residual |", "|" + "---|" * 12]
    for r in nd:
        lu, dis = r["SuperLU"], r["SuperLU chosen"]
        wm, wn = r["work"]
        lines.append(f"| {r['input']} | {r['n']:,} | {lu[0]:.3f} | {lu[1] / 1e6:.2f} M | {wm / 1e9:.3g} | "
                     f"{wn / 1e9:.3g} | {'nested dissection' if wn < wm else 'minimum degree'} | "
                     f"{dis[0]:.3f} | "
                     f"{dis[1] / 1e6:.2f} M | {1e3 * dis[2]:.1f} | {1e3 * dis[3]:.0f} | {dis[4]:.0e} |")
    lines += ["", "`spectral.eigs(meshlap.laplacian(V, F), 10)`, build + 10 verified pairs (the default's "
              "elements: quadratic up to `QUADRATIC_MAX_UNKNOWNS`, about 16,500 vertices), CPU seconds: "
              "the default's factorizations, every one forced to the other kind, and libigl's "
              "cotangent + eigsh.",
              "",
              "| input | n | default: factored by | default s | other | other s | COT + eigsh s | "
              "default / COT | eigenvalues agree to |", "|" + "---|" * 9]
    for r in erows:
        cot = r.get("COT")
        versus = ("—", "—") if cot is None else (f"{cot:.2f}", f"{r['default'] / cot:.1f}×")
        lines.append(f"| {r['input']} | {r['n']:,} | {r['factored by'][0]} | {r['default']:.2f} | "
                     f"{r['factored by'][1]} | {r['other']:.2f} | {versus[0]} | {versus[1]} | "
                     f"{r['agree']:.0e} |")
    lines += ["", "A volume's `heat.ImplicitHeat(op, τ)` and `solve.PoissonSolver(op)`, prepared and applied "
              "once (op built before), CPU seconds: factored by SuperLU (the default on a volume) and by "
              "LDLᵀ, beside `scipy.sparse.linalg.spsolve` of the same matrix (M − τS; −S with one vertex "
              "fixed) with its default ordering and pivoting.", "",
              "| input | use | SuperLU s | LDLᵀ s | scipy spsolve s | the two agree to |", "|" + "---|" * 6]
    for r in srows:
        lines.append(f"| {r['input']} | {r['use']} | {r['SuperLU']:.2f} | {r['LDLᵀ']:.2f} | "
                     f"{r['scipy']:.2f} | {r['agree']:.0e} |")
    print("\n".join(lines))
    if not args.no_write and not args.quick:
        took = time.time() - start
        extra = "".join(f" {Path(v).name}" for v in args.volumes)
        write_section("bench_factor.py", [f"Command: `python benchmarks/bench_factor.py"
                                          f"{' --volumes' + extra if extra else ''}` ({took:.0f} s; "
                                          "camelhead and the tetrahedral meshes from $MESHLAP_CORPUS; "
                                          "--volumes: pyvista/vtk-data's Data/ files of those names, "
                                          "Data/fea/kiefer/dataset.vtu for dataset.vtu).", "", *lines])


if __name__ == "__main__":
    main()
