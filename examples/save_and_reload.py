"""Mesh I/O: read a polygon mesh, build its operator once, save it, and use it again later
(from meshlap or from plain scipy); meshes from trimesh-like objects.

    python examples/save_and_reload.py [OUT_DIR]     # default: a temporary folder
"""

import sys
import tempfile
from pathlib import Path

import numpy as np
import scipy.sparse as sp

import meshlap
from meshlap.io import as_mesh, load_operator, read_mesh, save_operator, write_mesh

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp())
out.mkdir(parents=True, exist_ok=True)
data = Path(__file__).resolve().parents[1] / "tests" / "data"

# Quads stay quads: each face gives Area(t)/4 to each of its corners.
V, F = read_mesh(data / "spot-quads.obj")
print(f"spot-quads: {len(V):,} vertices, faces {F.shape}")
op = meshlap.laplacian(V, F, h=0.004, correction="none")
path = save_operator(out / "spot-quads.npz", op)
print(f"saved {path.name}: {path.stat().st_size / 2**20:.1f} MiB, {op.nnz:,} entries")

again = load_operator(path)  # L, M, S, mass, h, tol, radius, and the mesh
f = np.cos(2 * V[:, 0]) * V[:, 2]
assert np.array_equal(again @ f, op @ f)
print(f"reloaded: {again!r}; op @ f is bit-for-bit the same")

L = sp.load_npz(path)  # plain scipy sees the matrix L
print(f"scipy.sparse.load_npz: {L.format} matrix {L.shape}, max |L - op.L| = {abs(L - op.L).max()}")


class Shape:
    """Anything with vertices and faces works, e.g. trimesh.Trimesh (not needed here)."""

    def __init__(self, vertices, faces):
        self.vertices, self.faces = vertices, faces


Vs, Fs = meshlap.shapes.sphere(1000, seed=0)
Vs, Fs = as_mesh(Shape(Vs, Fs))
sphere_op = meshlap.laplacian(Vs, Fs, h=0.02, correction="none")
err = np.abs(sphere_op @ Vs[:, 2] + 2 * Vs[:, 2]).max()
print(f"sphere from a trimesh-like object: max |L z + 2z| = {err:.3f} (Δz = -2z; |2z| ≤ 2)")
print(f"wrote {write_mesh(out / 'sphere.ply', Vs, Fs)}")
assert err < 0.05
