"""The Galerkin pencil: symmetric, semidefinite, and its spectra on coarse meshes."""

import math
from pathlib import Path

import igl
import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.sparse.linalg import eigsh

import meshlap
from meshlap import MeshError, shapes, spectral, tuned
from meshlap.corrections import features, galerkin

DATA = Path(__file__).parent / "data"


def kernel_laplacian(*args, **kwargs):
    # the heat-kernel operator these tests are about (the default of meshes is the FEM pencil)
    return meshlap.laplacian(*args, **{"operator": "kernel", **kwargs})


def galerkin_laplacian(*args, **kwargs):
    # the Galerkin pencil, asked for by name (the kernel builder never takes it by itself)
    return meshlap.laplacian(*args, **{"operator": "galerkin", **kwargs})


def _err(lam, ref):
    return float(np.abs(lam[1:10] / ref[1:10] - 1).max())


def _sphere_exact():
    return np.array([d * (d + 1) for d in range(4) for _ in range(2 * d + 1)], float)[:10]


def _square_exact():  # Neumann on [-1, 1]²
    return np.array(sorted((math.pi / 2) ** 2 * (a * a + b * b) for a in range(5) for b in range(5))[:10])


def _cot_refined(V, F):
    # linear FEM on the mesh refined 16× (two midpoint subdivisions), the reference of
    # benchmarks/bench_spectra.py
    for _ in range(2):
        V, F = igl.upsample(V, F)
    L, M = igl.cotmatrix(V, F), igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI)
    return np.sort(eigsh(sp.csc_matrix(-L), 10, sp.csc_matrix(M), sigma=-1e-6, which="LM")[0])


def test_quadrature_rule_is_exact_for_quadratics():
    # degree 2 on a triangle in R³ and on a tetrahedron: ∫x² over the simplex
    P = np.array([[0.0, 0, 0], [2, 0, 0], [0, 1, 0], [0, 0, 3]])
    X, W, Phi = galerkin.quadrature_points(P, np.array([[0, 1, 2]]))
    assert np.allclose(Phi @ P, X)
    assert abs(W @ X[:, 0] ** 2 - 2 / 3) < 1e-12  # area 1: A (Σ x_i² + Σ_{i<j} x_i x_j) / 6
    X, W, _ = galerkin.quadrature_points(P, np.array([[0, 1, 2, 3]]))
    assert abs(W.sum() - 1.0) < 1e-12 and abs(W @ X[:, 0] ** 2 - 0.4) < 1e-12  # the same over 10


def test_pencil_symmetric_semidefinite_and_energy_of_a_neumann_mode():
    V, F = shapes.sphere(500, seed=0)
    S, m = galerkin.galerkin_pencil(V, F, 0.5 * 0.176**2, 2)
    assert abs(S - S.T).max() < 1e-12
    assert np.abs(S @ np.ones(len(V))).max() < 1e-9
    assert np.allclose(m, meshlap.geometry.from_mesh(V, F).mass)
    lam = sla.eigh(-S.toarray(), np.diag(m), eigvals_only=True)
    assert lam[0] > -1e-10 * lam[-1]
    # the energy of a Neumann mode f = cos(π(x + 1)/2) on [-1, 1]², ∫|∇f|² = π²/2: the kernel
    # misses 5.5% in the boundary band, the mirror images restore it to within 1%
    # (measured -5.5%, -0.6%; Richardson with images +0.8%)
    Vq, Fq = shapes.plane(400, seed=0, kind="stratified")
    g = meshlap.geometry.from_mesh(Vq, Fq)
    h = 0.5 * g.spacing**2
    bnd = g.boundary_samples(meshlap.assembly.cutoff_radius(h, 1e-8))
    f = np.cos(math.pi * (Vq[:, 0] + 1) / 2)
    cases = ((None, False, -0.07, -0.04), (bnd, False, -0.01, 0.01), (bnd, True, 0, 0.012))
    for boundary, dog, lo, hi in cases:
        S, _ = galerkin.galerkin_pencil(Vq, Fq, h, 2, dog=dog, boundary=boundary)
        assert lo < -f @ S @ f / (math.pi**2 / 2) - 1 < hi


@pytest.mark.parametrize("name, tol", [("torus", 0.013), ("sphere", 0.013), ("square", 0.008)])
def test_coarse_rows_of_bench_spectra(name, tol):
    # measured 0.95%, 0.96%, 0.57% (libigl's cotangent FEM: 2.25%, 1.85%, 2.45%)
    if name == "torus":
        V, F = shapes.torus(600, seed=0)
        ref = _cot_refined(V, F)
    elif name == "sphere":
        V, F = shapes.sphere(500, seed=0)
        ref = _sphere_exact()
    else:
        V, F = shapes.plane(400, seed=0, kind="stratified")
        ref = _square_exact()
    op = galerkin_laplacian(V, F)
    assert op.quadrature == "galerkin" and op.psd_margin > -1e-6
    S = op.S
    assert abs(S - S.T).max() < 1e-12
    assert _err(spectral.eigs(op, 10)[0], ref) < tol


def test_pointwise_rows_unchanged_and_vertex_option():
    V, F = shapes.sphere(500, seed=0)
    gal, vert = galerkin_laplacian(V, F), kernel_laplacian(V, F, quadrature="vertex")
    assert vert.quadrature == "vertex" and vert.quadrature_h is None
    assert (gal.L != vert.L).nnz == 0  # op @ f is the vertex rows either way
    assert abs(gal.L_sym - vert.L_sym).max() > 0
    assert gal.quadrature == "galerkin" and 0 < gal.quadrature_h < gal.h


def test_the_kernel_builder_keeps_the_vertex_pencil_unless_asked():
    # no automatic choice between pencils: the vertex pencil on a clean mesh and on a curve,
    # the Galerkin pencil only by name
    V, F = shapes.sphere(2000, seed=0)
    assert kernel_laplacian(V, F).quadrature == "vertex"
    P, E, _ = meshlap.samples.circle(200, kind="random")
    assert kernel_laplacian(P, E).quadrature == "vertex"
    assert galerkin_laplacian(P, E).quadrature == "galerkin"
    # the roughness that keeps the feature width off noise (corrections.features)
    noisy = V * (1 + 0.005 * np.random.default_rng(1).standard_normal((len(V), 1)))
    assert galerkin.shape_measures(V, F)[1] < 2
    angle, rough = galerkin.shape_measures(noisy, F)
    assert rough > tuned.NOISE_ROUGHNESS  # measured 3.65 (smooth: about 1)
    # the 12 edges of a box are creases (90° between faces), its face diagonals are not
    Vb = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    Fb = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                   [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    assert galerkin.shape_measures(Vb, Fb)[0] > 89
    assert galerkin.creases(Vb, Fb).shape == (12, 2)
    # the paper's operator and an explicit h are never changed
    assert kernel_laplacian(V, F, correction="none").quadrature == "vertex"
    assert kernel_laplacian(V, F, h=0.01).quadrature == "vertex"


def test_bad_quadrature_options():
    V, F = shapes.sphere(200, seed=0)
    with pytest.raises(MeshError, match="quadrature must be one of"):
        kernel_laplacian(V, F, quadrature="gauss")
    with pytest.raises(MeshError, match="integrates over (simplices|cells)"):
        meshlap.point_cloud_laplacian(V, quadrature="galerkin")
    with pytest.raises(MeshError, match="matrix_free"):
        kernel_laplacian(V, F, quadrature="galerkin", matrix_free=True)


def _cube_surface(m):
    # the surface of [-½, ½]³, m segments per edge, 6 m² squares cut along one diagonal
    g = np.linspace(-0.5, 0.5, m + 1)
    V, F, index = [], [], {}

    def vid(p):
        key = tuple(np.round(p, 12))
        if key not in index:
            index[key] = len(V)
            V.append(p)
        return index[key]

    for axis in range(3):
        for side in (-0.5, 0.5):
            for i in range(m):
                for j in range(m):
                    q = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        p = np.empty(3)
                        p[axis], p[(axis + 1) % 3], p[(axis + 2) % 3] = side, g[i + di], g[j + dj]
                        q.append(vid(p))
                    a, b, c, d = q if side > 0 else q[::-1]
                    F += [[a, b, c], [a, c, d]]
    return np.array(V), np.array(F)


def test_cube_surface_across_its_creases():
    # 386 vertices: measured 0.23% (libigl's cotangent FEM 1.52%; the vertex pencil 17.9%,
    # the Galerkin pencil with chord distances across the creases 18.9%)
    V, F = _cube_surface(8)
    ref = _cot_refined(V, F)
    op = galerkin_laplacian(V, F)
    assert op.quadrature == "galerkin" and op.psd_margin > -1e-6
    assert _err(spectral.eigs(op, 10)[0], ref) < 0.004
    e = meshlap.geometry.from_mesh(V, F).spacing
    S, m = galerkin.galerkin_pencil(V, F, 0.5 * e * e, 2)
    assert _err(sla.eigh(-S.toarray(), np.diag(m), eigvals_only=True, subset_by_index=[0, 9]), ref) > 0.1


def test_segments_cut_to_the_width():
    # a segment of length 3 at h = 0.01: pieces of at most 0.5·√h = 0.05, two Gauss points
    # each (degree 3: ∫₀³ x³ = 81/4), the hat functions interpolating the positions
    P = np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 0.2]])
    X, W, Phi = galerkin.quadrature_points(P, np.array([[0, 1], [1, 2]]), h=0.01)
    assert len(X) == 2 * (60 + 4)
    assert abs(W.sum() - 3.2) < 1e-12 and np.allclose(Phi @ P, X)
    on = X[:, 1] == 0
    assert abs(W[on] @ X[on, 0] ** 3 - 81 / 4) < 1e-10
    assert len(galerkin.quadrature_points(P, np.array([[0, 1]]))[0]) == 2  # without h: the 2-point rule


@pytest.mark.parametrize("closed", [True, False])
def test_curves_galerkin_pencil(closed):
    # 400 random angles on the circle: measured 0.11% against linear FEM's 0.55% (the vertex
    # pencil 10.9%); the open half circle (Neumann, eigenvalues m², ends mirrored), 200
    # vertices: 0.28% against 0.69%
    rng = np.random.default_rng(0)
    if closed:
        P, E, _ = meshlap.samples.circle(400, kind="random", seed=0)
        exact = np.array([0] + [m * m for m in range(1, 6) for _ in range(2)], float)[:10]
        bound = 0.002
    else:
        t = np.sort(np.r_[0.0, math.pi, rng.uniform(0, math.pi, 198)])
        P, E = np.column_stack([np.cos(t), np.sin(t)]), np.column_stack([np.arange(199), np.arange(1, 200)])
        exact = np.arange(10.0) ** 2
        bound = 0.004
    op = galerkin_laplacian(P, E)
    assert op.quadrature == "galerkin" and op.psd_margin > -1e-6
    S = op.S
    assert abs(S - S.T).max() < 1e-12 and np.abs(S @ np.ones(len(P))).max() < 1e-8
    err = _err(spectral.eigs(op, 10)[0], exact)
    fem = meshlap.baselines.cotangent(P, E)
    lam = np.sort(eigsh(sp.csc_matrix(-fem.S), 10, sp.diags(fem.mass).tocsc(), sigma=-1e-6)[0])
    fem_err = _err(lam, exact)
    assert err < bound and err < 0.6 * fem_err


def test_a_real_boundary_loop_takes_the_galerkin_pencil_by_default():
    """The Stanford bunny's longest boundary loop (55 vertices, segments 4.3× apart in length):
    a closed polyline of length ℓ is intrinsically a circle, eigenvalues (2πm/ℓ)². The default
    is the Galerkin pencil, measured 0.81% against linear FEM's 5.8% (bench_loops.py)."""
    V, F = igl.read_triangle_mesh(str(DATA / "stanford-bunny.obj"))
    P = V[igl.boundary_loop(F)]
    ell = np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1).sum()
    exact = np.r_[0.0, np.repeat((2 * np.pi * np.arange(1, 6) / ell) ** 2, 2)][:10]
    E = np.column_stack([np.arange(len(P)), (np.arange(len(P)) + 1) % len(P)])
    op = meshlap.laplacian(P, E)
    err = _err(spectral.eigs(op, 10)[0], exact)
    fem_err = _err(spectral.eigs(meshlap.baselines.cotangent(P, E), 10)[0], exact)
    assert op.decision.operator == "galerkin" and err < 0.012 and err < 0.25 * fem_err


def test_copies_are_welded_for_the_galerkin_pencil():
    """A closed polyline given as a chain whose last point repeats its first, and a sphere cut
    along a seam of duplicated vertices: the Galerkin pencil welds the copies as FEM does (the
    curve's default gave the open arc's (m/2)², the sphere 3.1 for l(l+1) = 2)."""
    t = np.linspace(0, 2 * np.pi, 401)
    P, E = np.c_[np.cos(t), np.sin(t)], np.c_[np.arange(400), np.arange(1, 401)]
    op = meshlap.laplacian(P, E)
    assert op.decision.operator == "galerkin"
    assert np.allclose(spectral.eigs(op, 5)[0], [0, 1, 1, 4, 4], atol=5e-3)
    V, F = shapes.sphere(800, seed=0)
    seam = np.flatnonzero(np.abs(V[:, 0]) < 0.08)
    copy = np.arange(len(V))
    copy[seam] = len(V) + np.arange(len(seam))
    right = V[F].mean(axis=1)[:, 0] > 0
    F2 = np.where(right[:, None], copy[F], F)
    with pytest.warns(meshlap.MeshWarning, match="duplicate vertices"):
        cut = meshlap.laplacian(np.vstack([V, V[seam]]), F2, operator="galerkin")
    whole = meshlap.laplacian(V, F, operator="galerkin")
    assert cut.quadrature == "galerkin"
    assert np.allclose(spectral.eigs(cut, 9)[0], spectral.eigs(whole, 9)[0], rtol=1e-6, atol=1e-9)


def test_curves_couple_along_their_arc_only():
    # two circles side by side: two zero eigenvalues, then 1 four times; a trefoil knot of 60
    # vertices, whose strands pass within the kernel's reach: measured 0.53% against linear
    # FEM's 1.98% (with the chord distance 228%)
    P, E, _ = meshlap.samples.circle(300, kind="random", seed=0)
    op = galerkin_laplacian(np.vstack([P, P + [2.5, 0]]), np.vstack([E, E + 300]))
    lam = spectral.eigs(op, 6)[0]
    assert np.abs(lam[:2]).max() < 1e-8 and np.abs(lam[2:] - 1).max() < 0.003
    def trefoil(s):
        return np.column_stack([np.sin(s) + 2 * np.sin(2 * s), np.cos(s) - 2 * np.cos(2 * s), -np.sin(3 * s)])

    K = trefoil(2 * math.pi * np.arange(60) / 60)
    ring = np.column_stack([np.arange(60), (np.arange(60) + 1) % 60])
    length = np.linalg.norm(np.diff(trefoil(np.linspace(0, 2 * math.pi, 200_001)), axis=0), axis=1).sum()
    exact = np.array([(2 * math.pi * ((j + 1) // 2) / length) ** 2 for j in range(10)])
    assert _err(spectral.eigs(galerkin_laplacian(K, ring), 10)[0], exact) < 0.008


def _hairpin(gap, step=0.05):
    # a strip of width 1 bent back on itself around a half cylinder of diameter gap: its two
    # flat legs of length 1 lie gap apart in space, 1 + π gap/2 and more along the surface
    r = gap / 2
    s = np.arange(0, 2 + math.pi * r + step / 2, step)
    phi = np.clip((s - 1) / r, 0, math.pi)
    x = np.where(s <= 1, s, np.where(s >= 1 + math.pi * r, 1 - (s - 1 - math.pi * r), 1 + r * np.sin(phi)))
    z = np.where(s <= 1, 0.0, np.where(s >= 1 + math.pi * r, gap, r - r * np.cos(phi)))
    v = np.arange(0, 1 + step / 2, step)
    V = np.array([[xi, vj, zi] for xi, zi in zip(x, z, strict=True) for vj in v])
    m = len(v)
    F = [[i * m + j, (i + 1) * m + j, (i + 1) * m + j + 1] for i in range(len(s) - 1) for j in range(m - 1)]
    F += [[i * m + j, (i + 1) * m + j + 1, i * m + j + 1] for i in range(len(s) - 1) for j in range(m - 1)]
    return V, np.array(F)


def test_pairs_through_the_air_are_dropped():
    # the hairpin's legs 0.1 apart, h = 0.5·0.05²: the kernel reaches 0.3 across; the pairs
    # between the legs away from the bend lose all but 1e-5 of their weight (what is left are
    # pairs near the bend, whose path along the surface is under SHORTCUT_RATIO times their
    # chord plus the slack), pairs along a leg keep all of theirs
    V, F = _hairpin(0.1)
    h = 0.5 * 0.05**2
    X, W, _ = galerkin.quadrature_points(V, F)
    radius = meshlap.assembly.cutoff_radius(h, 1e-8)
    Lq = meshlap.assembly.assemble(X, W, meshlap.widths.Widths(h, None, False), meshlap.assembly.Kernel(2))
    out, hit = meshlap.corrections.shortcuts.drop_shortcuts(Lq, V, F, X, radius)
    leg = X[:, 0] < 0.8
    before = Lq.tocoo()
    across = leg[before.row] & leg[before.col] & (np.abs(X[before.row, 2] - X[before.col, 2]) > 0.05)
    kept = np.asarray(out[before.row[across], before.col[across]]).ravel()
    assert np.abs(kept).sum() < 1e-5 * np.abs(before.data[across]).sum() and hit[leg].all()
    same = leg[before.row] & leg[before.col] & (np.abs(X[before.row, 2] - X[before.col, 2]) < 1e-9)
    assert (out[before.row[same], before.col[same]] != 0).all()
    assert np.abs(out @ np.ones(len(X))).max() < 1e-9 * np.abs(out.data).max()


def test_split_points_exact_for_quadratics_and_unsplit_as_before():
    P = np.array([[0.0, 0, 0], [2, 0, 0], [0, 1, 0]])
    for s in (1, 2, 3):
        X, W, Phi, face, corner = galerkin.split_points(P, np.array([[0, 1, 2]]), np.array([s]))
        assert len(X) == 3 * s * s and np.allclose(Phi @ P, X) and (face == 0).all()
        assert abs(W @ X[:, 0] ** 2 - 2 / 3) < 1e-12  # ∫x² over the triangle of area 1
        assert (corner == Phi.toarray().argmax(axis=1)).all()
    V, F = shapes.sphere(300, seed=0)
    X0, W0, Phi0 = galerkin.quadrature_points(V, F)
    X1, W1, Phi1, _, corner = galerkin.split_points(V, F, np.ones(len(F), dtype=int))
    assert (X0 == X1).all() and (W0 == W1).all() and (Phi0 != Phi1).nnz == 0 and (corner == F.ravel()).all()


def test_feature_width_pencil_symmetric_rows_sum_to_zero_semidefinite():
    # the cube surface's creases (convex: the default leaves them, here passed to narrow): the
    # width is the floor on a crease, grows with the distance to it, h beyond 1 width; the
    # triangles there are cut in 4; S symmetric with zero row sums, -S semidefinite
    V, F = _cube_surface(6)
    g = meshlap.geometry.from_mesh(V, F)
    h = tuned.GALERKIN_H_SCALE * g.spacing**2
    folds = galerkin.creases(V, F)
    hv = features.feature_widths(V, g.normals(), folds, h, crease=1.0)
    d = features.crease_distance(V, folds, np.inf)
    assert np.allclose(hv[d < 1e-9], tuned.FEATURE_FLOOR * h)
    far = d > math.sqrt(2 * h)
    assert far.sum() > 20 and (hv[far] == h).all()
    order = np.argsort(d, kind="stable")
    assert (np.diff(hv[order]) >= -1e-15).all()
    info = {}
    S, m = galerkin.galerkin_pencil(V, F, h, 2, crease_edges=folds, info=info, h_vertex=hv)
    assert info["points"] > 3 * len(F)
    assert abs(S - S.T).max() < 1e-12 * abs(S).max()
    assert np.abs(S @ np.ones(len(V))).max() < 1e-9 * abs(S).max()
    lam = sla.eigh(-S.toarray(), np.diag(m), eigvals_only=True)
    assert lam[0] > -1e-10 * lam[-1]
    # the default narrows next to concave creases only: the cube's are convex (across them
    # the unfolded distance is exact), it has no thin part, and keeps one width
    assert galerkin.creases(V, F, concave=True).shape == (0, 2)
    assert galerkin_laplacian(V, F)._built.assemble().narrowed == 0


def test_feature_width_narrows_next_to_grooves_not_on_noise():
    # fandisk: its 115 concave creases (of 700) narrow the width on 12% of its area
    Vf, Ff = igl.read_triangle_mesh("tests/data/fandisk.obj")
    g = meshlap.geometry.from_mesh(Vf, Ff)
    h = tuned.GALERKIN_H_SCALE * g.spacing**2
    grooves = galerkin.creases(Vf, Ff, concave=True)
    assert 50 < len(grooves) < 200 and len(galerkin.creases(Vf, Ff)) > 500
    hv = features.feature_widths(Vf, g.normals(), grooves, h)
    near = features.crease_distance(Vf, grooves, 0.5 * math.sqrt(2 * h)) < np.inf
    assert near.any() and (hv[near] < h).all() and 0.05 < (hv < h).mean() < 0.3
    # the 0.5% radial noise of bench_spectra's noisy sphere makes fake creases: ungated, the
    # width would narrow on a quarter of the sphere (89% at 16,000 vertices); the build's
    # noise gate narrows nothing
    V, F = shapes.sphere(2000, kind="random", seed=0)
    noisy = V * (1 + 0.005 * np.random.default_rng(1).standard_normal((len(V), 1)))
    gn = meshlap.geometry.from_mesh(noisy, F)
    hn = tuned.GALERKIN_H_SCALE * gn.spacing**2
    fake = features.feature_widths(noisy, gn.normals(), galerkin.creases(noisy, F, concave=True), hn)
    assert (fake < hn).mean() > 0.2
    op = kernel_laplacian(noisy, F, quadrature="galerkin")
    assert op.quadrature == "galerkin" and op._built.assemble().narrowed == 0
    off = kernel_laplacian(noisy, F, quadrature="galerkin", feature_width=False)
    assert (op.L_sym != off.L_sym).nnz == 0
    # an explicit h (the smoothing flow's) keeps one width unless asked
    Vt, Ft = shapes.torus(300, seed=0)  # its tube is 2.5 kernel widths across at h = 0.5 ē²
    ht = tuned.GALERKIN_H_SCALE * meshlap.geometry.from_mesh(Vt, Ft).spacing**2
    assert kernel_laplacian(Vt, Ft, h=ht, quadrature="galerkin")._built.assemble().narrowed == 0
    narrowed = kernel_laplacian(Vt, Ft, h=ht, quadrature="galerkin", feature_width=True)
    assert narrowed._built.assemble().narrowed > 0.5
    # the build's semidefinite check ran on the narrowed pencil, and passed
    assert narrowed.quadrature == "galerkin" and narrowed.psd_margin > -1e-6
    with pytest.raises(MeshError, match="feature_width must be"):
        kernel_laplacian(V, F, feature_width="yes")
    with pytest.raises(MeshError, match="only with quadrature='galerkin'"):
        kernel_laplacian(V, F, feature_width=True, quadrature="vertex")
    with pytest.raises(MeshError, match="only with quadrature='galerkin'"):
        kernel_laplacian(V, F, feature_width=True)


def test_short_cuts_dropped_in_place_as_in_a_copy():
    # a flattened sphere: its two sides closer than the cut-off lose their pairs; copy=False
    # changes the operator it is given and keeps the same entries as the copy
    from meshlap.assembly import Kernel, assemble, cutoff_radius
    from meshlap.corrections.shortcuts import drop_shortcuts
    V, F = shapes.sphere(500, seed=0)
    V = V * np.array([1.0, 1.0, 0.05])
    X, W, _ = galerkin.quadrature_points(V, F)
    Lq = assemble(X, W, meshlap.widths.Widths(0.01, None, False), Kernel(2))
    radius = cutoff_radius(0.01, 1e-8)
    copied, hit = drop_shortcuts(Lq, V, F, X, radius)
    assert hit.any() and abs(copied - Lq).max() > 0
    inplace, hit2 = drop_shortcuts(Lq, V, F, X, radius, copy=False)
    assert (hit2 == hit).all() and abs(inplace - copied).max() == 0 and abs(Lq - copied).max() == 0


def test_parts_are_apart_before_the_semidefinite_check():
    # VTK's hello.vtk writes each letter's strokes as separate 2-point segments: the H's bar
    # ends on its uprights without sharing their vertices, so each stroke is a part. The kernel
    # pairs between the parts carried the negative weights of a stroke's own pair; once they
    # were removed (after the check had passed) -S had an eigenvalue of -0.097 on this H (-0.106
    # and -0.074 on the whole word). Checked as
    # it is used, the Galerkin pencil fails and linear FEM on the same segments is built: one
    # zero per part, then FEM's. The kernel builder's own vertex pencil is semidefinite too.
    P = np.array([[0, 0, 0], [0, 2, 0], [0, 1, 0], [1, 1, 0], [1, 0, 0], [1, 2, 0]], float)
    E = np.array([[0, 1], [4, 5], [2, 3]])
    with pytest.warns(meshlap.MeshWarning, match="linear FEM on them instead"):
        op = meshlap.laplacian(P, E).assemble()
    # the decision records what was built: before the build, what was chosen
    assert meshlap.laplacian(P, E).decision.operator == "galerkin"
    assert op.decision.operator == "fem" and op.quadrature == "fem"
    assert "linear FEM on the same cells was built" in op.decision.reason
    lam = spectral.eigs(op, 5)[0]
    # three zeros; each stroke of length l is two vertices of mass l/2: λ = 4/l² (2, 1 for l = 2, 4 for l = 1)
    assert np.abs(lam[:3]).max() < 1e-9 and np.allclose(lam[3:], [1.0, 1.0])
    for kernel in (meshlap.laplacian(P, E, operator="kernel"), galerkin_laplacian(P, E)):
        S = kernel.S.toarray()
        m = kernel.mass
        low = np.linalg.eigvalsh(-S / np.sqrt(np.outer(m, m)))[0]
        assert low > -1e-9 * np.abs(S).max()
