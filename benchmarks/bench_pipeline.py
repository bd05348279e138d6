"""One default for every input: the corrected operator beside the paper's, in one run.

    python benchmarks/bench_pipeline.py            # the table of benchmarks/RESULTS.md
    python benchmarks/bench_pipeline.py --quick    # smaller inputs, a minute

For a sphere cloud, a circle (random angles), a unit cube of tetrahedra (Neumann) and the
flat torus in R⁴, with the library's default (the pencil its policy chose) and with
``correction="none"`` (the paper's operator at its own default h): the largest relative
error of the first eigenvalues against the exact ones, E2 = ‖Lf − Δf‖/‖Δf‖ of ``op @ f`` for
a function with a known Laplacian, and the build time.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from results_file import write_section  # noqa: E402

import meshlap  # noqa: E402
from meshlap import samples, spectral  # noqa: E402


def _sphere_cloud(n):
    P = samples.sphere_points(n, "random", seed=0)
    lam = np.array([deg * (deg + 1) for deg in range(4) for _ in range(2 * deg + 1)], float)
    x = P[:, 0]
    return dict(build=lambda **kw: meshlap.point_cloud_laplacian(P, **kw), exact=lam,
                f=x**2, lap=2 - 6 * x**2, what=f"random sphere cloud, {n:,} points", eig="16 eigenvalues")


def _circle(n):
    V, E, t = samples.circle(n, kind="random", seed=0)
    lam = np.array([0] + [m * m for m in range(1, 6) for _ in range(2)], float)
    return dict(build=lambda **kw: meshlap.laplacian(V, E, **kw), exact=lam, f=np.cos(2 * t),
                lap=-4 * np.cos(2 * t), what=f"unit circle, {n:,} random angles", eig="11 eigenvalues")


def _cube(m):
    V, T = samples.cube_tetrahedra(m)
    lam = np.sort([a * a + b * b + c * c for a in range(3) for b in range(3) for c in range(3)])[:10]
    x = V[:, 0]
    return dict(build=lambda **kw: meshlap.laplacian(V, T, k=3, **kw), exact=math.pi**2 * lam.astype(float),
                f=np.cos(math.pi * x), lap=-math.pi**2 * np.cos(math.pi * x),
                what=f"unit cube of tetrahedra, {m + 1}³ vertices (Neumann)", eig="10 eigenvalues")


def _flat_torus(n):
    P, th, ph = samples.flat_torus_points(n, seed=0)
    lam = np.sort([a * a + b * b for a in range(-2, 3) for b in range(-2, 3)]).astype(float)[:9]
    f = np.cos(th) * np.cos(ph)
    return dict(build=lambda **kw: meshlap.point_cloud_laplacian(P, **kw), exact=lam, f=f, lap=-2 * f,
                what=f"flat torus in R⁴, {n:,} points", eig="9 eigenvalues")


def measure(case: dict, correction: str | None) -> dict:
    kw = {} if correction is None else {"correction": correction}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = time.perf_counter()
        op = case["build"](**kw).assemble()  # the pencil eigs reads: on first use
        t_build = time.perf_counter() - t0
        lam = spectral.eigs(op, len(case["exact"]), tol=1e-6)[0]
    ex = case["exact"]
    eig = float(np.abs(lam[1:] / ex[1:] - 1).max())
    e2 = float(np.linalg.norm(op @ case["f"] - case["lap"]) / np.linalg.norm(case["lap"]))
    return dict(eig=eig, e2=e2, t=t_build, pencil=op.decision.operator, nnz=op.nnz / op.n_vertices)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    cases = ([_sphere_cloud(4000), _circle(400), _cube(10), _flat_torus(4000)] if args.quick else
             [_sphere_cloud(16000), _circle(2000), _cube(20), _flat_torus(16000)])
    rows = ["| input | spectrum | default: eigenvalues / E2 / build | paper's operator: eigenvalues / E2 / "
            "build |", "|---|---|---|---|"]
    for case in cases:
        d, p = measure(case, None), measure(case, "none")
        rows.append(f"| {case['what']} | {case['eig']} | {100 * d['eig']:.2g}% / {d['e2']:.2g} / "
                    f"{d['t']:.1f} s ({d['pencil']} pencil, {d['nnz']:.0f} per row) | "
                    f"{100 * p['eig']:.2g}% / {p['e2']:.2g} / {p['t']:.1f} s |")
        print(rows[-1], flush=True)
    cmd = "python benchmarks/bench_pipeline.py" + (" --quick" if args.quick else "")
    lines = [f"Command: `{cmd}` ({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, 2 cores, shared; "
             "the default's pencil is the one its policy chose, `op.decision.operator`; "
             "eigenvalues: largest relative error of the first nonzero "
             "ones against the exact values; E2 of `op @ f`, f = x² on the sphere, cos 2θ on the circle, "
             "cos πx in the cube, cos θ cos φ on the torus).", ""] + rows
    if not args.quick:
        write_section("One default for every input", lines)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
