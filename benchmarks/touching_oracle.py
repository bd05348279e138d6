"""A touching cloud given the mesh's knowledge: can the default's stars be kept on their sheets?

    MESHLAP_CORPUS=/path/to/corpus python benchmarks/touching_oracle.py            # the cow
    MESHLAP_CORPUS=/path/to/corpus python benchmarks/touching_oracle.py homer --detour 4

Where two sheets of a mesh come closer than its sampling (``real_corpus.touching`` > 0), the
vertices alone do not say which nearby points share a sheet. This script tells the default's
cloud pencil (linear FEM on every point's local Delaunay star) what only the mesh knows, in three
ways, and prints the spectrum error of each (bench_real.py's measure and cached reference):

- ``same-sheet neighbours``: every star is built from the nearest points that are less than
  ``--detour`` times farther along the mesh's edges than through space (the first 16 such among
  the ``--pool`` × 16 nearest; where fewer are, the nearest others fill the list, and they are
  counted);
- ``cross triangles cut``: the default's stars without the triangles two of whose corners are
  that far apart along the mesh; a point left in no triangle keeps its star (else it would be a
  part of its own), and those points are counted (a group of points the cut leaves loose
  together still adds a zero eigenvalue: the cow at ``--detour 4``);
- ``agreed triangles``: only the triangles that at least two of their corners' stars hold, each
  once (no mesh knowledge; the consistency test of tangential Delaunay complexes).

Before them it counts the touching points (``real_corpus.touching``'s, at ``--detour``) whose
nearest point of another sheet is nearer than their own sheet's 3rd and 6th nearest (a star
needs about six), and the cloud's normals against the mesh's there and elsewhere; after them,
the default's and robust-laplacian's eigenvalues matched to the
mesh's own cotangent modes by eigenvector (M-overlap of at least 0.9), where index-by-index
errors mislead: a pencil missing the reference's λ₂ is compared with its λ₃ from there on.
Last, the mesh's first three modes read in the default's cloud pencil: each one's Rayleigh
quotient, the share of it on the pencil's edges between sheets (``--detour`` as above) and the
quotient without those edges, which says whether those edges alone carry the error. Then what
robust-laplacian's pencil is made of where it leads: both pencils' masses over the mesh's area,
each pencil's error without its edges between sheets, and each stiffness with the other's mass.

It holds the mesh distances of all pairs (n² doubles): meant for meshes up to about 10,000
vertices (the cow: 2,903).
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

sys.path.insert(0, str(Path(__file__).resolve().parent))
import igl  # noqa: E402
import real_corpus as rc  # noqa: E402
import robust_laplacian  # noqa: E402
from bench_real import REF_VERSION, pct  # noqa: E402
from scipy.sparse.linalg import eigsh  # noqa: E402

import meshlap  # noqa: E402
import meshlap.geometry.pointcloud as pointcloud  # noqa: E402
from meshlap import fem  # noqa: E402


def mesh_distances(V: np.ndarray, C: np.ndarray, reach: float) -> np.ndarray:
    """Shortest paths along the mesh's edges up to ``reach`` (inf beyond), all pairs."""
    e = np.concatenate([C[:, [a, b]] for a in range(C.shape[1]) for b in range(a + 1, C.shape[1])])
    e = np.unique(np.sort(e, axis=1), axis=0)
    length = np.linalg.norm(V[e[:, 0]] - V[e[:, 1]], axis=1)
    graph = sp.coo_matrix((length, (e[:, 0], e[:, 1])), shape=(len(V),) * 2).tocsr()
    return dijkstra(graph, directed=False, limit=reach)


def apart(D: np.ndarray, V: np.ndarray, a: np.ndarray, b: np.ndarray, detour: float) -> np.ndarray:
    """Which pairs (a, b) lie on two sheets: at least ``detour`` times farther along the mesh's
    edges (``D``) than through space."""
    return D[a, b] >= detour * np.linalg.norm(V[a] - V[b], axis=1)


def pencil_error(geo, k: int, ref: np.ndarray, n_parts: int) -> tuple[float, np.ndarray]:
    S, m = fem.fem_pencil(geo)
    lam = rc.pencil_eigs(-S, sp.diags(m), k)
    rel = (lam[n_parts:n_parts + 9] - ref[n_parts:n_parts + 9]) / ref[n_parts:n_parts + 9]
    return float(np.abs(rel).max()), rel


def other_sheet_nearer(V: np.ndarray, D: np.ndarray, detour: float, reach: int = 64
                       ) -> tuple[str, np.ndarray]:
    """Among the points with another sheet's point in their 16 nearest (returned): how many have
    one nearer than their own sheet's 3rd and 6th nearest."""
    dist, idx = pointcloud._neighbours(pointcloud.KDTree(V), V, reach)
    other = D[idx[:, :1], idx] >= detour * np.maximum(dist, 1e-300)
    other[:, 0] = False
    touch = np.flatnonzero(other[:, :17].any(axis=1))
    firsts = []
    for p in touch:
        own = dist[p][~other[p]][1:]
        firsts.append([dist[p][other[p]].min() < (own[r] if len(own) > r else np.inf) for r in (2, 5)])
    third, sixth = np.sum(firsts, axis=0) if firsts else (0, 0)
    return (f"{len(touch)} touching points; another sheet nearer than their own sheet's 6th nearest: "
            f"{sixth}, than its 3rd: {third}"), touch


def normal_angles(V: np.ndarray, C: np.ndarray, geo, touch: np.ndarray) -> str:
    """The cloud's normals (the geometry's, from its 16 nearest) against the mesh's vertex
    normals: the median angle at the touching points and at the others."""
    cos = np.abs(np.einsum("ij,ij->i", geo.normals(), igl.per_vertex_normals(V, C)))
    angle = np.degrees(np.arccos(np.clip(cos, 0.0, 1.0)))
    rest = np.setdiff1d(np.arange(len(V)), touch)
    at = f"{np.median(angle[touch]):.0f}° at the touching points" if len(touch) else "no touching points"
    return f"the cloud's normals against the mesh's: median {at}, {np.median(angle[rest]):.0f}° at the others"


def matched(K: sp.spmatrix, M: sp.spmatrix, ref: np.ndarray, U: np.ndarray, k: int) -> str:
    """Each eigenpair of (K, M) against the reference value of the mesh mode (a column of U) it
    overlaps most, where that M-overlap is at least 0.9."""
    lam, X = eigsh(sp.csc_matrix(K), k, sp.csc_matrix(M), sigma=-1e-8)
    out = []
    for i in range(1, k - 1):
        x = X[:, i] / np.sqrt(X[:, i] @ (M @ X[:, i]))
        overlap = np.abs(U.T @ (M @ x))
        j = int(overlap.argmax())
        near = overlap[j] >= 0.9
        out.append(f"λ{i}→ref λ{j} {100 * (lam[i] / ref[j] - 1):+.0f}%" if near else f"λ{i}: mixed")
    return ", ".join(out)


def without(K: sp.spmatrix, D: np.ndarray, V: np.ndarray, detour: float) -> tuple[sp.csr_matrix, int]:
    """The stiffness K (rows summing to zero) without its edges between sheets (mesh detour ≥
    ``detour`` × their length), its diagonal made up again; and how many edges that cut."""
    A = sp.triu(K, 1).tocoo()
    cross = apart(D, V, A.row, A.col, detour)
    W = sp.coo_matrix((-A.data[~cross], (A.row[~cross], A.col[~cross])), shape=K.shape)
    W = (W + W.T).tocsr()
    return sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W, int(cross.sum())


def lead(K: sp.spmatrix, M: sp.spmatrix, S: sp.spmatrix, m: np.ndarray, area: float, D: np.ndarray,
         V: np.ndarray, detour: float, error) -> str:
    """What robust-laplacian's pencil (K, M) holds that the default's (-S, m) does not: both
    masses against the mesh's area, each pencil without its edges between sheets, and each
    stiffness with the other's mass (``error``: a pencil's spectrum error)."""
    Kc, cut = without(K, D, V, detour)
    Sc, cut_s = without(-S, D, V, detour)
    return "\n".join([
        f"masses over the mesh's area: robust-laplacian {M.diagonal().sum() / area:.3f}, default "
        f"{m.sum() / area:.3f}",
        f"without their edges between sheets: robust-laplacian {pct(error(Kc, M))} ({cut} cut), default "
        f"{pct(error(Sc, sp.diags(m)))} ({cut_s} cut)",
        f"robust-laplacian's stiffness with the default's mass {pct(error(K, sp.diags(m)))}, the "
        f"default's stiffness with robust-laplacian's mass {pct(error(-S, M))}"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("name", nargs="?", default="cow", help="a mesh of benchmarks/corpus.toml")
    ap.add_argument("--corpus", default=None)
    ap.add_argument("--detour", type=float, default=4.0)
    ap.add_argument("--pool", type=int, default=10, help="same-sheet neighbours among pool × 16 nearest")
    args = ap.parse_args()
    folder = rc.corpus_dir(args.corpus)
    entry = next(e for e in rc.manifest() if e["name"] == args.name)
    mesh = rc.load(folder / entry["file"], entry["format"])
    V, C = np.asarray(mesh.Vw, dtype=np.float64), mesh.Cw
    n_parts = rc.parts(C, len(V))
    k = 10 + n_parts
    cache = json.loads((folder / "reference-cache.json").read_text())
    ref = np.array(cache[f"{entry['sha256']}:k{k}:v{REF_VERSION}"]["ref"])
    D = mesh_distances(V, C, 60 * rc.mean_edge(V, C))
    show = lambda label, r: print(f"{label:34s} {100 * r[0]:6.1f}%   λ1..λ9: "  # noqa: E731
                                  + " ".join(f"{100 * x:+.1f}" for x in r[1]))
    warnings.simplefilter("ignore")
    counts, touch = other_sheet_nearer(V, D, args.detour)
    print(counts)
    L, M = robust_laplacian.point_cloud_laplacian(V)
    lam = rc.pencil_eigs(L, M, k)
    rel = (lam[n_parts:n_parts + 9] - ref[n_parts:n_parts + 9]) / ref[n_parts:n_parts + 9]
    show("robust-laplacian", (float(np.abs(rel).max()), rel))
    geo = meshlap.geometry.point_cloud_geometry(V)
    show("default", pencil_error(geo, k, ref, n_parts))
    print(normal_angles(V, C, geo, touch))
    stars, weight = geo._cache["fem_cells"]  # the default's star triangles, each a third

    # 1. stars from same-sheet neighbours
    plain = pointcloud._neighbours
    short = []

    def same_sheet(tree, Q, K):
        dist, idx = plain(tree, Q, min(args.pool * K, len(V) - 1))  # a small cloud has fewer
        other = D[idx[:, :1], idx] >= args.detour * np.maximum(dist, 1e-300)
        other[:, 0] = False
        short.append(int(((~other).sum(axis=1) <= K).sum()))
        order = np.argsort(other, axis=1, kind="stable")[:, :K + 1]
        return np.take_along_axis(dist, order, 1), np.take_along_axis(idx, order, 1)

    pointcloud._neighbours = same_sheet
    try:
        same = meshlap.geometry.point_cloud_geometry(V)
        show(f"same-sheet neighbours ({max(short)} filled)", pencil_error(same, k, ref, n_parts))
    finally:
        pointcloud._neighbours = plain

    # 2. the triangles that cross between sheets cut
    cross = np.zeros(len(stars), dtype=bool)
    for i, j in ((0, 1), (1, 2), (0, 2)):
        cross |= apart(D, V, stars[:, i], stars[:, j], args.detour)
    alone = np.bincount(stars[~cross].ravel(), minlength=len(V)) == 0
    geo._cache["fem_cells"] = (stars[~cross | alone[stars[:, 0]]], weight)
    show(f"cross triangles cut ({int(alone.sum())} kept)", pencil_error(geo, k, ref, n_parts))

    # 3. the triangles two or three stars agree on, each once
    tri, count = np.unique(np.sort(stars, axis=1), axis=0, return_counts=True)
    geo._cache["fem_cells"] = (tri[count >= 2], 1.0)
    show("agreed triangles", pencil_error(geo, k, ref, n_parts))

    # 4. robust-laplacian and the default matched by eigenvector to the mesh's cotangent modes
    cot, U = eigsh(sp.csc_matrix(-igl.cotmatrix(V, C)), len(ref),
                   sp.csc_matrix(igl.massmatrix(V, C, igl.MASSMATRIX_TYPE_VORONOI)), sigma=-1e-8)
    print("matched by eigenvector (M-overlap with the mesh's cotangent modes ≥ 0.9; their values "
          f"within {100 * np.abs(cot[1:] / ref[1:] - 1).max():.1f}% of the reference's):")
    print("  robust-laplacian:", matched(L, M, ref, U, 7))
    geo._cache["fem_cells"] = (stars, weight)
    S, m = fem.fem_pencil(geo)
    print("  default:         ", matched(-S, sp.diags(m), ref, U, 7))
    print(between_sheets(-S, m, U, cot, D, V, args.detour, "the default's pencil"))
    print(lead(L, M, S, m, float(igl.doublearea(V, C).sum() / 2), D, V, args.detour,
               lambda K, Mk: rc.spectrum_error(rc.pencil_eigs(K, Mk, k), ref, n_parts)))
    S, m = fem.fem_pencil(same)
    print(between_sheets(-S, m, U, cot, D, V, args.detour / 2, "the same-sheet pencil"))


def between_sheets(K: sp.spmatrix, m: np.ndarray, U: np.ndarray, cot: np.ndarray, D: np.ndarray,
                   V: np.ndarray, detour: float, name: str) -> str:
    """The mesh's first modes in the cloud pencil (K, m): each one's Rayleigh quotient, the share
    of its energy on the pencil's edges between sheets (mesh detour ≥ ``detour`` × their length),
    and its quotient without them."""
    A = sp.triu(K, 1).tocoo()
    w = -A.data
    cross = apart(D, V, A.row, A.col, detour)
    out = [f"the mesh's modes in {name} ({int(cross.sum())} of its {len(w)} edges with a detour "
           f"≥ {detour:g}):"]
    for j in (1, 2, 3):
        u = U[:, j]
        energy = w * (u[A.row] - u[A.col]) ** 2
        mass = u @ (m * u)
        out.append(f"  λ{j} {cot[j]:.4g}: Rayleigh quotient {energy.sum() / mass:.4g}, "
                   f"{energy[cross].sum() / energy.sum():.0%} of it between sheets, "
                   f"{energy[~cross].sum() / mass:.4g} without")
    return "\n".join(out)


if __name__ == "__main__":
    main()
