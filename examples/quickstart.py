"""Quickstart: read a mesh, build the Belkin–Sun–Wang operator, apply it, and compare it
with the cotangent Laplacian.

    python examples/quickstart.py [MESH]      # default: spot from tests/data
"""

import sys
from pathlib import Path

import numpy as np

import meshlap
from meshlap.baselines import cotangent
from meshlap.io import read_mesh

mesh = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "tests/data/spot.obj"
V, F = read_mesh(mesh)
print(f"{mesh.name}: {len(V):,} vertices, {len(F):,} faces")

op = meshlap.laplacian(V, F, correction="none")  # h from the mesh: (2 × mean edge length)²
print(op)

f = np.sin(3 * V[:, 1])  # any function on the vertices, or an (n, k) block of them
Lf = op @ f
print(f"L f for f = sin(3y): shape {Lf.shape}, values in [{Lf.min():.1f}, {Lf.max():.1f}]")
cot = cotangent(V, F)

# Both are Laplacians with L ≈ +Δ: constants are in the kernel, S = M L is symmetric and
# -fᵀ S f is the Dirichlet energy ∫|∇f|². The heat-kernel operator averages over a few
# rings of neighbours; as h shrinks its energy approaches the cotangent one. Point by point
# the two differ much more, because the cotangent values are noisy on spot's uneven
# triangles (notebooks/01-quickstart.ipynb draws both).
print(f"\nL·1 = 0: max |L 1| = {np.abs(op @ np.ones(len(V))).max():.1e}")
print(f"S symmetric: max |S - Sᵀ| = {abs(op.S - op.S.T).max():.1e}")
print(f"surface area: BSW mass {op.mass.sum():.4f}, Voronoi mass {cot.mass.sum():.4f}")
print("\nDirichlet energy -fᵀ S f of f = sin(3y):")
print(f"  COT              {-f @ (cot.S @ f):8.4f}")
for h in (op.h, op.h / 4, op.h / 16):
    op_h = meshlap.laplacian(V, F, h=h, correction="none")
    print(f"  BSW h = {h:.2e} {-f @ (op_h.S @ f):8.4f}")
