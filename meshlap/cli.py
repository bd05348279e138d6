"""The ``meshlap`` command: inspect a mesh, build and save its operator, and run the
library's main jobs from the shell.

Every subcommand has ``--help``. Bad input (a missing file, a mesh that cannot be used, a
bad argument) ends with a one-line message on stderr and a non-zero exit status: 1 for
errors in the input, 2 for command-line usage errors.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .cli_uses import add_distance_parser, save_values
from .errors import EigenError, MeshError
from .geometry.validation import check_faces
from .io import MESH_FORMATS, load_operator, save_operator
from .plot import plot_functions, plot_mesh  # matplotlib is imported where a figure is drawn
from .viewer import save_html, show

__all__ = ["main"]

PROG = "meshlap"
#: What info, build, eigs and curvature read (meshio adds its formats: pip install "meshlap[io]").
INPUTS = ("surfaces (.obj .off .ply .stl .vtk; .vtp by pyvista, .glb by trimesh), point clouds (.ply without "
          "faces, .pcd .xyz .csv .txt .pts .npy), tetrahedra (TetGen .node/.ele; .vtu .msh by meshio)")


# -- helpers ----------------------------------------------------------------------------
def _face_summary(F: Any, n: int) -> str:
    sizes, counts = np.unique(check_faces(F, n).sizes, return_counts=True)
    names = {3: "triangles", 4: "quads"}
    return ", ".join(f"{c:,} {names.get(int(s), f'{s}-gons')}" for s, c in zip(sizes, counts, strict=True))


#: What each kind of input is called, and the name of its measure (the sum of the masses).
_KINDS = {1: ("curve", "length"), 2: ("surface", "surface area"), 3: ("volume", "volume")}


def _read(args: argparse.Namespace) -> tuple[np.ndarray, Any, int | None]:
    """``(points, cells, k)`` of ``args.input``: a surface, a point cloud, a curve or a volume."""
    from .inputs import read_input

    return read_input(args.input)


def _build(args: argparse.Namespace, V: np.ndarray, F: Any, k: int | None = 2) -> Any:
    from .builders import laplacian, point_cloud_laplacian

    dtype = np.float32 if getattr(args, "float32", False) else np.float64
    # the library's default operator (the one notebooks and scripts get), unless --correction
    options = {"h": args.h, "tol": args.tol, "dtype": dtype, "correction": args.correction,
               "progress": getattr(args, "progress", False) or None}
    if getattr(args, "denoise", None) is not None:  # distance --denoise / --no-denoise
        options["denoise"] = args.denoise
    if F is None:
        return point_cloud_laplacian(V, k=args.dim, **options)
    return laplacian(V, F, k=k, **options)


def _operator_from(args: argparse.Namespace) -> tuple[Any, np.ndarray | None, Any]:
    """The operator named by ``args.input`` (a saved .npz, or built from a geometry file), its
    points and what to draw them with (faces; the hull of a volume; None for clouds)."""
    if Path(args.input).suffix.lower() == ".npz":
        op = load_operator(args.input)
        return op, getattr(op, "V", None), getattr(op, "faces", None)
    V, cells, k = _read(args)
    return _build(args, V, cells, k), V, _drawn(cells, k)


def _drawn(cells: Any, k: int | None) -> Any:
    from .inputs import boundary_triangles

    if k == 3:
        return boundary_triangles(cells)
    return cells if k == 2 else None


def _surface_only(cells: Any, k: int | None, what: str) -> None:
    if cells is None or k != 2:
        kind = "point cloud" if cells is None else _KINDS[k][0]
        raise MeshError(f"{what} needs a surface mesh; this input is a {kind}")


def _table(rows: Sequence[tuple[str, str]]) -> str:
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in rows)


def _need_suffixes(args: argparse.Namespace) -> None:
    for option, suffix in (("png", ".png"), ("html", ".html")):
        path = getattr(args, option)
        if path is not None and Path(path).suffix.lower() != suffix:
            raise MeshError(f"--{option} expects a file name ending in {suffix}; got {path!r}")


def _save_png(fig: Any, path: str) -> None:
    import matplotlib.pyplot as plt

    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    print(f"wrote {path}")


def _use_agg() -> None:
    # Figures are only ever written to files here; never open a window.
    try:
        import matplotlib
    except ImportError as exc:
        raise ImportError('writing figures needs matplotlib: pip install "meshlap[plot]"') from exc
    matplotlib.use("Agg")


# -- subcommands ------------------------------------------------------------------------
def cmd_info(args: argparse.Namespace) -> int:
    """Describe a mesh (or a saved operator), what the default builds from it, and its cost."""
    if Path(args.input).suffix.lower() == ".npz":
        op = load_operator(args.input)
        rows = [("file", str(args.input)), ("operator", _chosen(op)), ("vertices", f"{op.n_vertices:,}")]
        if op.h is not None:
            rows += [("h", f"{op.h:.6g}"), ("tol", f"{op.tol:.3g}"), ("radius", f"{op.radius:.6g}")]
        rows += [
            ("nnz", f"{op.nnz:,} ({op.nnz / op.n_vertices:.1f} per row)"),
            ("memory", f"{op.nbytes / 2**20:.1f} MiB ({op.L.dtype})"),
            ("mesh stored", "yes" if hasattr(op, "V") else "no"),
        ]
        print(_table(rows))
        return 0
    from .geometry.topology import diagnose
    from .operator import MeshLaplacian

    V, cells, k = _read(args)
    op = _build(args, V, cells, k)  # the decision only: the pencil and the rows come on first use
    geo, decision = op.geometry, op.decision
    bbox = V.max(axis=0) - V.min(axis=0)
    kind, measure = _KINDS[geo.dim]
    rows = [("file", str(args.input)), ("points" if cells is None else "vertices", f"{len(V):,}")]
    rows.append(("kind", f"point cloud (k={geo.dim}, --dim)") if cells is None else
                ("faces", _face_summary(cells, len(V))) if k == 2 else
                ("cells", f"{len(cells):,} {'tetrahedra' if k == 3 else 'edges'} ({kind})"))
    if cells is None and "parts" in decision.measured:  # a mesh's come in its diagnosis below
        rows.append(("parts", f"{decision.measured['parts']:,} (pieces its points' stars join)"))
    rows += [
        (measure, f"{geo.mass.sum():.6g}"),
        ("bounding box", " x ".join(f"{b:.4g}" for b in bbox)),
        ("operator", _chosen(op)),
        ("why", decision.reason),
        ("eigs solves", f"{decision.elements} elements (spectral.eigs)"),
        ("h", dict(op._summary())["h"]),  # the kernel's width, as the operator's repr gives it
        ("tol, radius", f"{op.tol:.3g}, {op.radius:.6g}"),
    ]
    if decision.operator == "fem":  # linear FEM's pencil: cheap, so counted exactly
        nnz, what = op.assemble().nnz, "nnz of S"
    else:  # the kernel's: estimated from a sample of rows, without assembling it
        probe = MeshLaplacian(geo, h=op.h, tol=op.tol, matrix_free=True, correction="none")
        nnz, what = probe.estimate_nnz(), "nnz of S ≈"
    rows.append((what, f"{nnz:,} ({nnz / len(V):.1f} per row), {nnz * 12 / 2**20:.1f} MiB in float64"))
    print(_table(rows))
    if k == 2 and cells is not None:
        print(diagnose(V, cells))
    return 0


def _chosen(op: Any) -> str:  # what the policy built, by the names laplacian's operator= takes
    d = getattr(op, "decision", None)
    return op.name if d is None else f"{d.built} (op.decision)"


def cmd_build(args: argparse.Namespace) -> int:
    """Build the operator of a mesh and save it as .npz."""
    V, cells, k = _read(args)
    out = Path(args.output) if args.output else Path(Path(args.input).stem + ".npz")
    op = _build(args, V, cells, k)
    path = save_operator(out, op, mesh=not args.no_mesh)
    print(op)
    print(f"wrote {path} ({path.stat().st_size / 2**20:.1f} MiB)")
    return 0


def cmd_eigs(args: argparse.Namespace) -> int:
    """The k smallest eigenpairs of -S φ = λ M φ; print them, optionally save and draw."""
    import time

    from .spectral import eigs

    _need_suffixes(args)
    op, V, F = _operator_from(args)
    t0, info = time.perf_counter(), {}
    lam, phi = eigs(op, args.k, elements=args.elements, info=info)
    seconds = time.perf_counter() - t0
    columns = {f"{d.operator}, {info['elements']}" if (d := getattr(op, "decision", None)) else op.name: lam}
    if args.compare_cot:
        if getattr(op, "faces", None) is None:
            raise MeshError("--compare-cot needs a surface mesh: a mesh file or an operator saved with it")
        from .baselines import cotangent

        columns["COT"] = eigs(cotangent(V, op.faces), args.k)[0]
    print(f"{args.k} smallest eigenvalues of -L (-S φ = λ M φ; φ M-orthonormal), {seconds:.1f} s:")
    print(f"{'i':>4}" + "".join(f"{name:>16}" for name in columns))
    for i in range(args.k):
        # the constant eigenvector's λ is 0 to rounding: print it as 0
        cells = [0.0 if abs(col[i]) < 1e-10 * max(abs(col[-1]), 1.0) else col[i] for col in columns.values()]
        print(f"{i:>4}" + "".join(f"{v:>16.6g}" for v in cells))
    if args.output:
        np.savez(args.output, eigenvalues=lam, eigenvectors=phi)
        print(f"wrote {args.output}")
    if args.html:
        if V is None:
            raise MeshError("--html needs the mesh: give a mesh file or an operator saved with it")
        shown = list(range(1, args.k))  # skip the constant eigenvector
        plot = show(V, F, phi[:, shown], titles=[f"φ{i}  λ = {lam[i]:.4g}" for i in shown], cmap="RdBu_r",
                    symmetric=True, up=args.up)
        print(f"wrote {save_html(plot, args.html)}")
    if args.png:
        if V is None:
            raise MeshError("--png needs the mesh: give a mesh file or an operator saved with it")
        _use_agg()
        drawn = list(range(1, min(args.k, 9)))  # skip the constant eigenvector
        fig = plot_functions(V, F, phi[:, drawn], titles=[f"φ{i}, λ = {lam[i]:.4g}" for i in drawn],
                             up=args.up)
        _save_png(fig, args.png)
    return 0


def cmd_smooth(args: argparse.Namespace) -> int:
    """Smooth a surface by implicit mean curvature flow and write the result."""
    from .progress import make_progress
    from .smoothing import mean_curvature_flow
    from .widths import default_h

    V, F, k = _read(args)
    _surface_only(F, k, "smooth")
    out = Path(args.output)
    if out.suffix.lower() not in MESH_FORMATS:
        raise MeshError(f"--output must end in one of {', '.join(MESH_FORMATS)}; got {out.name!r}")
    report = make_progress(args.progress or None)
    if args.dt is None and args.h is None and not (args.cot or args.fixed):
        # the library's default: denoise relative to the fitted surface, dt from the measured noise
        if report is not None:
            report(0.0, "smooth")
        W, info = mean_curvature_flow(V, F, steps=args.steps, keep_volume=args.keep_volume)
        if report is not None:
            report(1.0, "done")
        print(f"{len(info['volume']) - 1} denoising mean-curvature-flow step(s) of dt = 4σ² = "
              f"{info['dt']:.4g} (measured normal noise σ = {info['noise']:.4g})" if info["dt"] else
              "no step: the mesh reads as clean (op.decision.denoise; --dt gives the plain flow)")
        return _smoothed(V, W, F, info["volume"], out)
    # (mean edge)² for both: the operator damps frequencies up to about 1/h, and a step of
    # dt = h halves the components at that scale, i.e. noise at the scale of the edges
    h = default_h(V, F) / 4 if args.h is None else args.h
    dt = h if args.dt is None else args.dt
    args.steps = 3 if args.steps is None else args.steps
    kwargs: dict[str, Any] = {"keep_volume": args.keep_volume}
    if args.cot:
        from .baselines import cotangent

        kwargs["laplacian"] = lambda P, Q: cotangent(P, Q)
    else:
        kwargs["laplacian"] = lambda P, Q: _laplacian(P, Q, h, args.tol)
    if args.fixed or report is None:
        W, info = mean_curvature_flow(V, F, dt, args.steps, rebuild=not args.fixed, **kwargs)
        volumes = info["volume"]
    else:  # one step at a time, to report progress
        W, volumes = V, [None]
        for i in range(args.steps):
            report(i / args.steps, "smooth")
            W, info = mean_curvature_flow(W, F, dt, 1, **kwargs)
            volumes[-1:] = list(info["volume"])
        report(1.0, "done")
    print(f"{args.steps} implicit mean-curvature-flow step(s) of dt = {dt:.4g} with "
          f"{'COT' if args.cot else f'BSW (h = {h:.4g})'}{', operator held fixed' if args.fixed else ''}")
    return _smoothed(V, W, F, volumes, out)


def _smoothed(V: np.ndarray, W: np.ndarray, F: Any, volumes: list, out: Path) -> int:
    """Report how far the vertices moved and the volume, then write the smoothed mesh."""
    from .io import write_mesh

    move = np.linalg.norm(W - V, axis=1)
    print(f"vertex displacement: mean {move.mean():.4g}, max {move.max():.4g} "
          f"(bounding box diagonal {np.linalg.norm(np.ptp(V, axis=0)):.4g})")
    v0, v1 = volumes[0], volumes[-1]
    if v0 and np.isfinite(v0) and v0 != 0:
        print(f"enclosed volume: {v0:.6g} -> {v1:.6g} ({v1 / v0 - 1:+.2%})")
    write_mesh(out, W, F)
    print(f"wrote {out}")
    return 0


def _laplacian(V: np.ndarray, F: Any, h: float, tol: float) -> Any:
    from .builders import laplacian

    # smoothing is a filter at the scale of the edges: the paper's operator is the one wanted
    return laplacian(V, F, h=h, tol=tol, correction="none")


def cmd_curvature(args: argparse.Namespace) -> int:
    """Mean curvature per vertex from ΔX = -2H n; print a summary, optionally save and draw."""
    from .curvature import mean_curvature, mean_curvature_normal

    _need_suffixes(args)
    if args.output and Path(args.output).suffix.lower() not in (".npy", ".txt", ".csv"):
        raise MeshError(f"--output must end in .npy, .txt or .csv; got {args.output!r}")
    V, F, k = _read(args)
    if k != 2 and F is not None:
        raise MeshError(f"curvature needs a surface or a point cloud sampled from one; this input is a "
                        f"{_KINDS[k][0]}")
    op = _build(args, V, F, k)
    # a cloud has no faces to orient normals by: the unsigned |H| = |L X| / 2
    H = np.linalg.norm(mean_curvature_normal(op, V), axis=1) if F is None else mean_curvature(op, V, F)
    rows = {"BSW": H}
    if args.compare_cot:
        from .baselines import cotangent

        _surface_only(F, k, "--compare-cot")
        rows["COT"] = mean_curvature(cotangent(V, F), V, F)
    what = "|H| (unsigned: a point cloud has no orientation)" if F is None else "H"
    print(f"mean curvature {what} (ΔX = -2H n; H = 1/R on a sphere of radius R), {len(V):,} points")
    print(f"{'':<6}{'min':>11}{'5%':>11}{'median':>11}{'95%':>11}{'max':>11}")
    for name, values in rows.items():
        q = np.nanpercentile(values, [0, 5, 50, 95, 100])
        print(f"{name:<6}" + "".join(f"{v:>11.4g}" for v in q))
    missing = int(np.isnan(H).sum())
    if missing:
        print(f"{missing:,} vertices in no face have no normal: H is NaN there")
    if args.output:
        save_values(args.output, H)
    lo, hi = np.nanpercentile(H, [2, 98])  # a few extreme vertices would wash out the rest
    if args.html:
        plot = show(V, F, np.nan_to_num(H, nan=float(np.nanmedian(H))), cmap="coolwarm", vmin=lo, vmax=hi,
                    up=args.up, titles=[f"mean curvature of {Path(args.input).name}"])
        print(f"wrote {save_html(plot, args.html)}")
    if args.png:
        _use_agg()
        ax = plot_mesh(V, F, np.nan_to_num(H, nan=float(np.nanmedian(H))), vmin=lo, vmax=hi,
                       cmap="coolwarm", up=args.up, title=f"mean curvature of {Path(args.input).name}")
        _save_png(ax.figure, args.png)
    return 0


def cmd_reproduce(args: argparse.Namespace) -> int:
    """The paper's Tables 1–4: markdown tables and a convergence plot in a folder."""
    from .reproduce import FULL_NS, QUICK_NS, run

    ns = tuple(args.ns) if args.ns else (QUICK_NS if args.quick else FULL_NS)
    _use_agg()
    command = "meshlap reproduce" + (" --quick" if args.quick else "") + (
        " --ns " + " ".join(map(str, ns)) if args.ns else "")
    rep = run(ns=ns, out_dir=args.out, quick=args.quick, progress=args.progress or None,
              seed=args.seed, command=command)
    print(rep.markdown)
    for f in rep.files:
        print(f"wrote {f}")
    return 1 if (args.strict and not rep.ok) else 0


#: The sphere tables ``meshlap demo`` prints: our table, the error field in the paper's metric,
#: the paper's table number and the title.
_DEMO_TABLES = (
    ("uniform", "abs_linf", 3, "uniform sphere, max |Lf − Δf|  (Table 3; absolute, as in the paper)"),
    ("noisy", "l2", 4, "noisy sphere, ‖Lf − Δf‖₂ / ‖Δf‖₂  (Table 4)"),
)


def _trend(e: np.ndarray) -> str:
    # within ±20% from first to last counts as flat: COT's L∞ error on the uniform sphere
    ratio = e[-1] / e[0]
    return "falling" if ratio < 0.8 else ("rising" if ratio > 1.25 else "flat")


def cmd_demo(args: argparse.Namespace) -> int:
    """The paper's sphere experiment on built-in meshes, in seconds; no files needed."""
    import time

    from .reproduce import SPHERE_H, run

    t0 = time.perf_counter()
    rep = run(ns=args.ns, quick=True, plane_h=(), sphere_kinds=("uniform", "noisy"),
              progress=args.progress or None, variants=False)
    print("Belkin–Sun–Wang heat-kernel Laplacian (BSW) against the cotangent Laplacian (COT)")
    print(f"on unit spheres with n vertices, h = {SPHERE_H:g}: errors of L f against the exact Δf,")
    print("with the paper's published value and the ratio ours/paper where the paper has this n.")
    cells = [f"n = {n:,}" for n in rep.ns]
    for table, norm, paper_table, title in _DEMO_TABLES:
        print(f"\n{title}")
        print(f"  {'function':<9}{'method':<11}" + "".join(f"{c:>12}" for c in cells) + "  trend")
        for fn in dict.fromkeys(r.function for r in rep.select(table=table)):
            for method in ("BSW", "COT"):
                e = rep.errors(table, fn, method, norm)
                print(f"  {fn if method == 'BSW' else '':<9}{method:<11}" + "".join(f"{v:>12.4f}" for v in e)
                      + f"  {_trend(e)}")
                paper = {b.paper.n: b for b in rep.beside if not b.variant and
                         (b.paper.table, b.paper.function, b.paper.method) == (paper_table, fn, method)}
                if paper:
                    print(f"  {'':<9}{'paper':<11}" + "".join(
                        f"{paper[n].paper.error:>12g}" if n in paper else f"{'–':>12}" for n in rep.ns))
                    print(f"  {'':<9}{'ours/paper':<11}" + "".join(
                        f"{paper[n].ratio:>12.3g}" if n in paper else f"{'–':>12}" for n in rep.ns))
    print("\nClaims of the paper checked on these numbers:")
    for c in rep.checks:
        print(f"  [{'ok' if c.holds else 'FAIL'}] {c.claim}")
    print(f"\n{time.perf_counter() - t0:.1f} s. All four tables and a plot: meshlap reproduce --out DIR")
    return 0


# -- the parser -------------------------------------------------------------------------
def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer; got {text!r}") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive integer; got {value}")
    return value


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number; got {text!r}") from None
    if not np.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive number; got {value}")
    return value


def _kernel_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--h", type=_positive_float, default=None,
                   help="kernel width h (exp(-d²/4h)): the corrected kernel at that width, not the default")
    p.add_argument("--tol", type=float, default=None,
                   help="kernel tolerance: weights below it are dropped (default 1e-6 corrected, "
                        "1e-8 on curves and with --correction none; 0 = exact)")
    p.add_argument("--correction", choices=("richardson", "none"), default=None,
                   help="the kernel, not meshlap.laplacian's default (linear FEM on a mesh's cells): "
                        "richardson (the O(h) bias removed) or none (the paper's operator)")
    p.add_argument("--dim", type=int, choices=(1, 2, 3), default=2,
                   help="intrinsic dimension of a point cloud: 1 curve, 2 surface (default), 3 volume")


def _up_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--up", choices=("auto", "x", "y", "z", "-x", "-y", "-z"), default="auto",
                   help="the up direction in --png (default auto: the side the mesh stands on, "
                        "as meshlap.plot.up_axis finds it)")


def _progress_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--progress", action="store_true", help="draw a progress bar on stderr")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``meshlap`` command (all subcommands)."""
    from . import __version__

    parser = argparse.ArgumentParser(
        prog=PROG,
        description="The Belkin–Sun–Wang heat-kernel mesh Laplacian (SoCG 2008) from the shell. "
                    f"Inputs: {INPUTS}; operators: .npz written by 'meshlap build'.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    p = sub.add_parser("info", help="describe a mesh, point cloud, volume or saved operator",
                       description="Print a mesh's size and area, what meshlap.laplacian builds from it and "
                                   "why (op.decision), its pencil's size and a diagnosis (boundaries, ...).")
    p.add_argument("input", help="mesh, point cloud or volume file, or an operator .npz")
    _kernel_options(p)
    p.set_defaults(func=cmd_info)

    p = sub.add_parser("build", help="build the operator of a mesh and save it (.npz)",
                       description="Build L, M and the kernel parameters and save them as .npz "
                                   "(scipy.sparse.load_npz reads L; meshlap.io.load_operator reads all).")
    p.add_argument("input", help="mesh, point cloud or volume file")
    p.add_argument("-o", "--output", help="output .npz (default: the mesh's name with .npz, here)")
    _kernel_options(p)
    p.add_argument("--float32", action="store_true", help="store the values in float32 (half the memory)")
    p.add_argument("--no-mesh", action="store_true", help="do not store the vertices and faces")
    _progress_option(p)
    p.set_defaults(func=cmd_build)

    p = sub.add_parser("eigs", help="the smallest eigenvalues and eigenfunctions",
                       description="Compute the k smallest eigenpairs of -S φ = λ M φ (λ ≥ 0, φ "
                                   "M-orthonormal) of a mesh's operator, or of a saved one.")
    p.add_argument("input", help="mesh, point cloud or volume file, or an operator .npz from 'meshlap build'")
    p.add_argument("-k", type=_positive_int, default=10, help="number of eigenpairs (default 10)")
    p.add_argument("--elements", choices=["auto", "linear", "quadratic"], default="auto",
                   help="what to solve: the operator's pencil (linear) or, on a mesh, quadratic elements on "
                        "its triangles (default: the operator's choice, op.elements)")
    _kernel_options(p)
    p.add_argument("-o", "--output", help="save eigenvalues and eigenvectors to this .npz")
    p.add_argument("--png", help="draw the first eigenfunctions on the surface into this PNG")
    p.add_argument("--html", help="an interactive view of the eigenfunctions: standalone HTML (needs k3d)")
    _up_option(p)
    p.add_argument("--compare-cot", action="store_true",
                   help="also print the cotangent Laplacian's eigenvalues on the same mesh")
    _progress_option(p)
    p.set_defaults(func=cmd_eigs)

    p = sub.add_parser("smooth", help="smooth a surface by mean curvature flow",
                       description="Implicit mean curvature flow; writes the mesh. By default the "
                                   "denoising flow of smoothing.mean_curvature_flow (relative to the "
                                   "fitted surface, dt from the measured noise); with --dt, --h, --cot "
                                   "or --fixed the plain flow (M - dt S) X' = M X, the operator rebuilt "
                                   "from the moving surface at every step unless --fixed.")
    p.add_argument("input", help="mesh file")
    p.add_argument("-o", "--output", required=True, help="output mesh (.obj, .off, .ply or .stl)")
    p.add_argument("--dt", type=_positive_float,
                   help="time step of the plain flow (default: the denoising flow, dt = 4σ² from the "
                        "measured noise σ; with --h, --cot or --fixed: dt = h)")
    p.add_argument("--steps", type=_positive_int, default=None,
                   help="number of steps (default 2 for the denoising flow, 3 for the plain one)")
    p.add_argument("--h", type=_positive_float, default=None,
                   help="kernel width h of the plain flow (default (mean edge length)²)")
    p.add_argument("--tol", type=float, default=1e-8, help="kernel tolerance (default 1e-8)")
    p.add_argument("--fixed", action="store_true", help="keep the first step's operator (a linear filter)")
    p.add_argument("--keep-volume", action="store_true", help="rescale after each step to keep the volume")
    p.add_argument("--cot", action="store_true", help="use the cotangent Laplacian instead")
    _progress_option(p)
    p.set_defaults(func=cmd_smooth)

    p = sub.add_parser("curvature", help="mean curvature per vertex",
                       description="Mean curvature H at every vertex from ΔX = -2H n with the "
                                   "heat-kernel operator; prints percentiles, saves or draws it.")
    p.add_argument("input", help="surface mesh or point cloud file")
    _kernel_options(p)
    p.add_argument("-o", "--output", help="save H to .npy, .txt or .csv")
    p.add_argument("--png", help="draw the mesh coloured by H into this PNG")
    p.add_argument("--html", help="an interactive view of H: standalone HTML (needs k3d)")
    _up_option(p)
    p.add_argument("--compare-cot", action="store_true", help="also summarize the cotangent estimate")
    _progress_option(p)
    p.set_defaults(func=cmd_curvature)

    p = sub.add_parser("reproduce", help="the paper's Tables 1–4 and a convergence plot",
                       description="Recompute Tables 1–4 of Belkin–Sun–Wang (plane and four spheres, BSW "
                                   "against COT) and write tables.md and convergence.png to --out.")
    p.add_argument("--quick", action="store_true",
                   help="n = 500, 1000, 2000 (seconds) instead of 500 ... 16,000")
    p.add_argument("--ns", type=_positive_int, nargs="+", metavar="N", help="vertex counts to use")
    p.add_argument("--out", type=Path, default=Path("meshlap-tables"),
                   help="folder for tables.md and convergence.png (default ./meshlap-tables)")
    p.add_argument("--seed", type=int, default=0, help="seed of every mesh")
    p.add_argument("--strict", action="store_true", help="exit with status 1 if a claim of the paper fails")
    _progress_option(p)
    p.set_defaults(func=cmd_reproduce)

    p = sub.add_parser("demo", help="the paper's sphere experiment in seconds (no files needed)",
                       description="Run the Belkin–Sun–Wang sphere experiment on built-in meshes and print "
                                   "BSW and COT errors as n grows.")
    p.add_argument("--ns", type=_positive_int, nargs="+", metavar="N", default=(500, 2000, 8000),
                   help="vertex counts (default 500 2000 8000)")
    _progress_option(p)
    p.set_defaults(func=cmd_demo)
    add_distance_parser(sub, lambda q: (_kernel_options(q), _up_option(q), _progress_option(q)),
                        _operator_from)
    return parser


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"{PROG}: warning: {message}", file=sys.stderr if file is None else file)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``meshlap`` command; returns the exit status.

    Examples
    --------
    >>> main(["info", "no-such-mesh.obj"])
    1
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version and usage errors
        return int(exc.code or 0)
    with warnings.catch_warnings():
        warnings.showwarning = _one_line_warning
        try:
            status = int(args.func(args) or 0)
            sys.stdout.flush()  # a closed pipe shows here, not at exit
            return status
        except BrokenPipeError:  # the reader stopped (| head): stop quietly, as cat does
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return 141
        except (MeshError, EigenError, OSError, ImportError, MemoryError) as exc:
            print(f"{PROG}: error: {exc}", file=sys.stderr)
            return 1
        except KeyboardInterrupt:
            print(f"{PROG}: interrupted", file=sys.stderr)
            return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
