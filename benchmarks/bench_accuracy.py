"""Issue 12's accuracy table: the default, the corrected kernel (``operator="kernel"``), the paper's
operator and cotangent, plus build and eigs times of the default against the paper's operator and
what the kernel's options cost, in the same run.

    python benchmarks/bench_accuracy.py             # writes the "Accuracy" section of RESULTS.md
    python benchmarks/bench_accuracy.py --no-write  # prints only
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
import warnings
from pathlib import Path

import igl
import numpy as np

import meshlap
from meshlap import baselines, shapes, spectral

sys.path.insert(0, str(Path(__file__).parent))
from results_file import write_section  # noqa: E402

DATA = Path(__file__).resolve().parent.parent / "tests" / "data"
DEGREES = np.repeat(np.arange(6), 2 * np.arange(6) + 1)
EXACT = DEGREES * (DEGREES + 1.0)
#: the table's meshlap columns: the default, the corrected kernel, the paper's operator
BUILDERS = ({}, {"operator": "kernel"}, {"correction": "none"})


def e2(a: np.ndarray, t: np.ndarray) -> float:
    return float(np.linalg.norm(a - t) / np.linalg.norm(t))


def timed(fn):
    t = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t


def sphere_rows(kind: str, n: int) -> tuple[list[str], dict[str, float]]:
    V, F = shapes.sphere(n, kind=kind, seed=0)
    U = V / np.linalg.norm(V, axis=1, keepdims=True)
    funcs = shapes.sphere_functions()
    out, times = {}, {}
    ops = {
        "default": lambda: meshlap.laplacian(V, F),
        "kernel": lambda: meshlap.laplacian(V, F, operator="kernel"),
        "paper": lambda: meshlap.laplacian(V, F, correction="none"),
        "cotangent": lambda: baselines.cotangent(V, F),
    }
    for name, build in ops.items():
        op, tb = timed(build)
        (lam, _), te = timed(lambda op=op: spectral.eigs(op, 36))
        eig = float(np.max(np.abs(lam[1:] - EXACT[1:]) / EXACT[1:]))
        errs = [e2(op @ funcs[f][0](U), funcs[f][1](U)) for f in ("x^2", "exp(x)")]
        out[name] = (eig, *errs)
        times[name] = (tb, te)
    rows = [f"| sphere {n:,} {kind}: 36 eigenvalues vs l(l+1), max rel. error | "
            + " | ".join(f"{out[m][0]:.2%}" for m in ops) + " |",
            f"| sphere {n:,} {kind}: E2 of L x² / L eˣ | "
            + " | ".join(f"{out[m][1]:.4f} / {out[m][2]:.4f}" for m in ops) + " |"]
    return rows, times


def real_row(name: str) -> str:
    V, F = igl.read_triangle_mesh(str(DATA / f"{name}.obj"))
    used = np.unique(F)
    remap = np.full(len(V), -1)
    remap[used] = np.arange(len(used))
    V, F = V[used], remap[F]
    V = V / math.sqrt(igl.doublearea(V, F).sum() / 2)
    ref, _ = spectral.eigs(baselines.cotangent(V, F), 12)
    cells = []
    for kw in BUILDERS:
        lam, _ = spectral.eigs(meshlap.laplacian(V, F, **kw), 12)
        cells.append(f"{np.max(np.abs(lam[1:] - ref[1:]) / ref[1:]):.1%}")
    return (f"| {name}: first 12 eigenvalues, max rel. difference from cotangent on the same mesh | "
            + " | ".join(cells) + " | – |")


def plane_row(n: int) -> str:
    V, F = shapes.plane(n, seed=0)
    funcs = shapes.plane_functions()
    cells = []
    for kw in BUILDERS:
        op = meshlap.laplacian(V, F, **kw)
        cells.append(" / ".join(f"{e2(op @ f(V), lap(V)):.4f}" for f, lap in funcs.values()))
    cot = baselines.cotangent(V, F)
    cells.append(" / ".join(f"{e2(cot @ f(V), lap(V)):.4f}" for f, lap in funcs.values()))
    return f"| plane {n:,} random: E2 of L x² / L e^(x+y), all vertices | " + " | ".join(cells) + " |"


def noisy_row(n: int) -> str:
    V, F = shapes.sphere(n, kind="noisy", seed=0)
    U = V / np.linalg.norm(V, axis=1, keepdims=True)
    cells = []
    for build in (*(lambda kw=kw: meshlap.laplacian(V, F, **kw) for kw in BUILDERS),
                  lambda: baselines.cotangent(V, F)):
        op = build()
        funcs = shapes.sphere_functions().values()
        cells.append(" / ".join(f"{e2(op @ f(U), lap(U)):.4f}" for f, lap in funcs))
    return f"| noisy sphere {n:,}: E2 of L x / L x² / L eˣ | " + " | ".join(cells) + " |"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-write", action="store_true", help="print only")
    args = ap.parse_args()
    warnings.simplefilter("ignore", RuntimeWarning)
    load = os.getloadavg()
    # compile or load every builder's kernels first, so that no build below times a compilation
    small = shapes.sphere(500, seed=0)
    for kw in BUILDERS:
        spectral.eigs(meshlap.laplacian(*small, **kw), 4)
    stamp = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    lines = [f"Command: `python benchmarks/bench_accuracy.py` (issue 12; {stamp}). "
             f"Load average at the start: {load[0]:.2f}, {load[1]:.2f}, {load[2]:.2f} (2 cores shared with "
             "other jobs). default: `meshlap.laplacian(V, F)` (FEM on the intrinsic Delaunay "
             "triangulation; its `eigs` solve quadratic elements on the triangles, `op.elements`; "
             "`op @ f` the fitted point-wise rows); kernel: `operator=\"kernel\"`, the corrected heat "
             "kernel. On the real meshes the reference is the cotangent Laplacian of the same mesh, which "
             "the quadratic elements are more accurate than (bench_spectra.py and bench_real.py compare "
             "with refined meshes).", "",
             "| case | default | kernel | paper's operator (`correction=\"none\"`) | cotangent |",
             "|---|---|---|---|---|"]
    times = {}
    for kind in ("uniform", "random"):
        rows, t = sphere_rows(kind, 16000)
        lines += rows
        times[kind] = t
        print("\n".join(rows), flush=True)
    for row in (noisy_row(8000), plane_row(16000),
                *(real_row(m) for m in ("spot", "fandisk", "stanford-bunny"))):
        lines.append(row)
        print(row, flush=True)
    lines += ["", "Construction and `spectral.eigs(op, 36)` (tol 1e-8; it builds the pencil on first use) on "
              "the 16,000-vertex spheres, seconds, same run:", "",
              "| sphere | default build / eigs | paper build / eigs | ratio (build + eigs) |",
              "|---|---|---|---|"]
    for kind, t in times.items():
        d, p = t["default"], t["paper"]
        lines.append(f"| {kind} | {d[0]:.1f} / {d[1]:.1f} | {p[0]:.1f} / {p[1]:.1f} | "
                     f"{(d[0] + d[1]) / (p[0] + p[1]):.2f} |")
    V, F = shapes.sphere(16000, seed=0)
    lines += ["", "What each builder and option of the kernel costs: build of the 16,000-vertex uniform "
              "sphere with its pencil and point-wise rows (median of 3), and the bytes it holds:", "",
              "| builder, options | build s | MiB |", "|---|---|---|"]
    for label, kw in (("paper (`correction=\"none\"`)", {"correction": "none"}), ("default", {}),
                      ("kernel (`operator=\"kernel\"`)", {"operator": "kernel"}),
                      ("kernel, `pointwise=False`", {"pointwise": False}),
                      ("kernel, `arc_distance=False`", {"arc_distance": False}),
                      ("kernel, `check_psd=False`", {"check_psd": False})):
        # the build: construction, the pencil and the rows, each made on first use
        runs = [timed(lambda kw=kw: meshlap.laplacian(V, F, **kw).assemble().fit_rows()) for _ in range(3)]
        build = sorted(t for _, t in runs)[1]
        lines.append(f"| {label} | {build:.2f} | {runs[0][0].nbytes / 2**20:.0f} |")
    print("\n".join(lines[-13:]))
    if not args.no_write:
        write_section("Accuracy", lines)


if __name__ == "__main__":
    main()
