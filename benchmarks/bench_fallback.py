"""The kernel builder's fallback: the Richardson kernel against the plain one at explicit widths.

For bench_psd's inputs (2,000-vertex random sphere, plane and torus, spot, a 12³ tetrahedral
cube) and 20,000-vertex random, uniform and nonuniform spheres, at h = f · ē² (ē the mean edge):
the largest relative error of eigenvalues 1-9 of the Richardson operator (``check_psd=False``),
of the plain kernel with the default's arc distances and mirror images (its fallback), of the
same with chords, and of the paper's operator (``correction="none"``: chords, no images); the
semidefiniteness check's verdict; and what ``operator="kernel"`` builds (the Richardson
operator, the plain kernel where the check fails). References: the exact eigenvalues (sphere,
square, cube), else the cotangent Laplacian of the mesh refined twice.

    python benchmarks/bench_fallback.py          # the table (about 7 minutes on 2 cores)
    python benchmarks/bench_fallback.py --quick  # bench_psd's inputs at 0.3, 0.5, 1 and 2 ē² only
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_psd  # noqa: E402
import bench_spectra as B  # noqa: E402

import meshlap  # noqa: E402
from meshlap import shapes, spectral  # noqa: E402
from meshlap.corrections import psd  # noqa: E402

FRACTIONS = (0.3, 0.5, 0.7, 1.0, 1.5, 2.0, 3.0)
QUICK = (0.3, 0.5, 1.0, 2.0)


def inputs(quick: bool = False):
    """(name, (V, F), k, reference eigenvalues 0..9, fractions)."""
    # the random plane's cotangent Laplacian, refined, is 6% off its square's Neumann eigenvalues
    exact = {"sphere": B._sphere_exact(), "plane": B._square_exact(), "cube 12³": B._cube_exact()}
    for name, VF, k in bench_psd.inputs():
        ref = exact[name] if name in exact else B.cot(*B._refined(*VF))
        yield name, VF, k, ref, QUICK if quick else FRACTIONS
    if quick:
        return
    for kind in ("random", "uniform", "nonuniform"):
        VF = shapes.sphere(20000, kind=kind, seed=0)
        yield f"sphere 20k {kind}", VF, 2, B._sphere_exact(), (0.5, 1.0, 2.0)


def _error(op, ref):
    lam = np.sort(spectral.eigs(op, B.K, tol=1e-6)[0])
    return float(np.abs(lam[1:B.K] / ref[1:B.K] - 1).max())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="bench_psd's inputs at 0.3, 0.5, 1 and 2 ē² only")
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    print("| input | h / ē² | check | Richardson | plain, arc distance and images | plain, chords and images "
          "| paper's | `operator=\"kernel\"` |")
    print("|---|---|---|---|---|---|---|---|")
    for name, (V, F), k, ref, fractions in inputs(args.quick):
        kw = {"k": 3} if k == 3 else {}
        geo = meshlap.geometry.from_mesh(V, F, **kw)
        for f in fractions:
            h = f * geo.spacing**2
            rich = meshlap.laplacian(V, F, h=h, check_psd=False, pointwise=False, **kw)
            L = rich.L_sym / rich.moment_scale
            lam, scale = psd.smallest_eigenvalue(L, rich.mass, rich.geometry.points, rich.geometry.faces)
            passes = lam >= -psd.PSD_RTOL * scale
            # the plain kernel as the build makes it: the corrected default's tolerance and images
            arc, chord = (meshlap.laplacian(V, F, h=h, correction="none", arc_distance=a,
                                            neumann=rich.neumann, tol=meshlap.CORRECTED_TOL, **kw)
                          for a in (rich.arc_distance, False))
            paper = meshlap.laplacian(V, F, h=h, correction="none", **kw)
            now = meshlap.laplacian(V, F, h=h, operator="kernel", pointwise=False, **kw)
            errs = [_error(op, ref) for op in (rich, arc, chord, paper, now)]
            print(f"| {name} | {f:g} | {'passes' if passes else 'fails'} | {errs[0]:.2%} | {errs[1]:.2%} | "
                  f"{errs[2]:.2%} | {errs[3]:.2%} | {errs[4]:.2%} ({now.correction}) |",
                  flush=True)


if __name__ == "__main__":
    main()
