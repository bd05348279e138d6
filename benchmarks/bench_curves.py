"""Eigenvalues on curves: the default and the named builders on the segments beside linear FEM.

    python benchmarks/bench_curves.py                   # 24 curves, writes its RESULTS.md section
    python benchmarks/bench_curves.py --quick --no-write  # n = 60 and 200 only, prints

Closed curves (a circle, an ellipse 2:1, a trefoil knot in R³) and an open arc, sampled at
60, 200 and 1,000 uniform or random parameters; the exact eigenvalues of a closed curve of
length ℓ are (2πm/ℓ)², of an open one (Neumann) (πm/ℓ)², ℓ from a fine sampling. Largest
relative error of eigenvalues 1-9 for the default (``meshlap.laplacian(V, E)``, what
``op.decision`` chose), the Galerkin pencil (``operator="galerkin"``), the vertex pencil
(``operator="kernel"``), the paper's operator (``operator="paper"``) and linear FEM on the
segments (``meshlap.baselines.cotangent(V, E)``, lumped mass).
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import eigsh

sys.path.insert(0, str(Path(__file__).resolve().parent))
from results_file import write_section  # noqa: E402

import meshlap  # noqa: E402
from meshlap import baselines, spectral  # noqa: E402

K = 10


def _shape(name: str, t: np.ndarray) -> np.ndarray:
    s = 2 * np.pi * t
    if name == "circle":
        return np.column_stack([np.cos(s), np.sin(s)])
    if name == "ellipse":
        return np.column_stack([2 * np.cos(s), np.sin(s)])
    if name == "trefoil":
        return np.column_stack([np.sin(s) + 2 * np.sin(2 * s), np.cos(s) - 2 * np.cos(2 * s), -np.sin(3 * s)])
    return np.column_stack([3 * t, 0.3 * np.sin(2 * t)])  # a gently bent open arc


def curve(name: str, kind: str, n: int):
    """(V, E, exact eigenvalues 0..K-1)."""
    rng = np.random.default_rng(0)
    closed = name != "open arc"
    if closed:
        t = np.sort(rng.uniform(0, 1, n)) if kind == "random" else np.arange(n) / n
        E = np.column_stack([np.arange(n), (np.arange(n) + 1) % n])
    else:
        t = np.sort(np.r_[0, 1, rng.uniform(0, 1, n - 2)]) if kind == "random" else np.linspace(0, 1, n)
        E = np.column_stack([np.arange(n - 1), np.arange(1, n)])
    length = np.linalg.norm(np.diff(_shape(name, np.linspace(0, 1, 2_000_001)), axis=0), axis=1).sum()
    m = np.array([(j + 1) // 2 for j in range(K)]) if closed else np.arange(K)
    return _shape(name, t), E, ((2 if closed else 1) * np.pi * m / length) ** 2


def err(lam: np.ndarray, ref: np.ndarray) -> float:
    return float(np.abs(lam[1:K] / ref[1:K] - 1).max())


def eigs_error(op, ref: np.ndarray) -> float:
    return err(spectral.eigs(op, K, tol=1e-9)[0], ref)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="n = 60 and 200 only")
    ap.add_argument("--no-write", action="store_true", help="print only")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    head = ("| curve | sampling | n | default | Galerkin pencil | vertex pencil | paper's | linear FEM "
            "| default / FEM | Galerkin / default |\n|---|---|---|---|---|---|---|---|---|---|")
    lines = [head]
    print(head, flush=True)
    for name in ("circle", "ellipse", "trefoil", "open arc"):
        for kind in ("uniform", "random"):
            for n in (60, 200) if args.quick else (60, 200, 1000):
                V, E, ref = curve(name, kind, n)
                default = meshlap.laplacian(V, E)
                ours = eigs_error(default, ref)
                gal = eigs_error(meshlap.laplacian(V, E, operator="galerkin"), ref)
                vert = meshlap.laplacian(V, E, operator="kernel")
                v = eigs_error(vert, ref)
                paper = eigs_error(meshlap.laplacian(V, E, operator="paper"), ref)
                cot = baselines.cotangent(V, E)
                lam = eigsh(sp.csc_matrix(-cot.S), K, sp.diags(cot.mass).tocsc(), sigma=-1e-6)[0]
                fem = err(np.sort(lam), ref)
                fell = "" if vert.correction == "richardson" else f" ({vert.correction})"
                line = (f"| {name} | {kind} | {n:,} | {ours:.4%} ({default.decision.operator}) | {gal:.4%} | "
                        f"{v:.4%}{fell} | {paper:.4%} | {fem:.4%} | {ours / fem:.2f} | {gal / ours:.2f} |")
                lines.append(line)
                print(line, flush=True)
    quick = " --quick" if args.quick else ""
    stamp = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    body = [f"Command: `python benchmarks/bench_curves.py{quick}` ({stamp}). "
            "Largest relative error of eigenvalues 1-9 against "
            "(2πm/ℓ)² (closed) or (πm/ℓ)² (open, Neumann); default: `meshlap.laplacian(V, E)`, the builder "
            "`op.decision` chose in parentheses; Galerkin, vertex and paper's: `operator=\"galerkin\"`, "
            "`\"kernel\"`, `\"paper\"`; a correction in parentheses: the vertex pencil's check failed and "
            "it fell back to it; linear FEM: `meshlap.baselines.cotangent(V, E)`.", ""] + lines
    if not args.no_write:
        write_section("Curves: eigenvalues on segments", body)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
