"""Belkin–Sun–Wang's point: on a noisy mesh the heat-kernel Laplacian still converges,
the cotangent Laplacian does not. Writes a log-log plot.

    python examples/noisy_sphere.py [OUT_DIR]     # writes OUT_DIR/noisy_sphere.png (default: here)
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402

import meshlap  # noqa: E402
from meshlap.baselines import cotangent  # noqa: E402
from meshlap.plot import plot_convergence, slope  # noqa: E402

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(".")
out.mkdir(parents=True, exist_ok=True)
f, lap = meshlap.shapes.sphere_functions()["x^2"]
ns = [500, 1000, 2000, 4000]
errors = {"BSW (h = 0.01)": [], "COT": []}
for n in ns:
    # every vertex moved off the unit sphere by 5% of the mean edge; score at its projection
    V, F = meshlap.shapes.sphere(n, kind="noisy", seed=0)
    U = V / np.linalg.norm(V, axis=1, keepdims=True)
    bsw = meshlap.laplacian(V, F, h=0.01, correction="none")
    for name, op in [("BSW (h = 0.01)", bsw), ("COT", cotangent(V, F))]:
        e = op @ f(U) - lap(U)
        errors[name].append(np.linalg.norm(e) / np.linalg.norm(lap(U)))

print("normalized L2 error of L x² on a noisy unit sphere")
print("n       " + "".join(f"{name:>16}" for name in errors))
for i, n in enumerate(ns):
    print(f"{n:<8}" + "".join(f"{errors[name][i]:16.4f}" for name in errors))
ax = plot_convergence(ns, errors, ylabel="‖Lf − Δf‖₂ / ‖Δf‖₂", title="f = x² on a noisy sphere")
png = out / "noisy_sphere.png"
ax.figure.savefig(png, dpi=100, bbox_inches="tight")
print(f"wrote {png}")
assert slope(ns, errors["BSW (h = 0.01)"]) < -0.3 < 0 < slope(ns, errors["COT"])
