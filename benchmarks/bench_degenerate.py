"""Degenerate inputs against libigl's cotangent Laplacian, in one process: nearly coincident
vertices, and parts of far apart sizes.

    MESHLAP_CORPUS=/path/to/corpus python benchmarks/bench_degenerate.py   # RESULTS.md
    python benchmarks/bench_degenerate.py --no-write

Table 1: a 2,000-vertex sphere whose every 10th of its first 2,000 faces is split at a new
vertex ``d`` of the way from a corner to the opposite side's midpoint (``shapes.near_copies``:
200 copies, with needles and caps between each and its corner; at 10⁻⁹ the copies are
welded). λ₁ of the default's pencil (linear, and quadratic, the default's spectra) beside
libigl's cotangent pencil (eigsh, shift-invert) on the same triangles, ``eigs``'
``info["uncertified"]`` (each pair's bound with its residual's roundoff, over its eigenvalue:
a MeshWarning above 1e-3), its
shift-invert runs and the CPU seconds of build + 6 pairs.

Table 2: a unit sphere (800 vertices) beside one of radius ``s`` (200 vertices): the two zeros,
then λ₂ ... of the large sphere; ``info["parts"]``: each part is solved at its own scale
(:mod:`meshlap._parts`).

Table 3: part by part (the default) against the whole in one solve (forced; the default
before), on every multi-part surface of the corpus ($MESHLAP_CORPUS; skipped without it): CPU
seconds of 10 + parts pairs of the default's pencil (built before), what roundoff leaves the
whole's check, how far the whole's nonzero eigenvalues are from the parts', beside libigl's
cotangent + eigsh.

Table 4: geodesic distance on two spheres (radius 1 and 0.5, 1,000 vertices each, 0.05 apart)
with a source on each: mean error against the great-circle distance on each sphere, and the
vertices at ``inf`` from one source, for meshlap's heat method, libigl's and potpourri3d's.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path
from unittest import mock

import igl
import numpy as np
from scipy.sparse.linalg import eigsh

sys.path.insert(0, str(Path(__file__).resolve().parent))
import real_corpus as rc  # noqa: E402
from results_file import write_section  # noqa: E402

import meshlap  # noqa: E402
from meshlap import _parts, shapes, spectral  # noqa: E402


def cpu(fn, *args):
    t = time.process_time()
    out = fn(*args)
    return out, time.process_time() - t


def near_copies(d: float) -> tuple[np.ndarray, np.ndarray]:
    return shapes.near_copies(*shapes.sphere(2000, seed=0), d, np.arange(0, 2000, 10))


def solve(op, elements: str) -> tuple[np.ndarray, dict, float]:
    info: dict = {}
    t = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lam, _ = spectral.eigs(op, 6, elements=elements, info=info)
    return lam, info, time.process_time() - t


def copies_rows() -> list[str]:
    rows = []
    for d in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9):
        V, F = near_copies(d)
        t = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            op = meshlap.laplacian(V, F)
        build = time.process_time() - t
        lin, _, _ = solve(op, "linear")
        quad, info, seconds = solve(op, "quadratic")
        M = igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI).tocsc()
        cot = eigsh(-igl.cotmatrix(V, F).tocsc(), 5, M, sigma=-1e-3, return_eigenvectors=False)
        runs = info["tried"].count("shift-invert")
        rows.append(f"| {d:.0e} | {lin[1]:.5f} | {np.sort(cot)[1]:.5f} | {quad[1]:.5f} | "
                    f"{info['uncertified']:.1e} | {runs} | {build + seconds:.2f} |")
        print(rows[-1], file=sys.stderr, flush=True)
    return rows


def parts_rows() -> list[str]:
    V, F = shapes.sphere(800, seed=0)
    v, f = shapes.sphere(200, seed=1)
    rows = []
    for s in (1e-2, 1e-3, 1e-4, 1e-5, 1e-6):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            op = meshlap.laplacian(np.vstack([V, s * v + [0, 0, 1.0]]), np.vstack([F, f + 800]))
        lam, info, seconds = solve(op, "auto")
        rows.append(f"| {s:.0e} | {lam[0]:.2g} | {lam[1]:.2g} | {lam[2]:.5f} | {lam[5]:.5f} | "
                    f"{info.get('parts', '—')} | {info['complete']} | {seconds:.2f} |")
        print(rows[-1], file=sys.stderr, flush=True)
    return rows


def whole(op, k: int) -> tuple[tuple[np.ndarray, np.ndarray], dict]:
    # the whole pencil in one solve, as eigs did before parts came first: its parts unseen
    info: dict = {}
    with mock.patch.object(_parts, "part_labels", lambda S: (1, np.zeros(S.shape[0], np.int64))):
        return spectral.eigs(op, k, info=info), info


def cot_eigs(V: np.ndarray, F: np.ndarray, k: int) -> np.ndarray:
    M = igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI).tocsc()
    return eigsh(-igl.cotmatrix(V, F).tocsc(), k, M, sigma=-1e-8, return_eigenvectors=False)


def whole_and_by_part() -> list[str]:
    folder = rc.corpus_dir(None)
    rows = []
    for entry in rc.manifest() if folder.exists() else []:
        path = folder / entry["file"]
        if not path.exists():
            continue
        mesh = rc.load(path, entry["format"])
        parts = rc.parts(mesh.Cw, len(mesh.Vw))
        if mesh.tet or parts < 2:
            continue
        k = 10 + parts
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            op = meshlap.laplacian(mesh.V, mesh.faces)
            (lam, _), t_part = cpu(spectral.eigs, op, k)
            ((lam_whole, _), info), t_whole = cpu(whole, op, k)
        _, t_cot = cpu(cot_eigs, mesh.Vw, mesh.Cw, k)
        differ = np.abs(lam_whole[parts:] - lam[parts:]).max() / lam[parts:].max()
        rows.append(f"| {entry['name']} | {len(mesh.Vw):,} | {parts} | {t_part:.2f} | {t_whole:.2f} | "
                    f"{info['uncertified']:.1e} | {differ:.0e} | {t_cot:.2f} |")
        print(rows[-1], file=sys.stderr, flush=True)
    return rows


def geodesic_rows() -> list[str]:
    import potpourri3d as pp3d

    V, F = shapes.sphere(1000, seed=0)
    v, f = shapes.sphere(1000, seed=1)
    W, G = np.vstack([V, 0.5 * v + [2.05, 0, 0]]), np.vstack([F, f + 1000])
    exact = np.r_[np.arccos(np.clip(V @ V[0], -1, 1)), 0.5 * np.arccos(np.clip(v @ v[0], -1, 1))]
    hd = meshlap.HeatDistance(meshlap.laplacian(W, G))
    data = igl.HeatGeodesicsData()
    igl.heat_geodesics_precompute(W, G, data)
    solver = pp3d.MeshHeatMethodDistanceSolver(W, G)
    out = {"meshlap": (hd.compute([0, 1000]), hd.compute(0)),
           "libigl heat_geodesics": (igl.heat_geodesics_solve(data, np.array([0, 1000])),
                                     igl.heat_geodesics_solve(data, np.array([0]))),
           "potpourri3d": (solver.compute_distance_multisource([0, 1000]), solver.compute_distance(0))}
    rows = []
    for name, (both, one) in out.items():
        err = [np.abs(both[s] - exact[s]).mean() for s in (slice(0, 1000), slice(1000, None))]
        rows.append(f"| {name} | {err[0]:.4f} | {err[1]:.4f} | {int(np.isinf(one[1000:]).sum())} of 1,000 |")
    return rows


HEAD1 = ("Nearly coincident vertices: λ₁ (2.0 on the unit sphere) of the default's pencil, of libigl's "
         "cotangent pencil on the same triangles, and of the quadratic elements (the default's spectra), "
         "what roundoff leaves `eigs`' check (`info['uncertified']`: MeshWarning above 1e-3), its "
         "shift-invert runs, CPU s of build + 6 pairs.")
COLS1 = ("| d | default, linear | libigl cotangent | default, quadratic | uncertified | shift-invert runs "
         "| CPU s |")
HEAD2 = ("A unit sphere beside one of radius s: the two zeros, then the large sphere's λ₂ (2.0078 ×3) and "
         "λ₅ (6.0234), `info['parts']` (each solved at its own scale), `info['complete']`, CPU s.")
COLS2 = "| s | λ₀ | λ₁ | λ₂ | λ₅ | parts | complete | CPU s |"
HEAD3 = ("Every multi-part surface of the corpus: 10 + parts pairs of the default's pencil (built before), "
         "CPU s, part by part (the default) and the whole in one solve (forced, the default before; "
         "`meshlap._parts.part_labels` patched to see one part), what roundoff leaves the whole's check "
         "(`info['uncertified']`: MeshWarning above 1e-3; the parts' own are below it), the largest "
         "difference of the two's nonzero eigenvalues (relative to the largest), beside libigl's "
         "cotangent + eigsh.")
COLS3 = "| mesh | vertices | parts | by part s | whole s | whole uncertified | difference | COT + eigsh s |"
HEAD4 = ("Geodesic distance on two spheres (radius 1 and 0.5, 0.05 apart), a source on each: mean error "
         "against the great-circle distance on each sphere, and the vertices of the second sphere at `inf` "
         "from a source on the first.")
COLS4 = "| method | error, sphere 1 | error, sphere 2 | unreached at inf |"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-write", action="store_true", help="print; leave RESULTS.md")
    args = ap.parse_args()
    spectral.eigs(meshlap.laplacian(*shapes.sphere(300, seed=0)), 4)  # compile first
    start = time.time()
    lines = [HEAD1, "", COLS1, "|" + "---|" * 7, *copies_rows(), "", HEAD2, "", COLS2, "|" + "---|" * 8,
             *parts_rows(), "", HEAD3, "", COLS3, "|" + "---|" * 8, *whole_and_by_part(), "", HEAD4, "",
             COLS4, "|" + "---|" * 4, *geodesic_rows()]
    print("\n".join(lines))
    if not args.no_write:
        write_section("bench_degenerate.py", ["Command: `MESHLAP_CORPUS=/path/to/corpus python "
                                              f"benchmarks/bench_degenerate.py` "
                                              f"({time.time() - start:.0f} s).", "", *lines])


if __name__ == "__main__":
    main()
