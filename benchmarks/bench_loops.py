"""Curves from real meshes: the boundary loops of the corpus's open surfaces, in one run.

    python benchmarks/bench_loops.py                 # the table of benchmarks/RESULTS.md
    python benchmarks/bench_loops.py --no-write --corpus /path/to/corpus

A closed polyline of length ℓ is, intrinsically, a circle of length ℓ: its Laplace–Beltrami
eigenvalues are (2πm/ℓ)², twice each, whatever its shape in space. Each boundary loop of the
corpus's surface meshes (benchmarks/corpus.toml, welded; loops of at least 30 vertices that
pass through no position twice, the three longest per mesh) is one row: the largest relative
error of eigenvalues 1-9 of meshlap's default (``meshlap.laplacian(P, E)``, the builder in
``op.decision``), of linear FEM on the segments (``meshlap.baselines.cotangent(P, E)``: what
libigl, LaPy and robust-laplacian would build on a polyline), of the kernel's vertex pencil
(``operator="kernel"``) and of the paper's operator (``operator="paper"``); then of the loop's
points alone, without its segments (``meshlap.point_cloud_laplacian(P, k=1)``, the builder in
``op.decision``) and of the kernel on them (``operator="kernel"``). The loops are real sampling:
scanner boundaries, CAD rims, decimated edges, segment lengths up to 26× apart.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import real_corpus as rc  # noqa: E402
from results_file import write_section  # noqa: E402

import meshlap  # noqa: E402
from meshlap import spectral  # noqa: E402
from meshlap.baselines import cotangent  # noqa: E402

K = 10
MIN_VERTICES = 30
PER_MESH = 3


def loops(F: np.ndarray) -> list[np.ndarray]:
    """The boundary loops of a triangle mesh (edges in one face, in the faces' orientation); a
    vertex where two boundary edges start ends the chains through it (a pinch: not a curve)."""
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    key = np.sort(E, axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    bnd = E[cnt[inv.ravel()] == 1]
    starts, nout = np.unique(bnd[:, 0], return_counts=True)
    pinch = set(starts[nout > 1].tolist())
    nxt = {int(a): int(b) for a, b in bnd if a not in pinch}
    out, seen = [], set()
    for a in list(nxt):
        if a in seen:
            continue
        chain, v = [], a
        while v in nxt and v not in seen:
            seen.add(v)
            chain.append(v)
            v = nxt[v]
        if v == a and len(chain) >= MIN_VERTICES:
            out.append(np.array(chain))
    return sorted(out, key=len, reverse=True)[:PER_MESH]


def error(op, exact: np.ndarray) -> float:
    lam = spectral.eigs(op, K, tol=1e-8)[0]
    return float(np.abs(lam[1:] / exact[1:] - 1).max())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--corpus", default=None,
                    help="corpus folder (default: $MESHLAP_CORPUS, benchmarks/corpus)")
    ap.add_argument("--no-write", action="store_true", help="print the table; leave RESULTS.md")
    args = ap.parse_args(argv)
    folder = rc.corpus_dir(args.corpus)
    rows, ratios, clouds, below_paper, below_kernel, start = [], [], [], 0, 0, time.time()
    head = ["| mesh | loop | n | longest / shortest segment | default (builder) | linear FEM | kernel "
            "| paper's | default / FEM | points as a cloud (builder) | cloud, kernel | cloud / FEM |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    print("\n".join(head), flush=True)
    for entry, mesh in rc.surfaces(folder):
        for i, loop in enumerate(loops(mesh.Cw)):
            P = mesh.Vw[loop]
            if len(np.unique(P, axis=0)) < len(P):
                continue
            seg = np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1)
            exact = np.r_[0.0, np.repeat((2 * np.pi * np.arange(1, K // 2 + 1) / seg.sum()) ** 2, 2)][:K]
            E = np.column_stack([np.arange(len(P)), (np.arange(len(P)) + 1) % len(P)])
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                op = meshlap.laplacian(P, E)
                d, f = error(op, exact), error(cotangent(P, E), exact)
                kern = error(meshlap.laplacian(P, E, operator="kernel"), exact)
                paper = error(meshlap.laplacian(P, E, operator="paper"), exact)
                cloud = meshlap.point_cloud_laplacian(P, k=1)
                c = error(cloud, exact)
                ck = error(meshlap.point_cloud_laplacian(P, k=1, operator="kernel"), exact)
            ratios.append(d / f)
            clouds.append(c / f)
            below_kernel += c <= ck
            below_paper += d <= paper
            rows.append(f"| {entry['name']} | {i} | {len(P)} | {seg.max() / seg.min():.1f} | "
                        f"{d:.3g} ({op.decision.operator}) | {f:.3g} | {kern:.3g} | {paper:.3g} | "
                        f"{d / f:.2f} | {c:.3g} ({cloud.decision.operator}) | {ck:.3g} | {c / f:.2f} |")
            print(rows[-1], flush=True)
    r = np.array(ratios)
    summary = (f"{len(r)} loops; the default's error over linear FEM's: median {np.median(r):.3g}×, worst "
               f"{r.max():.3g}×, ahead (≤ 1×) on {int((r <= 1).sum())} of {len(r)}; at most the paper's "
               f"operator's error on {below_paper} of {len(r)}. The points alone as a cloud: over linear "
               f"FEM's error median {np.median(clouds):.3g}×, worst {np.max(clouds):.3g}×, within 1.5× on "
               f"{int((np.array(clouds) <= 1.5).sum())} of {len(r)}, at most the kernel's on the same points "
               f"on {below_kernel} of {len(r)}.")
    print(summary)
    if not args.no_write:
        cmd = "python benchmarks/bench_loops.py"
        write_section("Curves from real meshes: boundary loops", [
            f"Command: `{cmd}` ({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, 2 shared cores, "
            f"{time.time() - start:.0f} s). Largest relative error of eigenvalues 1-9 against (2πm/ℓ)², "
            "ℓ the loop's length (module docstring).", "", summary, "", *head, *rows])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
