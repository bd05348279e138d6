"""What each ingredient of the Galerkin pencil (``operator="galerkin"``) buys, on the coarse rows of
bench_spectra.py.

    python benchmarks/bench_quadrature.py             # writes its section of RESULTS.md
    python benchmarks/bench_quadrature.py --no-write  # prints only

Largest relative error of eigenvalues 1-9 (references as in bench_spectra.py: exact for the
sphere and the Neumann square, libigl's cotangent FEM on the mesh refined 16× for the torus
and the cube surface) for: the vertex pencil (one point per vertex, ``quadrature="vertex"``);
the kernel integrated over the triangles (3 points each) with a plain Gaussian or the
Richardson kernel; with the lumped mass as it is, the consistent mass, or the congruence that
carries the consistent mass onto the lumped one (as built); at h = c·ē² for three c; and
without the mirror images (square) or the unfolded distances across creases (cube).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_spectra as bs  # noqa: E402
from results_file import write_section  # noqa: E402

import meshlap  # noqa: E402
from meshlap import assembly, shapes, spectral, tuned  # noqa: E402
from meshlap.corrections import galerkin, neumann_images  # noqa: E402
from meshlap.geometry import frames  # noqa: E402
from meshlap.widths import Widths  # noqa: E402


def _raw(V, F, h, dog, boundary):
    # the Galerkin form before the mass congruence, and the consistent mass C
    X, W, Phi = galerkin.quadrature_points(V, F)
    Lq = assembly.assemble(X, W, Widths(h, None, False), assembly.Kernel(2, dog=dog))
    if boundary is not None:
        fr = frames.frames_from_samples(X, *boundary, assembly.cutoff_radius(h, 1e-8))
        Lq = neumann_images(Lq, X, fr, W, np.full(len(X), h), dog, 2)
    S = (sp.diags(W) @ Phi).T @ Lq @ Phi
    return 0.5 * (S + S.T), (Phi.T @ sp.diags(W) @ Phi).tocsr()


def _eig(S, M):
    M = M.toarray() if sp.issparse(M) else np.diag(M)
    return sla.eigh(-S.toarray(), M, eigvals_only=True, subset_by_index=[0, bs.K - 1])


def cases():
    Vt, Ft = shapes.torus(600, seed=0)
    yield "coarse torus, 600", Vt, Ft, bs.cot(*bs._refined(Vt, Ft))
    Vs, Fs = shapes.sphere(500, seed=0)
    yield "coarse sphere, 500", Vs, Fs, bs._sphere_exact()
    Vq, Fq = shapes.plane(400, seed=0, kind="stratified")
    yield "square, 400, Neumann", Vq, Fq, bs._square_exact()
    Vc, Fc = bs._cube_surface(20)
    yield "cube surface, 2,402", Vc, Fc, bs.cot(*bs._refined(Vc, Fc))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-write", action="store_true", help="print only")
    args = ap.parse_args()
    cols = ["vertex pencil", "Gaussian, C", "Richardson, lumped", "Richardson, C", "as built (congruence)",
            "h = 0.25 ē²", "h = 1 ē²", "no images / no unfolding"]
    head = "| input | " + " | ".join(cols) + " |\n|---|" + "---|" * len(cols)
    lines = [head]
    print(head, flush=True)
    for name, V, F, ref in cases():
        def err(lam, ref=ref):
            return f"{float(np.abs(lam[1:bs.K] / ref[1:bs.K] - 1).max()):.2%}"

        g = meshlap.geometry.from_mesh(V, F)
        h = tuned.GALERKIN_H_SCALE * g.spacing**2
        bnd = g.boundary_samples(assembly.cutoff_radius(4.0 * g.spacing**2, 1e-8))  # as the default samples
        folds = galerkin.creases(V, F)
        row = [err(spectral.eigs(meshlap.laplacian(V, F, quadrature="vertex"), bs.K)[0])]
        S, C = _raw(V, F, h, False, bnd)
        row.append(err(_eig(S, C)))
        S, C = _raw(V, F, h, True, bnd)
        row += [err(_eig(S, g.mass)), err(_eig(S, C))]
        for c in (tuned.GALERKIN_H_SCALE, 0.25, 1.0):
            S, m = galerkin.galerkin_pencil(V, F, c * g.spacing**2, 2, crease_edges=folds, boundary=bnd)
            row.append(err(_eig(S, m)))
        if bnd is not None or len(folds):
            S, m = galerkin.galerkin_pencil(V, F, h, 2)
            row.append(err(_eig(S, m)))
        else:
            row.append("–")
        line = f"| {name} | " + " | ".join(row) + " |"
        lines.append(line)
        print(line, flush=True)
    stamp = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    body = [f"Command: `python benchmarks/bench_quadrature.py` (2 cores; {stamp}). The Galerkin pencil is "
            "the named builder `operator=\"galerkin\"`, not the default (FEM). Largest relative error of "
            "eigenvalues 1-9; C: the consistent mass; h = 0.5 ē² unless the column says otherwise; the "
            "references are bench_spectra's.", ""] + lines
    if not args.no_write:
        write_section("Galerkin pencil: what each ingredient buys", body)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
