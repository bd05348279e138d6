"""Every use of the default operator on every input of the real corpus: does it run, is it finite?

    MESHLAP_CORPUS=/path/to/corpus python benchmarks/bench_real_uses.py [--only a,b] [--no-write]

For each mesh of ``benchmarks/corpus.toml`` as published (duplicate vertices, collapsed faces,
unreferenced vertices and all; tetrahedra with ``k=3``) and for its welded vertices as a point
cloud: ``laplacian`` / ``point_cloud_laplacian`` with their defaults, then ``op @ f``,
``spectral.eigs(op, 10)``, ``heat.heat_flow`` at t = 10⁻³·diameter², ``geodesic_distance``
from the first vertex with mass, ``harmonic`` between it and the farthest vertex,
``shape_dna(op, 10)``, ``wave_kernel_signature(op, 20, k)`` (k = 30 + parts, at most the vertices with
mass less one: all the pairs a 20-vertex mesh has), ``smooth_function``, the mean
curvature (``mean_curvature`` on faces, ``mean_curvature_normal`` otherwise) and a save/load
round trip (the reloaded ``op @ f`` equal). A use fails when it raises, when its result holds a
NaN or an infinity where a value is defined (``mean_curvature`` is NaN by definition at
vertices that no face uses), or when the reloaded operator differs. The table lists every
failure and the slowest uses; the corpus is built by ``build_corpus.py``.
"""

from __future__ import annotations

import argparse
import datetime
import platform
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
from scipy.sparse.csgraph import connected_components

sys.path.insert(0, str(Path(__file__).resolve().parent))
import real_corpus as rc  # noqa: E402
from results_file import write_section  # noqa: E402

import meshlap  # noqa: E402
from meshlap import curvature, descriptors, geodesics, heat, smoothing, spectral, store  # noqa: E402


def uses(op, V: np.ndarray, faces: bool, parts: int, folder: Path) -> list[tuple[str, float, str]]:
    """(use, seconds, "" or what went wrong) for every use on one operator of ``parts`` connected
    parts (the WKS asks for 30 eigenpairs beyond their zeros)."""
    f = V[:, 0] ** 2
    t = 1e-3 * float(np.linalg.norm(V.max(0) - V.min(0))) ** 2
    source = int(np.flatnonzero(np.asarray(op.geometry.mass) > 0)[0])  # a cloud's outliers have none
    far = int(np.argmax(np.linalg.norm(V - V[source], axis=1)))
    unused = ~np.isin(np.arange(len(V)), op.faces.triangles()) if faces else np.zeros(len(V), bool)

    def curv() -> np.ndarray:
        return curvature.mean_curvature(op)[~unused] if faces else curvature.mean_curvature_normal(op, V)

    def reload() -> np.ndarray:
        path = folder / "op.npz"
        store.save_operator(path, op)
        again = store.load_operator(path) @ f
        first = op @ f
        return np.zeros(1) if np.allclose(again, first, rtol=1e-12, atol=1e-12 * np.abs(first).max()) else \
            np.array([np.nan])

    most = int((op.mass > 0).sum()) - 1  # all the pairs a tiny mesh has
    steps = [("apply", lambda: op @ f), ("eigs", lambda: spectral.eigs(op, 10)[0]),
             ("heat", lambda: heat.heat_flow(op, f, t)),
             ("geodesic", lambda: geodesics.geodesic_distance(op, [source])),
             ("harmonic", lambda: meshlap.harmonic(op, [source, far], [0.0, 1.0])),
             ("shape_dna", lambda: descriptors.shape_dna(op, 10)),
             ("wks", lambda: descriptors.wave_kernel_signature(op, 20, min(30 + parts, most))),
             ("smooth", lambda: smoothing.smooth_function(op, f, t)), ("curvature", curv), ("reload", reload)]
    out = []
    for name, step in steps:
        began = time.perf_counter()
        try:
            value = np.asarray(step(), dtype=np.float64)
            # a geodesic distance is infinite on the parts the source cannot reach
            bad = np.isnan(value).any() if name == "geodesic" else not np.isfinite(value).all()
            problem = ("reloaded operator differs" if name == "reload" else "NaN or inf") if bad else ""
        except Exception as e:  # noqa: BLE001 - every failure is what this benchmark reports
            problem = f"{type(e).__name__}: {str(e).splitlines()[0][:160]}"
        out.append((name, time.perf_counter() - began, problem))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--corpus", help="the corpus folder (default $MESHLAP_CORPUS or benchmarks/corpus)")
    ap.add_argument("--only", help="comma-separated corpus names")
    ap.add_argument("--no-write", action="store_true", help="print, do not write RESULTS.md")
    args = ap.parse_args()
    corpus = rc.corpus_dir(args.corpus)
    only = set(args.only.split(",")) if args.only else None
    rows = []
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        for entry in rc.manifest():
            if only and entry["name"] not in only:
                continue
            mesh = rc.load(corpus / entry["file"], entry.get("format", ""))
            parts = rc.parts(mesh.Cw, len(mesh.Vw))
            inputs = [("tetrahedra" if mesh.tet else "mesh", lambda m=mesh: meshlap.laplacian(
                m.V, m.faces, k=3 if m.tet else None), mesh.V, not mesh.tet)]
            if not mesh.tet:
                inputs.append(("cloud", lambda m=mesh: meshlap.point_cloud_laplacian(m.Vw), mesh.Vw, False))
            for kind, build, V, faces in inputs:
                began = time.perf_counter()
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    try:
                        op = build()
                        results = [("build", time.perf_counter() - began, "")]
                        # a cloud's parts are its own: the stars join touching parts, and small
                        # features whose points are far from the rest stand apart
                        own = parts if kind != "cloud" else connected_components(op.S, directed=False)[0]
                        results += uses(op, V, faces, own, Path(tmp))
                    except Exception as e:  # noqa: BLE001
                        results = [("build", time.perf_counter() - began, f"{type(e).__name__}: {e}"[:160])]
                rows.append((entry["name"], kind, len(V), results))
                failed = [f"{u}: {p}" for u, _, p in results if p]
                print(f"{entry['name']}: {kind}, {sum(s for _, s, _ in results):.1f} s, "
                      f"{'; '.join(failed) or 'every use ran'}", flush=True)
    lines = table(rows, time.perf_counter() - started)
    print("\n".join(lines))
    if not args.no_write:
        write_section("bench_real_uses.py", lines)


def table(rows: list, seconds: float) -> list[str]:
    runs = [(name, kind, n, u, s, p) for name, kind, n, results in rows for u, s, p in results]
    failed = [r for r in runs if r[5]]
    inputs = {(r[0], r[1]) for r in runs}
    lines = [f"`python benchmarks/bench_real_uses.py` on {datetime.date.today()}, {platform.machine()}, "
             f"2 cores (shared), {seconds:.0f} s; meshlap {meshlap.__version__}.", "",
             f"{len(inputs)} inputs (meshes as published, tetrahedra, the meshes' vertices as clouds), "
             f"{len(runs)} uses: **{len(failed)} failed**.", ""]
    if failed:
        lines += ["| input | kind | vertices | use | failure |", "|---|---|---|---|---|"]
        lines += [f"| {r[0]} | {r[1]} | {r[2]} | {r[3]} | {r[5]} |" for r in failed] + [""]
    slow = sorted(runs, key=lambda r: -r[4])[:10]
    lines += ["The slowest uses:", "", "| input | kind | vertices | use | seconds |", "|---|---|---|---|---|"]
    lines += [f"| {r[0]} | {r[1]} | {r[2]} | {r[3]} | {r[4]:.1f} |" for r in slow]
    return lines


if __name__ == "__main__":
    main()
