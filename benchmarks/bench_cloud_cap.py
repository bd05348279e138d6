"""How far the curvature cap may narrow a cloud's kernel: the floor of meshlap.tuned.CLOUD_CAP_FLOOR.

    python benchmarks/bench_cloud_cap.py          # printed, a markdown table

The kernel's default widths on a surface's point cloud (``operator="kernel"``),
h_w = min(4a², β/κ_w²), raised to at least f·4a² for f in ``FLOORS`` (f = 0: the cap alone;
f = 1: no cap) and passed as explicit per-point widths; largest relative error of eigenvalues
1-9 against the exact values, and robust-laplacian's ``point_cloud_laplacian`` on the same points.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_spectra as B  # noqa: E402

import meshlap  # noqa: E402
from meshlap import samples, spectral, widths  # noqa: E402

FLOORS = (0.0, 0.25, 0.5, 0.75, 1.0)


def clouds():
    torus, sphere = samples.torus_eigenvalues(B.K), B._sphere_exact()
    return [("torus, 1,000 random", samples.torus_points(1000), torus),
            ("torus, 1,000 jittered", samples.torus_points(1000, "jittered"), torus),
            ("sphere, 1,000 random", samples.sphere_points(1000, "random", seed=0), sphere),
            ("torus, 4,000 random", samples.torus_points(4000), torus),
            ("torus, 4,000 random, 1% noise", samples.torus_points(4000, noise=0.01), torus),
            ("sphere, 4,000 random, 1% noise", samples.sphere_points(4000, "noisy", seed=0), sphere)]


def main() -> int:
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()  # no options: --help
    print("| cloud | capped widths / 4a² (min-median) | " + " | ".join(f"floor {f:g}" for f in FLOORS)
          + " | robust-laplacian |")
    print("|---|---|" + "---|" * (len(FLOORS) + 1))
    for name, P, exact in clouds():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", meshlap.MeshWarning)
            geo = meshlap.geometry.point_cloud_geometry(P)
            h0 = widths.h_scale(geo) * geo.spacing**2
            floor, widths.CLOUD_CAP_FLOOR = widths.CLOUD_CAP_FLOOR, 0.0  # the cap alone
            capped = widths.choose(geo, None, plain=False, curvature_limit=meshlap.tuned.CURVATURE_LIMIT)
            capped = capped.per_point(len(P))
            widths.CLOUD_CAP_FLOOR = floor
            errors = []
            for f in FLOORS:
                op = meshlap.laplacian(geo, h=np.maximum(capped, f * h0))
                lam = spectral.eigs(op, B.K, tol=1e-6)[0]
                errors.append(float(np.abs(lam[1:] / exact[1:B.K] - 1).max()))
        peer = float(np.abs(B.robust_cloud(P)[1:] / exact[1:B.K] - 1).max())
        print(f"| {name} | {capped.min() / h0:.2f}-{np.median(capped) / h0:.2f} | "
              + " | ".join(f"{e:.2%}" for e in errors) + f" | {peer:.2%} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
