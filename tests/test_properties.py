"""Property-based checks (hypothesis) on random valid meshes: random points on a sphere and
perturbed height-field grids, with h drawn relative to the mesh's own edge length.

For every such mesh the operator must have the structure eq. (1) of Belkin–Sun–Wang gives
it: S = M L = (M K M - diag(m ∘ K m)) / (4πh²) is a weighted graph Laplacian with weights
m_i K_ij m_j ≥ 0, so S is symmetric and -S positive semidefinite, and L's rows sum to zero.
It only depends on distances, so relabelling the vertices permutes it, a rigid motion
leaves it unchanged, and scaling by s with h → s²h divides it by s².
"""

import math

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import meshlap
from meshlap import shapes

SETTINGS = settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@st.composite
def meshes(draw):
    """A random valid mesh (V, F) and a kernel width h between (ē/2)² and (4ē)²."""
    seed = draw(st.integers(0, 2**31 - 1))
    rng = np.random.default_rng(seed)
    if draw(st.booleans()):
        V, F = shapes.sphere(draw(st.integers(20, 120)), kind="random", seed=seed)
    else:
        nx, ny = draw(st.integers(3, 10)), draw(st.integers(3, 10))
        xs, ys = np.meshgrid(np.linspace(0, 1, nx), np.linspace(0, 1, ny))
        jitter = draw(st.floats(0, 0.3)) / max(nx, ny)
        xy = np.column_stack([xs.ravel(), ys.ravel()]) + rng.uniform(-jitter, jitter, (nx * ny, 2))
        z = draw(st.floats(0, 0.5)) * rng.normal(size=nx * ny) / max(nx, ny)
        V = np.column_stack([xy, z])
        idx = np.arange(nx * ny).reshape(ny, nx)
        a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
        F = np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    edge = math.sqrt(meshlap.default_h(V, F)) / 2
    h = (edge * draw(st.floats(0.5, 4.0))) ** 2
    tol = draw(st.sampled_from([0.0, 1e-8, 1e-3]))
    return V, F, h, tol, rng


def scale_of(A):
    return np.abs(A).max()


@SETTINGS
@given(meshes())
def test_S_symmetric_negative_semidefinite_rows_sum_to_zero(mesh):
    V, F, h, tol, _ = mesh
    op = meshlap.laplacian(V, F, h=h, tol=tol, correction="none")
    L, S = op.L.toarray(), op.S.toarray()
    assert np.isfinite(L).all()
    assert np.abs(S - S.T).max() <= 1e-14 * scale_of(S)
    assert np.linalg.eigvalsh(-(S + S.T) / 2).min() >= -1e-12 * scale_of(S)
    assert np.abs(L.sum(axis=1)).max() <= 1e-12 * scale_of(L)
    assert np.all(L[~np.eye(len(V), dtype=bool)] >= 0)  # off-diagonal weights are non-negative


@SETTINGS
@given(meshes())
def test_relabelling_permutes_L(mesh):
    V, F, h, tol, rng = mesh
    perm = rng.permutation(len(V))  # new vertex i is old vertex perm[i]
    inv = np.argsort(perm)
    F2 = inv[F][rng.permutation(len(F))]  # faces renumbered and reordered
    F2 = np.roll(F2, rng.integers(3), axis=1)  # and each face rotated (same orientation)
    L = meshlap.laplacian(V, F, h=h, tol=tol, correction="none").L.toarray()
    L2 = meshlap.laplacian(V[perm], F2, h=h, tol=tol, correction="none").L.toarray()
    assert np.abs(L2 - L[np.ix_(perm, perm)]).max() <= 1e-13 * scale_of(L)


@SETTINGS
@given(meshes(), st.floats(-3, 3), st.floats(-50, 50))
def test_rigid_motion_and_scaling(mesh, log_s, shift):
    V, F, h, tol, rng = mesh
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    s = 10.0**log_s
    W = s * (V @ R.T + shift)
    L = meshlap.laplacian(V, F, h=h, tol=tol, correction="none").L.toarray()
    L2 = meshlap.laplacian(W, F, h=s * s * h, tol=tol, correction="none").L.toarray()
    # rounding of the moved coordinates (|shift| ≤ 50 next to edges ≥ 0.01) stays below 1e-9;
    # pairs right at the cut-off may fall on either side, which changes entries of size ≤ tol
    atol = (1e-9 + 2 * tol) * scale_of(L)
    assert np.abs(L2 * s * s - L).max() <= atol


@settings(max_examples=50, deadline=None)
@given(st.lists(st.integers(-(2**62), 2**62), max_size=60),
       st.lists(st.integers(-(2**62), 2**62), max_size=60),
       st.booleans())
def test_sorted_key_sets_are_numpys(keys, of, as_rows):
    # meshlap._keys replaces np.unique and np.isin on int64 keys and on rows keyed by their bytes
    from meshlap._keys import in_set, key_set

    a, b = np.array(keys, dtype=np.int64), np.array(of, dtype=np.int64)
    if as_rows:  # (m, 3) rows as one void key each, as stars._triangle_keys makes them beyond 2^21 points
        a = np.ascontiguousarray(np.repeat(a[:, None], 3, axis=1) % 7).view(np.dtype((np.void, 24))).ravel()
        b = np.ascontiguousarray(np.repeat(b[:, None], 3, axis=1) % 7).view(np.dtype((np.void, 24))).ravel()
    assert np.array_equal(key_set(a), np.unique(a))
    assert np.array_equal(in_set(a, b), np.isin(a, b))
    assert np.array_equal(in_set(a, key_set(b), of_sorted=True), np.isin(a, b))
