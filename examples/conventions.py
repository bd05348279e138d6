"""Conventions, side by side: the sign of the Laplacian, M-orthonormal eigenvectors, and one
implicit heat-flow (smoothing) step written with meshlap, libigl and robust-laplacian.

On the unit sphere the coordinate x is an eigenfunction, Δx = -2x, so one backward-Euler
step of the heat equation u_t = Δu with step t has the exact answer x / (1 + 2t); each
library's result is compared with it.

    python examples/conventions.py
"""

import igl
import numpy as np
import robust_laplacian
import scipy.sparse.linalg as sla

import meshlap
from meshlap.heat import implicit_heat
from meshlap.spectral import eigs

V, F = meshlap.shapes.sphere(2000, seed=0)
x = V[:, 0]
t = 0.05
exact = x / (1 + 2 * t)

# -- the three operators --------------------------------------------------------------
op = meshlap.laplacian(V, F, h=0.002, correction="none")  # L ≈ +Δ; S = M L symmetric, negative semidefinite
C = igl.cotmatrix(V, F)  # libigl: symmetric, negative semidefinite (the weak form of +Δ)
M_igl = igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI)
L_rl, M_rl = robust_laplacian.mesh_laplacian(V, F)  # positive semidefinite: the weak form of -Δ

print("sign: x·(S x) for each 'stiffness' matrix (∫|∇x|² = 8π/3 ≈ 8.38 on the sphere)")
print(f"  meshlap  S = M L : {x @ (op.S @ x):+.3f}")
print(f"  libigl   C       : {x @ (C @ x):+.3f}")
print(f"  robust   L       : {x @ (L_rl @ x):+.3f}")

# -- one implicit smoothing step: (M - t·S) u = M u0, written in each library's sign ------
u_meshlap = sla.spsolve((op.M - t * op.S).tocsc(), op.M @ x)
u_igl = sla.spsolve((M_igl - t * C).tocsc(), M_igl @ x)
u_rl = sla.spsolve((M_rl + t * L_rl).tocsc(), M_rl @ x)  # note the + : L_rl is -C

print(f"\none implicit heat step, t = {t}: relative error against x / (1 + 2t)")
errors = {}
for name, u in [("meshlap", u_meshlap), ("libigl", u_igl), ("robust-laplacian", u_rl)]:
    errors[name] = np.linalg.norm(u - exact) / np.linalg.norm(exact)
    print(f"  {name:<17}{errors[name]:.2e}")

# meshlap's own helper takes the same step (with a solver suited to its dense rows)
u_helper = implicit_heat(op, x, tau=t)
assert np.allclose(u_helper, u_meshlap, rtol=0, atol=1e-8)

# -- eigenvectors are M-orthonormal -------------------------------------------------------
# eigs solves -S φ = λ M φ (the eigenvalues of -L, λ ≥ 0, the first 0); the eigenvectors
# satisfy Φᵀ M Φ = I, not Φᵀ Φ = I. With scipy: eigsh(-S, k, M=M, sigma=-0.01).
lam, Phi = eigs(op, 6)
lam_scipy = np.sort(sla.eigsh(-op.S, k=6, M=op.M, sigma=-0.01)[0])
gram_M = Phi.T @ (op.M @ Phi)
gram = Phi.T @ Phi
print("\nfirst eigenvalues of -L (exact: 0, 2, 2, 2, 6, 6):", np.round(np.abs(lam), 3))
print(f"scipy's eigsh agrees: max |λ - λ_scipy| = {np.abs(lam - lam_scipy).max():.1e}")
print(f"max |Φᵀ M Φ - I| = {np.abs(gram_M - np.eye(6)).max():.1e}   (M-orthonormal)")
print(f"max |Φᵀ Φ - I|   = {np.abs(gram - np.eye(6)).max():.1e}   (not orthonormal)")

assert max(errors.values()) < 5e-3
assert np.abs(lam - lam_scipy).max() < 1e-6
assert np.abs(gram_M - np.eye(6)).max() < 1e-8 and np.abs(gram - np.eye(6)).max() > 0.1
