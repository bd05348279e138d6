"""The ``meshlap distance`` subcommand: geodesic distance by the heat method from the shell.

Kept beside :mod:`meshlap.cli`, which hands it its shared options and its operator reader.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .errors import MeshError

__all__ = ["add_distance_parser", "cmd_distance", "save_values"]


def save_values(path: str, values: np.ndarray) -> None:
    """Write per-vertex values (one column per field) to .npy, or as comma-separated text."""
    out = Path(path)
    if out.suffix.lower() == ".npy":
        np.save(out, values)
    else:
        np.savetxt(out, values, delimiter=",")
    print(f"wrote {out}")


def cmd_distance(args: argparse.Namespace, operator_from: Callable[[argparse.Namespace], Any]) -> int:
    """Distance from ``--source`` vertices; print a summary, save and draw it on request."""
    import time

    from .geodesics import HeatDistance

    if args.output and Path(args.output).suffix.lower() not in (".npy", ".txt", ".csv"):
        raise MeshError(f"-o expects a .npy, .txt or .csv file; got {args.output!r}")
    if args.png and Path(args.png).suffix.lower() != ".png":
        raise MeshError(f"--png expects a file name ending in .png; got {args.png!r}")
    op, V, F = operator_from(args)
    if getattr(op, "geometry", None) is None:
        raise MeshError("distance needs the geometry: give a mesh or point cloud file")
    t0 = time.perf_counter()
    hd = HeatDistance(op, t=args.t)
    setup = time.perf_counter() - t0
    sources = np.asarray(args.source, dtype=np.int64)
    t0 = time.perf_counter()
    d = hd.compute_many(sources, progress=args.progress or None) if args.each else hd.compute(sources)
    seconds = time.perf_counter() - t0
    far = d if d.ndim == 1 else d.min(axis=0)
    print(f"heat-method distance from vertex {', '.join(map(str, sources))} (t = {hd.t:.3g}; set-up "
          f"{setup:.2f} s, {seconds:.2f} s for {len(sources) if args.each else 1} field(s))")
    reached = np.isfinite(far)
    pct = np.percentile(far[reached], [50, 90, 100])
    print(f"median {pct[0]:.6g}, 90% {pct[1]:.6g}, max {pct[2]:.6g} at vertex "
          f"{int(np.flatnonzero(reached)[np.argmax(far[reached])])}")
    if not reached.all():
        print(f"{int((~reached).sum())} vertices lie on parts without a source or off the surface (a "
              "cloud's outliers): distance inf")
    if args.output:
        save_values(args.output, d.T)  # one column per source
    if args.png:
        if V is None:
            raise MeshError("--png needs the mesh: give a mesh or point cloud file")
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from .geometry.validation import check_faces
        from .plot import plot_mesh

        title = "geodesic distance"
        if not reached.all():  # the parts without a source are left out of the picture
            title += f" ({int((~reached).sum())} unreached vertices not drawn)"
            if F is not None:  # renumbered onto the reached vertices, so the axes span them alone
                tris = check_faces(F, len(V)).triangles()
                F = np.cumsum(reached)[tris[reached[tris].all(axis=1)]] - 1
            V, far = V[reached], far[reached]
        ax = plot_mesh(V, F, far, title=title, up=args.up)
        ax.figure.savefig(args.png, dpi=110, bbox_inches="tight")
        plt.close(ax.figure)
        print(f"wrote {args.png}")
    return 0


def add_distance_parser(sub: Any, shared: Callable[[argparse.ArgumentParser], None],
                        operator_from: Callable[[argparse.Namespace], Any]) -> None:
    """Add ``distance`` to the subcommands ``sub``; ``shared`` adds the kernel, up and progress options."""
    p = sub.add_parser("distance", help="geodesic distance from source vertices (heat method)",
                       description="Geodesic distance from --source vertices by the heat method (Crane et "
                                   "al. 2013) with the operator of a mesh, point cloud, curve or volume.")
    p.add_argument("input", help="mesh, point cloud, curve or volume file")
    p.add_argument("--source", type=int, nargs="+", required=True, metavar="V",
                   help="source vertex index (several: the distance to the nearest)")
    p.add_argument("--each", action="store_true",
                   help="one distance field per source (rows of a distance matrix) instead of the nearest")
    p.add_argument("--t", type=float, default=None, help="heat time (default: the mean spacing squared)")
    p.add_argument("--denoise", action=argparse.BooleanOptionalAction, default=None,
                   help="--denoise: the distance on the surface the input is a noisy sample of, whatever "
                        "the noise reads (meshlap.laplacian's denoise=True; a point cloud's projection); "
                        "--no-denoise: the mesh as given; default: where it reads as noise (docs/uses.md)")
    p.add_argument("-o", "--output", help="save the distance to .npy, .txt or .csv")
    p.add_argument("--png", help="draw the distance on the mesh into this PNG")
    shared(p)
    p.set_defaults(func=lambda args: cmd_distance(args, operator_from))
