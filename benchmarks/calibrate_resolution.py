"""Fit the constants of meshlap.resolution's two error models on 32 inputs, and check the verdicts.

    python benchmarks/calibrate_resolution.py                  # measure, fit, print
    python benchmarks/calibrate_resolution.py --cache m.json   # keep the measurements for a re-fit

For each input (random spheres of 500 to 16,000 vertices and a noisy one, tori of 300 to 5,000,
cube surfaces, fandisk, spot, squares and discs of 319 to 8,000 vertices, cubes of tetrahedra of
9³ to 17³, sphere clouds): the default's ``op.resolution`` figures, the measured largest
relative error of eigenvalues 1-9 of the default and of linear FEM (libigl's cotangent
Laplacian, LaPy on tetrahedra; robust-laplacian for clouds, not fitted), against the exact
values or the cotangent Laplacian 16× refined. The fit minimises the squared log-ratios of
predicted to measured errors, plus a penalty on every verdict that disagrees with the
measurement (warn above 1.6× FEM, stay silent below 1.45× and on the noisy and fine spheres).
Paste the printed constants into ``meshlap/resolution.py`` after a change of the numerics.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import warnings
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_spectra as B  # noqa: E402
import igl  # noqa: E402

import meshlap  # noqa: E402
from meshlap import resolution, samples, shapes, spectral  # noqa: E402

MUST_STAY_SILENT = ("sphere, 16,000 random vertices", "same, 0.5% radial noise")


def _unit_area(name):
    V, F = igl.read_triangle_mesh(str(B.DATA / f"{name}.obj"))
    return V / math.sqrt(igl.doublearea(V, F).sum() / 2), F


def inputs():
    """(name, kind, data, exact or reference eigenvalues)."""
    out = []
    for n in (500, 1000, 2000, 4000, 16000):
        out.append((f"sphere, {n:,} random vertices", "mesh", shapes.sphere(n, kind="random", seed=0),
                    B._sphere_exact()))
    V, F = shapes.sphere(16000, kind="random", seed=0)
    noise = 1 + 0.005 * np.random.default_rng(1).standard_normal((len(V), 1))
    out.append(("same, 0.5% radial noise", "mesh", (V * noise, F), B._sphere_exact()))
    meshes = [(f"torus, {n:,}", shapes.torus(n, seed=0)) for n in (300, 600, 1200, 2500, 5000)]
    meshes += [(f"cube surface, {m} per edge", B._cube_surface(m)) for m in (10, 20, 30)]
    meshes += [(name, _unit_area(name)) for name in ("fandisk", "spot")]
    out += [(name, "mesh", VF, B.cot(*B._refined(*VF))) for name, VF in meshes]
    for n in (400, 1000, 2000, 4000, 8000):
        out.append((f"square, {n:,}", "mesh", shapes.plane(n, seed=0, kind="stratified"), B._square_exact()))
        Vd, Fd = B._disc(n)
        out.append((f"disc, {len(Vd):,}", "mesh", (Vd, Fd), B._disc_exact()))
    for side in (8, 12, 16):
        out.append((f"cube of tetrahedra, {side + 1}³", "tets", samples.cube_tetrahedra(side),
                    B._cube_exact()))
    for n in (2000, 4000, 16000):
        out.append((f"sphere cloud, {n:,}", "cloud", samples.sphere_points(n, "random", seed=0),
                    B._sphere_exact()))
    return out


def _error(lam, ref):
    return float(np.abs(lam[1:B.K] / ref[1:B.K] - 1).max())


def measure():
    """Per input: name, kind, the resolution report (JSON), measured default and FEM errors."""
    rows = []
    for name, kind, data, ref in inputs():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", meshlap.MeshWarning)
            op = (meshlap.point_cloud_laplacian(data) if kind == "cloud"
                  else meshlap.laplacian(*data, **({"k": 3} if kind == "tets" else {})))
        peer = {"mesh": B.cot, "tets": B.lapy_tet, "cloud": B.robust_cloud}[kind]
        fem = peer(data) if kind == "cloud" else peer(*data)
        rows.append({"name": name, "kind": kind, "source": op.geometry.source,
                     "faces": op.geometry.faces is not None, "report": op.resolution.to_json(),
                     "default": _error(spectral.eigs(op, B.K, tol=1e-6)[0], ref), "fem": _error(fem, ref)})
        print(f"measured {name}: {rows[-1]['default']:.2%} / {rows[-1]['fem']:.2%}", flush=True)
    return rows


def fit(rows):
    """The fitted (default model, FEM model)."""
    keys_d, keys_f = list(resolution.DEFAULT_MODEL), list(resolution.FEM_MODEL)
    figs = [resolution.Resolution.from_json(r["report"]) for r in rows]

    def split(p):
        n = len(keys_d)
        return dict(zip(keys_d, p[:n], strict=True)), dict(zip(keys_f, p[n:], strict=True))

    def residuals(p):
        md, mf = split(p)
        out = []
        for r, fig in zip(rows, figs, strict=True):
            pd = sum(resolution.default_terms(fig, md).values())
            out.append(math.log(pd / r["default"]))
            pf = resolution.fem_error(fig, r["source"], r["faces"], mf)
            if pf is None or r["kind"] == "cloud":
                continue
            out.append(math.log(pf / r["fem"]))
            measured, predicted = r["default"] / r["fem"], pd / pf
            if measured > 1.6:
                out.append(5 * max(0.0, math.log(1.8 / predicted)))
            elif measured < 1.45 or r["name"] in MUST_STAY_SILENT:
                out.append(5 * max(0.0, math.log(predicted / 1.3)))
        return out

    p0 = [*resolution.DEFAULT_MODEL.values(), *resolution.FEM_MODEL.values()]
    lower = [0.3 if k == "R_0" else 0.0 for k in keys_d] + [0.0] * len(keys_f)
    upper = [1.0 if k == "R_0" else 50.0 for k in keys_d] + [50.0] * len(keys_f)
    return split(least_squares(residuals, p0, bounds=(lower, upper)).x)


def report(rows, md, mf):
    agree = 0
    print("| input | default measured / predicted | FEM measured / predicted | verdict | agrees |")
    print("|---|---|---|---|---|")
    for r in rows:
        fig = resolution.Resolution.from_json(r["report"])
        pd = sum(resolution.default_terms(fig, md).values())
        pf = resolution.fem_error(fig, r["source"], r["faces"], mf)
        warn = pf is not None and r["kind"] != "cloud" and pd > resolution.RATIO_LIMIT * pf
        ratio = r["default"] / r["fem"]
        ok = warn if ratio > resolution.RATIO_LIMIT else not warn or ratio > 1.45
        agree += ok
        fem = "–" if pf is None else f"{pf:.2%}"
        print(f"| {r['name']} | {r['default']:.2%} / {pd:.2%} | {r['fem']:.2%} / {fem} | "
              f"{'too coarse' if warn else 'resolved'} | {'yes' if ok else 'NO'} |")
    print(f"verdicts agreeing with the measurement: {agree} of {len(rows)}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache", type=Path, help="JSON file of measurements: read if it exists, else written")
    args = ap.parse_args(argv)
    if args.cache is not None and args.cache.exists():
        rows = json.loads(args.cache.read_text())
    else:
        rows = measure()
        if args.cache is not None:
            args.cache.write_text(json.dumps(rows))
    md, mf = fit(rows)
    print("DEFAULT_MODEL =", {k: float(f"{v:.3g}") for k, v in md.items()})
    print("FEM_MODEL =", {k: float(f"{v:.3g}") for k, v in mf.items()})
    report(rows, md, mf)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
