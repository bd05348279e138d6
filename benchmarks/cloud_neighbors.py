"""The cloud column of bench_real.py at other neighbour counts, meshlap's and robust-laplacian's.

    MESHLAP_CORPUS=/path/to/corpus python benchmarks/cloud_neighbors.py                 # all clouds
    MESHLAP_CORPUS=/path/to/corpus python benchmarks/cloud_neighbors.py --only cow,homer

Both point-cloud Laplacians build each point's local Delaunay triangles from its nearest
neighbours: meshlap's from 16 (``neighbors=``, growing where a star is not closed), robust-
laplacian's from 30 (``n_neighbors=``). For each mesh of the corpus this prints, for every count
of ``--counts``, the spectrum error (bench_real.py's: largest relative error of λ1..λ9 against the
cached refined-FEM reference) of meshlap's default cloud pencil and of robust-laplacian's at that
count, then for each count the summary bench_real.py gives the default, against robust-laplacian
at its own default of 30. Where a cloud touches itself (``real_corpus.touching`` > 0) the error is
mostly how many points of the other sheet the count lets into the triangles, which this shows:
it needs bench_real.py's reference cache (``python benchmarks/bench_real.py`` fills it).
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import real_corpus as rc  # noqa: E402
import robust_laplacian  # noqa: E402
from bench_real import REF_VERSION  # noqa: E402

import meshlap  # noqa: E402
from meshlap import spectral  # noqa: E402

ROBUST_DEFAULT = 30


def errors(V: np.ndarray, ref: np.ndarray, n_parts: int, k: int, counts: list[int]
           ) -> tuple[list[float], list[float]]:
    """meshlap's and robust-laplacian's spectrum error at each neighbour count."""
    ours, theirs = [], []
    def error(spectrum) -> float:  # a count beyond a tiny cloud's points fails: inf
        try:
            return rc.spectrum_error(spectrum(), ref, n_parts)
        except Exception:  # noqa: BLE001 - a failure is this count's result
            return float("inf")

    for c in counts:
        ours.append(error(lambda c=c: spectral.eigs(meshlap.point_cloud_laplacian(V, neighbors=c), k)[0]))
        theirs.append(error(lambda c=c: rc.pencil_eigs(
            *robust_laplacian.point_cloud_laplacian(V, n_neighbors=c), k)))
    return ours, theirs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--corpus", default=None)
    ap.add_argument("--only", default="", help="comma-separated mesh names")
    ap.add_argument("--counts", default="8,12,16,24,30,45", help="neighbour counts, comma-separated")
    args = ap.parse_args()
    counts = sorted({int(c) for c in args.counts.split(",")} | {ROBUST_DEFAULT})
    only = {s for s in args.only.split(",") if s}
    folder = rc.corpus_dir(args.corpus)
    cache = json.loads((folder / "reference-cache.json").read_text())
    warnings.simplefilter("ignore")
    print("error in %: meshlap (neighbors=c) / robust-laplacian (n_neighbors=c)")
    print(f"{'mesh':16s} {'touching':>8s}  " + "  ".join(f"{'c=' + str(c):>15s}" for c in counts))
    ratios = {c: [] for c in counts}
    for entry in rc.manifest():
        if only and entry["name"] not in only:
            continue
        mesh = rc.load(folder / entry["file"], entry["format"])
        if mesh.tet:
            continue
        n_parts = rc.parts(mesh.Cw, len(mesh.Vw))
        k = 10 + n_parts
        key = f"{entry['sha256']}:k{k}:v{REF_VERSION}"
        if key not in cache:
            print(f"{entry['name']}: no cached reference (run bench_real.py first)")
            continue
        ref = np.array(cache[key]["ref"])
        ours, theirs = errors(mesh.Vw, ref, n_parts, k, counts)
        robust = theirs[counts.index(ROBUST_DEFAULT)]
        for c, e in zip(counts, ours, strict=True):
            if np.isfinite(robust):  # where robust-laplacian fails there is nothing to compare
                ratios[c].append(e / robust)
        print(f"{entry['name']:16s} {rc.touching(mesh.Vw, mesh.Cw):8d}  "
              + "  ".join(f"{100 * a:7.3g}/{100 * b:<7.3g}" for a, b in zip(ours, theirs, strict=True)),
              flush=True)
    print(f"\nmeshlap at each count against robust-laplacian at its default ({ROBUST_DEFAULT}):")
    for c in counts:
        r = np.array(ratios[c])
        if len(r):
            print(f"  neighbors={c:<3d} within 1.5x in {int((r <= 1.5).sum())} of {len(r)}, ahead in "
                  f"{int((r <= 1).sum())}; ratio median {np.median(r):.3g}, worst {r.max():.3g}")


if __name__ == "__main__":
    main()
